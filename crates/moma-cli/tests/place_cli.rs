//! End-to-end tests of `moma place` on Fetch at MotionBenchMaker's small bookshelf: a
//! query that works (exit 0, the best candidate in the JSON and the figure written), one
//! that cannot (exit 3 with the reason, the JSON still written), and bad input (exit 1, no
//! output).

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../moma/tests/data");
const GROUP: &str = "torso_lift_joint,shoulder_pan_joint,shoulder_lift_joint,upperarm_roll_joint,\
elbow_flex_joint,forearm_roll_joint,wrist_flex_joint,wrist_roll_joint";

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("moma_place_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn place(scene: &str, wheels: &str, out: &Path, svg: &Path) -> Output {
    let fetch = format!("{DATA}/robots/fetch");
    let mbm = format!("{DATA}/scenes/motion_bench_maker");
    Command::new(env!("CARGO_BIN_EXE_moma"))
        .args([
            "place",
            &format!("{fetch}/fetch_description/robots/fetch.urdf"),
            "--srdf",
            &format!("{fetch}/fetch.srdf"),
            "--package-dir",
            &fetch,
            "--scene",
            &format!("{mbm}/{scene}"),
            "--query",
            &format!("{mbm}/configs/scenes/bookshelf/hard_queries_small.yaml"),
            "--frame",
            "gripper_link",
            "--group",
            GROUP,
            "--wheels",
            wheels,
            "--casters",
            &format!("{fetch}/casters.toml"),
            "--payload",
            "0.35",
            "--area=-0.2,0.0,0.3,0.6",
            "--headings",
            "8",
            "--output",
            out.to_str().unwrap(),
            "--svg",
            svg.to_str().unwrap(),
        ])
        .output()
        .expect("run moma")
}

#[test]
fn a_grasp_from_a_query_gets_ranked_placements() {
    let (out, svg) = (tmp("ok.json"), tmp("ok.svg"));
    let o = place(
        "fetch_queries/scenes/bookshelf_small-Front-Can1-0.yaml",
        "l_wheel_joint,r_wheel_joint",
        &out,
        &svg,
    );
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(v["found"], true);
    assert_eq!(v["grasp"]["object"], "Can1");
    let best = &v["candidates"][0];
    assert_eq!(best["q"].as_array().unwrap().len(), 3 + 15);
    assert!(best["clearance"].as_f64().unwrap() > 0.005);
    assert!(best["tip_over_margin"].as_f64().unwrap() > 0.0);
    assert!(best["grasp_error"][0].as_f64().unwrap() <= 0.01);
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<svg"));
}

#[test]
fn an_impossible_grasp_exits_3_with_the_reason() {
    // The nominal scene puts Can2 where the grasp of Can1's query is.
    let (out, svg) = (tmp("no.json"), tmp("no.svg"));
    let o = place(
        "configs/scenes/bookshelf/scene_small.yaml",
        "l_wheel_joint,r_wheel_joint",
        &out,
        &svg,
    );
    assert_eq!(o.status.code(), Some(3));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("no base pose reaches the grasp") && err.contains("reached only in collision"),
        "{err}"
    );
    let v: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(v["found"], false);
    assert!(
        v["reason"]
            .as_str()
            .unwrap()
            .contains("reached only in collision")
    );
}

#[test]
fn bad_wheels_exit_1_without_output() {
    let (out, svg) = (tmp("bad.json"), tmp("bad.svg"));
    let o = place(
        "fetch_queries/scenes/bookshelf_small-Front-Can1-0.yaml",
        "l_wheel_joint",
        &out,
        &svg,
    );
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--wheels"));
    assert!(!out.exists() && !svg.exists());
}

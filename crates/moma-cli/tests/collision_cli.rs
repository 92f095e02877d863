//! End-to-end tests of `moma collision`: Fetch in Pinocchio-layout states against the
//! coal reference (self pairs and a MotionBenchMaker scene), the SVG figure, and the
//! errors (message naming file and element, exit status 1, no output file).

use serde_json::Value;
use std::path::PathBuf;
use std::process::{Command, Output};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../moma/tests/data");

fn moma(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_moma"))
        .args(args)
        .output()
        .expect("run moma")
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("moma_collision_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn fetch_args<'a>(urdf: &'a str, srdf: &'a str, pkg: &'a str) -> Vec<&'a str> {
    vec![
        "collision",
        urdf,
        "--root",
        "fixed",
        "--srdf",
        srdf,
        "--package-dir",
        pkg,
    ]
}

#[test]
fn fetch_against_coal_with_a_scene_and_a_figure() {
    let reference: Value = serde_json::from_str(
        &std::fs::read_to_string(format!("{DATA}/collision/fetch_scene_public.json")).unwrap(),
    )
    .unwrap();
    let states: Vec<&Value> = reference["states"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["scene"] == "table_pick")
        .collect();
    let states_file = tmp("states.json");
    let qs: Vec<Value> = states
        .iter()
        .map(|s| serde_json::json!({"q": s["q"]}))
        .collect();
    std::fs::write(
        &states_file,
        serde_json::json!({ "states": qs }).to_string(),
    )
    .unwrap();
    let (urdf, srdf, pkg) = (
        format!("{DATA}/robots/fetch/fetch_description/robots/fetch.urdf"),
        format!("{DATA}/robots/fetch/fetch.srdf"),
        format!("{DATA}/robots/fetch"),
    );
    let scene = format!("{DATA}/scenes/motion_bench_maker/configs/scenes/table/scene_table.yaml");
    let (out, svg) = (tmp("out.json"), tmp("fig.svg"));
    let mut args = fetch_args(&urdf, &srdf, &pkg);
    args.extend([
        "--scene",
        &scene,
        "--states",
        states_file.to_str().unwrap(),
        "--layout",
        "pinocchio",
        "--output",
        out.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
    ]);
    let o = moma(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(got["pairs_enabled"].as_array().unwrap().len(), 76);
    let ref_pairs = reference["scenes"]["table_pick"]["pairs"]
        .as_array()
        .unwrap();
    for (s, want) in got["states"].as_array().unwrap().iter().zip(&states) {
        let pairs = s["pairs"].as_array().unwrap();
        assert_eq!(pairs.len(), 76 + ref_pairs.len());
        for (k, p) in ref_pairs.iter().enumerate() {
            let mine = pairs
                .iter()
                .find(|x| x["a"] == p[0] && x["b"] == p[1])
                .unwrap_or_else(|| panic!("pair {p} missing"));
            let d = mine["distance"].as_f64().unwrap();
            let w = want["distance_convex"][k].as_f64().unwrap();
            assert!((d - w).abs() <= 1e-6, "{p}: {d} vs coal {w}");
        }
        let min = s["min_distance"].as_f64().unwrap();
        let all_min = pairs
            .iter()
            .map(|p| p["distance"].as_f64().unwrap())
            .fold(f64::INFINITY, f64::min);
        assert_eq!(min, all_min);
        assert_eq!(s["in_collision"].as_bool().unwrap(), min < 0.0);
    }
    let fig = std::fs::read_to_string(&svg).unwrap();
    assert!(fig.starts_with("<svg") && fig.matches("<polygon").count() >= 2 * (21 + 12));
}

#[test]
fn bad_input_exits_1_and_writes_nothing() {
    let (urdf, srdf, pkg) = (
        format!("{DATA}/robots/fetch/fetch_description/robots/fetch.urdf"),
        format!("{DATA}/robots/fetch/fetch.srdf"),
        format!("{DATA}/robots/fetch"),
    );
    let states = tmp("one.json");
    std::fs::write(
        &states,
        format!("{{\"states\": [{{\"q\": {:?}}}]}}", vec![0.0; 15]),
    )
    .unwrap();
    let bad_scene = tmp("bad.yaml");
    std::fs::write(
        &bad_scene,
        "world:\n  collision_objects:\n    - header: {frame_id: base_link}\n      id: Shelf\n      primitives: [{type: cylinder, dimensions: [0.5, -0.1]}]\n      primitive_poses: [{position: [1, 0, 0], orientation: [0, 0, 0, 1]}]\n",
    )
    .unwrap();
    let out = tmp("never.json");
    let mut args = fetch_args(&urdf, &srdf, &pkg);
    args.extend([
        "--scene",
        bad_scene.to_str().unwrap(),
        "--states",
        states.to_str().unwrap(),
        "--output",
        out.to_str().unwrap(),
    ]);
    let o = moma(&args);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.yaml") && err.contains("Shelf") && err.contains("-0.1"),
        "{err}"
    );
    assert!(!out.exists());
    // Without the package folder: the link and the URI.
    let o = moma(&[
        "collision",
        &urdf,
        "--root",
        "fixed",
        "--states",
        states.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("link 'base_link'") && err.contains("package://fetch_description"),
        "{err}"
    );
}

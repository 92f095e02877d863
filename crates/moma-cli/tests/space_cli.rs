//! `moma space`, run as the built binary: the public free-flyer cases (Panda) against
//! Pinocchio's values, and clear errors (exit 1, no output file, no panic) on bad input.

use serde_json::{Value, json};
use std::path::PathBuf;
use std::process::{Command, Output};

fn moma() -> Command {
    Command::new(env!("CARGO_BIN_EXE_moma"))
}

fn lib_data() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../moma/tests/data")
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("moma_space_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn nums(v: &Value) -> Vec<f64> {
    match v {
        Value::Array(a) => a.iter().flat_map(nums).collect(),
        Value::Number(n) => vec![n.as_f64().unwrap()],
        other => panic!("not a number: {other}"),
    }
}

#[track_caller]
fn fails(out: &Output, needles: &[&str]) {
    assert_eq!(out.status.code(), Some(1), "exit status");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "moma panicked: {err}");
    for n in needles {
        assert!(err.contains(n), "stderr lacks '{n}': {err}");
    }
}

#[test]
fn public_cases_match_pinocchio() {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/space/multibody_public.json");
    let doc: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    for (i, case) in doc["cases"].as_array().unwrap().iter().enumerate() {
        let states = tmp(&format!("states{i}.json"));
        std::fs::write(
            &states,
            json!({ "states": [case["state"].clone()] }).to_string(),
        )
        .unwrap();
        let out_path = tmp(&format!("out{i}.json"));
        let out = moma()
            .arg("space")
            .arg(lib_data().join(case["urdf"].as_str().unwrap()))
            .args(["--frame", case["frame"].as_str().unwrap()])
            .arg("--states")
            .arg(&states)
            .arg("--output")
            .arg(&out_path)
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let got: Value =
            serde_json::from_str(&std::fs::read_to_string(&out_path).unwrap()).unwrap();
        let st = &got["states"][0];
        for (k, want) in case["expected"].as_object().unwrap() {
            let (g, w) = (nums(&st[k]), nums(want));
            assert_eq!(g.len(), w.len(), "case {i} {k}: length");
            for (a, b) in g.iter().zip(&w) {
                assert!((a - b).abs() <= 1e-10, "case {i} {k}: {a} vs {b}");
            }
        }
        // matrices keep their shapes: 6 × (nv − 6) and (nv − 6) × (nv − 6)
        assert_eq!(st["generalized_jacobian"].as_array().unwrap().len(), 6);
        assert_eq!(st["generalized_inertia"].as_array().unwrap().len(), 9);
    }
}

#[test]
fn momentum_is_optional_and_stdout_works() {
    let states = tmp("nomomentum.json");
    let mut q = vec![0.0; 16];
    q[6] = 1.0;
    std::fs::write(
        &states,
        json!({"states": [{"q": q, "qdot_joints": vec![0.1; 9]}]}).to_string(),
    )
    .unwrap();
    let out = moma()
        .arg("space")
        .arg(lib_data().join("pinocchio/urdf/panda.urdf"))
        .args(["--frame", "panda_hand_tcp", "--states"])
        .arg(&states)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["root"], "free-flyer");
    assert_eq!(v["states"][0]["v"].as_array().unwrap().len(), 15);
}

#[test]
fn bad_input_is_one_clear_error_and_no_file() {
    let panda = lib_data().join("pinocchio/urdf/panda.urdf");
    let mut q = vec![0.0; 16];
    q[6] = 1.0;
    let cases = [
        (
            json!({"states": [{"q": q, "qdot_joints": vec![0.1; 8]}]}),
            vec!["qdot_joints", "expected 9"],
        ),
        (
            json!({"states": [{"q": vec![0.0; 15], "qdot_joints": vec![0.1; 9]}]}),
            vec!["states[0] q"],
        ),
        (
            json!({"states": [{"q": q, "qdot_joints": vec![0.1; 9], "momentum": {"linear": [1, 2], "angular_about_com": [0, 0, 0]}}]}),
            vec!["momentum.linear"],
        ),
        (
            json!({"states": [{"q": q, "qdot_joints": vec![0.1; 9], "momentum": {"linear": [0, 0, 0]}}]}),
            vec!["angular_about_com"],
        ),
        (json!({"states": []}), vec!["empty"]),
    ];
    for (i, (doc, needles)) in cases.iter().enumerate() {
        let states = tmp(&format!("bad{i}.json"));
        std::fs::write(&states, doc.to_string()).unwrap();
        let out_path = tmp(&format!("bad_out{i}.json"));
        let out = moma()
            .arg("space")
            .arg(&panda)
            .args(["--frame", "panda_hand_tcp", "--states"])
            .arg(&states)
            .arg("--output")
            .arg(&out_path)
            .output()
            .unwrap();
        fails(&out, needles);
        assert!(!out_path.exists(), "case {i}: output written on error");
    }
    let out = moma()
        .arg("space")
        .arg(&panda)
        .args(["--frame", "no_such_frame", "--states"])
        .arg(tmp("bad0.json"))
        .output()
        .unwrap();
    fails(&out, &["no_such_frame"]);
    let out = moma().arg("space").arg(&panda).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn free_floating_scenarios_run_and_keep_the_momentum() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    for name in [
        "space_zero_momentum",
        "space_nonzero_momentum",
        "space_resolved_rate",
        "space_decoupled",
        "space_reaction_null_space",
        "space_capture",
    ] {
        let dir = tmp(name);
        let out = moma()
            .arg("simulate")
            .arg(root.join(format!("{name}.toml")))
            .arg("--output")
            .arg(&dir)
            .arg("--quiet")
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let s: Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                .unwrap();
        for d in s["momentum_drift"].as_array().unwrap() {
            for k in ["linear", "angular"] {
                assert!(d[k].as_f64().unwrap() < 1e-10, "{name}: {k} drift {}", d[k]);
            }
        }
        for f in [
            "trajectory.csv",
            "base_attitude.svg",
            "momentum.svg",
            "momentum_drift.svg",
            "ee_path.svg",
        ] {
            assert!(dir.join(f).is_file(), "{name}: {f}");
        }
        if name == "space_capture" {
            assert!(s["capture"]["max_difference"].as_f64().unwrap() < 1e-12);
        }
        if name.contains("rate") || name.contains("decoupled") || name.contains("null") {
            let p = nums(&s["final_frame_position"]);
            let goal = [0.45, 0.25, 0.45];
            let e: f64 = p
                .iter()
                .zip(goal)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                .sqrt();
            assert!(e < 1e-3, "{name}: hand {e} m from the goal");
        }
    }
}

#[test]
fn free_floating_scenario_errors() {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    let text = std::fs::read_to_string(root.join("space_resolved_rate.toml")).unwrap();
    let bad = [
        (
            text.replace("frame = \"panda_hand_tcp\"", "frame = \"nope\""),
            "robot.frame",
        ),
        (text.replace("gain = 1.5", "gain = -1.0"), "control"),
        (format!("gravity = 9.81\n{text}"), "zero gravity"),
    ];
    for (i, (t, needle)) in bad.iter().enumerate() {
        let p = root.join(format!("space_bad_{}_{i}.toml", std::process::id()));
        std::fs::write(&p, t).unwrap();
        let dir = tmp(&format!("bad_scenario{i}"));
        let out = moma()
            .arg("simulate")
            .arg(&p)
            .arg("--output")
            .arg(&dir)
            .output()
            .unwrap();
        std::fs::remove_file(&p).unwrap();
        fails(&out, &[needle]);
        assert!(!dir.join("summary.json").exists());
    }
}

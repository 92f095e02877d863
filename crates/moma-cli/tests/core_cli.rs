//! `moma inspect`, `moma dynamics` and `moma bench`, run as the built binary: outputs
//! against Pinocchio's reference values, and clear errors (non-zero exit, no output file,
//! no panic) on bad input.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn moma() -> Command {
    Command::new(env!("CARGO_BIN_EXE_moma"))
}

fn pinocchio_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../moma/tests/data/pinocchio")
}

fn panda() -> PathBuf {
    pinocchio_dir().join("urdf/panda.urdf")
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("moma_core_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn run(cmd: &mut Command) -> Output {
    cmd.output().expect("run moma")
}

#[track_caller]
fn ok_json(out: &Output) -> Value {
    assert!(
        out.status.success(),
        "moma failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("stdout is JSON")
}

#[track_caller]
fn fails(out: &Output, needles: &[&str]) {
    assert!(!out.status.success(), "moma unexpectedly succeeded");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "moma panicked: {err}");
    for n in needles {
        assert!(err.contains(n), "stderr lacks '{n}': {err}");
    }
}

fn nums(v: &Value) -> Vec<f64> {
    match v {
        Value::Array(a) => a.iter().flat_map(nums).collect(),
        Value::Number(n) => vec![n.as_f64().unwrap()],
        other => panic!("not a number: {other}"),
    }
}

#[track_caller]
fn close(what: &str, got: &Value, want: &Value) {
    let (g, w) = (nums(got), nums(want));
    assert_eq!(g.len(), w.len(), "{what} length");
    for (k, (a, b)) in g.iter().zip(&w).enumerate() {
        assert!(
            (a - b).abs() <= 1e-9 * b.abs().max(1.0),
            "{what}[{k}]: {a} vs {b}"
        );
    }
}

#[test]
fn inspect_reports_structure() {
    for (root, nq, nv, nframes) in [
        ("fixed", 9, 9, 26),
        ("planar", 12, 12, 27),
        ("free-flyer", 16, 15, 27),
    ] {
        let j = ok_json(&run(moma()
            .arg("inspect")
            .arg(panda())
            .args(["--root", root, "--json"])));
        assert_eq!(j["nq"], nq);
        assert_eq!(j["nv"], nv);
        assert_eq!(j["nframes"], nframes);
        assert_eq!(j["root"], root);
        assert_eq!(j["last_link"], "panda_hand_tcp");
        let joints = j["joints"].as_array().unwrap();
        assert_eq!(joints.len(), if root == "fixed" { 9 } else { 10 });
        let last = joints.last().unwrap();
        assert_eq!(last["name"], "panda_finger_joint2");
        assert_eq!(last["parent"], "panda_joint7");
        assert_eq!(last["idx_v"], nv - 1);
        assert_eq!(last["nq"], 1);
    }
    let j = ok_json(&run(moma().arg("inspect").arg(panda()).arg("--json")));
    assert!((j["total_mass"].as_f64().unwrap() - 16.822132000000003).abs() < 1e-12);
    assert_eq!(j["joints"][0]["type"], "revolute_z");
    let text = run(moma()
        .arg("inspect")
        .arg(panda())
        .args(["--root", "planar"]));
    assert!(text.status.success());
    let s = String::from_utf8_lossy(&text.stdout);
    assert!(s.contains("root_joint") && s.contains("planar") && s.contains("panda_hand_tcp"));
}

#[test]
fn dynamics_matches_pinocchio() {
    let reference: Value =
        serde_json::from_str(&std::fs::read_to_string(pinocchio_dir().join("panda.json")).unwrap())
            .unwrap();
    let states: Vec<Value> = reference["states"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| serde_json::json!({"q": s["q"], "v": s["v"], "a": s["a"], "tau": s["tau_in"]}))
        .collect();
    let input = tmp("panda_states.json");
    std::fs::write(&input, serde_json::json!({ "states": states }).to_string()).unwrap();
    let output = tmp("panda_out.json");
    let out = run(moma()
        .arg("dynamics")
        .arg(panda())
        .args(["--root", "fixed", "--states"])
        .arg(&input)
        .arg("--output")
        .arg(&output));
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let got: Value = serde_json::from_str(&std::fs::read_to_string(&output).unwrap()).unwrap();
    assert_eq!(got["frame"], "panda_hand_tcp");
    for (k, want) in reference["states"].as_array().unwrap().iter().enumerate() {
        let g = &got["states"][k];
        for key in [
            "rnea_tau",
            "crba_M",
            "aba_ddq",
            "nle",
            "gravity_torque",
            "com",
            "centroidal_map_Ag",
        ] {
            close(&format!("state {k} {key}"), &g[key], &want[key]);
        }
        for key in ["position", "rotation", "jacobian_local_world_aligned"] {
            close(&format!("state {k} {key}"), &g[key], &want["ee_frame"][key]);
        }
    }
    // stdout mode, another frame, zero gravity
    let j = ok_json(&run(moma()
        .arg("dynamics")
        .arg(panda())
        .args([
            "--root",
            "fixed",
            "--frame",
            "panda_link4",
            "--gravity",
            "0,0,0",
            "--states",
        ])
        .arg(&input)));
    assert_eq!(j["frame"], "panda_link4");
    assert_eq!(j["gravity"], serde_json::json!([0.0, 0.0, 0.0]));
    // zero gravity: no gravity torque
    assert!(
        nums(&j["states"][0]["gravity_torque"])
            .iter()
            .all(|x| *x == 0.0)
    );
}

#[test]
fn bench_reports_medians() {
    let j = ok_json(&run(moma()
        .env("NBATCH", "3")
        .env("WARMUP", "1")
        .arg("bench")
        .arg(panda())
        .args(["--root", "planar", "--json", "--label", "panda_planar"])));
    assert_eq!(j["robot"], "panda_planar");
    assert_eq!(j["nq"], 12);
    // the batch counts asked for are the ones used
    assert_eq!(j["nbatch"], 3);
    assert_eq!(j["warmup"], 1);
    for algo in [
        "rnea",
        "crba",
        "aba",
        "fk",
        "frame_jacobian",
        "rnea_derivatives",
        "aba_derivatives",
    ] {
        let med = j["median_ns"][algo].as_f64().unwrap();
        let min = j["min_ns"][algo].as_f64().unwrap();
        // a median of three batches is at least their minimum, and a real time
        assert!(
            med.is_finite() && min > 0.0 && min <= med,
            "{algo}: {min} vs {med}"
        );
        // well below a second per call on a 9-dof arm: the unit is nanoseconds per call,
        // not per batch or per run
        assert!(med < 1e8, "{algo}: {med} ns per call");
    }
}

#[test]
fn bench_refuses_a_model_without_joints_and_keeps_one_batch() {
    let urdf = write(
        "no_joints.urdf",
        r#"<robot name="box"><link name="base"><inertial><mass value="1"/>
           <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link></robot>"#,
    );
    fails(
        &run(moma().arg("bench").arg(&urdf).args(["--root", "fixed"])),
        &["no_joints.urdf", "no degrees of freedom"],
    );
    // more warm-up batches than batches: still one timed batch, no panic
    let j = ok_json(&run(moma()
        .env("NBATCH", "1")
        .env("WARMUP", "30")
        .arg("bench")
        .arg(panda())
        .args(["--root", "fixed", "--json"])));
    assert_eq!(j["nbatch"], 1);
    // one timed batch: its median is its minimum
    for algo in ["rnea", "crba", "aba", "fk", "frame_jacobian"] {
        let med = j["median_ns"][algo].as_f64().unwrap();
        assert!(med > 0.0, "{algo}");
        assert_eq!(med, j["min_ns"][algo].as_f64().unwrap(), "{algo}");
    }
}

fn write(name: &str, text: &str) -> PathBuf {
    let p = tmp(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn dynamics_fails(urdf: &Path, states: &Path, extra: &[&str], needles: &[&str]) {
    let output = tmp(&format!("never_{}.json", needles.len()));
    let _ = std::fs::remove_file(&output);
    let out = run(moma()
        .arg("dynamics")
        .arg(urdf)
        .args(["--root", "fixed", "--states"])
        .arg(states)
        .args(extra)
        .arg("--output")
        .arg(&output));
    fails(&out, needles);
    assert!(!output.exists(), "a failed run left an output file");
}

#[test]
fn bad_urdfs_are_reported() {
    let states = write("ok_states.json", r#"{"states": [{"q": [0.1]}]}"#);
    let cases = [
        (
            "malformed.urdf",
            "<robot name=\"x\"><link name=\"a\">",
            vec!["malformed.urdf", "malformed"],
        ),
        (
            "cyclic.urdf",
            r#"<robot name="x"><link name="a"/><link name="b"/>
               <joint name="j1" type="fixed"><parent link="a"/><child link="b"/></joint>
               <joint name="j2" type="fixed"><parent link="b"/><child link="a"/></joint></robot>"#,
            vec!["cyclic.urdf", "cyclic"],
        ),
        (
            "nonpd.urdf",
            r#"<robot name="x"><link name="a"/><link name="b"><inertial><mass value="1"/>
               <inertia ixx="-1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
               <joint name="j" type="continuous"><parent link="a"/><child link="b"/></joint></robot>"#,
            vec!["nonpd.urdf", "link 'b'", "positive definite"],
        ),
        (
            "floating.urdf",
            r#"<robot name="x"><link name="a"/><link name="b"/>
               <joint name="free" type="floating"><parent link="a"/><child link="b"/></joint></robot>"#,
            vec![
                "floating.urdf",
                "joint 'free'",
                "unsupported joint type 'floating'",
            ],
        ),
    ];
    for (name, text, needles) in cases {
        let urdf = write(name, text);
        dynamics_fails(&urdf, &states, &[], &needles);
        fails(&run(moma().arg("inspect").arg(&urdf)), &needles);
    }
    fails(
        &run(moma().arg("inspect").arg(tmp("missing.urdf"))),
        &["missing.urdf", "cannot read"],
    );
}

#[test]
fn bad_states_and_options_are_reported() {
    let urdf = panda();
    let wrong_len = write("wrong_len.json", r#"{"states": [{"q": [0, 0, 0]}]}"#);
    dynamics_fails(
        &urdf,
        &wrong_len,
        &[],
        &["wrong_len.json", "states[0] q", "expected length 9, got 3"],
    );
    let q9 = "[0, 0, 0, 0, 0, 0, 0, 0, 0]";
    let bad_v = write(
        "bad_v.json",
        &format!(r#"{{"states": [{{"q": {q9}, "v": [1, 2]}}]}}"#),
    );
    dynamics_fails(&urdf, &bad_v, &[], &["bad_v.json", "states[0] v", "got 2"]);
    let inf = write(
        "inf.json",
        &format!(r#"{{"states": [{{"q": {q9}, "tau": [0, 0, 0, 0, 1e999, 0, 0, 0, 0]}}]}}"#),
    );
    dynamics_fails(&urdf, &inf, &[], &["inf.json"]);
    let nan = write(
        "nan.json",
        r#"{"states": [{"q": [NaN, 0, 0, 0, 0, 0, 0, 0, 0]}]}"#,
    );
    dynamics_fails(&urdf, &nan, &[], &["nan.json", "invalid states file"]);
    let not_json = write("not_json.json", "states: []");
    dynamics_fails(&urdf, &not_json, &[], &["not_json.json"]);
    let empty = write("empty.json", r#"{"states": []}"#);
    dynamics_fails(&urdf, &empty, &[], &["empty.json", "empty"]);
    let ok = write("ok9.json", &format!(r#"{{"states": [{{"q": {q9}}}]}}"#));
    dynamics_fails(
        &urdf,
        &ok,
        &["--frame", "no_such_frame"],
        &["unknown frame 'no_such_frame'"],
    );
    dynamics_fails(
        &urdf,
        &tmp("absent_states.json"),
        &[],
        &["absent_states.json", "cannot read"],
    );
    let out = run(moma()
        .arg("dynamics")
        .arg(&urdf)
        .args(["--root", "fixed", "--gravity", "0,nan,1", "--states"])
        .arg(&ok));
    fails(&out, &["gravity"]);
    let out = run(moma().arg("inspect").arg(&urdf).args(["--root", "wheeled"]));
    fails(&out, &["wheeled"]);
}

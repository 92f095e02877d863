//! `moma osc` end to end: the Panda reference values, task-row selection, and a singular
//! task Jacobian refused with the state named and no output written.

use serde_json::{Value, json};
use std::path::{Path, PathBuf};
use std::process::Command;

fn data(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../moma/tests/data")
        .join(rel)
}

fn tmpdir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("moma-control-cli-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn moma(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_moma"))
        .args(args)
        .output()
        .unwrap()
}

fn flat(v: &Value) -> Vec<f64> {
    match v {
        Value::Array(a) => a.iter().flat_map(flat).collect(),
        Value::Number(n) => vec![n.as_f64().unwrap()],
        _ => panic!("{v}"),
    }
}

#[test]
fn osc_matches_the_panda_reference() {
    let reference: Value =
        serde_json::from_str(&std::fs::read_to_string(data("control/osc_public.json")).unwrap())
            .unwrap();
    let cases = reference["cases"].as_array().unwrap();
    let states: Vec<Value> = cases.iter().map(|c| c["state"].clone()).collect();
    let dir = tmpdir("panda");
    let sp = dir.join("states.json");
    std::fs::write(&sp, json!({ "states": states }).to_string()).unwrap();
    let out = dir.join("out.json");
    let urdf = data("pinocchio/urdf/panda.urdf");
    let o = moma(&[
        "osc",
        urdf.to_str().unwrap(),
        "--root",
        "fixed",
        "--frame",
        "panda_hand_tcp",
        "--states",
        sp.to_str().unwrap(),
        "--output",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    for (c, g) in cases.iter().zip(got["states"].as_array().unwrap()) {
        for (key, want) in c["expected"].as_object().unwrap() {
            let (a, b) = (flat(&g[key]), flat(want));
            assert_eq!(a.len(), b.len(), "{key}");
            for (x, y) in a.iter().zip(&b) {
                assert!(
                    (x - y).abs() <= 1e-8 * y.abs().max(1.0),
                    "{key}: {x} vs {y}"
                );
            }
        }
    }
    // position rows only: 3 × 3 Λ, 9 × 3 J̄; a 6-vector task acceleration is sub-selected
    let out3 = dir.join("out3.json");
    let o = moma(&[
        "osc",
        urdf.to_str().unwrap(),
        "--root",
        "fixed",
        "--frame",
        "panda_hand_tcp",
        "--states",
        sp.to_str().unwrap(),
        "--rows",
        "position",
        "-o",
        out3.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got: Value = serde_json::from_str(&std::fs::read_to_string(&out3).unwrap()).unwrap();
    assert_eq!(
        got["states"][0]["task_inertia"].as_array().unwrap().len(),
        3
    );
    assert_eq!(
        flat(&got["states"][0]["dynamically_consistent_inverse"]).len(),
        27
    );
}

#[test]
fn osc_singular_task_names_the_state() {
    let dir = tmpdir("singular");
    let sp = dir.join("states.json");
    let q = vec![0.0; 9];
    // state 1: the base frame does not move with any joint
    std::fs::write(
        &sp,
        json!({"states": [
            {"q": [0.1, 0.2, 0.3, -1.5, 0.2, 1.6, 0.4, 0.01, 0.01], "task_acceleration": [0, 0, 0, 0, 0, 0]},
            {"q": q, "task_acceleration": [0, 0, 0, 0, 0, 0]}
        ]})
        .to_string(),
    )
    .unwrap();
    let urdf = data("pinocchio/urdf/panda.urdf");
    let out = dir.join("out.json");
    let o = moma(&[
        "osc",
        urdf.to_str().unwrap(),
        "--root",
        "fixed",
        "--frame",
        "panda_link0",
        "--states",
        sp.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("states[0]") && err.contains("singular"),
        "{err}"
    );
    assert!(!out.exists());
    // wrong null-torque length is named
    std::fs::write(
        &sp,
        json!({"states": [{"q": vec![0.0; 9], "task_acceleration": [0, 0, 0, 0, 0, 0], "null_torque": [1.0]}]})
            .to_string(),
    )
    .unwrap();
    let o = moma(&[
        "osc",
        urdf.to_str().unwrap(),
        "--root",
        "fixed",
        "--frame",
        "panda_hand_tcp",
        "--states",
        sp.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("null_torque"));
}

//! End-to-end tests of `moma manipulability`, `moma ik` and `moma reach-map` on Panda.

use serde_json::Value;
use std::path::PathBuf;
use std::process::{Command, Output};

fn panda() -> String {
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../moma/tests/data/manipulability/panda.urdf"
    )
    .to_string()
}

fn moma(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_moma"))
        .args(args)
        .output()
        .expect("run moma")
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("moma_manip_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn json(out: &Output) -> Value {
    serde_json::from_slice(&out.stdout).unwrap_or_else(|e| {
        panic!(
            "bad JSON ({e}): {}\nstderr: {}",
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        )
    })
}

const BASE: &str = "diff-drive:r_w=0.08,b=0.27,d=0.12";

#[test]
fn manipulability_arm_and_whole_body() {
    let states = tmp("states.json");
    std::fs::write(
        &states,
        r#"{"states": [
            {"q": [0.5, -0.2, 0.3, 0.1, -0.5, 0.2, -2.0, 0.1, 1.6, 0.8, 0.02, 0.02],
             "u": [0.2, 0.1, 0.1, 0, 0.3, 0, 0, 0, 0.2, 0, 0]},
            {"q": [0, 0, 0, 0, 0.3, 0, -1.2, 0, 1.5, 0.7, 0.0, 0.0]}
        ]}"#,
    )
    .unwrap();
    let out = moma(&[
        "manipulability",
        &panda(),
        "--base",
        BASE,
        "--states",
        states.to_str().unwrap(),
        "--frame",
        "panda_hand_tcp",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = json(&out);
    let st = v["states"].as_array().unwrap();
    assert_eq!(st.len(), 2);
    for s in st {
        let arm = s["arm_value"].as_f64().unwrap();
        let wb = s["whole_body_value"].as_f64().unwrap();
        assert!(arm > 0.0 && wb >= arm, "{arm} {wb}");
        assert_eq!(s["whole_body"]["shape"], serde_json::json!([6, 11]));
        assert_eq!(s["arm"]["shape"], serde_json::json!([6, 9]));
    }
    assert_eq!(st[0]["jdot_u"].as_array().unwrap().len(), 6);
    assert!(st[1].get("jdot_u").is_none());

    // det(JᵀJ) on a wide Jacobian: undefined (null with a note), not an error.
    let out = moma(&[
        "manipulability",
        &panda(),
        "--states",
        states.to_str().unwrap(),
        "--measure",
        "det-jtj",
        "--base",
        BASE,
        "--json",
    ]);
    assert!(out.status.success());
    let v = json(&out);
    assert!(v["states"][0]["arm_value"].is_null());
    let note = v["states"][0]["notes"][0].as_str().unwrap();
    assert!(note.contains("identically zero"), "{note}");
    assert!(!String::from_utf8_lossy(&out.stdout).contains("NaN"));
}

#[test]
fn manipulability_bad_input() {
    let states = tmp("bad_states.json");
    std::fs::write(&states, r#"{"states": [{"q": [0.1, 0.2]}]}"#).unwrap();
    let out = moma(&[
        "manipulability",
        &panda(),
        "--states",
        states.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("states[0].q") && err.contains("expected length 9"),
        "{err}"
    );

    std::fs::write(
        &states,
        r#"{"states": [{"q": [0, 0, 0, 0, 0, 0, 0, 0, "x"]}]}"#,
    )
    .unwrap();
    let out = moma(&[
        "manipulability",
        &panda(),
        "--states",
        states.to_str().unwrap(),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("states[0].q[8]"));

    let out = moma(&[
        "manipulability",
        &panda(),
        "--states",
        states.to_str().unwrap(),
        "--measure",
        "bogus",
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("--measure"));

    let out = moma(&[
        "manipulability",
        &panda(),
        "--states",
        "/nonexistent/states.json",
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("states.json"));
}

#[test]
fn ik_converges_reports_and_fails_clearly() {
    // Reachable pose (FK of a configuration computed by the library in the unit tests; here
    // a pose inside the workspace, gripper pointing down).
    let out = moma(&[
        "ik",
        &panda(),
        "--frame",
        "panda_hand_tcp",
        "--target",
        "0.5,0.1,0.4,1,0,0,0",
        "--restarts",
        "10",
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = json(&out);
    assert_eq!(v["converged"], true);
    assert!(v["residual_norm"].as_f64().unwrap() <= 1e-6);
    assert_eq!(v["q"].as_array().unwrap().len(), 9);

    // Unreachable: a not-converged result with diagnostics and exit status 2.
    let out = moma(&[
        "ik",
        &panda(),
        "--frame",
        "panda_hand_tcp",
        "--target",
        "3,0,0.4",
        "--json",
    ]);
    assert_eq!(out.status.code(), Some(3));
    let v = json(&out);
    assert_eq!(v["converged"], false);
    assert_eq!(v["task_met"], false);
    let r = v["residual_norm"].as_f64().unwrap();
    assert!(r.is_finite() && r > 1.5, "{r}");
    // A position task reports the rows it solved: a position error equal to the residual
    // norm, and no orientation error.
    assert_eq!(v["residual"].as_array().unwrap().len(), 3);
    assert_eq!(v["position_error"].as_f64().unwrap(), r);
    assert!(v["orientation_error"].is_null(), "{v}");
    assert!(String::from_utf8_lossy(&out.stderr).contains("did not converge"));

    // Whole body: the base drives there.
    let out = moma(&[
        "ik",
        &panda(),
        "--frame",
        "panda_hand_tcp",
        "--target",
        "3,0,0.4",
        "--whole-body",
        "--base",
        BASE,
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = json(&out);
    assert_eq!(v["converged"], true);
    assert_eq!(v["q"].as_array().unwrap().len(), 12);

    // Bad input: wrong target length, unknown frame, wrong q0 length, zero quaternion.
    for (args, needle) in [
        (vec!["--target", "1,2,3,4"], "--target"),
        (vec!["--target", "0.5,0,0.4", "--frame", "nope"], "nope"),
        (vec!["--target", "0.5,0,0.4", "--q0", "0,0"], "--q0"),
        (vec!["--target", "0.5,0,0.4,0,0,0,0"], "quaternion"),
        (vec!["--target", "0.5,0,0.4", "--whole-body"], "--base"),
        (vec!["--target", "0.5,nan,0.4"], "--target"),
    ] {
        let mut a = vec!["ik", panda().leak() as &str];
        a.extend(args);
        let out = moma(&a);
        assert_eq!(out.status.code(), Some(1), "{a:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(err.contains(needle), "{a:?}: {err}");
    }
}

#[test]
fn reach_map_writes_svg_and_json() {
    let svg = tmp("map.svg");
    let js = tmp("map.json");
    let out = moma(&[
        "reach-map",
        &panda(),
        "--frame",
        "panda_hand_tcp",
        "--target",
        "1.0,0.5,0.5",
        "--area",
        "0,-0.5,2,1.5",
        "--step",
        "0.25",
        "--headings",
        "4",
        "--svg",
        svg.to_str().unwrap(),
        "-o",
        js.to_str().unwrap(),
        "--json",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = json(&out);
    assert_eq!(v["samples"], 9 * 9 * 4);
    let reachable = v["reachable"].as_u64().unwrap();
    assert!(reachable > 10 && reachable < 9 * 9 * 4);
    let best = &v["best"];
    assert_eq!(best["reachable"], true);
    // The best placement is within arm's reach of the target.
    let b = best["base"].as_array().unwrap();
    let d = (b[0].as_f64().unwrap() - 1.0).hypot(b[1].as_f64().unwrap() - 0.5);
    assert!(d < 1.2, "{d}");
    assert_eq!(v["cells"].as_array().unwrap().len(), 9);
    let text = std::fs::read_to_string(&svg).unwrap();
    assert!(
        text.starts_with("<svg") && text.contains("best") && text.trim_end().ends_with("</svg>")
    );
    let file: Value = serde_json::from_str(&std::fs::read_to_string(&js).unwrap()).unwrap();
    assert_eq!(file["best"], v["best"]);

    // Zero-size area: error, no output file.
    let svg2 = tmp("never.svg");
    let out = moma(&[
        "reach-map",
        &panda(),
        "--target",
        "1,0.5,0.5",
        "--area",
        "0,0,0,1",
        "--step",
        "0.1",
        "--svg",
        svg2.to_str().unwrap(),
    ]);
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("area"));
    assert!(!svg2.exists());
    for (area, step) in [("0,0,1", "0.1"), ("0,0,1,1", "0"), ("0,0,1,1", "-1")] {
        let out = moma(&[
            "reach-map",
            &panda(),
            "--target",
            "1,0.5,0.5",
            "--area",
            area,
            "--step",
            step,
        ]);
        assert_eq!(out.status.code(), Some(1), "{area} {step}");
    }
}

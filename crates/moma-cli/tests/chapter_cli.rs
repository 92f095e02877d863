//! `moma eval` end to end: every chapter reference file is reproduced within its
//! tolerance_hint, and bad input fails with a clear message and no output file.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::Command;

const FILES: [&str; 5] = [
    "m1_unicycle",
    "m2_platform_planar_arm",
    "m3_diffdrive_kinematics",
    "m4_cart_two_link",
    "m5_mobile_manipulator_3d",
];

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../moma/tests/data/chapter/{name}.json"))
}

fn tmpdir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("moma-chapter-cli-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn moma(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_moma"))
        .args(args)
        .output()
        .unwrap()
}

fn compare(path: &str, got: &Value, want: &Value, tol: f64, relative: bool) {
    match (got, want) {
        (Value::Number(a), Value::Number(b)) => {
            let (a, b) = (a.as_f64().unwrap(), b.as_f64().unwrap());
            let scale = if relative { b.abs().max(1.0) } else { 1.0 };
            assert!((a - b).abs() <= tol * scale, "{path}: got {a}, want {b}");
        }
        (Value::Array(a), Value::Array(b)) => {
            assert_eq!(a.len(), b.len(), "{path}");
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                compare(&format!("{path}[{i}]"), x, y, tol, relative);
            }
        }
        (Value::Object(a), Value::Object(b)) => {
            for (k, y) in b {
                compare(
                    &format!("{path}.{k}"),
                    a.get(k).unwrap_or_else(|| panic!("{path}.{k} missing")),
                    y,
                    tol,
                    relative,
                );
            }
        }
        _ => assert_eq!(got, want, "{path}"),
    }
}

#[test]
fn eval_reproduces_every_reference_file() {
    let dir = tmpdir("roundtrip");
    for name in FILES {
        let want: Value =
            serde_json::from_str(&std::fs::read_to_string(data(name)).unwrap()).unwrap();
        // strip the expected values so nothing can be echoed back
        let mut input = want.clone();
        for c in input["cases"].as_array_mut().unwrap() {
            let c = c.as_object_mut().unwrap();
            c.remove("outputs");
            let t = c["trajectory"]["t"].clone();
            c.insert("trajectory".into(), serde_json::json!({ "t": t }));
            if let Some(ctl) = c.get_mut("control").and_then(|v| v.as_object_mut()) {
                for k in [
                    "x_d0", "xdot_d0", "xddot_d0", "tau_x0", "u0", "e0", "edot0", "W0",
                ] {
                    ctl.remove(k);
                }
                let t = ctl["closed_loop"]["t"].clone();
                ctl.insert("closed_loop".into(), serde_json::json!({ "t": t }));
            }
        }
        let inp = dir.join(format!("{name}.in.json"));
        let out = dir.join(format!("{name}.out.json"));
        std::fs::write(&inp, serde_json::to_string(&input).unwrap()).unwrap();
        let r = moma(&[
            "eval",
            inp.to_str().unwrap(),
            "--output",
            out.to_str().unwrap(),
        ]);
        assert!(
            r.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&r.stderr)
        );
        let got: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        let rel = want["tolerance_hint"]["algebraic_rel"].as_f64().unwrap();
        let abs = want["tolerance_hint"]["trajectory_abs"].as_f64().unwrap();
        for (k, v) in want.as_object().unwrap() {
            if k != "cases" {
                assert_eq!(&got[k], v, "{name}: top-level {k}");
            }
        }
        for (g, w) in got["cases"]
            .as_array()
            .unwrap()
            .iter()
            .zip(want["cases"].as_array().unwrap())
        {
            compare(
                &format!("{name} {}", w["id"]),
                &g["outputs"],
                &w["outputs"],
                rel,
                true,
            );
            compare(
                &format!("{name} {}", w["id"]),
                &g["trajectory"],
                &w["trajectory"],
                abs,
                false,
            );
            assert_eq!(g["params"], w["params"]);
            if let Some(ctl) = w.get("control") {
                let mut at0 = ctl.clone();
                let cl = at0.as_object_mut().unwrap().remove("closed_loop").unwrap();
                compare(
                    &format!("{name} {} control", w["id"]),
                    &g["control"],
                    &at0,
                    rel,
                    true,
                );
                compare(
                    &format!("{name} {} closed loop", w["id"]),
                    &g["control"]["closed_loop"],
                    &cl,
                    abs,
                    false,
                );
                // the set-up is echoed exactly
                assert_eq!(g["control"]["Kp"], ctl["Kp"]);
            }
        }
    }
    // stdout mode
    let r = moma(&["eval", data("m1_unicycle").to_str().unwrap()]);
    assert!(r.status.success());
    let v: Value = serde_json::from_slice(&r.stdout).unwrap();
    assert_eq!(v["model"], "m1_unicycle");
}

fn expect_failure(tag: &str, doc: &str, needles: &[&str]) {
    let dir = tmpdir(tag);
    let inp = dir.join("in.json");
    let out = dir.join("out.json");
    std::fs::write(&inp, doc).unwrap();
    let r = moma(&["eval", inp.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(!r.status.success(), "{tag}: should fail");
    let err = String::from_utf8_lossy(&r.stderr);
    for n in needles {
        assert!(err.contains(n), "{tag}: message {err:?} lacks {n:?}");
    }
    assert!(!out.exists(), "{tag}: no partial output");
}

fn reference_with(name: &str, edit: impl FnOnce(&mut Value)) -> String {
    let mut v: Value = serde_json::from_str(&std::fs::read_to_string(data(name)).unwrap()).unwrap();
    edit(&mut v);
    serde_json::to_string(&v).unwrap()
}

#[test]
fn eval_errors_are_clear_and_leave_no_output() {
    expect_failure(
        "unknown",
        r#"{"model": "m7", "cases": []}"#,
        &[
            "unknown model 'm7'",
            "m1_unicycle",
            "m5_mobile_manipulator_3d",
        ],
    );
    expect_failure(
        "malformed",
        r#"{"model": "m1_unicycle", "cases": ["#,
        &["malformed JSON"],
    );
    expect_failure("nomodel", r#"{"cases": []}"#, &["model"]);
    expect_failure(
        "missing-param",
        &reference_with("m5_mobile_manipulator_3d", |v| {
            v["cases"][3]["params"]
                .as_object_mut()
                .unwrap()
                .remove("I_c");
        }),
        &["case 3", "I_c"],
    );
    // No silently ignored input: a parameter the model does not have is named, with the
    // model's parameters (m1 has no gravity; a typo of a real name).
    expect_failure(
        "unknown-param",
        &reference_with("m1_unicycle", |v| {
            v["cases"][1]["params"]["g"] = serde_json::json!(9.81)
        }),
        &[
            "case 1",
            "params.g",
            "unknown parameter 'g' of model m1_unicycle",
            "m, I, d, r_w, b",
        ],
    );
    expect_failure(
        "misspelt-param",
        &reference_with("m4_cart_two_link", |v| {
            let p = v["cases"][0]["params"].as_object_mut().unwrap();
            let l1 = p.remove("L1").unwrap();
            p.insert("l1".into(), l1);
        }),
        &["case 0", "params.l1", "m4_cart_two_link", "L1"],
    );
    expect_failure(
        "wrong-length",
        &reference_with("m2_platform_planar_arm", |v| {
            v["cases"][1]["state"]["q"] = serde_json::json!([1.0, 2.0])
        }),
        &["case 1", "state.q", "expected length 5"],
    );
    expect_failure(
        "non-number",
        &reference_with("m4_cart_two_link", |v| {
            v["cases"][0]["inputs"]["u"][2] = serde_json::json!("x")
        }),
        &["case 0", "inputs.u[2]"],
    );
    expect_failure(
        "negative-mass",
        &reference_with("m1_unicycle", |v| {
            v["cases"][2]["params"]["m"] = serde_json::json!(-3.0)
        }),
        &["case 2", "params.m", "positive"],
    );
    expect_failure(
        "overflow",
        r#"{"model": "m1_unicycle", "cases": [{"id": 0, "params": {"m": 1e999}}]}"#,
        &["malformed JSON"],
    );
    expect_failure(
        "unbalanced",
        &reference_with("m4_cart_two_link", |v| {
            v["cases"][0]["balanced"] = serde_json::json!(true)
        }),
        &["case 0", "balanced"],
    );
    expect_failure(
        "singular",
        &reference_with("m5_mobile_manipulator_3d", |v| {
            let th1 = v["cases"][0]["state"]["q"][4].clone();
            v["cases"][0]["state"]["q"][5] = th1;
        }),
        &["case 0", "singular"],
    );
}

#[test]
fn eval_rejects_a_bad_tolerance_and_a_missing_file() {
    let r = moma(&["eval", data("m1_unicycle").to_str().unwrap(), "--tol=0"]);
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("--tol"));
    let r = moma(&["eval", "/nonexistent/cases.json"]);
    assert!(!r.status.success());
    assert!(String::from_utf8_lossy(&r.stderr).contains("cannot read case file"));
}

#[test]
fn eval_unicycle_control_public_cases() {
    let input = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../moma/tests/data/control/unicycle_control.json");
    let want: Value = serde_json::from_str(&std::fs::read_to_string(&input).unwrap()).unwrap();
    let dir = tmpdir("unicycle");
    // strip the expected values so nothing can be echoed back
    let mut stripped = want.clone();
    for c in stripped["cases"].as_array_mut().unwrap() {
        c["trajectory"]
            .as_object_mut()
            .unwrap()
            .retain(|k, _| k == "t");
    }
    let input = dir.join("in.json");
    std::fs::write(&input, stripped.to_string()).unwrap();
    let out = dir.join("out.json");
    let o = moma(&["eval", input.to_str().unwrap(), "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    for (g, w) in got["cases"]
        .as_array()
        .unwrap()
        .iter()
        .zip(want["cases"].as_array().unwrap())
    {
        compare(
            "trajectory",
            &g["trajectory"],
            &w["trajectory"],
            1e-7,
            false,
        );
    }
    // an invalid Astolfi gain is an error naming the condition, and no output is written
    let mut bad = want.clone();
    bad["cases"][2]["gains"]["k_alpha"] = serde_json::json!(1.0);
    let bad_path = dir.join("bad.json");
    std::fs::write(&bad_path, bad.to_string()).unwrap();
    let out2 = dir.join("out2.json");
    let o = moma(&[
        "eval",
        bad_path.to_str().unwrap(),
        "-o",
        out2.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("k_alpha > k_rho"));
    assert!(!out2.exists());
}

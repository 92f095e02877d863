//! Every output and trajectory point of every case of the five chapter reference files
//! (m1–m5), to each file's `tolerance_hint`.

use moma::closed_form::cases::{DEFAULT_TOLERANCE, evaluate_document};
use serde_json::Value;

fn load(name: &str) -> Value {
    let path = format!(
        "{}/tests/data/chapter/{name}.json",
        env!("CARGO_MANIFEST_DIR")
    );
    serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap()
}

/// Compares `got` with `want` recursively; numbers must satisfy
/// `|got − want| ≤ tol·max(1, |want|)` (relative) or `≤ tol` (absolute).
fn compare(path: &str, got: &Value, want: &Value, tol: f64, relative: bool, worst: &mut f64) {
    match (got, want) {
        (Value::Number(a), Value::Number(b)) => {
            let (a, b) = (a.as_f64().unwrap(), b.as_f64().unwrap());
            let scale = if relative { b.abs().max(1.0) } else { 1.0 };
            let err = (a - b).abs() / scale;
            *worst = worst.max(err);
            assert!(
                err <= tol,
                "{path}: got {a}, want {b} (error {err:e} > {tol:e})"
            );
        }
        (Value::Array(a), Value::Array(b)) => {
            assert_eq!(a.len(), b.len(), "{path}: length");
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                compare(&format!("{path}[{i}]"), x, y, tol, relative, worst);
            }
        }
        (Value::Object(a), Value::Object(b)) => {
            for (k, y) in b {
                let x = a
                    .get(k)
                    .unwrap_or_else(|| panic!("{path}.{k}: missing in moma's output"));
                compare(&format!("{path}.{k}"), x, y, tol, relative, worst);
            }
        }
        _ => assert_eq!(got, want, "{path}"),
    }
}

fn check_file(name: &str) {
    let doc = load(name);
    let rel = doc["tolerance_hint"]["algebraic_rel"].as_f64().unwrap();
    let abs = doc["tolerance_hint"]["trajectory_abs"].as_f64().unwrap();
    // Start from a copy with outputs and trajectory states removed, so nothing is echoed.
    let mut input = doc.clone();
    for case in input["cases"].as_array_mut().unwrap() {
        let c = case.as_object_mut().unwrap();
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
    let out = evaluate_document(&input, DEFAULT_TOLERANCE).unwrap();
    let (mut worst_alg, mut worst_traj) = (0.0f64, 0.0f64);
    for (got, want) in out["cases"]
        .as_array()
        .unwrap()
        .iter()
        .zip(doc["cases"].as_array().unwrap())
    {
        let id = &want["id"];
        compare(
            &format!("{name} case {id} outputs"),
            &got["outputs"],
            &want["outputs"],
            rel,
            true,
            &mut worst_alg,
        );
        compare(
            &format!("{name} case {id} trajectory"),
            &got["trajectory"],
            &want["trajectory"],
            abs,
            false,
            &mut worst_traj,
        );
    }
    eprintln!(
        "{name}: worst algebraic {worst_alg:e} (tol {rel:e}), worst trajectory {worst_traj:e} (tol {abs:e})"
    );
    // every top-level field other than `cases` is preserved
    for (k, v) in doc.as_object().unwrap() {
        if k != "cases" {
            assert_eq!(&out[k], v, "top-level field {k}");
        }
    }
}

#[test]
fn m1_unicycle_reference() {
    check_file("m1_unicycle");
}

#[test]
fn m2_platform_planar_arm_reference() {
    check_file("m2_platform_planar_arm");
}

#[test]
fn m3_diffdrive_kinematics_reference() {
    check_file("m3_diffdrive_kinematics");
}

#[test]
fn m4_cart_two_link_reference() {
    check_file("m4_cart_two_link");
}

#[test]
fn m5_mobile_manipulator_3d_reference() {
    check_file("m5_mobile_manipulator_3d");
}

/// A case with d = 0 is evaluated with v = [v_F, φ̇] (the chapter's v_T = d φ̇ is singular).
#[test]
fn zero_offset_case_uses_the_yaw_rate() {
    let mut doc = load("m1_unicycle");
    let case = &mut doc["cases"].as_array_mut().unwrap()[0];
    case["params"]["d"] = serde_json::json!(0.0);
    case["state"]["v"] = serde_json::json!([0.5, 0.8]);
    case["trajectory"] = serde_json::json!({ "t": [0.0, 1.0] });
    doc["cases"] = serde_json::json!([case.clone()]);
    let out = evaluate_document(&doc, DEFAULT_TOLERANCE).unwrap();
    let o = &out["cases"][0]["outputs"];
    // φ̇ = v[1]; C = [−sin φ, cos φ, 0]; C q̇ = 0
    assert!((o["qdot"][2].as_f64().unwrap() - 0.8).abs() < 1e-15);
    assert_eq!(o["C"][0][2].as_f64().unwrap(), 0.0);
    let q0 = &out["cases"][0]["trajectory"]["q"][0];
    assert_eq!(q0, &doc["cases"][0]["state"]["q"]);
}

/// Errors name the case id as written (strings without quotes).
#[test]
fn string_ids_are_named_in_errors() {
    let mut doc = load("m2_platform_planar_arm");
    doc["cases"][1]["id"] = serde_json::json!("left-turn");
    doc["cases"][1]["params"]["b"] = serde_json::json!(-0.2);
    let e = evaluate_document(&doc, DEFAULT_TOLERANCE)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("case left-turn") && e.contains("params.b"),
        "{e}"
    );
}

/// A case horizon past `MAX_CASE_TIME` is refused up front, naming the time (a fuzzed
/// m2 case with one time set to 1e9 s kept the integrator running without end).
#[test]
fn case_horizon_is_bounded() {
    let mut doc = load("m2_platform_planar_arm");
    let case = doc["cases"].as_array().unwrap()[0].clone();
    let mut long = case.clone();
    long["trajectory"] = serde_json::json!({ "t": [0.0, 0.5, 1e9] });
    doc["cases"] = serde_json::json!([long]);
    let e = evaluate_document(&doc, DEFAULT_TOLERANCE)
        .unwrap_err()
        .to_string();
    assert!(e.contains("trajectory.t[2]") && e.contains("1000"), "{e}");
    let mut ok = case;
    ok["trajectory"] = serde_json::json!({ "t": [0.0, 0.5, 1.0] });
    doc["cases"] = serde_json::json!([ok]);
    assert!(evaluate_document(&doc, DEFAULT_TOLERANCE).is_ok());
}

/// The same bound on an m6 run's `trajectories.NAME.t` and on `joint_loop.period` (the
/// fuzzer's second timeout: an m6 run with one time set to 3.3e27 s).
#[test]
fn m6_run_horizon_is_bounded() {
    let doc = load("m6_space_manipulator");
    let case = doc["cases"].as_array().unwrap()[0].clone();
    let run = case["trajectories"]
        .as_object()
        .unwrap()
        .keys()
        .next()
        .unwrap()
        .clone();
    let mut long = case.clone();
    long["trajectories"][&run]["t"] = serde_json::json!([0.5, 3.3e27]);
    let mut d = doc.clone();
    d["cases"] = serde_json::json!([long]);
    let e = evaluate_document(&d, 1e-6).unwrap_err().to_string();
    assert!(
        e.contains(&format!("trajectories.{run}.t[1]")) && e.contains("1000"),
        "{e}"
    );
    let mut slow_loop = case;
    slow_loop["joint_loop"]["period"] = serde_json::json!(1e12);
    d["cases"] = serde_json::json!([slow_loop]);
    let e = evaluate_document(&d, 1e-6).unwrap_err().to_string();
    assert!(e.contains("joint_loop.period") && e.contains("1000"), "{e}");
}

/// A case whose parameters make the dynamics fast (the fuzzer's m5 case with one link
/// mass of 2.1e11 kg beside masses of a few kg needed 130,000 DOP853 steps for one second,
/// about 20 s) ends at the closed-form models' step budget with an error naming the case.
#[test]
fn stiff_case_stops_at_the_step_budget() {
    let mut doc = load("m5_mobile_manipulator_3d");
    let mut case = doc["cases"].as_array().unwrap()[0].clone();
    case.as_object_mut().unwrap().remove("outputs");
    case["params"]["M1"] = serde_json::json!(214798761983.0_f64);
    doc["cases"] = serde_json::json!([case]);
    let e = evaluate_document(&doc, 1e-9).unwrap_err().to_string();
    let budget = format!(
        "maximum number of steps ({})",
        moma::closed_form::CASE_MAX_STEPS
    );
    assert!(e.contains(&budget) && e.contains("case 0"), "{e}");
}

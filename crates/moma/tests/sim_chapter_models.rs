//! The reduced-coordinate simulator on the chapter's closed-form models: trajectories
//! against the reference vectors, energy balance and constraint residual monitors.

use moma::sim::chapter_models::chapter_system;
use moma::sim::monitor::MonitorLimits;
use moma::sim::settings::{ChannelProfile, InputProfile, IntegratorSettings};
use moma::sim::wheeled::{SimulationOptions, simulate};
use serde_json::Value;

fn load(name: &str) -> Value {
    let path = format!("{}/tests/data/mobile/{name}", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn constant(u: &[f64]) -> InputProfile {
    InputProfile {
        channels: u
            .iter()
            .map(|&value| ChannelProfile::Constant { value })
            .collect(),
    }
}

fn adaptive(tol: f64) -> IntegratorSettings {
    IntegratorSettings::adaptive(tol, tol)
}

fn check_trajectories(file: &str, model: &str, tol_abs: f64) {
    let data = load(file);
    for case in data["cases"].as_array().unwrap() {
        let mut sys = chapter_system(model, &case["params"]).unwrap();
        let q0 = floats(&case["state"]["q"]);
        let v0 = floats(&case["state"]["v"]);
        let u = floats(&case["inputs"]["u"]);
        let opts = SimulationOptions {
            duration: 1.0,
            integrator: adaptive(1e-12),
            record_interval: 0.5,
            limits: MonitorLimits::default(),
        };
        let res = simulate(sys.as_mut(), &constant(&u), &q0, &v0, &opts, &mut |_| {}).unwrap();
        let rec = &res.recorder;
        assert_eq!(rec.times, vec![0.0, 0.5, 1.0]);
        let tq = case["trajectory"]["q"].as_array().unwrap();
        let tv = case["trajectory"]["v"].as_array().unwrap();
        for k in 0..2 {
            for (a, b) in rec.q_row(k + 1).iter().zip(floats(&tq[k])) {
                assert!(
                    (a - b).abs() < tol_abs,
                    "{model} q at t={}: {a} vs {b}",
                    rec.times[k + 1]
                );
            }
            for (a, b) in rec.v_row(k + 1).iter().zip(floats(&tv[k])) {
                assert!(
                    (a - b).abs() < tol_abs,
                    "{model} v at t={}: {a} vs {b}",
                    rec.times[k + 1]
                );
            }
        }
        // The recorded multiplier at t = 0 is the reference λ.
        let lam0 = case["outputs"]["lambda"]
            .as_f64()
            .unwrap_or_else(|| floats(&case["outputs"]["lambda"])[0]);
        assert!(
            (rec.lambda_row(0)[0] - lam0).abs() < 1e-9 * (1.0 + lam0.abs()),
            "{model} λ"
        );
        // Energy balance with inputs: T + V − E0 − W stays at integration accuracy.
        assert!(
            res.monitor.relative_energy_error() < 1e-8,
            "{}",
            res.monitor.relative_energy_error()
        );
        assert!(
            res.monitor.max_residual < 1e-12,
            "{}",
            res.monitor.max_residual
        );
    }
}

#[test]
fn m1_trajectories_match_the_reference() {
    check_trajectories("m1_unicycle.json", "m1", 1e-7);
}

#[test]
fn m2_trajectories_match_the_reference() {
    check_trajectories("m2_platform_planar_arm.json", "m2", 1e-7);
}

#[test]
fn m5_trajectories_match_the_reference() {
    check_trajectories("m5_mobile_manipulator_3d.json", "m5", 1e-6);
}

#[test]
fn unforced_energy_drift_below_1e9_over_10_s_and_residual_below_1e12() {
    // m2 has G = 0; m5 with gravity: gravity is conservative, the input does no work.
    for (file, model) in [
        ("m2_platform_planar_arm.json", "m2"),
        ("m5_mobile_manipulator_3d.json", "m5"),
    ] {
        let data = load(file);
        let case = &data["cases"][1];
        let mut sys = chapter_system(model, &case["params"]).unwrap();
        let q0 = floats(&case["state"]["q"]);
        let v0 = floats(&case["state"]["v"]);
        let opts = SimulationOptions {
            duration: 10.0,
            integrator: adaptive(1e-12),
            record_interval: 0.1,
            limits: MonitorLimits::default(),
        };
        let zero = InputProfile::zero(sys.nu());
        let res = simulate(sys.as_mut(), &zero, &q0, &v0, &opts, &mut |_| {}).unwrap();
        let drift = res.monitor.relative_energy_error();
        assert!(drift < 1e-9, "{model}: relative energy drift {drift:e}");
        let rel_t = res.monitor.max_energy_error / res.recorder.kinetic[0];
        assert!(rel_t < 1e-9, "{model}: drift relative to T0 {rel_t:e}");
        assert!(
            res.monitor.max_residual < 1e-12,
            "{model}: residual {:e}",
            res.monitor.max_residual
        );
        assert_eq!(res.recorder.work.iter().copied().fold(0.0, f64::max), 0.0);
        assert_eq!(res.recorder.len(), 101);
    }
}

#[test]
fn rk4_converges_at_fourth_order() {
    let data = load("m2_platform_planar_arm.json");
    let case = &data["cases"][0];
    let q0 = floats(&case["state"]["q"]);
    let v0 = floats(&case["state"]["v"]);
    let u = constant(&floats(&case["inputs"]["u"]));
    let want = floats(&case["trajectory"]["q"][1]);
    let mut errs = Vec::new();
    for dt in [0.02, 0.01] {
        let mut sys = chapter_system("m2", &case["params"]).unwrap();
        let opts = SimulationOptions {
            duration: 1.0,
            integrator: IntegratorSettings::rk4(dt),
            record_interval: 0.5,
            limits: MonitorLimits::default(),
        };
        let res = simulate(sys.as_mut(), &u, &q0, &v0, &opts, &mut |_| {}).unwrap();
        let got = res.recorder.q_row(2);
        errs.push(
            got.iter()
                .zip(&want)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max),
        );
        assert!(res.monitor.max_residual < 1e-12);
    }
    let ratio = errs[0] / errs[1];
    assert!(
        ratio > 12.0 && ratio < 20.0,
        "RK4 error ratio {ratio} ({errs:?})"
    );
}

#[test]
fn bad_inputs_and_blow_up_are_reported() {
    let data = load("m1_unicycle.json");
    let case = &data["cases"][0];
    let mut sys = chapter_system("m1", &case["params"]).unwrap();
    let q0 = floats(&case["state"]["q"]);
    let v0 = floats(&case["state"]["v"]);
    let opts = SimulationOptions {
        duration: 1.0,
        integrator: IntegratorSettings::rk4(0.01),
        record_interval: 0.1,
        limits: MonitorLimits {
            blowup: 10.0,
            ..Default::default()
        },
    };
    // Huge torques drive the state past the blow-up bound: a Numerical error with the time.
    let err = simulate(
        sys.as_mut(),
        &constant(&[1e6, 1e6]),
        &q0,
        &v0,
        &opts,
        &mut |_| {},
    )
    .unwrap_err();
    assert!(matches!(err, moma::Error::Numerical { .. }), "{err}");
    // Wrong input count and NaN initial state.
    assert!(
        simulate(
            sys.as_mut(),
            &constant(&[0.0]),
            &q0,
            &v0,
            &opts,
            &mut |_| {}
        )
        .is_err()
    );
    let nan_q = vec![f64::NAN, 0.0, 0.0];
    let err = simulate(
        sys.as_mut(),
        &constant(&[0.0, 0.0]),
        &nan_q,
        &v0,
        &opts,
        &mut |_| {},
    )
    .unwrap_err();
    assert!(err.to_string().contains("initial q"), "{err}");
    // Unknown model and missing parameter.
    assert!(chapter_system("m9", &case["params"]).is_err());
    let mut p = case["params"].clone();
    p.as_object_mut().unwrap().remove("d");
    let err = chapter_system("m1", &p).err().unwrap();
    assert!(err.to_string().contains('d'), "{err}");
}

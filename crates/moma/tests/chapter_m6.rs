//! Chapter model m6 (planar free-floating space manipulator): every output, trajectory
//! sample and joint-loop rotation of the public reference cases, to the file's tolerance;
//! SpaceDyn's generalized Jacobian and the dynamic-singularity and joint-loop values of the
//! planar two-link robot in the same closed form; conservation of P, L_O, L_c.

use moma::closed_form::cases::{DEFAULT_TOLERANCE, evaluate_document};
use moma::closed_form::m6_space_manipulator::{Q, SpaceManipulator, SpaceManipulatorParams};
use moma::sim::{AdaptiveOptions, Dop853, OdeSystem};
use nalgebra::Vector2;
use serde_json::Value;

fn load(path: &str) -> Value {
    let p = format!("{}/tests/data/{path}", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

fn compare(path: &str, got: &Value, want: &Value, tol: f64, relative: bool) {
    match (got, want) {
        (Value::Number(a), Value::Number(b)) => {
            let (a, b) = (a.as_f64().unwrap(), b.as_f64().unwrap());
            let scale = if relative { b.abs().max(1.0) } else { 1.0 };
            assert!(
                (a - b).abs() / scale <= tol,
                "{path}: got {a}, want {b} (tol {tol:e})"
            );
        }
        (Value::Array(a), Value::Array(b)) => {
            assert_eq!(a.len(), b.len(), "{path}: length");
            for (i, (x, y)) in a.iter().zip(b).enumerate() {
                compare(&format!("{path}[{i}]"), x, y, tol, relative);
            }
        }
        (Value::Object(a), Value::Object(b)) => {
            for (k, y) in b {
                let x = a.get(k).unwrap_or_else(|| panic!("{path}.{k}: missing"));
                compare(&format!("{path}.{k}"), x, y, tol, relative);
            }
        }
        _ => assert_eq!(got, want, "{path}"),
    }
}

const RESULTS: [&str; 6] = [
    "q",
    "qdot",
    "P",
    "L_O",
    "psi_from_omega_exact",
    "psi_from_omega_chapter",
];

#[test]
fn public_cases_reproduced() {
    let doc = load("chapter/m6_space_manipulator.json");
    let rel = doc["tolerance_hint"]["algebraic_rel"].as_f64().unwrap();
    let abs = doc["tolerance_hint"]["trajectory_abs"].as_f64().unwrap();
    let mut input = doc.clone();
    for case in input["cases"].as_array_mut().unwrap() {
        let c = case.as_object_mut().unwrap();
        c.remove("outputs");
        for run in c["trajectories"].as_object_mut().unwrap().values_mut() {
            for k in RESULTS {
                run.as_object_mut().unwrap().remove(k);
            }
        }
        c["joint_loop"].as_object_mut().unwrap().remove("delta_psi");
    }
    let got = evaluate_document(&input, DEFAULT_TOLERANCE).unwrap();
    for (i, (g, w)) in got["cases"]
        .as_array()
        .unwrap()
        .iter()
        .zip(doc["cases"].as_array().unwrap())
        .enumerate()
    {
        compare(
            &format!("case {i} outputs"),
            &g["outputs"],
            &w["outputs"],
            rel,
            true,
        );
        compare(
            &format!("case {i} trajectories"),
            &g["trajectories"],
            &w["trajectories"],
            abs,
            false,
        );
        compare(
            &format!("case {i} joint_loop"),
            &g["joint_loop"],
            &w["joint_loop"],
            abs,
            false,
        );
        // ψ from the exact base rate follows the simulated ψ; the chapter's does not
        for run in g["trajectories"].as_object().unwrap().values() {
            for (q, pe) in run["q"]
                .as_array()
                .unwrap()
                .iter()
                .zip(run["psi_from_omega_exact"].as_array().unwrap())
            {
                assert!((q[2].as_f64().unwrap() - pe.as_f64().unwrap()).abs() < 1e-9);
            }
        }
    }
}

fn spacedyn_robot() -> SpaceManipulator {
    SpaceManipulator::new(SpaceManipulatorParams {
        m0: 100.0,
        I0: 10.0,
        b0x: 0.5,
        b0y: 0.0,
        m1: 10.0,
        m2: 5.0,
        l1: 1.0,
        l2: 1.0,
        lc1: 0.5,
        lc2: 0.5,
        I1: 1.0,
        I2: 0.5,
    })
    .unwrap()
}

fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn closed_form_generalized_jacobian_is_spacedyns() {
    let sys = spacedyn_robot();
    let doc = load("space/spacedyn_gj_planar2link.json");
    for case in doc["cases"].as_array().unwrap() {
        let qj = nums(&case["q"]);
        let q = Q::from([0.0, 0.0, 0.0, qj[0], qj[1]]);
        let (_, _, _, _, js) = sys.generalized_jacobian(&q).unwrap();
        for (r, row) in case["GJ_rows_vx_vy_wz"]
            .as_array()
            .unwrap()
            .iter()
            .enumerate()
        {
            let row = nums(row);
            for k in 0..2 {
                assert!((js[(r, k)] - row[k]).abs() < 1e-12);
            }
        }
        let qd = nums(&case["qd"]);
        let w = sys.base_rate(&q, &Vector2::new(qd[0], qd[1]), 0.0);
        assert!((w - nums(&case["base_w0"])[2]).abs() < 1e-12);
    }
    // theory 3.5: at q = (0.3, 0.6), q̇ = (1, 0.5) the exact base rate, not the chapter's
    let q = Q::from([0.0, 0.0, 0.0, 0.3, 0.6]);
    let th = Vector2::new(1.0, 0.5);
    assert!((sys.base_rate(&q, &th, 0.0) + 0.556761).abs() < 1e-6);
    assert!((sys.base_rate(&q, &th, 0.0) - sys.base_rate_chapter(&th)).abs() > 0.3);
}

#[test]
fn closed_form_dynamic_singularities() {
    let sys = spacedyn_robot();
    let doc = load("space/free_floating_dynamic_singularity.json");
    for spot in doc["spot_values"].as_array().unwrap() {
        let qj = nums(&spot["q"]);
        let (dg, df) = sys
            .position_determinants(&Q::from([0.0, 0.0, 0.4, qj[0], qj[1]]))
            .unwrap();
        assert!((dg - spot["det_GJ_pos"].as_f64().unwrap()).abs() < 1e-12);
        assert!((df - spot["det_fixed_base_pos"].as_f64().unwrap()).abs() < 1e-12);
    }
}

struct Loop<'a>(&'a SpaceManipulator, f64, bool);

impl OdeSystem for Loop<'_> {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, _x: &[f64], dx: &mut [f64]) -> moma::Result<()> {
        // q1 = 0.3 + a sin 2πt, q2 = 0.6 + a (1 − cos 2πt), optionally reversed in time
        let w = 2.0 * std::f64::consts::PI;
        let (tt, sgn) = if self.2 { (1.0 - t, -1.0) } else { (t, 1.0) };
        let a = self.1;
        let q = Q::from([
            0.0,
            0.0,
            0.0,
            0.3 + a * (w * tt).sin(),
            0.6 + a * (1.0 - (w * tt).cos()),
        ]);
        let thd = Vector2::new(a * w * (w * tt).cos(), a * w * (w * tt).sin()) * sgn;
        dx[0] = self.0.base_rate(&q, &thd, 0.0);
        Ok(())
    }
}

#[test]
fn joint_loop_rotates_the_base() {
    let sys = spacedyn_robot();
    let doc = load("space/free_floating_loop.json");
    for r in doc["results"].as_array().unwrap() {
        let a = r["a"].as_f64().unwrap();
        for (rev, key) in [(false, "net_base_rotation"), (true, "reversed")] {
            let mut dp = Dop853::new(1, AdaptiveOptions::with_tolerance(1e-13)).unwrap();
            let d = dp
                .solve_at(&mut Loop(&sys, a, rev), 0.0, &[0.0], &[1.0])
                .unwrap()[0][0];
            let want = r[key].as_f64().unwrap();
            assert!((d - want).abs() < 1e-11, "a = {a} {key}: {d} vs {want}");
        }
    }
}

#[test]
fn momentum_is_conserved_with_and_without_torque() {
    let sys = spacedyn_robot();
    let q0 = Q::from([0.1, -0.2, 0.3, 0.3, 0.6]);
    let qd0 = Q::from([0.05, -0.02, 0.1, 1.0, 0.5]);
    let times: Vec<f64> = (1..=10).map(|k| k as f64 * 0.5).collect();
    for tau in [Vector2::zeros(), Vector2::new(1.0, -0.5)] {
        let (p0, lo0, lc0) = sys.momentum(&q0, &qd0);
        let samples = sys.simulate(&q0, &qd0, &tau, &times, 1e-12).unwrap();
        for s in &samples {
            let (p, lo, lc) = sys.momentum(&s.q, &s.qdot);
            assert!(
                (p - p0).norm() < 1e-10 && (lo - lo0).abs() < 1e-10 && (lc - lc0).abs() < 1e-10
            );
            assert!((s.psi_exact - s.q[2]).abs() < 1e-9);
        }
    }
}

//! The whole-body Jacobian composition `J̄ = J·N` against the chapter's model m3
//! (reference vectors): wheel-rate inputs, the platform-yaw term, det J, the exact base
//! integration, and the bias term `J̄̇ u`.

use moma::mobile::DiffDrive;
use moma::mobile::whole_body::{
    BaseInputs, bias_acceleration, inputs_to_velocity, integrate_base, whole_body_jacobian,
};
use nalgebra::{DMatrix, DVector};
use serde_json::Value;

fn load() -> Value {
    let path = format!(
        "{}/tests/data/manipulability/m3_diffdrive_kinematics.json",
        env!("CARGO_MANIFEST_DIR")
    );
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn mat(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = serde_json::from_value(v.clone()).unwrap();
    DMatrix::from_fn(rows.len(), rows[0].len(), |i, j| rows[i][j])
}

fn vecf(v: &Value) -> Vec<f64> {
    serde_json::from_value(v.clone()).unwrap()
}

struct M3 {
    drive: DiffDrive,
    l: f64,
    l1: f64,
    l2: f64,
}

impl M3 {
    fn new(p: &Value) -> Self {
        let g = |k: &str| p[k].as_f64().unwrap();
        Self {
            drive: DiffDrive::new(g("r_w"), g("b"), g("d")).unwrap(),
            l: g("L"),
            l1: g("L1"),
            l2: g("L2"),
        }
    }

    /// X = [x_B, y_B, x_E, y_E, z_E] from q = [x, y, φ, φ1, θ1, θ2] (m3 (a)).
    fn x(&self, q: &[f64]) -> DVector<f64> {
        let (phi, phi1, th1, th2) = (q[2], q[3], q[4], q[5]);
        let th12 = th1 - th2;
        let xb = q[0] + self.l * phi.cos();
        let yb = q[1] + self.l * phi.sin();
        let rho = self.l1 * th1.sin() + self.l2 * th12.sin();
        let eta = self.l1 * th1.cos() + self.l2 * th12.cos();
        let pt = phi + phi1;
        DVector::from_vec(vec![xb, yb, xb + rho * pt.cos(), yb + rho * pt.sin(), eta])
    }

    /// dX/dq by central differences (5 × 6): the "frame Jacobian" w.r.t. [ẋ, ẏ, φ̇, …].
    fn dxdq(&self, q: &[f64]) -> DMatrix<f64> {
        let h = 1e-6;
        let mut j = DMatrix::zeros(5, 6);
        for k in 0..6 {
            let mut a = q.to_vec();
            let mut b = q.to_vec();
            a[k] += h;
            b[k] -= h;
            let d = (self.x(&a) - self.x(&b)) / (2.0 * h);
            j.set_column(k, &d);
        }
        j
    }

    /// q(t) under constant inputs u (wheel rates + joint rates), exact.
    fn q_at(&self, q0: &[f64], u: &[f64], t: f64) -> Vec<f64> {
        let w = self.drive.wheel_to_platform();
        let v = w[(0, 0)] * u[0] + w[(0, 1)] * u[1];
        let om = w[(1, 0)] * u[0] + w[(1, 1)] * u[1];
        let b = integrate_base(&self.drive, [q0[0], q0[1], q0[2]], v * t, om * t);
        vec![
            b[0],
            b[1],
            b[2],
            q0[3] + u[2] * t,
            q0[4] + u[3] * t,
            q0[5] + u[4] * t,
        ]
    }
}

#[test]
fn whole_body_jacobian_matches_m3_with_yaw_term() {
    let d = load();
    for case in d["cases"].as_array().unwrap() {
        let m3 = M3::new(&case["params"]);
        let q = vecf(&case["state"]["q"]);
        let out = &case["outputs"];
        let jq = m3.dxdq(&q);
        let jbar = whole_body_jacobian(&m3.drive, BaseInputs::Wheels, q[2], &jq).unwrap();
        let jref = mat(&out["J"]);
        let err = (&jbar - &jref).abs().max();
        assert!(err < 1e-8, "case {}: |J - J_ref| = {err}", case["id"]);
        let det = jbar.determinant();
        let det_ref = out["det_J"].as_f64().unwrap();
        assert!((det - det_ref).abs() < 1e-7 * det_ref.abs().max(1e-3));
        // The chapter's printed (5.31) Jacobian lacks the yaw term: we must differ from it
        // exactly in the wheel columns of the x_E, y_E rows.
        let printed = mat(&out["J_chapter_5_31"]);
        let diff = &jbar - &printed;
        assert!(diff.view((2, 0), (2, 2)).abs().max() > 1e-6);
        assert!(diff.view((0, 2), (5, 3)).abs().max() < 1e-8);
        // N_C and q̇ = N u.
        let u = DVector::from_vec(vecf(&case["inputs"]["v"]));
        let qd = inputs_to_velocity(&m3.drive, BaseInputs::Wheels, q[2], &u);
        let qd_ref = vecf(&out["qdot"]);
        for k in 0..6 {
            assert!((qd[k] - qd_ref[k]).abs() < 1e-12);
        }
        let xd = &jbar * &u;
        let xd_ref = vecf(&out["Xdot"]);
        for k in 0..5 {
            assert!((xd[k] - xd_ref[k]).abs() < 1e-8);
        }
    }
}

#[test]
fn exact_base_integration_matches_m3_trajectory() {
    let d = load();
    for case in d["cases"].as_array().unwrap() {
        let m3 = M3::new(&case["params"]);
        let q0 = vecf(&case["state"]["q"]);
        let u = vecf(&case["inputs"]["v"]);
        let traj = &case["trajectory"];
        let ts = vecf(&traj["t"]);
        for (i, &t) in ts.iter().enumerate() {
            let q = m3.q_at(&q0, &u, t);
            let q_ref = vecf(&traj["q"][i]);
            for k in 0..6 {
                assert!(
                    (q[k] - q_ref[k]).abs() < 1e-8,
                    "case {} t={t} q[{k}]: {} vs {}",
                    case["id"],
                    q[k],
                    q_ref[k]
                );
            }
            let x = m3.x(&q);
            let x_ref = vecf(&traj["X"][i]);
            for k in 0..5 {
                assert!((x[k] - x_ref[k]).abs() < 1e-8);
            }
        }
    }
}

#[test]
fn bias_term_is_second_derivative_along_constant_inputs() {
    let d = load();
    for inputs in [BaseInputs::Wheels, BaseInputs::Platform] {
        for case in d["cases"].as_array().unwrap() {
            let m3 = M3::new(&case["params"]);
            let q = vecf(&case["state"]["q"]);
            let mut u = vecf(&case["inputs"]["v"]);
            if inputs == BaseInputs::Platform {
                // Reinterpret the first two as (v, ω) of a moderate size.
                u[0] *= 0.05;
                u[1] *= 0.1;
            }
            let uu = DVector::from_vec(u.clone());
            let qd = inputs_to_velocity(&m3.drive, inputs, q[2], &uu);
            // J̇ q̇ of the position map: second directional derivative along q̇.
            let h = 1e-4;
            let plus: Vec<f64> = (0..6).map(|k| q[k] + h * qd[k]).collect();
            let minus: Vec<f64> = (0..6).map(|k| q[k] - h * qd[k]).collect();
            let jdqd = (m3.x(&plus) - 2.0 * m3.x(&q) + m3.x(&minus)) / (h * h);
            let jq = m3.dxdq(&q);
            let bias = bias_acceleration(&m3.drive, inputs, q[2], &jq, &jdqd, &uu).unwrap();
            // Reference: Ẍ along the exact constant-input motion.
            let (v, om) = match inputs {
                BaseInputs::Wheels => {
                    let w = m3.drive.wheel_to_platform();
                    (
                        w[(0, 0)] * u[0] + w[(0, 1)] * u[1],
                        w[(1, 0)] * u[0] + w[(1, 1)] * u[1],
                    )
                }
                BaseInputs::Platform => (u[0], u[1]),
            };
            let q_t = |t: f64| {
                let b = integrate_base(&m3.drive, [q[0], q[1], q[2]], v * t, om * t);
                vec![
                    b[0],
                    b[1],
                    b[2],
                    q[3] + u[2] * t,
                    q[4] + u[3] * t,
                    q[5] + u[4] * t,
                ]
            };
            let xdd = (m3.x(&q_t(h)) - 2.0 * m3.x(&q) + m3.x(&q_t(-h))) / (h * h);
            let err = (&bias - &xdd).abs().max();
            assert!(err < 1e-5, "{inputs:?} case {}: {err}", case["id"]);
        }
    }
}

#[test]
fn bad_shapes_are_errors() {
    let drive = DiffDrive::new(0.1, 0.25, 0.0).unwrap();
    assert!(whole_body_jacobian(&drive, BaseInputs::Platform, 0.0, &DMatrix::zeros(6, 2)).is_err());
    let j = DMatrix::zeros(6, 5);
    let u = DVector::zeros(3);
    assert!(
        bias_acceleration(
            &drive,
            BaseInputs::Platform,
            0.0,
            &j,
            &DVector::zeros(6),
            &u
        )
        .is_err()
    );
    let u = DVector::from_vec(vec![f64::NAN, 0.0, 0.0, 0.0]);
    assert!(
        bias_acceleration(
            &drive,
            BaseInputs::Platform,
            0.0,
            &j,
            &DVector::zeros(6),
            &u
        )
        .is_err()
    );
}

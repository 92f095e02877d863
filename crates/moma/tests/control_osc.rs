//! Operational-space control: the Panda reference values, dynamic consistency, the
//! planar 2R worked numbers and the exact-model computed-torque error (theory.md 5.6–5.7),
//! and the reduced model of an arm on a non-holonomic platform.

use moma::control::osc::{OscData, ReducedOscData, osc_fixed_base, osc_from_terms, osc_reduced};
use moma::io::urdf::model_from_urdf_file;
use moma::kinematics::{ReferenceFrame, frame_acceleration_bias, frame_jacobian};
use moma::mobile::wheeled::{WheeledData, actuation_matrix, reduced_dynamics};
use moma::multibody::{Data, RootJoint};
use moma::sim::{AdaptiveOptions, Dop853, OdeSystem};
use nalgebra::{DMatrix, DVector, Matrix2, Matrix6xX, Vector2};
use rand::{Rng, SeedableRng};
use serde_json::Value;

fn data_dir() -> String {
    format!("{}/tests/data", env!("CARGO_MANIFEST_DIR"))
}

fn load(name: &str) -> Value {
    serde_json::from_str(
        &std::fs::read_to_string(format!("{}/control/{name}", data_dir())).unwrap(),
    )
    .unwrap()
}

fn vecf(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn mat(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = v.as_array().unwrap().iter().map(vecf).collect();
    DMatrix::from_fn(rows.len(), rows[0].len(), |i, j| rows[i][j])
}

fn close(a: &DMatrix<f64>, b: &DMatrix<f64>, tol: f64, what: &str) {
    assert_eq!(a.shape(), b.shape(), "{what}");
    for (x, y) in a.iter().zip(b.iter()) {
        assert!(
            (x - y).abs() <= tol * y.abs().max(1.0),
            "{what}: {x} vs {y}"
        );
    }
}

#[test]
fn panda_reference_and_dynamic_consistency() {
    let doc = load("osc_public.json");
    let model = model_from_urdf_file(
        format!("{}/pinocchio/urdf/panda.urdf", data_dir()),
        RootJoint::Fixed,
    )
    .unwrap();
    let frame = model.frame_id("panda_hand_tcp").unwrap();
    let mut data = Data::new(&model);
    let mut od = OscData::new(model.nv, &[0, 1, 2, 3, 4, 5]);
    let mut rng = rand::rngs::StdRng::seed_from_u64(11);
    for case in doc["cases"].as_array().unwrap() {
        let s = &case["state"];
        let q = DVector::from_vec(vecf(&s["q"]));
        let v = DVector::from_vec(vecf(&s["v"]));
        let a = DVector::from_vec(vecf(&s["task_acceleration"]));
        let t0 = DVector::from_vec(vecf(&s["null_torque"]));
        osc_fixed_base(&model, &mut data, &mut od, frame, &q, &v, &a, &t0).unwrap();
        let e = &case["expected"];
        close(&od.task_inertia, &mat(&e["task_inertia"]), 1e-9, "Λ");
        close(
            &od.dynamically_consistent_inverse,
            &mat(&e["dynamically_consistent_inverse"]),
            1e-9,
            "J̄",
        );
        close(
            &od.nullspace_projector,
            &mat(&e["nullspace_projector"]),
            1e-9,
            "N",
        );
        for (key, got) in [
            ("acceleration_bias", &od.acceleration_bias),
            ("task_force", &od.task_force),
            ("torque", &od.torque),
        ] {
            let want = DMatrix::from_vec(got.len(), 1, vecf(&e[key]));
            close(
                &DMatrix::from_vec(got.len(), 1, got.as_slice().to_vec()),
                &want,
                1e-9,
                key,
            );
        }
        // Λ is symmetric positive definite and equals (J H⁻¹ Jᵀ)⁻¹.
        let h = data.mass_matrix.clone();
        let j = od.jacobian.clone();
        let lam_inv = &j * h.clone().cholesky().unwrap().inverse() * j.transpose();
        close(
            &(lam_inv * &od.task_inertia),
            &DMatrix::identity(6, 6),
            1e-8,
            "ΛΛ⁻¹",
        );
        assert!((&od.task_inertia - od.task_inertia.transpose()).norm() == 0.0);
        assert!(od.task_inertia.clone().cholesky().is_some());
        // Dynamic consistency: J H⁻¹ Nᵀ τ₀ = 0 for random τ₀.
        for _ in 0..5 {
            let tau0 = DVector::from_fn(model.nv, |_, _| rng.random_range(-10.0..10.0));
            let nt = od.nullspace_projector.transpose() * &tau0;
            let mut acc = DVector::zeros(6);
            od.task_acceleration_of(&nt, &mut acc);
            assert!(acc.norm() < 1e-9 * (1.0 + tau0.norm()), "{acc}");
        }
        // The commanded task acceleration is realised: J H⁻¹ (τ − h) + J̇v = a_des.
        let mut acc = DVector::zeros(6);
        od.task_acceleration_of(&(&od.torque - &data.nle), &mut acc);
        acc += &od.acceleration_bias;
        assert!((acc - &a).norm() < 1e-8 * (1.0 + a.norm()));
    }
}

#[test]
fn rank_deficient_task_is_singular() {
    let model = model_from_urdf_file(
        format!("{}/pinocchio/urdf/panda.urdf", data_dir()),
        RootJoint::Fixed,
    )
    .unwrap();
    let frame = model.frame_id("panda_link0").unwrap();
    let mut data = Data::new(&model);
    let mut od = OscData::new(model.nv, &[0, 1, 2]);
    let q = DVector::zeros(model.nq);
    let z = DVector::zeros(model.nv);
    let e = osc_fixed_base(
        &model,
        &mut data,
        &mut od,
        frame,
        &q,
        &z,
        &DVector::zeros(3),
        &z,
    );
    assert!(matches!(e, Err(moma::Error::Singular { .. })), "{e:?}");
    assert!(moma::control::osc::task_conditioning(&od) < 1e-12);
}

/// Planar 2R, point masses m1 (elbow) and m2 (tip), gravity −y (theory.md 5.6).
struct TwoR {
    m1: f64,
    m2: f64,
    a1: f64,
    a2: f64,
    g: f64,
}

impl TwoR {
    fn terms(&self, q: &[f64; 2], qd: &[f64; 2]) -> (Matrix2<f64>, Vector2<f64>, Vector2<f64>) {
        let (m1, m2, a1, a2, g) = (self.m1, self.m2, self.a1, self.a2, self.g);
        let c2 = q[1].cos();
        let s2 = q[1].sin();
        let h11 = (m1 + m2) * a1 * a1 + m2 * a2 * a2 + 2.0 * m2 * a1 * a2 * c2;
        let h12 = m2 * a2 * a2 + m2 * a1 * a2 * c2;
        let h22 = m2 * a2 * a2;
        let hh = m2 * a1 * a2 * s2;
        let b = Vector2::new(
            -hh * (2.0 * qd[0] * qd[1] + qd[1] * qd[1]),
            hh * qd[0] * qd[0],
        );
        let c1 = q[0].cos();
        let c12 = (q[0] + q[1]).cos();
        let gv = Vector2::new(
            (m1 + m2) * g * a1 * c1 + m2 * g * a2 * c12,
            m2 * g * a2 * c12,
        );
        (Matrix2::new(h11, h12, h12, h22), b, gv)
    }
    fn x(&self, q: &[f64; 2]) -> Vector2<f64> {
        Vector2::new(
            self.a1 * q[0].cos() + self.a2 * (q[0] + q[1]).cos(),
            self.a1 * q[0].sin() + self.a2 * (q[0] + q[1]).sin(),
        )
    }
    fn jac(&self, q: &[f64; 2]) -> Matrix2<f64> {
        let (s1, c1) = q[0].sin_cos();
        let (s12, c12) = (q[0] + q[1]).sin_cos();
        Matrix2::new(
            -self.a1 * s1 - self.a2 * s12,
            -self.a2 * s12,
            self.a1 * c1 + self.a2 * c12,
            self.a2 * c12,
        )
    }
    fn jdot_qdot(&self, q: &[f64; 2], qd: &[f64; 2]) -> Vector2<f64> {
        let (s1, c1) = q[0].sin_cos();
        let (s12, c12) = (q[0] + q[1]).sin_cos();
        let w12 = qd[0] + qd[1];
        Vector2::new(
            -self.a1 * c1 * qd[0] * qd[0] - self.a2 * c12 * w12 * w12,
            -self.a1 * s1 * qd[0] * qd[0] - self.a2 * s12 * w12 * w12,
        )
    }
    /// OSC with a_des: fills `od` from the closed forms.
    fn osc(&self, od: &mut OscData, q: &[f64; 2], qd: &[f64; 2], a: &Vector2<f64>) {
        let (h, b, g) = self.terms(q, qd);
        let j = self.jac(q);
        od.jacobian.copy_from(&j);
        od.acceleration_bias.copy_from(&self.jdot_qdot(q, qd));
        let hd = DMatrix::from_column_slice(2, 2, h.as_slice());
        let bias = DVector::from_column_slice((b + g).as_slice());
        osc_from_terms(
            od,
            &hd,
            &bias,
            &DVector::from_column_slice(a.as_slice()),
            &DVector::zeros(2),
        )
        .unwrap();
    }
}

const ROBOT: TwoR = TwoR {
    m1: 2.0,
    m2: 1.0,
    a1: 0.6,
    a2: 0.5,
    g: 9.81,
};

#[test]
fn planar_2r_worked_numbers() {
    let d = load("coordinated_and_osf.json");
    let at = &d["osf_2r"]["at"];
    let (q, qd) = ([0.4, 1.1], [0.3, -0.2]);
    let (h, b, g) = ROBOT.terms(&q, &qd);
    close(
        &DMatrix::from_column_slice(2, 2, h.as_slice()),
        &mat(&at["M"]),
        1e-12,
        "M",
    );
    for (got, key) in [(b, "b"), (g, "gvec")] {
        let w = vecf(&at[key]);
        assert!(
            (got[0] - w[0]).abs() < 1e-12 && (got[1] - w[1]).abs() < 1e-12,
            "{key}"
        );
    }
    let mut od = OscData::new(2, &[0, 1]);
    // a_des = 0: F = μ + p
    ROBOT.osc(&mut od, &q, &qd, &Vector2::zeros());
    close(&od.task_inertia, &mat(&at["Lambda"]), 1e-12, "Λ");
    let (mu, p) = (vecf(&at["mu"]), vecf(&at["p"]));
    for k in 0..2 {
        assert!((od.task_force[k] - mu[k] - p[k]).abs() < 1e-11);
    }
    // Square J: Λ = J⁻ᵀ M J⁻¹ (congruence), symmetric.
    let j = ROBOT.jac(&q);
    let ji = j.try_inverse().unwrap();
    let cong = ji.transpose() * h * ji;
    close(
        &DMatrix::from_column_slice(2, 2, cong.as_slice()),
        &od.task_inertia,
        1e-12,
        "J⁻ᵀMJ⁻¹",
    );
    // The chapter's similarity transform J M J⁻¹ is not symmetric.
    let sim = j * h * ji;
    assert!((sim[(0, 1)] - sim[(1, 0)]).abs() > 1e-2);
}

struct CtLoop {
    od: OscData,
    kp: f64,
    kv: f64,
}

impl CtLoop {
    fn desired(t: f64) -> (Vector2<f64>, Vector2<f64>, Vector2<f64>) {
        let (s, c) = t.sin_cos();
        (
            Vector2::new(0.7 + 0.1 * c, 0.5 + 0.1 * s),
            Vector2::new(-0.1 * s, 0.1 * c),
            Vector2::new(-0.1 * c, -0.1 * s),
        )
    }
}

impl OdeSystem for CtLoop {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> moma::Result<()> {
        let (q, qd) = ([x[0], x[1]], [x[2], x[3]]);
        let (xd, vd, ad) = Self::desired(t);
        let e = xd - ROBOT.x(&q);
        let ed = vd - ROBOT.jac(&q) * Vector2::new(qd[0], qd[1]);
        let a = ad + self.kv * ed + self.kp * e;
        ROBOT.osc(&mut self.od, &q, &qd, &a);
        let (h, b, g) = ROBOT.terms(&q, &qd);
        let tau = Vector2::new(self.od.torque[0], self.od.torque[1]);
        let qdd = h.try_inverse().unwrap() * (tau - b - g);
        dx.copy_from_slice(&[qd[0], qd[1], qdd[0], qdd[1]]);
        Ok(())
    }
}

/// Exact-model computed torque (OSC with a* = ẍ_d + K_v ė + K_p e): the simulated error
/// equals the analytic `e(t) = (e0 + (ė0 + 5 e0) t) e^{−5t}` (K_p = 25, K_v = 10).
#[test]
fn computed_torque_error_is_the_analytic_solution() {
    let d = load("coordinated_and_osf.json");
    let checks = d["osf_2r"]["closed_loop"]["error_check_vs_analytic"]
        .as_array()
        .unwrap()
        .clone();
    let (q0, qd0) = ([0.4, 1.1], [0.3, -0.2]);
    let (xd, vd, _) = CtLoop::desired(0.0);
    let e0 = xd - ROBOT.x(&q0);
    let ed0 = vd - ROBOT.jac(&q0) * Vector2::new(qd0[0], qd0[1]);
    let mut sys = CtLoop {
        od: OscData::new(2, &[0, 1]),
        kp: 25.0,
        kv: 10.0,
    };
    let times: Vec<f64> = (0..=60).map(|k| 0.05 * f64::from(k)).collect();
    let mut dp = Dop853::new(4, AdaptiveOptions::with_tolerance(1e-12)).unwrap();
    let rows = dp
        .solve_at(&mut sys, 0.0, &[q0[0], q0[1], qd0[0], qd0[1]], &times)
        .unwrap();
    for (r, &t) in rows.iter().zip(&times) {
        let (xd, _, _) = CtLoop::desired(t);
        let e = xd - ROBOT.x(&[r[0], r[1]]);
        let analytic = (e0 + (ed0 + 5.0 * e0) * t) * (-5.0 * t).exp();
        assert!((e - analytic).norm() < 1e-8, "t {t}: {e} vs {analytic}");
    }
    for c in &checks {
        let t = c["t"].as_f64().unwrap();
        let want = vecf(&c["e_analytic"]);
        let analytic = (e0 + (ed0 + 5.0 * e0) * t) * (-5.0 * t).exp();
        assert!((analytic[0] - want[0]).abs() < 1e-12 && (analytic[1] - want[1]).abs() < 1e-12);
    }
}

/// Reduced model of an arm on the non-holonomic platform (chapter robot m5 as a
/// multibody model): the torque N_Cᵀ Q from `osc_reduced`, mapped to the actuators and
/// fed to the independent reduced forward dynamics, realises the commanded task
/// acceleration of the tip; and the null-space torque does not reach the task.
#[test]
fn reduced_osc_on_the_mobile_manipulator() {
    let doc: Value = serde_json::from_str(
        &std::fs::read_to_string(format!(
            "{}/chapter/m5_mobile_manipulator_3d.json",
            data_dir()
        ))
        .unwrap(),
    )
    .unwrap();
    let mut rng = rand::rngs::StdRng::seed_from_u64(5);
    for case in doc["cases"].as_array().unwrap().iter().take(3) {
        let params = serde_json::from_value(case["params"].clone()).unwrap();
        let wm = moma::closed_form::multibody_models::m5_model(&params).unwrap();
        let frame = wm.model.frame_id("tip").unwrap();
        let q = DVector::from_vec(vecf(&case["state"]["q_joint"]));
        let nr = wm.nr();
        let v_r = DVector::from_fn(nr, |_, _| rng.random_range(-0.5..0.5));
        let a = DVector::from_fn(3, |_, _| rng.random_range(-1.0..1.0));
        let tau0 = DVector::from_fn(nr, |_, _| rng.random_range(-5.0..5.0));
        let mut rod = ReducedOscData::new(&wm, &[0, 1, 2]);
        osc_reduced(&wm, &mut rod, frame, &q, &v_r, &a, &tau0).unwrap();
        // actuators: N_Cᵀ S u = τ_r
        let mut s = DMatrix::zeros(wm.nv(), wm.nu());
        actuation_matrix(&wm, &q, &mut s);
        let ns = rod.wheeled.basis.transpose() * &s;
        let u = ns.lu().solve(&rod.osc.torque).unwrap();
        let mut wd = WheeledData::new(&wm);
        reduced_dynamics(&wm, &mut wd, &q, &v_r, u.as_slice(), None).unwrap();
        let qddot = wd.reduced.qddot.clone();
        let qdot = wd.qdot.clone();
        let mut data = Data::new(&wm.model);
        let bias = frame_acceleration_bias(
            &wm.model,
            &mut data,
            &q,
            &qdot,
            frame,
            ReferenceFrame::LocalWorldAligned,
        )
        .to_vector();
        let mut j = Matrix6xX::zeros(wm.nv());
        frame_jacobian(
            &wm.model,
            &mut data,
            &q,
            frame,
            ReferenceFrame::LocalWorldAligned,
            &mut j,
        );
        let acc = j * &qddot + bias;
        for k in 0..3 {
            assert!(
                (acc[k] - a[k]).abs() < 1e-8 * (1.0 + a.norm()),
                "{acc} vs {a}"
            );
        }
        let nt = rod.osc.nullspace_projector.transpose() * &tau0;
        let mut out = DVector::zeros(3);
        rod.osc.task_acceleration_of(&nt, &mut out);
        assert!(out.norm() < 1e-9 * (1.0 + tau0.norm()));
    }
}

impl TwoR {
    /// Task-space Λ, C_x (Christoffel-consistent: C_x = Λ (J H⁻¹ C_q − J̇) J⁻¹) and p.
    fn task_model(
        &self,
        q: &[f64; 2],
        qd: &[f64; 2],
    ) -> (Matrix2<f64>, Matrix2<f64>, Vector2<f64>) {
        let (h, _, g) = self.terms(q, qd);
        let hc = -self.m2 * self.a1 * self.a2 * q[1].sin();
        let cq = Matrix2::new(hc * qd[1], hc * (qd[0] + qd[1]), -hc * qd[0], 0.0);
        let (s1, c1) = q[0].sin_cos();
        let (s12, c12) = (q[0] + q[1]).sin_cos();
        let w = qd[0] + qd[1];
        let jdot = Matrix2::new(
            -self.a1 * c1 * qd[0] - self.a2 * c12 * w,
            -self.a2 * c12 * w,
            -self.a1 * s1 * qd[0] - self.a2 * s12 * w,
            -self.a2 * s12 * w,
        );
        let j = self.jac(q);
        let ji = j.try_inverse().unwrap();
        let hi = h.try_inverse().unwrap();
        let lam = ji.transpose() * h * ji;
        let cx = lam * (j * hi * cq - jdot) * ji;
        let p = lam * j * hi * g;
        (lam, cx, p)
    }
}

struct DecoupledLoop {
    coupling: moma::control::task::Coupling,
    kp: Matrix2<f64>,
    kv: Matrix2<f64>,
}

impl OdeSystem for DecoupledLoop {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> moma::Result<()> {
        let (q, qd) = ([x[0], x[1]], [x[2], x[3]]);
        let (xd, vd, ad) = CtLoop::desired(t);
        let j = ROBOT.jac(&q);
        let xdot = j * Vector2::new(qd[0], qd[1]);
        let (lam, cx, p) = ROBOT.task_model(&q, &qd);
        let f = moma::control::task::decoupled::<2, 1>(
            &lam,
            &cx,
            &p,
            &xdot,
            &(xd - ROBOT.x(&q)),
            &(vd - xdot),
            &ad,
            &self.kp,
            &self.kv,
            self.coupling,
        );
        let (h, b, g) = ROBOT.terms(&q, &qd);
        let qdd = h.try_inverse().unwrap() * (j.transpose() * f - b - g);
        dx.copy_from_slice(&[qd[0], qd[1], qdd[0], qdd[1]]);
        Ok(())
    }
}

/// The chapter's decoupled control on the 2R split (x row | y row) with different gains
/// per block: compensated, each block's error is the critically damped solution of its
/// own equation; naive (cross terms dropped), the error visibly departs from it.
#[test]
fn decoupled_control_compensated_versus_naive() {
    use moma::control::task::Coupling;
    let (q0, qd0) = ([0.4, 1.1], [0.3, -0.2]);
    let (xd, vd, _) = CtLoop::desired(0.0);
    let e0 = xd - ROBOT.x(&q0);
    let ed0 = vd - ROBOT.jac(&q0) * Vector2::new(qd0[0], qd0[1]);
    let rates = [5.0, 4.0];
    let kp = Matrix2::new(25.0, 0.0, 0.0, 16.0);
    let kv = Matrix2::new(10.0, 0.0, 0.0, 8.0);
    let times: Vec<f64> = (0..=40).map(|k| 0.05 * f64::from(k)).collect();
    let mut worst = [0.0f64; 2];
    for (idx, coupling) in [Coupling::Compensated, Coupling::Naive]
        .into_iter()
        .enumerate()
    {
        let mut sys = DecoupledLoop { coupling, kp, kv };
        let mut dp = Dop853::new(4, AdaptiveOptions::with_tolerance(1e-12)).unwrap();
        let rows = dp
            .solve_at(&mut sys, 0.0, &[q0[0], q0[1], qd0[0], qd0[1]], &times)
            .unwrap();
        for (r, &t) in rows.iter().zip(&times) {
            let (xd, _, _) = CtLoop::desired(t);
            let e = xd - ROBOT.x(&[r[0], r[1]]);
            for k in 0..2 {
                let l = rates[k];
                let analytic = (e0[k] + (ed0[k] + l * e0[k]) * t) * (-l * t).exp();
                worst[idx] = worst[idx].max((e[k] - analytic).abs());
            }
        }
    }
    assert!(worst[0] < 1e-8, "compensated: {}", worst[0]);
    assert!(worst[1] > 1e-3, "naive coupling should show: {}", worst[1]);
    // C_x is Christoffel-consistent: Λ̇ − 2 C_x is skew (finite difference of Λ along the motion).
    let (q, qd) = ([0.4, 1.1], [0.3, -0.2]);
    let hstep = 1e-6;
    let lp = ROBOT
        .task_model(&[q[0] + hstep * qd[0], q[1] + hstep * qd[1]], &qd)
        .0;
    let lm = ROBOT
        .task_model(&[q[0] - hstep * qd[0], q[1] - hstep * qd[1]], &qd)
        .0;
    let (_, cx, _) = ROBOT.task_model(&q, &qd);
    let s = (lp - lm) / (2.0 * hstep) - 2.0 * cx;
    assert!((s + s.transpose()).norm() < 1e-7, "{s}");
}

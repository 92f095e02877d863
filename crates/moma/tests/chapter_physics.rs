//! Physics checks of the chapter's closed-form models: Christoffel skew-symmetry (by
//! finite differences), C N_C = 0, energy conservation, constraint residual along
//! trajectories, task-space identities, the balanced cart, d = 0 and singular cases.

use moma::Error;
use moma::closed_form::ConstantInputOde;
use moma::closed_form::PlatformVelocity;
use moma::closed_form::lagrange::{self, LagrangianSystem, PfaffianSystem};
use moma::closed_form::m1_unicycle::{Unicycle, UnicycleParams};
use moma::closed_form::m2_platform_arm::{PlatformArm, PlatformArmParams};
use moma::closed_form::m3_diffdrive::{DiffDriveKinematics, DiffDriveKinematicsParams};
use moma::closed_form::m4_cart_two_link::{CartTwoLink, CartTwoLinkParams};
use moma::closed_form::m5_mobile_manipulator::{
    MobileManipulator, MobileManipulatorParams, joint_to_absolute,
};
use moma::sim::{AdaptiveOptions, DormandPrince45};
use nalgebra::{SMatrix, SVector, Vector3};
use serde_json::Value;

fn cases(name: &str) -> Vec<Value> {
    let path = format!(
        "{}/tests/data/chapter/{name}.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let doc: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    doc["cases"].as_array().unwrap().clone()
}

fn vec_of<const K: usize>(v: &Value) -> SVector<f64, K> {
    let x: Vec<f64> = serde_json::from_value(v.clone()).unwrap();
    SVector::from_column_slice(&x)
}

/// ‖(Ḣ − 2C_cor) + (Ḣ − 2C_cor)ᵀ‖ with Ḣ by central finite differences along q̇.
fn skew_defect<S: LagrangianSystem<N>, const N: usize>(
    sys: &S,
    q: &SVector<f64, N>,
    qd: &SVector<f64, N>,
) -> f64 {
    let eps = 1e-6;
    let hp = lagrange::mass_matrix(sys, &(q + qd * eps));
    let hm = lagrange::mass_matrix(sys, &(q - qd * eps));
    let hdot = (hp - hm) / (2.0 * eps);
    let c = lagrange::lagrange_terms(sys, q, qd).coriolis;
    let k = hdot - c * 2.0;
    (k + k.transpose()).norm() / (1.0 + hdot.norm())
}

fn constraint_defect<
    S: PfaffianSystem<N, NV, NU>,
    const N: usize,
    const NV: usize,
    const NU: usize,
>(
    sys: &S,
    q: &SVector<f64, N>,
) -> f64 {
    let ct = lagrange::constraint_terms(sys, q, &SVector::<f64, NV>::zeros());
    (ct.constraint * ct.basis).norm()
}

#[test]
fn christoffel_skew_and_constraint_basis_all_models() {
    for c in cases("m2_platform_planar_arm") {
        let sys = PlatformArm::new(
            serde_json::from_value::<PlatformArmParams>(c["params"].clone()).unwrap(),
        )
        .unwrap();
        let q = vec_of::<5>(&c["state"]["q"]);
        let qd = vec_of::<5>(&c["outputs"]["qdot"]);
        assert!(skew_defect(&sys, &q, &qd) < 1e-8);
        assert!(constraint_defect(&sys, &q) < 1e-14);
    }
    for c in cases("m4_cart_two_link") {
        let sys = CartTwoLink::new(
            serde_json::from_value::<CartTwoLinkParams>(c["params"].clone()).unwrap(),
        )
        .unwrap();
        let q = vec_of::<3>(&c["state"]["q"]);
        let qd = vec_of::<3>(&c["state"]["qdot"]);
        assert!(skew_defect(&sys, &q, &qd) < 1e-8);
    }
    for c in cases("m5_mobile_manipulator_3d") {
        let sys = MobileManipulator::new(
            serde_json::from_value::<MobileManipulatorParams>(c["params"].clone()).unwrap(),
        )
        .unwrap();
        let q = vec_of::<6>(&c["state"]["q"]);
        let qd = vec_of::<6>(&c["outputs"]["qdot"]);
        assert!(skew_defect(&sys, &q, &qd) < 1e-8);
        assert!(constraint_defect(&sys, &q) < 1e-14);
    }
    for c in cases("m1_unicycle") {
        let sys =
            Unicycle::new(serde_json::from_value::<UnicycleParams>(c["params"].clone()).unwrap())
                .unwrap();
        let q = vec_of::<3>(&c["state"]["q"]);
        assert!(constraint_defect(&sys, &q) < 1e-14);
    }
}

fn m5_case(c: &Value, g: Option<f64>) -> MobileManipulator {
    let mut p: MobileManipulatorParams = serde_json::from_value(c["params"].clone()).unwrap();
    if let Some(g) = g {
        p.g = g;
    }
    MobileManipulator::new(p).unwrap()
}

#[test]
fn m5_task_space_identity_reduced_skew_and_joint_coordinates() {
    for c in cases("m5_mobile_manipulator_3d") {
        let sys = m5_case(&c, None);
        let q = vec_of::<6>(&c["state"]["q"]);
        let v = vec_of::<5>(&c["state"]["v"]);
        let u = vec_of::<5>(&c["inputs"]["u"]);
        let o = sys.evaluate(&q, &v, &u).unwrap();
        let t = &o.task;
        // Hx ẍ + BV ẋ + B G = B Q
        let r = t.Hx * t.xddot + t.BV * t.xdot + t.BgG - t.BQ;
        assert!(r.norm() < 1e-9 * (1.0 + t.BQ.norm()), "task identity {r}");
        // full equation with λ: H q̈ + h + G = Q − Cᵀλ
        let r = o.H * o.qddot + o.h + o.G - o.Q + o.C.transpose() * o.lambda;
        assert!(r.norm() < 1e-9 * (1.0 + o.Q.norm()));
        // λ formula of the spec: (C H⁻¹ Cᵀ)⁻¹ (C H⁻¹ (Q − h − G) + Ċ q̇), Ċ q̇ = −φ̇ v_F
        let hinv = o.H.try_inverse().unwrap();
        let cdq = -o.qdot[2] * v[0];
        let lam = ((o.C * hinv * (o.Q - o.h - o.G))[(0, 0)] + cdq)
            / (o.C * hinv * o.C.transpose())[(0, 0)];
        assert!((lam - o.lambda).abs() < 1e-8 * (1.0 + lam.abs()));
        // Ṁr − 2Cr skew (finite differences along the motion)
        let eps = 1e-6;
        let mr_at = |s: f64| {
            let qs = q + o.qdot * s;
            let ct = lagrange::constraint_terms(&sys, &qs, &v);
            ct.basis.transpose() * lagrange::mass_matrix(&sys, &qs) * ct.basis
        };
        let mrdot = (mr_at(eps) - mr_at(-eps)) / (2.0 * eps);
        let k = mrdot - o.Cr * 2.0;
        assert!((k + k.transpose()).norm() < 1e-6 * (1.0 + mrdot.norm()));
        // joint coordinates: H_joint = Pᵀ H P, and G_joint = ∂V/∂q_j
        let p = joint_to_absolute();
        assert!((o.H_joint - p.transpose() * o.H * p).norm() < 1e-12);
        // H symmetric positive definite
        assert!((o.H - o.H.transpose()).norm() < 1e-14);
        assert!(o.H.cholesky().is_some());
        assert!(t.Hx.cholesky().is_some());
    }
}

#[test]
fn m3_det_formula_and_consistency_with_m5() {
    for c in cases("m3_diffdrive_kinematics") {
        let p: DiffDriveKinematicsParams = serde_json::from_value(c["params"].clone()).unwrap();
        let sys = DiffDriveKinematics::new(p.clone()).unwrap();
        let q = vec_of::<6>(&c["state"]["q"]);
        let v = vec_of::<5>(&c["inputs"]["v"]);
        let o = sys.evaluate(&q, &v).unwrap();
        let (th1, th2) = (q[4], q[5]);
        let rho = p.L1 * th1.sin() + p.L2 * (th1 - th2).sin();
        let det = p.r_w.powi(2) * p.L1 * p.L2 * (p.d + p.L) * rho * th2.sin() / (2.0 * p.b);
        assert!((o.det_J - det).abs() < 1e-12 * (1.0 + det.abs()));
        // Xdot by finite differences of X along q̇ = N_C v
        let qa: [f64; 6] = (q + o.qdot * 1e-6).as_slice().try_into().unwrap();
        let qb: [f64; 6] = (q - o.qdot * 1e-6).as_slice().try_into().unwrap();
        let xa = SVector::<f64, 5>::from(sys.task_generic(&qa));
        let xb = SVector::<f64, 5>::from(sys.task_generic(&qb));
        assert!(((xa - xb) / 2e-6 - o.Xdot).norm() < 1e-7);
        // wheel-rate kinematics: V = r_w/2 (θ̇L + θ̇R), ω = r_w/(2b)(θ̇R − θ̇L)
        let vf = p.r_w / 2.0 * (v[0] + v[1]);
        let w = p.r_w / (2.0 * p.b) * (v[1] - v[0]);
        assert!((o.qdot[2] - w).abs() < 1e-14);
        let (s, cph) = q[2].sin_cos();
        assert!((o.qdot[0] - (vf * cph - p.d * w * s)).abs() < 1e-14);
    }
}

#[test]
fn energy_conserved_with_zero_input_and_no_gravity_over_10s() {
    let opts = AdaptiveOptions::with_tolerance(1e-12);
    let c1 = &cases("m1_unicycle")[0];
    let m1 = Unicycle::new(serde_json::from_value(c1["params"].clone()).unwrap()).unwrap();
    let (q, v) = (
        vec_of::<3>(&c1["state"]["q"]),
        vec_of::<2>(&c1["state"]["v"]),
    );
    let e0 = m1.kinetic_energy(&q, &v);
    let s = m1
        .simulate(&q, &v, &SVector::zeros(), &[10.0], 1e-12)
        .unwrap();
    let e1 = m1.kinetic_energy(&s[0].0, &s[0].1);
    assert!(((e1 - e0) / e0).abs() < 1e-9, "m1 drift {}", (e1 - e0) / e0);

    let c2 = &cases("m2_platform_planar_arm")[0];
    let m2 = PlatformArm::new(serde_json::from_value(c2["params"].clone()).unwrap()).unwrap();
    let (q, v) = (
        vec_of::<5>(&c2["state"]["q"]),
        vec_of::<4>(&c2["state"]["v"]),
    );
    let e0 = m2.kinetic_energy(&q, &v);
    let s = m2
        .simulate(&q, &v, &SVector::zeros(), &[10.0], 1e-12)
        .unwrap();
    let e1 = m2.kinetic_energy(&s[0].0, &s[0].1);
    assert!(((e1 - e0) / e0).abs() < 1e-9, "m2 drift {}", (e1 - e0) / e0);

    for c in cases("m5_mobile_manipulator_3d").iter().take(2) {
        let m5 = m5_case(c, Some(0.0));
        let (q, v) = (vec_of::<6>(&c["state"]["q"]), vec_of::<5>(&c["state"]["v"]));
        let e0 = m5.energy(&q, &v);
        let mut ode = ConstantInputOde {
            system: &m5,
            input: SVector::<f64, 5>::zeros(),
        };
        let mut dp = DormandPrince45::new(11, opts).unwrap();
        let x0: Vec<f64> = q.iter().chain(v.iter()).copied().collect();
        let rows = dp
            .solve_at(&mut ode, 0.0, &x0, &[2.5, 5.0, 7.5, 10.0])
            .unwrap();
        for r in rows {
            let (qt, vt) = (
                SVector::<f64, 6>::from_column_slice(&r[..6]),
                SVector::<f64, 5>::from_column_slice(&r[6..]),
            );
            let e = m5.energy(&qt, &vt);
            assert!(((e - e0) / e0).abs() < 1e-9, "m5 drift {}", (e - e0) / e0);
            // C q̇ residual along the reduced trajectory
            let ct = lagrange::constraint_terms(&m5, &qt, &vt);
            assert!((ct.constraint * ct.qdot)[(0, 0)].abs() < 1e-12);
        }
        assert!(dp.stats.accepted > 10 && dp.stats.rhs_evals >= 6 * dp.stats.accepted);
    }

    for c in cases("m4_cart_two_link").iter().take(2) {
        let mut p: CartTwoLinkParams = serde_json::from_value(c["params"].clone()).unwrap();
        p.g = 0.0;
        let m4 = CartTwoLink::new(p).unwrap();
        let (q, qd) = (
            vec_of::<3>(&c["state"]["q"]),
            vec_of::<3>(&c["state"]["qdot"]),
        );
        let e0 = m4.energy(&q, &qd);
        let s = m4
            .simulate(&q, &qd, &Vector3::zeros(), &[10.0], 1e-12)
            .unwrap();
        let e1 = m4.energy(&s[0].0, &s[0].1);
        assert!(((e1 - e0) / e0).abs() < 1e-9, "m4 drift {}", (e1 - e0) / e0);
    }
}

#[test]
fn energy_with_gravity_conserved_for_m5() {
    // with gravity, T + V is conserved as well (u = 0, the constraint is workless)
    let c = &cases("m5_mobile_manipulator_3d")[1];
    let m5 = m5_case(c, None);
    let (q, v) = (vec_of::<6>(&c["state"]["q"]), vec_of::<5>(&c["state"]["v"]));
    let e0 = m5.energy(&q, &v);
    let s = m5
        .simulate(&q, &v, &SVector::zeros(), &[1.0], 1e-12)
        .unwrap();
    let e1 = m5.energy(&s[0].0, &s[0].1);
    assert!((e1 - e0).abs() < 1e-9 * (1.0 + e0.abs()));
}

#[test]
fn balanced_cart_is_a_free_mass() {
    for c in cases("m4_cart_two_link")
        .iter()
        .filter(|c| c["balanced"] == true)
    {
        let m4 = CartTwoLink::new(serde_json::from_value(c["params"].clone()).unwrap()).unwrap();
        assert!(m4.is_balanced(1e-12));
        let (q, qd, u) = (
            vec_of::<3>(&c["state"]["q"]),
            vec_of::<3>(&c["state"]["qdot"]),
            vec_of::<3>(&c["inputs"]["u"]),
        );
        let o = m4.evaluate(&q, &qd, &u).unwrap();
        assert!(o.G.norm() < 1e-12 && o.h.norm() < 1e-12);
        assert!(o.H[(0, 1)].abs() < 1e-12 && o.H[(0, 2)].abs() < 1e-12);
        let mt = m4.params.total_mass();
        assert!((o.qddot[0] - u[0] / mt).abs() < 1e-12);
        // the arm pushes on the cart with exactly (−m_arm d̈0, −m_arm g)
        let ma = m4.params.arm_mass();
        assert!((o.arm_force_on_cart[0] + ma * o.qddot[0]).abs() < 1e-9);
        assert!((o.arm_force_on_cart[1] + ma * m4.params.g).abs() < 1e-9);
        // (5.65): I11 θ̈1 + I22 (θ̈1 − θ̈2) = τ1; (5.63): I22 (θ̈2 − θ̈1) = τ2
        assert!((o.I11 * o.qddot[1] + o.I22 * (o.qddot[1] - o.qddot[2]) - u[1]).abs() < 1e-9);
        assert!((o.I22 * (o.qddot[2] - o.qddot[1]) - u[2]).abs() < 1e-9);
        // d0(t) = d0 + ḋ0 t + ½ f/M_T t²
        let s = m4.simulate(&q, &qd, &u, &[1.0, 2.0], 1e-12).unwrap();
        for (t, (qt, _)) in [1.0, 2.0].iter().zip(&s) {
            let d0 = q[0] + qd[0] * t + 0.5 * u[0] / mt * t * t;
            assert!((qt[0] - d0).abs() < 1e-9);
        }
    }
    // balancing offsets make Γ1 = Γ2 = 0 for an unbalanced case
    let c = &cases("m4_cart_two_link")[0];
    let mut p: CartTwoLinkParams = serde_json::from_value(c["params"].clone()).unwrap();
    let (l1, l2) = p.balancing_offsets();
    p.L1cm = l1;
    p.L2cm = l2;
    assert!(p.gamma1().abs() < 1e-12 && p.gamma2().abs() < 1e-12);
}

#[test]
fn zero_axle_offset_uses_the_yaw_rate() {
    let c = &cases("m2_platform_planar_arm")[0];
    let mut p: PlatformArmParams = serde_json::from_value(c["params"].clone()).unwrap();
    // d ≠ 0: both parametrisations describe the same motion, v_yaw = [v_F, v_T/d, …]
    let lat = PlatformArm::with_velocity(p.clone(), PlatformVelocity::LateralVelocity).unwrap();
    let yaw = PlatformArm::with_velocity(p.clone(), PlatformVelocity::YawRate).unwrap();
    let q = vec_of::<5>(&c["state"]["q"]);
    let v = vec_of::<4>(&c["state"]["v"]);
    let u = vec_of::<4>(&c["inputs"]["u"]);
    let vy = SVector::<f64, 4>::new(v[0], v[1] / p.d, v[2], v[3]);
    let a = lat.evaluate(&q, &v, &u).unwrap();
    let b = yaw.evaluate(&q, &vy, &u).unwrap();
    assert!((a.qdot - b.qdot).norm() < 1e-12);
    assert!((a.qddot - b.qddot).norm() < 1e-9 * (1.0 + a.qddot.norm()));
    assert!((a.lambda - b.lambda).abs() < 1e-9 * (1.0 + a.lambda.abs()));
    // d = 0: automatic choice, finite results, the lateral form is reported singular
    p.d = 0.0;
    let m = PlatformArm::new(p.clone()).unwrap();
    assert_eq!(m.velocity, PlatformVelocity::YawRate);
    let o = m.evaluate(&q, &vy, &u).unwrap();
    assert!(o.qddot.iter().all(|x| x.is_finite()));
    assert!((o.C * o.N_C).norm() < 1e-15);
    assert!(matches!(
        PlatformArm::with_velocity(p, PlatformVelocity::LateralVelocity),
        Err(Error::Singular { .. })
    ));
    let mut p1: UnicycleParams =
        serde_json::from_value(cases("m1_unicycle")[0]["params"].clone()).unwrap();
    p1.d = 0.0;
    let m1 = Unicycle::new(p1).unwrap();
    let s = m1
        .simulate(
            &Vector3::zeros(),
            &SVector::<f64, 2>::new(1.0, 0.5),
            &SVector::<f64, 2>::new(0.1, 0.2),
            &[1.0],
            1e-12,
        )
        .unwrap();
    // with d = 0 the constraint is ẏ cos φ − ẋ sin φ = 0
    let o = m1.evaluate(&s[0].0, &s[0].1, &SVector::zeros()).unwrap();
    assert!((o.C * o.qdot)[(0, 0)].abs() < 1e-12);
}

#[test]
fn singular_and_invalid_inputs_are_reported() {
    let c = &cases("m5_mobile_manipulator_3d")[0];
    let m5 = m5_case(c, None);
    let mut q = vec_of::<6>(&c["state"]["q"]);
    let v = vec_of::<5>(&c["state"]["v"]);
    let u = vec_of::<5>(&c["inputs"]["u"]);
    q[5] = q[4]; // θ2 = 0: stretched arm, A singular
    assert!(matches!(
        m5.evaluate(&q, &v, &u),
        Err(Error::Singular { .. })
    ));
    q[5] = f64::NAN;
    assert!(matches!(
        m5.evaluate(&q, &v, &u),
        Err(Error::NonFinite { .. })
    ));
    let mut p: MobileManipulatorParams = serde_json::from_value(c["params"].clone()).unwrap();
    p.m1 = -1.0;
    let e = MobileManipulator::new(p).unwrap_err().to_string();
    assert!(e.contains("params.m1"), "{e}");
    let mut p: UnicycleParams =
        serde_json::from_value(cases("m1_unicycle")[0]["params"].clone()).unwrap();
    p.inertia = f64::INFINITY;
    assert!(matches!(Unicycle::new(p), Err(Error::NonFinite { .. })));
    // a massless arm makes Mr singular: reported, not divided by
    let c2 = &cases("m2_platform_planar_arm")[0];
    let mut p: PlatformArmParams = serde_json::from_value(c2["params"].clone()).unwrap();
    p.m1 = 0.0;
    p.m2 = 0.0;
    p.M1 = 0.0;
    p.M2 = 0.0;
    let m = PlatformArm::new(p).unwrap();
    let r = m.evaluate(
        &vec_of::<5>(&c2["state"]["q"]),
        &vec_of::<4>(&c2["state"]["v"]),
        &vec_of::<4>(&c2["inputs"]["u"]),
    );
    assert!(matches!(r, Err(Error::Singular { .. })));
    let _: SMatrix<f64, 1, 1> = SMatrix::zeros();
}

#[test]
fn dormand_prince_45_also_reproduces_the_m5_reference_trajectories() {
    for c in cases("m5_mobile_manipulator_3d") {
        let m5 = m5_case(&c, None);
        let (q, v, u) = (
            vec_of::<6>(&c["state"]["q"]),
            vec_of::<5>(&c["state"]["v"]),
            vec_of::<5>(&c["inputs"]["u"]),
        );
        let mut ode = ConstantInputOde {
            system: &m5,
            input: u,
        };
        let mut dp = DormandPrince45::new(11, AdaptiveOptions::with_tolerance(1e-12)).unwrap();
        let x0: Vec<f64> = q.iter().chain(v.iter()).copied().collect();
        let times: Vec<f64> = serde_json::from_value(c["trajectory"]["t"].clone()).unwrap();
        let rows = dp.solve_at(&mut ode, 0.0, &x0, &times).unwrap();
        for (k, r) in rows.iter().enumerate() {
            let want_q: Vec<f64> = serde_json::from_value(c["trajectory"]["q"][k].clone()).unwrap();
            let want_v: Vec<f64> = serde_json::from_value(c["trajectory"]["v"][k].clone()).unwrap();
            for (a, b) in r.iter().zip(want_q.iter().chain(want_v.iter())) {
                assert!((a - b).abs() < 1e-8, "{a} vs {b}");
            }
        }
    }
}

#[test]
fn m5_task_space_skew_and_closed_loop_lyapunov_balance() {
    use moma::closed_form::m5_mobile_manipulator::TaskController;
    for c in cases("m5_mobile_manipulator_3d") {
        let m5 = m5_case(&c, None);
        let q = vec_of::<6>(&c["state"]["q"]);
        let v = vec_of::<5>(&c["state"]["v"]);
        let u = vec_of::<5>(&c["inputs"]["u"]);
        let o = m5.evaluate(&q, &v, &u).unwrap();
        // Ḣx − 2 BV skew-symmetric (Ḣx by central differences along q̇ = N_C v)
        let eps = 1e-6;
        let hx = |s: f64| m5.evaluate(&(q + o.qdot * s), &v, &u).unwrap().task.Hx;
        let hxdot = (hx(eps) - hx(-eps)) / (2.0 * eps);
        let k = hxdot - o.task.BV * 2.0;
        assert!(
            (k + k.transpose()).norm() < 1e-6 * (1.0 + hxdot.norm()),
            "{}",
            (k + k.transpose()).norm()
        );

        let ctl = &c["control"];
        let mat = |key: &str| {
            let rows: Vec<Vec<f64>> = serde_json::from_value(ctl[key].clone()).unwrap();
            SMatrix::<f64, 5, 5>::from_fn(|i, j| rows[i][j])
        };
        let controller = TaskController {
            x_ref: vec_of::<5>(&ctl["x_ref"]),
            amp: vec_of::<5>(&ctl["amp"]),
            omega: vec_of::<5>(&ctl["omega"]),
            kp: mat("Kp"),
            kd: mat("Kd"),
        };
        let (q0, v0) = (vec_of::<6>(&ctl["q0"]), vec_of::<5>(&ctl["v0"]));
        let w0 = controller.control(&m5, 0.0, &q0, &v0).unwrap().w;
        let times = [0.1, 0.2, 0.4, 0.6, 0.8, 1.0];
        let samples = controller.simulate(&m5, &q0, &v0, &times, 1e-12).unwrap();
        let mut last = w0;
        for s in &samples {
            // W(t) = W(0) − ∫ ėᵀ Kd ė dt, and W never increases
            assert!(
                (s.w - (w0 - s.dissipated)).abs() < 1e-9 * (1.0 + w0),
                "t = {}: {} vs {}",
                s.t,
                s.w,
                w0 - s.dissipated
            );
            assert!(s.w <= last + 1e-12);
            last = s.w;
        }
    }
}

#[test]
fn model_state_round_trips_and_validates() {
    use moma::closed_form::m5_mobile_manipulator::State;
    let s =
        State::from_slices(&[0.0, 1.0, 2.0, 3.0, 4.0, 5.0], &[6.0, 7.0, 8.0, 9.0, 10.0]).unwrap();
    assert_eq!(State::from_ode(&s.to_ode()).unwrap(), s);
    assert!(matches!(
        State::from_slices(&[0.0; 5], &[0.0; 5]),
        Err(Error::WrongLength { .. })
    ));
    assert!(matches!(
        State::from_slices(&[f64::NAN; 6], &[0.0; 5]),
        Err(Error::NonFinite { .. })
    ));
}

#[test]
fn state_derivative_matches_the_evaluated_outputs() {
    for c in cases("m5_mobile_manipulator_3d") {
        let m5 = m5_case(&c, None);
        let s = moma::closed_form::m5_mobile_manipulator::State {
            q: vec_of::<6>(&c["state"]["q"]),
            v: vec_of::<5>(&c["state"]["v"]),
        };
        let u = vec_of::<5>(&c["inputs"]["u"]);
        let d = m5.state_derivative(&s, &u).unwrap();
        let o = m5.evaluate(&s.q, &s.v, &u).unwrap();
        assert!((d.q - o.qdot).norm() < 1e-14);
        assert!((d.v - o.vdot).norm() < 1e-10 * (1.0 + o.vdot.norm()));
    }
    for c in cases("m4_cart_two_link") {
        let m4 = CartTwoLink::new(serde_json::from_value(c["params"].clone()).unwrap()).unwrap();
        let s = moma::closed_form::m4_cart_two_link::State {
            q: vec_of::<3>(&c["state"]["q"]),
            v: vec_of::<3>(&c["state"]["qdot"]),
        };
        let u = vec_of::<3>(&c["inputs"]["u"]);
        let d = m4.state_derivative(&s, &u).unwrap();
        let want = vec_of::<3>(&c["outputs"]["qddot"]);
        assert!((d.v - want).norm() < 1e-9 * (1.0 + want.norm()));
    }
}

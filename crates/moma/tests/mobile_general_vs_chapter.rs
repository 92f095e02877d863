//! The general wheeled-model dynamics (rigid-body core + analytic differential-drive
//! basis) on the chapter's robots rebuilt through `ModelBuilder` must equal the chapter's
//! reference vectors (H, h, G, Mr, Cr, cr, Gr, Qr, v̇, q̈, λ) and the closed forms.
//!
//! Velocity parametrisations differ by a constant map: the general model uses
//! `v_r = [v_F, ω, q̇_joints…]`, the chapter `v = T v_r` (`v_T = d ω`, and m5's absolute
//! angles `φ̇t = ω + φ̇1`, `θ̇12 = θ̇1 − θ̇2`). Then `Mr = Tᵀ Mr_ch T`, `Cr = Tᵀ Cr_ch T`,
//! `Qr = Tᵀ Qr_ch`, `v̇_ch = T v̇`, and λ is the same.

use moma::closed_form::m1_unicycle::UnicycleParams;
use moma::closed_form::m2_platform_arm::PlatformArmParams;
use moma::closed_form::m5_mobile_manipulator::{MobileManipulatorParams, joint_to_absolute};
use moma::closed_form::multibody_models::{m1_model, m2_model, m5_model};
use moma::dynamics::coriolis_matrix;
use moma::mobile::reduced_forward_dynamics;
use moma::mobile::wheeled::{WheeledData, WheeledModel, lagrange_multipliers, reduced_dynamics};
use nalgebra::{DMatrix, DVector};
use serde_json::Value;

fn load(name: &str) -> Value {
    let path = format!("{}/tests/data/mobile/{name}", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn vector(v: &Value) -> DVector<f64> {
    match v {
        Value::Array(a) => DVector::from_iterator(a.len(), a.iter().map(|x| x.as_f64().unwrap())),
        Value::Number(n) => DVector::from_element(1, n.as_f64().unwrap()),
        _ => panic!("not a vector: {v}"),
    }
}

fn matrix(v: &Value) -> DMatrix<f64> {
    let rows = v.as_array().unwrap();
    let c = rows[0].as_array().unwrap().len();
    DMatrix::from_fn(rows.len(), c, |i, j| rows[i][j].as_f64().unwrap())
}

fn close(what: &str, got: &DMatrix<f64>, want: &DMatrix<f64>, rel: f64) {
    assert_eq!(got.shape(), want.shape(), "{what} shape");
    let err = (got - want).norm();
    let scale = want.norm().max(1.0);
    assert!(
        err <= rel * scale,
        "{what}: error {err:e}\n got {got}\nwant {want}"
    );
}

fn closev(what: &str, got: &DVector<f64>, want: &DVector<f64>, rel: f64) {
    close(
        what,
        &DMatrix::from_column_slice(got.len(), 1, got.as_slice()),
        &DMatrix::from_column_slice(want.len(), 1, want.as_slice()),
        rel,
    );
}

/// Runs the general model at the case state and compares everything. `t` maps the
/// general reduced velocity to the chapter's, `p` the joint velocities to the chapter's
/// coordinates (identity except for m5).
fn compare(
    wm: &WheeledModel,
    case: &Value,
    q_joint: DVector<f64>,
    t: &DMatrix<f64>,
    p: &DMatrix<f64>,
    mass_key: &str,
) {
    let out = &case["outputs"];
    let v_ch = vector(&case["state"]["v"]);
    let u: Vec<f64> = vector(&case["inputs"]["u"]).iter().copied().collect();
    let v_r = t.clone().lu().solve(&v_ch).unwrap();
    let mut wd = WheeledData::new(wm);
    let tol = 1e-9;
    // Joint-space terms: H_j = Pᵀ H P, h_j = Pᵀ h, G_j = Pᵀ G.
    let qdot = {
        let mut n = DMatrix::zeros(wm.nv(), wm.nr());
        moma::mobile::admissible_velocity_basis(wm, &q_joint, &mut n);
        n * &v_r
    };
    let c_cor = coriolis_matrix(&wm.model, &mut wd.data, &q_joint, &qdot).clone();
    reduced_dynamics(wm, &mut wd, &q_joint, &v_r, &u, Some(&c_cor)).unwrap();
    let pt = p.transpose();
    close(
        "H",
        &wd.data.mass_matrix,
        &(&pt * matrix(&out[mass_key]) * p),
        tol,
    );
    let zero = DVector::zeros(p.nrows());
    let h_ref = out.get("h").map(vector).unwrap_or_else(|| zero.clone());
    let g_ref = out.get("G").map(vector).unwrap_or_else(|| zero.clone());
    let r = &wd.reduced;
    let tt = t.transpose();
    close("Mr", &r.mass_matrix, &(&tt * matrix(&out["Mr"]) * t), tol);
    close("Cr", &r.coriolis, &(&tt * matrix(&out["Cr"]) * t), tol);
    closev("cr", &r.velocity_terms, &(&tt * vector(&out["cr"])), tol);
    let gr_ref = out
        .get("Gr")
        .map(vector)
        .unwrap_or_else(|| DVector::zeros(t.nrows()));
    closev("Gr", &r.gravity, &(&tt * gr_ref), tol);
    closev("Qr", &r.force, &(&tt * vector(&out["Qr"])), tol);
    closev("vdot", &(t * &r.vdot), &vector(&out["vdot"]), tol);
    closev("qddot", &(p * &r.qddot), &vector(&out["qddot"]), tol);
    closev("lambda", &r.lambda, &vector(&out["lambda"]), tol);
    // Gravity and velocity terms of the full model.
    closev(
        "G",
        &moma::dynamics::gravity_torque(&wm.model, &mut wd.data, &q_joint).clone(),
        &(&pt * &g_ref),
        tol,
    );
    let nle = moma::dynamics::nonlinear_effects(&wm.model, &mut wd.data, &q_joint, &qdot).clone();
    closev("h + G", &nle, &(&pt * (&h_ref + &g_ref)), tol);
    // The fast path gives the same v̇ and λ.
    let v_r = DVector::from_column_slice(v_r.as_slice());
    let fast = reduced_forward_dynamics(wm, &mut wd, &q_joint, &v_r, &u)
        .unwrap()
        .clone();
    closev("vdot (fast path)", &(t * fast), &vector(&out["vdot"]), tol);
    let lam = lagrange_multipliers(wm, &mut wd, &q_joint).unwrap().clone();
    closev("lambda (fast path)", &lam, &vector(&out["lambda"]), tol);
}

fn t_platform(d: f64, n: usize) -> DMatrix<f64> {
    let mut t = DMatrix::identity(n, n);
    t[(1, 1)] = d;
    t
}

#[test]
fn m1_general_equals_chapter() {
    for case in load("m1_unicycle.json")["cases"].as_array().unwrap() {
        let p: UnicycleParams = serde_json::from_value(case["params"].clone()).unwrap();
        let wm = m1_model(&p).unwrap();
        compare(
            &wm,
            case,
            vector(&case["state"]["q"]),
            &t_platform(p.d, 2),
            &DMatrix::identity(3, 3),
            "M",
        );
    }
}

#[test]
fn m2_general_equals_chapter() {
    for case in load("m2_platform_planar_arm.json")["cases"]
        .as_array()
        .unwrap()
    {
        let p: PlatformArmParams = serde_json::from_value(case["params"].clone()).unwrap();
        let wm = m2_model(&p).unwrap();
        compare(
            &wm,
            case,
            vector(&case["state"]["q"]),
            &t_platform(p.d, 4),
            &DMatrix::identity(5, 5),
            "H",
        );
    }
}

#[test]
fn m5_general_equals_chapter() {
    for case in load("m5_mobile_manipulator_3d.json")["cases"]
        .as_array()
        .unwrap()
    {
        let p: MobileManipulatorParams = serde_json::from_value(case["params"].clone()).unwrap();
        let wm = m5_model(&p).unwrap();
        let pm = joint_to_absolute();
        let pm = DMatrix::from_fn(6, 6, |i, j| pm[(i, j)]);
        // v_ch = [v_F, v_T, φ̇t, θ̇1, θ̇12] from v_r = [v_F, ω, φ̇1, θ̇1, θ̇2].
        let mut t = DMatrix::zeros(5, 5);
        t[(0, 0)] = 1.0;
        t[(1, 1)] = p.d;
        t[(2, 1)] = 1.0;
        t[(2, 2)] = 1.0;
        t[(3, 3)] = 1.0;
        t[(4, 3)] = 1.0;
        t[(4, 4)] = -1.0;
        let qj = vector(&case["state"]["q_joint"]);
        close(
            "H_joint",
            &{
                let mut wd = WheeledData::new(&wm);
                moma::dynamics::crba(&wm.model, &mut wd.data, &qj).clone()
            },
            &matrix(&case["outputs"]["H_joint"]),
            1e-9,
        );
        compare(&wm, case, qj, &t, &pm, "H");
    }
}

#[test]
fn wheel_rate_kinematics_match_the_chapter_m3_reference() {
    use moma::mobile::wheeled::{frame_velocity_world, velocity_from_wheel_rates};
    let data = load("m3_diffdrive_kinematics.json");
    for case in data["cases"].as_array().unwrap() {
        let g = &case["params"];
        let f = |k: &str| g[k].as_f64().unwrap();
        // m3 is m5's geometry; masses are irrelevant to kinematics.
        let p: MobileManipulatorParams = serde_json::from_value(serde_json::json!({
            "M_cart": 20.0, "I_p": 2.0, "I_c": 0.01, "d": f("d"), "L": f("L"), "r_w": f("r_w"),
            "b": f("b"), "m1": 2.0, "m2": 1.5, "M1": 0.3, "M2": 0.2, "L1": f("L1"), "L2": f("L2"),
            "L1cm": 0.5 * f("L1"), "L2cm": 0.5 * f("L2"), "k1": 0.1, "k2": 0.1, "k1y": 0.05,
            "k2y": 0.05, "g": 9.81
        }))
        .unwrap();
        let wm = m5_model(&p).unwrap();
        let mut wd = WheeledData::new(&wm);
        let q = vector(&case["state"]["q"]);
        let rates = vector(&case["inputs"]["v"]);
        let mut qdot = DVector::zeros(wm.nv());
        velocity_from_wheel_rates(
            &wm,
            &q,
            [rates[0], rates[1]],
            &rates.as_slice()[2..],
            &mut qdot,
        );
        closev(
            "qdot from wheel rates",
            &qdot,
            &vector(&case["outputs"]["qdot"]),
            1e-12,
        );
        let xdot = vector(&case["outputs"]["Xdot"]);
        let b = frame_velocity_world(&wm, &mut wd, &q, &qdot, wm.model.frame_id("phi1").unwrap());
        assert!(
            (b[0] - xdot[0]).abs() < 1e-12 && (b[1] - xdot[1]).abs() < 1e-12,
            "B velocity"
        );
        assert!(b[2].abs() < 1e-12);
        let e = frame_velocity_world(&wm, &mut wd, &q, &qdot, wm.model.frame_id("tip").unwrap());
        for k in 0..3 {
            assert!(
                (e[k] - xdot[2 + k]).abs() < 1e-12,
                "E velocity {k}: {} vs {}",
                e[k],
                xdot[2 + k]
            );
        }
        // The arm base B is a platform point L ahead of the CM.
        let pb = moma::mobile::wheeled::platform_point_velocity(
            &wm.base.drive,
            q[2],
            [p.L, 0.0],
            [rates[0], rates[1]],
        );
        assert!((pb[0] - xdot[0]).abs() < 1e-12 && (pb[1] - xdot[1]).abs() < 1e-12);
    }
}

/// Closed form (chapter branch code) against the general multibody result at seeded
/// random states and perturbed parameters, beyond the reference cases.
#[test]
fn closed_forms_equal_the_general_model_at_random_states() {
    use moma::closed_form::lagrange::evaluate_constrained;
    use moma::closed_form::m2_platform_arm::PlatformArm;
    use moma::closed_form::m5_mobile_manipulator::MobileManipulator;
    use nalgebra::SVector;
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let m2_cases = load("m2_platform_planar_arm.json");
    let m5_cases = load("m5_mobile_manipulator_3d.json");
    for k in 0..10 {
        // m2
        let mut params = m2_cases["cases"][k % 5]["params"].clone();
        for (_, v) in params.as_object_mut().unwrap() {
            *v = serde_json::json!(v.as_f64().unwrap() * rng.random_range(0.8..1.25));
        }
        let p: PlatformArmParams = serde_json::from_value(params).unwrap();
        let cf = PlatformArm::new(p.clone()).unwrap();
        let wm = m2_model(&p).unwrap();
        let q = SVector::<f64, 5>::from_fn(|_, _| rng.random_range(-3.0..3.0));
        let v = SVector::<f64, 4>::from_fn(|_, _| rng.random_range(-1.0..1.0));
        let u = SVector::<f64, 4>::from_fn(|_, _| rng.random_range(-2.0..2.0));
        let ev = evaluate_constrained(&cf, &q, &v, &u).unwrap();
        let t = t_platform(p.d, 4);
        let qd = DVector::from_column_slice(q.as_slice());
        let vr = t
            .clone()
            .lu()
            .solve(&DVector::from_column_slice(v.as_slice()))
            .unwrap();
        let mut wd = WheeledData::new(&wm);
        reduced_dynamics(&wm, &mut wd, &qd, &vr, u.as_slice(), None).unwrap();
        let tt = t.transpose();
        let mr_cf = DMatrix::from_fn(4, 4, |i, j| ev.mr[(i, j)]);
        close("m2 Mr", &wd.reduced.mass_matrix, &(&tt * mr_cf * &t), 1e-10);
        let vd_cf = DVector::from_column_slice(ev.vdot.as_slice());
        closev("m2 vdot", &(&t * &wd.reduced.vdot), &vd_cf, 1e-10);
        assert!((wd.reduced.lambda[0] - ev.lambda).abs() < 1e-10 * (1.0 + ev.lambda.abs()));
        // m5 (joint coordinates on the general side)
        let mut params = m5_cases["cases"][k % 5]["params"].clone();
        for (name, v) in params.as_object_mut().unwrap() {
            if name != "g" {
                *v = serde_json::json!(v.as_f64().unwrap() * rng.random_range(0.8..1.25));
            }
        }
        let p: MobileManipulatorParams = serde_json::from_value(params).unwrap();
        let cf = MobileManipulator::new(p.clone()).unwrap();
        let wm = m5_model(&p).unwrap();
        let qj = DVector::from_fn(6, |_, _| rng.random_range(-3.0..3.0));
        let pm = joint_to_absolute();
        let q_abs = pm * SVector::<f64, 6>::from_column_slice(qj.as_slice());
        let v = SVector::<f64, 5>::from_fn(|_, _| rng.random_range(-1.0..1.0));
        let u = SVector::<f64, 5>::from_fn(|_, _| rng.random_range(-2.0..2.0));
        let ev = evaluate_constrained(&cf, &q_abs, &v, &u).unwrap();
        let mut t = DMatrix::zeros(5, 5);
        t[(0, 0)] = 1.0;
        t[(1, 1)] = p.d;
        t[(2, 1)] = 1.0;
        t[(2, 2)] = 1.0;
        t[(3, 3)] = 1.0;
        t[(4, 3)] = 1.0;
        t[(4, 4)] = -1.0;
        let vr = t
            .clone()
            .lu()
            .solve(&DVector::from_column_slice(v.as_slice()))
            .unwrap();
        let mut wd = WheeledData::new(&wm);
        reduced_dynamics(&wm, &mut wd, &qj, &vr, u.as_slice(), None).unwrap();
        let mr_cf = DMatrix::from_fn(5, 5, |i, j| ev.mr[(i, j)]);
        close(
            "m5 Mr",
            &wd.reduced.mass_matrix,
            &(t.transpose() * mr_cf * &t),
            1e-10,
        );
        let vd_cf = DVector::from_column_slice(ev.vdot.as_slice());
        closev("m5 vdot", &(&t * &wd.reduced.vdot), &vd_cf, 1e-9);
        assert!((wd.reduced.lambda[0] - ev.lambda).abs() < 1e-9 * (1.0 + ev.lambda.abs()));
        // Fast path too.
        let fast = reduced_forward_dynamics(&wm, &mut wd, &qj, &vr, u.as_slice())
            .unwrap()
            .clone();
        closev("m5 vdot (fast)", &(&t * fast), &vd_cf, 1e-9);
    }
}

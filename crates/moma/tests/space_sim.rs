//! Free-floating simulation: SpaceDyn's forward-dynamics run of the planar two-link arm
//! (RK4 at 1 ms and adaptive), momentum conservation of Panda as a free flyer over 10 s
//! (zero and non-zero momentum), the fixed CoM at zero linear momentum, the capture jump
//! (momentum equal before and after), and resolved-rate control through J*.

use moma::io::urdf::model_from_urdf_file;
use moma::kinematics::{self, ReferenceFrame};
use moma::multibody::{Data, Model, RootJoint};
use moma::sim::Rk4;
use moma::sim::free_floating::{
    self, FreeFloatingOde, TargetBody, capture, momentum_drift, resolved_rate,
};
use moma::space::{self, SpaceData};
use moma::spatial::Force;
use nalgebra::{DVector, Matrix3, Matrix6xX, Vector3};
use rand::SeedableRng;
use serde_json::Value;

fn data_dir() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

fn load_model(rel: &str) -> Model {
    let mut m = model_from_urdf_file(data_dir().join(rel), RootJoint::FreeFlyer).unwrap();
    m.gravity = Vector3::zeros();
    m
}

fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// Checks one recorded state of the planar robot against a SpaceDyn sample.
fn check_spacedyn(x: &[f64], s: &Value, tol: f64) {
    let nq = 9;
    let r0 = nums(&s["base_R0"]);
    let th = 2.0 * x[5].atan2(x[6]);
    let want_q = nums(&s["q"]);
    let want_qd = nums(&s["qd"]);
    let t = s["t"].as_f64().unwrap();
    let errs = [
        x[0] - r0[0],
        x[1] - r0[1],
        th - s["base_theta"].as_f64().unwrap(),
        x[7] - want_q[0],
        x[8] - want_q[1],
        x[nq + 6] - want_qd[0],
        x[nq + 7] - want_qd[1],
        x[nq + 5] - s["base_w0z"].as_f64().unwrap(),
    ];
    for (i, e) in errs.iter().enumerate() {
        assert!(e.abs() < tol, "t = {t}: component {i} off by {e:e}");
    }
}

#[test]
fn forward_dynamics_matches_spacedyn() {
    let doc: Value = serde_json::from_str(
        &std::fs::read_to_string(data_dir().join("space/spacedyn_fdyn_planar2link.json")).unwrap(),
    )
    .unwrap();
    let model = load_model("space/planar2link.urdf");
    let mut x = vec![0.0; model.nq + model.nv];
    x[6] = 1.0;
    x[7] = 0.3;
    x[8] = 0.6;
    let x0 = x.clone();
    let samples = doc["samples"].as_array().unwrap();
    // RK4, 1 ms, as SpaceDyn's f_dyn_rk2
    let mut ode = FreeFloatingOde::new(&model).unwrap();
    ode.torque = DVector::from_vec(vec![1.0, -0.5]);
    let mut rk = Rk4::new(x.len());
    let mut step = 0usize;
    for s in samples {
        let t = s["t"].as_f64().unwrap();
        let target = (t / 1e-3).round() as usize;
        while step < target {
            ode.rk4_step(&mut rk, step as f64 * 1e-3, &mut x, 1e-3)
                .unwrap();
            step += 1;
        }
        check_spacedyn(&x, s, 1e-9);
    }
    // adaptive DOP853
    let times: Vec<f64> = samples.iter().map(|s| s["t"].as_f64().unwrap()).collect();
    let q0 = DVector::from_column_slice(&x0[..model.nq]);
    let v0 = DVector::from_column_slice(&x0[model.nq..]);
    let tau = DVector::from_vec(vec![1.0, -0.5]);
    let run = free_floating::simulate(&model, &q0, &v0, &tau, &times, 1e-12).unwrap();
    for (r, s) in run.iter().zip(samples) {
        let x: Vec<f64> = r.q.iter().chain(r.v.iter()).copied().collect();
        check_spacedyn(&x, s, 1e-10);
        assert!(r.momentum.linear.norm() < 1e-11 && r.momentum.angular.norm() < 1e-11);
    }
}

fn panda_state(seed: u64, model: &Model) -> (DVector<f64>, Vec<f64>) {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let q = kinematics::random_configuration(model, &mut rng);
    let qd: Vec<f64> = (0..model.nv - 6)
        .map(|k| 0.4 * ((k as f64) * 0.7).sin())
        .collect();
    (q, qd)
}

#[test]
fn momentum_is_conserved_over_ten_seconds() {
    let model = load_model("pinocchio/urdf/panda.urdf");
    let mut data = Data::new(&model);
    let mut sd = SpaceData::new(&model).unwrap();
    let times: Vec<f64> = (0..=100).map(|k| k as f64 * 0.1).collect();
    for (seed, h) in [
        (1, Force::zero()),
        (
            2,
            Force::new(Vector3::new(0.5, -1.0, 0.2), Vector3::new(0.3, 0.1, -0.4)),
        ),
    ] {
        let (q, qd) = panda_state(seed, &model);
        space::base_velocity(&model, &mut data, &mut sd, &q, &qd, &h).unwrap();
        let v = sd.v.clone();
        // torques on the arm joints only (the light fingers would fly off)
        let tau = DVector::from_fn(model.nv - 6, |k, _| {
            if k < 7 {
                0.02 * (k as f64 - 3.0) / 3.0
            } else {
                0.0
            }
        });
        let run = free_floating::simulate(&model, &q, &v, &tau, &times, 1e-13).unwrap();
        let d = momentum_drift(&run, sd.total_mass);
        eprintln!("seed {seed}: {d:?}");

        assert!(d.linear < 1e-10 && d.angular < 1e-10, "seed {seed}: {d:?}");
        assert!(d.com < 1e-10, "seed {seed}: CoM {d:?}");
        // the base does move (the test is not vacuous)
        let last = run.last().unwrap();
        assert!((&last.q - &run[0].q).rows(0, 7).norm() > 1e-3);
        if h.linear.norm() == 0.0 {
            assert!((last.com - run[0].com).norm() < 1e-10);
        }
        for s in &run {
            let n: f64 = s.q.rows(3, 4).norm();
            assert!((n - 1.0).abs() < 1e-15);
        }
    }
}

#[test]
fn capture_conserves_momentum() {
    let model = load_model("pinocchio/urdf/panda.urdf");
    let mut data = Data::new(&model);
    let mut sd = SpaceData::new(&model).unwrap();
    let frame = model.frame_id("panda_hand_tcp").unwrap();
    let (q, qd) = panda_state(4, &model);
    let h = Force::new(Vector3::new(0.1, 0.0, -0.2), Vector3::new(0.0, 0.2, 0.1));
    space::base_velocity(&model, &mut data, &mut sd, &q, &qd, &h).unwrap();
    let v = sd.v.clone();
    let target = TargetBody {
        mass: 3.0,
        com_in_frame: Vector3::new(0.0, 0.0, 0.1),
        inertia_com: Matrix3::from_diagonal(&Vector3::new(0.02, 0.03, 0.04)),
        linear_velocity: Vector3::new(-0.3, 0.2, 0.1),
        angular_velocity: Vector3::new(0.1, -0.2, 0.3),
    };
    let c = capture(&model, &q, &v, frame, &target).unwrap();
    let db = c.momentum_before.to_vector();
    let da = c.momentum_after.to_vector();
    assert!((db - da).norm() < 1e-12, "{db} vs {da}");
    assert!((c.model.total_mass() - model.total_mass() - 3.0).abs() < 1e-12);
    // the velocity did jump, and the combined body's frame moves with the target's
    // rigid motion afterwards: simulation continues with the combined model
    assert!((&c.v - &v).norm() > 1e-3);
    let mut cm = c.model.clone();
    cm.gravity = Vector3::zeros();
    let run = free_floating::simulate(
        &cm,
        &q,
        &c.v,
        &DVector::zeros(cm.nv - 6),
        &[0.0, 1.0, 2.0],
        1e-12,
    )
    .unwrap();
    let d = momentum_drift(&run, cm.total_mass());
    assert!(d.linear < 1e-10 && d.angular < 1e-10);
}

#[test]
fn resolved_rate_through_the_generalized_jacobian() {
    // zero momentum: the joint rates from J*⁺ ẋ_d give exactly ẋ_d at the frame
    let model = load_model("pinocchio/urdf/panda.urdf");
    let mut data = Data::new(&model);
    let mut sd = SpaceData::new(&model).unwrap();
    let frame = model.frame_id("panda_hand_tcp").unwrap();
    let (q, _) = panda_state(6, &model);
    let xd = [0.05, -0.02, 0.03, 0.1, 0.0, -0.1];
    for h in [
        Force::zero(),
        Force::new(Vector3::new(0.2, 0.0, 0.0), Vector3::new(0.0, 0.0, 0.3)),
    ] {
        let qd = resolved_rate(
            &model,
            &mut data,
            &mut sd,
            &q,
            frame,
            &[0, 1, 2, 3, 4, 5],
            &xd,
            &h,
            0.0,
        )
        .unwrap();
        space::base_velocity(&model, &mut data, &mut sd, &q, qd.as_slice(), &h).unwrap();
        let v = sd.v.clone();
        let mut j = Matrix6xX::zeros(model.nv);
        kinematics::frame_jacobian(
            &model,
            &mut data,
            &q,
            frame,
            ReferenceFrame::LocalWorldAligned,
            &mut j,
        );
        let x = j * v;
        for i in 0..6 {
            assert!(
                (x[i] - xd[i]).abs() < 1e-10,
                "row {i}: {} vs {}",
                x[i],
                xd[i]
            );
        }
    }
}

fn settings(
    model: &Model,
    control: Option<free_floating::ResolvedRateControl>,
) -> free_floating::FloatingSettings {
    free_floating::FloatingSettings {
        frame: model.frame_id("panda_hand_tcp").unwrap(),
        duration: 6.0,
        record_interval: 0.05,
        integrator: moma::sim::settings::IntegratorSettings::adaptive(1e-10, 1e-10),
        torque: Vec::new(),
        joint_damping: 0.0,
        control,
        capture: None,
    }
}

fn start(model: &Model, h: &Force) -> (DVector<f64>, DVector<f64>) {
    let mut q = kinematics::neutral(model);
    for (k, x) in [0.0, -0.3, 0.0, -2.0, 0.0, 1.8, 0.8, 0.02, 0.02]
        .iter()
        .enumerate()
    {
        q[7 + k] = *x;
    }
    let mut data = Data::new(model);
    let mut sd = SpaceData::new(model).unwrap();
    space::base_velocity(model, &mut data, &mut sd, &q, &[0.0; 9], h).unwrap();
    (q, sd.v.clone())
}

fn base_rotation(run: &free_floating::FloatingRun) -> f64 {
    let a = free_floating::base_attitude(&run.samples[0].q);
    let b = free_floating::base_attitude(&run.samples.last().unwrap().q);
    a.angle_to(&b)
}

#[test]
fn controlled_runs_reach_the_goal_and_keep_the_momentum() {
    let model = load_model("pinocchio/urdf/panda.urdf");
    let goal = Vector3::new(0.45, 0.25, 0.45);
    let ctl = |dc: bool, rns: bool| free_floating::ResolvedRateControl {
        target: goal,
        gain: 1.5,
        damping: 0.0,
        drift_compensation: dc,
        reaction_null_space: rns,
    };
    // zero momentum: plain resolved rate through J* converges while the base turns
    let (q, v) = start(&model, &Force::zero());
    let rr =
        free_floating::run(&model, &q, &v, &settings(&model, Some(ctl(false, false)))).unwrap();
    let err0 = (rr.frame_positions[0] - goal).norm();
    let err = (rr.frame_positions.last().unwrap() - goal).norm();
    assert!(err < 1e-3 * err0, "resolved rate: {err0} → {err}");
    assert!(rr.drift[0].linear < 1e-12 && rr.drift[0].angular < 1e-12 && rr.drift[0].com < 1e-9);
    let rot_rr = base_rotation(&rr);
    assert!(rot_rr > 1e-3, "the base does turn: {rot_rr}");
    // reaction null space: same goal, less base rotation
    let rns =
        free_floating::run(&model, &q, &v, &settings(&model, Some(ctl(false, true)))).unwrap();
    let err = (rns.frame_positions.last().unwrap() - goal).norm();
    assert!(err < 1e-3 * err0, "RNS: {err0} → {err}");
    let rot_rns = base_rotation(&rns);
    assert!(rot_rns < 0.5 * rot_rr, "RNS {rot_rns} vs plain {rot_rr}");
    // non-zero momentum: the drift is a disturbance unless cancelled (5.145)
    let h = Force::new(Vector3::zeros(), Vector3::new(0.0, 0.0, 0.8));
    let (q, v) = start(&model, &h);
    let with =
        free_floating::run(&model, &q, &v, &settings(&model, Some(ctl(true, false)))).unwrap();
    let without =
        free_floating::run(&model, &q, &v, &settings(&model, Some(ctl(false, false)))).unwrap();
    let e_with = (with.frame_positions.last().unwrap() - goal).norm();
    let e_without = (without.frame_positions.last().unwrap() - goal).norm();
    assert!(e_with < 1e-3 * err0, "decoupled: {e_with}");
    assert!(
        e_without > 100.0 * e_with,
        "uncompensated {e_without} vs {e_with}"
    );
    assert!(with.drift[0].angular < 1e-12);
}

#[test]
fn approach_capture_post_capture() {
    let model = load_model("pinocchio/urdf/panda.urdf");
    let (q, mut v) = start(&model, &Force::zero());
    for (k, x) in [0.2, 0.1, 0.0, 0.15, 0.0, -0.1, 0.0].iter().enumerate() {
        v[6 + k] = *x;
    }
    let mut s = settings(&model, None);
    s.duration = 4.0;
    s.integrator = moma::sim::settings::IntegratorSettings::adaptive(1e-12, 1e-12);
    s.joint_damping = 0.5;
    s.capture = Some(free_floating::CaptureEvent {
        time: 1.5,
        target: TargetBody {
            mass: 4.0,
            com_in_frame: Vector3::new(0.0, 0.0, 0.08),
            inertia_com: Matrix3::from_diagonal(&Vector3::new(0.03, 0.03, 0.02)),
            linear_velocity: Vector3::new(-0.1, 0.05, 0.0),
            angular_velocity: Vector3::new(0.0, 0.2, 0.4),
        },
    });
    let run = free_floating::run(&model, &q, &v, &s).unwrap();
    let c = run.capture.as_ref().unwrap();
    assert!((c.momentum_before.to_vector() - c.momentum_after.to_vector()).norm() < 1e-12);
    assert_eq!(run.drift.len(), 2);
    for d in &run.drift {
        assert!(
            d.linear < 1e-10 && d.angular < 1e-10 && d.com < 1e-9,
            "{d:?}"
        );
    }
    // after the capture the combined system carries the target's momentum
    let last = run.samples.last().unwrap();
    assert!((last.momentum.linear - c.momentum_after.linear).norm() < 1e-10);
    assert!(last.momentum.linear.norm() > 0.1);
    // joint damping brought the arm to rest relative to the base
    assert!(
        last.v.rows(6, 9).norm() < 0.15 * v.rows(6, 9).norm(),
        "{}",
        last.v.rows(6, 9).norm()
    );
}

/// A free-floating run has one step budget for all its phases: the capture run whose
/// two phases take `n` DOP853 steps in all stops inside its second phase when the
/// budget is one step short of them.
#[test]
fn the_step_budget_spans_both_phases_of_a_capture() {
    let model = load_model("pinocchio/urdf/panda.urdf");
    let (q, v) = start(&model, &Force::zero());
    let mut s = settings(&model, None);
    s.duration = 2.0;
    s.integrator = moma::sim::settings::IntegratorSettings::adaptive(1e-8, 1e-8);
    s.capture = Some(free_floating::CaptureEvent {
        time: 0.5,
        target: TargetBody {
            mass: 4.0,
            com_in_frame: Vector3::new(0.0, 0.0, 0.08),
            inertia_com: Matrix3::from_diagonal(&Vector3::new(0.03, 0.03, 0.02)),
            linear_velocity: Vector3::new(-0.1, 0.05, 0.0),
            angular_velocity: Vector3::new(0.0, 0.2, 0.4),
        },
    });
    let n = free_floating::run(&model, &q, &v, &s).unwrap().steps as u64;
    let moma::sim::settings::IntegratorSettings::Adaptive { max_steps, .. } = &mut s.integrator
    else {
        unreachable!()
    };
    *max_steps = Some(n - 1);
    let err = free_floating::run(&model, &q, &v, &s).unwrap_err();
    let moma::Error::Numerical { t, message } = &err else {
        panic!("{err}")
    };
    assert!(*t > 0.5 && *t < 2.0, "{err}");
    assert!(
        message.contains("DOP853") && message.contains(&format!("step budget of {} steps", n - 1)),
        "{err}"
    );
}

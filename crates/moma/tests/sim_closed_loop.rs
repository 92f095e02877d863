//! The closed-loop simulator: the chapter's task-space laws on m5 against the reference
//! closed loop, exact-model computed torque and reduced OSC on a URDF arm on a
//! differential drive against the analytic second-order error, the unicycle laws driving
//! a wheeled URDF robot dynamically, the zero-order hold, saturation reports and
//! Lyapunov monitors.

use moma::closed_form::m5_mobile_manipulator::{MobileManipulator, MobileManipulatorParams};
use moma::control::pursuit::{PurePursuit, PurePursuitParams};
use moma::control::task::Coupling;
use moma::control::unicycle::{Aicardi, Astolfi, ConstantInputReference, Kanayama, Samson};
use moma::io::urdf::model_from_urdf_file;
use moma::mobile::{DiffDrive, WheeledBase, WheeledModel};
use moma::multibody::RootJoint;
use moma::sim::chapter_models::m5;
use moma::sim::closed_loop::{ClosedLoopOptions, ClosedLoopResult, simulate_closed_loop};
use moma::sim::feedback::{
    M5TaskController, OscController, OscGains, PlatformController, PlatformLaw, PointReference,
    TaskLaw, TrackingReference, VelocityServo,
};
use moma::sim::monitor::MonitorLimits;
use moma::sim::settings::IntegratorSettings;
use moma::sim::wheeled_system::WheeledSystem;
use serde_json::Value;

fn data(path: &str) -> String {
    format!("{}/tests/data/{path}", env!("CARGO_MANIFEST_DIR"))
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn arr5(v: &Value) -> [f64; 5] {
    floats(v).try_into().unwrap()
}

fn diag5(v: &Value) -> [f64; 5] {
    let rows = v.as_array().unwrap();
    std::array::from_fn(|i| rows[i][i].as_f64().unwrap())
}

fn options(
    duration: f64,
    period: Option<f64>,
    integrator: IntegratorSettings,
) -> ClosedLoopOptions {
    ClosedLoopOptions {
        duration,
        integrator,
        control_period: period,
        record_interval: 0.005,
        limits: MonitorLimits::default(),
        lyapunov_tolerance: 1e-12,
    }
}

fn adaptive(tol: f64) -> IntegratorSettings {
    IntegratorSettings::adaptive(tol, tol)
}

fn m5_case() -> Value {
    let doc: Value = serde_json::from_str(
        &std::fs::read_to_string(data("chapter/m5_mobile_manipulator_3d.json")).unwrap(),
    )
    .unwrap();
    doc["cases"][0].clone()
}

fn m5_controller(case: &Value, law: TaskLaw) -> M5TaskController {
    let params: MobileManipulatorParams = serde_json::from_value(case["params"].clone()).unwrap();
    let c = &case["control"];
    M5TaskController::new(
        MobileManipulator::new(params).unwrap(),
        law,
        arr5(&c["x_ref"]),
        arr5(&c["amp"]),
        arr5(&c["omega"]),
        diag5(&c["Kp"]),
        diag5(&c["Kd"]),
        None,
    )
    .unwrap()
}

fn run_m5(law: TaskLaw, duration: f64, period: Option<f64>) -> (ClosedLoopResult, Value) {
    let case = m5_case();
    let params: MobileManipulatorParams = serde_json::from_value(case["params"].clone()).unwrap();
    let mut plant = m5(params).unwrap();
    let mut ctl = m5_controller(&case, law);
    let c = &case["control"];
    let res = simulate_closed_loop(
        &mut plant,
        &mut ctl,
        &floats(&c["q0"]),
        &floats(&c["v0"]),
        &options(duration, period, adaptive(1e-11)),
        None,
        &mut |_| {},
    )
    .unwrap();
    (res, case)
}

/// PD+ (5.122 corrected) on m5 in the closed-loop simulator reproduces the reference
/// closed loop (an independent computation): q, v, e and W at t = 0.5 and 1; W never
/// increases and its rate is −ėᵀ Kd ė.
#[test]
fn m5_pd_plus_matches_the_reference_closed_loop() {
    let (res, case) = run_m5(TaskLaw::PdPlus, 1.0, None);
    let cl = &case["control"]["closed_loop"];
    let rec = &res.recorder;
    for (k, t) in floats(&cl["t"]).iter().enumerate() {
        let i = rec
            .times
            .iter()
            .position(|s| (s - t).abs() < 1e-12)
            .unwrap();
        for (a, b) in rec.q_row(i).iter().zip(floats(&cl["q"][k])) {
            assert!((a - b).abs() < 1e-8, "q at {t}: {a} vs {b}");
        }
        for (a, b) in rec.v_row(i).iter().zip(floats(&cl["v"][k])) {
            assert!((a - b).abs() < 1e-8, "v at {t}: {a} vs {b}");
        }
        for (a, b) in res.error_row(i).iter().zip(floats(&cl["e"][k])) {
            assert!((a - b).abs() < 1e-8, "e at {t}: {a} vs {b}");
        }
        let w = cl["W"][k].as_f64().unwrap();
        assert!((res.lyapunov[i] - w).abs() < 1e-8, "W at {t}");
    }
    let rep = res.lyapunov_report.unwrap();
    assert!(rep.monotone(), "{:?}", rep.violations);
    // V − V₀ − ∫V̇ by the trapezoidal rule on 5 ms samples: quadrature error only
    assert!(
        rep.max_integral_error.unwrap() < 1e-4 * rep.v_first,
        "{rep:?}"
    );
}

/// Exact-model task-space computed torque and the compensated decoupled law on m5:
/// every task coordinate's error is the analytic solution of `ë + K_v ė + K_p e = 0`; the
/// naive decoupled law departs from it (the coupling it drops is visible).
#[test]
fn m5_computed_torque_and_decoupling_errors_are_analytic() {
    let case = m5_case();
    let c = &case["control"];
    let (kp, kd) = (diag5(&c["Kp"]), diag5(&c["Kd"]));
    let e0 = floats(&c["e0"]);
    let ed0 = floats(&c["edot0"]);
    // e = x − x_d obeys ë + kd ė + kp e = 0 (real distinct or complex roots)
    let analytic = |k: usize, t: f64| {
        let (a, b) = (kd[k], kp[k]);
        let disc = a * a - 4.0 * b;
        if disc > 0.0 {
            let s = disc.sqrt();
            let (r1, r2) = (0.5 * (-a + s), 0.5 * (-a - s));
            let c2 = (ed0[k] - r1 * e0[k]) / (r2 - r1);
            let c1 = e0[k] - c2;
            c1 * (r1 * t).exp() + c2 * (r2 * t).exp()
        } else {
            let w = (-disc).sqrt() * 0.5;
            let s = -0.5 * a;
            (s * t).exp() * (e0[k] * (w * t).cos() + (ed0[k] - s * e0[k]) / w * (w * t).sin())
        }
    };
    let mut worst = Vec::new();
    for law in [
        TaskLaw::ComputedTorque,
        TaskLaw::Decoupled(Coupling::Compensated),
        TaskLaw::Decoupled(Coupling::Naive),
    ] {
        let (res, _) = run_m5(law, 1.0, None);
        let mut w = 0.0f64;
        for (i, &t) in res.recorder.times.iter().enumerate() {
            for (k, e) in res.error_row(i).iter().enumerate() {
                w = w.max((e - analytic(k, t)).abs());
            }
        }
        worst.push(w);
    }
    assert!(worst[0] < 1e-8, "computed torque: {}", worst[0]);
    assert!(worst[1] < 1e-8, "compensated: {}", worst[1]);
    assert!(
        worst[2] > 1e-4,
        "naive should show the coupling: {}",
        worst[2]
    );
}

/// Under a zero-order hold the loop is sampled at the control ticks (inputs constant
/// between them), and a coarse hold degrades tracking against continuous feedback.
#[test]
fn zero_order_hold_samples_at_the_ticks() {
    let (cont, _) = run_m5(TaskLaw::ComputedTorque, 1.0, None);
    let (held, _) = run_m5(TaskLaw::ComputedTorque, 1.0, Some(0.01));
    assert_eq!(held.control_ticks, 100);
    assert_eq!(held.control_period, Some(0.01));
    assert_eq!(held.recorder.times.len(), 101);
    let last = held.recorder.len() - 1;
    let (a, b) = (held.error_row(last), cont.error_row(last));
    let gap: f64 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(gap > 1e-9 && gap < 1e-2, "hold vs continuous: {gap}");
    // the energy balance holds for held inputs as well
    assert!(held.monitor.relative_energy_error() < 1e-8);
}

fn panda_on_diff_drive() -> WheeledModel {
    let model = model_from_urdf_file(data("pinocchio/urdf/panda.urdf"), RootJoint::Planar).unwrap();
    WheeledModel::new(
        model,
        WheeledBase::new(DiffDrive::new(0.1, 0.3, 0.2).unwrap()),
    )
    .unwrap()
}

/// Reduced OSC on a URDF arm (Panda) on a differential drive, continuous feedback on the
/// exact model: the tip's position error is the analytic critically damped solution
/// `e(t) = (e0 + (ė0 + λ e0) t) e^{−λt}` although a null-space posture torque acts all
/// along (it does not reach the task: dynamic consistency through N_C), and V decreases
/// at the analytic rate.
fn osc_panda_run(posture_kp: f64) -> ClosedLoopResult {
    let wm = panda_on_diff_drive();
    let q0: Vec<f64> = vec![
        0.0, 0.0, 0.3, 0.1, -0.4, 0.2, -2.0, 0.1, 1.8, 0.7, 0.01, 0.01,
    ];
    let mut v0 = vec![0.0; wm.nr()];
    v0[0] = 0.1;
    v0[3] = 0.2;
    let lam = 4.0;
    let gains = OscGains {
        kp: lam * lam,
        kv: 2.0 * lam,
        posture_kp,
        posture_kd: 2.0,
    };
    let posture = vec![0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8, 0.02, 0.02];
    let reference = PointReference::Circle {
        center: [0.55, 0.1, 0.55],
        radius: 0.1,
        period: 4.0,
        phase: 0.0,
    };
    let mut ctl = OscController::new(
        wm.clone(),
        "panda_hand_tcp",
        reference.clone(),
        gains,
        posture,
        None,
    )
    .unwrap();
    let mut plant = WheeledSystem::new(wm);
    let res = simulate_closed_loop(
        &mut plant,
        &mut ctl,
        &q0,
        &v0,
        &options(1.0, None, adaptive(1e-11)),
        None,
        &mut |_| {},
    )
    .unwrap();
    let e0 = res.error_row(0).to_vec();
    let ee0: f64 = e0.iter().map(|e| e * e).sum();
    let v_first = res.lyapunov[0];
    // Fit-free check: e(t) e^{λt} is affine in t, so its second difference vanishes.
    let n = res.recorder.len();
    let g: Vec<Vec<f64>> = (0..n)
        .map(|i| {
            let t = res.recorder.times[i];
            res.error_row(i)
                .iter()
                .map(|e| e * (lam * t).exp())
                .collect()
        })
        .collect();
    let h = 0.005;
    let mut worst = 0.0f64;
    for i in 1..n - 1 {
        for k in 0..3 {
            worst = worst.max(((g[i + 1][k] - 2.0 * g[i][k] + g[i - 1][k]) / (h * h)).abs());
        }
    }
    assert!(worst < 1e-6, "e(t)·e^(λt) not affine: {worst}");
    assert!(ee0 > 1e-4, "the run must start with an error");
    let rep = res.lyapunov_report.clone().unwrap();
    assert!(rep.monotone(), "{:?}", rep.violations);
    assert!(rep.max_integral_error.unwrap() < 1e-4 * v_first, "{rep:?}");
    res
}

#[test]
fn reduced_osc_on_a_urdf_arm_on_the_platform_is_exact() {
    let with_posture = osc_panda_run(5.0);
    let without = osc_panda_run(0.0);
    // the posture torque changed the motion of the arm ...
    let last = with_posture.recorder.len() - 1;
    let dq: f64 = with_posture
        .recorder
        .q_row(last)
        .iter()
        .zip(without.recorder.q_row(last))
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(dq > 1e-3, "posture torque had no effect: {dq}");
    // ... but not the task error
    for i in 0..=last {
        for (a, b) in with_posture.error_row(i).iter().zip(without.error_row(i)) {
            assert!((a - b).abs() < 1e-8, "sample {i}: {a} vs {b}");
        }
    }
}

fn diffdrive_arm() -> WheeledModel {
    let model = model_from_urdf_file(data("mobile/diffdrive_arm.urdf"), RootJoint::Planar).unwrap();
    let mut base = WheeledBase::new(DiffDrive::new(0.08, 0.25, 0.1).unwrap());
    base.wheel_joints = Some(["left_wheel_joint".into(), "right_wheel_joint".into()]);
    WheeledModel::new(model, base).unwrap()
}

fn run_platform(
    law: PlatformLaw,
    q0: &[f64],
    duration: f64,
    max_speed: Option<f64>,
    max_torque: Option<f64>,
) -> ClosedLoopResult {
    let wm = diffdrive_arm();
    let arm: Vec<f64> = wm.arm_dofs().iter().map(|&d| q0[d]).collect();
    let mut ctl = PlatformController::new(
        wm.clone(),
        law,
        VelocityServo {
            gain: 20.0,
            arm_kp: 100.0,
            arm_kd: 20.0,
        },
        arm,
        max_speed,
        max_torque,
    )
    .unwrap();
    let mut plant = WheeledSystem::new(wm);
    let nr = plant.robot.nr();
    simulate_closed_loop(
        &mut plant,
        &mut ctl,
        q0,
        &vec![0.0; nr],
        &ClosedLoopOptions {
            record_interval: 0.1,
            ..options(duration, Some(0.01), IntegratorSettings::rk4(0.002))
        },
        None,
        &mut |_| {},
    )
    .unwrap()
}

fn q_start(x: f64, y: f64, th: f64) -> Vec<f64> {
    // [x, y, θ, left wheel, right wheel, turret, shoulder, elbow]
    let d = 0.1;
    // the axle midpoint at (x, y): the base origin is d ahead of it
    vec![
        x + d * th.cos(),
        y + d * th.sin(),
        th,
        0.0,
        0.0,
        0.0,
        2.8,
        0.3,
    ]
}

fn last_error(res: &ClosedLoopResult) -> Vec<f64> {
    res.error_row(res.recorder.len() - 1).to_vec()
}

/// Every unicycle law and pure pursuit drives the wheeled URDF robot (tracked wheels,
/// three-joint arm) to its goal or reference through the inner computed-torque loop.
#[test]
fn unicycle_laws_drive_the_wheeled_urdf_robot() {
    let kan = run_platform(
        PlatformLaw::Kanayama(
            Kanayama::new(1.0, 4.0, 4.0).unwrap(),
            TrackingReference::Constant(ConstantInputReference { vr: 0.4, wr: 0.2 }),
        ),
        &q_start(-0.3, 0.2, 0.3),
        12.0,
        None,
        None,
    );
    let e = last_error(&kan);
    assert!(e.iter().all(|x| x.abs() < 2e-3), "kanayama {e:?}");
    let rep = kan.lyapunov_report.as_ref().unwrap();
    assert!(rep.v_last < 1e-3 * rep.v_first, "{rep:?}");
    let goal = [0.0, 0.0, 0.0];
    let ast = run_platform(
        PlatformLaw::Astolfi(Astolfi::new(0.6, 2.0, -0.5).unwrap(), goal),
        &q_start(-1.5, -0.8, 0.4),
        25.0,
        None,
        None,
    );
    let e = last_error(&ast);
    assert!(e.iter().all(|x| x.abs() < 1e-2), "astolfi {e:?}");
    assert!(ast.lyapunov_report.is_none());
    let aic = run_platform(
        PlatformLaw::Aicardi(Aicardi::new(0.6, 1.5, 1.0).unwrap(), goal),
        &q_start(-1.5, -0.8, 0.4),
        25.0,
        None,
        None,
    );
    let e = last_error(&aic);
    assert!(e.iter().all(|x| x.abs() < 1e-2), "aicardi {e:?}");
    let sam = run_platform(
        PlatformLaw::Samson(Samson::new(1.0, 2.0, 1.0).unwrap(), goal),
        &q_start(-0.4, 0.3, 0.5),
        30.0,
        None,
        None,
    );
    let rep = sam.lyapunov_report.as_ref().unwrap();
    // slow, not exponential: V halves in 30 s, and never rises
    assert!(
        rep.v_last < 0.6 * rep.v_first && rep.monotone(),
        "samson {rep:?}"
    );
    let path = vec![[0.0, 0.0], [1.5, 0.0], [1.5, 1.5]];
    let pp = run_platform(
        PlatformLaw::PurePursuit(
            Box::new(PurePursuit::new(PurePursuitParams::default()).unwrap()),
            path,
        ),
        &q_start(0.0, 0.1, 0.0),
        15.0,
        None,
        None,
    );
    let e = last_error(&pp);
    assert!(
        e[1] <= 0.3,
        "pure pursuit should end within the goal tolerance: {e:?}"
    );
    let worst_cross = (0..pp.recorder.len())
        .map(|i| pp.error_row(i)[0])
        .fold(0.0, f64::max);
    assert!(worst_cross < 0.3, "cross-track {worst_cross}");
}

/// Wheel-speed and wheel-torque limits act through the wheel map and are reported with
/// their first time; under tight torque limits V is no longer monotone and the monitor
/// says when.
#[test]
fn saturation_and_lyapunov_violations_are_reported() {
    let law = || {
        PlatformLaw::Kanayama(
            Kanayama::new(1.0, 4.0, 4.0).unwrap(),
            TrackingReference::Constant(ConstantInputReference { vr: 0.6, wr: 0.3 }),
        )
    };
    let free = run_platform(law(), &q_start(-0.5, 0.4, 0.6), 6.0, None, None);
    assert_eq!(free.saturation.speed + free.saturation.torque, 0);
    let limited = run_platform(law(), &q_start(-0.5, 0.4, 0.6), 6.0, Some(6.0), Some(0.3));
    let s = limited.saturation;
    assert!(s.speed > 0 && s.first_speed.is_some(), "{s:?}");
    assert!(s.torque > 0 && s.first_torque == Some(0.0), "{s:?}");
    for i in 0..limited.recorder.len() {
        let u = limited.recorder.u_row(i);
        assert!(u[0].abs() <= 0.3 + 1e-12 && u[1].abs() <= 0.3 + 1e-12);
    }
    let rep = limited.lyapunov_report.as_ref().unwrap();
    assert!(!rep.monotone());
    assert!(rep.violations[0].t > 0.0);
}

fn osc_fixed_run(posture_kp: f64) -> ClosedLoopResult {
    use moma::sim::feedback::FixedOscController;
    use moma::sim::fixed_base::FixedBaseSystem;
    let model = model_from_urdf_file(data("pinocchio/urdf/panda.urdf"), RootJoint::Fixed).unwrap();
    let q0 = vec![0.1, -0.4, 0.2, -2.0, 0.1, 1.8, 0.7, 0.01, 0.01];
    let mut v0 = vec![0.0; model.nv];
    v0[1] = 0.2;
    let lam = 5.0;
    let gains = OscGains {
        kp: lam * lam,
        kv: 2.0 * lam,
        posture_kp,
        posture_kd: 1.0,
    };
    let posture = vec![0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8, 0.02, 0.02];
    let reference = PointReference::Line {
        from: [0.4, -0.1, 0.4],
        to: [0.5, 0.2, 0.6],
        duration: 1.0,
    };
    let mut ctl = FixedOscController::new(
        model.clone(),
        "panda_hand_tcp",
        reference,
        gains,
        posture,
        None,
    )
    .unwrap();
    let mut plant = FixedBaseSystem::new(model).unwrap();
    simulate_closed_loop(
        &mut plant,
        &mut ctl,
        &q0,
        &v0,
        &options(1.0, None, adaptive(1e-11)),
        None,
        &mut |_| {},
    )
    .unwrap()
}

/// Fixed-base OSC (Panda) in closed loop on the exact model: the tool point's error is
/// the critically damped analytic solution, and the null-space posture torque changes
/// the arm's motion but not the task error (J H⁻¹ Nᵀ τ₀ = 0 along the run).
#[test]
fn fixed_base_osc_error_is_the_analytic_solution() {
    let lam = 5.0;
    let a = osc_fixed_run(8.0);
    let b = osc_fixed_run(0.0);
    let n = a.recorder.len();
    let h = 0.005;
    let mut worst = 0.0f64;
    for i in 1..n - 1 {
        for k in 0..3 {
            let g = |j: usize| a.error_row(j)[k] * (lam * a.recorder.times[j]).exp();
            worst = worst.max(((g(i + 1) - 2.0 * g(i) + g(i - 1)) / (h * h)).abs());
        }
    }
    assert!(worst < 1e-6, "e(t)·e^(λt) not affine: {worst}");
    assert!(a.error_row(0).iter().any(|e| e.abs() > 1e-2));
    let dq = a
        .recorder
        .q_row(n - 1)
        .iter()
        .zip(b.recorder.q_row(n - 1))
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    assert!(dq > 1e-3, "{dq}");
    for i in 0..n {
        for (x, y) in a.error_row(i).iter().zip(b.error_row(i)) {
            assert!((x - y).abs() < 1e-8);
        }
    }
    assert!(a.lyapunov_report.as_ref().unwrap().monotone());
    assert!(a.monitor.relative_energy_error() < 1e-8);
}

//! Coordinated base/arm control (theory section 2.6) of a wheeled URDF robot in closed
//! loop: the turret and the elbow of the arm are coordinated with the differential drive
//! while the end effector follows a line that leaves the arm's reach from the start.

use moma::io::urdf::model_from_urdf_file;
use moma::mobile::{DiffDrive, WheeledBase, WheeledModel};
use moma::multibody::RootJoint;
use moma::sim::closed_loop::{ClosedLoopOptions, ClosedLoopResult, simulate_closed_loop};
use moma::sim::coordinated::{CoordinatedController, CoordinatedGains};
use moma::sim::feedback::{PointReference, VelocityServo};
use moma::sim::monitor::MonitorLimits;
use moma::sim::settings::IntegratorSettings;
use moma::sim::wheeled_system::WheeledSystem;

fn data(path: &str) -> String {
    format!("{}/tests/data/{path}", env!("CARGO_MANIFEST_DIR"))
}

fn robot() -> WheeledModel {
    let model = model_from_urdf_file(data("mobile/diffdrive_arm.urdf"), RootJoint::Planar).unwrap();
    let mut base = WheeledBase::new(DiffDrive::new(0.08, 0.25, 0.1).unwrap());
    base.wheel_joints = Some(["left_wheel_joint".into(), "right_wheel_joint".into()]);
    WheeledModel::new(model, base).unwrap()
}

/// Preferred posture: turret ahead, shoulder leaning 0.8 rad forward, elbow −0.2 rad
/// (near the largest |det| of the turret/elbow horizontal Jacobian for this shoulder).
const POSTURE: [f64; 3] = [0.0, 0.8, -0.2];
/// Start: arm away from the preferred posture.
const Q0: [f64; 8] = [0.0, 0.0, 0.0, 0.0, 0.0, 0.3, 0.8, 0.3];
const LINE_END: [f64; 3] = [2.6, 0.6, 0.0];

fn controller(max_wheel_speed: Option<f64>) -> CoordinatedController {
    CoordinatedController::new(
        robot(),
        "tool",
        ["turret_joint", "elbow_joint"],
        PointReference::Line {
            from: [0.6, 0.1, 0.0],
            to: LINE_END,
            duration: 10.0,
        },
        CoordinatedGains { k_e: 2.0, k_y: 1.0 },
        POSTURE.to_vec(),
        VelocityServo {
            gain: 20.0,
            arm_kp: 100.0,
            arm_kd: 20.0,
        },
        max_wheel_speed,
        None,
    )
    .unwrap()
}

fn run(ctl: &mut CoordinatedController, duration: f64) -> ClosedLoopResult {
    let mut plant = WheeledSystem::new(robot());
    let nr = plant.robot.nr();
    simulate_closed_loop(
        &mut plant,
        ctl,
        &Q0,
        &vec![0.0; nr],
        &ClosedLoopOptions {
            duration,
            integrator: IntegratorSettings::rk4(0.002),
            control_period: Some(0.01),
            record_interval: 0.02,
            limits: MonitorLimits::default(),
            lyapunov_tolerance: 1e-9,
        },
        None,
        &mut |_| {},
    )
    .unwrap()
}

#[test]
fn end_effector_tracks_a_line_beyond_the_arms_reach_with_the_arm_kept_near_its_preferred_posture() {
    let mut ctl = controller(None);
    let w_star = ctl.preferred_manipulability();
    let y_star = ctl.y_star();
    let r = run(&mut ctl, 12.0);
    let rec = &r.recorder;
    // The line ends 2.4 m from where the turret starts (0.25 m ahead of the axle): three
    // times the arm's length (0.4 + 0.3 m), so a fixed-base arm could not follow it.
    let reach = 0.7;
    let from_turret = (LINE_END[0] - 0.25).hypot(LINE_END[1]);
    assert!(from_turret > 3.0 * reach, "{from_turret}");
    // y* is the preferred posture's end effector seen from the axle (turret 0.25 m ahead)
    assert!((y_star[0] - 0.25 - (0.4 * 0.8f64.sin() + 0.3 * 0.6f64.sin())).abs() < 1e-9);
    assert!(y_star[1].abs() < 1e-12);
    let mut worst_e = 0.0f64;
    let mut worst_y = 0.0f64;
    let mut min_w = f64::INFINITY;
    for i in 0..rec.len() {
        let t = rec.times[i];
        let e = r.error_row(i);
        if t >= 2.0 {
            worst_e = worst_e.max(e[0].hypot(e[1]));
            min_w = min_w.min(r.signal_row(i)[0]);
        }
        if t >= 3.0 {
            worst_y = worst_y.max(e[2].hypot(e[3]));
        }
    }
    // tracking while the line is driven (the inner loop's lag: a few mm) and at the end
    assert!(worst_e < 5e-3, "end-effector error {worst_e}");
    let last = rec.len() - 1;
    let e = r.error_row(last);
    assert!(e[0].hypot(e[1]) < 1e-4, "final error {e:?}");
    // the platform keeps the arm at its preferred posture: y → y*, manipulability ≈ w*
    assert!(worst_y < 1e-2, "relative output error {worst_y}");
    assert!(
        min_w > 0.95 * w_star,
        "manipulability {min_w} vs preferred {w_star}"
    );
    // the start posture is less manipulable than the preferred one
    assert!(r.signal_row(0)[0] < 0.7 * w_star);
    // the platform drove: the axle moved by about the line's length
    let q = rec.q_row(last);
    assert!(q[0].hypot(q[1]) > 1.9, "{q:?}");
    // heading: the zero dynamics settle on the line's direction (stable forward)
    let dir = (LINE_END[1] - 0.1).atan2(LINE_END[0] - 0.6);
    assert!((q[2] - dir).abs() < 0.01, "heading {} vs {dir}", q[2]);
    // V of the kinematic law falls by six orders of magnitude
    let v = &r.lyapunov;
    assert!(v[last] < 1e-6 * v[0], "{} {}", v[0], v[last]);
}

#[test]
fn the_platform_does_not_slip_sideways() {
    let mut ctl = controller(None);
    let r = run(&mut ctl, 6.0);
    let rec = &r.recorder;
    assert!(r.monitor.max_residual < 1e-12, "{}", r.monitor.max_residual);
    // lateral velocity of the axle midpoint (0.1 m behind the base origin), by central
    // differences of the recorded poses
    let d = 0.1;
    let axle = |i: usize| {
        let q = rec.q_row(i);
        [q[0] - d * q[2].cos(), q[1] - d * q[2].sin(), q[2]]
    };
    let mut worst = 0.0f64;
    let mut fastest = 0.0f64;
    for i in 1..rec.len() - 1 {
        let (a, b, c) = (axle(i - 1), axle(i + 1), axle(i));
        let dt = rec.times[i + 1] - rec.times[i - 1];
        let (vx, vy) = ((b[0] - a[0]) / dt, (b[1] - a[1]) / dt);
        worst = worst.max((-vx * c[2].sin() + vy * c[2].cos()).abs());
        fastest = fastest.max(vx.hypot(vy));
    }
    assert!(fastest > 0.2, "{fastest}");
    assert!(worst < 1e-3 * fastest.max(1.0), "lateral speed {worst}");
}

#[test]
fn wheel_speed_limits_are_applied_and_reported() {
    let mut ctl = controller(Some(3.0));
    let r = run(&mut ctl, 12.0);
    assert!(r.saturation.speed > 0);
    let t0 = r.saturation.first_speed.unwrap();
    assert!(t0 < 6.0, "{t0}");
    // wheel rates (v entries 0, 1 are [v, ω]; wheel angle rates from the recorded
    // wheel angles) stay within the limit up to the servo's lag
    let rec = &r.recorder;
    let mut peak = 0.0f64;
    for i in 1..rec.len() {
        let (a, b) = (rec.q_row(i - 1), rec.q_row(i));
        let dt = rec.times[i] - rec.times[i - 1];
        peak = peak
            .max(((b[3] - a[3]) / dt).abs())
            .max(((b[4] - a[4]) / dt).abs());
    }
    assert!(peak < 3.0 * 1.05, "wheel rate {peak}");
}

#[test]
fn bad_set_up_is_refused_naming_the_field() {
    let line = PointReference::Line {
        from: [0.6, 0.1, 0.0],
        to: LINE_END,
        duration: 10.0,
    };
    let servo = VelocityServo {
        gain: 20.0,
        arm_kp: 100.0,
        arm_kd: 20.0,
    };
    let g = CoordinatedGains { k_e: 2.0, k_y: 1.0 };
    let make = |joints: [&str; 2], posture: Vec<f64>, g: CoordinatedGains| {
        CoordinatedController::new(
            robot(),
            "tool",
            joints,
            line.clone(),
            g,
            posture,
            servo,
            None,
            None,
        )
        .unwrap_err()
        .to_string()
    };
    let e = make(["turret_joint", "left_wheel_joint"], POSTURE.to_vec(), g);
    assert!(e.contains("controller.joints"), "{e}");
    let e = make(["turret_joint", "turret_joint"], POSTURE.to_vec(), g);
    assert!(e.contains("controller.joints"), "{e}");
    let e = make(["turret_joint", "elbow_joint"], vec![0.0; 2], g);
    assert!(e.contains("controller.posture"), "{e}");
    // an upright arm: the end effector over the turret, no horizontal reach to move
    let e = make(["turret_joint", "elbow_joint"], vec![0.0; 3], g);
    assert!(e.contains("singular"), "{e}");
    let e = make(
        ["turret_joint", "elbow_joint"],
        POSTURE.to_vec(),
        CoordinatedGains { k_e: 0.0, k_y: 1.0 },
    );
    assert!(e.contains("K_E"), "{e}");
}

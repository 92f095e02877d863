//! A platform reference planned on a map (configuration space, D* Lite, curvature-bounded
//! smoothing, time parameterisation: the calls `moma mission` makes), tracked in closed
//! loop by Kanayama's law on a wheeled URDF robot across nav2's depot map.

use moma::control::unicycle::Kanayama;
use moma::io::urdf::model_from_urdf_file;
use moma::mission::planned::{PlannedPathRequest, plan_platform_reference};
use moma::mobile::{DiffDrive, WheeledBase, WheeledModel};
use moma::multibody::RootJoint;
use moma::planning::trajectory::DiffDriveLimits;
use moma::planning::{MapKind, OccupancyGrid, load_map};
use moma::sim::closed_loop::{ClosedLoopOptions, simulate_closed_loop};
use moma::sim::feedback::{PlatformController, PlatformLaw, TrackingReference, VelocityServo};
use moma::sim::monitor::MonitorLimits;
use moma::sim::settings::IntegratorSettings;
use moma::sim::wheeled_system::WheeledSystem;

fn data(path: &str) -> String {
    format!("{}/tests/data/{path}", env!("CARGO_MANIFEST_DIR"))
}

fn request(start: [f64; 3], goal: [f64; 3]) -> PlannedPathRequest {
    PlannedPathRequest {
        start,
        goal,
        footprint_radius: 0.4,
        unknown_is_obstacle: true,
        limits: DiffDriveLimits {
            v_max: 0.8,
            omega_max: 1.0,
            a_max: 0.5,
            alpha_max: 1.0,
        },
        kappa_max: 2.0,
        dt: 0.02,
    }
}

#[test]
fn kanayama_tracks_a_path_planned_across_the_depot_to_the_goal() {
    let map = load_map(
        std::path::Path::new(&data("planning/rosmaps/nav2/depot.yaml")),
        None,
    )
    .unwrap()
    .grid;
    let (start, goal) = ([2.5, 3.0, 0.0], [17.0, 7.3, 0.0]);
    let planned = plan_platform_reference(&map, &request(start, goal)).unwrap();
    let pts = planned.trajectory.points();
    let (first, last) = (pts[0], pts[pts.len() - 1]);
    assert!((first.x - start[0]).hypot(first.y - start[1]) < 1e-9);
    assert!(
        (last.x - goal[0]).hypot(last.y - goal[1]) < 1e-6,
        "{last:?}"
    );
    assert!(planned.cells > 100);
    // the reference keeps its speed limit and stays in free space
    for p in pts {
        assert!(
            p.v.abs() <= 0.8 + 1e-9 && p.omega.abs() <= 1.0 + 1e-9,
            "{p:?}"
        );
        let (cx, cy) = map.world_to_cell("p", p.x, p.y).unwrap();
        assert_eq!(
            map.cells[cy * map.width + cx],
            0,
            "{p:?} not on a free cell"
        );
    }
    let duration = last.t + 3.0;
    // the robot: the axle midpoint starts at the planned start (base origin d ahead)
    let model = model_from_urdf_file(data("mobile/diffdrive_arm.urdf"), RootJoint::Planar).unwrap();
    let mut base = WheeledBase::new(DiffDrive::new(0.08, 0.25, 0.1).unwrap());
    base.wheel_joints = Some(["left_wheel_joint".into(), "right_wheel_joint".into()]);
    let wm = WheeledModel::new(model, base).unwrap();
    let q0 = [start[0] + 0.1, start[1], 0.0, 0.0, 0.0, 0.0, 2.8, 0.3];
    let arm: Vec<f64> = wm.arm_dofs().iter().map(|&d| q0[d]).collect();
    let mut ctl = PlatformController::new(
        wm.clone(),
        PlatformLaw::Kanayama(
            Kanayama::new(2.0, 8.0, 4.0).unwrap(),
            TrackingReference::Sampled(planned.trajectory.clone()),
        ),
        VelocityServo {
            gain: 20.0,
            arm_kp: 100.0,
            arm_kd: 20.0,
        },
        arm,
        None,
        None,
    )
    .unwrap();
    let mut plant = WheeledSystem::new(wm);
    let r = simulate_closed_loop(
        &mut plant,
        &mut ctl,
        &q0,
        &[0.0; 5],
        &ClosedLoopOptions {
            duration,
            integrator: IntegratorSettings::rk4(0.004),
            control_period: Some(0.02),
            record_interval: 0.1,
            limits: MonitorLimits::default(),
            lyapunov_tolerance: 1e-9,
        },
        None,
        &mut |_| {},
    )
    .unwrap();
    let rec = &r.recorder;
    let n = rec.len();
    let mut worst = 0.0f64;
    for i in 0..n {
        let e = r.error_row(i);
        worst = worst.max(e[0].hypot(e[1]));
        // the axle midpoint stays on free cells of the map
        let q = rec.q_row(i);
        let (x, y) = (q[0] - 0.1 * q[2].cos(), q[1] - 0.1 * q[2].sin());
        let (cx, cy) = map.world_to_cell("axle", x, y).unwrap();
        assert_eq!(map.cells[cy * map.width + cx], 0, "t = {}", rec.times[i]);
    }
    assert!(worst < 0.05, "tracking error {worst}");
    let q = rec.q_row(n - 1);
    let axle = [q[0] - 0.1 * q[2].cos(), q[1] - 0.1 * q[2].sin()];
    let miss = (axle[0] - goal[0]).hypot(axle[1] - goal[1]);
    assert!(miss < 0.01, "final axle {axle:?}, {miss} m from the goal");
}

/// A 4 m × 4 m room with a closed 1 m × 1 m box inside: a goal in the box is free but
/// cannot be reached from outside it.
fn walled_box() -> OccupancyGrid {
    let (w, h) = (80, 80);
    let mut free = vec![true; w * h];
    for i in 30..=50 {
        for (x, y) in [(i, 30), (i, 50), (30, i), (50, i)] {
            free[y * w + x] = false;
        }
    }
    let mut g = OccupancyGrid::from_free_mask(w, h, &free, MapKind::Ros).unwrap();
    g.resolution = 0.05;
    g
}

#[test]
fn an_unreachable_goal_is_an_error_naming_the_goal() {
    let g = walled_box();
    let mut r = request([0.6, 0.6, 0.0], [2.0, 2.0, 0.0]);
    r.footprint_radius = 0.2;
    let e = plan_platform_reference(&g, &r).unwrap_err().to_string();
    assert!(
        e.contains("reference.goal") && e.contains("unreachable"),
        "{e}"
    );
    // the same goal from inside the box is reachable
    r.start = [1.8, 2.0, 0.0];
    plan_platform_reference(&g, &r).unwrap();
}

#[test]
fn start_or_goal_in_an_obstacle_or_bad_numbers_are_named() {
    let g = walled_box();
    let mut r = request([1.5, 2.0, 0.0], [0.6, 0.6, 0.0]);
    r.footprint_radius = 0.2;
    let e = plan_platform_reference(&g, &r).unwrap_err().to_string();
    assert!(e.contains("reference.start"), "{e}");
    let mut r = request([0.6, 0.6, 0.0], [9.0, 0.6, 0.0]);
    r.footprint_radius = 0.2;
    let e = plan_platform_reference(&g, &r).unwrap_err().to_string();
    assert!(e.contains("reference.goal"), "{e}");
    let mut r = request([0.6, 0.6, 0.0], [3.0, 0.6, 0.0]);
    r.footprint_radius = f64::NAN;
    let e = plan_platform_reference(&g, &r).unwrap_err().to_string();
    assert!(e.contains("reference.footprint_radius"), "{e}");
}

//! `moma::mission` end to end on the shipped depot map (nav2's, 30 m x 15 m at 5 cm) and
//! the shipped mobile manipulator: short missions reach their goal, an obstacle on the
//! path triggers a D* Lite re-plan, a sealed goal and a posture that tips at rest end
//! with `reached: false` and a reason, runs are deterministic, input errors are errors.

use std::path::{Path, PathBuf};

use moma::mission::{Mission, MissionFile, MissionResult, run, scenario::from_file};

fn scenarios() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios")
}

/// A short mission in the open lower-left part of the depot (about 4 m), with `extra`
/// TOML appended (obstacles, overrides of whole tables).
fn mission_text(goal: &str, extra: &str) -> String {
    format!(
        r#"
name = "test"
[map]
file = "maps/depot.yaml"
[robot]
urdf = "robots/mobile_manipulator.urdf"
drive = {{ r_w = 0.10, b = 0.22, d = 0.0 }}
wheel_joints = ["left_wheel_joint", "right_wheel_joint"]
casters = [
  {{ name = "fl", position = [0.24, 0.16] }},
  {{ name = "fr", position = [0.24, -0.16] }},
  {{ name = "rl", position = [-0.24, 0.16] }},
  {{ name = "rr", position = [-0.24, -0.16] }},
]
footprint_radius = 0.38
end_effector = "tool0"
transport_posture = [0.0, -0.5, 2.6, 1.04, 0.0, 0.0]
[start]
pose = [2.0, 2.0, 0.0]
{goal}
[limits]
v_max = 1.0
omega_max = 1.0
a_max = 0.5
alpha_max = 1.0
mu = 0.6
{extra}
"#
    )
}

const GOAL: &str = "[goal]\npose = [5.5, 3.5, 1.5707963]";

fn parse(text: &str) -> moma::Result<Mission> {
    let file: MissionFile = toml::from_str(text).expect("test mission parses");
    from_file(file, &scenarios().join("test.toml"), &scenarios())
}

fn mission(text: &str) -> MissionResult {
    run(&parse(text).expect("valid mission")).expect("mission runs")
}

#[test]
fn short_mission_reaches_its_goal_without_tipping() {
    let r = mission(&mission_text(GOAL, ""));
    assert!(r.reached, "{:?}", r.reason);
    assert!(r.reason.is_none());
    assert_eq!(r.replans(), 0);
    let last = r.samples.q.last().unwrap();
    assert!((last[0] - 5.5).hypot(last[1] - 3.5) < 0.1);
    assert!((last[2] - std::f64::consts::FRAC_PI_2).abs() < 0.1);
    // the ZMP stays inside the support all along, the footprint never touches
    let zmp = r.min_zmp_margin().unwrap();
    assert!(zmp > 0.05, "min ZMP margin {zmp}");
    assert!(r.samples.zmp_margin.iter().all(|z| z.is_some()));
    assert!(r.min_clearance().unwrap() > 0.0);
    assert!(r.min_force_angle().unwrap() > 0.0);
    // the motion really moved: the robot drove the ~4 m at up to v_max
    let vmax = r.samples.v.iter().copied().fold(0.0, f64::max);
    assert!(vmax > 0.5 && vmax <= 1.01, "peak speed {vmax}");
    // the arm held its transport posture while driving
    let arm: Vec<usize> = r
        .arm_names
        .iter()
        .map(|n| r.q_names.iter().position(|q| q == n).unwrap())
        .collect();
    let posture = [0.0, -0.5, 2.6, 1.04, 0.0, 0.0];
    for (q, phase) in r.samples.q.iter().zip(&r.samples.phase) {
        if *phase == "drive" {
            for (k, &j) in arm.iter().enumerate() {
                assert!(
                    (q[j] - posture[k]).abs() < 0.02,
                    "joint {k} drifted: {}",
                    q[j]
                );
            }
        }
    }
}

#[test]
fn end_effector_reaches_its_target_at_the_goal() {
    let goal = "[goal]\npose = [5.5, 3.5, 1.5707963]\nend_effector = [5.5, 4.2, 0.9]";
    let m = parse(&mission_text(goal, "")).expect("valid mission");
    let r = run(&m).expect("mission runs");
    assert!(r.reached, "{:?}", r.reason);
    let ee = r.samples.ee.last().unwrap();
    let err = ((ee[0] - 5.5).powi(2) + (ee[1] - 4.2).powi(2) + (ee[2] - 0.9).powi(2)).sqrt();
    assert!(err < 0.02, "end-effector error {err}");
    assert!(r.samples.phase.contains(&"reach"));
    assert!(r.events.iter().any(|e| e.kind == "reached"));
    // the platform held still while the arm reached
    let reach: Vec<usize> = (0..r.samples.t.len())
        .filter(|&i| r.samples.phase[i] == "reach")
        .collect();
    let q0 = &r.samples.q[reach[0]];
    let q1 = r.samples.q.last().unwrap();
    assert!((q0[0] - q1[0]).hypot(q0[1] - q1[1]) < 0.01);
    assert!(r.min_zmp_margin().unwrap() > 0.0);
    energy_balance_holds(&m, &r);
}

/// The plant is conservative (ideal rolling, no friction): a run that starts and ends at
/// rest turns its actuators' net work into potential energy only. The potential energy
/// is evaluated on the recorded end states by `dynamics::potential_energy`; the work is
/// the plant's own integral of Qᵀq̇ over its integration steps.
fn energy_balance_holds(m: &Mission, r: &MissionResult) {
    let model = &m.robot.model;
    let mut data = moma::multibody::Data::new(model);
    let mut potential = |q: &Vec<f64>| {
        moma::dynamics::potential_energy(model, &mut data, &nalgebra::DVector::from_vec(q.clone()))
    };
    let gained = potential(r.samples.q.last().unwrap()) - potential(&r.samples.q[0]);
    assert!(
        r.samples.v.last().unwrap().abs() < 1e-4 && r.samples.omega.last().unwrap().abs() < 1e-4
    );
    assert!(
        gained.abs() > 1.0,
        "the reach should lift the arm: {gained} J"
    );
    assert!(
        (r.input_work - gained).abs() < 1e-6,
        "input work {} J, potential energy gained {gained} J",
        r.input_work
    );
}

#[test]
fn obstacle_on_the_path_triggers_a_replan_and_the_goal_is_still_reached() {
    let extra = "[[obstacles]]\nt = 1.0\ncenter = [4.5, 2.75]\nradius = 0.35";
    let r = mission(&mission_text(GOAL, extra));
    assert!(r.reached, "{:?}", r.reason);
    assert_eq!(r.replans(), 1, "{:#?}", r.events);
    let p = &r.plans[1];
    assert!((p.t - 1.0).abs() < 1e-9);
    assert!(
        p.v_start > 0.1,
        "the re-plan continues from the current speed"
    );
    assert!(p.search.expanded > 0);
    // the new path keeps the footprint off the obstacle disk
    for w in &p.path {
        assert!((w[0] - 4.5).hypot(w[1] - 2.75) > 0.35 + 0.38, "{w:?}");
    }
    assert!(r.min_clearance().unwrap() > 0.0);
    // an obstacle away from the path does not re-plan
    let far = "[[obstacles]]\nt = 1.5\ncenter = [10.0, 12.0]\nradius = 0.35";
    let r2 = mission(&mission_text(GOAL, far));
    assert!(r2.reached);
    assert_eq!(r2.replans(), 0);
    assert!(r2.events.iter().any(|e| e.kind == "obstacle"));
}

#[test]
fn a_crate_too_close_to_avoid_is_a_collision_and_ends_the_mission() {
    // appears 1 m ahead of a robot at 0.75 m/s, on its line: the stop along the old path
    // would run into it, and the re-plan from speed cannot swing wide enough in time
    let extra = "[[obstacles]]\nt = 1.5\ncenter = [3.5, 2.1]\nradius = 0.35";
    let r = mission(&mission_text(GOAL, extra));
    assert!(!r.reached);
    assert!(r.reason.as_deref().unwrap().contains("collision"));
    assert!(r.events.iter().any(|e| e.kind == "contact"));
    assert!(r.min_clearance().unwrap() < 0.0);
}

#[test]
fn a_crate_ahead_of_a_robot_at_speed_is_avoided_by_stopping_along_the_old_path() {
    // appears 1.6 m ahead of a robot at 0.75 m/s: the way around it turns sooner than that
    // speed allows, so the base brakes to rest along the path it was on (within a_max),
    // then follows the path planned from where it stopped
    let extra = "[[obstacles]]\nt = 1.5\ncenter = [4.2, 2.6]\nradius = 0.35";
    let r = mission(&mission_text(GOAL, extra));
    assert!(r.reached, "{:?}", r.reason);
    let replan = r.events.iter().find(|e| e.kind == "replan").unwrap();
    assert!(replan.text.contains("brakes to rest"), "{}", replan.text);
    assert!(r.min_clearance().unwrap() > 0.0);
    let s = &r.samples;
    assert!(s.omega_ref.iter().all(|w| w.abs() <= 1.0 + 1e-9));
    // the stop (within 2 s: 0.75 m/s at a_max = 0.5 m/s² takes 1.5 s) on the line the
    // base was driving
    let i = (0..s.t.len())
        .filter(|&i| s.t[i] > 1.5 && s.t[i] < 3.5)
        .min_by(|&a, &b| s.v_ref[a].abs().total_cmp(&s.v_ref[b].abs()))
        .unwrap();
    assert!(s.v_ref[i].abs() < 0.02 && s.v[i].abs() < 0.02, "{}", s.v[i]);
    assert!(
        (s.q[i][1] - 2.0).abs() < 0.05,
        "stopped at {:?}",
        &s.q[i][..3]
    );
}

#[test]
fn an_obstacle_that_seals_the_goal_ends_the_mission_with_a_reason() {
    let extra = "[[obstacles]]\nt = 1.0\ncenter = [5.5, 3.5]\nradius = 0.8";
    let r = mission(&mission_text(GOAL, extra));
    assert!(!r.reached);
    let reason = r.reason.as_deref().unwrap();
    assert!(reason.contains("seals the goal"), "{reason}");
    assert_eq!(r.replans(), 0);
    assert!(r.time_to_goal.is_none());
    assert!(!r.samples.t.is_empty());
}

#[test]
fn a_goal_enclosed_by_walls_is_unreachable() {
    // inside a shelf block of the depot: free cells (0.3 m from any occupied one), walled in
    let goal = "[goal]\npose = [23.725, 3.175, 0.0]";
    let text = mission_text(goal, "").replace("footprint_radius = 0.38", "footprint_radius = 0.2");
    let r = mission(&text);
    assert!(!r.reached);
    assert!(r.reason.unwrap().contains("unreachable"));
    assert_eq!(r.samples.t.len(), 1);
}

#[test]
fn a_posture_that_tips_at_rest_ends_the_mission_with_a_reason() {
    // casters only behind the axle while the arm's mass sits ahead of it
    let text = mission_text(GOAL, "").replace(
        "casters = [\n  { name = \"fl\", position = [0.24, 0.16] },\n  { name = \"fr\", position = [0.24, -0.16] },",
        "casters = [",
    );
    let r = mission(&text);
    assert!(!r.reached);
    assert!(r.reason.unwrap().contains("tip"), "{:?}", r.events);
    assert!(r.tip_limits.forward.is_none());
}

#[test]
fn two_runs_give_identical_results() {
    let extra = "[[obstacles]]\nt = 1.0\ncenter = [4.5, 2.75]\nradius = 0.35";
    let a = mission(&mission_text(GOAL, extra));
    let b = mission(&mission_text(GOAL, extra));
    assert_eq!(a.samples, b.samples);
    assert_eq!(a.events, b.events);
    assert_eq!(a.plans.len(), b.plans.len());
    for (p, q) in a.plans.iter().zip(&b.plans) {
        assert_eq!(p.cells, q.cells);
        assert_eq!(p.path, q.path);
    }
}

#[test]
fn input_errors_are_errors() {
    let err = |text: &str| {
        parse(text)
            .and_then(|m| run(&m).map(|_| ()))
            .unwrap_err()
            .to_string()
    };
    // goal in an obstacle of the map (the depot's outer wall)
    let e = err(&mission_text("[goal]\npose = [0.02, 5.0, 0.0]", ""));
    assert!(e.contains("goal.pose"), "{e}");
    // goal outside the map
    let e = err(&mission_text("[goal]\npose = [50.0, 5.0, 0.0]", ""));
    assert!(e.contains("goal.pose") && e.contains("outside"), "{e}");
    // start where the footprint does not fit (0.2 m from the wall)
    let e =
        err(&mission_text(GOAL, "").replace("pose = [2.0, 2.0, 0.0]", "pose = [0.3, 2.0, 0.0]"));
    assert!(
        e.contains("start.pose") && e.contains("does not fit"),
        "{e}"
    );
    // a footprint that fits nowhere
    let e =
        err(&mission_text(GOAL, "").replace("footprint_radius = 0.38", "footprint_radius = 9.0"));
    assert!(e.contains("fits nowhere"), "{e}");
    // wrong arm posture length
    let e = err(&mission_text(GOAL, "").replace(
        "transport_posture = [0.0, -0.5, 2.6, 1.04, 0.0, 0.0]",
        "transport_posture = [0.0, 1.0]",
    ));
    assert!(
        e.contains("robot.transport_posture") && e.contains("expected 6"),
        "{e}"
    );
    // bad limits
    let e = err(&mission_text(GOAL, "").replace("v_max = 1.0", "v_max = -1.0"));
    assert!(e.contains("limits.v_max"), "{e}");
    let e = err(&mission_text(
        GOAL,
        "[[obstacles]]\nt = -1.0\ncenter = [1.0, 1.0]\nradius = 0.2",
    ));
    assert!(e.contains("obstacles[0].t"), "{e}");
}

#[test]
fn unknown_keys_name_the_key_and_the_file() {
    let dir = std::env::temp_dir().join(format!("moma-mission-keys-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("bad.toml");
    let text = mission_text(GOAL, "").replace("mu = 0.6", "mu = 0.6\nv_maxx = 2.0");
    std::fs::write(&path, text).unwrap();
    let e = moma::mission::load(&path).unwrap_err().to_string();
    assert!(e.contains("bad.toml") && e.contains("v_maxx"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The shipped mobile manipulator with its root frame moved `d` ahead of the driven-axle
/// midpoint (the same physical robot: every joint hung on the root and the chassis'
/// centre of mass shifted by −d along x), written to a temporary folder.
fn offset_urdf(d: f64, tag: &str) -> PathBuf {
    let text = std::fs::read_to_string(scenarios().join("robots/mobile_manipulator.urdf"))
        .expect("shipped URDF");
    let shift = |line: &str| -> String {
        let (head, rest) = line.split_once("xyz=\"").expect("origin with xyz");
        let (xyz, tail) = rest.split_once('"').expect("closing quote");
        let v: Vec<f64> = xyz.split_whitespace().map(|s| s.parse().unwrap()).collect();
        format!("{head}xyz=\"{} {} {}\"{tail}", v[0] - d, v[1], v[2])
    };
    let (mut in_base, mut base_child) = (false, false);
    let mut out = String::new();
    for line in text.lines() {
        let l = line.trim_start();
        if l.starts_with("<link name=\"base_link\"") {
            in_base = true;
        } else if l.starts_with("</link>") {
            in_base = false;
        } else if l.starts_with("<joint ") || l.starts_with("</joint>") {
            base_child = false;
        } else if l.starts_with("<parent link=\"base_link\"") {
            base_child = true;
        }
        if l.starts_with("<origin ") && (in_base || base_child) {
            out.push_str(&shift(line));
        } else {
            out.push_str(line);
        }
        out.push('\n');
    }
    let dir = std::env::temp_dir().join(format!("moma-mission-d-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("offset.urdf");
    std::fs::write(&path, out).unwrap();
    path
}

/// The short mission with the base frame `d` ahead of the axle: the same robot, the same
/// axle-midpoint start (2, 2, 0) and goal (5.5, 3.5, π/2) as [`mission_text`], so the
/// base frame poses are those moved `d` along the heading.
fn offset_mission(d: f64, tag: &str) -> (MissionResult, PathBuf) {
    let urdf = offset_urdf(d, tag);
    let caster = |x: f64, y: f64| format!("[{}, {y}]", x - d);
    let text = mission_text(
        &format!("[goal]\npose = [5.5, {}, 1.5707963267948966]", 3.5 + d),
        "",
    )
    .replace(
        "urdf = \"robots/mobile_manipulator.urdf\"",
        &format!("urdf = {:?}", urdf.to_str().unwrap()),
    )
    .replace("d = 0.0", &format!("d = {d}"))
    .replace(
        "pose = [2.0, 2.0, 0.0]",
        &format!("pose = [{}, 2.0, 0.0]", 2.0 + d),
    )
    .replace("[0.24, 0.16]", &caster(0.24, 0.16))
    .replace("[0.24, -0.16]", &caster(0.24, -0.16))
    .replace("[-0.24, 0.16]", &caster(-0.24, 0.16))
    .replace("[-0.24, -0.16]", &caster(-0.24, -0.16));
    let r = mission(&text);
    (r, urdf)
}

/// Checks an offset mission: the goal is reached within tolerance, the axle midpoint
/// never slips sideways while the base frame origin (d ahead) does move sideways in the
/// turns, the wheels roll without slipping, and the footprint stays clear.
fn check_offset_mission(d: f64, tag: &str) {
    let (r, urdf) = offset_mission(d, tag);
    assert!(r.reached, "d = {d}: {:?} {:#?}", r.reason, r.events);
    let last = r.samples.q.last().unwrap();
    let pe = (last[0] - 5.5).hypot(last[1] - (3.5 + d));
    let he = (last[2] - std::f64::consts::FRAC_PI_2).abs();
    assert!(
        pe < 0.02 && he < 0.02,
        "d = {d}: final error {pe} m, {he} rad"
    );
    assert!(r.min_clearance().unwrap() > 0.0);
    assert!(r.min_zmp_margin().unwrap() > 0.0);
    // the reference and the executed base path agree (base frame origin on both)
    let te = r.max_tracking_error().unwrap();
    assert!(te < 0.01, "d = {d}: tracking error {te}");
    let col = |n: &str| r.q_names.iter().position(|q| q == n).unwrap();
    let (jl, jr) = (col("left_wheel_joint"), col("right_wheel_joint"));
    let (rw, b) = (0.10, 0.22);
    let (mut axle_lat, mut base_lat, mut roll, mut moved) = (0.0f64, 0.0f64, 0.0f64, 0.0);
    for w in r.samples.q.windows(2) {
        let (p, q) = (&w[0], &w[1]);
        let th = 0.5 * (p[2] + q[2]);
        let (e, lat) = ([th.cos(), th.sin()], [-th.sin(), th.cos()]);
        let axle = |s: &[f64]| [s[0] - d * s[2].cos(), s[1] - d * s[2].sin()];
        let (a0, a1) = (axle(p), axle(q));
        let da = [a1[0] - a0[0], a1[1] - a0[1]];
        axle_lat = axle_lat.max((da[0] * lat[0] + da[1] * lat[1]).abs());
        base_lat = base_lat.max(((q[0] - p[0]) * lat[0] + (q[1] - p[1]) * lat[1]).abs());
        // each wheel's contact moves forward by r_w times its rotation
        let fwd = da[0] * e[0] + da[1] * e[1];
        let dth = q[2] - p[2];
        roll = roll
            .max((fwd - b * dth - rw * (q[jl] - p[jl])).abs())
            .max((fwd + b * dth - rw * (q[jr] - p[jr])).abs());
        moved += fwd.abs();
    }
    assert!(moved > 3.0, "d = {d}: drove {moved} m");
    // per 20 ms sample: the axle's sideways motion is the finite-difference error only
    assert!(
        axle_lat < 2e-5,
        "d = {d}: axle slid {axle_lat} m sideways in a sample"
    );
    assert!(roll < 2e-5, "d = {d}: a wheel slid {roll} m in a sample");
    // the base frame origin swings sideways by d·Δθ in turns (what the test tells apart)
    assert!(
        base_lat > 20.0 * axle_lat && base_lat > 1e-3 * d.abs(),
        "d = {d}: base frame sideways {base_lat}, axle {axle_lat}"
    );
    let _ = std::fs::remove_dir_all(urdf.parent().unwrap());
}

#[test]
fn base_frame_ahead_of_the_axle_is_planned_and_tracked_on_the_axle() {
    check_offset_mission(0.2, "ahead");
}

#[test]
fn base_frame_behind_the_axle_is_planned_and_tracked_on_the_axle() {
    check_offset_mission(-0.15, "behind");
}

#[test]
fn a_goal_heading_no_smooth_path_ends_with_is_taken_by_a_turn_in_place() {
    // the goal faces back the way the robot comes: no curvature-bounded path ends there
    // with that heading, so the path ends with its arrival heading and the base turns
    // in place on the goal
    let goal = "[goal]\npose = [5.5, 2.0, 3.14159265]";
    let r = mission(&mission_text(goal, ""));
    assert!(r.reached, "{:?} {:#?}", r.reason, r.events);
    let ev = r
        .events
        .iter()
        .find(|e| e.kind == "smoothing")
        .unwrap_or_else(|| panic!("no smoothing event: {:#?}", r.events));
    assert!(
        ev.text.contains("turns in place at the goal"),
        "{}",
        ev.text
    );
    let last = r.samples.q.last().unwrap();
    assert!((last[0] - 5.5).hypot(last[1] - 2.0) < 0.1);
    let he = moma::control::wrap_angle(std::f64::consts::PI - last[2]).abs();
    assert!(he < 0.1, "final heading error {he}");
    // the turn happened on the spot after the reference ended (arrive phase)
    let arrive: Vec<usize> = (0..r.samples.t.len())
        .filter(|&i| r.samples.phase[i] == "arrive")
        .collect();
    let (q0, q1) = (
        &r.samples.q[arrive[0]],
        &r.samples.q[*arrive.last().unwrap()],
    );
    let turned = moma::control::wrap_angle(q1[2] - q0[2]).abs();
    assert!(turned > 2.0, "turned {turned} rad at the goal");
    assert!((q0[0] - q1[0]).hypot(q0[1] - q1[1]) < 0.15);
}

/// A loader that counts its calls and records what it was asked for, delegating to the
/// file system (or refusing every map).
struct Counting {
    calls: std::cell::RefCell<Vec<String>>,
    refuse_maps: bool,
}

impl moma::mission::scenario::Loader for Counting {
    fn map(&self, path: &Path, resolution: Option<f64>) -> moma::Result<moma::planning::LoadedMap> {
        self.calls
            .borrow_mut()
            .push(format!("map {}", path.display()));
        if self.refuse_maps {
            return Err(moma::Error::invalid("map", "refused by the test loader"));
        }
        moma::mission::scenario::FileSystem.map(path, resolution)
    }
    fn urdf(
        &self,
        path: &Path,
        root: moma::multibody::RootJoint,
    ) -> moma::Result<moma::multibody::Model> {
        self.calls
            .borrow_mut()
            .push(format!("urdf {} {root:?}", path.display()));
        moma::mission::scenario::FileSystem.urdf(path, root)
    }
}

#[test]
fn a_mission_reads_its_map_and_robot_through_the_loader_it_is_given() {
    use moma::mission::scenario::from_file_with;
    let text = mission_text(GOAL, "");
    let file: MissionFile = toml::from_str(&text).unwrap();
    let l = Counting {
        calls: Default::default(),
        refuse_maps: false,
    };
    let path = scenarios().join("test.toml");
    let m = from_file_with(file.clone(), &path, &scenarios(), &l).unwrap();
    // one call each, with the paths resolved against the base and the planar root
    let calls = l.calls.borrow().clone();
    assert_eq!(
        calls,
        [
            format!("map {}", scenarios().join("maps/depot.yaml").display()),
            format!(
                "urdf {} Planar",
                scenarios().join("robots/mobile_manipulator.urdf").display()
            ),
        ]
    );
    // the same mission as the file system's path gives
    let direct = parse(&text).unwrap();
    assert_eq!(m.map, direct.map);
    assert_eq!(m.robot.model.nq, direct.robot.model.nq);
    assert_eq!(m.ee_frame, direct.ee_frame);
    assert_eq!(m.transport, direct.transport);
    // a loader's error is the mission's error, naming the field
    let refusing = Counting {
        calls: Default::default(),
        refuse_maps: true,
    };
    let e = from_file_with(file, &path, &scenarios(), &refusing)
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("map.file") && e.contains("refused by the test loader"),
        "{e}"
    );
    assert_eq!(
        refusing.calls.borrow().len(),
        1,
        "no robot loaded after the map failed"
    );
}

#[test]
fn a_mission_that_cannot_finish_records_no_brake_it_never_made() {
    // the goal is sealed at t = 1 s: the run ends there, and its last sample shows the
    // torques the plant last had, not a brake that no step applied
    let extra = "[[obstacles]]\nt = 1.0\ncenter = [5.5, 3.5]\nradius = 0.8";
    let r = mission(&mission_text(GOAL, extra));
    assert!(!r.reached);
    let end = r.duration;
    let late: Vec<&str> = r
        .events
        .iter()
        .filter(|e| e.t >= end - 1e-9)
        .map(|e| e.kind.as_str())
        .collect();
    for kind in ["torque_limit", "slip", "min_zmp_margin"] {
        assert!(
            !late.contains(&kind),
            "{kind} event at the end: {:#?}",
            r.events
        );
    }
    let u = r.samples.u.last().unwrap();
    assert!(
        u[0].abs() < 40.0 && u[1].abs() < 40.0,
        "last wheel torques {u:?}"
    );
    let zmp = r.min_zmp_margin().unwrap();
    assert!(zmp > 0.0, "min ZMP margin {zmp}");
    assert_eq!(r.torque_saturated_steps, 0);
}

/// The shipped robot with its root frame raised `h` (every origin on the root lowered by
/// `h`: the same physical robot, its root no longer on the ground).
fn raised_root_urdf(h: f64, tag: &str) -> PathBuf {
    let text = std::fs::read_to_string(scenarios().join("robots/mobile_manipulator.urdf"))
        .expect("shipped URDF");
    let mut out = String::new();
    let (mut in_base, mut base_child) = (false, false);
    for line in text.lines() {
        let l = line.trim_start();
        if l.starts_with("<link name=\"base_link\"") {
            in_base = true;
        } else if l.starts_with("</link>") {
            in_base = false;
        } else if l.starts_with("<joint ") || l.starts_with("</joint>") {
            base_child = false;
        } else if l.starts_with("<parent link=\"base_link\"") {
            base_child = true;
        }
        if l.starts_with("<origin ") && (in_base || base_child) {
            let (head, rest) = line.split_once("xyz=\"").unwrap();
            let (xyz, tail) = rest.split_once('"').unwrap();
            let v: Vec<f64> = xyz.split_whitespace().map(|s| s.parse().unwrap()).collect();
            out.push_str(&format!(
                "{head}xyz=\"{} {} {}\"{tail}",
                v[0],
                v[1],
                v[2] - h
            ));
        } else {
            out.push_str(line);
        }
        out.push('\n');
    }
    let dir = std::env::temp_dir().join(format!("moma-mission-z-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("raised.urdf");
    std::fs::write(&path, out).unwrap();
    path
}

#[test]
fn a_root_at_axle_height_gets_the_ground_from_the_wheels() {
    // the same robot described from its axle (root 0.1 m above the ground): the ground
    // height comes from the wheel joints and the radius, so the tip-over limits and the
    // monitored ZMP margins are those of the robot described from the ground
    let urdf = raised_root_urdf(0.1, "axle");
    let raised = mission_text(GOAL, "").replace(
        "urdf = \"robots/mobile_manipulator.urdf\"",
        &format!("urdf = {:?}", urdf.to_str().unwrap()),
    );
    let (a, b) = (
        parse(&mission_text(GOAL, "")).unwrap(),
        parse(&raised).unwrap(),
    );
    let (la, lb) = (
        moma::mission::transport_tip_limits(&a).unwrap(),
        moma::mission::transport_tip_limits(&b).unwrap(),
    );
    for (x, y) in [
        (la.forward, lb.forward),
        (la.backward, lb.backward),
        (la.left, lb.left),
        (la.right, lb.right),
    ] {
        let (x, y) = (x.unwrap(), y.unwrap());
        assert!((x - y).abs() < 1e-9 * x.abs(), "tip limit {x} vs {y}");
    }
    let (ra, rb) = (run(&a).unwrap(), run(&b).unwrap());
    let (za, zb) = (ra.min_zmp_margin().unwrap(), rb.min_zmp_margin().unwrap());
    assert!((za - zb).abs() < 1e-6, "min ZMP margin {za} vs {zb}");
}

#[test]
fn a_run_length_error_names_the_field_the_user_set() {
    let err = |extra: &str| {
        parse(&mission_text(GOAL, extra))
            .and_then(|m| run(&m).map(|_| ()))
            .unwrap_err()
            .to_string()
    };
    // only dt set: the default time limit is not the user's field
    let e = err("[simulation]\ndt = 1e-9\nrecord_interval = 1.0");
    assert!(
        e.contains("test.toml: simulation.dt: 0.000000001 s over the default time limit"),
        "{e}"
    );
    assert!(e.contains("more than 5e7"), "{e}");
    // only the record interval set (at dt): the samples bound names it
    let e = err("[simulation]\ndt = 1e-5\nrecord_interval = 1e-5");
    assert!(
        e.contains("test.toml: simulation.record_interval: 0.00001 s over the default"),
        "{e}"
    );
    assert!(e.contains("more than 2e6"), "{e}");
    // the time limit set: it is the field named
    let e = err("[simulation]\ndt = 1e-9\ntime_limit = 60.0");
    assert!(e.contains("test.toml: simulation.time_limit: 60 s"), "{e}");
}

/// The recorded monitors agree with the recorded states evaluated independently: the
/// clearance at every sample against a brute-force distance from the base to every
/// occupied cell of the map (no distance transform, no search window), and the ZMP margin
/// at the final rest state against the static margin of the centre of mass computed by
/// `dynamics::center_of_mass` in the support polygon written out from the mission file's
/// wheels and casters.
#[test]
fn recorded_monitors_match_an_independent_evaluation() {
    // a goal within a metre of the obstacle near (7.5, 4.0), so the clearance is exact there
    let goal = "[goal]\npose = [6.8, 3.0, 1.5707963]\nend_effector = [6.8, 3.7, 0.9]";
    let m = parse(&mission_text(goal, "")).expect("valid mission");
    let r = run(&m).expect("mission runs");
    assert!(r.reached, "{:?}", r.reason);

    // clearance: footprint radius 0.38 m, exact within 1 m beyond it
    let grid = &m.map.grid;
    let occupied = grid.obstacle_mask(moma::planning::grid::OCCUPIED, false);
    let cells: Vec<(f64, f64)> = (0..grid.height)
        .flat_map(|y| (0..grid.width).map(move |x| (x, y)))
        .filter(|&(x, y)| occupied[grid.index(x, y)])
        .map(|(x, y)| (x as f64, y as f64))
        .collect();
    assert!(!cells.is_empty());
    let mut compared = 0;
    for (q, &recorded) in r.samples.q.iter().zip(&r.samples.clearance) {
        let [fx, fy] = grid.world_to_cell_f(q[0], q[1]);
        let cell_distance = cells
            .iter()
            .map(|&(x, y)| {
                let dx = (x - fx).max(fx - (x + 1.0)).max(0.0);
                let dy = (y - fy).max(fy - (y + 1.0)).max(0.0);
                dx.hypot(dy)
            })
            .fold(f64::INFINITY, f64::min);
        let truth = cell_distance * grid.resolution - 0.38;
        if truth < 0.9 {
            assert!(
                (recorded - truth).abs() < 1e-9,
                "clearance {recorded} m recorded, {truth} m by brute force at ({}, {})",
                q[0],
                q[1]
            );
            compared += 1;
        } else {
            // near and beyond the exact band's edge (decided on the distance transform's
            // cell value) the monitor may report a lower bound, within 1.5 cells
            assert!(recorded <= truth + 1e-9 && recorded >= truth - 1.5 * grid.resolution);
        }
    }
    assert!(
        compared > 100,
        "only {compared} samples near obstacles; min {}",
        r.min_clearance().unwrap()
    );

    // ZMP at rest: the centre of mass's ground projection in the base frame against the
    // hull of the wheel contacts (0, ±0.22) and the casters (±0.24, ±0.16), counter-clockwise
    let hull = [
        (0.24, -0.16),
        (0.24, 0.16),
        (0.0, 0.22),
        (-0.24, 0.16),
        (-0.24, -0.16),
        (0.0, -0.22),
    ];
    let last = r.samples.q.last().unwrap();
    let model = &m.robot.model;
    let mut data = moma::multibody::Data::new(model);
    let com = moma::dynamics::center_of_mass(
        model,
        &mut data,
        &nalgebra::DVector::from_vec(last.clone()),
    );
    let (s, c) = last[2].sin_cos();
    let (wx, wy) = (com.x - last[0], com.y - last[1]);
    let (px, py) = (c * wx + s * wy, -s * wx + c * wy);
    let margin = (0..hull.len())
        .map(|i| {
            let (a, b) = (hull[i], hull[(i + 1) % hull.len()]);
            let (ex, ey) = (b.0 - a.0, b.1 - a.1);
            (ex * (py - a.1) - ey * (px - a.0)) / ex.hypot(ey)
        })
        .fold(f64::INFINITY, f64::min);
    let recorded = r
        .samples
        .zmp_margin
        .last()
        .unwrap()
        .expect("ZMP defined at rest");
    assert!(margin > 0.0);
    assert!(
        (recorded - margin).abs() < 1e-4,
        "ZMP margin {recorded} m recorded, static margin {margin} m"
    );
}

//! `moma mission` with law `mpc` (`[control] law = "mpc"`, the whole-body MPC of
//! `[control.mpc]`): the shipped `scenarios/mission_pass_by.toml` asks the arm to touch a
//! point beside the path, 4.5 m before the goal; the MPC touches it on the move and the
//! drive-then-reach law, on the same file, drives to the goal and cannot reach back. The
//! default mission with law `mpc` (`scenarios/mission_mpc.toml`) re-plans round the crate
//! and reaches its shelf target. Fetch's warehouse mission with the MPC
//! (`scenarios/mission_fetch_mpc.toml`, every constraint on) reaches its goal within the
//! limits, which needs the law to hold the planned acceleration between solves rather
//! than the solve's torques. What law `mpc` does not run is refused, naming the field.

use std::path::{Path, PathBuf};

use moma::mission::{self, Mission, MissionFile, MissionResult, scenario::from_file};

fn scenarios() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios")
}

/// The shipped mission `name` with each `from` replaced by its `to`, validated as if it
/// were the file.
fn variant(name: &str, edits: &[(&str, &str)]) -> moma::Result<Mission> {
    let path = scenarios().join(name);
    let mut text = std::fs::read_to_string(&path).unwrap();
    for (from, to) in edits {
        assert!(text.contains(from), "{name} lacks '{from}'");
        text = text.replacen(from, to, 1);
    }
    let file: MissionFile = toml::from_str(&text).expect("parses");
    from_file(file, &path, &scenarios())
}

fn run(m: &Mission) -> MissionResult {
    mission::run(m).unwrap_or_else(|e| panic!("{}: {e}", m.name))
}

/// The text of `name` from `[control]` up to `[output]`: the law's keys.
fn control_tables(name: &str) -> String {
    let text = std::fs::read_to_string(scenarios().join(name)).unwrap();
    let (a, b) = (
        text.find("[control]").unwrap(),
        text.find("[output]").unwrap(),
    );
    text[a..b].to_string()
}

fn event<'a>(r: &'a MissionResult, kind: &str) -> Option<&'a mission::Event> {
    r.events.iter().find(|e| e.kind == kind)
}

#[test]
fn the_pass_by_target_is_touched_on_the_move_by_the_mpc_and_missed_by_drive_then_reach() {
    let name = "mission_pass_by.toml";
    let m = mission::load(&scenarios().join(name)).unwrap();
    let target = m.goal().unwrap().end_effector.unwrap();
    let mpc = run(&m);
    assert!(mpc.reached, "{:?}", mpc.reason);
    assert!(
        mpc.samples
            .phase
            .iter()
            .all(|p| *p == "whole_body" || *p == "done")
    );
    // The touch: within the 2 cm tolerance, the base still driving, well before the goal.
    let touch = event(&mpc, "reached").expect("a touch event");
    let i = mpc.samples.t.iter().position(|&t| t >= touch.t).unwrap();
    let base_speed = mpc.samples.v[i];
    let x_at_touch = mpc.samples.q[i][0];
    assert!(base_speed > 0.2, "base speed at the touch {base_speed}");
    assert!(x_at_touch < 9.0, "touched at x = {x_at_touch}");
    let s = mpc.mpc.as_ref().expect("the MPC's summary");
    assert!(s.min_ee_error.unwrap() <= 0.02, "{s:?}");
    assert!(s.solves > 100, "{s:?}");
    // Upright and within the plan: the ZMP inside the support, the footprint clear.
    assert!(mpc.min_zmp_margin().unwrap() > 0.0);
    assert!(mpc.min_clearance().unwrap() > 0.0);

    // The same file with the default law: drives to the goal, then cannot reach back.
    let default = variant(
        name,
        &[(
            &control_tables(name),
            "[control]\nlaw = \"drive_then_reach\"\n\n",
        )],
    )
    .unwrap();
    let d = run(&default);
    assert!(!d.reached);
    let reason = d.reason.as_deref().unwrap();
    assert!(reason.contains("end effector"), "{reason}");
    assert!(d.mpc.is_none());
    // Its closest approach over the run: about the 4.5 m back to the target.
    let closest = d
        .samples
        .ee
        .iter()
        .map(|e| {
            ((e[0] - target[0]).powi(2) + (e[1] - target[1]).powi(2) + (e[2] - target[2]).powi(2))
                .sqrt()
        })
        .fold(f64::INFINITY, f64::min);
    assert!(closest > 0.3, "closest {closest}");
}

#[test]
fn the_default_mission_with_the_mpc_replans_round_the_crate_and_reaches_the_shelf() {
    let m = mission::load(&scenarios().join("mission_mpc.toml")).unwrap();
    let r = run(&m);
    assert!(r.reached, "{:?} {:?}", r.reason, r.events);
    assert_eq!(r.replans(), 1, "the crate at t = 5 s");
    assert!(r.min_clearance().unwrap() > 0.0);
    assert!(r.min_zmp_margin().unwrap() > 0.0);
    let s = r.mpc.as_ref().unwrap();
    assert!(s.min_ee_error.unwrap() <= 0.02, "{s:?}");
    let summary = mission::summary(&m, &r);
    assert_eq!(summary["mpc"]["solves"], s.solves);
}

/// The limits of Fetch's warehouse mission with the MPC, checked at the shipped start
/// and at three moved ones (`fetch_keeps_its_limits_from_moved_starts`): the goal within
/// 30 s, the gripper within 2 cm of its target, the ZMP margin (planned and in the
/// plant) above its set value 0.05 m, no joint past a position limit, clearance to the
/// racks, the torques clipped on fewer than 5 % of the steps, and the torque, wheel-speed
/// and joint-speed limits. Those three hold in the plan by construction, not by a
/// penalty: the joint speeds of the next knot are a bound on the input, the wheel rates
/// of the next knot and the wheels' torques of the first input are the polygon the
/// platform input is projected onto (`docs/mpc.md`, "Limits the solver enforces"). What
/// the plant then does past them (measured, one solver iteration a solve: at most
/// 0.014 rad/s of joint speed and 0.001 rad/s of wheel rate, no torque) is the plant leaving the plan between solves, bounded here: torque asked
/// past a limit at most 0.01 N·m (the arm's torques are still a penalty), wheel rates at
/// most 0.01 rad/s and joint speeds at most 0.02 rad/s past theirs (before: up to
/// 1.37 N·m, 0.72 rad/s and 0.13 rad/s at these starts).
fn fetch_warehouse_limits_hold(r: &MissionResult, start: &str) {
    assert!(r.reached, "{start}: {:?} {:?}", r.reason, r.events);
    let t_goal = r.time_to_goal.expect("a time to goal");
    assert!(t_goal < 30.0, "{start}: time to goal {t_goal}");
    let s = r.mpc.as_ref().expect("the MPC's summary");
    assert!(s.min_ee_error.unwrap() <= 0.02, "{start}: {s:?}");
    assert!(
        r.torque_saturated_steps * 20 < r.steps,
        "{start}: {} of {} steps clipped",
        r.torque_saturated_steps,
        r.steps
    );
    assert!(s.joint_position_excess <= 0.0, "{start}: {s:?}");
    assert!(s.min_zmp_margin >= 0.05, "{start}: {s:?}");
    let zmp = r.min_zmp_margin().unwrap();
    assert!(zmp >= 0.05, "{start}: plant's smallest ZMP margin {zmp}");
    assert!(r.min_clearance().unwrap() > 0.0, "{start}");
    assert!(s.max_torque_excess <= 0.01, "{start}: {s:?}");
    assert!(s.wheel_speed_excess <= 0.01, "{start}: {s:?}");
    assert!(s.joint_speed_excess <= 0.02, "{start}: {s:?}");
}

/// Fetch's warehouse mission with the MPC: one solve per 50 ms, 25 simulation steps of
/// 2 ms; in between, the law recomputes the torques of the planned acceleration at the
/// measured state. Holding the solve's torques over those 25 steps instead let Fetch's
/// light joints drift from the plan within the period: the run reached its goal only at
/// 29.1 s, with joint speeds 3.8 rad/s and a joint 0.37 rad past their limits.
#[test]
fn fetch_reaches_its_warehouse_goal_with_the_mpc_within_its_limits() {
    let m = mission::load(&scenarios().join("mission_fetch_mpc.toml")).unwrap();
    let r = run(&m);
    fetch_warehouse_limits_hold(&r, "shipped start");
}

/// The same limits from moved starts: with the start moved by 1e-9, -1e-7 and 1e-6 m
/// along x, each run's round-off, and so its closed loop, differs from the shipped
/// start's from the first solve on (the closed loop amplifies round-off, `docs/mpc.md`,
/// "In closed loop"); limits that held only as penalties broke at two of these three.
#[test]
fn fetch_keeps_its_limits_from_moved_starts() {
    for (x, moved) in [
        ("-5.399999999", "+1e-9 m"),
        ("-5.400000100000001", "-1e-7 m"),
        ("-5.399999", "+1e-6 m"),
    ] {
        let m = variant(
            "mission_fetch_mpc.toml",
            &[("pose = [-5.4, -12.0", &format!("pose = [{x}, -12.0"))],
        )
        .unwrap();
        let r = run(&m);
        fetch_warehouse_limits_hold(&r, &format!("start moved by {moved}"));
    }
}

/// The pass-by mission with a post (radius 0.3 m) that appears at t = 1 s just above
/// the path, 2.5 m ahead: the re-plan passes it as closely as the configuration space
/// allows. With `control.mpc.map_clearance` (0.1 m) the MPC keeps the footprint off the
/// post (and off the map's walls) by that much, up to `MAP_CLEARANCE_TOLERANCE`; without
/// it the base follows the re-planned path, which grazes the post.
#[test]
fn the_map_clearance_constraint_keeps_the_base_off_an_obstacle_that_appears() {
    let post = "[[obstacles]]\nt = 1.0\ncenter = [5.0, 9.55]\nradius = 0.3\n\n[control]";
    let set = 0.1;
    let without = run(&variant("mission_pass_by.toml", &[("[control]", post)]).unwrap());
    let with_key = format!("clearance = false\nmap_clearance = {set}");
    let with = run(&variant(
        "mission_pass_by.toml",
        &[("[control]", post), ("clearance = false", &with_key)],
    )
    .unwrap());
    for r in [&without, &with] {
        assert!(r.reached, "{:?} {:?}", r.reason, r.events);
        assert_eq!(r.replans(), 1, "the post at t = 1 s");
    }
    let (c_without, c_with) = (
        without.min_clearance().unwrap(),
        with.min_clearance().unwrap(),
    );
    assert!(
        c_without < set - 0.03,
        "without the constraint: {c_without}"
    );
    assert!(
        c_with >= set - MAP_CLEARANCE_TOLERANCE,
        "with map_clearance = {set}: {c_with} (without: {c_without})"
    );
    let planned = with.mpc.as_ref().unwrap().planned_violations.map_clearance;
    let unset = without
        .mpc
        .as_ref()
        .unwrap()
        .planned_violations
        .map_clearance;
    assert_eq!(unset, None, "no map-clearance row without the key");
    assert!(
        planned.is_some_and(|p| p < 0.05),
        "largest planned shortfall {planned:?}"
    );
}

/// What the recorded clearance (the footprint's exact distance to the occupied cells'
/// edges) may fall below the map-clearance set value: the MPC's field over-estimates
/// that distance by up to 0.21 cells (0.01 m on the depot's 5 cm cells), and the
/// augmented Lagrangian, one multiplier step per solve, lets a little through.
const MAP_CLEARANCE_TOLERANCE: f64 = 0.02;

/// A refused case: the shipped mission edited, and the field its error must name.
type RefusedCase<'a> = (&'a str, Vec<(&'a str, String)>, &'a str);

#[test]
fn what_law_mpc_does_not_run_is_refused_naming_the_field() {
    let mpc = control_tables("mission_mpc.toml");
    let cases: Vec<RefusedCase> = vec![
        (
            "mission_mpc.toml",
            vec![("stages = 20", "stages = 0".into())],
            "control.mpc.stages",
        ),
        (
            "mission_mpc.toml",
            vec![("dt = 0.05", "dt = -0.05".into())],
            "control.mpc.dt",
        ),
        (
            "mission_mpc.toml",
            vec![("\"wrist_3_joint\"]", "\"no_such_joint\"]".into())],
            "control.mpc.joints",
        ),
        (
            "mission_mpc.toml",
            vec![("period = 0.05", "period = 0.003".into())],
            "control.period",
        ),
        (
            "mission_mpc.toml",
            vec![("reach_radius = 1.0", "reach_radius = -1.0".into())],
            "control.reach_radius",
        ),
        (
            "mission_mpc.toml",
            vec![("law = \"mpc\"", "law = \"drive_then_reach\"".into())],
            "control.mpc",
        ),
        (
            "mission_mpc.toml",
            vec![(
                "clearance = false",
                "clearance = false\nmap_clearance = -0.1".into(),
            )],
            "control.mpc.map_clearance",
        ),
        (
            "mission_mpc.toml",
            vec![(
                "clearance = false",
                "clearance = false\nmap_clearance = nan".into(),
            )],
            "control.mpc.map_clearance",
        ),
        (
            "mission_mpc.toml",
            vec![(
                "clearance = false",
                "clearance = false\nclearance_pairs = 0".into(),
            )],
            "control.mpc.clearance_pairs",
        ),
        (
            "mission_mpc.toml",
            vec![(
                "clearance = false",
                "clearance = false\nclearance_band = -0.01".into(),
            )],
            "control.mpc.clearance_band",
        ),
        (
            "mission_contact.toml",
            vec![("[simulation]", format!("{mpc}\n[simulation]"))],
            "simulation.plant",
        ),
        (
            "mission_fetch_pick.toml",
            vec![("[output]", format!("{mpc}\n[output]"))],
            "task",
        ),
    ];
    for (name, edits, field) in cases {
        let edits: Vec<(&str, &str)> = edits.iter().map(|(a, b)| (*a, b.as_str())).collect();
        let e = variant(name, &edits).expect_err(field).to_string();
        assert!(e.contains(field), "{name} {field}: {e}");
    }
}

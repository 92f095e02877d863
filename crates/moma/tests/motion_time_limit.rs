//! The arm planner's time limit holds in every phase: from the deadline on, the planning
//! group's check refuses every state unchecked (`ClearanceChecker::set_deadline`), so the
//! phases after the search — shortcutting, the redundant-waypoint pass, the timing's blend
//! checks — evaluate no state once it has passed and keep the search's checked path (the
//! trajectory stops at its waypoints), and `plan_motion` returns within its limit plus the
//! state in hand. Scene: table_pick-Front-Can1-0's with two plates as their triangles
//! (`concave_plates`, as `moma motion --mesh exact` reads it), Fetch's arm and torso.

use moma::collision::{GeometryModel, Scene, SceneOptions, read_scene};
use moma::motion::{
    ClearanceChecker, JointGroup, MeshSource, MotionGoal, MotionOptions, MotionProblem, NotSolved,
    plan_motion, surface_links_for_states,
};
use moma::multibody::{Model, RootJoint};
use moma::planning::{
    JointLimits, JointSpace, Planned, RrtConnectOptions, RrtConnectWorkspace, ShortcutOptions,
    StateValidity, TimingOptions, rrt_connect, shortcut, time_optimal,
};
use std::time::{Duration, Instant};

mod fetch_common;
use fetch_common::{FetchQueries, data_dir, fetch_dir, fetch_geometry, fetch_urdf, numbers};

const MARGIN: f64 = 2e-3;

struct Plates {
    model: Model,
    geometry: GeometryModel,
    scene: Scene,
    group: JointGroup,
    start: Vec<f64>,
    goal: Vec<f64>,
}

impl Plates {
    /// The planning problem of the query.
    fn problem(&self) -> MotionProblem<'_> {
        MotionProblem {
            model: &self.model,
            geometry: &self.geometry,
            scene: &self.scene,
            group: &self.group,
        }
    }
}

/// The query table_pick-Front-Can1-0 among its scene plus the two plates, as triangles.
fn plates() -> Plates {
    let (model, gm) = fetch_geometry(RootJoint::Fixed);
    let queries = FetchQueries::load();
    let group = queries.group(&model);
    let query = queries.query("table_pick-Front-Can1-0");
    let (start, goal) = (numbers(&query["start"]), numbers(&query["goal_state"]));
    let scene = read_scene(
        &data_dir().join("scenes/motion_bench_maker/concave_plates/scene.yaml"),
        &SceneOptions {
            world_frames: vec!["world".into(), "base_link".into()],
            package_dirs: Vec::new(),
        },
    )
    .unwrap()
    .with_mesh_triangles()
    .unwrap();
    let source = MeshSource {
        urdf: fetch_urdf(),
        package_dirs: vec![fetch_dir()],
    };
    let (geometry, _) =
        surface_links_for_states(&model, &gm, &scene, &group, &[&start], MARGIN, &source).unwrap();
    Plates {
        model,
        geometry,
        scene,
        group,
        start,
        goal,
    }
}

fn group_state(group: &JointGroup, q: &[f64]) -> Vec<f64> {
    let mut x = vec![0.0; group.dim()];
    group.extract(q, &mut x);
    x
}

#[test]
fn past_the_deadline_shortcutting_and_timing_check_no_state_and_keep_the_path() {
    let p = plates();
    let dim = p.group.dim();
    let mut checker = ClearanceChecker::new(
        &p.model,
        &p.geometry,
        &p.scene,
        &p.group,
        &p.start,
        MARGIN,
        &vec![1.0; dim],
    )
    .unwrap();
    let space = JointSpace::new(p.group.lower.clone(), p.group.upper.clone(), 0.01).unwrap();
    let (xa, xb) = (
        group_state(&p.group, &p.start),
        group_state(&p.group, &p.goal),
    );
    let options = RrtConnectOptions {
        seed: 0,
        time_limit: Duration::from_secs(120),
        ..RrtConnectOptions::default()
    };
    let path = match rrt_connect(
        &space,
        &mut checker,
        &xa,
        &xb,
        &options,
        &mut RrtConnectWorkspace::new(),
    )
    .unwrap()
    {
        Planned::Solved { path, .. } => path,
        other => panic!("not solved: {other:?}"),
    };
    assert!(
        path.len() >= 3,
        "{} waypoints: no corner to blend",
        path.len()
    );
    let shortcuts = ShortcutOptions {
        attempts: 100,
        seed: 0,
        min_gain: 0.0,
        drop_redundant: true,
        probe: Some(0.25),
    };
    let limits = JointLimits {
        velocity: p.group.velocity.clone(),
        acceleration: vec![1.0; dim],
    };
    let mut scratch = Vec::new();

    // Past the deadline: every state refused, none evaluated.
    checker.set_deadline(Some(Instant::now()));
    let before = checker.states_checked;
    assert!(
        !checker.is_valid(&xa),
        "a clear state passed past the deadline"
    );
    assert!(!checker.segment_valid(
        &space,
        path.waypoint(0),
        path.waypoint(1),
        &mut scratch,
        &mut 0
    ));
    // The path timed as the planner times it.
    let time = |checker: &mut ClearanceChecker| {
        time_optimal(&space, checker, &path, &limits, &TimingOptions::default()).unwrap()
    };
    let kept = shortcut(&space, &mut checker, &path, &shortcuts, &mut 0).unwrap();
    assert_eq!(kept, path, "the path changed past the deadline");
    let timed = time(&mut checker);
    assert_eq!(timed.blend_deviations.len(), path.len() - 2);
    // A deviation of 0: the trajectory comes to rest at that waypoint.
    assert!(
        timed.blend_deviations.iter().all(|d| *d == 0.0),
        "a blend past the deadline: {:?}",
        timed.blend_deviations
    );
    assert_eq!(
        checker.states_checked, before,
        "states evaluated past the deadline"
    );

    // The same calls without a deadline evaluate states, shorten the path and blend a
    // corner: the counts above can fail.
    checker.set_deadline(None);
    assert!(checker.is_valid(&xa));
    let shorter = shortcut(&space, &mut checker, &path, &shortcuts, &mut 0).unwrap();
    assert!(shorter.length(&space) < path.length(&space));
    let timed = time(&mut checker);
    assert!(timed.blend_deviations.iter().any(|d| *d > 0.0));
    assert!(checker.states_checked > before + 1);
}

#[test]
fn plan_motion_returns_within_its_limit_and_a_phase_begun_past_it_checks_nothing() {
    let p = plates();
    let problem = p.problem();
    let goal = MotionGoal::State(p.goal.clone());
    // Solved runs whose search, shortcutting, timing ended past the limit.
    let (mut solved, mut late) = (0, [0; 3]);
    for limit_ms in [20u64, 50, 100, 200, 400] {
        for seed in 0..3 {
            let mut o = MotionOptions::new(p.group.dim());
            o.time_limit = Duration::from_millis(limit_ms);
            o.seed = seed;
            let began = Instant::now();
            let r = plan_motion(&problem, &p.start, &goal, &o).unwrap();
            let wall = began.elapsed();
            // One state check here takes well under 10 ms even on a loaded machine; the
            // wide margin keeps the test from timing noise.
            assert!(
                wall <= o.time_limit + Duration::from_millis(750),
                "{limit_ms} ms, seed {seed}: {wall:?}"
            );
            let Some(traj) = &r.trajectory else {
                assert_eq!(r.not_solved, Some(NotSolved::TimeLimit));
                continue;
            };
            solved += 1;
            let states = r.path.len() + traj.t.len();
            assert!(
                (1..=states).contains(&r.closest_states),
                "{}",
                r.closest_states
            );
            assert!(r.closest.is_some());
            // A phase that began past the limit evaluated no state, and the report then
            // covers the start only.
            let searched = r.phases.setup + r.phases.ik + r.phases.search;
            let shortened = searched + r.phases.shortcut;
            let timed = shortened + r.phases.timing;
            if searched >= o.time_limit {
                late[0] += 1;
                assert_eq!(r.phase_checks.shortcut, 0, "{limit_ms} ms, seed {seed}");
            }
            if shortened >= o.time_limit {
                late[1] += 1;
                assert_eq!(r.phase_checks.timing, 0, "{limit_ms} ms, seed {seed}");
            }
            if timed >= o.time_limit {
                late[2] += 1;
                assert_eq!(r.closest_states, 1, "{limit_ms} ms, seed {seed}");
            }
        }
    }
    eprintln!(
        "solved {solved} of 15 runs; past the limit after the search {}, the shortcutting {}, \
         the timing {}",
        late[0], late[1], late[2]
    );
}

#[test]
fn with_time_to_spare_the_minimum_covers_every_waypoint_and_sample() {
    let p = plates();
    let problem = p.problem();
    let mut o = MotionOptions::new(p.group.dim());
    o.time_limit = Duration::from_secs(60);
    let r = plan_motion(&problem, &p.start, &MotionGoal::State(p.goal.clone()), &o).unwrap();
    let traj = r.trajectory.as_ref().expect("solved");
    assert_eq!(r.closest_states, r.path.len() + traj.t.len());
    // The minimum is no larger than any one state's, the start's included.
    let mut checker = ClearanceChecker::new(
        &p.model,
        &p.geometry,
        &p.scene,
        &p.group,
        &p.start,
        MARGIN,
        &vec![1.0; p.group.dim()],
    )
    .unwrap();
    let least = r.closest.as_ref().unwrap().distance;
    for q in r.path.iter().chain(&traj.q).step_by(7) {
        let d = checker
            .distance_report(&group_state(&p.group, q))
            .unwrap()
            .distance;
        assert!(least <= d, "{least} above a state's {d}");
    }
}

//! Joint-space motion planning on synthetic problems whose answer is known: RRT-Connect,
//! shortcutting and time-optimal timing with blends.

use moma::Error;
use moma::planning::{
    JointLimits, JointPath, JointSpace, PlanLimit, Planned, RrtConnectOptions, RrtConnectWorkspace,
    ShortcutOptions, TimingOptions, rrt_connect, shortcut, time_optimal,
};
use std::time::{Duration, Instant};

/// The unit square with a wall `0.45 < x < 0.55` open only for `0.8 < y < 0.9`.
fn wall_with_gap(q: &[f64]) -> bool {
    !(q[0] > 0.45 && q[0] < 0.55 && !(q[1] > 0.8 && q[1] < 0.9))
}

/// `[-1, 1]^7` with a wall `|x0| < 0.05` open only where `|x1| < 0.1` and `|x2| < 0.1`.
fn narrow_passage(q: &[f64]) -> bool {
    !(q[0].abs() < 0.05 && !(q[1].abs() < 0.1 && q[2].abs() < 0.1))
}

/// `[-1, 1]^7` cut in two by the wall `|x0| < 0.05`.
fn closed_wall(q: &[f64]) -> bool {
    q[0].abs() >= 0.05
}

const START7: [f64; 7] = [-0.8, 0.5, -0.5, 0.3, -0.3, 0.2, -0.2];
/// The straight segment from [`START7`] crosses the wall at `x1 = 0.5`, outside the hole.
const GOAL7: [f64; 7] = [0.8, 0.5, 0.5, -0.3, 0.3, -0.2, 0.2];

fn square() -> JointSpace {
    JointSpace::new(vec![0.0; 2], vec![1.0; 2], 0.005).unwrap()
}

fn cube7() -> JointSpace {
    JointSpace::new(vec![-1.0; 7], vec![1.0; 7], 0.01).unwrap()
}

fn solve(
    space: &JointSpace,
    validity: fn(&[f64]) -> bool,
    start: &[f64],
    goal: &[f64],
    seed: u64,
    ws: &mut RrtConnectWorkspace,
) -> JointPath {
    let options = RrtConnectOptions {
        seed,
        ..RrtConnectOptions::default()
    };
    let mut v = validity;
    match rrt_connect(space, &mut v, start, goal, &options, ws).unwrap() {
        Planned::Solved { path, .. } => path,
        other => panic!("not solved: {other:?}"),
    }
}

fn valid(space: &JointSpace, validity: fn(&[f64]) -> bool, path: &JointPath) -> bool {
    let mut v = validity;
    path.is_valid(space, &mut v, &mut 0)
}

/// The `y` at which each segment of a 2-D path crosses `x = 0.5`.
fn crossings(path: &JointPath) -> Vec<f64> {
    (1..path.len())
        .filter_map(|i| {
            let (a, b) = (path.waypoint(i - 1), path.waypoint(i));
            let (lo, hi) = (a[0].min(b[0]), a[0].max(b[0]));
            (lo <= 0.5 && 0.5 <= hi && a[0] != b[0])
                .then(|| a[1] + (0.5 - a[0]) / (b[0] - a[0]) * (b[1] - a[1]))
        })
        .collect()
}

#[test]
fn two_d_wall_path_goes_through_the_gap_and_is_no_shorter_than_the_shortest() {
    let space = square();
    let mut ws = RrtConnectWorkspace::new();
    let (start, goal) = ([0.1, 0.1], [0.9, 0.1]);
    // The shortest path bends around the gap's lower corners (0.45, 0.8), (0.55, 0.8).
    let shortest = 2.0 * (0.35f64.powi(2) + 0.7f64.powi(2)).sqrt() + 0.1;
    for seed in 0..20 {
        let path = solve(&space, wall_with_gap, &start, &goal, seed, &mut ws);
        assert_eq!(path.waypoint(0), start);
        assert_eq!(path.waypoint(path.len() - 1), goal);
        assert!(valid(&space, wall_with_gap, &path), "seed {seed}");
        let ys = crossings(&path);
        assert!(!ys.is_empty());
        assert!(
            ys.iter().all(|y| *y > 0.8 && *y < 0.9),
            "seed {seed}: {ys:?}"
        );
        assert!(path.length(&space) >= shortest, "seed {seed}");
        let mut checks = 0;
        let mut v = wall_with_gap;
        let short = shortcut(
            &space,
            &mut v,
            &path,
            &ShortcutOptions {
                attempts: 200,
                seed,
                ..ShortcutOptions::default()
            },
            &mut checks,
        )
        .unwrap();
        assert!(valid(&space, wall_with_gap, &short), "seed {seed}");
        assert!(short.length(&space) <= path.length(&space));
        assert!(short.length(&space) >= shortest);
        assert!(checks > 0);
    }
}

#[test]
fn seven_d_narrow_passage_is_solved_through_the_hole() {
    let space = cube7();
    let mut ws = RrtConnectWorkspace::new();
    for seed in 0..10 {
        let path = solve(&space, narrow_passage, &START7, &GOAL7, seed, &mut ws);
        assert!(valid(&space, narrow_passage, &path), "seed {seed}");
        assert_eq!(path.waypoint(0), START7);
        assert_eq!(path.waypoint(path.len() - 1), GOAL7);
        assert!(path.len() > 2);
        // Some waypoint-to-waypoint segment crosses x0 = 0, inside the hole.
        let through = (1..path.len()).any(|i| {
            let (a, b) = (path.waypoint(i - 1), path.waypoint(i));
            if (a[0] < 0.0) == (b[0] < 0.0) {
                return false;
            }
            let f = -a[0] / (b[0] - a[0]);
            let y1 = a[1] + f * (b[1] - a[1]);
            let y2 = a[2] + f * (b[2] - a[2]);
            y1.abs() < 0.1 && y2.abs() < 0.1
        });
        assert!(through, "seed {seed}");
    }
}

#[test]
fn same_seed_same_path_also_in_a_reused_workspace() {
    let space = cube7();
    let mut ws = RrtConnectWorkspace::new();
    let first = solve(&space, narrow_passage, &START7, &GOAL7, 7, &mut ws);
    // Another query in between leaves nothing behind in the workspace.
    let _ = solve(&space, narrow_passage, &GOAL7, &START7, 3, &mut ws);
    let again = solve(&space, narrow_passage, &START7, &GOAL7, 7, &mut ws);
    let fresh = solve(
        &space,
        narrow_passage,
        &START7,
        &GOAL7,
        7,
        &mut RrtConnectWorkspace::new(),
    );
    assert_eq!(first, again);
    assert_eq!(first, fresh);
    let other = solve(&space, narrow_passage, &START7, &GOAL7, 8, &mut ws);
    assert_ne!(first, other);
}

#[test]
fn unsolvable_problem_ends_at_the_iteration_limit_with_counts() {
    let space = cube7();
    let options = RrtConnectOptions {
        max_iterations: 2000,
        time_limit: Duration::from_secs(60),
        ..RrtConnectOptions::default()
    };
    let mut v = closed_wall;
    let out = rrt_connect(
        &space,
        &mut v,
        &START7,
        &GOAL7,
        &options,
        &mut RrtConnectWorkspace::new(),
    )
    .unwrap();
    match out {
        Planned::NotSolved { limit, stats } => {
            assert_eq!(limit, PlanLimit::Iterations);
            assert_eq!(stats.iterations, 2000);
            assert!(stats.nodes > 2 && stats.checks > 2000);
        }
        solved => panic!("solved a closed wall: {solved:?}"),
    }
}

#[test]
fn unsolvable_problem_ends_at_the_time_limit() {
    let space = cube7();
    let options = RrtConnectOptions {
        max_iterations: usize::MAX,
        time_limit: Duration::from_millis(50),
        ..RrtConnectOptions::default()
    };
    let mut v = closed_wall;
    let began = Instant::now();
    let out = rrt_connect(
        &space,
        &mut v,
        &START7,
        &GOAL7,
        &options,
        &mut RrtConnectWorkspace::new(),
    )
    .unwrap();
    let took = began.elapsed();
    match out {
        Planned::NotSolved { limit, stats } => {
            assert_eq!(limit, PlanLimit::Time);
            assert!(stats.elapsed >= Duration::from_millis(50));
            assert!(stats.iterations > 0);
        }
        solved => panic!("solved a closed wall: {solved:?}"),
    }
    assert!(took < Duration::from_millis(500), "{took:?}");
}

/// The unit square with a wall of no thickness at `x = 0.5`, open only for `0.8 < y <
/// 0.9`: every state is valid, only a segment check sees the wall. The segments that cross
/// it outside the opening are counted.
struct ThinWall {
    blocked: usize,
}

impl moma::planning::StateValidity for ThinWall {
    fn is_valid(&mut self, _q: &[f64]) -> bool {
        true
    }

    fn segment_valid(
        &mut self,
        _space: &JointSpace,
        a: &[f64],
        b: &[f64],
        _scratch: &mut Vec<f64>,
        checks: &mut u64,
    ) -> bool {
        *checks += 1;
        if (a[0] - 0.5) * (b[0] - 0.5) > 0.0 {
            return true;
        }
        let f = if a[0] == b[0] {
            0.0
        } else {
            (0.5 - a[0]) / (b[0] - a[0])
        };
        let y = a[1] + f * (b[1] - a[1]);
        let open = y > 0.8 && y < 0.9;
        if !open {
            self.blocked += 1;
        }
        open
    }
}

#[test]
fn lazy_search_cuts_the_edges_its_paths_fail_on_and_returns_a_checked_path() {
    // The probes at the resolution never see the wall: only the paths' segment checks do.
    let space = JointSpace::new(vec![0.0; 2], vec![1.0; 2], 0.01).unwrap();
    let options = RrtConnectOptions {
        lazy: true,
        ..RrtConnectOptions::default()
    };
    let mut wall = ThinWall { blocked: 0 };
    let out = rrt_connect(
        &space,
        &mut wall,
        &[0.1, 0.1],
        &[0.9, 0.1],
        &options,
        &mut RrtConnectWorkspace::new(),
    )
    .unwrap();
    let path = out.path().expect("solved").clone();
    // The straight segment and at least one path through the wall were refused.
    assert!(wall.blocked >= 2, "blocked {}", wall.blocked);
    let blocked = wall.blocked;
    assert!(path.is_valid(&space, &mut wall, &mut 0));
    assert_eq!(wall.blocked, blocked);
    let ys = crossings(&path);
    assert!(
        !ys.is_empty() && ys.iter().all(|y| *y > 0.8 && *y < 0.9),
        "{ys:?}"
    );
}

#[test]
fn a_probe_reports_how_far_a_segment_stays_valid() {
    let space = JointSpace::new(vec![0.0], vec![1.0], 0.1).unwrap();
    let mut below = |q: &[f64]| q[0] < 0.55;
    let mut checks = 0;
    let mut scratch = Vec::new();
    // States 0.1, …, 0.5 pass, 0.6 fails: 5 of the 10 steps, 6 states checked.
    assert_eq!(
        space.discrete_valid_prefix(&mut below, &[0.0], &[1.0], &mut scratch, &mut checks),
        (5, 10)
    );
    assert_eq!(checks, 6);
    assert_eq!(
        space.discrete_valid_prefix(&mut below, &[0.0], &[0.5], &mut scratch, &mut checks),
        (5, 5)
    );
    assert_eq!(checks, 11);
}

/// A bug trap in `[-1, 1]^3`: the shell `0.3 ≤ max |x_i| ≤ 0.35` around the origin, open
/// only through a hole at `x0 > 0` where `|x1|, |x2| < 0.08`.
fn bug_trap(q: &[f64]) -> bool {
    let m = q.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let in_shell = (0.3..=0.35).contains(&m);
    let in_hole = q[0] > 0.0 && q[1].abs() < 0.08 && q[2].abs() < 0.08;
    !in_shell || in_hole
}

#[test]
fn a_dynamic_domain_leaves_a_bug_trap_with_fewer_checked_states() {
    // Lazy probes every 0.02 (steps of at most 0.3), from the trap's centre out; the
    // same 16 seeds with and without the domain: nodes by the shell stop drawing steps
    // into it.
    let space = JointSpace::new(vec![-1.0; 3], vec![1.0; 3], 0.02).unwrap();
    let mut ws = RrtConnectWorkspace::new();
    let mut run = |domain_radius: Option<f64>| {
        let mut checks = Vec::new();
        for seed in 0..16 {
            let options = RrtConnectOptions {
                seed,
                max_step: Some(0.3),
                lazy: true,
                domain_radius,
                time_limit: Duration::from_secs(600),
                ..RrtConnectOptions::default()
            };
            let mut v = bug_trap;
            let out = rrt_connect(
                &space,
                &mut v,
                &[0.0; 3],
                &[-0.8, 0.7, -0.6],
                &options,
                &mut ws,
            )
            .unwrap();
            let path = out.path().expect("solved");
            assert!(valid(&space, bug_trap, path));
            checks.push(out.stats().checks);
        }
        checks.iter().sum::<u64>()
    };
    // 196,983 checked states without, 66,000 with a radius of 0.1 (when written).
    let (without, with) = (run(None), run(Some(0.1)));
    assert!(
        2 * with < without,
        "{with} checked states with the domain, {without} without"
    );
}

#[test]
fn shortcutting_never_lengthens_and_stays_valid() {
    let space = cube7();
    let mut ws = RrtConnectWorkspace::new();
    for seed in 0..10 {
        let path = solve(&space, narrow_passage, &START7, &GOAL7, seed, &mut ws);
        let mut v = narrow_passage;
        let short = shortcut(
            &space,
            &mut v,
            &path,
            &ShortcutOptions {
                attempts: 100,
                seed,
                ..ShortcutOptions::default()
            },
            &mut 0,
        )
        .unwrap();
        assert!(valid(&space, narrow_passage, &short), "seed {seed}");
        assert!(short.length(&space) <= path.length(&space), "seed {seed}");
        assert!(short.len() <= path.len());
        assert_eq!(short.waypoint(0), START7);
        assert_eq!(short.waypoint(short.len() - 1), GOAL7);
    }
}

/// The closed-form time of a straight segment `Δq` from rest to rest: path parameter
/// `σ ∈ [0, 1]`, `σ̇ ≤ V = min v_i/|Δq_i|`, `σ̈ ≤ A = min a_i/|Δq_i|`.
#[test]
fn shortcuts_below_the_least_gain_are_not_checked() {
    let space = cube7();
    let mut ws = RrtConnectWorkspace::new();
    let (mut all, mut gainful) = (0, 0);
    for seed in 0..10 {
        let path = solve(&space, narrow_passage, &START7, &GOAL7, seed, &mut ws);
        let run = |min_gain: f64, checks: &mut u64| {
            let mut v = narrow_passage;
            let options = ShortcutOptions {
                attempts: 100,
                seed,
                min_gain,
                drop_redundant: false,
                probe: None,
            };
            shortcut(&space, &mut v, &path, &options, checks).unwrap()
        };
        // No shortcut gains the whole length: nothing is checked, nothing changes.
        let mut none = 0;
        assert_eq!(run(1.0, &mut none), path);
        assert_eq!(none, 0);
        let mut c = 0;
        run(0.0, &mut c);
        all += c;
        let mut c = 0;
        let short = run(0.05, &mut c);
        gainful += c;
        assert!(valid(&space, narrow_passage, &short));
        assert!(short.length(&space) <= path.length(&space) + 1e-12);
    }
    assert!(
        gainful < all,
        "{gainful} checked states with a least gain, {all} without"
    );
}

/// Probes at a coarse spacing first reject the shortcuts through the wall before their
/// segment check: fewer states are checked, and every segment of the result still passed
/// the segment check at the resolution.
#[test]
fn probing_shortcuts_first_checks_fewer_states() {
    let space = cube7();
    let mut ws = RrtConnectWorkspace::new();
    let (mut probed, mut plain) = (0, 0);
    for seed in 0..10 {
        let path = solve(&space, narrow_passage, &START7, &GOAL7, seed, &mut ws);
        let run = |probe: Option<f64>, checks: &mut u64| {
            let mut v = narrow_passage;
            let options = ShortcutOptions {
                attempts: 100,
                seed,
                probe,
                ..ShortcutOptions::default()
            };
            shortcut(&space, &mut v, &path, &options, checks).unwrap()
        };
        let short = run(Some(0.25), &mut probed);
        assert!(valid(&space, narrow_passage, &short), "seed {seed}");
        assert!(short.length(&space) <= path.length(&space) + 1e-12);
        run(None, &mut plain);
    }
    assert!(
        probed < plain,
        "{probed} checked states with probes, {plain} without"
    );
}

#[test]
fn a_probe_spacing_that_is_not_positive_is_an_error() {
    let space = cube7();
    let path = JointPath::from_flat(7, [[-0.8; 7], [-0.5; 7], [-0.2; 7]].concat());
    for probe in [0.0, -0.1, f64::NAN, f64::INFINITY, 1e-9] {
        let mut v = narrow_passage;
        let options = ShortcutOptions {
            probe: Some(probe),
            ..ShortcutOptions::default()
        };
        let err = shortcut(&space, &mut v, &path, &options, &mut 0).unwrap_err();
        assert!(err.to_string().contains("probe"), "{probe}: {err}");
    }
}

#[test]
fn the_redundant_waypoint_pass_runs_only_when_asked() {
    let space = cube7();
    // Three waypoints on one free line: the middle one is redundant.
    let path = JointPath::from_flat(7, [[-0.8; 7], [-0.5; 7], [-0.2; 7]].concat());
    let mut v = narrow_passage;
    let mut options = ShortcutOptions {
        attempts: 0,
        drop_redundant: false,
        ..ShortcutOptions::default()
    };
    let mut checks = 0;
    assert_eq!(
        shortcut(&space, &mut v, &path, &options, &mut checks).unwrap(),
        path
    );
    assert_eq!(checks, 0);
    options.drop_redundant = true;
    let short = shortcut(&space, &mut v, &path, &options, &mut checks).unwrap();
    assert_eq!(short.to_vecs(), vec![vec![-0.8; 7], vec![-0.2; 7]]);
    assert!(checks > 0);
}

fn trapezoid_time(dq: &[f64], v: &[f64], a: &[f64]) -> f64 {
    let vmax = dq
        .iter()
        .zip(v)
        .map(|(d, v)| v / d.abs())
        .fold(f64::INFINITY, f64::min);
    let amax = dq
        .iter()
        .zip(a)
        .map(|(d, a)| a / d.abs())
        .fold(f64::INFINITY, f64::min);
    if vmax * vmax / amax <= 1.0 {
        1.0 / vmax + vmax / amax
    } else {
        2.0 / amax.sqrt()
    }
}

fn check_limits(traj: &moma::planning::JointTrajectory, limits: &JointLimits) {
    let tol = 1.0 + 1e-9;
    for k in 0..traj.t.len() {
        for i in 0..limits.velocity.len() {
            assert!(
                traj.qd[k][i].abs() <= limits.velocity[i] * tol,
                "qd[{k}][{i}] = {}",
                traj.qd[k][i]
            );
            assert!(
                traj.qdd[k][i].abs() <= limits.acceleration[i] * tol,
                "qdd[{k}][{i}] = {}",
                traj.qdd[k][i]
            );
        }
    }
    let last = traj.t.len() - 1;
    assert!(
        traj.qd[0]
            .iter()
            .chain(&traj.qd[last])
            .all(|v| v.abs() < 1e-12)
    );
    assert_eq!(traj.t[last], traj.duration);
    // Velocity is continuous: no jump larger than the acceleration limit allows.
    for k in 1..traj.t.len() {
        let dt = traj.t[k] - traj.t[k - 1];
        for i in 0..limits.velocity.len() {
            let jump = (traj.qd[k][i] - traj.qd[k - 1][i]).abs();
            assert!(
                jump <= limits.acceleration[i] * dt * tol + 1e-12,
                "qd jump at sample {k}, joint {i}"
            );
        }
    }
}

#[test]
fn a_straight_segment_takes_the_bang_coast_bang_time() {
    let space =
        JointSpace::with_weights(vec![-2.0; 3], vec![2.0; 3], vec![1.0, 2.0, 0.5], 0.01).unwrap();
    let (q0, q1) = ([-0.5, 0.3, 0.0], [0.5, -0.2, 0.2]);
    let dq: Vec<f64> = q0.iter().zip(&q1).map(|(a, b)| b - a).collect();
    let path = JointPath::from_flat(3, [q0, q1].concat());
    let acceleration = vec![2.0, 3.0, 0.1];
    // Coasting (joint 1 limits the speed, joint 2 the acceleration), then no coasting.
    for velocity in [vec![1.0, 0.2, 1.0], vec![10.0, 10.0, 10.0]] {
        let limits = JointLimits {
            velocity: velocity.clone(),
            acceleration: acceleration.clone(),
        };
        let mut always = |_: &[f64]| true;
        let traj = time_optimal(
            &space,
            &mut always,
            &path,
            &limits,
            &TimingOptions::default(),
        )
        .unwrap();
        let best = trapezoid_time(&dq, &velocity, &acceleration);
        assert!(
            traj.duration >= best * (1.0 - 1e-9),
            "{} < {best}",
            traj.duration
        );
        assert!(
            traj.duration <= best * (1.0 + 1e-3),
            "{} vs {best}",
            traj.duration
        );
        check_limits(&traj, &limits);
        assert_eq!(traj.q[0], q0);
        let last = traj.q.len() - 1;
        for i in 0..3 {
            assert!((traj.q[last][i] - q1[i]).abs() < 1e-12);
        }
    }
}

#[test]
fn planned_path_is_timed_within_limits_and_blends_stay_valid() {
    let space = cube7();
    let mut ws = RrtConnectWorkspace::new();
    let limits = JointLimits {
        velocity: vec![1.0, 1.2, 0.8, 1.5, 2.0, 2.0, 2.5],
        acceleration: vec![3.0, 2.0, 4.0, 5.0, 6.0, 6.0, 8.0],
    };
    for seed in 0..5 {
        let path = solve(&space, narrow_passage, &START7, &GOAL7, seed, &mut ws);
        let mut v = narrow_passage;
        let short = shortcut(
            &space,
            &mut v,
            &path,
            &ShortcutOptions {
                attempts: 100,
                seed,
                ..ShortcutOptions::default()
            },
            &mut 0,
        )
        .unwrap();
        let options = TimingOptions::default();
        let traj = time_optimal(&space, &mut v, &short, &limits, &options).unwrap();
        check_limits(&traj, &limits);
        // Checked states are at most the resolution apart, so every state of the
        // trajectory lies within half of it of a valid state: outside the wall eroded by it.
        let h = 0.5 * space.resolution() + 1e-9;
        for (k, q) in traj.q.iter().enumerate() {
            let in_eroded_wall =
                q[0].abs() < 0.05 - h && !(q[1].abs() < 0.1 + h && q[2].abs() < 0.1 + h);
            assert!(
                !in_eroded_wall && space.contains(q),
                "seed {seed} sample {k}: {q:?}"
            );
        }
        assert_eq!(traj.blend_deviations.len(), short.len() - 2);
        assert!(
            traj.blend_deviations
                .iter()
                .all(|d| *d <= options.max_deviation * (1.0 + 1e-12))
        );
    }
}

#[test]
fn a_blend_that_would_cut_an_obstacle_shrinks_or_stops() {
    let space = JointSpace::new(vec![-0.5; 2], vec![1.5; 2], 0.001).unwrap();
    let path = JointPath::from_flat(2, vec![0.0, 0.0, 1.0, 0.0, 1.0, 1.0]);
    let limits = JointLimits {
        velocity: vec![1.0, 1.0],
        acceleration: vec![1.0, 1.0],
    };
    let options = TimingOptions {
        max_deviation: 0.1,
        ..TimingOptions::default()
    };
    // Free space ends 0.01 inside the corner: the 0.1 blend cuts into the obstacle.
    let mut near = |q: &[f64]| !(q[0] < 0.99 && q[1] > 0.01);
    let traj = time_optimal(&space, &mut near, &path, &limits, &options).unwrap();
    let d = traj.blend_deviations[0];
    assert!(d > 0.0 && d < 0.1, "{d}");
    assert!(traj.q.iter().all(|q| near(q)));
    check_limits(&traj, &limits);
    // Nothing off the two segments is valid: the trajectory stops at the corner.
    let mut on_segments = |q: &[f64]| q[0] >= 1.0 || q[1] <= 0.0;
    let traj = time_optimal(&space, &mut on_segments, &path, &limits, &options).unwrap();
    assert_eq!(traj.blend_deviations, vec![0.0]);
    assert!(traj.q.iter().all(|q| on_segments(q)));
    check_limits(&traj, &limits);
    // Stopping costs time: two rest-to-rest unit segments.
    let one = trapezoid_time(&[1.0], &[1.0], &[1.0]);
    assert!(
        (traj.duration - 2.0 * one).abs() < 1e-3 * one,
        "{}",
        traj.duration
    );
}

#[test]
fn bad_input_names_the_field() {
    let named = |e: Error, field: &str| {
        let text = e.to_string();
        assert!(text.contains(field), "{text} does not name {field}");
    };
    named(
        JointSpace::new(vec![0.0], vec![1.0], 0.0).unwrap_err(),
        "resolution",
    );
    named(
        JointSpace::new(vec![0.0], vec![1.0], 1e-12).unwrap_err(),
        "resolution",
    );
    named(
        JointSpace::new(vec![2.0], vec![1.0], 0.1).unwrap_err(),
        "lower[0]",
    );
    named(
        JointSpace::new(vec![0.0, 0.0], vec![1.0], 0.1).unwrap_err(),
        "upper",
    );
    named(
        JointSpace::with_weights(vec![0.0], vec![1.0], vec![-1.0], 0.1).unwrap_err(),
        "weights[0]",
    );
    let space = square();
    let mut ws = RrtConnectWorkspace::new();
    let opts = RrtConnectOptions::default();
    let mut v = wall_with_gap;
    named(
        rrt_connect(&space, &mut v, &[1.5, 0.1], &[0.9, 0.1], &opts, &mut ws).unwrap_err(),
        "start[0]",
    );
    named(
        rrt_connect(&space, &mut v, &[0.1, 0.1], &[0.5, 0.1], &opts, &mut ws).unwrap_err(),
        "goal",
    );
    named(
        rrt_connect(&space, &mut v, &[0.1], &[0.9, 0.1], &opts, &mut ws).unwrap_err(),
        "start",
    );
    named(
        rrt_connect(
            &space,
            &mut v,
            &[f64::NAN, 0.1],
            &[0.9, 0.1],
            &opts,
            &mut ws,
        )
        .unwrap_err(),
        "start",
    );
    let bad_step = RrtConnectOptions {
        max_step: Some(0.0),
        ..opts
    };
    named(
        rrt_connect(&space, &mut v, &[0.1, 0.1], &[0.9, 0.1], &bad_step, &mut ws).unwrap_err(),
        "max_step",
    );
    let bad_domain = RrtConnectOptions {
        domain_radius: Some(-1.0),
        ..RrtConnectOptions::default()
    };
    named(
        rrt_connect(
            &space,
            &mut v,
            &[0.1, 0.1],
            &[0.9, 0.1],
            &bad_domain,
            &mut ws,
        )
        .unwrap_err(),
        "domain_radius",
    );
    for (share, radius, field) in [
        (1.5, 0.3, "local_share"),
        (f64::NAN, 0.3, "local_share"),
        (0.3, 0.0, "local_radius"),
        (0.3, f64::INFINITY, "local_radius"),
    ] {
        let bad_local = RrtConnectOptions {
            local_share: share,
            local_radius: radius,
            ..RrtConnectOptions::default()
        };
        named(
            rrt_connect(
                &space,
                &mut v,
                &[0.1, 0.1],
                &[0.9, 0.1],
                &bad_local,
                &mut ws,
            )
            .unwrap_err(),
            field,
        );
    }
    let path = JointPath::from_flat(2, vec![0.1, 0.1, 0.2, 0.2]);
    named(
        shortcut(
            &space,
            &mut v,
            &path,
            &ShortcutOptions {
                min_gain: 1.5,
                ..ShortcutOptions::default()
            },
            &mut 0,
        )
        .unwrap_err(),
        "min_gain",
    );
    let limits = JointLimits {
        velocity: vec![1.0, 0.0],
        acceleration: vec![1.0, 1.0],
    };
    named(
        time_optimal(&space, &mut v, &path, &limits, &TimingOptions::default()).unwrap_err(),
        "velocity limits[1]",
    );
    let limits = JointLimits {
        velocity: vec![1.0, 1.0],
        acceleration: vec![1.0, 1.0],
    };
    let tiny = TimingOptions {
        path_step: 1e-12,
        ..TimingOptions::default()
    };
    named(
        time_optimal(&space, &mut v, &path, &limits, &tiny).unwrap_err(),
        "path_step",
    );
    let tiny = TimingOptions {
        sample_period: 1e-12,
        ..TimingOptions::default()
    };
    named(
        time_optimal(&space, &mut v, &path, &limits, &tiny).unwrap_err(),
        "sample_period",
    );
    let outside = JointPath::from_flat(2, vec![0.1, 0.1, 2.0, 0.2]);
    named(
        shortcut(
            &space,
            &mut v,
            &outside,
            &ShortcutOptions::default(),
            &mut 0,
        )
        .unwrap_err(),
        "path waypoint 1",
    );
}

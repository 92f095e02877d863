//! Collision-free motion of a planning group from a start state to a goal state or a goal
//! pose: goal states by IK ([`super::goal`]), RRT-Connect with the conservative segment
//! check ([`super::clearance`]), shortcutting, then time-optimal timing with blends that
//! are checked too, and a report of the closest pair. The time limit holds in every
//! phase: from the deadline on the checker refuses every state unchecked
//! ([`ClearanceChecker::set_deadline`]), so what only improves a checked path (shortcuts,
//! dropped waypoints, blends) is skipped and the trajectory stops at those waypoints, and
//! the report measures states only while time is left; a run returns within the limit
//! plus the one state in hand as it passes. See `docs/motion.md`.

use super::clearance::{ClearanceChecker, ClosestPair};
use super::goal::{GoalPose, ik_goals};
use super::group::JointGroup;
use crate::collision::{GeometryModel, Scene};
use crate::multibody::Model;
use crate::planning::{
    JointLimits, JointPath, JointSpace, Planned, RrtConnectOptions, RrtConnectWorkspace,
    ShortcutOptions, TimingOptions, rrt_connect, shortcut, time_optimal,
};
use crate::{Error, Result};
use std::time::{Duration, Instant};

/// Shortcut attempts between two looks at the time limit.
const SHORTCUT_ROUND: usize = 25;

/// The least gain a shortcut must offer to be checked, as a fraction of the path's length.
const SHORTCUT_MIN_GAIN: f64 = 0.01;

/// Where the motion must end.
#[derive(Clone, Debug, PartialEq)]
pub enum MotionGoal {
    /// A full configuration (its joints outside the group must equal the start's).
    State(Vec<f64>),
    /// A pose of a frame, reached by IK over the group.
    Pose(GoalPose),
}

impl MotionGoal {
    /// The goal configuration when the goal is a state.
    #[must_use]
    pub fn state(&self) -> Option<&[f64]> {
        match self {
            MotionGoal::State(q) => Some(q),
            MotionGoal::Pose(_) => None,
        }
    }
}

/// The options of [`plan_motion`].
#[derive(Clone, Debug, PartialEq)]
pub struct MotionOptions {
    /// The longest planning time (IK, search, shortcutting, timing and the report
    /// together; module docs).
    pub time_limit: Duration,
    /// The seed of every random choice (IK seeds, samples, shortcuts).
    pub seed: u64,
    /// The clearance (m) every checked state keeps from the scene and between links (half
    /// of it holds everywhere in between); a start or goal state closer than that shrinks
    /// it to half its own clearance.
    pub margin: f64,
    /// The largest joint-space distance between the blend states the timing checks; each
    /// checked state vouches for half of it around it.
    pub resolution: f64,
    /// RRT-Connect's longest step (joint-space norm); `None`: 0.2 × the box diagonal.
    pub max_step: Option<f64>,
    /// The search checks its steps state by state this far apart (joint-space norm,
    /// each state clear of the margin) and runs the continuous check only on the segments
    /// of the paths it finds (`planning::rrt_connect`'s lazy edges; a segment that fails is
    /// cut from its tree and the search goes on); `None`: every step is checked
    /// continuously. Either way every returned segment passed the continuous check.
    pub search_resolution: Option<f64>,
    /// The search's dynamic domain: a tree node whose step was blocked takes later random
    /// samples only this close to it (joint-space norm; `planning::rrt_connect`'s
    /// `domain_radius`); `None`: every sample is taken.
    pub search_domain: Option<f64>,
    /// The share of the search's samples drawn near the extending tree's own nodes
    /// (`planning::rrt_connect`'s `local_share`), in `[0, 1]`; 0: all uniform.
    pub search_local_share: f64,
    /// How far a local sample lies from its node at most, per joint (rad or m;
    /// `planning::rrt_connect`'s `local_radius`).
    pub search_local_radius: f64,
    /// The search's tree with fewer live nodes extends next instead of the two
    /// alternating (`planning::rrt_connect`'s `balanced`): a tree stuck in a pocket gets
    /// the iterations, where its blocked steps cost one probe each.
    pub search_balanced: bool,
    /// IK seeds tried for a goal pose.
    pub ik_attempts: usize,
    /// Distinct collision-free IK solutions sought before planning.
    pub ik_solutions: usize,
    /// Random shortcut attempts (in rounds of 25, while the time limit allows).
    pub shortcut_attempts: usize,
    /// Acceleration limit per group joint (m/s² or rad/s²).
    pub acceleration: Vec<f64>,
    /// The largest distance of a timing blend from its waypoint (joint-space norm).
    pub max_deviation: f64,
    /// The time between trajectory samples (s).
    pub sample_period: f64,
}

impl MotionOptions {
    /// The defaults for a group of `dim` joints: 1 s, seed 0, a 2 mm margin, blends
    /// checked every 0.01 rad (or m), search steps of at most 1 rad (or m; Fetch's arm box
    /// diagonal is about 13) probed every 0.25 rad (or m) and checked continuously on the
    /// paths found, a dynamic domain of 2 rad (or m) around blocked nodes, 30 % of the
    /// samples within 0.8 rad (or m) per joint of a tree node, the smaller tree extending
    /// next, 200 IK seeds for up to 4 solutions, 100 shortcut
    /// attempts, 1 rad/s² (m/s²) on every joint, blends within 0.1, samples every 10 ms.
    #[must_use]
    pub fn new(dim: usize) -> Self {
        MotionOptions {
            time_limit: Duration::from_secs(1),
            seed: 0,
            margin: 2e-3,
            resolution: 0.01,
            max_step: Some(1.0),
            search_resolution: Some(0.25),
            search_domain: Some(2.0),
            search_local_share: 0.3,
            search_local_radius: 0.8,
            search_balanced: true,
            ik_attempts: 200,
            ik_solutions: 4,
            shortcut_attempts: 100,
            acceleration: vec![1.0; dim],
            max_deviation: 0.1,
            sample_period: 0.01,
        }
    }
}

/// Why a query was not solved.
#[derive(Clone, Debug, PartialEq)]
pub enum NotSolved {
    /// The time limit passed before a path was found.
    TimeLimit,
    /// The search's iteration limit was reached.
    IterationLimit,
    /// No IK attempt reached the goal pose within the tolerances and the joint limits.
    GoalUnreachable {
        /// Attempts made.
        attempts: usize,
        /// The smallest position error reached (m).
        best_position_error: f64,
        /// The smallest rotation error reached (rad).
        best_orientation_error: f64,
    },
    /// IK reached the pose, but every solution was in collision.
    GoalInCollision {
        /// Attempts made.
        attempts: usize,
        /// Attempts that reached the pose.
        reached: usize,
    },
}

impl std::fmt::Display for NotSolved {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            NotSolved::TimeLimit => write!(f, "time limit reached before a path was found"),
            NotSolved::IterationLimit => write!(f, "iteration limit reached"),
            NotSolved::GoalUnreachable {
                attempts,
                best_position_error,
                ..
            } if *attempts == 0 => write!(
                f,
                "goal pose unreachable: {best_position_error:.4} m beyond every position the \
                 group's joints can move the frame to (no IK attempted)"
            ),
            NotSolved::GoalUnreachable {
                attempts,
                best_position_error,
                best_orientation_error,
            } => write!(
                f,
                "goal pose unreachable: no IK solution within the joint limits and the \
                 tolerances in {attempts} attempts (closest: {best_position_error:.4} m, \
                 {best_orientation_error:.4} rad)"
            ),
            NotSolved::GoalInCollision { attempts, reached } => write!(
                f,
                "goal pose reachable only in collision: {reached} of {attempts} IK attempts \
                 reached it, every solution touches the scene or the robot"
            ),
        }
    }
}

/// A timed trajectory in full configurations.
#[derive(Clone, Debug, PartialEq)]
pub struct MotionTrajectory {
    /// Sample times (s).
    pub t: Vec<f64>,
    /// Full configuration per sample.
    pub q: Vec<Vec<f64>>,
    /// Group joint velocities per sample.
    pub qd: Vec<Vec<f64>>,
    /// The total time (s).
    pub duration: f64,
}

/// The outcome of [`plan_motion`].
#[derive(Clone, Debug, PartialEq)]
pub struct MotionResult {
    /// `None` when solved, else why not.
    pub not_solved: Option<NotSolved>,
    /// Planning time (IK, search, shortcut and timing; not the report pass).
    pub planning_time: Duration,
    /// The goal state reached (full configuration), when solved.
    pub goal_state: Option<Vec<f64>>,
    /// Path waypoints (full configurations), joined by straight segments.
    pub path: Vec<Vec<f64>>,
    /// The timed trajectory, when solved.
    pub trajectory: Option<MotionTrajectory>,
    /// The closest pair (exact distances) over the first [`Self::closest_states`] of the
    /// path's waypoints followed by the trajectory's samples, when solved.
    pub closest: Option<ClosestPair>,
    /// The states `closest` covers, counted along the path's waypoints and then the
    /// trajectory's samples: all `path.len() + t.len()` of them when the time limit left
    /// room, else a prefix (the start always: it is measured before planning).
    pub closest_states: usize,
    /// States checked for collision while planning.
    pub checks: u64,
    /// Exact pair distances computed while planning (the pairs no bound ruled out).
    pub distances: u64,
    /// RRT-Connect iterations.
    pub iterations: usize,
    /// Where the planning time went.
    pub phases: PhaseTimes,
    /// Where the checked states went (phase by phase; they sum to `checks`).
    pub phase_checks: PhaseChecks,
    /// IK attempts for a goal pose (0 for a goal state).
    pub ik_attempts: usize,
    /// Collision-free IK goal states found.
    pub ik_solutions: usize,
    /// The margin kept: the option's, or half the start's (goal state's) clearance when
    /// that is smaller.
    pub margin: f64,
}

/// Where the planning time went, phase by phase (wall clock).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PhaseTimes {
    /// Building the collision check and checking the start and goal states.
    pub setup: Duration,
    /// Goal states by IK (goal poses only).
    pub ik: Duration,
    /// RRT-Connect.
    pub search: Duration,
    /// Shortcutting.
    pub shortcut: Duration,
    /// Time-optimal timing with its blend checks.
    pub timing: Duration,
}

/// The states checked in each phase of the planning.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PhaseChecks {
    /// The start and goal states.
    pub setup: u64,
    /// Goal states by IK (goal poses only).
    pub ik: u64,
    /// RRT-Connect: its probes and the continuous checks of the paths it found.
    pub search: u64,
    /// Shortcutting.
    pub shortcut: u64,
    /// The timing's blend checks.
    pub timing: u64,
}

/// A planning problem: the robot, its geometry, the scene and the group.
#[derive(Clone, Copy, Debug)]
pub struct MotionProblem<'a> {
    /// The rigid-body model.
    pub model: &'a Model,
    /// Its collision geometry.
    pub geometry: &'a GeometryModel,
    /// The obstacles.
    pub scene: &'a Scene,
    /// The joints that move.
    pub group: &'a JointGroup,
}

fn closest_message(c: &ClosestPair, what: &str) -> String {
    let other = if c.scene_object {
        format!("scene object '{}'", c.other)
    } else {
        format!("link '{}'", c.other)
    };
    format!(
        "{other} intersects link '{}' at the {what} ({:.4} m deep)",
        c.link, -c.distance
    )
}

/// Checks a full state: length, finite, group in the box, clear of everything; returns
/// the group's state and its closest pair (`None` when nothing is checked).
fn check_state(
    problem: &MotionProblem<'_>,
    checker: &mut ClearanceChecker<'_>,
    field: &str,
    q: &[f64],
) -> Result<(Vec<f64>, Option<ClosestPair>)> {
    crate::error::ensure_len(field, problem.model.nq, q.len())?;
    crate::error::ensure_finite(field, q)?;
    problem.group.check_in_box(field, q)?;
    let mut x = vec![0.0; problem.group.dim()];
    problem.group.extract(q, &mut x);
    let clearance = checker.distance_report(&x);
    if let Some(c) = &clearance
        && c.distance <= 0.0
    {
        return Err(Error::invalid(
            field,
            closest_message(c, &format!("{field} state")),
        ));
    }
    Ok((x, clearance))
}

/// The distance of a closest pair (infinite for none).
fn distance_of(c: Option<&ClosestPair>) -> f64 {
    c.map_or(f64::INFINITY, |c| c.distance)
}

fn check_options(o: &MotionOptions, dim: usize) -> Result<()> {
    crate::error::ensure_len("acceleration limits", dim, o.acceleration.len())?;
    for (field, v) in [
        ("resolution", o.resolution),
        ("sample_period", o.sample_period),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::invalid(field, format!("{v} is not positive")));
        }
    }
    for (field, v) in [
        ("search_resolution", o.search_resolution),
        ("search_domain", o.search_domain),
    ] {
        if let Some(r) = v
            && !(r.is_finite() && r > 0.0)
        {
            return Err(Error::invalid(
                field,
                format!("{r} is not a positive finite length"),
            ));
        }
    }
    if !(0.0..=1.0).contains(&o.search_local_share) {
        return Err(Error::invalid(
            "search_local_share",
            format!("{} is not a share in [0, 1]", o.search_local_share),
        ));
    }
    if !(o.search_local_radius.is_finite() && o.search_local_radius > 0.0) {
        return Err(Error::invalid(
            "search_local_radius",
            format!("{} is not a positive finite length", o.search_local_radius),
        ));
    }
    if !(o.max_deviation.is_finite() && o.max_deviation >= 0.0) {
        return Err(Error::invalid("max_deviation", "is negative or not finite"));
    }
    Ok(())
}

/// Plans a collision-free, timed motion of the group (module docs); the start is a full
/// configuration, the joints outside the group stay where it puts them.
///
/// # Errors
/// [`Error::InvalidInput`] naming the field for bad input: a start or goal state of the
/// wrong length, outside the planning box, or in contact (naming the link and the scene
/// object or the other link; touching counts), a goal state that moves joints outside the group, invalid
/// options.
pub fn plan_motion(
    problem: &MotionProblem<'_>,
    start: &[f64],
    goal: &MotionGoal,
    options: &MotionOptions,
) -> Result<MotionResult> {
    let began = Instant::now();
    let deadline = began + options.time_limit;
    let group = problem.group;
    let dim = group.dim();
    check_options(options, dim)?;
    crate::error::ensure_len("start", problem.model.nq, start.len())?;
    let weights = vec![1.0; dim];
    let mut checker = ClearanceChecker::new(
        problem.model,
        problem.geometry,
        problem.scene,
        group,
        start,
        options.margin,
        &weights,
    )?;
    let space = JointSpace::with_weights(
        group.lower.clone(),
        group.upper.clone(),
        weights,
        options.resolution,
    )?;
    let (x_start, start_pair) = check_state(problem, &mut checker, "start", start)?;
    // A start (or goal state) closer than the margin shrinks it to half its clearance.
    checker.set_margin(options.margin.min(0.5 * distance_of(start_pair.as_ref())));
    // No state is evaluated past the time limit (the one in hand as it passes aside).
    checker.set_deadline(Some(deadline));
    let mut result = MotionResult {
        not_solved: None,
        planning_time: Duration::ZERO,
        goal_state: None,
        path: Vec::new(),
        trajectory: None,
        closest: None,
        closest_states: 0,
        checks: 0,
        distances: 0,
        iterations: 0,
        phases: PhaseTimes::default(),
        phase_checks: PhaseChecks::default(),
        ik_attempts: 0,
        ik_solutions: 0,
        margin: 0.0,
    };
    let mut mark = began;
    let mut lap = || {
        let now = Instant::now();
        let d = now - mark;
        mark = now;
        d
    };
    result.phases.setup = lap();
    // The states checked so far, to split them by phase.
    let mut counted = 0u64;
    let mut count = |checker: &ClearanceChecker<'_>| {
        let n = checker.states_checked - counted;
        counted = checker.states_checked;
        n
    };
    result.phase_checks.setup = count(&checker);
    let goals: Vec<Vec<f64>> = match goal {
        MotionGoal::State(q) => {
            let (x, goal_pair) = check_state(problem, &mut checker, "goal", q)?;
            checker.set_margin(checker.margin().min(0.5 * distance_of(goal_pair.as_ref())));
            if let Some(j) =
                (0..problem.model.nq).find(|&i| !group.q_index.contains(&i) && q[i] != start[i])
            {
                return Err(Error::invalid(
                    "goal",
                    format!(
                        "coordinate {j} is outside the group and differs from the start \
                         ({} vs {})",
                        q[j], start[j]
                    ),
                ));
            }
            result.phases.setup += lap();
            result.phase_checks.setup += count(&checker);
            vec![x]
        }
        MotionGoal::Pose(pose) => {
            let found = ik_goals(
                problem.model,
                group,
                start,
                pose,
                &mut checker,
                options.ik_attempts,
                options.ik_solutions.max(1),
                options.seed,
                deadline,
            )?;
            result.phases.ik = lap();
            result.phase_checks.ik = count(&checker);
            result.ik_attempts = found.attempts;
            result.ik_solutions = found.states.len();
            if found.states.is_empty() {
                // No attempt (the goal is out of reach) is the reason even past the deadline.
                result.not_solved = Some(if Instant::now() >= deadline && found.attempts > 0 {
                    NotSolved::TimeLimit
                } else if found.reached == 0 {
                    NotSolved::GoalUnreachable {
                        attempts: found.attempts,
                        best_position_error: found.best_position_error,
                        best_orientation_error: found.best_orientation_error,
                    }
                } else {
                    NotSolved::GoalInCollision {
                        attempts: found.attempts,
                        reached: found.reached,
                    }
                });
                result.checks = checker.states_checked;
                result.distances = checker.distances_computed;
                result.margin = checker.margin();
                result.planning_time = began.elapsed();
                return Ok(result);
            }
            found.states
        }
    };
    // Search: towards each goal state in turn, sharing the time left.
    // A lazy search probes its steps at its own resolution.
    let search_space = match options.search_resolution {
        Some(r) => JointSpace::with_weights(
            group.lower.clone(),
            group.upper.clone(),
            space.weights().to_vec(),
            r,
        )?,
        None => space.clone(),
    };
    let mut ws = RrtConnectWorkspace::new();
    let mut found: Option<(JointPath, usize)> = None;
    let mut limit = NotSolved::TimeLimit;
    for (k, x_goal) in goals.iter().enumerate() {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            break;
        }
        let share = left / (goals.len() - k) as u32;
        let rrt = RrtConnectOptions {
            max_step: options.max_step,
            time_limit: share,
            seed: options.seed.wrapping_add(k as u64),
            lazy: options.search_resolution.is_some(),
            domain_radius: options.search_domain,
            local_share: options.search_local_share,
            local_radius: options.search_local_radius,
            balanced: options.search_balanced,
            ..RrtConnectOptions::default()
        };
        match rrt_connect(&search_space, &mut checker, &x_start, x_goal, &rrt, &mut ws)? {
            Planned::Solved { path, stats } => {
                result.iterations += stats.iterations;
                found = Some((path, k));
                break;
            }
            Planned::NotSolved { limit: l, stats } => {
                result.iterations += stats.iterations;
                if l == crate::planning::PlanLimit::Iterations {
                    limit = NotSolved::IterationLimit;
                }
            }
        }
    }
    result.phases.search = lap();
    result.phase_checks.search = count(&checker);
    let Some((path, k)) = found else {
        result.not_solved = Some(limit);
        result.margin = checker.margin();
        result.checks = checker.states_checked;
        result.distances = checker.distances_computed;
        result.planning_time = began.elapsed();
        return Ok(result);
    };
    let path = shorten(&space, &mut checker, path, options, deadline)?;
    result.phases.shortcut = lap();
    result.phase_checks.shortcut = count(&checker);
    let timed = time_path(&space, &mut checker, group, &path, options)?;
    result.phases.timing = lap();
    result.phase_checks.timing = count(&checker);
    result.planning_time = began.elapsed();
    result.checks = checker.states_checked;
    result.distances = checker.distances_computed;
    result.margin = checker.margin();
    let full = |x: &[f64]| -> Vec<f64> {
        let mut q = start.to_vec();
        group.embed(x, &mut q);
        q
    };
    result.goal_state = Some(full(&goals[k]));
    let waypoints = path.to_vecs();
    result.path = waypoints.iter().map(|x| full(x)).collect();
    // Report: the start's closest pair (measured in the setup), then the waypoints after
    // it and the samples, while the time limit allows.
    let later = waypoints[1..].iter().chain(&timed.q).map(Vec::as_slice);
    let (closest, measured) = closest_until(&mut checker, start_pair, later, deadline);
    result.closest_states = 1 + measured;
    result.closest = closest;
    result.trajectory = Some(MotionTrajectory {
        t: timed.t,
        q: timed.q.iter().map(|x| full(x)).collect(),
        qd: timed.qd,
        duration: timed.duration,
    });
    Ok(result)
}

/// Shortens the search's `path` (its segments are checked): shortcut rounds of
/// [`SHORTCUT_ROUND`] attempts, each seeded from the seed and its number, until the
/// attempts are spent or `deadline` passes, then one pass dropping the redundant
/// waypoints if time remains. Both only improve a valid path: a check refused at the
/// deadline ([`ClearanceChecker::set_deadline`]) keeps the path as it is.
fn shorten(
    space: &JointSpace,
    checker: &mut ClearanceChecker<'_>,
    mut path: JointPath,
    options: &MotionOptions,
    deadline: Instant,
) -> Result<JointPath> {
    let mut extra = 0u64;
    let mut round = 0u64;
    let mut left = options.shortcut_attempts;
    let mut shortcuts = ShortcutOptions {
        attempts: 0,
        seed: options.seed,
        min_gain: SHORTCUT_MIN_GAIN,
        drop_redundant: false,
        // A candidate is probed at the search's resolution first: most that fail do so
        // at a probe, before the continuous check's exact distances.
        probe: options.search_resolution,
    };
    while left > 0 && Instant::now() < deadline {
        shortcuts.attempts = left.min(SHORTCUT_ROUND);
        shortcuts.seed = options.seed.wrapping_add(round);
        path = shortcut(space, checker, &path, &shortcuts, &mut extra)?;
        left -= shortcuts.attempts;
        round += 1;
    }
    if Instant::now() < deadline {
        shortcuts.attempts = 0;
        shortcuts.drop_redundant = true;
        path = shortcut(space, checker, &path, &shortcuts, &mut extra)?;
    }
    Ok(path)
}

/// Times `path` (time-optimal, blends at its waypoints checked state by state, each
/// state vouching for half the resolution around it). A blend whose states the checker
/// refuses, past its deadline too, is halved and then dropped: the trajectory stops at
/// that waypoint, on the path's own checked segments.
fn time_path(
    space: &JointSpace,
    checker: &mut ClearanceChecker<'_>,
    group: &JointGroup,
    path: &JointPath,
    options: &MotionOptions,
) -> Result<crate::planning::JointTrajectory> {
    checker.set_tube(0.5 * options.resolution);
    let timed = time_optimal(
        space,
        checker,
        path,
        &JointLimits {
            velocity: group.velocity.clone(),
            acceleration: options.acceleration.clone(),
        },
        &TimingOptions {
            max_deviation: options.max_deviation,
            sample_period: options.sample_period,
            ..TimingOptions::default()
        },
    );
    checker.set_tube(0.0);
    timed
}

/// The closest pair over `first` (already measured) and the `states` measured in turn
/// while `deadline` has not passed; returns it and how many of `states` it covers.
fn closest_until<'s>(
    checker: &mut ClearanceChecker<'_>,
    first: Option<ClosestPair>,
    states: impl Iterator<Item = &'s [f64]>,
    deadline: Instant,
) -> (Option<ClosestPair>, usize) {
    let mut closest = first;
    let mut measured = 0;
    for x in states {
        if Instant::now() >= deadline {
            break;
        }
        measured += 1;
        if let Some(c) = checker.distance_report(x)
            && c.distance < distance_of(closest.as_ref())
        {
            closest = Some(c);
        }
    }
    (closest, measured)
}

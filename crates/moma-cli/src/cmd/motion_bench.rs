//! `moma motion-bench SCENE_DIR --robot ROBOT.urdf [--srdf FILE] [--package-dir DIR]...
//! [--goal state|pose] [--runs N] [--time-limit s] [--seed N] [--mesh convex|exact] [--problem NAME] [--json
//! OUT.json]`: runs every query of a query folder (`SCENE_DIR/queries.json`, schema in
//! `docs/motion.md`) with `moma motion`'s planner and prints the success rate and the
//! median and 95th-percentile planning time per problem and overall.

use super::collision::MeshMode;
use super::motion::{Robot, options, parse_goal_pose, parse_group};
use anyhow::{Context, Result, bail};
use moma::motion::MotionGoal;
use moma::multibody::RootJoint;
use serde::{Deserialize, Serialize};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `moma motion-bench`.
#[derive(clap::Args)]
pub struct Args {
    /// The query folder: `queries.json` and the scene files it names.
    pub scene_dir: PathBuf,
    /// The robot description (URDF).
    #[arg(long)]
    pub robot: PathBuf,
    /// SRDF whose `<disable_collisions>` pairs are not checked.
    #[arg(long)]
    pub srdf: Option<PathBuf>,
    /// Folder against which `package://PKG/...` mesh URIs resolve; repeatable.
    #[arg(long = "package-dir")]
    pub package_dirs: Vec<PathBuf>,
    /// Plan to each query's goal state, or to its goal pose (IK on the file's `ee_frame`).
    #[arg(long, value_enum, default_value_t = GoalKind::State)]
    pub goal: GoalKind,
    /// Position tolerance of a goal pose (m).
    #[arg(long, default_value_t = 0.01)]
    pub position_tolerance: f64,
    /// Orientation tolerance of a goal pose (rad).
    #[arg(long, default_value_t = 0.01)]
    pub orientation_tolerance: f64,
    /// Seeded runs per query (seeds `seed`, `seed + 1`, …).
    #[arg(long, default_value_t = 1)]
    pub runs: u64,
    /// Longest planning time per run (s).
    #[arg(long, default_value_t = 1.0)]
    pub time_limit: f64,
    /// Seed of the first run.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Clearance every state keeps (m).
    #[arg(long, default_value_t = 0.002)]
    pub margin: f64,
    /// How the scenes' meshes enter the distances (as `moma motion --mesh`).
    #[arg(long, value_enum, default_value_t = MeshMode::Convex)]
    pub mesh: MeshMode,
    /// Only the queries of this problem.
    #[arg(long)]
    pub problem: Option<String>,
    /// Write every run's result here.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// Which goal of a query to plan to.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum GoalKind {
    /// The query's goal state.
    State,
    /// The query's goal pose of `ee_frame`.
    Pose,
}

#[derive(Deserialize)]
struct QueryFile {
    group: Vec<String>,
    ee_frame: String,
    queries: Vec<Query>,
}

#[derive(Deserialize)]
struct Query {
    name: String,
    problem: String,
    scene: String,
    start: Vec<f64>,
    goal_state: Vec<f64>,
    goal_pose: Vec<f64>,
}

#[derive(Serialize)]
struct Run {
    name: String,
    problem: String,
    seed: u64,
    solved: bool,
    reason: Option<String>,
    planning_time_s: f64,
    checks: u64,
    distances: u64,
    min_distance: Option<f64>,
    /// The states `min_distance` covers (`moma motion`'s `min_distance_states`).
    min_distance_states: usize,
    /// Seconds from the call to the plan's return: planning, the report, and the swap of
    /// links in contact at the start for their mesh surfaces before it.
    wall_s: f64,
    /// Seconds in setup, IK, search, shortcutting and timing.
    phases_s: [f64; 5],
    /// States checked in setup, IK, search, shortcutting and timing.
    phase_checks: [u64; 5],
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    // Linear interpolation between the closest ranks (numpy's default).
    let x = p / 100.0 * (sorted.len() - 1) as f64;
    let (i, f) = (x.floor() as usize, x - x.floor());
    let next = sorted[(i + 1).min(sorted.len() - 1)];
    sorted[i] + f * (next - sorted[i])
}

/// Runs `moma motion-bench`.
pub fn run(args: Args) -> Result<()> {
    let file = args.scene_dir.join("queries.json");
    let text = std::fs::read_to_string(&file)
        .with_context(|| format!("{}: cannot read the query file", file.display()))?;
    let qf: QueryFile = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a query file", file.display()))?;
    if args.runs == 0 || args.runs > 1000 {
        bail!("--runs: {} is not in 1..=1000", args.runs);
    }
    let robot = Robot::load(
        &args.robot,
        RootJoint::Fixed,
        args.srdf.as_deref(),
        &args.package_dirs,
    )?;
    let group = parse_group(&robot.model, &qf.group.join(","))
        .with_context(|| format!("{}: group", file.display()))?;
    let mut runs: Vec<Run> = Vec::new();
    for (k, q) in qf.queries.iter().enumerate() {
        if args.problem.as_ref().is_some_and(|p| *p != q.problem) {
            continue;
        }
        let field = format!("{}: queries[{k}] ({})", file.display(), q.name);
        let scene = robot
            .scene(&args.scene_dir.join(&q.scene), args.mesh)
            .with_context(|| field.clone())?;
        let goal = match args.goal {
            GoalKind::State => MotionGoal::State(q.goal_state.clone()),
            GoalKind::Pose => {
                let values: Vec<String> = q.goal_pose.iter().map(f64::to_string).collect();
                MotionGoal::Pose(
                    parse_goal_pose(
                        &robot.model,
                        &format!("{}:{}", qf.ee_frame, values.join(",")),
                        args.position_tolerance,
                        args.orientation_tolerance,
                    )
                    .with_context(|| field.clone())?,
                )
            }
        };
        for r in 0..args.runs {
            let seed = args.seed + r;
            let opts = options(group.dim(), args.time_limit, seed, args.margin, "1.0")?;
            let began = Instant::now();
            let planned = robot.plan(&scene, &group, &q.start, &goal, &opts);
            let wall_s = began.elapsed().as_secs_f64();
            let run = match planned {
                Ok((res, _)) => Run {
                    name: q.name.clone(),
                    problem: q.problem.clone(),
                    seed,
                    solved: res.not_solved.is_none(),
                    reason: res.not_solved.as_ref().map(ToString::to_string),
                    planning_time_s: res.planning_time.as_secs_f64(),
                    checks: res.checks,
                    distances: res.distances,
                    min_distance: res.closest.as_ref().map(|c| c.distance),
                    min_distance_states: res.closest_states,
                    wall_s,
                    phases_s: [
                        res.phases.setup,
                        res.phases.ik,
                        res.phases.search,
                        res.phases.shortcut,
                        res.phases.timing,
                    ]
                    .map(|d| d.as_secs_f64()),
                    phase_checks: [
                        res.phase_checks.setup,
                        res.phase_checks.ik,
                        res.phase_checks.search,
                        res.phase_checks.shortcut,
                        res.phase_checks.timing,
                    ],
                },
                Err(e) => Run {
                    name: q.name.clone(),
                    problem: q.problem.clone(),
                    seed,
                    solved: false,
                    reason: Some(format!("error: {e}")),
                    planning_time_s: f64::NAN,
                    checks: 0,
                    distances: 0,
                    min_distance: None,
                    min_distance_states: 0,
                    wall_s,
                    phases_s: [f64::NAN; 5],
                    phase_checks: [0; 5],
                },
            };
            runs.push(run);
        }
    }
    if runs.is_empty() {
        bail!("{}: no query to run", file.display());
    }
    let mut problems: Vec<String> = Vec::new();
    for r in &runs {
        if !problems.contains(&r.problem) {
            problems.push(r.problem.clone());
        }
    }
    problems.push("overall".into());
    println!(
        "# moma motion-bench: {} runs, time limit {} s, goal {:?}, margin {} m",
        runs.len(),
        args.time_limit,
        args.goal,
        args.margin
    );
    println!(
        "{:18} {:>7} {:>11} {:>10} {:>9} {:>10}",
        "problem", "queries", "solved", "median ms", "p95 ms", "checks/run"
    );
    for p in &problems {
        let rs: Vec<&Run> = runs
            .iter()
            .filter(|r| p == "overall" || r.problem == *p)
            .collect();
        let mut times: Vec<f64> = rs
            .iter()
            .filter(|r| r.solved)
            .map(|r| r.planning_time_s * 1e3)
            .collect();
        times.sort_by(f64::total_cmp);
        let mut checks: Vec<f64> = rs.iter().map(|r| r.checks as f64).collect();
        checks.sort_by(f64::total_cmp);
        let queries = rs
            .iter()
            .map(|r| r.name.as_str())
            .collect::<std::collections::BTreeSet<_>>()
            .len();
        let solved = rs.iter().filter(|r| r.solved).count();
        println!(
            "{:18} {:>7} {:>5}/{:<5} {:>10.1} {:>9.1} {:>10.0}",
            p,
            queries,
            solved,
            rs.len(),
            percentile(&times, 50.0),
            percentile(&times, 95.0),
            percentile(&checks, 50.0)
        );
    }
    // Where the time went, over every run that got past its input checks.
    let timed: Vec<&Run> = runs.iter().filter(|r| r.phases_s[0].is_finite()).collect();
    let (mut totals, mut phase_checks) = ([0.0; 5], [0.0; 5]);
    for r in &timed {
        let sums = totals.iter_mut().zip(&mut phase_checks);
        for ((time, checked), (s, n)) in sums.zip(r.phases_s.iter().zip(r.phase_checks)) {
            *time += s;
            *checked += n as f64;
        }
    }
    let all: f64 = totals.iter().sum();
    let checks = timed.iter().map(|r| r.checks).sum::<u64>().max(1) as f64;
    let distances: u64 = timed.iter().map(|r| r.distances).sum();
    if all > 0.0 {
        println!(
            "# time: {}; {:.1} µs per checked state, {:.1} exact pair distances per state \
             (wall clock, all phases)",
            phase_shares(totals, all),
            1e6 * all / checks,
            distances as f64 / checks
        );
        println!("# checked states: {}", phase_shares(phase_checks, checks));
    }
    if let Some(path) = &args.json {
        crate::output::write_json(path, &runs)?;
    }
    Ok(())
}

/// `setup p %, IK p %, search p %, shortcut p %, timing p %`: each phase's part of `whole`.
fn phase_shares(parts: [f64; 5], whole: f64) -> String {
    ["setup", "IK", "search", "shortcut", "timing"]
        .iter()
        .zip(parts)
        .map(|(name, part)| format!("{name} {:.1} %", 100.0 * part / whole))
        .collect::<Vec<_>>()
        .join(", ")
}

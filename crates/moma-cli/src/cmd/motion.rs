//! `moma motion ROBOT.urdf --root fixed [--srdf FILE] [--package-dir DIR]... --scene
//! SCENE.yaml --group J1,J2,… --start STATES.json (--goal-state STATES.json | --goal-pose
//! FRAME:x,y,z,qx,qy,qz,qw [--position-tolerance m] [--orientation-tolerance rad])
//! [--time-limit s] [--seed N] [--mesh convex|exact] [--output OUT.json]`: a collision-free, timed motion of a
//! joint group among a scene's obstacles (`docs/motion.md`). Exit 3 when not solved, with
//! the reason; the JSON is written either way.

use super::collision::MeshMode;
use super::common::{goal_not_reached, load_model, parse_list, parse_root, read_states};
use anyhow::{Context, Result, anyhow, bail};
use moma::collision::{GeometryModel, GeometryOptions, Scene, SceneOptions, read_scene};
use moma::ik::tasks::target_from_slice;
use moma::motion::{
    GoalPose, JointGroup, MeshSource, MotionGoal, MotionOptions, MotionProblem, MotionResult,
    plan_motion, surface_links_for_states,
};
use moma::multibody::{FrameKind, Model, RootJoint};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Duration;

/// Arguments of `moma motion`.
#[derive(clap::Args)]
pub struct Args {
    /// The robot description (URDF); its `<collision>` elements are the geometry.
    pub urdf: PathBuf,
    /// Root joint: fixed (the scene's poses are in the robot's root link or `world`).
    #[arg(long, value_parser = parse_root)]
    pub root: RootJoint,
    /// SRDF whose `<disable_collisions>` pairs are not checked.
    #[arg(long)]
    pub srdf: Option<PathBuf>,
    /// Folder against which `package://PKG/...` mesh URIs resolve; repeatable.
    #[arg(long = "package-dir")]
    pub package_dirs: Vec<PathBuf>,
    /// MoveIt planning-scene YAML (MotionBenchMaker's schema).
    #[arg(long)]
    pub scene: PathBuf,
    /// The joints that move, comma-separated (e.g. Fetch's arm_with_torso).
    #[arg(long)]
    pub group: String,
    /// States file: its first state's `q` (full model order, moma's layout) is the start.
    #[arg(long)]
    pub start: PathBuf,
    /// States file: its first state's `q` is the goal.
    #[arg(
        long,
        conflicts_with = "goal_pose",
        required_unless_present = "goal_pose"
    )]
    pub goal_state: Option<PathBuf>,
    /// Goal pose of a frame: FRAME:x,y,z,qx,qy,qz,qw (or FRAME:x,y,z, identity rotation),
    /// in the world (root link) frame.
    #[arg(long)]
    pub goal_pose: Option<String>,
    /// Largest distance of the frame from the goal position (m).
    #[arg(long, default_value_t = 0.01)]
    pub position_tolerance: f64,
    /// Largest rotation angle of the frame from the goal orientation (rad).
    #[arg(long, default_value_t = 0.01)]
    pub orientation_tolerance: f64,
    /// Longest planning time (s).
    #[arg(long, default_value_t = 1.0)]
    pub time_limit: f64,
    /// Seed of every random choice.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Clearance every state keeps from the scene and between links (m).
    #[arg(long, default_value_t = 0.002)]
    pub margin: f64,
    /// How the scene's meshes enter the distances, as `moma collision --mesh`: each as its
    /// convex hull, or each as its triangles (a concave mesh, such as a shelf unit, then has
    /// no inside).
    #[arg(long, value_enum, default_value_t = MeshMode::Convex)]
    pub mesh: MeshMode,
    /// Acceleration limit of every group joint (rad/s², m/s²): one value, or one per joint.
    #[arg(long, default_value = "1.0")]
    pub max_acceleration: String,
    /// Write the JSON here (atomically) instead of standard output.
    #[arg(long)]
    pub output: Option<PathBuf>,
}

/// The robot as the planner needs it.
pub struct Robot {
    /// The rigid-body model.
    pub model: Model,
    /// Its collision geometry (hulls).
    pub geometry: GeometryModel,
    /// Where its meshes are (for links swapped to their mesh surfaces).
    pub source: MeshSource,
}

impl Robot {
    /// Loads the model and its geometry.
    pub fn load(
        urdf: &Path,
        root: RootJoint,
        srdf: Option<&Path>,
        package_dirs: &[PathBuf],
    ) -> Result<Self> {
        let model = load_model(urdf, root)?;
        let geometry = GeometryModel::from_urdf(
            &model,
            urdf,
            &GeometryOptions {
                package_dirs: package_dirs.to_vec(),
                srdf: srdf.map(Path::to_path_buf),
            },
        )?;
        Ok(Robot {
            model,
            geometry,
            source: MeshSource {
                urdf: urdf.to_path_buf(),
                package_dirs: package_dirs.to_vec(),
            },
        })
    }

    /// Reads a scene whose poses are in `world` or (fixed root) the root link; with
    /// [`MeshMode::Exact`] its meshes are their triangles ([`Scene::with_mesh_triangles`]).
    pub fn scene(&self, path: &Path, mesh: MeshMode) -> Result<Scene> {
        let mut world_frames = vec!["world".to_string()];
        if self.model.root == RootJoint::Fixed
            && let Some(f) = self.model.frames.iter().find(|f| f.kind == FrameKind::Body)
        {
            world_frames.push(f.name.clone());
        }
        let scene = read_scene(
            path,
            &SceneOptions {
                world_frames,
                package_dirs: self.source.package_dirs.clone(),
            },
        )?;
        Ok(match mesh {
            MeshMode::Convex => scene,
            MeshMode::Exact => scene
                .with_mesh_triangles()
                .with_context(|| format!("{}: --mesh exact", path.display()))?,
        })
    }

    /// Plans one query: swaps concave links in contact at the start (or at a goal state)
    /// for their mesh surfaces, then plans. Returns the result and the links swapped.
    pub fn plan(
        &self,
        scene: &Scene,
        group: &JointGroup,
        start: &[f64],
        goal: &MotionGoal,
        options: &MotionOptions,
    ) -> Result<(MotionResult, Vec<String>)> {
        moma::error::ensure_len("start", self.model.nq, start.len())?;
        let states: Vec<&[f64]> = std::iter::once(start).chain(goal.state()).collect();
        let (geometry, swapped) = surface_links_for_states(
            &self.model,
            &self.geometry,
            scene,
            group,
            &states,
            options.margin,
            &self.source,
        )?;
        let problem = MotionProblem {
            model: &self.model,
            geometry: &geometry,
            scene,
            group,
        };
        Ok((plan_motion(&problem, start, goal, options)?, swapped))
    }
}

/// The group from `J1,J2,…`.
pub fn parse_group(model: &Model, text: &str) -> Result<JointGroup> {
    let names: Vec<&str> = text.split(',').map(str::trim).collect();
    JointGroup::new(model, &names).context("--group")
}

/// The first state's q of a states file.
pub fn first_q(path: &Path) -> Result<Vec<f64>> {
    let states = read_states(path, &["q"])?;
    states
        .into_iter()
        .next()
        .map(|s| s.q)
        .ok_or_else(|| anyhow!("{}: states: the file holds no state", path.display()))
}

/// Parses `FRAME:x,y,z[,qx,qy,qz,qw]`.
pub fn parse_goal_pose(model: &Model, text: &str, pos_tol: f64, rot_tol: f64) -> Result<GoalPose> {
    let (frame, values) = text
        .split_once(':')
        .ok_or_else(|| anyhow!("--goal-pose: expected FRAME:x,y,z,qx,qy,qz,qw, got '{text}'"))?;
    let frame = model
        .frame_id(frame)
        .map_err(|e| anyhow!("--goal-pose: {e}"))?;
    let values = parse_list("--goal-pose", values)?;
    let target = target_from_slice(&values).map_err(|e| anyhow!("--goal-pose: {e}"))?;
    for (name, v) in [
        ("--position-tolerance", pos_tol),
        ("--orientation-tolerance", rot_tol),
    ] {
        if !(v.is_finite() && v > 0.0) {
            bail!("{name}: {v} is not a positive number");
        }
    }
    Ok(GoalPose {
        frame,
        target,
        position_tolerance: pos_tol,
        orientation_tolerance: rot_tol,
    })
}

/// The smallest acceleration limit `--max-acceleration` takes (rad/s², m/s²).
const MIN_ACCELERATION: f64 = 1e-3;

/// The input a planning error is about, as its context: the goal-state file (or
/// `--goal-pose`) for the goal's faults, the start file for the others (the start's own
/// faults, and its swap to mesh surfaces).
fn name_plan_error(e: anyhow::Error, start: &Path, goal: Option<&Path>) -> anyhow::Error {
    let field = match e.downcast_ref::<moma::Error>() {
        Some(
            moma::Error::InvalidInput { field, .. }
            | moma::Error::WrongLength { field, .. }
            | moma::Error::NonFinite { field },
        ) => field.as_str(),
        _ => "",
    };
    if field.starts_with("goal") {
        match goal {
            Some(p) => e.context(p.display().to_string()),
            None => e.context("--goal-pose"),
        }
    } else {
        e.context(start.display().to_string())
    }
}

/// The options from the command line's values.
pub fn options(
    dim: usize,
    time_limit: f64,
    seed: u64,
    margin: f64,
    acceleration: &str,
) -> Result<MotionOptions> {
    if !(time_limit.is_finite() && time_limit > 0.0 && time_limit <= 86_400.0) {
        bail!("--time-limit: {time_limit} is not a positive number of seconds (at most a day)");
    }
    if !(margin.is_finite() && (0.0..=1.0).contains(&margin)) {
        bail!("--margin: {margin} is not a length in [0, 1] m");
    }
    let acc = parse_list("--max-acceleration", acceleration)?;
    let acc = match acc.len() {
        1 => vec![acc[0]; dim],
        n if n == dim => acc,
        n => bail!("--max-acceleration: {n} values for a group of {dim} joints (give 1 or {dim})"),
    };
    if let Some(i) = acc.iter().position(|a| *a <= 0.0) {
        bail!("--max-acceleration: element {i} is not positive");
    }
    // Below it the timed motion outlasts the 10^7 samples it may have (at 1e-3 rad/s² a
    // path across a joint's whole range takes minutes, not days).
    if let Some(i) = acc.iter().position(|a| *a < MIN_ACCELERATION) {
        bail!(
            "--max-acceleration: element {i} ({:e}) is below {MIN_ACCELERATION} (rad/s², m/s²)",
            acc[i]
        );
    }
    let mut o = MotionOptions::new(dim);
    o.time_limit = Duration::from_secs_f64(time_limit);
    o.seed = seed;
    o.margin = margin;
    o.acceleration = acc;
    Ok(o)
}

#[derive(Serialize)]
struct TrajectoryOut {
    t: Vec<f64>,
    q: Vec<Vec<f64>>,
}

#[derive(Serialize)]
struct Output {
    solved: bool,
    reason: Option<String>,
    planning_time_s: f64,
    path: Vec<Vec<f64>>,
    trajectory: TrajectoryOut,
    duration_s: Option<f64>,
    min_distance: Option<f64>,
    closest_pair: Option<[String; 2]>,
    min_distance_states: usize,
    checks: u64,
    iterations: usize,
    ik_attempts: usize,
    ik_solutions: usize,
    goal_state: Option<Vec<f64>>,
    group: Vec<String>,
    seed: u64,
    margin: f64,
    velocity_limits: Vec<f64>,
    acceleration_limits: Vec<f64>,
    mesh_surface_links: Vec<String>,
}

/// Runs `moma motion`.
pub fn run(args: Args) -> Result<()> {
    if args.root != RootJoint::Fixed {
        bail!("--root: motion plans a fixed-base group; got {}", args.root);
    }
    let robot = Robot::load(
        &args.urdf,
        args.root,
        args.srdf.as_deref(),
        &args.package_dirs,
    )?;
    let scene = robot.scene(&args.scene, args.mesh)?;
    let group = parse_group(&robot.model, &args.group)?;
    let start = first_q(&args.start)?;
    let goal = match (&args.goal_state, &args.goal_pose) {
        (Some(p), _) => MotionGoal::State(first_q(p)?),
        (None, Some(text)) => MotionGoal::Pose(parse_goal_pose(
            &robot.model,
            text,
            args.position_tolerance,
            args.orientation_tolerance,
        )?),
        (None, None) => bail!("give --goal-state or --goal-pose"),
    };
    let opts = options(
        group.dim(),
        args.time_limit,
        args.seed,
        args.margin,
        &args.max_acceleration,
    )?;
    let (r, swapped) = robot
        .plan(&scene, &group, &start, &goal, &opts)
        .map_err(|e| name_plan_error(e, &args.start, args.goal_state.as_deref()))?;
    let out = Output {
        solved: r.not_solved.is_none(),
        reason: r.not_solved.as_ref().map(ToString::to_string),
        planning_time_s: r.planning_time.as_secs_f64(),
        path: r.path.clone(),
        trajectory: TrajectoryOut {
            t: r.trajectory
                .as_ref()
                .map(|t| t.t.clone())
                .unwrap_or_default(),
            q: r.trajectory
                .as_ref()
                .map(|t| t.q.clone())
                .unwrap_or_default(),
        },
        duration_s: r.trajectory.as_ref().map(|t| t.duration),
        min_distance: r.closest.as_ref().map(|c| c.distance),
        closest_pair: r
            .closest
            .as_ref()
            .map(|c| [c.link.clone(), c.other.clone()]),
        min_distance_states: r.closest_states,
        checks: r.checks,
        iterations: r.iterations,
        ik_attempts: r.ik_attempts,
        ik_solutions: r.ik_solutions,
        goal_state: r.goal_state.clone(),
        group: group.names.clone(),
        seed: args.seed,
        margin: r.margin,
        velocity_limits: group.velocity.clone(),
        acceleration_limits: opts.acceleration.clone(),
        mesh_surface_links: swapped,
    };
    match &args.output {
        Some(p) => crate::output::write_json(p, &out)?,
        None => crate::output::print_json(&out)?,
    }
    match &r.not_solved {
        None => Ok(()),
        Some(reason) => goal_not_reached(format!("motion not solved: {reason}")),
    }
}

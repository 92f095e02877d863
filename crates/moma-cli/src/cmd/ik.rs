//! `moma ik`: inverse kinematics of an arm frame, or whole-body resolved-rate motion of
//! a manipulator on a differential-drive base.

use super::common::{
    check_ik_budget, frame_name, frame_of, goal_not_reached, load_model, parse_base, parse_list,
    parse_task_rows,
};
use crate::output::{print_json, write_json};
use anyhow::{Result, anyhow, bail};
use moma::ik::model::ModelFrame;
use moma::ik::tasks::{PoseTask, WholeBodyTask, pose_error, target_from_slice};
use moma::ik::{
    IkOptions, IkResult, IkWorkspace, KinematicTask, NullSpaceObjective, solve_with_restarts,
};
use moma::manipulability::Measure;
use moma::mobile::DiffDrive;
use moma::mobile::whole_body::BaseInputs;
use moma::multibody::{Model, RootJoint};
use nalgebra::{DVector, Isometry3};
use rand::SeedableRng;
use serde::Serialize;
use std::path::PathBuf;
use std::sync::Arc;

/// Arguments of `moma ik`.
#[derive(clap::Args)]
pub struct Args {
    /// Robot model (URDF).
    pub robot: PathBuf,
    /// Target in world: x,y,z (position) or x,y,z,qx,qy,qz,qw (pose).
    #[arg(long, allow_hyphen_values = true)]
    pub target: String,
    /// End-effector frame (default: the deepest link).
    #[arg(long)]
    pub frame: Option<String>,
    /// Move base and arm together (needs --base); q then starts with [x, y, θ].
    #[arg(long)]
    pub whole_body: bool,
    /// Differential-drive platform for --whole-body: diff-drive:r_w=R,b=B,d=D.
    #[arg(long)]
    pub base: Option<String>,
    /// Base inputs for --whole-body: platform (v, ω) or wheels.
    #[arg(long, default_value = "platform")]
    pub inputs: String,
    /// Task rows (default: position for a 3-value target, full for a 7-value one).
    #[arg(long)]
    pub rows: Option<String>,
    /// Initial configuration (nq values, comma separated; whole body: x,y,θ first).
    #[arg(long, allow_hyphen_values = true)]
    pub q0: Option<String>,
    /// Start from a random configuration drawn with this seed (instead of the neutral
    /// one); also seeds the restarts.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Layout of --q0 and of the output q: moma or pinocchio (planar root [x, y, cos θ,
    /// sin θ]; continuous joints as cos, sin).
    #[arg(long, value_enum, default_value_t = super::common::Layout::Moma)]
    pub layout: super::common::Layout,
    /// Convergence tolerance on the residual norm (m, rad).
    #[arg(long, default_value_t = 1e-6)]
    pub tol: f64,
    /// Maximum iterations per attempt.
    #[arg(long, default_value_t = 200)]
    pub max_iters: usize,
    /// Random restarts when an attempt does not converge.
    #[arg(long, default_value_t = 0)]
    pub restarts: usize,
    /// Whole body: weight of the base inputs against the arm joints (larger = the base
    /// moves less).
    #[arg(long, default_value_t = 1.0)]
    pub base_weight: f64,
    /// Secondary objective in the task null space: none, manipulability, posture.
    #[arg(long, default_value = "none")]
    pub null_space: String,
    /// Gain of the null-space objective.
    #[arg(long, default_value_t = 0.2)]
    pub null_gain: f64,
    /// Print JSON on standard output.
    #[arg(long)]
    pub json: bool,
    /// Also write the JSON result to this file.
    #[arg(long, short)]
    pub output: Option<PathBuf>,
}

#[derive(Serialize)]
struct Output {
    robot: String,
    frame: String,
    whole_body: bool,
    target: Vec<f64>,
    rows: Vec<usize>,
    converged: bool,
    /// The task residual is within the tolerance (true also when a null-space objective
    /// was still improving at the iteration limit).
    task_met: bool,
    status: moma::ik::IkStatus,
    residual_norm: f64,
    residual: Vec<f64>,
    /// Norm of the solved position rows (m); null when the task has none.
    position_error: Option<f64>,
    /// Norm of the solved orientation rows (rad); null when the task has none.
    orientation_error: Option<f64>,
    iterations: usize,
    sigma_min: f64,
    q: Vec<f64>,
    /// Achieved frame pose: x, y, z, qx, qy, qz, qw.
    pose: Vec<f64>,
    time_ms: f64,
}

fn pose_vec(p: &Isometry3<f64>) -> Vec<f64> {
    let t = p.translation.vector;
    let q = p.rotation.coords;
    vec![t.x, t.y, t.z, q.x, q.y, q.z, q.w]
}

/// The platform for `--whole-body`, if any.
fn parse_drive(args: &Args) -> Result<Option<DiffDrive>> {
    match (&args.base, args.whole_body) {
        (Some(b), true) => Ok(Some(parse_base(b)?)),
        (None, true) => bail!("--whole-body needs --base diff-drive:r_w=R,b=B,d=D"),
        (Some(_), false) => bail!("--base is only used with --whole-body"),
        (None, false) => Ok(None),
    }
}

/// The initial configuration: `--q0`, a seeded random one (base at the origin), or the
/// neutral one.
fn initial_q(args: &Args, model: &Model, whole_body: bool) -> Result<DVector<f64>> {
    let nq = model.nq;
    match (&args.q0, args.seed) {
        (Some(s), _) => {
            let v = super::common::LayoutConv::new(model, args.layout)
                .q_in(parse_list("--q0", s)?, "--q0")?;
            if v.len() != nq {
                bail!(
                    "--q0: expected {nq} values ({}), got {}",
                    if whole_body {
                        "x, y, θ and the joints"
                    } else {
                        "one per configuration coordinate"
                    },
                    v.len()
                );
            }
            Ok(DVector::from_vec(v))
        }
        (None, Some(seed)) => {
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let mut q = moma::kinematics::random_configuration(model, &mut rng);
            if whole_body {
                q.rows_mut(0, 3).fill(0.0);
            }
            Ok(q)
        }
        (None, None) => Ok(moma::kinematics::neutral(model)),
    }
}

/// The solver options: tolerance, budget, base weights, null-space objective.
fn solver_options(args: &Args, nv_task: usize, whole_body: bool) -> Result<IkOptions> {
    let null_space = match args.null_space.as_str() {
        "none" => NullSpaceObjective::None,
        "manipulability" => NullSpaceObjective::Manipulability {
            measure: Measure::Yoshikawa,
            gain: args.null_gain,
        },
        "posture" => NullSpaceObjective::Posture {
            gain: args.null_gain,
        },
        other => bail!("--null-space: unknown '{other}'; expected none, manipulability, posture"),
    };
    let weights = whole_body.then(|| {
        let mut w = vec![1.0; nv_task];
        w[0] = args.base_weight;
        w[1] = args.base_weight;
        w
    });
    Ok(IkOptions {
        tolerance: args.tol,
        max_iterations: args.max_iters,
        weights,
        null_space,
        ..IkOptions::default()
    })
}

/// Runs `moma ik`. When the solver does not converge the result is still printed and
/// written (`-o`), then `GoalNotReached` gives exit status 3.
pub fn run(args: Args) -> Result<()> {
    let tvals = parse_list("--target", &args.target)?;
    let target = target_from_slice(&tvals).map_err(|e| anyhow!("--target: {e}"))?;
    let rows = parse_task_rows(args.rows.as_deref(), &tvals)?;
    check_ik_budget(args.tol, args.max_iters, args.restarts)?;
    if !(args.null_gain.is_finite() && args.null_gain >= 0.0) {
        bail!(
            "--null-gain: must be finite and >= 0, got {}",
            args.null_gain
        );
    }
    // The weights scale the damped normal matrix; beyond twelve decades either way its
    // Cholesky loses every digit (a subnormal weight made it "not positive definite").
    if !(args.base_weight.is_finite() && (1e-12..=1e12).contains(&args.base_weight)) {
        bail!(
            "--base-weight: must lie in [1e-12, 1e12], got {}",
            args.base_weight
        );
    }
    let drive = parse_drive(&args)?;
    let inputs: BaseInputs = args.inputs.parse().map_err(|e| anyhow!("--inputs: {e}"))?;
    let root = if drive.is_some() {
        RootJoint::Planar
    } else {
        RootJoint::Fixed
    };
    let model = Arc::new(load_model(&args.robot, root)?);
    let kin = frame_of(&model, args.frame.as_deref(), &args.robot)?;
    let name = frame_name(&kin);
    let q0 = initial_q(&args, &model, drive.is_some())?;
    let nv_task = if drive.is_some() {
        model.nv - 1
    } else {
        model.nv
    };
    let options = solver_options(&args, nv_task, drive.is_some())?;
    let posture = matches!(options.null_space, NullSpaceObjective::Posture { .. });
    let seed = args.seed.unwrap_or(0);
    let start = std::time::Instant::now();
    let (result, pose): (IkResult, Isometry3<f64>) = match drive {
        Some(drive) => {
            let mut task = WholeBodyTask::new(kin, drive, inputs, target, &rows)?;
            if posture {
                task = task.with_preferred_posture(q0.rows(3, model.nq - 3).into_owned())?;
            }
            run_task(&mut task, &q0, &options, args.restarts, seed)?
        }
        None => {
            let mut task = PoseTask::new(kin, target, &rows)?;
            if posture {
                task = task.with_preferred_posture(q0.clone())?;
            }
            run_task(&mut task, &q0, &options, args.restarts, seed)?
        }
    };
    let time_ms = start.elapsed().as_secs_f64() * 1e3;
    let e = pose_error(&pose, &target);
    // Errors of the rows the task solved only (no orientation error for a position task).
    let solved = rows.indices();
    let part = |range: std::ops::Range<usize>| {
        let sel: Vec<f64> = range.filter(|r| solved.contains(r)).map(|r| e[r]).collect();
        (!sel.is_empty()).then(|| sel.iter().map(|x| x * x).sum::<f64>().sqrt())
    };
    let out = Output {
        robot: args.robot.display().to_string(),
        frame: name,
        whole_body: drive.is_some(),
        target: tvals,
        rows: rows.indices(),
        converged: result.converged,
        task_met: result.task_met,
        status: result.status,
        residual_norm: result.residual_norm,
        residual: result.residual.iter().copied().collect(),
        position_error: part(0..3),
        orientation_error: part(3..6),
        iterations: result.iterations,
        sigma_min: result.sigma_min,
        q: super::common::LayoutConv::new(&model, args.layout).q_out(result.q.as_slice()),
        pose: pose_vec(&pose),
        time_ms,
    };
    report(&args, &out)
}

/// Writes and prints the result; an unconverged one ends in `GoalNotReached`.
fn report(args: &Args, out: &Output) -> Result<()> {
    if let Some(path) = &args.output {
        write_json(path, out)?;
    }
    if args.json {
        print_json(out)?;
    } else {
        let mut parts = Vec::new();
        if let Some(p) = out.position_error {
            parts.push(format!("position {p:.3e} m"));
        }
        if let Some(o) = out.orientation_error {
            parts.push(format!("orientation {o:.3e} rad"));
        }
        outln!(
            "{}: frame '{}' {} after {} iterations: residual {:.3e} ({}), σ_min {:.3e}",
            out.robot,
            out.frame,
            if out.converged {
                "converged".to_string()
            } else if out.task_met {
                "reached the target; null-space objective still improving at the iteration \
                 limit"
                    .to_string()
            } else {
                format!("NOT converged ({:?})", out.status)
            },
            out.iterations,
            out.residual_norm,
            parts.join(", "),
            out.sigma_min
        );
        let qs: Vec<String> = out.q.iter().map(|x| format!("{x:.6}")).collect();
        outln!("q = [{}]", qs.join(", "));
    }
    if !out.task_met {
        return goal_not_reached(format!(
            "inverse kinematics did not converge ({:?}, residual {:.3e} > tol {:.1e}); \
             the target may be out of reach or blocked by joint limits (try --restarts)",
            out.status, out.residual_norm, args.tol
        ));
    }
    Ok(())
}

/// Pose-task access for the output.
trait LastPose {
    fn last(&self) -> Isometry3<f64>;
}

impl LastPose for PoseTask<ModelFrame> {
    fn last(&self) -> Isometry3<f64> {
        *self.last_pose()
    }
}

impl LastPose for WholeBodyTask<ModelFrame> {
    fn last(&self) -> Isometry3<f64> {
        *self.last_pose()
    }
}

fn run_task<T: KinematicTask + LastPose>(
    task: &mut T,
    q0: &DVector<f64>,
    options: &IkOptions,
    restarts: usize,
    seed: u64,
) -> Result<(IkResult, Isometry3<f64>)> {
    let mut ws = IkWorkspace::new(task);
    let r = solve_with_restarts(task, q0, options, restarts, seed, &mut ws)?;
    // Re-evaluate at the returned q so the reported pose belongs to it.
    let mut e = DVector::zeros(task.task_dim());
    let mut j = nalgebra::DMatrix::zeros(task.task_dim(), task.nv());
    task.residual_and_jacobian(&r.q, &mut e, &mut j)?;
    Ok((r, task.last()))
}

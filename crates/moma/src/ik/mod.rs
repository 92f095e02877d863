//! Inverse kinematics: damped least squares / Levenberg–Marquardt for arms, whole-body
//! resolved-rate motion for mobile manipulators.
//!
//! The solver core ([`solve`]) works on any [`KinematicTask`]: something that maps a
//! configuration `q` to a task residual `e(q)` (m) and its Jacobian `J = ∂e/∂δ` with
//! respect to a velocity-like increment `δ` (nv), and that knows how to integrate `q ⊕ δ`.
//! Each iteration solves the weighted, damped least-squares step (Levenberg–Marquardt)
//!
//! ```text
//! δ = −W⁻¹ Jᵀ (J W⁻¹ Jᵀ + λ I)⁻¹ e  +  k_N (I − J# J) ∇φ
//! ```
//!
//! with `W = diag(weights)` trading one input against another (e.g. base motion against
//! arm motion), adaptive damping `λ` (decreased after a step that reduces `‖e‖`,
//! increased and retried after one that does not; this makes the step robust at and near
//! singularities) and an optional secondary objective `φ` (manipulability, or a preferred
//! posture) followed in the (damped) null space of the task. Inputs at a joint limit that
//! the step would push further out are frozen (their `W⁻¹` entry set to zero) and the step
//! re-solved, so iterates stay within the limits without losing the task.
//!
//! The result ([`IkResult`]) says whether the residual of the task rows fell below the
//! tolerance (`task_met`) and whether the solver converged (`converged`: the task is met
//! and, with a null-space objective, that objective settled too), with the final residual
//! of the rows it solved, the iteration count and why the solver stopped. An unreachable
//! target ends as [`IkStatus::Stalled`] (a local minimum of `‖e‖`) or
//! [`IkStatus::MaxIterations`]; a met task whose null-space objective was still moving at
//! the iteration limit ends as [`IkStatus::ObjectiveUnsettled`]; never an error or NaN.
//!
//! Tasks on real models (frame pose of a URDF arm, whole-body pose of a mobile
//! manipulator) live in [`tasks`]; base-placement maps (IK and a manipulability measure
//! over a grid of base poses) in [`placement`]; [`model::ModelFrame`] binds a task to a
//! frame of a [`Model`](crate::multibody::Model). [`placement`] evaluates the base-pose
//! grid with rayon, one workspace per worker, each pose solved on its own from the same
//! starting points (seed, then fixed restarts), so the map depends neither on the thread
//! count nor on the visiting order; its whole-body measure takes the frame Jacobian of the
//! arm mounted on a planar root ([`crate::multibody::mount_on_root`]) from
//! [`crate::kinematics`].

pub mod model;
pub mod placement;
pub mod tasks;

use crate::error::{Error, Result, ensure_finite};
use crate::linalg::{cholesky_in_place, cholesky_solve};
use crate::manipulability::{JacobianSvd, Measure, evaluate_svd};
use nalgebra::{DMatrix, DVector};

/// Step norm below which the secondary objective counts as settled.
const SECONDARY_STEP_TOL: f64 = 1e-7;

/// A kinematic task for [`solve`]: residual, Jacobian and configuration update.
pub trait KinematicTask {
    /// Number of configuration coordinates `nq`.
    fn nq(&self) -> usize;
    /// Number of velocity/increment coordinates `nv` (columns of the Jacobian).
    fn nv(&self) -> usize;
    /// Task dimension `m` (rows of the residual and the Jacobian).
    fn task_dim(&self) -> usize;
    /// Writes the residual `e(q)` (zero at the solution) and `J = ∂e/∂δ` (m × nv).
    fn residual_and_jacobian(
        &mut self,
        q: &DVector<f64>,
        residual: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<()>;
    /// `out = q ⊕ δ`, then projected into the feasible set (joint limits).
    fn integrate(&self, q: &DVector<f64>, delta: &DVector<f64>, out: &mut DVector<f64>);
    /// Marks in `blocked` the increment coordinates that sit at a limit and that `delta`
    /// would push out of it. The default has no limits.
    fn blocked_inputs(&self, _q: &DVector<f64>, _delta: &DVector<f64>, _blocked: &mut [bool]) {}
    /// The columns of the task Jacobian whose manipulability the null-space term
    /// maximises (default: all; a whole-body task returns the arm's columns).
    fn manipulability_columns(&self) -> std::ops::Range<usize> {
        0..self.nv()
    }
    /// Writes into `out` a random configuration near `current` for a restart (e.g. the
    /// same base pose, random arm joints within the limits); false if unsupported.
    fn random_configuration(
        &self,
        _current: &DVector<f64>,
        _rng: &mut dyn rand::RngCore,
        _out: &mut DVector<f64>,
    ) -> bool {
        false
    }
    /// Gradient (in increment coordinates) of a preferred-posture objective
    /// `−½‖q − q_pref‖²`; returns false when the task has no preferred posture.
    fn posture_gradient(&self, _q: &DVector<f64>, _gradient: &mut DVector<f64>) -> bool {
        false
    }
}

/// The secondary objective followed in the null space of the task.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum NullSpaceObjective {
    /// No secondary objective.
    #[default]
    None,
    /// Ascend a manipulability measure of the Jacobian columns
    /// [`KinematicTask::manipulability_columns`] (finite-difference gradient).
    Manipulability {
        /// Which measure (it must be larger-is-better).
        measure: Measure,
        /// Gain k_N.
        gain: f64,
    },
    /// Move towards the task's preferred posture ([`KinematicTask::posture_gradient`]).
    Posture {
        /// Gain k_N.
        gain: f64,
    },
}

impl NullSpaceObjective {
    /// Gain k_N of the objective (0 for [`NullSpaceObjective::None`]).
    fn gain(&self) -> f64 {
        match *self {
            NullSpaceObjective::Manipulability { gain, .. }
            | NullSpaceObjective::Posture { gain } => gain,
            NullSpaceObjective::None => 0.0,
        }
    }
}

/// Options of [`solve`].
#[derive(Clone, Debug, PartialEq)]
pub struct IkOptions {
    /// Convergence tolerance on `‖e‖` (task units: m and rad).
    pub tolerance: f64,
    /// Maximum number of iterations (accepted plus rejected steps).
    pub max_iterations: usize,
    /// Initial damping λ₀.
    pub initial_damping: f64,
    /// Smallest damping λ (keeps the step finite at singularities).
    pub min_damping: f64,
    /// Largest damping: beyond it the solver declares itself stalled.
    pub max_damping: f64,
    /// Largest step norm `‖δ‖` (rad or m) per iteration.
    pub max_step: f64,
    /// Per-input weights (length nv, > 0); a larger weight makes that input move less.
    /// `None` means all ones.
    pub weights: Option<Vec<f64>>,
    /// Secondary objective in the task null space.
    pub null_space: NullSpaceObjective,
    /// Stop as stalled after this many consecutive accepted steps that each reduce `‖e‖`
    /// by less than the relative amount [`IkOptions::stall_relative`] (the linear crawl
    /// towards the closest point of an unreachable target).
    pub stall_iterations: usize,
    /// Relative decrease of `‖e‖` per step below which a step counts as slow.
    pub stall_relative: f64,
}

impl Default for IkOptions {
    fn default() -> Self {
        Self {
            tolerance: 1e-6,
            max_iterations: 200,
            initial_damping: 1e-3,
            min_damping: 1e-10,
            max_damping: 1e8,
            max_step: 0.5,
            weights: None,
            null_space: NullSpaceObjective::None,
            stall_iterations: 4,
            stall_relative: 1e-3,
        }
    }
}

/// Why [`solve`] stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum IkStatus {
    /// `‖e‖ ≤ tolerance`, and the null-space objective (if any) settled: its step fell
    /// below 1e-7 or no step improves it while keeping the task met.
    Converged,
    /// `‖e‖ ≤ tolerance`, but the iteration budget ran out while the null-space objective
    /// was still improving (the task is met; the secondary objective is not optimal).
    ObjectiveUnsettled,
    /// The iteration budget ran out.
    MaxIterations,
    /// No step reduces `‖e‖` any more (a local minimum: typically an unreachable target
    /// or joint limits in the way).
    Stalled,
}

/// The outcome of [`solve`].
#[derive(Clone, Debug, serde::Serialize)]
pub struct IkResult {
    /// The final configuration (the best one found).
    pub q: DVector<f64>,
    /// True when the solver converged ([`IkStatus::Converged`]).
    pub converged: bool,
    /// True when the task residual is within the tolerance, `‖e‖ ≤ tolerance`
    /// ([`IkStatus::Converged`] or [`IkStatus::ObjectiveUnsettled`]).
    pub task_met: bool,
    /// Why the solver stopped.
    pub status: IkStatus,
    /// Final residual norm `‖e‖` over the task rows (only the rows the task solves).
    pub residual_norm: f64,
    /// Final residual vector, one entry per task row.
    pub residual: DVector<f64>,
    /// Iterations used (accepted and rejected steps).
    pub iterations: usize,
    /// Final damping λ.
    pub damping: f64,
    /// Smallest singular value of the task Jacobian at the final configuration
    /// (≈ 0 means the solution is at a singularity).
    pub sigma_min: f64,
}

/// Reusable buffers for [`solve`] (allocate once per thread, reuse across calls).
#[derive(Clone, Debug)]
pub struct IkWorkspace {
    e: DVector<f64>,
    e_trial: DVector<f64>,
    j: DMatrix<f64>,
    j_trial: DMatrix<f64>,
    q_trial: DVector<f64>,
    delta: DVector<f64>,
    winv: DVector<f64>,
    winv_eff: DVector<f64>,
    blocked: Vec<bool>,
    a: DMatrix<f64>,
    y: DVector<f64>,
    grad: DVector<f64>,
    q_probe: DVector<f64>,
    e_probe: DVector<f64>,
    j_probe: DMatrix<f64>,
    unit: DVector<f64>,
}

impl IkWorkspace {
    /// Buffers sized for `task`.
    pub fn new<T: KinematicTask + ?Sized>(task: &T) -> Self {
        let (m, nq, nv) = (task.task_dim(), task.nq(), task.nv());
        Self {
            e: DVector::zeros(m),
            e_trial: DVector::zeros(m),
            j: DMatrix::zeros(m, nv),
            j_trial: DMatrix::zeros(m, nv),
            q_trial: DVector::zeros(nq),
            delta: DVector::zeros(nv),
            winv: DVector::from_element(nv, 1.0),
            winv_eff: DVector::from_element(nv, 1.0),
            blocked: vec![false; nv],
            a: DMatrix::zeros(m, m),
            y: DVector::zeros(m),
            grad: DVector::zeros(nv),
            q_probe: DVector::zeros(nq),
            e_probe: DVector::zeros(m),
            j_probe: DMatrix::zeros(m, nv),
            unit: DVector::zeros(nv),
        }
    }

    fn fits<T: KinematicTask + ?Sized>(&self, task: &T) -> bool {
        self.e.len() == task.task_dim()
            && self.q_trial.len() == task.nq()
            && self.delta.len() == task.nv()
    }
}

/// Solves `e(q) = 0` from the seed `q0` by weighted damped least squares
/// (Levenberg–Marquardt), see the module documentation.
#[doc(alias = "dls")]
#[doc(alias = "levenberg_marquardt")]
pub fn solve<T: KinematicTask + ?Sized>(
    task: &mut T,
    q0: &DVector<f64>,
    options: &IkOptions,
    ws: &mut IkWorkspace,
) -> Result<IkResult> {
    prepare_solve(task, q0, options, ws)?;
    let (nq, nv) = (task.nq(), task.nv());
    // Start from the seed projected into the feasible set.
    let zero = DVector::zeros(nv);
    let mut q = DVector::zeros(nq);
    task.integrate(q0, &zero, &mut q);
    task.residual_and_jacobian(&q, &mut ws.e, &mut ws.j)?;
    check_finite_eval(&ws.e, &ws.j)?;
    let mut lm = LmState {
        err: ws.e.norm(),
        lambda: options.initial_damping,
        iterations: 0,
        slow: 0,
        ns_scale: 1.0,
    };
    // With a secondary objective the solver keeps improving it after the task is met,
    // as long as the residual stays within the tolerance and the step is not negligible.
    let secondary = options.null_space.gain() > 0.0;
    let status = loop {
        let met = lm.err <= options.tolerance;
        if let Some(status) = lm.stop_status(met, secondary, options) {
            break status;
        }
        lm.iterations += 1;
        // Null-space direction (computed at the current q, reused across retries).
        let have_grad = secondary_gradient(task, &q, options, ws)?;
        step_with_blocked_inputs(task, &q, ws, lm.lambda, have_grad, lm.ns_scale, options)?;
        let norm = ws.delta.norm();
        if met && norm < SECONDARY_STEP_TOL {
            break IkStatus::Converged;
        }
        if norm > options.max_step {
            ws.delta *= options.max_step / norm;
        }
        if let Some(status) = try_step(task, &mut q, ws, &mut lm, met, secondary, options)? {
            break status;
        }
    };
    let sigma_min = JacobianSvd::new(&ws.j)
        .map(|s| s.sigma_min())
        .unwrap_or(0.0);
    Ok(IkResult {
        converged: status == IkStatus::Converged,
        task_met: matches!(status, IkStatus::Converged | IkStatus::ObjectiveUnsettled),
        q,
        status,
        residual_norm: lm.err,
        residual: ws.e.clone(),
        iterations: lm.iterations,
        damping: lm.lambda,
        sigma_min,
    })
}

/// The iteration state of [`solve`]'s Levenberg–Marquardt loop.
struct LmState {
    /// Residual norm at the current q.
    err: f64,
    /// Damping λ.
    lambda: f64,
    /// Iterations so far (accepted and rejected steps).
    iterations: usize,
    /// Consecutive accepted steps that improved the residual too little.
    slow: usize,
    /// Share of the null-space term in the step: halved after a rejected step before the
    /// damping grows, so the secondary objective never prevents convergence.
    ns_scale: f64,
}

impl LmState {
    /// Why the loop stops before the next iteration, if it does (`met`: the residual is
    /// within the tolerance).
    fn stop_status(&self, met: bool, secondary: bool, options: &IkOptions) -> Option<IkStatus> {
        if met && !secondary {
            return Some(IkStatus::Converged);
        }
        if self.iterations >= options.max_iterations || self.lambda > options.max_damping {
            return Some(if met && self.lambda > options.max_damping {
                // no step improves the objective while keeping the task met: settled
                IkStatus::Converged
            } else if met {
                IkStatus::ObjectiveUnsettled
            } else if self.iterations >= options.max_iterations {
                IkStatus::MaxIterations
            } else {
                IkStatus::Stalled
            });
        }
        None
    }
}

/// Checks the seed and options of [`solve`], sizes the workspace for `task` and sets the
/// inverse weights.
fn prepare_solve<T: KinematicTask + ?Sized>(
    task: &T,
    q0: &DVector<f64>,
    options: &IkOptions,
    ws: &mut IkWorkspace,
) -> Result<()> {
    let (nq, nv) = (task.nq(), task.nv());
    crate::error::ensure_len("ik seed q0", nq, q0.len())?;
    ensure_finite("ik seed q0", q0.iter())?;
    validate_options(options, nv)?;
    if !ws.fits(task) {
        *ws = IkWorkspace::new(task);
    }
    match &options.weights {
        Some(w) => {
            for k in 0..nv {
                ws.winv[k] = 1.0 / w[k];
            }
        }
        None => ws.winv.fill(1.0),
    }
    Ok(())
}

/// The damped weighted step `ws.delta` at `q`, re-solved once with the inputs that the
/// task blocks ([`KinematicTask::blocked_inputs`]) frozen.
fn step_with_blocked_inputs<T: KinematicTask + ?Sized>(
    task: &mut T,
    q: &DVector<f64>,
    ws: &mut IkWorkspace,
    lambda: f64,
    have_grad: bool,
    ns_scale: f64,
    options: &IkOptions,
) -> Result<()> {
    let (m, nv) = (task.task_dim(), task.nv());
    ws.winv_eff.copy_from(&ws.winv);
    ws.blocked.iter_mut().for_each(|b| *b = false);
    for pass in 0..2 {
        damped_step(ws, lambda, m, nv, have_grad, ns_scale, options)?;
        if pass == 0 {
            task.blocked_inputs(q, &ws.delta, &mut ws.blocked);
            if !ws.blocked.iter().any(|&b| b) {
                break;
            }
            for k in 0..nv {
                if ws.blocked[k] {
                    ws.winv_eff[k] = 0.0;
                }
            }
        }
    }
    Ok(())
}

/// Evaluates the trial `q ⊕ ws.delta`, accepts it (into `q`, `ws.e`, `ws.j`) when it
/// lowers the residual (or keeps a met task met while a secondary objective runs), and
/// adapts the damping and null-space share; `Some(Stalled)` when progress has stalled.
fn try_step<T: KinematicTask + ?Sized>(
    task: &mut T,
    q: &mut DVector<f64>,
    ws: &mut IkWorkspace,
    lm: &mut LmState,
    met: bool,
    secondary: bool,
    options: &IkOptions,
) -> Result<Option<IkStatus>> {
    task.integrate(q, &ws.delta, &mut ws.q_trial);
    task.residual_and_jacobian(&ws.q_trial, &mut ws.e_trial, &mut ws.j_trial)?;
    let err_trial = ws.e_trial.norm();
    let finite = err_trial.is_finite() && ws.j_trial.iter().all(|x| x.is_finite());
    let err = lm.err;
    let accept =
        finite && (err_trial < err || (secondary && met && err_trial <= options.tolerance));
    if accept {
        if !met && err - err_trial <= options.stall_relative * err {
            lm.slow += 1;
        } else {
            lm.slow = 0;
        }
        std::mem::swap(q, &mut ws.q_trial);
        std::mem::swap(&mut ws.e, &mut ws.e_trial);
        std::mem::swap(&mut ws.j, &mut ws.j_trial);
        lm.err = err_trial;
        lm.lambda = (lm.lambda / 3.0).max(options.min_damping);
        lm.ns_scale = (lm.ns_scale * 2.0).min(1.0);
        if lm.slow >= options.stall_iterations && lm.err > options.tolerance {
            return Ok(Some(IkStatus::Stalled));
        }
    } else if secondary && lm.ns_scale > 1e-3 {
        lm.ns_scale *= 0.25;
    } else {
        lm.ns_scale = 0.0;
        lm.lambda *= 8.0;
    }
    Ok(None)
}

/// [`solve`] from `q0`, then, while not converged, from up to `restarts` random
/// configurations ([`KinematicTask::random_configuration`], seeded by `seed`); returns the
/// first result that meets the task ([`IkResult::task_met`]) or the one with the smallest
/// residual. `iterations` counts all attempts.
pub fn solve_with_restarts<T: KinematicTask + ?Sized>(
    task: &mut T,
    q0: &DVector<f64>,
    options: &IkOptions,
    restarts: usize,
    seed: u64,
    ws: &mut IkWorkspace,
) -> Result<IkResult> {
    use rand::SeedableRng;
    let mut best = solve(task, q0, options, ws)?;
    let mut total = best.iterations;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut seed_q = q0.clone();
    for _ in 0..restarts {
        if best.task_met {
            break;
        }
        if !task.random_configuration(q0, &mut rng, &mut seed_q) {
            break;
        }
        let r = solve(task, &seed_q, options, ws)?;
        total += r.iterations;
        if r.task_met || r.residual_norm < best.residual_norm {
            best = r;
        }
    }
    best.iterations = total;
    Ok(best)
}

fn validate_options(o: &IkOptions, nv: usize) -> Result<()> {
    let positive = [
        ("ik tolerance", o.tolerance),
        ("ik initial_damping", o.initial_damping),
        ("ik min_damping", o.min_damping),
        ("ik max_damping", o.max_damping),
        ("ik max_step", o.max_step),
    ];
    for (field, v) in positive {
        if !v.is_finite() || v <= 0.0 {
            return Err(Error::invalid(
                field,
                format!("must be finite and > 0, got {v}"),
            ));
        }
    }
    if !o.stall_relative.is_finite() || o.stall_relative < 0.0 {
        return Err(Error::invalid(
            "ik stall_relative",
            format!("must be finite and >= 0, got {}", o.stall_relative),
        ));
    }
    if let Some(w) = &o.weights {
        crate::error::ensure_len("ik weights", nv, w.len())?;
        for (k, &x) in w.iter().enumerate() {
            if !x.is_finite() || x <= 0.0 {
                return Err(Error::invalid(
                    format!("ik weights[{k}]"),
                    format!("must be finite and > 0, got {x}"),
                ));
            }
        }
    }
    if let NullSpaceObjective::Manipulability { measure, .. } = &o.null_space
        && !measure.larger_is_better()
    {
        return Err(Error::invalid(
            "ik null-space measure",
            format!("'{measure}' is smaller-is-better; choose one to maximise"),
        ));
    }
    // `None` has gain 0, which passes.
    let gain = o.null_space.gain();
    if !gain.is_finite() || gain < 0.0 {
        return Err(Error::invalid(
            "ik null-space gain",
            "must be finite and >= 0",
        ));
    }
    Ok(())
}

fn check_finite_eval(e: &DVector<f64>, j: &DMatrix<f64>) -> Result<()> {
    if e.iter().chain(j.iter()).all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(Error::Numerical {
            t: 0.0,
            message: "inverse kinematics: non-finite residual or Jacobian at the seed".into(),
        })
    }
}

/// δ = −W⁻¹Jᵀ(JW⁻¹Jᵀ + λI)⁻¹ e + k (∇φ − W⁻¹Jᵀ(JW⁻¹Jᵀ + λI)⁻¹ J ∇φ).
fn damped_step(
    ws: &mut IkWorkspace,
    lambda: f64,
    m: usize,
    nv: usize,
    have_grad: bool,
    ns_scale: f64,
    options: &IkOptions,
) -> Result<()> {
    // A = J W⁻¹ Jᵀ + λ I
    for r in 0..m {
        for c in 0..=r {
            let mut s = 0.0;
            for k in 0..nv {
                s += ws.j[(r, k)] * ws.winv_eff[k] * ws.j[(c, k)];
            }
            ws.a[(r, c)] = s;
            ws.a[(c, r)] = s;
        }
        ws.a[(r, r)] += lambda;
    }
    // Right-hand side: −e (+ J ∇φ projected out below).
    let gain = options.null_space.gain() * ns_scale;
    let use_grad = have_grad && gain > 0.0;
    // y = A⁻¹ (−e − k J W⁻¹ g)   so that δ = W⁻¹ Jᵀ y + k W⁻¹ g
    for r in 0..m {
        let mut s = -ws.e[r];
        if use_grad {
            let mut jg = 0.0;
            for k in 0..nv {
                jg += ws.j[(r, k)] * ws.winv_eff[k] * ws.grad[k];
            }
            s -= gain * jg;
        }
        ws.y[r] = s;
    }
    if cholesky_in_place(&mut ws.a, 0.0).is_err() {
        return Err(Error::Numerical {
            t: 0.0,
            message: "inverse kinematics: damped normal matrix not positive definite".into(),
        });
    }
    cholesky_solve(&ws.a, &mut ws.y);
    for k in 0..nv {
        let mut s = 0.0;
        for r in 0..m {
            s += ws.j[(r, k)] * ws.y[r];
        }
        let mut d = ws.winv_eff[k] * s;
        if use_grad {
            d += gain * ws.winv_eff[k] * ws.grad[k];
        }
        ws.delta[k] = d;
    }
    Ok(())
}

/// Fills `ws.grad` with the gradient of the secondary objective; false if none.
fn secondary_gradient<T: KinematicTask + ?Sized>(
    task: &mut T,
    q: &DVector<f64>,
    options: &IkOptions,
    ws: &mut IkWorkspace,
) -> Result<bool> {
    match &options.null_space {
        NullSpaceObjective::None => Ok(false),
        NullSpaceObjective::Posture { .. } => Ok(task.posture_gradient(q, &mut ws.grad)),
        NullSpaceObjective::Manipulability { measure, .. } => {
            let cols = task.manipulability_columns();
            let value = |j: &DMatrix<f64>| -> f64 {
                let sub = j.columns(cols.start, cols.len()).into_owned();
                JacobianSvd::new(&sub)
                    .and_then(|s| evaluate_svd(measure, &s))
                    .unwrap_or(0.0)
            };
            let w0 = value(&ws.j);
            let h = 1e-6;
            let nv = task.nv();
            // Finite-difference direction, from the workspace (no allocation per
            // iteration); it is all zeros between probes.
            ws.unit.fill(0.0);
            for k in 0..nv {
                ws.unit[k] = h;
                task.integrate(q, &ws.unit, &mut ws.q_probe);
                ws.unit[k] = 0.0;
                task.residual_and_jacobian(&ws.q_probe, &mut ws.e_probe, &mut ws.j_probe)?;
                let g = (value(&ws.j_probe) - w0) / h;
                ws.grad[k] = if g.is_finite() { g } else { 0.0 };
            }
            Ok(true)
        }
    }
}

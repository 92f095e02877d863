//! The discrete optimal-control problem the solver works on: `N` stages of dynamics
//! `x_{k+1} = f_k(x_k, u_k)`, stage costs `ℓ_k(x_k, u_k)`, a terminal cost `ℓ_N(x_N)` and
//! box bounds on each input that may depend on the knot's state (and an admissible set
//! within the box that the rollouts project onto). State constraints and input–state constraints are the
//! problem's own business: the whole-body problem folds them into its costs as
//! augmented-Lagrangian terms ([`super::constraints`]) and updates the multipliers once
//! per MPC solve, after the solver returns (so the cost is one function within a solve).

use nalgebra::{DMatrix, DVector};

use crate::error::Result;

/// The first- and second-order model of one stage at a point `(x, u)`: the dynamics'
/// Jacobians and the cost's gradient and Gauss–Newton Hessian. At the terminal stage only
/// `lx` and `lxx` are read.
#[derive(Clone, Debug)]
pub struct StageModel {
    /// ∂f/∂x (nx × nx).
    pub a: DMatrix<f64>,
    /// ∂f/∂u (nx × nu).
    pub b: DMatrix<f64>,
    /// ∂ℓ/∂x (nx).
    pub lx: DVector<f64>,
    /// ∂ℓ/∂u (nu).
    pub lu: DVector<f64>,
    /// ∂²ℓ/∂x² (nx × nx), symmetric positive semidefinite.
    pub lxx: DMatrix<f64>,
    /// ∂²ℓ/∂u² (nu × nu), symmetric positive semidefinite.
    pub luu: DMatrix<f64>,
    /// ∂²ℓ/∂u∂x (nu × nx).
    pub lux: DMatrix<f64>,
}

impl StageModel {
    /// Zeroed buffers for `nx` states and `nu` inputs.
    #[must_use]
    pub fn new(nx: usize, nu: usize) -> Self {
        Self {
            a: DMatrix::zeros(nx, nx),
            b: DMatrix::zeros(nx, nu),
            lx: DVector::zeros(nx),
            lu: DVector::zeros(nu),
            lxx: DMatrix::zeros(nx, nx),
            luu: DMatrix::zeros(nu, nu),
            lux: DMatrix::zeros(nu, nx),
        }
    }

    /// Sets every cost term to zero (the dynamics' Jacobians are overwritten by the
    /// problem anyway).
    pub fn clear_cost(&mut self) {
        self.lx.fill(0.0);
        self.lu.fill(0.0);
        self.lxx.fill(0.0);
        self.luu.fill(0.0);
        self.lux.fill(0.0);
    }
}

/// A finite-horizon discrete optimal-control problem with box-bounded inputs.
pub trait OptimalControlProblem {
    /// State dimension.
    fn nx(&self) -> usize;
    /// Input dimension.
    fn nu(&self) -> usize;
    /// Number of stages N (inputs `u_0 … u_{N−1}`, states `x_0 … x_N`).
    fn horizon(&self) -> usize;
    /// Writes `x_{k+1} = f_k(x, u)` into `next`.
    ///
    /// # Errors
    /// Whatever the model reports (a singular mass matrix, say).
    fn dynamics(
        &mut self,
        k: usize,
        x: &DVector<f64>,
        u: &DVector<f64>,
        next: &mut DVector<f64>,
    ) -> Result<()>;
    /// The stage cost `ℓ_k(x, u)`, or the terminal cost `ℓ_N(x)` when `u` is `None`.
    ///
    /// # Errors
    /// As [`OptimalControlProblem::dynamics`].
    fn cost(&mut self, k: usize, x: &DVector<f64>, u: Option<&DVector<f64>>) -> Result<f64>;
    /// Fills `out` with the stage model at `(x, u)` (terminal: `u` is `None`, only the
    /// cost terms) and returns the cost there.
    ///
    /// # Errors
    /// As [`OptimalControlProblem::dynamics`].
    fn approximate(
        &mut self,
        k: usize,
        x: &DVector<f64>,
        u: Option<&DVector<f64>>,
        out: &mut StageModel,
    ) -> Result<f64>;
    /// A lower bound of the stage cost `ℓ_k` (terminal: `k = N`) that holds for every
    /// `(x, u)` within one solve; the line search stops a rollout as soon as the cost so
    /// far plus the bounds of the stages left cannot be accepted any more. `−∞` (the
    /// default) never stops one.
    fn cost_lower_bound(&self, _k: usize) -> f64 {
        f64::NEG_INFINITY
    }
    /// Lower and upper bounds of `u_k` at the state `x` of knot `k` (`±∞` for a free
    /// component), written into `lo` and `hi` (`lo ≤ hi`): the box the backward pass's
    /// stage QPs keep the step in.
    fn input_bounds(
        &self,
        k: usize,
        x: &DVector<f64>,
        lo: &mut DVector<f64>,
        hi: &mut DVector<f64>,
    );
    /// Moves `u` onto the inputs admissible at the state `x` of knot `k`, where every
    /// rollout applies it; `lo` and `hi` are scratch of length `nu`. The default clamps
    /// `u` to [`OptimalControlProblem::input_bounds`]; a problem whose admissible set is
    /// that box cut by further constraints the rollout enforces exactly projects onto
    /// it, the result staying within the box.
    fn admissible_input(
        &mut self,
        k: usize,
        x: &DVector<f64>,
        u: &mut DVector<f64>,
        lo: &mut DVector<f64>,
        hi: &mut DVector<f64>,
    ) {
        self.clamp_to_input_bounds(k, x, u, lo, hi);
    }
    /// Clamps `u` to [`OptimalControlProblem::input_bounds`] at the state `x` of knot `k`
    /// (written into `lo` and `hi`): the default [`OptimalControlProblem::admissible_input`],
    /// and the first step of a problem's own.
    fn clamp_to_input_bounds(
        &self,
        k: usize,
        x: &DVector<f64>,
        u: &mut DVector<f64>,
        lo: &mut DVector<f64>,
        hi: &mut DVector<f64>,
    ) {
        self.input_bounds(k, x, lo, hi);
        for i in 0..u.len() {
            u[i] = u[i].clamp(lo[i], hi[i]);
        }
    }
    /// Called by the solver after every pass that evaluated all the knots of the
    /// trajectory it keeps (its models, or an accepted line-search rollout): what the
    /// problem recorded in that pass describes the trajectory the solve returns, unless
    /// a later pass is kept. The default does nothing.
    fn keep_evaluation(&mut self) {}
}

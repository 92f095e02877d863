//! Box-constrained iterative LQR (DDP with the dynamics' second derivatives left out):
//! a Riccati backward pass over the stage models, each stage's input step the solution
//! of a box QP ([`super::box_qp`]), and a forward pass that rolls the nonlinear dynamics
//! out under the affine policy `u = ū + α k + K (x − x̄)` (each input moved onto the
//! problem's admissible inputs at its knot's state) with a backtracking line search
//! on the total cost. Levenberg–Marquardt regularisation `μ I` on `Q_uu` grows when a
//! stage's free block is not positive definite or no step decreases the cost.
//!
//! With linear dynamics, quadratic costs and inactive bounds the first iteration is the
//! exact finite-horizon LQR solution (the backward pass is the discrete Riccati
//! recursion), which the tests check against an independent Riccati iteration.
//!
//! Every buffer is allocated in [`Solver::new`]; [`Solver::solve`] does not allocate.

use nalgebra::{DMatrix, DVector};

use super::box_qp::BoxQp;
use super::problem::{OptimalControlProblem, StageModel};
use crate::error::{Error, Result};
use crate::linalg::cholesky_solve_columns;

/// Settings of [`Solver::solve`].
#[derive(Clone, Debug)]
pub struct SolverOptions {
    /// Iterations at most (each one backward pass and one line search).
    pub max_iterations: usize,
    /// Stop when the decrease the quadratic model predicts for a full step is below this.
    pub tolerance: f64,
    /// Initial regularisation μ.
    pub mu_init: f64,
    /// Regularisation below which μ is set to zero.
    pub mu_min: f64,
    /// Regularisation above which the solve gives up improving.
    pub mu_max: f64,
    /// Step lengths tried by the line search, largest first.
    pub line_search: Vec<f64>,
    /// When no step length is accepted: `false` raises the regularisation and iterates
    /// again; `true` ends the solve there, with the trajectory it has (a real-time
    /// budget: from μ = 0 the next μ, 10⁻⁶, is too small against `Q_uu` to change the
    /// step, so the next iteration would repeat the same rejected rollouts).
    pub stop_on_failed_line_search: bool,
}

impl Default for SolverOptions {
    fn default() -> Self {
        Self {
            max_iterations: 50,
            tolerance: 1e-9,
            mu_init: 0.0,
            mu_min: 1e-9,
            mu_max: 1e10,
            line_search: vec![1.0, 0.5, 0.25, 0.125, 0.0625, 0.03125],
            stop_on_failed_line_search: false,
        }
    }
}

/// State and input trajectory: `xs[0..=N]`, `us[0..N]`.
#[derive(Clone, Debug)]
pub struct Trajectory {
    /// States x_0 … x_N.
    pub xs: Vec<DVector<f64>>,
    /// Inputs u_0 … u_{N−1}.
    pub us: Vec<DVector<f64>>,
}

impl Trajectory {
    /// Zero states and inputs for `n` stages.
    #[must_use]
    pub fn zeros(nx: usize, nu: usize, n: usize) -> Self {
        Self {
            xs: vec![DVector::zeros(nx); n + 1],
            us: vec![DVector::zeros(nu); n],
        }
    }
}

/// What one solve did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveStats {
    /// Iterations run (backward passes with a line search).
    pub iterations: usize,
    /// Total cost of the returned trajectory.
    pub cost: f64,
    /// Whether the predicted decrease fell below the tolerance.
    pub converged: bool,
    /// Regularisation at the end.
    pub mu: f64,
    /// Forward rollouts of the line search (whole, or stopped once they could no longer
    /// be accepted).
    pub rollouts: usize,
}

/// The iLQR workspace.
#[derive(Clone, Debug)]
pub struct Solver {
    nx: usize,
    nu: usize,
    n: usize,
    /// Stage models of the current trajectory (N + 1, the last terminal).
    stages: Vec<StageModel>,
    /// Feed-forward steps k_k.
    pub feedforward: Vec<DVector<f64>>,
    /// Feedback gains K_k (nu × nx).
    pub gains: Vec<DMatrix<f64>>,
    trial: Trajectory,
    /// `rest_bound[k]`: the sum of the problem's cost lower bounds of stages k … N.
    rest_bound: Vec<f64>,
    vx: DVector<f64>,
    vxx: DMatrix<f64>,
    qx: DVector<f64>,
    qu: DVector<f64>,
    qxx: DMatrix<f64>,
    quu: DMatrix<f64>,
    qux: DMatrix<f64>,
    vxx_a: DMatrix<f64>,
    vxx_b: DMatrix<f64>,
    /// The non-zero entries of the stage's A and B (`(row, column, value)`): the
    /// products with them skip the zeros (a whole-body MPC's A is the identity plus a
    /// few entries, its B a few entries a column).
    a_nz: Vec<(usize, usize, f64)>,
    b_nz: Vec<(usize, usize, f64)>,
    /// Kᵀ of the stage (the product with a transpose as a plain product).
    gains_t: DMatrix<f64>,
    lo: DVector<f64>,
    hi: DVector<f64>,
    /// The problem's input bounds at a knot (scratch of `input_bounds`).
    bound_lo: DVector<f64>,
    bound_hi: DVector<f64>,
    qp: BoxQp,
    tmp_x: DVector<f64>,
    tmp_u: DVector<f64>,
    tmp_ux: DMatrix<f64>,
    tmp_xx: DMatrix<f64>,
}

impl Solver {
    /// A workspace for `nx` states, `nu` inputs and `n` stages.
    #[must_use]
    pub fn new(nx: usize, nu: usize, n: usize) -> Self {
        Self {
            nx,
            nu,
            n,
            stages: vec![StageModel::new(nx, nu); n + 1],
            feedforward: vec![DVector::zeros(nu); n],
            gains: vec![DMatrix::zeros(nu, nx); n],
            trial: Trajectory::zeros(nx, nu, n),
            rest_bound: vec![0.0; n + 2],
            vx: DVector::zeros(nx),
            vxx: DMatrix::zeros(nx, nx),
            qx: DVector::zeros(nx),
            qu: DVector::zeros(nu),
            qxx: DMatrix::zeros(nx, nx),
            quu: DMatrix::zeros(nu, nu),
            qux: DMatrix::zeros(nu, nx),
            vxx_a: DMatrix::zeros(nx, nx),
            vxx_b: DMatrix::zeros(nx, nu),
            a_nz: Vec::with_capacity(nx * nx),
            b_nz: Vec::with_capacity(nx * nu),
            gains_t: DMatrix::zeros(nx, nu),
            lo: DVector::zeros(nu),
            hi: DVector::zeros(nu),
            bound_lo: DVector::zeros(nu),
            bound_hi: DVector::zeros(nu),
            qp: BoxQp::new(nu),
            tmp_x: DVector::zeros(nx),
            tmp_u: DVector::zeros(nu),
            tmp_ux: DMatrix::zeros(nu, nx),
            tmp_xx: DMatrix::zeros(nx, nx),
        }
    }

    /// Improves `traj` (its inputs are the initial guess; its states are overwritten by
    /// the rollout from `x0`) for at most `opts.max_iterations` iterations.
    ///
    /// # Errors
    /// [`Error::Invalid`] on dimensions that do not match the workspace; whatever the
    /// problem reports.
    pub fn solve<P: OptimalControlProblem + ?Sized>(
        &mut self,
        problem: &mut P,
        x0: &DVector<f64>,
        traj: &mut Trajectory,
        opts: &SolverOptions,
    ) -> Result<SolveStats> {
        self.roll_out_guess(problem, x0, traj)?;
        let mut mu = opts.mu_init;
        let mut stats = SolveStats::default();
        let mut cost = 0.0;
        let mut need_model = true;
        #[allow(unused_assignments)]
        for it in 0..opts.max_iterations {
            if need_model {
                cost = self.approximate_all(problem, traj)?;
                problem.keep_evaluation();
                need_model = false;
            }
            stats.iterations = it + 1;
            // Backward pass, raising μ until every stage's QP is convex.
            let (d1, d2) = loop {
                if let Some(d) = self.backward_pass(problem, traj, mu) {
                    break d;
                }
                mu = (mu * 10.0).max(1e-6);
                if mu > opts.mu_max {
                    stats.cost = cost;
                    stats.mu = mu;
                    return Ok(stats);
                }
            };
            if -(d1 + 0.5 * d2) < opts.tolerance {
                stats.converged = true;
                break;
            }
            let mut accepted = false;
            for &alpha in &opts.line_search {
                let expected = -(alpha * d1 + 0.5 * alpha * alpha * d2);
                // Costs above this are rejected, so the rollout may stop once it is sure
                // to exceed it.
                let limit = cost - 1e-4 * expected.max(0.0);
                let new_cost = self.forward(problem, traj, alpha, limit)?;
                stats.rollouts += 1;
                if new_cost.is_finite()
                    && cost - new_cost >= 1e-4 * expected.max(0.0)
                    && new_cost < cost
                {
                    std::mem::swap(traj, &mut self.trial);
                    problem.keep_evaluation();
                    cost = new_cost;
                    accepted = true;
                    break;
                }
            }
            if accepted {
                mu = if mu * 0.1 < opts.mu_min {
                    0.0
                } else {
                    mu * 0.1
                };
                need_model = true;
            } else {
                if opts.stop_on_failed_line_search {
                    break;
                }
                mu = (mu * 10.0).max(1e-6);
                if mu > opts.mu_max {
                    break;
                }
            }
        }
        stats.cost = cost;
        stats.mu = mu;
        Ok(stats)
    }

    /// The linearisation the first iteration of [`Solver::solve`] works on: `traj`'s
    /// inputs rolled out from `x0`, each moved onto the inputs admissible at its knot,
    /// and every stage's model there (read with [`Solver::stages`]); returns the total
    /// cost. With
    /// [`Solver::backward_pass`] it is one iteration's quadratic program and its Riccati
    /// solution, for comparing that pass with other QP solvers on the same problem.
    ///
    /// # Errors
    /// As [`Solver::solve`].
    pub fn linearize<P: OptimalControlProblem + ?Sized>(
        &mut self,
        problem: &mut P,
        x0: &DVector<f64>,
        traj: &mut Trajectory,
    ) -> Result<f64> {
        self.roll_out_guess(problem, x0, traj)?;
        self.approximate_all(problem, traj)
    }

    /// The stage models of the last linearisation (N + 1, the last terminal).
    #[must_use]
    pub fn stages(&self) -> &[StageModel] {
        &self.stages
    }

    /// Checks the dimensions, rolls the guess out from `x0` (each input moved onto the
    /// inputs admissible at its knot) and sums the lower bounds of the stages left (for
    /// stopping hopeless rollouts).
    fn roll_out_guess<P: OptimalControlProblem + ?Sized>(
        &mut self,
        problem: &mut P,
        x0: &DVector<f64>,
        traj: &mut Trajectory,
    ) -> Result<()> {
        if problem.nx() != self.nx || problem.nu() != self.nu || problem.horizon() != self.n {
            return Err(Error::invalid(
                "solver",
                format!(
                    "workspace is for nx = {}, nu = {}, N = {}; the problem has {}, {}, {}",
                    self.nx,
                    self.nu,
                    self.n,
                    problem.nx(),
                    problem.nu(),
                    problem.horizon()
                ),
            ));
        }
        // Roll the guess out, each input moved onto the inputs admissible at its knot.
        traj.xs[0].copy_from(x0);
        for k in 0..self.n {
            let (xs, rest) = traj.xs.split_at_mut(k + 1);
            problem.admissible_input(
                k,
                &xs[k],
                &mut traj.us[k],
                &mut self.bound_lo,
                &mut self.bound_hi,
            );
            problem.dynamics(k, &xs[k], &traj.us[k], &mut rest[0])?;
        }
        // Suffix sums of the stage costs' lower bounds (for stopping hopeless rollouts).
        self.rest_bound[self.n + 1] = 0.0;
        for k in (0..=self.n).rev() {
            self.rest_bound[k] = self.rest_bound[k + 1] + problem.cost_lower_bound(k);
        }
        Ok(())
    }

    /// Every stage's model along `traj` into `self.stages`; returns the total cost.
    fn approximate_all<P: OptimalControlProblem + ?Sized>(
        &mut self,
        problem: &mut P,
        traj: &Trajectory,
    ) -> Result<f64> {
        let mut cost = 0.0;
        for k in 0..self.n {
            cost += problem.approximate(k, &traj.xs[k], Some(&traj.us[k]), &mut self.stages[k])?;
        }
        cost += problem.approximate(self.n, &traj.xs[self.n], None, &mut self.stages[self.n])?;
        Ok(cost)
    }

    /// The Riccati backward pass over the stage models with regularisation `mu`: the
    /// feed-forward steps and gains (`feedforward`, `gains`) of the quadratic program of
    /// the stage models at `traj`; returns the expected-decrease coefficients
    /// `(Σ kᵀQu, Σ kᵀQuu k)`, or `None` when a stage QP is not convex.
    pub fn backward_pass<P: OptimalControlProblem + ?Sized>(
        &mut self,
        problem: &P,
        traj: &Trajectory,
        mu: f64,
    ) -> Option<(f64, f64)> {
        let term = &self.stages[self.n];
        self.vx.copy_from(&term.lx);
        self.vxx.copy_from(&term.lxx);
        let (mut d1, mut d2) = (0.0, 0.0);
        for k in (0..self.n).rev() {
            let s = &self.stages[k];
            // Qx = lx + Aᵀ Vx, Qu = lu + Bᵀ Vx.
            self.qx.copy_from(&s.lx);
            self.qx.gemv_tr(1.0, &s.a, &self.vx, 1.0);
            self.qu.copy_from(&s.lu);
            self.qu.gemv_tr(1.0, &s.b, &self.vx, 1.0);
            // Vxx A and Vxx B; Qxx = lxx + Aᵀ Vxx A, Quu = luu + Bᵀ Vxx B,
            // Qux = lux + Bᵀ Vxx A, each product over the non-zero entries of A or B.
            non_zeros(&s.a, &mut self.a_nz);
            non_zeros(&s.b, &mut self.b_nz);
            mul_sparse(&self.vxx, &self.a_nz, &mut self.vxx_a);
            mul_sparse(&self.vxx, &self.b_nz, &mut self.vxx_b);
            self.qxx.copy_from(&s.lxx);
            add_sparse_tr_mul(&self.a_nz, &self.vxx_a, &mut self.qxx);
            self.quu.copy_from(&s.luu);
            add_sparse_tr_mul(&self.b_nz, &self.vxx_b, &mut self.quu);
            self.qux.copy_from(&s.lux);
            add_sparse_tr_mul(&self.b_nz, &self.vxx_a, &mut self.qux);
            for i in 0..self.nu {
                self.quu[(i, i)] += mu;
            }
            // Step bounds: the input bounds at the knot's state less the current input.
            problem.input_bounds(k, &traj.xs[k], &mut self.bound_lo, &mut self.bound_hi);
            let u = &traj.us[k];
            for i in 0..self.nu {
                self.lo[i] = (self.bound_lo[i] - u[i]).min(0.0);
                self.hi[i] = (self.bound_hi[i] - u[i]).max(0.0);
            }
            // Warm start the QP from the previous feed-forward step.
            self.tmp_u.copy_from(&self.feedforward[k]);
            if !self
                .qp
                .solve(&self.quu, &self.qu, &self.lo, &self.hi, &self.tmp_u)
            {
                return None;
            }
            self.feedforward[k].copy_from(&self.qp.x);
            // K = −Quu_ff⁻¹ Qux on the free rows, 0 on the clamped ones (the factor is
            // the identity on the clamped rows and columns, so their zeros stay zero).
            let gains = &mut self.gains[k];
            for j in 0..self.nx {
                for i in 0..self.nu {
                    gains[(i, j)] = if self.qp.clamped[i] {
                        0.0
                    } else {
                        -self.qux[(i, j)]
                    };
                }
            }
            cholesky_solve_columns(&self.qp.factor, gains);
            let kff = &self.feedforward[k];
            // Expected decrease terms.
            self.quu.mul_to(kff, &mut self.tmp_u);
            d1 += kff.dot(&self.qu);
            d2 += kff.dot(&self.tmp_u);
            // Vx = Qx + Kᵀ Quu k + Kᵀ Qu + Quxᵀ k.
            self.vx.copy_from(&self.qx);
            self.vx.gemv_tr(1.0, gains, &self.tmp_u, 1.0);
            self.vx.gemv_tr(1.0, gains, &self.qu, 1.0);
            self.vx.gemv_tr(1.0, &self.qux, kff, 1.0);
            // Vxx = Qxx + Kᵀ Quu K + Kᵀ Qux + Quxᵀ K, formed as Qxx + Kᵀ (Quu K + 2 Qux),
            // whose symmetric part (below) is the same matrix: Kᵀ Qux + Quxᵀ K is the
            // symmetric part of 2 Kᵀ Qux.
            self.quu.mul_to(gains, &mut self.tmp_ux);
            for (t, q) in self.tmp_ux.iter_mut().zip(self.qux.iter()) {
                *t += 2.0 * q;
            }
            gains.transpose_to(&mut self.gains_t);
            self.vxx.copy_from(&self.qxx);
            self.vxx.gemm(1.0, &self.gains_t, &self.tmp_ux, 1.0);
            // Symmetrise (the step above, and rounding).
            self.tmp_xx.copy_from(&self.vxx);
            for i in 0..self.nx {
                for j in 0..self.nx {
                    self.vxx[(i, j)] = 0.5 * (self.tmp_xx[(i, j)] + self.tmp_xx[(j, i)]);
                }
            }
        }
        Some((d1, d2))
    }

    /// Rolls out the policy with step `alpha` into `self.trial`; returns its cost, or `+∞`
    /// as soon as the cost so far plus the lower bounds of the stages left exceeds
    /// `limit` (the trial is then incomplete, and rejected).
    fn forward<P: OptimalControlProblem + ?Sized>(
        &mut self,
        problem: &mut P,
        traj: &Trajectory,
        alpha: f64,
        limit: f64,
    ) -> Result<f64> {
        self.trial.xs[0].copy_from(&traj.xs[0]);
        let mut cost = 0.0;
        for k in 0..self.n {
            // u = ū + α k + K (x − x̄), moved onto the inputs admissible at x.
            self.tmp_x.copy_from(&self.trial.xs[k]);
            self.tmp_x -= &traj.xs[k];
            let u = &mut self.trial.us[k];
            u.copy_from(&traj.us[k]);
            u.axpy(alpha, &self.feedforward[k], 1.0);
            u.gemv(1.0, &self.gains[k], &self.tmp_x, 1.0);
            problem.admissible_input(
                k,
                &self.trial.xs[k],
                u,
                &mut self.bound_lo,
                &mut self.bound_hi,
            );
            cost += problem.cost(k, &self.trial.xs[k], Some(&self.trial.us[k]))?;
            if cost + self.rest_bound[k + 1] > limit {
                return Ok(f64::INFINITY);
            }
            let (xs, rest) = self.trial.xs.split_at_mut(k + 1);
            problem.dynamics(k, &xs[k], &self.trial.us[k], &mut rest[0])?;
        }
        cost += problem.cost(self.n, &self.trial.xs[self.n], None)?;
        Ok(cost)
    }
}

/// The non-zero entries of `m` as `(row, column, value)`, column by column, into `out`
/// (no allocation within its capacity).
fn non_zeros(m: &DMatrix<f64>, out: &mut Vec<(usize, usize, f64)>) {
    out.clear();
    for j in 0..m.ncols() {
        for (i, &v) in m.column(j).iter().enumerate() {
            if v != 0.0 {
                out.push((i, j, v));
            }
        }
    }
}

/// `out = M S` for `S` given by its non-zero entries `s` (`non_zeros`): column `j` of
/// `out` is `Σ_k S_kj M_:k` over the entries of column `j`.
fn mul_sparse(m: &DMatrix<f64>, s: &[(usize, usize, f64)], out: &mut DMatrix<f64>) {
    out.fill(0.0);
    for &(k, j, v) in s {
        out.column_mut(j).axpy(v, &m.column(k), 1.0);
    }
}

/// `out += Sᵀ X` for `S` given by its non-zero entries `s` (`non_zeros`): row `i` of
/// `out` gains `S_ki X_k:` for each entry `(k, i)`.
fn add_sparse_tr_mul(s: &[(usize, usize, f64)], x: &DMatrix<f64>, out: &mut DMatrix<f64>) {
    for c in 0..x.ncols() {
        let xc = x.column(c);
        let mut oc = out.column_mut(c);
        for &(k, i, v) in s {
            oc[i] += v * xc[k];
        }
    }
}

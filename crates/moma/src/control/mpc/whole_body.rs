//! The whole-body MPC: the receding-horizon problem on [`MpcRobot`] (dynamics, costs,
//! constraints), solved by [`Solver`] from the previous solution shifted one stage.
//!
//! Transition (semi-implicit Euler, step `dt`, exact Jacobians):
//!
//! ```text
//! ν⁺ = ν + dt u,   [x y θ]⁺ = [x y θ] + dt N_b(θ) [v ω]⁺,   q_c⁺ = q_c + dt q̇_c⁺
//! ```
//!
//! with `ν = [v, ω, q̇_c]` and `N_b(θ)` the platform block of the admissible-velocity
//! basis. The dynamics proper enter through the torque constraints: the torques that
//! realise `u` are the reduced model's inverse dynamics.

use std::time::Instant;

use nalgebra::{DMatrix, DVector, Matrix2, Vector2, Vector3};

use super::constraints::{ConstraintSet, ConstraintSettings, clearance_rows};
use super::costs::{CostWeights, KnotReference, knot_cost};
use super::distance_field::MapClearance;
use super::problem::{OptimalControlProblem, StageModel};
use super::report::{SolveReport, Violations};
use super::robot::{KnotWorkspace, MpcRobot, evaluate_knot, select_pairs};
use super::solver::{SolveStats, Solver, SolverOptions, Trajectory};
use super::warm_start::shift_solution;
use crate::error::{Error, Result};

/// Horizon, bounds, weights, constraints and solver settings.
#[derive(Clone, Debug)]
pub struct MpcSettings {
    /// Stages N.
    pub stages: usize,
    /// Stage length (s); the horizon is `stages · dt`.
    pub dt: f64,
    /// Bound on `|v̇|` (m/s²).
    pub max_linear_acceleration: f64,
    /// Bound on `|ω̇|` (rad/s²).
    pub max_angular_acceleration: f64,
    /// Bound on each moved joint's `|q̈|`.
    pub max_joint_acceleration: f64,
    /// Cost weights.
    pub weights: CostWeights,
    /// Constraint set values and penalty.
    pub constraints: ConstraintSettings,
    /// Solver settings (its iteration budget is the per-solve budget).
    pub solver: SolverOptions,
}

impl Default for MpcSettings {
    fn default() -> Self {
        Self {
            stages: 20,
            dt: 0.05,
            max_linear_acceleration: 3.0,
            max_angular_acceleration: 6.0,
            max_joint_acceleration: 6.0,
            weights: CostWeights::default(),
            constraints: ConstraintSettings::default(),
            solver: SolverOptions {
                max_iterations: 4,
                tolerance: 1e-6,
                stop_on_failed_line_search: true,
                ..SolverOptions::default()
            },
        }
    }
}

/// The problem the solver sees (kept apart from the solver so both can be borrowed).
#[derive(Clone, Debug)]
pub struct MpcProblem {
    /// The robot.
    pub robot: MpcRobot,
    /// Settings.
    pub settings: MpcSettings,
    /// The reference at each knot (N + 1), set by the caller before a solve.
    pub reference: Vec<KnotReference>,
    /// Posture of the moved joints the regulariser pulls to.
    pub posture: DVector<f64>,
    /// Full configuration holding the joints the MPC does not move.
    pub hold: DVector<f64>,
    /// Multipliers and the last values of the constraints.
    pub constraints: ConstraintSet,
    /// The map the base footprint keeps `settings.constraints.map_clearance` from
    /// (`None`: no map; the caller's to set and refresh).
    pub map: Option<MapClearance>,
    ws: KnotWorkspace,
    lo: DVector<f64>,
    hi: DVector<f64>,
    /// The constraints on the first input that hold exactly at the solve's measured
    /// state, each affine in it there: row `r` is `first_rows[r] · u_0 + first_offsets[r]
    /// ≤ 0`; set at the start of each solve ([`MpcProblem::linearize_first_input`]).
    /// The first [`WHEEL_TORQUE_ROWS`] bound the wheels' torques; the next
    /// `first_zmp_rows` keep the ZMP margin.
    first_rows: DMatrix<f64>,
    first_offsets: DVector<f64>,
    first_zmp_rows: usize,
    /// The half-planes of [`OptimalControlProblem::admissible_input`] (scratch, with
    /// room for every row).
    planes: Vec<Vector3<f64>>,
    /// Per knot, the ZMP margin and clearance of the last evaluation.
    min_zmp: Vec<f64>,
    min_clearance: Vec<f64>,
    /// The same as of the last [`OptimalControlProblem::keep_evaluation`].
    kept_min_zmp: Vec<f64>,
    kept_min_clearance: Vec<f64>,
}

impl MpcProblem {
    /// The distance at or beyond which knot `k`'s clearance rows are inactive, so that
    /// pairs that far apart need no query: a row `c = (d_min − d) / ℓ` enters only where
    /// `λ + ρ c > 0`, that is `d < d_min + λ ℓ / ρ`; beyond it the term, its
    /// derivatives and the multiplier step are the same whatever `d` is. With
    /// `derivatives`, at least `d_min` plus the clearance band, within which an inactive
    /// row gives the model its curvature. `−∞` (no query) at knot 0, whose state is
    /// measured, and without a clearance constraint.
    fn distance_cutoff(&self, k: usize, derivatives: bool) -> f64 {
        let s = &self.settings.constraints;
        match s.clearance {
            Some(_) if k == 0 => f64::NEG_INFINITY,
            None => f64::NEG_INFINITY,
            Some(d) => {
                let lambda = self.constraints.lambda[k].as_slice()[clearance_rows(&self.robot, s)]
                    .iter()
                    .fold(0.0, |m: f64, &l| m.max(l));
                let reach = lambda * s.length_scale / s.penalty;
                d + if derivatives {
                    reach.max(s.clearance_band)
                } else {
                    reach
                }
            }
        }
    }

    /// The exact constraints on the first input at the measured state `x0`
    /// (`first_rows`, `first_offsets`), from one evaluation of knot 0 with derivatives
    /// at the first input `u0`: at a fixed state the wheels' torques
    /// `(N_Cᵀ S)⁻¹ (M_r u + c_r + G_r)` and the gravito-inertial wrench `[f; M]` (about
    /// the ground point below the origin) are affine in `u`. The rows:
    ///
    /// - `±τ_i − torque_fraction · τ_max,i ≤ 0` for each wheel `i`;
    /// - with a ZMP set value `m`, for each edge of the support (inward normal `n`, a
    ///   point `a` on it) the ZMP `p = (−M_y / f_z, M_x / f_z)` at least `m` inside,
    ///   `n·p ≥ n·a + m`, which for `f_z < 0` is `n_y M_x − n_x M_y − (n·a + m) f_z ≤ 0`;
    ///   and `f_z ≤ −10⁻⁶ m_robot |g|` (the robot presses on the ground, so the ZMP
    ///   exists). Together: the ZMP margin at the measured state is at least `m`.
    fn linearize_first_input(&mut self, x0: &DVector<f64>, u0: &DVector<f64>) {
        self.ws.distance_cutoff = f64::NEG_INFINITY;
        evaluate_knot(&self.robot, &mut self.ws, &self.hold, x0, Some(u0), true);
        let vals = &self.ws.values;
        let nu = u0.len();
        // row r: coefficients over u and the value at u0, then offset = value − row · u0.
        let mut set = |r: usize, row: &dyn Fn(usize) -> f64, value: f64| {
            let mut offset = value;
            for j in 0..nu {
                let d = row(j);
                self.first_rows[(r, j)] = d;
                offset -= d * u0[j];
            }
            self.first_offsets[r] = offset;
        };
        for i in 0..2 {
            let lim = self.settings.constraints.torque_fraction * self.robot.torque_limit[i];
            for (side, sign) in [1.0, -1.0].into_iter().enumerate() {
                set(
                    2 * i + side,
                    &|j| sign * vals.torque_du[(i, j)],
                    sign * vals.torque[i] - lim,
                );
            }
        }
        self.first_zmp_rows = 0;
        let Some(margin) = self.settings.constraints.zmp_margin else {
            return;
        };
        let (w, dw) = (&vals.ground_wrench, &vals.ground_wrench_du);
        let support = self.ws.support();
        // Coefficients c of c · [f; M].
        let mut coeffs = |r: usize, c: [f64; 6]| {
            let value = (0..6).map(|i| c[i] * w[i]).sum();
            set(r, &|j| (0..6).map(|i| c[i] * dw[(i, j)]).sum(), value);
        };
        for e in 0..support.len() {
            let edge = support.edge(e);
            let n = edge.inward;
            let d = n.x * edge.from.x + n.y * edge.from.y + margin;
            coeffs(WHEEL_TORQUE_ROWS + e, [0.0, 0.0, -d, n.y, -n.x, 0.0]);
        }
        let weight = 1e-6 * self.robot.stability.gravity.norm() * self.ws.mass();
        let lift_off = WHEEL_TORQUE_ROWS + support.len();
        coeffs(lift_off, [0.0, 0.0, 1.0, 0.0, 0.0, 0.0]);
        self.first_offsets[lift_off] += weight;
        self.first_zmp_rows = support.len() + 1;
    }

    /// Evaluates knot `k` and its costs and constraint terms.
    fn knot(
        &mut self,
        k: usize,
        x: &DVector<f64>,
        u: Option<&DVector<f64>>,
        mut out: Option<&mut StageModel>,
    ) -> Result<f64> {
        self.ws.distance_cutoff = self.distance_cutoff(k, out.is_some());
        evaluate_knot(&self.robot, &mut self.ws, &self.hold, x, u, out.is_some());
        let (clearance, gradient) = match (&self.map, self.settings.constraints.map_clearance) {
            (Some(map), Some(_)) if k > 0 => map.at([x[0], x[1], x[2]]),
            _ => (f64::INFINITY, [0.0; 3]),
        };
        self.ws.values.map_clearance = clearance;
        self.ws.values.map_clearance_dx = gradient;
        let vals = &self.ws.values;
        self.min_zmp[k] = if u.is_some() {
            vals.zmp_margin.unwrap_or(f64::NEG_INFINITY)
        } else {
            f64::INFINITY
        };
        self.min_clearance[k] = if k > 0 {
            vals.distances[0]
        } else {
            f64::INFINITY
        };
        if let Some(o) = out.as_deref_mut() {
            o.clear_cost();
        }
        let c = knot_cost(
            &self.robot,
            &self.settings.weights,
            &self.reference[k],
            &self.posture,
            x,
            u,
            vals,
            out.as_deref_mut(),
        );
        let a = self.constraints.knot_terms(
            &self.robot,
            &self.settings.constraints,
            k,
            x,
            u,
            vals,
            out,
        );
        Ok(c + a)
    }
}

impl OptimalControlProblem for MpcProblem {
    fn nx(&self) -> usize {
        self.robot.nx()
    }
    fn nu(&self) -> usize {
        self.robot.nu()
    }
    fn horizon(&self) -> usize {
        self.settings.stages
    }
    fn dynamics(
        &mut self,
        _k: usize,
        x: &DVector<f64>,
        u: &DVector<f64>,
        next: &mut DVector<f64>,
    ) -> Result<()> {
        let n = self.robot.n_moved();
        let h = self.settings.dt;
        let dd = &self.robot.wheeled.base.drive;
        next.copy_from(x);
        for i in 0..2 + n {
            next[3 + n + i] += h * u[i];
        }
        let nb = dd.basis(x[2]);
        let (v, w) = (next[3 + n], next[4 + n]);
        for r in 0..3 {
            next[r] += h * (nb[(r, 0)] * v + nb[(r, 1)] * w);
        }
        for i in 0..n {
            next[3 + i] += h * next[5 + n + i];
        }
        Ok(())
    }
    fn cost(&mut self, k: usize, x: &DVector<f64>, u: Option<&DVector<f64>>) -> Result<f64> {
        self.knot(k, x, u, None)
    }
    fn approximate(
        &mut self,
        k: usize,
        x: &DVector<f64>,
        u: Option<&DVector<f64>>,
        out: &mut StageModel,
    ) -> Result<f64> {
        if let Some(u) = u {
            let n = self.robot.n_moved();
            let h = self.settings.dt;
            let dd = &self.robot.wheeled.base.drive;
            let nb = dd.basis(x[2]);
            let dnb = dd.basis_dot(x[2], 1.0);
            let (v, w) = (x[3 + n] + h * u[0], x[4 + n] + h * u[1]);
            out.a.fill_with_identity();
            out.b.fill(0.0);
            for r in 0..3 {
                out.a[(r, 2)] += h * (dnb[(r, 0)] * v + dnb[(r, 1)] * w);
                for c in 0..2 {
                    out.a[(r, 3 + n + c)] = h * nb[(r, c)];
                    out.b[(r, c)] = h * h * nb[(r, c)];
                }
            }
            for i in 0..n {
                out.a[(3 + i, 5 + n + i)] = h;
                out.b[(3 + i, 2 + i)] = h * h;
            }
            for i in 0..2 + n {
                out.b[(3 + n + i, i)] = h;
            }
        }
        self.knot(k, x, u, Some(out))
    }
    /// The costs are weighted squares (≥ 0 with non-negative weights) and each
    /// augmented-Lagrangian term is at least `−λ²/2ρ`; the multipliers do not move within
    /// a solve.
    fn cost_lower_bound(&self, k: usize) -> f64 {
        let w = &self.settings.weights;
        let rho = self.settings.constraints.penalty;
        let weights = [
            w.base_position,
            w.base_yaw,
            w.ee_position,
            w.ee_orientation,
            w.platform_velocity,
            w.joint_velocity,
            w.platform_acceleration,
            w.joint_acceleration,
            w.posture,
            w.terminal,
        ];
        if rho.is_nan() || rho <= 0.0 || weights.iter().any(|v| v.is_nan() || *v < 0.0) {
            return f64::NEG_INFINITY;
        }
        -self.constraints.lambda[k].norm_squared() / (2.0 * rho)
    }
    /// The acceleration bounds cut, for each moved joint, by its speed limit at the next
    /// knot: `q̇⁺ = q̇ + dt q̈` is affine in `q̈`, so `|q̇⁺| ≤ q̇_max` is the interval
    /// `[(−q̇_max − q̇)/dt, (q̇_max − q̇)/dt]` for the knot's `q̇`, intersected with the
    /// acceleration bound (where the two do not meet, `|q̇|` beyond what one stage at the
    /// bound brings back, the bound nearest the limits: full braking).
    fn input_bounds(
        &self,
        _k: usize,
        x: &DVector<f64>,
        lo: &mut DVector<f64>,
        hi: &mut DVector<f64>,
    ) {
        lo.copy_from(&self.lo);
        hi.copy_from(&self.hi);
        let n = self.robot.n_moved();
        let h = self.settings.dt;
        for i in 0..n {
            let (a_lo, a_hi) = (self.lo[2 + i], self.hi[2 + i]);
            let (vmax, qd) = (self.robot.speed_limit[i], x[5 + n + i]);
            lo[2 + i] = ((-vmax - qd) / h).clamp(a_lo, a_hi);
            hi[2 + i] = ((vmax - qd) / h).clamp(a_lo, a_hi);
        }
    }
    /// The box of [`MpcProblem::input_bounds`], the wheel-rate limit at the next knot
    /// and, at knot 0, the exact constraints of the measured state (the wheels' torque
    /// limits and the ZMP margin, [`MpcProblem::linearize_first_input`]).
    /// `φ̇⁺ = W ([v, ω] + dt [v̇, ω̇])` is affine in the platform's accelerations, so
    /// `|φ̇⁺_L|, |φ̇⁺_R| ≤ φ̇_max` is a box on the wheels' accelerations `z = W [v̇, ω̇]`;
    /// the acceleration bounds on `(v̇, ω̇)` are a parallelogram there; and each row of
    /// knot 0, affine in the input, is one more half-plane in `z` for the arm's inputs
    /// given. The platform input is moved to the nearest point (in `z`) of their
    /// intersection, a convex polygon; where it is empty, the nearest point of the
    /// polygon without the wheel rates, then without the ZMP margin too, then of the
    /// acceleration bounds alone (a wheel beyond what one stage can bring back: the
    /// nearest the limit it gets; an arm input that tips the robot whatever the base
    /// does: the wheels' torques kept).
    fn admissible_input(
        &mut self,
        k: usize,
        x: &DVector<f64>,
        u: &mut DVector<f64>,
        lo: &mut DVector<f64>,
        hi: &mut DVector<f64>,
    ) {
        self.clamp_to_input_bounds(k, x, u, lo, hi);
        let n = self.robot.n_moved();
        let w = &self.robot.wheel_map;
        let Some(w_inv) = w.try_inverse() else {
            return;
        };
        let dt = self.settings.dt;
        let limit = self.robot.wheel_rate_limit;
        let rate = w * Vector2::new(x[3 + n], x[4 + n]);
        // Half-planes a·z ≤ b as (a, b): the acceleration bounds (rows of W⁻¹), the
        // rows of knot 0 (wheel torques, ZMP), the wheel rates.
        let planes = &mut self.planes;
        planes.clear();
        for i in 0..2 {
            let r = w_inv.row(i);
            planes.push(Vector3::new(r[0], r[1], hi[i]));
            planes.push(Vector3::new(-r[0], -r[1], -lo[i]));
        }
        let rows_here = if k == 0 {
            WHEEL_TORQUE_ROWS + self.first_zmp_rows
        } else {
            0
        };
        for r in 0..rows_here {
            let row = self.first_rows.row(r);
            let mut rest = self.first_offsets[r];
            for j in 2..u.len() {
                rest += row[j] * u[j];
            }
            let a = Vector2::new(row[0], row[1]).transpose() * w_inv;
            planes.push(Vector3::new(a[0], a[1], -rest));
        }
        for i in 0..2 {
            let mut e = Vector2::zeros();
            e[i] = 1.0;
            planes.push(Vector3::new(e[0], e[1], (limit - rate[i]) / dt));
            planes.push(Vector3::new(-e[0], -e[1], (limit + rate[i]) / dt));
        }
        let speed = 4 + rows_here;
        let torque = 4 + rows_here.min(WHEEL_TORQUE_ROWS);
        let z0 = w * Vector2::new(u[0], u[1]);
        let z = nearest_in_polygon(planes, z0)
            .or_else(|| nearest_in_polygon(&planes[..speed], z0))
            .or_else(|| nearest_in_polygon(&planes[..torque], z0))
            .or_else(|| nearest_in_polygon(&planes[..4], z0))
            .unwrap_or(z0);
        let p = w_inv * z;
        u[0] = p[0].clamp(lo[0], hi[0]);
        u[1] = p[1].clamp(lo[1], hi[1]);
    }
    /// Keeps the constraint rows, violations, ZMP margins and clearances of the pass:
    /// the report and the multiplier step of the solve read them, with no pass of
    /// their own over the returned trajectory.
    fn keep_evaluation(&mut self) {
        self.constraints.keep();
        self.kept_min_zmp.copy_from_slice(&self.min_zmp);
        self.kept_min_clearance.copy_from_slice(&self.min_clearance);
    }
}

/// Rows of [`MpcProblem::linearize_first_input`] that bound the wheels' torques: `±τ_i`
/// for each of the two wheels.
const WHEEL_TORQUE_ROWS: usize = 4;

/// The whole-body MPC: problem, solver workspace and the last solution.
#[derive(Clone, Debug)]
pub struct WholeBodyMpc {
    /// The problem (reference, posture and held joints are the caller's to set).
    pub problem: MpcProblem,
    solver: Solver,
    /// The last solution (the warm start of the next solve).
    pub solution: Trajectory,
    x0: DVector<f64>,
    /// The plant state of the last [`WholeBodyMpc::first_input_torques_at`]: MPC state
    /// and full configuration (the held joints' positions).
    x_now: DVector<f64>,
    hold_now: DVector<f64>,
    solved_once: bool,
}

impl WholeBodyMpc {
    /// An MPC for `robot` with `settings`; the posture and held joints start at
    /// `q_start` (a full configuration of the robot's model).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a horizon shorter than one stage, a non-positive step or
    /// acceleration bound, or a configuration of the wrong length.
    pub fn new(robot: MpcRobot, settings: MpcSettings, q_start: &DVector<f64>) -> Result<Self> {
        if settings.stages == 0 {
            return Err(Error::invalid("mpc.stages", "must be at least 1"));
        }
        if settings.constraints.clearance_pairs == 0 {
            return Err(Error::invalid("mpc.clearance_pairs", "must be at least 1"));
        }
        let band = settings.constraints.clearance_band;
        if !(band >= 0.0 && band.is_finite()) {
            return Err(Error::invalid(
                "mpc.clearance_band",
                format!("must be zero or positive, got {band}"),
            ));
        }
        for (field, v) in [
            ("mpc.dt", settings.dt),
            (
                "mpc.max_linear_acceleration",
                settings.max_linear_acceleration,
            ),
            (
                "mpc.max_angular_acceleration",
                settings.max_angular_acceleration,
            ),
            (
                "mpc.max_joint_acceleration",
                settings.max_joint_acceleration,
            ),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(Error::invalid(field, format!("must be positive, got {v}")));
            }
        }
        if q_start.len() != robot.wheeled.model.nq {
            return Err(Error::invalid(
                "q_start",
                format!(
                    "length {} != nq = {}",
                    q_start.len(),
                    robot.wheeled.model.nq
                ),
            ));
        }
        let (nx, nu, n) = (robot.nx(), robot.nu(), settings.stages);
        let mut lo = DVector::from_element(nu, -settings.max_joint_acceleration);
        lo[0] = -settings.max_linear_acceleration;
        lo[1] = -settings.max_angular_acceleration;
        let hi = -&lo;
        let row_capacity = WHEEL_TORQUE_ROWS + robot.stability.support.len() + 1;
        let posture =
            DVector::from_iterator(robot.n_moved(), robot.dofs.iter().map(|&d| q_start[d]));
        let problem = MpcProblem {
            ws: KnotWorkspace::new(&robot, settings.constraints.clearance_pairs),
            constraints: ConstraintSet::new(&robot, &settings.constraints, n),
            map: None,
            reference: vec![KnotReference::default(); n + 1],
            posture,
            hold: q_start.clone(),
            lo,
            hi,
            first_rows: DMatrix::zeros(row_capacity, nu),
            first_offsets: DVector::zeros(row_capacity),
            first_zmp_rows: 0,
            planes: Vec::with_capacity(8 + row_capacity),
            min_zmp: vec![f64::INFINITY; n + 1],
            min_clearance: vec![f64::INFINITY; n + 1],
            kept_min_zmp: vec![f64::INFINITY; n + 1],
            kept_min_clearance: vec![f64::INFINITY; n + 1],
            robot,
            settings,
        };
        Ok(Self {
            problem,
            solver: Solver::new(nx, nu, n),
            solution: Trajectory::zeros(nx, nu, n),
            x0: DVector::zeros(nx),
            x_now: DVector::zeros(nx),
            hold_now: q_start.clone(),
            solved_once: false,
        })
    }

    /// Sets the reference of every knot from `f(t_k)`, `t_k = t + k dt` (no allocation).
    pub fn set_reference(&mut self, t: f64, mut f: impl FnMut(f64) -> KnotReference) {
        let dt = self.problem.settings.dt;
        for (k, r) in self.problem.reference.iter_mut().enumerate() {
            *r = f(t + dt * k as f64);
        }
    }

    /// Solves from the plant state `(q, v_r)` (the held joints are read from `q`);
    /// after the first solve, starts from the previous solution shifted one stage.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for states of the wrong length; what the model reports.
    pub fn solve(&mut self, q: &[f64], v_r: &[f64]) -> Result<SolveReport> {
        let start = Instant::now();
        let robot = &self.problem.robot;
        check_plant_state(robot, q, v_r)?;
        robot.state_from_plant(q, v_r, &mut self.x0);
        self.problem.hold.copy_from_slice(q);
        let p = &mut self.problem;
        select_pairs(
            &p.robot,
            &mut p.ws,
            &p.hold,
            p.settings.constraints.activation_distance,
        );
        if self.solved_once {
            shift_solution(&mut self.solution.us, &mut self.problem.constraints.lambda);
        }
        self.problem
            .linearize_first_input(&self.x0, &self.solution.us[0]);
        let opts = self.problem.settings.solver.clone();
        let stats: SolveStats =
            self.solver
                .solve(&mut self.problem, &self.x0, &mut self.solution, &opts)?;
        self.solved_once = true;
        // One multiplier step per solve, at the returned trajectory's values (those of
        // the solver's last kept pass over it).
        let cs = &self.problem.settings.constraints;
        let (penalty, cap) = (cs.penalty, cs.max_multiplier);
        self.problem.constraints.update(penalty, cap);
        let map_constraint = cs.map_clearance.is_some();
        let mut v = Violations::default();
        for row in &self.problem.constraints.kept_violation {
            v = v.max(&Violations::from_array(*row, map_constraint));
        }
        Ok(SolveReport {
            time: start.elapsed(),
            iterations: stats.iterations,
            rollouts: stats.rollouts,
            cost: stats.cost,
            converged: stats.converged,
            violations: v,
            min_zmp_margin: self
                .problem
                .kept_min_zmp
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min),
            min_clearance: self
                .problem
                .kept_min_clearance
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min),
        })
    }

    /// The actuator torques that realise the first planned input `[v̇, ω̇, q̈_c]` at the
    /// plant state `(q, v_r)` (inverse dynamics of the reduced model), written into `tau`
    /// (nu of the full model: wheels, then every arm joint); the joints the MPC does not
    /// move are held at `q`'s positions and get the torque that keeps their acceleration
    /// zero. Clipped to the limits when `clip`.
    ///
    /// At the state of the last solve these are the torques its torque constraint bounds.
    /// Between solves, at the measured state, they keep the planned acceleration (the
    /// input the MPC's model holds over a stage) where a torque held from the solve drifts
    /// from it as the state moves: the velocity and gravity terms of a light joint change
    /// within the period.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for states of the wrong length.
    pub fn first_input_torques_at(
        &mut self,
        q: &[f64],
        v_r: &[f64],
        tau: &mut [f64],
        clip: bool,
    ) -> Result<()> {
        let p = &mut self.problem;
        check_plant_state(&p.robot, q, v_r)?;
        p.robot.state_from_plant(q, v_r, &mut self.x_now);
        self.hold_now.copy_from_slice(q);
        p.ws.distance_cutoff = f64::NEG_INFINITY;
        evaluate_knot(
            &p.robot,
            &mut p.ws,
            &self.hold_now,
            &self.x_now,
            Some(&self.solution.us[0]),
            false,
        );
        for (i, t) in tau.iter_mut().enumerate() {
            let v = p.ws.values.torque[i];
            let lim = p.robot.torque_limit[i];
            *t = if clip { v.clamp(-lim, lim) } else { v };
        }
        Ok(())
    }

    /// The first planned input `[v̇, ω̇, q̈_c]`.
    #[must_use]
    pub fn first_input(&self) -> &DVector<f64> {
        &self.solution.us[0]
    }
}

/// [`Error::InvalidInput`] unless `q` and `v_r` are a plant state of `robot` (nq and nr
/// long).
fn check_plant_state(robot: &MpcRobot, q: &[f64], v_r: &[f64]) -> Result<()> {
    let (nq, nr) = (robot.wheeled.model.nq, robot.wheeled.nr());
    if q.len() != nq || v_r.len() != nr {
        return Err(Error::invalid(
            "mpc state",
            format!(
                "q has {} (nq = {nq}), v has {} (nr = {nr})",
                q.len(),
                v_r.len()
            ),
        ));
    }
    Ok(())
}

/// The point nearest `z0` of the convex polygon `{z : a·z ≤ b}` of the half-planes
/// `(a, b)` (feasible to a relative 1e-9): `z0` itself if inside, else the nearest of its
/// projections onto the lines and their pairwise corners that lie inside (the nearest
/// point of a polygon is on an edge or at a corner); `None` when no candidate is inside
/// (the polygon is empty).
fn nearest_in_polygon(planes: &[Vector3<f64>], z0: Vector2<f64>) -> Option<Vector2<f64>> {
    let inside = |z: &Vector2<f64>| {
        z.iter().all(|c| c.is_finite())
            && planes
                .iter()
                .all(|p| p.x * z[0] + p.y * z[1] <= p.z + 1e-9 * (1.0 + p.z.abs()))
    };
    if inside(&z0) {
        return Some(z0);
    }
    let mut best: Option<(f64, Vector2<f64>)> = None;
    let mut consider = |z: Vector2<f64>| {
        if inside(&z) {
            let d = (z - z0).norm_squared();
            if best.is_none_or(|(b, _)| d < b) {
                best = Some((d, z));
            }
        }
    };
    for (i, p) in planes.iter().enumerate() {
        let a = Vector2::new(p.x, p.y);
        let aa = a.norm_squared();
        if aa > 0.0 {
            consider(z0 - a * ((a.dot(&z0) - p.z) / aa));
        }
        for q in &planes[i + 1..] {
            if let Some(m_inv) = Matrix2::new(p.x, p.y, q.x, q.y).try_inverse() {
                consider(m_inv * Vector2::new(p.z, q.z));
            }
        }
    }
    best.map(|(_, z)| z)
}

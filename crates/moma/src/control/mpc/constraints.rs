//! The MPC's constraints and their augmented-Lagrangian terms.
//!
//! Every constraint is an inequality `c(x, u) ≤ 0`, scaled to be dimensionless (a torque
//! by its limit, a speed by its limit, the ZMP margin and the clearances by
//! [`ConstraintSettings::length_scale`]). Each enters the stage cost as the
//! Powell–Hestenes–Rockafellar term
//!
//! ```text
//! (1 / 2ρ) (max(0, λ + ρ c)² − λ²)
//! ```
//!
//! with gradient `max(0, λ + ρ c) ∇c` and Gauss–Newton Hessian `ρ ∇c ∇cᵀ` where active;
//! after each MPC solve the multipliers move to `max(0, λ + ρ c)`, capped at
//! [`ConstraintSettings::max_multiplier`] (a safeguarded augmented Lagrangian: a
//! constraint the plan cannot meet, such as a clearance already below its set value at
//! the measured state, would otherwise raise its multiplier by `ρ c` at every solve
//! without bound, and the cost it dominates would leave the line search no step).
//!
//! A clearance row inactive at the linearisation but within
//! [`ConstraintSettings::clearance_band`] of its set value still adds its Gauss–Newton
//! curvature `ρ ∇c ∇cᵀ` to the stage model (not its gradient, and not to the cost): the
//! step's model then resists closing a pair that is about to become active, which the
//! model of the active rows alone cannot see.
//!
//! Kinds, per knot (state constraints from knot 1 on, since `x_0` is measured; the
//! input–state ones at knots 0 … N − 1):
//!
//! | kind | constraint | derivative |
//! | --- | --- | --- |
//! | torque | `|τ_i| ≤ τ_max,i`, every actuator, `τ = (N_Cᵀ S)⁻¹ (Mr v̇_r + cr + Gr)` | `∂τ/∂u` exact with Mr frozen; `∂τ/∂x` left out |
//! | wheel speed | `|φ̇_L|, |φ̇_R| ≤ φ̇_max` | exact (linear) |
//! | joint speed | `|q̇_i| ≤ q̇_max,i` | exact |
//! | joint position | `lower + δ ≤ q_i ≤ upper − δ` | exact |
//! | ZMP | margin ≥ `zmp_margin` | in u exact (momentum rate affine in q̈); in x the point-mass linearisation, on the critical edge |
//! | clearance | one row per nearest pair (self pairs, scene; the [`ConstraintSettings::clearance_pairs`] nearest, ascending): distance ≥ `clearance` | that pair's distance derivative |
//! | map clearance | base footprint's clearance on the map's distance field ≥ `map_clearance` | the bilinear field's gradient in `(x, y, θ)` |
//!
//! The joint-speed and wheel-speed limits, and the wheels' torque limits and the ZMP
//! margin of the first input, are also enforced exactly by the solver, on every input it
//! applies (the whole-body problem's `input_bounds` and `admissible_input`,
//! `docs/mpc.md`, "Limits the solver enforces"); their rows here then stay inactive
//! unless the limit cannot be met in one stage (for the ZMP at knot 0: by the platform's
//! inputs, the arm's given).

use nalgebra::DVector;

use super::problem::StageModel;
use super::robot::{KnotValues, MpcRobot};

/// The constraint kinds, in report order.
pub const KINDS: [&str; 7] = [
    "torque",
    "wheel_speed",
    "joint_speed",
    "joint_position",
    "zmp",
    "clearance",
    "map_clearance",
];

/// Set values and the augmented-Lagrangian penalty.
#[derive(Clone, Debug)]
pub struct ConstraintSettings {
    /// Smallest ZMP margin allowed (m); `None`: no tip-over constraint.
    pub zmp_margin: Option<f64>,
    /// Smallest distance to the scene and between enabled link pairs (m); `None`: none.
    pub clearance: Option<f64>,
    /// Smallest clearance of the base footprint to the map's obstacles (m), on the
    /// problem's [`super::MapClearance`]; `None`: none.
    pub map_clearance: Option<f64>,
    /// Distance kept from the joint position limits (rad or m).
    pub position_margin: f64,
    /// Fraction of the torque limits the MPC may plan with (≤ 1).
    pub torque_fraction: f64,
    /// Penalty ρ.
    pub penalty: f64,
    /// Largest multiplier (the multipliers are kept in `[0, max_multiplier]`).
    pub max_multiplier: f64,
    /// Length that scales the ZMP and clearance constraints (m).
    pub length_scale: f64,
    /// Self pairs farther apart than this at the start of a solve are not checked in
    /// that solve (m; `∞`: every enabled pair).
    pub activation_distance: f64,
    /// Clearance rows per knot (≥ 1): one for each of the nearest this many pairs (self
    /// pairs and scene link–object pairs), each with its own distance, gradient and
    /// multiplier, so the step's model sees a second pair that closes while the
    /// nearest one opens.
    pub clearance_pairs: usize,
    /// Width of the band above the clearance's set value (m) within which an inactive
    /// clearance row still gives the step's model its Gauss–Newton curvature
    /// `ρ ∇c ∇cᵀ` (no gradient, no cost): the model then resists a step that closes a
    /// pair about to become active. 0: none.
    pub clearance_band: f64,
}

impl Default for ConstraintSettings {
    fn default() -> Self {
        Self {
            zmp_margin: Some(0.05),
            clearance: Some(0.03),
            map_clearance: None,
            position_margin: 0.02,
            torque_fraction: 1.0,
            penalty: 1000.0,
            max_multiplier: 1000.0,
            length_scale: 0.02,
            activation_distance: 0.25,
            clearance_pairs: 4,
            clearance_band: 0.003,
        }
    }
}

/// Rows per knot for `robot` with `s`.
#[must_use]
pub fn rows(robot: &MpcRobot, s: &ConstraintSettings) -> usize {
    2 * robot.torque_limit.len() + 4 + 4 * robot.n_moved() + 2 + s.clearance_pairs
}

/// The clearance rows in a knot's rows (the last but one group: the ZMP's row before
/// them, the map clearance's after them), nearest pair first.
#[must_use]
pub fn clearance_rows(robot: &MpcRobot, s: &ConstraintSettings) -> std::ops::Range<usize> {
    let end = rows(robot, s) - 1;
    end - s.clearance_pairs..end
}

/// Multipliers and the last evaluated values (scaled) of every row of every knot.
#[derive(Clone, Debug)]
pub struct ConstraintSet {
    /// `lambda[k][row]`.
    pub lambda: Vec<DVector<f64>>,
    /// `value[k][row]`: the scaled `c` of the last evaluation (`−∞`: not applied).
    pub value: Vec<DVector<f64>>,
    /// Physical violation per kind (`max(0, ·)` in SI units) per knot: `[k][kind]`.
    pub violation: Vec<[f64; 7]>,
    /// `value` as of the last [`ConstraintSet::keep`]: the rows of the trajectory the
    /// solver returned, which [`ConstraintSet::update`] steps the multipliers from.
    pub kept_value: Vec<DVector<f64>>,
    /// `violation` as of the last [`ConstraintSet::keep`].
    pub kept_violation: Vec<[f64; 7]>,
    gx: DVector<f64>,
    gu: DVector<f64>,
}

impl ConstraintSet {
    /// Zero multipliers for `n + 1` knots.
    #[must_use]
    pub fn new(robot: &MpcRobot, s: &ConstraintSettings, n: usize) -> Self {
        let m = rows(robot, s);
        Self {
            lambda: vec![DVector::zeros(m); n + 1],
            value: vec![DVector::from_element(m, f64::NEG_INFINITY); n + 1],
            violation: vec![[0.0; 7]; n + 1],
            kept_value: vec![DVector::from_element(m, f64::NEG_INFINITY); n + 1],
            kept_violation: vec![[0.0; 7]; n + 1],
            gx: DVector::zeros(robot.nx()),
            gu: DVector::zeros(robot.nu()),
        }
    }

    /// Keeps the values and violations of the last evaluation of every knot (no
    /// allocation).
    pub fn keep(&mut self) {
        for (kept, v) in self.kept_value.iter_mut().zip(&self.value) {
            kept.copy_from(v);
        }
        self.kept_violation.copy_from_slice(&self.violation);
    }

    /// Moves every multiplier to `λ + ρ c` kept in `[0, max_multiplier]`, with the
    /// values `c` of the last [`ConstraintSet::keep`].
    pub fn update(&mut self, penalty: f64, max_multiplier: f64) {
        for (l, c) in self.lambda.iter_mut().zip(&self.kept_value) {
            for (li, &ci) in l.iter_mut().zip(c.iter()) {
                if ci.is_finite() {
                    *li = (*li + penalty * ci).clamp(0.0, max_multiplier);
                }
            }
        }
    }

    /// The augmented-Lagrangian cost of knot `k` at `(x, u)` (terminal: `u = None`)
    /// from the knot's values; records the rows' values and violations, and with `out`
    /// adds the gradient and Hessian.
    #[allow(clippy::too_many_arguments)]
    pub fn knot_terms(
        &mut self,
        robot: &MpcRobot,
        s: &ConstraintSettings,
        k: usize,
        x: &DVector<f64>,
        u: Option<&DVector<f64>>,
        vals: &KnotValues,
        mut out: Option<&mut StageModel>,
    ) -> f64 {
        let n = robot.n_moved();
        let rho = s.penalty;
        let state_rows = k > 0;
        let input_rows = u.is_some();
        let mut cost = 0.0;
        let mut row = 0;
        let viol = &mut self.violation[k];
        *viol = [0.0; 7];
        let (lambda, value, gx, gu) = (
            &self.lambda[k],
            &mut self.value[k],
            &mut self.gx,
            &mut self.gu,
        );
        // One row: scaled value c, physical violation, kind, the scaled value above which
        // the row gives its curvature while inactive (`+∞`: never), and a closure
        // writing ∇c.
        let mut apply = |c: f64,
                         phys: f64,
                         kind: usize,
                         band_floor: f64,
                         grad: &mut dyn FnMut(&mut DVector<f64>, &mut DVector<f64>),
                         out: &mut Option<&mut StageModel>| {
            let l = lambda[row];
            value[row] = c;
            row += 1;
            if !c.is_finite() {
                return;
            }
            viol[kind] = viol[kind].max(phys.max(0.0));
            let a = l + rho * c;
            let active = a > 0.0;
            if active {
                cost += (a * a - l * l) / (2.0 * rho);
            } else {
                cost -= l * l / (2.0 * rho);
            }
            if let Some(o) = out.as_deref_mut()
                && (active || c > band_floor)
            {
                gx.fill(0.0);
                gu.fill(0.0);
                grad(gx, gu);
                if active {
                    o.lx.axpy(a, gx, 1.0);
                    o.lu.axpy(a, gu, 1.0);
                }
                o.lxx.ger(rho, gx, gx, 1.0);
                o.luu.ger(rho, gu, gu, 1.0);
                o.lux.ger(rho, gu, gx, 1.0);
            }
        };
        let never = f64::INFINITY;
        let off = f64::NEG_INFINITY;
        // Torques.
        for i in 0..robot.torque_limit.len() {
            let lim = s.torque_fraction * robot.torque_limit[i];
            let tau = vals.torque[i];
            for sign in [1.0, -1.0] {
                let (c, phys) = if input_rows {
                    ((sign * tau - lim) / lim, sign * tau - robot.torque_limit[i])
                } else {
                    (off, 0.0)
                };
                apply(
                    c,
                    phys,
                    0,
                    never,
                    &mut |_, gu| {
                        for j in 0..gu.len() {
                            gu[j] = sign * vals.torque_du[(i, j)] / lim;
                        }
                    },
                    &mut out,
                );
            }
        }
        // Wheel rates.
        let wl = robot.wheel_rate_limit;
        for side in 0..2 {
            let (a, b) = (robot.wheel_map[(side, 0)], robot.wheel_map[(side, 1)]);
            let rate = a * x[3 + n] + b * x[4 + n];
            for sign in [1.0, -1.0] {
                let (c, phys) = if state_rows {
                    ((sign * rate - wl) / wl, sign * rate - wl)
                } else {
                    (off, 0.0)
                };
                apply(
                    c,
                    phys,
                    1,
                    never,
                    &mut |gx, _| {
                        gx[3 + n] = sign * a / wl;
                        gx[4 + n] = sign * b / wl;
                    },
                    &mut out,
                );
            }
        }
        // Joint speeds and positions.
        for i in 0..n {
            let vmax = robot.speed_limit[i];
            let qd = x[5 + n + i];
            for sign in [1.0, -1.0] {
                let (c, phys) = if state_rows {
                    ((sign * qd - vmax) / vmax, sign * qd - vmax)
                } else {
                    (off, 0.0)
                };
                apply(
                    c,
                    phys,
                    2,
                    never,
                    &mut |gx, _| gx[5 + n + i] = sign / vmax,
                    &mut out,
                );
            }
        }
        for i in 0..n {
            let q = x[3 + i];
            let hi = robot.upper[i] - s.position_margin;
            let lo = robot.lower[i] + s.position_margin;
            let (c_hi, p_hi) = if state_rows && hi.is_finite() {
                (q - hi, q - robot.upper[i])
            } else {
                (off, 0.0)
            };
            apply(c_hi, p_hi, 3, never, &mut |gx, _| gx[3 + i] = 1.0, &mut out);
            let (c_lo, p_lo) = if state_rows && lo.is_finite() {
                (lo - q, robot.lower[i] - q)
            } else {
                (off, 0.0)
            };
            apply(
                c_lo,
                p_lo,
                3,
                never,
                &mut |gx, _| gx[3 + i] = -1.0,
                &mut out,
            );
        }
        // ZMP margin (lift-off counts as a margin of −1 m).
        let ls = s.length_scale;
        let (c, phys) = match (s.zmp_margin, input_rows) {
            (Some(m), true) => {
                let margin = vals.zmp_margin.unwrap_or(-1.0);
                ((m - margin) / ls, m - margin)
            }
            _ => (off, 0.0),
        };
        apply(
            c,
            phys,
            4,
            never,
            &mut |gx, gu| {
                gx.axpy(-1.0 / ls, &vals.zmp_dx, 0.0);
                gu.axpy(-1.0 / ls, &vals.zmp_du, 0.0);
            },
            &mut out,
        );
        // Clearance: one row per nearest pair, in the order of their distances.
        let band_floor = -s.clearance_band / ls;
        for (slot, &dist) in vals.distances.iter().enumerate() {
            let (c, phys) = match s.clearance {
                Some(d) if state_rows && dist.is_finite() => ((d - dist) / ls, d - dist),
                _ => (off, 0.0),
            };
            let grad = &vals.distances_dx[slot];
            apply(
                c,
                phys,
                5,
                band_floor,
                &mut |gx, _| gx.axpy(-1.0 / ls, grad, 0.0),
                &mut out,
            );
        }
        // Map clearance of the base footprint (the base pose's first three states).
        let (c, phys) = match s.map_clearance {
            Some(d) if state_rows && vals.map_clearance.is_finite() => {
                ((d - vals.map_clearance) / ls, d - vals.map_clearance)
            }
            _ => (off, 0.0),
        };
        apply(
            c,
            phys,
            6,
            never,
            &mut |gx, _| {
                for (i, g) in vals.map_clearance_dx.iter().enumerate() {
                    gx[i] = -g / ls;
                }
            },
            &mut out,
        );
        cost
    }
}

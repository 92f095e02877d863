//! The interface every constrained plant offers the simulators: a mechanical system in
//! reduced coordinates (`q̇ = N_C(q) v`, `Mr v̇ + Cr v + Gr = Qr`) with its energy, input
//! power, constraint residual and multipliers. The wheeled URDF model
//! ([`crate::sim::wheeled_system`]) and the chapter's closed-form models
//! ([`crate::sim::chapter_models`]) implement it.

use crate::error::Result;

/// A constrained mechanical system in reduced coordinates `q̇ = N_C(q) v`,
/// `Mr v̇ + Cr v + Gr = Qr`.
pub trait ReducedSystem {
    /// Number of configuration coordinates `q`.
    fn nq(&self) -> usize;
    /// Number of reduced velocities `v`.
    fn nv(&self) -> usize;
    /// Number of inputs `u`.
    fn nu(&self) -> usize;
    /// Names of the configuration coordinates (length [`ReducedSystem::nq`]).
    fn q_names(&self) -> Vec<String>;
    /// Names of the reduced velocities.
    fn v_names(&self) -> Vec<String>;
    /// Names of the inputs.
    fn u_names(&self) -> Vec<String>;
    /// SI units of the configuration coordinates (`"m"`, `"rad"`), one per q name.
    fn q_units(&self) -> Vec<&'static str>;
    /// SI units of the reduced velocities (`"m/s"`, `"rad/s"`).
    fn v_units(&self) -> Vec<&'static str>;
    /// SI units of the inputs (`"N m"` for torques, `"N"` for forces).
    fn u_units(&self) -> Vec<&'static str>;
    /// Writes `q̇ = N_C(q) v` and the reduced acceleration `v̇` under input `u`.
    fn dynamics(
        &mut self,
        q: &[f64],
        v: &[f64],
        u: &[f64],
        qdot: &mut [f64],
        vdot: &mut [f64],
    ) -> Result<()>;
    /// Kinetic and potential energy `(T, V)` (J).
    fn energy(&mut self, q: &[f64], v: &[f64]) -> Result<(f64, f64)>;
    /// Power of the inputs `Qᵀ q̇ = (S u)ᵀ N_C v` (W).
    fn input_power(&mut self, q: &[f64], v: &[f64], u: &[f64]) -> Result<f64>;
    /// Constraint residual `‖C(q) N_C(q) v‖`.
    fn constraint_residual(&mut self, q: &[f64], v: &[f64]) -> Result<f64>;
    /// Number of constraint rows k (length of the multiplier vector).
    fn nk(&self) -> usize;
    /// Lagrange multipliers λ (k) at `(q, v)` under input `u`; for the no-side-slip row,
    /// `−λ` is the lateral ground force on the axle along `e_lat = (−sin θ, cos θ)`.
    fn multipliers(&mut self, q: &[f64], v: &[f64], u: &[f64], out: &mut [f64]) -> Result<()>;
}

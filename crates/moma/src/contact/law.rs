//! The compliant contact law: a linear spring-damper in the normal direction, clamped so
//! the ground only pushes, and Coulomb friction regularised below a slip velocity.

use nalgebra::Vector2;

/// Normal force (N, ≥ 0) for penetration `depth` (m, positive into the ground) and
/// penetration rate `depth_rate` (m/s): `max(0, k δ + c δ̇)` while `δ > 0`, else 0.
#[inline]
#[must_use]
pub fn normal_force(stiffness: f64, damping: f64, depth: f64, depth_rate: f64) -> f64 {
    if depth <= 0.0 {
        return 0.0;
    }
    (stiffness * depth + damping * depth_rate).max(0.0)
}

/// Friction force (N, in the ground plane) on a contact whose material point slides at
/// `slip` (m/s) under normal force `normal`: `−μ N s / max(|s|, v_ε)` — viscous below
/// the regularisation velocity `v_ε`, Coulomb's `μ N` opposite the slip above it.
#[inline]
#[must_use]
pub fn friction_force(
    mu: f64,
    normal: f64,
    slip_velocity: f64,
    slip: &Vector2<f64>,
) -> Vector2<f64> {
    let speed = slip.norm();
    -slip * (mu * normal / speed.max(slip_velocity))
}

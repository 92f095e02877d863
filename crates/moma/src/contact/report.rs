//! What one ground contact did over a step.

use nalgebra::{Vector2, Vector3};

/// The state of one ground contact, evaluated at the start of the last step (the forces
/// applied over it).
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct ContactReport {
    /// The contact point (world, m): the lowest point of the wheel disk or caster sphere.
    pub point: Vector3<f64>,
    /// Penetration δ into the ground (m; negative above it).
    pub depth: f64,
    /// Normal force N ≥ 0 (N).
    pub normal: f64,
    /// Slip velocity: the ground-plane velocity `[x, y]` (world, m/s) of the body's
    /// material point at the contact.
    pub slip: Vector2<f64>,
    /// Friction force `[x, y]` on the robot (world, N); zero for a frictionless caster.
    pub friction: Vector2<f64>,
    /// The contact carries no normal force (lifted off, or separating).
    pub lifted: bool,
    /// A frictional contact slides: it carries normal force and its slip speed is at or
    /// above the regularisation velocity, so friction has reached `μ N`.
    pub slipping: bool,
}

//! Acceleration limits of a posture at rest: how hard the whole robot, translating as
//! one rigid body, may accelerate in a horizontal direction before the ZMP leaves the
//! support.

use nalgebra::Vector3;

use super::polygon::SupportPolygon;

/// The largest accelerations (m/s²) along the base axes before tip-over; `None` when the
/// robot already tips at rest, gravity has no downward component, or no edge limits that
/// direction.
#[derive(Clone, Copy, Debug, PartialEq, Default, serde::Serialize)]
pub struct AccelerationLimits {
    /// Along +x of the base (speeding up forwards, or braking while reversing).
    pub forward: Option<f64>,
    /// Along −x of the base (braking while driving forwards).
    pub backward: Option<f64>,
    /// Along +y of the base.
    pub left: Option<f64>,
    /// Along −y of the base.
    pub right: Option<f64>,
}

/// Largest `λ ≥ 0` such that every body accelerating at `λ u` (a horizontal unit vector
/// `u`, world axes; no rotation, joints held) keeps the ZMP inside `support`.
///
/// The wrench of that motion is `f = M (g − λ u)` with no moment about the centre of
/// mass `c`, so with `n · u = 0` the ZMP `c − h f / (n · f)` (h: height of c above the
/// ground) moves linearly in λ, and each signed edge distance `s_i(λ) = s_i(0) + λ k_i`;
/// the limit is `min_{k_i < 0} s_i(0) / (−k_i)`.
///
/// `None` when `n · g ≥ 0` (no downward gravity), when the ZMP at rest is already
/// outside (`min s_i(0) < 0`), when `u` has a vertical component or no length, or when
/// no edge limits the direction (the ZMP does not move towards any edge, e.g. a CoM on
/// the ground plane). A ZMP at rest exactly on an edge the motion pushes it across gives 0.
#[must_use]
pub fn acceleration_limit(
    mass: f64,
    com: &Vector3<f64>,
    gravity: &Vector3<f64>,
    support: &SupportPolygon,
    direction: &Vector3<f64>,
) -> Option<f64> {
    let un = direction.norm();
    if !(mass > 0.0 && gravity.z < 0.0 && un > 0.0 && un.is_finite()) {
        return None;
    }
    let u = direction / un;
    if u.z.abs() > 1e-12 {
        return None;
    }
    let h = com.z - support.ground_z();
    // ZMP(λ) = c − h (g − λ u) / g_z on the ground plane (n = ẑ).
    let zmp0 = com - gravity * (h / gravity.z);
    let dzmp = u * (h / gravity.z);
    let mut best: Option<f64> = None;
    for i in 0..support.len() {
        let e = support.edge(i);
        let s0 = e.inward.dot(&(zmp0 - e.from));
        if s0 < 0.0 {
            return None;
        }
        let k = e.inward.dot(&dzmp);
        if k < 0.0 {
            let lim = s0 / -k;
            best = Some(best.map_or(lim, |b: f64| b.min(lim)));
        }
    }
    best
}

/// [`acceleration_limit`] along the base axes of heading `yaw` (rad): forward = `(cos, sin, 0)`.
#[must_use]
pub fn acceleration_limits(
    mass: f64,
    com: &Vector3<f64>,
    gravity: &Vector3<f64>,
    support: &SupportPolygon,
    yaw: f64,
) -> AccelerationLimits {
    let (s, c) = yaw.sin_cos();
    let fwd = Vector3::new(c, s, 0.0);
    let left = Vector3::new(-s, c, 0.0);
    let lim = |d: Vector3<f64>| acceleration_limit(mass, com, gravity, support, &d);
    AccelerationLimits {
        forward: lim(fwd),
        backward: lim(-fwd),
        left: lim(left),
        right: lim(-left),
    }
}

//! 6-D spatial algebra on nalgebra: rigid transforms ([`SE3`]), twists ([`Motion`]),
//! wrenches ([`Force`]) and spatial inertias ([`Inertia`]).
//!
//! Conventions (as Pinocchio): spatial vectors are `[linear; angular]`; a transform
//! `a_from_b` maps coordinates of frame `b` into frame `a`; a [`Motion`] expressed in a
//! frame is the twist of the body at that frame's origin, with that frame's axes.
//!
//! A transform is a small [`SE3`] (rotation matrix and translation) rather than
//! nalgebra's `Isometry3`, because moving spatial vectors is cheaper with the rotation
//! stored as a matrix. Every joint angle's sine and cosine is [`trig::sin_cos`],
//! branch-free arithmetic that vectorises, so the multi-state RNEA gives the same bits as
//! the single one.

mod inertia;
mod motion;
mod se3;
pub mod trig;

pub use inertia::Inertia;
pub use motion::{Force, Motion};
pub use se3::{SE3, exp3, exp6, log3, log6, rotation_from_rpy, rpy_from_rotation};

use nalgebra::{Matrix3, Vector3};

/// Skew-symmetric cross-product matrix `[v]×` (3 × 3), with `[v]× w = v × w`.
#[doc(alias = "hat")]
#[must_use]
pub fn skew(v: &Vector3<f64>) -> Matrix3<f64> {
    Matrix3::new(0.0, -v.z, v.y, v.z, 0.0, -v.x, -v.y, v.x, 0.0)
}

//! Whole-body Jacobian `J̄ = J·N` of a manipulator on a differential-drive platform.
//!
//! The model's root is the planar platform joint with `q = [x, y, θ, q_arm…]` and
//! velocity `q̇ = [ẋ, ẏ, θ̇, q̇_arm…]` (world axes). A frame Jacobian `J` (task rows ×
//! nv) with respect to that velocity — e.g. `LocalWorldAligned`, rows `[linear; angular]`
//! — already contains the platform rotation's contribution `ω ẑ × r` in its θ column
//! (the term the chapter's eq. 5.31 leaves out). The non-holonomic constraint removes the
//! lateral direction: `q̇ = N(q) u` with
//!
//! ```text
//! N = blockdiag(N_C(θ) [W], I)      u = [v, ω, q̇_arm]  or  [φ̇_L, φ̇_R, q̇_arm]
//! ```
//!
//! ([`BaseInputs`]: platform inputs, or wheel rates through `W`), so the task velocity is
//! `ẋ = J̄ u` with `J̄ = J N` (Bayle, Fourquet & Renaud 2003; the chapter's `J N_C`).
//! Its time-derivative product, the task acceleration at `u̇ = 0`, is
//! `J̄̇ u = J̇ q̇ + J Ṅ u`, where `J̇ q̇` is the frame's classical acceleration at zero
//! joint acceleration (from the rigid-body core) and `Ṅ u` only involves the base block.
//!
//! These functions are pure linear algebra over a frame Jacobian, so they apply to any
//! arm model; [`crate::ik::tasks`] combines them with forward kinematics.

use super::DiffDrive;
use crate::error::{Error, Result, ensure_finite, ensure_len};
use nalgebra::{DMatrix, DVector, Matrix3x2};
use std::str::FromStr;

/// Which platform velocities parametrise the whole-body inputs `u`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BaseInputs {
    /// `u_base = [v, ω]`: forward speed of the axle midpoint and yaw rate.
    #[default]
    Platform,
    /// `u_base = [φ̇_L, φ̇_R]`: wheel spin rates (left, right).
    Wheels,
}

impl FromStr for BaseInputs {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "platform" | "v-omega" | "unicycle" => Ok(BaseInputs::Platform),
            "wheels" | "wheel-rates" => Ok(BaseInputs::Wheels),
            other => Err(Error::invalid(
                "base inputs",
                format!("unknown '{other}'; expected platform (v, ω) or wheels"),
            )),
        }
    }
}

/// The 3×2 base block of `N`: `N_C(θ)` or `N_C(θ) W`.
#[doc(alias = "N_C")]
pub fn base_block(drive: &DiffDrive, inputs: BaseInputs, theta: f64) -> Matrix3x2<f64> {
    match inputs {
        BaseInputs::Platform => drive.basis(theta),
        BaseInputs::Wheels => drive.wheel_basis(theta),
    }
}

/// Time derivative of [`base_block`] for heading rate `θ̇`.
pub fn base_block_dot(
    drive: &DiffDrive,
    inputs: BaseInputs,
    theta: f64,
    theta_dot: f64,
) -> Matrix3x2<f64> {
    match inputs {
        BaseInputs::Platform => drive.basis_dot(theta, theta_dot),
        BaseInputs::Wheels => drive.basis_dot(theta, theta_dot) * drive.wheel_to_platform(),
    }
}

/// Number of whole-body inputs for a model with `nv` velocity coordinates
/// (the planar root's 3 become 2).
pub fn input_dim(nv: usize) -> usize {
    nv.saturating_sub(1)
}

/// `J̄ = J N(θ)`: writes the whole-body Jacobian (rows × (nv − 1)) into `out`.
///
/// `frame_jacobian` is rows × nv with the planar root velocity `[ẋ, ẏ, θ̇]` in columns
/// 0..3; `out` must be rows × (nv − 1).
#[doc(alias = "J_bar")]
#[doc(alias = "whole_body_jacobian")]
pub fn compose_jacobian(
    drive: &DiffDrive,
    inputs: BaseInputs,
    theta: f64,
    frame_jacobian: &DMatrix<f64>,
    out: &mut DMatrix<f64>,
) -> Result<()> {
    let (rows, nv) = frame_jacobian.shape();
    if nv < 3 {
        return Err(Error::invalid(
            "frame jacobian",
            format!("needs the 3 planar-root columns, got {nv} columns"),
        ));
    }
    ensure_len("whole-body jacobian rows", rows, out.nrows())?;
    ensure_len("whole-body jacobian columns", nv - 1, out.ncols())?;
    let n = base_block(drive, inputs, theta);
    for r in 0..rows {
        for c in 0..2 {
            out[(r, c)] = frame_jacobian[(r, 0)] * n[(0, c)]
                + frame_jacobian[(r, 1)] * n[(1, c)]
                + frame_jacobian[(r, 2)] * n[(2, c)];
        }
        for k in 3..nv {
            out[(r, k - 1)] = frame_jacobian[(r, k)];
        }
    }
    Ok(())
}

/// Allocating form of [`compose_jacobian`].
pub fn whole_body_jacobian(
    drive: &DiffDrive,
    inputs: BaseInputs,
    theta: f64,
    frame_jacobian: &DMatrix<f64>,
) -> Result<DMatrix<f64>> {
    let mut out = DMatrix::zeros(frame_jacobian.nrows(), input_dim(frame_jacobian.ncols()));
    compose_jacobian(drive, inputs, theta, frame_jacobian, &mut out)?;
    Ok(out)
}

/// The model velocity `q̇ = N(θ) u` of whole-body inputs `u` (length nv − 1).
pub fn inputs_to_velocity(
    drive: &DiffDrive,
    inputs: BaseInputs,
    theta: f64,
    u: &DVector<f64>,
) -> DVector<f64> {
    let n = base_block(drive, inputs, theta);
    let mut qd = DVector::zeros(u.len() + 1);
    for r in 0..3 {
        qd[r] = n[(r, 0)] * u[0] + n[(r, 1)] * u[1];
    }
    for k in 2..u.len() {
        qd[k + 1] = u[k];
    }
    qd
}

/// `J̄̇ u = J̇ q̇ + J Ṅ u`: the task acceleration at zero input acceleration.
///
/// `j_dot_qdot` is the frame's `J̇ q̇` at `q̇ = N u` (rows), `frame_jacobian` is `J`
/// (rows × nv), `u` the whole-body inputs (nv − 1).
#[doc(alias = "Jdot_qdot")]
pub fn bias_acceleration(
    drive: &DiffDrive,
    inputs: BaseInputs,
    theta: f64,
    frame_jacobian: &DMatrix<f64>,
    j_dot_qdot: &DVector<f64>,
    u: &DVector<f64>,
) -> Result<DVector<f64>> {
    let (rows, nv) = frame_jacobian.shape();
    ensure_len("whole-body inputs u", nv.saturating_sub(1), u.len())?;
    ensure_len("J̇q̇", rows, j_dot_qdot.len())?;
    ensure_finite("whole-body inputs u", u.iter())?;
    let n = base_block(drive, inputs, theta);
    let theta_dot = n[(2, 0)] * u[0] + n[(2, 1)] * u[1];
    let nd = base_block_dot(drive, inputs, theta, theta_dot);
    let mut out = j_dot_qdot.clone();
    for c in 0..3 {
        let qdd = nd[(c, 0)] * u[0] + nd[(c, 1)] * u[1];
        for r in 0..rows {
            out[r] += frame_jacobian[(r, c)] * qdd;
        }
    }
    Ok(out)
}

/// Exact motion of the platform under constant inputs for unit time: the base pose
/// `[x, y, θ]` after the axle midpoint moves along an arc with forward displacement
/// `s` (m) and heading change `α` (rad). Used to integrate whole-body increments so
/// every iterate satisfies the no-side-slip constraint.
pub fn integrate_base(drive: &DiffDrive, pose: [f64; 3], s: f64, alpha: f64) -> [f64; 3] {
    let [x, y, th] = pose;
    let d = drive.d;
    // Axle midpoint.
    let (s0, c0) = th.sin_cos();
    let (px, py) = (x - d * c0, y - d * s0);
    let th1 = th + alpha;
    let (s1, c1) = th1.sin_cos();
    // Displacement of P0 along the arc: ∫ s·e(θ + α t) dt for t ∈ [0, 1].
    let (dx, dy) = if alpha.abs() < 1e-6 {
        // Series of the exact form (accurate to O(α³)).
        let mid = th + 0.5 * alpha;
        let f = 1.0 - alpha * alpha / 24.0;
        (s * f * mid.cos(), s * f * mid.sin())
    } else {
        (s * (s1 - s0) / alpha, s * (c0 - c1) / alpha)
    };
    let (px1, py1) = (px + dx, py + dy);
    [px1 + d * c1, py1 + d * s1, th1]
}

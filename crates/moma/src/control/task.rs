//! Task-space laws on a task-space model `Λ ẍ + μ_x ẋ + p = F` (sections 5.4–5.5 of the
//! chapter, corrected as in the project's chapter-model notes, m5):
//!
//! * [`pd_plus`] — the chapter's law (5.122) in corrected form, PD+ (Paden & Panja 1988):
//!   `F = Λ ẍ_d + C_x ẋ_d + p − K_d ė − K_p e` with `e = x − x_d` and `C_x` evaluated at the
//!   actual state. The closed loop is `Λ ë + (C_x + K_d) ė + K_p e = 0`; with
//!   `W = ½ ėᵀ Λ ė + ½ eᵀ K_p e`, `Ẇ = −ėᵀ K_d ė` **provided `Λ̇ − 2 C_x` is skew** (C_x from
//!   the Christoffel symbols). The chapter's `Ẇ` drops `½ ėᵀ Λ̇ ė` and asks for
//!   "K_d + BV positive definite"; the correct condition is K_p, K_d ≻ 0 and a
//!   skew-consistent C_x. (`closed_form::m5_mobile_manipulator::TaskController` is this
//!   law on m5, with Λ = Hx = A⁻ᵀ Mr A⁻¹ the congruence, not the chapter's similarity.)
//! * [`computed_torque`] — task-space inverse dynamics
//!   `F = Λ (ẍ_d + K_v ė_d + K_p e_d) + C_x ẋ + p` with `e_d = x_d − x`: the error obeys
//!   `ë_d + K_v ė_d + K_p e_d = 0` exactly with the exact model.
//! * [`decoupled`] — the chapter's decoupled control (5.129–5.133) on a two-block split
//!   `x = (x₁ platform, x₂ arm)`. Each block runs computed torque with its own diagonal
//!   blocks of Λ and C_x; the cross terms `Λ₁₂ ẍ₂ + C₁₂ ẋ₂` (and vice versa) are the
//!   chapter's "auxiliary inputs". They need the *other block's acceleration*, an algebraic
//!   loop in the print. [`Coupling::Naive`] drops them (the chapter's decoupling claim
//!   taken literally: the error of each block is then driven by the other's motion);
//!   [`Coupling::DesiredAcceleration`] feeds the other block's desired acceleration
//!   forward (exact only when tracking is perfect); [`Coupling::Compensated`] uses the
//!   other block's *commanded* acceleration `ẍ* = ẍ_d + K_v ė_d + K_p e_d`, which resolves
//!   the loop exactly: the sum equals full computed torque, so each block's error obeys
//!   its own linear equation.
//!
//! All laws are on fixed-size nalgebra matrices (`N` task rows).

use nalgebra::{SMatrix, SVector};

/// PD+ task force `F = Λ ẍ_d + C_x ẋ_d + p − K_d ė − K_p e` (`e = x − x_d`,
/// `ė = ẋ − ẋ_d`), and `W = ½ ėᵀ Λ ė + ½ eᵀ K_p e`.
#[allow(clippy::too_many_arguments)]
#[must_use]
pub fn pd_plus<const N: usize>(
    lambda: &SMatrix<f64, N, N>,
    cx: &SMatrix<f64, N, N>,
    p: &SVector<f64, N>,
    e: &SVector<f64, N>,
    edot: &SVector<f64, N>,
    xdot_d: &SVector<f64, N>,
    xddot_d: &SVector<f64, N>,
    kp: &SMatrix<f64, N, N>,
    kd: &SMatrix<f64, N, N>,
) -> (SVector<f64, N>, f64) {
    let f = lambda * xddot_d + cx * xdot_d + p - kd * edot - kp * e;
    let w = 0.5 * edot.dot(&(lambda * edot)) + 0.5 * e.dot(&(kp * e));
    (f, w)
}

/// Task-space computed torque `F = Λ (ẍ_d + K_v ė_d + K_p e_d) + C_x ẋ + p`
/// (`e_d = x_d − x`, `ė_d = ẋ_d − ẋ`); `mu` is `C_x ẋ` (or any task-space velocity term).
#[allow(clippy::too_many_arguments)]
#[must_use]
pub fn computed_torque<const N: usize>(
    lambda: &SMatrix<f64, N, N>,
    mu: &SVector<f64, N>,
    p: &SVector<f64, N>,
    e_d: &SVector<f64, N>,
    edot_d: &SVector<f64, N>,
    xddot_d: &SVector<f64, N>,
    kp: &SMatrix<f64, N, N>,
    kv: &SMatrix<f64, N, N>,
) -> SVector<f64, N> {
    lambda * (xddot_d + kv * edot_d + kp * e_d) + mu + p
}

/// How [`decoupled`] treats the cross-block terms.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Coupling {
    /// Drop `Λ₁₂ ẍ₂ + C₁₂ ẋ₂` and `Λ₂₁ ẍ₁ + C₂₁ ẋ₁`.
    Naive,
    /// Use the other block's desired acceleration `ẍ_d` (feed-forward).
    DesiredAcceleration,
    /// Use the other block's commanded acceleration `ẍ*` (exact decoupling).
    Compensated,
}

/// The chapter's decoupled control on the split of the first `A` task rows (platform)
/// and the remaining `N − A` rows (arm): `F_i = Λ_ii ẍ*_i + C_ii ẋ_i + p_i + U_i` with
/// `ẍ* = ẍ_d + K_v ė_d + K_p e_d`, `U_i` the cross terms per [`Coupling`]. `kp`, `kv` are
/// block-diagonal gains (their off-diagonal blocks are ignored). Returns F.
///
/// # Panics
/// If `A > N`.
#[allow(clippy::too_many_arguments)]
#[must_use]
pub fn decoupled<const N: usize, const A: usize>(
    lambda: &SMatrix<f64, N, N>,
    cx: &SMatrix<f64, N, N>,
    p: &SVector<f64, N>,
    xdot: &SVector<f64, N>,
    e_d: &SVector<f64, N>,
    edot_d: &SVector<f64, N>,
    xddot_d: &SVector<f64, N>,
    kp: &SMatrix<f64, N, N>,
    kv: &SMatrix<f64, N, N>,
    coupling: Coupling,
) -> SVector<f64, N> {
    assert!(A <= N, "platform block larger than the task");
    let in_block = |i: usize, j: usize| (i < A) == (j < A);
    let mut kp_b = *kp;
    let mut kv_b = *kv;
    for i in 0..N {
        for j in 0..N {
            if !in_block(i, j) {
                kp_b[(i, j)] = 0.0;
                kv_b[(i, j)] = 0.0;
            }
        }
    }
    let cmd = xddot_d + kv_b * edot_d + kp_b * e_d;
    let mut f = *p;
    for i in 0..N {
        for j in 0..N {
            if in_block(i, j) {
                f[i] += lambda[(i, j)] * cmd[j] + cx[(i, j)] * xdot[j];
            } else {
                match coupling {
                    Coupling::Naive => {}
                    Coupling::DesiredAcceleration => {
                        f[i] += lambda[(i, j)] * xddot_d[j] + cx[(i, j)] * xdot[j];
                    }
                    Coupling::Compensated => {
                        f[i] += lambda[(i, j)] * cmd[j] + cx[(i, j)] * xdot[j];
                    }
                }
            }
        }
    }
    f
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Matrix3, Vector3};

    #[test]
    fn compensated_decoupling_equals_full_computed_torque() {
        let lambda = Matrix3::new(2.0, 0.3, 0.2, 0.3, 1.5, 0.1, 0.2, 0.1, 1.0);
        let cx = Matrix3::new(0.1, -0.2, 0.3, 0.4, 0.0, -0.1, 0.2, 0.5, 0.05);
        let p = Vector3::new(0.0, 0.1, 9.0);
        let xdot = Vector3::new(0.2, -0.1, 0.3);
        let (e, ed, xdd) = (
            Vector3::new(0.1, -0.2, 0.05),
            Vector3::new(0.0, 0.3, -0.1),
            Vector3::new(0.5, 0.0, -1.0),
        );
        let kp = Matrix3::from_diagonal(&Vector3::new(25.0, 16.0, 9.0));
        let kv = Matrix3::from_diagonal(&Vector3::new(10.0, 8.0, 6.0));
        let full = computed_torque(&lambda, &(cx * xdot), &p, &e, &ed, &xdd, &kp, &kv);
        let dec = decoupled::<3, 1>(
            &lambda,
            &cx,
            &p,
            &xdot,
            &e,
            &ed,
            &xdd,
            &kp,
            &kv,
            Coupling::Compensated,
        );
        assert!((full - dec).norm() < 1e-13);
        let naive = decoupled::<3, 1>(
            &lambda,
            &cx,
            &p,
            &xdot,
            &e,
            &ed,
            &xdd,
            &kp,
            &kv,
            Coupling::Naive,
        );
        assert!((full - naive).norm() > 1e-2);
    }

    /// The feed-forward of the other block's desired acceleration is exact when that
    /// block tracks perfectly: at zero error it equals full computed torque; with an error
    /// in the platform block only, the platform rows (fed the arm's exact commanded
    /// acceleration, which is its desired one) still equal full computed torque and the
    /// arm rows (fed the platform's desired instead of its commanded acceleration) do not.
    #[test]
    fn desired_acceleration_feed_forward_is_exact_only_for_a_perfectly_tracking_block() {
        let lambda = Matrix3::new(2.0, 0.3, 0.2, 0.3, 1.5, 0.1, 0.2, 0.1, 1.0);
        let cx = Matrix3::new(0.1, -0.2, 0.3, 0.4, 0.0, -0.1, 0.2, 0.5, 0.05);
        let p = Vector3::new(0.0, 0.1, 9.0);
        let xdot = Vector3::new(0.2, -0.1, 0.3);
        let xdd = Vector3::new(0.5, 0.0, -1.0);
        let kp = Matrix3::from_diagonal(&Vector3::new(25.0, 16.0, 9.0));
        let kv = Matrix3::from_diagonal(&Vector3::new(10.0, 8.0, 6.0));
        let law = |e: &Vector3<f64>, ed: &Vector3<f64>| {
            let full = computed_torque(&lambda, &(cx * xdot), &p, e, ed, &xdd, &kp, &kv);
            let ff = decoupled::<3, 1>(
                &lambda,
                &cx,
                &p,
                &xdot,
                e,
                ed,
                &xdd,
                &kp,
                &kv,
                Coupling::DesiredAcceleration,
            );
            (full, ff)
        };
        let (full, ff) = law(&Vector3::zeros(), &Vector3::zeros());
        assert!((full - ff).norm() < 1e-13, "{full} vs {ff}");
        // platform (row 0) error only
        let (full, ff) = law(&Vector3::new(0.1, 0.0, 0.0), &Vector3::new(-0.2, 0.0, 0.0));
        assert!((full[0] - ff[0]).abs() < 1e-13, "{full} vs {ff}");
        for arm_row in 1..3 {
            assert!((full[arm_row] - ff[arm_row]).abs() > 1e-2, "{full} vs {ff}");
        }
    }
}

//! The configuration manifold: neutral, integrate, difference, random configurations.

use crate::multibody::{JointType, Model};
use crate::spatial::{Motion, exp6, log6};
use nalgebra::{DVector, Quaternion, UnitQuaternion, Vector3};
use rand::Rng;
use std::f64::consts::PI;

/// The neutral configuration is defined with the model (`Data::new` needs it, and
/// `multibody` sits below `kinematics`); it is re-exported here beside its siblings.
#[doc(no_inline)]
pub use crate::multibody::neutral;

fn ff_parts(q: &[f64]) -> (Vector3<f64>, UnitQuaternion<f64>) {
    (
        Vector3::new(q[0], q[1], q[2]),
        UnitQuaternion::from_quaternion(Quaternion::new(q[6], q[3], q[4], q[5])),
    )
}

fn ff_write(out: &mut [f64], p: &Vector3<f64>, r: &UnitQuaternion<f64>) {
    out[..3].copy_from_slice(p.as_slice());
    let c = r.as_ref().coords; // [x, y, z, w]
    out[3..7].copy_from_slice(c.as_slice());
}

/// `q ⊕ v`: the configuration reached from q (nq) by following the constant velocity v
/// (nv) for one unit of time, written into `out` (nq).
///
/// Revolute, prismatic and planar coordinates add (the planar velocity is in world axes);
/// a free-flyer moves by `world_from_base · exp6(v)` (base-frame twist, as Pinocchio).
///
/// # Panics
/// On wrong vector lengths.
pub fn integrate(model: &Model, q: &DVector<f64>, v: &DVector<f64>, out: &mut DVector<f64>) {
    assert_eq!(q.len(), model.nq, "q length");
    assert_eq!(v.len(), model.nv, "v length");
    assert_eq!(out.len(), model.nq, "out length");
    for i in 1..model.njoints {
        let (iq, iv) = (model.idx_q[i], model.idx_v[i]);
        match model.joint_types[i] {
            JointType::FreeFlyer => {
                let (p, r) = ff_parts(&q.as_slice()[iq..iq + 7]);
                let d = exp6(&Motion::new(
                    Vector3::new(v[iv], v[iv + 1], v[iv + 2]),
                    Vector3::new(v[iv + 3], v[iv + 4], v[iv + 5]),
                ));
                let p1 = p + r * d.translation;
                let dq = UnitQuaternion::from_rotation_matrix(
                    &nalgebra::Rotation3::from_matrix_unchecked(d.rotation),
                );
                let mut r1 = r * dq;
                // keep the sign of w stable (same hemisphere as the input)
                if r1.as_ref().coords.dot(&r.as_ref().coords) < 0.0 {
                    r1 = UnitQuaternion::new_unchecked(-r1.into_inner());
                }
                ff_write(&mut out.as_mut_slice()[iq..iq + 7], &p1, &r1);
            }
            _ => {
                for k in 0..model.nqs[i] {
                    out[iq + k] = q[iq + k] + v[iv + k];
                }
            }
        }
    }
}

/// `q1 ⊖ q0`: the velocity v (nv) with `integrate(q0, v) = q1`, written into `out`.
///
/// Angles that wrap take the shortest way, in `[−π, π)`: a continuous joint (a revolute
/// joint whose position range is unbounded on both sides, as the URDF loader makes
/// `continuous` joints) and the heading θ of a planar root. Only the angle wraps for a
/// planar root: its velocity is in world axes, so `x` and `y` subtract (Pinocchio's planar
/// difference is an SE(2) log in the local frame instead). Bounded revolute and prismatic
/// coordinates subtract; a free-flyer takes `log6(M₀⁻¹ M₁)` (base-frame twist).
///
/// # Panics
/// On wrong vector lengths.
pub fn difference(model: &Model, q0: &DVector<f64>, q1: &DVector<f64>, out: &mut DVector<f64>) {
    assert_eq!(q0.len(), model.nq, "q0 length");
    assert_eq!(q1.len(), model.nq, "q1 length");
    assert_eq!(out.len(), model.nv, "out length");
    for i in 1..model.njoints {
        let (iq, iv) = (model.idx_q[i], model.idx_v[i]);
        match model.joint_types[i] {
            JointType::FreeFlyer => {
                let m0 = crate::multibody::free_flyer_transform(&q0.as_slice()[iq..iq + 7]);
                let m1 = crate::multibody::free_flyer_transform(&q1.as_slice()[iq..iq + 7]);
                let d = log6(&m0.inverse_compose(&m1));
                for k in 0..3 {
                    out[iv + k] = d.linear[k];
                    out[iv + 3 + k] = d.angular[k];
                }
            }
            JointType::Planar => {
                out[iv] = q1[iq] - q0[iq];
                out[iv + 1] = q1[iq + 1] - q0[iq + 1];
                out[iv + 2] = wrap_angle(q1[iq + 2] - q0[iq + 2]);
            }
            jt if jt.is_revolute() && is_continuous(model, iq) => {
                out[iv] = wrap_angle(q1[iq] - q0[iq]);
            }
            _ => {
                for k in 0..model.nvs[i] {
                    out[iv + k] = q1[iq + k] - q0[iq + k];
                }
            }
        }
    }
}

/// True when the revolute coordinate `iq` has no position limit on either side (a
/// continuous joint: its angle wraps).
fn is_continuous(model: &Model, iq: usize) -> bool {
    model.lower_position_limit[iq] == f64::NEG_INFINITY
        && model.upper_position_limit[iq] == f64::INFINITY
}

/// `a` moved by a multiple of 2π into `[−π, π)`.
#[must_use]
pub fn wrap_angle(a: f64) -> f64 {
    let w = (a + PI).rem_euclid(2.0 * PI) - PI;
    // rem_euclid can round up to exactly 2π for tiny negative inputs
    if w >= PI { w - 2.0 * PI } else { w }
}

/// Normalises the free-flyer quaternions of q in place.
pub fn normalize(model: &Model, q: &mut DVector<f64>) {
    for i in 1..model.njoints {
        if matches!(model.joint_types[i], JointType::FreeFlyer) {
            let iq = model.idx_q[i];
            let n = q.rows(iq + 3, 4).norm();
            if n > 0.0 {
                for k in 3..7 {
                    q[iq + k] /= n;
                }
            }
        }
    }
}

fn sample(
    rng: &mut (impl Rng + ?Sized),
    lo: f64,
    hi: f64,
    default_lo: f64,
    default_hi: f64,
) -> f64 {
    let (a, b) = if lo.is_finite() && hi.is_finite() {
        (lo, hi)
    } else if lo.is_finite() {
        (lo, lo + (default_hi - default_lo))
    } else if hi.is_finite() {
        (hi - (default_hi - default_lo), hi)
    } else {
        (default_lo, default_hi)
    };
    if b > a { rng.random_range(a..=b) } else { a }
}

/// A random configuration (nq), uniform within the position limits. Where a limit is
/// infinite: angles in [−π, π], translations (prismatic, planar x, y, free-flyer position)
/// in [−1, 1] m; free-flyer orientations are uniform over SO(3). Allocates.
///
/// Seed the generator (e.g. `rand_chacha::ChaCha8Rng::seed_from_u64`) for reproducibility.
pub fn random_configuration(model: &Model, rng: &mut (impl Rng + ?Sized)) -> DVector<f64> {
    let mut q = neutral(model);
    let lo = &model.lower_position_limit;
    let hi = &model.upper_position_limit;
    for i in 1..model.njoints {
        let iq = model.idx_q[i];
        match model.joint_types[i] {
            JointType::FreeFlyer => {
                for k in 0..3 {
                    q[iq + k] = sample(rng, lo[iq + k], hi[iq + k], -1.0, 1.0);
                }
                let (u1, u2, u3): (f64, f64, f64) = (rng.random(), rng.random(), rng.random());
                let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
                q[iq + 3] = a * (2.0 * PI * u2).sin();
                q[iq + 4] = a * (2.0 * PI * u2).cos();
                q[iq + 5] = b * (2.0 * PI * u3).sin();
                q[iq + 6] = b * (2.0 * PI * u3).cos();
            }
            JointType::Planar => {
                q[iq] = sample(rng, lo[iq], hi[iq], -1.0, 1.0);
                q[iq + 1] = sample(rng, lo[iq + 1], hi[iq + 1], -1.0, 1.0);
                q[iq + 2] = sample(rng, lo[iq + 2], hi[iq + 2], -PI, PI);
            }
            jt if jt.is_revolute() => q[iq] = sample(rng, lo[iq], hi[iq], -PI, PI),
            _ => q[iq] = sample(rng, lo[iq], hi[iq], -1.0, 1.0),
        }
    }
    q
}

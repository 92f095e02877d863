//! Recursive Newton–Euler algorithm and its special cases.

use crate::kinematics::{assert_nv, assert_sizes, update_joint_placement};
use crate::multibody::{Data, Model};
use crate::spatial::Motion;
use nalgebra::DVector;

/// RNEA core: writes τ = H(q)a + C(q,v)v + g(q) into `data.tau`; `None` velocity or
/// acceleration means zero; `with_gravity = false` drops g.
pub(crate) fn rnea_impl(
    model: &Model,
    data: &mut Data,
    qs: &[f64],
    vs: Option<&[f64]>,
    as_: Option<&[f64]>,
    with_gravity: bool,
) {
    data.v[0] = Motion::zero();
    data.a[0] = if with_gravity {
        Motion::new(-model.gravity, nalgebra::Vector3::zeros())
    } else {
        Motion::zero()
    };
    for i in 1..model.njoints {
        update_joint_placement(model, data, i, qs);
        let jt = &model.joint_types[i];
        let p = model.parents[i].0;
        let (iq, iv) = (model.idx_q[i], model.idx_v[i]);
        let (nqi, nvi) = (model.nqs[i], model.nvs[i]);
        let qi = &qs[iq..iq + nqi];
        let m = data.parent_from_joint[i];
        let slot = jt.axis_slot();
        let mut acc = m.inverse_act_motion(&data.a[p]);
        if let Some(a) = as_ {
            match slot {
                Some(k) => add_to_slot(&mut acc, k, a[iv]),
                None => acc += jt.motion(qi, &a[iv..iv + nvi]),
            }
        }
        let inertia = &model.inertias[i];
        if let Some(v) = vs {
            let vi = &v[iv..iv + nvi];
            let mut vel = m.inverse_act_motion(&data.v[p]);
            match slot {
                Some(k) => {
                    add_to_slot(&mut vel, k, vi[0]);
                    acc += cross_slot(&vel, k, vi[0]);
                }
                None => {
                    let vj = jt.motion(qi, vi);
                    vel += vj;
                    acc += vel.cross_motion(&vj);
                }
            }
            if jt.has_bias() {
                acc += jt.bias(qi, vi);
            }
            data.v[i] = vel;
            data.f[i] = inertia.mul_motion(&acc) + vel.cross_force(&inertia.mul_motion(&vel));
        } else {
            data.v[i] = Motion::zero();
            data.f[i] = inertia.mul_motion(&acc);
        }
        data.a[i] = acc;
    }
    for i in (1..model.njoints).rev() {
        let jt = &model.joint_types[i];
        let (iq, iv) = (model.idx_q[i], model.idx_v[i]);
        let nvi = model.nvs[i];
        let fi = data.f[i];
        if nvi == 1 {
            data.tau[iv] = jt.project_force_1dof(&fi);
        } else {
            jt.project_force(
                &qs[iq..iq + model.nqs[i]],
                &fi,
                &mut data.tau.as_mut_slice()[iv..iv + nvi],
            );
        }
        let p = model.parents[i].0;
        if p > 0 {
            let fp = data.parent_from_joint[i].act_force(&fi);
            data.f[p] += fp;
        }
    }
}

/// `m += x·e_k`.
#[inline]
fn add_to_slot(m: &mut Motion, k: usize, x: f64) {
    if k < 3 {
        m.linear[k] += x;
    } else {
        m.angular[k - 3] += x;
    }
}

/// `a × (w·e_j)` for a 3-vector `a` and axis `j`, without the products by zero.
#[inline]
fn cross_axis(a: &nalgebra::Vector3<f64>, j: usize, w: f64) -> nalgebra::Vector3<f64> {
    match j {
        0 => nalgebra::Vector3::new(0.0, a.z * w, -(a.y * w)),
        1 => nalgebra::Vector3::new(-(a.z * w), 0.0, a.x * w),
        _ => nalgebra::Vector3::new(a.y * w, -(a.x * w), 0.0),
    }
}

/// `vel × (w·e_k)` (`Motion::cross_motion` with the joint twist of axis slot `k`).
#[inline]
fn cross_slot(vel: &Motion, k: usize, w: f64) -> Motion {
    if k < 3 {
        // [ω × w e_k; 0]
        Motion::new(cross_axis(&vel.angular, k, w), nalgebra::Vector3::zeros())
    } else {
        // [v × w e_k; ω × w e_k]
        Motion::new(
            cross_axis(&vel.linear, k - 3, w),
            cross_axis(&vel.angular, k - 3, w),
        )
    }
}

/// Inverse dynamics by the recursive Newton–Euler algorithm:
/// τ = H(q)·a + C(q, v)·v + g(q) (nv), returned and stored in `data.tau`.
///
/// Also fills `data.parent_from_joint`, body twists `data.v`, accelerations `data.a`
/// (joint frames, including the fictitious −gravity) and `data.f` (force transmitted
/// through each joint, joint frame).
///
/// # Panics
/// If q, v, a have the wrong length or `data` was not made for `model`.
///
/// # References
/// R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, §5.3,
/// doi:10.1007/978-1-4899-7560-7.
#[doc(alias = "inverse_dynamics")]
pub fn rnea<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    a: &DVector<f64>,
) -> &'d DVector<f64> {
    assert_sizes(model, data, q);
    assert_nv(model, v, "v");
    assert_nv(model, a, "a");
    rnea_impl(
        model,
        data,
        q.as_slice(),
        Some(v.as_slice()),
        Some(a.as_slice()),
        true,
    );
    &data.tau
}

/// Nonlinear effects h(q, v) = C(q, v)·v + g(q) (nv): RNEA with a = 0, stored in
/// `data.nle` (and `data.tau`).
///
/// # Panics
/// On wrong vector lengths.
#[doc(alias = "bias_forces")]
#[doc(alias = "h")]
pub fn nonlinear_effects<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
) -> &'d DVector<f64> {
    assert_sizes(model, data, q);
    assert_nv(model, v, "v");
    rnea_impl(model, data, q.as_slice(), Some(v.as_slice()), None, true);
    data.nle.copy_from(&data.tau);
    &data.nle
}

/// Generalised gravity g(q) (nv): RNEA with v = a = 0, stored in `data.gravity_torque`
/// (and `data.tau`).
///
/// # Panics
/// On wrong vector lengths.
#[doc(alias = "G")]
#[doc(alias = "gravity_forces")]
pub fn gravity_torque<'d>(model: &Model, data: &'d mut Data, q: &DVector<f64>) -> &'d DVector<f64> {
    assert_sizes(model, data, q);
    rnea_impl(model, data, q.as_slice(), None, None, true);
    data.gravity_torque.copy_from(&data.tau);
    &data.gravity_torque
}

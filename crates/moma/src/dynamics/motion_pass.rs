//! The kinematic forward pass shared by the analytical derivatives of the dynamics
//! ([`super::derivatives`]) and of frame motion ([`super::frame_derivatives`]): every
//! joint's world placement, twist and acceleration, and per velocity coordinate its world
//! motion-subspace column and the 6-vectors the derivatives are built from.
//!
//! The pass runs with a constant joint-frame motion subspace for every joint (Pinocchio's
//! planar joint, base-frame velocity), so perturbing coordinate `k` of joint `j` moves the
//! joint frame of `j` and everything below it rigidly by the world twist `J_k`. With `λ`
//! the parent joint of `j`: `w_k = v_λ × J_k` (the intrinsic change of every twist below),
//! `u_k = a_λ × J_k + v_λ × w_k` (of every acceleration below, beside the rotation) and
//! `(v_λ + v_j) × J_k` (∂ of the accelerations below with respect to the velocity `v_k`,
//! beside `J_k × ·`).

use crate::kinematics::update_joint_placement;
use crate::multibody::{Data, JointType, Model};
use crate::spatial::SE3;
use nalgebra::{Vector3, Vector6};

/// The per-joint and per-dof results of the pass (world frame), sized once for a model.
#[derive(Clone, Debug)]
pub(super) struct MotionTerms {
    /// Per joint: placement, twist, acceleration (with the root's acceleration given to
    /// [`MotionTerms::step`], −g for the dynamics, 0 for kinematics).
    pub(super) world_from_joint: Vec<SE3>,
    pub(super) vel: Vec<Vector6<f64>>,
    pub(super) acc: Vec<Vector6<f64>>,
    /// Per dof: world motion-subspace column J, w = v_λ × J, u = a_λ × J + v_λ × w and
    /// (v_λ + v_j) × J.
    pub(super) jac: Vec<Vector6<f64>>,
    pub(super) w: Vec<Vector6<f64>>,
    pub(super) u: Vec<Vector6<f64>>,
    pub(super) dadv: Vec<Vector6<f64>>,
}

impl MotionTerms {
    pub(super) fn new(model: &Model) -> Self {
        let (n, nv) = (model.njoints, model.nv);
        Self {
            world_from_joint: vec![SE3::identity(); n],
            vel: vec![Vector6::zeros(); n],
            acc: vec![Vector6::zeros(); n],
            jac: vec![Vector6::zeros(); nv],
            w: vec![Vector6::zeros(); nv],
            u: vec![Vector6::zeros(); nv],
            dadv: vec![Vector6::zeros(); nv],
        }
    }

    /// Joint `i` (its parent done): placement from `qs`, twist and acceleration from the
    /// pass-convention `v_local`, `a_local`, and its dofs' vectors. `root_acc` is the
    /// acceleration of the fixed world.
    #[inline]
    #[allow(clippy::too_many_arguments)]
    pub(super) fn step(
        &mut self,
        model: &Model,
        data: &mut Data,
        i: usize,
        qs: &[f64],
        v_local: &[f64],
        a_local: &[f64],
        root_acc: &Vector6<f64>,
    ) {
        update_joint_placement(model, data, i, qs);
        let p = model.parents[i].0;
        let local = data.parent_from_joint[i];
        let (omi, v_parent, a_parent) = if p == 0 {
            (local, Vector6::zeros(), *root_acc)
        } else {
            (
                self.world_from_joint[p].compose(&local),
                self.vel[p],
                self.acc[p],
            )
        };
        let jt = &model.joint_types[i];
        let iv = model.idx_v[i];
        let mut vel = v_parent;
        let mut acc = a_parent;
        for k in iv..iv + model.nvs[i] {
            let jk = act_motion(&omi, &local_column(jt, k - iv));
            self.jac[k] = jk;
            vel += jk * v_local[k];
            acc += jk * a_local[k];
        }
        acc += cross_motion(&vel, &(vel - v_parent));
        let v_sum = v_parent + vel;
        for k in iv..iv + model.nvs[i] {
            let jk = self.jac[k];
            let w = cross_motion(&v_parent, &jk);
            self.u[k] = cross_motion(&a_parent, &jk) + cross_motion(&v_parent, &w);
            self.w[k] = w;
            self.dadv[k] = cross_motion(&v_sum, &jk);
        }
        self.world_from_joint[i] = omi;
        self.vel[i] = vel;
        self.acc[i] = acc;
    }
}

/// Column `k` of joint `i`'s motion subspace in its own frame, constant for every kind
/// (the planar joint's in its base-frame velocity convention).
#[inline]
fn local_column(jt: &JointType, k: usize) -> Vector6<f64> {
    match jt {
        JointType::Planar => {
            let mut s = Vector6::zeros();
            s[[0, 1, 5][k]] = 1.0;
            s
        }
        JointType::FreeFlyer => {
            let mut s = Vector6::zeros();
            s[k] = 1.0;
            s
        }
        JointType::RevoluteUnaligned { axis } => {
            Vector6::new(0.0, 0.0, 0.0, axis.x, axis.y, axis.z)
        }
        JointType::PrismaticUnaligned { axis } => {
            Vector6::new(axis.x, axis.y, axis.z, 0.0, 0.0, 0.0)
        }
        aligned => {
            let mut s = Vector6::zeros();
            s[aligned.axis_slot().expect("aligned joint")] = 1.0;
            s
        }
    }
}

#[inline]
pub(super) fn split(x: &Vector6<f64>) -> (Vector3<f64>, Vector3<f64>) {
    (
        Vector3::new(x[0], x[1], x[2]),
        Vector3::new(x[3], x[4], x[5]),
    )
}

#[inline]
pub(super) fn join(l: Vector3<f64>, a: Vector3<f64>) -> Vector6<f64> {
    Vector6::new(l.x, l.y, l.z, a.x, a.y, a.z)
}

/// `m` moved by `x` into its parent frame (`X m`).
#[inline]
pub(super) fn act_motion(x: &SE3, m: &Vector6<f64>) -> Vector6<f64> {
    let (l, a) = split(m);
    let ra = x.rotation * a;
    join(x.rotation * l + x.translation.cross(&ra), ra)
}

/// `m` moved by `x⁻¹` (`X⁻¹ m`).
#[inline]
pub(super) fn inverse_act_motion(x: &SE3, m: &Vector6<f64>) -> Vector6<f64> {
    let (l, a) = split(m);
    join(
        x.rotation.tr_mul(&(l - x.translation.cross(&a))),
        x.rotation.tr_mul(&a),
    )
}

/// `v × m` (motion cross product, `[ω × m_l + v_l × m_ω; ω × m_ω]`).
#[inline]
pub(super) fn cross_motion(v: &Vector6<f64>, m: &Vector6<f64>) -> Vector6<f64> {
    let ((vl, va), (ml, ma)) = (split(v), split(m));
    join(va.cross(&ml) + vl.cross(&ma), va.cross(&ma))
}

/// `v ×* f` (force cross product, `[ω × f_l; v_l × f_l + ω × f_ω]`).
#[inline]
pub(super) fn cross_force(v: &Vector6<f64>, f: &Vector6<f64>) -> Vector6<f64> {
    let ((vl, va), (fl, fa)) = (split(v), split(f));
    join(va.cross(&fl), vl.cross(&fl) + va.cross(&fa))
}

//! Analytical derivatives of a frame's placement, velocity and acceleration with respect
//! to q, v and a: what Pinocchio's `computeForwardKinematicsDerivatives` followed by
//! `getFrameJacobian`, `getFrameVelocityDerivatives` and
//! `getFrameAccelerationDerivatives` compute, in the same three reference frames.
//!
//! [`forward_kinematics_derivatives`] runs one pass over the tree at `(q, v, a)`; then
//! [`frame_velocity_derivatives`] and [`frame_acceleration_derivatives`] read any frame's
//! derivatives from it (6 × nv each, rows linear then angular, entry `(r, j)` =
//! ∂out_r/∂in_j), and [`frame_motion`] its placement, velocity and acceleration. Nothing
//! allocates after [`FrameDerivativeData::new`].
//!
//! # What is differentiated
//!
//! The frame's twist `V` and spatial acceleration `A` (its time derivative, the classical
//! acceleration of the frame origin being `A_lin + ω × V_lin` in the frame's axes),
//! expressed as [`ReferenceFrame`] says:
//!
//! * `World`: the spatial twist (velocity of the body point at the world origin), world
//!   axes;
//! * `Local`: velocity of the frame origin and angular velocity, frame axes;
//! * `LocalWorldAligned`: the same vectors in world axes.
//!
//! q is perturbed along the tangent `q ⊕ δq` ([`crate::kinematics::integrate`]; moma's
//! layout: a planar root's velocity in world axes). ∂V/∂v = ∂A/∂a = the frame Jacobian
//! `J` of [`crate::kinematics::frame_jacobian`] in the same frame, which is also the
//! placement's derivative: `M(q ⊕ δq) = M exp(J δq)` to first order for `Local`,
//! `exp(J δq) M` for `World`, and for `LocalWorldAligned` `δp = J_lin δq` and
//! `δR = (J_ang δq)× R`.
//!
//! For `World` and `Local` every matrix is the derivative of the quantity. For
//! `LocalWorldAligned` the ∂/∂q matrices are, as Pinocchio defines them, the derivatives
//! of the world quantities moved to the frame origin with world axes (the frame's own
//! displacement is not differentiated): the derivative of `V` itself adds
//! `ω × J_lin` (ω the frame's angular velocity) to the linear rows of ∂V/∂q, and that of
//! `A` adds `α × J_lin` (α = `A_ang`) to those of ∂A/∂q.
//!
//! # The formulas
//!
//! With the world columns `J_m` and the vectors `w_m`, `u_m`, `(v_λ + v_j) × J_m` of the
//! kinematic pass ([`super::motion_pass`]), and `V`, `A` the world twist and acceleration
//! of the frame's joint, for every coordinate `m` that supports the frame:
//!
//! * `∂V/∂q_m = J_m × V + w_m`, `∂V/∂v_m = J_m`;
//! * `∂A/∂q_m = J_m × A + w_m × V + u_m`, `∂A/∂v_m = (v_λ + v_j) × J_m + J_m × V`,
//!   `∂A/∂a_m = J_m`.
//!
//! `J_m × ·` is the rigid rotation of a world vector by the perturbation; it cancels in the
//! frame's `Local` expression (which moves with it), leaving `X⁻¹ (∂V/∂q_m − J_m × V)`
//! with `X` the frame's world placement; `LocalWorldAligned` keeps the world derivative
//! and moves it to the frame origin. The pass runs with Pinocchio's planar joint
//! (base-frame velocity); a planar root is brought to moma's layout by the chain rule of
//! [`PinocchioLayout::frame_velocity_derivatives_from_pinocchio`] and
//! [`PinocchioLayout::frame_acceleration_derivatives_from_pinocchio`].
//!
//! # References
//! J. Carpentier, N. Mansard, "Analytical Derivatives of Rigid Body Dynamics Algorithms",
//! Robotics: Science and Systems, 2018, doi:10.15607/RSS.2018.XIV.038.

use super::motion_pass::{MotionTerms, cross_motion, inverse_act_motion, join, split};
use crate::io::pinocchio_layout::PinocchioLayout;
use crate::kinematics::{ReferenceFrame, assert_nv};
use crate::multibody::{Data, FrameIndex, Model};
use crate::spatial::{Motion, SE3};
use nalgebra::{DVector, Matrix6xX, Vector3, Vector6};

/// The workspace of the frame derivatives: the kinematic pass of
/// [`forward_kinematics_derivatives`] at one state, sized once for a model by
/// [`FrameDerivativeData::new`].
#[derive(Clone, Debug)]
pub struct FrameDerivativeData {
    data: Data,
    layout: PinocchioLayout,
    /// The pass (world frame, no gravity).
    motion: MotionTerms,
    /// Velocity and acceleration in the pass's convention (planar: base frame).
    v_local: DVector<f64>,
    a_local: DVector<f64>,
    /// The state of the last pass, moma's layout (for the planar root's chain rule).
    q: DVector<f64>,
    v: DVector<f64>,
    a: DVector<f64>,
}

impl FrameDerivativeData {
    /// Allocates every buffer for `model`.
    #[must_use]
    pub fn new(model: &Model) -> Self {
        let nv = model.nv;
        Self {
            data: Data::new(model),
            layout: PinocchioLayout::new(model),
            motion: MotionTerms::new(model),
            v_local: DVector::zeros(nv),
            a_local: DVector::zeros(nv),
            q: crate::kinematics::neutral(model),
            v: DVector::zeros(nv),
            a: DVector::zeros(nv),
        }
    }

    /// True if this workspace was sized for `model`.
    #[must_use]
    pub fn fits(&self, model: &Model) -> bool {
        self.data.fits(model) && self.motion.jac.len() == model.nv
    }
}

/// The kinematic pass of the frame derivatives at `(q, v, a)` (moma's layout): every
/// joint's placement, twist and acceleration and the per-coordinate vectors, kept in `fd`
/// for [`frame_velocity_derivatives`], [`frame_acceleration_derivatives`] and
/// [`frame_motion`] (Pinocchio's `computeForwardKinematicsDerivatives`).
///
/// # Panics
/// If q, v, a have the wrong length or `fd` was not made for `model`.
pub fn forward_kinematics_derivatives(
    model: &Model,
    fd: &mut FrameDerivativeData,
    q: &DVector<f64>,
    v: &DVector<f64>,
    a: &DVector<f64>,
) {
    assert!(
        fd.fits(model),
        "FrameDerivativeData was not made for this model"
    );
    assert_eq!(
        q.len(),
        model.nq,
        "q has {} entries, the model nq = {}",
        q.len(),
        model.nq
    );
    assert_nv(model, v, "v");
    assert_nv(model, a, "a");
    fd.q.copy_from(q);
    fd.v.copy_from(v);
    fd.a.copy_from(a);
    let (qs, vs) = (q.as_slice(), v.as_slice());
    fd.layout.v_to_pinocchio(qs, vs, fd.v_local.as_mut_slice());
    fd.layout
        .a_to_pinocchio(qs, vs, a.as_slice(), fd.a_local.as_mut_slice());
    let root = Vector6::zeros();
    for i in 1..model.njoints {
        fd.motion.step(
            model,
            &mut fd.data,
            i,
            qs,
            fd.v_local.as_slice(),
            fd.a_local.as_slice(),
            &root,
        );
    }
}

/// The world placement of `frame`, its twist and its spatial acceleration expressed in
/// `rf` (see the module docs), at the state of the last
/// [`forward_kinematics_derivatives`].
#[must_use]
pub fn frame_motion(
    model: &Model,
    fd: &FrameDerivativeData,
    frame: FrameIndex,
    rf: ReferenceFrame,
) -> (SE3, Motion, Motion) {
    let (m, i) = placement(model, fd, frame);
    let express = |x: &Vector6<f64>| {
        let y = match rf {
            ReferenceFrame::World => *x,
            ReferenceFrame::Local => inverse_act_motion(&m, x),
            ReferenceFrame::LocalWorldAligned => shift(x, &m.translation),
        };
        let (l, a) = split(&y);
        Motion::new(l, a)
    };
    (m, express(&fd.motion.vel[i]), express(&fd.motion.acc[i]))
}

/// Derivatives of the twist of `frame` in `rf` at the state of the last
/// [`forward_kinematics_derivatives`]: `dv_dq` = ∂V/∂q and `dv_dv` = ∂V/∂v (the frame
/// Jacobian, also the placement's derivative; module docs), 6 × nv each, overwritten.
/// Pinocchio's `getFrameVelocityDerivatives`.
///
/// # Panics
/// If a matrix does not have nv columns or `fd` was not made for `model`.
pub fn frame_velocity_derivatives(
    model: &Model,
    fd: &FrameDerivativeData,
    frame: FrameIndex,
    rf: ReferenceFrame,
    dv_dq: &mut Matrix6xX<f64>,
    dv_dv: &mut Matrix6xX<f64>,
) {
    assert!(
        fd.fits(model),
        "FrameDerivativeData was not made for this model"
    );
    for x in [&*dv_dq, &*dv_dv] {
        assert_eq!(
            x.ncols(),
            model.nv,
            "derivative matrices must have nv columns"
        );
    }
    let (m, i) = placement(model, fd, frame);
    let mt = &fd.motion;
    let vel = mt.vel[i];
    fill_support(model, i, &mut [&mut *dv_dq, &mut *dv_dv], |k| {
        let j = mt.jac[k];
        match rf {
            ReferenceFrame::World => [cross_motion(&j, &vel) + mt.w[k], j],
            ReferenceFrame::Local => [inverse_act_motion(&m, &mt.w[k]), inverse_act_motion(&m, &j)],
            ReferenceFrame::LocalWorldAligned => [
                shift(&(cross_motion(&j, &vel) + mt.w[k]), &m.translation),
                shift(&j, &m.translation),
            ],
        }
    });
    fd.layout.frame_velocity_derivatives_from_pinocchio(
        fd.q.as_slice(),
        fd.v.as_slice(),
        dv_dq,
        dv_dv,
    );
}

/// Derivatives of the spatial acceleration of `frame` in `rf` at the state of the last
/// [`forward_kinematics_derivatives`], and of its twist: `dv_dq` = ∂V/∂q, `da_dq` =
/// ∂A/∂q, `da_dv` = ∂A/∂v and `da_da` = ∂A/∂a (the frame Jacobian), 6 × nv each,
/// overwritten. Pinocchio's `getFrameAccelerationDerivatives` (∂V/∂v = ∂A/∂a).
///
/// # Panics
/// If a matrix does not have nv columns or `fd` was not made for `model`.
#[allow(clippy::too_many_arguments)]
pub fn frame_acceleration_derivatives(
    model: &Model,
    fd: &FrameDerivativeData,
    frame: FrameIndex,
    rf: ReferenceFrame,
    dv_dq: &mut Matrix6xX<f64>,
    da_dq: &mut Matrix6xX<f64>,
    da_dv: &mut Matrix6xX<f64>,
    da_da: &mut Matrix6xX<f64>,
) {
    assert!(
        fd.fits(model),
        "FrameDerivativeData was not made for this model"
    );
    for x in [&*dv_dq, &*da_dq, &*da_dv, &*da_da] {
        assert_eq!(
            x.ncols(),
            model.nv,
            "derivative matrices must have nv columns"
        );
    }
    let (m, i) = placement(model, fd, frame);
    let mt = &fd.motion;
    let (vel, acc) = (mt.vel[i], mt.acc[i]);
    fill_support(
        model,
        i,
        &mut [&mut *dv_dq, &mut *da_dq, &mut *da_dv, &mut *da_da],
        |k| {
            let j = mt.jac[k];
            let jv = cross_motion(&j, &vel);
            // the world derivatives without the rigid rotation J × (V, A)
            let dv = mt.w[k];
            let da = cross_motion(&mt.w[k], &vel) + mt.u[k];
            let dav = mt.dadv[k] + jv;
            match rf {
                ReferenceFrame::World => [dv + jv, da + cross_motion(&j, &acc), dav, j],
                ReferenceFrame::Local => [
                    inverse_act_motion(&m, &dv),
                    inverse_act_motion(&m, &da),
                    inverse_act_motion(&m, &dav),
                    inverse_act_motion(&m, &j),
                ],
                ReferenceFrame::LocalWorldAligned => {
                    let p = &m.translation;
                    [
                        shift(&(dv + jv), p),
                        shift(&(da + cross_motion(&j, &acc)), p),
                        shift(&dav, p),
                        shift(&j, p),
                    ]
                }
            }
        },
    );
    fd.layout.frame_acceleration_derivatives_from_pinocchio(
        fd.q.as_slice(),
        fd.v.as_slice(),
        fd.a.as_slice(),
        dv_dq,
        da_dq,
        da_dv,
        da_da,
    );
}

/// The frame's world placement and its parent joint.
fn placement(model: &Model, fd: &FrameDerivativeData, frame: FrameIndex) -> (SE3, usize) {
    let fr = &model.frames[frame.0];
    let i = fr.parent_joint.0;
    (fd.motion.world_from_joint[i].compose(&fr.placement), i)
}

/// A world-frame spatial vector moved to the point `p`, world axes
/// (`[x_lin + x_ang × p; x_ang]`).
#[inline]
fn shift(x: &Vector6<f64>, p: &Vector3<f64>) -> Vector6<f64> {
    let (l, a) = split(x);
    join(l + a.cross(p), a)
}

/// Zeroes the matrices and writes, for every velocity coordinate `k` of the joints that
/// support joint `i`, column `k` of each from `col(k)`.
fn fill_support<const N: usize>(
    model: &Model,
    i: usize,
    out: &mut [&mut Matrix6xX<f64>; N],
    col: impl Fn(usize) -> [Vector6<f64>; N],
) {
    for m in out.iter_mut() {
        m.fill(0.0);
    }
    let mut j = i;
    while j > 0 {
        for k in model.idx_v[j]..model.idx_v[j] + model.nvs[j] {
            for (m, c) in out.iter_mut().zip(col(k)) {
                m.set_column(k, &c);
            }
        }
        j = model.parents[j].0;
    }
}

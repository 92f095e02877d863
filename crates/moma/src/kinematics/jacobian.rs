//! Frame Jacobians and J̇·q̇.

use super::{assert_nv, assert_sizes, update_joint_placement};
use crate::multibody::{Data, FrameIndex, Model};
use crate::spatial::{Motion, SE3};
use nalgebra::{DVector, Matrix6xX};

/// In which frame a frame's twist (and hence its Jacobian) is expressed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum ReferenceFrame {
    /// World frame: the twist of the body at the WORLD origin, world axes (spatial twist).
    World,
    /// The frame itself: velocity of the frame origin and angular velocity, frame axes.
    Local,
    /// Velocity of the frame origin and angular velocity, WORLD axes (the "classical"
    /// end-effector velocity [ṗ; ω]).
    #[default]
    LocalWorldAligned,
}

/// Converts a world spatial twist to the twist of frame `m` (world_from_frame) in `rf`.
#[inline]
fn convert(world: &Motion, m: &SE3, rf: ReferenceFrame) -> Motion {
    match rf {
        ReferenceFrame::World => *world,
        ReferenceFrame::LocalWorldAligned => Motion::new(
            world.linear + world.angular.cross(&m.translation),
            world.angular,
        ),
        ReferenceFrame::Local => m.inverse_act_motion(world),
    }
}

/// All joint Jacobians in the world frame: forward kinematics, then
/// `data.joint_jacobians` (6 × nv) column k = S_k expressed in the world frame.
///
/// # Panics
/// On wrong vector lengths.
pub fn compute_joint_jacobians(model: &Model, data: &mut Data, q: &DVector<f64>) {
    super::forward_kinematics(model, data, q);
    for i in 1..model.njoints {
        let m = data.world_from_joint[i];
        let iv = model.idx_v[i];
        for k in 0..model.nvs[i] {
            let c = m.act_motion(&data.s[iv + k]);
            data.joint_jacobians
                .fixed_view_mut::<6, 1>(0, iv + k)
                .copy_from(&c.to_vector());
        }
    }
}

/// Frame Jacobian J (6 × nv, rows linear then angular) from the placements already in
/// `data.world_from_joint` (run [`forward_kinematics`](super::forward_kinematics) first):
/// `J·v` is the frame's twist in `rf`. Also updates `data.world_from_frame[frame]`.
///
/// # Panics
/// If `out` is not 6 × nv.
pub fn frame_jacobian_from_kinematics(
    model: &Model,
    data: &mut Data,
    frame: FrameIndex,
    rf: ReferenceFrame,
    out: &mut Matrix6xX<f64>,
) {
    assert_eq!(out.ncols(), model.nv, "Jacobian must have nv columns");
    let fr = &model.frames[frame.0];
    let m = data.world_from_joint[fr.parent_joint.0].compose(&fr.placement);
    data.world_from_frame[frame.0] = m;
    out.as_mut_slice().fill(0.0);
    let mut j = fr.parent_joint.0;
    while j != 0 {
        let mj = &data.world_from_joint[j];
        let iv = model.idx_v[j];
        for k in 0..model.nvs[j] {
            let col = convert(&mj.act_motion(&data.s[iv + k]), &m, rf);
            let mut c = out.column_mut(iv + k);
            c[0] = col.linear.x;
            c[1] = col.linear.y;
            c[2] = col.linear.z;
            c[3] = col.angular.x;
            c[4] = col.angular.y;
            c[5] = col.angular.z;
        }
        j = model.parents[j].0;
    }
}

/// Frame Jacobian J (6 × nv) at configuration q, kinematics included (only the joints
/// supporting the frame are updated in `data.world_from_joint`): `J·v` is the twist of
/// `frame` expressed in `rf`, `[linear; angular]`.
///
/// # Panics
/// On wrong vector lengths or if `out` is not 6 × nv.
///
/// # Examples
/// ```
/// # use moma::{io::urdf::model_from_urdf_str, multibody::{Data, RootJoint}};
/// # use moma::kinematics::{frame_jacobian, ReferenceFrame};
/// # let urdf = r#"<robot name="r"><link name="a"/><link name="b"/>
/// #   <joint name="j" type="continuous"><parent link="a"/><child link="b"/>
/// #   <origin xyz="1 0 0"/><axis xyz="0 0 1"/></joint></robot>"#;
/// let model = model_from_urdf_str(urdf, RootJoint::Planar, "r.urdf")?;
/// let mut data = Data::new(&model);
/// let mut j = nalgebra::Matrix6xX::zeros(model.nv);
/// let q = nalgebra::DVector::zeros(model.nq);
/// frame_jacobian(&model, &mut data, &q, model.frame_id("b")?, ReferenceFrame::LocalWorldAligned, &mut j);
/// // base rotation θ̇ moves the link origin (1, 0) along +y
/// assert_eq!(j[(1, 2)], 1.0);
/// # Ok::<(), moma::Error>(())
/// ```
pub fn frame_jacobian(
    model: &Model,
    data: &mut Data,
    q: &DVector<f64>,
    frame: FrameIndex,
    rf: ReferenceFrame,
    out: &mut Matrix6xX<f64>,
) {
    assert_sizes(model, data, q);
    let qs = q.as_slice();
    data.path.clear();
    let mut j = model.frames[frame.0].parent_joint.0;
    while j != 0 {
        data.path.push(j);
        j = model.parents[j].0;
    }
    for k in (0..data.path.len()).rev() {
        let i = data.path[k];
        update_joint_placement(model, data, i, qs);
        let p = model.parents[i].0;
        data.world_from_joint[i] = if p == 0 {
            data.parent_from_joint[i]
        } else {
            data.world_from_joint[p].compose(&data.parent_from_joint[i])
        };
    }
    frame_jacobian_from_kinematics(model, data, frame, rf, out);
}

/// Twist of `frame` in `rf` from the body twists in `data.v` (run
/// [`forward_kinematics_second_order`](super::forward_kinematics_second_order) first).
#[must_use]
pub fn frame_velocity(model: &Model, data: &Data, frame: FrameIndex, rf: ReferenceFrame) -> Motion {
    let fr = &model.frames[frame.0];
    let vj = &data.v[fr.parent_joint.0];
    let local = fr.placement.inverse_act_motion(vj);
    let m = data.world_from_joint[fr.parent_joint.0].compose(&fr.placement);
    match rf {
        ReferenceFrame::Local => local,
        ReferenceFrame::LocalWorldAligned => {
            Motion::new(m.rotation * local.linear, m.rotation * local.angular)
        }
        ReferenceFrame::World => m.act_motion(&local),
    }
}

/// J̇·q̇ of a frame (the acceleration bias: the frame acceleration when q̈ = 0), consistent
/// with [`frame_jacobian`] in the same `rf`, i.e. `d/dt (J(q)·v) = J·q̇̇ + J̇·q̇`:
/// * `Local`: spatial acceleration of the frame in its own axes;
/// * `LocalWorldAligned`: classical acceleration [p̈; ω̇] of the frame origin, world axes;
/// * `World`: spatial acceleration in the world frame.
///
/// Runs forward kinematics with velocities (fills `data.v`, `data.a` with q̈ = 0).
///
/// # Panics
/// On wrong vector lengths.
pub fn frame_acceleration_bias(
    model: &Model,
    data: &mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    frame: FrameIndex,
    rf: ReferenceFrame,
) -> Motion {
    assert_sizes(model, data, q);
    assert_nv(model, v, "v");
    super::forward_kinematics_second_order_impl(model, data, q.as_slice(), v.as_slice(), None);
    let fr = &model.frames[frame.0];
    let j = fr.parent_joint.0;
    let v_f = fr.placement.inverse_act_motion(&data.v[j]);
    let a_f = fr.placement.inverse_act_motion(&data.a[j]);
    let m = data.world_from_joint[j].compose(&fr.placement);
    data.world_from_frame[frame.0] = m;
    match rf {
        ReferenceFrame::Local => a_f,
        ReferenceFrame::LocalWorldAligned => Motion::new(
            m.rotation * (a_f.linear + v_f.angular.cross(&v_f.linear)),
            m.rotation * a_f.angular,
        ),
        ReferenceFrame::World => m.act_motion(&a_f),
    }
}

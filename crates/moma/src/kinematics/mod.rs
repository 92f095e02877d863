//! Forward kinematics, frame placements, frame Jacobians, J̇·q̇, and the configuration
//! manifold (`integrate`, `difference`, `neutral`, `random_configuration`).
//!
//! Every function takes the immutable [`Model`] and writes into a
//! [`Data`] made for it; none allocates. Vector inputs are
//! `&DVector<f64>` (q: nq entries, v and a: nv entries); a wrong length is a programming
//! error and panics (validate user input first, e.g. with [`check_state`]).

mod configuration;
mod jacobian;

pub use configuration::{
    difference, integrate, neutral, normalize, random_configuration, wrap_angle,
};
pub use jacobian::{
    ReferenceFrame, compute_joint_jacobians, frame_acceleration_bias, frame_jacobian,
    frame_jacobian_from_kinematics, frame_velocity,
};

use crate::multibody::{Data, FrameIndex, Model};
use crate::spatial::{Motion, SE3};
use crate::{Error, Result};
use nalgebra::DVector;

pub(crate) fn assert_sizes(model: &Model, data: &Data, q: &DVector<f64>) {
    assert_eq!(
        q.len(),
        model.nq,
        "q has {} entries, the model nq = {}",
        q.len(),
        model.nq
    );
    assert!(data.fits(model), "Data was not made for this Model");
}

pub(crate) fn assert_nv(model: &Model, v: &DVector<f64>, what: &str) {
    assert_eq!(
        v.len(),
        model.nv,
        "{what} has {} entries, the model nv = {}",
        v.len(),
        model.nv
    );
}

/// Updates `data.parent_from_joint[i]` (and the q-dependent motion subspace columns) of
/// joint `i` for configuration `q`.
#[inline]
pub(crate) fn update_joint_placement(model: &Model, data: &mut Data, i: usize, q: &[f64]) {
    let jt = &model.joint_types[i];
    let qi = &q[model.idx_q[i]..model.idx_q[i] + model.nqs[i]];
    data.parent_from_joint[i] = jt.parent_from_joint(&model.joint_placements[i], qi);
    if matches!(jt, crate::multibody::JointType::Planar) {
        // S = [[c, −s, 0; 0], [s, c, 0; 0], [0; e_z]] (the third column is constant)
        let iv = model.idx_v[i];
        let (s, c) = crate::spatial::trig::sin_cos(qi[2]);
        data.s[iv].linear = nalgebra::Vector3::new(c, -s, 0.0);
        data.s[iv + 1].linear = nalgebra::Vector3::new(s, c, 0.0);
    }
}

/// Forward kinematics: fills `data.parent_from_joint` and `data.world_from_joint` for
/// configuration q (nq).
///
/// # Panics
/// If `q.len() != model.nq` or `data` was not made for `model`.
///
/// # Examples
/// ```
/// # use moma::{io::urdf::model_from_urdf_str, multibody::{Data, RootJoint}};
/// # let urdf = r#"<robot name="r"><link name="a"/><link name="b"/>
/// #   <joint name="j" type="continuous"><parent link="a"/><child link="b"/>
/// #   <origin xyz="1 0 0"/><axis xyz="0 0 1"/></joint></robot>"#;
/// let model = model_from_urdf_str(urdf, RootJoint::Fixed, "r.urdf")?;
/// let mut data = Data::new(&model);
/// moma::kinematics::forward_kinematics(&model, &mut data, &nalgebra::DVector::zeros(1));
/// assert_eq!(data.world_from_joint[1].translation.x, 1.0);
/// # Ok::<(), moma::Error>(())
/// ```
pub fn forward_kinematics(model: &Model, data: &mut Data, q: &DVector<f64>) {
    assert_sizes(model, data, q);
    let qs = q.as_slice();
    for i in 1..model.njoints {
        update_joint_placement(model, data, i, qs);
        let p = model.parents[i].0;
        data.world_from_joint[i] = if p == 0 {
            data.parent_from_joint[i]
        } else {
            data.world_from_joint[p].compose(&data.parent_from_joint[i])
        };
    }
}

/// Forward kinematics with velocities and accelerations: placements as
/// [`forward_kinematics`], plus body twists `data.v[i]` and spatial accelerations
/// `data.a[i]` (joint frames, gravity NOT included).
///
/// # Panics
/// On wrong vector lengths.
pub fn forward_kinematics_second_order(
    model: &Model,
    data: &mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    a: &DVector<f64>,
) {
    assert_sizes(model, data, q);
    assert_nv(model, v, "v");
    assert_nv(model, a, "a");
    forward_kinematics_second_order_impl(
        model,
        data,
        q.as_slice(),
        v.as_slice(),
        Some(a.as_slice()),
    );
}

/// Kinematics with velocities (and accelerations when `as_` is given, else q̈ = 0).
pub(crate) fn forward_kinematics_second_order_impl(
    model: &Model,
    data: &mut Data,
    qs: &[f64],
    vs: &[f64],
    as_: Option<&[f64]>,
) {
    data.v[0] = Motion::zero();
    data.a[0] = Motion::zero();
    for i in 1..model.njoints {
        update_joint_placement(model, data, i, qs);
        let jt = &model.joint_types[i];
        let p = model.parents[i].0;
        let (iq, iv) = (model.idx_q[i], model.idx_v[i]);
        let qi = &qs[iq..iq + model.nqs[i]];
        let vi = &vs[iv..iv + model.nvs[i]];
        let m = data.parent_from_joint[i];
        data.world_from_joint[i] = if p == 0 {
            m
        } else {
            data.world_from_joint[p].compose(&m)
        };
        let vj = jt.motion(qi, vi);
        let vel = m.inverse_act_motion(&data.v[p]) + vj;
        let mut acc = m.inverse_act_motion(&data.a[p]) + jt.bias(qi, vi) + vel.cross_motion(&vj);
        if let Some(a) = as_ {
            acc += jt.motion(qi, &a[iv..iv + model.nvs[i]]);
        }
        data.v[i] = vel;
        data.a[i] = acc;
    }
}

/// Frame placements: `data.world_from_frame[f] = world_from_joint[parent] · placement`
/// for every frame. Requires [`forward_kinematics`] first.
pub fn update_frame_placements(model: &Model, data: &mut Data) {
    for (k, fr) in model.frames.iter().enumerate() {
        data.world_from_frame[k] = data.world_from_joint[fr.parent_joint.0].compose(&fr.placement);
    }
}

/// Forward kinematics followed by [`update_frame_placements`].
///
/// # Panics
/// On wrong vector lengths.
pub fn frames_forward_kinematics(model: &Model, data: &mut Data, q: &DVector<f64>) {
    forward_kinematics(model, data, q);
    update_frame_placements(model, data);
}

/// Placement `world_from_frame` of one frame (computes it from
/// `data.world_from_joint`, so [`forward_kinematics`] must have run), also stored in
/// `data.world_from_frame`.
pub fn update_frame_placement(model: &Model, data: &mut Data, frame: FrameIndex) -> SE3 {
    let fr = &model.frames[frame.0];
    let m = data.world_from_joint[fr.parent_joint.0].compose(&fr.placement);
    data.world_from_frame[frame.0] = m;
    m
}

/// Checks a user-supplied state: q has nq entries, v / a / τ have nv (pass `None` to skip
/// one), every value finite. `source` names the input (e.g. `states.json state 3`).
///
/// # Errors
/// [`Error::WrongLength`] or [`Error::NonFinite`] naming the field.
pub fn check_state(
    model: &Model,
    source: &str,
    q: Option<&[f64]>,
    v: Option<&[f64]>,
    a: Option<&[f64]>,
    tau: Option<&[f64]>,
) -> Result<()> {
    for (name, vals, n) in [
        ("q", q, model.nq),
        ("v", v, model.nv),
        ("a", a, model.nv),
        ("tau", tau, model.nv),
    ] {
        if let Some(x) = vals {
            crate::error::ensure_len(&format!("{source} {name}"), n, x.len())?;
            if let Some(k) = x.iter().position(|y| !y.is_finite()) {
                return Err(Error::NonFinite {
                    field: format!("{source} {name}[{k}]"),
                });
            }
        }
    }
    if let Some(q) = q {
        for i in 1..model.njoints {
            if matches!(model.joint_types[i], crate::multibody::JointType::FreeFlyer) {
                let iq = model.idx_q[i];
                let n =
                    (q[iq + 3].powi(2) + q[iq + 4].powi(2) + q[iq + 5].powi(2) + q[iq + 6].powi(2))
                        .sqrt();
                if (n - 1.0).abs() > 1e-6 {
                    return Err(Error::invalid(
                        format!("{source} q[{}..{}]", iq + 3, iq + 7),
                        format!(
                            "free-flyer quaternion of joint '{}' must have unit norm, got {n}",
                            model.names[i]
                        ),
                    ));
                }
            }
        }
    }
    Ok(())
}

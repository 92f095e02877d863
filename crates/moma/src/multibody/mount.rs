//! Mounting a fixed-based model on a moving root: the arm of a mobile manipulator, given
//! on its own, placed on a planar (or free-flying) base.

use super::{Frame, FrameIndex, FrameKind, JointIndex, JointType, Model, RootJoint};
use crate::spatial::SE3;
use crate::{Error, Result};
use nalgebra::DVector;

/// Name of the root joint that [`mount_on_root`] adds (the URDF loader's name for it).
pub const MOUNT_ROOT_JOINT_NAME: &str = "root_joint";

/// The model `arm` (fixed root) mounted at `mount` (the arm's base, i.e. its world frame,
/// in the frame of the new root body) on a new `root` joint: q = [root coordinates,
/// arm q], v = [root velocity, arm v].
///
/// The new model is the old one with one joint inserted after the universe: joint `i` of
/// `arm` becomes joint `i + 1`, frame `f ≥ 1` becomes frame `f + 1` (frame 1 is the new
/// root joint's frame), so frame and joint lookups by name keep working. Joints, frames
/// and the bodies fixed to the arm's world (its `inertias[0]`) that hung from the
/// universe now hang from the root body, placed by `mount`. Limits, names and gravity are
/// kept; the root joint is unlimited.
///
/// With `root = RootJoint::Planar` this is the kinematic model of a mobile manipulator
/// whose platform pose is `[x, y, θ]` and whose arm base sits at `mount` on the platform;
/// its frame Jacobians (e.g. `LocalWorldAligned`) are the ones the whole-body measures
/// need.
///
/// # Errors
/// `arm` is not fixed-based (`arm.root != RootJoint::Fixed`), `root` is
/// `RootJoint::Fixed`, the mount is not a rigid transform, or `arm` already has a joint
/// named [`MOUNT_ROOT_JOINT_NAME`].
pub fn mount_on_root(arm: &Model, root: RootJoint, mount: &SE3) -> Result<Model> {
    let root_type = mount_root_type(arm, root, mount)?;
    let (rq, rv) = (root_type.nq(), root_type.nv());
    let joints = MountedJoints::new(arm, root_type, mount);
    let mut inertias = vec![
        crate::spatial::Inertia::zero(),
        arm.inertias[0].transformed(mount),
    ];
    inertias.extend(arm.inertias.iter().skip(1).copied());
    let mut joint_of_dof = vec![JointIndex(1); rv];
    joint_of_dof.extend(arm.joint_of_dof.iter().map(|&j| shift_joint(j)));
    Ok(Model {
        name: arm.name.clone(),
        nq: arm.nq + rq,
        nv: arm.nv + rv,
        njoints: arm.njoints + 1,
        names: joints.names,
        parents: joints.parents,
        joint_types: joints.joint_types,
        idx_q: joints.idx_q,
        idx_v: joints.idx_v,
        nqs: joints.nqs,
        nvs: joints.nvs,
        joint_placements: joints.joint_placements,
        inertias,
        frames: mounted_frames(arm, mount),
        gravity: arm.gravity,
        lower_position_limit: prepend(f64::NEG_INFINITY, rq, &arm.lower_position_limit),
        upper_position_limit: prepend(f64::INFINITY, rq, &arm.upper_position_limit),
        velocity_limit: prepend(f64::INFINITY, rv, &arm.velocity_limit),
        effort_limit: prepend(f64::INFINITY, rv, &arm.effort_limit),
        joint_of_dof,
        root,
        last_link: shift_frame(arm.last_link),
    })
}

/// The checks of [`mount_on_root`]'s inputs; the type of the new root joint.
fn mount_root_type(arm: &Model, root: RootJoint, mount: &SE3) -> Result<JointType> {
    if arm.root != RootJoint::Fixed {
        return Err(Error::invalid(
            "mounted model",
            format!(
                "model '{}' has a {} root; only a fixed-based model can be mounted",
                arm.name, arm.root
            ),
        ));
    }
    let root_type = match root {
        RootJoint::Fixed => {
            return Err(Error::invalid(
                "mount root",
                "a mounted model needs a planar or free-flyer root",
            ));
        }
        RootJoint::Planar => JointType::Planar,
        RootJoint::FreeFlyer => JointType::FreeFlyer,
    };
    crate::error::ensure_finite(
        "mount",
        mount.rotation.iter().chain(mount.translation.iter()),
    )?;
    let should_be_identity =
        mount.rotation.transpose() * mount.rotation - nalgebra::Matrix3::identity();
    if should_be_identity.norm() > 1e-9 || mount.rotation.determinant() < 0.0 {
        return Err(Error::invalid(
            "mount",
            "rotation is not a proper rotation matrix",
        ));
    }
    if arm.names.iter().any(|n| n == MOUNT_ROOT_JOINT_NAME) {
        return Err(Error::invalid(
            format!("joint '{MOUNT_ROOT_JOINT_NAME}'"),
            "this name is reserved for the root joint of the mounted model",
        ));
    }
    Ok(root_type)
}

/// Joint `j` of the arm in the mounted model.
fn shift_joint(j: JointIndex) -> JointIndex {
    JointIndex(j.0 + 1)
}

/// Frame `f` of the arm in the mounted model (the universe's frame stays; the new root
/// joint's frame is frame 1).
fn shift_frame(f: FrameIndex) -> FrameIndex {
    FrameIndex(if f.0 == 0 { 1 } else { f.0 + 1 })
}

/// `n` copies of `head` followed by `tail`.
fn prepend(head: f64, n: usize, tail: &DVector<f64>) -> DVector<f64> {
    DVector::from_iterator(
        n + tail.len(),
        std::iter::repeat_n(head, n).chain(tail.iter().copied()),
    )
}

/// The per-joint tables of the mounted model: the universe, the new root joint, then the
/// arm's joints, the ones that hung from the universe placed by `mount`.
struct MountedJoints {
    names: Vec<String>,
    parents: Vec<JointIndex>,
    joint_types: Vec<JointType>,
    idx_q: Vec<usize>,
    idx_v: Vec<usize>,
    nqs: Vec<usize>,
    nvs: Vec<usize>,
    joint_placements: Vec<SE3>,
}

impl MountedJoints {
    fn new(arm: &Model, root_type: JointType, mount: &SE3) -> Self {
        let (rq, rv) = (root_type.nq(), root_type.nv());
        let mut names = vec![arm.names[0].clone(), MOUNT_ROOT_JOINT_NAME.to_string()];
        names.extend(arm.names.iter().skip(1).cloned());
        let mut parents = vec![JointIndex(0), JointIndex(0)];
        parents.extend(arm.parents.iter().skip(1).map(|&p| shift_joint(p)));
        let mut joint_types = vec![arm.joint_types[0], root_type];
        joint_types.extend(arm.joint_types.iter().skip(1).copied());
        let mut idx_q = vec![0, 0];
        idx_q.extend(arm.idx_q.iter().skip(1).map(|i| i + rq));
        let mut idx_v = vec![0, 0];
        idx_v.extend(arm.idx_v.iter().skip(1).map(|i| i + rv));
        let mut nqs = vec![0, rq];
        nqs.extend(arm.nqs.iter().skip(1).copied());
        let mut nvs = vec![0, rv];
        nvs.extend(arm.nvs.iter().skip(1).copied());
        let mut joint_placements = vec![SE3::identity(), SE3::identity()];
        joint_placements.extend(
            arm.joint_placements
                .iter()
                .enumerate()
                .skip(1)
                .map(|(i, p)| {
                    if arm.parents[i].0 == 0 {
                        mount.compose(p)
                    } else {
                        *p
                    }
                }),
        );
        MountedJoints {
            names,
            parents,
            joint_types,
            idx_q,
            idx_v,
            nqs,
            nvs,
            joint_placements,
        }
    }
}

/// The frames of the mounted model: the universe's, the new root joint's, then the
/// arm's, renumbered, the ones fixed to the arm's world placed by `mount`.
fn mounted_frames(arm: &Model, mount: &SE3) -> Vec<Frame> {
    let mut frames = vec![
        arm.frames[0].clone(),
        Frame {
            name: MOUNT_ROOT_JOINT_NAME.to_string(),
            parent_joint: JointIndex(1),
            parent_frame: FrameIndex(0),
            placement: SE3::identity(),
            kind: FrameKind::Joint,
        },
    ];
    frames.extend(arm.frames.iter().skip(1).map(|f| Frame {
        name: f.name.clone(),
        parent_joint: shift_joint(f.parent_joint),
        parent_frame: shift_frame(f.parent_frame),
        placement: if f.parent_joint.0 == 0 {
            mount.compose(&f.placement)
        } else {
            f.placement
        },
        kind: f.kind,
    }));
    frames
}

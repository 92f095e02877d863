//! The immutable robot model.

use super::{FrameIndex, JointIndex, JointType};
use crate::spatial::{Inertia, SE3};
use crate::{Error, Result};
use nalgebra::{DVector, Vector3};

/// What a frame marks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameKind {
    /// The world (frame 0).
    Universe,
    /// A joint's own frame (one per moving joint, including the root joint).
    Joint,
    /// A fixed joint of the source description (merged away).
    FixedJoint,
    /// A link (body) of the source description.
    Body,
    /// A user-defined operational frame.
    Operational,
}

impl FrameKind {
    /// Stable lowercase name (`universe`, `joint`, `fixed_joint`, `body`, `operational`).
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self {
            FrameKind::Universe => "universe",
            FrameKind::Joint => "joint",
            FrameKind::FixedJoint => "fixed_joint",
            FrameKind::Body => "body",
            FrameKind::Operational => "operational",
        }
    }
}

/// A named frame rigidly attached to a joint.
#[derive(Clone, Debug, PartialEq)]
pub struct Frame {
    /// Frame name (link or joint name for frames built from a URDF).
    pub name: String,
    /// The joint whose body carries the frame.
    pub parent_joint: JointIndex,
    /// The frame it was attached to in the source tree (itself for the universe).
    pub parent_frame: FrameIndex,
    /// `joint_from_frame`: placement of the frame in its joint's frame.
    pub placement: SE3,
    /// What the frame marks.
    pub kind: FrameKind,
}

/// The root joint connecting a robot's root link to the world.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum RootJoint {
    /// The root link is fixed to the world.
    #[default]
    Fixed,
    /// A planar mobile base: q = [x, y, θ], v = [ẋ, ẏ, θ̇] in world axes.
    Planar,
    /// A free-flying (space) base: q = [x, y, z, qx, qy, qz, qw], v = base twist in the
    /// base frame.
    FreeFlyer,
}

impl std::str::FromStr for RootJoint {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "fixed" => Ok(RootJoint::Fixed),
            "planar" => Ok(RootJoint::Planar),
            "free-flyer" | "freeflyer" | "free_flyer" => Ok(RootJoint::FreeFlyer),
            other => Err(Error::invalid(
                "root joint",
                format!("'{other}' is not one of fixed, planar, free-flyer"),
            )),
        }
    }
}

impl std::fmt::Display for RootJoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            RootJoint::Fixed => "fixed",
            RootJoint::Planar => "planar",
            RootJoint::FreeFlyer => "free-flyer",
        })
    }
}

/// An immutable kinematic tree with inertias: the robot model.
///
/// Joint 0 is the universe (the world, no degree of freedom); every other joint `i` has a
/// parent `parents[i] < i`. Arrays indexed by joint have `njoints` entries. Built by
/// [`ModelBuilder`](super::ModelBuilder) or the URDF loader
/// ([`crate::io::urdf::model_from_urdf_file`]); algorithms take it by shared reference
/// together with a [`Data`](super::Data) workspace.
#[derive(Clone, Debug)]
pub struct Model {
    /// Model (robot) name.
    pub name: String,
    /// Dimension of the configuration vector q.
    pub nq: usize,
    /// Dimension of the velocity vector v (= number of degrees of freedom).
    pub nv: usize,
    /// Number of joints, including the universe (joint 0).
    pub njoints: usize,
    /// Joint names (`"universe"` for joint 0).
    pub names: Vec<String>,
    /// Parent joint of each joint (the universe is its own parent).
    pub parents: Vec<JointIndex>,
    /// Joint types (entry 0, the universe, is unused and set to `RevoluteZ`).
    pub joint_types: Vec<JointType>,
    /// Index of each joint's first coordinate in q.
    pub idx_q: Vec<usize>,
    /// Index of each joint's first coordinate in v.
    pub idx_v: Vec<usize>,
    /// Number of configuration coordinates of each joint (0 for the universe).
    pub nqs: Vec<usize>,
    /// Number of velocity coordinates of each joint (0 for the universe).
    pub nvs: Vec<usize>,
    /// `parent_from_joint` at q = 0: placement of each joint frame in its parent's frame.
    pub joint_placements: Vec<SE3>,
    /// Spatial inertia of the body carried by each joint, in the joint frame (entry 0:
    /// bodies fixed to the world; they take no part in the dynamics, mass or CoM).
    pub inertias: Vec<Inertia>,
    /// Frames (frame 0 is the universe).
    pub frames: Vec<Frame>,
    /// Gravity acceleration in world axes (m/s²), default [0, 0, −9.81].
    pub gravity: Vector3<f64>,
    /// Lower position limits (nq); −∞ where unlimited.
    pub lower_position_limit: DVector<f64>,
    /// Upper position limits (nq); +∞ where unlimited.
    pub upper_position_limit: DVector<f64>,
    /// Velocity limits (nv); +∞ where unlimited.
    pub velocity_limit: DVector<f64>,
    /// Effort limits (nv); +∞ where unlimited.
    pub effort_limit: DVector<f64>,
    /// Joint index owning each velocity coordinate (nv).
    pub joint_of_dof: Vec<JointIndex>,
    /// The root joint kind.
    pub root: RootJoint,
    /// The "last link" frame, default end-effector of the CLI (see
    /// [`Model::last_link_frame`]).
    pub last_link: FrameIndex,
}

impl Model {
    /// Number of frames.
    #[must_use]
    pub fn nframes(&self) -> usize {
        self.frames.len()
    }

    /// The frame called `name` (the first one in frame order if several share it).
    ///
    /// # Errors
    /// [`Error::Unknown`] if there is no such frame.
    pub fn frame_id(&self, name: &str) -> Result<FrameIndex> {
        self.frames
            .iter()
            .position(|f| f.name == name)
            .map(FrameIndex)
            .ok_or_else(|| Error::Unknown {
                kind: "frame",
                name: name.to_string(),
            })
    }

    /// The joint called `name`.
    ///
    /// # Errors
    /// [`Error::Unknown`] if there is no such joint.
    pub fn joint_id(&self, name: &str) -> Result<JointIndex> {
        self.names
            .iter()
            .position(|n| n == name)
            .map(JointIndex)
            .ok_or_else(|| Error::Unknown {
                kind: "joint",
                name: name.to_string(),
            })
    }

    /// Total mass of the moving bodies (kg): bodies fixed to the world are excluded, as in
    /// Pinocchio.
    #[must_use]
    pub fn total_mass(&self) -> f64 {
        self.inertias.iter().skip(1).map(Inertia::mass).sum()
    }

    /// The "last link": the last body (link) frame in frame order. URDF models are
    /// traversed depth-first with child joints sorted by name, as Pinocchio does, so this
    /// is the frame `model.frames[-1]` Pinocchio would report (e.g. `panda_hand_tcp`,
    /// `tool0` on UR5). Used as the default end-effector frame by the CLI.
    #[must_use]
    pub fn last_link_frame(&self) -> FrameIndex {
        self.last_link
    }

    /// True if `ancestor` is `joint` or one of its ancestors.
    #[must_use]
    pub fn is_ancestor(&self, ancestor: JointIndex, joint: JointIndex) -> bool {
        let mut j = joint.0;
        loop {
            if j == ancestor.0 {
                return true;
            }
            if j == 0 {
                return false;
            }
            j = self.parents[j].0;
        }
    }
}

/// The neutral configuration q₀ (nq): zeros, identity quaternion for a free-flyer.
/// Allocates. (Also reachable as `kinematics::neutral`.)
#[must_use]
pub fn neutral(model: &Model) -> DVector<f64> {
    let mut q = DVector::zeros(model.nq);
    for i in 1..model.njoints {
        if matches!(model.joint_types[i], JointType::FreeFlyer) {
            q[model.idx_q[i] + 6] = 1.0;
        }
    }
    q
}

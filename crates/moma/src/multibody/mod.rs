//! Multibody model (immutable [`Model`], built by [`ModelBuilder`] or the URDF loader)
//! and its reusable workspace [`Data`].
//!
//! Joints are a closed enum ([`JointType`]); joint 0 is the universe; joints are stored
//! in an order where every parent precedes its children. Each joint carries the rigid
//! body made of its child link and every link attached to it through fixed joints
//! (their inertias are merged; each such link and fixed joint keeps a [`Frame`]).
//!
//! Storage is Pinocchio's: the tree lives in per-joint arrays with `parents[i] < i`. The
//! URDF loader orders joints depth-first (child joints by name, as urdfdom); a model
//! built in another parents-first order is valid, and the CRBA then takes a slower
//! ancestor walk, decided once in [`Data::new`]. [`JointType`] has axis-aligned revolute
//! and prismatic variants (a unit motion subspace: the algorithms add and cross a joint's
//! twist by its one coordinate), variants about an unaligned axis, `Planar` and
//! `FreeFlyer`.
//!
//! Root joints ([`RootJoint`]):
//! * `Fixed`: the root link is welded to the world (its inertia is ignored, as in
//!   Pinocchio).
//! * `Planar`: q = [x, y, θ] and v = [ẋ, ẏ, θ̇] in WORLD axes (so `integrate` is a plain
//!   sum). Pinocchio stores [x, y, cos θ, sin θ] with a base-frame velocity instead.
//! * `FreeFlyer`: q = [x, y, z, qx, qy, qz, qw], v = [v; ω] in the BASE frame (as
//!   Pinocchio).
//!
//! Mimic joints of a URDF are loaded as independent joints.
//!
//! # Examples
//! A two-link planar arm built by hand, then its mass matrix:
//! ```
//! use moma::multibody::{Data, JointIndex, JointLimits, JointType, ModelBuilder};
//! use moma::spatial::{Inertia, SE3};
//! use nalgebra::{DVector, Matrix3, Vector3};
//!
//! let mut b = ModelBuilder::new("two_link_arm");
//! let rod = Inertia::new(1.0, Vector3::new(0.5, 0.0, 0.0), Matrix3::from_diagonal(&Vector3::new(0.0, 1.0 / 12.0, 1.0 / 12.0)));
//! let shoulder = b.add_joint(JointIndex(0), "shoulder", JointType::RevoluteZ,
//!     SE3::identity(), JointLimits::scalar(-3.0, 3.0, 2.0, 10.0))?;
//! b.append_body_inertia(shoulder, &rod, &SE3::identity())?;
//! let elbow = b.add_joint(shoulder, "elbow", JointType::RevoluteZ,
//!     SE3::from_translation(Vector3::new(1.0, 0.0, 0.0)), JointLimits::scalar(-3.0, 3.0, 2.0, 10.0))?;
//! b.append_body_inertia(elbow, &rod, &SE3::identity())?;
//! let model = b.build()?;
//!
//! let mut data = Data::new(&model);
//! let q = DVector::from_vec(vec![0.3, 0.0]);
//! let h = moma::dynamics::crba(&model, &mut data, &q);
//! // H11 = 2 I + m1 r1² + m2 (l1² + r2² + 2 l1 r2 cos q2) with I = 1/12, r = 0.5, l = 1
//! approx::assert_relative_eq!(h[(0, 0)], 2.0 / 12.0 + 0.25 + 1.0 + 0.25 + 1.0, epsilon = 1e-12);
//! # Ok::<(), moma::Error>(())
//! ```

mod builder;
mod crba_plan;
mod data;
mod joint;
mod model;
mod mount;

pub use builder::{JointLimits, ModelBuilder};
pub use data::{ArticulatedInertia, Data};
pub use joint::{FrameIndex, JointIndex, JointType, axis_rotation, free_flyer_transform};
pub use model::{Frame, FrameKind, Model, RootJoint, neutral};
pub use mount::{MOUNT_ROOT_JOINT_NAME, mount_on_root};

//! Arm motion planning among obstacles: a collision-free, timed motion of a group of
//! joints (e.g. Fetch's torso lift and arm) from a start state to a goal state or a goal
//! pose of a frame.
//!
//! * [`JointGroup`]: the joints that move, their planning box (URDF limits; continuous
//!   joints in `[-π, π]`, not wrapped) and velocity limits.
//! * [`ClearanceChecker`]: the robot's geometry against itself (SRDF-filtered pairs) and
//!   the scene; a segment passes only if the clearance of its checked states covers the
//!   largest motion of any geometry point in between (a conservative continuous check).
//! * [`ik_goals`]: collision-free IK solutions of a goal pose over the group.
//! * [`plan_motion`]: goal states, RRT-Connect, shortcutting, time-optimal timing with
//!   checked blends ([`crate::planning`]'s joint-space planner core).
//!
//! Algorithm, check resolution and limits: `docs/motion.md`.

pub mod clearance;
pub mod goal;
pub mod grasp_query;
pub mod group;
mod link_ball_gaps;
pub mod placement;
pub mod plan;
pub mod surface;

pub use clearance::{ClearanceChecker, ClosestPair};
pub use goal::{GoalPose, GroupFrame, IkGoals, ik_goals};
pub use group::JointGroup;
pub use plan::{
    MotionGoal, MotionOptions, MotionProblem, MotionResult, MotionTrajectory, NotSolved,
    PhaseChecks, PhaseTimes, plan_motion,
};
pub use surface::{
    MeshSource, PATCH_TRIANGLES, Patching, surface_links_for_states, with_mesh_surface,
};

//! Whole-body model predictive control of a differential-drive mobile manipulator on its
//! reduced (constraint-eliminated) model: the base drives and the arm reaches in one
//! optimal-control problem, kept within its torque, speed and position limits, upright
//! (ZMP margin) and clear of the scene, of itself and of the map's obstacles. See `docs/mpc.md`.
//!
//! | file | concept |
//! | --- | --- |
//! | [`problem`] | the discrete optimal-control problem the solver works on |
//! | [`robot`] | the robot as the MPC predicts it: state layout, limits, one knot's torques, ZMP margin, clearance, end-effector pose and their derivatives |
//! | [`distance_field`] | the map's distance field and the base footprint's clearance on it, with its gradient in the base pose |
//! | [`costs`] | base path and end-effector pose tracking, effort, posture |
//! | [`constraints`] | the constraint kinds and their augmented-Lagrangian terms |
//! | [`box_qp`] | the box-constrained QP of one backward-pass stage |
//! | [`solver`] | box-constrained iLQR: Riccati backward pass, line-searched rollout |
//! | [`warm_start`] | the previous solution shifted by one stage |
//! | [`report`] | per-solve time, iterations and constraint violations |
//! | [`whole_body`] | the MPC: problem + solver + warm start, and the torques to apply |

pub mod box_qp;
pub mod constraints;
pub mod costs;
pub mod distance_field;
pub mod problem;
pub mod report;
pub mod robot;
pub mod solver;
pub mod warm_start;
pub mod whole_body;

pub use constraints::{ConstraintSettings, KINDS};
pub use costs::{CostWeights, KnotReference};
pub use distance_field::{DistanceField, MapClearance};
pub use problem::{OptimalControlProblem, StageModel};
pub use report::{SolveReport, Violations};
pub use robot::{Clearance, MpcRobot};
pub use solver::{SolveStats, Solver, SolverOptions, Trajectory};
pub use whole_body::{MpcSettings, WholeBodyMpc};

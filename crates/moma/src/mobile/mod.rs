//! Wheeled platforms: wheel contacts, Pfaffian constraints, admissible-velocity basis,
//! reduced dynamics, whole-body Jacobian.

pub mod diff_drive;

pub use diff_drive::DiffDrive;
pub mod nullspace;
pub mod reduced;

pub use nullspace::NullSpaceBasis;
pub use reduced::{JointSpaceTerms, ReducedDynamics, lagrange_multipliers_dae};

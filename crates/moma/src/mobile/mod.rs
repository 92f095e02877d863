//! Wheeled platforms: wheel contacts, Pfaffian constraints, admissible-velocity basis,
//! reduced dynamics, whole-body Jacobian.

pub mod diff_drive;
pub mod whole_body;

pub use diff_drive::DiffDrive;
pub use whole_body::whole_body_jacobian;

//! Wheeled platforms: wheel contacts, Pfaffian constraints, admissible-velocity basis,
//! reduced dynamics, whole-body Jacobian.

pub mod constrained_aba;
pub mod diff_drive;
pub mod nullspace;
pub mod reduced;
pub mod urdf_drive;
pub mod wheeled;
pub mod whole_body;

pub use constrained_aba::reduced_forward_dynamics;
pub use diff_drive::DiffDrive;
pub use nullspace::NullSpaceBasis;
pub use reduced::{JointSpaceTerms, ReducedDynamics, lagrange_multipliers_dae};
pub use urdf_drive::{caster_list_problem, casters_from_str, read_casters, wheeled_base_from_urdf};
pub use wheeled::{
    Caster, WheeledBase, WheeledData, WheeledModel, actuation_matrix, admissible_velocity_basis,
    admissible_velocity_basis_dot, constraint_matrix, lagrange_multipliers,
};
pub use whole_body::whole_body_jacobian;

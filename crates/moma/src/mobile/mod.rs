//! Wheeled platforms: wheel contacts, Pfaffian constraints, admissible-velocity basis,
//! reduced dynamics, whole-body Jacobian.
//!
//! [`WheeledModel`] wraps a planar-rooted [`Model`](crate::multibody::Model) with a
//! [`WheeledBase`] (a [`DiffDrive`], casters, optional tracked wheel joints). It gives the
//! Pfaffian rows C(q) (no side slip, plus the rolling rows for tracked wheels), an
//! analytic basis N_C(q) for the reduced velocity `v_r = [v, ω, q̇_arm]` (valid for every
//! offset d, d = 0 included) and Ṅ_C, and the actuation map S ([`wheeled`]). The reduced
//! dynamics `Mr v̇ + Cr v + Gr = Qr` take one of two routes: with massless wheels the
//! constraint sits only on the base, so one ABA pass plus a 2 × 2 solve is exact
//! ([`constrained_aba`]); otherwise CRBA + RNEA (with a = Ṅ_C v) + an in-place Cholesky.
//! λ costs one more RNEA. [`ReducedDynamics`] is the same projection for any H, h, G
//! source, and [`NullSpaceBasis`] gives a continuous orthonormal N_C for arbitrary user
//! constraint rows. [`whole_body`] turns a frame Jacobian into J̄ = J·N_C (inputs (v, ω)
//! or wheel rates, any task rows, plus J̄̇u), including the platform-yaw term.
//! [`urdf_drive`] reads the drive from a URDF and the casters from a file.

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

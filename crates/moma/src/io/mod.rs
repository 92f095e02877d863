//! Input and output: the URDF loader, the JSON states files of the command line, and the
//! map between moma's state layout and Pinocchio's.
//!
//! The URDF loader ([`urdf`]) visits child joints in byte order of their names, as
//! urdfdom does, so state vectors have Pinocchio's layout except for a planar base
//! (`[x, y, θ]`) and continuous joints (one angle); [`pinocchio_layout`] states that
//! difference once, with the chain rule for both directions (the derivatives of the
//! dynamics use it inside the library, and `--layout pinocchio` on the command line).
//! The loader reads only kinematics and inertia (visual, collision and material elements
//! are removed before parsing; the collision geometry has its own reader in
//! [`crate::collision`]), names the link or joint at fault, takes link inertias whose
//! negative eigenvalue is within 1e-6 kg·m² as export rounding (real robots ship them:
//! TIAGo's 1 mg antenna links) and refuses larger ones, requires every merged body to be
//! positive semidefinite so H stays positive definite, refuses a revolute or prismatic
//! joint without `<limit>` (as urdfdom) and floating or planar joints inside the file
//! (the base is chosen with the root option).

pub mod pinocchio_layout;
pub mod states;
pub mod urdf;

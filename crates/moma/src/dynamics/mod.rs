//! Rigid-body dynamics: inverse dynamics ([`rnea`]), the mass matrix ([`crba`]), forward
//! dynamics ([`aba`]), gravity and nonlinear effects, a Christoffel-consistent Coriolis
//! matrix, energies, centre of mass and centroidal momentum, and the analytical
//! derivatives of inverse and forward dynamics ([`rnea_derivatives`], [`aba_derivatives`])
//! and of a frame's placement, velocity and acceleration
//! ([`forward_kinematics_derivatives`], [`frame_velocity_derivatives`],
//! [`frame_acceleration_derivatives`]).
//!
//! Every algorithm is a free function `f(&model, &mut data, q, …)` over a
//! [`Model`](crate::multibody::Model) and its [`Data`](crate::multibody::Data); inputs are
//! `&DVector<f64>` (q: nq, v / a / τ: nv); results are borrowed from `data`. After
//! `Data::new` none of them allocates. Wrong lengths panic (validate user input with
//! [`crate::kinematics::check_state`]).
//!
//! The algorithms use the local (joint-frame) convention of Featherstone and Pinocchio,
//! with specialised kernels for axis-aligned revolute and prismatic joints.

mod aba;
pub(crate) use aba::{aba_forward_pass, accelerate_one_dof, condense_one_dof};
mod centroidal;
mod coriolis;
mod crba;
mod derivatives;
mod frame_derivatives;
mod motion_pass;
mod rnea;
mod rnea_batch;
mod tree_ltdl;

pub use aba::aba;
pub use centroidal::{
    center_of_mass, centroidal_momentum, centroidal_momentum_matrix, kinetic_energy,
    potential_energy,
};
pub use coriolis::coriolis_matrix;
pub use crba::crba;
pub use derivatives::{DerivativeData, aba_derivatives, rnea_derivatives};
pub use frame_derivatives::{
    FrameDerivativeData, forward_kinematics_derivatives, frame_acceleration_derivatives,
    frame_motion, frame_velocity_derivatives,
};
pub use rnea::{gravity_torque, nonlinear_effects, rnea};
pub use rnea_batch::{BatchData, BatchIsa, RNEA_LANES, rnea_batch, rnea_batch_isa};

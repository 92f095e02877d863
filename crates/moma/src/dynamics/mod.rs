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
//!
//! # How they are built
//!
//! * RNEA, ABA and CRBA run in joint frames; the Jacobians, the Coriolis matrix and the
//!   centroidal map run in the world frame.
//! * [`crba`] is Pinocchio's local variant: composite inertias in joint frames; each
//!   subtree's force columns (one 6-vector each) move to the parent once per joint, and
//!   when the parent is the root only the components a revolute, prismatic or planar root
//!   needs are computed; every entry of H is written to both triangles as its column is
//!   produced; a large subtree under a long chain (a hand on an arm) is finished at its
//!   root joint by bringing the ancestors' motion subspaces down to it instead, chosen by a
//!   cost model once per model in `Data::new`. A model whose joints are not in depth-first
//!   order (some subtree's dofs not one contiguous range) takes a slower ancestor walk,
//!   also detected once in `Data::new`.
//! * [`rnea_batch`] runs the same RNEA pass on [`RNEA_LANES`] (eight) states at once,
//!   structure-of-arrays over the lanes (`[f64; 8]` per scalar, loops LLVM turns into
//!   SIMD), each lane doing the scalar pass's operations in the same order, so its torques
//!   are bit-for-bit [`rnea`]'s (the Python `rnea_batch` uses it). What makes that
//!   possible: every joint angle's sine and cosine is [`crate::spatial::trig::sin_cos`],
//!   branch-free arithmetic that vectorises (rather than libm), and an axis-aligned
//!   joint's twist is added and crossed by its one coordinate in both passes. Its group
//!   loop is compiled three times, for the portable target, AVX2 and AVX-512F
//!   ([`BatchIsa`], chosen at run time; no fused multiply–add, so the same bits), and the
//!   joint kinds outside the lanes' (unaligned axes, planar, free-flyer) are computed out
//!   of line, lane by lane with the scalar joint code, so the lane values stay in
//!   registers.
//! * [`rnea_derivatives`] and [`aba_derivatives`] are Carpentier and Mansard's (and
//!   Pinocchio's) world-frame pair of passes: the forward pass stores per dof the world
//!   Jacobian column and three 6-vectors built from the parent's twist and acceleration,
//!   per body its world inertia (mass, first moment, rotational inertia) and the velocity
//!   variation B in closed form (two of its 3 × 3 blocks vanish); the backward pass
//!   accumulates the composite inertia, B and force and writes each joint's rows against
//!   its ancestors' columns and its columns against its ancestors' rows (τ, H and ∂τ/∂v
//!   first, ∂τ/∂q in a second pass). They run with constant joint-frame subspaces (the
//!   planar root in Pinocchio's base-frame velocity); moma's planar layout is reached by
//!   the chain rule that [`crate::io::pinocchio_layout`] states once for both directions.
//!   ABA's derivatives are −H⁻¹ ∂τ/∂x at a = q̈ with no separate ABA (the passes run at
//!   a = 0, q̈ = H⁻¹(τ − h), then the terms linear in a are updated), H factorised as LᵀDL
//!   with the tree's sparsity (Featherstone) and `[I, −∂τ/∂q, −∂τ/∂v]` solved row by row
//!   along the ancestor chains.
//! * The frame derivatives ([`forward_kinematics_derivatives`] and the two readers) take a
//!   frame's ∂V/∂q, ∂A/∂q, ∂A/∂v and Jacobian off the same kinematic pass (run without
//!   gravity), in Pinocchio's three reference frames, and reach moma's planar layout by
//!   the same chain rule.

mod aba;
pub(crate) use aba::{aba_forward_pass, accelerate_one_dof, condense_one_dof};
mod centroidal;
mod coriolis;
mod crba;
mod dense_product;
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

//! # moma — mobile manipulation in Rust
//!
//! Kinematics, dynamics, stability, control, simulation and motion planning of wheeled
//! mobile robot manipulators (a non-holonomic differential-drive platform carrying a
//! serial arm) and of free-floating space manipulators, after the chapter "Kinematics,
//! Dynamics, and Control of Mobile Robot Manipulators": rigid-body algorithms on fixed,
//! planar and free-flyer roots, wheel constraints and reduced dynamics, the chapter's
//! closed-form models (m1–m6), whole-body kinematics, manipulability, inverse kinematics,
//! tip-over stability ([`stability`]), controllers with Lyapunov monitors ([`control`]),
//! free-floating robots ([`space`]) and grid motion planning.
//!
//! ## Conventions
//!
//! * SI units (m, kg, kg·m², s, N, N·m) and radians everywhere; one scalar type, `f64`.
//! * Spatial vectors are stored `[linear; angular]` (as Pinocchio).
//! * Transforms are named `a_from_b`, so composition reads right to left.
//! * Quaternions are stored `[x, y, z, w]`.
//!
//! ## Data flow
//!
//! An immutable [`multibody::Model`] (validated once) and a reusable [`multibody::Data`]
//! (all buffers allocated once by `Data::new(&model)`); algorithms are free functions
//! `algorithm(&model, &mut data, q, v, …)` that write their results into `data` and do
//! not allocate.
//!
//! ## Allocation and cross-checks
//!
//! Counting-allocator tests prove that the hot paths allocate nothing once their
//! workspaces are built: every rigid-body algorithm on depth-first and non-depth-first
//! trees with each root (`tests/rigid_body_no_alloc.rs`); the reduced dynamics,
//! multipliers and the simulator's right-hand side (`mobile_alloc.rs`); IK iterations
//! without an objective or with the posture objective, one RK4 / Dormand–Prince / DOP853
//! step, A* (`astar_cost`) and D* Lite queries after warm-up (the queues keep the largest
//! size they reached) and `DStarLite::clone_from` once the copy has reached the source's
//! size (`hot_path_alloc.rs`); the geometry queries, the contact step, operational-space
//! control, the space algorithms and the stability measures (`collision_alloc.rs`,
//! `contact_alloc.rs`, `control_no_alloc.rs`, `space_no_alloc.rs`,
//! `stability_no_alloc.rs`). Not covered, and allocating: the manipulability measures
//! (one SVD each), hence IK iterations with the manipulability objective, and the paths
//! the searches return.
//!
//! `bench/xcheck_pinocchio.py`, with the `rigid_body_dump` example, compares the whole
//! rigid-body core against Pinocchio on every example-robot-data robot, synthetic edge
//! cases (`bench/xcheck_urdf/`) and seeded random trees; the results are in
//! `bench/xcheck_pinocchio_results.md`.
//!
//! ## Glossary (textbook symbol → Rust name)
//!
//! | symbol | meaning | Rust |
//! | --- | --- | --- |
//! | H, M | joint-space inertia (mass) matrix | `dynamics::crba` → `data.mass_matrix` |
//! | h, C(q,q̇)q̇ | nonlinear effects | `dynamics::nonlinear_effects` |
//! | G | gravity torques | `dynamics::gravity_torque` |
//! | C_cor | Christoffel-consistent Coriolis matrix | `dynamics::coriolis_matrix` |
//! | C(q) | Pfaffian constraint matrix | `mobile::constraint_matrix` |
//! | N_C | admissible-velocity basis | `mobile::admissible_velocity_basis` |
//! | J | frame Jacobian | `kinematics::frame_jacobian` |
//! | J·N_C | whole-body Jacobian | `mobile::whole_body_jacobian` |

pub mod closed_form;
pub mod collision;
pub mod contact;
pub mod control;
pub mod dynamics;
pub mod error;
pub mod ik;
pub mod io;
pub mod kinematics;
pub(crate) mod linalg;
pub mod manipulability;
pub mod mission;
pub mod mobile;
pub mod motion;
pub mod multibody;
pub mod ode;
pub mod planning;
pub mod sim;
pub mod sim_config;
pub mod space;
pub mod spatial;
pub mod stability;
pub mod sweep;

pub use error::{Error, Result};

//! The simulation loop, monitors and recorders.
//!
//! The ODE integrators live one layer down in [`crate::ode`] (the chapter's closed forms
//! use them too); their types are re-exported here so `moma::sim::Rk4` and friends keep
//! working.

pub mod chapter_models;
pub mod closed_loop;
pub mod computed_torque;
pub mod contact_run;
pub mod coordinated;
pub mod feedback;
pub mod fixed_base;
pub mod free_floating;
pub mod model_mismatch;
pub mod monitor;
pub mod mpc_loop;
pub mod recorder;
pub mod reduced_system;
pub mod settings;
pub mod stability_monitor;
mod stepping;
pub mod wheeled;
pub mod wheeled_system;

#[doc(no_inline)]
pub use crate::ode::{
    AdaptiveOptions, AdaptiveRk, Dop853, DormandPrince45, EmbeddedMethod, OdeSystem, Rk4,
    StepBudget, StepStats,
};

//! Integrators, the simulation loop and recorders.
//!
//! [`integrators`] holds the generic ODE machinery: the [`OdeSystem`] trait, fixed-step
//! classical Runge–Kutta ([`Rk4`]) and adaptive embedded pairs with error control
//! ([`AdaptiveRk`]: Dormand–Prince 5(4) as [`DormandPrince45`], order-8 DOP853 as
//! [`Dop853`]), exact output at requested times, step statistics, NaN / blow-up detection
//! and a step-count guard.

pub mod chapter_models;
pub mod free_floating;
pub mod integrators;
pub mod monitor;
pub mod recorder;
pub mod scenario;
pub mod wheeled;
pub mod wheeled_system;

pub use integrators::{
    AdaptiveOptions, AdaptiveRk, Dop853, DormandPrince45, EmbeddedMethod, OdeSystem, Rk4, StepStats,
};

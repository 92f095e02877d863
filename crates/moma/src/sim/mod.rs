//! Integrators, the simulation loop and recorders.
//!
//! [`integrators`] holds the generic ODE machinery: the [`OdeSystem`] trait, fixed-step
//! classical Runge–Kutta ([`Rk4`]) and the adaptive embedded Dormand–Prince 5(4) pair
//! ([`DormandPrince45`]) with error control, output at requested times, step statistics,
//! NaN / blow-up detection and a step-count guard.

pub mod integrators;

pub use integrators::{AdaptiveOptions, DormandPrince45, OdeSystem, Rk4, StepStats};
pub mod chapter_models;
pub mod monitor;
pub mod recorder;
pub mod scenario;
pub mod wheeled;
pub mod wheeled_system;

//! The simulation loop, monitors and recorders.
//!
//! The ODE integrators live one layer down in [`crate::ode`] (the chapter's closed forms
//! use them too); their types are re-exported here so `moma::sim::Rk4` and friends keep
//! working.
//!
//! # Plants, loops and monitors
//!
//! * Plants: [`reduced_system::ReducedSystem`] is the plant interface; a URDF wheeled
//!   model ([`wheeled_system`]) or a chapter model m1/m2/m5 ([`chapter_models`]) is
//!   simulated in reduced coordinates, so C q̇ = 0 holds by construction; a fixed-base arm
//!   is [`fixed_base`]; the free-floating robot is [`free_floating`]; the contact plant of
//!   [`crate::contact`] is run with a rolling model's inputs or law by [`contact_run`],
//!   and accelerated steadily (by d'Alembert's principle, its gravity tilted) until a
//!   contact lifts by [`lift_off`], beside the tip-over limit `stability` predicts.
//! * Open loop: [`wheeled::simulate_observed`] integrates the state `[q, v, W]` (the input
//!   work integrated in the state, so [`monitor`] checks the energy balance) under the
//!   input profiles, integrator choice and step budget of [`settings`], and hands every
//!   recorded sample to a [`wheeled::SampleObserver`], which may end the run.
//!   [`stability_monitor::StabilityMonitor`] is one: it rebuilds the full multibody state
//!   (q, N_C v, N_C v̇ + Ṅ_C v) with its own copy of the wheeled model and workspace (one
//!   extra reduced forward dynamics per recorded sample, none per integrator step),
//!   evaluates [`crate::stability`] on it with the wheel set-up's support, and takes the
//!   contact loads and wheel slip from `stability::loads` and the multipliers.
//! * Closed loop: [`closed_loop::simulate_closed_loop`] drives any `ReducedSystem` with a
//!   [`closed_loop::FeedbackLaw`] sampled with a zero-order hold (or continuously);
//!   [`feedback`] binds the [`crate::control`] laws to plants: the unicycle laws and pure
//!   pursuit to wheeled URDF robots through an inner computed-torque loop on the reduced
//!   dynamics, reduced OSC to an arm on the platform, the task-space laws to m5 (whose
//!   task controller calls `control::task::pd_plus`); [`coordinated`] runs coordinated
//!   base/arm control on a wheeled URDF robot through the same inner loop (the law solved
//!   on the measured frame position and reduced Jacobian); [`mpc_law`] makes the
//!   whole-body MPC a law (computed torque of its first planned input, one
//!   [`mpc_run::MpcSample`] per solve), which [`mpc_loop`] runs at a fixed period; [`mpc_table`] is the MPC's settings table both
//!   files share (`[controller.mpc]`, `[control.mpc]`) and builds the MPC from it. A planned platform reference comes from `mission::planned`, one layer
//!   up.
//! * The plant ODE `[q, v, W]` under held inputs is [`held_input::HeldInputOde`], the one
//!   right-hand side of the open loop, the closed loop and `moma mission`. The one loop of
//!   a plant under held inputs is [`held_loop::run_held_loop`] (measure, the law's tick,
//!   advance): `simulate_closed_loop` under a control period, the contact run and the
//!   mission run on it, the plant [`rolling_plant::RollingPlant`] or
//!   [`contact_run::HeldContactPlant`]. The grid stepping and per-sample recording shared
//!   by the open- and closed-loop runs are in `stepping`; [`recorder::Recorder`] holds what the CLI's writers read.
//! * [`computed_torque::ComputedTorque`] is the one map from a desired reduced
//!   acceleration (or force) to the wheel and joint torques of a wheeled robot, used by
//!   the inner loop, OSC, the coordinated law and the mission.
//!
//! The simulator reads no file: `moma simulate`'s schema is `crate::sim_config::schema`,
//! one layer up with the rest of the scenario file.

pub mod chapter_models;
pub mod closed_loop;
pub mod computed_torque;
pub mod contact_run;
pub mod coordinated;
pub mod feedback;
pub mod fixed_base;
pub mod free_floating;
pub mod held_input;
pub mod held_loop;
pub mod lift_off;
pub mod model_mismatch;
pub mod monitor;
pub mod mpc_law;
pub mod mpc_loop;
pub mod mpc_run;
pub mod mpc_table;
pub mod recorder;
pub mod reduced_system;
pub mod rolling_plant;
pub mod sensor_noise;
pub mod settings;
pub mod stability_monitor;
pub(crate) mod stepping;
pub mod uncertainty;
pub mod wheeled;
pub mod wheeled_system;

#[doc(no_inline)]
pub use crate::ode::{
    AdaptiveOptions, AdaptiveRk, Dop853, DormandPrince45, EmbeddedMethod, OdeSystem, Rk4,
    StepBudget, StepStats,
};

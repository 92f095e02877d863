//! Feedback control: the non-holonomic laws the chapter cites (section 5.1) and the
//! task-space laws of its sections 5.4–5.5, in corrected form.
//!
//! Every law implements one small trait, [`Controller`]: it maps (time, state, reference)
//! to an actuation written into a caller-owned buffer and, where the law has a Lyapunov
//! function, reports its value `V` and its analytic rate `V̇` along the closed loop, so a
//! [`lyapunov::LyapunovMonitor`] can compare them with what the run actually does.
//!
//! | module | laws |
//! | --- | --- |
//! | [`unicycle`] | Kanayama tracking, Samson's time-varying stabiliser, Astolfi's polar law, Aicardi's Lyapunov polar law, wheel-speed and wheel-torque limits |
//! | [`pursuit`] | regulated pure pursuit (nav2's default path follower) |
//! | [`osc`] | Khatib's operational-space control with a dynamically consistent null space: fixed base, and the reduced model of a non-holonomic platform |
//! | [`task`] | the chapter's PD+ law (5.122) corrected, task-space computed torque, decoupled control (5.129–5.133) naive and compensated |
//! | [`coordinated`] | Yamamoto–Yun style coordinated base/arm control (kinematic) |
//! | [`lyapunov`] | Lyapunov monitors: V along a run, dV/dt against the analytic rate, monotonicity violations with their time |
//!
//! Layering: `control` uses `kinematics`, `dynamics` and `mobile`; it integrates nothing
//! itself (closed loops are run by `closed_form::control_cases`, which runs the unicycle
//! case schema of `moma eval` with the DOP853 driver, and by the simulator,
//! [`crate::sim::closed_loop`], whose [`crate::sim::feedback`] binds these laws to plants).
//!
//! Operational-space control keeps every buffer in an [`osc::OscData`] workspace: two
//! factorisations with the crate's one in-place Cholesky, and plain loops for the small
//! products, because nalgebra's dynamic `gemm` allocates a packing buffer. The reduced
//! variant builds `J N_C`, `N_Cᵀ H N_C` and the reduced biases from the [`crate::mobile`]
//! terms.

pub mod coordinated;
pub mod lyapunov;
pub mod mpc;
pub mod osc;
pub mod pursuit;
pub mod task;
pub mod unicycle;

use crate::error::Result;

/// A feedback law: `(t, state, reference) → actuation`, with its Lyapunov function where
/// the law has one.
///
/// The actuation is written into `out` (owned by the caller, so a law on a hot path does
/// not allocate). `lyapunov` and `lyapunov_rate` return `None` for laws without a
/// Lyapunov function (Astolfi's polar law, pure pursuit, …).
pub trait Controller {
    /// The plant state the law reads.
    type State: ?Sized;
    /// What the law tracks or stabilises to (a reference sample, a goal pose, …).
    type Reference: ?Sized;
    /// The actuation it produces (platform inputs, torques, …).
    type Actuation: ?Sized;

    /// Writes the actuation at `(t, state, reference)` into `out`.
    ///
    /// # Errors
    /// When the law is undefined at this state (a singular task Jacobian, …).
    fn actuation(
        &mut self,
        t: f64,
        state: &Self::State,
        reference: &Self::Reference,
        out: &mut Self::Actuation,
    ) -> Result<()>;

    /// The Lyapunov value `V(t, state)`, if the law has one.
    fn lyapunov(&self, _t: f64, _state: &Self::State, _reference: &Self::Reference) -> Option<f64> {
        None
    }

    /// The analytic rate `V̇` along the closed loop of this law (with its own, unsaturated
    /// actuation), if the law has a Lyapunov function.
    fn lyapunov_rate(
        &self,
        _t: f64,
        _state: &Self::State,
        _reference: &Self::Reference,
    ) -> Option<f64> {
        None
    }
}

/// `a` wrapped to (−π, π].
#[must_use]
pub fn wrap_angle(a: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    let mut r = a.rem_euclid(TAU);
    if r > PI {
        r -= TAU;
    }
    r
}

#[cfg(test)]
mod tests {
    use super::wrap_angle;
    use std::f64::consts::PI;

    #[test]
    fn wrap_is_in_half_open_interval() {
        assert_eq!(wrap_angle(PI), PI);
        assert!((wrap_angle(-PI) - PI).abs() < 1e-15);
        assert!((wrap_angle(3.0 * PI + 0.25) - (-PI + 0.25)).abs() < 1e-12);
        assert!((wrap_angle(-0.3) + 0.3).abs() < 1e-15);
    }
}

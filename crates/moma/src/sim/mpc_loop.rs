//! The whole-body MPC ([`crate::control::mpc::WholeBodyMpc`]) in closed loop on a
//! reduced-model plant ([`ReducedSystem`], a [`crate::sim::wheeled_system::WheeledSystem`]
//! of the same robot): [`run_mpc_loop`] is [`simulate_closed_loop`] with the MPC as its
//! law ([`MpcLaw`]) at a fixed control period, RK4 with a whole number of substeps per
//! period, and the run's [`MpcRun`] (one sample per solve, its summary) as the result.

use crate::control::mpc::{KnotReference, WholeBodyMpc};
use crate::error::{Error, Result};
use crate::sim::closed_loop::{ClosedLoopOptions, simulate_closed_loop};
use crate::sim::monitor::MonitorLimits;
use crate::sim::mpc_law::MpcLaw;
use crate::sim::mpc_run::MpcRun;
use crate::sim::reduced_system::ReducedSystem;
use crate::sim::settings::IntegratorSettings;

/// Settings of a closed-loop run.
#[derive(Clone, Copy, Debug)]
pub struct MpcLoopSettings {
    /// Duration (s).
    pub duration: f64,
    /// Control period (s): one solve per period, torques held over it.
    pub period: f64,
    /// RK4 steps per period.
    pub substeps: usize,
}

/// Runs `mpc` in closed loop on `plant` (the same robot) from `(q0, v0)`; `reference(t)`
/// gives the knot reference at time `t`. `mpc` ends warm, at its last solution.
///
/// # Errors
/// [`Error::Invalid`] for a non-positive duration or period, zero substeps or states of
/// the wrong length; what the solver, the closed loop or the plant report.
pub fn run_mpc_loop(
    mpc: &mut WholeBodyMpc,
    plant: &mut dyn ReducedSystem,
    q0: &[f64],
    v0: &[f64],
    settings: &MpcLoopSettings,
    reference: impl FnMut(f64) -> KnotReference,
) -> Result<MpcRun> {
    for (field, v) in [("duration", settings.duration), ("period", settings.period)] {
        if !(v > 0.0 && v.is_finite()) {
            return Err(Error::invalid(field, format!("must be positive, got {v}")));
        }
    }
    if settings.substeps == 0 {
        return Err(Error::invalid("substeps", "must be at least 1"));
    }
    let mut law = MpcLaw::new(mpc.clone(), reference);
    let options = ClosedLoopOptions {
        duration: settings.duration,
        integrator: IntegratorSettings::Rk4 {
            dt: settings.period / settings.substeps as f64,
            max_steps: None,
        },
        control_period: Some(settings.period),
        record_interval: settings.period,
        limits: MonitorLimits::default(),
        lyapunov_tolerance: 0.0,
    };
    simulate_closed_loop(plant, &mut law, q0, v0, &options, None, &mut |_| {})?;
    let (solved, run) = law.finish();
    *mpc = solved;
    Ok(run)
}

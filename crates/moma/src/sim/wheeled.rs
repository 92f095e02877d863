//! Simulation of a wheeled (Pfaffian-constrained) system in reduced coordinates.
//!
//! The state is `x = [q, v, W]`: the configuration `q`, the reduced velocity `v` with
//! `q̇ = N_C(q) v`, and the work `W = ∫ Qᵀ q̇ dt` done by the inputs, integrated along
//! with the motion so the energy balance `T + V − (T₀ + V₀) − W = 0` can be checked to
//! integrator accuracy. Because `q̇` is always `N_C v` and `C N_C = 0`, the constraint
//! `C q̇ = 0` holds by construction (to rounding), whatever the integrator.
//!
//! Any model implementing [`ReducedSystem`] can be simulated: the general wheeled URDF
//! model ([`crate::mobile::WheeledModel`]) and the chapter's closed-form models.

use crate::error::{Error, Result};
use crate::ode::{OdeSystem, StepStats};
use crate::sim::held_input::HeldInputOde;
use crate::sim::monitor::{Monitor, MonitorLimits};
use crate::sim::recorder::Recorder;
use crate::sim::reduced_system::ReducedSystem;
use crate::sim::settings::{InputProfile, IntegratorSettings};
use crate::sim::stepping::{
    Grid, check_rk4_budget, integrate_on_grid, record_plant_sample, start_recording,
    validate_run_common,
};

/// Largest number of recorded samples [`simulate`] accepts (`duration / record_interval`):
/// beyond it the recorder's buffers would exhaust memory before the first step.
pub const MAX_RECORDED_SAMPLES: f64 = 10_000_000.0;

/// Largest number of fixed RK4 steps [`simulate`] accepts (`duration / dt`) with the
/// largest step budget a scenario may set
/// ([`crate::sim::settings::MAX_STEP_BUDGET`]); the default budget,
/// [`crate::sim::settings::DEFAULT_MAX_STEPS`], is smaller.
pub const MAX_RK4_STEPS: f64 = crate::sim::settings::MAX_STEP_BUDGET as f64;

/// The ODE `ẋ = f(t, x)` of a [`ReducedSystem`] under an [`InputProfile`], state
/// `[q, v, W]`.
pub struct ReducedOde<'a, S: ReducedSystem + ?Sized> {
    system: &'a mut S,
    input: &'a InputProfile,
    u: Vec<f64>,
}

impl<'a, S: ReducedSystem + ?Sized> ReducedOde<'a, S> {
    /// Wraps `system` driven by `input` (one channel per input).
    pub fn new(system: &'a mut S, input: &'a InputProfile) -> Result<Self> {
        crate::error::ensure_len("inputs", system.nu(), input.channels.len())?;
        let nu = system.nu();
        Ok(Self {
            system,
            input,
            u: vec![0.0; nu],
        })
    }
}

impl<S: ReducedSystem + ?Sized> OdeSystem for ReducedOde<'_, S> {
    fn dim(&self) -> usize {
        self.system.nq() + self.system.nv() + 1
    }

    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<()> {
        self.input.eval(t, &mut self.u);
        HeldInputOde {
            system: &mut *self.system,
            u: &self.u,
        }
        .rhs(t, x, dx)
    }
}

/// Settings of one simulation run.
#[derive(Debug, Clone, Copy)]
pub struct SimulationOptions {
    /// Duration (s), > 0.
    pub duration: f64,
    /// Integrator.
    pub integrator: IntegratorSettings,
    /// Recording interval (s): a sample every `record_interval` (and at the end).
    pub record_interval: f64,
    /// Monitor limits.
    pub limits: MonitorLimits,
}

/// The result of a run: the recording, the monitor statistics and the integrator's.
#[derive(Debug, Clone)]
pub struct SimulationResult {
    /// The sampled trajectory.
    pub recorder: Recorder,
    /// Drift and residual statistics.
    pub monitor: Monitor,
    /// Integrator step statistics.
    pub stats: StepStats,
    /// The time of the recorded sample at which a [`SampleObserver`] stopped the run
    /// (the last sample recorded); `None` when the run reached its duration.
    pub stopped_at: Option<f64>,
}

/// Watches every recorded sample of a run (after it is recorded) and may end the run
/// there: [`SampleObserver::observe`] returns `true` to stop.
pub trait SampleObserver {
    /// Sees the sample at time `t`: configuration `q`, reduced velocity `v`, input `u`.
    ///
    /// # Errors
    /// An error ends the run with that error.
    fn observe(&mut self, t: f64, q: &[f64], v: &[f64], u: &[f64]) -> Result<bool>;
}

/// Simulates `system` from `(q0, v0)` under `input`; `progress(t)` is called after every
/// recorded sample (for progress bars).
pub fn simulate(
    system: &mut dyn ReducedSystem,
    input: &InputProfile,
    q0: &[f64],
    v0: &[f64],
    options: &SimulationOptions,
    progress: &mut dyn FnMut(f64),
) -> Result<SimulationResult> {
    simulate_observed(system, input, q0, v0, options, progress, None)
}

/// [`simulate`] with an `observer` that sees every recorded sample (t = 0 included) and
/// may stop the run there ([`SimulationResult::stopped_at`]).
pub fn simulate_observed<'a>(
    system: &mut dyn ReducedSystem,
    input: &'a InputProfile,
    q0: &[f64],
    v0: &[f64],
    options: &SimulationOptions,
    progress: &mut dyn FnMut(f64),
    observer: Option<&'a mut dyn SampleObserver>,
) -> Result<SimulationResult> {
    let n_samples = validate_run(system, input, q0, v0, options)?;
    let (nq, nv) = (system.nq(), system.nv());
    let mut x = vec![0.0; nq + nv + 1];
    x[..nq].copy_from_slice(q0);
    x[nq..nq + nv].copy_from_slice(v0);
    let mut rec = RunRecorder::new(system, input, q0, v0, options, n_samples)?;
    rec.observer = observer;
    if rec.record(system, 0.0, &x)? {
        return Ok(SimulationResult {
            recorder: rec.recorder,
            monitor: rec.monitor,
            stats: StepStats::default(),
            stopped_at: Some(0.0),
        });
    }
    // One right-hand side for the whole run: building it per step would allocate its
    // input buffer inside the step loop. `record` reaches the system through it.
    let mut ode = ReducedOde::new(system, input)?;
    let (d, ri) = (options.duration, options.record_interval);
    // RK4: the step rounded to divide the duration, a sample every `every` steps and at
    // the end; adaptive: a stop at every recording time and at the end.
    let (steps, h, every) = match options.integrator {
        IntegratorSettings::Rk4 { dt, .. } => {
            let steps = (d / dt).round().max(1.0) as usize;
            let h = d / steps as f64;
            (steps, h, ((ri / h).round() as usize).max(1))
        }
        IntegratorSettings::Adaptive { .. } => (0, 0.0, 1),
    };
    let rk4_end = |k: usize| ((k + 1) * every).min(steps) as f64 * h;
    let rk4_steps = |k: usize| every.min(steps - k * every);
    let adaptive_end = |k: usize| ((k + 1) as f64 * ri).min(d);
    let grid = match options.integrator {
        IntegratorSettings::Rk4 { .. } => Grid {
            n: steps.div_ceil(every),
            end: &rk4_end,
            rk4: Some((h, &rk4_steps)),
            switches: false,
            max_step_cap: d,
        },
        IntegratorSettings::Adaptive { .. } => {
            let mut n = ((d / ri).ceil() as usize).max(1);
            while adaptive_end(n - 1) < d {
                n += 1;
            }
            while n > 1 && adaptive_end(n - 2) >= d {
                n -= 1;
            }
            Grid {
                n,
                end: &adaptive_end,
                rk4: None,
                switches: false,
                max_step_cap: d,
            }
        }
    };
    let stats = integrate_on_grid(
        &mut ode,
        &mut x,
        options.integrator,
        &options.limits,
        grid,
        &mut |ode, _, t1, x| {
            let stop = rec.record(&mut *ode.system, t1, x)?;
            progress(t1);
            Ok(stop)
        },
    )?;
    Ok(SimulationResult {
        recorder: rec.recorder,
        monitor: rec.monitor,
        stats,
        stopped_at: rec.stopped_at,
    })
}

/// Checks the inputs of a run and its size bounds; returns the number of samples to
/// record (including t = 0).
fn validate_run(
    system: &dyn ReducedSystem,
    input: &InputProfile,
    q0: &[f64],
    v0: &[f64],
    options: &SimulationOptions,
) -> Result<usize> {
    crate::error::ensure_len("inputs", system.nu(), input.channels.len())?;
    validate_run_common(
        system,
        q0,
        v0,
        &options.integrator,
        options.duration,
        options.record_interval,
    )?;
    for (i, ch) in input.channels.iter().enumerate() {
        ch.validate(&format!("inputs[{i}]"))?;
    }
    let n_samples_f = (options.duration / options.record_interval).ceil();
    if n_samples_f > MAX_RECORDED_SAMPLES {
        return Err(Error::invalid(
            "record interval",
            format!(
                "duration / record interval = {n_samples_f:e} samples exceeds the limit of {MAX_RECORDED_SAMPLES:e}"
            ),
        ));
    }
    check_rk4_budget(&options.integrator, options.duration)?;
    Ok(n_samples_f as usize + 1)
}

/// The recorder and monitor of a run, with the buffers one sample needs.
struct RunRecorder<'a> {
    observer: Option<&'a mut dyn SampleObserver>,
    stopped_at: Option<f64>,
    recorder: Recorder,
    monitor: Monitor,
    input: &'a InputProfile,
    u: Vec<f64>,
    lam: Vec<f64>,
    nq: usize,
    nv: usize,
}

impl<'a> RunRecorder<'a> {
    fn new(
        system: &mut dyn ReducedSystem,
        input: &'a InputProfile,
        q0: &[f64],
        v0: &[f64],
        options: &SimulationOptions,
        n_samples: usize,
    ) -> Result<Self> {
        let (recorder, monitor) = start_recording(system, q0, v0, options.limits, n_samples)?;
        let nk = system.nk();
        Ok(Self {
            observer: None,
            stopped_at: None,
            recorder,
            monitor,
            input,
            u: vec![0.0; system.nu()],
            lam: vec![0.0; nk],
            nq: system.nq(),
            nv: system.nv(),
        })
    }

    /// Monitors and records the state `x = [q, v, W]` at time `t`; true when the
    /// observer stops the run here.
    fn record(&mut self, system: &mut dyn ReducedSystem, t: f64, x: &[f64]) -> Result<bool> {
        let (nq, nv) = (self.nq, self.nv);
        let (q, v) = (&x[..nq], &x[nq..nq + nv]);
        self.input.eval(t, &mut self.u);
        record_plant_sample(
            system,
            &mut self.recorder,
            &mut self.monitor,
            &mut self.lam,
            t,
            x,
            &self.u,
        )?;
        if let Some(obs) = self.observer.as_mut()
            && obs.observe(t, q, v, &self.u)?
        {
            self.stopped_at = Some(t);
            return Ok(true);
        }
        Ok(false)
    }
}

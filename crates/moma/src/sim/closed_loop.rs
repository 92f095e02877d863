//! Closed-loop simulation: a feedback law driving a [`ReducedSystem`].
//!
//! The controller is sampled with a **zero-order hold**: at every control tick
//! `t_k = k T` it reads the state `(q, v)` and writes the actuator inputs `u_k`, which are
//! held over `[t_k, t_{k+1})` while the plant is integrated (fixed-step RK4 with `dt`
//! dividing `T`, or adaptive Dormand–Prince 5(4) stopping exactly at every tick, its
//! cached derivative dropped at each switch). With no control period the law is
//! evaluated inside the right-hand side (continuous feedback), which is what an
//! exact-model test needs (the closed loop is then an ODE the integrator resolves to its
//! tolerance).
//!
//! The state is `[q, v, W]` as in [`crate::sim::wheeled`], so the energy balance of the
//! plant (`T + V − T₀ − V₀ − W`, with the held inputs' work `W`) and the constraint residual
//! are monitored as in open loop. In addition, at every recorded sample the controller
//! reports its tracking error and, when the law has one, its Lyapunov value `V` and the
//! analytic rate `V̇`; a [`LyapunovMonitor`] turns those into the run's report
//! (monotonicity violations with their time, the largest gap between the recorded `V`
//! and `V₀ + ∫ V̇`). Saturation of wheel speeds or torques is counted per tick with the
//! first time it happened.

use crate::control::lyapunov::{LyapunovMonitor, LyapunovReport};
use crate::error::{Error, Result};
use crate::ode::{OdeSystem, StepStats};
use crate::sim::held_input::HeldInputOde;
use crate::sim::held_loop::{Tick, TickEnd, TickLaw, run_held_loop};
use crate::sim::monitor::{Monitor, MonitorLimits};
use crate::sim::mpc_run::MpcRun;
use crate::sim::recorder::Recorder;
use crate::sim::reduced_system::ReducedSystem;
use crate::sim::rolling_plant::RollingPlant;
use crate::sim::sensor_noise::SensorNoise;
use crate::sim::settings::IntegratorSettings;
use crate::sim::stepping::{
    Grid, check_rk4_budget, check_rk4_steps, integrate_on_grid, record_plant_sample,
    start_recording, validate_run_common,
};
use crate::sim::wheeled::MAX_RECORDED_SAMPLES;

/// Largest number of control ticks a run accepts (`duration / control_period`).
pub const MAX_CONTROL_TICKS: f64 = 100_000_000.0;

/// What limited the command at one control tick.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SaturationFlags {
    /// A wheel-speed (or other velocity) limit scaled the command down.
    pub speed: bool,
    /// A torque limit clipped an actuator input.
    pub torque: bool,
}

/// Clips every input to `[-limit, limit]`; true when one was clipped (the torque flag of
/// [`SaturationFlags`]).
pub(crate) fn clip_inputs(u: &mut [f64], limit: f64) -> bool {
    let mut hit = false;
    for x in u.iter_mut() {
        if x.abs() > limit {
            *x = x.signum() * limit;
            hit = true;
        }
    }
    hit
}

/// What the controller reports at a recorded sample.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Observation {
    /// The Lyapunov value V, if the law has one.
    pub lyapunov: Option<f64>,
    /// The law's analytic rate V̇ at this state (with its own, unsaturated actuation).
    pub lyapunov_rate: Option<f64>,
}

/// A feedback law on a [`ReducedSystem`]: reads `(t, q, v)`, writes the actuator inputs.
pub trait FeedbackLaw {
    /// Number of inputs it writes (the plant's `nu`).
    fn nu(&self) -> usize;
    /// Names of the tracking-error components it reports (with units in brackets).
    fn error_names(&self) -> Vec<String>;
    /// Whether [`FeedbackLaw::observe`] reports a Lyapunov value.
    fn has_lyapunov(&self) -> bool;
    /// Writes the inputs `u` at `(t, q, v)` and says what saturated.
    ///
    /// # Errors
    /// When the law is undefined at this state (a singular task Jacobian, …).
    fn control(&mut self, t: f64, q: &[f64], v: &[f64], u: &mut [f64]) -> Result<SaturationFlags>;
    /// Writes the tracking error at `(t, q, v)` into `error` and returns V, V̇.
    ///
    /// # Errors
    /// As [`FeedbackLaw::control`].
    fn observe(&mut self, t: f64, q: &[f64], v: &[f64], error: &mut [f64]) -> Result<Observation>;
    /// Names (with units in brackets) of further signals the law reports at every
    /// recorded sample (e.g. the arm's manipulability); none by default.
    fn signal_names(&self) -> Vec<String> {
        Vec::new()
    }
    /// Writes the signals of [`FeedbackLaw::signal_names`] at `(t, q, v)`.
    ///
    /// # Errors
    /// As [`FeedbackLaw::control`].
    fn signals(&mut self, _t: f64, _q: &[f64], _v: &[f64], _out: &mut [f64]) -> Result<()> {
        Ok(())
    }
    /// What a law that solves a model-predictive control problem at each tick recorded:
    /// one sample per solve and their summary ([`crate::sim::mpc_law::MpcLaw`]); `None`
    /// for the other laws.
    fn mpc_run(&self) -> Option<MpcRun> {
        None
    }
}

/// Settings of a closed-loop run.
#[derive(Debug, Clone, Copy)]
pub struct ClosedLoopOptions {
    /// Duration (s), > 0.
    pub duration: f64,
    /// Plant integrator.
    pub integrator: IntegratorSettings,
    /// Control period T (s) of the zero-order hold; `None`: continuous feedback. The
    /// period is rounded so that a whole number of ticks fills the duration.
    pub control_period: Option<f64>,
    /// Recording interval (s) (rounded to a whole number of ticks under a hold).
    pub record_interval: f64,
    /// Monitor limits.
    pub limits: MonitorLimits,
    /// Increase of V between consecutive samples tolerated as round-off.
    pub lyapunov_tolerance: f64,
}

/// Saturation statistics of a run.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SaturationReport {
    /// Control evaluations.
    pub evaluations: usize,
    /// Evaluations whose velocity command was scaled down.
    pub speed: usize,
    /// Evaluations with a clipped torque.
    pub torque: usize,
    /// First time a speed limit acted.
    pub first_speed: Option<f64>,
    /// First time a torque limit acted.
    pub first_torque: Option<f64>,
}

impl SaturationReport {
    fn add(&mut self, t: f64, f: SaturationFlags) {
        self.evaluations += 1;
        if f.speed {
            self.speed += 1;
            self.first_speed.get_or_insert(t);
        }
        if f.torque {
            self.torque += 1;
            self.first_torque.get_or_insert(t);
        }
    }
}

/// The result of a closed-loop run.
#[derive(Debug, Clone)]
pub struct ClosedLoopResult {
    /// The sampled trajectory (q, v, the applied inputs u, energies, residual).
    pub recorder: Recorder,
    /// Energy-balance and residual statistics of the plant.
    pub monitor: Monitor,
    /// Integrator statistics.
    pub stats: StepStats,
    /// Names of the tracking-error components.
    pub error_names: Vec<String>,
    /// Tracking errors, one row of `error_names.len()` per sample.
    pub errors: Vec<f64>,
    /// Names of the law's further signals ([`FeedbackLaw::signal_names`]).
    pub signal_names: Vec<String>,
    /// The signals, one row of `signal_names.len()` per sample.
    pub signals: Vec<f64>,
    /// V per sample (empty when the law has no Lyapunov function).
    pub lyapunov: Vec<f64>,
    /// The law's analytic V̇ per sample (empty likewise).
    pub lyapunov_rate: Vec<f64>,
    /// The Lyapunov monitor's summary (`None` without a Lyapunov function).
    pub lyapunov_report: Option<LyapunovReport>,
    /// Saturation statistics.
    pub saturation: SaturationReport,
    /// Control ticks (evaluations of the law under a hold; right-hand-side calls when
    /// continuous).
    pub control_ticks: usize,
    /// The control period actually used (`None`: continuous).
    pub control_period: Option<f64>,
}

impl ClosedLoopResult {
    /// The tracking-error row of sample `i`.
    #[must_use]
    pub fn error_row(&self, i: usize) -> &[f64] {
        let m = self.error_names.len();
        &self.errors[i * m..(i + 1) * m]
    }

    /// The signal row of sample `i`.
    #[must_use]
    pub fn signal_row(&self, i: usize) -> &[f64] {
        let m = self.signal_names.len();
        &self.signals[i * m..(i + 1) * m]
    }
}

/// The plant ODE `[q, v, W]` under continuous feedback: the law evaluated inside the
/// right-hand side.
struct ContinuousOde<'a> {
    system: &'a mut dyn ReducedSystem,
    law: &'a mut dyn FeedbackLaw,
    u: Vec<f64>,
    saturation: SaturationReport,
}

impl OdeSystem for ContinuousOde<'_> {
    fn dim(&self) -> usize {
        self.system.nq() + self.system.nv() + 1
    }

    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<()> {
        let (nq, nv) = (self.system.nq(), self.system.nv());
        let (q, rest) = x.split_at(nq);
        let f = self.law.control(t, q, &rest[..nv], &mut self.u)?;
        self.saturation.add(t, f);
        HeldInputOde {
            system: &mut *self.system,
            u: &self.u,
        }
        .rhs(t, x, dx)
    }
}

struct Rec {
    recorder: Recorder,
    monitor: Monitor,
    lyap: Option<LyapunovMonitor>,
    errors: Vec<f64>,
    err: Vec<f64>,
    signals: Vec<f64>,
    sig: Vec<f64>,
    lambda: Vec<f64>,
    rate: Vec<f64>,
}

impl Rec {
    /// The recorder and monitors of a run of `n_samples` samples, for a law with `ne`
    /// error components, `ns` signals and (if `has_v`) a Lyapunov function.
    #[allow(clippy::too_many_arguments)]
    fn new(
        system: &mut dyn ReducedSystem,
        q0: &[f64],
        v0: &[f64],
        options: &ClosedLoopOptions,
        n_samples: usize,
        ne: usize,
        ns: usize,
        has_v: bool,
    ) -> Result<Self> {
        let (recorder, monitor) = start_recording(system, q0, v0, options.limits, n_samples)?;
        let nk = system.nk();
        Ok(Rec {
            recorder,
            monitor,
            lyap: has_v
                .then(|| LyapunovMonitor::with_capacity(n_samples, options.lyapunov_tolerance)),
            errors: Vec::with_capacity(n_samples * ne),
            err: vec![0.0; ne],
            signals: Vec::with_capacity(n_samples * ns),
            sig: vec![0.0; ns],
            lambda: vec![0.0; nk],
            rate: Vec::with_capacity(if has_v { n_samples } else { 0 }),
        })
    }

    /// Records the state `x = [q, v, W]` at `t` under the inputs `u` and what `law`
    /// observes there.
    fn record(
        &mut self,
        system: &mut dyn ReducedSystem,
        law: &mut dyn FeedbackLaw,
        u: &[f64],
        t: f64,
        x: &[f64],
    ) -> Result<()> {
        let (nq, nv) = (system.nq(), system.nv());
        let (q, v) = (&x[..nq], &x[nq..nq + nv]);
        record_plant_sample(
            system,
            &mut self.recorder,
            &mut self.monitor,
            &mut self.lambda,
            t,
            x,
            u,
        )?;
        let obs = law.observe(t, q, v, &mut self.err)?;
        self.errors.extend_from_slice(&self.err);
        if !self.sig.is_empty() {
            law.signals(t, q, v, &mut self.sig)?;
            self.signals.extend_from_slice(&self.sig);
        }
        if let (Some(m), Some(val)) = (self.lyap.as_mut(), obs.lyapunov) {
            m.record(t, val, obs.lyapunov_rate);
            self.rate.push(obs.lyapunov_rate.unwrap_or(f64::NAN));
        }
        Ok(())
    }
}

/// Runs `law` on `system` from `(q0, v0)`; `progress(t)` is called after every recorded
/// sample. Under a control period the run is the held-input loop
/// ([`crate::sim::held_loop::run_held_loop`]) on the rolling plant, the law measuring the
/// state through `noise` when given (one draw per control tick; the record, the
/// monitors, the tracking errors and the Lyapunov values keep the plant's own state);
/// with continuous feedback the law is evaluated inside the integrated right-hand side.
///
/// # Errors
/// Invalid options or initial state (named), `noise` without a control period, a run
/// that goes numerically wrong (with its time), or a law that fails at some state.
///
/// # Panics
/// If `law.nu()` differs from `system.nu()`.
pub fn simulate_closed_loop(
    system: &mut dyn ReducedSystem,
    law: &mut dyn FeedbackLaw,
    q0: &[f64],
    v0: &[f64],
    options: &ClosedLoopOptions,
    noise: Option<&mut SensorNoise>,
    progress: &mut dyn FnMut(f64),
) -> Result<ClosedLoopResult> {
    assert_eq!(
        law.nu(),
        system.nu(),
        "law and plant disagree on the inputs"
    );
    validate_run_common(
        system,
        q0,
        v0,
        &options.integrator,
        options.duration,
        options.record_interval,
    )?;
    if !(options.lyapunov_tolerance.is_finite() && options.lyapunov_tolerance >= 0.0) {
        return Err(Error::invalid(
            "lyapunov tolerance",
            "must be a finite number >= 0",
        ));
    }
    if noise.is_some() && options.control_period.is_none() {
        return Err(Error::invalid(
            "sensor noise",
            "is drawn once per control tick: it needs a control period",
        ));
    }
    let (nq, nv) = (system.nq(), system.nv());
    let grid = TickGrid::new(options)?;
    check_rk4_budget(&options.integrator, options.duration)?;
    let error_names = law.error_names();
    let signal_names = law.signal_names();
    let mut rec = Rec::new(
        system,
        q0,
        v0,
        options,
        grid.n_samples,
        error_names.len(),
        signal_names.len(),
        law.has_lyapunov(),
    )?;
    let mut x = vec![0.0; nq + nv + 1];
    x[..nq].copy_from_slice(q0);
    x[nq..nq + nv].copy_from_slice(v0);
    let run = integrate_ticks(system, law, &mut rec, x, options, &grid, noise, progress)?;
    let lyapunov_report = rec.lyap.as_ref().map(LyapunovMonitor::report);
    let lyapunov = rec
        .lyap
        .as_ref()
        .map(|m| m.values().to_vec())
        .unwrap_or_default();
    Ok(ClosedLoopResult {
        recorder: rec.recorder,
        monitor: rec.monitor,
        stats: run.stats,
        error_names,
        errors: rec.errors,
        signal_names,
        signals: rec.signals,
        lyapunov,
        lyapunov_rate: rec.rate,
        lyapunov_report,
        saturation: run.saturation,
        control_ticks: run.control_ticks,
        control_period: options.control_period.map(|_| grid.period),
    })
}

/// The segments a run is integrated over: control ticks under a hold, recording
/// intervals with continuous feedback.
struct TickGrid {
    /// Number of segments.
    ticks: usize,
    /// Segment length (s): the control period actually used, or the recording interval.
    period: f64,
    /// Segments per recorded sample.
    every: usize,
    /// Samples recorded at most.
    n_samples: usize,
}

impl TickGrid {
    /// The grid of `options`, with the tick and sample counts bounded.
    fn new(options: &ClosedLoopOptions) -> Result<Self> {
        let (ticks, period, every) = match options.control_period {
            Some(p) => {
                crate::error::ensure_positive("controller.period", p)?;
                let n = (options.duration / p).round().max(1.0);
                if n > MAX_CONTROL_TICKS {
                    return Err(Error::invalid(
                        "controller.period",
                        format!(
                            "duration / period = {n:e} ticks exceeds the limit of {MAX_CONTROL_TICKS:e}"
                        ),
                    ));
                }
                let h = options.duration / n;
                let every = (options.record_interval / h).round().max(1.0);
                (n as usize, h, every as usize)
            }
            None => {
                let n = (options.duration / options.record_interval).ceil();
                if n > MAX_RECORDED_SAMPLES {
                    return Err(Error::invalid(
                        "record interval",
                        format!(
                            "duration / record interval = {n:e} samples exceeds the limit of {MAX_RECORDED_SAMPLES:e}"
                        ),
                    ));
                }
                (n as usize, options.record_interval, 1)
            }
        };
        let n_samples = ticks / every + 2;
        if n_samples as f64 > MAX_RECORDED_SAMPLES {
            return Err(Error::invalid(
                "record interval",
                format!("{n_samples} samples exceed the limit of {MAX_RECORDED_SAMPLES:e}"),
            ));
        }
        Ok(Self {
            ticks,
            period,
            every,
            n_samples,
        })
    }
}

/// What a run's stepping gathered.
struct TickRun {
    stats: StepStats,
    saturation: SaturationReport,
    control_ticks: usize,
}

/// Integrates the loop from `x` over the tick grid (RK4: `sub` steps per segment):
/// under a hold, the held-input loop on the rolling plant (measuring through `noise`),
/// recording and sampling the law at every tick; with continuous feedback (no noise),
/// the law inside the right-hand side, recording at every segment end.
#[allow(clippy::too_many_arguments)]
fn integrate_ticks(
    system: &mut dyn ReducedSystem,
    law: &mut dyn FeedbackLaw,
    rec: &mut Rec,
    x: Vec<f64>,
    options: &ClosedLoopOptions,
    tg: &TickGrid,
    noise: Option<&mut SensorNoise>,
    progress: &mut dyn FnMut(f64),
) -> Result<TickRun> {
    let (ticks, period, every) = (tg.ticks, tg.period, tg.every);
    // RK4: `sub` steps per tick (hold) or per recording interval (continuous)
    let sub = match options.integrator {
        IntegratorSettings::Rk4 { dt, .. } => (period / dt).round().max(1.0) as usize,
        IntegratorSettings::Adaptive { .. } => 1,
    };
    // every tick takes `sub` steps (at least one, even with dt above the period)
    check_rk4_steps(&options.integrator, ticks as f64 * sub as f64)?;
    let h = period / sub as f64;
    let end = |k: usize| {
        if k + 1 == ticks {
            options.duration
        } else {
            ((k + 1) as f64 * period).min(options.duration)
        }
    };
    let steps = |_: usize| sub;
    let continuous = options.control_period.is_none();
    let grid = Grid {
        n: ticks,
        end: &end,
        rk4: Some((h, &steps)),
        switches: !continuous,
        max_step_cap: period,
    };
    if continuous {
        let nu = system.nu();
        let mut ode = ContinuousOde {
            system,
            law,
            u: vec![0.0; nu],
            saturation: SaturationReport::default(),
        };
        let mut x = x;
        // the input applied at each recorded instant
        let mut record = |ode: &mut ContinuousOde<'_>, t: f64, x: &[f64]| {
            let (nq, nv) = (ode.system.nq(), ode.system.nv());
            ode.law.control(t, &x[..nq], &x[nq..nq + nv], &mut ode.u)?;
            rec.record(&mut *ode.system, &mut *ode.law, &ode.u, t, x)
        };
        record(&mut ode, 0.0, &x)?;
        let stats = integrate_on_grid(
            &mut ode,
            &mut x,
            options.integrator,
            &options.limits,
            grid,
            &mut |ode, _, t1, x| {
                record(ode, t1, x)?;
                progress(t1);
                Ok(false)
            },
        )?;
        return Ok(TickRun {
            stats,
            control_ticks: ode.saturation.evaluations,
            saturation: ode.saturation,
        });
    }
    let mut plant = RollingPlant::new(system, x, options.integrator, &options.limits, grid)?;
    let mut tick = HoldTick {
        law,
        rec,
        saturation: SaturationReport::default(),
        ticks,
        every,
        progress,
    };
    run_held_loop(&mut plant, &mut tick, noise)?;
    Ok(TickRun {
        stats: plant.stats(),
        control_ticks: tick.saturation.evaluations,
        saturation: tick.saturation,
    })
}

/// The tick of a law under a hold: the law sampled at every tick but the last on the
/// measured state, the record (the plant's own state) at every `every`-th tick and the
/// last.
struct HoldTick<'a> {
    law: &'a mut dyn FeedbackLaw,
    rec: &'a mut Rec,
    saturation: SaturationReport,
    ticks: usize,
    every: usize,
    progress: &'a mut dyn FnMut(f64),
}

impl TickLaw<RollingPlant<'_, dyn ReducedSystem + '_>> for HoldTick<'_> {
    fn tick(
        &mut self,
        plant: &mut RollingPlant<'_, dyn ReducedSystem + '_>,
        now: &mut Tick<'_>,
    ) -> Result<TickEnd> {
        let (k, t) = (now.k, now.t);
        let last = k == self.ticks;
        if !last {
            let f = self.law.control(t, now.q, now.v, now.u)?;
            self.saturation.add(t, f);
        }
        if k == 0 || k.is_multiple_of(self.every) || last {
            self.rec
                .record(&mut *plant.system, &mut *self.law, now.u, t, &plant.x)?;
            if k > 0 {
                (self.progress)(t);
            }
        }
        Ok(if last { TickEnd::Stop } else { TickEnd::Hold })
    }

    /// The last tick only records.
    fn measures(&self, k: usize) -> bool {
        k != self.ticks
    }
}

//! The stepping loop and the per-sample bookkeeping shared by the open-loop
//! ([`crate::sim::wheeled`]) and closed-loop ([`crate::sim::closed_loop`]) runs of a
//! [`ReducedSystem`]: both integrate the state `[q, v, W]` over a grid of segment ends
//! (recording times, or control ticks), stopping there to record or to sample the law.

use crate::error::{Error, Result};
use crate::ode::{AdaptiveOptions, DormandPrince45, OdeSystem, Rk4, StepBudget, StepStats};
use crate::sim::monitor::{Monitor, MonitorLimits};
use crate::sim::recorder::{Recorder, Sample};
use crate::sim::reduced_system::ReducedSystem;
use crate::sim::settings::{DEFAULT_MAX_STEPS, IntegratorSettings, MAX_STEP_BUDGET};

/// Where a run stops: `n` segment ends `end(k)`, k = 0..n; with RK4, segment k takes
/// `steps(k)` steps of `h` from the previous end.
pub(crate) struct Grid<'a> {
    /// Number of segments.
    pub n: usize,
    /// End time of segment k.
    pub end: &'a dyn Fn(usize) -> f64,
    /// RK4: step size and steps of segment k (unused by the adaptive integrator).
    pub rk4: Option<(f64, &'a dyn Fn(usize) -> usize)>,
    /// The right-hand side changes at every segment end (a held input switched): the
    /// adaptive integrator's cached derivative is dropped there.
    pub switches: bool,
    /// Largest adaptive step (on top of the integrator's own `max_step`).
    pub max_step_cap: f64,
}

/// What happens at a segment end: `(ode, k, t_k, x)`, true to stop the run.
pub(crate) type SegmentEnd<'a, O> = dyn FnMut(&mut O, usize, f64, &[f64]) -> Result<bool> + 'a;

/// Integrates `x` over `grid` with `integrator`, calling `at_end(ode, k, t_k, x)` at every
/// segment end; stops early when it returns true. The whole run has one step budget,
/// [`IntegratorSettings::step_budget`], shared by all segments.
///
/// # Errors
/// The integrator's errors (blow-up, step-size underflow), the step budget running out
/// ([`budget_exhausted`]) and those of `at_end`.
pub(crate) fn integrate_on_grid<O: OdeSystem>(
    ode: &mut O,
    x: &mut [f64],
    integrator: IntegratorSettings,
    limits: &MonitorLimits,
    grid: Grid<'_>,
    at_end: &mut SegmentEnd<'_, O>,
) -> Result<StepStats> {
    let mut stepper = GridStepper::new(x.len(), integrator, limits, grid)?;
    while stepper.k < stepper.grid.n {
        let k = stepper.k;
        let t1 = stepper.advance(ode, x, None)?;
        if at_end(ode, k, t1, x)? {
            break;
        }
    }
    Ok(stepper.stats())
}

/// The integrator of a run over a [`Grid`], one segment at a time: fixed-step RK4 (the
/// segment's steps of `h`) or adaptive Dormand–Prince 5(4) (stopping exactly at the
/// segment's end, its cached derivative dropped there when the grid switches), with the
/// run's one step budget.
pub(crate) struct GridStepper<'g> {
    grid: Grid<'g>,
    integrator: IntegratorSettings,
    method: GridMethod,
    budget: StepBudget,
    /// The next segment.
    k: usize,
    /// The time reached (s): the end of the last segment.
    t: f64,
}

enum GridMethod {
    Rk4(Rk4),
    Adaptive(DormandPrince45),
}

impl<'g> GridStepper<'g> {
    /// The stepper of a state of `dim` components over `grid` (blow-up bound from
    /// `limits`).
    ///
    /// # Errors
    /// The adaptive integrator's options.
    ///
    /// # Panics
    /// An RK4 integrator on a grid without RK4 steps.
    pub(crate) fn new(
        dim: usize,
        integrator: IntegratorSettings,
        limits: &MonitorLimits,
        grid: Grid<'g>,
    ) -> Result<Self> {
        let method = match integrator {
            IntegratorSettings::Rk4 { .. } => {
                assert!(grid.rk4.is_some(), "RK4 grid without a step");
                let mut rk = Rk4::new(dim);
                rk.blowup = limits.blowup;
                GridMethod::Rk4(rk)
            }
            IntegratorSettings::Adaptive {
                rtol,
                atol,
                max_step,
                ..
            } => {
                let opts = AdaptiveOptions {
                    rtol,
                    atol,
                    blowup: limits.blowup,
                    max_step: max_step.unwrap_or(f64::INFINITY).min(grid.max_step_cap),
                    ..AdaptiveOptions::default()
                };
                GridMethod::Adaptive(DormandPrince45::new(dim, opts)?)
            }
        };
        Ok(Self {
            budget: StepBudget::new(integrator.step_budget()),
            grid,
            integrator,
            method,
            k: 0,
            t: 0.0,
        })
    }

    /// The time reached (s).
    pub(crate) fn time(&self) -> f64 {
        self.t
    }

    /// The integrator's statistics so far.
    pub(crate) fn stats(&self) -> StepStats {
        match &self.method {
            GridMethod::Rk4(rk) => rk.stats,
            GridMethod::Adaptive(dp) => dp.stats,
        }
    }

    /// Integrates `x` over the next segment and returns its end time. `first_stage`, when
    /// given, is `ode`'s derivative at the segment's start `(t, x)` (computed by the
    /// caller): RK4 takes it as its first step's first stage ([`Rk4::step_from_derivative`],
    /// the same step with one evaluation fewer); the adaptive integrator ignores it.
    ///
    /// # Errors
    /// The integrator's errors (blow-up, step-size underflow) and the step budget running
    /// out ([`budget_exhausted`]).
    pub(crate) fn advance<O: OdeSystem>(
        &mut self,
        ode: &mut O,
        x: &mut [f64],
        first_stage: Option<&[f64]>,
    ) -> Result<f64> {
        let (k, t0) = (self.k, self.t);
        let t1 = (self.grid.end)(k);
        match &mut self.method {
            GridMethod::Rk4(rk) => {
                let (h, steps) = self.grid.rk4.expect("RK4 grid without a step");
                let n = steps(k);
                if !self.budget.take(n) {
                    return Err(self.exhausted(t0));
                }
                for s in 0..n {
                    let t = t0 + s as f64 * h;
                    match first_stage {
                        Some(dx) if s == 0 => rk.step_from_derivative(ode, t, x, dx, h)?,
                        _ => rk.step(ode, t, x, h)?,
                    }
                }
            }
            GridMethod::Adaptive(dp) => {
                let mut t = t0;
                if !dp.integrate_to_within(ode, &mut t, x, t1, &mut self.budget)? {
                    return Err(self.exhausted(t));
                }
                if self.grid.switches {
                    dp.invalidate_derivative();
                }
            }
        }
        self.k += 1;
        self.t = t1;
        Ok(t1)
    }

    fn exhausted(&self, t: f64) -> Error {
        let duration = if self.grid.n == 0 {
            0.0
        } else {
            (self.grid.end)(self.grid.n - 1)
        };
        budget_exhausted(
            self.integrator.method_name(),
            &self.integrator,
            &self.budget,
            t,
            duration,
        )
    }
}

/// The error of a run whose step budget ran out (`method` names the integrator) at simulated time `t` of `duration`:
/// it names the integrator, the budget, the time reached and what to change.
pub(crate) fn budget_exhausted(
    method: &str,
    integrator: &IntegratorSettings,
    budget: &StepBudget,
    t: f64,
    duration: f64,
) -> Error {
    let set = budget_origin(integrator, "the default");
    let advice = match integrator {
        IntegratorSettings::Adaptive { .. } => {
            "the adaptive integrator's steps are this short when the closed loop or the \
             plant is stiff (large gains, a very light or very stiff body): such a run needs \
             the fixed-step integrator (method = \"rk4\" with a dt below its fastest time \
             constant) or smaller gains"
        }
        IntegratorSettings::Rk4 { .. } => "a larger dt or a shorter duration needs fewer steps",
    };
    Error::Numerical {
        t,
        message: format!(
            "{method}: the run's step budget of {} steps ({set}, at most {MAX_STEP_BUDGET:e}) \
             ran out at t = {t} s of {duration} s: {advice}",
            budget.limit,
        ),
    }
}

/// The checks every run of `system` makes first: initial state sizes and finiteness,
/// the integrator settings, a positive duration and recording interval.
///
/// # Errors
/// The first failing check, named.
pub(crate) fn validate_run_common(
    system: &dyn ReducedSystem,
    q0: &[f64],
    v0: &[f64],
    integrator: &IntegratorSettings,
    duration: f64,
    record_interval: f64,
) -> Result<()> {
    crate::error::ensure_len("initial q", system.nq(), q0.len())?;
    crate::error::ensure_len("initial v", system.nv(), v0.len())?;
    crate::error::ensure_finite("initial q", q0)?;
    crate::error::ensure_finite("initial v", v0)?;
    integrator.validate()?;
    crate::error::ensure_positive("duration", duration)?;
    crate::error::ensure_positive("record interval", record_interval)
}

/// Where the run's step budget comes from, for messages: the scenario's key, or
/// `default` and the key that sets it.
fn budget_origin(integrator: &IntegratorSettings, default: &str) -> String {
    if integrator.max_steps().is_some() {
        "integrator.max_steps".to_string()
    } else {
        format!("{default}; integrator.max_steps sets it")
    }
}

/// The RK4 step budget of a run, checked before it starts: `steps` fixed steps against
/// [`IntegratorSettings::step_budget`] (checked after the sample budget, so that the
/// first bound a run exceeds is named).
///
/// # Errors
/// More steps than the budget, naming `integrator.dt`.
pub(crate) fn check_rk4_steps(integrator: &IntegratorSettings, steps: f64) -> Result<()> {
    let budget = integrator.step_budget();
    if matches!(integrator, IntegratorSettings::Rk4 { .. }) && steps > budget as f64 {
        let set = budget_origin(integrator, "the default budget");
        return Err(Error::invalid(
            "integrator.dt",
            format!(
                "duration / dt = {steps:e} RK4 steps exceed the run's step budget of {budget} \
                 ({set}, at most {MAX_STEP_BUDGET:e}): a larger dt or a shorter duration \
                 needs fewer"
            ),
        ));
    }
    Ok(())
}

/// [`check_rk4_steps`] for a run of `duration / dt` steps.
///
/// # Errors
/// As [`check_rk4_steps`].
pub(crate) fn check_rk4_budget(integrator: &IntegratorSettings, duration: f64) -> Result<()> {
    if let IntegratorSettings::Rk4 { dt, .. } = integrator {
        check_rk4_steps(integrator, (duration / dt).round())?;
    }
    Ok(())
}

const _: () = assert!(DEFAULT_MAX_STEPS <= MAX_STEP_BUDGET);

/// A recorder for `system` (names, units, multiplier names) with room for `n_samples`,
/// and the energy monitor started at `(q0, v0)`.
///
/// # Errors
/// The system's energy at the initial state.
pub(crate) fn start_recording(
    system: &mut dyn ReducedSystem,
    q0: &[f64],
    v0: &[f64],
    limits: MonitorLimits,
    n_samples: usize,
) -> Result<(Recorder, Monitor)> {
    let mut recorder = Recorder::new(
        system.q_names(),
        system.v_names(),
        system.u_names(),
        n_samples,
    );
    recorder.set_units(system.q_units(), system.v_units(), system.u_units());
    recorder.lambda_names = (0..system.nk()).map(|i| format!("lambda_{i}")).collect();
    let (t0, p0) = system.energy(q0, v0)?;
    Ok((recorder, Monitor::new(limits, t0, p0)))
}

/// Monitors the state `x = [q, v, W]` at time `t` under input `u` (energy balance,
/// constraint residual) and records it with the multipliers (`lam` a buffer of `nk`).
///
/// # Errors
/// The monitor's (a blow-up or non-finite state, with its time) and the system's.
pub(crate) fn record_plant_sample(
    system: &mut dyn ReducedSystem,
    recorder: &mut Recorder,
    monitor: &mut Monitor,
    lam: &mut [f64],
    t: f64,
    x: &[f64],
    u: &[f64],
) -> Result<()> {
    let (nq, nv) = (system.nq(), system.nv());
    let (q, v) = (&x[..nq], &x[nq..nq + nv]);
    let (kin, pot) = system.energy(q, v)?;
    let res = system.constraint_residual(q, v)?;
    monitor.check(t, x, kin, pot, x[nq + nv], res)?;
    system.multipliers(q, v, u, lam)?;
    recorder.lambda.extend_from_slice(lam);
    recorder.push(Sample {
        t,
        q,
        v,
        u,
        kinetic: kin,
        potential: pot,
        work: x[nq + nv],
        residual: res,
    });
    Ok(())
}

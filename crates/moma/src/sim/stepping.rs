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
    grid: &Grid<'_>,
    at_end: &mut SegmentEnd<'_, O>,
) -> Result<StepStats> {
    let mut budget = StepBudget::new(integrator.step_budget());
    let duration = if grid.n == 0 {
        0.0
    } else {
        (grid.end)(grid.n - 1)
    };
    let exhausted = |budget: &StepBudget, t: f64| {
        budget_exhausted(integrator.method_name(), &integrator, budget, t, duration)
    };
    match integrator {
        IntegratorSettings::Rk4 { .. } => {
            let (h, steps) = grid.rk4.expect("RK4 grid without a step");
            let mut rk = Rk4::new(x.len());
            rk.blowup = limits.blowup;
            let mut t0 = 0.0;
            for k in 0..grid.n {
                if !budget.take(steps(k)) {
                    return Err(exhausted(&budget, t0));
                }
                for s in 0..steps(k) {
                    rk.step(ode, t0 + s as f64 * h, x, h)?;
                }
                let t1 = (grid.end)(k);
                if at_end(ode, k, t1, x)? {
                    break;
                }
                t0 = t1;
            }
            Ok(rk.stats)
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
            let mut dp = DormandPrince45::new(x.len(), opts)?;
            let mut t = 0.0;
            for k in 0..grid.n {
                let t1 = (grid.end)(k);
                if !dp.integrate_to_within(ode, &mut t, x, t1, &mut budget)? {
                    return Err(exhausted(&budget, t));
                }
                if at_end(ode, k, t1, x)? {
                    break;
                }
                if grid.switches {
                    dp.invalidate_derivative();
                }
            }
            Ok(dp.stats)
        }
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

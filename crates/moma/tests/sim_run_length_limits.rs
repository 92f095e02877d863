//! A simulation whose duration is absurd relative to its step or its
//! recording interval is refused up front (it used to abort on a multi-terabyte
//! allocation, or to run for ever) instead of exhausting memory or time.

use moma::sim::chapter_models::chapter_system;
use moma::sim::monitor::MonitorLimits;
use moma::sim::settings::{ChannelProfile, InputProfile, IntegratorSettings};
use moma::sim::wheeled::{SimulationOptions, simulate};
use serde_json::json;

fn run(duration: f64, dt: f64, record_interval: f64) -> moma::Result<()> {
    run_with(duration, IntegratorSettings::rk4(dt), record_interval).map(|_| ())
}

fn run_with(
    duration: f64,
    integrator: IntegratorSettings,
    record_interval: f64,
) -> moma::Result<moma::sim::StepStats> {
    let params = json!({"m": 26.44, "I": 0.358, "d": -0.134, "r_w": 0.048, "b": 0.176});
    let mut sys = chapter_system("m1", &params).unwrap();
    let input = InputProfile {
        channels: vec![
            ChannelProfile::Constant { value: 0.1 },
            ChannelProfile::Constant { value: 0.2 },
        ],
    };
    let opts = SimulationOptions {
        duration,
        integrator,
        record_interval,
        limits: MonitorLimits::default(),
    };
    simulate(
        sys.as_mut(),
        &input,
        &[0.0, 0.0, 0.0],
        &[0.0, 0.0],
        &opts,
        &mut |_| {},
    )
    .map(|r| r.stats)
}

#[test]
fn too_many_recorded_samples_is_an_error_not_an_abort() {
    let err = run(1e12, 1e3, 0.01).unwrap_err();
    assert!(matches!(err, moma::Error::InvalidInput { .. }), "{err}");
    assert!(err.to_string().contains("record interval"), "{err}");
}

#[test]
fn too_many_rk4_steps_is_an_error_not_a_hang() {
    let err = run(3.0, 1e-300, 1.0).unwrap_err();
    assert!(matches!(err, moma::Error::InvalidInput { .. }), "{err}");
    assert!(err.to_string().contains("integrator.dt"), "{err}");
}

#[test]
fn a_sane_run_still_passes() {
    run(0.1, 0.001, 0.01).unwrap();
}

/// Dormand–Prince at `tol` with a step budget of `max_steps` for the whole run.
fn adaptive(tol: f64, max_steps: Option<u64>) -> IntegratorSettings {
    IntegratorSettings::Adaptive {
        rtol: tol,
        atol: tol,
        max_step: None,
        max_steps,
    }
}

#[test]
fn the_adaptive_step_budget_bounds_the_whole_run_not_each_interval() {
    // 200 recording intervals of a step or two each
    let stats = run_with(2.0, adaptive(1e-10, None), 0.01).unwrap();
    let total = (stats.accepted + stats.rejected) as u64;
    assert!(total >= 200, "{stats:?}");
    // exactly enough
    run_with(2.0, adaptive(1e-10, Some(total)), 0.01).unwrap();
    // half of it: far more than any one interval needs, but the run as a whole stops
    let err = run_with(2.0, adaptive(1e-10, Some(total / 2)), 0.01).unwrap_err();
    let moma::Error::Numerical { t, message } = &err else {
        panic!("{err}")
    };
    assert!(*t > 0.5 && *t < 1.5, "{err}");
    for needle in [
        "Dormand-Prince 5(4)",
        &format!("step budget of {} steps", total / 2),
        "integrator.max_steps",
        "of 2 s",
        "rk4",
    ] {
        assert!(message.contains(needle), "lacks {needle}: {err}");
    }
}

#[test]
fn rk4_steps_beyond_the_budget_are_refused_before_the_run() {
    let rk4 = |max_steps| IntegratorSettings::Rk4 {
        dt: 1e-3,
        max_steps,
    };
    run_with(1.0, rk4(Some(1000)), 0.01).unwrap();
    let err = run_with(1.0, rk4(Some(999)), 0.01).unwrap_err();
    assert!(matches!(err, moma::Error::InvalidInput { .. }), "{err}");
    let msg = err.to_string();
    assert!(
        msg.contains("integrator.dt") && msg.contains("step budget of 999"),
        "{msg}"
    );
    // the default budget
    let err = run_with(
        2.0 * moma::sim::settings::DEFAULT_MAX_STEPS as f64 * 1e-3,
        rk4(None),
        1.0,
    )
    .unwrap_err();
    assert!(err.to_string().contains("the default budget"), "{err}");
}

#[test]
fn a_step_budget_outside_its_bounds_is_refused() {
    for n in [0, moma::sim::settings::MAX_STEP_BUDGET + 1] {
        let err = run_with(0.1, adaptive(1e-9, Some(n)), 0.01).unwrap_err();
        assert!(err.to_string().contains("integrator.max_steps"), "{err}");
    }
}

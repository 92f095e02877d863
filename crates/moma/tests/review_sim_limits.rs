//! Review regressions: a simulation whose duration is absurd relative to its step or its
//! recording interval is refused up front (it used to abort on a multi-terabyte
//! allocation, or to run for ever) instead of exhausting memory or time.

use moma::sim::chapter_models::chapter_system;
use moma::sim::monitor::MonitorLimits;
use moma::sim::scenario::{ChannelProfile, InputProfile, IntegratorSettings};
use moma::sim::wheeled::{SimulationOptions, simulate};
use serde_json::json;

fn run(duration: f64, dt: f64, record_interval: f64) -> moma::Result<()> {
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
        integrator: IntegratorSettings::Rk4 { dt },
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
    .map(|_| ())
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

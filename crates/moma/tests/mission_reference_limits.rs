//! The mission's timed reference keeps the platform limits on every sample of every plan,
//! re-plans included: a re-plan made while driving at speed onto a path that turns
//! sooner than that speed allows starts at the fastest speed it admits (the robot brakes
//! onto it) rather than at the current speed, which would break ω_max while braking (it reached
//! 1.218 rad/s with ω_max = 1 on the shipped mission before).

use std::path::Path;

use moma::mission::{load, run};

#[test]
fn every_reference_sample_of_the_shipped_missions_keeps_the_limits() {
    let scenarios = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios");
    for name in ["mission.toml", "mission_offset.toml"] {
        let m = load(&scenarios.join(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        let r = run(&m).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert!(
            r.replans() >= 1,
            "{name}: the obstacle should force a re-plan"
        );
        let l = &m.file.limits;
        let s = &r.samples;
        let worst_w = s.omega_ref.iter().fold(0.0f64, |a, w| a.max(w.abs()));
        let worst_v = s.v_ref.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        assert!(
            worst_w <= l.omega_max * (1.0 + 1e-9),
            "{name}: reference turn rate {worst_w} rad/s > omega_max = {}",
            l.omega_max
        );
        assert!(
            worst_v <= l.v_max * (1.0 + 1e-9),
            "{name}: reference speed {worst_v} m/s > v_max = {}",
            l.v_max
        );
    }
}

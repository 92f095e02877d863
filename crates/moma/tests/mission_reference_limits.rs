//! The mission's timed reference keeps the platform limits on every sample of every plan,
//! re-plans included, and the base follows it closely. A re-plan made while driving at
//! speed onto a path that does not admit that speed at its start used to brake onto the
//! new path past ω_max (1.218 rad/s with ω_max = 1 on the shipped mission, with a 1.3 cm
//! tracking error); the base now brakes to rest along the old path and then follows a
//! path planned from where it stopped.

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
        // the reference speed is continuous, braking and speeding up within a_max (the
        // recorded samples are a fixed time apart; the reference is linear between its
        // own samples, so a finite difference bounds its acceleration)
        for (k, w) in s.t.windows(2).enumerate() {
            let a = (s.v_ref[k + 1] - s.v_ref[k]) / (w[1] - w[0]);
            assert!(
                a.abs() <= l.a_max * (1.0 + 1e-6),
                "{name}: the reference speed changes at {a} m/s² at t = {} s (a_max = {})",
                w[0],
                l.a_max
            );
        }
        let e = r.max_tracking_error().unwrap();
        assert!(e < 0.005, "{name}: tracking error {e} m");
    }
}

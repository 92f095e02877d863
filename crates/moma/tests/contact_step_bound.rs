//! The stable-step bound of the contact's spring-damper for a soft, damped contact, where
//! its closed form used to cancel to zero and refuse every step.

use moma::contact::spring_damper_step_bound;

/// |x| after 20 000 steps of semi-implicit Euler on `m ẍ = −k x − c ẋ` from x = 1.
fn spring_damper(k: f64, c: f64, m: f64, dt: f64) -> f64 {
    let (mut x, mut v) = (1.0f64, 0.0f64);
    for _ in 0..20_000 {
        v += dt * (-k * x - c * v) / m;
        x += dt * v;
    }
    x.abs()
}

#[test]
fn a_soft_damped_contact_keeps_its_bound() {
    // k = 1e-12 N/m, c = 2000 N·s/m, m = 7.9 kg: ζ ≈ 3.6e8, where √(1 + ζ²) − ζ
    // cancelled to 0. The bound is then the damping's own, dt < 2m/c: the step is
    // stable just below it and unstable just above.
    let (k, c, m) = (1e-12, 2e3, 7.9);
    let b = spring_damper_step_bound(k, c, m);
    assert!((b - 2.0 * m / c).abs() < 1e-9 * b, "{b} vs {}", 2.0 * m / c);
    assert!(spring_damper(k, c, m, 0.98 * b) <= 1.0);
    let above = spring_damper(k, c, m, 1.02 * b);
    assert!(above.is_nan() || above > 1e3, "{above}");
    // A damping of 1e300 N·s/m: a positive (tiny) bound, not 0 or NaN.
    let b = spring_damper_step_bound(1e5, 1e300, 7.9);
    assert!(b > 0.0 && b < 1e-290, "{b}");
}

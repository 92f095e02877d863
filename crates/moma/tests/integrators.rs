//! Integrator tests: RK4 order, Dormand–Prince 5(4) accuracy against closed-form
//! solutions, step statistics, NaN / blow-up detection, the step-count guard and error
//! propagation from the right-hand side.

use moma::Error;
use moma::ode::{AdaptiveOptions, DormandPrince45, OdeSystem, Rk4};

/// Harmonic oscillator ẍ = −ω² x; x(t) = cos ωt, ẋ = −ω sin ωt.
struct Oscillator {
    omega: f64,
}
impl OdeSystem for Oscillator {
    fn dim(&self) -> usize {
        2
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> moma::Result<()> {
        dx[0] = x[1];
        dx[1] = -self.omega * self.omega * x[0];
        Ok(())
    }
}

/// Time-dependent scalar ODE ẋ = x cos t; x(t) = exp(sin t).
struct ExpSin;
impl OdeSystem for ExpSin {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> moma::Result<()> {
        dx[0] = x[0] * t.cos();
        Ok(())
    }
}

/// ẋ = x², blows up at t = 1 from x(0) = 1.
struct Riccati;
impl OdeSystem for Riccati {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> moma::Result<()> {
        dx[0] = x[0] * x[0];
        Ok(())
    }
}

/// Fails with a singular error once t > 0.5.
struct FailsLater;
impl OdeSystem for FailsLater {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, _x: &[f64], dx: &mut [f64]) -> moma::Result<()> {
        if t > 0.5 {
            return Err(Error::Singular {
                what: "test matrix".into(),
                detail: None,
            });
        }
        dx[0] = 1.0;
        Ok(())
    }
}

fn rk4_error(steps: usize) -> f64 {
    let mut rk = Rk4::new(1);
    let mut x = [1.0];
    rk.integrate(&mut ExpSin, 0.0, &mut x, 2.0, steps).unwrap();
    (x[0] - 2f64.sin().exp()).abs()
}

#[test]
fn rk4_is_fourth_order() {
    let (e1, e2, e3) = (rk4_error(20), rk4_error(40), rk4_error(80));
    let (r1, r2) = (e1 / e2, e2 / e3);
    assert!((14.0..18.0).contains(&r1), "ratio {r1}");
    assert!((14.0..18.0).contains(&r2), "ratio {r2}");
}

#[test]
fn rk4_counts_steps_and_evaluations() {
    let mut rk = Rk4::new(2);
    let mut x = [1.0, 0.0];
    rk.integrate(&mut Oscillator { omega: 2.0 }, 0.0, &mut x, 1.0, 1000)
        .unwrap();
    assert_eq!(rk.stats.accepted, 1000);
    assert_eq!(rk.stats.rhs_evals, 4000);
    assert!((x[0] - 2f64.cos()).abs() < 1e-11);
}

#[test]
fn dormand_prince_meets_tolerance_on_known_solutions() {
    for tol in [1e-6, 1e-9, 1e-12] {
        let mut dp = DormandPrince45::new(2, AdaptiveOptions::with_tolerance(tol)).unwrap();
        let times: Vec<f64> = (1..=10).map(|k| k as f64).collect();
        let omega = 3.0;
        let out = dp
            .solve_at(&mut Oscillator { omega }, 0.0, &[1.0, 0.0], &times)
            .unwrap();
        for (t, row) in times.iter().zip(&out) {
            let err =
                (row[0] - (omega * t).cos()).abs() + (row[1] + omega * (omega * t).sin()).abs();
            // global error stays within a modest multiple of the local tolerance
            assert!(err < 200.0 * tol, "tol {tol}: t = {t}, error {err:e}");
        }
        assert!(dp.stats.accepted > 0);
        assert!(dp.stats.rhs_evals >= 6 * dp.stats.accepted);
    }
    let mut dp = DormandPrince45::new(1, AdaptiveOptions::with_tolerance(1e-12)).unwrap();
    let out = dp
        .solve_at(&mut ExpSin, 0.0, &[1.0], &[0.3, 1.0, 5.0])
        .unwrap();
    for (t, row) in [0.3f64, 1.0, 5.0].iter().zip(&out) {
        assert!((row[0] - t.sin().exp()).abs() < 1e-11);
    }
}

#[test]
fn dormand_prince_fewer_steps_at_looser_tolerance() {
    let steps = |tol: f64| {
        let mut dp = DormandPrince45::new(2, AdaptiveOptions::with_tolerance(tol)).unwrap();
        dp.solve_at(&mut Oscillator { omega: 1.0 }, 0.0, &[1.0, 0.0], &[10.0])
            .unwrap();
        dp.stats.accepted
    };
    let (a, b) = (steps(1e-6), steps(1e-11));
    // fifth order: 10^5 tighter tolerance ≈ 10× more steps
    assert!(b > 5 * a && b < 20 * a, "{a} vs {b}");
}

#[test]
fn blow_up_is_reported_with_time() {
    let mut dp = DormandPrince45::new(1, AdaptiveOptions::with_tolerance(1e-9)).unwrap();
    match dp.solve_at(&mut Riccati, 0.0, &[1.0], &[2.0]) {
        Err(Error::Numerical { t, .. }) => assert!(t > 0.9 && t <= 1.0, "t = {t}"),
        other => panic!("expected a numerical error, got {other:?}"),
    }
    let mut rk = Rk4::new(1);
    let mut x = [1.0];
    assert!(matches!(
        rk.integrate(&mut Riccati, 0.0, &mut x, 2.0, 100),
        Err(Error::Numerical { .. })
    ));
}

#[test]
fn nan_state_is_rejected() {
    let mut dp = DormandPrince45::new(2, AdaptiveOptions::default()).unwrap();
    let r = dp.solve_at(
        &mut Oscillator { omega: 1.0 },
        0.0,
        &[f64::NAN, 0.0],
        &[1.0],
    );
    assert!(matches!(r, Err(Error::Numerical { .. })));
}

#[test]
fn step_count_guard_and_rhs_errors_propagate() {
    let opts = AdaptiveOptions {
        max_steps: 5,
        ..AdaptiveOptions::with_tolerance(1e-12)
    };
    let mut dp = DormandPrince45::new(2, opts).unwrap();
    let r = dp.solve_at(&mut Oscillator { omega: 10.0 }, 0.0, &[1.0, 0.0], &[100.0]);
    assert!(matches!(r, Err(Error::Numerical { .. })));
    let mut dp = DormandPrince45::new(1, AdaptiveOptions::default()).unwrap();
    assert!(matches!(
        dp.solve_at(&mut FailsLater, 0.0, &[0.0], &[1.0]),
        Err(Error::Singular { .. })
    ));
}

#[test]
fn invalid_options_and_times_are_rejected() {
    assert!(DormandPrince45::new(1, AdaptiveOptions::with_tolerance(-1.0)).is_err());
    assert!(
        DormandPrince45::new(
            1,
            AdaptiveOptions {
                rtol: f64::NAN,
                ..Default::default()
            }
        )
        .is_err()
    );
    let mut dp = DormandPrince45::new(1, AdaptiveOptions::default()).unwrap();
    assert!(dp.solve_at(&mut ExpSin, 0.0, &[1.0], &[1.0, 0.5]).is_err());
    // wrong state length
    assert!(matches!(
        dp.solve_at(&mut ExpSin, 0.0, &[1.0, 2.0], &[1.0]),
        Err(Error::WrongLength { .. })
    ));
    let mut rk = Rk4::new(1);
    assert!(rk.integrate(&mut ExpSin, 0.0, &mut [1.0], 1.0, 0).is_err());
}

#[test]
fn dop853_meets_tolerance_with_fewer_steps_than_dp45() {
    use moma::ode::Dop853;
    let times: Vec<f64> = (1..=10).map(|k| k as f64).collect();
    let omega = 3.0;
    for tol in [1e-6, 1e-9, 1e-12] {
        let mut d8 = Dop853::new(2, AdaptiveOptions::with_tolerance(tol)).unwrap();
        let out = d8
            .solve_at(&mut Oscillator { omega }, 0.0, &[1.0, 0.0], &times)
            .unwrap();
        for (t, row) in times.iter().zip(&out) {
            let err =
                (row[0] - (omega * t).cos()).abs() + (row[1] + omega * (omega * t).sin()).abs();
            assert!(err < 200.0 * tol, "tol {tol}: t = {t}, error {err:e}");
        }
        let mut d5 = DormandPrince45::new(2, AdaptiveOptions::with_tolerance(tol)).unwrap();
        d5.solve_at(&mut Oscillator { omega }, 0.0, &[1.0, 0.0], &times)
            .unwrap();
        if tol <= 1e-9 {
            assert!(
                d8.stats.accepted * 2 < d5.stats.accepted,
                "{} vs {}",
                d8.stats.accepted,
                d5.stats.accepted
            );
        }
        assert!(d8.stats.rhs_evals >= 12 * d8.stats.accepted);
    }
    let mut d8 = Dop853::new(1, AdaptiveOptions::with_tolerance(1e-13)).unwrap();
    let out = d8
        .solve_at(&mut ExpSin, 0.0, &[1.0], &[0.3, 1.0, 5.0])
        .unwrap();
    for (t, row) in [0.3f64, 1.0, 5.0].iter().zip(&out) {
        assert!((row[0] - t.sin().exp()).abs() < 1e-12);
    }
    // blow-up and the step guard work the same way
    let mut d8 = Dop853::new(1, AdaptiveOptions::with_tolerance(1e-9)).unwrap();
    assert!(matches!(
        d8.solve_at(&mut Riccati, 0.0, &[1.0], &[2.0]),
        Err(Error::Numerical { .. })
    ));
}

/// Local error of one DOP853 step scales like h⁹ (8th-order method).
#[test]
fn dop853_is_eighth_order() {
    use moma::ode::Dop853;
    let err = |h: f64| {
        // a single forced step of size h: max_step = h, loose tolerance so it is accepted
        let opts = AdaptiveOptions {
            initial_step: Some(h),
            max_step: h,
            ..AdaptiveOptions::with_tolerance(1.0)
        };
        let mut d8 = Dop853::new(1, opts).unwrap();
        let out = d8.solve_at(&mut ExpSin, 0.0, &[1.0], &[8.0 * h]).unwrap();
        assert_eq!(d8.stats.accepted, 8);
        (out[0][0] - (8.0 * h).sin().exp()).abs()
    };
    let (e1, e2) = (err(0.2), err(0.1));
    let ratio = e1 / e2;
    // global error of an order-8 method: ratio 2^8 = 256 on halving h
    assert!(
        ratio > 150.0 && ratio < 400.0,
        "ratio {ratio} ({e1:e}, {e2:e})"
    );
}

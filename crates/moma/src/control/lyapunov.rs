//! Lyapunov monitors: record `V` (and the law's analytic `V̇`) along a closed-loop run,
//! compare the derivative the run actually shows with the analytic one, and report
//! violations of monotonicity with their time (e.g. under torque saturation, where the
//! law's `V̇ ≤ 0` argument no longer applies).
//!
//! The monitor only stores samples; it is fed by whoever runs the loop (the case
//! evaluator, the simulator, a test). No allocation after [`LyapunovMonitor::with_capacity`]
//! as long as the capacity is not exceeded.

/// One violation of `V(t_k) ≤ V(t_{k−1}) + tolerance`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Violation {
    /// Time of the sample where V rose.
    pub t: f64,
    /// How much V rose over the previous sample.
    pub increase: f64,
}

/// A summary of a monitored run.
#[derive(Clone, Debug, PartialEq)]
pub struct LyapunovReport {
    /// Number of samples.
    pub samples: usize,
    /// `V` at the first and the last sample.
    pub v_first: f64,
    /// `V` at the last sample.
    pub v_last: f64,
    /// Every time V increased by more than the tolerance.
    pub violations: Vec<Violation>,
    /// Largest |V(t_k) − V(t_0) − ∫ V̇_analytic dt| (trapezoidal rule on the samples),
    /// `None` when no analytic rate was recorded.
    pub max_integral_error: Option<f64>,
    /// Largest |central difference of V − V̇_analytic| at interior samples.
    pub max_rate_error: Option<f64>,
}

impl LyapunovReport {
    /// Whether V never rose by more than the tolerance.
    #[must_use]
    pub fn monotone(&self) -> bool {
        self.violations.is_empty()
    }
}

/// Records `(t, V, V̇_analytic)` along a run.
#[derive(Clone, Debug, Default)]
pub struct LyapunovMonitor {
    t: Vec<f64>,
    v: Vec<f64>,
    rate: Vec<f64>,
    has_rate: bool,
    /// Increase of V between consecutive samples tolerated as round-off.
    pub tolerance: f64,
}

impl LyapunovMonitor {
    /// An empty monitor for up to `n` samples, tolerating increases up to `tolerance`.
    #[must_use]
    pub fn with_capacity(n: usize, tolerance: f64) -> Self {
        Self {
            t: Vec::with_capacity(n),
            v: Vec::with_capacity(n),
            rate: Vec::with_capacity(n),
            has_rate: true,
            tolerance,
        }
    }

    /// Records a sample. `rate` is the law's analytic V̇ (if any sample lacks it, the
    /// derivative comparison is skipped).
    pub fn record(&mut self, t: f64, v: f64, rate: Option<f64>) {
        self.t.push(t);
        self.v.push(v);
        match rate {
            Some(r) => self.rate.push(r),
            None => {
                self.has_rate = false;
                self.rate.push(f64::NAN);
            }
        }
    }

    /// The recorded V values.
    #[must_use]
    pub fn values(&self) -> &[f64] {
        &self.v
    }

    /// The recorded times.
    #[must_use]
    pub fn times(&self) -> &[f64] {
        &self.t
    }

    /// The summary of what was recorded.
    #[must_use]
    pub fn report(&self) -> LyapunovReport {
        let n = self.t.len();
        let mut violations = Vec::new();
        for k in 1..n {
            let inc = self.v[k] - self.v[k - 1];
            if inc > self.tolerance {
                violations.push(Violation {
                    t: self.t[k],
                    increase: inc,
                });
            }
        }
        let (mut ie, mut re) = (None, None);
        if self.has_rate && n >= 2 {
            let mut integral = 0.0;
            let mut worst = 0.0f64;
            for k in 1..n {
                integral += 0.5 * (self.t[k] - self.t[k - 1]) * (self.rate[k] + self.rate[k - 1]);
                worst = worst.max((self.v[k] - self.v[0] - integral).abs());
            }
            ie = Some(worst);
            let mut worst = 0.0f64;
            for k in 1..n.saturating_sub(1) {
                let dt = self.t[k + 1] - self.t[k - 1];
                if dt > 0.0 {
                    let d = (self.v[k + 1] - self.v[k - 1]) / dt;
                    worst = worst.max((d - self.rate[k]).abs());
                }
            }
            if n >= 3 {
                re = Some(worst);
            }
        }
        LyapunovReport {
            samples: n,
            v_first: self.v.first().copied().unwrap_or(f64::NAN),
            v_last: self.v.last().copied().unwrap_or(f64::NAN),
            violations,
            max_integral_error: ie,
            max_rate_error: re,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_exponential_has_no_violation_and_matching_rate() {
        let mut m = LyapunovMonitor::with_capacity(1001, 1e-12);
        for k in 0..=1000 {
            let t = 0.005 * f64::from(k);
            m.record(t, (-t).exp(), Some(-(-t).exp()));
        }
        let r = m.report();
        assert!(r.monotone());
        assert!(r.max_integral_error.unwrap() < 1e-5);
        assert!(r.max_rate_error.unwrap() < 1e-5);
    }

    #[test]
    fn reports_the_time_of_an_increase() {
        let mut m = LyapunovMonitor::with_capacity(4, 0.0);
        for (t, v) in [(0.0, 3.0), (1.0, 2.0), (2.0, 2.5), (3.0, 1.0)] {
            m.record(t, v, None);
        }
        let r = m.report();
        assert_eq!(r.violations.len(), 1);
        assert_eq!(r.violations[0].t, 2.0);
        assert!((r.violations[0].increase - 0.5).abs() < 1e-15);
        assert!(r.max_rate_error.is_none());
    }
}

//! ODE integrators: fixed-step RK4 and adaptive Dormand–Prince 5(4).
//!
//! Both work on any [`OdeSystem`] `ẋ = f(t, x)` of dimension `n`, allocate their stage
//! buffers once (in `new`) and never per step. The right-hand side returns a
//! [`Result`], so a singular mass matrix or other numerical trouble inside `f` stops the
//! integration with that error. Non-finite states and states whose magnitude exceeds
//! [`AdaptiveOptions::blowup`] are reported as [`Error::Numerical`] with the time.

use crate::error::{Error, Result};

/// A first-order ODE system `ẋ = f(t, x)`.
pub trait OdeSystem {
    /// The state dimension `n`.
    fn dim(&self) -> usize;
    /// Writes `f(t, x)` into `dx` (both of length [`OdeSystem::dim`]).
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<()>;
}

/// Step statistics of an integrator (cumulative since creation or the last reset).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepStats {
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected steps (adaptive integrators only).
    pub rejected: usize,
    /// Right-hand-side evaluations.
    pub rhs_evals: usize,
}

fn check_state(t: f64, x: &[f64], blowup: f64) -> Result<()> {
    for (i, xi) in x.iter().enumerate() {
        if !xi.is_finite() {
            return Err(Error::Numerical {
                t,
                message: format!("state component {i} is not finite"),
            });
        }
        if xi.abs() > blowup {
            return Err(Error::Numerical {
                t,
                message: format!(
                    "state component {i} = {xi:e} exceeds the blow-up bound {blowup:e}"
                ),
            });
        }
    }
    Ok(())
}

fn check_dim(sys: &impl OdeSystem, n: usize, x: &[f64]) -> Result<()> {
    if sys.dim() != n || x.len() != n {
        return Err(Error::WrongLength {
            field: "ODE state".into(),
            expected: n,
            got: if sys.dim() != n { sys.dim() } else { x.len() },
        });
    }
    Ok(())
}

/// Classical fourth-order Runge–Kutta with a fixed step.
#[doc(alias = "RK4")]
#[derive(Clone, Debug)]
pub struct Rk4 {
    k1: Vec<f64>,
    k2: Vec<f64>,
    k3: Vec<f64>,
    k4: Vec<f64>,
    tmp: Vec<f64>,
    /// Blow-up bound on |x_i| (default 1e12).
    pub blowup: f64,
    /// Statistics.
    pub stats: StepStats,
}

impl Rk4 {
    /// Allocates the stage buffers for a system of dimension `n`.
    pub fn new(n: usize) -> Self {
        Rk4 {
            k1: vec![0.0; n],
            k2: vec![0.0; n],
            k3: vec![0.0; n],
            k4: vec![0.0; n],
            tmp: vec![0.0; n],
            blowup: 1e12,
            stats: StepStats::default(),
        }
    }

    /// One step of size `h` from `(t, x)`; `x` is overwritten with the state at `t + h`.
    pub fn step<S: OdeSystem>(&mut self, sys: &mut S, t: f64, x: &mut [f64], h: f64) -> Result<()> {
        let n = self.k1.len();
        check_dim(sys, n, x)?;
        sys.rhs(t, x, &mut self.k1)?;
        for i in 0..n {
            self.tmp[i] = x[i] + 0.5 * h * self.k1[i];
        }
        sys.rhs(t + 0.5 * h, &self.tmp, &mut self.k2)?;
        for i in 0..n {
            self.tmp[i] = x[i] + 0.5 * h * self.k2[i];
        }
        sys.rhs(t + 0.5 * h, &self.tmp, &mut self.k3)?;
        for i in 0..n {
            self.tmp[i] = x[i] + h * self.k3[i];
        }
        sys.rhs(t + h, &self.tmp, &mut self.k4)?;
        for i in 0..n {
            x[i] += h / 6.0 * (self.k1[i] + 2.0 * self.k2[i] + 2.0 * self.k3[i] + self.k4[i]);
        }
        self.stats.accepted += 1;
        self.stats.rhs_evals += 4;
        check_state(t + h, x, self.blowup)
    }

    /// Integrates from `t0` to `t1` with `steps` equal steps, overwriting `x`.
    pub fn integrate<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t0: f64,
        x: &mut [f64],
        t1: f64,
        steps: usize,
    ) -> Result<()> {
        if steps == 0 || !(t1 - t0).is_finite() {
            return Err(Error::invalid(
                "RK4 steps",
                "need at least one step over a finite interval",
            ));
        }
        let h = (t1 - t0) / steps as f64;
        for s in 0..steps {
            self.step(sys, t0 + s as f64 * h, x, h)?;
        }
        Ok(())
    }
}

/// Error-control settings of the adaptive integrator.
#[derive(Clone, Copy, Debug)]
pub struct AdaptiveOptions {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance.
    pub atol: f64,
    /// First step size; `None` picks it automatically (Hairer's heuristic).
    pub initial_step: Option<f64>,
    /// Largest step allowed.
    pub max_step: f64,
    /// Maximum number of steps (accepted + rejected) per call of `integrate_to`.
    pub max_steps: usize,
    /// Blow-up bound on |x_i|.
    pub blowup: f64,
}

impl Default for AdaptiveOptions {
    fn default() -> Self {
        AdaptiveOptions {
            rtol: 1e-9,
            atol: 1e-9,
            initial_step: None,
            max_step: f64::INFINITY,
            max_steps: 1_000_000,
            blowup: 1e12,
        }
    }
}

impl AdaptiveOptions {
    /// Options with `rtol = atol = tol`.
    pub fn with_tolerance(tol: f64) -> Self {
        AdaptiveOptions {
            rtol: tol,
            atol: tol,
            ..Default::default()
        }
    }

    fn validate(&self) -> Result<()> {
        if !(self.rtol > 0.0 && self.rtol.is_finite()) {
            return Err(Error::invalid("rtol", "must be positive and finite"));
        }
        if !(self.atol > 0.0 && self.atol.is_finite()) {
            return Err(Error::invalid("atol", "must be positive and finite"));
        }
        if !(self.max_step > 0.0) {
            return Err(Error::invalid("max_step", "must be positive"));
        }
        if let Some(h) = self.initial_step
            && !(h > 0.0 && h.is_finite())
        {
            return Err(Error::invalid(
                "initial_step",
                "must be positive and finite",
            ));
        }
        Ok(())
    }
}

// Dormand–Prince 5(4) tableau (Dormand & Prince 1980; Hairer, Nørsett & Wanner, table 5.2).
const C2: f64 = 1.0 / 5.0;
const C3: f64 = 3.0 / 10.0;
const C4: f64 = 4.0 / 5.0;
const C5: f64 = 8.0 / 9.0;
const A21: f64 = 1.0 / 5.0;
const A31: f64 = 3.0 / 40.0;
const A32: f64 = 9.0 / 40.0;
const A41: f64 = 44.0 / 45.0;
const A42: f64 = -56.0 / 15.0;
const A43: f64 = 32.0 / 9.0;
const A51: f64 = 19372.0 / 6561.0;
const A52: f64 = -25360.0 / 2187.0;
const A53: f64 = 64448.0 / 6561.0;
const A54: f64 = -212.0 / 729.0;
const A61: f64 = 9017.0 / 3168.0;
const A62: f64 = -355.0 / 33.0;
const A63: f64 = 46732.0 / 5247.0;
const A64: f64 = 49.0 / 176.0;
const A65: f64 = -5103.0 / 18656.0;
const B1: f64 = 35.0 / 384.0;
const B3: f64 = 500.0 / 1113.0;
const B4: f64 = 125.0 / 192.0;
const B5: f64 = -2187.0 / 6784.0;
const B6: f64 = 11.0 / 84.0;
// E = b(5th) − b̂(4th)
const E1: f64 = 71.0 / 57600.0;
const E3: f64 = -71.0 / 16695.0;
const E4: f64 = 71.0 / 1920.0;
const E5: f64 = -17253.0 / 339200.0;
const E6: f64 = 22.0 / 525.0;
const E7: f64 = -1.0 / 40.0;

/// Adaptive embedded Runge–Kutta pair of Dormand and Prince, order 5(4), with local
/// extrapolation (the 5th-order solution is propagated), FSAL, and step-size control on
/// the RMS norm of the error scaled by `atol + rtol·max(|x|, |x_new|)`.
///
/// Output at requested times is exact (steps are shortened to land on them), so no
/// interpolation error is added.
#[doc(alias = "DOPRI5")]
#[doc(alias = "RK45")]
#[derive(Clone, Debug)]
pub struct DormandPrince45 {
    /// Error-control settings.
    pub options: AdaptiveOptions,
    k: [Vec<f64>; 7],
    y1: Vec<f64>,
    tmp: Vec<f64>,
    h: Option<f64>,
    fsal_valid: bool,
    /// Statistics.
    pub stats: StepStats,
}

impl DormandPrince45 {
    /// Allocates the buffers for dimension `n` with the given options.
    pub fn new(n: usize, options: AdaptiveOptions) -> Result<Self> {
        options.validate()?;
        Ok(DormandPrince45 {
            options,
            k: std::array::from_fn(|_| vec![0.0; n]),
            y1: vec![0.0; n],
            tmp: vec![0.0; n],
            h: options.initial_step,
            fsal_valid: false,
            stats: StepStats::default(),
        })
    }

    /// Forgets the step-size history (call before integrating a new, unrelated problem).
    pub fn reset(&mut self) {
        self.h = self.options.initial_step;
        self.fsal_valid = false;
        self.stats = StepStats::default();
    }

    /// The step size the controller proposes next (if any step was taken).
    pub fn next_step(&self) -> Option<f64> {
        self.h
    }

    fn scale(&self, a: f64, b: f64) -> f64 {
        self.options.atol + self.options.rtol * a.abs().max(b.abs())
    }

    fn initial_step<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: f64,
        x: &[f64],
        span: f64,
    ) -> Result<f64> {
        let n = x.len();
        let (mut d0, mut d1) = (0.0, 0.0);
        for i in 0..n {
            let sc = self.scale(x[i], x[i]);
            d0 += (x[i] / sc).powi(2);
            d1 += (self.k[0][i] / sc).powi(2);
        }
        let nf = n.max(1) as f64;
        let (d0, d1) = ((d0 / nf).sqrt(), (d1 / nf).sqrt());
        let h0 = if d0 < 1e-5 || d1 < 1e-5 {
            1e-6
        } else {
            0.01 * d0 / d1
        };
        let h0 = h0.min(span).min(self.options.max_step);
        for i in 0..n {
            self.tmp[i] = x[i] + h0 * self.k[0][i];
        }
        sys.rhs(t + h0, &self.tmp, &mut self.k[1])?;
        self.stats.rhs_evals += 1;
        let mut d2 = 0.0;
        for i in 0..n {
            let sc = self.scale(x[i], x[i]);
            d2 += ((self.k[1][i] - self.k[0][i]) / sc).powi(2);
        }
        let d2 = (d2 / nf).sqrt() / h0;
        let h1 = if d1.max(d2) <= 1e-15 {
            (h0 * 1e-3).max(1e-6)
        } else {
            (0.01 / d1.max(d2)).powf(1.0 / 5.0)
        };
        Ok((100.0 * h0).min(h1).min(span).min(self.options.max_step))
    }

    /// Integrates from `*t` to `t_end` (≥ `*t`), overwriting `x` and `*t`. The step-size
    /// history is kept between calls, so calling this for successive output times costs
    /// nothing extra.
    pub fn integrate_to<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
    ) -> Result<()> {
        let n = self.y1.len();
        check_dim(sys, n, x)?;
        if !t_end.is_finite() || !t.is_finite() || t_end < *t {
            return Err(Error::invalid(
                "output time",
                format!("must be finite and not before the current time {}", *t),
            ));
        }
        check_state(*t, x, self.options.blowup)?;
        if t_end == *t {
            return Ok(());
        }
        if !self.fsal_valid {
            sys.rhs(*t, x, &mut self.k[0])?;
            self.stats.rhs_evals += 1;
            self.fsal_valid = true;
        }
        let mut h = match self.h {
            Some(h) => h,
            None => self.initial_step(sys, *t, x, t_end - *t)?,
        };
        let mut steps = 0usize;
        loop {
            let remaining = t_end - *t;
            if remaining <= 0.0 {
                return Ok(());
            }
            steps += 1;
            if steps > self.options.max_steps {
                return Err(Error::Numerical {
                    t: *t,
                    message: format!(
                        "maximum number of steps ({}) exceeded before t = {t_end}",
                        self.options.max_steps
                    ),
                });
            }
            h = h.min(self.options.max_step);
            let last = h >= remaining * (1.0 - 1e-12);
            let hs = if last { remaining } else { h };
            if hs <= 16.0 * f64::EPSILON * t.abs().max(1e-300) {
                return Err(Error::Numerical {
                    t: *t,
                    message: format!("step size underflow (h = {hs:e})"),
                });
            }
            let err = self.try_step(sys, *t, x, hs)?;
            if err <= 1.0 {
                *t = if last { t_end } else { *t + hs };
                x.copy_from_slice(&self.y1);
                self.k.swap(0, 6);
                self.stats.accepted += 1;
                check_state(*t, x, self.options.blowup)?;
                let fac = if err == 0.0 {
                    5.0
                } else {
                    (0.9 * err.powf(-0.2)).clamp(0.2, 5.0)
                };
                // Do not let a short final step shrink the remembered step.
                h = if last { h.max(hs * fac) } else { hs * fac };
                self.h = Some(h);
                if last {
                    return Ok(());
                }
            } else {
                self.stats.rejected += 1;
                if !err.is_finite() {
                    h = hs * 0.1;
                } else {
                    h = hs * (0.9 * err.powf(-0.2)).clamp(0.1, 0.9);
                }
            }
        }
    }

    /// Attempts one step of size `h`; writes the candidate into `y1` and `k[6]` and
    /// returns the scaled error norm.
    fn try_step<S: OdeSystem>(&mut self, sys: &mut S, t: f64, x: &[f64], h: f64) -> Result<f64> {
        let n = x.len();
        let [k1, k2, k3, k4, k5, k6, k7] = &mut self.k;
        let tmp = &mut self.tmp;
        for i in 0..n {
            tmp[i] = x[i] + h * A21 * k1[i];
        }
        sys.rhs(t + C2 * h, tmp, k2)?;
        for i in 0..n {
            tmp[i] = x[i] + h * (A31 * k1[i] + A32 * k2[i]);
        }
        sys.rhs(t + C3 * h, tmp, k3)?;
        for i in 0..n {
            tmp[i] = x[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]);
        }
        sys.rhs(t + C4 * h, tmp, k4)?;
        for i in 0..n {
            tmp[i] = x[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
        }
        sys.rhs(t + C5 * h, tmp, k5)?;
        for i in 0..n {
            tmp[i] =
                x[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i]);
        }
        sys.rhs(t + h, tmp, k6)?;
        for i in 0..n {
            self.y1[i] =
                x[i] + h * (B1 * k1[i] + B3 * k3[i] + B4 * k4[i] + B5 * k5[i] + B6 * k6[i]);
        }
        sys.rhs(t + h, &self.y1, k7)?;
        self.stats.rhs_evals += 6;
        let mut acc = 0.0;
        for i in 0..n {
            let e =
                h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
            let sc = self.options.atol + self.options.rtol * x[i].abs().max(self.y1[i].abs());
            acc += (e / sc).powi(2);
        }
        let err = (acc / n.max(1) as f64).sqrt();
        Ok(if err.is_nan() { f64::INFINITY } else { err })
    }

    /// Integrates from `(t0, x0)` and returns the states at the requested `times`
    /// (non-decreasing, ≥ `t0`), one row per time.
    pub fn solve_at<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t0: f64,
        x0: &[f64],
        times: &[f64],
    ) -> Result<Vec<Vec<f64>>> {
        self.reset();
        let mut x = x0.to_vec();
        let mut t = t0;
        let mut out = Vec::with_capacity(times.len());
        for (i, &te) in times.iter().enumerate() {
            if !te.is_finite() || te < t {
                return Err(Error::invalid(
                    format!("t[{i}]"),
                    "output times must be finite, non-decreasing and not before the start",
                ));
            }
            self.integrate_to(sys, &mut t, &mut x, te)?;
            out.push(x.clone());
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Decay;
    impl OdeSystem for Decay {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<()> {
            dx[0] = -x[0];
            Ok(())
        }
    }

    #[test]
    fn dp45_exponential_decay() {
        let mut dp = DormandPrince45::new(1, AdaptiveOptions::with_tolerance(1e-12)).unwrap();
        let out = dp
            .solve_at(&mut Decay, 0.0, &[1.0], &[0.5, 1.0, 2.0])
            .unwrap();
        for (row, t) in out.iter().zip([0.5f64, 1.0, 2.0]) {
            assert!((row[0] - (-t).exp()).abs() < 1e-11);
        }
    }
}

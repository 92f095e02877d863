//! Run-time monitors of a constrained simulation: constraint residual |C q̇|, energy
//! balance (kinetic + potential − work of the inputs) and NaN / blow-up detection.

use serde::Serialize;

use crate::error::{Error, Result};

/// Limits a [`Monitor`] enforces; exceeding one stops the simulation with
/// [`Error::Numerical`].
#[derive(Debug, Clone, Copy, Serialize, serde::Deserialize)]
pub struct MonitorLimits {
    /// Largest allowed |state component| before the run counts as blown up.
    pub blowup: f64,
    /// Largest allowed constraint residual ‖C q̇‖ (infinite disables the check).
    pub max_residual: f64,
}

impl Default for MonitorLimits {
    fn default() -> Self {
        Self {
            blowup: 1e12,
            max_residual: f64::INFINITY,
        }
    }
}

/// Running statistics of the monitored quantities.
#[doc(alias = "drift")]
#[derive(Debug, Clone, Serialize)]
pub struct Monitor {
    /// The limits in force.
    pub limits: MonitorLimits,
    /// Initial mechanical energy T₀ + V₀ (J).
    pub initial_energy: f64,
    /// Energy scale used for the relative drift: max(|T₀| + |V₀|, max |W|, 1e-300).
    pub energy_scale: f64,
    /// Largest |(T + V) − (T₀ + V₀) − W| seen (J).
    pub max_energy_error: f64,
    /// Largest constraint residual ‖C q̇‖ seen.
    pub max_residual: f64,
    /// Samples checked.
    pub samples: usize,
}

impl Monitor {
    /// A monitor for a run starting with kinetic energy `t0` and potential `v0`.
    pub fn new(limits: MonitorLimits, t0: f64, v0: f64) -> Self {
        Self {
            limits,
            initial_energy: t0 + v0,
            energy_scale: (t0.abs() + v0.abs()).max(1e-300),
            max_energy_error: 0.0,
            max_residual: 0.0,
            samples: 0,
        }
    }

    /// Checks one sample at time `t`: state finite and bounded, residual within limits;
    /// updates the drift statistics.
    pub fn check(
        &mut self,
        t: f64,
        state: &[f64],
        kinetic: f64,
        potential: f64,
        work: f64,
        residual: f64,
    ) -> Result<()> {
        for (i, x) in state.iter().enumerate() {
            if !x.is_finite() {
                return Err(Error::Numerical {
                    t,
                    message: format!("state component {i} is not finite"),
                });
            }
            if x.abs() > self.limits.blowup {
                return Err(Error::Numerical {
                    t,
                    message: format!("state component {i} = {x:e} blew up"),
                });
            }
        }
        for (what, x) in [
            ("kinetic energy", kinetic),
            ("potential energy", potential),
            ("input work", work),
            ("constraint residual", residual),
        ] {
            if !x.is_finite() {
                return Err(Error::Numerical {
                    t,
                    message: format!("{what} is not finite"),
                });
            }
        }
        if residual > self.limits.max_residual {
            return Err(Error::Numerical {
                t,
                message: format!(
                    "constraint residual |C q̇| = {residual:e} exceeds {:e}",
                    self.limits.max_residual
                ),
            });
        }
        self.energy_scale = self.energy_scale.max(work.abs());
        let err = (kinetic + potential - self.initial_energy - work).abs();
        self.max_energy_error = self.max_energy_error.max(err);
        self.max_residual = self.max_residual.max(residual);
        self.samples += 1;
        Ok(())
    }

    /// Largest energy-balance error relative to [`Monitor::energy_scale`].
    pub fn relative_energy_error(&self) -> f64 {
        self.max_energy_error / self.energy_scale
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tracks_drift_and_rejects_nan_and_blowup() {
        let mut m = Monitor::new(MonitorLimits::default(), 2.0, 1.0);
        m.check(0.0, &[1.0], 2.0, 1.0, 0.0, 0.0).unwrap();
        m.check(1.0, &[1.0], 2.5, 1.0, 0.4, 1e-15).unwrap();
        assert!((m.max_energy_error - 0.1).abs() < 1e-12);
        assert!((m.relative_energy_error() - 0.1 / 3.0).abs() < 1e-12);
        assert_eq!(m.max_residual, 1e-15);
        assert!(m.check(2.0, &[f64::NAN], 0.0, 0.0, 0.0, 0.0).is_err());
        assert!(m.check(2.0, &[1e13], 0.0, 0.0, 0.0, 0.0).is_err());
        let mut strict = Monitor::new(
            MonitorLimits {
                max_residual: 1e-9,
                ..Default::default()
            },
            1.0,
            0.0,
        );
        assert!(strict.check(0.0, &[0.0], 1.0, 0.0, 0.0, 1e-6).is_err());
    }
}

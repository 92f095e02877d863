//! What a simulation run is driven by and integrated with: the input profiles
//! ([`InputProfile`], one [`ChannelProfile`] per input), the integrator choice
//! ([`IntegratorSettings`]) and the step budget of a run ([`DEFAULT_MAX_STEPS`],
//! [`MAX_STEP_BUDGET`]). The scenario file ([`crate::sim_config::schema`]) reads them; the
//! simulators ([`crate::sim::wheeled`], [`crate::sim::closed_loop`],
//! [`crate::sim::free_floating`]) take them.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// One input channel as a function of time.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ChannelProfile {
    /// `u(t) = value`.
    Constant {
        /// The value (N·m for torques).
        value: f64,
    },
    /// Piecewise constant: `u(t) = values[i]` for `times[i] ≤ t < times[i+1]`, 0 before
    /// `times[0]`, `values[last]` after the last time.
    Piecewise {
        /// Switching times (s), strictly increasing.
        times: Vec<f64>,
        /// Values, one per switching time.
        values: Vec<f64>,
    },
    /// `u(t) = offset + amplitude · sin(2π frequency t + phase)`.
    Sinusoid {
        /// Constant part.
        #[serde(default)]
        offset: f64,
        /// Amplitude.
        amplitude: f64,
        /// Frequency (Hz).
        frequency: f64,
        /// Phase (rad).
        #[serde(default)]
        phase: f64,
    },
}

impl ChannelProfile {
    /// The value at time `t`.
    pub fn eval(&self, t: f64) -> f64 {
        match self {
            ChannelProfile::Constant { value } => *value,
            ChannelProfile::Piecewise { times, values } => {
                let i = times.partition_point(|&s| s <= t);
                if i == 0 { 0.0 } else { values[i - 1] }
            }
            ChannelProfile::Sinusoid {
                offset,
                amplitude,
                frequency,
                phase,
            } => offset + amplitude * (std::f64::consts::TAU * frequency * t + phase).sin(),
        }
    }

    /// Checks finiteness and, for piecewise profiles, matching lengths and increasing times;
    /// `field` names the channel in errors.
    pub fn validate(&self, field: &str) -> Result<()> {
        match self {
            ChannelProfile::Constant { value } => {
                crate::error::ensure_finite(&format!("{field}.value"), [value])
            }
            ChannelProfile::Piecewise { times, values } => {
                crate::error::ensure_finite(&format!("{field}.times"), times)?;
                crate::error::ensure_finite(&format!("{field}.values"), values)?;
                crate::error::ensure_len(&format!("{field}.values"), times.len(), values.len())?;
                if times.is_empty() {
                    return Err(Error::invalid(
                        format!("{field}.times"),
                        "need at least one switching time",
                    ));
                }
                if times.windows(2).any(|w| w[1] <= w[0]) {
                    return Err(Error::invalid(
                        format!("{field}.times"),
                        "switching times must be strictly increasing",
                    ));
                }
                Ok(())
            }
            ChannelProfile::Sinusoid {
                offset,
                amplitude,
                frequency,
                phase,
            } => crate::error::ensure_finite(
                &format!("{field} (offset, amplitude, frequency, phase)"),
                [offset, amplitude, frequency, phase],
            ),
        }
    }
}

/// A vector input `u(t)`: one [`ChannelProfile`] per input channel.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct InputProfile {
    /// The channels, in the model's input order.
    pub channels: Vec<ChannelProfile>,
}

impl InputProfile {
    /// All channels zero (`n` of them).
    pub fn zero(n: usize) -> Self {
        Self {
            channels: vec![ChannelProfile::Constant { value: 0.0 }; n],
        }
    }

    /// Writes `u(t)` into `u`.
    ///
    /// # Panics
    /// If `u.len()` differs from the number of channels.
    pub fn eval(&self, t: f64, u: &mut [f64]) {
        assert_eq!(u.len(), self.channels.len(), "input length");
        for (ui, ch) in u.iter_mut().zip(&self.channels) {
            *ui = ch.eval(t);
        }
    }
}

/// The step budget of a whole run when the scenario sets none (`integrator.max_steps`):
/// every step of every integration the run makes (fixed RK4 steps, accepted and
/// rejected adaptive steps, over all recording intervals, control ticks and phases)
/// counts against it. A million steps is a few hundred times what any shipped scenario
/// takes and keeps the costliest plants of the shipped set well under a minute.
pub const DEFAULT_MAX_STEPS: u64 = 100_000;

/// The largest step budget a scenario may ask for (`integrator.max_steps`).
pub const MAX_STEP_BUDGET: u64 = 100_000_000;

/// Integrator choice.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "snake_case", deny_unknown_fields)]
pub enum IntegratorSettings {
    /// Classical RK4 with fixed step `dt` (s).
    Rk4 {
        /// Step (s).
        dt: f64,
        /// Step budget of the whole run (1 ..= [`MAX_STEP_BUDGET`]); default
        /// [`DEFAULT_MAX_STEPS`].
        #[serde(default, skip_serializing_if = "Option::is_none")]
        max_steps: Option<u64>,
    },
    /// Adaptive Dormand–Prince 5(4) with relative and absolute tolerances.
    Adaptive {
        /// Relative tolerance.
        rtol: f64,
        /// Absolute tolerance.
        atol: f64,
        /// Largest step (s); default: unlimited.
        #[serde(default)]
        max_step: Option<f64>,
        /// Step budget of the whole run, accepted and rejected steps
        /// (1 ..= [`MAX_STEP_BUDGET`]); default [`DEFAULT_MAX_STEPS`].
        #[serde(default, skip_serializing_if = "Option::is_none")]
        max_steps: Option<u64>,
    },
}

impl IntegratorSettings {
    /// Checks positivity and finiteness of the settings.
    pub fn validate(&self) -> Result<()> {
        let pos =
            |field: &str, x: f64| crate::error::ensure_positive(&format!("integrator.{field}"), x);
        match *self {
            IntegratorSettings::Rk4 { dt, .. } => pos("dt", dt)?,
            IntegratorSettings::Adaptive {
                rtol,
                atol,
                max_step,
                ..
            } => {
                pos("rtol", rtol)?;
                pos("atol", atol)?;
                if let Some(m) = max_step {
                    pos("max_step", m)?;
                }
            }
        }
        if let Some(n) = self.max_steps()
            && !(1..=MAX_STEP_BUDGET).contains(&n)
        {
            return Err(Error::invalid(
                "integrator.max_steps",
                format!("must be between 1 and {MAX_STEP_BUDGET:e} steps, got {n}"),
            ));
        }
        Ok(())
    }

    /// RK4 with step `dt` and the default step budget.
    #[must_use]
    pub fn rk4(dt: f64) -> Self {
        IntegratorSettings::Rk4 {
            dt,
            max_steps: None,
        }
    }

    /// Adaptive Dormand–Prince 5(4) at `rtol`, `atol` with no step cap and the default
    /// step budget.
    #[must_use]
    pub fn adaptive(rtol: f64, atol: f64) -> Self {
        IntegratorSettings::Adaptive {
            rtol,
            atol,
            max_step: None,
            max_steps: None,
        }
    }

    /// The step budget the scenario set (`integrator.max_steps`), if any.
    #[must_use]
    pub fn max_steps(&self) -> Option<u64> {
        match *self {
            IntegratorSettings::Rk4 { max_steps, .. }
            | IntegratorSettings::Adaptive { max_steps, .. } => max_steps,
        }
    }

    /// The step budget of a run: `integrator.max_steps`, or [`DEFAULT_MAX_STEPS`]
    /// (clamped to [`MAX_STEP_BUDGET`]; [`IntegratorSettings::validate`] refuses more).
    #[must_use]
    pub fn step_budget(&self) -> usize {
        let n = self
            .max_steps()
            .unwrap_or(DEFAULT_MAX_STEPS)
            .min(MAX_STEP_BUDGET);
        usize::try_from(n).unwrap_or(usize::MAX)
    }

    /// The name of the integrator in messages.
    #[must_use]
    pub fn method_name(&self) -> &'static str {
        match self {
            IntegratorSettings::Rk4 { .. } => "RK4",
            IntegratorSettings::Adaptive { .. } => "Dormand-Prince 5(4)",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profiles_evaluate_and_validate() {
        let c = ChannelProfile::Constant { value: 2.0 };
        assert_eq!(c.eval(5.0), 2.0);
        let p = ChannelProfile::Piecewise {
            times: vec![0.0, 1.0],
            values: vec![1.0, -1.0],
        };
        assert_eq!(p.eval(-0.5), 0.0);
        assert_eq!(p.eval(0.5), 1.0);
        assert_eq!(p.eval(1.0), -1.0);
        p.validate("u[0]").unwrap();
        let s = ChannelProfile::Sinusoid {
            offset: 1.0,
            amplitude: 2.0,
            frequency: 0.25,
            phase: 0.0,
        };
        assert!((s.eval(1.0) - 3.0).abs() < 1e-12);
        let bad = ChannelProfile::Piecewise {
            times: vec![1.0, 0.5],
            values: vec![1.0, 2.0],
        };
        assert!(
            bad.validate("u[1]")
                .unwrap_err()
                .to_string()
                .contains("u[1].times")
        );
        assert!(
            ChannelProfile::Constant { value: f64::NAN }
                .validate("u[2]")
                .is_err()
        );
        assert!(IntegratorSettings::rk4(0.0).validate().is_err());
        let t: IntegratorSettings =
            toml::from_str("method = \"adaptive\"\nrtol = 1e-9\natol = 1e-12").unwrap();
        t.validate().unwrap();
        assert_eq!(t.step_budget(), DEFAULT_MAX_STEPS as usize);
        // an unset budget is not written (summaries stay as they were)
        assert!(!serde_json::to_string(&t).unwrap().contains("max_steps"));
        let t: IntegratorSettings =
            toml::from_str("method = \"rk4\"\ndt = 1e-3\nmax_steps = 5000").unwrap();
        t.validate().unwrap();
        assert_eq!(t.step_budget(), 5000);
        assert!(
            serde_json::to_string(&t)
                .unwrap()
                .contains("\"max_steps\":5000")
        );
        for n in [0, MAX_STEP_BUDGET + 1] {
            let t = IntegratorSettings::Rk4 {
                dt: 1e-3,
                max_steps: Some(n),
            };
            assert!(
                t.validate()
                    .unwrap_err()
                    .to_string()
                    .contains("integrator.max_steps")
            );
        }
        assert!(
            toml::from_str::<IntegratorSettings>("method = \"rk4\"\ndt = 1e-3\nmax_steps = -1")
                .is_err()
        );
    }
}

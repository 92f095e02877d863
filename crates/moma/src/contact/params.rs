//! The contact law's parameters, their defaults and the checks made before a run.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// Parameters of the compliant contact law and of the time step (see `docs/contact.md`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ContactParams {
    /// Normal stiffness k (N/m): `N = k δ + c δ̇` for a penetration δ > 0.
    pub stiffness: f64,
    /// Normal damping c (N·s/m).
    pub damping: f64,
    /// Coulomb friction coefficient μ of the wheels (> 0).
    pub mu: f64,
    /// Regularisation velocity v_ε (m/s): below it friction is viscous,
    /// `F_t = −μ N v_t / v_ε`; at and above it, Coulomb's `−μ N v_t / |v_t|`.
    pub slip_velocity: f64,
    /// Time step dt (s) of the semi-implicit Euler scheme.
    pub dt: f64,
    /// Largest penetration (m) a wheel or caster may have at the start.
    pub start_penetration_tol: f64,
}

impl Default for ContactParams {
    fn default() -> Self {
        Self {
            stiffness: 1.0e5,
            damping: 2.0e3,
            mu: 1.0,
            slip_velocity: 0.05,
            dt: 1.0e-4,
            start_penetration_tol: 1.0e-3,
        }
    }
}

impl ContactParams {
    /// Checks every field on its own: all finite, `stiffness`, `mu`, `slip_velocity`,
    /// `dt` positive, `damping` and `start_penetration_tol` not negative. The checks
    /// that depend on the robot (the stable step) are [`spring_damper_step_bound`] and
    /// [`friction_step_bound`], made when a run starts.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the field (`contact.mu`, …).
    pub fn validate(&self) -> Result<()> {
        let fields = [
            ("contact.stiffness", self.stiffness, false),
            ("contact.damping", self.damping, true),
            ("contact.mu", self.mu, false),
            ("contact.slip_velocity", self.slip_velocity, false),
            ("contact.dt", self.dt, false),
            (
                "contact.start_penetration_tol",
                self.start_penetration_tol,
                true,
            ),
        ];
        for (name, x, zero_ok) in fields {
            if !x.is_finite() {
                return Err(Error::NonFinite { field: name.into() });
            }
            if x < 0.0 || (!zero_ok && x == 0.0) {
                return Err(Error::invalid(
                    name,
                    format!("must be {}, got {x}", if zero_ok { "≥ 0" } else { "> 0" }),
                ));
            }
        }
        Ok(())
    }
}

/// The largest stable step of semi-implicit Euler on the spring-damper `m ẍ = −k x − c ẋ`
/// (`k, c ≥ 0`): `dt < 4 m / (c + √(c² + 4 k m))`, which is `2 (√(1 + ζ²) − ζ) / ω_n` with
/// `ω_n = √(k/m)`, `ζ = c / (2 √(k m))` (`2/ω_n` without damping, `2 m / c` without
/// stiffness, unbounded without either). The step's amplification matrix has trace
/// `2 − 2ζω_n dt − ω_n² dt²` and determinant `1 − 2ζω_n dt`; of Jury's conditions,
/// `1 − trace + det > 0` holds for any `k > 0`, `1 + trace + det > 0` gives this bound, and
/// `|det| < 1` (`dt < 1/(ζ ω_n)`) follows from it. Serves the contact's normal law and the
/// PD laws that hold joints on the contact plant ([`crate::sim::lift_off`]).
#[must_use]
pub fn spring_damper_step_bound(stiffness: f64, damping: f64, mass: f64) -> f64 {
    // √(c² + 4km) as a hypotenuse: no overflow for a huge damping (a tiny bound, not 0)
    4.0 * mass / (damping + damping.hypot(2.0 * (stiffness * mass).sqrt()))
}

/// The largest stable step of explicit Euler on the viscous branch of regularised friction,
/// `m v̇ = −(μ N / v_ε) v`: `dt < 2 m v_ε / (μ N)`.
#[must_use]
pub fn friction_step_bound(mu: f64, normal: f64, slip_velocity: f64, mass: f64) -> f64 {
    2.0 * mass * slip_velocity / (mu * normal)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs semi-implicit Euler on `m ẍ = −k x − c ẋ` from x = 1, ẋ = 1 for 20 000 steps
    /// and returns |x| at the end (NaN once it has overflowed).
    fn spring_damper(k: f64, c: f64, m: f64, dt: f64) -> f64 {
        let (mut x, mut v) = (1.0f64, 1.0f64);
        for _ in 0..20_000 {
            v += dt * (-k * x - c * v) / m;
            x += dt * v;
        }
        x.abs()
    }

    #[test]
    fn the_spring_damper_bound_separates_decay_from_growth() {
        // The last two: a PD-held light joint (kp, kd on 2e-4 kg·m²) and a damper alone.
        for (k, c, m) in [
            (1e5, 0.0, 1.0),
            (2.0, 0.04, 2e-4),
            (0.0, 50.0, 0.01),
            (1e5, 2e3, 1.0),
            (1e5, 2e3, 10.0),
            (1e6, 50.0, 3.0),
            // a soft, damped contact (ζ ≈ 3.6e8), where 2(√(1 + ζ²) − ζ)/ω_n cancels to 0
            (1e-12, 2e3, 7.9),
        ] {
            let b = spring_damper_step_bound(k, c, m);
            // Bounded below the bound (undamped it is neutrally stable, the amplitude of x
            // up to 1/√(1 − (ω_n dt/2)²) ≈ 5 at 0.98 × the bound), unbounded above it (NaN
            // once it has overflowed).
            let below = spring_damper(k, c, m, 0.98 * b);
            assert!(
                below < 10.0,
                "k {k} c {c} m {m}: 0.98 × bound gives {below}"
            );
            let above = spring_damper(k, c, m, 1.02 * b);
            assert!(
                above.is_nan() || above > 1e3,
                "k {k} c {c} m {m}: 1.02 × bound gives {above}"
            );
        }
    }

    #[test]
    fn a_huge_damping_gives_a_tiny_bound_not_zero() {
        let b = spring_damper_step_bound(1e5, 1e300, 7.9);
        assert!(b > 0.0 && b < 1e-290, "{b}");
    }

    #[test]
    fn the_friction_bound_separates_decay_from_growth() {
        let (mu, n, ve, m) = (1.0, 280.0, 0.05, 0.5);
        let b = friction_step_bound(mu, n, ve, m);
        let run = |dt: f64| {
            let mut v = 0.01f64;
            for _ in 0..20_000 {
                v -= dt * mu * n * v / (ve * m);
            }
            v.abs()
        };
        assert!(run(0.98 * b) < 0.01);
        let v = run(1.02 * b);
        assert!(v.is_nan() || v > 1.0, "{v}");
    }

    #[test]
    fn each_field_is_checked_by_name() {
        let ok = ContactParams::default();
        assert!(ok.validate().is_ok());
        let cases: [(ContactParams, &str); 4] = [
            (ContactParams { mu: 0.0, ..ok }, "contact.mu"),
            (
                ContactParams {
                    damping: -1.0,
                    ..ok
                },
                "contact.damping",
            ),
            (
                ContactParams {
                    stiffness: f64::INFINITY,
                    ..ok
                },
                "contact.stiffness",
            ),
            (
                ContactParams {
                    slip_velocity: 0.0,
                    ..ok
                },
                "contact.slip_velocity",
            ),
        ];
        for (p, field) in cases {
            let e = p.validate().unwrap_err().to_string();
            assert!(e.contains(field), "{e}");
        }
    }
}

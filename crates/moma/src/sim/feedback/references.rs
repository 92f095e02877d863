//! The references the feedback laws track: a time-sampled platform trajectory
//! ([`SampledTrajectory`]), what Kanayama's law tracks ([`TrackingReference`]) and a 3-D
//! end-effector reference ([`PointReference`]).

use crate::control::unicycle::{ConstantInputReference, ReferenceSample};
use crate::control::wrap_angle;
use crate::error::{Error, Result};
use crate::planning::trajectory::TrajectoryPoint;

/// A time-sampled platform trajectory (from [`crate::planning::trajectory`]),
/// interpolated linearly between samples (the heading along the shorter arc) and held
/// at rest at its last sample.
#[derive(Clone, Debug)]
pub struct SampledTrajectory {
    points: Vec<TrajectoryPoint>,
}

impl SampledTrajectory {
    /// Wraps samples with strictly increasing times.
    ///
    /// # Errors
    /// No sample, or times not strictly increasing.
    pub fn new(points: Vec<TrajectoryPoint>) -> Result<Self> {
        if points.is_empty() {
            return Err(Error::invalid("trajectory", "no samples"));
        }
        if points.windows(2).any(|w| w[1].t <= w[0].t) {
            return Err(Error::invalid(
                "trajectory",
                "sample times must be strictly increasing",
            ));
        }
        Ok(Self { points })
    }

    /// The samples.
    #[must_use]
    pub fn points(&self) -> &[TrajectoryPoint] {
        &self.points
    }

    /// The reference sample at time t.
    #[must_use]
    pub fn at(&self, t: f64) -> ReferenceSample {
        let p = &self.points;
        let last = p[p.len() - 1];
        if t >= last.t {
            return ReferenceSample {
                pose: [last.x, last.y, last.theta],
                v: 0.0,
                w: 0.0,
            };
        }
        let i = p.partition_point(|s| s.t <= t);
        if i == 0 {
            let f = p[0];
            return ReferenceSample {
                pose: [f.x, f.y, f.theta],
                v: f.v,
                w: f.omega,
            };
        }
        let (a, b) = (p[i - 1], p[i]);
        let s = (t - a.t) / (b.t - a.t);
        let lerp = |x: f64, y: f64| x + s * (y - x);
        ReferenceSample {
            pose: [
                lerp(a.x, b.x),
                lerp(a.y, b.y),
                a.theta + s * wrap_angle(b.theta - a.theta),
            ],
            v: lerp(a.v, b.v),
            w: lerp(a.omega, b.omega),
        }
    }
}

/// What Kanayama's law tracks.
#[derive(Clone, Debug)]
pub enum TrackingReference {
    /// Constant `(v_r, ω_r)` from the origin: the circle of radius `v_r/ω_r`, or a line.
    Constant(ConstantInputReference),
    /// A time-parameterised planned path.
    Sampled(SampledTrajectory),
}

impl TrackingReference {
    /// The sample at time t.
    #[must_use]
    pub fn at(&self, t: f64) -> ReferenceSample {
        match self {
            Self::Constant(c) => c.at(t),
            Self::Sampled(s) => s.at(t),
        }
    }
}

/// A 3-D end-effector reference: position, velocity and acceleration at time t.
#[derive(Clone, Debug, PartialEq)]
pub enum PointReference {
    /// From `from` to `to` in `duration` with a quintic (rest-to-rest) time scaling,
    /// then held.
    Line {
        /// Start (m).
        from: [f64; 3],
        /// End (m).
        to: [f64; 3],
        /// Duration (s), > 0.
        duration: f64,
    },
    /// The horizontal circle `c + r (cos φ, sin φ, 0)`, `φ = φ₀ + 2π t / period`.
    Circle {
        /// Centre (m).
        center: [f64; 3],
        /// Radius (m), > 0.
        radius: f64,
        /// Period (s), > 0.
        period: f64,
        /// Phase φ₀ (rad).
        phase: f64,
    },
    /// Through `points` at `times` (strictly increasing, the first ≥ 0), each leg a
    /// quintic rest-to-rest motion; the first point is held before `times[0]`, the last
    /// after the last time.
    Waypoints {
        /// Points (m).
        points: Vec<[f64; 3]>,
        /// Their times (s).
        times: Vec<f64>,
    },
}

/// The quintic rest-to-rest scaling `s(τ) = 10τ³ − 15τ⁴ + 6τ⁵` and its first two
/// derivatives in τ.
fn quintic(tau: f64) -> (f64, f64, f64) {
    let t = tau.clamp(0.0, 1.0);
    let (t2, t3) = (t * t, t * t * t);
    (
        t3 * (10.0 - 15.0 * t + 6.0 * t2),
        30.0 * t2 * (1.0 - 2.0 * t + t2),
        60.0 * t * (1.0 - 3.0 * t + 2.0 * t2),
    )
}

impl PointReference {
    /// Checks finiteness, positive durations and increasing times (field names in errors).
    ///
    /// # Errors
    /// The first bad field.
    pub fn validate(&self) -> Result<()> {
        let pos = crate::error::ensure_positive;
        match self {
            Self::Line { from, to, duration } => {
                crate::error::ensure_finite("reference.from", from)?;
                crate::error::ensure_finite("reference.to", to)?;
                pos("reference.duration", *duration)
            }
            Self::Circle {
                center,
                radius,
                period,
                phase,
            } => {
                crate::error::ensure_finite("reference.center", center)?;
                crate::error::ensure_finite("reference.phase", [phase])?;
                pos("reference.radius", *radius)?;
                pos("reference.period", *period)
            }
            Self::Waypoints { points, times } => {
                if points.is_empty() {
                    return Err(Error::invalid(
                        "reference.points",
                        "need at least one point",
                    ));
                }
                crate::error::ensure_len("reference.times", points.len(), times.len())?;
                for p in points {
                    crate::error::ensure_finite("reference.points", p)?;
                }
                crate::error::ensure_finite("reference.times", times)?;
                if times[0] < 0.0 || times.windows(2).any(|w| w[1] <= w[0]) {
                    return Err(Error::invalid(
                        "reference.times",
                        "must start at >= 0 and be strictly increasing",
                    ));
                }
                Ok(())
            }
        }
    }

    /// `(x_d, ẋ_d, ẍ_d)` at time t.
    #[must_use]
    pub fn at(&self, t: f64) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let leg = |a: &[f64; 3], b: &[f64; 3], t0: f64, dur: f64| {
            let (s, sd, sdd) = quintic((t - t0) / dur);
            let (mut x, mut v, mut acc) = ([0.0; 3], [0.0; 3], [0.0; 3]);
            for k in 0..3 {
                let d = b[k] - a[k];
                x[k] = a[k] + s * d;
                v[k] = sd * d / dur;
                acc[k] = sdd * d / (dur * dur);
            }
            (x, v, acc)
        };
        match self {
            Self::Line { from, to, duration } => leg(from, to, 0.0, *duration),
            Self::Circle {
                center,
                radius,
                period,
                phase,
            } => {
                let w = std::f64::consts::TAU / period;
                let (s, c) = (phase + w * t).sin_cos();
                (
                    [center[0] + radius * c, center[1] + radius * s, center[2]],
                    [-radius * w * s, radius * w * c, 0.0],
                    [-radius * w * w * c, -radius * w * w * s, 0.0],
                )
            }
            Self::Waypoints { points, times } => {
                let n = points.len();
                if n == 1 || t <= times[0] {
                    return (points[0], [0.0; 3], [0.0; 3]);
                }
                if t >= times[n - 1] {
                    return (points[n - 1], [0.0; 3], [0.0; 3]);
                }
                let i = times.partition_point(|&s| s <= t);
                leg(
                    &points[i - 1],
                    &points[i],
                    times[i - 1],
                    times[i] - times[i - 1],
                )
            }
        }
    }
}

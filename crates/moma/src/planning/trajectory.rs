//! From a path to motion: time parameterisation of a polyline for a differential-drive
//! robot under velocity and acceleration limits.
//!
//! The robot turns in place toward each segment, then drives it straight, both with
//! trapezoidal (or, when too short to reach the limit, triangular) velocity profiles that
//! start and end at rest. Every sample therefore satisfies `|v| ≤ v_max`, `|ω| ≤ ω_max`,
//! `|v̇| ≤ a_max`, `|ω̇| ≤ α_max` and the non-holonomic constraint (the velocity always
//! points along the heading), so a tracking controller can follow it.

use crate::{Error, Result};

/// Velocity and acceleration limits of a differential drive.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DiffDriveLimits {
    /// Largest forward speed `v_max` (m/s).
    pub v_max: f64,
    /// Largest turn rate `ω_max` (rad/s).
    pub omega_max: f64,
    /// Largest linear acceleration `a_max` (m/s²).
    pub a_max: f64,
    /// Largest angular acceleration `α_max` (rad/s²).
    pub alpha_max: f64,
}

impl DiffDriveLimits {
    fn validate(&self) -> Result<()> {
        for (n, v) in [
            ("v_max", self.v_max),
            ("omega_max", self.omega_max),
            ("a_max", self.a_max),
            ("alpha_max", self.alpha_max),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(
                    n,
                    format!("must be finite and > 0, got {v}"),
                ));
            }
        }
        Ok(())
    }
}

/// One sample of the reference trajectory.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TrajectoryPoint {
    /// Time (s).
    pub t: f64,
    /// Position x (m).
    pub x: f64,
    /// Position y (m).
    pub y: f64,
    /// Heading θ (rad, in (−π, π]).
    pub theta: f64,
    /// Forward speed v (m/s).
    pub v: f64,
    /// Turn rate ω (rad/s).
    pub omega: f64,
}

/// Direction-dependent linear acceleration limits (m/s²) of the platform along its
/// heading, e.g. the tip-over limits of a loaded robot: `forward` bounds speeding up
/// (acceleration along +heading), `backward` bounds braking (acceleration along
/// −heading). Each applies on top of [`DiffDriveLimits::a_max`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DirectionalAcceleration {
    /// Largest acceleration along the heading (m/s²), > 0.
    pub forward: f64,
    /// Largest deceleration, i.e. acceleration against the heading (m/s²), > 0.
    pub backward: f64,
}

/// Trapezoidal rest-to-rest profile over a distance `d ≥ 0` accelerating at `a_up` and
/// braking at `a_down`: returns (duration, position(t), velocity(t)).
struct Trapezoid {
    d: f64,
    vp: f64,
    a_up: f64,
    a_down: f64,
    t_acc: f64,
    t_cruise: f64,
    t_dec: f64,
}

impl Trapezoid {
    fn new(d: f64, vmax: f64, amax: f64) -> Self {
        Self::asymmetric(d, vmax, amax, amax)
    }
    fn asymmetric(d: f64, vmax: f64, a_up: f64, a_down: f64) -> Self {
        // distance to reach v and stop again: v² (1/a_up + 1/a_down) / 2
        let k = 0.5 * (1.0 / a_up + 1.0 / a_down);
        let (vp, t_cruise) = if d >= vmax * vmax * k {
            (vmax, (d - vmax * vmax * k) / vmax)
        } else {
            ((d / k).sqrt(), 0.0)
        };
        Self {
            d,
            vp,
            a_up,
            a_down,
            t_acc: vp / a_up,
            t_cruise,
            t_dec: vp / a_down,
        }
    }
    fn duration(&self) -> f64 {
        self.t_acc + self.t_cruise + self.t_dec
    }
    fn at(&self, t: f64) -> (f64, f64) {
        let t = t.clamp(0.0, self.duration());
        if t <= self.t_acc {
            (0.5 * self.a_up * t * t, self.a_up * t)
        } else if t <= self.t_acc + self.t_cruise {
            (
                0.5 * self.a_up * self.t_acc * self.t_acc + self.vp * (t - self.t_acc),
                self.vp,
            )
        } else {
            let r = self.duration() - t;
            (self.d - 0.5 * self.a_down * r * r, self.a_down * r)
        }
    }
}

fn wrap(a: f64) -> f64 {
    let mut a = a % std::f64::consts::TAU;
    if a > std::f64::consts::PI {
        a -= std::f64::consts::TAU;
    } else if a <= -std::f64::consts::PI {
        a += std::f64::consts::TAU;
    }
    a
}

/// Most samples [`time_parameterize`] returns (48 bytes each: 480 MB). The count follows
/// from the path length, the limits and `dt`, all user input, so it is checked before
/// anything is allocated.
pub const MAX_TRAJECTORY_SAMPLES: usize = 10_000_000;

/// Time-parameterises the polyline `waypoints` (world coordinates, metres) for a
/// differential drive starting at rest with heading `initial_heading` (defaults to the
/// first segment's direction). Samples every `dt` seconds plus every segment end.
///
/// # Errors
/// Non-positive or non-finite limits or `dt`, an empty or non-finite path, and a
/// trajectory that would need more than [`MAX_TRAJECTORY_SAMPLES`] samples (a tiny `dt`
/// or tiny limits for the path's length).
#[doc(alias = "time_parameterization")]
pub fn time_parameterize(
    waypoints: &[[f64; 2]],
    initial_heading: Option<f64>,
    limits: &DiffDriveLimits,
    dt: f64,
) -> Result<Vec<TrajectoryPoint>> {
    time_parameterize_directional(waypoints, initial_heading, limits, None, dt)
}

/// [`time_parameterize`] with the straight segments' acceleration further bounded by
/// direction: speeding up at most `accel.forward`, braking at most `accel.backward`
/// (each also at most `a_max`). Pass the tip-over acceleration limits of the loaded robot
/// (`moma::stability`) so that no straight segment of the motion tips it; the turns in
/// place keep `α_max`.
///
/// # Errors
/// As [`time_parameterize`], and for a non-positive or non-finite directional limit.
pub fn time_parameterize_directional(
    waypoints: &[[f64; 2]],
    initial_heading: Option<f64>,
    limits: &DiffDriveLimits,
    accel: Option<&DirectionalAcceleration>,
    dt: f64,
) -> Result<Vec<TrajectoryPoint>> {
    limits.validate()?;
    let (a_up, a_down) = match accel {
        Some(d) => {
            for (n, v) in [("forward", d.forward), ("backward", d.backward)] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(Error::invalid(
                        format!("acceleration limit {n}"),
                        format!("must be finite and > 0, got {v}"),
                    ));
                }
            }
            (d.forward.min(limits.a_max), d.backward.min(limits.a_max))
        }
        None => (limits.a_max, limits.a_max),
    };
    if !(dt.is_finite() && dt > 0.0) {
        return Err(Error::invalid(
            "dt",
            format!("must be finite and > 0, got {dt}"),
        ));
    }
    if waypoints.is_empty() {
        return Err(Error::invalid("waypoints", "the path is empty"));
    }
    crate::error::ensure_finite("waypoints", waypoints.iter().flatten())?;
    let mut pts = vec![waypoints[0]];
    for w in &waypoints[1..] {
        let last = pts.last().expect("non-empty");
        if (w[0] - last[0]).hypot(w[1] - last[1]) > 1e-12 {
            pts.push(*w);
        }
    }
    let first_dir = if pts.len() > 1 {
        (pts[1][1] - pts[0][1]).atan2(pts[1][0] - pts[0][0])
    } else {
        0.0
    };
    let mut theta = wrap(initial_heading.unwrap_or(first_dir));
    let (samples, duration) = sample_count(&pts, theta, limits, dt);
    if samples.is_nan() || samples > MAX_TRAJECTORY_SAMPLES as f64 {
        return Err(Error::invalid(
            "trajectory samples",
            format!(
                "a {duration:.3e} s trajectory sampled every dt = {dt:e} s needs {samples:.3e} \
                 samples, more than the limit of {MAX_TRAJECTORY_SAMPLES}; use a larger dt or \
                 larger velocity and acceleration limits"
            ),
        ));
    }
    let mut t0 = 0.0;
    let mut out = vec![TrajectoryPoint {
        t: 0.0,
        x: pts[0][0],
        y: pts[0][1],
        theta,
        v: 0.0,
        omega: 0.0,
    }];
    let push_phase =
        |out: &mut Vec<TrajectoryPoint>, t0: f64, dur: f64, f: &dyn Fn(f64) -> TrajectoryPoint| {
            let n = (dur / dt).floor() as usize;
            for k in 1..=n {
                let tau = k as f64 * dt;
                if tau < dur - 1e-12 {
                    out.push(f(tau).with_time(t0 + tau));
                }
            }
            out.push(f(dur).with_time(t0 + dur));
        };
    for seg in pts.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        let heading = (b[1] - a[1]).atan2(b[0] - a[0]);
        let turn = wrap(heading - theta);
        if turn.abs() > 1e-12 {
            let prof = Trapezoid::new(turn.abs(), limits.omega_max, limits.alpha_max);
            let (th0, sgn) = (theta, turn.signum());
            push_phase(&mut out, t0, prof.duration(), &|tau| {
                let (s, w) = prof.at(tau);
                TrajectoryPoint {
                    t: 0.0,
                    x: a[0],
                    y: a[1],
                    theta: wrap(th0 + sgn * s),
                    v: 0.0,
                    omega: sgn * w,
                }
            });
            t0 += prof.duration();
        }
        theta = heading;
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        let prof = Trapezoid::asymmetric(len, limits.v_max, a_up, a_down);
        let (c, s) = (heading.cos(), heading.sin());
        push_phase(&mut out, t0, prof.duration(), &|tau| {
            let (d, v) = prof.at(tau);
            TrajectoryPoint {
                t: 0.0,
                x: a[0] + c * d,
                y: a[1] + s * d,
                theta: heading,
                v,
                omega: 0.0,
            }
        });
        t0 += prof.duration();
    }
    Ok(out)
}

/// The number of samples and the duration [`time_parameterize`] produces for the
/// deduplicated polyline `pts` from heading `theta` (as floats: they may be huge).
fn sample_count(pts: &[[f64; 2]], mut theta: f64, limits: &DiffDriveLimits, dt: f64) -> (f64, f64) {
    let mut samples = 1.0;
    let mut duration = 0.0;
    let mut phase = |dur: f64| {
        samples += (dur / dt).floor() + 1.0;
        duration += dur;
    };
    for seg in pts.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        let heading = (b[1] - a[1]).atan2(b[0] - a[0]);
        let turn = wrap(heading - theta);
        if turn.abs() > 1e-12 {
            phase(Trapezoid::new(turn.abs(), limits.omega_max, limits.alpha_max).duration());
        }
        theta = heading;
        let len = (b[0] - a[0]).hypot(b[1] - a[1]);
        phase(Trapezoid::new(len, limits.v_max, limits.a_max).duration());
    }
    (samples, duration)
}

impl TrajectoryPoint {
    fn with_time(mut self, t: f64) -> Self {
        self.t = t;
        self
    }
}

//! From a path to motion: time parameterisation of a polyline for a differential-drive
//! robot under velocity and acceleration limits.
//!
//! The robot turns in place toward each segment, then drives it straight, both with
//! trapezoidal (or, when too short to reach the limit, triangular) velocity profiles that
//! start and end at rest. Every sample therefore satisfies `|v| ≤ v_max`, `|ω| ≤ ω_max`,
//! `|v̇| ≤ a_max`, `|ω̇| ≤ α_max` and the non-holonomic constraint (the velocity always
//! points along the heading), so a tracking controller can follow it.

use super::MAX_TRAJECTORY_SAMPLES;
use super::curvature::{PathSample, SmoothPath};
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
#[derive(Debug, Clone, Copy, PartialEq)]
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
    let (a_up, a_down) = straight_accelerations(limits, accel)?;
    if !(dt.is_finite() && dt > 0.0) {
        return Err(Error::invalid(
            "dt",
            format!("must be finite and > 0, got {dt}"),
        ));
    }
    let pts = distinct_waypoints(waypoints)?;
    let first_dir = if pts.len() > 1 {
        (pts[1][1] - pts[0][1]).atan2(pts[1][0] - pts[0][0])
    } else {
        0.0
    };
    let mut theta = wrap(initial_heading.unwrap_or(first_dir));
    check_sample_count(&pts, theta, limits, (a_up, a_down), dt)?;
    let mut t0 = 0.0;
    let mut out = vec![TrajectoryPoint {
        t: 0.0,
        x: pts[0][0],
        y: pts[0][1],
        theta,
        v: 0.0,
        omega: 0.0,
    }];
    for seg in pts.windows(2) {
        let (a, b) = (seg[0], seg[1]);
        let heading = (b[1] - a[1]).atan2(b[0] - a[0]);
        let turn = wrap(heading - theta);
        if turn.abs() > 1e-12 {
            let prof = Trapezoid::new(turn.abs(), limits.omega_max, limits.alpha_max);
            let (th0, sgn) = (theta, turn.signum());
            push_phase(&mut out, t0, prof.duration(), dt, &|tau| {
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
        push_phase(&mut out, t0, prof.duration(), dt, &|tau| {
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

/// The straight segments' acceleration limits (speeding up, braking): the directional
/// limits, each at most `a_max`, or `a_max` both ways without them.
fn straight_accelerations(
    limits: &DiffDriveLimits,
    accel: Option<&DirectionalAcceleration>,
) -> Result<(f64, f64)> {
    let Some(d) = accel else {
        return Ok((limits.a_max, limits.a_max));
    };
    for (n, v) in [("forward", d.forward), ("backward", d.backward)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::invalid(
                format!("acceleration limit {n}"),
                format!("must be finite and > 0, got {v}"),
            ));
        }
    }
    Ok((d.forward.min(limits.a_max), d.backward.min(limits.a_max)))
}

/// The waypoints without consecutive repeats (closer than 1e-12 m), after checking that
/// there is one and that all are finite.
fn distinct_waypoints(waypoints: &[[f64; 2]]) -> Result<Vec<[f64; 2]>> {
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
    Ok(pts)
}

/// The sample count of the trajectory bounded by [`MAX_TRAJECTORY_SAMPLES`] before any
/// sample is allocated.
fn check_sample_count(
    pts: &[[f64; 2]],
    theta: f64,
    limits: &DiffDriveLimits,
    accel: (f64, f64),
    dt: f64,
) -> Result<()> {
    let (samples, duration) = sample_count(pts, theta, limits, accel, dt);
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
    Ok(())
}

/// Appends the samples of one phase of duration `dur` starting at `t0`, every `dt` and
/// at its end (`f(τ)` is the point τ into the phase).
#[inline]
fn push_phase(
    out: &mut Vec<TrajectoryPoint>,
    t0: f64,
    dur: f64,
    dt: f64,
    f: &dyn Fn(f64) -> TrajectoryPoint,
) {
    let n = (dur / dt).floor() as usize;
    for k in 1..=n {
        let tau = k as f64 * dt;
        if tau < dur - 1e-12 {
            out.push(f(tau).with_time(t0 + tau));
        }
    }
    out.push(f(dur).with_time(t0 + dur));
}

/// The number of samples and the duration [`time_parameterize`] produces for the
/// deduplicated polyline `pts` from heading `theta` (as floats: they may be huge).
fn sample_count(
    pts: &[[f64; 2]],
    mut theta: f64,
    limits: &DiffDriveLimits,
    (a_up, a_down): (f64, f64),
    dt: f64,
) -> (f64, f64) {
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
        phase(Trapezoid::asymmetric(len, limits.v_max, a_up, a_down).duration());
    }
    (samples, duration)
}

impl TrajectoryPoint {
    fn with_time(mut self, t: f64) -> Self {
        self.t = t;
        self
    }
}

/// Tip-over acceleration limits (m/s²) of the loaded platform along its base axes: the
/// planar acceleration of the base may reach `forward` along +x (speeding up), `backward`
/// along −x (braking), `left` along +y and `right` along −y (the centripetal acceleration
/// of a left / right turn). Each is > 0; a side that no support edge limits may be `+∞`.
///
/// Take them from `moma::stability::acceleration_limits` (its `None`, "no edge limits
/// this direction", becomes `f64::INFINITY`; a posture that tips at rest has no limits
/// at all and cannot be timed).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TipOverAcceleration {
    /// Along +x of the base (m/s²).
    pub forward: f64,
    /// Along −x of the base (m/s²).
    pub backward: f64,
    /// Along +y of the base (m/s²).
    pub left: f64,
    /// Along −y of the base (m/s²).
    pub right: f64,
}

impl TipOverAcceleration {
    fn validate(&self) -> Result<()> {
        for (n, v) in [
            ("forward", self.forward),
            ("backward", self.backward),
            ("left", self.left),
            ("right", self.right),
        ] {
            if v.is_nan() || v <= 0.0 {
                return Err(Error::invalid(
                    format!("tip-over acceleration limit {n}"),
                    format!("must be > 0 (or +inf), got {v}"),
                ));
            }
        }
        Ok(())
    }
}

/// One sample of a [`TimedPath`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TimedSample {
    /// Time (s).
    pub t: f64,
    /// Arc length along the path (m).
    pub s: f64,
    /// Position x (m).
    pub x: f64,
    /// Position y (m).
    pub y: f64,
    /// Heading (rad), continuous (not wrapped).
    pub theta: f64,
    /// Forward speed (m/s), ≥ 0.
    pub v: f64,
    /// Turn rate ω = κ v (m/s · 1/m), or the pivot's rate during a turn in place (rad/s).
    pub omega: f64,
    /// Tangential acceleration dv/dt (m/s²).
    pub a: f64,
    /// Angular acceleration dω/dt (rad/s²).
    pub alpha: f64,
    /// Path curvature (1/m); 0 during the turn in place.
    pub kappa: f64,
}

/// The turn in place before the path: an angle profile.
#[derive(Debug, Clone, Copy, PartialEq)]
struct PivotProfile {
    prof: Trapezoid,
    sign: f64,
    theta0: f64,
    xy: [f64; 2],
}

/// A path with its speed profile, from [`time_parameterize_curve`].
///
/// The profile is defined on a grid of arc lengths (the path's samples, subdivided when
/// there are fewer than 16 intervals) with a constant tangential acceleration on every
/// interval (v² linear in s), so between grid points v, s and ω follow in closed form.
#[derive(Debug, Clone, PartialEq)]
pub struct TimedPath {
    path: SmoothPath,
    pivot: Option<PivotProfile>,
    /// Arc length, curvature, time and speed at the grid points.
    s: Vec<f64>,
    kappa: Vec<f64>,
    t: Vec<f64>,
    v: Vec<f64>,
    /// Tangential acceleration on each interval (one fewer than the grid points).
    acc: Vec<f64>,
    overspeed_until: Option<f64>,
}

impl TimedPath {
    /// Total time (s), the start's turn in place included.
    pub fn duration(&self) -> f64 {
        *self.t.last().expect("a timed path has a grid point")
    }

    /// The timed path's geometry.
    pub fn path(&self) -> &SmoothPath {
        &self.path
    }

    /// Duration of the turn in place at the start (s), 0 without one.
    pub fn pivot_duration(&self) -> f64 {
        self.pivot.map_or(0.0, |p| p.prof.duration())
    }

    /// When `v_start` was faster than the path allows at its start: the arc length (m)
    /// up to which the profile brakes as hard as the tangential limits allow while
    /// exceeding some speed limit of the path; `None` when every limit holds everywhere.
    pub fn overspeed_until(&self) -> Option<f64> {
        self.overspeed_until
    }

    /// The state at time `t` (clamped to `[0, duration]`), interpolated exactly within
    /// the profile's interval (constant acceleration) and evaluated on the exact
    /// geometry; O(log n).
    pub fn sample(&self, t: f64) -> TimedSample {
        let t = if t.is_nan() {
            0.0
        } else {
            t.clamp(0.0, self.duration())
        };
        let t_p = self.pivot_duration();
        if let Some(p) = &self.pivot
            && t < t_p
        {
            let (ang, w) = p.prof.at(t);
            let acc = if t < p.prof.t_acc {
                p.prof.a_up
            } else if t <= p.prof.t_acc + p.prof.t_cruise {
                0.0
            } else {
                -p.prof.a_down
            };
            return TimedSample {
                t,
                s: 0.0,
                x: p.xy[0],
                y: p.xy[1],
                theta: p.theta0 + p.sign * ang,
                v: 0.0,
                omega: p.sign * w,
                a: 0.0,
                alpha: p.sign * acc,
                kappa: 0.0,
            };
        }
        let n = self.t.len();
        let i = if n == 1 {
            0
        } else {
            self.t.partition_point(|&ti| ti <= t).clamp(1, n - 1) - 1
        };
        if n == 1 {
            return self.state_at(0, 0.0, t);
        }
        self.state_at(i, t - self.t[i], t)
    }

    fn state_at(&self, i: usize, tau: f64, t: f64) -> TimedSample {
        let (v0, a) = (self.v[i], self.acc.get(i).copied().unwrap_or(0.0));
        let (mut s, mut v) = (self.s[i] + v0 * tau + 0.5 * a * tau * tau, v0 + a * tau);
        if i + 1 < self.s.len() {
            s = s.clamp(self.s[i], self.s[i + 1]);
            v = v.max(0.0);
        }
        let dk = if i + 1 < self.s.len() {
            (self.kappa[i + 1] - self.kappa[i]) / (self.s[i + 1] - self.s[i])
        } else {
            0.0
        };
        let p = self.path.at(s);
        TimedSample {
            t,
            s,
            x: p.x,
            y: p.y,
            theta: p.theta,
            v,
            omega: p.kappa * v,
            a,
            alpha: dk * v * v + p.kappa * a,
            kappa: p.kappa,
        }
    }

    /// The states at the profile's grid points (exact times; `a` and `alpha` those of the
    /// interval that starts there, the last point's those of the last interval), after
    /// the turn in place if there is one.
    pub fn knots(&self) -> Vec<TimedSample> {
        let n = self.t.len();
        (0..n)
            .map(|i| {
                if i + 1 == n && n > 1 {
                    let mut k = self.state_at(i - 1, self.t[i] - self.t[i - 1], self.t[i]);
                    k.s = self.s[i];
                    k.v = self.v[i];
                    k.omega = self.kappa[i] * self.v[i];
                    k.kappa = self.kappa[i];
                    let p = self.path.at(self.s[i]);
                    (k.x, k.y, k.theta) = (p.x, p.y, p.theta);
                    let dk = (self.kappa[i] - self.kappa[i - 1]) / (self.s[i] - self.s[i - 1]);
                    k.alpha = dk * k.v * k.v + k.kappa * k.a;
                    k
                } else {
                    self.state_at(i, 0.0, self.t[i])
                }
            })
            .collect()
    }

    /// Samples every `dt` seconds from 0, plus the final time.
    ///
    /// # Errors
    /// A non-positive or non-finite `dt`, or more than [`MAX_TRAJECTORY_SAMPLES`] samples.
    pub fn samples(&self, dt: f64) -> Result<Vec<TimedSample>> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Error::invalid(
                "dt",
                format!("must be finite and > 0, got {dt}"),
            ));
        }
        let d = self.duration();
        let count = (d / dt).floor() + 2.0;
        if count > MAX_TRAJECTORY_SAMPLES as f64 {
            return Err(Error::invalid(
                "trajectory samples",
                format!(
                    "a {d:.3e} s trajectory sampled every dt = {dt:e} s needs {count:.3e} \
                     samples, more than the limit of {MAX_TRAJECTORY_SAMPLES}; use a larger dt"
                ),
            ));
        }
        let n = (d / dt).floor() as usize;
        let mut out = Vec::with_capacity(n + 2);
        for k in 0..=n {
            let t = k as f64 * dt;
            if t < d - 1e-12 || k == 0 {
                out.push(self.sample(t));
            }
        }
        if d > 0.0 {
            out.push(self.sample(d));
        }
        Ok(out)
    }
}

/// One linear constraint `c0 u0 + c1 u1 ≤ d` on the squared speeds at the ends of an
/// interval.
type Lin = (f64, f64, f64);

/// The constraints of interval `[s0, s0 + h]` with curvatures `k0`, `k1`.
fn interval_constraints(
    h: f64,
    k0: f64,
    k1: f64,
    limits: &DiffDriveLimits,
    tip: Option<&TipOverAcceleration>,
    out: &mut Vec<Lin>,
) {
    out.clear();
    let ia = 1.0 / (2.0 * h); // a = ia (u1 − u0)
    // |a| ≤ a_max
    out.push((-ia, ia, limits.a_max));
    out.push((ia, -ia, limits.a_max));
    // |dω/dt| = |κ' u + κ a| ≤ α_max at both ends (linear in s in between: exact).
    let dk = (k1 - k0) / h;
    for (c0, c1) in [(dk - k0 * ia, k0 * ia), (-k1 * ia, dk + k1 * ia)] {
        out.push((c0, c1, limits.alpha_max));
        out.push((-c0, -c1, limits.alpha_max));
    }
    // The tip-over diamond |a_t| / A_t± + |κ u| / A_n± ≤ 1 at both ends and the middle.
    if let Some(tp) = tip {
        let (f, b, l, r) = (
            1.0 / tp.forward,
            1.0 / tp.backward,
            1.0 / tp.left,
            1.0 / tp.right,
        );
        let km = 0.5 * (k0 + k1);
        for (n0, n1) in [(k0, 0.0), (0.5 * km, 0.5 * km), (0.0, k1)] {
            // a_n = n0 u0 + n1 u1
            for (ta, na) in [(f, l), (f, -r), (-b, l), (-b, -r)] {
                out.push((-ta * ia + na * n0, ta * ia + na * n1, 1.0));
            }
        }
    }
}

/// The interval `[lo, hi]` of u1 allowed by `cons` for a given u0 (`lo > hi`: none).
fn u1_range(cons: &[Lin], u0: f64, hi0: f64) -> (f64, f64) {
    let (mut lo, mut hi) = (0.0f64, hi0);
    for &(c0, c1, d) in cons {
        let rhs = d - c0 * u0;
        if c1 > 0.0 {
            hi = hi.min(rhs / c1);
        } else if c1 < 0.0 {
            lo = lo.max(rhs / c1);
        } else if rhs < -1e-12 * d.abs().max(1.0) {
            return (1.0, 0.0);
        }
    }
    (lo, hi)
}

fn feasible(lo: f64, hi: f64) -> bool {
    lo <= hi + 1e-12 * hi.abs().max(1e-12)
}

/// Near time-optimal speed profile along `path` for a differential drive, starting at
/// speed `v_start` and ending at (most) `v_end` (m/s).
///
/// The squared speed u = v² is taken linear in s between grid points (constant
/// tangential acceleration per interval). Every interval obeys, as linear constraints
/// in the squared speeds at its ends: `v ≤ v_max`; `|κ| v ≤ ω_max`; `|a| ≤ a_max`;
/// `|α| = |dκ/ds · v² + κ a| ≤ α_max` at both ends (this expression is linear in s along
/// the interval, so it holds all along); and, with `tip`, the planar acceleration of the
/// base (tangential a, lateral κ v²) inside the diamond whose vertices are the four
/// tip-over limits, at both ends and the middle. A backward pass computes for every grid
/// point the largest squared speed from which the rest of the path can still be driven
/// within the limits (each step a one-variable feasibility question, solved by
/// bisection); a forward pass then takes the largest admissible speed at every step
/// (the reachability analysis of TOPP-RA, Pham & Pham 2018, whose greedy forward pass is
/// time-optimal for the discretised problem).
///
/// **Why the diamond is safe.** The ZMP is an affine function of the rigid-body
/// acceleration, so the accelerations that keep it inside the support polygon form a
/// convex set; it contains the four axis points (each limit is the largest acceleration
/// along its axis, `moma::stability::acceleration_limits`), hence their convex hull, the
/// diamond. The limits, and so this guarantee, assume the whole robot translating with
/// the base (the arm held, the base's own rotation neglected).
///
/// **Turn in place.** A path with a [`SmoothPath::pivot`] starts with a rest-to-rest turn
/// in place (trapezoidal in angle under ω_max, α_max; the tip-over limits, which are for
/// translation, do not restrict it), which needs `v_start = 0`.
///
/// **Re-planning without stopping.** With `v_start > 0` the profile continues from that
/// speed. If it exceeds what the path allows at its start, the profile brakes as hard as
/// `min(a_max, tip.backward)` allows, ignoring the other limits, until it is back inside
/// them; [`TimedPath::overspeed_until`] then says up to which arc length.
///
/// # Errors
/// Invalid limits (non-finite or ≤ 0; a tip-over limit NaN or ≤ 0), a negative or
/// non-finite `v_start` / `v_end`, `v_start > 0` with a pivot, a path that cannot be
/// driven (a zero speed limit inside it).
pub fn time_parameterize_curve(
    path: &SmoothPath,
    limits: &DiffDriveLimits,
    tip: Option<&TipOverAcceleration>,
    v_start: f64,
    v_end: f64,
) -> Result<TimedPath> {
    limits.validate()?;
    if let Some(t) = tip {
        t.validate()?;
    }
    for (n, v) in [("v_start", v_start), ("v_end", v_end)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(Error::invalid(
                n,
                format!("must be finite and >= 0, got {v}"),
            ));
        }
    }
    let pivot = pivot_profile(path, limits, v_start)?;
    let t_p = pivot.map_or(0.0, |p| p.prof.duration());
    let (s, kappa) = profile_grid(path.samples());
    let n = s.len();
    if n == 1 {
        return Ok(TimedPath {
            path: path.clone(),
            pivot,
            s,
            kappa,
            t: vec![t_p],
            v: vec![v_start],
            acc: vec![],
            overspeed_until: None,
        });
    }
    let u_max = squared_speed_bound(limits, v_start, s[n - 1] - s[0])?;
    let cap = speed_caps(&kappa, u_max, limits, tip);
    let mut cons = Vec::with_capacity(20);
    let kmax = controllable_speeds(&s, &kappa, &cap, limits, tip, v_end, &mut cons);
    let limits_along = ProfileLimits {
        s: &s,
        kappa: &kappa,
        cap: &cap,
        kmax: &kmax,
    };
    let (u, overspeed_until) = limits_along.forward_pass(limits, tip, v_start, &mut cons);
    let v: Vec<f64> = u.iter().map(|&x| x.sqrt()).collect();
    let (t, acc) = times_and_accelerations(&s, &u, &v, t_p)?;
    Ok(TimedPath {
        path: path.clone(),
        pivot,
        s,
        kappa,
        t,
        v,
        acc,
        overspeed_until,
    })
}

/// The turn in place before `path` (`None` without a pivot), which needs `v_start = 0`.
fn pivot_profile(
    path: &SmoothPath,
    limits: &DiffDriveLimits,
    v_start: f64,
) -> Result<Option<PivotProfile>> {
    if path.pivot() == 0.0 {
        return Ok(None);
    }
    if v_start > 0.0 {
        return Err(Error::invalid(
            "v_start",
            format!(
                "the path starts with a turn in place ({:.3} rad), so it must start at \
                 rest, got {v_start} m/s",
                path.pivot()
            ),
        ));
    }
    let smp = path.samples();
    Ok(Some(PivotProfile {
        prof: Trapezoid::new(path.pivot().abs(), limits.omega_max, limits.alpha_max),
        sign: path.pivot().signum(),
        theta0: path.start_heading(),
        xy: [smp[0].x, smp[0].y],
    }))
}

/// The profile's grid of arc lengths and curvatures: the path's samples, subdivided
/// (linearly) to at least 16 intervals.
fn profile_grid(smp: &[PathSample]) -> (Vec<f64>, Vec<f64>) {
    let intervals = smp.len() - 1;
    let split = if intervals == 0 {
        1
    } else {
        16usize.div_ceil(intervals).max(1)
    };
    let mut s = Vec::with_capacity(intervals * split + 1);
    let mut kappa = Vec::with_capacity(intervals * split + 1);
    s.push(smp[0].s);
    kappa.push(smp[0].kappa);
    for w in smp.windows(2) {
        for k in 1..=split {
            let f = k as f64 / split as f64;
            s.push(w[0].s + f * (w[1].s - w[0].s));
            kappa.push(w[0].kappa + f * (w[1].kappa - w[0].kappa));
        }
    }
    (s, kappa)
}

/// The bound on u = v² along a path of `length` (m): `v_max²`, or the square of the
/// fastest speed any profile reaches, `v_start² + 2 a_max · length`, when that is lower.
/// The second bound changes no profile (no admissible one exceeds it); it keeps u finite
/// when `v_max` is so large (above about 1.3e154 m/s) that its square overflows.
///
/// # Errors
/// `v_start` whose square overflows; `v_max` and `a_max · length` both too large for a
/// finite squared speed.
fn squared_speed_bound(limits: &DiffDriveLimits, v_start: f64, length: f64) -> Result<f64> {
    let u_start = v_start * v_start;
    if !u_start.is_finite() {
        return Err(Error::invalid(
            "v_start",
            format!("must be below 1e150 m/s (its square must be finite), got {v_start}"),
        ));
    }
    let u_max = (limits.v_max * limits.v_max).min(u_start + 2.0 * limits.a_max * length);
    if !u_max.is_finite() {
        return Err(Error::invalid(
            "v_max",
            format!(
                "{} m/s with a_max = {} m/s² on a {length} m path: the squared speed \
                 overflows; v_max must be below 1e150 m/s",
                limits.v_max, limits.a_max
            ),
        ));
    }
    Ok(u_max)
}

/// The static caps on u = v² at every grid point: `u_max` (the squared speed bound),
/// `ω_max / |κ|` and, with `tip`, the lateral tip-over limit on κ v².
fn speed_caps(
    kappa: &[f64],
    u_max: f64,
    limits: &DiffDriveLimits,
    tip: Option<&TipOverAcceleration>,
) -> Vec<f64> {
    kappa
        .iter()
        .map(|&k| {
            let mut c = u_max;
            if k != 0.0 {
                c = c.min((limits.omega_max / k).powi(2));
                if let Some(tp) = tip {
                    let side = if k > 0.0 { tp.left } else { tp.right };
                    c = c.min(side / k.abs());
                }
            }
            c
        })
        .collect()
}

/// The backward pass: the largest controllable u at every grid point (from which the
/// rest of the path can still be driven within the limits, ending at most at `v_end`).
fn controllable_speeds(
    s: &[f64],
    kappa: &[f64],
    cap: &[f64],
    limits: &DiffDriveLimits,
    tip: Option<&TipOverAcceleration>,
    v_end: f64,
    cons: &mut Vec<Lin>,
) -> Vec<f64> {
    let n = s.len();
    let mut kmax = vec![0.0; n];
    kmax[n - 1] = cap[n - 1].min(v_end * v_end);
    for i in (0..n - 1).rev() {
        let h = s[i + 1] - s[i];
        interval_constraints(h, kappa[i], kappa[i + 1], limits, tip, cons);
        let ok = |u0: f64| {
            let (lo, hi) = u1_range(cons, u0, kmax[i + 1].min(cap[i + 1]));
            feasible(lo, hi)
        };
        kmax[i] = if ok(cap[i]) {
            cap[i]
        } else {
            largest_feasible(cap[i], ok)
        };
    }
    kmax
}

/// The largest u0 in `[0, hi]` with `ok(u0)` (`ok(0)` assumed), by bisection to a
/// relative 1e-14 or 60 halvings.
#[inline]
fn largest_feasible(hi: f64, ok: impl Fn(f64) -> bool) -> f64 {
    let (mut a, mut b) = (0.0, hi);
    for _ in 0..60 {
        let m = 0.5 * (a + b);
        if ok(m) {
            a = m;
        } else {
            b = m;
        }
        if b - a <= 1e-14 * b {
            break;
        }
    }
    a
}

/// The grid and the per-point limits of the profile (arc lengths, curvatures, static
/// caps, controllable squared speeds).
struct ProfileLimits<'a> {
    s: &'a [f64],
    kappa: &'a [f64],
    cap: &'a [f64],
    kmax: &'a [f64],
}

impl ProfileLimits<'_> {
    /// The forward pass from u = `v_start`²: the largest admissible u at every step,
    /// braking (and reporting up to which arc length) while faster than the path allows.
    fn forward_pass(
        &self,
        limits: &DiffDriveLimits,
        tip: Option<&TipOverAcceleration>,
        v_start: f64,
        cons: &mut Vec<Lin>,
    ) -> (Vec<f64>, Option<f64>) {
        let (s, kappa, cap, kmax) = (self.s, self.kappa, self.cap, self.kmax);
        let n = s.len();
        let mut u = vec![0.0; n];
        u[0] = v_start * v_start;
        let mut overspeed_until = None;
        let brake = tip.map_or(limits.a_max, |t| t.backward.min(limits.a_max));
        for i in 0..n - 1 {
            let h = s[i + 1] - s[i];
            if u[i] > kmax[i] * (1.0 + 1e-9) + 1e-12 {
                // Faster than the path allows: brake as hard as the tangential limits allow.
                let braked = (u[i] - 2.0 * h * brake).max(0.0);
                u[i + 1] = if braked < kmax[i + 1] {
                    kmax[i + 1].min(u[i])
                } else {
                    braked
                };
                overspeed_until = Some(s[i + 1]);
                continue;
            }
            interval_constraints(h, kappa[i], kappa[i + 1], limits, tip, cons);
            let (lo, hi) = u1_range(cons, u[i].min(kmax[i]), kmax[i + 1].min(cap[i + 1]));
            u[i + 1] = hi.max(lo.min(hi)).max(0.0);
        }
        (u, overspeed_until)
    }
}

/// The times (from `t_p`, the pivot's duration) and the per-interval accelerations of
/// the squared-speed profile `u` (`v` = √u) on the grid `s`.
///
/// # Errors
/// A zero speed at both ends of an interval: the path cannot be driven.
fn times_and_accelerations(
    s: &[f64],
    u: &[f64],
    v: &[f64],
    t_p: f64,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let n = s.len();
    let mut t = vec![t_p; n];
    let mut acc = vec![0.0; n - 1];
    for i in 0..n - 1 {
        let h = s[i + 1] - s[i];
        let vs = v[i] + v[i + 1];
        if vs <= 0.0 {
            return Err(Error::Planning(format!(
                "the path cannot be driven: the speed limit is zero at s = {:.3} m",
                s[i]
            )));
        }
        t[i + 1] = t[i] + 2.0 * h / vs;
        acc[i] = (u[i + 1] - u[i]) / (2.0 * h);
    }
    Ok((t, acc))
}

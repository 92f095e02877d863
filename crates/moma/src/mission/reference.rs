//! The timed reference the platform tracks: samples of pose, speeds and accelerations,
//! built from a planned cell path.

use crate::error::Result;
use crate::planning::curvature::SmoothPath;
use crate::planning::curve_timing::{CurvatureTiming, TimedCurve, time_cells_curved};
use crate::planning::trajectory::{DiffDriveLimits, TipOverAcceleration, time_parameterize_curve};
use crate::planning::{OccupancyGrid, SearchGrid};

/// One reference sample (world frame).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct RefSample {
    /// Mission time (s).
    pub t: f64,
    /// Position x (m).
    pub x: f64,
    /// Position y (m).
    pub y: f64,
    /// Heading (rad).
    pub theta: f64,
    /// Forward speed (m/s).
    pub v: f64,
    /// Yaw rate (rad/s).
    pub omega: f64,
    /// Forward acceleration (m/s²).
    pub a: f64,
    /// Yaw acceleration (rad/s²).
    pub alpha: f64,
}

/// The pose of the driven-axle midpoint P0 (the unicycle point) of a base pose
/// `[x, y, θ]` whose origin lies `d` ahead of it: `[x − d cos θ, y − d sin θ, θ]`.
pub(super) fn axle_pose(base: [f64; 3], d: f64) -> [f64; 3] {
    if d == 0.0 {
        return base;
    }
    let (s, c) = base[2].sin_cos();
    [base[0] - d * c, base[1] - d * s, base[2]]
}

/// The reference of the base frame origin for a reference sample of the axle midpoint
/// (position moved `d` ahead along the reference heading; speeds as they are).
pub(super) fn base_reference(mut r: RefSample, d: f64) -> RefSample {
    if d != 0.0 {
        let (s, c) = r.theta.sin_cos();
        r.x += d * c;
        r.y += d * s;
    }
    r
}

/// A timed reference: samples in increasing time.
///
/// The reference is planned for the unicycle point of the platform, the driven-axle
/// midpoint P0: `samples` are poses and speeds of P0 (its forward speed `v` and the yaw
/// rate are the platform inputs of the reduced model). The base frame origin lies `d`
/// ahead of P0 along the heading, at `(x + d cos θ, y + d sin θ)`; for `d = 0` the two
/// coincide.
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    /// The samples of the axle midpoint (at least one).
    pub samples: Vec<RefSample>,
    /// The smoothed geometric path of the base frame origin (world, m), for drawing.
    pub path: Vec<[f64; 2]>,
    /// The curvature bound the smoothing used (1/m).
    pub kappa_max: f64,
    /// `true` when the path ends with the heading it arrives with (no smooth path ends at
    /// the goal heading); the heading is then taken by a turn in place at the goal.
    pub turn_at_goal: bool,
    /// The geometry the samples follow (of the axle midpoint; the last one when the
    /// reference joins a braking stretch and a new path, see [`brake_along`]).
    pub geometry: SmoothPath,
    /// Arc length along [`Reference::geometry`] of every sample (m); NaN for the samples
    /// of a stop along an earlier path, which are not on it.
    pub arc: Vec<f64>,
    /// `Some(s)` when the timing started faster than the path allows at its start and
    /// braked past some limit of the path (ω_max among them) up to arc length `s`.
    pub overspeed_until: Option<f64>,
}

impl Reference {
    /// First sample time.
    pub fn t_start(&self) -> f64 {
        self.samples[0].t
    }

    /// Last sample time.
    pub fn t_end(&self) -> f64 {
        self.samples[self.samples.len() - 1].t
    }

    /// The reference at mission time `t` (linear interpolation; before the start the
    /// first sample, after the end the last one at rest).
    pub fn at(&self, t: f64) -> RefSample {
        let s = &self.samples;
        if t <= s[0].t {
            return s[0];
        }
        let n = s.len();
        if t >= s[n - 1].t {
            let mut last = s[n - 1];
            last.t = t;
            last.v = 0.0;
            last.omega = 0.0;
            last.a = 0.0;
            last.alpha = 0.0;
            return last;
        }
        let i = s.partition_point(|p| p.t <= t) - 1;
        let (p, q) = (&s[i], &s[i + 1]);
        let dt = q.t - p.t;
        let f = if dt > 0.0 { (t - p.t) / dt } else { 0.0 };
        let lerp = |a: f64, b: f64| a + f * (b - a);
        let dth = crate::control::wrap_angle(q.theta - p.theta);
        RefSample {
            t,
            x: lerp(p.x, q.x),
            y: lerp(p.y, q.y),
            theta: crate::control::wrap_angle(p.theta + f * dth),
            v: lerp(p.v, q.v),
            omega: lerp(p.omega, q.omega),
            a: p.a,
            alpha: p.alpha,
        }
    }
}

/// What the timing of a new reference starts from.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TimingStart {
    /// Mission time of the first sample (s).
    pub t0: f64,
    /// Exact start pose `[x, y, θ]` of the axle midpoint.
    pub pose: [f64; 3],
    /// Current forward speed (m/s).
    pub v: f64,
}

/// Builds a reference from a cell path with the curvature-limited timing of
/// [`time_cells_curved`] (curvature-bounded smoothing against the configuration space
/// from the exact start pose to the exact goal pose, then the near time-optimal time
/// parameterisation under the platform limits and the tip-over accelerations),
/// continuing from the current speed and shifted to mission time `start.t0`. A path that
/// must begin with a turn in place cannot start moving: it is then timed from rest (the
/// robot brakes onto it; the caller's reference starts with `v = 0`). A path that allows
/// less than the current speed at its start is timed from the current speed and brakes
/// onto it, not held to ω_max while braking ([`Reference::overspeed_until`] says so; the
/// mission then stops along the old path instead, [`brake_along`], and times the new
/// path from that stop). When no smooth path ends at the goal pose with `kappa_max`,
/// tighter bounds (2x, 4x) are tried, then the heading the cell path arrives with (see
/// [`Reference`]). `start`, `goal` and `cspace` are those of the axle midpoint; `d`
/// places the base frame origin on the drawn path.
#[allow(clippy::too_many_arguments)]
pub(crate) fn build_reference(
    map: &OccupancyGrid,
    cspace: &SearchGrid,
    cells: &[(usize, usize)],
    start: &TimingStart,
    goal: [f64; 3],
    d: f64,
    limits: &DiffDriveLimits,
    tip: &TipOverAcceleration,
    kappa_max: f64,
    dt: f64,
) -> Result<Reference> {
    let timing = CurvatureTiming {
        limits: *limits,
        tip: *tip,
        kappa_max,
        dt,
    };
    let curve = time_cells_curved(map, cspace, cells, start.pose, start.v, goal, &timing)?;
    Ok(reference_of_curve(curve, start.t0, d))
}

/// The reference of a timed curve of the axle midpoint: its samples at mission time
/// `t0` on, the drawn path of the base frame origin `d` ahead.
pub(crate) fn reference_of_curve(curve: TimedCurve, t0: f64, d: f64) -> Reference {
    let samples = curve
        .samples
        .iter()
        .map(|p| RefSample {
            t: t0 + p.t,
            x: p.x,
            y: p.y,
            theta: crate::control::wrap_angle(p.theta),
            v: p.v,
            omega: p.omega,
            a: p.a,
            alpha: p.alpha,
        })
        .collect();
    let path = curve.geometry;
    let drawn = if d == 0.0 {
        path.points()
    } else {
        path.samples()
            .iter()
            .map(|p| {
                let (s, c) = p.theta.sin_cos();
                [p.x + d * c, p.y + d * s]
            })
            .collect()
    };
    Reference {
        samples,
        path: drawn,
        kappa_max: curve.kappa_max,
        turn_at_goal: curve.turn_at_goal,
        arc: curve.samples.iter().map(|p| p.s).collect(),
        overspeed_until: curve.overspeed_until,
        geometry: path,
    }
}

/// The arc length along `r`'s geometry at mission time `t` (interpolated between
/// samples; clamped to the first and last).
fn arc_at(r: &Reference, t: f64) -> f64 {
    let s = &r.samples;
    let n = s.len();
    if t <= s[0].t {
        return r.arc[0];
    }
    if t >= s[n - 1].t {
        return r.arc[n - 1];
    }
    let i = s.partition_point(|p| p.t <= t) - 1;
    let dt = s[i + 1].t - s[i].t;
    let f = if dt > 0.0 { (t - s[i].t) / dt } else { 0.0 };
    r.arc[i] + f * (r.arc[i + 1] - r.arc[i])
}

/// A stop along the path of `old` from where it is at mission time `t0`, starting at
/// speed `v` (m/s, ≥ 0): the stretch of `old`'s geometry long enough to brake to rest at
/// `min(a_max, tip.backward)` (with 10 % to spare, up to the path's end), timed under
/// the platform limits and the tip-over accelerations from `v` to rest. Its turn rate
/// stays within ω_max wherever the old path admits the braking speeds, as it did the
/// old reference's. Returns the samples, from `t0` every `dt`.
///
/// # Errors
/// As [`time_parameterize_curve`], or [`SmoothPath::from_curvature`].
pub(crate) fn brake_along(
    old: &Reference,
    t0: f64,
    v: f64,
    limits: &DiffDriveLimits,
    tip: &TipOverAcceleration,
    dt: f64,
) -> Result<Vec<RefSample>> {
    let g = &old.geometry;
    let s0 = arc_at(old, t0);
    if !s0.is_finite() {
        return Err(crate::error::Error::invalid(
            "reference",
            "no geometry at this time (it is stopping along a previous path)",
        ));
    }
    let decel = limits.a_max.min(tip.backward);
    let v = v.max(0.0);
    let s1 = (s0 + 1.1 * v * v / (2.0 * decel) + 1e-3).min(g.length());
    let start = g.at(s0);
    let mut pieces = Vec::new();
    let mut prev = start;
    for p in g.samples().iter().filter(|p| p.s > s0 && p.s < s1) {
        pieces.push((p.s - prev.s, prev.kappa, p.kappa));
        prev = *p;
    }
    let end = g.at(s1);
    if s1 > prev.s {
        pieces.push((s1 - prev.s, prev.kappa, end.kappa));
    }
    let stretch = SmoothPath::from_curvature([start.x, start.y, start.theta], &pieces, 0.02)?;
    let timed = time_parameterize_curve(&stretch, limits, Some(tip), v, 0.0)?;
    Ok(timed
        .samples(dt)?
        .iter()
        .map(|p| RefSample {
            t: t0 + p.t,
            x: p.x,
            y: p.y,
            theta: crate::control::wrap_angle(p.theta),
            v: p.v,
            omega: p.omega,
            a: p.a,
            alpha: p.alpha,
        })
        .collect())
}

//! Time-optimal timing of a joint-space path under per-joint velocity and acceleration
//! limits, with circular blends at the waypoints (the path model of Kunz and Stilman,
//! "Time-Optimal Trajectory Generation for Path Following with Bounded Acceleration and
//! Velocity", RSS 2012, which MoveIt's TOTG implements).
//!
//! **Path.** The geometry lives in the weighted coordinates `x_i = w_i q_i` of the
//! [`JointSpace`], so lengths and the blend deviation are in its weighted norm. At each
//! interior waypoint with a turn angle `α`, the corner is replaced by the circular arc
//! tangent to both segments whose distance from the waypoint is at most
//! [`TimingOptions::max_deviation`] and whose tangent points lie at most half-way along
//! either segment; velocity is then continuous along the path.
//!
//! **Blends stay valid.** Each arc is checked with the caller's validity check at states at
//! most the resolution apart (arc length); if any is invalid the deviation is halved, up to
//! [`TimingOptions::blend_halvings`] times, and then the waypoint keeps its corner and the
//! trajectory comes to rest there. The straight pieces between arcs lie on the path's own
//! segments (checked at the resolution by the planner or [`super::shortcut`]).
//!
//! **Timing.** The arc length `s` is cut into a grid (at most
//! [`TimingOptions::path_step`] apart, at least 8 intervals per arc, every piece boundary a
//! grid point) and `u = ṡ²` is taken linear in `s` on each interval, i.e. constant path
//! acceleration `s̈`. On each interval, with `P_i` and `Q_i` the largest `|x_i'(s)|` and
//! `|x_i''(s)|` over it, the limits are imposed as `P_i √u ≤ w_i v_i` and
//! `P_i |s̈| + Q_i max u ≤ w_i a_i`: since `ẋ_i = x_i' ṡ` and `ẍ_i = x_i' s̈ + x_i'' ṡ²`,
//! every joint keeps its limits at **every instant**, not only at grid points. A forward
//! pass (fastest acceleration from rest) and a backward pass (fastest deceleration to rest)
//! give the largest such `u` at every grid point: the time-optimal profile on the grid.
//! On a straight piece `x'' = 0` and `x'` is constant, so the bounds are exact and a single
//! segment is timed as the bang–coast–bang trapezoid (or triangle) up to one grid interval.
//! On an arc the bound on `ẍ_i` adds both terms' largest values (sound, slightly slower
//! than the exact switching-point integration of Kunz and Stilman).

use super::joint_space::{JointPath, JointSpace, StateValidity};
use crate::{Error, Result, error::ensure_finite};

/// The most grid intervals along a path (bounds the memory of the timing).
pub const MAX_GRID_INTERVALS: usize = 2_000_000;
/// The most output samples.
pub const MAX_SAMPLES: usize = 10_000_000;

/// Per-joint limits, in the joints' own units (m/s, rad/s, m/s², rad/s²).
#[derive(Debug, Clone, PartialEq)]
pub struct JointLimits {
    /// Velocity limits, positive.
    pub velocity: Vec<f64>,
    /// Acceleration limits, positive.
    pub acceleration: Vec<f64>,
}

/// The options of [`time_optimal`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TimingOptions {
    /// The largest distance of a blend from its waypoint (weighted norm); 0: stop at every
    /// corner.
    pub max_deviation: f64,
    /// How many times a blend that fails the validity check is retried at half the
    /// deviation before the waypoint keeps its corner.
    pub blend_halvings: usize,
    /// The longest grid interval along the path (weighted norm).
    pub path_step: f64,
    /// The time between output samples (s); the last sample is at the end.
    pub sample_period: f64,
}

impl Default for TimingOptions {
    fn default() -> Self {
        TimingOptions {
            max_deviation: 0.1,
            blend_halvings: 4,
            path_step: 1e-3,
            sample_period: 0.01,
        }
    }
}

/// A timed joint trajectory, sampled.
#[derive(Debug, Clone, PartialEq)]
pub struct JointTrajectory {
    /// Sample times, from 0 to `duration`.
    pub t: Vec<f64>,
    /// Joint positions per sample.
    pub q: Vec<Vec<f64>>,
    /// Joint velocities per sample.
    pub qd: Vec<Vec<f64>>,
    /// Joint accelerations per sample.
    pub qdd: Vec<Vec<f64>>,
    /// The total time.
    pub duration: f64,
    /// The blend deviation used at each interior waypoint of the path (after dropping
    /// repeated waypoints); 0 where it stops.
    pub blend_deviations: Vec<f64>,
    /// Validity checks made on the blends.
    pub checks: u64,
}

/// A piece of the blended path in weighted coordinates.
#[derive(Debug, Clone)]
enum Piece {
    /// `start + s·dir`, `s ∈ [0, len]`, `dir` a unit vector.
    Line {
        start: Vec<f64>,
        dir: Vec<f64>,
        len: f64,
    },
    /// `center + r (ex cos θ + ey sin θ)`, `θ = s / r ∈ [0, angle]`.
    Arc {
        center: Vec<f64>,
        ex: Vec<f64>,
        ey: Vec<f64>,
        r: f64,
        angle: f64,
        /// Per coordinate, `x'` and `x''·(−r)` as harmonics `A cos(θ − ψ)`
        /// ([`Harmonic::new`]), so [`Piece::bounds`] takes no arctangent per call.
        harmonics: Vec<(Harmonic, Harmonic)>,
    },
}

/// `c cos θ + s sin θ` as `amplitude · cos(θ − phase)`.
#[derive(Clone, Copy, Debug)]
struct Harmonic {
    amplitude: f64,
    phase: f64,
}

impl Harmonic {
    fn new(c: f64, s: f64) -> Self {
        Harmonic {
            amplitude: c.hypot(s),
            phase: s.atan2(c),
        }
    }

    /// `max |c cos θ + s sin θ|` over `θ ∈ [a, b]`.
    fn max_abs(&self, a: f64, b: f64) -> f64 {
        if self.amplitude == 0.0 {
            return 0.0;
        }
        // |cos| is 1 at multiples of π.
        let (fa, fb) = (a - self.phase, b - self.phase);
        let k = (fa / std::f64::consts::PI).ceil();
        if k * std::f64::consts::PI <= fb {
            self.amplitude
        } else {
            self.amplitude * fa.cos().abs().max(fb.cos().abs())
        }
    }
}

impl Piece {
    fn len(&self) -> f64 {
        match self {
            Piece::Line { len, .. } => *len,
            Piece::Arc { r, angle, .. } => r * angle,
        }
    }

    /// Position, first and second derivative in `s` at local arc length `s`.
    fn eval(&self, s: f64, x: &mut [f64], dx: &mut [f64], ddx: &mut [f64]) {
        match self {
            Piece::Line { start, dir, .. } => {
                for i in 0..x.len() {
                    x[i] = start[i] + s * dir[i];
                    dx[i] = dir[i];
                    ddx[i] = 0.0;
                }
            }
            Piece::Arc {
                center, ex, ey, r, ..
            } => {
                let (sn, cs) = (s / r).sin_cos();
                for i in 0..x.len() {
                    x[i] = center[i] + r * (ex[i] * cs + ey[i] * sn);
                    dx[i] = -ex[i] * sn + ey[i] * cs;
                    ddx[i] = -(ex[i] * cs + ey[i] * sn) / r;
                }
            }
        }
    }

    /// The largest `|x_i'|` and `|x_i''|` over local arc lengths `[a, b]`.
    fn bounds(&self, a: f64, b: f64, p: &mut [f64], q: &mut [f64]) {
        match self {
            Piece::Line { dir, .. } => {
                for i in 0..p.len() {
                    p[i] = dir[i].abs();
                    q[i] = 0.0;
                }
            }
            Piece::Arc { harmonics, r, .. } => {
                let (ta, tb) = (a / r, b / r);
                for (i, (first, second)) in harmonics.iter().enumerate() {
                    // x' = ey cos θ − ex sin θ, x'' = −(ex cos θ + ey sin θ) / r.
                    p[i] = first.max_abs(ta, tb);
                    q[i] = second.max_abs(ta, tb) / r;
                }
            }
        }
    }
}

/// Blends, checks and times `path` (see the module docs).
///
/// # Errors
/// [`Error::InvalidInput`] naming the field: a path of another dimension or outside the
/// box, limits of the wrong length or not positive, options not positive (the deviation
/// may be 0), a path needing more than [`MAX_GRID_INTERVALS`] grid intervals or more than
/// [`MAX_SAMPLES`] samples.
pub fn time_optimal(
    space: &JointSpace,
    validity: &mut impl StateValidity,
    path: &JointPath,
    limits: &JointLimits,
    options: &TimingOptions,
) -> Result<JointTrajectory> {
    let dim = space.dim();
    check_inputs(space, path, limits, options)?;
    let w = space.weights();
    // Weighted waypoints, repeats dropped.
    let mut pts: Vec<Vec<f64>> = Vec::new();
    for i in 0..path.len() {
        let x: Vec<f64> = path.waypoint(i).iter().zip(w).map(|(q, w)| q * w).collect();
        if pts.last().is_none_or(|p| dist(p, &x) > 0.0) {
            pts.push(x);
        }
    }
    let vx: Vec<f64> = limits.velocity.iter().zip(w).map(|(v, w)| v * w).collect();
    let ax: Vec<f64> = limits
        .acceleration
        .iter()
        .zip(w)
        .map(|(a, w)| a * w)
        .collect();
    let to_q = |x: &[f64]| -> Vec<f64> { x.iter().zip(w).map(|(x, w)| x / w).collect() };
    if pts.len() == 1 {
        let q = to_q(&pts[0]);
        return Ok(JointTrajectory {
            t: vec![0.0],
            q: vec![q],
            qd: vec![vec![0.0; dim]],
            qdd: vec![vec![0.0; dim]],
            duration: 0.0,
            blend_deviations: Vec::new(),
            checks: 0,
        });
    }
    // Blends at the interior waypoints: (tangent distance d, arc), d = 0 without an arc;
    // `stops[k]` for a corner kept at waypoint k.
    let n = pts.len();
    let mut checks = 0u64;
    let mut blend_d = vec![0.0; n];
    let mut arcs: Vec<Option<Piece>> = vec![None; n];
    let mut stops = vec![false; n];
    let mut blend_deviations = Vec::with_capacity(n.saturating_sub(2));
    let mut q_scratch = vec![0.0; dim];
    for k in 1..n - 1 {
        let (l1, l2) = (dist(&pts[k - 1], &pts[k]), dist(&pts[k], &pts[k + 1]));
        let y1: Vec<f64> = (0..dim).map(|i| (pts[k][i] - pts[k - 1][i]) / l1).collect();
        let y2: Vec<f64> = (0..dim).map(|i| (pts[k + 1][i] - pts[k][i]) / l2).collect();
        let cos = y1
            .iter()
            .zip(&y2)
            .map(|(a, b)| a * b)
            .sum::<f64>()
            .clamp(-1.0, 1.0);
        let alpha = cos.acos();
        if alpha < 1e-9 {
            blend_deviations.push(0.0);
            continue; // straight on: no corner
        }
        let mut deviation = options.max_deviation;
        let mut chosen = None;
        if std::f64::consts::PI - alpha > 1e-6 {
            for _ in 0..=options.blend_halvings {
                if deviation <= 0.0 {
                    break;
                }
                let (d, arc, actual) = blend(&pts[k], &y1, &y2, l1, l2, alpha, deviation);
                if arc_valid(space, validity, &arc, &mut q_scratch, &mut checks) {
                    chosen = Some((d, arc, actual));
                    break;
                }
                deviation *= 0.5;
            }
        }
        match chosen {
            Some((d, arc, actual)) => {
                blend_d[k] = d;
                arcs[k] = Some(arc);
                blend_deviations.push(actual);
            }
            None => {
                stops[k] = true;
                blend_deviations.push(0.0);
            }
        }
    }
    // Pieces in order, and which grid node must be at rest.
    let mut pieces: Vec<Piece> = Vec::new();
    let mut rest_after: Vec<bool> = Vec::new(); // rest at the end of piece j
    for k in 0..n - 1 {
        let l = dist(&pts[k], &pts[k + 1]);
        let dir: Vec<f64> = (0..dim).map(|i| (pts[k + 1][i] - pts[k][i]) / l).collect();
        let start: Vec<f64> = (0..dim).map(|i| pts[k][i] + blend_d[k] * dir[i]).collect();
        let len = l - blend_d[k] - blend_d[k + 1];
        if len > 0.0 {
            pieces.push(Piece::Line { start, dir, len });
            rest_after.push(stops[k + 1]);
        } else if let Some(last) = rest_after.last_mut() {
            *last |= stops[k + 1];
        }
        if let Some(arc) = arcs[k + 1].take() {
            pieces.push(arc);
            rest_after.push(false);
        }
    }
    // The grid: nodes at global arc length `s`, interval j on piece `piece[j]` from local
    // arc length `local[j]` to `local[j] + (s[j + 1] − s[j])`.
    let mut intervals = 0usize;
    for p in &pieces {
        intervals = intervals.saturating_add(piece_intervals(p, options.path_step));
    }
    if intervals > MAX_GRID_INTERVALS {
        return Err(Error::invalid(
            "path_step",
            format!(
                "{} needs {intervals} grid intervals along the path; at most {MAX_GRID_INTERVALS}",
                options.path_step
            ),
        ));
    }
    let mut s = Vec::with_capacity(intervals + 1);
    let mut piece_of = Vec::with_capacity(intervals);
    let mut local = Vec::with_capacity(intervals);
    let mut cap = Vec::with_capacity(intervals + 1); // u bound per node
    s.push(0.0);
    cap.push(0.0);
    let (mut pb, mut qb) = (vec![0.0; dim], vec![0.0; dim]);
    let mut interval_cap = Vec::with_capacity(intervals);
    for (j, p) in pieces.iter().enumerate() {
        let m = piece_intervals(p, options.path_step);
        let (len, s0) = (p.len(), *s.last().unwrap_or(&0.0));
        for k in 0..m {
            let (a, b) = (len * k as f64 / m as f64, len * (k + 1) as f64 / m as f64);
            p.bounds(a, b, &mut pb, &mut qb);
            let mut c = f64::INFINITY;
            for i in 0..dim {
                if pb[i] > 0.0 {
                    c = c.min((vx[i] / pb[i]).powi(2));
                }
                if qb[i] > 0.0 {
                    c = c.min(ax[i] / qb[i]);
                }
            }
            interval_cap.push(c);
            piece_of.push(j as u32);
            local.push(a);
            s.push(s0 + b);
            let last = cap.len() - 1;
            cap[last] = f64::min(cap[last], c);
            cap.push(c);
        }
        if rest_after[j] {
            let last = cap.len() - 1;
            cap[last] = 0.0;
        }
    }
    let last = cap.len() - 1;
    cap[last] = 0.0;
    // Forward then backward pass on u = ṡ².
    let reach = |j: usize, u_from: f64, pb: &mut [f64], qb: &mut [f64]| -> f64 {
        let step = s[j + 1] - s[j];
        let p = &pieces[piece_of[j] as usize];
        p.bounds(local[j], local[j] + step, pb, qb);
        let mut best = f64::INFINITY;
        for i in 0..dim {
            let den = pb[i] / (2.0 * step) + qb[i];
            if den > 0.0 {
                best = best.min((ax[i] + pb[i] * u_from / (2.0 * step)) / den);
            }
        }
        best
    };
    let mut u = cap;
    for j in 0..intervals {
        let r = reach(j, u[j], &mut pb, &mut qb);
        u[j + 1] = u[j + 1].min(r);
    }
    for j in (0..intervals).rev() {
        let r = reach(j, u[j + 1], &mut pb, &mut qb);
        u[j] = u[j].min(r);
    }
    // Times of the grid nodes.
    let mut t = Vec::with_capacity(intervals + 1);
    t.push(0.0);
    for j in 0..intervals {
        let den = u[j].sqrt() + u[j + 1].sqrt();
        if den.is_nan() || den <= 0.0 {
            return Err(Error::Numerical {
                t: t[j],
                message: format!("path speed zero on both ends of grid interval {j}"),
            });
        }
        t.push(t[j] + 2.0 * (s[j + 1] - s[j]) / den);
    }
    let duration = t[intervals];
    let samples = (duration / options.sample_period).ceil();
    if samples.is_nan() || samples >= MAX_SAMPLES as f64 {
        return Err(Error::invalid(
            "sample_period",
            format!(
                "{} s gives {samples} samples over {duration} s; at most {MAX_SAMPLES}",
                options.sample_period
            ),
        ));
    }
    let samples = samples as usize;
    let mut out = JointTrajectory {
        t: Vec::with_capacity(samples + 1),
        q: Vec::with_capacity(samples + 1),
        qd: Vec::with_capacity(samples + 1),
        qdd: Vec::with_capacity(samples + 1),
        duration,
        blend_deviations,
        checks,
    };
    let (mut x, mut dx, mut ddx) = (vec![0.0; dim], vec![0.0; dim], vec![0.0; dim]);
    let mut j = 0;
    for k in 0..=samples {
        let time = if k == samples {
            duration
        } else {
            k as f64 * options.sample_period
        };
        while j + 1 < intervals && t[j + 1] <= time {
            j += 1;
        }
        let step = s[j + 1] - s[j];
        let sdd = (u[j + 1] - u[j]) / (2.0 * step);
        let tau = (time - t[j]).clamp(0.0, t[j + 1] - t[j]);
        let v0 = u[j].sqrt();
        let ds = (v0 * tau + 0.5 * sdd * tau * tau).clamp(0.0, step);
        let sd = (v0 + sdd * tau).max(0.0);
        pieces[piece_of[j] as usize].eval(local[j] + ds, &mut x, &mut dx, &mut ddx);
        out.t.push(time);
        out.q.push(to_q(&x));
        out.qd.push((0..dim).map(|i| dx[i] * sd / w[i]).collect());
        out.qdd.push(
            (0..dim)
                .map(|i| (dx[i] * sdd + ddx[i] * sd * sd) / w[i])
                .collect(),
        );
    }
    Ok(out)
}

fn check_inputs(
    space: &JointSpace,
    path: &JointPath,
    limits: &JointLimits,
    options: &TimingOptions,
) -> Result<()> {
    let dim = space.dim();
    if path.dim() != dim || path.is_empty() {
        return Err(Error::invalid(
            "path",
            format!(
                "{} waypoints of {} joints; needs at least one of {dim}",
                path.len(),
                path.dim()
            ),
        ));
    }
    for i in 0..path.len() {
        space.check_state(&format!("path waypoint {i}"), path.waypoint(i))?;
    }
    for (field, values) in [
        ("velocity limits", &limits.velocity),
        ("acceleration limits", &limits.acceleration),
    ] {
        crate::error::ensure_len(field, dim, values.len())?;
        ensure_finite(field, values)?;
        if let Some(i) = values.iter().position(|v| *v <= 0.0) {
            return Err(Error::invalid(
                format!("{field}[{i}]"),
                format!("{} is not positive", values[i]),
            ));
        }
    }
    ensure_finite(
        "timing options",
        [
            &options.max_deviation,
            &options.path_step,
            &options.sample_period,
        ],
    )?;
    if options.max_deviation < 0.0 {
        return Err(Error::invalid("max_deviation", "is negative"));
    }
    if options.path_step <= 0.0 {
        return Err(Error::invalid("path_step", "is not positive"));
    }
    if options.sample_period <= 0.0 {
        return Err(Error::invalid("sample_period", "is not positive"));
    }
    if options.blend_halvings > 60 {
        return Err(Error::invalid("blend_halvings", "is above 60"));
    }
    Ok(())
}

/// Grid intervals of a piece: at most `path_step` long, at least 8 on an arc.
fn piece_intervals(piece: &Piece, path_step: f64) -> usize {
    let m = (piece.len() / path_step).ceil();
    let m = if m.is_finite() {
        m.min(usize::MAX as f64) as usize
    } else {
        usize::MAX
    };
    match piece {
        Piece::Line { .. } => m.max(1),
        Piece::Arc { .. } => m.max(8),
    }
}

fn dist(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (y - x) * (y - x))
        .sum::<f64>()
        .sqrt()
}

/// The arc at `corner` between unit directions `y1` (in) and `y2` (out) turning by
/// `alpha`, at most `deviation` from the corner and reaching at most half of either
/// segment: returns the tangent distance, the arc and its actual deviation.
fn blend(
    corner: &[f64],
    y1: &[f64],
    y2: &[f64],
    l1: f64,
    l2: f64,
    alpha: f64,
    deviation: f64,
) -> (f64, Piece, f64) {
    let half = 0.5 * alpha;
    let d = (0.5 * l1)
        .min(0.5 * l2)
        .min(deviation * half.sin() / (1.0 - half.cos()));
    let r = d / half.tan();
    let diff: Vec<f64> = y2.iter().zip(y1).map(|(a, b)| a - b).collect();
    let diff_norm = diff.iter().map(|v| v * v).sum::<f64>().sqrt();
    let center: Vec<f64> = (0..corner.len())
        .map(|i| corner[i] + diff[i] / diff_norm * r / half.cos())
        .collect();
    let ex: Vec<f64> = (0..corner.len())
        .map(|i| (corner[i] - d * y1[i] - center[i]) / r)
        .collect();
    let actual = d * (1.0 - half.cos()) / half.sin();
    let harmonics = ex
        .iter()
        .zip(y1)
        .map(|(&x, &y)| (Harmonic::new(y, -x), Harmonic::new(x, y)))
        .collect();
    let arc = Piece::Arc {
        harmonics,
        center,
        ex,
        ey: y1.to_vec(),
        r,
        angle: alpha,
    };
    (d, arc, actual)
}

/// Checks the arc's states at most the resolution apart in arc length.
fn arc_valid(
    space: &JointSpace,
    validity: &mut impl StateValidity,
    arc: &Piece,
    q: &mut [f64],
    checks: &mut u64,
) -> bool {
    let len = arc.len();
    let m = (len / space.resolution()).ceil().max(1.0) as usize;
    let dim = space.dim();
    let (mut x, mut dx, mut ddx) = (vec![0.0; dim], vec![0.0; dim], vec![0.0; dim]);
    for k in 0..=m {
        arc.eval(len * k as f64 / m as f64, &mut x, &mut dx, &mut ddx);
        for i in 0..dim {
            q[i] = x[i] / space.weights()[i];
        }
        *checks += 1;
        if !space.contains(q) || !validity.is_valid(q) {
            return false;
        }
    }
    true
}

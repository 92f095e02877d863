//! Curvature-bounded smoothing of grid paths for a differential drive.
//!
//! [`smooth_diff_drive`] turns the cell path of a search on the footprint-dilated C-space
//! ([`SearchGrid`]) into a path the platform can drive forwards without stopping: it starts
//! at the exact start pose and ends at the exact goal pose `[x, y, θ]` (world metres, not
//! cell centres), its heading is continuous, its curvature is continuous, piecewise linear
//! in arc length and bounded by `κ_max`, and every point of it lies in a free C-space cell.
//!
//! # Method
//!
//! 1. **Polyline.** The cell centres (the first and last cell replaced by the exact start
//!    and goal positions) are shortcut greedily to a line-of-sight polyline: from each kept
//!    vertex, jump to the farthest following point whose straight segment crosses only free
//!    cells (an exact cell traversal in the map frame). The shortcut first keeps a
//!    clearance margin ([`SmoothOptions::clearance`], measured with the exact distance
//!    transform of the C-space and never more than the grid path's own clearance there), so
//!    that the corner blends, which cut inside the corners, have room; when that fails the
//!    margin is halved, down to zero.
//! 2. **Start and goal poses.** A short stub along the start heading (start → start +
//!    e·h) and one along the goal heading (goal − e·h → goal) are added as the polyline's
//!    first and last segments, so the path leaves and enters along the exact headings; the
//!    stub length e is the shortest of a ladder (multiples of `1/κ_max`) for which the
//!    stub's corner blend fits and is free. When the start heading points away from the
//!    first segment by more than [`SmoothOptions::max_start_turn`], or no start stub works,
//!    the robot **turns in place at the start** toward the first segment instead: the path
//!    then records that pivot ([`SmoothPath::pivot`], a signed angle) and its samples begin
//!    with the heading after the pivot. No turn in place happens anywhere else.
//! 3. **Corner blends.** Every corner of deflection δ is replaced by a symmetric
//!    continuous-curvature turn: a clothoid (κ rising linearly from 0 at sharpness σ), a
//!    circular arc of curvature κ_c, and the mirror clothoid (or two clothoids alone when δ
//!    is too small to reach κ_c). Each corner tries the loosest blend of a ladder (κ_c =
//!    κ_max/λ, σ = σ_max/λ², λ = 6, 4, 3, 2, 1.5, 1: the same shape scaled by λ) whose
//!    tangent length fits its share of the two segments and whose curve crosses only free
//!    cells, so corners shrink toward the tightest admissible turn only where space
//!    requires. Two corners turning the same way without room between them are merged
//!    into one at the intersection of the outer segments (when the two new segments are
//!    free); a corner whose every turn crosses an obstacle is moved outward along its
//!    bisector, by up to three times the cut of its tightest turn, when the two new
//!    segments are free.
//! 4. **Check.** The assembled path is sampled every [`SmoothOptions::ds`] plus at every
//!    piece boundary, and the cells crossed by the chords between samples are checked once
//!    more against the C-space.
//!
//! When no variant works the error names the corner (world position) or the end that
//! failed and why (no room for the tightest blend, or the blend crosses an obstacle).
//! Curvature is continuous, so the time parameterisation
//! ([`super::trajectory::time_parameterize_curve`]) never has to stop at a corner.

use super::MAX_TRAJECTORY_SAMPLES;
use super::astar::SearchGrid;
use super::edt::distance_transform;
use super::grid::OccupancyGrid;
use crate::{Error, Result};
use std::f64::consts::PI;

/// One sample of a [`SmoothPath`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PathSample {
    /// Arc length from the start (m).
    pub s: f64,
    /// Position x in the map's world frame (m).
    pub x: f64,
    /// Position y (m).
    pub y: f64,
    /// Heading (rad), continuous along the path (not wrapped).
    pub theta: f64,
    /// Signed curvature dθ/ds (1/m), positive turning left.
    pub kappa: f64,
}

/// Options of [`smooth_diff_drive`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SmoothOptions {
    /// Largest |curvature| (1/m): the tightest turn has radius `1 / kappa_max`.
    pub kappa_max: f64,
    /// Sample spacing along the path (m).
    pub ds: f64,
    /// Largest |dκ/ds| (1/m²) of the clothoids. At speed v a clothoid needs an angular
    /// acceleration σ v², so this trades tight corners for corner speed.
    pub sharpness_max: f64,
    /// Largest start deflection (rad) taken by a forward turn; beyond it the robot turns
    /// in place at the start.
    pub max_start_turn: f64,
    /// Preferred clearance (m) of the polyline to the C-space obstacles, relaxed where
    /// the grid path itself is closer or no path keeps it.
    pub clearance: f64,
}

impl SmoothOptions {
    /// Options for a curvature bound `kappa_max` (1/m): `ds` 0.02 m, `sharpness_max`
    /// 2 κ_max² (a clothoid reaches κ_max within 1/(2 κ_max) of arc), `max_start_turn`
    /// π/2, `clearance` 1/(2 κ_max) (half the tightest radius).
    pub fn new(kappa_max: f64) -> Self {
        Self {
            kappa_max,
            ds: 0.02,
            sharpness_max: 2.0 * kappa_max * kappa_max,
            max_start_turn: 0.5 * PI,
            clearance: 0.5 / kappa_max,
        }
    }

    fn validate(&self) -> Result<()> {
        for (n, v) in [
            ("kappa_max", self.kappa_max),
            ("ds", self.ds),
            ("sharpness_max", self.sharpness_max),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(Error::invalid(
                    n,
                    format!("must be finite and > 0, got {v}"),
                ));
            }
        }
        if !(self.max_start_turn.is_finite() && (0.0..=PI).contains(&self.max_start_turn)) {
            return Err(Error::invalid(
                "max_start_turn",
                format!("must lie in [0, π], got {}", self.max_start_turn),
            ));
        }
        if !(self.clearance.is_finite() && self.clearance >= 0.0) {
            return Err(Error::invalid(
                "clearance",
                format!("must be finite and >= 0, got {}", self.clearance),
            ));
        }
        Ok(())
    }
}

impl Default for SmoothOptions {
    /// [`SmoothOptions::new`]`(2.0)`: turns of radius ≥ 0.5 m.
    fn default() -> Self {
        Self::new(2.0)
    }
}

/// A piece of constant or linearly varying curvature.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Piece {
    s0: f64,
    len: f64,
    k0: f64,
    k1: f64,
    x0: f64,
    y0: f64,
    th0: f64,
}

/// Gauss–Legendre nodes and weights on [−1, 1], 5 points (exact for degree 9).
const GL5: [(f64, f64); 5] = [
    (0.0, 0.568_888_888_888_888_9),
    (-0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (0.538_469_310_105_683_1, 0.478_628_670_499_366_5),
    (-0.906_179_845_938_664, 0.236_926_885_056_189_1),
    (0.906_179_845_938_664, 0.236_926_885_056_189_1),
];

impl Piece {
    /// (x, y, θ, κ) at arc length `u` into the piece.
    fn eval(&self, u: f64) -> (f64, f64, f64, f64) {
        let dk = if self.len > 0.0 {
            (self.k1 - self.k0) / self.len
        } else {
            0.0
        };
        let th = |w: f64| self.th0 + self.k0 * w + 0.5 * dk * w * w;
        let kappa = self.k0 + dk * u;
        let theta = th(u);
        let (x, y) = if dk == 0.0 && self.k0 == 0.0 {
            (self.x0 + u * self.th0.cos(), self.y0 + u * self.th0.sin())
        } else if dk == 0.0 {
            let k = self.k0;
            (
                self.x0 + (theta.sin() - self.th0.sin()) / k,
                self.y0 - (theta.cos() - self.th0.cos()) / k,
            )
        } else {
            // Composite 5-point Gauss–Legendre on sub-intervals of at most 5 cm: the
            // integrand cos/sin of a quadratic is integrated to rounding error.
            let n = ((u / 0.05).ceil() as usize).max(1);
            let h = u / n as f64;
            let (mut x, mut y) = (self.x0, self.y0);
            for i in 0..n {
                let mid = (i as f64 + 0.5) * h;
                for &(z, w) in &GL5 {
                    let (s, c) = th(mid + 0.5 * h * z).sin_cos();
                    x += 0.5 * h * w * c;
                    y += 0.5 * h * w * s;
                }
            }
            (x, y)
        };
        (x, y, theta, kappa)
    }
}

/// A smooth, curvature-bounded path from [`smooth_diff_drive`].
#[derive(Debug, Clone, PartialEq)]
pub struct SmoothPath {
    pieces: Vec<Piece>,
    samples: Vec<PathSample>,
    length: f64,
    pivot: f64,
    start_heading: f64,
}

impl SmoothPath {
    /// Total arc length (m); 0 for a turn in place alone.
    pub fn length(&self) -> f64 {
        self.length
    }

    /// The samples, every `ds` of arc length plus every boundary of the path's pieces
    /// (curvature is linear between consecutive samples), the first at s = 0 and the last
    /// at s = [`SmoothPath::length`].
    pub fn samples(&self) -> &[PathSample] {
        &self.samples
    }

    /// The exact path point at arc length `s` (clamped to `[0, length]`), found by binary
    /// search over the pieces (O(log n)).
    pub fn at(&self, s: f64) -> PathSample {
        let s = if s.is_nan() {
            0.0
        } else {
            s.clamp(0.0, self.length)
        };
        if self.pieces.is_empty() {
            return self.samples[0];
        }
        let i = self.pieces.partition_point(|p| p.s0 <= s).saturating_sub(1);
        let p = &self.pieces[i];
        let (x, y, theta, kappa) = p.eval((s - p.s0).min(p.len));
        PathSample {
            s,
            x,
            y,
            theta,
            kappa,
        }
    }

    /// The largest |κ| of the path (1/m) (κ is linear between samples, so this is exact).
    pub fn max_abs_curvature(&self) -> f64 {
        self.samples.iter().fold(0.0, |m, p| m.max(p.kappa.abs()))
    }

    /// The sample positions `[x, y]`.
    pub fn points(&self) -> Vec<[f64; 2]> {
        self.samples.iter().map(|p| [p.x, p.y]).collect()
    }

    /// The signed turn in place (rad, positive counter-clockwise) the robot makes at the
    /// start before driving the path; 0 when it drives off directly. The samples begin
    /// with the heading after the pivot: `samples()[0].theta = start θ + pivot`.
    pub fn pivot(&self) -> f64 {
        self.pivot
    }

    /// The start heading before the pivot (rad), as given.
    pub fn start_heading(&self) -> f64 {
        self.start_heading
    }

    /// A path given by its curvature profile: from `start` (`[x, y, θ]`), pieces
    /// `(length, κ at the piece's start, κ at its end)` with κ linear in between (a line,
    /// an arc or a clothoid), sampled every `ds`. No map and no curvature bound are
    /// involved: this builds known geometries (a straight line, a circle) to time, or a
    /// path planned elsewhere.
    ///
    /// # Errors
    /// Non-finite values, a negative piece length, a non-positive `ds`, or more than
    /// [`MAX_TRAJECTORY_SAMPLES`] samples.
    pub fn from_curvature(start: [f64; 3], pieces: &[(f64, f64, f64)], ds: f64) -> Result<Self> {
        crate::error::ensure_finite("start pose", start.iter())?;
        for (i, &(len, k0, k1)) in pieces.iter().enumerate() {
            crate::error::ensure_finite(&format!("piece {i}"), [len, k0, k1].iter())?;
            if len < 0.0 {
                return Err(Error::invalid(
                    format!("piece {i} length"),
                    format!("must be >= 0, got {len}"),
                ));
            }
        }
        if !(ds.is_finite() && ds > 0.0) {
            return Err(Error::invalid(
                "ds",
                format!("must be finite and > 0, got {ds}"),
            ));
        }
        let total: f64 = pieces.iter().map(|p| p.0).sum();
        let count = total / ds + pieces.len() as f64 + 2.0;
        if count > MAX_TRAJECTORY_SAMPLES as f64 {
            return Err(Error::invalid(
                "ds",
                format!(
                    "a {total:.3} m path sampled every {ds} m needs {count:.3e} samples, more \
                     than the limit of {MAX_TRAJECTORY_SAMPLES}"
                ),
            ));
        }
        let ps = chain(pieces, 0.0, (start[0], start[1], start[2]));
        Ok(sample_pieces(
            ps,
            [start[0], start[1]],
            start[2],
            0.0,
            start[2],
            ds,
        ))
    }
}

/// Samples pieces every `ds` plus at every piece boundary (the count was checked).
fn sample_pieces(
    pieces: Vec<Piece>,
    sxy: [f64; 2],
    th0: f64,
    pivot: f64,
    start_heading: f64,
    ds: f64,
) -> SmoothPath {
    let length = pieces.last().map_or(0.0, |p| p.s0 + p.len);
    let mut samples = Vec::with_capacity((length / ds) as usize + pieces.len() + 2);
    samples.push(PathSample {
        s: 0.0,
        x: sxy[0],
        y: sxy[1],
        theta: th0,
        kappa: pieces.first().map_or(0.0, |p| p.k0),
    });
    for p in &pieces {
        let n = ((p.len / ds).ceil() as usize).max(1);
        for k in 1..=n {
            let u = p.len * k as f64 / n as f64;
            let (x, y, theta, kappa) = p.eval(u);
            samples.push(PathSample {
                s: p.s0 + u,
                x,
                y,
                theta,
                kappa,
            });
        }
    }
    SmoothPath {
        pieces,
        samples,
        length,
        pivot,
        start_heading,
    }
}

/// Map frame and C-space for the checks.
struct Space<'a> {
    cs: &'a SearchGrid,
    frame: &'a OccupancyGrid,
    /// Distance (cells) to the nearest C-space obstacle over a window of the grid.
    dist: Vec<f32>,
    win: (i64, i64, usize, usize),
}

impl Space<'_> {
    fn to_cell(&self, p: [f64; 2]) -> [f64; 2] {
        self.frame.world_to_cell_f(p[0], p[1])
    }

    fn clearance_at(&self, ix: i64, iy: i64) -> f32 {
        let (x0, y0, w, h) = self.win;
        let (lx, ly) = (ix - x0, iy - y0);
        if lx < 0 || ly < 0 || lx as usize >= w || ly as usize >= h {
            f32::INFINITY
        } else {
            self.dist[ly as usize * w + lx as usize]
        }
    }

    /// `true` if the segment between two world points crosses only free cells whose
    /// clearance is at least `min_clear` cells.
    fn segment_free(&self, a: [f64; 2], b: [f64; 2], min_clear: f32) -> bool {
        let (p, q) = (self.to_cell(a), self.to_cell(b));
        traverse(p, q, |x, y| {
            self.cs.is_free(x, y) && (min_clear <= 0.0 || self.clearance_at(x, y) >= min_clear)
        })
    }
}

/// Visits the cells (unit squares `[i, i+1) × [j, j+1)`) a segment in continuous cell
/// coordinates crosses, in order (Amanatides & Woo 1987); where it passes exactly through
/// a corner both side cells are visited too. Stops and returns `false` at the first cell
/// `f` rejects.
fn traverse(p: [f64; 2], q: [f64; 2], mut f: impl FnMut(i64, i64) -> bool) -> bool {
    let cell = |v: f64| v.floor() as i64;
    let (mut ix, mut iy) = (cell(p[0]), cell(p[1]));
    let (ex, ey) = (cell(q[0]), cell(q[1]));
    if !f(ix, iy) {
        return false;
    }
    let (dx, dy) = (q[0] - p[0], q[1] - p[1]);
    let step = |d: f64| {
        if d > 0.0 {
            1
        } else if d < 0.0 {
            -1
        } else {
            0
        }
    };
    let (sx, sy) = (step(dx), step(dy));
    let t_delta = |d: f64| {
        if d != 0.0 {
            1.0 / d.abs()
        } else {
            f64::INFINITY
        }
    };
    let t_first = |pv: f64, i: i64, d: f64| {
        if d > 0.0 {
            ((i + 1) as f64 - pv) / d
        } else if d < 0.0 {
            (i as f64 - pv) / d
        } else {
            f64::INFINITY
        }
    };
    let (tdx, tdy) = (t_delta(dx), t_delta(dy));
    let (mut tmx, mut tmy) = (t_first(p[0], ix, dx), t_first(p[1], iy, dy));
    let n = (ex - ix).abs() + (ey - iy).abs() + 2;
    for _ in 0..n {
        if ix == ex && iy == ey {
            return true;
        }
        if (tmx - tmy).abs() <= 1e-12 * tmx.abs().max(1.0) {
            if !f(ix + sx, iy) || !f(ix, iy + sy) {
                return false;
            }
            ix += sx;
            iy += sy;
            tmx += tdx;
            tmy += tdy;
        } else if tmx < tmy {
            ix += sx;
            tmx += tdx;
        } else {
            iy += sy;
            tmy += tdy;
        }
        if !f(ix, iy) {
            return false;
        }
    }
    // Rounding left the walk short of the end cell: check it too.
    f(ex, ey)
}

/// Geometry of a symmetric continuous-curvature corner blend (left turn, canonical frame:
/// starts at the origin heading +x).
#[derive(Debug, Clone, Copy)]
struct Blend {
    /// Distance from the corner vertex to each tangent point.
    t: f64,
    /// Peak curvature (κ_c, or less for a clothoid pair).
    kp: f64,
    /// Length of each clothoid.
    lc: f64,
    /// Length of the arc (0 for a clothoid pair).
    la: f64,
    /// Distance from the vertex to the blend's midpoint (how far it cuts the corner).
    dev: f64,
}

fn blend(delta: f64, kc: f64, sigma: f64) -> Blend {
    let d = delta.abs();
    let (kp, lc, la) = if d >= kc * kc / sigma {
        (kc, kc / sigma, (d - kc * kc / sigma) / kc)
    } else {
        let kp = (d * sigma).sqrt();
        (kp, kp / sigma, 0.0)
    };
    // Half blend: the clothoid, then half the arc, ending at heading δ/2.
    let c = Piece {
        s0: 0.0,
        len: lc,
        k0: 0.0,
        k1: kp,
        x0: 0.0,
        y0: 0.0,
        th0: 0.0,
    };
    let (x1, y1, th1, _) = c.eval(lc);
    let a = Piece {
        s0: 0.0,
        len: 0.5 * la,
        k0: kp,
        k1: kp,
        x0: x1,
        y0: y1,
        th0: th1,
    };
    let (xm, ym, _, _) = if la > 0.0 {
        a.eval(0.5 * la)
    } else {
        (x1, y1, th1, kp)
    };
    // The midpoint lies on the corner's bisector: V = (t, 0), M = V + r (−sin δ/2, cos δ/2).
    let t = xm + ym * (0.5 * d).tan();
    let dev = ym / (0.5 * d).cos();
    Blend { t, kp, lc, la, dev }
}

/// Scale ladder of the blends, loosest first.
const LADDER: [f64; 6] = [6.0, 4.0, 3.0, 2.0, 1.5, 1.0];

/// Stub lengths tried at the start and the goal, in units of 1/κ_max.
const STUBS: [f64; 13] = [
    0.25, 0.5, 0.75, 1.0, 1.25, 1.5, 1.75, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0,
];

/// The curvature pieces `(len, k0, k1)` of a blend turning left (`sign` 1) or right (−1).
fn blend_pieces(b: &Blend, sign: f64) -> Vec<(f64, f64, f64)> {
    let mut v = vec![(b.lc, 0.0, sign * b.kp)];
    if b.la > 0.0 {
        v.push((b.la, sign * b.kp, sign * b.kp));
    }
    v.push((b.lc, sign * b.kp, 0.0));
    v
}

/// Chains curvature pieces `(len, k0, k1)` from a pose.
fn chain(parts: &[(f64, f64, f64)], s0: f64, pose: (f64, f64, f64)) -> Vec<Piece> {
    let mut out = Vec::with_capacity(parts.len());
    let (mut s, mut x, mut y, mut th) = (s0, pose.0, pose.1, pose.2);
    for &(len, k0, k1) in parts {
        if len <= 1e-12 {
            continue;
        }
        let p = Piece {
            s0: s,
            len,
            k0,
            k1,
            x0: x,
            y0: y,
            th0: th,
        };
        let (nx, ny, nth, _) = p.eval(len);
        out.push(p);
        s += len;
        x = nx;
        y = ny;
        th = nth;
    }
    out
}

/// `true` if the pieces cross only free cells (chords every ≤ ¼ cell).
fn pieces_free(sp: &Space<'_>, pieces: &[Piece]) -> bool {
    let step = 0.25 * sp.frame.resolution;
    for p in pieces {
        let n = ((p.len / step).ceil() as usize).max(1);
        let (mut px, mut py, _, _) = p.eval(0.0);
        for k in 1..=n {
            let (x, y, _, _) = p.eval(p.len * k as f64 / n as f64);
            if !sp.segment_free([px, py], [x, y], 0.0) {
                return false;
            }
            px = x;
            py = y;
        }
    }
    true
}

fn wrap(a: f64) -> f64 {
    let mut a = a % std::f64::consts::TAU;
    if a > PI {
        a -= std::f64::consts::TAU;
    } else if a <= -PI {
        a += std::f64::consts::TAU;
    }
    a
}

fn dir(a: [f64; 2], b: [f64; 2]) -> f64 {
    (b[1] - a[1]).atan2(b[0] - a[0])
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (b[0] - a[0]).hypot(b[1] - a[1])
}

/// Why an attempt failed: which corner (index into the polyline) and a message.
struct Failure {
    corner: usize,
    message: String,
}

/// The end of the path an attempt's failure is blamed on.
enum End {
    Start,
    Goal,
    Other,
}

/// Greedy line-of-sight shortcut of the points `d`; `clear[k]` is the clearance (cells)
/// at `d[k]`, `margin` the clearance wanted (cells). Returns the kept points.
fn shortcut(
    sp: &Space<'_>,
    d: &[[f64; 2]],
    clear: &[f32],
    margin: f32,
) -> std::result::Result<Vec<[f64; 2]>, usize> {
    let n = d.len();
    let mut out = vec![d[0]];
    let mut i = 0;
    // Clearance asked of a segment i → j: the margin, or less where the grid path itself
    // is closer to an obstacle (one cell of slack: a diagonal step passes side cells).
    let need = |lo: f32| {
        if margin <= 0.0 {
            0.0
        } else {
            margin.min(lo) - 1.0
        }
    };
    while i < n - 1 {
        let mut best = None;
        let mut lo = clear[i];
        let mut j = i + 1;
        while j < n {
            lo = lo.min(clear[j]);
            if !sp.segment_free(d[i], d[j], need(lo)) {
                break;
            }
            best = Some(j);
            j += 1;
        }
        if best.is_none() {
            // Not even the next point is in sight (a stub end): the farthest visible one.
            let mut lo_all = clear[i..].iter().copied().fold(f32::INFINITY, f32::min);
            for j in (i + 1..n).rev() {
                lo_all = lo_all.min(clear[j]);
                if sp.segment_free(d[i], d[j], need(lo_all)) {
                    best = Some(j);
                    break;
                }
            }
        }
        let Some(mut b) = best else {
            return Err(i);
        };
        if b < n - 1 {
            let lo_all = clear[i..].iter().copied().fold(f32::INFINITY, f32::min);
            if sp.segment_free(d[i], d[n - 1], need(lo_all)) {
                b = n - 1;
            }
        }
        out.push(d[b]);
        i = b;
    }
    Ok(out)
}

/// Blends the corners of polyline `v` starting with heading `th0`; `fixed_first` /
/// `fixed_last`: the first / last segment is a stub that only its inner corner may use.
fn blend_polyline(
    sp: &Space<'_>,
    poly: &[[f64; 2]],
    th0: f64,
    opts: &SmoothOptions,
) -> std::result::Result<Vec<Piece>, Failure> {
    let mut v = poly.to_vec();
    let last = poly.len() - 2;
    let mut tag: Vec<usize> = (0..poly.len()).collect();
    let mut pushes = 0;
    loop {
        let (i, room, message) = match blend_once(sp, &v, th0, opts) {
            Ok(p) => return Ok(p),
            Err(e) => e,
        };
        // No room between two corners turning the same way: merge them into one corner
        // at the intersection of the outer segments, if that is free; then retry.
        let mut merged = false;
        if room {
            for a in [i, i - 1] {
                if a >= 1
                    && a + 1 < v.len() - 1
                    && let Some(x) = merge_corners(sp, &v, a)
                {
                    let b = a + 1;
                    v[a] = x;
                    v.remove(b);
                    if tag[b] == 1 || tag[b] == last {
                        tag[a] = tag[b];
                    }
                    tag.remove(b);
                    merged = true;
                    break;
                }
            }
        }
        // A blend crossing an obstacle: move the vertex outward along the corner's
        // bisector (by up to three times the blend's cut) so the turn swings wide.
        if !room && tag[i] != 1 && tag[i] != last && pushes < 4 * poly.len() {
            pushes += 1;
            if let Some(x) = push_corner(sp, &v, i, opts) {
                v[i] = x;
                merged = true;
            }
        }
        if !merged {
            return Err(Failure {
                corner: tag[i],
                message,
            });
        }
    }
}

/// Corner `i` of `v` moved outward along its bisector so that its tightest blend and the
/// two segments to its neighbours are free, if some push does that.
fn push_corner(sp: &Space<'_>, v: &[[f64; 2]], i: usize, opts: &SmoothOptions) -> Option<[f64; 2]> {
    let (p, q, r) = (v[i - 1], v[i], v[i + 1]);
    let (a, b) = (dir(p, q), dir(q, r));
    let delta = wrap(b - a);
    let (ui, uo) = ([a.cos(), a.sin()], [b.cos(), b.sin()]);
    let w = [ui[0] - uo[0], ui[1] - uo[1]];
    let n = w[0].hypot(w[1]);
    if n < 1e-9 {
        return None;
    }
    let out = [w[0] / n, w[1] / n];
    let bl = blend(delta, opts.kappa_max, opts.sharpness_max);
    let step = bl.dev.max(0.5 * sp.frame.resolution);
    for k in 1..=6 {
        let d = 0.5 * k as f64 * step;
        let x = [q[0] + d * out[0], q[1] + d * out[1]];
        if !(sp.segment_free(p, x, 0.0) && sp.segment_free(x, r, 0.0)) {
            continue;
        }
        let (a2, b2) = (dir(p, x), dir(x, r));
        let d2 = wrap(b2 - a2);
        let b = blend(d2, opts.kappa_max, opts.sharpness_max);
        if b.t > dist(p, x).min(dist(x, r)) {
            continue;
        }
        let p_in = [x[0] - b.t * a2.cos(), x[1] - b.t * a2.sin()];
        let ps = chain(&blend_pieces(&b, d2.signum()), 0.0, (p_in[0], p_in[1], a2));
        if pieces_free(sp, &ps) {
            return Some(x);
        }
    }
    None
}

/// The intersection of the segments before corner `a` and after corner `a + 1` of `v`,
/// if both corners turn the same way by less than π together, the point lies ahead on
/// both lines and the two new segments are free.
fn merge_corners(sp: &Space<'_>, v: &[[f64; 2]], a: usize) -> Option<[f64; 2]> {
    let (p, q0, q1, r) = (v[a - 1], v[a], v[a + 1], v[a + 2]);
    let d1 = [q0[0] - p[0], q0[1] - p[1]];
    let d2 = [q1[0] - r[0], q1[1] - r[1]];
    let (t1, t2) = (
        wrap(dir(q0, q1) - dir(p, q0)),
        wrap(dir(q1, r) - dir(q0, q1)),
    );
    if t1 * t2 <= 0.0 || (t1 + t2).abs() >= PI - 1e-3 {
        return None;
    }
    // p + α d1 = r + β d2
    let det = d1[0] * (-d2[1]) - d1[1] * (-d2[0]);
    if det.abs() < 1e-15 {
        return None;
    }
    let (ex, ey) = (r[0] - p[0], r[1] - p[1]);
    let al = (ex * (-d2[1]) - ey * (-d2[0])) / det;
    let be = (d1[0] * ey - d1[1] * ex) / det;
    if !(al > 0.0 && be > 0.0) {
        return None;
    }
    let x = [p[0] + al * d1[0], p[1] + al * d1[1]];
    (sp.segment_free(p, x, 0.0) && sp.segment_free(x, r, 0.0)).then_some(x)
}

fn blend_once(
    sp: &Space<'_>,
    v: &[[f64; 2]],
    th0: f64,
    opts: &SmoothOptions,
) -> std::result::Result<Vec<Piece>, (usize, bool, String)> {
    let m = v.len() - 1; // segments
    let seg: Vec<f64> = (0..m).map(|j| dist(v[j], v[j + 1])).collect();
    // Deflection at corner i (1..m): from segment i−1 to segment i; heading of segment 0
    // is th0 (it runs along the start heading by construction).
    let mut heading = vec![th0; m];
    let mut delta = vec![0.0; m + 1];
    for i in 1..m {
        let d = wrap(dir(v[i], v[i + 1]) - dir(v[i - 1], v[i]));
        delta[i] = d;
        heading[i] = heading[i - 1] + d;
    }
    let (km, sm) = (opts.kappa_max, opts.sharpness_max);
    let tight: Vec<f64> = (0..=m)
        .map(|i| {
            if i == 0 || i == m || delta[i].abs() < 1e-9 {
                0.0
            } else {
                blend(delta[i], km, sm).t
            }
        })
        .collect();
    // Share of a segment a corner may use: all of an end segment, else what the other
    // end's corner leaves (its chosen blend, or its tightest one for corners not yet done).
    let mut chosen = vec![0.0f64; m + 1];
    let mut blends: Vec<Option<Blend>> = vec![None; m + 1];
    for i in 1..m {
        if delta[i].abs() < 1e-9 {
            continue;
        }
        let avail_in = seg[i - 1] - chosen[i - 1];
        let avail_out = seg[i] - tight[i + 1];
        if tight[i] > avail_in.min(avail_out) + 1e-12 || delta[i].abs() >= PI - 1e-9 {
            return Err((
                i,
                true,
                format!(
                    "the corner at ({:.3}, {:.3}) turns by {:.1}° and its tightest turn \
                     (radius {:.3} m) needs {:.3} m of straight on each side, but only \
                     {:.3} m and {:.3} m are free",
                    v[i][0],
                    v[i][1],
                    delta[i].to_degrees(),
                    1.0 / km,
                    tight[i],
                    avail_in.max(0.0),
                    avail_out.max(0.0)
                ),
            ));
        }
        let sign = delta[i].signum();
        let mut ok = None;
        for &lam in &LADDER {
            let b = blend(delta[i], km / lam, sm / (lam * lam));
            if b.t > avail_in.min(avail_out) + 1e-12 {
                continue;
            }
            let th_in = heading[i - 1];
            let p_in = [v[i][0] - b.t * th_in.cos(), v[i][1] - b.t * th_in.sin()];
            let ps = chain(&blend_pieces(&b, sign), 0.0, (p_in[0], p_in[1], th_in));
            if pieces_free(sp, &ps) {
                ok = Some(b);
                break;
            }
        }
        let Some(b) = ok else {
            return Err((
                i,
                false,
                format!(
                    "every turn of radius >= {:.3} m at the corner at ({:.3}, {:.3}) (turning by \
                     {:.1}°) crosses an obstacle of the configuration space",
                    1.0 / km,
                    v[i][0],
                    v[i][1],
                    delta[i].to_degrees()
                ),
            ));
        };
        chosen[i] = b.t;
        blends[i] = Some(b);
    }
    // Assemble: line, blend, line, ... from the start pose.
    let mut parts = Vec::new();
    for j in 0..m {
        let line = seg[j] - chosen[j] - chosen[j + 1];
        parts.push((line.max(0.0), 0.0, 0.0));
        if j + 1 < m
            && let Some(b) = &blends[j + 1]
        {
            parts.extend(blend_pieces(b, delta[j + 1].signum()));
        }
    }
    Ok(chain(&parts, 0.0, (v[0][0], v[0][1], th0)))
}

/// Turns a grid path into a smooth, curvature-bounded path for a differential drive from
/// the exact `start` pose to the exact `goal` pose (`[x, y, θ]`, world metres and
/// radians, in the frame of `frame`: its origin, resolution and kind place the cells).
/// `cells` is the search's cell path on the C-space `cspace` (its first and last cells
/// stand for the start and goal and are replaced by the exact positions). See the
/// [module documentation](self) for the method and the guarantees.
///
/// # Errors
/// Non-finite poses, invalid options, an empty path, a `frame` whose size differs from
/// `cspace`, a start or goal outside the map or in a blocked cell, a sample count above
/// [`MAX_TRAJECTORY_SAMPLES`], and no feasible smooth path ([`Error::Planning`], naming
/// the corner or end that failed and why).
pub fn smooth_diff_drive(
    cspace: &SearchGrid,
    frame: &OccupancyGrid,
    cells: &[(usize, usize)],
    start: [f64; 3],
    goal: [f64; 3],
    opts: &SmoothOptions,
) -> Result<SmoothPath> {
    check_smooth_inputs(cspace, frame, cells, start, goal, opts)?;
    let (sxy, gxy) = ([start[0], start[1]], [goal[0], goal[1]]);
    if dist(sxy, gxy) < 1e-9 {
        let pivot = wrap(goal[2] - start[2]);
        return finish(
            vec![],
            sxy,
            start[2] + pivot,
            pivot,
            start[2],
            opts,
            frame,
            cspace,
        );
    }
    check_cells_inside(cspace, cells)?;
    let dense = dense_points(frame, cells, sxy, gxy);
    // Clearance of the C-space over the path's bounding box plus the margin wanted.
    let margin_cells = (opts.clearance / frame.resolution).min(1e4);
    let problem = SmoothProblem {
        sp: clearance_window(cspace, frame, &dense, margin_cells),
        dense,
        start,
        goal,
        sxy,
        gxy,
        r: 1.0 / opts.kappa_max,
        opts,
    };
    let mut last_err = String::new();
    for margin in clearance_margins(margin_cells) {
        match problem.smooth_with_margin(margin) {
            Ok(p) => return Ok(p),
            Err(e) => last_err = e,
        }
    }
    Err(Error::Planning(format!(
        "no feasible smooth path for kappa_max = {} 1/m: {last_err}",
        opts.kappa_max
    )))
}

/// The checks of [`smooth_diff_drive`]'s inputs made before the start = goal case: the
/// options, finite poses, a non-empty path, a frame of the C-space's size, and start and
/// goal on free cells of the map.
fn check_smooth_inputs(
    cspace: &SearchGrid,
    frame: &OccupancyGrid,
    cells: &[(usize, usize)],
    start: [f64; 3],
    goal: [f64; 3],
    opts: &SmoothOptions,
) -> Result<()> {
    opts.validate()?;
    crate::error::ensure_finite("start pose", start.iter())?;
    crate::error::ensure_finite("goal pose", goal.iter())?;
    if cells.is_empty() {
        return Err(Error::invalid("cells", "the grid path is empty"));
    }
    if frame.width != cspace.width() || frame.height != cspace.height() {
        return Err(Error::invalid(
            "frame",
            format!(
                "the map frame has {} x {} cells but the configuration space {} x {}",
                frame.width,
                frame.height,
                cspace.width(),
                cspace.height()
            ),
        ));
    }
    for (what, p) in [("start", start), ("goal", goal)] {
        let c = frame.world_to_cell(what, p[0], p[1])?;
        cspace.check_cell(what, c)?;
    }
    Ok(())
}

/// Every cell of the grid path lies inside the map.
fn check_cells_inside(cspace: &SearchGrid, cells: &[(usize, usize)]) -> Result<()> {
    for &(x, y) in cells {
        if x >= cspace.width() || y >= cspace.height() {
            return Err(Error::invalid(
                "cells",
                format!(
                    "cell ({x}, {y}) lies outside the {} x {} map",
                    cspace.width(),
                    cspace.height()
                ),
            ));
        }
    }
    Ok(())
}

/// The dense points of the path: the exact start, the interior cell centres, the exact
/// goal.
fn dense_points(
    frame: &OccupancyGrid,
    cells: &[(usize, usize)],
    sxy: [f64; 2],
    gxy: [f64; 2],
) -> Vec<[f64; 2]> {
    let mut dense = Vec::with_capacity(cells.len().max(2));
    dense.push(sxy);
    if cells.len() > 2 {
        for &(x, y) in &cells[1..cells.len() - 1] {
            dense.push(frame.cell_to_world(x as f64, y as f64));
        }
    }
    dense.push(gxy);
    dense
}

/// The C-space's clearance over the bounding box of `dense` padded by the margin wanted
/// (`margin_cells`) plus three cells, clipped to the map.
fn clearance_window<'a>(
    cspace: &'a SearchGrid,
    frame: &'a OccupancyGrid,
    dense: &[[f64; 2]],
    margin_cells: f64,
) -> Space<'a> {
    let pad = margin_cells.ceil() as i64 + 3;
    let (mut x0, mut y0, mut x1, mut y1) = (i64::MAX, i64::MAX, i64::MIN, i64::MIN);
    for p in dense {
        let c = frame.world_to_cell_f(p[0], p[1]);
        x0 = x0.min(c[0].floor() as i64);
        y0 = y0.min(c[1].floor() as i64);
        x1 = x1.max(c[0].floor() as i64);
        y1 = y1.max(c[1].floor() as i64);
    }
    let (wx0, wy0) = ((x0 - pad).max(0), (y0 - pad).max(0));
    let wx1 = (x1 + pad).min(cspace.width() as i64 - 1);
    let wy1 = (y1 + pad).min(cspace.height() as i64 - 1);
    let (ww, wh) = ((wx1 - wx0 + 1) as usize, (wy1 - wy0 + 1) as usize);
    let mut obst = Vec::with_capacity(ww * wh);
    for y in wy0..=wy1 {
        for x in wx0..=wx1 {
            obst.push(!cspace.is_free(x, y));
        }
    }
    Space {
        cs: cspace,
        frame,
        dist: distance_transform(&obst, ww, wh),
        win: (wx0, wy0, ww, wh),
    }
}

/// The clearance margins tried in turn (cells): the one wanted, halved while at least one
/// cell, then none.
fn clearance_margins(margin_cells: f64) -> Vec<f32> {
    let mut margins = vec![];
    let mut m = margin_cells as f32;
    while m >= 1.0 {
        margins.push(m);
        m *= 0.5;
    }
    margins.push(0.0);
    margins
}

/// What [`smooth_diff_drive`] works on once its inputs are checked.
struct SmoothProblem<'a> {
    sp: Space<'a>,
    /// Start, interior cell centres, goal (world metres).
    dense: Vec<[f64; 2]>,
    start: [f64; 3],
    goal: [f64; 3],
    sxy: [f64; 2],
    gxy: [f64; 2],
    /// The smallest turning radius, 1 / κ_max.
    r: f64,
    opts: &'a SmoothOptions,
}

/// Which stubs (straight runs along the start and goal headings) an attempt uses, and
/// how long they are (indices into [`STUBS`]).
struct StubChoice {
    /// The plain path leaves the start off its heading, within the allowed start turn.
    need_start: bool,
    /// The path arrives at the goal off its heading.
    need_goal: bool,
    /// Turn in place toward the path instead of a start stub.
    pivot_mode: bool,
    is: usize,
    ig: usize,
}

impl StubChoice {
    /// The next choice after an attempt failed at `end` with `msg`, or the margin's final
    /// error when no choice is left (`goal_heading` for its message).
    fn after_failure(&mut self, end: End, msg: String, goal_heading: f64) -> Result<(), String> {
        match end {
            End::Start => {
                self.is += 1;
                if self.is == STUBS.len() {
                    // No forward start: turn in place toward the path instead.
                    self.pivot_mode = true;
                }
                Ok(())
            }
            End::Goal => {
                self.ig += 1;
                if self.ig == STUBS.len() {
                    return Err(format!(
                        "the goal heading {goal_heading:.3} rad cannot be reached driving \
                         forwards: {msg}"
                    ));
                }
                Ok(())
            }
            End::Other => Err(msg),
        }
    }
}

/// The outcome of one attempt with a given choice of stubs.
enum Attempt {
    /// Blended pieces and the heading of the first one.
    Pieces(Vec<Piece>, f64),
    /// The start stub changed the last segment: the goal needs a stub too.
    NeedGoalStub,
    /// The attempt failed; the end it is blamed on and why.
    Failed(End, String),
}

impl SmoothProblem<'_> {
    /// The clearance (cells) of the C-space at the world point `p`.
    fn clearance_of(&self, p: [f64; 2]) -> f32 {
        let c = self.sp.frame.world_to_cell_f(p[0], p[1]);
        self.sp
            .clearance_at(c[0].floor() as i64, c[1].floor() as i64)
    }

    /// Smoothing with the clearance `margin` (cells): the plain shortcut decides whether
    /// stubs and a pivot are needed, then stub lengths are tried until one blends and
    /// samples free. The error is the last failure's message.
    fn smooth_with_margin(&self, margin: f32) -> Result<SmoothPath, String> {
        let (start, goal) = (self.start, self.goal);
        let clear: Vec<f32> = self.dense.iter().map(|&p| self.clearance_of(p)).collect();
        let Ok(plain) = shortcut(&self.sp, &self.dense, &clear, margin) else {
            return Err("the grid path is not free in the configuration space".into());
        };
        let d0 = wrap(dir(plain[0], plain[1]) - start[2]);
        let pivot_mode = d0.abs() > self.opts.max_start_turn;
        let mut stubs = StubChoice {
            need_start: d0.abs() > 1e-9 && !pivot_mode,
            need_goal: wrap(dir(plain[plain.len() - 2], self.gxy) - goal[2]).abs() > 1e-9,
            pivot_mode,
            is: 0,
            ig: 0,
        };
        loop {
            match self.attempt(&stubs, &clear, margin) {
                Attempt::Pieces(pieces, th0) => {
                    let (sp, opts) = (&self.sp, self.opts);
                    let (sxy, s0) = (self.sxy, start[2]);
                    return finish(pieces, sxy, th0, th0 - s0, s0, opts, sp.frame, sp.cs)
                        .map_err(|e| e.to_string());
                }
                Attempt::NeedGoalStub => stubs.need_goal = true,
                Attempt::Failed(end, msg) => stubs.after_failure(end, msg, goal[2])?,
            }
        }
    }

    /// One attempt: the stubs of `stubs` checked free, the shortcut of the dense points
    /// from the stubs' ends, and its polyline blended.
    fn attempt(&self, stubs: &StubChoice, clear: &[f32], margin: f32) -> Attempt {
        let (sxy, gxy, start, goal) = (self.sxy, self.gxy, self.start, self.goal);
        let use_start_stub = stubs.need_start && !stubs.pivot_mode;
        let need_goal_stub = stubs.need_goal;
        let e_s = if use_start_stub {
            STUBS[stubs.is] * self.r
        } else {
            0.0
        };
        let e_g = if need_goal_stub {
            STUBS[stubs.ig] * self.r
        } else {
            0.0
        };
        let s_stub = [sxy[0] + e_s * start[2].cos(), sxy[1] + e_s * start[2].sin()];
        let g_stub = [gxy[0] - e_g * goal[2].cos(), gxy[1] - e_g * goal[2].sin()];
        if use_start_stub && !self.sp.segment_free(sxy, s_stub, 0.0) {
            return Attempt::Failed(
                End::Start,
                "the straight stub along the start heading crosses an obstacle".to_string(),
            );
        }
        if need_goal_stub && !self.sp.segment_free(g_stub, gxy, 0.0) {
            return Attempt::Failed(
                End::Goal,
                "the straight stub along the goal heading crosses an obstacle".to_string(),
            );
        }
        let mut d = self.dense.clone();
        let mut c = clear.to_vec();
        if use_start_stub {
            d[0] = s_stub;
            c[0] = self.clearance_of(s_stub);
        }
        if need_goal_stub {
            let k = d.len() - 1;
            d[k] = g_stub;
            c[k] = self.clearance_of(g_stub);
        }
        let mut poly = match shortcut(&self.sp, &d, &c, margin) {
            Ok(poly) => poly,
            Err(i) => {
                let end = if i == 0 && use_start_stub {
                    End::Start
                } else if need_goal_stub {
                    End::Goal
                } else {
                    End::Other
                };
                let msg = "no straight line of sight from a stub's end to the grid path";
                return Attempt::Failed(end, msg.to_string());
            }
        };
        if use_start_stub {
            poly.insert(0, sxy);
        }
        if need_goal_stub {
            poly.push(gxy);
        } else if wrap(dir(poly[poly.len() - 2], gxy) - goal[2]).abs() > 1e-9 {
            return Attempt::NeedGoalStub;
        }
        // The first segment runs along the start heading (a stub, or the plain path
        // already aligned), or along the pivot's heading.
        let th0 = if stubs.pivot_mode {
            start[2] + wrap(dir(poly[0], poly[1]) - start[2])
        } else {
            start[2]
        };
        let last = poly.len() - 2;
        match blend_polyline(&self.sp, &poly, th0, self.opts) {
            Ok(pieces) => Attempt::Pieces(pieces, th0),
            Err(f) => {
                let s = use_start_stub && f.corner == 1;
                let g = need_goal_stub && f.corner == last;
                let end = match (s, g) {
                    (true, true) if stubs.is <= stubs.ig => End::Start,
                    (true, true) | (false, true) => End::Goal,
                    (true, false) => End::Start,
                    (false, false) => End::Other,
                };
                Attempt::Failed(end, f.message)
            }
        }
    }
}

/// Samples the pieces and checks them once more against the C-space.
#[allow(clippy::too_many_arguments)]
fn finish(
    pieces: Vec<Piece>,
    sxy: [f64; 2],
    th0: f64,
    pivot: f64,
    start_heading: f64,
    opts: &SmoothOptions,
    frame: &OccupancyGrid,
    cspace: &SearchGrid,
) -> Result<SmoothPath> {
    let length = pieces.last().map_or(0.0, |p| p.s0 + p.len);
    let count = length / opts.ds + pieces.len() as f64 + 2.0;
    if count > MAX_TRAJECTORY_SAMPLES as f64 {
        return Err(Error::invalid(
            "ds",
            format!(
                "a {length:.3} m path sampled every {} m needs {count:.3e} samples, more than \
                 the limit of {MAX_TRAJECTORY_SAMPLES}",
                opts.ds
            ),
        ));
    }
    let path = sample_pieces(pieces, sxy, th0, pivot, start_heading, opts.ds);
    let sp = Space {
        cs: cspace,
        frame,
        dist: vec![],
        win: (0, 0, 0, 0),
    };
    for w in path.samples.windows(2) {
        if !sp.segment_free([w[0].x, w[0].y], [w[1].x, w[1].y], 0.0) {
            return Err(Error::Planning(format!(
                "the smoothed path crosses an obstacle near ({:.3}, {:.3})",
                w[1].x, w[1].y
            )));
        }
    }
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blend_is_symmetric_and_turns_by_delta() {
        for &d in &[0.1, 0.5, 1.0, 2.0, 2.8] {
            let b = blend(d, 2.0, 8.0);
            let ps = chain(&blend_pieces(&b, 1.0), 0.0, (0.0, 0.0, 0.0));
            let last = ps.last().unwrap();
            let (x, y, th, k) = last.eval(last.len);
            assert!((th - d).abs() < 1e-12, "{th} vs {d}");
            assert!(k.abs() < 1e-12);
            // ends on the outgoing line at distance t from the vertex (t, 0)
            let (ex, ey) = (b.t + b.t * d.cos(), b.t * d.sin());
            assert!(
                (x - ex).abs() < 1e-12 && (y - ey).abs() < 1e-12,
                "{x} {y} vs {ex} {ey}"
            );
            assert!(b.kp <= 2.0 + 1e-12);
        }
    }

    #[test]
    fn traverse_visits_corner_neighbours() {
        let mut v = vec![];
        traverse([0.5, 0.5], [2.5, 2.5], |x, y| {
            v.push((x, y));
            true
        });
        assert!(v.contains(&(1, 0)) && v.contains(&(0, 1)) && v.contains(&(2, 2)));
        let mut w = vec![];
        traverse([0.2, 0.5], [3.7, 0.5], |x, y| {
            w.push((x, y));
            true
        });
        assert_eq!(w, vec![(0, 0), (1, 0), (2, 0), (3, 0)]);
    }
}

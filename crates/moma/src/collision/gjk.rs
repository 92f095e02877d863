//! Signed distance between two placed convex shapes: GJK to a certified duality gap, EPA
//! for overlapping cores, written here on the shapes' support functions.
//!
//! Why not parry's queries: the reference (coal with a 1e-12 m absolute duality gap) is
//! graded at 1e-6 m on distances and 1e-5 m on witness points; a default-tolerance
//! GJK/EPA misses both (see `docs/collision.md`). This GJK stops only when the gap
//! between the upper bound |v| and the lower bound v·w/|v| is below [`GAP_TOLERANCE`]
//! (or no step shrinks |v| any more), and every closest point it reports is an explicit
//! convex combination of support points, so the distance it returns is never below the
//! true one by more than round-off. EPA stops when the support point in the closest
//! face's normal lies within [`GAP_TOLERANCE`] of that face, or when adding it would
//! not leave a closed convex polytope (round-off, for a point almost on the faces): then
//! it keeps the last sound polytope's closest face, so its work is bounded by
//! [`MAX_ITERATIONS`] iterations over at most 2V − 4 faces
//! ([`EpaWorkspace::faces_visited`]).

use super::convex::{Convex, Support};
use crate::spatial::SE3;
use nalgebra::Vector3;

/// Absolute duality-gap tolerance of GJK and EPA (m).
pub const GAP_TOLERANCE: f64 = 1e-12;
/// Iteration cap of GJK and of EPA (each).
pub const MAX_ITERATIONS: usize = 1000;

/// A point of the Minkowski difference A − B with the points of A and B it came from.
#[derive(Clone, Copy, Debug, Default)]
struct SupportPoint {
    w: Vector3<f64>,
    a: Vector3<f64>,
    b: Vector3<f64>,
}

/// The result of one signed-distance query.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PairDistance {
    /// Signed distance (m): the gap between the shapes, or minus the penetration depth.
    pub distance: f64,
    /// World point on the first shape.
    pub witness_a: Vector3<f64>,
    /// World point on the second shape.
    pub witness_b: Vector3<f64>,
    /// Unit normal with `witness_b − witness_a = distance · normal`.
    pub normal: Vector3<f64>,
}

/// Per-pair warm start: the last separating direction and the hull vertices the support
/// climbs started from.
#[derive(Clone, Copy, Debug)]
pub struct WarmStart {
    direction: Vector3<f64>,
    /// The hull vertex shape A's support climbs start from.
    pub(super) hint_a: usize,
    hint_b: usize,
}

impl Default for WarmStart {
    fn default() -> Self {
        WarmStart {
            direction: Vector3::x(),
            hint_a: 0,
            hint_b: 0,
        }
    }
}

impl WarmStart {
    /// The direction the last query ended with (world): a point of A − B, so `−direction`
    /// points from the first shape towards the second.
    #[must_use]
    pub fn direction(&self) -> Vector3<f64> {
        self.direction
    }
}

/// A face of the EPA polytope.
#[derive(Clone, Copy, Debug)]
struct Face {
    v: [usize; 3],
    n: Vector3<f64>,
    d: f64,
    live: bool,
}

/// EPA's buffers, kept between queries so that a query allocates nothing once they have
/// grown to the largest polytope met.
#[derive(Clone, Debug, Default)]
pub struct EpaWorkspace {
    vertices: Vec<SupportPoint>,
    faces: Vec<Face>,
    horizon: Vec<(usize, usize)>,
    /// Faces the last EPA visited (closest-face scans and visibility tests).
    faces_visited: usize,
}

impl EpaWorkspace {
    /// The faces the last EPA visited: its closest-face scans and visibility tests, the
    /// work of one query, bounded by [`MAX_ITERATIONS`] iterations over at most 2V - 4
    /// faces (V ≤ [`MAX_ITERATIONS`] + 4 vertices).
    #[must_use]
    pub fn faces_visited(&self) -> usize {
        self.faces_visited
    }
}

struct Placed<'a, S: ?Sized> {
    shape: &'a S,
    pose: &'a SE3,
}

impl<S: Support + ?Sized> Placed<'_, S> {
    /// World support point of the core in world direction `d`.
    fn core(&self, d: &Vector3<f64>, hint: &mut usize) -> Vector3<f64> {
        let local = self.pose.rotation.tr_mul(d);
        self.pose.rotation * self.shape.core_support(&local, hint) + self.pose.translation
    }
}

struct Pair<'a, A: ?Sized, B: ?Sized> {
    a: Placed<'a, A>,
    b: Placed<'a, B>,
    /// Add the margins to the support function (EPA on overlapping cores).
    inflate: bool,
}

impl<'a, A: Support + ?Sized, B: Support + ?Sized> Pair<'a, A, B> {
    /// The two placed shapes, support functions on their cores (no margins).
    fn new(a: &'a A, pose_a: &'a SE3, b: &'a B, pose_b: &'a SE3) -> Self {
        Pair {
            a: Placed {
                shape: a,
                pose: pose_a,
            },
            b: Placed {
                shape: b,
                pose: pose_b,
            },
            inflate: false,
        }
    }

    /// Support point of A − B in direction `d`.
    fn support(&self, d: &Vector3<f64>, warm: &mut WarmStart) -> SupportPoint {
        let mut a = self.a.core(d, &mut warm.hint_a);
        let mut b = self.b.core(&-d, &mut warm.hint_b);
        if self.inflate {
            let n = d.norm();
            if n > 0.0 {
                a += d * (self.a.shape.margin() / n);
                b -= d * (self.b.shape.margin() / n);
            }
        }
        SupportPoint { w: a - b, a, b }
    }
}

/// Signed distance between shape `a` at `pose_a` and shape `b` at `pose_b` (world poses),
/// with witness points in the world frame.
pub fn signed_distance(
    a: &Convex,
    pose_a: &SE3,
    b: &Convex,
    pose_b: &SE3,
    warm: &mut WarmStart,
    epa: &mut EpaWorkspace,
) -> PairDistance {
    let mut pair = Pair::new(a, pose_a, b, pose_b);
    let margin = a.margin() + b.margin();
    let mut simplex = [SupportPoint::default(); 4];
    match gjk(&pair, warm, &mut simplex, f64::NEG_INFINITY, f64::INFINITY) {
        Gjk::Separated { distance, wa, wb } => {
            let normal = (wb - wa) / distance;
            PairDistance {
                distance: distance - margin,
                witness_a: wa + normal * a.margin(),
                witness_b: wb - normal * b.margin(),
                normal,
            }
        }
        Gjk::Overlap { n } => {
            pair.inflate = margin > 0.0;
            match epa_depth(&pair, warm, &simplex[..n], epa) {
                Some(r) => r,
                // A flat Minkowski difference (degenerate shapes): touching.
                None => {
                    let p = simplex[0];
                    PairDistance {
                        distance: 0.0,
                        witness_a: p.a,
                        witness_b: p.a,
                        normal: Vector3::z(),
                    }
                }
            }
        }
        Gjk::Within { .. } => unreachable!("no upper bound is below -inf"),
    }
}

/// Distance between two placed shapes as surfaces meeting: their gap when apart, `0`
/// (no EPA) when they touch or overlap, with world witness points (when touching, a
/// point common to both within 1e-10 m) and the unit normal (zero when touching). The
/// exact triangle-mesh distances ([`super::exact`]) measure triangles with it.
pub fn gap_distance<A: Support + ?Sized, B: Support + ?Sized>(
    a: &A,
    pose_a: &SE3,
    b: &B,
    pose_b: &SE3,
    warm: &mut WarmStart,
) -> PairDistance {
    let pair = Pair::new(a, pose_a, b, pose_b);
    let (ma, mb) = (a.margin(), b.margin());
    let mut simplex = [SupportPoint::default(); 4];
    match gjk(&pair, warm, &mut simplex, f64::NEG_INFINITY, f64::INFINITY) {
        Gjk::Separated { distance, wa, wb } if distance > ma + mb => {
            let normal = (wb - wa) / distance;
            PairDistance {
                distance: distance - ma - mb,
                witness_a: wa + normal * ma,
                witness_b: wb - normal * mb,
                normal,
            }
        }
        Gjk::Separated { wa, wb, .. } => {
            // Cores apart by at most the margins (so these are positive): a point between
            // them on the segment.
            touching(wa + (wb - wa) * (ma / (ma + mb)))
        }
        Gjk::Overlap { n } => {
            let (_, _, weights) = closest_on_simplex(&simplex[..n], 0);
            let p = (0..n).fold(Vector3::zeros(), |p, i| p + simplex[i].a * weights[i]);
            touching(p)
        }
        Gjk::Within { .. } => unreachable!("no upper bound is below -inf"),
    }
}

/// Two shapes touching at world point `p`.
fn touching(p: Vector3<f64>) -> PairDistance {
    PairDistance {
        distance: 0.0,
        witness_a: p,
        witness_b: p,
        normal: Vector3::zeros(),
    }
}

/// The signed distance of [`signed_distance`], or, when it lies outside `(within,
/// enough]`, a bound that shows so: a lower bound above `enough` (GJK stops at the first
/// separating plane that shows the distance exceeds it), or an upper bound at most
/// `within` (GJK stops at the first point of the Minkowski difference that close; cores
/// that overlap give the upper bound without EPA). A caller that only needs "more than
/// `enough`" or "at most `within`" pays for no further iteration. Between the two the
/// value is the signed distance itself.
#[allow(clippy::too_many_arguments)]
pub fn distance_outside(
    a: &Convex,
    pose_a: &SE3,
    b: &Convex,
    pose_b: &SE3,
    within: f64,
    enough: f64,
    warm: &mut WarmStart,
    epa: &mut EpaWorkspace,
) -> f64 {
    let pair = Pair::new(a, pose_a, b, pose_b);
    let margin = a.margin() + b.margin();
    let mut simplex = [SupportPoint::default(); 4];
    // A lower bound on the cores' distance bounds the signed distance only when positive.
    let above = enough.max(0.0) + margin;
    match gjk(&pair, warm, &mut simplex, within + margin, above) {
        Gjk::Separated { distance, .. } => distance - margin,
        Gjk::Within { upper } => upper - margin,
        // Cores this close: the shapes are at most `CONTACT - margin` apart.
        Gjk::Overlap { .. } if CONTACT - margin <= within => CONTACT - margin,
        Gjk::Overlap { .. } => signed_distance(a, pose_a, b, pose_b, warm, epa).distance,
    }
}

/// Whether the two placed shapes overlap (signed distance < 0, or cores within 1e-10 m),
/// with GJK stopped at the first separating plane.
pub fn overlaps(a: &Convex, pose_a: &SE3, b: &Convex, pose_b: &SE3, warm: &mut WarmStart) -> bool {
    let pair = Pair::new(a, pose_a, b, pose_b);
    let margin = a.margin() + b.margin();
    let mut simplex = [SupportPoint::default(); 4];
    match gjk(&pair, warm, &mut simplex, f64::NEG_INFINITY, margin) {
        Gjk::Separated { distance, .. } => distance < margin,
        Gjk::Within { .. } | Gjk::Overlap { .. } => true,
    }
}

enum Gjk {
    Separated {
        distance: f64,
        wa: Vector3<f64>,
        wb: Vector3<f64>,
    },
    /// The cores are at most `upper` apart (at most `stop_within`; never below it by
    /// more than the true distance).
    Within { upper: f64 },
    /// The cores overlap or touch; `simplex[..n]` holds the last simplex.
    Overlap { n: usize },
}

/// Distances below this (m) between cores count as contact and go to EPA.
const CONTACT: f64 = 1e-10;

/// GJK on the cores; stops early once the lower bound exceeds `stop_above` (returning it
/// as the distance), or once the upper bound |v| (a point of the Minkowski difference) is
/// at most `stop_within` and above contact ([`Gjk::Within`]).
fn gjk<A: Support + ?Sized, B: Support + ?Sized>(
    pair: &Pair<A, B>,
    warm: &mut WarmStart,
    simplex: &mut [SupportPoint; 4],
    stop_within: f64,
    stop_above: f64,
) -> Gjk {
    let dir = if warm.direction.norm_squared() > 0.0 {
        warm.direction
    } else {
        Vector3::x()
    };
    simplex[0] = pair.support(&-dir, warm);
    let mut n = 1;
    let mut weights = [1.0, 0.0, 0.0, 0.0];
    let mut v = simplex[0].w;
    for _ in 0..MAX_ITERATIONS {
        let vv = v.norm_squared();
        let vn = vv.sqrt();
        if vn <= CONTACT {
            return Gjk::Overlap { n };
        }
        if vn <= stop_within {
            warm.direction = v;
            return Gjk::Within { upper: vn };
        }
        let w = pair.support(&-v, warm);
        let lower = v.dot(&w.w) / vn;
        if lower > stop_above {
            warm.direction = v;
            return Gjk::Separated {
                distance: lower,
                wa: w.a,
                wb: w.b,
            };
        }
        // Upper bound |v|, lower bound v·w/|v|.
        if vn - v.dot(&w.w) / vn <= GAP_TOLERANCE || simplex[..n].iter().any(|s| s.w == w.w) {
            break;
        }
        simplex[n] = w;
        n += 1;
        // The new point is part of the closest sub-simplex (it improved on v).
        let (m, new_v, new_weights) = closest_on_simplex(&simplex[..n], 1 << (n - 1));
        if new_v.norm_squared() == 0.0 {
            return Gjk::Overlap { n };
        }
        if new_v.norm_squared() >= vv {
            // No progress: round-off floor reached; keep the previous simplex.
            n -= 1;
            break;
        }
        // Compact the simplex to the points with non-zero weight.
        let old = *simplex;
        let mut k = 0;
        for (i, &wt) in new_weights.iter().enumerate().take(n) {
            if m & (1 << i) != 0 {
                simplex[k] = old[i];
                weights[k] = wt;
                k += 1;
            }
        }
        n = k;
        v = new_v;
    }
    let mut wa = Vector3::zeros();
    let mut wb = Vector3::zeros();
    for i in 0..n {
        wa += simplex[i].a * weights[i];
        wb += simplex[i].b * weights[i];
    }
    let distance = (wa - wb).norm();
    if distance <= CONTACT {
        return Gjk::Overlap { n };
    }
    warm.direction = wa - wb;
    Gjk::Separated { distance, wa, wb }
}

/// The point of the simplex closest to the origin: (mask of the supporting points; the
/// point, exactly zero when the origin is inside the tetrahedron; the weights indexed
/// like the input).
/// Every sub-simplex holding the points of mask `required` whose projection of the origin
/// has non-negative barycentric weights is a candidate; the smallest candidate wins. Each
/// candidate is rebuilt from its weights, so it is a point of the simplex whatever the
/// round-off of the solve.
fn closest_on_simplex(s: &[SupportPoint], required: usize) -> (usize, Vector3<f64>, [f64; 4]) {
    let n = s.len();
    let mut best = (0usize, Vector3::zeros(), [0.0; 4]);
    let mut best_norm = f64::INFINITY;
    for mask in (1usize..(1 << n)).filter(|m| m & required == required) {
        let idx: arrayvec_like::Idx = arrayvec_like::Idx::from_mask(mask, n);
        let Some(mu) = project(s, &idx) else {
            continue;
        };
        let mut p = Vector3::zeros();
        let mut weights = [0.0; 4];
        for (k, &i) in idx.as_slice().iter().enumerate() {
            p += s[i].w * mu[k];
            weights[i] = mu[k];
        }
        let full = idx.len == 4;
        let norm = if full { 0.0 } else { p.norm_squared() };
        if norm < best_norm || (norm == best_norm && idx.len < best.0.count_ones() as usize) {
            best_norm = norm;
            best = (mask, if full { Vector3::zeros() } else { p }, weights);
        }
    }
    best
}

mod arrayvec_like {
    /// Up to four indices.
    pub struct Idx {
        pub i: [usize; 4],
        pub len: usize,
    }
    impl Idx {
        pub fn from_mask(mask: usize, n: usize) -> Self {
            let mut i = [0; 4];
            let mut len = 0;
            for k in 0..n {
                if mask & (1 << k) != 0 {
                    i[len] = k;
                    len += 1;
                }
            }
            Idx { i, len }
        }
        pub fn as_slice(&self) -> &[usize] {
            &self.i[..self.len]
        }
    }
}

/// Barycentric weights of the origin's projection on the affine hull of the chosen
/// points, if they are all non-negative and the points are affinely independent.
fn project(s: &[SupportPoint], idx: &arrayvec_like::Idx) -> Option<[f64; 4]> {
    let p0 = s[idx.i[0]].w;
    let k = idx.len - 1;
    let mut mu = [0.0; 4];
    match k {
        0 => {
            mu[0] = 1.0;
        }
        1 => {
            let e = s[idx.i[1]].w - p0;
            let ee = e.norm_squared();
            if ee <= 0.0 {
                return None;
            }
            let l = -e.dot(&p0) / ee;
            mu[0] = 1.0 - l;
            mu[1] = l;
        }
        2 => {
            let e1 = s[idx.i[1]].w - p0;
            let e2 = s[idx.i[2]].w - p0;
            let (a, b, c) = (e1.dot(&e1), e1.dot(&e2), e2.dot(&e2));
            let det = a * c - b * b;
            if det <= 1e-14 * a * c {
                return None;
            }
            let (r1, r2) = (-e1.dot(&p0), -e2.dot(&p0));
            let l1 = (r1 * c - r2 * b) / det;
            let l2 = (a * r2 - b * r1) / det;
            mu[0] = 1.0 - l1 - l2;
            mu[1] = l1;
            mu[2] = l2;
        }
        _ => {
            let (e1, e2, e3) = (s[idx.i[1]].w - p0, s[idx.i[2]].w - p0, s[idx.i[3]].w - p0);
            let c23 = e2.cross(&e3);
            let det = e1.dot(&c23);
            let scale = e1.norm() * e2.norm() * e3.norm();
            if det.abs() <= 1e-12 * scale {
                return None;
            }
            // Solve [e1 e2 e3] λ = −p0 (the origin in the tetrahedron's affine
            // coordinates) by Cramer's rule.
            let r = -p0;
            let l = [
                r.dot(&c23) / det,
                e1.dot(&r.cross(&e3)) / det,
                e1.dot(&e2.cross(&r)) / det,
            ];
            mu[0] = 1.0 - l[0] - l[1] - l[2];
            mu[1] = l[0];
            mu[2] = l[1];
            mu[3] = l[2];
        }
    }
    mu[..=k].iter().all(|m| *m >= 0.0).then_some(mu)
}

/// EPA on the (possibly inflated) Minkowski difference, from GJK's last simplex.
fn epa_depth<A: Support + ?Sized, B: Support + ?Sized>(
    pair: &Pair<A, B>,
    warm: &mut WarmStart,
    start: &[SupportPoint],
    ws: &mut EpaWorkspace,
) -> Option<PairDistance> {
    ws.vertices.clear();
    ws.faces.clear();
    ws.vertices.extend_from_slice(start);
    // Blow the simplex up to a tetrahedron.
    let axes = [Vector3::x(), Vector3::y(), Vector3::z()];
    let mut tries = 0;
    while ws.vertices.len() < 4 && tries < 12 {
        let v = &ws.vertices;
        let dirs: [Vector3<f64>; 2] = match v.len() {
            1 => {
                let a = axes[tries % 3];
                [a, -a]
            }
            2 => {
                let e = v[1].w - v[0].w;
                let a = axes[e.iamin()];
                let d1 = e.cross(&a);
                let d = if tries % 2 == 0 { d1 } else { e.cross(&d1) };
                [d, -d]
            }
            _ => {
                let nrm = (v[1].w - v[0].w).cross(&(v[2].w - v[0].w));
                [nrm, -nrm]
            }
        };
        tries += 1;
        for d in dirs {
            if d.norm_squared() == 0.0 {
                continue;
            }
            let p = pair.support(&d, warm);
            let base = ws.vertices[0].w;
            let gain = d.dot(&(p.w - base)) / d.norm();
            if gain > 1e-9 {
                ws.vertices.push(p);
                break;
            }
        }
    }
    if ws.vertices.len() < 4 {
        return None;
    }
    let v = &ws.vertices;
    let centroid = (v[0].w + v[1].w + v[2].w + v[3].w) / 4.0;
    for f in [[0, 1, 2], [0, 3, 1], [0, 2, 3], [1, 3, 2]] {
        let face = make_face(&ws.vertices, f, Some(&centroid))?;
        ws.faces.push(face);
    }
    ws.faces_visited = 0;
    let mut face = ws.faces[0];
    for _ in 0..MAX_ITERATIONS {
        ws.faces_visited += ws.faces.len();
        face = ws.faces[closest_face(&ws.faces)?];
        let p = pair.support(&face.n, warm);
        if face.n.dot(&p.w) - face.d <= GAP_TOLERANCE || ws.vertices.iter().any(|q| q.w == p.w) {
            break;
        }
        let new = ws.vertices.len();
        ws.vertices.push(p);
        ws.horizon.clear();
        ws.faces_visited += ws.faces.len();
        for f in &mut ws.faces {
            if f.n.dot(&(p.w - ws.vertices[f.v[0]].w)) > 0.0 {
                f.live = false;
                for k in 0..3 {
                    let e = (f.v[k], f.v[(k + 1) % 3]);
                    if let Some(pos) = ws.horizon.iter().position(|h| *h == (e.1, e.0)) {
                        ws.horizon.swap_remove(pos);
                    } else {
                        ws.horizon.push(e);
                    }
                }
            }
        }
        ws.faces.retain(|f| f.live);
        // The faces the new point sees must be bounded by one loop of edges, each giving a
        // well-formed face: then the polytope stays a closed triangulated surface, with at
        // most 2V - 4 faces. A point almost on the polytope can break this by round-off
        // (a face seen and its neighbour not): stop with the last sound polytope's
        // closest face instead of growing a broken one.
        if !is_one_loop(&ws.horizon) {
            break;
        }
        let kept = ws.faces.len();
        for h in 0..ws.horizon.len() {
            let (i, j) = ws.horizon[h];
            if let Some(f) = make_face(&ws.vertices, [i, j, new], None) {
                ws.faces.push(f);
            }
        }
        if ws.faces.len() - kept != ws.horizon.len() || ws.faces.len() + 4 > 2 * ws.vertices.len() {
            break;
        }
    }
    let [a, b, c] = face.v.map(|i| ws.vertices[i]);
    let proj = face.n * face.d;
    let l = barycentric(&proj, &a.w, &b.w, &c.w);
    let wa = a.a * l[0] + b.a * l[1] + c.a * l[2];
    let wb = a.b * l[0] + b.b * l[1] + c.b * l[2];
    warm.direction = -face.n;
    Some(PairDistance {
        distance: -face.d,
        witness_a: wa,
        witness_b: wb,
        normal: face.n,
    })
}

/// Whether the directed edges `h` form one closed loop (each vertex left by one edge).
fn is_one_loop(h: &[(usize, usize)]) -> bool {
    let Some(&(start, mut at)) = h.first() else {
        return false;
    };
    let mut steps = 1;
    while at != start {
        let mut leaving = h.iter().filter(|e| e.0 == at);
        let (Some(e), None) = (leaving.next(), leaving.next()) else {
            return false;
        };
        at = e.1;
        steps += 1;
        if steps > h.len() {
            return false;
        }
    }
    steps == h.len()
}

fn closest_face(faces: &[Face]) -> Option<usize> {
    let mut best = None;
    let mut best_d = f64::INFINITY;
    for (i, f) in faces.iter().enumerate() {
        if f.live && f.d < best_d {
            best_d = f.d;
            best = Some(i);
        }
    }
    best
}

fn make_face(v: &[SupportPoint], mut f: [usize; 3], inside: Option<&Vector3<f64>>) -> Option<Face> {
    let mut n = (v[f[1]].w - v[f[0]].w).cross(&(v[f[2]].w - v[f[0]].w));
    let len = n.norm();
    if len == 0.0 || !len.is_finite() {
        return None;
    }
    n /= len;
    if let Some(c) = inside
        && n.dot(&(v[f[0]].w - c)) < 0.0
    {
        n = -n;
        f.swap(1, 2);
    }
    Some(Face {
        v: f,
        n,
        d: n.dot(&v[f[0]].w),
        live: true,
    })
}

/// Barycentric coordinates of `p` (in the triangle's plane) in triangle (a, b, c).
fn barycentric(p: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>, c: &Vector3<f64>) -> [f64; 3] {
    let (v0, v1, v2) = (b - a, c - a, p - a);
    let (d00, d01, d11) = (v0.dot(&v0), v0.dot(&v1), v1.dot(&v1));
    let (d20, d21) = (v2.dot(&v0), v2.dot(&v1));
    let den = d00 * d11 - d01 * d01;
    if den <= 0.0 {
        return [1.0, 0.0, 0.0];
    }
    let l1 = (d11 * d20 - d01 * d21) / den;
    let l2 = (d00 * d21 - d01 * d20) / den;
    [1.0 - l1 - l2, l1, l2]
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;

    fn cube(h: f64) -> Convex {
        Convex::Box {
            half: Vector3::repeat(h),
        }
    }

    /// Two triangles: parallel 0.3 apart (closest points anywhere on the overlap, at that
    /// distance), an edge over a face, and crossing (0, a common point); a triangle
    /// against a sphere subtracts the radius.
    #[test]
    fn triangle_gaps_touch_at_zero() {
        use crate::collision::convex::Triangle;
        let v = Vector3::new;
        let flat = Triangle([v(0.0, 0.0, 0.0), v(1.0, 0.0, 0.0), v(0.0, 1.0, 0.0)]);
        let id = SE3::identity();
        let up = SE3::from_translation(v(0.1, 0.1, 0.3));
        let mut w = WarmStart::default();
        let r = gap_distance(&flat, &id, &flat, &up, &mut w);
        assert!((r.distance - 0.3).abs() < 1e-12, "{r:?}");
        assert!((r.normal - Vector3::z()).norm() < 1e-9);
        assert!(((r.witness_b - r.witness_a).norm() - 0.3).abs() < 1e-12);
        // A vertical triangle whose lowest edge is 0.2 above the face's middle.
        let wall = Triangle([v(0.1, 0.2, 0.2), v(0.4, 0.2, 0.2), v(0.2, 0.2, 1.0)]);
        let r = gap_distance(&flat, &id, &wall, &id, &mut WarmStart::default());
        assert!((r.distance - 0.2).abs() < 1e-12, "{r:?}");
        // The same wall pushed through the face: crossing, at 0, the point on both.
        let down = SE3::from_translation(v(0.0, 0.0, -0.5));
        let r = gap_distance(&flat, &id, &wall, &down, &mut WarmStart::default());
        assert_eq!(r.distance, 0.0);
        assert_eq!(r.normal, Vector3::zeros());
        assert!(r.witness_a.z.abs() < 1e-9, "{r:?}");
        // A ball of radius 0.1 centred 0.5 above the face.
        let ball = Convex::Sphere { radius: 0.1 };
        let above = SE3::from_translation(v(0.2, 0.2, 0.5));
        let r = gap_distance(&flat, &id, &ball, &above, &mut WarmStart::default());
        assert!((r.distance - 0.4).abs() < 1e-12 && (r.witness_b.z - 0.4).abs() < 1e-12);
        let inside = SE3::from_translation(v(0.2, 0.2, 0.05));
        let r = gap_distance(&flat, &id, &ball, &inside, &mut WarmStart::default());
        assert_eq!(r.distance, 0.0);
    }

    #[test]
    fn boxes_apart_and_overlapping() {
        let mut w = WarmStart::default();
        let mut ws = EpaWorkspace::default();
        let pa = SE3::identity();
        let pb = SE3::from_translation(Vector3::new(3.0, 0.2, -0.1));
        let r = signed_distance(&cube(1.0), &pa, &cube(0.5), &pb, &mut w, &mut ws);
        assert!((r.distance - 1.5).abs() < 1e-12, "{r:?}");
        assert!((r.witness_a.x - 1.0).abs() < 1e-12 && (r.witness_b.x - 2.5).abs() < 1e-12);
        let pb = SE3::from_translation(Vector3::new(1.2, 0.0, 0.0));
        let r = signed_distance(&cube(1.0), &pa, &cube(0.5), &pb, &mut w, &mut ws);
        assert!((r.distance + 0.3).abs() < 1e-12, "{r:?}");
        assert!((r.normal.x.abs() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn spheres_and_capsules_use_their_cores() {
        let mut w = WarmStart::default();
        let mut ws = EpaWorkspace::default();
        let s = Convex::Sphere { radius: 0.5 };
        let c = Convex::Capsule {
            radius: 0.25,
            half_length: 1.0,
        };
        // The capsule's segment runs along x = 1 from z = −1 to 1: 1 − 0.5 − 0.25 apart.
        let pb = SE3::from_translation(Vector3::new(1.0, 0.0, 0.0));
        let r = signed_distance(&s, &SE3::identity(), &c, &pb, &mut w, &mut ws);
        assert!((r.distance - 0.25).abs() < 1e-12, "{r:?}");
        assert!((r.witness_a - Vector3::new(0.5, 0.0, 0.0)).norm() < 1e-12);
        assert!((r.witness_b - Vector3::new(0.75, 0.0, 0.0)).norm() < 1e-12);
        // Overlapping cores: EPA on the inflated shapes, a sphere inside a sphere.
        let pb = SE3::from_translation(Vector3::new(0.1, 0.0, 0.0));
        let r = signed_distance(&s, &SE3::identity(), &s, &pb, &mut w, &mut ws);
        assert!((r.distance + 0.9).abs() < 1e-3, "{r:?}");
    }

    #[test]
    fn distance_outside_decides_with_bounds_and_is_exact_between() {
        let mut w = WarmStart::default();
        let mut ws = EpaWorkspace::default();
        let pa = SE3::identity();
        // Apart by 0.5, touching, overlapping by 0.3.
        for (x, d) in [(2.0, 0.5), (1.5, 0.0), (1.2, -0.3)] {
            let pb = SE3::from_translation(Vector3::new(x, 0.1, 0.0));
            let (a, b) = (cube(1.0), cube(0.5));
            // Between the bounds: the distance itself.
            let v = distance_outside(&a, &pa, &b, &pb, -1.0, 1.0, &mut w, &mut ws);
            assert!((v - d).abs() < 1e-12, "{x}: {v} vs {d}");
            // At most `within`: an upper bound, never below the distance.
            let v = distance_outside(&a, &pa, &b, &pb, 0.6, 1.0, &mut w, &mut ws);
            assert!(v <= 0.6 && v >= d - 1e-12, "{x}: {v} vs {d}");
            // Above `enough`: a lower bound, never above the distance.
            let v = distance_outside(&a, &pa, &b, &pb, -1.0, d - 0.1, &mut w, &mut ws);
            assert!(v > d - 0.1 && v <= d + 1e-12, "{x}: {v} vs {d}");
        }
        // Overlapping cores decided at most `within` skip EPA: the bound is not the depth.
        let pb = SE3::from_translation(Vector3::new(1.2, 0.1, 0.0));
        let v = distance_outside(&cube(1.0), &pa, &cube(0.5), &pb, 0.01, 1.0, &mut w, &mut ws);
        assert!((0.0..=0.01).contains(&v), "{v}");
    }

    /// A patch of Fetch's torso mesh surface (13 vertices, the torso's frame) and the
    /// pick's can (a cylinder) held at a random arm posture, overlapping by 15.5 mm: EPA's
    /// point on the can's rim that converged to within 1.3e-11 m of the polytope saw a face
    /// and not its neighbour by round-off, and the broken polytope grew to 1.4 million
    /// faces (26 s, then a positive "depth" of 32 mm).
    fn torso_patch_and_can() -> (Convex, SE3, Convex, SE3) {
        let v = [
            [
                -0.018678657710552216,
                -0.07823757082223892,
                0.48767927289009094,
            ],
            [
                -0.018678657710552216,
                -0.07124803215265274,
                0.47767695784568787,
            ],
            [
                -0.018678657710552216,
                -0.06102566048502922,
                0.4710288345813751,
            ],
            [
                -0.018678657710552216,
                -0.053860366344451904,
                0.2861594259738922,
            ],
            [
                -0.018678657710552216,
                -0.05000000074505806,
                0.28831377625465393,
            ],
            [
                -0.018678657710552216,
                -0.04905466362833977,
                0.4687000811100006,
            ],
            [
                -0.018678657710552216,
                -0.0002500000118743628,
                0.28831377625465393,
            ],
            [
                -0.018678657710552216,
                -0.0002500000118743628,
                0.4687000811100006,
            ],
            [
                0.034171100705862045,
                -0.09398100525140762,
                0.42087385058403015,
            ],
            [
                0.036079831421375275,
                -0.059844303876161575,
                0.47451213002204895,
            ],
            [0.03651868551969528, -0.0471743568778038, 0.4208739101886749],
            [
                0.037139393389225006,
                -0.0002500000118743628,
                0.37741538882255554,
            ],
            [
                0.037465132772922516,
                -0.00025035993894562125,
                0.47262606024742126,
            ],
        ];
        let patch = Convex::Hull {
            vertices: v.iter().map(|p| Vector3::from(*p)).collect(),
            neighbours: Vec::new(),
        };
        let pose_patch = SE3::new(
            Matrix3::from_column_slice(&[1.0, 0.0, 0.0, 0.0, 1.0, -6.123e-17, 0.0, 6.123e-17, 1.0]),
            Vector3::new(-0.086875, 1.9355935210512733e-18, 0.4090418491107508),
        );
        let can = Convex::Cylinder {
            radius: 0.03,
            half_height: 0.07,
        };
        let pose_can = SE3::new(
            Matrix3::from_column_slice(&[
                -0.7261298381733813,
                -0.377342966185498,
                0.5747588572476541,
                0.6683973136809866,
                -0.5833773451805426,
                0.46142811378820736,
                0.16118464312191716,
                0.7192239977923652,
                0.6758227221847664,
            ]),
            Vector3::new(
                -0.10400289933693851,
                -0.059528324588966994,
                0.6446143782264571,
            ),
        );
        (patch, pose_patch, can, pose_can)
    }

    #[test]
    fn epa_stops_at_a_polytope_that_round_off_breaks() {
        let (patch, pose_patch, can, pose_can) = torso_patch_and_can();
        let mut ws = EpaWorkspace::default();
        let r = signed_distance(
            &patch,
            &pose_patch,
            &can,
            &pose_can,
            &mut WarmStart::default(),
            &mut ws,
        );
        // Bounded work: a few thousand face visits (the broken polytope took 1.4e8).
        assert!(ws.faces_visited() < 10_000, "{}", ws.faces_visited());
        assert!((r.distance + 0.015463).abs() < 1e-6, "{r:?}");
        // The depth is the translation that separates them: the can moved along the
        // normal by the depth less 1 µm still overlaps, by the depth and 1 µm more is
        // 1 µm clear.
        for (extra, clear) in [(-1e-6, false), (1e-6, true)] {
            let moved = SE3::new(
                pose_can.rotation,
                pose_can.translation + r.normal * (-r.distance + extra),
            );
            let d = signed_distance(
                &patch,
                &pose_patch,
                &can,
                &moved,
                &mut WarmStart::default(),
                &mut ws,
            )
            .distance;
            assert_eq!(d > 0.0, clear, "{extra}: {d}");
            assert!((d - extra).abs() < 1e-9, "{extra}: {d}");
        }
    }
}

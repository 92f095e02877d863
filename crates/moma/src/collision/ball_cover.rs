//! Balls whose union holds a convex hull: the hull cut into slabs along its longest box
//! axis, one ball around each slab's piece.
//!
//! The piece of `conv(V)` between two parallel planes is the convex hull of the points
//! of `V` between them and of the points where the segments joining two points of `V`
//! cross the planes (every vertex of the piece is a vertex of the hull inside the slab or
//! the crossing of a hull edge, and a hull edge joins two points of `V`; with the hull's
//! edge graph only its edges are cut, else every pair of points). A ball around
//! those points holds the piece, so the balls together hold the whole hull: a positive
//! gap between every ball and another shape is a positive distance between the hull and
//! that shape. Thin balls along a long link bound its distance far more tightly than one
//! ball around all of it.

use nalgebra::Vector3;

/// A ball: centre and radius, in the hull's frame.
pub type CoverBall = (Vector3<f64>, f64);

/// The most slabs a hull is cut into.
pub const MAX_SLABS: usize = 6;

/// Balls whose union holds `conv(vertices)`: `slabs` (at least 1) equal slabs along the
/// longest axis of the vertices' box, one ball per slab that holds some of the hull.
/// `neighbours` is the hull's edge graph ([`super::Convex::Hull`]'s), or empty lists
/// when it is not known (then every pair of vertices is cut). Empty for no vertices.
#[must_use]
pub fn hull_ball_cover(
    vertices: &[Vector3<f64>],
    neighbours: &[Vec<usize>],
    slabs: usize,
) -> Vec<CoverBall> {
    if vertices.is_empty() {
        return Vec::new();
    }
    let (lo, hi) = vertices.iter().fold(
        (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        ),
        |(lo, hi), v| (lo.inf(v), hi.sup(v)),
    );
    let axis = (hi - lo).imax();
    let slabs = slabs.max(1);
    let width = (hi[axis] - lo[axis]) / slabs as f64;
    if slabs == 1 || width <= 0.0 {
        return vec![ball_around(vertices.iter().copied())];
    }
    let plane = |k: usize| lo[axis] + width * k as f64;
    // Per slab: the points of its piece; slab `k` is `plane(k) ≤ x ≤ plane(k + 1)`, the
    // outer ones unbounded outwards (a vertex on a plane belongs to both sides).
    let mut points: Vec<Vec<Vector3<f64>>> = vec![Vec::new(); slabs];
    for v in vertices {
        for (k, piece) in points.iter_mut().enumerate() {
            let below = k == 0 || v[axis] >= plane(k);
            let above = k + 1 == slabs || v[axis] <= plane(k + 1);
            if below && above {
                piece.push(*v);
            }
        }
    }
    let graph = neighbours.len() == vertices.len() && neighbours.iter().all(|n| !n.is_empty());
    let edges = (0..vertices.len()).flat_map(|i| {
        let ends: Box<dyn Iterator<Item = usize>> = if graph {
            Box::new(neighbours[i].iter().copied().filter(move |&j| j > i))
        } else {
            Box::new(i + 1..vertices.len())
        };
        ends.map(move |j| (i, j))
    });
    for (i, j) in edges {
        {
            let (a, b) = (&vertices[i], &vertices[j]);
            let (p, q) = if a[axis] <= b[axis] { (a, b) } else { (b, a) };
            // The inner planes strictly between the two ends.
            for k in 1..slabs {
                let t = plane(k);
                if p[axis] < t && t < q[axis] {
                    let s = (t - p[axis]) / (q[axis] - p[axis]);
                    let mut x = p + (q - p) * s;
                    x[axis] = t;
                    points[k - 1].push(x);
                    points[k].push(x);
                }
            }
        }
    }
    points
        .into_iter()
        .filter(|pts| !pts.is_empty())
        .map(|pts| ball_around(pts.into_iter()))
        .collect()
}

/// A ball around the points: centre at their box's middle, radius to the farthest one
/// (widened by a relative 1e-12 for round-off).
fn ball_around(points: impl Iterator<Item = Vector3<f64>> + Clone) -> CoverBall {
    let (lo, hi) = points.clone().fold(
        (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        ),
        |(lo, hi), v| (lo.inf(&v), hi.sup(&v)),
    );
    let centre = (lo + hi) / 2.0;
    let radius = points.map(|p| (p - centre).norm()).fold(0.0, f64::max);
    (centre, radius * (1.0 + 1e-12) + 1e-15)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::mesh::convex_hull_vertices;

    /// A long box's corners, and the box sheared with an inner point: every point of the
    /// hull (random convex combinations of the points, the midpoints of every pair) lies
    /// in some ball, cutting every pair or only the hull's edges, and the balls are much
    /// smaller than the hull's one ball.
    #[test]
    fn cover_holds_the_hull_and_is_tighter() {
        let mut corners = Vec::new();
        for &x in &[-0.5, 0.5] {
            for &y in &[-0.05, 0.05] {
                for &z in &[-0.04, 0.04] {
                    corners.push(Vector3::new(x, y, z));
                }
            }
        }
        let sheared: Vec<Vector3<f64>> = corners
            .iter()
            .map(|c| Vector3::new(c.x + 0.3 * c.y, c.y + 0.2 * c.x, c.z))
            .chain(std::iter::once(Vector3::new(0.1, 0.0, 0.0)))
            .collect();
        for points in [&corners, &sheared] {
            let hull = convex_hull_vertices(points);
            assert!(hull.neighbours.iter().all(|n| !n.is_empty()));
            for (vertices, neighbours) in [
                (points.clone(), Vec::new()),
                (hull.vertices.clone(), hull.neighbours.clone()),
            ] {
                let cover = hull_ball_cover(&vertices, &neighbours, 5);
                assert_eq!(cover.len(), 5);
                let inside = |p: &Vector3<f64>| cover.iter().any(|(c, r)| (p - c).norm() <= *r);
                let mut seed = 12345u64;
                let mut next = || {
                    seed = seed
                        .wrapping_mul(6364136223846793005)
                        .wrapping_add(1442695040888963407);
                    (seed >> 11) as f64 / (1u64 << 53) as f64
                };
                for _ in 0..20_000 {
                    let w: Vec<f64> = points.iter().map(|_| next().powi(4)).collect();
                    let total: f64 = w.iter().sum();
                    let p = points
                        .iter()
                        .zip(&w)
                        .fold(Vector3::zeros(), |s, (v, wi)| s + v * (wi / total));
                    assert!(inside(&p), "{p:?} outside every ball");
                }
                for a in points.iter() {
                    for b in points.iter() {
                        assert!(inside(&((a + b) / 2.0)));
                    }
                }
                let one = hull_ball_cover(&vertices, &neighbours, 1)[0].1;
                let largest = cover.iter().map(|b| b.1).fold(0.0, f64::max);
                assert!(largest < 0.4 * one, "{largest} vs {one}");
            }
        }
    }

    #[test]
    fn one_point_and_flat_sets() {
        assert!(hull_ball_cover(&[], &[], 3).is_empty());
        let p = Vector3::new(1.0, 2.0, 3.0);
        let c = hull_ball_cover(&[p], &[], 4);
        assert_eq!(c.len(), 1);
        assert!((c[0].0 - p).norm() < 1e-15 && c[0].1 < 1e-12);
    }
}

//! The support polygon: convex hull of the ground contacts, clockwise seen from above.

use nalgebra::{Vector2, Vector3};

use crate::error::{Error, Result};

/// One tip-over axis (edge) of a support polygon, in world coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Edge {
    /// A point on the axis: vertex i (on the ground plane).
    pub from: Vector3<f64>,
    /// The next vertex i + 1 (for the two-contact segment support: `from` + `axis`).
    pub to: Vector3<f64>,
    /// Unit tip-over axis `a_i` (from `from` to `to` for a polygon).
    pub axis: Vector3<f64>,
    /// Unit inward normal of the edge in the ground plane, `a_i × ẑ`.
    pub inward: Vector3<f64>,
}

/// Whether a support is a real polygon or the two-contact segment of a planar model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SupportKind {
    /// At least three non-collinear contacts: edge i runs from vertex i to vertex i + 1.
    Polygon,
    /// Two contacts of a model that moves in one vertical plane (the chapter's cart):
    /// two tip-over axes, one through each contact, perpendicular to the segment.
    Segment,
}

/// A support polygon on the horizontal ground plane `z = ground_z` (normal +z).
///
/// Vertices are the convex hull of the contacts ordered **clockwise seen from above**
/// (Papadopoulos & Rey), starting at the vertex of smallest x (ties: smallest y); edge
/// `i` runs from vertex `i` to vertex `i + 1` (mod n), and the interior lies to the right
/// of every directed edge, so the inward normal is `a_i × ẑ`. Contacts strictly inside
/// the hull or on an edge between two vertices are dropped.
///
/// Build it once in the base frame ([`SupportPolygon::from_points`],
/// [`SupportPolygon::from_wheeled_base`]) and move it with the base pose
/// ([`SupportPolygon::place_into`], allocation-free), or build it directly in world
/// coordinates.
#[derive(Clone, Debug, PartialEq)]
pub struct SupportPolygon {
    vertices: Vec<Vector2<f64>>,
    ground_z: f64,
    kind: SupportKind,
}

/// Relative tolerance under which three contacts count as collinear (times the squared
/// size of the contact set).
const COLLINEAR_TOL: f64 = 1e-12;

fn cross2(o: &Vector2<f64>, a: &Vector2<f64>, b: &Vector2<f64>) -> f64 {
    (a.x - o.x) * (b.y - o.y) - (a.y - o.y) * (b.x - o.x)
}

/// Index of the vertex with the smallest x (ties: smallest y); the lowest index on full ties.
fn start_index(v: &[Vector2<f64>]) -> usize {
    let mut best = 0;
    for (i, p) in v.iter().enumerate().skip(1) {
        let b = &v[best];
        if p.x < b.x || (p.x == b.x && p.y < b.y) {
            best = i;
        }
    }
    best
}

impl SupportPolygon {
    /// The convex hull of ground contact points `points` (`[x, y]`, on `z = 0`).
    ///
    /// # Errors
    /// [`Error::NonFinite`] for a non-finite coordinate, [`Error::InvalidInput`] when
    /// fewer than three non-collinear contacts remain.
    pub fn from_points(points: &[Vector2<f64>]) -> Result<Self> {
        Self::from_points_at_height(points, 0.0)
    }

    /// As [`SupportPolygon::from_points`] on the ground plane `z = ground_z`.
    ///
    /// # Errors
    /// As [`SupportPolygon::from_points`].
    pub fn from_points_at_height(points: &[Vector2<f64>], ground_z: f64) -> Result<Self> {
        for (k, p) in points.iter().enumerate() {
            if !(p.x.is_finite() && p.y.is_finite()) {
                return Err(Error::NonFinite {
                    field: format!("support point {k}"),
                });
            }
        }
        if !ground_z.is_finite() {
            return Err(Error::NonFinite {
                field: "support ground height".into(),
            });
        }
        let vertices = convex_hull(points)?;
        Ok(Self {
            vertices,
            ground_z,
            kind: SupportKind::Polygon,
        })
    }

    /// The support of a wheeled base in its base frame: the two drive-wheel contacts
    /// (under the wheel axes, `d` behind the base origin) and the casters.
    ///
    /// # Errors
    /// As [`SupportPolygon::from_points`] (a base without at least one caster off the
    /// axle has fewer than three non-collinear contacts).
    pub fn from_wheeled_base(base: &crate::mobile::WheeledBase) -> Result<Self> {
        Self::from_points(&base.support_points())
    }

    /// The support of a wheeled robot: [`SupportPolygon::from_wheeled_base`] on the
    /// ground of [`crate::mobile::WheeledModel::ground_z`] (derived from the wheel
    /// geometry, so a URDF rooted at axle height gets the right ZMP and tip limits).
    ///
    /// # Errors
    /// As [`SupportPolygon::from_points`].
    pub fn from_wheeled_model(robot: &crate::mobile::WheeledModel) -> Result<Self> {
        Self::from_points_at_height(&robot.base.support_points(), robot.ground_z())
    }

    /// The two-contact support of a model moving in one vertical plane (the chapter's
    /// cart): contacts `a` and `b` on `z = ground_z`. The two tip-over axes pass through
    /// the contacts, perpendicular to the segment and horizontal; edge 0 is at the contact
    /// of smaller x (ties: smaller y), with the inward normal pointing along the segment.
    ///
    /// # Errors
    /// [`Error::NonFinite`], or [`Error::InvalidInput`] if the contacts coincide.
    pub fn segment(a: Vector2<f64>, b: Vector2<f64>, ground_z: f64) -> Result<Self> {
        if !(a.iter().chain(b.iter()).all(|x| x.is_finite()) && ground_z.is_finite()) {
            return Err(Error::NonFinite {
                field: "support segment".into(),
            });
        }
        let scale = a.norm().max(b.norm()).max(1.0);
        if (b - a).norm() <= 1e-12 * scale {
            return Err(Error::invalid(
                "support segment",
                "the two contacts coincide",
            ));
        }
        let mut v = vec![a, b];
        if start_index(&v) == 1 {
            v.swap(0, 1);
        }
        Ok(Self {
            vertices: v,
            ground_z,
            kind: SupportKind::Segment,
        })
    }

    /// Number of edges (= vertices; 2 for a segment).
    #[must_use]
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    /// Never true (a support has at least two vertices); for clippy's `len` convention.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// Polygon or segment.
    #[must_use]
    pub fn kind(&self) -> SupportKind {
        self.kind
    }

    /// Height of the ground plane (m).
    #[must_use]
    pub fn ground_z(&self) -> f64 {
        self.ground_z
    }

    /// Vertex `i` on the ground plane.
    #[must_use]
    pub fn vertex(&self, i: usize) -> Vector3<f64> {
        let p = self.vertices[i];
        Vector3::new(p.x, p.y, self.ground_z)
    }

    /// The vertices `[x, y]` in order (clockwise from above).
    #[must_use]
    pub fn vertices_xy(&self) -> &[Vector2<f64>] {
        &self.vertices
    }

    /// Edge `i` (tip-over axis i).
    ///
    /// # Panics
    /// If `i >= self.len()`.
    #[must_use]
    pub fn edge(&self, i: usize) -> Edge {
        let n = self.vertices.len();
        match self.kind {
            SupportKind::Polygon => {
                let from = self.vertex(i);
                let to = self.vertex((i + 1) % n);
                let axis = (to - from).normalize();
                let inward = Vector3::new(axis.y, -axis.x, 0.0);
                Edge {
                    from,
                    to,
                    axis,
                    inward,
                }
            }
            SupportKind::Segment => {
                let (p, other) = (self.vertex(i), self.vertex(1 - i));
                let inward = (other - p).normalize();
                // inward = a × ẑ = (a_y, −a_x, 0)  ⇒  a = (−inward_y, inward_x, 0)
                let axis = Vector3::new(-inward.y, inward.x, 0.0);
                Edge {
                    from: p,
                    to: p + axis,
                    axis,
                    inward,
                }
            }
        }
    }

    /// Writes this support (given in a base frame) into `out`, moved by the planar pose
    /// `(x, y, yaw)` of the base on the ground: rotation about z then translation; the
    /// start vertex is chosen again in the new frame. `out` keeps its capacity, so this
    /// does not allocate once `out` has held a support as large.
    pub fn place_into(&self, x: f64, y: f64, yaw: f64, out: &mut SupportPolygon) {
        let (s, c) = yaw.sin_cos();
        out.vertices.clear();
        out.vertices.extend(
            self.vertices
                .iter()
                .map(|p| Vector2::new(x + c * p.x - s * p.y, y + s * p.x + c * p.y)),
        );
        out.ground_z = self.ground_z;
        out.kind = self.kind;
        let k = start_index(&out.vertices);
        out.vertices.rotate_left(k);
    }
}

/// Andrew's monotone chain; returns the strict convex hull clockwise from above, starting
/// at the smallest-x (then smallest-y) vertex.
fn convex_hull(points: &[Vector2<f64>]) -> Result<Vec<Vector2<f64>>> {
    let too_few = |n: usize| {
        Error::invalid(
            "support polygon",
            format!(
                "needs at least three non-collinear contact points, got {n} \
                 (after dropping duplicates and collinear points)"
            ),
        )
    };
    if points.len() < 3 {
        return Err(too_few(points.len()));
    }
    let mut pts: Vec<Vector2<f64>> = points.to_vec();
    pts.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    pts.dedup();
    let scale = pts
        .iter()
        .map(|p| (p - pts[0]).norm_squared())
        .fold(0.0, f64::max)
        .max(f64::MIN_POSITIVE);
    let tol = COLLINEAR_TOL * scale;
    // Lower hull (counter-clockwise from the leftmost point), then upper hull.
    let mut hull: Vec<Vector2<f64>> = Vec::with_capacity(2 * pts.len());
    for p in &pts {
        while hull.len() >= 2 && cross2(&hull[hull.len() - 2], &hull[hull.len() - 1], p) <= tol {
            hull.pop();
        }
        hull.push(*p);
    }
    let lower = hull.len() + 1;
    for p in pts.iter().rev().skip(1) {
        while hull.len() >= lower && cross2(&hull[hull.len() - 2], &hull[hull.len() - 1], p) <= tol
        {
            hull.pop();
        }
        hull.push(*p);
    }
    hull.pop(); // the first point again
    if hull.len() < 3 {
        return Err(too_few(hull.len()));
    }
    // Counter-clockwise starting at the leftmost-lowest point; reverse to clockwise and
    // keep the same start vertex.
    hull[1..].reverse();
    let k = start_index(&hull);
    hull.rotate_left(k);
    Ok(hull)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn box4() -> Vec<Vector2<f64>> {
        vec![
            Vector2::new(0.5, 0.3),
            Vector2::new(0.5, -0.3),
            Vector2::new(-0.5, -0.3),
            Vector2::new(-0.5, 0.3),
        ]
    }

    #[test]
    fn hull_is_clockwise_from_the_smallest_x_vertex_in_any_input_order() {
        let expected = [
            Vector2::new(-0.5, -0.3),
            Vector2::new(-0.5, 0.3),
            Vector2::new(0.5, 0.3),
            Vector2::new(0.5, -0.3),
        ];
        let mut pts = box4();
        for perm in 0..24 {
            // every permutation of four points, via Heap-style index shuffles
            let mut idx = [0usize, 1, 2, 3];
            let mut k = perm;
            for i in (1..4).rev() {
                idx.swap(i, k % (i + 1));
                k /= i + 1;
            }
            let input: Vec<_> = idx.iter().map(|&i| pts[i]).collect();
            let poly = SupportPolygon::from_points(&input).unwrap();
            assert_eq!(poly.vertices_xy(), &expected, "permutation {perm}");
        }
        // with an interior contact and a contact in the middle of an edge
        pts.push(Vector2::new(0.1, 0.0));
        pts.push(Vector2::new(0.0, 0.3));
        let poly = SupportPolygon::from_points(&pts).unwrap();
        assert_eq!(poly.vertices_xy(), &expected);
        for i in 0..4 {
            let e = poly.edge(i);
            // interior to the right of each directed edge
            let c = Vector3::new(0.0, 0.0, 0.0);
            assert!(e.inward.dot(&(c - e.from)) > 0.0);
            assert!((e.axis.norm() - 1.0).abs() < 1e-15);
        }
    }

    #[test]
    fn too_few_or_collinear_contacts_are_errors() {
        let two = [Vector2::new(0.0, 0.0), Vector2::new(1.0, 0.0)];
        assert!(SupportPolygon::from_points(&two).is_err());
        let line = [
            Vector2::new(0.0, 0.0),
            Vector2::new(1.0, 1.0),
            Vector2::new(2.0, 2.0),
            Vector2::new(0.5, 0.5),
        ];
        let e = SupportPolygon::from_points(&line).unwrap_err().to_string();
        assert!(e.contains("three non-collinear"), "{e}");
        let dup = [Vector2::new(0.0, 0.0); 3];
        assert!(SupportPolygon::from_points(&dup).is_err());
        let nan = [
            Vector2::new(0.0, 0.0),
            Vector2::new(1.0, f64::NAN),
            Vector2::new(0.0, 1.0),
        ];
        assert!(matches!(
            SupportPolygon::from_points(&nan),
            Err(Error::NonFinite { .. })
        ));
    }

    #[test]
    fn placing_keeps_the_order_convention() {
        let poly = SupportPolygon::from_points(&box4()).unwrap();
        let mut out = poly.clone();
        for k in 0..40 {
            let yaw = -3.1 + 0.16 * k as f64;
            poly.place_into(1.0, -2.0, yaw, &mut out);
            let v = out.vertices_xy();
            let s = start_index(v);
            assert_eq!(s, 0);
            // clockwise: negative signed area
            let mut area = 0.0;
            for i in 0..v.len() {
                let (a, b) = (v[i], v[(i + 1) % v.len()]);
                area += a.x * b.y - b.x * a.y;
            }
            assert!(area < 0.0);
            assert!((area.abs() / 2.0 - 0.6).abs() < 1e-12);
        }
    }

    #[test]
    fn segment_axes_point_inwards() {
        let s =
            SupportPolygon::segment(Vector2::new(0.4, 0.0), Vector2::new(-0.2, 0.0), -0.1).unwrap();
        assert_eq!(s.len(), 2);
        let (e0, e1) = (s.edge(0), s.edge(1));
        assert_eq!(e0.from, Vector3::new(-0.2, 0.0, -0.1));
        assert_eq!(e0.inward, Vector3::new(1.0, 0.0, 0.0));
        assert_eq!(e1.inward, Vector3::new(-1.0, 0.0, 0.0));
        // a × ẑ = inward
        for e in [e0, e1] {
            assert!((e.axis.cross(&Vector3::z()) - e.inward).norm() < 1e-15);
        }
        assert!(SupportPolygon::segment(Vector2::zeros(), Vector2::zeros(), 0.0).is_err());
    }
}

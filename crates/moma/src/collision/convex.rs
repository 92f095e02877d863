//! Convex shapes and their support functions in their own frame.
//!
//! A shape is a *core* (a hull, a box, a cylinder, a point or a segment) plus a *margin*
//! (the radius of a sphere or capsule): the shape is the core's Minkowski sum with a ball
//! of that radius. The distance code runs on the cores and subtracts the margins, which is
//! exact and converges in a few steps where a round support map would need many.

use nalgebra::Vector3;

/// A convex shape in its own frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Convex {
    /// The convex hull of a point set (a mesh's hull), with hull-edge adjacency used to
    /// climb to the support vertex from the last one found.
    Hull {
        /// Hull vertices.
        vertices: Vec<Vector3<f64>>,
        /// Neighbours of each vertex along hull edges; empty lists if the climb cannot
        /// be trusted (then every vertex is scanned).
        neighbours: Vec<Vec<usize>>,
    },
    /// A box centred on the origin with these half side lengths.
    Box {
        /// Half side lengths along x, y, z.
        half: Vector3<f64>,
    },
    /// A cylinder along z, centred on the origin.
    Cylinder {
        /// Radius.
        radius: f64,
        /// Half of the height.
        half_height: f64,
    },
    /// A sphere centred on the origin (core: the origin; margin: the radius).
    Sphere {
        /// Radius.
        radius: f64,
    },
    /// A capsule along z centred on the origin (core: the segment; margin: the radius).
    Capsule {
        /// Radius.
        radius: f64,
        /// Half of the segment's length (the cylindrical part).
        half_length: f64,
    },
}

/// Hulls with more vertices than this climb along edges; smaller ones are scanned.
const CLIMB_ABOVE: usize = 24;

impl Convex {
    /// The radius added around the core.
    #[must_use]
    pub fn margin(&self) -> f64 {
        match self {
            Convex::Sphere { radius } | Convex::Capsule { radius, .. } => *radius,
            _ => 0.0,
        }
    }

    /// A point of the core that maximises `d · p`; `hint` is the hull vertex to start the
    /// climb from (updated to the one found), unused by the other shapes.
    #[must_use]
    pub fn core_support(&self, d: &Vector3<f64>, hint: &mut usize) -> Vector3<f64> {
        match self {
            Convex::Hull {
                vertices,
                neighbours,
            } => {
                let climb = vertices.len() > CLIMB_ABOVE
                    && neighbours.first().is_some_and(|n| !n.is_empty());
                let best = if climb {
                    climb_support(vertices, neighbours, d, (*hint).min(vertices.len() - 1))
                } else {
                    scan_support(vertices, d)
                };
                *hint = best;
                vertices[best]
            }
            Convex::Box { half } => Vector3::new(
                half.x.copysign(d.x),
                half.y.copysign(d.y),
                half.z.copysign(d.z),
            ),
            Convex::Cylinder {
                radius,
                half_height,
            } => {
                let r = d.x.hypot(d.y);
                let z = half_height.copysign(d.z);
                if r > 0.0 {
                    Vector3::new(radius * d.x / r, radius * d.y / r, z)
                } else {
                    Vector3::new(0.0, 0.0, z)
                }
            }
            Convex::Sphere { .. } => Vector3::zeros(),
            Convex::Capsule { half_length, .. } => {
                Vector3::new(0.0, 0.0, half_length.copysign(d.z))
            }
        }
    }

    /// Radius of a ball about the origin that holds the whole shape (margin included).
    #[must_use]
    pub fn bounding_radius(&self) -> f64 {
        match self {
            Convex::Hull { vertices, .. } => vertices.iter().map(|v| v.norm()).fold(0.0, f64::max),
            Convex::Box { half } => half.norm(),
            Convex::Cylinder {
                radius,
                half_height,
            } => radius.hypot(*half_height),
            Convex::Sphere { radius } => *radius,
            Convex::Capsule {
                radius,
                half_length,
            } => radius + half_length,
        }
    }

    /// Half extents of the shape's axis-aligned bounding box in its own frame, about
    /// `centre`: `(centre, half)`.
    #[must_use]
    pub fn local_aabb(&self) -> (Vector3<f64>, Vector3<f64>) {
        match self {
            Convex::Hull { vertices, .. } => {
                let mut lo = Vector3::repeat(f64::INFINITY);
                let mut hi = Vector3::repeat(f64::NEG_INFINITY);
                for v in vertices {
                    lo = lo.inf(v);
                    hi = hi.sup(v);
                }
                ((lo + hi) / 2.0, (hi - lo) / 2.0)
            }
            Convex::Box { half } => (Vector3::zeros(), *half),
            Convex::Cylinder {
                radius,
                half_height,
            } => (
                Vector3::zeros(),
                Vector3::new(*radius, *radius, *half_height),
            ),
            Convex::Sphere { radius } => (Vector3::zeros(), Vector3::repeat(*radius)),
            Convex::Capsule {
                radius,
                half_length,
            } => (
                Vector3::zeros(),
                Vector3::new(*radius, *radius, radius + half_length),
            ),
        }
    }
}

/// What GJK needs of a convex shape: its core's support point and its margin.
pub trait Support {
    /// The radius added around the core.
    fn margin(&self) -> f64;
    /// A point of the core that maximises `d · p` (`hint`: see [`Convex::core_support`]).
    fn core_support(&self, d: &Vector3<f64>, hint: &mut usize) -> Vector3<f64>;
}

impl Support for Convex {
    fn margin(&self) -> f64 {
        Convex::margin(self)
    }
    fn core_support(&self, d: &Vector3<f64>, hint: &mut usize) -> Vector3<f64> {
        Convex::core_support(self, d, hint)
    }
}

/// A triangle of a mesh (its three vertices): a flat convex shape without margin, the
/// element of the exact triangle-mesh distances ([`super::exact`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Triangle(pub [Vector3<f64>; 3]);

impl Triangle {
    /// Axis-aligned bounding box (min, max) in the mesh's frame.
    #[must_use]
    pub fn aabb(&self) -> (Vector3<f64>, Vector3<f64>) {
        let [a, b, c] = &self.0;
        (a.inf(b).inf(c), a.sup(b).sup(c))
    }
}

impl Support for Triangle {
    fn margin(&self) -> f64 {
        0.0
    }
    fn core_support(&self, d: &Vector3<f64>, _hint: &mut usize) -> Vector3<f64> {
        let [a, b, c] = &self.0;
        let (da, db, dc) = (a.dot(d), b.dot(d), c.dot(d));
        if da >= db && da >= dc {
            *a
        } else if db >= dc {
            *b
        } else {
            *c
        }
    }
}

/// The first vertex that maximises `d · v`, as a sequential scan finds it, by four
/// independent lanes (vertex `i` in lane `i % 4`, each keeping its first maximiser) that
/// the processor runs side by side, then the best lane, the lowest index on ties.
fn scan_support(vertices: &[Vector3<f64>], d: &Vector3<f64>) -> usize {
    let mut best = [0usize; 4];
    let mut best_dot = [f64::NEG_INFINITY; 4];
    let chunks = vertices.chunks_exact(4);
    let rest = chunks.remainder();
    for (c, chunk) in chunks.enumerate() {
        for (l, v) in chunk.iter().enumerate() {
            let s = v.dot(d);
            if s > best_dot[l] {
                best_dot[l] = s;
                best[l] = 4 * c + l;
            }
        }
    }
    let base = vertices.len() - rest.len();
    for (l, v) in rest.iter().enumerate() {
        let s = v.dot(d);
        if s > best_dot[l] {
            best_dot[l] = s;
            best[l] = base + l;
        }
    }
    let mut k = 0;
    for l in 1..4 {
        if best_dot[l] > best_dot[k] || (best_dot[l] == best_dot[k] && best[l] < best[k]) {
            k = l;
        }
    }
    best[k]
}

/// Hill climb along hull edges: on a convex polytope a vertex no neighbour improves on
/// is a global maximiser of `d · p`.
fn climb_support(
    vertices: &[Vector3<f64>],
    neighbours: &[Vec<usize>],
    d: &Vector3<f64>,
    start: usize,
) -> usize {
    let mut best = start;
    let mut best_dot = vertices[best].dot(d);
    loop {
        let mut moved = false;
        for &n in &neighbours[best] {
            let s = vertices[n].dot(d);
            if s > best_dot {
                best_dot = s;
                best = n;
                moved = true;
            }
        }
        if !moved {
            return best;
        }
    }
}

//! A ball's gap to a shape in closed form: the distance from the ball's centre to a box,
//! cylinder, sphere or capsule (0 inside), less its radius, which is the distance between
//! the ball and the shape when they are apart and a lower bound on the distance of
//! anything inside the ball. A hull is bounded by the 26 planes of its discrete-orientation
//! polytope in its own frame (normals along the frame's axes, the diagonals of its
//! faces and of the cube; each plane at the hull's support value along its normal): the
//! hull lies behind every plane, so the largest signed distance of the point beyond a
//! plane is a lower bound on its distance to the hull, exact where the nearest feature is
//! a face parallel to one of them.
//!
//! The arm planner's state check tries these gaps, one per cover ball
//! ([`super::ball_cover`]), before any GJK: a few dozen multiplications against GJK's
//! iterations of support maps.

use super::convex::Convex;
use crate::spatial::SE3;
use nalgebra::{Matrix3, Vector3};

/// The normals of a hull's bounding planes (unnormalised: each row's length is in
/// [`INV_NORMS`]).
const DOP: [[f64; 3]; 26] = [
    [1.0, 0.0, 0.0],
    [-1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, -1.0, 0.0],
    [0.0, 0.0, 1.0],
    [0.0, 0.0, -1.0],
    [1.0, 1.0, 0.0],
    [1.0, -1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [-1.0, -1.0, 0.0],
    [1.0, 0.0, 1.0],
    [1.0, 0.0, -1.0],
    [-1.0, 0.0, 1.0],
    [-1.0, 0.0, -1.0],
    [0.0, 1.0, 1.0],
    [0.0, 1.0, -1.0],
    [0.0, -1.0, 1.0],
    [0.0, -1.0, -1.0],
    [1.0, 1.0, 1.0],
    [1.0, 1.0, -1.0],
    [1.0, -1.0, 1.0],
    [1.0, -1.0, -1.0],
    [-1.0, 1.0, 1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [-1.0, -1.0, -1.0],
];

/// The shape's own description, in its frame.
#[derive(Clone, Copy, Debug)]
pub enum ShapeBound {
    /// A box centred on the origin with these half sides.
    Box { half: Vector3<f64> },
    /// A hull behind 26 planes: plane `i` is `DOP[i] · x ≤ offsets[i]` (the unit normal's
    /// offset times `DOP[i]`'s length, widened by 1e-12 m for round-off).
    Planes { offsets: [f64; 26] },
    /// A cylinder along z, centred on the origin.
    Cylinder { radius: f64, half_height: f64 },
    /// A segment along z from `-half_length` to `half_length`, swept by `radius` (a
    /// sphere has `half_length` 0).
    Capsule { radius: f64, half_length: f64 },
}

impl ShapeBound {
    /// The bound of `shape` in its own frame.
    #[must_use]
    pub fn new(shape: &Convex) -> Self {
        match shape {
            Convex::Box { half } => ShapeBound::Box { half: *half },
            Convex::Cylinder {
                radius,
                half_height,
            } => ShapeBound::Cylinder {
                radius: *radius,
                half_height: *half_height,
            },
            Convex::Sphere { radius } => ShapeBound::Capsule {
                radius: *radius,
                half_length: 0.0,
            },
            Convex::Capsule {
                radius,
                half_length,
            } => ShapeBound::Capsule {
                radius: *radius,
                half_length: *half_length,
            },
            Convex::Hull { vertices, .. } => {
                let mut offsets = [f64::NEG_INFINITY; 26];
                for v in vertices {
                    for (o, n) in offsets.iter_mut().zip(&DOP) {
                        *o = o.max(n[0] * v.x + n[1] * v.y + n[2] * v.z);
                    }
                }
                for (o, n) in offsets.iter_mut().zip(&DOP) {
                    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
                    *o += 1e-12 * len;
                }
                ShapeBound::Planes { offsets }
            }
        }
    }

    /// The distance from point `x` (shape frame) to the shape (0 inside; for a hull a
    /// lower bound, module docs).
    #[must_use]
    pub fn point_distance(&self, x: &Vector3<f64>) -> f64 {
        match self {
            ShapeBound::Box { half } => Vector3::new(
                (x.x.abs() - half.x).max(0.0),
                (x.y.abs() - half.y).max(0.0),
                (x.z.abs() - half.z).max(0.0),
            )
            .norm(),
            ShapeBound::Planes { offsets } => {
                let mut beyond = 0.0f64;
                for (i, (o, n)) in offsets.iter().zip(&DOP).enumerate() {
                    let s = n[0] * x.x + n[1] * x.y + n[2] * x.z - o;
                    beyond = beyond.max(s * INV_NORMS[i]);
                }
                beyond
            }
            ShapeBound::Cylinder {
                radius,
                half_height,
            } => {
                let radial = ((x.x * x.x + x.y * x.y).sqrt() - radius).max(0.0);
                let axial = (x.z.abs() - half_height).max(0.0);
                (radial * radial + axial * axial).sqrt()
            }
            ShapeBound::Capsule {
                radius,
                half_length,
            } => {
                let along = x.z.clamp(-half_length, *half_length);
                (Vector3::new(x.x, x.y, x.z - along).norm() - radius).max(0.0)
            }
        }
    }
}

/// `1 / |DOP[i]|`, rounded down so a plane's distance is never overstated.
const INV_NORMS: [f64; 26] = {
    const A: f64 = 0.707_106_781_186_547_4; // 1/√2, rounded down
    const B: f64 = 0.577_350_269_189_625_7; // 1/√3, rounded down
    [
        1.0, 1.0, 1.0, 1.0, 1.0, 1.0, A, A, A, A, A, A, A, A, A, A, A, A, B, B, B, B, B, B, B, B,
    ]
};

/// A shape placed in the world, ready for [`PlacedShape::point_distance`].
#[derive(Clone, Copy, Debug)]
pub struct PlacedShape {
    /// `shape_from_world`'s rotation (the pose's transposed) and the pose's translation.
    rotation_t: Matrix3<f64>,
    translation: Vector3<f64>,
    bound: ShapeBound,
}

impl PlacedShape {
    /// `shape` placed at `pose` (world from shape).
    #[must_use]
    pub fn new(shape: &Convex, pose: &SE3) -> Self {
        PlacedShape {
            rotation_t: pose.rotation.transpose(),
            translation: pose.translation,
            bound: ShapeBound::new(shape),
        }
    }

    /// Moves the shape to `pose` (world from shape).
    pub fn set_pose(&mut self, pose: &SE3) {
        self.rotation_t = pose.rotation.transpose();
        self.translation = pose.translation;
    }

    /// The distance from world point `p` to the shape ([`ShapeBound::point_distance`]).
    #[must_use]
    pub fn point_distance(&self, p: &Vector3<f64>) -> f64 {
        self.bound
            .point_distance(&(self.rotation_t * (p - self.translation)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::gjk::{EpaWorkspace, WarmStart, signed_distance};
    use nalgebra::{Rotation3, Unit};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Against GJK's signed distance between each shape and a tiny sphere at random points
    /// around it, the shapes placed at random poses: equal to 1e-9 m where apart, 0 where
    /// the point is inside; a hull's box distance is never above the hull's distance.
    #[test]
    fn matches_gjk_on_primitives_and_bounds_hulls() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let hull = crate::collision::mesh::convex_hull_vertices(&[
            Vector3::new(0.1, 0.0, 0.0),
            Vector3::new(-0.05, 0.08, 0.01),
            Vector3::new(-0.04, -0.07, 0.03),
            Vector3::new(0.02, 0.01, 0.2),
            Vector3::new(0.0, 0.02, -0.1),
        ]);
        let shapes = [
            Convex::Box {
                half: Vector3::new(0.3, 0.05, 0.12),
            },
            Convex::Cylinder {
                radius: 0.04,
                half_height: 0.15,
            },
            Convex::Sphere { radius: 0.07 },
            Convex::Capsule {
                radius: 0.03,
                half_length: 0.2,
            },
            Convex::Hull {
                vertices: hull.vertices,
                neighbours: hull.neighbours,
            },
        ];
        let point = Convex::Sphere { radius: 0.0 };
        let (mut inside, mut apart) = (0, 0);
        for (k, shape) in shapes.iter().enumerate() {
            for _ in 0..400 {
                let axis = Unit::new_normalize(Vector3::new(
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                    rng.random_range(-1.0..1.0),
                ));
                let pose = SE3::new(
                    Rotation3::from_axis_angle(&axis, rng.random_range(-3.0..3.0)).into_inner(),
                    Vector3::new(
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                        rng.random_range(-1.0..1.0),
                    ),
                );
                // Within 1.5 times the shape's box: inside and near its surface.
                let (centre, half) = shape.local_aabb();
                let p = pose.act_point(
                    &(centre
                        + half.component_mul(&Vector3::new(
                            rng.random_range(-1.5..1.5),
                            rng.random_range(-1.5..1.5),
                            rng.random_range(-1.5..1.5),
                        ))),
                );
                let placed = PlacedShape::new(shape, &pose);
                let d = placed.point_distance(&p);
                let gjk = signed_distance(
                    shape,
                    &pose,
                    &point,
                    &SE3::from_translation(p),
                    &mut WarmStart::default(),
                    &mut EpaWorkspace::default(),
                )
                .distance;
                if k == 4 {
                    assert!(d <= gjk.max(0.0) + 1e-12, "hull: {d} above {gjk}");
                } else {
                    assert!((d - gjk.max(0.0)).abs() < 1e-9, "shape {k}: {d} vs {gjk}");
                }
                if gjk > 0.0 {
                    apart += 1;
                } else {
                    inside += 1;
                }
            }
        }
        assert!(
            inside > 100 && apart > 1000,
            "{inside} inside, {apart} apart"
        );
    }
}

//! Outlines of the placed geometry: world points whose convex hull holds each shape, the
//! robot's footprint on the ground (for the planner's polygon C-space) and the
//! projections the CLI draws.

use super::convex::Convex;
use super::geometry_data::GeometryData;
use super::geometry_model::GeometryModel;
use crate::multibody::{Data, Model, RootJoint};
use crate::spatial::SE3;
use nalgebra::{Rotation2, Vector2, Vector3};

/// Segments of the polygon that replaces a circle in [`outline_points`].
pub const CIRCLE_SEGMENTS: usize = 32;

/// World points whose convex hull contains the placed shape: a hull's vertices and a
/// box's corners (exact), a cylinder's, sphere's or capsule's circles as polygons of
/// [`CIRCLE_SEGMENTS`] sides *circumscribed* about them (so the hull contains the shape
/// and exceeds it by at most r·(1/cos(π/32) − 1) ≈ 0.0048·r). Appends to `out`.
pub fn outline_points(shape: &Convex, pose: &SE3, out: &mut Vec<Vector3<f64>>) {
    let n = CIRCLE_SEGMENTS;
    let grow = 1.0 / (std::f64::consts::PI / n as f64).cos();
    let circle = |centre: Vector3<f64>,
                  r: f64,
                  axis_a: Vector3<f64>,
                  axis_b: Vector3<f64>,
                  out: &mut Vec<Vector3<f64>>| {
        for k in 0..n {
            let t = 2.0 * std::f64::consts::PI * k as f64 / n as f64;
            out.push(pose.act_point(&(centre + (axis_a * t.cos() + axis_b * t.sin()) * r * grow)));
        }
    };
    let (x, y, z) = (Vector3::x(), Vector3::y(), Vector3::z());
    match shape {
        Convex::Hull { vertices, .. } => out.extend(vertices.iter().map(|v| pose.act_point(v))),
        Convex::Box { half } => {
            for k in 0..8 {
                let s = Vector3::new(
                    if k & 1 == 0 { -1.0 } else { 1.0 },
                    if k & 2 == 0 { -1.0 } else { 1.0 },
                    if k & 4 == 0 { -1.0 } else { 1.0 },
                );
                out.push(pose.act_point(&half.component_mul(&s)));
            }
        }
        Convex::Cylinder {
            radius,
            half_height,
        } => {
            circle(z * *half_height, *radius, x, y, out);
            circle(-z * *half_height, *radius, x, y, out);
        }
        Convex::Sphere { radius } | Convex::Capsule { radius, .. } => {
            let h = match shape {
                Convex::Capsule { half_length, .. } => *half_length,
                _ => 0.0,
            };
            // Three great circles (circumscribed twice: along their planes and across)
            // bound the ball by grow² · r.
            let r = radius * grow;
            for c in [z * h, -z * h] {
                circle(c, r, x, y, out);
                circle(c, r, y, z, out);
                circle(c, r, z, x, out);
            }
        }
    }
}

/// The robot's footprint in the posture of `gd` (after `update_geometry_placements`):
/// the convex hull, counter-clockwise in the world x–y plane, of every shape of every
/// link projected on the ground. It contains the projection of the geometry (round
/// shapes enter through circumscribed polygons, see [`outline_points`]). `points` is a
/// scratch buffer.
#[must_use]
pub fn footprint(
    gm: &GeometryModel,
    gd: &GeometryData,
    points: &mut Vec<Vector3<f64>>,
) -> Vec<Vector2<f64>> {
    points.clear();
    for (o, pose) in gm.objects.iter().zip(&gd.placements) {
        outline_points(&o.shape, pose, points);
    }
    hull_2d(points.iter().map(|p| Vector2::new(p.x, p.y)))
}

/// The ground pose `(x, y, yaw)` of a mobile base after forward kinematics: the root
/// joint's position in the world x–y plane and the heading of its x axis projected on
/// the ground. `None` for a fixed root (the footprint then stays in the world frame).
#[must_use]
pub fn base_ground_pose(model: &Model, data: &Data) -> Option<(Vector2<f64>, f64)> {
    if model.root == RootJoint::Fixed || model.njoints < 2 {
        return None;
    }
    let m = &data.world_from_joint[1];
    let r = &m.rotation;
    Some((
        Vector2::new(m.translation.x, m.translation.y),
        r[(1, 0)].atan2(r[(0, 0)]),
    ))
}

/// The footprint of [`footprint`] expressed in a planar frame on the ground with origin
/// `origin` and heading `yaw` (world x–y): with the base's ground pose
/// ([`base_ground_pose`]) it is the heading-aware footprint a planner moves with the
/// base, as `moma plan --footprint` takes it. Counter-clockwise.
#[must_use]
pub fn footprint_in(
    gm: &GeometryModel,
    gd: &GeometryData,
    origin: &Vector2<f64>,
    yaw: f64,
    points: &mut Vec<Vector3<f64>>,
) -> Vec<Vector2<f64>> {
    let to_frame = Rotation2::new(-yaw);
    footprint(gm, gd, points)
        .into_iter()
        .map(|p| to_frame * (p - origin))
        .collect()
}

/// The convex hull of planar points, counter-clockwise, without collinear points
/// (Andrew's monotone chain). Fewer than three distinct points come back as they are.
#[must_use]
pub fn hull_2d(points: impl Iterator<Item = Vector2<f64>>) -> Vec<Vector2<f64>> {
    let mut p: Vec<Vector2<f64>> = points.collect();
    p.sort_by(|a, b| a.x.total_cmp(&b.x).then(a.y.total_cmp(&b.y)));
    p.dedup();
    if p.len() < 3 {
        return p;
    }
    let turn = |o: &Vector2<f64>, a: &Vector2<f64>, b: &Vector2<f64>| (a - o).perp(&(b - o));
    let mut hull: Vec<Vector2<f64>> = Vec::with_capacity(2 * p.len());
    for pass in 0..2 {
        let start = hull.len();
        let iter: Box<dyn Iterator<Item = &Vector2<f64>>> = if pass == 0 {
            Box::new(p.iter())
        } else {
            Box::new(p.iter().rev())
        };
        for q in iter {
            while hull.len() >= start + 2
                && turn(&hull[hull.len() - 2], &hull[hull.len() - 1], q) <= 0.0
            {
                hull.pop();
            }
            hull.push(*q);
        }
        hull.pop();
    }
    hull
}

//! A plane between two convex shapes, a lower bound on their distance from one support
//! point of each: for a unit normal `n`, every point of `A` lies at most `h_A(n)` along
//! it and every point of `B` at least `−h_B(−n)`, so the shapes are at least
//! `−h_B(−n) − h_A(n)` apart (`h` the support value, margins included). Any normal gives
//! a true bound; the one GJK left the pair with at the last query (its separating
//! direction) gives a tight one while the pair has moved little since, so a check that
//! needs "farther than a bound" can try it before a GJK run: one support map per shape
//! against GJK's two or more.

use super::convex::Convex;
use crate::spatial::SE3;
use nalgebra::Vector3;

/// The support value `max over the placed shape of n·x` (margin included); `hint` is the
/// hull vertex to start the climb from ([`Convex::core_support`]).
pub fn support_value(shape: &Convex, pose: &SE3, n: &Vector3<f64>, hint: &mut usize) -> f64 {
    let local = pose.rotation.tr_mul(n);
    let p = pose.act_point(&shape.core_support(&local, hint));
    n.dot(&p) + shape.margin() * n.norm()
}

/// The gap between shape `a` at `pose_a` and shape `b` at `pose_b` along the plane normal
/// `n` (world, pointing from `a` towards `b`, any length but zero): a lower bound on
/// their distance when positive (module docs), `−∞` for a zero or non-finite normal.
/// `hints` are the hull vertices the two support climbs start from.
pub fn plane_gap(
    a: &Convex,
    pose_a: &SE3,
    b: &Convex,
    pose_b: &SE3,
    n: &Vector3<f64>,
    hints: &mut (usize, usize),
) -> f64 {
    let len = n.norm();
    if !(len > 0.0 && len.is_finite()) {
        return f64::NEG_INFINITY;
    }
    let n = n / len;
    let reach_a = support_value(a, pose_a, &n, &mut hints.0);
    let reach_b = support_value(b, pose_b, &-n, &mut hints.1);
    // Round-off of the unit normal and of the dot products, well above 1e-16 per metre.
    -reach_b - reach_a - 1e-12
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collision::gjk::{EpaWorkspace, WarmStart, signed_distance};
    use nalgebra::{Rotation3, Unit};
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random_pose(rng: &mut ChaCha8Rng, spread: f64) -> SE3 {
        let axis = Unit::new_normalize(Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ));
        SE3::new(
            Rotation3::from_axis_angle(&axis, rng.random_range(-3.0..3.0)).into_inner(),
            Vector3::new(
                rng.random_range(-spread..spread),
                rng.random_range(-spread..spread),
                rng.random_range(-spread..spread),
            ),
        )
    }

    /// Random hulls, boxes, cylinders, spheres and capsules at random poses, near and
    /// overlapping, along random normals and along GJK's own: the plane's gap is never
    /// above GJK's signed distance (to 1e-12 m), and along GJK's normal it is the
    /// distance (to 1e-5 m) for shapes apart.
    #[test]
    fn never_above_the_distance_and_tight_along_gjks_normal() {
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        let points: Vec<Vector3<f64>> = (0..40)
            .map(|_| {
                Vector3::new(
                    rng.random_range(-0.3..0.3),
                    rng.random_range(-0.1..0.1),
                    rng.random_range(-0.05..0.05),
                )
            })
            .collect();
        let hull = crate::collision::mesh::convex_hull_vertices(&points);
        let shapes = [
            Convex::Hull {
                vertices: hull.vertices,
                neighbours: hull.neighbours,
            },
            Convex::Box {
                half: Vector3::new(0.2, 0.1, 0.3),
            },
            Convex::Cylinder {
                radius: 0.1,
                half_height: 0.2,
            },
            Convex::Sphere { radius: 0.15 },
            Convex::Capsule {
                radius: 0.05,
                half_length: 0.2,
            },
        ];
        let (mut apart, mut tight) = (0, 0);
        for trial in 0..4000 {
            let a = &shapes[trial % shapes.len()];
            let b = &shapes[(trial / shapes.len()) % shapes.len()];
            let (pa, pb) = (random_pose(&mut rng, 0.6), random_pose(&mut rng, 0.6));
            let exact = signed_distance(
                a,
                &pa,
                b,
                &pb,
                &mut WarmStart::default(),
                &mut EpaWorkspace::default(),
            );
            let mut hints = (rng.random_range(0..4), rng.random_range(0..4));
            let n = Vector3::new(
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
                rng.random_range(-1.0..1.0),
            );
            let gap = plane_gap(a, &pa, b, &pb, &n, &mut hints);
            assert!(gap <= exact.distance + 1e-12, "{gap} > {}", exact.distance);
            if exact.distance > 1e-6 {
                apart += 1;
                let along = plane_gap(a, &pa, b, &pb, &exact.normal, &mut hints);
                assert!(along <= exact.distance + 1e-12);
                // A cylinder's GJK normal is exact only to about the square root of
                // GJK's duality gap (its support map is curved): 1e-5 m, not 1e-12.
                assert!(
                    (along - exact.distance).abs() < 1e-5,
                    "{along} against {}",
                    exact.distance
                );
                tight += 1;
            }
        }
        assert!(apart > 1000 && tight == apart, "{apart} pairs apart");
        let mut hints = (0, 0);
        let zero = plane_gap(
            &shapes[0],
            &SE3::identity(),
            &shapes[1],
            &SE3::identity(),
            &Vector3::zeros(),
            &mut hints,
        );
        assert_eq!(zero, f64::NEG_INFINITY);
    }
}

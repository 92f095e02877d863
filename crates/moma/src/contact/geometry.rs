//! Where a wheel disk and a caster sphere touch the ground plane z = 0.

use nalgebra::Vector3;

/// The lowest point of a disk (a wheel) of radius `radius` centred at `centre` with unit
/// axle direction `axis` (world): `centre − r w/|w|` with `w = ẑ − (ẑ·a) a` the upward
/// direction in the disk's plane. A disk lying flat (`|w|` ≈ 0) touches with its centre.
#[inline]
#[must_use]
pub fn disk_lowest_point(centre: &Vector3<f64>, axis: &Vector3<f64>, radius: f64) -> Vector3<f64> {
    let w = Vector3::z() - axis * axis.z;
    let n = w.norm();
    if n < 1e-9 {
        *centre
    } else {
        centre - w * (radius / n)
    }
}

/// The lowest point of a sphere of radius `radius` centred at `centre`.
#[inline]
#[must_use]
pub fn sphere_lowest_point(centre: &Vector3<f64>, radius: f64) -> Vector3<f64> {
    centre - Vector3::z() * radius
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_disk_point_is_the_lowest_of_the_wheel_circle() {
        let centre = Vector3::new(0.3, -0.2, 0.1);
        let r = 0.08;
        for axis in [
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(0.3, 0.9, 0.2).normalize(),
            Vector3::new(-0.5, 0.1, -0.7).normalize(),
        ] {
            let p = disk_lowest_point(&centre, &axis, r);
            assert!(((p - centre).norm() - r).abs() < 1e-12, "on the circle");
            assert!((p - centre).dot(&axis).abs() < 1e-12, "in the disk's plane");
            // Sample the circle: nothing lower.
            let e1 = axis.cross(&Vector3::x()).normalize();
            let e2 = axis.cross(&e1);
            for k in 0..3600 {
                let a = k as f64 * std::f64::consts::TAU / 3600.0;
                let q = centre + (e1 * a.cos() + e2 * a.sin()) * r;
                assert!(q.z >= p.z - 1e-12, "axis {axis:?}: {} below {}", q.z, p.z);
            }
        }
        // A disk lying flat touches with its centre.
        let flat = disk_lowest_point(&centre, &Vector3::z(), r);
        assert_eq!(flat, centre);
        assert_eq!(sphere_lowest_point(&centre, r).z, centre.z - r);
    }
}

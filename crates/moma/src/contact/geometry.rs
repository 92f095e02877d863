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

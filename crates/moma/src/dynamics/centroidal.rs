//! Centre of mass, energies and centroidal momentum.

use crate::kinematics::{assert_nv, assert_sizes, forward_kinematics};
use crate::multibody::{Data, Model};
use crate::spatial::{Force, Inertia};
use nalgebra::{DVector, Matrix6xX, Vector3};

/// Centre of mass of the moving bodies in the world frame (m), stored in `data.com`.
/// Runs forward kinematics. Bodies fixed to the world are excluded (as Pinocchio); a
/// massless model gives the origin.
///
/// # Panics
/// On wrong vector lengths.
#[doc(alias = "com")]
pub fn center_of_mass(model: &Model, data: &mut Data, q: &DVector<f64>) -> Vector3<f64> {
    forward_kinematics(model, data, q);
    let mut m = 0.0;
    let mut h = Vector3::zeros();
    for i in 1..model.njoints {
        let ii = &model.inertias[i];
        let oi = &data.world_from_joint[i];
        m += ii.mass();
        h += oi.rotation * ii.first_moment() + oi.translation * ii.mass();
    }
    data.com = if m > 0.0 { h / m } else { Vector3::zeros() };
    data.com
}

/// Kinetic energy T = ½ vᵀ H(q) v (J), stored in `data.kinetic_energy`. Runs forward
/// kinematics with velocities.
///
/// # Panics
/// On wrong vector lengths.
#[doc(alias = "T")]
pub fn kinetic_energy(model: &Model, data: &mut Data, q: &DVector<f64>, v: &DVector<f64>) -> f64 {
    assert_sizes(model, data, q);
    assert_nv(model, v, "v");
    crate::kinematics::forward_kinematics_second_order_impl(
        model,
        data,
        q.as_slice(),
        v.as_slice(),
        None,
    );
    let mut t = 0.0;
    for i in 1..model.njoints {
        t += model.inertias[i].kinetic_energy(&data.v[i]);
    }
    data.kinetic_energy = t;
    t
}

/// Potential energy V = −Σ mᵢ g·cᵢ (J) of the moving bodies in the gravity field
/// `model.gravity`, stored in `data.potential_energy`. Runs forward kinematics.
///
/// # Panics
/// On wrong vector lengths.
#[doc(alias = "V")]
pub fn potential_energy(model: &Model, data: &mut Data, q: &DVector<f64>) -> f64 {
    forward_kinematics(model, data, q);
    let mut e = 0.0;
    for i in 1..model.njoints {
        let ii = &model.inertias[i];
        let oi = &data.world_from_joint[i];
        let h = oi.rotation * ii.first_moment() + oi.translation * ii.mass();
        e -= model.gravity.dot(&h);
    }
    data.potential_energy = e;
    e
}

/// Centroidal momentum matrix A_g (6 × nv): `A_g·v` is the momentum of the moving bodies,
/// `[linear; angular]` with the angular part about the centre of mass, world axes (as
/// Pinocchio's `ccrba`). Stored in `data.centroidal_momentum_matrix`; also fills
/// `data.com` and world-frame `data.composite_inertias` (entry 0: the whole robot).
///
/// # Panics
/// On wrong vector lengths.
#[doc(alias = "Ag")]
#[doc(alias = "A_g")]
#[doc(alias = "centroidal_map")]
pub fn centroidal_momentum_matrix<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &DVector<f64>,
) -> &'d Matrix6xX<f64> {
    forward_kinematics(model, data, q);
    let n = model.njoints;
    data.composite_inertias[0] = Inertia::zero();
    for i in 1..n {
        data.composite_inertias[i] = model.inertias[i].transformed(&data.world_from_joint[i]);
    }
    for i in (1..n).rev() {
        let p = model.parents[i].0;
        let yi = data.composite_inertias[i];
        data.composite_inertias[p] += yi;
    }
    let total = data.composite_inertias[0];
    let com = total.com();
    data.com = com;
    for i in 1..n {
        let iv = model.idx_v[i];
        let yi = data.composite_inertias[i];
        for k in 0..model.nvs[i] {
            let s = data.world_from_joint[i].act_motion(&data.s[iv + k]);
            let f = yi.mul_motion(&s);
            let ang = f.angular - com.cross(&f.linear);
            let mut c = data.centroidal_momentum_matrix.column_mut(iv + k);
            c[0] = f.linear.x;
            c[1] = f.linear.y;
            c[2] = f.linear.z;
            c[3] = ang.x;
            c[4] = ang.y;
            c[5] = ang.z;
        }
    }
    &data.centroidal_momentum_matrix
}

/// Centroidal momentum h_g = A_g(q)·v (`[linear; angular about the CoM]`, world axes),
/// stored in `data.centroidal_momentum` (A_g in `data.centroidal_momentum_matrix`).
///
/// # Panics
/// On wrong vector lengths.
#[doc(alias = "hg")]
#[doc(alias = "h_g")]
pub fn centroidal_momentum(
    model: &Model,
    data: &mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
) -> Force {
    assert_nv(model, v, "v");
    centroidal_momentum_matrix(model, data, q);
    let ag = &data.centroidal_momentum_matrix;
    let mut h = [0.0; 6];
    for (j, col) in ag.column_iter().enumerate() {
        for r in 0..6 {
            h[r] += col[r] * v[j];
        }
    }
    let f = Force::new(
        Vector3::new(h[0], h[1], h[2]),
        Vector3::new(h[3], h[4], h[5]),
    );
    data.centroidal_momentum = f;
    f
}

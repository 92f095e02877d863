//! Computed torque on the reduced model of a wheeled robot: the one map from a desired
//! reduced acceleration `a` (or a reduced generalised force `Qr`) to the actuator inputs
//! `u = [τ_L, τ_R, τ_arm…]`, used by every closed loop on a wheeled URDF robot (the
//! platform laws' inner loop, the coordinated law, operational-space control and the
//! mission).
//!
//! `Qr = Mr a + (cr + Gr)` with `Mr`, `cr + Gr` the reduced dynamics of the state under
//! zero input; then `N_Cᵀ S u = Qr`. `N_Cᵀ S` is block diagonal: the identity on the arm
//! and a 2 × 2 block on the wheels that does not depend on the configuration for a
//! differential drive (the heading rotates the wheel forces and the admissible
//! directions alike), so it is inverted once, at construction. Each input is then clipped
//! at its own bound.

use nalgebra::{DMatrix, DVector, Matrix2, Vector2};

use crate::error::{Error, Result};
use crate::mobile::{ReducedDynamics, WheeledModel, actuation_matrix, admissible_velocity_basis};

/// The wheel block `B` of `N_Cᵀ S` at `q` (`Qr[0..2] = B u[0..2]`).
#[must_use]
pub fn wheel_block(wm: &WheeledModel, q: &DVector<f64>) -> Matrix2<f64> {
    let mut basis = DMatrix::zeros(wm.nv(), wm.nr());
    let mut s = DMatrix::zeros(wm.nv(), wm.nu());
    admissible_velocity_basis(wm, q, &mut basis);
    actuation_matrix(wm, q, &mut s);
    let mut b = Matrix2::zeros();
    for a in 0..2 {
        for j in 0..2 {
            let mut acc = 0.0;
            for i in 0..wm.nv() {
                acc += basis[(i, a)] * s[(i, j)];
            }
            b[(a, j)] = acc;
        }
    }
    b
}

/// The computed-torque map of one wheeled robot with its input bounds.
#[derive(Clone, Debug)]
pub struct ComputedTorque {
    /// `B⁻¹`, the inverse of the wheel block of `N_Cᵀ S`.
    wheel_map_inv: Matrix2<f64>,
    /// `|u_i| ≤ bounds[i]` (infinite: unbounded).
    bounds: Vec<f64>,
}

impl ComputedTorque {
    /// The map of `wm` (its wheel block taken at the neutral configuration) with one bound
    /// per input (`f64::INFINITY` for none).
    ///
    /// # Errors
    /// [`Error::Singular`] when the wheel block is singular (a zero wheel radius or
    /// track); [`Error::InvalidInput`] when `bounds` does not hold one bound per input or
    /// a bound is not positive.
    pub fn new(wm: &WheeledModel, bounds: Vec<f64>) -> Result<Self> {
        crate::error::ensure_len("input bounds", wm.nu(), bounds.len())?;
        if let Some(b) = bounds.iter().find(|b| !(**b > 0.0)) {
            return Err(Error::invalid(
                "input bounds",
                format!("must be positive, got {b}"),
            ));
        }
        let q = crate::multibody::neutral(&wm.model);
        let b = wheel_block(wm, &q);
        let wheel_map_inv = b.try_inverse().ok_or_else(|| Error::Singular {
            what: "actuator map N_Cᵀ S (wheel block)".into(),
            detail: Some(format!("determinant {:e}", b.determinant())),
        })?;
        Ok(Self {
            wheel_map_inv,
            bounds,
        })
    }

    /// The bounds of the inputs.
    #[must_use]
    pub fn bounds(&self) -> &[f64] {
        &self.bounds
    }

    /// Writes the inputs `u` that give the reduced acceleration `a` on the reduced
    /// dynamics `reduced` (evaluated under zero input: `velocity_terms` = cr + Gr),
    /// clipped at the bounds; `true` if any input was clipped.
    ///
    /// # Panics
    /// On lengths that differ from the model's.
    pub fn inputs(&self, reduced: &ReducedDynamics, a: &DVector<f64>, u: &mut [f64]) -> bool {
        let (mr, bias) = (&reduced.mass_matrix, &reduced.velocity_terms);
        assert_eq!(a.len(), mr.nrows(), "desired acceleration length");
        self.map(
            |i| bias[i] + (0..a.len()).map(|j| mr[(i, j)] * a[j]).sum::<f64>(),
            u,
        )
    }

    /// Writes the inputs `u` with `N_Cᵀ S u = tau_r` (a reduced generalised force),
    /// clipped at the bounds; `true` if any input was clipped.
    ///
    /// # Panics
    /// On lengths that differ from the model's.
    pub fn inputs_from_reduced_force(&self, tau_r: &[f64], u: &mut [f64]) -> bool {
        assert_eq!(tau_r.len(), u.len(), "reduced force length");
        self.map(|i| tau_r[i], u)
    }

    fn map(&self, qr: impl Fn(usize) -> f64, u: &mut [f64]) -> bool {
        assert_eq!(u.len(), self.bounds.len(), "input length");
        let wheels = self.wheel_map_inv * Vector2::new(qr(0), qr(1));
        u[0] = wheels[0];
        u[1] = wheels[1];
        for (i, ui) in u.iter_mut().enumerate().skip(2) {
            *ui = qr(i);
        }
        let mut clipped = false;
        for (ui, &bound) in u.iter_mut().zip(&self.bounds) {
            if ui.abs() > bound {
                *ui = bound.copysign(*ui);
                clipped = true;
            }
        }
        clipped
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::urdf::model_from_urdf_file;
    use crate::mobile::wheeled::{
        WheeledBase, reduced_forward_dynamics_crba, reduced_forward_dynamics_under_inputs,
    };
    use crate::mobile::{DiffDrive, WheeledData};
    use crate::multibody::RootJoint;

    fn robot(tracked: bool, d: f64) -> WheeledModel {
        let urdf = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../scenarios/robots/mobile_manipulator.urdf"
        );
        let model = model_from_urdf_file(urdf, RootJoint::Planar).unwrap();
        let mut base = WheeledBase::new(DiffDrive::new(0.1, 0.22, d).unwrap());
        if tracked {
            base.wheel_joints = Some(["left_wheel_joint".into(), "right_wheel_joint".into()]);
        }
        WheeledModel::new(model, base).unwrap()
    }

    /// The wheel block is taken once: it must not depend on the configuration.
    #[test]
    fn the_wheel_block_does_not_depend_on_the_configuration() {
        for (tracked, d) in [(true, 0.0), (false, 0.0), (false, 0.15), (true, 0.15)] {
            let wm = robot(tracked, d);
            let b0 = wheel_block(&wm, &crate::multibody::neutral(&wm.model));
            assert!(b0.determinant().abs() > 1e-6);
            for k in 0..5 {
                let q = DVector::from_fn(wm.model.nq, |i, _| {
                    (1.7 * (i + 1) as f64 + 0.9 * k as f64).sin() * 3.0
                });
                let b = wheel_block(&wm, &q);
                assert!((b - b0).amax() < 1e-12, "{tracked} {d}: {b} vs {b0}");
            }
        }
    }

    /// The inputs reproduce the desired reduced acceleration through the plant's own
    /// forward dynamics, and a bound clips.
    #[test]
    fn inputs_give_the_desired_acceleration_on_the_plant() {
        let wm = robot(true, 0.0);
        let (nq, nr, nu) = (wm.model.nq, wm.nr(), wm.nu());
        let q = DVector::from_fn(nq, |i, _| 0.3 * (i as f64 + 0.5).cos());
        let v = DVector::from_fn(nr, |i, _| 0.2 * (i as f64 + 1.0).sin());
        let a = DVector::from_fn(nr, |i, _| 0.5 - 0.1 * i as f64);
        let mut wd = WheeledData::new(&wm);
        reduced_forward_dynamics_crba(&wm, &mut wd, &q, &v, &vec![0.0; nu]).unwrap();
        let ct = ComputedTorque::new(&wm, vec![f64::INFINITY; nu]).unwrap();
        let mut u = vec![0.0; nu];
        assert!(!ct.inputs(&wd.reduced, &a, &mut u));
        let mut plant = WheeledData::new(&wm);
        let vdot = reduced_forward_dynamics_crba(&wm, &mut plant, &q, &v, &u)
            .unwrap()
            .clone();
        assert!((&vdot - &a).amax() < 1e-9, "{vdot} vs {a}");
        // the controller's evaluation under the torques is the plant's, to the bit
        reduced_forward_dynamics_under_inputs(&wm, &mut wd, &q, &u).unwrap();
        assert_eq!(wd.reduced.vdot, vdot);
        assert_eq!(wd.reduced.qddot, plant.reduced.qddot);

        let peak = u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let bounded = ComputedTorque::new(&wm, vec![0.5 * peak; nu]).unwrap();
        let mut uc = vec![0.0; nu];
        assert!(bounded.inputs(&wd.reduced, &a, &mut uc));
        assert!(uc.iter().all(|x| x.abs() <= 0.5 * peak));
        assert!(ComputedTorque::new(&wm, vec![0.0; nu]).is_err());
        assert!(ComputedTorque::new(&wm, vec![1.0; nu + 1]).is_err());
    }
}

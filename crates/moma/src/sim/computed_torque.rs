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
        if let Some(b) = bounds.iter().find(|b| b.is_nan() || **b <= 0.0) {
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

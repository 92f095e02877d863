//! [`M5TaskController`]: the chapter's task-space laws on model m5
//! ([`crate::control::task`]): PD+, task-space computed torque and the decoupled control.

use crate::closed_form::m5_mobile_manipulator::MobileManipulator;
use crate::control::task::{Coupling, computed_torque, decoupled, pd_plus};
use crate::error::{Error, Result};
use crate::sim::closed_loop::{FeedbackLaw, Observation, SaturationFlags, clip_inputs};
use nalgebra::{SMatrix, SVector};

/// The task-space law of [`M5TaskController`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TaskLaw {
    /// PD+ (chapter 5.122 corrected).
    PdPlus,
    /// Task-space computed torque.
    ComputedTorque,
    /// The chapter's decoupled control (platform block `[x_B, y_B]`, arm block the
    /// other three coordinates) with the given treatment of the cross terms.
    Decoupled(Coupling),
}

/// The chapter's task-space laws on m5, tracking `x_d(t) = x_ref + amp ⊙ sin(ω ⊙ t)` in
/// the task coordinates `x = [x_B, y_B, x_E − x_B, y_E − y_B, z_E]`.
///
/// V: PD+ reports `W = ½ ėᵀ Hx ė + ½ eᵀ Kp e` with `Ẇ = −ėᵀ Kd ė`; the computed-torque
/// and decoupled laws report `V = ½ |ė|² + ½ eᵀ Kp e` with the rate `−ėᵀ Kd ė` of the
/// linear error equation `ë + Kd ė + Kp e = 0` they aim at (exact for computed torque
/// and compensated decoupling; for the naive and feed-forward variants the gap between V
/// and `V₀ + ∫ V̇` shows the neglected coupling).
#[derive(Clone, Debug)]
pub struct M5TaskController {
    model: MobileManipulator,
    /// The law.
    pub law: TaskLaw,
    /// `x_ref`.
    pub x_ref: SVector<f64, 5>,
    /// Amplitudes.
    pub amp: SVector<f64, 5>,
    /// Angular frequencies (rad/s).
    pub omega: SVector<f64, 5>,
    /// Kp (diagonal).
    pub kp: SMatrix<f64, 5, 5>,
    /// Kd (diagonal; K_v of computed torque).
    pub kd: SMatrix<f64, 5, 5>,
    max_torque: Option<f64>,
}

impl M5TaskController {
    /// Diagonal gains `kp`, `kd` (each > 0) and the sinusoidal reference.
    ///
    /// # Errors
    /// Non-positive or non-finite gains, non-finite reference values, a bad torque limit.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        model: MobileManipulator,
        law: TaskLaw,
        x_ref: [f64; 5],
        amp: [f64; 5],
        omega: [f64; 5],
        kp: [f64; 5],
        kd: [f64; 5],
        max_torque: Option<f64>,
    ) -> Result<Self> {
        crate::error::ensure_finite("reference.x_ref", &x_ref)?;
        crate::error::ensure_finite("reference.amplitude", &amp)?;
        crate::error::ensure_finite("reference.omega", &omega)?;
        for (n, g) in [("controller.kp", kp), ("controller.kd", kd)] {
            for (i, &x) in g.iter().enumerate() {
                crate::error::ensure_positive(&format!("{n}[{i}]"), x)?;
            }
        }
        if let Some(m) = max_torque {
            crate::error::ensure_positive("controller.max_torque", m)?;
        }
        Ok(Self {
            model,
            law,
            x_ref: SVector::from(x_ref),
            amp: SVector::from(amp),
            omega: SVector::from(omega),
            kp: SMatrix::from_diagonal(&SVector::from(kp)),
            kd: SMatrix::from_diagonal(&SVector::from(kd)),
            max_torque,
        })
    }

    /// `(x_d, ẋ_d, ẍ_d)` at time t.
    #[must_use]
    pub fn desired(&self, t: f64) -> (SVector<f64, 5>, SVector<f64, 5>, SVector<f64, 5>) {
        let s = self.omega.map(|w| (w * t).sin());
        let c = self.omega.map(|w| (w * t).cos());
        let aw = self.amp.component_mul(&self.omega);
        (
            self.x_ref + self.amp.component_mul(&s),
            aw.component_mul(&c),
            -aw.component_mul(&self.omega).component_mul(&s),
        )
    }

    fn state(q: &[f64], v: &[f64]) -> (SVector<f64, 6>, SVector<f64, 5>) {
        (SVector::from_column_slice(q), SVector::from_column_slice(v))
    }
}

impl FeedbackLaw for M5TaskController {
    fn nu(&self) -> usize {
        5
    }

    fn error_names(&self) -> Vec<String> {
        ["e_xB [m]", "e_yB [m]", "e_dxE [m]", "e_dyE [m]", "e_zE [m]"]
            .iter()
            .map(|s| (*s).to_string())
            .collect()
    }

    fn has_lyapunov(&self) -> bool {
        true
    }

    fn control(&mut self, t: f64, q: &[f64], v: &[f64], u: &mut [f64]) -> Result<SaturationFlags> {
        let (q, v) = Self::state(q, v);
        let tt = self.model.task_terms(&q, &v)?;
        let (xd, vd, ad) = self.desired(t);
        let f = match self.law {
            TaskLaw::PdPlus => {
                pd_plus(
                    &tt.hx,
                    &tt.bv,
                    &tt.bg,
                    &(tt.x - xd),
                    &(tt.xdot - vd),
                    &vd,
                    &ad,
                    &self.kp,
                    &self.kd,
                )
                .0
            }
            TaskLaw::ComputedTorque => computed_torque(
                &tt.hx,
                &(tt.bv * tt.xdot),
                &tt.bg,
                &(xd - tt.x),
                &(vd - tt.xdot),
                &ad,
                &self.kp,
                &self.kd,
            ),
            TaskLaw::Decoupled(c) => decoupled::<5, 2>(
                &tt.hx,
                &tt.bv,
                &tt.bg,
                &tt.xdot,
                &(xd - tt.x),
                &(vd - tt.xdot),
                &ad,
                &self.kp,
                &self.kd,
                c,
            ),
        };
        let sol = tt
            .actuation
            .lu()
            .solve(&(tt.a.transpose() * f))
            .ok_or_else(|| Error::Singular {
                what: "actuator map N_Cᵀ S".into(),
                detail: None,
            })?;
        u.copy_from_slice(sol.as_slice());
        let torque = self.max_torque.is_some_and(|m| clip_inputs(u, m));
        Ok(SaturationFlags {
            speed: false,
            torque,
        })
    }

    fn observe(&mut self, t: f64, q: &[f64], v: &[f64], e: &mut [f64]) -> Result<Observation> {
        let (q, v) = Self::state(q, v);
        let tt = self.model.task_terms(&q, &v)?;
        let (xd, vd, _) = self.desired(t);
        let err = tt.x - xd;
        let ed = tt.xdot - vd;
        e.copy_from_slice(err.as_slice());
        let pot = 0.5 * err.dot(&(self.kp * err));
        let kin = match self.law {
            TaskLaw::PdPlus => 0.5 * ed.dot(&(tt.hx * ed)),
            _ => 0.5 * ed.dot(&ed),
        };
        Ok(Observation {
            lyapunov: Some(kin + pot),
            lyapunov_rate: Some(-ed.dot(&(self.kd * ed))),
        })
    }
}

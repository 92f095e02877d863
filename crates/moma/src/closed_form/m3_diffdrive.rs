//! m3 — differential-drive wheel-rate kinematics, the whole-body Jacobian of the capstan
//! arm and its manipulability (chapter 5.3, 5.3.1; eqs 5.20–5.39).
//!
//! `q = [x, y, φ, φ1, θ1, θ2]`: platform CM, heading, capstan angle relative to the
//! platform, shoulder pitch from the upward vertical, elbow (link 2 at `θ12 = θ1 − θ2`
//! from the vertical). Input rates `v = [θ̇_L, θ̇_R, φ̇1, θ̇1, θ̇2]`. The capstan axis and
//! shoulder B is `L` ahead of the CM at height 0; task vector `X = [x_B, y_B, x_E, y_E, z_E]`.
//!
//! The whole-body Jacobian `J = ∂X/∂q · N_C` includes the platform-yaw term `ω ẑ × r_BE`
//! that the printed (5.30)–(5.31) omit; the printed version is returned separately
//! ([`DiffDriveOutputs::J_chapter_5_31`]) for contrast.
//! `det J = r_w² L1 L2 (d+L) ρ sin θ2 / (2b)`: J is singular for `d + L = 0`, `ρ = 0` or
//! `sin θ2 = 0`.

use super::ad::{Real, seed_all};
use super::{Manipulability, check_finite, finite, manipulability, positive, ser, to_dmatrix};
use crate::error::{Error, Result};
use crate::ode::{Dop853, OdeSystem};
use nalgebra::{Matrix3, SMatrix, SVector};
use serde::{Deserialize, Serialize};

/// Configuration `q = [x, y, φ, φ1, θ1, θ2]` of this kinematic model (its inputs are the
/// rates `v = [θ̇_L, θ̇_R, φ̇1, θ̇1, θ̇2]`).
pub type Configuration = SVector<f64, 6>;

/// Parameters of m3 (SI units).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[allow(non_snake_case)]
#[serde(deny_unknown_fields)]
pub struct DiffDriveKinematicsParams {
    /// Wheel radius.
    pub r_w: f64,
    /// Half track (wheels 2b apart).
    pub b: f64,
    /// CM ahead of the axle midpoint.
    pub d: f64,
    /// Capstan axis B ahead of the CM.
    pub L: f64,
    /// Link-1 length.
    pub L1: f64,
    /// Link-2 length.
    pub L2: f64,
}

impl DiffDriveKinematicsParams {
    /// Checks signs and finiteness.
    pub fn validate(&self) -> Result<()> {
        positive("r_w", self.r_w)?;
        positive("b", self.b)?;
        finite("d", self.d)?;
        finite("L", self.L)?;
        positive("L1", self.L1)?;
        positive("L2", self.L2)
    }
}

/// The m3 kinematic model.
#[derive(Clone, Debug)]
pub struct DiffDriveKinematics {
    /// Parameters.
    pub params: DiffDriveKinematicsParams,
}

/// Every output of m3 at `(q, v)` (names as in the reference vectors).
#[derive(Clone, Debug, Serialize)]
#[allow(non_snake_case)]
pub struct DiffDriveOutputs {
    /// `N_C = blockdiag(N11(φ) W, I3)` (6×5), `q̇ = N_C v`.
    #[serde(serialize_with = "ser::mat")]
    pub N_C: SMatrix<f64, 6, 5>,
    /// q̇.
    #[serde(serialize_with = "ser::vec")]
    pub qdot: SVector<f64, 6>,
    /// Task vector `X = [x_B, y_B, x_E, y_E, z_E]`.
    #[serde(serialize_with = "ser::vec")]
    pub X: SVector<f64, 5>,
    /// Platform block `J_P` (2×2): velocity of B from the wheel rates.
    #[serde(serialize_with = "ser::mat")]
    pub J_P: SMatrix<f64, 2, 2>,
    /// Whole-body Jacobian `J` (5×5).
    #[serde(serialize_with = "ser::mat")]
    pub J: SMatrix<f64, 5, 5>,
    /// `Ẋ = J v`.
    #[serde(serialize_with = "ser::vec")]
    pub Xdot: SVector<f64, 5>,
    /// det J.
    pub det_J: f64,
    /// The printed (5.31) `[[J_P, 0], [J_P; 0, T_IB J_mV]]` (not the correct Jacobian).
    #[serde(serialize_with = "ser::mat")]
    pub J_chapter_5_31: SMatrix<f64, 5, 5>,
    /// Arm Jacobian in platform axes w.r.t. `[φ1, θ1, θ2]`.
    #[serde(serialize_with = "ser::mat")]
    pub J_mV: SMatrix<f64, 3, 3>,
    /// Measures of J (5×5).
    pub manipulability_J: Manipulability,
    /// Measures of rows 3–5 of J (3×5).
    pub manipulability_J_endeffector: Manipulability,
    /// Measures of J_mV (3×3).
    pub manipulability_J_mV: Manipulability,
}

impl DiffDriveKinematics {
    /// Validates the parameters.
    pub fn new(params: DiffDriveKinematicsParams) -> Result<Self> {
        params.validate()?;
        Ok(DiffDriveKinematics { params })
    }

    /// The task vector `X(q)`, generic for differentiation.
    pub fn task_generic<T: Real>(&self, q: &[T; 6]) -> [T; 5] {
        let p = &self.params;
        let (phi, phi1, th1, th2) = (q[2], q[3], q[4], q[5]);
        let th12 = th1 - th2;
        let phit = phi + phi1;
        let rho = th1.sin() * p.L1 + th12.sin() * p.L2;
        let eta = th1.cos() * p.L1 + th12.cos() * p.L2;
        let xb = q[0] + phi.cos() * p.L;
        let yb = q[1] + phi.sin() * p.L;
        [xb, yb, xb + rho * phit.cos(), yb + rho * phit.sin(), eta]
    }

    /// `N_C(q)` (6×5): wheel-rate kinematics of the CM and identity on the arm rates.
    #[doc(alias = "N_C")]
    pub fn velocity_basis(&self, q: &SVector<f64, 6>) -> SMatrix<f64, 6, 5> {
        let p = &self.params;
        let (s, c) = q[2].sin_cos();
        let (k, kd) = (p.r_w / 2.0, p.r_w * p.d / (2.0 * p.b));
        let mut n = SMatrix::<f64, 6, 5>::zeros();
        n[(0, 0)] = c * k + s * kd;
        n[(0, 1)] = c * k - s * kd;
        n[(1, 0)] = s * k - c * kd;
        n[(1, 1)] = s * k + c * kd;
        n[(2, 0)] = -p.r_w / (2.0 * p.b);
        n[(2, 1)] = p.r_w / (2.0 * p.b);
        n[(3, 2)] = 1.0;
        n[(4, 3)] = 1.0;
        n[(5, 4)] = 1.0;
        n
    }

    /// Whole-body Jacobian `J = ∂X/∂q · N_C` (5×5).
    pub fn jacobian(&self, q: &SVector<f64, 6>) -> SMatrix<f64, 5, 5> {
        let qa: [f64; 6] = q.as_slice().try_into().expect("length 6");
        let x = self.task_generic(&seed_all(&qa));
        let dx = SMatrix::<f64, 5, 6>::from_fn(|i, j| x[i].du[j]);
        dx * self.velocity_basis(q)
    }

    /// `J_mV = ∂(E − B in platform axes)/∂[φ1, θ1, θ2]`.
    pub fn arm_jacobian_platform(&self, q: &SVector<f64, 6>) -> Matrix3<f64> {
        let p = &self.params;
        let (phi1, th1, th2) = (q[3], q[4], q[5]);
        let th12 = th1 - th2;
        let rho = p.L1 * th1.sin() + p.L2 * th12.sin();
        let eta = p.L1 * th1.cos() + p.L2 * th12.cos();
        let (s1, c1) = phi1.sin_cos();
        let l2c = p.L2 * th12.cos();
        Matrix3::new(
            -rho * s1,
            eta * c1,
            -l2c * c1,
            rho * c1,
            eta * s1,
            -l2c * s1,
            0.0,
            -rho,
            p.L2 * th12.sin(),
        )
    }

    /// Evaluates every output at `(q, v)`.
    pub fn evaluate(&self, q: &SVector<f64, 6>, v: &SVector<f64, 5>) -> Result<DiffDriveOutputs> {
        check_finite("state.q", q)?;
        check_finite("inputs.v", v)?;
        let qa: [f64; 6] = q.as_slice().try_into().expect("length 6");
        let n = self.velocity_basis(q);
        let j = self.jacobian(q);
        let j_p = j.fixed_view::<2, 2>(0, 0).into_owned();
        let j_mv = self.arm_jacobian_platform(q);
        let (s, c) = q[2].sin_cos();
        let rot = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
        let mut jc = SMatrix::<f64, 5, 5>::zeros();
        jc.fixed_view_mut::<2, 2>(0, 0).copy_from(&j_p);
        jc.fixed_view_mut::<2, 2>(2, 0).copy_from(&j_p);
        jc.fixed_view_mut::<3, 3>(2, 2).copy_from(&(rot * j_mv));
        let x = self.task_generic(&qa);
        let jd = to_dmatrix(&j);
        Ok(DiffDriveOutputs {
            N_C: n,
            qdot: n * v,
            X: SVector::from(x),
            J_P: j_p,
            J: j,
            Xdot: j * v,
            det_J: j.determinant(),
            J_chapter_5_31: jc,
            J_mV: j_mv,
            manipulability_J: manipulability(&jd)?,
            manipulability_J_endeffector: manipulability(&jd.rows(2, 3).into_owned())?,
            manipulability_J_mV: manipulability(&to_dmatrix(&j_mv))?,
        })
    }

    /// Integrates `q̇ = N_C(q) v` with constant rates `v` from `q0` at t = 0 and returns
    /// `(q, X)` at `times` (DOP853, tolerance `tol`).
    #[allow(clippy::type_complexity)]
    pub fn simulate(
        &self,
        q0: &SVector<f64, 6>,
        v: &SVector<f64, 5>,
        times: &[f64],
        tol: f64,
    ) -> Result<Vec<(SVector<f64, 6>, SVector<f64, 5>)>> {
        check_finite("state.q", q0)?;
        check_finite("inputs.v", v)?;
        let mut ode = KinematicOde { model: self, v: *v };
        let mut dp = Dop853::new(6, super::case_integrator_options(tol))?;
        let rows = dp.solve_at(&mut ode, 0.0, q0.as_slice(), times)?;
        Ok(rows
            .iter()
            .map(|r| {
                let q = SVector::<f64, 6>::from_column_slice(r);
                let qa: [f64; 6] = r.as_slice().try_into().expect("length 6");
                (q, SVector::from(self.task_generic(&qa)))
            })
            .collect())
    }
}

/// `q̇ = N_C(q) v` with constant wheel and joint rates, as an [`OdeSystem`].
pub struct KinematicOde<'a> {
    /// The model.
    pub model: &'a DiffDriveKinematics,
    /// Constant rates `v`.
    pub v: SVector<f64, 5>,
}

impl OdeSystem for KinematicOde<'_> {
    fn dim(&self) -> usize {
        6
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<()> {
        let q = SVector::<f64, 6>::from_column_slice(x);
        let qd = self.model.velocity_basis(&q) * self.v;
        if !qd.iter().all(|v| v.is_finite()) {
            return Err(Error::Numerical {
                t,
                message: "non-finite q̇".into(),
            });
        }
        dx.copy_from_slice(qd.as_slice());
        Ok(())
    }
}

//! m1 — the unicycle / differential-drive platform (chapter 5.1, eqs 5.1–5.13).
//!
//! `q = [x, y, φ]` (CM position, heading); `v = [v_F, v_T]`, forward and lateral velocity
//! of the CM (`v_T = d φ̇`), or `v = [v_F, φ̇]` when `d = 0`
//! (see [`PlatformVelocity`]). Inputs `u = [τ_L, τ_R]` (wheel torques).
//! `C = [−sin φ, cos φ, −d]`, `M = diag(m, m, I)`, `M q̈ = S u − Cᵀλ`.

use super::ad::Real;
use super::lagrange::{self, LagrangianSystem, PfaffianSystem};
use super::{PlatformVelocity, check_finite, finite, platform_basis, positive, ser};
use crate::error::Result;
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

/// State `(q, v)` of this model.
pub type State = super::ModelState<3, 2>;

/// Parameters of the unicycle platform (SI units).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct UnicycleParams {
    /// Platform mass `m` (kg).
    pub m: f64,
    /// Yaw inertia about the CM `I` (kg·m²).
    #[serde(rename = "I")]
    pub inertia: f64,
    /// Offset `d` of the CM ahead of the driven-axle midpoint (m, may be ≤ 0).
    pub d: f64,
    /// Wheel radius `r_w` (m).
    pub r_w: f64,
    /// Half track `b` (m; the wheels are 2b apart).
    pub b: f64,
}

impl UnicycleParams {
    /// Checks that masses and lengths are positive and everything is finite.
    pub fn validate(&self) -> Result<()> {
        positive("m", self.m)?;
        positive("I", self.inertia)?;
        finite("d", self.d)?;
        positive("r_w", self.r_w)?;
        positive("b", self.b)
    }
}

/// The m1 model: validated parameters and the velocity parametrisation.
#[derive(Clone, Debug)]
pub struct Unicycle {
    /// Parameters.
    pub params: UnicycleParams,
    /// Velocity parametrisation of `v`.
    pub velocity: PlatformVelocity,
}

/// Every output of m1 at `(q, v, u)` (names as in the reference vectors).
#[derive(Clone, Debug, Serialize)]
#[allow(non_snake_case)]
pub struct UnicycleOutputs {
    /// Constraint row C (1×3).
    #[serde(serialize_with = "ser::mat")]
    pub C: SMatrix<f64, 1, 3>,
    /// Velocity basis N_C (3×2).
    #[serde(serialize_with = "ser::mat")]
    pub N_C: SMatrix<f64, 3, 2>,
    /// Ṅ_C.
    #[serde(serialize_with = "ser::mat")]
    pub Ndot_C: SMatrix<f64, 3, 2>,
    /// q̇ = N_C v.
    #[serde(serialize_with = "ser::vec")]
    pub qdot: SVector<f64, 3>,
    /// Mass matrix M = diag(m, m, I).
    #[serde(serialize_with = "ser::mat")]
    pub M: SMatrix<f64, 3, 3>,
    /// Actuator map S (3×2).
    #[serde(serialize_with = "ser::mat")]
    pub S: SMatrix<f64, 3, 2>,
    /// Q = S u.
    #[serde(serialize_with = "ser::vec")]
    pub Q: SVector<f64, 3>,
    /// Mr = N_Cᵀ M N_C.
    #[serde(serialize_with = "ser::mat")]
    pub Mr: SMatrix<f64, 2, 2>,
    /// Cr = N_Cᵀ M Ṅ_C.
    #[serde(serialize_with = "ser::mat")]
    pub Cr: SMatrix<f64, 2, 2>,
    /// cr = Cr v.
    #[serde(serialize_with = "ser::vec")]
    pub cr: SVector<f64, 2>,
    /// Qr = N_Cᵀ Q.
    #[serde(serialize_with = "ser::vec")]
    pub Qr: SVector<f64, 2>,
    /// v̇.
    #[serde(serialize_with = "ser::vec")]
    pub vdot: SVector<f64, 2>,
    /// q̈ = N_C v̇ + Ṅ_C v.
    #[serde(serialize_with = "ser::vec")]
    pub qddot: SVector<f64, 3>,
    /// λ (one constraint).
    #[serde(serialize_with = "ser::one")]
    pub lambda: f64,
    /// −Cᵀλ.
    #[serde(serialize_with = "ser::vec")]
    pub constraint_force: SVector<f64, 3>,
}

impl Unicycle {
    /// Validates `params` and picks the parametrisation automatically
    /// ([`PlatformVelocity::auto`]).
    pub fn new(params: UnicycleParams) -> Result<Self> {
        let velocity = PlatformVelocity::auto(params.d);
        Self::with_velocity(params, velocity)
    }

    /// Validates `params` with an explicit parametrisation (`LateralVelocity` with `d = 0`
    /// is [`crate::Error::Singular`]).
    pub fn with_velocity(params: UnicycleParams, velocity: PlatformVelocity) -> Result<Self> {
        params.validate()?;
        velocity.check(params.d)?;
        Ok(Unicycle { params, velocity })
    }

    /// The reduced ODE right-hand side `(q̇, v̇) = (N_C v, Mr⁻¹(Qr − Cr v − Gr))` at `state`.
    pub fn state_derivative(&self, state: &State, u: &SVector<f64, 2>) -> Result<State> {
        check_finite("state.q", &state.q)?;
        check_finite("state.v", &state.v)?;
        check_finite("inputs.u", u)?;
        let (q, v) = lagrange::state_derivative(self, &state.q, &state.v, u)?;
        Ok(State { q, v })
    }

    /// Evaluates every output at `(q, v, u)`.
    pub fn evaluate(
        &self,
        q: &SVector<f64, 3>,
        v: &SVector<f64, 2>,
        u: &SVector<f64, 2>,
    ) -> Result<UnicycleOutputs> {
        check_finite("state.q", q)?;
        check_finite("state.v", v)?;
        check_finite("inputs.u", u)?;
        let e = lagrange::evaluate_constrained(self, q, v, u)?;
        Ok(UnicycleOutputs {
            C: e.constraint.constraint,
            N_C: e.constraint.basis,
            Ndot_C: e.constraint.basis_rate,
            qdot: e.constraint.qdot,
            M: e.terms.mass,
            S: e.input_matrix,
            Q: e.q_force,
            Mr: e.mr,
            Cr: e.cr_matrix,
            cr: e.cr,
            Qr: e.qr,
            vdot: e.vdot,
            qddot: e.qddot,
            lambda: e.lambda,
            constraint_force: e.constraint_force,
        })
    }

    /// Kinetic energy `½ q̇ᵀ M q̇` with `q̇ = N_C v`.
    pub fn kinetic_energy(&self, q: &SVector<f64, 3>, v: &SVector<f64, 2>) -> f64 {
        let ct = lagrange::constraint_terms(self, q, v);
        let h = lagrange::mass_matrix(self, q);
        0.5 * ct.qdot.dot(&(h * ct.qdot))
    }

    /// States `(q, v)` at `times` under constant `u`, from `(q0, v0)` at t = 0
    /// (DOP853 at `rtol = atol = tol`).
    #[allow(clippy::type_complexity)]
    pub fn simulate(
        &self,
        q0: &SVector<f64, 3>,
        v0: &SVector<f64, 2>,
        u: &SVector<f64, 2>,
        times: &[f64],
        tol: f64,
    ) -> Result<Vec<(SVector<f64, 3>, SVector<f64, 2>)>> {
        check_finite("state.q", q0)?;
        check_finite("state.v", v0)?;
        check_finite("inputs.u", u)?;
        super::simulate_reduced(self, q0, v0, u, times, tol)
    }
}

impl LagrangianSystem<3> for Unicycle {
    fn mass_matrix_generic<T: Real>(&self, _q: &[T; 3]) -> [[T; 3]; 3] {
        let z = T::cst(0.0);
        let m = T::cst(self.params.m);
        [[m, z, z], [z, m, z], [z, z, T::cst(self.params.inertia)]]
    }
    fn potential_generic<T: Real>(&self, _q: &[T; 3]) -> T {
        T::cst(0.0)
    }
}

impl PfaffianSystem<3, 2, 2> for Unicycle {
    fn constraint_row_generic<T: Real>(&self, q: &[T; 3]) -> [T; 3] {
        [-q[2].sin(), q[2].cos(), T::cst(-self.params.d)]
    }
    fn velocity_basis_generic<T: Real>(&self, q: &[T; 3]) -> [[T; 2]; 3] {
        platform_basis(q[2], self.params.d, self.velocity)
    }
    fn input_matrix(&self, q: &SVector<f64, 3>) -> SMatrix<f64, 3, 2> {
        let p = &self.params;
        let (s, c) = q[2].sin_cos();
        let k = 1.0 / p.r_w;
        SMatrix::<f64, 3, 2>::new(c * k, c * k, s * k, s * k, -p.b * k, p.b * k)
    }
}

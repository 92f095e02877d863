//! m2 — platform + horizontal (SCARA-like) two-link arm (chapter 5.2, eqs 5.14–5.19).
//!
//! `q = [x, y, φ, θ1, θ2]`: platform CM, heading, link-1 angle relative to the heading,
//! link-2 angle relative to link 1 (CCW seen from above). The arm base is
//! `B = CM + L e(φ)`. `v = [v_F, v_T, θ̇1, θ̇2]` (or `[v_F, φ̇, θ̇1, θ̇2]` when `d = 0`).
//! Inputs `u = [τ_L, τ_R, τ_1, τ_2]`. The arm is horizontal, so `G = 0`.

use super::ad::Real;
use super::lagrange::{self, LagrangianSystem, PfaffianSystem};
use super::{PlatformVelocity, check_finite, finite, nonnegative, platform_basis, positive, ser};
use crate::error::Result;
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

/// State `(q, v)` of this model.
pub type State = super::ModelState<5, 4>;

/// Parameters of m2 (SI units).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[allow(non_snake_case)]
#[serde(deny_unknown_fields)]
pub struct PlatformArmParams {
    /// Platform mass `m_p`.
    pub m_p: f64,
    /// Platform yaw inertia about its CM `I_p`.
    pub I_p: f64,
    /// CM ahead of the axle midpoint `d`.
    pub d: f64,
    /// Arm base ahead of the CM `L`.
    pub L: f64,
    /// Wheel radius `r_w`.
    pub r_w: f64,
    /// Half track `b`.
    pub b: f64,
    /// Link-1 mass.
    pub m1: f64,
    /// Link-2 mass.
    pub m2: f64,
    /// Lumped mass at the elbow.
    pub M1: f64,
    /// Tip mass.
    pub M2: f64,
    /// Link-1 length.
    pub L1: f64,
    /// Link-2 length.
    pub L2: f64,
    /// Joint 1 to link-1 CM (signed).
    pub L1cm: f64,
    /// Joint 2 to link-2 CM (signed).
    pub L2cm: f64,
    /// Link-1 radius of gyration about its CM (yaw).
    pub k1: f64,
    /// Link-2 radius of gyration about its CM (yaw).
    pub k2: f64,
}

impl PlatformArmParams {
    /// Checks signs and finiteness of every parameter.
    pub fn validate(&self) -> Result<()> {
        positive("m_p", self.m_p)?;
        positive("I_p", self.I_p)?;
        finite("d", self.d)?;
        finite("L", self.L)?;
        positive("r_w", self.r_w)?;
        positive("b", self.b)?;
        nonnegative("m1", self.m1)?;
        nonnegative("m2", self.m2)?;
        nonnegative("M1", self.M1)?;
        nonnegative("M2", self.M2)?;
        positive("L1", self.L1)?;
        positive("L2", self.L2)?;
        finite("L1cm", self.L1cm)?;
        finite("L2cm", self.L2cm)?;
        nonnegative("k1", self.k1)?;
        nonnegative("k2", self.k2)
    }

    /// `m_arm = m1 + m2 + M1 + M2`.
    pub fn arm_mass(&self) -> f64 {
        self.m1 + self.m2 + self.M1 + self.M2
    }
    /// `Γ1 = m1 L1cm + (m2 + M1 + M2) L1`.
    pub fn gamma1(&self) -> f64 {
        self.m1 * self.L1cm + (self.m2 + self.M1 + self.M2) * self.L1
    }
    /// `Γ2 = m2 L2cm + M2 L2`.
    pub fn gamma2(&self) -> f64 {
        self.m2 * self.L2cm + self.M2 * self.L2
    }
    /// `I11 = m1(L1cm² + k1²) + (m2 + M1 + M2) L1²`.
    pub fn i11(&self) -> f64 {
        self.m1 * (self.L1cm.powi(2) + self.k1.powi(2))
            + (self.m2 + self.M1 + self.M2) * self.L1.powi(2)
    }
    /// `I22 = m2(L2cm² + k2²) + M2 L2²`.
    pub fn i22(&self) -> f64 {
        self.m2 * (self.L2cm.powi(2) + self.k2.powi(2)) + self.M2 * self.L2.powi(2)
    }
}

/// The m2 model.
#[derive(Clone, Debug)]
pub struct PlatformArm {
    /// Parameters.
    pub params: PlatformArmParams,
    /// Velocity parametrisation of the platform block.
    pub velocity: PlatformVelocity,
}

/// Every output of m2 at `(q, v, u)` (names as in the reference vectors).
#[derive(Clone, Debug, Serialize)]
#[allow(non_snake_case)]
pub struct PlatformArmOutputs {
    /// Constraint row C (1×5).
    #[serde(serialize_with = "ser::mat")]
    pub C: SMatrix<f64, 1, 5>,
    /// N_C (5×4).
    #[serde(serialize_with = "ser::mat")]
    pub N_C: SMatrix<f64, 5, 4>,
    /// Ṅ_C.
    #[serde(serialize_with = "ser::mat")]
    pub Ndot_C: SMatrix<f64, 5, 4>,
    /// q̇ = N_C v.
    #[serde(serialize_with = "ser::vec")]
    pub qdot: SVector<f64, 5>,
    /// Mass matrix H.
    #[serde(serialize_with = "ser::mat")]
    pub H: SMatrix<f64, 5, 5>,
    /// Christoffel Coriolis matrix.
    #[serde(serialize_with = "ser::mat")]
    pub C_coriolis: SMatrix<f64, 5, 5>,
    /// h = C_cor q̇.
    #[serde(serialize_with = "ser::vec")]
    pub h: SVector<f64, 5>,
    /// G (zero: horizontal arm).
    #[serde(serialize_with = "ser::vec")]
    pub G: SVector<f64, 5>,
    /// S (5×4).
    #[serde(serialize_with = "ser::mat")]
    pub S: SMatrix<f64, 5, 4>,
    /// Q = S u.
    #[serde(serialize_with = "ser::vec")]
    pub Q: SVector<f64, 5>,
    /// Mr.
    #[serde(serialize_with = "ser::mat")]
    pub Mr: SMatrix<f64, 4, 4>,
    /// Cr.
    #[serde(serialize_with = "ser::mat")]
    pub Cr: SMatrix<f64, 4, 4>,
    /// cr = Cr v.
    #[serde(serialize_with = "ser::vec")]
    pub cr: SVector<f64, 4>,
    /// Qr.
    #[serde(serialize_with = "ser::vec")]
    pub Qr: SVector<f64, 4>,
    /// v̇.
    #[serde(serialize_with = "ser::vec")]
    pub vdot: SVector<f64, 4>,
    /// q̈.
    #[serde(serialize_with = "ser::vec")]
    pub qddot: SVector<f64, 5>,
    /// λ.
    #[serde(serialize_with = "ser::one")]
    pub lambda: f64,
    /// −Cᵀλ.
    #[serde(serialize_with = "ser::vec")]
    pub constraint_force: SVector<f64, 5>,
}

impl PlatformArm {
    /// Validates `params`; parametrisation chosen by [`PlatformVelocity::auto`].
    pub fn new(params: PlatformArmParams) -> Result<Self> {
        let velocity = PlatformVelocity::auto(params.d);
        Self::with_velocity(params, velocity)
    }

    /// Validates `params` with an explicit parametrisation.
    pub fn with_velocity(params: PlatformArmParams, velocity: PlatformVelocity) -> Result<Self> {
        params.validate()?;
        velocity.check(params.d)?;
        Ok(PlatformArm { params, velocity })
    }

    /// The reduced ODE right-hand side `(q̇, v̇) = (N_C v, Mr⁻¹(Qr − Cr v − Gr))` at `state`.
    pub fn state_derivative(&self, state: &State, u: &SVector<f64, 4>) -> Result<State> {
        check_finite("state.q", &state.q)?;
        check_finite("state.v", &state.v)?;
        check_finite("inputs.u", u)?;
        let (q, v) = lagrange::state_derivative(self, &state.q, &state.v, u)?;
        Ok(State { q, v })
    }

    /// Evaluates every output at `(q, v, u)`.
    pub fn evaluate(
        &self,
        q: &SVector<f64, 5>,
        v: &SVector<f64, 4>,
        u: &SVector<f64, 4>,
    ) -> Result<PlatformArmOutputs> {
        check_finite("state.q", q)?;
        check_finite("state.v", v)?;
        check_finite("inputs.u", u)?;
        let e = lagrange::evaluate_constrained(self, q, v, u)?;
        Ok(PlatformArmOutputs {
            C: e.constraint.constraint,
            N_C: e.constraint.basis,
            Ndot_C: e.constraint.basis_rate,
            qdot: e.constraint.qdot,
            H: e.terms.mass,
            C_coriolis: e.terms.coriolis,
            h: e.terms.h,
            G: e.terms.gravity,
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

    /// Kinetic energy `½ q̇ᵀ H q̇` with `q̇ = N_C v` (the potential is zero).
    pub fn kinetic_energy(&self, q: &SVector<f64, 5>, v: &SVector<f64, 4>) -> f64 {
        let ct = lagrange::constraint_terms(self, q, v);
        let h = lagrange::mass_matrix(self, q);
        0.5 * ct.qdot.dot(&(h * ct.qdot))
    }

    /// States `(q, v)` at `times` under constant `u` (DOP853, tolerance `tol`).
    #[allow(clippy::type_complexity)]
    pub fn simulate(
        &self,
        q0: &SVector<f64, 5>,
        v0: &SVector<f64, 4>,
        u: &SVector<f64, 4>,
        times: &[f64],
        tol: f64,
    ) -> Result<Vec<(SVector<f64, 5>, SVector<f64, 4>)>> {
        check_finite("state.q", q0)?;
        check_finite("state.v", v0)?;
        check_finite("inputs.u", u)?;
        super::simulate_reduced(self, q0, v0, u, times, tol)
    }
}

impl LagrangianSystem<5> for PlatformArm {
    fn mass_matrix_generic<T: Real>(&self, q: &[T; 5]) -> [[T; 5]; 5] {
        let p = &self.params;
        let (phi, th1, th2) = (q[2], q[3], q[4]);
        let a1 = phi + th1;
        let a2 = a1 + th2;
        let (g1, g2, l) = (p.gamma1(), p.gamma2(), p.L);
        let m_arm = p.arm_mass();
        let (s1, c1, s2, c2) = (a1.sin(), a1.cos(), a2.sin(), a2.cos());
        let lam = (th1.cos() * g1 + (th1 + th2).cos() * g2) * l;
        let z = T::cst(0.0);
        let mt = T::cst(p.m_p + m_arm);
        let h15 = s2 * (-g2);
        let h25 = c2 * g2;
        let h14 = s1 * (-g1) + h15;
        let h24 = c1 * g1 + h25;
        let h13 = phi.sin() * (-m_arm * l) + h14;
        let h23 = phi.cos() * (m_arm * l) + h24;
        let h45 = th2.cos() * (g2 * p.L1) + p.i22();
        let h44 = th2.cos() * (2.0 * g2 * p.L1) + (p.i11() + p.i22());
        let h55 = T::cst(p.i22());
        let h33 = lam * 2.0 + h44 + (p.I_p + m_arm * l * l);
        let h34 = lam + h44;
        let h35 = (th1 + th2).cos() * (l * g2) + h45;
        [
            [mt, z, h13, h14, h15],
            [z, mt, h23, h24, h25],
            [h13, h23, h33, h34, h35],
            [h14, h24, h34, h44, h45],
            [h15, h25, h35, h45, h55],
        ]
    }
    fn potential_generic<T: Real>(&self, _q: &[T; 5]) -> T {
        T::cst(0.0)
    }
}

impl PfaffianSystem<5, 4, 4> for PlatformArm {
    fn constraint_row_generic<T: Real>(&self, q: &[T; 5]) -> [T; 5] {
        let z = T::cst(0.0);
        [-q[2].sin(), q[2].cos(), T::cst(-self.params.d), z, z]
    }
    fn velocity_basis_generic<T: Real>(&self, q: &[T; 5]) -> [[T; 4]; 5] {
        let n = platform_basis(q[2], self.params.d, self.velocity);
        let (z, o) = (T::cst(0.0), T::cst(1.0));
        [
            [n[0][0], n[0][1], z, z],
            [n[1][0], n[1][1], z, z],
            [n[2][0], n[2][1], z, z],
            [z, z, o, z],
            [z, z, z, o],
        ]
    }
    fn input_matrix(&self, q: &SVector<f64, 5>) -> SMatrix<f64, 5, 4> {
        let p = &self.params;
        let (s, c) = q[2].sin_cos();
        let k = 1.0 / p.r_w;
        let mut m = SMatrix::<f64, 5, 4>::zeros();
        m[(0, 0)] = c * k;
        m[(0, 1)] = c * k;
        m[(1, 0)] = s * k;
        m[(1, 1)] = s * k;
        m[(2, 0)] = -p.b * k;
        m[(2, 1)] = p.b * k;
        m[(3, 2)] = 1.0;
        m[(4, 3)] = 1.0;
        m
    }
}

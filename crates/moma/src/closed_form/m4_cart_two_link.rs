//! m4 — cart with a two-link arm in a vertical plane; tip-over and the balanced
//! manipulator (chapter 5.3.2, eqs 5.40–5.66).
//!
//! `q = [d0, θ1, θ2]`, `u = [f, τ1, τ2]`. x is horizontal (the cart direction, the chapter's
//! z_w), z is up (the chapter's x_w). θ1 is measured from the upward vertical, positive
//! towards +x; link 2 makes `θ12 = θ1 − θ2` with the vertical (the chapter's convention:
//! a positive θ2 turns link 2 back towards the vertical). `H q̈ + h + G = u`.
//!
//! Balanced arm: `Γ1 = Γ2 = 0` (counterweighted links, `L2cm = −M2 L2/m2`,
//! `L1cm = −(m2+M1+M2) L1/m1`) gives `G = 0`, `h = 0` and a block-diagonal H; the force of
//! the arm on the cart is then `(−m_arm d̈0, −m_arm g)`, but the motor reaction `−τ1` still
//! acts on the cart.

use super::ad::Real;
use super::lagrange::{self, LagrangianSystem};
use super::{check_finite, finite, nonnegative, positive, ser};
use crate::error::Result;
use crate::ode::{AdaptiveOptions, Dop853, OdeSystem};
use nalgebra::{SMatrix, SVector, Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// State `(q, v)` of this model (`v = q̇`).
pub type State = super::ModelState<3, 3>;

/// Parameters of m4 (SI units).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[allow(non_snake_case)]
pub struct CartTwoLinkParams {
    /// Link-1 mass.
    pub m1: f64,
    /// Link-2 mass.
    pub m2: f64,
    /// Lumped mass at the elbow.
    pub M1: f64,
    /// Tip mass.
    pub M2: f64,
    /// Cart mass.
    pub M_cart: f64,
    /// Link-1 length.
    pub L1: f64,
    /// Link-2 length.
    pub L2: f64,
    /// Joint 1 to link-1 CM (signed; negative = counterweighted).
    pub L1cm: f64,
    /// Joint 2 to link-2 CM (signed).
    pub L2cm: f64,
    /// Link-1 radius of gyration about its CM.
    pub k1: f64,
    /// Link-2 radius of gyration about its CM.
    pub k2: f64,
    /// Gravitational acceleration.
    pub g: f64,
}

impl CartTwoLinkParams {
    /// Checks signs and finiteness.
    pub fn validate(&self) -> Result<()> {
        nonnegative("m1", self.m1)?;
        nonnegative("m2", self.m2)?;
        nonnegative("M1", self.M1)?;
        nonnegative("M2", self.M2)?;
        positive("M_cart", self.M_cart)?;
        positive("L1", self.L1)?;
        positive("L2", self.L2)?;
        finite("L1cm", self.L1cm)?;
        finite("L2cm", self.L2cm)?;
        nonnegative("k1", self.k1)?;
        nonnegative("k2", self.k2)?;
        finite("g", self.g)
    }
    /// Arm mass `m1 + m2 + M1 + M2`.
    pub fn arm_mass(&self) -> f64 {
        self.m1 + self.m2 + self.M1 + self.M2
    }
    /// `M_T = m_arm + M_cart`.
    pub fn total_mass(&self) -> f64 {
        self.arm_mass() + self.M_cart
    }
    /// `Γ1 = m1 L1cm + (m2 + M1 + M2) L1`.
    pub fn gamma1(&self) -> f64 {
        self.m1 * self.L1cm + (self.m2 + self.M1 + self.M2) * self.L1
    }
    /// `Γ2 = m2 L2cm + M2 L2`.
    pub fn gamma2(&self) -> f64 {
        self.m2 * self.L2cm + self.M2 * self.L2
    }
    /// `I11 = m1 L1cm² + (M1 + m2 + M2) L1² + m1 k1²`.
    pub fn i11(&self) -> f64 {
        self.m1 * (self.L1cm.powi(2) + self.k1.powi(2))
            + (self.m2 + self.M1 + self.M2) * self.L1.powi(2)
    }
    /// `I22 = m2 L2cm² + M2 L2² + m2 k2²`.
    pub fn i22(&self) -> f64 {
        self.m2 * (self.L2cm.powi(2) + self.k2.powi(2)) + self.M2 * self.L2.powi(2)
    }
    /// The link-CM offsets that balance the arm (`Γ1 = Γ2 = 0`): `(L1cm, L2cm)`.
    /// Needs `m1 > 0`, `m2 > 0`.
    pub fn balancing_offsets(&self) -> (f64, f64) {
        (
            -(self.m2 + self.M1 + self.M2) * self.L1 / self.m1,
            -self.M2 * self.L2 / self.m2,
        )
    }
}

/// The m4 model.
#[derive(Clone, Debug)]
pub struct CartTwoLink {
    /// Parameters.
    pub params: CartTwoLinkParams,
}

/// Every output of m4 at `(q, q̇, u)` (names as in the reference vectors).
#[derive(Clone, Debug, Serialize)]
#[allow(non_snake_case)]
pub struct CartTwoLinkOutputs {
    /// Mass matrix H.
    #[serde(serialize_with = "ser::mat")]
    pub H: SMatrix<f64, 3, 3>,
    /// Christoffel Coriolis matrix.
    #[serde(serialize_with = "ser::mat")]
    pub C_coriolis: SMatrix<f64, 3, 3>,
    /// h = C_cor q̇.
    #[serde(serialize_with = "ser::vec")]
    pub h: SVector<f64, 3>,
    /// G = ∂V/∂q.
    #[serde(serialize_with = "ser::vec")]
    pub G: SVector<f64, 3>,
    /// q̈ = H⁻¹(u − h − G).
    #[serde(serialize_with = "ser::vec")]
    pub qddot: SVector<f64, 3>,
    /// Γ1.
    pub Gamma1: f64,
    /// Γ2.
    pub Gamma2: f64,
    /// M_T.
    pub M_Total: f64,
    /// I11.
    pub I11: f64,
    /// I22.
    pub I22: f64,
    /// Force `[F_x, F_z]` of the arm on the cart at the shoulder, `−(ṗ_arm + m_arm g ẑ)`.
    #[serde(serialize_with = "ser::vec")]
    pub arm_force_on_cart: SVector<f64, 2>,
    /// Torque of the arm on the cart, `−τ1` (motor reaction).
    pub arm_torque_on_cart: f64,
    /// ½ q̇ᵀ H q̇.
    pub kinetic_energy: f64,
    /// V = g(Γ1 cos θ1 + Γ2 cos θ12).
    pub potential_energy: f64,
}

impl CartTwoLink {
    /// Validates the parameters.
    pub fn new(params: CartTwoLinkParams) -> Result<Self> {
        params.validate()?;
        Ok(CartTwoLink { params })
    }

    /// Whether the arm is balanced (`|Γ1|, |Γ2| ≤ tol`).
    pub fn is_balanced(&self, tol: f64) -> bool {
        self.params.gamma1().abs() <= tol && self.params.gamma2().abs() <= tol
    }

    /// Forward dynamics `q̈ = H⁻¹(u − h − G)`.
    pub fn forward_dynamics(
        &self,
        q: &Vector3<f64>,
        qdot: &Vector3<f64>,
        u: &Vector3<f64>,
    ) -> Result<Vector3<f64>> {
        let t = lagrange::lagrange_terms(self, q, qdot);
        lagrange::spd_solve(&t.mass, &(u - t.h - t.gravity), "mass matrix H")
    }

    /// The ODE right-hand side `(q̇, q̈)` at `state = (q, q̇)`.
    pub fn state_derivative(&self, state: &State, u: &Vector3<f64>) -> Result<State> {
        check_finite("state.q", &state.q)?;
        check_finite("state.qdot", &state.v)?;
        check_finite("inputs.u", u)?;
        Ok(State {
            q: state.v,
            v: self.forward_dynamics(&state.q, &state.v, u)?,
        })
    }

    /// Evaluates every output at `(q, q̇, u)`.
    pub fn evaluate(
        &self,
        q: &Vector3<f64>,
        qdot: &Vector3<f64>,
        u: &Vector3<f64>,
    ) -> Result<CartTwoLinkOutputs> {
        check_finite("state.q", q)?;
        check_finite("state.qdot", qdot)?;
        check_finite("inputs.u", u)?;
        let p = &self.params;
        let t = lagrange::lagrange_terms(self, q, qdot);
        let qddot = lagrange::spd_solve(&t.mass, &(u - t.h - t.gravity), "mass matrix H")?;
        let (g1, g2) = (p.gamma1(), p.gamma2());
        let (th1, th12) = (q[1], q[1] - q[2]);
        let (w1, w12) = (qdot[1], qdot[1] - qdot[2]);
        let (a1, a12) = (qddot[1], qddot[1] - qddot[2]);
        let m_arm = p.arm_mass();
        let pdot_x = m_arm * qddot[0]
            + g1 * (th1.cos() * a1 - th1.sin() * w1 * w1)
            + g2 * (th12.cos() * a12 - th12.sin() * w12 * w12);
        let pdot_z = -g1 * (th1.sin() * a1 + th1.cos() * w1 * w1)
            - g2 * (th12.sin() * a12 + th12.cos() * w12 * w12);
        Ok(CartTwoLinkOutputs {
            H: t.mass,
            C_coriolis: t.coriolis,
            h: t.h,
            G: t.gravity,
            qddot,
            Gamma1: g1,
            Gamma2: g2,
            M_Total: p.total_mass(),
            I11: p.i11(),
            I22: p.i22(),
            arm_force_on_cart: Vector2::new(-pdot_x, -(pdot_z + m_arm * p.g)),
            arm_torque_on_cart: -u[1],
            kinetic_energy: t.kinetic_energy,
            potential_energy: t.potential_energy,
        })
    }

    /// Total energy `T + V`.
    pub fn energy(&self, q: &Vector3<f64>, qdot: &Vector3<f64>) -> f64 {
        let h = lagrange::mass_matrix(self, q);
        let (v, _) = lagrange::potential_and_gravity(self, q);
        0.5 * qdot.dot(&(h * qdot)) + v
    }

    /// States `(q, q̇)` at `times` under constant `u` (DOP853, tolerance `tol`).
    #[allow(clippy::type_complexity)]
    pub fn simulate(
        &self,
        q0: &Vector3<f64>,
        qdot0: &Vector3<f64>,
        u: &Vector3<f64>,
        times: &[f64],
        tol: f64,
    ) -> Result<Vec<(Vector3<f64>, Vector3<f64>)>> {
        check_finite("state.q", q0)?;
        check_finite("state.qdot", qdot0)?;
        check_finite("inputs.u", u)?;
        let mut ode = CartOde { model: self, u: *u };
        let x0 = [q0[0], q0[1], q0[2], qdot0[0], qdot0[1], qdot0[2]];
        let mut dp = Dop853::new(6, AdaptiveOptions::with_tolerance(tol))?;
        let rows = dp.solve_at(&mut ode, 0.0, &x0, times)?;
        Ok(rows
            .iter()
            .map(|r| {
                (
                    Vector3::new(r[0], r[1], r[2]),
                    Vector3::new(r[3], r[4], r[5]),
                )
            })
            .collect())
    }
}

/// m4 under a constant input as an [`OdeSystem`] on `x = [q; q̇]`.
pub struct CartOde<'a> {
    /// The model.
    pub model: &'a CartTwoLink,
    /// Constant input `u = [f, τ1, τ2]`.
    pub u: Vector3<f64>,
}

impl OdeSystem for CartOde<'_> {
    fn dim(&self) -> usize {
        6
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<()> {
        let q = Vector3::new(x[0], x[1], x[2]);
        let qd = Vector3::new(x[3], x[4], x[5]);
        let qdd = self.model.forward_dynamics(&q, &qd, &self.u)?;
        dx[..3].copy_from_slice(qd.as_slice());
        dx[3..].copy_from_slice(qdd.as_slice());
        Ok(())
    }
}

impl LagrangianSystem<3> for CartTwoLink {
    fn mass_matrix_generic<T: Real>(&self, q: &[T; 3]) -> [[T; 3]; 3] {
        let p = &self.params;
        let (th1, th2) = (q[1], q[2]);
        let th12 = th1 - th2;
        let (g1, g2, i22) = (p.gamma1(), p.gamma2(), p.i22());
        let h01 = th1.cos() * g1 + th12.cos() * g2;
        let h02 = th12.cos() * (-g2);
        let h11 = th2.cos() * (2.0 * g2 * p.L1) + (p.i11() + i22);
        let h12 = th2.cos() * (-g2 * p.L1) + (-i22);
        [
            [T::cst(p.total_mass()), h01, h02],
            [h01, h11, h12],
            [h02, h12, T::cst(i22)],
        ]
    }
    fn potential_generic<T: Real>(&self, q: &[T; 3]) -> T {
        let p = &self.params;
        let th12 = q[1] - q[2];
        (q[1].cos() * p.gamma1() + th12.cos() * p.gamma2()) * p.g
    }
}

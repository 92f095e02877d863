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
//!
//! Tip-over ([`CartTwoLink::stability`]): the cart stands on two wheel contacts a
//! [`CartSupport::wheelbase`] apart, centred under the shoulder, on the ground
//! [`CartSupport::shoulder_height`] below it. In 3-D terms the plane of motion is x–z
//! (y = 0, link rotations about +y), the support is the segment between the contacts and
//! its two tip-over axes run along y through them (rear = edge 0, front = edge 1).

use super::ad::Real;
use super::lagrange::{self, LagrangianSystem};
use super::{check_finite, finite, nonnegative, positive, ser};
use crate::error::Result;
use crate::ode::{Dop853, OdeSystem};
use crate::spatial::Inertia;
use crate::stability::{GravitoInertialWrench, StabilityReport, SupportPolygon, evaluate_measures};
use nalgebra::{Matrix3, SMatrix, SVector, Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// State `(q, v)` of this model (`v = q̇`).
pub type State = super::ModelState<3, 3>;

/// Parameters of m4 (SI units).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[allow(non_snake_case)]
#[serde(deny_unknown_fields)]
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

/// One body of the cart in its plane: `(mass, [x, z], [ẍ, z̈], m k², angular acceleration)`.
type CartBody = (f64, Vector2<f64>, Vector2<f64>, f64, f64);

/// Where the cart touches the ground (the model itself has no wheels).
#[derive(Clone, Copy, Debug, Deserialize, Serialize, PartialEq)]
pub struct CartSupport {
    /// Distance between the rear and front wheel contacts (m), > 0; the contacts are at
    /// `d0 ∓ wheelbase / 2`.
    pub wheelbase: f64,
    /// Height of the shoulder (and the cart's mass) above the ground (m), ≥ 0.
    pub shoulder_height: f64,
}

impl CartSupport {
    /// Checks signs and finiteness.
    pub fn validate(&self) -> Result<()> {
        positive("wheelbase", self.wheelbase)?;
        nonnegative("shoulder_height", self.shoulder_height)
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

    /// The five bodies (cart, link 1, M1, link 2, M2) at `(q, q̇, q̈)`, each as
    /// `(mass, [x, z], [ẍ, z̈], m k², angular acceleration)` in the cart's plane.
    fn bodies(&self, q: &Vector3<f64>, qdot: &Vector3<f64>, qddot: &Vector3<f64>) -> [CartBody; 5] {
        let p = &self.params;
        let (th1, th12) = (q[1], q[1] - q[2]);
        let (w1, w12) = (qdot[1], qdot[1] - qdot[2]);
        let (a1, a12) = (qddot[1], qddot[1] - qddot[2]);
        let (s1, c1, s12, c12) = (th1.sin(), th1.cos(), th12.sin(), th12.cos());
        // a point at distance l along a link of angle θ from the vertical
        let pos = |l: f64, s: f64, c: f64| Vector2::new(l * s, l * c);
        let acc = |l: f64, s: f64, c: f64, w: f64, al: f64| {
            Vector2::new(l * (c * al - s * w * w), -l * (s * al + c * w * w))
        };
        let cart = Vector2::new(q[0], 0.0);
        let cart_a = Vector2::new(qddot[0], 0.0);
        let elbow = cart + pos(p.L1, s1, c1);
        let elbow_a = cart_a + acc(p.L1, s1, c1, w1, a1);
        [
            (p.M_cart, cart, cart_a, 0.0, 0.0),
            (
                p.m1,
                cart + pos(p.L1cm, s1, c1),
                cart_a + acc(p.L1cm, s1, c1, w1, a1),
                p.m1 * p.k1 * p.k1,
                a1,
            ),
            (p.M1, elbow, elbow_a, 0.0, 0.0),
            (
                p.m2,
                elbow + pos(p.L2cm, s12, c12),
                elbow_a + acc(p.L2cm, s12, c12, w12, a12),
                p.m2 * p.k2 * p.k2,
                a12,
            ),
            (
                p.M2,
                elbow + pos(p.L2, s12, c12),
                elbow_a + acc(p.L2, s12, c12, w12, a12),
                0.0,
                0.0,
            ),
        ]
    }

    /// The gravito-inertial wrench of state `(q, q̇, q̈)` in 3-D (plane of motion x–z,
    /// y = 0, the shoulder at height 0): `f = Σ m_k (g − a_k)`, moment about the CoM
    /// `Σ (r_k − c) × m_k (g − a_k) − Σ m_k k_k² θ̈_k ŷ`.
    pub fn gravito_inertial_wrench(
        &self,
        q: &Vector3<f64>,
        qdot: &Vector3<f64>,
        qddot: &Vector3<f64>,
    ) -> GravitoInertialWrench {
        let g = Vector3::new(0.0, 0.0, -self.params.g);
        let bodies = self.bodies(q, qdot, qddot);
        let to3 = |v: Vector2<f64>| Vector3::new(v.x, 0.0, v.y);
        let mass: f64 = bodies.iter().map(|b| b.0).sum();
        let com = bodies.iter().map(|b| to3(b.1) * b.0).sum::<Vector3<f64>>() / mass;
        let mut force = Vector3::zeros();
        let mut moment = Vector3::zeros();
        for (m, r, a, mk2, alpha) in bodies {
            let load = (g - to3(a)) * m;
            force += load;
            moment += (to3(r) - com).cross(&load) - Vector3::new(0.0, mk2 * alpha, 0.0);
        }
        GravitoInertialWrench {
            mass,
            com,
            force,
            moment_about_com: moment,
        }
    }

    /// World spatial inertia of the arm (links and lumped masses, not the cart) at `q`,
    /// for the Moment-Height measure; link inertia `m k²` about y.
    pub fn arm_inertia(&self, q: &Vector3<f64>) -> Inertia {
        let z = Vector3::zeros();
        let mut total = Inertia::zero();
        for (m, r, _, mk2, _) in self.bodies(q, &z, &z).into_iter().skip(1) {
            let ic = Matrix3::from_diagonal(&Vector3::new(0.0, mk2, 0.0));
            total += Inertia::new(m, Vector3::new(r.x, 0.0, r.y), ic);
        }
        total
    }

    /// ZMP, Force-Angle and Moment-Height of the cart on `support` at `(q, q̇, q̈)`: the
    /// support is the segment between the wheel contacts (edge 0 the rear axis, edge 1
    /// the front), the Moment-Height body set is the arm.
    pub fn stability(
        &self,
        support: &CartSupport,
        q: &Vector3<f64>,
        qdot: &Vector3<f64>,
        qddot: &Vector3<f64>,
    ) -> Result<StabilityReport> {
        support.validate()?;
        check_finite("state.q", q)?;
        check_finite("state.qdot", qdot)?;
        check_finite("state.qddot", qddot)?;
        let half = 0.5 * support.wheelbase;
        let seg = SupportPolygon::segment(
            Vector2::new(q[0] - half, 0.0),
            Vector2::new(q[0] + half, 0.0),
            -support.shoulder_height,
        )?;
        let w = self.gravito_inertial_wrench(q, qdot, qddot);
        let mut out = StabilityReport::with_capacity(2);
        evaluate_measures(&w, &seg, &self.arm_inertia(q), &mut out);
        Ok(out)
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
        let mut dp = Dop853::new(6, super::case_integrator_options(tol))?;
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

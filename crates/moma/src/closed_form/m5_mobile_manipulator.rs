//! m5 — 3-D mobile manipulator: platform + capstan + two-link arm; task-space model
//! (chapter 5.4–5.5, eqs 5.67–5.133).
//!
//! Coordinates are the chapter's absolute-angle choice (5.108):
//! `q = [x, y, φ, φt, θ1, θ12]` with `φt = φ + φ1` (capstan heading) and `θ12 = θ1 − θ2`
//! (link-2 angle from the vertical). Joint coordinates `q_j = [x, y, φ, φ1, θ1, θ2]`,
//! `q = P q_j`. Velocities `v = [v_F, v_T, φ̇t, θ̇1, θ̇12]` (or `[v_F, φ̇, …]` for `d = 0`).
//! Inputs `u = [τ_L, τ_R, τ_c, τ_s, τ_e]`.
//!
//! Corrections to the print (see `docs/chapter.md`): platform-yaw coefficient
//! `I_p + m_arm L²` and coupling `m_arm L` (5.100, 5.106), `I_m` without the spurious ½
//! and with `sin²θ1` on link 1's `k1y²` (5.101), the factor L in H(φ, θ1), H(φ, θ12)
//! (5.106), the Christoffel velocity term instead of (5.111)–(5.112), and the task-space
//! `B = (J N_C)⁻ᵀ N_Cᵀ`, `V = (H Ṅ_C + C_cor N_C − H N_C A⁻¹ Ȧ) A⁻¹` (5.114–5.119).
//! `I_c` (capstan yaw inertia) is an addition; `I_c = 0` recovers the chapter.

use super::ad::{Real, seed_direction};
use super::lagrange::{self, ConstrainedEvaluation, LagrangianSystem, PfaffianSystem};
use super::{
    Manipulability, PlatformVelocity, check_finite, finite, manipulability, nonnegative,
    platform_basis, positive, ser, to_dmatrix,
};
use crate::error::{Error, Result};
use nalgebra::{SMatrix, SVector};
use serde::{Deserialize, Serialize};

/// State `(q, v)` of this model.
pub type State = super::ModelState<6, 5>;

/// Parameters of m5 (SI units).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[allow(non_snake_case)]
#[serde(deny_unknown_fields)]
pub struct MobileManipulatorParams {
    /// Platform mass (CM at (x, y)).
    pub M_cart: f64,
    /// Platform yaw inertia about its CM.
    pub I_p: f64,
    /// Capstan yaw inertia about its axis (0 in the chapter).
    pub I_c: f64,
    /// CM ahead of the axle midpoint.
    pub d: f64,
    /// Capstan axis B ahead of the CM.
    pub L: f64,
    /// Wheel radius.
    pub r_w: f64,
    /// Half track.
    pub b: f64,
    /// Link-1 mass.
    pub m1: f64,
    /// Link-2 mass.
    pub m2: f64,
    /// Elbow lumped mass.
    pub M1: f64,
    /// Tip mass.
    pub M2: f64,
    /// Link-1 length.
    pub L1: f64,
    /// Link-2 length.
    pub L2: f64,
    /// Joint to link-1 CM.
    pub L1cm: f64,
    /// Joint to link-2 CM.
    pub L2cm: f64,
    /// Link-1 pitch radius of gyration (about the CM, parallel to the joint axis).
    pub k1: f64,
    /// Link-2 pitch radius of gyration.
    pub k2: f64,
    /// Link-1 radius of gyration about the CM axis normal to the joint axis and the link.
    pub k1y: f64,
    /// Link-2 radius of gyration about the same kind of axis.
    pub k2y: f64,
    /// Gravitational acceleration.
    pub g: f64,
}

impl MobileManipulatorParams {
    /// Checks signs and finiteness.
    pub fn validate(&self) -> Result<()> {
        positive("M_cart", self.M_cart)?;
        positive("I_p", self.I_p)?;
        nonnegative("I_c", self.I_c)?;
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
        nonnegative("k2", self.k2)?;
        nonnegative("k1y", self.k1y)?;
        nonnegative("k2y", self.k2y)?;
        finite("g", self.g)
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

/// The joint-to-absolute coordinate map P (`q = P q_j`).
pub fn joint_to_absolute() -> SMatrix<f64, 6, 6> {
    let mut p = SMatrix::<f64, 6, 6>::identity();
    p[(3, 2)] = 1.0; // φt = φ + φ1
    p[(5, 5)] = -1.0; // θ12 = θ1 − θ2
    p[(5, 4)] = 1.0;
    p
}

struct TaskCore {
    x: SVector<f64, 5>,
    xdot: SVector<f64, 5>,
    j: SMatrix<f64, 5, 6>,
    a: SMatrix<f64, 5, 5>,
    adot: SMatrix<f64, 5, 5>,
    hx: SMatrix<f64, 5, 5>,
    b: SMatrix<f64, 5, 6>,
    vm: SMatrix<f64, 6, 5>,
}

/// The m5 model.
#[derive(Clone, Debug)]
pub struct MobileManipulator {
    /// Parameters.
    pub params: MobileManipulatorParams,
    /// Velocity parametrisation of the platform block.
    pub velocity: PlatformVelocity,
}

/// Task-space model at `(q, v, u)`: `Hx ẍ + (B V) ẋ + B G = B Q`.
#[derive(Clone, Debug, Serialize)]
#[allow(non_snake_case)]
pub struct TaskSpace {
    /// `x = [x_B, y_B, x_E − x_B, y_E − y_B, z_E]`.
    #[serde(serialize_with = "ser::vec", rename = "x_task")]
    pub x: SVector<f64, 5>,
    /// `ẋ = A v`.
    #[serde(serialize_with = "ser::vec", rename = "xdot_task")]
    pub xdot: SVector<f64, 5>,
    /// `ẍ = A v̇ + Ȧ v`.
    #[serde(serialize_with = "ser::vec", rename = "xddot_task")]
    pub xddot: SVector<f64, 5>,
    /// `J = ∂x/∂q` (5×6).
    #[serde(serialize_with = "ser::mat")]
    pub J: SMatrix<f64, 5, 6>,
    /// `A = J N_C` (5×5).
    #[serde(serialize_with = "ser::mat", rename = "A_JN")]
    pub A: SMatrix<f64, 5, 5>,
    /// `Ȧ = J̇ N_C + J Ṅ_C`.
    #[serde(serialize_with = "ser::mat")]
    pub Adot: SMatrix<f64, 5, 5>,
    /// `Hx = A⁻ᵀ Mr A⁻¹`.
    #[serde(serialize_with = "ser::mat")]
    pub Hx: SMatrix<f64, 5, 5>,
    /// `B = A⁻ᵀ N_Cᵀ` (5×6).
    #[serde(serialize_with = "ser::mat")]
    pub B: SMatrix<f64, 5, 6>,
    /// `V = (H Ṅ_C + C_cor N_C − H N_C A⁻¹ Ȧ) A⁻¹` (6×5).
    #[serde(serialize_with = "ser::mat")]
    pub V: SMatrix<f64, 6, 5>,
    /// `B V`.
    #[serde(serialize_with = "ser::mat")]
    pub BV: SMatrix<f64, 5, 5>,
    /// `B G`.
    #[serde(serialize_with = "ser::vec")]
    pub BgG: SVector<f64, 5>,
    /// `B Q`.
    #[serde(serialize_with = "ser::vec")]
    pub BQ: SVector<f64, 5>,
    /// Manipulability measures of A.
    pub manipulability_A: Manipulability,
}

/// The task-space terms of [`MobileManipulator::task_terms`].
#[derive(Clone, Debug)]
pub struct TaskTerms {
    /// `x = [x_B, y_B, x_E − x_B, y_E − y_B, z_E]`.
    pub x: SVector<f64, 5>,
    /// `ẋ = A v`.
    pub xdot: SVector<f64, 5>,
    /// `A = J N_C`.
    pub a: SMatrix<f64, 5, 5>,
    /// `Hx = A⁻ᵀ Mr A⁻¹` (symmetric positive definite).
    pub hx: SMatrix<f64, 5, 5>,
    /// `B V` (the task-space Coriolis matrix, `Ḣx − 2 B V` skew).
    pub bv: SMatrix<f64, 5, 5>,
    /// `B G` (task-space gravity).
    pub bg: SVector<f64, 5>,
    /// `N_Cᵀ S` (5×5).
    pub actuation: SMatrix<f64, 5, 5>,
}

/// Every output of m5 at `(q, v, u)` (names as in the reference vectors).
#[derive(Clone, Debug, Serialize)]
#[allow(non_snake_case)]
pub struct MobileManipulatorOutputs {
    /// Mass matrix H (absolute-angle coordinates).
    #[serde(serialize_with = "ser::mat")]
    pub H: SMatrix<f64, 6, 6>,
    /// Christoffel Coriolis matrix.
    #[serde(serialize_with = "ser::mat")]
    pub C_coriolis: SMatrix<f64, 6, 6>,
    /// h = C_cor q̇.
    #[serde(serialize_with = "ser::vec")]
    pub h: SVector<f64, 6>,
    /// G = ∂V/∂q.
    #[serde(serialize_with = "ser::vec")]
    pub G: SVector<f64, 6>,
    /// Capstan-axis inertia of the arm `I_m(θ1, θ12)` (with `I_c`).
    pub I_m: f64,
    /// ½ q̇ᵀ H q̇.
    pub kinetic_energy: f64,
    /// g(Γ1 cos θ1 + Γ2 cos θ12).
    pub potential_energy: f64,
    /// C (1×6).
    #[serde(serialize_with = "ser::mat")]
    pub C: SMatrix<f64, 1, 6>,
    /// N_C (6×5).
    #[serde(serialize_with = "ser::mat")]
    pub N_C: SMatrix<f64, 6, 5>,
    /// Ṅ_C.
    #[serde(serialize_with = "ser::mat")]
    pub Ndot_C: SMatrix<f64, 6, 5>,
    /// q̇ = N_C v.
    #[serde(serialize_with = "ser::vec")]
    pub qdot: SVector<f64, 6>,
    /// S (6×5).
    #[serde(serialize_with = "ser::mat")]
    pub S: SMatrix<f64, 6, 5>,
    /// Q = S u.
    #[serde(serialize_with = "ser::vec")]
    pub Q: SVector<f64, 6>,
    /// Mr.
    #[serde(serialize_with = "ser::mat")]
    pub Mr: SMatrix<f64, 5, 5>,
    /// Cr.
    #[serde(serialize_with = "ser::mat")]
    pub Cr: SMatrix<f64, 5, 5>,
    /// cr = Cr v.
    #[serde(serialize_with = "ser::vec")]
    pub cr: SVector<f64, 5>,
    /// Gr.
    #[serde(serialize_with = "ser::vec")]
    pub Gr: SVector<f64, 5>,
    /// Qr.
    #[serde(serialize_with = "ser::vec")]
    pub Qr: SVector<f64, 5>,
    /// v̇.
    #[serde(serialize_with = "ser::vec")]
    pub vdot: SVector<f64, 5>,
    /// q̈.
    #[serde(serialize_with = "ser::vec")]
    pub qddot: SVector<f64, 6>,
    /// λ.
    #[serde(serialize_with = "ser::one")]
    pub lambda: f64,
    /// `Pᵀ H P` (joint coordinates).
    #[serde(serialize_with = "ser::mat")]
    pub H_joint: SMatrix<f64, 6, 6>,
    /// `Pᵀ G`.
    #[serde(serialize_with = "ser::vec")]
    pub G_joint: SVector<f64, 6>,
    /// `Pᵀ h`.
    #[serde(serialize_with = "ser::vec")]
    pub h_joint: SVector<f64, 6>,
    /// Task-space model.
    #[serde(flatten)]
    pub task: TaskSpace,
}

impl MobileManipulator {
    /// Validates `params`; parametrisation by [`PlatformVelocity::auto`].
    pub fn new(params: MobileManipulatorParams) -> Result<Self> {
        let velocity = PlatformVelocity::auto(params.d);
        Self::with_velocity(params, velocity)
    }

    /// Validates `params` with an explicit parametrisation.
    pub fn with_velocity(
        params: MobileManipulatorParams,
        velocity: PlatformVelocity,
    ) -> Result<Self> {
        params.validate()?;
        velocity.check(params.d)?;
        Ok(MobileManipulator { params, velocity })
    }

    /// `I_m(θ1, θ12)`.
    pub fn capstan_inertia_generic<T: Real>(&self, th1: T, th12: T) -> T {
        let p = &self.params;
        let (s1, s12) = (th1.sin(), th12.sin());
        let r2cm = s1 * p.L1 + s12 * p.L2cm;
        let r2 = s1 * p.L1 + s12 * p.L2;
        s1 * s1 * (p.m1 * (p.k1y.powi(2) + p.L1cm.powi(2)) + p.M1 * p.L1 * p.L1)
            + (s12 * s12 * p.k2y.powi(2) + r2cm * r2cm) * p.m2
            + r2 * r2 * p.M2
            + p.I_c
    }

    /// The task vector `x(q) = [x_B, y_B, x_E − x_B, y_E − y_B, z_E]`.
    pub fn task_generic<T: Real>(&self, q: &[T; 6]) -> [T; 5] {
        let p = &self.params;
        let (phi, phit, th1, th12) = (q[2], q[3], q[4], q[5]);
        let rho = th1.sin() * p.L1 + th12.sin() * p.L2;
        let eta = th1.cos() * p.L1 + th12.cos() * p.L2;
        [
            q[0] + phi.cos() * p.L,
            q[1] + phi.sin() * p.L,
            rho * phit.cos(),
            rho * phit.sin(),
            eta,
        ]
    }

    /// `J = ∂x/∂q` (5×6) in closed form.
    pub fn task_jacobian_generic<T: Real>(&self, q: &[T; 6]) -> [[T; 6]; 5] {
        let p = &self.params;
        let (phi, phit, th1, th12) = (q[2], q[3], q[4], q[5]);
        let rho = th1.sin() * p.L1 + th12.sin() * p.L2;
        let eta = th1.cos() * p.L1 + th12.cos() * p.L2;
        let (z, o) = (T::cst(0.0), T::cst(1.0));
        let (cpt, spt) = (phit.cos(), phit.sin());
        let (a1, a2) = (th1.cos() * p.L1, th12.cos() * p.L2);
        let _ = eta;
        [
            [o, z, phi.sin() * (-p.L), z, z, z],
            [z, o, phi.cos() * p.L, z, z, z],
            [z, z, z, -(rho * spt), a1 * cpt, a2 * cpt],
            [z, z, z, rho * cpt, a1 * spt, a2 * spt],
            [z, z, z, z, th1.sin() * (-p.L1), th12.sin() * (-p.L2)],
        ]
    }

    fn check_state(q: &SVector<f64, 6>, v: &SVector<f64, 5>, u: &SVector<f64, 5>) -> Result<()> {
        check_finite("state.q", q)?;
        check_finite("state.v", v)?;
        check_finite("inputs.u", u)
    }

    /// The task-space core at `(q, v)`: `x, ẋ, J, A, Ȧ, A⁻¹, Hx, B, V` (no manipulability,
    /// no input-dependent terms). Singular A is [`Error::Singular`].
    fn task_core(
        &self,
        q: &SVector<f64, 6>,
        v: &SVector<f64, 5>,
        ct: &lagrange::ConstraintTerms<6, 5>,
        terms: &lagrange::LagrangeTerms<6>,
    ) -> Result<TaskCore> {
        let qa: [f64; 6] = q.as_slice().try_into().expect("length 6");
        let qd: [f64; 6] = ct.qdot.as_slice().try_into().expect("length 6");
        let jr = self.task_jacobian_generic(&qa);
        let j = SMatrix::<f64, 5, 6>::from_fn(|i, k| jr[i][k]);
        let jd_raw = self.task_jacobian_generic(&seed_direction(&qa, &qd));
        let jdot = SMatrix::<f64, 5, 6>::from_fn(|i, k| jd_raw[i][k].du[0]);
        let n = &ct.basis;
        let ndot = &ct.basis_rate;
        let a = j * n;
        let adot = jdot * n + j * ndot;
        let a_inv = a.try_inverse().ok_or_else(|| Error::Singular {
            what: "task Jacobian A = J N_C".into(),
            detail: Some(
                "d + L = 0, ρ = 0 (end effector on the capstan axis) or sin θ2 = 0".into(),
            ),
        })?;
        let cond = a.norm() * a_inv.norm();
        if !cond.is_finite() || cond > 1e13 {
            return Err(Error::Singular {
                what: "task Jacobian A = J N_C".into(),
                detail: Some(format!("condition number {cond:e}")),
            });
        }
        let a_inv_t = a_inv.transpose();
        let h = &terms.mass;
        let mr = n.transpose() * h * n;
        let hx = a_inv_t * mr * a_inv;
        let b = a_inv_t * n.transpose();
        let vm = (h * ndot + terms.coriolis * n - h * n * a_inv * adot) * a_inv;
        Ok(TaskCore {
            x: SVector::from(self.task_generic(&qa)),
            xdot: a * v,
            j,
            a,
            adot,
            hx,
            b,
            vm,
        })
    }

    /// The task-space quantities from a constrained evaluation at `(q, v)`.
    pub fn task_space(
        &self,
        q: &SVector<f64, 6>,
        v: &SVector<f64, 5>,
        e: &ConstrainedEvaluation<6, 5, 5>,
    ) -> Result<TaskSpace> {
        let c = self.task_core(q, v, &e.constraint, &e.terms)?;
        Ok(TaskSpace {
            x: c.x,
            xdot: c.xdot,
            xddot: c.a * e.vdot + c.adot * v,
            J: c.j,
            A: c.a,
            Adot: c.adot,
            Hx: c.hx,
            B: c.b,
            V: c.vm,
            BV: c.b * c.vm,
            BgG: c.b * e.terms.gravity,
            BQ: c.b * e.q_force,
            manipulability_A: manipulability(&to_dmatrix(&c.a))?,
        })
    }

    /// The task-space model a feedback law needs at `(q, v)`: `x`, `ẋ = A v`, `A = J N_C`,
    /// `Hx = A⁻ᵀ Mr A⁻¹`, the Christoffel-consistent `B V`, `B G` and the actuator map
    /// `N_Cᵀ S` (so that `N_Cᵀ S u = Aᵀ τ_x` gives the inputs of a task force τ_x).
    ///
    /// # Errors
    /// [`Error::Singular`] when A is singular or ill-conditioned.
    pub fn task_terms(&self, q: &SVector<f64, 6>, v: &SVector<f64, 5>) -> Result<TaskTerms> {
        let ct = lagrange::constraint_terms(self, q, v);
        let terms = lagrange::lagrange_terms(self, q, &ct.qdot);
        let core = self.task_core(q, v, &ct, &terms)?;
        Ok(TaskTerms {
            x: core.x,
            xdot: core.xdot,
            a: core.a,
            hx: core.hx,
            bv: core.b * core.vm,
            bg: core.b * terms.gravity,
            actuation: ct.basis.transpose() * self.input_matrix(q),
        })
    }

    /// The reduced ODE right-hand side `(q̇, v̇) = (N_C v, Mr⁻¹(Qr − Cr v − Gr))` at `state`.
    pub fn state_derivative(&self, state: &State, u: &SVector<f64, 5>) -> Result<State> {
        check_finite("state.q", &state.q)?;
        check_finite("state.v", &state.v)?;
        check_finite("inputs.u", u)?;
        let (q, v) = lagrange::state_derivative(self, &state.q, &state.v, u)?;
        Ok(State { q, v })
    }

    /// Evaluates every output at `(q, v, u)`.
    pub fn evaluate(
        &self,
        q: &SVector<f64, 6>,
        v: &SVector<f64, 5>,
        u: &SVector<f64, 5>,
    ) -> Result<MobileManipulatorOutputs> {
        Self::check_state(q, v, u)?;
        let e = lagrange::evaluate_constrained(self, q, v, u)?;
        let task = self.task_space(q, v, &e)?;
        let p = joint_to_absolute();
        let pt = p.transpose();
        Ok(MobileManipulatorOutputs {
            H: e.terms.mass,
            C_coriolis: e.terms.coriolis,
            h: e.terms.h,
            G: e.terms.gravity,
            I_m: self.capstan_inertia_generic(q[4], q[5]),
            kinetic_energy: e.terms.kinetic_energy,
            potential_energy: e.terms.potential_energy,
            C: e.constraint.constraint,
            N_C: e.constraint.basis,
            Ndot_C: e.constraint.basis_rate,
            qdot: e.constraint.qdot,
            S: e.input_matrix,
            Q: e.q_force,
            Mr: e.mr,
            Cr: e.cr_matrix,
            cr: e.cr,
            Gr: e.gr,
            Qr: e.qr,
            vdot: e.vdot,
            qddot: e.qddot,
            lambda: e.lambda,
            H_joint: pt * e.terms.mass * p,
            G_joint: pt * e.terms.gravity,
            h_joint: pt * e.terms.h,
            task,
        })
    }

    /// Total energy `½ q̇ᵀ H q̇ + V` at `(q, v)`.
    pub fn energy(&self, q: &SVector<f64, 6>, v: &SVector<f64, 5>) -> f64 {
        let ct = lagrange::constraint_terms(self, q, v);
        let h = lagrange::mass_matrix(self, q);
        let (pot, _) = lagrange::potential_and_gravity(self, q);
        0.5 * ct.qdot.dot(&(h * ct.qdot)) + pot
    }

    /// States `(q, v)` at `times` under constant `u` (DOP853, tolerance `tol`).
    #[allow(clippy::type_complexity)]
    pub fn simulate(
        &self,
        q0: &SVector<f64, 6>,
        v0: &SVector<f64, 5>,
        u: &SVector<f64, 5>,
        times: &[f64],
        tol: f64,
    ) -> Result<Vec<(SVector<f64, 6>, SVector<f64, 5>)>> {
        Self::check_state(q0, v0, u)?;
        super::simulate_reduced(self, q0, v0, u, times, tol)
    }
}

impl LagrangianSystem<6> for MobileManipulator {
    fn mass_matrix_generic<T: Real>(&self, q: &[T; 6]) -> [[T; 6]; 6] {
        let p = &self.params;
        let (phi, phit, th1, th12) = (q[2], q[3], q[4], q[5]);
        let phi1 = phit - phi;
        let (g1, g2, l) = (p.gamma1(), p.gamma2(), p.L);
        let m_arm = p.arm_mass();
        let mt = T::cst(m_arm + p.M_cart);
        let z = T::cst(0.0);
        let rho_g = th1.sin() * g1 + th12.sin() * g2;
        let (c1g, c12g) = (th1.cos() * g1, th12.cos() * g2);
        let (cp, sp, cpt, spt) = (phi.cos(), phi.sin(), phit.cos(), phit.sin());
        let (c_phi1, s_phi1) = (phi1.cos(), phi1.sin());
        let h02 = sp * (-m_arm * l);
        let h03 = -(rho_g * spt);
        let h04 = c1g * cpt;
        let h05 = c12g * cpt;
        let h12 = cp * (m_arm * l);
        let h13 = rho_g * cpt;
        let h14 = c1g * spt;
        let h15 = c12g * spt;
        let h22 = T::cst(p.I_p + m_arm * l * l);
        let h23 = rho_g * c_phi1 * l;
        let h24 = c1g * s_phi1 * l;
        let h25 = c12g * s_phi1 * l;
        let h33 = self.capstan_inertia_generic(th1, th12);
        let h44 = T::cst(p.i11());
        let h45 = (th1 - th12).cos() * (g2 * p.L1);
        let h55 = T::cst(p.i22());
        [
            [mt, z, h02, h03, h04, h05],
            [z, mt, h12, h13, h14, h15],
            [h02, h12, h22, h23, h24, h25],
            [h03, h13, h23, h33, z, z],
            [h04, h14, h24, z, h44, h45],
            [h05, h15, h25, z, h45, h55],
        ]
    }
    fn potential_generic<T: Real>(&self, q: &[T; 6]) -> T {
        let p = &self.params;
        (q[4].cos() * p.gamma1() + q[5].cos() * p.gamma2()) * p.g
    }
}

impl PfaffianSystem<6, 5, 5> for MobileManipulator {
    fn constraint_row_generic<T: Real>(&self, q: &[T; 6]) -> [T; 6] {
        let z = T::cst(0.0);
        [-q[2].sin(), q[2].cos(), T::cst(-self.params.d), z, z, z]
    }
    fn velocity_basis_generic<T: Real>(&self, q: &[T; 6]) -> [[T; 5]; 6] {
        let n = platform_basis(q[2], self.params.d, self.velocity);
        let (z, o) = (T::cst(0.0), T::cst(1.0));
        [
            [n[0][0], n[0][1], z, z, z],
            [n[1][0], n[1][1], z, z, z],
            [n[2][0], n[2][1], z, z, z],
            [z, z, o, z, z],
            [z, z, z, o, z],
            [z, z, z, z, o],
        ]
    }
    fn input_matrix(&self, q: &SVector<f64, 6>) -> SMatrix<f64, 6, 5> {
        let p = &self.params;
        let (s, c) = q[2].sin_cos();
        let k = 1.0 / p.r_w;
        let mut m = SMatrix::<f64, 6, 5>::zeros();
        m[(0, 0)] = c * k;
        m[(0, 1)] = c * k;
        m[(1, 0)] = s * k;
        m[(1, 1)] = s * k;
        m[(2, 0)] = -p.b * k;
        m[(2, 1)] = p.b * k;
        m[(2, 2)] = -1.0;
        m[(3, 2)] = 1.0;
        m[(4, 3)] = 1.0;
        m[(4, 4)] = 1.0;
        m[(5, 4)] = -1.0;
        m
    }
}

/// Task-space tracking controller of m5 (chapter 5.5, corrected): PD+ with computed
/// feed-forward,
/// `τ_x = Hx ẍ_d + (B V) ẋ_d + B G − Kd ė − Kp e` (B V at the actual state), actuators from
/// `N_Cᵀ S u = Aᵀ τ_x`. With a Christoffel-consistent V the closed loop is
/// `Hx ë + (Kd + B V) ė + Kp e = 0` and `W = ½ ėᵀ Hx ė + ½ eᵀ Kp e` has `Ẇ = −ėᵀ Kd ė`.
/// The desired trajectory is `x_d(t) = x_ref + amp ⊙ sin(ω ⊙ t)`.
#[derive(Clone, Debug)]
pub struct TaskController {
    /// Reference offset `x_ref`.
    pub x_ref: SVector<f64, 5>,
    /// Amplitudes.
    pub amp: SVector<f64, 5>,
    /// Angular frequencies ω (rad/s).
    pub omega: SVector<f64, 5>,
    /// Stiffness `Kp` (positive definite).
    pub kp: SMatrix<f64, 5, 5>,
    /// Damping `Kd` (positive definite).
    pub kd: SMatrix<f64, 5, 5>,
}

/// Controller outputs at one instant.
#[derive(Clone, Debug)]
pub struct ControlOutput {
    /// `x_d(t)`.
    pub x_d: SVector<f64, 5>,
    /// `ẋ_d(t)`.
    pub xdot_d: SVector<f64, 5>,
    /// `ẍ_d(t)`.
    pub xddot_d: SVector<f64, 5>,
    /// Task-space force `τ_x`.
    pub tau_x: SVector<f64, 5>,
    /// Actuator torques `u`.
    pub u: SVector<f64, 5>,
    /// `e = x − x_d`.
    pub e: SVector<f64, 5>,
    /// `ė = ẋ − ẋ_d`.
    pub edot: SVector<f64, 5>,
    /// Lyapunov function `W = ½ ėᵀ Hx ė + ½ eᵀ Kp e`.
    pub w: f64,
    /// Dissipation rate `ėᵀ Kd ė`.
    pub dissipation: f64,
}

/// A closed-loop sample: state, error, W and the dissipated energy `∫ ėᵀ Kd ė dt`.
#[derive(Clone, Debug)]
pub struct ClosedLoopSample {
    /// Time.
    pub t: f64,
    /// q.
    pub q: SVector<f64, 6>,
    /// v.
    pub v: SVector<f64, 5>,
    /// e.
    pub e: SVector<f64, 5>,
    /// W.
    pub w: f64,
    /// `∫₀ᵗ ėᵀ Kd ė dt`.
    pub dissipated: f64,
}

impl TaskController {
    /// Checks finiteness and that Kp, Kd are symmetric positive definite.
    pub fn validate(&self) -> Result<()> {
        check_finite("control.x_ref", &self.x_ref)?;
        check_finite("control.amp", &self.amp)?;
        check_finite("control.omega", &self.omega)?;
        for (name, k) in [("control.Kp", &self.kp), ("control.Kd", &self.kd)] {
            crate::error::ensure_finite(name, k.iter())?;
            if (k - k.transpose()).norm() > 1e-12 * (1.0 + k.norm()) || k.cholesky().is_none() {
                return Err(Error::invalid(name, "must be symmetric positive definite"));
            }
        }
        Ok(())
    }

    /// Desired `(x_d, ẋ_d, ẍ_d)` at time t.
    pub fn desired(&self, t: f64) -> (SVector<f64, 5>, SVector<f64, 5>, SVector<f64, 5>) {
        let s = self.omega.map(|w| (w * t).sin());
        let c = self.omega.map(|w| (w * t).cos());
        let x = self.x_ref + self.amp.component_mul(&s);
        let xd = self.amp.component_mul(&self.omega).component_mul(&c);
        let xdd = -self
            .amp
            .component_mul(&self.omega)
            .component_mul(&self.omega)
            .component_mul(&s);
        (x, xd, xdd)
    }

    /// Controller outputs at `(t, q, v)`.
    pub fn control(
        &self,
        model: &MobileManipulator,
        t: f64,
        q: &SVector<f64, 6>,
        v: &SVector<f64, 5>,
    ) -> Result<ControlOutput> {
        let ct = lagrange::constraint_terms(model, q, v);
        let terms = lagrange::lagrange_terms(model, q, &ct.qdot);
        let core = model.task_core(q, v, &ct, &terms)?;
        let (x_d, xdot_d, xddot_d) = self.desired(t);
        let e = core.x - x_d;
        let edot = core.xdot - xdot_d;
        let bv = core.b * core.vm;
        let (tau_x, w) = crate::control::task::pd_plus(
            &core.hx,
            &bv,
            &(core.b * terms.gravity),
            &e,
            &edot,
            &xdot_d,
            &xddot_d,
            &self.kp,
            &self.kd,
        );
        let ns = ct.basis.transpose() * model.input_matrix(q);
        let u = ns
            .lu()
            .solve(&(core.a.transpose() * tau_x))
            .ok_or_else(|| Error::Singular {
                what: "actuator map N_Cᵀ S".into(),
                detail: None,
            })?;
        Ok(ControlOutput {
            x_d,
            xdot_d,
            xddot_d,
            tau_x,
            u,
            e,
            edot,
            w,
            dissipation: edot.dot(&(self.kd * edot)),
        })
    }

    /// Simulates the closed loop from `(q0, v0)` at t = 0 and samples it at `times`
    /// (DOP853 at `rtol = atol = tol`; the dissipated energy is integrated alongside).
    pub fn simulate(
        &self,
        model: &MobileManipulator,
        q0: &SVector<f64, 6>,
        v0: &SVector<f64, 5>,
        times: &[f64],
        tol: f64,
    ) -> Result<Vec<ClosedLoopSample>> {
        self.validate()?;
        check_finite("control.q0", q0)?;
        check_finite("control.v0", v0)?;
        let mut ode = ClosedLoopOde {
            model,
            controller: self,
        };
        let mut x0 = [0.0; 12];
        x0[..6].copy_from_slice(q0.as_slice());
        x0[6..11].copy_from_slice(v0.as_slice());
        let mut dp = crate::ode::Dop853::new(12, super::case_integrator_options(tol))?;
        let rows = dp.solve_at(&mut ode, 0.0, &x0, times)?;
        rows.iter()
            .zip(times)
            .map(|(r, &t)| {
                let q = SVector::<f64, 6>::from_column_slice(&r[..6]);
                let v = SVector::<f64, 5>::from_column_slice(&r[6..11]);
                let c = self.control(model, t, &q, &v)?;
                Ok(ClosedLoopSample {
                    t,
                    q,
                    v,
                    e: c.e,
                    w: c.w,
                    dissipated: r[11],
                })
            })
            .collect()
    }
}

/// The m5 closed loop as an [`crate::ode::OdeSystem`] on `[q; v; ∫ ėᵀKdė]`.
pub struct ClosedLoopOde<'a> {
    /// The model.
    pub model: &'a MobileManipulator,
    /// The controller.
    pub controller: &'a TaskController,
}

impl crate::ode::OdeSystem for ClosedLoopOde<'_> {
    fn dim(&self) -> usize {
        12
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<()> {
        let q = SVector::<f64, 6>::from_column_slice(&x[..6]);
        let v = SVector::<f64, 5>::from_column_slice(&x[6..11]);
        let c = self.controller.control(self.model, t, &q, &v)?;
        let (qd, vd) = lagrange::state_derivative(self.model, &q, &v, &c.u)?;
        dx[..6].copy_from_slice(qd.as_slice());
        dx[6..11].copy_from_slice(vd.as_slice());
        dx[11] = c.dissipation;
        Ok(())
    }
}

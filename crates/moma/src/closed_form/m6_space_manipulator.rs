//! m6 — planar free-floating space manipulator (chapter 5.7, eqs 5.134–5.145), in the
//! corrected form of `docs/chapter.md`.
//!
//! `q = [x0, y0, ψ, θ1, θ2]`: base CM, base attitude, joint angles (θ1 from the base
//! x-axis, θ2 from link 1). Joint 1 sits at `(b0x, b0y)` in the base frame. No gravity and
//! no external wrench: `H q̈ + C_cor q̇ = [0, 0, 0, τ1, τ2]`.
//!
//! The momentum `P = (Hq̇)[0:2]`, `L_O = (Hq̇)[2] + r0 × P` and `L_c = L_O − r_c × P` are
//! conserved. `L_c = I_sys(θ) ψ̇ + h_θ(θ)·θ̇`, with `I_sys = H[2][2] − (r_c − r0) × H[0:2][2]`
//! and `h_θj = H[2][3+j] − (r_c − r0) × H[0:2][3+j]` (the same as
//! `Σ I_i + Σ m_i |r_i − r_c|²` and its joint counterpart: L_c does not depend on the CM
//! velocity). The base rate is `ω = (L_c − h_θ·θ̇)/I_sys`; the chapter's 5.142 read with
//! centroidal inertias is `−((I1+I2)θ̇1 + I2 θ̇2)/(I0+I1+I2)`, which drops the orbital
//! momentum of the links (kept here only as the reference it is compared with).

use super::ad::Real;
use super::lagrange::{self, LagrangianSystem};
use super::{check_finite, finite, positive, ser};
use crate::error::{Error, Result};
use crate::ode::{Dop853, OdeSystem};
use nalgebra::{Matrix2, Matrix3, SMatrix, SVector, Vector2, Vector3};
use serde::{Deserialize, Serialize};

/// `q` (5).
pub type Q = SVector<f64, 5>;

/// Parameters of m6 (SI units; I are centroidal inertias).
#[derive(Clone, Debug, Deserialize, Serialize, PartialEq)]
#[allow(non_snake_case)]
#[serde(deny_unknown_fields)]
pub struct SpaceManipulatorParams {
    /// Base mass.
    pub m0: f64,
    /// Base centroidal inertia.
    pub I0: f64,
    /// Joint-1 x offset in the base frame.
    pub b0x: f64,
    /// Joint-1 y offset in the base frame.
    pub b0y: f64,
    /// Link-1 mass.
    pub m1: f64,
    /// Link-2 mass.
    pub m2: f64,
    /// Link-1 length.
    pub l1: f64,
    /// Link-2 length.
    pub l2: f64,
    /// Joint 1 to link-1 CM.
    pub lc1: f64,
    /// Joint 2 to link-2 CM.
    pub lc2: f64,
    /// Link-1 centroidal inertia.
    pub I1: f64,
    /// Link-2 centroidal inertia.
    pub I2: f64,
}

impl SpaceManipulatorParams {
    /// Checks signs and finiteness.
    pub fn validate(&self) -> Result<()> {
        positive("m0", self.m0)?;
        positive("I0", self.I0)?;
        finite("b0x", self.b0x)?;
        finite("b0y", self.b0y)?;
        positive("m1", self.m1)?;
        positive("m2", self.m2)?;
        positive("l1", self.l1)?;
        positive("l2", self.l2)?;
        finite("lc1", self.lc1)?;
        finite("lc2", self.lc2)?;
        positive("I1", self.I1)?;
        positive("I2", self.I2)
    }

    /// Total mass.
    pub fn total_mass(&self) -> f64 {
        self.m0 + self.m1 + self.m2
    }
}

/// The m6 model.
#[derive(Clone, Debug)]
pub struct SpaceManipulator {
    /// Parameters.
    pub params: SpaceManipulatorParams,
}

/// Positions and position Jacobians (2 × 5 each, as columns) of the three body CMs and
/// the end effector.
struct Kin<T> {
    r: [[T; 2]; 4],
    jac: [[[T; 2]; 5]; 4],
}

/// Every output of m6 (names as in the reference vectors).
#[derive(Clone, Debug, Serialize)]
#[allow(non_snake_case)]
pub struct SpaceManipulatorOutputs {
    /// Mass matrix H.
    #[serde(serialize_with = "ser::mat")]
    pub H: SMatrix<f64, 5, 5>,
    /// Christoffel Coriolis matrix at the zero-momentum velocity.
    #[serde(serialize_with = "ser::mat")]
    pub C_coriolis_zero_momentum: SMatrix<f64, 5, 5>,
    /// `C_cor q̇` at the zero-momentum velocity.
    #[serde(serialize_with = "ser::vec")]
    pub h_zero_momentum: SVector<f64, 5>,
    /// `q̈ = H⁻¹([0, 0, 0, τ] − h)` at the zero-momentum velocity.
    #[serde(serialize_with = "ser::vec")]
    pub qddot_zero_momentum_torque: SVector<f64, 5>,
    /// System CM r_c.
    #[serde(serialize_with = "ser::vec")]
    pub system_cm: Vector2<f64>,
    /// I_sys(θ).
    pub I_sys: f64,
    /// h_θ(θ).
    #[serde(serialize_with = "ser::vec")]
    pub h_theta: Vector2<f64>,
    /// ω = −h_θ·θ̇/I_sys.
    pub omega_zero_momentum: f64,
    /// (ẋ0, ẏ0) for P = 0.
    #[serde(serialize_with = "ser::vec")]
    pub base_velocity_zero_momentum: Vector2<f64>,
    /// The chapter's 5.142 with centroidal inertias (not momentum-consistent).
    pub omega_chapter_5_142: f64,
    /// H[0:3, 0:3].
    #[serde(serialize_with = "ser::mat")]
    pub H_b: Matrix3<f64>,
    /// H[0:3, 3:5].
    #[serde(serialize_with = "ser::mat")]
    pub H_bm: SMatrix<f64, 3, 2>,
    /// ∂(x_E, y_E, α_E)/∂(x0, y0, ψ).
    #[serde(serialize_with = "ser::mat")]
    pub J_b: Matrix3<f64>,
    /// ∂(x_E, y_E, α_E)/∂θ.
    #[serde(serialize_with = "ser::mat")]
    pub J_m: SMatrix<f64, 3, 2>,
    /// Generalized Jacobian J* = J_m − J_b H_b⁻¹ H_bm.
    #[serde(serialize_with = "ser::mat")]
    pub J_star: SMatrix<f64, 3, 2>,
    /// (x_E, y_E, α_E = ψ + θ1 + θ2).
    #[serde(serialize_with = "ser::vec")]
    pub ee_pose: Vector3<f64>,
    /// J* θ̇.
    #[serde(serialize_with = "ser::vec")]
    pub ee_velocity_zero_momentum: Vector3<f64>,
    /// P at the non-zero-momentum velocity.
    #[serde(serialize_with = "ser::vec")]
    pub P_nonzero: Vector2<f64>,
    /// L_O there.
    pub L_O_nonzero: f64,
    /// L_c there.
    pub L_c_nonzero: f64,
    /// ω = (L_c − h_θ·θ̇)/I_sys there.
    pub omega_nonzero: f64,
    /// J* θ̇ + J_b H_b⁻¹ (H q̇)[0:3] there.
    #[serde(serialize_with = "ser::vec")]
    pub ee_velocity_nonzero: Vector3<f64>,
}

/// One sample of a simulated run.
#[derive(Clone, Debug)]
pub struct Sample {
    /// q.
    pub q: Q,
    /// q̇.
    pub qdot: Q,
    /// Linear momentum P.
    pub p: Vector2<f64>,
    /// Angular momentum about the origin L_O.
    pub l_o: f64,
    /// ψ integrated from the exact base rate `(L_c(0) − h_θ θ̇)/I_sys`.
    pub psi_exact: f64,
    /// ψ integrated from the chapter's 5.142.
    pub psi_chapter: f64,
}

fn cross2(a: &[f64; 2], b: &[f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

impl SpaceManipulator {
    /// Validates the parameters.
    pub fn new(params: SpaceManipulatorParams) -> Result<Self> {
        params.validate()?;
        Ok(SpaceManipulator { params })
    }

    fn kin<T: Real>(&self, q: &[T; 5]) -> Kin<T> {
        let p = &self.params;
        let z = T::cst(0.0);
        let one = T::cst(1.0);
        let (x0, y0, psi) = (q[0], q[1], q[2]);
        let a = psi + q[3];
        let c = a + q[4];
        let (cp, sp) = (psi.cos(), psi.sin());
        // R(ψ) b and its derivative ẑ × R b
        let rb = [cp * p.b0x - sp * p.b0y, sp * p.b0x + cp * p.b0y];
        let rbp = [-rb[1], rb[0]];
        let (ca, sa, cc, sc) = (a.cos(), a.sin(), c.cos(), c.sin());
        let j1 = [x0 + rb[0], y0 + rb[1]];
        let j2 = [j1[0] + ca * p.l1, j1[1] + sa * p.l1];
        let r1 = [j1[0] + ca * p.lc1, j1[1] + sa * p.lc1];
        let r2 = [j2[0] + cc * p.lc2, j2[1] + sc * p.lc2];
        let re = [j2[0] + cc * p.l2, j2[1] + sc * p.l2];
        let ea = [-sa, ca];
        let ec = [-sc, cc];
        let col = |d1: f64, d2: f64, lc: f64| -> [[T; 2]; 5] {
            // point J1 + d1 e(a) + (lc along c), with d2 selecting link 2's contribution
            let pa = [ea[0] * d1, ea[1] * d1];
            let pc = [ec[0] * (d2 * lc), ec[1] * (d2 * lc)];
            [
                [one, z],
                [z, one],
                [rbp[0] + pa[0] + pc[0], rbp[1] + pa[1] + pc[1]],
                [pa[0] + pc[0], pa[1] + pc[1]],
                [pc[0], pc[1]],
            ]
        };
        let base = [[one, z], [z, one], [z, z], [z, z], [z, z]];
        Kin {
            r: [[x0, y0], r1, r2, re],
            jac: [
                base,
                col(p.lc1, 0.0, 0.0),
                col(p.l1, 1.0, p.lc2),
                col(p.l1, 1.0, p.l2),
            ],
        }
    }

    /// H(q).
    pub fn mass_matrix(&self, q: &Q) -> SMatrix<f64, 5, 5> {
        lagrange::mass_matrix(self, q)
    }

    /// System CM r_c (m).
    pub fn system_cm(&self, q: &Q) -> Vector2<f64> {
        let p = &self.params;
        let k = self.kin(&to_array(q));
        let m = [p.m0, p.m1, p.m2];
        let mut c = Vector2::zeros();
        for i in 0..3 {
            c += Vector2::new(k.r[i][0], k.r[i][1]) * m[i];
        }
        c / p.total_mass()
    }

    /// `(I_sys, h_θ)` at q (they depend on θ only).
    pub fn momentum_coefficients(&self, q: &Q) -> (f64, Vector2<f64>) {
        let h = self.mass_matrix(q);
        let d = self.system_cm(q) - Vector2::new(q[0], q[1]);
        let d = [d.x, d.y];
        let lc = |j: usize| h[(2, j)] - cross2(&d, &[h[(0, j)], h[(1, j)]]);
        (lc(2), Vector2::new(lc(3), lc(4)))
    }

    /// `(P, L_O, L_c)` at `(q, q̇)`.
    pub fn momentum(&self, q: &Q, qdot: &Q) -> (Vector2<f64>, f64, f64) {
        let hq = self.mass_matrix(q) * qdot;
        let pv = [hq[0], hq[1]];
        let l_o = hq[2] + cross2(&[q[0], q[1]], &pv);
        let rc = self.system_cm(q);
        let l_c = l_o - cross2(&[rc.x, rc.y], &pv);
        (Vector2::new(pv[0], pv[1]), l_o, l_c)
    }

    /// Base rate `ω = (L_c − h_θ·θ̇)/I_sys`.
    pub fn base_rate(&self, q: &Q, theta_dot: &Vector2<f64>, l_c: f64) -> f64 {
        let (i_sys, h_theta) = self.momentum_coefficients(q);
        (l_c - h_theta.dot(theta_dot)) / i_sys
    }

    /// The chapter's 5.142 read with centroidal inertias.
    pub fn base_rate_chapter(&self, theta_dot: &Vector2<f64>) -> f64 {
        let p = &self.params;
        -((p.I1 + p.I2) * theta_dot[0] + p.I2 * theta_dot[1]) / (p.I0 + p.I1 + p.I2)
    }

    /// `(x_E, y_E, α_E)` and its Jacobian (3 × 5).
    pub fn end_effector(&self, q: &Q) -> (Vector3<f64>, SMatrix<f64, 3, 5>) {
        let k = self.kin(&to_array(q));
        let mut j = SMatrix::<f64, 3, 5>::zeros();
        for c in 0..5 {
            j[(0, c)] = k.jac[3][c][0];
            j[(1, c)] = k.jac[3][c][1];
        }
        j[(2, 2)] = 1.0;
        j[(2, 3)] = 1.0;
        j[(2, 4)] = 1.0;
        (Vector3::new(k.r[3][0], k.r[3][1], q[2] + q[3] + q[4]), j)
    }

    /// The generalized-Jacobian blocks `(H_b, H_bm, J_b, J_m, J*)` at q.
    #[allow(clippy::type_complexity)]
    pub fn generalized_jacobian(
        &self,
        q: &Q,
    ) -> Result<(
        Matrix3<f64>,
        SMatrix<f64, 3, 2>,
        Matrix3<f64>,
        SMatrix<f64, 3, 2>,
        SMatrix<f64, 3, 2>,
    )> {
        let h = self.mass_matrix(q);
        let hb: Matrix3<f64> = h.fixed_view::<3, 3>(0, 0).into_owned();
        let hbm: SMatrix<f64, 3, 2> = h.fixed_view::<3, 2>(0, 3).into_owned();
        let (_, j) = self.end_effector(q);
        let jb: Matrix3<f64> = j.fixed_view::<3, 3>(0, 0).into_owned();
        let jm: SMatrix<f64, 3, 2> = j.fixed_view::<3, 2>(0, 3).into_owned();
        let chol = hb.cholesky().ok_or_else(|| Error::Singular {
            what: "base block H_b".into(),
            detail: None,
        })?;
        let js = jm - jb * chol.solve(&hbm);
        Ok((hb, hbm, jb, jm, js))
    }

    /// det of the position rows of J* and of the fixed-base Jacobian J_m (dynamic
    /// singularities: the first is zero where the second is not).
    pub fn position_determinants(&self, q: &Q) -> Result<(f64, f64)> {
        let (_, _, _, jm, js) = self.generalized_jacobian(q)?;
        let d = |m: &SMatrix<f64, 3, 2>| {
            Matrix2::new(m[(0, 0)], m[(0, 1)], m[(1, 0)], m[(1, 1)]).determinant()
        };
        Ok((d(&js), d(&jm)))
    }

    /// `q̈ = H⁻¹([0, 0, 0, τ] − C_cor q̇)`.
    pub fn forward_dynamics(&self, q: &Q, qdot: &Q, torque: &Vector2<f64>) -> Result<Q> {
        let t = lagrange::lagrange_terms(self, q, qdot);
        let u = Q::from([0.0, 0.0, 0.0, torque[0], torque[1]]);
        lagrange::spd_solve(&t.mass, &(u - t.h), "mass matrix H")
    }

    /// Every output at `q`, joint rates θ̇, the zero- and non-zero-momentum velocities and
    /// the torque.
    pub fn evaluate(
        &self,
        q: &Q,
        theta_dot: &Vector2<f64>,
        qdot_zero: &Q,
        qdot_nonzero: &Q,
        torque: &Vector2<f64>,
    ) -> Result<SpaceManipulatorOutputs> {
        check_finite("state.q", q)?;
        check_finite("state.theta_dot", theta_dot)?;
        check_finite("state.qdot_zero_momentum", qdot_zero)?;
        check_finite("state.qdot_nonzero_momentum", qdot_nonzero)?;
        check_finite("inputs.torque", torque)?;
        let t = lagrange::lagrange_terms(self, q, qdot_zero);
        let u = Q::from([0.0, 0.0, 0.0, torque[0], torque[1]]);
        let qddot = lagrange::spd_solve(&t.mass, &(u - t.h), "mass matrix H")?;
        let rc = self.system_cm(q);
        let (i_sys, h_theta) = self.momentum_coefficients(q);
        let omega0 = -h_theta.dot(theta_dot) / i_sys;
        let h = t.mass;
        let w = [omega0, theta_dot[0], theta_dot[1]];
        let m = self.params.total_mass();
        let mut vb = Vector2::zeros();
        for (k, wk) in w.iter().enumerate() {
            vb -= Vector2::new(h[(0, 2 + k)], h[(1, 2 + k)]) * (*wk / m);
        }
        let (hb, hbm, jb, jm, js) = self.generalized_jacobian(q)?;
        let (ee_pose, _) = self.end_effector(q);
        let (p_nz, l_o, l_c) = self.momentum(q, qdot_nonzero);
        let th_nz = Vector2::new(qdot_nonzero[3], qdot_nonzero[4]);
        let hq = h * qdot_nonzero;
        let drift = jb
            * hb.cholesky()
                .expect("checked in generalized_jacobian")
                .solve(&Vector3::new(hq[0], hq[1], hq[2]));
        Ok(SpaceManipulatorOutputs {
            H: h,
            C_coriolis_zero_momentum: t.coriolis,
            h_zero_momentum: t.h,
            qddot_zero_momentum_torque: qddot,
            system_cm: rc,
            I_sys: i_sys,
            h_theta,
            omega_zero_momentum: omega0,
            base_velocity_zero_momentum: vb,
            omega_chapter_5_142: self.base_rate_chapter(theta_dot),
            H_b: hb,
            H_bm: hbm,
            J_b: jb,
            J_m: jm,
            J_star: js,
            ee_pose,
            ee_velocity_zero_momentum: js * theta_dot,
            P_nonzero: p_nz,
            L_O_nonzero: l_o,
            L_c_nonzero: l_c,
            omega_nonzero: (l_c - h_theta.dot(&th_nz)) / i_sys,
            ee_velocity_nonzero: js * th_nz + drift,
        })
    }

    /// Simulates from `(q0, q̇0)` under a constant torque (DOP853, `rtol = atol = tol`),
    /// with ψ also integrated from the exact base rate and from the chapter's formula.
    pub fn simulate(
        &self,
        q0: &Q,
        qdot0: &Q,
        torque: &Vector2<f64>,
        times: &[f64],
        tol: f64,
    ) -> Result<Vec<Sample>> {
        check_finite("state.q", q0)?;
        check_finite("qdot0", qdot0)?;
        check_finite("torque", torque)?;
        let (_, _, l_c0) = self.momentum(q0, qdot0);
        let mut ode = SpaceOde {
            model: self,
            torque: *torque,
            l_c0,
        };
        let mut x0 = [0.0; 12];
        x0[..5].copy_from_slice(q0.as_slice());
        x0[5..10].copy_from_slice(qdot0.as_slice());
        x0[10] = q0[2];
        x0[11] = q0[2];
        let mut dp = Dop853::new(12, super::case_integrator_options(tol))?;
        let rows = dp.solve_at(&mut ode, 0.0, &x0, times)?;
        Ok(rows
            .iter()
            .map(|r| {
                let q = Q::from_column_slice(&r[..5]);
                let qdot = Q::from_column_slice(&r[5..10]);
                let (p, l_o, _) = self.momentum(&q, &qdot);
                Sample {
                    q,
                    qdot,
                    p,
                    l_o,
                    psi_exact: r[10],
                    psi_chapter: r[11],
                }
            })
            .collect())
    }

    /// Net base rotation Δψ after the closed joint loop
    /// `θ(t) = θ0 + [a1 (1 − cos 2πt/T), a2 sin 2πt/T]`, t ∈ [0, T], at zero momentum.
    pub fn joint_loop_rotation(
        &self,
        theta0: &Vector2<f64>,
        amplitude: &Vector2<f64>,
        period: f64,
        tol: f64,
    ) -> Result<f64> {
        check_finite("theta0", theta0)?;
        check_finite("joint_loop.amplitude", amplitude)?;
        if !(period.is_finite() && period > 0.0) {
            return Err(Error::invalid(
                "joint_loop.period",
                format!("must be positive, got {period}"),
            ));
        }
        let mut ode = LoopOde {
            model: self,
            theta0: *theta0,
            amplitude: *amplitude,
            period,
        };
        let mut dp = Dop853::new(1, super::case_integrator_options(tol))?;
        let rows = dp.solve_at(&mut ode, 0.0, &[0.0], &[period])?;
        Ok(rows[0][0])
    }
}

fn to_array(q: &Q) -> [f64; 5] {
    [q[0], q[1], q[2], q[3], q[4]]
}

struct SpaceOde<'a> {
    model: &'a SpaceManipulator,
    torque: Vector2<f64>,
    l_c0: f64,
}

impl OdeSystem for SpaceOde<'_> {
    fn dim(&self) -> usize {
        12
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<()> {
        let q = Q::from_column_slice(&x[..5]);
        let qd = Q::from_column_slice(&x[5..10]);
        let qdd = self
            .model
            .forward_dynamics(&q, &qd, &self.torque)
            .map_err(|e| e.singular_at_time(t))?;
        let th = Vector2::new(qd[3], qd[4]);
        dx[..5].copy_from_slice(qd.as_slice());
        dx[5..10].copy_from_slice(qdd.as_slice());
        dx[10] = self.model.base_rate(&q, &th, self.l_c0);
        dx[11] = self.model.base_rate_chapter(&th);
        Ok(())
    }
}

struct LoopOde<'a> {
    model: &'a SpaceManipulator,
    theta0: Vector2<f64>,
    amplitude: Vector2<f64>,
    period: f64,
}

impl OdeSystem for LoopOde<'_> {
    fn dim(&self) -> usize {
        1
    }
    fn rhs(&mut self, t: f64, _x: &[f64], dx: &mut [f64]) -> Result<()> {
        let w = 2.0 * std::f64::consts::PI / self.period;
        let (s, c) = (w * t).sin_cos();
        let a = self.amplitude;
        let th = self.theta0 + Vector2::new(a[0] * (1.0 - c), a[1] * s);
        let thd = Vector2::new(a[0] * w * s, a[1] * w * c);
        let q = Q::from([0.0, 0.0, 0.0, th[0], th[1]]);
        dx[0] = self.model.base_rate(&q, &thd, 0.0);
        Ok(())
    }
}

impl LagrangianSystem<5> for SpaceManipulator {
    fn mass_matrix_generic<T: Real>(&self, q: &[T; 5]) -> [[T; 5]; 5] {
        let p = &self.params;
        let k = self.kin(q);
        let m = [p.m0, p.m1, p.m2];
        // angular-velocity rows of the three bodies: ψ̇, ψ̇+θ̇1, ψ̇+θ̇1+θ̇2
        let w: [[f64; 5]; 3] = [
            [0.0, 0.0, 1.0, 0.0, 0.0],
            [0.0, 0.0, 1.0, 1.0, 0.0],
            [0.0, 0.0, 1.0, 1.0, 1.0],
        ];
        let inertia = [p.I0, p.I1, p.I2];
        let mut h = [[T::cst(0.0); 5]; 5];
        for i in 0..5 {
            for j in 0..5 {
                let mut s = T::cst(0.0);
                for b in 0..3 {
                    let (a, c) = (k.jac[b][i], k.jac[b][j]);
                    s = s + (a[0] * c[0] + a[1] * c[1]) * m[b];
                    s = s + inertia[b] * w[b][i] * w[b][j];
                }
                h[i][j] = s;
            }
        }
        h
    }
    fn potential_generic<T: Real>(&self, _q: &[T; 5]) -> T {
        T::cst(0.0)
    }
}

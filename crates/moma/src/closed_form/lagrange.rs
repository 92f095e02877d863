//! The generic Euler–Lagrange machinery shared by the closed-form models.
//!
//! A model supplies its mass matrix `H(q)` and potential energy `V(q)` (and, for a
//! non-holonomic platform, its constraint row `C(q)`, velocity basis `N_C(q)` and actuator
//! map `S(q)`) as closed-form expressions generic over [`Real`]. This module derives
//! everything else from them exactly (forward-mode differentiation, no finite
//! differences):
//!
//! * `C_cor[i][j] = Σ_k ½(∂H_ij/∂q_k + ∂H_ik/∂q_j − ∂H_jk/∂q_i) q̇_k` (Christoffel),
//! * `h = C_cor q̇`, `G = ∂V/∂q`,
//! * `Ṅ_C = Σ_k ∂N_C/∂q_k q̇_k`, `Ċ q̇`,
//! * the reduced model `Mr v̇ + Cr v + Gr = Qr` and the multiplier λ.
//!
//! The sign convention is `H q̈ + h + G = Q − Cᵀλ`, `C q̇ = 0`, `q̇ = N_C v`.

use super::ad::{Dual, Real, seed_all, seed_direction};
use crate::error::{Error, Result};
use nalgebra::{Cholesky, SMatrix, SVector};

/// A mechanical system given by its mass matrix and potential energy in closed form.
pub trait LagrangianSystem<const N: usize> {
    /// Mass matrix `H(q)` (symmetric, full `N×N` array, row-major).
    fn mass_matrix_generic<T: Real>(&self, q: &[T; N]) -> [[T; N]; N];
    /// Potential energy `V(q)` (gravity included).
    fn potential_generic<T: Real>(&self, q: &[T; N]) -> T;
}

/// A Lagrangian system with one Pfaffian (no-side-slip) constraint `C(q) q̇ = 0`,
/// an admissible-velocity basis `q̇ = N_C(q) v` and an actuator map `Q = S(q) u`.
pub trait PfaffianSystem<const N: usize, const NV: usize, const NU: usize>:
    LagrangianSystem<N>
{
    /// The constraint row `C(q)` (1×N).
    fn constraint_row_generic<T: Real>(&self, q: &[T; N]) -> [T; N];
    /// The velocity basis `N_C(q)` (N×NV), with `C N_C = 0`.
    fn velocity_basis_generic<T: Real>(&self, q: &[T; N]) -> [[T; NV]; N];
    /// The actuator map `S(q)` (N×NU).
    fn input_matrix(&self, q: &SVector<f64, N>) -> SMatrix<f64, N, NU>;
}

fn to_mat<const R: usize, const C: usize>(a: &[[f64; C]; R]) -> SMatrix<f64, R, C> {
    SMatrix::from_fn(|i, j| a[i][j])
}

/// `H(q)`.
pub fn mass_matrix<S: LagrangianSystem<N>, const N: usize>(
    sys: &S,
    q: &SVector<f64, N>,
) -> SMatrix<f64, N, N> {
    let qa: [f64; N] = q.as_slice().try_into().expect("static length");
    to_mat(&sys.mass_matrix_generic(&qa))
}

/// `H(q)` and its partial derivatives `∂H/∂q_k`, k = 0..N.
pub fn mass_matrix_partials<S: LagrangianSystem<N>, const N: usize>(
    sys: &S,
    q: &SVector<f64, N>,
) -> (SMatrix<f64, N, N>, [SMatrix<f64, N, N>; N]) {
    let qa: [f64; N] = q.as_slice().try_into().expect("static length");
    let hd = sys.mass_matrix_generic::<Dual<N>>(&seed_all(&qa));
    let h = SMatrix::from_fn(|i, j| hd[i][j].re);
    let dh = std::array::from_fn(|k| SMatrix::from_fn(|i, j| hd[i][j].du[k]));
    (h, dh)
}

/// `Ḣ = Σ_k ∂H/∂q_k q̇_k`.
pub fn mass_matrix_rate<S: LagrangianSystem<N>, const N: usize>(
    sys: &S,
    q: &SVector<f64, N>,
    qdot: &SVector<f64, N>,
) -> SMatrix<f64, N, N> {
    let qa: [f64; N] = q.as_slice().try_into().expect("static length");
    let qd: [f64; N] = qdot.as_slice().try_into().expect("static length");
    let hd = sys.mass_matrix_generic::<Dual<1>>(&seed_direction(&qa, &qd));
    SMatrix::from_fn(|i, j| hd[i][j].du[0])
}

/// Christoffel Coriolis matrix `C_cor(q, q̇)` from the partials `∂H/∂q_k`.
#[doc(alias = "C_cor")]
pub fn christoffel_coriolis<const N: usize>(
    dh: &[SMatrix<f64, N, N>; N],
    qdot: &SVector<f64, N>,
) -> SMatrix<f64, N, N> {
    SMatrix::from_fn(|i, j| {
        let mut s = 0.0;
        for k in 0..N {
            s += (dh[k][(i, j)] + dh[j][(i, k)] - dh[i][(j, k)]) * qdot[k];
        }
        0.5 * s
    })
}

/// Potential energy `V(q)` and gravity vector `G = ∂V/∂q`.
pub fn potential_and_gravity<S: LagrangianSystem<N>, const N: usize>(
    sys: &S,
    q: &SVector<f64, N>,
) -> (f64, SVector<f64, N>) {
    let qa: [f64; N] = q.as_slice().try_into().expect("static length");
    let v = sys.potential_generic::<Dual<N>>(&seed_all(&qa));
    (v.re, SVector::from_fn(|k, _| v.du[k]))
}

/// Unconstrained dynamics terms at `(q, q̇)`.
#[derive(Clone, Debug)]
pub struct LagrangeTerms<const N: usize> {
    /// Mass matrix H.
    pub mass: SMatrix<f64, N, N>,
    /// Christoffel Coriolis matrix C_cor.
    pub coriolis: SMatrix<f64, N, N>,
    /// Velocity term h = C_cor q̇.
    pub h: SVector<f64, N>,
    /// Gravity term G = ∂V/∂q.
    pub gravity: SVector<f64, N>,
    /// Kinetic energy ½ q̇ᵀ H q̇.
    pub kinetic_energy: f64,
    /// Potential energy V.
    pub potential_energy: f64,
}

/// Evaluates H, C_cor, h, G and the energies.
pub fn lagrange_terms<S: LagrangianSystem<N>, const N: usize>(
    sys: &S,
    q: &SVector<f64, N>,
    qdot: &SVector<f64, N>,
) -> LagrangeTerms<N> {
    let (mass, dh) = mass_matrix_partials(sys, q);
    let coriolis = christoffel_coriolis(&dh, qdot);
    let h = coriolis * qdot;
    let (potential_energy, gravity) = potential_and_gravity(sys, q);
    let kinetic_energy = 0.5 * qdot.dot(&(mass * qdot));
    LagrangeTerms {
        mass,
        coriolis,
        h,
        gravity,
        kinetic_energy,
        potential_energy,
    }
}

/// Solves `A x = b` for a symmetric positive-definite `A`, reporting singularity.
pub fn spd_solve<const N: usize>(
    a: &SMatrix<f64, N, N>,
    b: &SVector<f64, N>,
    what: &str,
) -> Result<SVector<f64, N>> {
    let chol = Cholesky::new(*a).ok_or_else(|| Error::Singular {
        what: what.to_string(),
        detail: Some("not positive definite".into()),
    })?;
    if !b.iter().all(|v| v.is_finite()) {
        return Err(Error::Singular {
            what: what.to_string(),
            detail: Some(
                "right-hand side not finite (the inputs or the state overflow f64)".into(),
            ),
        });
    }
    let x = chol.solve(b);
    if x.iter().all(|v| v.is_finite()) {
        Ok(x)
    } else {
        Err(Error::Singular {
            what: what.to_string(),
            detail: Some(
                "solution not finite (a near-singular matrix, or inputs too large for f64)".into(),
            ),
        })
    }
}

/// Constraint row, basis, its rate and `Ċ q̇` at `(q, v)`.
#[derive(Clone, Debug)]
pub struct ConstraintTerms<const N: usize, const NV: usize> {
    /// C(q) (1×N).
    pub constraint: SMatrix<f64, 1, N>,
    /// N_C(q).
    pub basis: SMatrix<f64, N, NV>,
    /// Ṅ_C(q, q̇).
    pub basis_rate: SMatrix<f64, N, NV>,
    /// q̇ = N_C v.
    pub qdot: SVector<f64, N>,
    /// Ċ q̇.
    pub constraint_rate_qdot: f64,
}

/// Evaluates the constraint quantities of a Pfaffian system.
pub fn constraint_terms<S, const N: usize, const NV: usize, const NU: usize>(
    sys: &S,
    q: &SVector<f64, N>,
    v: &SVector<f64, NV>,
) -> ConstraintTerms<N, NV>
where
    S: PfaffianSystem<N, NV, NU>,
{
    let qa: [f64; N] = q.as_slice().try_into().expect("static length");
    let basis = to_mat(&sys.velocity_basis_generic(&qa));
    let constraint = SMatrix::<f64, 1, N>::from_fn(|_, j| sys.constraint_row_generic(&qa)[j]);
    let qdot = basis * v;
    let qd: [f64; N] = qdot.as_slice().try_into().expect("static length");
    let seeded = seed_direction(&qa, &qd);
    let nd = sys.velocity_basis_generic::<Dual<1>>(&seeded);
    let basis_rate = SMatrix::from_fn(|i, j| nd[i][j].du[0]);
    let cd = sys.constraint_row_generic::<Dual<1>>(&seeded);
    let constraint_rate_qdot = (0..N).map(|j| cd[j].du[0] * qd[j]).sum();
    ConstraintTerms {
        constraint,
        basis,
        basis_rate,
        qdot,
        constraint_rate_qdot,
    }
}

/// Every output of a constrained model at `(q, v, u)`.
#[derive(Clone, Debug)]
pub struct ConstrainedEvaluation<const N: usize, const NV: usize, const NU: usize> {
    /// Constraint quantities.
    pub constraint: ConstraintTerms<N, NV>,
    /// Unconstrained dynamics terms at q̇ = N_C v.
    pub terms: LagrangeTerms<N>,
    /// Actuator map S.
    pub input_matrix: SMatrix<f64, N, NU>,
    /// Generalised input force Q = S u.
    pub q_force: SVector<f64, N>,
    /// Reduced mass matrix Mr = N_Cᵀ H N_C.
    pub mr: SMatrix<f64, NV, NV>,
    /// Reduced velocity matrix Cr = N_Cᵀ (H Ṅ_C + C_cor N_C).
    pub cr_matrix: SMatrix<f64, NV, NV>,
    /// cr = Cr v.
    pub cr: SVector<f64, NV>,
    /// Gr = N_Cᵀ G.
    pub gr: SVector<f64, NV>,
    /// Qr = N_Cᵀ Q.
    pub qr: SVector<f64, NV>,
    /// v̇ = Mr⁻¹ (Qr − Cr v − Gr).
    pub vdot: SVector<f64, NV>,
    /// q̈ = N_C v̇ + Ṅ_C v.
    pub qddot: SVector<f64, N>,
    /// Lagrange multiplier λ.
    pub lambda: f64,
    /// Constraint generalised force −Cᵀ λ.
    pub constraint_force: SVector<f64, N>,
}

/// Evaluates the full constrained model and its λ-free reduced form.
///
/// λ is recovered from the full equation as the least-squares multiplier
/// `λ = (C Cᵀ)⁻¹ C (Q − h − G − H q̈)`, which equals
/// `(C H⁻¹ Cᵀ)⁻¹ (C H⁻¹ (Q − h − G) + Ċ q̇)` but stays defined when H itself is singular
/// (e.g. m5 with `I_c = 0` and a vertical arm).
pub fn evaluate_constrained<S, const N: usize, const NV: usize, const NU: usize>(
    sys: &S,
    q: &SVector<f64, N>,
    v: &SVector<f64, NV>,
    u: &SVector<f64, NU>,
) -> Result<ConstrainedEvaluation<N, NV, NU>>
where
    S: PfaffianSystem<N, NV, NU>,
{
    let constraint = constraint_terms(sys, q, v);
    let terms = lagrange_terms(sys, q, &constraint.qdot);
    let input_matrix = sys.input_matrix(q);
    let q_force = input_matrix * u;
    let n = &constraint.basis;
    let nt = n.transpose();
    let mr = nt * terms.mass * n;
    let cr_matrix = nt * (terms.mass * constraint.basis_rate + terms.coriolis * n);
    let cr = cr_matrix * v;
    let gr = nt * terms.gravity;
    let qr = nt * q_force;
    let vdot = spd_solve(&mr, &(qr - cr - gr), "reduced mass matrix Mr")?;
    let qddot = n * vdot + constraint.basis_rate * v;
    let residual = q_force - terms.h - terms.gravity - terms.mass * qddot;
    let c = &constraint.constraint;
    let cct = (c * c.transpose())[(0, 0)];
    let lambda = (c * residual)[(0, 0)] / cct;
    let constraint_force = -c.transpose() * lambda;
    Ok(ConstrainedEvaluation {
        constraint,
        terms,
        input_matrix,
        q_force,
        mr,
        cr_matrix,
        cr,
        gr,
        qr,
        vdot,
        qddot,
        lambda,
        constraint_force,
    })
}

/// The state derivative `(q̇, v̇)` of a closed-form model: `q̇ = N_C v` and the reduced
/// forward dynamics `v̇ = Mr⁻¹(Qr − Cr v − Gr)` (the hot path of simulation: no
/// allocation). The general wheeled model's counterpart is
/// [`crate::mobile::reduced_forward_dynamics`].
#[doc(alias = "reduced_forward_dynamics")]
pub fn state_derivative<S, const N: usize, const NV: usize, const NU: usize>(
    sys: &S,
    q: &SVector<f64, N>,
    v: &SVector<f64, NV>,
    u: &SVector<f64, NU>,
) -> Result<(SVector<f64, N>, SVector<f64, NV>)>
where
    S: PfaffianSystem<N, NV, NU>,
{
    let ct = constraint_terms(sys, q, v);
    let (mass, dh) = mass_matrix_partials(sys, q);
    // h = C_cor q̇ = Σ_jk (∂_k H_ij − ½ ∂_i H_jk) q̇_j q̇_k
    let qd = &ct.qdot;
    let mut hdot_qd = SVector::<f64, N>::zeros();
    let mut grad_t = SVector::<f64, N>::zeros();
    for k in 0..N {
        hdot_qd += dh[k] * qd * qd[k];
    }
    for i in 0..N {
        grad_t[i] = qd.dot(&(dh[i] * qd));
    }
    let h = hdot_qd - grad_t * 0.5;
    let (_, g) = potential_and_gravity(sys, q);
    let qf = sys.input_matrix(q) * u;
    let n = &ct.basis;
    let nt = n.transpose();
    let mr = nt * mass * n;
    let rhs = nt * (qf - h - g - mass * (ct.basis_rate * v));
    let vdot = spd_solve(&mr, &rhs, "reduced mass matrix Mr")?;
    Ok((ct.qdot, vdot))
}

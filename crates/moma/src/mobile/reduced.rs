//! Reduced (constraint-eliminated) dynamics of a Pfaffian-constrained system.
//!
//! With `H q̈ + h + G = Q − Cᵀλ`, `C q̇ = 0` and the admissible velocities
//! `q̇ = N_C v` (`C N_C = 0`), premultiplying by `N_Cᵀ` removes λ:
//!
//! ```text
//! Mr v̇ + Cr v + Gr = Qr,   Mr = N_Cᵀ H N_C,  Cr = N_Cᵀ(H Ṅ_C + C_cor N_C),
//!                          Gr = N_Cᵀ G,      Qr = N_Cᵀ Q,     q̈ = N_C v̇ + Ṅ_C v.
//! ```
//!
//! Only the product `cr = Cr v = N_Cᵀ(H Ṅ_C v + h)` (with `h = C_cor q̇`) is needed for
//! forward dynamics, so [`ReducedDynamics::compute`] never forms the Coriolis matrix;
//! [`ReducedDynamics::compute_coriolis`] adds the full `Cr` when it is wanted.
//!
//! The multipliers follow from the full equation once `q̈` is known:
//! `Cᵀλ = Q − G − h − H q̈`, solved in the least-squares sense
//! `λ = (C Cᵀ)⁻¹ C (Q − G − h − H q̈)`; this equals the DAE formula
//! `λ = (C H⁻¹ Cᵀ)⁻¹ (C H⁻¹ (Q − h − G) + Ċ q̇)` (see [`lagrange_multipliers_dae`]) and
//! costs no inverse of H. The constraint generalised force is `−Cᵀλ`.
//!
//! Every buffer is allocated in [`ReducedDynamics::new`]; the `compute*` methods do not
//! allocate.

use nalgebra::{DMatrix, DVector};

use crate::error::{Error, Result};
use crate::linalg::{cholesky_in_place, cholesky_solve};

/// Relative pivot tolerance of the Cholesky factorisations of Mr and C H⁻¹ Cᵀ: a pivot
/// not above `PIVOT_TOL` times the largest diagonal entry counts as singular.
pub(crate) const PIVOT_TOL: f64 = 1e-14;

/// Joint-space terms of `H q̈ + h + G = Q − Cᵀλ` at one state, borrowed from wherever they
/// were computed (the rigid-body core or a closed-form model).
#[derive(Debug, Clone, Copy)]
pub struct JointSpaceTerms<'a> {
    /// Mass matrix H (n×n), symmetric positive definite.
    pub mass_matrix: &'a DMatrix<f64>,
    /// Velocity-product terms h = C_cor(q, q̇) q̇ (n), gravity excluded.
    pub velocity_terms: &'a DVector<f64>,
    /// Gravity generalised force G = ∂V/∂q (n).
    pub gravity: &'a DVector<f64>,
    /// Applied generalised force Q (n).
    pub force: &'a DVector<f64>,
}

/// Reduced dynamics `Mr v̇ + Cr v + Gr = Qr` with its workspace.
#[doc(alias = "Mr")]
#[doc(alias = "reduced_dynamics")]
#[derive(Debug, Clone)]
pub struct ReducedDynamics {
    n: usize,
    r: usize,
    k: usize,
    /// Reduced mass matrix Mr = N_Cᵀ H N_C (r×r).
    pub mass_matrix: DMatrix<f64>,
    /// Reduced Coriolis matrix Cr = N_Cᵀ(H Ṅ_C + C_cor N_C) (r×r); filled only by
    /// [`ReducedDynamics::compute_coriolis`].
    pub coriolis: DMatrix<f64>,
    /// Reduced velocity terms cr = Cr v = N_Cᵀ(H Ṅ_C v + h) (r).
    pub velocity_terms: DVector<f64>,
    /// Reduced gravity Gr = N_Cᵀ G (r).
    pub gravity: DVector<f64>,
    /// Reduced applied force Qr = N_Cᵀ Q (r).
    pub force: DVector<f64>,
    /// Reduced acceleration v̇ (r).
    pub vdot: DVector<f64>,
    /// Full acceleration q̈ = N_C v̇ + Ṅ_C v (n).
    pub qddot: DVector<f64>,
    /// Lagrange multipliers λ (k), filled by [`ReducedDynamics::compute_multipliers`].
    pub lambda: DVector<f64>,
    /// Constraint generalised force −Cᵀλ (n).
    pub constraint_force: DVector<f64>,
    /// Cholesky factor of Mr (lower triangle), valid after `compute`.
    chol: DMatrix<f64>,
    hn: DMatrix<f64>,
    nd_v: DVector<f64>,
    tmp_n: DVector<f64>,
    tmp_r: DVector<f64>,
    cct: DMatrix<f64>,
    tmp_k: DVector<f64>,
}

impl ReducedDynamics {
    /// Workspace for `n` coordinates, `r` reduced velocities and `k` constraints.
    pub fn new(n: usize, r: usize, k: usize) -> Self {
        Self {
            n,
            r,
            k,
            mass_matrix: DMatrix::zeros(r, r),
            coriolis: DMatrix::zeros(r, r),
            velocity_terms: DVector::zeros(r),
            gravity: DVector::zeros(r),
            force: DVector::zeros(r),
            vdot: DVector::zeros(r),
            qddot: DVector::zeros(n),
            lambda: DVector::zeros(k),
            constraint_force: DVector::zeros(n),
            chol: DMatrix::zeros(r, r),
            hn: DMatrix::zeros(n, r),
            nd_v: DVector::zeros(n),
            tmp_n: DVector::zeros(n),
            tmp_r: DVector::zeros(r),
            cct: DMatrix::zeros(k, k),
            tmp_k: DVector::zeros(k),
        }
    }

    /// `(n, r, k)`: coordinates, reduced velocities, constraints.
    pub fn dims(&self) -> (usize, usize, usize) {
        (self.n, self.r, self.k)
    }

    /// Computes Mr, cr, Gr, Qr, the reduced forward dynamics v̇ and q̈ for the basis
    /// `n_c` (n×r), its rate `n_c_dot` (n×r) and the reduced velocity `v` (r).
    ///
    /// Reports [`Error::Singular`] if Mr is not positive definite (e.g. N_C loses rank).
    ///
    /// # Panics
    /// On dimension mismatch.
    pub fn compute(
        &mut self,
        terms: &JointSpaceTerms<'_>,
        n_c: &DMatrix<f64>,
        n_c_dot: &DMatrix<f64>,
        v: &DVector<f64>,
    ) -> Result<&DVector<f64>> {
        let (n, r) = (self.n, self.r);
        assert_eq!(terms.mass_matrix.shape(), (n, n), "H shape");
        assert_eq!(n_c.shape(), (n, r), "N_C shape");
        assert_eq!(n_c_dot.shape(), (n, r), "Ṅ_C shape");
        assert_eq!(v.len(), r, "v length");
        // Mr = N_Cᵀ (H N_C).
        terms.mass_matrix.mul_to(n_c, &mut self.hn);
        n_c.tr_mul_to(&self.hn, &mut self.mass_matrix);
        symmetrize(&mut self.mass_matrix);
        // cr = N_Cᵀ (H Ṅ_C v + h).
        n_c_dot.mul_to(v, &mut self.nd_v);
        self.tmp_n.copy_from(terms.velocity_terms);
        self.tmp_n.gemv(1.0, terms.mass_matrix, &self.nd_v, 1.0);
        n_c.tr_mul_to(&self.tmp_n, &mut self.velocity_terms);
        n_c.tr_mul_to(terms.gravity, &mut self.gravity);
        n_c.tr_mul_to(terms.force, &mut self.force);
        self.solve_reduced()?;
        // q̈ = N_C v̇ + Ṅ_C v.
        self.qddot.copy_from(&self.nd_v);
        self.qddot.gemv(1.0, n_c, &self.vdot, 1.0);
        Ok(&self.vdot)
    }

    /// Sets Mr, cr, Gr, Qr directly (for callers that exploit the structure of N_C, such
    /// as the wheeled-model fast path) and solves for v̇; `qddot` is left to the caller.
    pub(crate) fn solve_reduced(&mut self) -> Result<()> {
        self.chol.copy_from(&self.mass_matrix);
        cholesky_in_place(&mut self.chol, PIVOT_TOL).map_err(|pivot| Error::Singular {
            what: "reduced mass matrix Mr = N_Cᵀ H N_C".into(),
            detail: Some(format!("not positive definite (pivot {pivot})")),
        })?;
        for i in 0..self.r {
            self.tmp_r[i] = self.force[i] - self.velocity_terms[i] - self.gravity[i];
        }
        cholesky_solve(&self.chol, &mut self.tmp_r);
        self.vdot.copy_from(&self.tmp_r);
        Ok(())
    }

    /// Mutable access to `(Mr, cr, Gr, Qr)` for structured fast paths.
    pub(crate) fn parts_mut(
        &mut self,
    ) -> (
        &mut DMatrix<f64>,
        &mut DVector<f64>,
        &mut DVector<f64>,
        &mut DVector<f64>,
    ) {
        (
            &mut self.mass_matrix,
            &mut self.velocity_terms,
            &mut self.gravity,
            &mut self.force,
        )
    }

    /// Also forms the reduced Coriolis matrix `Cr = N_Cᵀ(H Ṅ_C + C_cor N_C)` from the
    /// Christoffel Coriolis matrix `c_cor` (n×n). Call after [`ReducedDynamics::compute`].
    pub fn compute_coriolis(
        &mut self,
        mass_matrix: &DMatrix<f64>,
        c_cor: &DMatrix<f64>,
        n_c: &DMatrix<f64>,
        n_c_dot: &DMatrix<f64>,
    ) {
        mass_matrix.mul_to(n_c_dot, &mut self.hn);
        self.hn.gemm(1.0, c_cor, n_c, 1.0);
        n_c.tr_mul_to(&self.hn, &mut self.coriolis);
    }

    /// Lagrange multipliers `λ = (C Cᵀ)⁻¹ C (Q − G − h − H q̈)` and the constraint force
    /// `−Cᵀλ`, for the constraint rows `c` (k×n). Call after [`ReducedDynamics::compute`].
    pub fn compute_multipliers(
        &mut self,
        terms: &JointSpaceTerms<'_>,
        c: &DMatrix<f64>,
    ) -> Result<&DVector<f64>> {
        assert_eq!(c.shape(), (self.k, self.n), "C shape");
        // tmp = Q − G − h − H q̈
        self.tmp_n.copy_from(terms.force);
        self.tmp_n -= terms.gravity;
        self.tmp_n -= terms.velocity_terms;
        self.tmp_n.gemv(-1.0, terms.mass_matrix, &self.qddot, 1.0);
        c.mul_to(&self.tmp_n, &mut self.tmp_k);
        for i in 0..self.k {
            for j in 0..self.k {
                self.cct[(i, j)] = c.row(i).dot(&c.row(j));
            }
        }
        cholesky_in_place(&mut self.cct, PIVOT_TOL).map_err(|_| Error::Singular {
            what: "constraint matrix C C^T".into(),
            detail: Some("constraint rows are linearly dependent".into()),
        })?;
        cholesky_solve(&self.cct, &mut self.tmp_k);
        self.lambda.copy_from(&self.tmp_k);
        c.tr_mul_to(&self.lambda, &mut self.constraint_force);
        self.constraint_force.neg_mut();
        Ok(&self.lambda)
    }
}

/// Lagrange multipliers by the full-coordinate DAE formula (reference implementation,
/// allocates): `λ = (C H⁻¹ Cᵀ)⁻¹ (C H⁻¹ (Q − h − G) + Ċ q̇)`.
#[doc(alias = "lambda")]
pub fn lagrange_multipliers_dae(
    terms: &JointSpaceTerms<'_>,
    c: &DMatrix<f64>,
    c_dot_qdot: &DVector<f64>,
) -> Result<DVector<f64>> {
    let chol = terms
        .mass_matrix
        .clone()
        .cholesky()
        .ok_or_else(|| Error::Singular {
            what: "mass matrix H".into(),
            detail: None,
        })?;
    let hinv_ct = chol.solve(&c.transpose());
    let rhs = terms.force - terms.velocity_terms - terms.gravity;
    let hinv_rhs = chol.solve(&rhs);
    let a = c * hinv_ct;
    let b = c * hinv_rhs + c_dot_qdot;
    a.cholesky()
        .map(|ch| ch.solve(&b))
        .ok_or_else(|| Error::Singular {
            what: "C H⁻¹ Cᵀ".into(),
            detail: None,
        })
}

fn symmetrize(m: &mut DMatrix<f64>) {
    let r = m.nrows();
    for i in 0..r {
        for j in 0..i {
            let s = 0.5 * (m[(i, j)] + m[(j, i)]);
            m[(i, j)] = s;
            m[(j, i)] = s;
        }
    }
}

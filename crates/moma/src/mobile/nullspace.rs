//! Numeric admissible-velocity basis for any set of Pfaffian constraint rows.
//!
//! For a constraint matrix `C` (k×n, full row rank) the basis `N_C` (n×(n−k)) is an
//! orthonormal basis of `ker C`, computed from the SVD of `C`. An orthonormal basis of a
//! subspace is only defined up to a rotation `R ∈ O(n−k)`; to keep `N_C(q(t))` continuous
//! along a trajectory, [`NullSpaceBasis::update`] aligns each new basis with the previous
//! one by the orthogonal Procrustes rotation (the polar factor of `N_newᵀ N_prev`), i.e. it
//! picks the orthonormal basis of the new null space closest to the old one.
//!
//! # The time derivative
//!
//! That alignment is, to first order, *parallel transport* of the basis: the gauge with
//! `N_Cᵀ Ṅ_C = 0`. Differentiating `C N_C = 0` gives `Ċ N_C + C Ṅ_C = 0`; with `Ṅ_C` in the
//! range of `Cᵀ` (which `N_Cᵀ Ṅ_C = 0` means) the unique solution is
//!
//! ```text
//! Ṅ_C = −C⁺ Ċ N_C,      C⁺ = Cᵀ (C Cᵀ)⁻¹,
//! ```
//!
//! computed analytically from `Ċ` (no finite differences). It equals the finite
//! difference of successive aligned bases to first order in the step, which the tests
//! check.

use nalgebra::DMatrix;

use crate::error::{Error, Result};

/// An orthonormal, continuity-preserving admissible-velocity basis N_C of `ker C`
/// (n×(n−k)) and its derivative Ṅ_C, for user-supplied constraint rows.
#[doc(alias = "N_C")]
#[derive(Debug, Clone)]
pub struct NullSpaceBasis {
    n: usize,
    k: usize,
    /// The current basis N_C (n×(n−k)), orthonormal columns, `C N_C = 0`.
    pub basis: DMatrix<f64>,
    /// Its time derivative Ṅ_C (n×(n−k)) in the parallel-transport gauge `N_Cᵀ Ṅ_C = 0`.
    pub basis_dot: DMatrix<f64>,
    has_previous: bool,
    /// Singular-value ratio below which `C` counts as rank deficient.
    pub rank_tolerance: f64,
}

impl NullSpaceBasis {
    /// A basis for k constraint rows on n velocities (k < n).
    pub fn new(n: usize, k: usize) -> Result<Self> {
        if k >= n {
            return Err(Error::invalid(
                "constraint rows",
                format!("need fewer constraints than velocities, got k = {k}, n = {n}"),
            ));
        }
        Ok(Self {
            n,
            k,
            basis: DMatrix::zeros(n, n - k),
            basis_dot: DMatrix::zeros(n, n - k),
            has_previous: false,
            rank_tolerance: 1e-10,
        })
    }

    /// Forgets the previous basis (the next update picks the SVD's own orientation).
    pub fn reset(&mut self) {
        self.has_previous = false;
    }

    /// Recomputes `N_C` for the constraint rows `c` (k×n) and `Ṅ_C = −C⁺ Ċ N_C` for their
    /// rate `c_dot` (k×n). Reports [`Error::Singular`] if `c` is rank deficient.
    ///
    /// This uses an SVD and allocates; it is meant for analysis and for models whose
    /// constraints have no analytic basis, not for the simulator's hot loop (which uses
    /// the analytic differential-drive basis).
    ///
    /// # Panics
    /// If `c` or `c_dot` is not k×n.
    pub fn update(&mut self, c: &DMatrix<f64>, c_dot: &DMatrix<f64>) -> Result<()> {
        let (n, k) = (self.n, self.k);
        assert_eq!(c.shape(), (k, n), "constraint matrix shape");
        assert_eq!(c_dot.shape(), (k, n), "constraint rate shape");
        crate::error::ensure_finite("constraint matrix C", c.iter())?;
        crate::error::ensure_finite("constraint rate Ċ", c_dot.iter())?;
        // Full SVD of Cᵀ (n×k): its left singular vectors beyond the first k span ker C.
        let mut ct_sq = DMatrix::zeros(n, n);
        ct_sq.view_mut((0, 0), (n, k)).copy_from(&c.transpose());
        let svd = ct_sq.svd(true, false);
        let u = svd.u.as_ref().expect("SVD computed with U");
        // Sort singular values (descending) with their vectors.
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
        let smax = svd.singular_values[order[0]];
        let smin = if k > 0 {
            svd.singular_values[order[k - 1]]
        } else {
            smax
        };
        if k > 0 && (smax <= 0.0 || smin <= self.rank_tolerance * smax) {
            return Err(Error::Singular {
                what: "constraint matrix C".into(),
                detail: Some(format!(
                    "rank deficient (σ_min/σ_max = {:.3e})",
                    if smax > 0.0 { smin / smax } else { 0.0 }
                )),
            });
        }
        let mut fresh = DMatrix::zeros(n, n - k);
        for (j, &col) in order[k..].iter().enumerate() {
            fresh.set_column(j, &u.column(col));
        }
        if self.has_previous {
            // Procrustes: R = polar factor of freshᵀ N_prev; N = fresh R.
            let m = fresh.transpose() * &self.basis;
            let s = m.svd(true, true);
            let r = s.u.expect("U") * s.v_t.expect("Vᵀ");
            self.basis = fresh * r;
        } else {
            self.basis = fresh;
        }
        self.has_previous = true;
        if k == 0 {
            self.basis_dot.fill(0.0);
            return Ok(());
        }
        // Ṅ = −Cᵀ (C Cᵀ)⁻¹ Ċ N.
        let cct = c * c.transpose();
        let chol = cct.cholesky().ok_or_else(|| Error::Singular {
            what: "C Cᵀ".into(),
            detail: None,
        })?;
        let rhs = c_dot * &self.basis;
        self.basis_dot = -(c.transpose() * chol.solve(&rhs));
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rows(t: f64) -> (DMatrix<f64>, DMatrix<f64>) {
        // Two smooth constraint rows on five velocities and their time derivative.
        let c = DMatrix::from_row_slice(
            2,
            5,
            &[
                -t.sin(),
                t.cos(),
                -0.3,
                0.0,
                0.1 * t,
                t.cos(),
                t.sin(),
                -0.25,
                -0.1,
                0.0,
            ],
        );
        let cd = DMatrix::from_row_slice(
            2,
            5,
            &[
                -t.cos(),
                -t.sin(),
                0.0,
                0.0,
                0.1,
                -t.sin(),
                t.cos(),
                0.0,
                0.0,
                0.0,
            ],
        );
        (c, cd)
    }

    #[test]
    fn basis_is_orthonormal_null_space_and_derivative_matches_aligned_difference() {
        let mut nb = NullSpaceBasis::new(5, 2).unwrap();
        let t0 = 0.4;
        let (c, cd) = rows(t0);
        nb.update(&c, &cd).unwrap();
        assert!((&c * &nb.basis).norm() < 1e-14);
        let gram = nb.basis.transpose() * &nb.basis;
        assert!((gram - DMatrix::identity(3, 3)).norm() < 1e-13);
        let n0 = nb.basis.clone();
        let nd = nb.basis_dot.clone();
        assert!(
            (n0.transpose() * &nd).norm() < 1e-13,
            "parallel-transport gauge"
        );
        // Finite difference of the aligned basis: forward and back by h.
        let h = 1e-5;
        let (c1, cd1) = rows(t0 + h);
        nb.update(&c1, &cd1).unwrap();
        let n1 = nb.basis.clone();
        let mut back = nb.clone();
        back.basis = n0.clone();
        let (cm, cdm) = rows(t0 - h);
        back.update(&cm, &cdm).unwrap();
        let fd = (n1 - back.basis) / (2.0 * h);
        assert!((fd - nd).norm() < 1e-6, "FD of the aligned basis vs −C⁺ĊN");
    }

    #[test]
    fn aligned_basis_is_continuous_along_a_path() {
        let mut nb = NullSpaceBasis::new(5, 2).unwrap();
        let mut prev: Option<DMatrix<f64>> = None;
        for i in 0..200 {
            let t = 0.05 * i as f64;
            let (c, cd) = rows(t);
            nb.update(&c, &cd).unwrap();
            if let Some(p) = &prev {
                assert!((&nb.basis - p).norm() < 0.1, "jump at t = {t}");
            }
            prev = Some(nb.basis.clone());
        }
    }

    #[test]
    fn rank_deficient_rows_are_reported() {
        let mut nb = NullSpaceBasis::new(3, 2).unwrap();
        let c = DMatrix::from_row_slice(2, 3, &[1.0, 0.0, 0.0, 2.0, 0.0, 0.0]);
        let err = nb.update(&c, &DMatrix::zeros(2, 3)).unwrap_err();
        assert!(matches!(err, Error::Singular { .. }), "{err}");
        assert!(NullSpaceBasis::new(2, 2).is_err());
    }
}

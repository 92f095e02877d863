//! Small dense linear algebra shared by the layers above: one in-place Cholesky
//! factorisation and its solve, for the workspaces that must not allocate (the reduced
//! dynamics of `mobile`, the damped least-squares step of `ik`, operational-space control).

use nalgebra::{DMatrix, DVector};

/// In-place Cholesky `A = L Lᵀ` of a symmetric matrix (only the lower triangle is read;
/// it becomes L, the strict upper triangle is left as it was).
///
/// A pivot counts as failed when it is not finite, not positive, or not above
/// `rel_pivot_tol` times the largest diagonal magnitude of `A` (pass 0 to accept every
/// positive pivot). Returns the index of the failing pivot. Does not allocate.
///
/// # Panics
/// If `a` is not square.
pub(crate) fn cholesky_in_place(
    a: &mut DMatrix<f64>,
    rel_pivot_tol: f64,
) -> std::result::Result<(), usize> {
    let n = a.nrows();
    assert_eq!(a.ncols(), n, "cholesky_in_place: matrix must be square");
    let floor = if rel_pivot_tol > 0.0 {
        rel_pivot_tol * (0..n).map(|i| a[(i, i)].abs()).fold(0.0, f64::max)
    } else {
        0.0
    };
    // left-looking on contiguous columns (column-major storage): column j, rows j..n,
    // becomes A[j.., j] − Σ_k L[j, k] L[j.., k], then is scaled by its pivot
    let s = a.as_mut_slice();
    for j in 0..n {
        for k in 0..j {
            let ljk = s[k * n + j];
            if ljk != 0.0 {
                let (left, right) = s.split_at_mut(j * n);
                let src = &left[k * n + j..k * n + n];
                for (d, x) in right[j..n].iter_mut().zip(src) {
                    *d -= ljk * x;
                }
            }
        }
        let d = s[j * n + j];
        if !d.is_finite() || d <= 0.0 || d <= floor {
            return Err(j);
        }
        let d = d.sqrt();
        s[j * n + j] = d;
        for x in &mut s[j * n + j + 1..j * n + n] {
            *x /= d;
        }
    }
    Ok(())
}

/// Solves `L Lᵀ x = b` in place with the factor from [`cholesky_in_place`]
/// (forward then backward substitution). Does not allocate.
///
/// # Panics
/// If `b` does not have as many entries as `l` has rows.
pub(crate) fn cholesky_solve(l: &DMatrix<f64>, b: &mut DVector<f64>) {
    let n = l.nrows();
    assert_eq!(
        b.len(),
        n,
        "cholesky_solve: right-hand side has the wrong length"
    );
    for i in 0..n {
        let mut s = b[i];
        for k in 0..i {
            s -= l[(i, k)] * b[k];
        }
        b[i] = s / l[(i, i)];
    }
    for i in (0..n).rev() {
        let mut s = b[i];
        for k in i + 1..n {
            s -= l[(k, i)] * b[k];
        }
        b[i] = s / l[(i, i)];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_solves_and_reports_indefinite() {
        let a = DMatrix::from_row_slice(3, 3, &[4.0, 1.0, 0.5, 1.0, 3.0, 0.2, 0.5, 0.2, 2.0]);
        let mut l = a.clone();
        cholesky_in_place(&mut l, 1e-14).unwrap();
        let mut x = DVector::from_vec(vec![1.0, -2.0, 0.5]);
        let b = x.clone();
        cholesky_solve(&l, &mut x);
        assert!((&a * x - b).norm() < 1e-14);
        let mut bad = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert_eq!(cholesky_in_place(&mut bad, 0.0), Err(1));
    }

    #[test]
    fn relative_pivot_tolerance_rejects_tiny_positive_pivots() {
        // Second pivot 1e-16 against a scale of 1: positive, but below 1e-14 · 1.
        let a = DMatrix::from_row_slice(2, 2, &[1.0, 0.0, 0.0, 1e-16]);
        assert_eq!(cholesky_in_place(&mut a.clone(), 1e-14), Err(1));
        assert_eq!(cholesky_in_place(&mut a.clone(), 0.0), Ok(()));
        // A negative pivot fails even when the scale is not finite.
        let mut b = DMatrix::from_row_slice(2, 2, &[-1.0, 0.0, 0.0, f64::INFINITY]);
        assert_eq!(cholesky_in_place(&mut b, 1e-14), Err(0));
    }
}

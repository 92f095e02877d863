//! Small dense linear algebra shared by the layers above: one in-place Cholesky
//! factorisation and its solves (one vector, or each column of a matrix), for the workspaces that must not allocate (the reduced
//! dynamics of `mobile`, the damped least-squares step of `ik`, operational-space control),
//! and one singular value decomposition with its left vectors (manipulability measures and
//! ellipsoids, pseudo-inverses).

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

/// Solves `L Lᵀ x = b` in place on each column of `b` with the factor from
/// [`cholesky_in_place`] (L the lower factor, column-major; operational-space control's
/// inverses, the MPC's feedback gains). Does not allocate.
///
/// # Panics
/// If `b` does not have as many rows as `l`.
pub(crate) fn cholesky_solve_columns(l: &DMatrix<f64>, b: &mut DMatrix<f64>) {
    let n = l.nrows();
    assert_eq!(
        b.nrows(),
        n,
        "cholesky_solve_columns: right-hand side has the wrong rows"
    );
    let ls = l.as_slice();
    for c in 0..b.ncols() {
        let x = &mut b.as_mut_slice()[c * n..(c + 1) * n];
        // L y = b: column-oriented forward substitution
        for i in 0..n {
            let xi = x[i] / ls[i * n + i];
            x[i] = xi;
            for (d, lv) in x[i + 1..].iter_mut().zip(&ls[i * n + i + 1..(i + 1) * n]) {
                *d -= xi * lv;
            }
        }
        // Lᵀ x = y: dot products with contiguous columns of L
        for i in (0..n).rev() {
            let dot: f64 = ls[i * n + i + 1..(i + 1) * n]
                .iter()
                .zip(&x[i + 1..])
                .map(|(a, b)| a * b)
                .sum();
            x[i] = (x[i] - dot) / ls[i * n + i];
        }
    }
}

/// Sweeps after which [`row_jacobi_svd`] gives up (it needs well under ten for the task
/// Jacobians and constraint matrices of this crate; each sweep converges quadratically).
const JACOBI_MAX_SWEEPS: usize = 60;

/// A singular value decomposition `A = U Wᵀ` from one-sided Jacobi rotations on the rows
/// of `A` (m × n): `U` is m × m orthogonal and the columns of `W` (n × m) are mutually
/// orthogonal, column i being `σᵢ vᵢ`, so `A = Σᵢ σᵢ uᵢ vᵢᵀ`.
///
/// Why not `nalgebra::SVD`: with singular vectors requested, nalgebra 0.35's
/// bidiagonal QR returns wrong singular values and vectors for some rank-deficient
/// matrices of every shape (of 2,394 random rank-deficient products `A·B` of up to 8 × 8,
/// 333 failed `A = U Σ Vᵀ` by more than 1e-9, some by order one; full-rank ones and the
/// values-only decomposition were right). Rank-deficient Jacobians are exactly the
/// singular postures manipulability is asked about.
#[derive(Clone, Debug)]
pub(crate) struct RowJacobiSvd {
    /// `σ₁ ≥ … ≥ σ_m ≥ 0`, one per row of `A` (beyond min(m, n) they are zero up to rounding).
    pub sigma: DVector<f64>,
    /// Left singular vectors `uᵢ` (columns), m × m, in the order of `sigma`.
    pub u: DMatrix<f64>,
    /// Columns `σᵢ vᵢ`, n × m, in the order of `sigma`.
    pub w: DMatrix<f64>,
}

/// One-sided (Hestenes) Jacobi SVD of `a` (m × n, all finite, m and n non-zero):
/// rotations `G` make the rows of `G A` orthogonal; `U = Gᵀ`, `σᵢ` are the row norms.
/// Small singular values come out to high relative accuracy and zero rows stay zero, so
/// rank-deficient input is handled like any other. The input is scaled by its largest
/// magnitude first, so entries near the overflow limit work too. `None` for a non-finite
/// entry, or if the rotations have not converged after 60 sweeps (not seen on any input).
pub(crate) fn row_jacobi_svd(a: &DMatrix<f64>) -> Option<RowJacobiSvd> {
    if a.iter().any(|x| !x.is_finite()) {
        return None;
    }
    let (m, n) = a.shape();
    let scale = a.amax();
    let mut w = a.transpose();
    let mut u = DMatrix::identity(m, m);
    if scale > 0.0 {
        w /= scale;
        if !orthogonalize_columns(w.as_mut_slice(), u.as_mut_slice(), n, m) {
            return None;
        }
    }
    let norms: Vec<f64> = (0..m).map(|i| w.column(i).norm()).collect();
    let mut order: Vec<usize> = (0..m).collect();
    order.sort_by(|&x, &y| norms[y].total_cmp(&norms[x]));
    Some(RowJacobiSvd {
        sigma: DVector::from_iterator(m, order.iter().map(|&i| norms[i] * scale)),
        u: DMatrix::from_fn(m, m, |r, c| u[(r, order[c])]),
        w: DMatrix::from_fn(n, m, |r, c| w[(r, order[c])] * scale),
    })
}

/// Cyclic Jacobi sweeps over the `m` columns (length `n`, column-major in `w`) until
/// every pair is orthogonal, each rotation applied to the columns of `u` (m × m) too;
/// false after [`JACOBI_MAX_SWEEPS`]. Squared column norms are kept up to date across a
/// sweep (`‖w_p‖² − tγ`, `‖w_q‖² + tγ`) and recomputed at the start of each.
fn orthogonalize_columns(w: &mut [f64], u: &mut [f64], n: usize, m: usize) -> bool {
    let tol = f64::EPSILON * (n.max(1) as f64);
    // columns this small against the whole matrix are rounding noise of a zero row of
    // A: rotating them against each other never settles, and they count as zero anyway
    let total: f64 = w.iter().map(|x| x * x).sum();
    let negligible = (f64::EPSILON * (m * n) as f64).powi(2) * total;
    let mut d = vec![0.0; m];
    for _ in 0..JACOBI_MAX_SWEEPS {
        for (i, di) in d.iter_mut().enumerate() {
            *di = w[i * n..(i + 1) * n].iter().map(|x| x * x).sum();
        }
        let mut rotated = false;
        for p in 0..m {
            for q in p + 1..m {
                let (alpha, beta) = (d[p], d[q]);
                if alpha.min(beta) <= negligible {
                    continue;
                }
                let (head, tail) = w.split_at_mut(q * n);
                let (wp, wq) = (&mut head[p * n..(p + 1) * n], &mut tail[..n]);
                let gamma: f64 = wp.iter().zip(wq.iter()).map(|(x, y)| x * y).sum();
                if gamma == 0.0 || gamma.abs() <= tol * (alpha * beta).sqrt() {
                    continue;
                }
                let zeta = (beta - alpha) / (2.0 * gamma);
                // t = sign ζ / (|ζ| + √(1 + ζ²)), |t| ≤ 1; for |ζ| beyond 1e150, where ζ²
                // overflows, t = 1 / (2ζ) to full precision (no hypot: it is slow)
                let t = if zeta.abs() < 1e150 {
                    zeta.signum() / (zeta.abs() + (1.0 + zeta * zeta).sqrt())
                } else {
                    0.5 / zeta
                };
                let c = 1.0 / (1.0 + t * t).sqrt();
                let s = c * t;
                rotate(wp, wq, c, s);
                let (head, tail) = u.split_at_mut(q * m);
                rotate(&mut head[p * m..(p + 1) * m], &mut tail[..m], c, s);
                d[p] = alpha - t * gamma;
                d[q] = beta + t * gamma;
                rotated = true;
            }
        }
        if !rotated {
            return true;
        }
    }
    false
}

/// `(x, y) ← (c x − s y, s x + c y)`, entry by entry.
fn rotate(x: &mut [f64], y: &mut [f64], c: f64, s: f64) {
    for (a, b) in x.iter_mut().zip(y.iter_mut()) {
        let (xa, yb) = (*a, *b);
        *a = c * xa - s * yb;
        *b = s * xa + c * yb;
    }
}

/// The Moore–Penrose pseudo-inverse `A⁺ = Σ_{σᵢ > tol·σ₁} vᵢ uᵢᵀ / σᵢ` (n × m) from
/// [`row_jacobi_svd`]; singular values at or below `rel_tol · σ₁` count as zero. `None`
/// when the decomposition does not converge.
pub(crate) fn pseudo_inverse(a: &DMatrix<f64>, rel_tol: f64) -> Option<DMatrix<f64>> {
    let svd = row_jacobi_svd(a)?;
    let (m, n) = a.shape();
    let cut = (rel_tol * svd.sigma.get(0).copied().unwrap_or(0.0)).max(f64::MIN_POSITIVE);
    let mut out = DMatrix::zeros(n, m);
    for i in 0..m {
        let s = svd.sigma[i];
        if s > cut {
            // vᵢ / σᵢ = wᵢ / σᵢ², added as a rank-one update (no temporary matrices)
            out.ger(1.0 / (s * s), &svd.w.column(i), &svd.u.column(i), 1.0);
        }
    }
    Some(out)
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

    /// Random `A·B` products of rank r ≤ min(m, n), every shape up to 8 × 8 (the family
    /// on which nalgebra's SVD with vectors fails), plus zero and extreme-scale matrices.
    fn test_matrices() -> Vec<DMatrix<f64>> {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
        let mut out = Vec::new();
        for _ in 0..3000 {
            let m = rng.random_range(1..9usize);
            let n = rng.random_range(1..9usize);
            let r = rng.random_range(1..=m.min(n));
            let a = DMatrix::<f64>::from_fn(m, r, |_, _| rng.random_range(-1.0..1.0));
            let b = DMatrix::<f64>::from_fn(r, n, |_, _| rng.random_range(-1.0..1.0));
            out.push(a * b);
        }
        out.push(DMatrix::zeros(3, 5));
        out.push(DMatrix::from_row_slice(3, 2, &[1.0, 2.0, 2.0, 4.0, -1.0, -2.0]) * 1e300);
        out.push(DMatrix::from_row_slice(
            2,
            3,
            &[1e-300, 0.0, 0.0, 0.0, 3e-310, 0.0],
        ));
        out
    }

    #[test]
    fn jacobi_svd_reconstructs_rank_deficient_matrices_of_every_shape() {
        let mut deficient = 0;
        for a in test_matrices() {
            let (m, n) = a.shape();
            let svd = row_jacobi_svd(&a).expect("converges");
            let scale = a.amax().max(f64::MIN_POSITIVE);
            // A = U Wᵀ, U orthogonal, W's columns orthogonal with norms σ, σ descending
            let rec = &svd.u * svd.w.transpose();
            assert!(
                (rec - &a).amax() <= 1e-13 * scale,
                "{m}x{n}: reconstruction"
            );
            let utu = svd.u.transpose() * &svd.u - DMatrix::<f64>::identity(m, m);
            assert!(utu.amax() < 1e-13, "{m}x{n}: U orthogonal");
            let ws = &svd.w / scale;
            let wtw = ws.transpose() * &ws;
            for i in 0..m {
                assert!(
                    (ws.column(i).norm() - svd.sigma[i] / scale).abs() <= 1e-13,
                    "{m}x{n}: σ{i} is the column norm"
                );
                for j in 0..i {
                    assert!(wtw[(i, j)].abs() <= 1e-13, "{m}x{n}: W orthogonal");
                }
                if i > 0 {
                    assert!(svd.sigma[i] <= svd.sigma[i - 1], "{m}x{n}: descending");
                }
            }
            // the values agree with nalgebra's values-only decomposition (which is right)
            if scale < 1e100 && scale > 1e-100 {
                let mut reference: Vec<f64> = a
                    .clone()
                    .svd(false, false)
                    .singular_values
                    .iter()
                    .copied()
                    .collect();
                reference.sort_by(|x, y| y.total_cmp(x));
                for (i, s) in reference.iter().enumerate() {
                    assert!((svd.sigma[i] - s).abs() <= 1e-12 * scale, "{m}x{n}: σ{i}");
                }
                if reference.last().is_some_and(|&s| s < 1e-12) {
                    deficient += 1;
                }
            }
        }
        assert!(
            deficient > 1000,
            "the set exercises rank deficiency ({deficient})"
        );
    }

    #[test]
    fn pseudo_inverse_meets_the_penrose_conditions_on_singular_matrices() {
        for a in test_matrices() {
            let scale = a.amax();
            if !(1e-100..1e100).contains(&scale) {
                continue;
            }
            let p = pseudo_inverse(&a, 1e-12).expect("converges");
            let pa = &p * &a;
            let ap = &a * &p;
            let tol = 1e-9;
            assert!((&a * &pa - &a).amax() <= tol * scale, "A A⁺ A = A");
            assert!(
                (&p * &ap - &p).amax() <= tol * p.amax().max(1.0),
                "A⁺ A A⁺ = A⁺"
            );
            assert!((&ap - ap.transpose()).amax() <= tol, "A A⁺ symmetric");
            assert!((&pa - pa.transpose()).amax() <= tol, "A⁺ A symmetric");
        }
    }
}

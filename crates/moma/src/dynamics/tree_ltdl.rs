//! The tree-sparse `H = Lᵀ D L` factorisation of a joint-space inertia matrix and its
//! solve (Featherstone, *Rigid Body Dynamics Algorithms*, §6.5, the "LTDL" algorithm).
//!
//! For a kinematic tree whose degrees of freedom are numbered parents first, `H_ij` is
//! zero unless one of `i`, `j` is an ancestor of the other, and the factor `L` (unit lower
//! triangular) keeps that pattern: `L_ki ≠ 0` only for `i` an ancestor of `k`. Factorising
//! costs `Σ_k depth(k)²` and one solve `2 Σ_k depth(k)` multiply–adds per right-hand side,
//! instead of the dense `n³/3` and `n²`; for a chain the two are the same, for a branched
//! robot (TIAGo's head, arm and fingers) far fewer.
//!
//! Degrees of freedom are ordered as the model's velocity coordinates; a joint with
//! several of them is a chain of one-dof nodes (its first one's parent is the last one of
//! the parent joint).

use crate::multibody::Model;
use nalgebra::DMatrix;

/// The parent of a degree of freedom that has none.
pub(crate) const NO_PARENT: usize = usize::MAX;

/// The parent of each velocity coordinate in the tree of one-dof nodes ([`NO_PARENT`] for
/// the first coordinate of a joint attached to the universe).
pub(crate) fn dof_parents(model: &Model) -> Vec<usize> {
    let mut parent = vec![NO_PARENT; model.nv];
    for i in 1..model.njoints {
        let iv = model.idx_v[i];
        let p = model.parents[i].0;
        for k in 0..model.nvs[i] {
            parent[iv + k] = if k > 0 {
                iv + k - 1
            } else if p > 0 && model.nvs[p] > 0 {
                model.idx_v[p] + model.nvs[p] - 1
            } else {
                // a zero-dof parent passes on its own parent's last coordinate
                last_dof_above(model, p)
            };
        }
    }
    parent
}

/// The last velocity coordinate of the nearest ancestor-or-self of joint `j` that has one.
fn last_dof_above(model: &Model, mut j: usize) -> usize {
    while j > 0 {
        if model.nvs[j] > 0 {
            return model.idx_v[j] + model.nvs[j] - 1;
        }
        j = model.parents[j].0;
    }
    NO_PARENT
}

/// Factorises `h` (symmetric; only the entries `(i, k)` with `i` an ancestor-or-self of
/// `k` are read, i.e. its upper triangle) in place into `Lᵀ D L`: the diagonal becomes
/// `D`, and the entry `(i, k)` above it becomes `L_ki`, so that row `k` of `L` is
/// contiguous in the column-major storage (at `k n + i`). Other entries are left as they
/// were.
///
/// `chain_start` is [`chain_starts`] of `parent`: a coordinate's ancestors are taken a run
/// of consecutive coordinates at a time (a joint's own coordinates, a serial arm), each
/// run one vectorised multiply–add.
///
/// Returns the index of the first pivot (counting from the leaves) that is not positive
/// and finite, i.e. when `h` is not positive definite. Does not allocate.
pub(crate) fn ltdl_in_place(
    h: &mut DMatrix<f64>,
    parent: &[usize],
    chain_start: &[usize],
) -> Result<(), usize> {
    let n = h.nrows();
    debug_assert_eq!((parent.len(), chain_start.len()), (n, n));
    let h = h.as_mut_slice();
    for k in (0..n).rev() {
        let d = h[k * n + k];
        if !(d.is_finite() && d > 0.0) {
            return Err(k);
        }
        let (above, from_k) = h.split_at_mut(k * n);
        let row_k = &mut from_k[..n];
        let mut i = parent[k];
        while i != NO_PARENT {
            let a = row_k[i] / d;
            let row_i = &mut above[i * n..(i + 1) * n];
            // H_ij −= a H_kj for j ancestor-or-self of i; row k's entries up to i are
            // still H's (they become L's as i reaches them)
            let mut j = i;
            while j != NO_PARENT {
                let top = chain_start[j];
                for (x, y) in row_i[top..=j].iter_mut().zip(&row_k[top..=j]) {
                    *x -= a * y;
                }
                j = parent[top];
            }
            row_k[i] = a;
            i = parent[i];
        }
    }
    Ok(())
}

/// For each coordinate `j`, the first of the longest run `s, s + 1, …, j` in which each
/// coordinate is the parent of the next: `j`'s ancestors-or-self are such runs, the next
/// one ending at `parent[s]`.
pub(crate) fn chain_starts(parent: &[usize]) -> Vec<usize> {
    let mut start: Vec<usize> = (0..parent.len()).collect();
    for j in 1..parent.len() {
        if parent[j] == j - 1 {
            start[j] = start[j - 1];
        }
    }
    start
}

/// Which entries of the right-hand sides of [`ltdl_solve_rows`] can be nonzero.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Rhs<'a> {
    /// Any: every row of `B` is solved over its full width `m`.
    Dense,
    /// `H⁻¹` alone: `m = n`, row `k` of `B` is `e_kᵀ`. On return row `k` holds `H⁻¹` on
    /// the columns `k..n` only (its upper triangle; the rest is left unspecified).
    Inverse {
        /// Per coordinate, one past the last coordinate of its subtree.
        end: &'a [usize],
    },
}

/// Solves `H Y = B` for many right-hand sides at once, with `H = Lᵀ D L` from
/// [`ltdl_in_place`]. `rows` holds `B` by rows, `n` blocks of `m` (block `r` is row `r`
/// of `B`, so every step works on contiguous columns), and is overwritten by `Y` in the
/// same layout. On the way up the tree each row is added to its ancestors' rows; on the
/// way down each row gathers its ancestors' rows a block of columns at a time, summed in
/// registers and stored once. With [`Rhs::Inverse`] the steps skip the columns known to be
/// zero on the way up and the lower triangle on the way down. Does not
/// allocate.
///
/// The multiply–adds are compiled three times and chosen at run time: AVX-512F or
/// AVX2 with fused multiply–adds when the CPU has them, else the build's baseline; the
/// results differ by rounding only.
pub(crate) fn ltdl_solve_rows(
    fact: &DMatrix<f64>,
    parent: &[usize],
    rows: &mut [f64],
    m: usize,
    rhs: Rhs<'_>,
) {
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("fma")
        {
            #[allow(unsafe_code)]
            // SAFETY: `solve_avx512` only requires AVX-512F and FMA, detected here.
            return unsafe { solve_avx512(fact, parent, rows, m, rhs) };
        }
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            #[allow(unsafe_code)]
            // SAFETY: `solve_avx2` only requires AVX2 and FMA, detected here.
            return unsafe { solve_avx2(fact, parent, rows, m, rhs) };
        }
    }
    solve::<false, 16>(fact, parent, rows, m, rhs);
}

/// [`solve`] compiled for AVX-512F, with fused multiply–adds.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,fma")]
fn solve_avx512(fact: &DMatrix<f64>, parent: &[usize], rows: &mut [f64], m: usize, rhs: Rhs<'_>) {
    solve::<true, 32>(fact, parent, rows, m, rhs);
}

/// [`solve`] compiled for AVX2, with fused multiply–adds.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn solve_avx2(fact: &DMatrix<f64>, parent: &[usize], rows: &mut [f64], m: usize, rhs: Rhs<'_>) {
    solve::<true, 32>(fact, parent, rows, m, rhs);
}

/// The two triangular solves and the diagonal scaling of [`ltdl_solve_rows`].
#[inline(always)]
fn solve<const FMA: bool, const W: usize>(
    fact: &DMatrix<f64>,
    parent: &[usize],
    rows: &mut [f64],
    m: usize,
    rhs: Rhs<'_>,
) {
    let n = fact.nrows();
    debug_assert_eq!(rows.len(), n * m);
    match rhs {
        Rhs::Dense => {}
        Rhs::Inverse { end } => debug_assert_eq!((m, end.len()), (n, n)),
    }
    let f = fact.as_slice();
    // Lᵀ Z = B: from the leaves, each finished row updates its ancestors' rows
    for k in (0..n).rev() {
        let (above, from_k) = rows.split_at_mut(k * m);
        let row_k = &from_k[..m];
        let mut i = parent[k];
        while i != NO_PARENT {
            let (a, row_i) = (-f[k * n + i], &mut above[i * m..(i + 1) * m]);
            match rhs {
                Rhs::Dense => axpy::<FMA>(row_i, a, row_k),
                // e_k's part lives on k's subtree
                Rhs::Inverse { end } => axpy::<FMA>(&mut row_i[k..end[k]], a, &row_k[k..end[k]]),
            }
            i = parent[i];
        }
    }
    // D Y' = Z and L Y = Y': from the root, each row is scaled and takes its ancestors'
    // finished rows, gathered in registers a block of columns at a time (one store per
    // entry instead of one per ancestor)
    for k in 0..n {
        // H⁻¹'s upper triangle only: columns k.. of the first block, read from rows i < k
        let lo = match rhs {
            Rhs::Dense => 0,
            Rhs::Inverse { .. } => k,
        };
        let (above, from_k) = rows.split_at_mut(k * m);
        let row_k = &mut from_k[..m];
        let s = 1.0 / f[k * n + k];
        // the last 8 columns first, while row k still holds Z there: they cover the
        // columns the blocks of 8 leave over, without a single-column tail
        let last =
            (m - lo >= 8).then(|| gather::<FMA, 8>(row_k, above, m, m - 8, s, f, n, parent, k));
        let mut c = lo;
        while c + W <= m {
            let y = gather::<FMA, W>(row_k, above, m, c, s, f, n, parent, k);
            row_k[c..c + W].copy_from_slice(&y);
            c += W;
        }
        while c + 8 <= m {
            let y = gather::<FMA, 8>(row_k, above, m, c, s, f, n, parent, k);
            row_k[c..c + 8].copy_from_slice(&y);
            c += 8;
        }
        if let Some(y) = last {
            row_k[m - 8..].copy_from_slice(&y);
        } else {
            while c < m {
                row_k[c] = gather::<FMA, 1>(row_k, above, m, c, s, f, n, parent, k)[0];
                c += 1;
            }
        }
    }
}

/// Columns `c..c + B` of row `k` of the downward solve: `s row_k − Σ L_ki row_i` over
/// `k`'s ancestors `i` (whose rows are in `above`, `m` entries each), accumulated in `B`
/// registers.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn gather<const FMA: bool, const B: usize>(
    row_k: &[f64],
    above: &[f64],
    m: usize,
    c: usize,
    s: f64,
    f: &[f64],
    n: usize,
    parent: &[usize],
    k: usize,
) -> [f64; B] {
    let z: &[f64; B] = (&row_k[c..c + B]).try_into().expect("B columns");
    let mut acc = [0.0; B];
    for (a, x) in acc.iter_mut().zip(z) {
        *a = *x * s;
    }
    let mut i = parent[k];
    while i != NO_PARENT {
        let l = -f[k * n + i];
        let src: &[f64; B] = (&above[i * m + c..i * m + c + B])
            .try_into()
            .expect("B columns");
        for (a, x) in acc.iter_mut().zip(src) {
            *a = if FMA { l.mul_add(*x, *a) } else { *a + l * x };
        }
        i = parent[i];
    }
    acc
}

/// One past the last velocity coordinate of each coordinate's subtree (coordinates are
/// numbered parents first, so a subtree lies in `k..end[k]`, not necessarily all of it).
pub(crate) fn subtree_ends(parent: &[usize]) -> Vec<usize> {
    let mut end: Vec<usize> = (1..=parent.len()).collect();
    for k in (0..parent.len()).rev() {
        if parent[k] != NO_PARENT {
            end[parent[k]] = end[parent[k]].max(end[k]);
        }
    }
    end
}

/// `y += a x`, fused when `FMA` (only where the target has the instruction).
#[inline(always)]
fn axpy<const FMA: bool>(y: &mut [f64], a: f64, x: &[f64]) {
    for (d, s) in y.iter_mut().zip(x) {
        *d = if FMA { a.mul_add(*s, *d) } else { *d + a * s };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A branched tree of 7 dofs: 0 - 1 - 2 - {3 - 4, 5 - 6}.
    const PARENT: [usize; 7] = [NO_PARENT, 0, 1, 2, 3, 2, 5];

    fn is_ancestor_or_self(mut k: usize, i: usize) -> bool {
        while k != NO_PARENT {
            if k == i {
                return true;
            }
            k = PARENT[k];
        }
        false
    }

    /// A unit lower-triangular L with the tree's pattern and a positive D, fixed numbers.
    fn factors() -> (DMatrix<f64>, Vec<f64>) {
        let n = PARENT.len();
        let l = DMatrix::from_fn(n, n, |k, i| {
            if k == i {
                1.0
            } else if i < k && is_ancestor_or_self(k, i) {
                0.3 * ((3 * k + 5 * i) as f64).sin() + 0.1
            } else {
                0.0
            }
        });
        let d = (0..n).map(|k| 0.5 + 0.25 * k as f64).collect();
        (l, d)
    }

    #[test]
    fn factorisation_recovers_the_factors() {
        let (l, d) = factors();
        let n = d.len();
        let h = l.transpose() * DMatrix::from_diagonal(&d.clone().into()) * &l;
        // the product has the tree pattern: cousins are zero
        assert_eq!(h[(4, 6)], 0.0);
        let mut f = h.clone();
        ltdl_in_place(&mut f, &PARENT, &chain_starts(&PARENT)).unwrap();
        for k in 0..n {
            assert!((f[(k, k)] - d[k]).abs() < 1e-13, "D_{k}");
            for i in 0..k {
                if is_ancestor_or_self(k, i) {
                    assert!((f[(i, k)] - l[(k, i)]).abs() < 1e-13, "L_{k}{i}");
                }
            }
        }
    }

    /// Solves `H Y = B` for `B` of `m` columns by rows (the tree factorisation) and
    /// checks `Y` against a dense LU solve.
    fn check_rows_solve(m: usize, b_entry: impl Fn(usize, usize) -> f64) {
        let (l, d) = factors();
        let n = d.len();
        let h = l.transpose() * DMatrix::from_diagonal(&d.into()) * &l;
        let b = DMatrix::from_fn(n, m, b_entry);
        let want = h.clone().lu().solve(&b).unwrap();
        let mut f = h;
        ltdl_in_place(&mut f, &PARENT, &chain_starts(&PARENT)).unwrap();
        let mut rows: Vec<f64> = (0..n)
            .flat_map(|r| (0..m).map(move |c| (r, c)))
            .map(|(r, c)| b[(r, c)])
            .collect();
        ltdl_solve_rows(&f, &PARENT, &mut rows, m, Rhs::Dense);
        for r in 0..n {
            for c in 0..m {
                assert!((rows[r * m + c] - want[(r, c)]).abs() < 1e-12, "Y {r} {c}");
            }
        }
    }

    #[test]
    fn solve_by_rows_matches_the_dense_solve() {
        check_rows_solve(3, |r, c| ((r * 3 + c) as f64).cos());
    }

    #[test]
    fn wide_right_hand_sides_match_the_dense_solve() {
        // 45 columns: the downward gather's register blocks of 32 and 8 and the last 8
        // columns overlapping them take part (3 columns, above, take single columns)
        check_rows_solve(45, |r, c| ((r * 45 + c) as f64 * 0.7).sin() + 0.2);
    }

    #[test]
    fn inverse_rows_skip_only_zeros() {
        let (l, d) = factors();
        let n = d.len();
        let h = l.transpose() * DMatrix::from_diagonal(&d.into()) * &l;
        let end = subtree_ends(&PARENT);
        assert_eq!(end, vec![7, 7, 7, 5, 5, 7, 7]);
        let hinv = h.clone().lu().try_inverse().unwrap();
        let mut f = h;
        ltdl_in_place(&mut f, &PARENT, &chain_starts(&PARENT)).unwrap();
        let mut rows = vec![0.0; n * n];
        for r in 0..n {
            rows[r * n + r] = 1.0;
        }
        ltdl_solve_rows(&f, &PARENT, &mut rows, n, Rhs::Inverse { end: &end });
        for r in 0..n {
            for c in r..n {
                assert!(
                    (rows[r * n + c] - hinv[(r, c)]).abs() < 1e-12,
                    "H⁻¹ {r} {c}"
                );
            }
        }
    }

    #[test]
    fn chains_start_where_a_parent_is_not_the_previous_coordinate() {
        // 0 - 1 - 2 - {3 - 4, 5 - 6}: 0..=4 is one run (each the parent of the next), 5
        // starts one (its parent is 2); 6's ancestors-or-self are the runs 5..=6 and 0..=2
        assert_eq!(chain_starts(&PARENT), vec![0, 0, 0, 0, 0, 5, 5]);
    }

    #[test]
    fn an_indefinite_matrix_is_reported() {
        let mut h = DMatrix::identity(7, 7);
        h[(5, 5)] = -1.0;
        assert_eq!(
            ltdl_in_place(&mut h, &PARENT, &chain_starts(&PARENT)),
            Err(5)
        );
    }
}

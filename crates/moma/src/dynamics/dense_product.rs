//! The dense product `C = −A B` of square column-major matrices, without allocating:
//! register-blocked, a tile of 8 rows × `CB` columns of `C` summed in registers over the
//! whole inner dimension, each column of `A` loaded once per tile and each entry of `B`
//! once per tile and broadcast (nalgebra's product allocates its packing buffers).
//!
//! Tiles cover `C` with the last row and column tiles moved back to end at `n` when `n` is
//! not a multiple of the tile, so they overlap their neighbours; an entry computed twice
//! is computed the same way both times. Below a tile's size the columns are summed one at a
//! time.

/// `c = −a b` for `n × n` column-major `a`, `b`, `c` (slices of `n²` entries).
///
/// The multiply–adds are compiled three times and chosen at run time: AVX-512F or AVX2
/// with fused multiply–adds when the CPU has them, else the build's baseline; the
/// results differ by rounding only.
pub(crate) fn neg_mul(a: &[f64], b: &[f64], c: &mut [f64], n: usize) {
    assert!(a.len() == n * n && b.len() == n * n && c.len() == n * n);
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("fma")
        {
            #[allow(unsafe_code)]
            // SAFETY: `neg_mul_avx512` only requires AVX-512F and FMA, detected here.
            return unsafe { neg_mul_avx512(a, b, c, n) };
        }
        if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
        {
            #[allow(unsafe_code)]
            // SAFETY: `neg_mul_avx2` only requires AVX2 and FMA, detected here.
            return unsafe { neg_mul_avx2(a, b, c, n) };
        }
    }
    tiles::<false, 4>(a, b, c, n);
}

/// [`tiles`] compiled for AVX-512F, with fused multiply–adds: 8 column tiles, eight
/// 8-wide accumulators.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,fma")]
fn neg_mul_avx512(a: &[f64], b: &[f64], c: &mut [f64], n: usize) {
    tiles::<true, 8>(a, b, c, n);
}

/// [`tiles`] compiled for AVX2, with fused multiply–adds: 4 column tiles, eight 4-wide
/// accumulators.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn neg_mul_avx2(a: &[f64], b: &[f64], c: &mut [f64], n: usize) {
    tiles::<true, 4>(a, b, c, n);
}

/// Rows of one tile.
const R: usize = 8;

/// Every tile of `c = −a b`, `CB` columns wide.
#[inline(always)]
fn tiles<const FMA: bool, const CB: usize>(a: &[f64], b: &[f64], c: &mut [f64], n: usize) {
    if n < R.max(CB) {
        // column by column: c_j = −Σ_k a_k b_kj, each a multiply–add of a whole column
        for (c_j, b_j) in c.chunks_exact_mut(n).zip(b.chunks_exact(n)) {
            c_j.fill(0.0);
            for (a_k, &x) in a.chunks_exact(n).zip(b_j) {
                for (d, y) in c_j.iter_mut().zip(a_k) {
                    *d = if FMA { y.mul_add(-x, *d) } else { *d - y * x };
                }
            }
        }
        return;
    }
    let starts = |t: usize| (0..n.div_ceil(t)).map(move |s| (s * t).min(n - t));
    for j0 in starts(CB) {
        for i0 in starts(R) {
            tile::<FMA, CB>(a, b, c, n, i0, j0);
        }
    }
}

/// Rows `i0..i0 + 8` of columns `j0..j0 + CB` of `c = −a b`.
#[inline(always)]
fn tile<const FMA: bool, const CB: usize>(
    a: &[f64],
    b: &[f64],
    c: &mut [f64],
    n: usize,
    i0: usize,
    j0: usize,
) {
    let mut acc = [[0.0; R]; CB];
    let bs: [&[f64]; CB] = std::array::from_fn(|t| &b[(j0 + t) * n..(j0 + t + 1) * n]);
    for k in 0..n {
        let col: &[f64; R] = (&a[k * n + i0..k * n + i0 + R]).try_into().expect("R rows");
        for (acc_t, b_t) in acc.iter_mut().zip(&bs) {
            let x = b_t[k];
            for (s, y) in acc_t.iter_mut().zip(col) {
                *s = if FMA { y.mul_add(x, *s) } else { *s + y * x };
            }
        }
    }
    for (t, acc_t) in acc.iter().enumerate() {
        let at = (j0 + t) * n + i0;
        for (d, s) in c[at..at + R].iter_mut().zip(acc_t) {
            *d = -*s;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::neg_mul;
    use nalgebra::DMatrix;

    fn check(n: usize) {
        let a = DMatrix::from_fn(n, n, |r, c| ((r * n + c) as f64 * 0.37).sin());
        let b = DMatrix::from_fn(n, n, |r, c| ((r + 3 * c) as f64 * 0.11).cos() + 0.5);
        let mut c = DMatrix::from_element(n, n, f64::NAN);
        neg_mul(a.as_slice(), b.as_slice(), c.as_mut_slice(), n);
        let expected = -(&a * &b);
        for (x, y) in c.iter().zip(expected.iter()) {
            assert!(
                (x - y).abs() < 1e-12 * (1.0 + y.abs()),
                "n = {n}: {x} vs {y}"
            );
        }
    }

    #[test]
    fn products_match_nalgebra_for_every_tiling() {
        // below a tile, one tile, tiles that fit, and last tiles that overlap
        for n in [1, 5, 7, 8, 9, 15, 16, 17, 48, 51, 54] {
            check(n);
        }
    }
}

//! Sine and cosine of a joint angle, written so that one state or several at once give the
//! same bits.
//!
//! [`sin_cos`] is what every revolute joint of the library evaluates (`rnea`, `crba`,
//! `aba`, the kinematics, and the multi-state `rnea_batch`). Its body, [`sin_cos_reduced`],
//! is straight-line arithmetic with no call and no branch: the argument is reduced by the
//! nearest multiple of π/2 (Cody–Waite, with π/2 split into 33 + 33 + 53 bits, so the
//! reduced angle is carried as a head and a tail), the two minimax polynomials of the
//! classical `fdlibm` kernels give sine and cosine on [−π/4, π/4], and the quadrant picks
//! and signs them. A loop of it over an array therefore compiles to SIMD instructions, and
//! each lane computes exactly the operations of the scalar call (Rust never contracts
//! `a * b + c` into a fused multiply–add), so the multi-state kernel stays bit-for-bit the
//! single call.
//!
//! Accuracy: within one unit in the last place of the correctly rounded values on
//! |x| < [`REDUCED_RANGE`] (the unit tests compare it with the platform's `sin_cos` on
//! random and adversarial arguments); `sin_cos(0) = (0, 1)` and `sin x = x` below 2⁻²⁶,
//! exactly. Outside that range, and for NaN or infinities, [`sin_cos`] returns the
//! platform's `f64::sin_cos`.

/// |x| below which [`sin_cos`] uses its own reduction and polynomials (the platform's
/// `sin_cos` beyond): far past any joint angle, and well inside the 2²⁰·π/2 up to which
/// the two-step Cody–Waite reduction is accurate.
pub const REDUCED_RANGE: f64 = 1.0e5;

// 2/π, and π/2 split into 33-bit heads with their tails (the constants of fdlibm's
// `__ieee754_rem_pio2`; bit patterns, the decimal values beside them).
const INV_PIO2: f64 = std::f64::consts::FRAC_2_PI;
const PIO2_1: f64 = f64::from_bits(0x3FF921FB54400000); // 1.57079632673412561417e0
const PIO2_2: f64 = f64::from_bits(0x3DD0B4611A600000); // 6.07710050630396597660e-11
const PIO2_2T: f64 = f64::from_bits(0x3BA3198A2E037073); // 2.02226624879595063154e-21
// 1.5 · 2⁵²: adding it rounds to the nearest integer, which lands in the low mantissa bits
const ROUND_MAGIC: f64 = 6_755_399_441_055_744.0;

// Minimax coefficients of sin x = x + x³·S(x²) and cos x = 1 − x²/2 + x⁴·C(x²) on
// [−π/4, π/4] (fdlibm's `__kernel_sin` and `__kernel_cos`), as bit patterns.
const S1: f64 = f64::from_bits(0xBFC5555555555549); // -1.66666666666666324348e-1
const S2: f64 = f64::from_bits(0x3F8111111110F8A6); // 8.33333333332248946124e-3
const S3: f64 = f64::from_bits(0xBF2A01A019C161D5); // -1.98412698298579493134e-4
const S4: f64 = f64::from_bits(0x3EC71DE357B1FE7D); // 2.75573137070700676789e-6
const S5: f64 = f64::from_bits(0xBE5AE5E68A2B9CEB); // -2.50507602534068634195e-8
const S6: f64 = f64::from_bits(0x3DE5D93A5ACFD57C); // 1.58969099521155010221e-10
const C1: f64 = f64::from_bits(0x3FA555555555554C); // 4.16666666666666019037e-2
const C2: f64 = f64::from_bits(0xBF56C16C16C15177); // -1.38888888888741095749e-3
const C3: f64 = f64::from_bits(0x3EFA01A019CB1590); // 2.48015872894767294178e-5
const C4: f64 = f64::from_bits(0xBE927E4F809C52AD); // -2.75573143513906633035e-7
const C5: f64 = f64::from_bits(0x3E21EE9EBDB4B1C4); // 2.08757232129817482790e-9
const C6: f64 = f64::from_bits(0xBDA8FAE9BE8838D4); // -1.13596475577881948265e-11

/// `(sin x, cos x)`: [`sin_cos_reduced`] on |x| < [`REDUCED_RANGE`], the platform's
/// `f64::sin_cos` otherwise (and for NaN and infinities).
#[inline]
#[must_use]
pub fn sin_cos(x: f64) -> (f64, f64) {
    if in_reduced_range(x) {
        sin_cos_reduced(x)
    } else {
        x.sin_cos()
    }
}

/// Whether [`sin_cos`] takes [`sin_cos_reduced`] for `x` (|x| < [`REDUCED_RANGE`]; false
/// for NaN): the one test for a caller that runs the reduced body on many angles at once
/// and must fall back where [`sin_cos`] does.
#[inline(always)]
#[must_use]
pub fn in_reduced_range(x: f64) -> bool {
    x.abs() < REDUCED_RANGE
}

/// `(sin x, cos x)` for |x| < [`REDUCED_RANGE`], branch-free (see the module
/// documentation); meaningless beyond that range, where [`sin_cos`] does not call it.
#[inline(always)]
#[must_use]
pub fn sin_cos_reduced(x: f64) -> (f64, f64) {
    // n = nearest integer to x·2/π, its low bits read from the rounded sum's mantissa
    let shifted = x * INV_PIO2 + ROUND_MAGIC;
    let quadrant = shifted.to_bits() & 3;
    let n = shifted - ROUND_MAGIC;
    // y = x − n·π/2 as head + tail (n·PIO2_1 and n·PIO2_2 are exact: n has < 21 bits)
    let r1 = x - n * PIO2_1;
    let w1 = n * PIO2_2;
    let r = r1 - w1;
    let w = n * PIO2_2T - ((r1 - r) - w1);
    let y = r - w;
    let yt = (r - y) - w;
    // the kernels on [−π/4, π/4] with the tail yt
    let z = y * y;
    let zz = z * z;
    let rs = S2 + z * (S3 + z * S4) + z * zz * (S5 + z * S6);
    let v = z * y;
    let sin_k = y - ((z * (0.5 * yt - v * rs) - yt) - v * S1);
    let rc = z * (C1 + z * (C2 + z * C3)) + zz * zz * (C4 + z * (C5 + z * C6));
    let hz = 0.5 * z;
    let one_hz = 1.0 - hz;
    let cos_k = one_hz + (((1.0 - one_hz) - hz) + (z * rc - y * yt));
    // sin x = x exactly when x is below 2⁻²⁶ (keeps the sign of a zero)
    let tiny = x.abs() < 1.490_116_119_384_765_6e-8;
    let sin_k = if tiny { x } else { sin_k };
    // quadrant n mod 4: (s, c), (c, −s), (−s, −c), (−c, s)
    let swap = quadrant & 1 != 0;
    let (s, c) = if swap { (cos_k, sin_k) } else { (sin_k, cos_k) };
    let s = if quadrant & 2 != 0 { -s } else { s };
    let c = if (quadrant + 1) & 2 != 0 { -c } else { c };
    (s, c)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// |a − b| in units of the spacing of doubles at b (the last place of the platform's
    /// value).
    fn ulps(a: f64, b: f64) -> f64 {
        if a == b {
            return 0.0;
        }
        let m = b.abs();
        let spacing = f64::from_bits(m.to_bits() + 1) - m;
        (a - b).abs() / spacing
    }

    fn check(x: f64, worst: &mut f64) {
        let x = if x.is_finite() { x } else { 0.0 };
        let (s, c) = sin_cos(x);
        let (s0, c0) = x.sin_cos();
        let e = ulps(s, s0).max(ulps(c, c0));
        assert!(
            e <= 1.0,
            "sin_cos({x:e}) = ({s:e}, {c:e}), platform ({s0:e}, {c0:e}): {e} ulp"
        );
        *worst = worst.max(e);
    }

    #[test]
    fn agrees_with_the_platform_within_one_ulp() {
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut u = || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut worst: f64 = 0.0;
        for _ in 0..200_000 {
            check((u() * 2.0 - 1.0) * 7.0, &mut worst);
        }
        for _ in 0..100_000 {
            check((u() * 2.0 - 1.0) * REDUCED_RANGE, &mut worst);
        }
        // around the multiples of π/4 up to the range, where reduction and quadrant change
        for k in -2000..2000 {
            for step in [-3i64, -1, 0, 1, 3] {
                let x = f64::from_bits(
                    (k as f64 * std::f64::consts::FRAC_PI_4)
                        .to_bits()
                        .wrapping_add_signed(step),
                );
                check(x, &mut worst);
                check(x * 61.0, &mut worst);
            }
        }
        // tiny, subnormal and boundary magnitudes
        for x in [
            1e-300, 5e-324, 1e-9, 1.49e-8, 1.5e-8, 1e-5, 0.785, 99_999.99,
        ] {
            check(x, &mut worst);
            check(-x, &mut worst);
        }
        assert!(worst <= 1.0);
        eprintln!("worst difference from the platform: {worst} ulp");
    }

    #[test]
    fn exact_at_zero_and_platform_beyond_the_range() {
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
        let (s, c) = sin_cos(-0.0);
        assert!(s == 0.0 && s.is_sign_negative() && c == 1.0);
        assert_eq!(sin_cos(1e-10), (1e-10, 1.0));
        for x in [REDUCED_RANGE, -3.0e7, 1e300] {
            assert_eq!(sin_cos(x), x.sin_cos());
        }
        let (s, c) = sin_cos(f64::NAN);
        assert!(s.is_nan() && c.is_nan());
        let (s, c) = sin_cos(f64::INFINITY);
        assert!(s.is_nan() && c.is_nan());
    }

    #[test]
    fn a_loop_over_lanes_gives_the_scalar_bits() {
        let xs: Vec<f64> = (0..4096).map(|i| (i as f64 - 2048.0) * 0.013_7).collect();
        let mut s = vec![0.0; xs.len()];
        let mut c = vec![0.0; xs.len()];
        for (k, x) in xs.iter().enumerate() {
            (s[k], c[k]) = sin_cos_reduced(*x);
        }
        for (k, x) in xs.iter().enumerate() {
            assert_eq!((s[k].to_bits(), c[k].to_bits()), {
                let (a, b) = sin_cos(*x);
                (a.to_bits(), b.to_bits())
            });
        }
    }
}

//! The box-constrained quadratic program of one stage of the backward pass:
//! `min ½ δᵀ H δ + gᵀ δ` subject to `lo ≤ δ ≤ hi`, by projected Newton (Bertsekas 1982,
//! as Tassa, Mansard and Todorov use it in box-constrained DDP, ICRA 2014): each
//! iteration fixes the components that sit on a bound with the gradient pushing outward
//! (the clamped set), takes the Newton step in the others and searches along its
//! projection onto the box.
//!
//! The Hessian of the free components is factorised in place in an `n × n` buffer whose
//! clamped rows and columns are replaced by the identity, so solves with it leave the
//! clamped components at zero and nothing is allocated after [`BoxQp::new`].

use nalgebra::{DMatrix, DVector};

use crate::linalg::{cholesky_in_place, cholesky_solve};

/// Newton iterations at most.
const MAX_ITERATIONS: usize = 30;
/// Stop when the free part of the gradient is below this norm.
const GRADIENT_TOLERANCE: f64 = 1e-10;
/// Armijo fraction of the projected line search.
const ARMIJO: f64 = 0.1;
/// Smallest projected step length tried.
const MIN_STEP: f64 = 1e-12;

/// Workspace and result of the box QP.
#[derive(Clone, Debug)]
pub struct BoxQp {
    /// The solution δ.
    pub x: DVector<f64>,
    /// Whether each component is clamped at the solution.
    pub clamped: Vec<bool>,
    /// Cholesky factor (lower) of the free block of H, identity on the clamped rows.
    pub factor: DMatrix<f64>,
    grad: DVector<f64>,
    step: DVector<f64>,
    trial: DVector<f64>,
    factored: Vec<bool>,
}

impl BoxQp {
    /// A workspace for `n` variables.
    #[must_use]
    pub fn new(n: usize) -> Self {
        Self {
            x: DVector::zeros(n),
            clamped: vec![false; n],
            factor: DMatrix::zeros(n, n),
            grad: DVector::zeros(n),
            step: DVector::zeros(n),
            trial: DVector::zeros(n),
            factored: vec![true; n],
        }
    }

    /// Solves the QP from the start point `x0` (projected onto the box first). Returns
    /// `false` if the free block of `h` is not positive definite (the caller regularises
    /// and tries again). On success `self.factor` factorises the free block of the final
    /// clamped set.
    pub fn solve(
        &mut self,
        h: &DMatrix<f64>,
        g: &DVector<f64>,
        lo: &DVector<f64>,
        hi: &DVector<f64>,
        x0: &DVector<f64>,
    ) -> bool {
        let n = g.len();
        for i in 0..n {
            self.x[i] = x0[i].clamp(lo[i], hi[i]);
        }
        let mut have_factor = false;
        for _ in 0..MAX_ITERATIONS {
            h.mul_to(&self.x, &mut self.grad);
            self.grad += g;
            let mut changed = !have_factor;
            let mut n_free = 0;
            let mut free_norm2 = 0.0;
            for i in 0..n {
                let c = (self.x[i] <= lo[i] && self.grad[i] > 0.0)
                    || (self.x[i] >= hi[i] && self.grad[i] < 0.0);
                self.clamped[i] = c;
                changed |= c == self.factored[i];
                if !c {
                    n_free += 1;
                    free_norm2 += self.grad[i] * self.grad[i];
                }
            }
            if n_free == 0 {
                return self.factorize(h);
            }
            if changed {
                if !self.factorize(h) {
                    return false;
                }
                have_factor = true;
            }
            if free_norm2.sqrt() < GRADIENT_TOLERANCE {
                return true;
            }
            // Newton step on the free components, zero on the clamped ones.
            for i in 0..n {
                self.step[i] = if self.clamped[i] { 0.0 } else { -self.grad[i] };
            }
            cholesky_solve(&self.factor, &mut self.step);
            let f0 = self.value(h, g);
            let mut alpha = 1.0;
            let mut accepted = false;
            while alpha >= MIN_STEP {
                for i in 0..n {
                    self.trial[i] = (self.x[i] + alpha * self.step[i]).clamp(lo[i], hi[i]);
                }
                std::mem::swap(&mut self.x, &mut self.trial);
                let f1 = self.value(h, g);
                // Predicted decrease along the projected step: g·(x1 − x0).
                let mut pred = 0.0;
                for i in 0..n {
                    pred += self.grad[i] * (self.x[i] - self.trial[i]);
                }
                if f1 - f0 <= ARMIJO * pred {
                    accepted = true;
                    break;
                }
                std::mem::swap(&mut self.x, &mut self.trial);
                alpha *= 0.5;
            }
            if !accepted {
                // No decrease along the projection: x is optimal to rounding.
                return true;
            }
        }
        true
    }

    /// `½ xᵀ H x + gᵀ x` at the current `x`.
    fn value(&self, h: &DMatrix<f64>, g: &DVector<f64>) -> f64 {
        let n = g.len();
        let mut v = 0.0;
        for j in 0..n {
            let xj = self.x[j];
            if xj == 0.0 {
                continue;
            }
            let mut col = 0.0;
            for i in 0..n {
                col += h[(i, j)] * self.x[i];
            }
            v += xj * (0.5 * col + g[j]);
        }
        v
    }

    /// Factorises the free block of `h` for the current clamped set.
    fn factorize(&mut self, h: &DMatrix<f64>) -> bool {
        let n = h.nrows();
        for j in 0..n {
            for i in 0..n {
                self.factor[(i, j)] = if self.clamped[i] || self.clamped[j] {
                    if i == j { 1.0 } else { 0.0 }
                } else {
                    h[(i, j)]
                };
            }
        }
        for i in 0..n {
            self.factored[i] = !self.clamped[i];
        }
        cholesky_in_place(&mut self.factor, 1e-14).is_ok()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 2-variable QP whose unconstrained minimum (1, −3) lies outside the box
    /// [−1, 2] × [−1, 1]: the solution is found by hand from the KKT conditions.
    #[test]
    fn clamps_the_component_pushed_out_and_solves_the_rest() {
        // H = [[2, 1], [1, 2]], unconstrained minimum x* = (1, −3): g = −H x* = (1, 5).
        let h = DMatrix::from_row_slice(2, 2, &[2.0, 1.0, 1.0, 2.0]);
        let g = DVector::from_vec(vec![1.0, 5.0]);
        let lo = DVector::from_vec(vec![-1.0, -1.0]);
        let hi = DVector::from_vec(vec![2.0, 1.0]);
        let mut qp = BoxQp::new(2);
        assert!(qp.solve(&h, &g, &lo, &hi, &DVector::zeros(2)));
        // x2 = −1 (clamped: gradient 2 x2 + x1 + 5 > 0 there); x1 minimises
        // x1² + x1 x2 + x1 = x1² at x2 = −1 → x1 = 0.
        assert!((qp.x[1] + 1.0).abs() < 1e-12, "{}", qp.x);
        assert!(qp.x[0].abs() < 1e-12, "{}", qp.x);
        assert_eq!(qp.clamped, vec![false, true]);
    }

    #[test]
    fn reports_an_indefinite_free_block() {
        let h = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        let g = DVector::from_vec(vec![0.1, 0.1]);
        let inf = DVector::from_element(2, f64::INFINITY);
        let mut qp = BoxQp::new(2);
        assert!(!qp.solve(&h, &g, &(-&inf), &inf, &DVector::zeros(2)));
    }
}

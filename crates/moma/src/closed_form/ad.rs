//! Forward-mode automatic differentiation for the closed-form models.
//!
//! Each model writes its mass matrix, potential energy, constraint row, velocity basis and
//! task map **once**, generic over [`Real`]. Evaluating them with [`Dual`] numbers gives
//! the exact partial derivatives (∂H/∂q_k for the Christoffel symbols, ∂V/∂q for G,
//! directional derivatives for Ṅ_C, Ċ and J̇) to rounding, with no finite differences.

use std::ops::{Add, Mul, Neg, Sub};

/// The scalar operations the closed-form expressions need (`f64` or a [`Dual`]).
pub trait Real:
    Copy
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Neg<Output = Self>
    + Mul<f64, Output = Self>
    + Add<f64, Output = Self>
{
    /// A constant (zero derivative).
    fn cst(x: f64) -> Self;
    /// Sine.
    fn sin(self) -> Self;
    /// Cosine.
    fn cos(self) -> Self;
    /// The value part.
    fn re(self) -> f64;
}

impl Real for f64 {
    #[inline]
    fn cst(x: f64) -> Self {
        x
    }
    #[inline]
    fn sin(self) -> Self {
        f64::sin(self)
    }
    #[inline]
    fn cos(self) -> Self {
        f64::cos(self)
    }
    #[inline]
    fn re(self) -> f64 {
        self
    }
}

/// A dual number `re + Σ du_k ε_k` with `K` independent infinitesimals (ε_i ε_j = 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dual<const K: usize> {
    /// Value.
    pub re: f64,
    /// Partial derivatives with respect to the `K` seeds.
    pub du: [f64; K],
}

impl<const K: usize> Dual<K> {
    /// The `k`-th seed variable with value `x` (derivative 1 along seed `k`).
    pub fn var(x: f64, k: usize) -> Self {
        let mut du = [0.0; K];
        du[k] = 1.0;
        Dual { re: x, du }
    }
    /// A value with a given derivative vector.
    pub fn new(re: f64, du: [f64; K]) -> Self {
        Dual { re, du }
    }
}

impl<const K: usize> Add for Dual<K> {
    type Output = Self;
    #[inline]
    fn add(mut self, o: Self) -> Self {
        self.re += o.re;
        for k in 0..K {
            self.du[k] += o.du[k];
        }
        self
    }
}

impl<const K: usize> Sub for Dual<K> {
    type Output = Self;
    #[inline]
    fn sub(mut self, o: Self) -> Self {
        self.re -= o.re;
        for k in 0..K {
            self.du[k] -= o.du[k];
        }
        self
    }
}

impl<const K: usize> Mul for Dual<K> {
    type Output = Self;
    #[inline]
    fn mul(self, o: Self) -> Self {
        let mut du = [0.0; K];
        for k in 0..K {
            du[k] = self.du[k] * o.re + self.re * o.du[k];
        }
        Dual {
            re: self.re * o.re,
            du,
        }
    }
}

impl<const K: usize> Neg for Dual<K> {
    type Output = Self;
    #[inline]
    fn neg(mut self) -> Self {
        self.re = -self.re;
        for k in 0..K {
            self.du[k] = -self.du[k];
        }
        self
    }
}

impl<const K: usize> Mul<f64> for Dual<K> {
    type Output = Self;
    #[inline]
    fn mul(mut self, s: f64) -> Self {
        self.re *= s;
        for k in 0..K {
            self.du[k] *= s;
        }
        self
    }
}

impl<const K: usize> Add<f64> for Dual<K> {
    type Output = Self;
    #[inline]
    fn add(mut self, s: f64) -> Self {
        self.re += s;
        self
    }
}

impl<const K: usize> Real for Dual<K> {
    #[inline]
    fn cst(x: f64) -> Self {
        Dual {
            re: x,
            du: [0.0; K],
        }
    }
    #[inline]
    fn sin(self) -> Self {
        let (s, c) = self.re.sin_cos();
        let mut du = self.du;
        for d in du.iter_mut() {
            *d *= c;
        }
        Dual { re: s, du }
    }
    #[inline]
    fn cos(self) -> Self {
        let (s, c) = self.re.sin_cos();
        let mut du = self.du;
        for d in du.iter_mut() {
            *d *= -s;
        }
        Dual { re: c, du }
    }
    #[inline]
    fn re(self) -> f64 {
        self.re
    }
}

/// Seeds `q` as `N` independent variables (for full gradients / Jacobians).
pub fn seed_all<const N: usize>(q: &[f64; N]) -> [Dual<N>; N] {
    std::array::from_fn(|k| Dual::var(q[k], k))
}

/// Seeds `q` with the single direction `qdot` (for time derivatives along a motion).
pub fn seed_direction<const N: usize>(q: &[f64; N], qdot: &[f64; N]) -> [Dual<1>; N] {
    std::array::from_fn(|k| Dual::new(q[k], [qdot[k]]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn product_and_trig_rules() {
        let x = Dual::<2>::var(0.7, 0);
        let y = Dual::<2>::var(-1.3, 1);
        let f = x.sin() * y.cos() * 2.0 + x * y;
        assert!((f.re - (2.0 * 0.7f64.sin() * (-1.3f64).cos() - 0.91)).abs() < 1e-15);
        assert!((f.du[0] - (2.0 * 0.7f64.cos() * (-1.3f64).cos() - 1.3)).abs() < 1e-15);
        assert!((f.du[1] - (-2.0 * 0.7f64.sin() * (-1.3f64).sin() + 0.7)).abs() < 1e-15);
    }
}

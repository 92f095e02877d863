//! Noise on the state a feedback law measures ([`SensorNoise`]): the `[uncertainty]`
//! sensor noise of `moma simulate` and `moma mission`, drawn by the held-input loop
//! (`sim::held_loop::run_held_loop`, its one way in).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

use crate::error::{Error, Result};

/// Additive zero-mean Gaussian noise on a measured state: each call of
/// [`SensorNoise::measure`] gives `q + σ_q ⊙ n_q` and `v + σ_v ⊙ n_v` with fresh standard
/// normal `n` (Box–Muller on a ChaCha8 generator of the given seed; the coordinates
/// first, then the velocities, in order). A clone continues the same sequence. Does not
/// allocate.
#[derive(Clone, Debug)]
pub struct SensorNoise {
    std_q: Vec<f64>,
    std_v: Vec<f64>,
    rng: ChaCha8Rng,
}

impl SensorNoise {
    /// Per-coordinate standard deviations `std_q` (one per configuration coordinate) and
    /// `std_v` (one per velocity), noise drawn from `seed`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming `std_q[i]` / `std_v[i]` for a negative or non-finite
    /// deviation.
    pub fn new(std_q: Vec<f64>, std_v: Vec<f64>, seed: u64) -> Result<Self> {
        for (name, xs) in [("std_q", &std_q), ("std_v", &std_v)] {
            if let Some(i) = xs.iter().position(|s| !(s.is_finite() && *s >= 0.0)) {
                return Err(Error::invalid(
                    format!("{name}[{i}]"),
                    format!("must be a finite number >= 0, got {}", xs[i]),
                ));
            }
        }
        Ok(Self {
            std_q,
            std_v,
            rng: ChaCha8Rng::seed_from_u64(seed),
        })
    }

    /// Number of coordinates and of velocities it measures.
    #[must_use]
    pub fn sizes(&self) -> (usize, usize) {
        (self.std_q.len(), self.std_v.len())
    }

    /// Writes the measurement of the state `(q, v)` into `(q_out, v_out)`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming `sensor noise` if a length differs from
    /// [`SensorNoise::sizes`].
    pub fn measure(
        &mut self,
        q: &[f64],
        v: &[f64],
        q_out: &mut [f64],
        v_out: &mut [f64],
    ) -> Result<()> {
        let (nq, nv) = self.sizes();
        if [q.len(), q_out.len()] != [nq; 2] || [v.len(), v_out.len()] != [nv; 2] {
            return Err(Error::invalid(
                "sensor noise",
                format!(
                    "deviations for {nq} coordinates and {nv} velocities, the state has {} and {}",
                    q.len(),
                    v.len()
                ),
            ));
        }
        for ((m, x), s) in q_out.iter_mut().zip(q).zip(&self.std_q) {
            *m = x + s * standard_normal(&mut self.rng);
        }
        for ((m, x), s) in v_out.iter_mut().zip(v).zip(&self.std_v) {
            *m = x + s * standard_normal(&mut self.rng);
        }
        Ok(())
    }
}

/// A standard normal draw (Box–Muller; `u1` in `(0, 1]` so its logarithm is finite).
pub fn standard_normal(rng: &mut ChaCha8Rng) -> f64 {
    let u1: f64 = 1.0 - rng.random::<f64>();
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn standard_normal_has_unit_variance() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let n = 20_000;
        let xs: Vec<f64> = (0..n).map(|_| standard_normal(&mut rng)).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        // 4-sigma bands of the sample mean (1/√n) and variance (√(2/n)).
        assert!(mean.abs() < 4.0 / (n as f64).sqrt(), "{mean}");
        assert!((var - 1.0).abs() < 4.0 * (2.0 / n as f64).sqrt(), "{var}");
    }
}

//! The `[uncertainty]` table shared by `moma simulate` and `moma mission` files: how the
//! plant differs from the model the controller keeps (a payload on a named link, a scale
//! on the link masses, the wheels' friction μ on the contact plant) and the noise on the
//! state the controller measures, each drawn from a stated distribution with a seed. The
//! schema, its checks and the draw ([`UncertaintySpec::draw`]) live here, below both
//! files' readers; a draw perturbs the plant's model
//! ([`crate::sim::model_mismatch::ModelPerturbation`]) and gives the sensor noise
//! ([`sensor_noise`]) the run hands to its held-input loop; the law's own (nominal)
//! model is never touched. Schema in `docs/simulate.md`.

use std::path::Path;

use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result, at, chain};
use crate::multibody::Model;
use crate::sim::model_mismatch::{ModelPerturbation, Payload};
use crate::sim::sensor_noise::{SensorNoise, standard_normal};

/// An [`Error::Scenario`] with a formatted message.
macro_rules! bail {
    ($($t:tt)*) => {
        return Err(Error::Scenario(format!($($t)*)))
    };
}

/// A scalar drawn from a distribution: a fixed number, `{ uniform = [lo, hi] }` or
/// `{ normal = [mean, std] }` (truncated to mean ± 3 std by redrawing).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, Serialize)]
#[serde(untagged)]
pub enum Dist {
    /// This value.
    Fixed(f64),
    /// Uniform on `[lo, hi]`.
    Uniform {
        /// `[lo, hi]`.
        uniform: [f64; 2],
    },
    /// Normal `(mean, std)`, truncated to `mean ± 3 std`.
    Normal {
        /// `[mean, std]`.
        normal: [f64; 2],
    },
}

/// Truncation of [`Dist::Normal`] in standard deviations.
pub const NORMAL_TRUNCATION: f64 = 3.0;

impl Dist {
    /// The smallest and largest value it can draw.
    #[must_use]
    pub fn support(&self) -> (f64, f64) {
        match *self {
            Dist::Fixed(x) => (x, x),
            Dist::Uniform { uniform: [lo, hi] } => (lo, hi),
            Dist::Normal { normal: [m, s] } => {
                (m - NORMAL_TRUNCATION * s, m + NORMAL_TRUNCATION * s)
            }
        }
    }

    /// Checks the parameters (finite, `lo <= hi`, `std >= 0`) and that every value it can
    /// draw is at least `min` (or above it, when `strict`) and at most `max`.
    fn check(&self, field: &str, min: f64, strict: bool, max: f64) -> Result<()> {
        let params: &[f64] = match self {
            Dist::Fixed(x) => std::slice::from_ref(x),
            Dist::Uniform { uniform } => uniform,
            Dist::Normal { normal } => normal,
        };
        if let Some(i) = crate::error::first_non_finite(params) {
            bail!("{field}: parameter {i} is not a finite number");
        }
        match *self {
            Dist::Uniform { uniform: [lo, hi] } if lo > hi => {
                bail!("{field}: uniform = [lo, hi] needs lo <= hi, got {lo} > {hi}")
            }
            Dist::Normal { normal: [_, s] } if s < 0.0 => {
                bail!("{field}: normal = [mean, std] needs std >= 0, got {s}")
            }
            _ => {}
        }
        let (lo, hi) = self.support();
        if hi > max || lo < -max {
            bail!(
                "{field}: can draw {:e}, beyond the bound {max:e} (for a normal, mean ± \
                 {NORMAL_TRUNCATION} std)",
                if hi > max { hi } else { lo }
            );
        }
        if lo < min || (strict && lo <= min) {
            bail!(
                "{field}: can draw {lo:e}, the value must be {} {min} (for a normal, \
                 mean - {NORMAL_TRUNCATION} std)",
                if strict { ">" } else { ">=" }
            );
        }
        Ok(())
    }

    /// A draw from the generator of `seed` on its own `stream`, so each quantity's draw
    /// depends only on the seed and the quantity.
    #[must_use]
    pub fn draw(&self, seed: u64, stream: u64) -> f64 {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        rng.set_stream(stream);
        match *self {
            Dist::Fixed(x) => x,
            Dist::Uniform { uniform: [lo, hi] } => lo + (hi - lo) * rng.random::<f64>(),
            Dist::Normal { normal: [m, s] } => loop {
                let z = standard_normal(&mut rng);
                if z.abs() <= NORMAL_TRUNCATION {
                    break m + s * z;
                }
            },
        }
    }
}

/// `payload = { link, mass, position }`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PayloadSpec {
    /// The link (a frame of the robot description).
    pub link: String,
    /// Mass (kg, every draw ≥ 0).
    pub mass: Dist,
    /// Position in the link's frame (m), default its origin.
    #[serde(default = "origin")]
    pub position: [Dist; 3],
}

fn origin() -> [Dist; 3] {
    [Dist::Fixed(0.0); 3]
}

/// `sensor_noise = { q = [...], v = [...] }`: standard deviations of zero-mean Gaussian
/// noise on each measured coordinate and velocity (default 0).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct SensorNoiseSpec {
    /// One per reduced coordinate `[x, y, θ, joints…]` (m or rad).
    #[serde(default)]
    pub q: Option<Vec<f64>>,
    /// One per reduced velocity `[v, ω, arm rates…]` (m/s or rad/s).
    #[serde(default)]
    pub v: Option<Vec<f64>>,
}

/// The `[uncertainty]` table.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct UncertaintySpec {
    /// Seed of every draw.
    pub seed: u64,
    /// A payload on a named link.
    #[serde(default)]
    pub payload: Option<PayloadSpec>,
    /// Factor on every link's mass and rotational inertia (every draw > 0).
    #[serde(default)]
    pub link_mass_scale: Option<Dist>,
    /// The wheels' friction μ (contact plant only; every draw > 0).
    #[serde(default)]
    pub mu: Option<Dist>,
    /// Noise on the measured state.
    #[serde(default)]
    pub sensor_noise: Option<SensorNoiseSpec>,
}

/// What one seed drew.
#[derive(Clone, Debug, PartialEq)]
pub struct Draw {
    /// The plant's model perturbation.
    pub perturbation: ModelPerturbation,
    /// The wheels' friction μ, if drawn.
    pub mu: Option<f64>,
    /// Seed of the measurement noise.
    pub noise_seed: u64,
}

// Bounds of the draws, far beyond any robot's, inside what its dynamics can integrate (a
// payload of 1e300 kg, a mass scale of 1e-300 or a noise of 1e300 only ended the run in a
// singular mass matrix or a non-finite energy, naming no field).
/// Largest payload mass (kg).
pub const MAX_PAYLOAD_MASS: f64 = 1e4;
/// Largest payload offset from its link's origin, per axis (m).
pub const MAX_PAYLOAD_OFFSET: f64 = 100.0;
/// Smallest link mass scale (the largest is its inverse).
pub const MIN_MASS_SCALE: f64 = 1e-3;
/// Largest friction coefficient μ.
pub const MAX_MU: f64 = 100.0;
/// Largest sensor-noise standard deviation (m, rad, m/s or rad/s).
pub const MAX_NOISE_STD: f64 = 100.0;

// The generator stream of each quantity.
const STREAM_PAYLOAD_MASS: u64 = 1;
const STREAM_PAYLOAD_POSITION: u64 = 2; // 2, 3, 4
const STREAM_MASS_SCALE: u64 = 5;
const STREAM_MU: u64 = 6;

impl UncertaintySpec {
    /// Checks every distribution (finite parameters; a payload mass ≥ 0, a mass scale and
    /// μ > 0 for every value they can draw), naming `uncertainty.<field>`.
    ///
    /// # Errors
    /// [`Error::Scenario`] with the field's message.
    pub fn check(&self) -> Result<()> {
        if let Some(p) = &self.payload {
            p.mass
                .check("uncertainty.payload.mass", 0.0, false, MAX_PAYLOAD_MASS)?;
            for (i, d) in p.position.iter().enumerate() {
                d.check(
                    &format!("uncertainty.payload.position[{i}]"),
                    f64::NEG_INFINITY,
                    false,
                    MAX_PAYLOAD_OFFSET,
                )?;
            }
        }
        if let Some(d) = &self.link_mass_scale {
            d.check(
                "uncertainty.link_mass_scale",
                MIN_MASS_SCALE,
                false,
                1.0 / MIN_MASS_SCALE,
            )?;
        }
        if let Some(d) = &self.mu {
            d.check("uncertainty.mu", 0.0, true, MAX_MU)?;
        }
        if let Some(n) = &self.sensor_noise {
            for (name, xs) in [("q", &n.q), ("v", &n.v)] {
                if let Some(xs) = xs
                    && let Some(i) = xs
                        .iter()
                        .position(|s| !(s.is_finite() && (0.0..=MAX_NOISE_STD).contains(s)))
                {
                    bail!(
                        "uncertainty.sensor_noise.{name}[{i}] must be a number in [0, \
                         {MAX_NOISE_STD}], got {:e}",
                        xs[i]
                    );
                }
            }
        }
        Ok(())
    }

    /// The draws of this table's seed.
    #[must_use]
    pub fn draw(&self) -> Draw {
        let s = self.seed;
        let payload = self.payload.as_ref().map(|p| Payload {
            link: p.link.clone(),
            mass: p.mass.draw(s, STREAM_PAYLOAD_MASS),
            position: Vector3::from_fn(|i, _| {
                p.position[i].draw(s, STREAM_PAYLOAD_POSITION + i as u64)
            }),
        });
        Draw {
            perturbation: ModelPerturbation {
                mass_scale: self
                    .link_mass_scale
                    .map_or(1.0, |d| d.draw(s, STREAM_MASS_SCALE)),
                payload,
            },
            mu: self.mu.map(|d| d.draw(s, STREAM_MU)),
            noise_seed: s,
        }
    }

    /// True if a noise deviation is positive.
    #[must_use]
    pub fn has_noise(&self) -> bool {
        self.sensor_noise
            .as_ref()
            .is_some_and(|n| n.q.iter().chain(n.v.iter()).flatten().any(|s| *s > 0.0))
    }
}

/// Applies a scenario's draw to the plant's `model`, with errors naming
/// `uncertainty.payload.link` and so on.
///
/// # Errors
/// [`Error::Scenario`] naming the file and field.
pub fn perturb(draw: &Draw, model: &mut Model, path: &Path) -> Result<()> {
    draw.perturbation.apply(model).map_err(|e| match e {
        Error::InvalidInput { field, message } => Error::Scenario(at(
            path,
            &format!(
                "uncertainty.{}: {message}",
                if field == "mass_scale" {
                    "link_mass_scale"
                } else {
                    field.as_str()
                }
            ),
        )),
        e => Error::Scenario(at(path, &format!("uncertainty: {}", chain(&e)))),
    })
}

/// The table's sensor noise on a measured state whose coordinate and velocity names are
/// `names` (their counts are the sizes; the names make the error of a wrong length),
/// seeded by the draw; `None` when no deviation is positive.
///
/// # Errors
/// [`Error::Scenario`] naming `uncertainty.sensor_noise.q` / `.v` for a wrong length.
pub fn sensor_noise(
    spec: &UncertaintySpec,
    names: (&[String], &[String]),
    path: &Path,
) -> Result<Option<SensorNoise>> {
    let Some(n) = spec.sensor_noise.as_ref().filter(|_| spec.has_noise()) else {
        return Ok(None);
    };
    let mut stds = Vec::with_capacity(2);
    for (field, given, want) in [("q", &n.q, names.0), ("v", &n.v, names.1)] {
        let s = given.clone().unwrap_or_else(|| vec![0.0; want.len()]);
        if s.len() != want.len() {
            bail!(
                "{}",
                at(
                    path,
                    &format!(
                        "uncertainty.sensor_noise.{field}: expected {} values ({}), got {}",
                        want.len(),
                        want.join(", "),
                        s.len()
                    )
                )
            );
        }
        stds.push(s);
    }
    let std_v = stds.pop().unwrap_or_default();
    let std_q = stds.pop().unwrap_or_default();
    SensorNoise::new(std_q, std_v, spec.draw().noise_seed)
        .map(Some)
        .map_err(|e| Error::Scenario(at(path, &format!("uncertainty.sensor_noise: {e}"))))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(text: &str) -> UncertaintySpec {
        toml::from_str(text).unwrap()
    }

    #[test]
    fn draws_stay_in_their_support_and_depend_on_the_seed_and_quantity_only() {
        let d = Dist::Normal { normal: [1.0, 0.1] };
        let xs: Vec<f64> = (0..2000).map(|s| d.draw(s, 1)).collect();
        assert!(xs.iter().all(|x| (0.7..=1.3).contains(x)));
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        // The sample mean of 2000 draws of std ≤ 0.1: within 4 × 0.1/√2000 of 1.
        assert!((mean - 1.0).abs() < 4.0 * 0.1 / 2000f64.sqrt(), "{mean}");
        let u = Dist::Uniform {
            uniform: [2.0, 3.0],
        };
        let ys: Vec<f64> = (0..2000).map(|s| u.draw(s, 5)).collect();
        assert!(ys.iter().all(|y| (2.0..=3.0).contains(y)));
        assert!(ys.iter().any(|y| *y < 2.1) && ys.iter().any(|y| *y > 2.9));
        // Adding μ does not change the payload's draw.
        let a = spec("seed = 4\npayload = { link = \"tool\", mass = { uniform = [0, 2] } }");
        let b = spec(
            "seed = 4\nmu = { normal = [0.8, 0.1] }\n\
             payload = { link = \"tool\", mass = { uniform = [0, 2] } }",
        );
        assert_eq!(a.draw().perturbation, b.draw().perturbation);
        let c = spec("seed = 5\npayload = { link = \"tool\", mass = { uniform = [0, 2] } }");
        assert_ne!(a.draw().perturbation, c.draw().perturbation);
    }

    #[test]
    fn bad_distributions_name_the_field() {
        let e = |t: &str| spec(t).check().unwrap_err().to_string();
        assert!(e("seed = 1\nmu = { normal = [0.5, 0.2] }").contains("uncertainty.mu: can draw"));
        assert!(e("seed = 1\nmu = 0.0").contains("uncertainty.mu"));
        assert!(
            e("seed = 1\nlink_mass_scale = { uniform = [1.2, 0.8] }")
                .contains("uncertainty.link_mass_scale: uniform = [lo, hi] needs lo <= hi")
        );
        assert!(
            e("seed = 1\npayload = { link = \"a\", mass = { uniform = [-1, 1] } }")
                .contains("uncertainty.payload.mass")
        );
        assert!(
            e("seed = 1\nsensor_noise = { q = [0.0, -0.1] }")
                .contains("uncertainty.sensor_noise.q[1]")
        );
        assert!(toml::from_str::<UncertaintySpec>("seed = 1\nfriction = 0.3").is_err());
    }
}

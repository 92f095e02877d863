//! Model mismatch between the plant and the controller: a perturbation of the plant's
//! rigid-body model (a scale on every link's mass and rotational inertia, a point-mass
//! payload on a named link) and noise on the state the feedback law measures. The law
//! keeps its nominal model; only the plant's [`Model`] is perturbed
//! ([`ModelPerturbation::apply`]), and the law sees the plant's state through
//! [`NoisyMeasurement`] (its [`SensorNoise`] in `sim::sensor_noise`).
//!
//! What is drawn (the values of a perturbation, the seed of the noise) is the caller's
//! (`sim::uncertainty` reads and draws them from a file's `[uncertainty]`).

use crate::error::{Error, Result};
use crate::multibody::Model;
use crate::sim::closed_loop::{FeedbackLaw, Observation, SaturationFlags};
use crate::sim::mpc_run::MpcRun;
use crate::sim::sensor_noise::SensorNoise;
use crate::spatial::Inertia;
use nalgebra::Vector3;

/// A point mass attached to a link.
#[derive(Clone, Debug, PartialEq)]
pub struct Payload {
    /// The link (a frame of the model) it sits on.
    pub link: String,
    /// Mass (kg, ≥ 0).
    pub mass: f64,
    /// Position in the link's frame (m).
    pub position: Vector3<f64>,
}

/// A perturbation of a plant's rigid-body model.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelPerturbation {
    /// Factor on every body's mass and rotational inertia about its centre of mass
    /// (centres of mass unchanged); 1 leaves the model as it is.
    pub mass_scale: f64,
    /// A point mass added to a link, if any.
    pub payload: Option<Payload>,
}

impl Default for ModelPerturbation {
    fn default() -> Self {
        Self {
            mass_scale: 1.0,
            payload: None,
        }
    }
}

impl ModelPerturbation {
    /// Applies the perturbation to `model`: every body's inertia scaled by
    /// [`ModelPerturbation::mass_scale`], then the payload added to the body that carries
    /// its link's frame, at the link-frame position mapped into that body's frame.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming `payload.link` for an unknown link or one on the
    /// fixed world, `mass_scale` unless positive and finite, `payload.mass` unless finite
    /// and ≥ 0, `payload.position` unless finite. The model is unchanged on error.
    pub fn apply(&self, model: &mut Model) -> Result<()> {
        crate::error::ensure_positive("mass_scale", self.mass_scale)?;
        let attach = match &self.payload {
            None => None,
            Some(p) => {
                if !(p.mass.is_finite() && p.mass >= 0.0) {
                    return Err(Error::invalid(
                        "payload.mass",
                        format!("must be a finite number >= 0, got {}", p.mass),
                    ));
                }
                crate::error::ensure_finite("payload.position", p.position.iter())?;
                let f = model
                    .frame_id(&p.link)
                    .map_err(|e| Error::invalid("payload.link", e.to_string()))?;
                let fr = &model.frames[f.0];
                if fr.parent_joint.0 == 0 {
                    return Err(Error::invalid(
                        "payload.link",
                        format!("'{}' is not on a moving body", p.link),
                    ));
                }
                Some((
                    fr.parent_joint.0,
                    Inertia::point_mass(p.mass, fr.placement.act_point(&p.position)),
                ))
            }
        };
        let s = self.mass_scale;
        for inertia in model.inertias.iter_mut().skip(1) {
            let m = inertia.mass();
            if m > 0.0 {
                *inertia = Inertia::new(s * m, inertia.com(), inertia.inertia_about_com() * s);
            }
        }
        if let Some((j, extra)) = attach {
            model.inertias[j] += extra;
        }
        Ok(())
    }
}

/// A feedback law that measures the state through [`SensorNoise`]: at every
/// [`FeedbackLaw::control`] call the noisy state goes to the inner law. The tracking
/// error and signals it reports ([`FeedbackLaw::observe`], [`FeedbackLaw::signals`]) are
/// those of the true state. Does not allocate after construction.
pub struct NoisyMeasurement {
    inner: Box<dyn FeedbackLaw>,
    noise: SensorNoise,
    q: Vec<f64>,
    v: Vec<f64>,
}

impl NoisyMeasurement {
    /// Wraps `inner` with `noise`.
    #[must_use]
    pub fn new(inner: Box<dyn FeedbackLaw>, noise: SensorNoise) -> Self {
        let (nq, nv) = noise.sizes();
        Self {
            inner,
            noise,
            q: vec![0.0; nq],
            v: vec![0.0; nv],
        }
    }
}

impl FeedbackLaw for NoisyMeasurement {
    fn nu(&self) -> usize {
        self.inner.nu()
    }
    fn error_names(&self) -> Vec<String> {
        self.inner.error_names()
    }
    fn has_lyapunov(&self) -> bool {
        self.inner.has_lyapunov()
    }
    fn control(&mut self, t: f64, q: &[f64], v: &[f64], u: &mut [f64]) -> Result<SaturationFlags> {
        self.noise.measure(q, v, &mut self.q, &mut self.v)?;
        self.inner.control(t, &self.q, &self.v, u)
    }
    fn observe(&mut self, t: f64, q: &[f64], v: &[f64], error: &mut [f64]) -> Result<Observation> {
        self.inner.observe(t, q, v, error)
    }
    fn signal_names(&self) -> Vec<String> {
        self.inner.signal_names()
    }
    fn signals(&mut self, t: f64, q: &[f64], v: &[f64], out: &mut [f64]) -> Result<()> {
        self.inner.signals(t, q, v, out)
    }
    fn mpc_run(&self) -> Option<MpcRun> {
        self.inner.mpc_run()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::urdf::model_from_urdf_file;
    use crate::multibody::RootJoint;

    fn robot() -> Model {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenarios/robots/diffdrive_arm.urdf");
        model_from_urdf_file(path, RootJoint::Planar).unwrap()
    }

    /// Body by body: the scale multiplies mass and rotational inertia and keeps the centre
    /// of mass; the payload's first moment lands on the body carrying its link.
    #[test]
    fn scale_and_payload_change_the_bodies_they_name() {
        let m0 = robot();
        let mut m = m0.clone();
        let p = ModelPerturbation {
            mass_scale: 1.5,
            payload: Some(Payload {
                link: "forearm".into(),
                mass: 2.0,
                position: Vector3::new(0.0, 0.0, 0.3),
            }),
        };
        p.apply(&mut m).unwrap();
        assert!((m.total_mass() - (1.5 * m0.total_mass() + 2.0)).abs() < 1e-9);
        let j = m.frames[m.frame_id("forearm").unwrap().0].parent_joint.0;
        for k in 1..m.njoints {
            let (a, b) = (&m0.inertias[k], &m.inertias[k]);
            if k == j {
                // m c of the body plus the payload's first moment at its position.
                let at = m0.frames[m0.frame_id("forearm").unwrap().0]
                    .placement
                    .act_point(&Vector3::new(0.0, 0.0, 0.3));
                let want = a.com() * (1.5 * a.mass()) + at * 2.0;
                assert!((b.first_moment() - want).norm() < 1e-12);
            } else {
                assert!((b.mass() - 1.5 * a.mass()).abs() < 1e-12);
                assert!((b.com() - a.com()).norm() < 1e-12);
                assert!((b.inertia_about_com() - a.inertia_about_com() * 1.5).norm() < 1e-12);
            }
        }
        let bad = |p: ModelPerturbation| p.apply(&mut robot()).unwrap_err().to_string();
        let mut q = p.clone();
        q.payload.as_mut().unwrap().link = "nope".into();
        assert!(bad(q).contains("payload.link"));
        let mut q = p.clone();
        q.mass_scale = 0.0;
        assert!(bad(q).contains("mass_scale"));
        let mut q = p;
        q.payload.as_mut().unwrap().mass = -1.0;
        assert!(bad(q).contains("payload.mass"));
    }
}

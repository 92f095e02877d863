//! Model mismatch between the plant and the controller: a perturbation of the plant's
//! rigid-body model (a scale on every link's mass and rotational inertia, a point-mass
//! payload on a named link). The law keeps its nominal model; only the plant's [`Model`]
//! is perturbed ([`ModelPerturbation::apply`]). The other half of a mismatch, noise on
//! the state the law measures, is `sim::sensor_noise`'s, drawn by the held-input loop.
//!
//! What is drawn (the values of a perturbation, the seed of the noise) is the caller's
//! (`sim::uncertainty` reads and draws them from a file's `[uncertainty]`).

use crate::error::{Error, Result};
use crate::multibody::Model;
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

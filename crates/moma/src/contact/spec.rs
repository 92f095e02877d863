//! What touches the ground: drive wheels (disks on revolute joints) and casters (spheres
//! fixed to a frame, or at a position in a link's frame).

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::multibody::{FrameKind, Model};

/// A drive wheel: a disk of radius `radius` centred on the origin of the revolute joint
/// `joint`, its axle along the joint axis. Frictional (Coulomb, μ of the contact
/// parameters); it rolls when its contact point does not slip.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WheelSpec {
    /// Name of the wheel's revolute (continuous) joint.
    pub joint: String,
    /// Wheel radius (m, > 0).
    pub radius: f64,
}

/// A caster modelled as a **ball caster**: a sphere of radius `radius`, in frictionless
/// point contact with the ground — it carries normal force only. A free-swivel caster
/// wheel turns to trail its motion and so, apart from rolling resistance and swivel
/// transients (not modelled), transmits no horizontal force either; this is also the
/// caster of the reduced (rolling) model, where a caster adds no constraint.
///
/// The sphere's centre is given one of two ways: on the origin of a frame of the
/// description (`frame`: a link or a fixed-joint frame), or at `position` in the frame
/// of the link `link` (for a description without caster links). Exactly one of the two.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CasterSpec {
    /// Name of the frame at the sphere's centre; or `link` and `position`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub frame: Option<String>,
    /// Name of the link `position` is given in (with `position`, instead of `frame`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub link: Option<String>,
    /// The sphere's centre `[x, y, z]` in `link`'s frame (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub position: Option<[f64; 3]>,
    /// Sphere radius (m, ≥ 0).
    pub radius: f64,
}

/// Where a caster sphere's centre is, resolved on a model.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct CasterPlace {
    /// The caster's name in reports and column names: the frame, or `link [x y z]` (no
    /// commas, so that it stays one CSV field).
    pub name: String,
    /// The joint whose body carries it.
    pub joint: usize,
    /// The centre in that joint's frame (m).
    pub centre: Vector3<f64>,
}

impl CasterSpec {
    /// A caster of radius `radius` centred on the origin of `frame`.
    #[must_use]
    pub fn on_frame(frame: impl Into<String>, radius: f64) -> Self {
        Self {
            frame: Some(frame.into()),
            link: None,
            position: None,
            radius,
        }
    }

    /// A caster of radius `radius` centred at `position` in the frame of `link`.
    #[must_use]
    pub fn at_position(link: impl Into<String>, position: [f64; 3], radius: f64) -> Self {
        Self {
            frame: None,
            link: Some(link.into()),
            position: Some(position),
            radius,
        }
    }

    /// The centre of caster `k` (its index in `contact.casters`) on `model`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the field (`contact.casters[k].frame`, `.link`,
    /// `.position`): both or neither of `frame` and `link`/`position`, one of `link` and
    /// `position` without the other, a frame or link the model lacks;
    /// [`Error::NonFinite`] for a non-finite `position`.
    pub(crate) fn place(&self, k: usize, model: &Model) -> Result<CasterPlace> {
        let field = |f: &str| format!("contact.casters[{k}].{f}");
        match (&self.frame, &self.link, &self.position) {
            (Some(frame), None, None) => {
                let f = model.frame_id(frame).map_err(|_| {
                    Error::invalid(field("frame"), format!("the model has no frame '{frame}'"))
                })?;
                let fr = &model.frames[f.0];
                Ok(CasterPlace {
                    name: frame.clone(),
                    joint: fr.parent_joint.0,
                    centre: fr.placement.translation,
                })
            }
            (None, Some(link), Some(p)) => {
                if crate::error::first_non_finite(p).is_some() {
                    return Err(Error::NonFinite {
                        field: field("position"),
                    });
                }
                let fr = model
                    .frames
                    .iter()
                    .find(|f| f.kind == FrameKind::Body && &f.name == link)
                    .ok_or_else(|| {
                        Error::invalid(field("link"), format!("the model has no link '{link}'"))
                    })?;
                Ok(CasterPlace {
                    name: format!("{link} [{} {} {}]", p[0], p[1], p[2]),
                    joint: fr.parent_joint.0,
                    centre: fr.placement.act_point(&Vector3::from(*p)),
                })
            }
            (Some(_), _, _) => Err(Error::invalid(
                field(if self.position.is_some() {
                    "position"
                } else {
                    "link"
                }),
                "give the caster either on a frame (frame) or by its position in a link's \
                 frame (link and position), not both",
            )),
            (None, None, None) => Err(Error::invalid(
                field("frame"),
                "missing: give frame, or link and position",
            )),
            (None, Some(_), None) => Err(Error::invalid(
                field("position"),
                "missing: the centre [x, y, z] in the frame of link",
            )),
            (None, None, Some(_)) => Err(Error::invalid(
                field("link"),
                "missing: the link whose frame position is given in",
            )),
        }
    }
}

//! What touches the ground: drive wheels (disks on revolute joints) and casters (spheres
//! fixed to a frame).

use serde::{Deserialize, Serialize};

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

/// A caster modelled as a **ball caster**: a sphere of radius `radius` centred on the
/// origin of frame `frame` (a link or a fixed-joint frame), in frictionless point contact
/// with the ground — it carries normal force only. A free-swivel caster wheel turns to
/// trail its motion and so, apart from rolling resistance and swivel transients (not
/// modelled), transmits no horizontal force either; this is also the caster of the
/// reduced (rolling) model, where a caster adds no constraint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CasterSpec {
    /// Name of the frame at the sphere's centre.
    pub frame: String,
    /// Sphere radius (m, ≥ 0).
    pub radius: f64,
}

//! The mission's footprint: the disk about the base frame origin that the configuration
//! space dilates the obstacles by, either typed in the file (`robot.footprint_radius`) or
//! taken from the robot's collision geometry at its transport posture (`robot.footprint
//! = "robot"`).
//!
//! The mission's planner (D* Lite on a disk-dilated grid, `plan.rs`) takes a disk, so the
//! robot's footprint enters as the radius of the smallest disk about the base frame origin
//! that holds the footprint polygon ([`crate::collision::footprint`]: the convex hull of
//! every collision shape projected on the ground), plus the file's padding. The polygon is
//! kept for the summary.

use nalgebra::DVector;

use crate::collision::{GeometryData, GeometryModel, footprint, update_geometry_placements};
use crate::mobile::WheeledModel;
use crate::multibody::Data;

/// Where the mission's footprint came from.
#[derive(Debug, Clone, PartialEq)]
pub enum FootprintSource {
    /// `robot.footprint_radius`, typed in the file.
    Radius,
    /// The robot's collision geometry at the transport posture.
    Robot {
        /// The footprint polygon in the base frame (x forward, y left; m),
        /// counter-clockwise.
        polygon: Vec<[f64; 2]>,
        /// The radius of the smallest disk about the base frame origin that holds the
        /// polygon (m), before the padding.
        circumscribed: f64,
        /// Added to `circumscribed` (m).
        padding: f64,
    },
}

/// The footprint the mission plans and monitors with.
#[derive(Debug, Clone, PartialEq)]
pub struct MissionFootprint {
    /// Radius (m) of the disk about the base frame origin that covers the robot.
    pub radius: f64,
    /// Where it came from.
    pub source: FootprintSource,
}

impl MissionFootprint {
    /// A radius typed in the file.
    #[must_use]
    pub fn given(radius: f64) -> Self {
        Self {
            radius,
            source: FootprintSource::Radius,
        }
    }

    /// The footprint of `robot` (with collision geometry `gm`) with its arm joints at
    /// `arm` (one angle per [`WheeledModel::arm_dofs`] entry) and the platform at the
    /// origin, the other joints (the wheels) at zero: the polygon in the base frame and
    /// the disk about the base frame origin that holds it, grown by `padding`.
    #[must_use]
    pub fn from_robot(robot: &WheeledModel, gm: &GeometryModel, arm: &[f64], padding: f64) -> Self {
        let model = &robot.model;
        let mut q = DVector::zeros(model.nq);
        for (&i, &a) in robot.arm_dofs().iter().zip(arm) {
            q[i] = a;
        }
        let mut data = Data::new(model);
        crate::kinematics::forward_kinematics(model, &mut data, &q);
        let mut gd = GeometryData::new(gm);
        update_geometry_placements(gm, &data, &mut gd);
        // The planar root at q = 0 puts the base frame on the world frame.
        let polygon: Vec<[f64; 2]> = footprint(gm, &gd, &mut Vec::new())
            .iter()
            .map(|p| [p.x, p.y])
            .collect();
        let circumscribed = polygon.iter().map(|p| p[0].hypot(p[1])).fold(0.0, f64::max);
        Self {
            radius: circumscribed + padding,
            source: FootprintSource::Robot {
                polygon,
                circumscribed,
                padding,
            },
        }
    }

    /// The footprint as `summary.json` reports it: `source` (`"footprint_radius"` or
    /// `"robot"`), `radius` (m), and for the robot's footprint the `posture`
    /// (`"transport"`), the `polygon` in the base frame, the `circumscribed` radius and
    /// the `padding`.
    #[must_use]
    pub fn to_json(&self) -> serde_json::Value {
        use serde_json::json;
        match &self.source {
            FootprintSource::Radius => json!({
                "source": "footprint_radius",
                "radius": self.radius,
            }),
            FootprintSource::Robot {
                polygon,
                circumscribed,
                padding,
            } => json!({
                "source": "robot",
                "posture": "transport",
                "radius": self.radius,
                "circumscribed": circumscribed,
                "padding": padding,
                "polygon": polygon,
            }),
        }
    }
}

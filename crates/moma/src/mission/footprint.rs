//! The mission's footprint: the disk about the base frame origin that the configuration
//! space dilates the obstacles by, either typed in the file (`robot.footprint_radius`) or
//! taken from the robot's collision geometry at its transport posture (`robot.footprint
//! = "robot"`).
//!
//! A typed radius is planned as that disk. The robot's footprint is the polygon
//! [`crate::collision::footprint`] gives (the convex hull of every collision shape
//! projected on the ground): the mission searches the C-space of the largest disk about
//! the driven-axle midpoint inside it ([`MissionFootprint::planning_polygon`], a lower
//! bound: a pose that disk blocks, the polygon blocks at every heading) and checks the
//! smoothed, timed path with the polygon at each sample's heading (`plan.rs`,
//! [`crate::planning::footprint_clearance`]); [`MissionFootprint::radius`], the disk about
//! the base frame origin that holds the polygon, plus the padding, is the fallback when
//! no path the polygon passes is found.

use nalgebra::{DVector, Vector2};

use crate::collision::footprint::hull_2d;
use crate::collision::{
    GeometryData, GeometryModel, footprint, outline_points, update_geometry_placements,
};
use crate::mobile::WheeledModel;
use crate::multibody::Data;
use crate::planning::costmap::Footprint;

/// The collision geometry of `robot` placed with its arm joints at `arm` (one angle per
/// [`WheeledModel::arm_dofs`] entry), the other joints (the wheels) at zero and the
/// planar root at q = 0, which puts the base frame on the world frame.
pub(crate) fn placed_at_posture(
    robot: &WheeledModel,
    gm: &GeometryModel,
    arm: &[f64],
) -> GeometryData {
    let model = &robot.model;
    let mut q = DVector::zeros(model.nq);
    for (&i, &a) in robot.arm_dofs().iter().zip(arm) {
        q[i] = a;
    }
    let mut data = Data::new(model);
    crate::kinematics::forward_kinematics(model, &mut data, &q);
    let mut gd = GeometryData::new(gm);
    update_geometry_placements(gm, &data, &mut gd);
    gd
}

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
        let gd = placed_at_posture(robot, gm, arm);
        let polygon: Vec<[f64; 2]> = footprint(gm, &gd, &mut Vec::new())
            .iter()
            .map(|p| [p.x, p.y])
            .collect();
        Self::of_polygon(polygon, padding)
    }

    /// The footprint of `polygon` (base frame): the disk about the base frame origin that
    /// holds it, grown by `padding`.
    fn of_polygon(polygon: Vec<[f64; 2]>, padding: f64) -> Self {
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

    /// The footprint while carrying: with the robot's polygon, the convex hull of it and
    /// of the held object's collision shapes (the last link of `carried`, the robot's
    /// geometry with the object attached) projected on the ground with the arm joints at
    /// `arm`, the platform at the origin; the same footprint when the object's outline
    /// lies inside the polygon. A typed radius is kept as typed (it is taken to cover
    /// what the robot carries).
    #[must_use]
    pub fn carrying(&self, robot: &WheeledModel, carried: &GeometryModel, arm: &[f64]) -> Self {
        let FootprintSource::Robot {
            polygon, padding, ..
        } = &self.source
        else {
            return self.clone();
        };
        let Some(held) = carried.links.last() else {
            return self.clone();
        };
        let gd = placed_at_posture(robot, carried, arm);
        let mut points = Vec::new();
        for k in held.first..held.first + held.count {
            outline_points(&carried.objects[k].shape, &gd.placements[k], &mut points);
        }
        let outside = |p: &Vector2<f64>| {
            let n = polygon.len();
            n < 3
                || (0..n).any(|k| {
                    let (a, b) = (polygon[k], polygon[(k + 1) % n]);
                    (b[0] - a[0]) * (p.y - a[1]) - (b[1] - a[1]) * (p.x - a[0]) < 0.0
                })
        };
        if !points.iter().map(|p| p.xy()).any(|p| outside(&p)) {
            return self.clone();
        }
        let hull = hull_2d(
            polygon
                .iter()
                .map(|p| Vector2::new(p[0], p[1]))
                .chain(points.iter().map(|p| p.xy())),
        );
        Self::of_polygon(hull.iter().map(|p| [p.x, p.y]).collect(), *padding)
    }

    /// The padding (m) the footprint keeps from the obstacles: the file's for the
    /// robot's polygon, 0 for a typed radius (the radius covers it).
    #[must_use]
    pub fn padding(&self) -> f64 {
        match &self.source {
            FootprintSource::Radius => 0.0,
            FootprintSource::Robot { padding, .. } => *padding,
        }
    }

    /// The robot's polygon for the heading-aware check, with the base frame origin `d`
    /// ahead of the driven-axle midpoint: the polygon in the base frame and the radius
    /// of the largest disk about the axle midpoint inside it (m, before the padding).
    /// `None` for a typed radius, and for a polygon that does not hold the axle midpoint
    /// strictly inside (that disk would not be a lower bound; the mission then plans on
    /// the circumscribed disk).
    #[must_use]
    pub fn planning_polygon(&self, d: f64) -> Option<(Footprint, f64)> {
        let FootprintSource::Robot { polygon, .. } = &self.source else {
            return None;
        };
        let about_axle = Footprint::new(polygon.iter().map(|p| [p[0] + d, p[1]]).collect()).ok()?;
        let inscribed = about_axle.inscribed_radius();
        (inscribed > 0.0).then_some(())?;
        Some((Footprint::new(polygon.clone()).ok()?, inscribed))
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

//! Obstacles with heights: boxes placed on the map (`[[map.boxes]]`: a pose `[x, y, yaw]`
//! on the map, a size and a z range) and the objects of a `[task]`'s scene, each checked
//! once at load in 3-D against the robot's collision geometry at the transport posture
//! ([`block_by_height`]), then rasterised into the map as blocked, or left out when the
//! robot passes under it.
//!
//! The check: the robot, placed anywhere on the map at any heading, meets a box spanning
//! z₀..z₁ (a scene object: its bounding box's z extent) exactly when some of its
//! geometry lies within the horizontal slab z₀ ≤ z ≤ z₁
//! (the planner may put any part of the robot under the box's outline). So the verdict
//! is the signed distance ([`crate::collision::compute_scene_distances`]) from the robot's
//! geometry to that slab, taken over the whole footprint: a box whose slab the robot
//! clears by more than the footprint's padding is not an obstacle (a table top the base
//! passes under with the arm tucked); any other box blocks the cells its outline covers
//! (a table the raised arm would hit). One distance query per box, at load.
//!
//! A pick's drive on carries the object: the same check with the object attached to the
//! robot's geometry ([`HeldObjectBlocks`], `Mission::drive_on_map`) blocks, on the drive
//! on's map, the objects the robot passes under bare but not holding it (a can held above
//! the robot's top under a table top the robot alone clears).

use nalgebra::{Matrix3, Rotation3, Vector3};
use serde::{Deserialize, Serialize};

use super::footprint::placed_at_posture;
use crate::collision::footprint::hull_2d;
use crate::collision::{
    Convex, GeometryData, GeometryModel, Scene, SceneData, SceneObject, compute_scene_distances,
    footprint, outline_points,
};
use crate::error::{Error, Result};
use crate::mobile::WheeledModel;
use crate::planning::OccupancyGrid;
use crate::planning::costmap::{CellContact, polygon_cells};
use crate::planning::grid::OCCUPIED;
use crate::spatial::SE3;

/// `[[map.boxes]]`: a box standing on or above the map.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    /// Centre `[x, y]` on the map (m, world) and yaw (rad) of the box's x side.
    pub pose: [f64; 3],
    /// Side lengths `[along its x, along its y]` (m).
    pub size: [f64; 2],
    /// Heights of its bottom and top `[z_min, z_max]` above the ground (m).
    pub z: [f64; 2],
}

/// What the 3-D check decided for one box.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BoxVerdict {
    /// The signed distance (m) from the robot's geometry at the transport posture to the
    /// box's height slab (negative: the robot reaches into it).
    pub clearance: f64,
    /// `true`: the box is an obstacle of the map (clearance not above the padding).
    pub blocked: bool,
}

impl BoxSpec {
    /// Checks the numbers (`field` names the box in errors): finite, positive sides, a
    /// bottom at or above the ground and below the top.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming `field` and the entry.
    pub fn check(&self, field: &str) -> Result<()> {
        for (k, x) in [
            ("pose", &self.pose[..]),
            ("size", &self.size[..]),
            ("z", &self.z[..]),
        ] {
            if let Some(i) = crate::error::first_non_finite(x) {
                return Err(Error::invalid(
                    format!("{field}.{k}"),
                    format!("entry {i} is not a finite number"),
                ));
            }
        }
        if self.size.iter().any(|&s| s <= 0.0) {
            return Err(Error::invalid(
                format!("{field}.size"),
                format!("sides must be positive, got {:?}", self.size),
            ));
        }
        if !(self.z[0] >= 0.0 && self.z[0] < self.z[1]) {
            return Err(Error::invalid(
                format!("{field}.z"),
                format!(
                    "needs 0 <= z_min < z_max (m above the ground), got {:?}",
                    self.z
                ),
            ));
        }
        Ok(())
    }

    /// The box as a scene object named `id`.
    ///
    /// # Errors
    /// As [`SceneObject::new`] (never for a checked box).
    pub fn object(&self, id: &str) -> Result<SceneObject> {
        let [x, y, yaw] = self.pose;
        let rotation: Matrix3<f64> = *Rotation3::from_axis_angle(&Vector3::z_axis(), yaw).matrix();
        let pose = SE3::new(rotation, Vector3::new(x, y, 0.5 * (self.z[0] + self.z[1])));
        let half = Vector3::new(
            0.5 * self.size[0],
            0.5 * self.size[1],
            0.5 * (self.z[1] - self.z[0]),
        );
        SceneObject::new(id, vec![(pose, Convex::Box { half })])
    }
}

/// The signed distance (m) from the robot's geometry placed in `gd` (base frame on the
/// world frame) to the horizontal slab `z[0] ≤ z ≤ z[1]` under and around its whole
/// footprint.
#[must_use]
pub fn slab_clearance(gm: &GeometryModel, gd: &mut GeometryData, z: [f64; 2]) -> f64 {
    let reach = footprint(gm, gd, &mut Vec::new())
        .iter()
        .map(|p| p.norm())
        .fold(0.0, f64::max);
    let half = Vector3::new(reach + 1.0, reach + 1.0, 0.5 * (z[1] - z[0]));
    let pose = SE3::from_translation(Vector3::new(0.0, 0.0, 0.5 * (z[0] + z[1])));
    let slab = SceneObject::new("slab", vec![(pose, Convex::Box { half })])
        .expect("one shape, a valid object");
    let scene = Scene {
        objects: vec![slab],
    };
    let mut sd = SceneData::new(gm, &scene);
    compute_scene_distances(gm, gd, &scene, &mut sd)
}

/// Marks occupied every cell of `grid` that the ground outline of `objects` overlaps
/// (per shape, the convex hull of the shape projected on the ground, [`outline_points`]);
/// returns the number of cells newly occupied. The one rasteriser of scene objects placed
/// on a mission's map: the boxes the robot cannot pass under and a `[task]`'s furniture
/// (cells off the map are ignored).
pub fn block_scene_footprint(grid: &mut OccupancyGrid, objects: &[SceneObject]) -> usize {
    let mut points = Vec::new();
    let mut newly = 0;
    for s in objects.iter().flat_map(|o| &o.shapes) {
        points.clear();
        outline_points(&s.shape, &s.pose, &mut points);
        let hull: Vec<[f64; 2]> = hull_2d(points.iter().map(|p| p.xy()))
            .iter()
            .map(|p| grid.world_to_cell_f(p.x, p.y))
            .collect();
        for (x, y) in polygon_cells(&hull, grid.width, grid.height, CellContact::Overlapping) {
            let c = &mut grid.cells[y * grid.width + x];
            if *c != OCCUPIED {
                *c = OCCUPIED;
                newly += 1;
            }
        }
    }
    newly
}

/// Checks each box of `boxes` against `robot`'s geometry `gm` at the arm posture
/// `transport` and blocks on `grid` those whose slab the robot does not clear by more
/// than `padding` (m); the boxes as scene objects (named `map.boxes[k]`) and their
/// verdicts, in file order ([`block_by_height`]).
///
/// # Errors
/// A box with invalid numbers (named `map.boxes[k]`).
pub fn place_boxes(
    grid: &mut OccupancyGrid,
    boxes: &[BoxSpec],
    robot: &WheeledModel,
    gm: &GeometryModel,
    transport: &[f64],
    padding: f64,
) -> Result<(Vec<SceneObject>, Vec<BoxVerdict>)> {
    let objects = boxes
        .iter()
        .enumerate()
        .map(|(k, b)| {
            let field = format!("map.boxes[{k}]");
            b.check(&field)?;
            b.object(&field)
        })
        .collect::<Result<Vec<_>>>()?;
    let verdicts = block_by_height(grid, &objects, robot, gm, transport, padding);
    Ok((objects, verdicts))
}

/// The one rasteriser of objects with heights on a mission's map (`[[map.boxes]]` and a
/// `[task]`'s scene): each object's height range (its bounding box's z extent) is a slab,
/// checked once against `robot`'s geometry `gm` at the arm posture `transport`
/// ([`slab_clearance`]); the objects whose slab the robot does not clear by more than
/// `padding` (m) block the cells of their ground outline ([`block_scene_footprint`]), the
/// others (a table top the robot passes under) are left off the map. The verdicts in
/// the order of `objects`.
pub fn block_by_height(
    grid: &mut OccupancyGrid,
    objects: &[SceneObject],
    robot: &WheeledModel,
    gm: &GeometryModel,
    transport: &[f64],
    padding: f64,
) -> Vec<BoxVerdict> {
    if objects.is_empty() {
        return Vec::new();
    }
    let mut gd = placed_at_posture(robot, gm, transport);
    let mut blocked = Vec::new();
    let verdicts = objects
        .iter()
        .map(|o| {
            let (lo, hi) = o.aabb();
            let clearance = slab_clearance(gm, &mut gd, [lo.z, hi.z]);
            let v = BoxVerdict {
                clearance,
                // (a distance that is not a number blocks)
                blocked: clearance.is_nan() || clearance <= padding,
            };
            if v.blocked {
                blocked.push(o.clone());
            }
            v
        })
        .collect();
    block_scene_footprint(grid, &blocked);
    verdicts
}

/// An obstacle with a height that holding an object changes: the robot at the transport
/// posture passes under it bare, and holding the object it does not.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HeldObjectBlocks {
    /// Its name: `map.boxes[k]`, or the `[task]` scene object's id.
    pub name: String,
    /// The verdict on the robot's geometry.
    pub bare: BoxVerdict,
    /// The verdict on the robot's geometry with the object attached.
    pub holding: BoxVerdict,
}

/// The map of a drive on that holds an object: blocks on `grid` (the mission's map,
/// where each of `objects` is blocked by its verdict in `bare`, aligned with it) the
/// objects whose slab `carried`, the robot's geometry with the object attached
/// ([`GeometryModel::with_attached`]), does not clear by more than `padding` (m) at the
/// arm posture `transport` ([`block_by_height`] on that geometry); returns those that the
/// bare robot passed under, in the order of `objects` (each named by its id).
pub fn block_by_height_holding(
    grid: &mut OccupancyGrid,
    objects: &[SceneObject],
    bare: &[BoxVerdict],
    robot: &WheeledModel,
    carried: &GeometryModel,
    transport: &[f64],
    padding: f64,
) -> Vec<HeldObjectBlocks> {
    let holding = block_by_height(grid, objects, robot, carried, transport, padding);
    objects
        .iter()
        .zip(bare)
        .zip(holding)
        .filter(|((_, bare), holding)| holding.blocked && !bare.blocked)
        .map(|((o, bare), holding)| HeldObjectBlocks {
            name: o.id.clone(),
            bare: *bare,
            holding,
        })
        .collect()
}

/// The map a pick's drive on plans on: the mission's, with the obstacles with heights
/// that the robot holding the object does not pass under blocked
/// ([`block_by_height_holding`]).
#[derive(Debug, Clone)]
pub struct DriveOnMap {
    /// The map.
    pub grid: OccupancyGrid,
    /// The obstacles it blocks that the mission's map leaves off (the robot passes under
    /// them bare), in the order of `[[map.boxes]]` then the scene's objects.
    pub blocks: Vec<HeldObjectBlocks>,
}

//! The planning pipeline of `moma plan`, the Python `plan` and the mission (its first
//! plan, the drive on after a pick and the `reference` of `moma simulate`): a map, a
//! footprint, start and goal, a search and limits in; the configuration space, the cell
//! path, the smoothed path and the timed reference out. With [`Search::DStarLite`] the
//! plan hands over the D* Lite state, which the mission keeps re-planning incrementally
//! as obstacles appear.
//!
//! Coordinates and lengths are in the map's own units ([`MapFrame`]): world metres on a
//! ROS map, cells on a Moving AI map. The footprint is a point, a disk (the obstacles
//! dilated by its radius, one distance transform; a cell is blocked when its centre lies
//! within the radius plus half a cell of an obstacle cell's centre,
//! [`costmap::disk_reach`]) or a polygon in the robot frame. A planned point behind the
//! footprint's origin ([`PlanRequest::axle_offset`], the driven-axle midpoint of a base
//! whose frame lies `d` ahead of it) dilates the disk by `|d|`. A
//! polygon is searched over (x, y, heading) on the 8-heading lattice of
//! [`costmap::footprint_cspace`] (each heading's C-space exact for obstacle cells taken
//! as the squares they cover: a pose is blocked when the polygon there meets one; blocked
//! within the inscribed radius plus half a cell, free beyond the circumscribed radius
//! plus half a cell's diagonal, the polygon tested against the squares in the band
//! between; turns in place checked on the swept footprint), so the path's every pose and
//! turn is collision-free at the heading it is driven with, which nav2's Smac planners
//! also do on their heading lattices.
//!
//! A point or disk plan may also be checked with a convex polygon
//! ([`PlanRequest::polygon_check`], nav2's way with a polygon footprint on a cheap
//! C-space): every pose of the timed reference with the polygon at the pose's heading
//! ([`PathCheck`]); the plan lists the cells of the poses that collide
//! ([`Plan::colliding`]) and hands the check over ([`Plan::path_check`]). The start and
//! goal poses are checked too, at the request's headings ([`PlanRequest::start_yaw`],
//! [`PlanRequest::goal_yaw`]) or else at the timed path's there: a collision there is an
//! error naming the request's field, the robot cannot stand there. The mission
//! plans so: D* Lite on the disk inside its footprint polygon, which re-plans
//! incrementally on (x, y) cells, each path it re-times checked with the polygon.

use super::costmap::{self, Footprint, InflationParams};
use super::curve_timing::{CurvatureTiming, TimedCurve, time_cells_curved};
use std::time::Instant;

use super::dstar_lite::DStarLite;
use super::edt::distance_transform;
use super::footprint_clearance::{ConvexFootprint, PathCheck};
use super::potential::{DescentEnd, GoalTerm, PotentialParams, descend, potential_field};
use super::smooth::{polyline_length, smooth};
use super::trajectory::{DiffDriveLimits, TrajectoryPoint, time_parameterize};
use super::{MapKind, OccupancyGrid, SearchGrid, astar};
use crate::{Error, Result};

/// The frame a request's points and lengths are in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Frame {
    /// The map's own units: world metres on a ROS map; cells on a Moving AI map, points
    /// being cells (`moma plan`, the Python `plan`).
    #[default]
    Map,
    /// World coordinates on every map (a point anywhere in a cell,
    /// [`OccupancyGrid::world_to_cell`]; lengths over the map's resolution): the
    /// mission's, whose robot stands anywhere.
    World,
}

/// A map with the frame its user's coordinates are in.
#[derive(Debug, Clone, Copy)]
pub struct MapFrame<'a> {
    /// The map.
    pub grid: &'a OccupancyGrid,
    /// The frame of the coordinates.
    pub frame: Frame,
}

impl<'a> MapFrame<'a> {
    /// The map's own frame of `grid` ([`Frame::Map`]).
    #[must_use]
    pub fn new(grid: &'a OccupancyGrid) -> Self {
        Self::in_frame(grid, Frame::Map)
    }

    /// `grid` with coordinates in `frame`.
    #[must_use]
    pub fn in_frame(grid: &'a OccupancyGrid, frame: Frame) -> Self {
        Self { grid, frame }
    }

    /// `true` in world units (a ROS map, or [`Frame::World`]), `false` in cells (a
    /// Moving AI map in its own frame).
    #[must_use]
    pub fn world(&self) -> bool {
        self.frame == Frame::World || self.grid.kind == MapKind::Ros
    }

    /// A length in map units in cells.
    #[must_use]
    pub fn units_to_cells(&self, v: f64) -> f64 {
        if self.world() {
            v / self.grid.resolution
        } else {
            v
        }
    }

    /// A length in cells in map units.
    #[must_use]
    pub fn cells_to_units(&self, v: f64) -> f64 {
        if self.world() {
            v * self.grid.resolution
        } else {
            v
        }
    }

    /// `"m"` or `"cells"`.
    #[must_use]
    pub fn units(&self) -> &'static str {
        if self.world() { "m" } else { "cells" }
    }

    /// A cell in the user's frame: `(x, y) m (cell (i, j))` on a ROS map (the cell
    /// centre's world coordinates), `cell (i, j)` on a Moving AI map.
    #[must_use]
    pub fn describe(&self, c: (usize, usize)) -> String {
        if self.world() {
            let [x, y] = self.grid.cell_to_world(c.0 as f64, c.1 as f64);
            format!("({x:.3}, {y:.3}) m (cell ({}, {}))", c.0, c.1)
        } else {
            format!("cell ({}, {})", c.0, c.1)
        }
    }

    /// The cell of a point given in the user's frame (`what` names it in errors).
    ///
    /// # Errors
    /// A point off the map; on a Moving AI map, a point that is not a cell (integers).
    pub fn cell_of(&self, what: &str, x: f64, y: f64) -> Result<(usize, usize)> {
        let g = self.grid;
        if self.world() {
            return g.world_to_cell(what, x, y);
        }
        if x < 0.0
            || y < 0.0
            || x.fract() != 0.0
            || y.fract() != 0.0
            || x >= g.width as f64
            || y >= g.height as f64
        {
            return Err(Error::invalid(
                what,
                format!(
                    "({}, {}) must be a cell of the {} x {} map (integers from 0)",
                    short(x),
                    short(y),
                    g.width,
                    g.height
                ),
            ));
        }
        Ok((x as usize, y as usize))
    }
}

/// A number for a message: plain when moderate, in exponent form when huge or tiny.
fn short(x: f64) -> String {
    if x == 0.0 || (1e-4..1e6).contains(&x.abs()) || !x.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// The robot's shape on the ground, in map units, about the planned point.
#[derive(Debug, Clone, PartialEq)]
pub enum RobotFootprint {
    /// A point: the C-space is the map's obstacles.
    Point,
    /// A disk of this radius (≥ 0).
    Disk(f64),
    /// A polygon in the robot frame (containing its origin); searched over 8 headings.
    Polygon(Footprint),
}

/// The search over the C-space.
#[derive(Debug, Clone, PartialEq)]
pub enum Search {
    /// A* (octile, no corner cutting).
    Astar,
    /// D* Lite (its first plan; the cost of A*).
    DStarLite,
    /// A* over nav2-style inflation costs (lengths in map units).
    CostAware {
        /// The inflation layer's parameters.
        inflation: InflationParams,
        /// The cost travel multiplier.
        cost_multiplier: f64,
    },
    /// Steepest descent of a potential field.
    Potential {
        /// Euclidean or geodesic goal term.
        term: GoalTerm,
        /// Goal weight w.
        goal_weight: f64,
        /// Obstacle influence range in map units (`None`: 5 cells).
        influence: Option<f64>,
    },
}

/// The names the caller's user set the inputs by, for the errors (`moma plan`:
/// [`PlanFields::default`]; the mission: `start.pose`, `goal.pose`,
/// `robot.footprint_radius`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PlanFields {
    /// The start's field.
    pub start: &'static str,
    /// The goal's field.
    pub goal: &'static str,
    /// The disk footprint's radius field.
    pub radius: &'static str,
}

impl Default for PlanFields {
    /// `start`, `goal`, `radius` (`moma plan`'s and the Python `plan`'s names).
    fn default() -> Self {
        Self {
            start: "start",
            goal: "goal",
            radius: "radius",
        }
    }
}

/// What to plan.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanRequest {
    /// Start `[x, y]` in map units.
    pub start: [f64; 2],
    /// Start heading (rad, world frame); `None` faces the first segment.
    pub start_yaw: Option<f64>,
    /// Goal `[x, y]` in map units.
    pub goal: [f64; 2],
    /// Goal heading (rad, world frame): the curvature-limited timing arrives with it (and
    /// needs it), the polygon check checks the goal pose at it; `None` arrives along the
    /// last segment (the stop-and-turn timing's end, which takes none).
    pub goal_yaw: Option<f64>,
    /// The frame of the points and lengths.
    pub frame: Frame,
    /// Unknown cells are obstacles (else free).
    pub unknown_is_obstacle: bool,
    /// The robot's shape.
    pub footprint: RobotFootprint,
    /// How far ahead of the planned point (start, goal and path) the footprint's origin
    /// lies along the heading, in map units: the `d` of a base planned at its driven-axle
    /// midpoint. A disk footprint is then searched on the obstacles dilated by
    /// `radius + |axle_offset|`, the disk about the planned point that holds the
    /// footprint at every heading (exact for 0). Only with a point or disk footprint.
    pub axle_offset: f64,
    /// The names of the inputs in the caller's errors.
    pub fields: PlanFields,
    /// The search.
    pub search: Search,
    /// Turn cost per 45° of the polygon search (cells of travel).
    pub turn_cost: f64,
    /// Shortcut smoothing of the cell path (the polygon's path is never shortcut: its
    /// headings hold only along the cells searched).
    pub smooth: bool,
    /// The timing; `None` plans the path alone.
    pub timing: Option<Timing>,
    /// With a point or disk footprint: the polygon the timed reference is checked with,
    /// pose by pose ([`Plan::colliding`]); the check is handed over in
    /// [`Plan::path_check`] (with no timing, for the caller's own timed paths).
    pub polygon_check: Option<PolygonCheck>,
}

/// The convex footprint polygon a point or disk plan's timed path is checked with
/// ([`PathCheck`]): the disk being the largest about the planned point inside the
/// polygon, the C-space never blocks a pose the polygon could take, and the check finds
/// the poses it cannot.
#[derive(Debug, Clone, PartialEq)]
pub struct PolygonCheck {
    /// The polygon about its origin (map units), convex.
    pub polygon: Footprint,
    /// The clearance it must keep from the obstacle cells (map units, ≥ 0).
    pub padding: f64,
    /// How far ahead of the planned point the polygon's origin lies along the heading
    /// (map units; the drive's `d` when the driven-axle midpoint is planned).
    pub ahead: f64,
}

impl PolygonCheck {
    /// The check of the convex polygon `vertices` with `padding`, its origin `ahead` of
    /// the planned point, validated: the errors name the caller's fields, `fields[0]`
    /// the polygon's (fewer than 3 vertices, non-finite, no area, not convex) and
    /// `fields[1]` the padding's (negative or not finite).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming one of `fields`.
    pub fn new(
        vertices: Vec<[f64; 2]>,
        padding: f64,
        ahead: f64,
        fields: [&str; 2],
    ) -> Result<Self> {
        let named = |e: Error| match e {
            Error::InvalidInput { message, .. } => Error::invalid(fields[0], message),
            Error::NonFinite { .. } => Error::invalid(fields[0], "the vertices must be finite"),
            other => other,
        };
        let polygon = Footprint::new(vertices).map_err(named)?;
        ConvexFootprint::new(&polygon, 1.0).map_err(named)?;
        if !(padding.is_finite() && padding >= 0.0) {
            return Err(Error::invalid(
                fields[1],
                format!("must be a finite length >= 0, got {padding}"),
            ));
        }
        Ok(Self {
            polygon,
            padding,
            ahead,
        })
    }
}

/// The polygon check of a plan as `moma plan` writes it in `path.json` (`robot.check`)
/// and the Python `plan` returns it (`check`).
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct PolygonCheckReport {
    /// `"polygon"`.
    pub kind: &'static str,
    /// The polygon's vertices about its origin (map units).
    pub vertices: Vec<[f64; 2]>,
    /// The clearance it keeps (map units).
    pub padding: f64,
    /// [`Plan::colliding`]: the cells of the timed path's poses where it collides.
    pub colliding: Vec<[usize; 2]>,
}

/// `moma plan`'s stop-and-turn limits by default (its `--v-max`, `--omega-max`,
/// `--a-max`, `--alpha-max`; map units per second), which the Python `plan` times a
/// path with to check it with a polygon.
pub const PLAN_LIMITS: DiffDriveLimits = DiffDriveLimits {
    v_max: 0.5,
    omega_max: 1.0,
    a_max: 0.5,
    alpha_max: 2.0,
};

/// `moma plan`'s sampling period by default (s, its `--dt`).
pub const PLAN_DT: f64 = 0.1;

/// How the path is timed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Timing {
    /// Stop and turn: straight segments between the smoothed waypoints, turning in place
    /// at each ([`super::trajectory::time_parameterize`]; `moma plan`'s).
    StopAndTurn {
        /// Platform limits.
        limits: DiffDriveLimits,
        /// Sampling period (s).
        dt: f64,
    },
    /// Curvature-limited: the cell path smoothed under a curvature bound from the start
    /// pose to the goal pose (the headings [`PlanRequest::start_yaw`] and
    /// [`PlanRequest::goal_yaw`] are then required) and timed from rest under the
    /// platform limits and tip-over accelerations ([`time_cells_curved`]; the
    /// mission's). Point and disk footprints only.
    Curvature {
        /// Limits, curvature bound and sampling.
        timing: CurvatureTiming,
    },
}

/// How the search ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlanStatus {
    /// A path to the goal.
    Found,
    /// A potential-field descent stuck in a local minimum (the cells up to it).
    LocalMinimum,
    /// No path: the plan's `report` says why; no cells.
    Unreachable,
}

/// The pipeline's products.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Start cell.
    pub start_cell: (usize, usize),
    /// Goal cell.
    pub goal_cell: (usize, usize),
    /// The map's obstacle cells (`true` = occupied; unknown cells as the request says).
    pub occupied: Vec<bool>,
    /// Distance (cells, centre to centre) from each cell to the nearest occupied cell
    /// ([`distance_transform`] of [`Plan::occupied`]).
    pub distance: Vec<f32>,
    /// The centre-to-centre distance (cells) within which an occupied cell blocks a cell
    /// of the disk C-space: [`costmap::disk_reach`] of the radius plus `|axle_offset|`
    /// (of 0 for a point or polygon).
    pub reach_cells: f64,
    /// The C-space the path lives on (`true` = free); for a polygon, the cells free at
    /// every heading.
    pub cspace: SearchGrid,
    /// With [`Search::DStarLite`]: the D* Lite state after the first plan (its C-space
    /// is [`Plan::cspace`]), to re-plan from incrementally (`move_start`, `set_blocked`,
    /// `compute`).
    pub dstar: Option<DStarLite>,
    /// Wall time of the search (s): building it and finding the path.
    pub search_s: f64,
    /// How the search ended.
    pub status: PlanStatus,
    /// One line on the search's outcome (the reason when unreachable).
    pub report: String,
    /// The cell path, start to goal.
    pub cells: Vec<(usize, usize)>,
    /// Per-cell heading (rad, grid frame) for a polygon.
    pub headings: Option<Vec<f64>>,
    /// Cost in cells (`None` for a stuck descent).
    pub cost_cells: Option<f64>,
    /// Expanded cells or states.
    pub expanded: usize,
    /// The smoothed path's cells (direction changes only without smoothing).
    pub smoothed: Vec<(usize, usize)>,
    /// The smoothed path in map units (cell centres).
    pub waypoints: Vec<[f64; 2]>,
    /// The timed reference (empty without [`PlanRequest::timing`]; with
    /// [`Timing::Curvature`] the pose and speeds of [`Plan::curve`]'s samples).
    pub trajectory: Vec<TrajectoryPoint>,
    /// With [`Timing::Curvature`]: the smoothed geometry and its timed samples.
    pub curve: Option<TimedCurve>,
    /// With [`PlanRequest::polygon_check`]: the check, to check the caller's own paths
    /// (on its own occupied cells) with.
    pub path_check: Option<PathCheck>,
    /// With [`PlanRequest::polygon_check`]: the cells of the [`Plan::trajectory`]'s poses
    /// where the polygon collides (each once, in path order; empty when it passes or
    /// without a trajectory), checked against [`Plan::occupied`].
    pub colliding: Vec<(usize, usize)>,
}

impl Plan {
    /// The plan's outcome as `moma plan` writes it (`status` of `path.json`):
    /// `"unreachable"`, `"local_minimum"`, `"colliding"` (a pose of the timed path where
    /// the polygon check collides) or `"found"`.
    #[must_use]
    pub fn outcome(&self) -> &'static str {
        match self.status {
            PlanStatus::Unreachable => "unreachable",
            PlanStatus::LocalMinimum => "local_minimum",
            PlanStatus::Found if !self.colliding.is_empty() => "colliding",
            PlanStatus::Found => "found",
        }
    }

    /// The polygon check of `req` (the request this plan answers) with its verdict;
    /// `None` without [`PlanRequest::polygon_check`].
    #[must_use]
    pub fn check_report(&self, req: &PlanRequest) -> Option<PolygonCheckReport> {
        req.polygon_check.as_ref().map(|pc| PolygonCheckReport {
            kind: "polygon",
            vertices: pc.polygon.vertices.clone(),
            padding: pc.padding,
            colliding: self.colliding.iter().map(|c| [c.0, c.1]).collect(),
        })
    }
}

/// Runs the pipeline on `grid` (see the module documentation).
///
/// # Errors
/// Start or goal off the map, in an obstacle or unknown cell, or inside the C-space
/// obstacle (each naming the request's field; the start's message says when the
/// footprint fits nowhere on the map), or where the polygon check's polygon collides (at
/// the request's heading, or at the timed path's when it gives none; naming the
/// field); invalid footprint, offset, search or timing
/// parameters; an oversized map or footprint C-space. An unreachable goal is not an
/// error ([`PlanStatus::Unreachable`]).
pub fn plan(grid: &OccupancyGrid, req: &PlanRequest) -> Result<Plan> {
    let mf = MapFrame::in_frame(grid, req.frame);
    let (w, h) = (grid.width, grid.height);
    let fields = req.fields;
    let obst = grid.obstacle_mask(super::grid::OCCUPIED, req.unknown_is_obstacle);
    // validates the map size for the searches before anything else is built
    SearchGrid::from_obstacles(&obst, w, h)?;
    let start = mf.cell_of(fields.start, req.start[0], req.start[1])?;
    let goal = mf.cell_of(fields.goal, req.goal[0], req.goal[1])?;
    for (what, c) in [(fields.start, start), (fields.goal, goal)] {
        if obst[c.1 * w + c.0] {
            let kind = if grid.cells[c.1 * w + c.0] < 0 {
                "an unknown cell (unknown cells are obstacles unless declared free)"
            } else {
                "an obstacle"
            };
            return Err(Error::Planning(format!(
                "{what} at {} lies in {kind}",
                mf.describe(c)
            )));
        }
    }
    let radius = match req.footprint {
        RobotFootprint::Disk(r) => r,
        _ => 0.0,
    };
    if !(radius.is_finite() && radius >= 0.0) {
        return Err(Error::invalid(
            fields.radius,
            format!("must be a finite non-negative number, got {radius}"),
        ));
    }
    let offset = req.axle_offset;
    if !offset.is_finite() || (offset != 0.0 && matches!(req.footprint, RobotFootprint::Polygon(_)))
    {
        return Err(Error::invalid(
            "axle offset",
            format!("must be finite, and 0 with a polygonal footprint, got {offset}"),
        ));
    }
    for (what, yaw) in [(fields.start, req.start_yaw), (fields.goal, req.goal_yaw)] {
        if yaw.is_some_and(|y| !y.is_finite()) {
            return Err(Error::NonFinite {
                field: format!("{what} heading"),
            });
        }
    }
    match req.timing {
        Some(Timing::Curvature { .. })
            if matches!(req.footprint, RobotFootprint::Polygon(_))
                || req.start_yaw.is_none()
                || req.goal_yaw.is_none() =>
        {
            return Err(Error::invalid(
                "timing",
                "the curvature-limited timing needs the start heading, the goal heading and \
                 a point or disk footprint (a polygon's path is timed stop-and-turn, at the \
                 headings searched)",
            ));
        }
        Some(Timing::StopAndTurn { .. }) if req.goal_yaw.is_some() => {
            return Err(Error::invalid(
                "timing",
                format!(
                    "the stop-and-turn timing ends along the path's last segment: it takes no \
                     {} heading",
                    fields.goal
                ),
            ));
        }
        _ => {}
    }
    let dilation = radius + offset.abs();
    let distance = distance_transform(&obst, w, h);
    let reach_cells = costmap::disk_reach(mf.units_to_cells(dilation));
    let blocked = costmap::dilate_disk(&distance, mf.units_to_cells(dilation));
    let cspace = SearchGrid::from_obstacles(&blocked, w, h)?;
    // for an offset the messages say that the planned point is the axle midpoint
    let offset_note = if offset == 0.0 {
        String::new()
    } else {
        format!(
            " (the driven-axle midpoint is planned, {} {u} behind the footprint's origin: \
             on the obstacles dilated by the radius + {} = {} {u})",
            short(offset),
            short(offset.abs()),
            short(dilation),
            u = mf.units()
        )
    };
    for (what, c) in [(fields.start, start), (fields.goal, goal)] {
        if !cspace.is_free(c.0 as i64, c.1 as i64) {
            let nowhere = if blocked.iter().all(|&b| b) {
                "; the footprint fits nowhere on the map (every cell lies within that \
                 distance of an obstacle or unknown cell)"
            } else {
                ""
            };
            return Err(Error::Planning(format!(
                "{what} at {} is closer than the robot radius {} {u} to an obstacle (inside \
                 the configuration-space obstacle): the footprint does not fit there, an \
                 obstacle cell's centre lies {:.3} {u} from it{offset_note}{nowhere}",
                mf.describe(c),
                short(radius),
                mf.cells_to_units(f64::from(distance[c.1 * w + c.0])),
                u = mf.units()
            )));
        }
    }
    let mut path_check = match &req.polygon_check {
        None => None,
        Some(_) if matches!(req.footprint, RobotFootprint::Polygon(_)) => {
            return Err(Error::invalid(
                "polygon check",
                "a polygonal footprint is searched at its headings already; the polygon \
                 check is for a point or disk footprint's path",
            ));
        }
        Some(pc) => Some(PathCheck::new(
            &pc.polygon,
            pc.padding,
            pc.ahead,
            mf.cells_to_units(1.0),
        )?),
    };
    // the ends the request gives headings for; the others at the timed path's (`finish`)
    if let (Some(check), Some(pc)) = (path_check.as_mut(), &req.polygon_check) {
        for (what, point, yaw) in [
            (fields.start, req.start, req.start_yaw),
            (fields.goal, req.goal, req.goal_yaw),
        ] {
            if let Some(yaw) = yaw {
                check_end(&mf, check, pc, &obst, what, point, (yaw, false))?;
            }
        }
    }
    let ends = Ends { start, goal };
    let clock = Instant::now();
    let found = match (&req.footprint, &req.search) {
        (RobotFootprint::Polygon(fp), Search::Astar) => {
            search_polygon(&mf, &obst, &distance, &ends, req, fp)?
        }
        (RobotFootprint::Polygon(_), _) => {
            return Err(Error::invalid(
                "footprint",
                "a polygonal footprint is searched with A* (not D* Lite, cost-aware A* or \
                 a potential field)",
            ));
        }
        (_, Search::Astar | Search::DStarLite) => search_graph(&mf, &ends, req, cspace)?,
        (
            _,
            Search::CostAware {
                inflation,
                cost_multiplier,
            },
        ) => {
            let unknown: Vec<bool> = grid.cells.iter().map(|&v| v < 0).collect();
            let res = if mf.world() { grid.resolution } else { 1.0 };
            let costs = costmap::inflation_layer(&obst, Some(&unknown), w, h, res, inflation)?;
            let sg =
                SearchGrid::from_costs(&costs, w, h, *cost_multiplier, !req.unknown_is_obstacle)?;
            search_graph(&mf, &ends, req, sg)?
        }
        (
            _,
            Search::Potential {
                term,
                goal_weight,
                influence,
            },
        ) => {
            let params = PotentialParams {
                goal_weight: *goal_weight,
                influence: influence.map_or(5.0, |r| mf.units_to_cells(r)),
            };
            search_potential(&mf, &ends, *term, &params, cspace)?
        }
    };
    let search_s = clock.elapsed().as_secs_f64();
    let map = MapProducts {
        occupied: obst,
        distance,
        reach_cells,
        search_s,
        path_check,
    };
    finish(&mf, req, ends, found, map)
}

/// What the pipeline built from the map besides the search's products.
struct MapProducts {
    occupied: Vec<bool>,
    distance: Vec<f32>,
    reach_cells: f64,
    search_s: f64,
    path_check: Option<PathCheck>,
}

/// Start and goal cells.
#[derive(Clone, Copy)]
struct Ends {
    start: (usize, usize),
    goal: (usize, usize),
}

/// What a search found.
struct Found {
    status: PlanStatus,
    report: String,
    cells: Vec<(usize, usize)>,
    headings: Option<Vec<f64>>,
    cost_cells: Option<f64>,
    expanded: usize,
    cspace: SearchGrid,
    dstar: Option<DStarLite>,
}

fn unreachable(report: String, cspace: SearchGrid) -> Found {
    Found {
        status: PlanStatus::Unreachable,
        report,
        cells: Vec::new(),
        headings: None,
        cost_cells: None,
        expanded: 0,
        cspace,
        dstar: None,
    }
}

/// A* over (x, y, 8 headings) for a polygon.
fn search_polygon(
    mf: &MapFrame<'_>,
    obst: &[bool],
    distance: &[f32],
    ends: &Ends,
    req: &PlanRequest,
    fp: &Footprint,
) -> Result<Found> {
    let (w, h) = (mf.grid.width, mf.grid.height);
    let fp_cells = Footprint::new(
        fp.vertices
            .iter()
            .map(|v| [mf.units_to_cells(v[0]), mf.units_to_cells(v[1])])
            .collect(),
    )?;
    let cs = costmap::footprint_cspace_with_distance(obst, distance, w, h, 1.0, &fp_cells, 8)?;
    // A cell is free for smoothing and drawing when it is free at every heading.
    let all_free = cs.slices.iter().fold(vec![true; w * h], |acc, s| {
        acc.iter().zip(s).map(|(a, b)| *a && *b).collect()
    });
    let cspace = SearchGrid::from_obstacles(&all_free, w, h)?;
    let yaw = req.start_yaw.unwrap_or(0.0) - if mf.world() { mf.grid.origin[2] } else { 0.0 };
    let k = ((yaw / std::f64::consts::FRAC_PI_4).round() as i64).rem_euclid(8) as usize;
    let start = (ends.start.0, ends.start.1, k);
    let Some(p) = costmap::astar_footprint(&cs, start, ends.goal, req.turn_cost)? else {
        return Ok(unreachable(
            format!(
                "no path from the start at {} to the goal at {}: the footprint cannot reach \
                 the goal at any sequence of headings (explored the whole reachable (x, y, \
                 heading) space); the robot may be larger than the passages",
                mf.describe(ends.start),
                mf.describe(ends.goal)
            ),
            cspace,
        ));
    };
    Ok(Found {
        status: PlanStatus::Found,
        report: format!(
            "found a path for the footprint (cost {:.3} {}, {} states expanded)",
            mf.cells_to_units(p.cost),
            mf.units(),
            p.expanded
        ),
        cells: p.states.iter().map(|s| (s.0, s.1)).collect(),
        headings: Some(
            p.states
                .iter()
                .map(|s| s.2 as f64 * std::f64::consts::FRAC_PI_4)
                .collect(),
        ),
        cost_cells: Some(p.cost),
        expanded: p.expanded,
        cspace,
        dstar: None,
    })
}

/// A* or D* Lite over `sg`.
fn search_graph(
    mf: &MapFrame<'_>,
    ends: &Ends,
    req: &PlanRequest,
    sg: SearchGrid,
) -> Result<Found> {
    let (start, goal) = (ends.start, ends.goal);
    let (path, expanded, dstar) = if matches!(req.search, Search::DStarLite) {
        let mut d = DStarLite::new(&sg, start, goal)?;
        let c = d.compute();
        let path = c.and_then(|c| d.path().map(|p| (p, c)));
        (path, d.expanded(), Some(d))
    } else {
        let p = astar(&sg, start, goal)?;
        let e = p.as_ref().map_or(0, |p| p.expanded);
        (p.map(|p| (p.cells, p.cost)), e, None)
    };
    let Some((cells, cost)) = path else {
        let why = match req.footprint {
            RobotFootprint::Disk(r) => format!(
                "for a robot of radius {r} {} (the inflated obstacles close every passage \
                 between them)",
                mf.units()
            ),
            _ => "(they lie in disconnected free regions)".into(),
        };
        let mut found = unreachable(
            format!(
                "no path: the goal at {} is not reachable from the start at {} {why}",
                mf.describe(goal),
                mf.describe(start)
            ),
            sg,
        );
        // D* Lite's state still serves re-plans (a cut-off goal may open again)
        found.dstar = dstar;
        return Ok(found);
    };
    Ok(Found {
        status: PlanStatus::Found,
        report: format!(
            "found a path of cost {:.3} {} ({expanded} cells expanded)",
            mf.cells_to_units(cost),
            mf.units()
        ),
        cells,
        headings: None,
        cost_cells: Some(cost),
        expanded,
        cspace: sg,
        dstar,
    })
}

/// Steepest descent of a potential field over `sg`.
fn search_potential(
    mf: &MapFrame<'_>,
    ends: &Ends,
    term: GoalTerm,
    params: &PotentialParams,
    sg: SearchGrid,
) -> Result<Found> {
    let field = potential_field(&sg, ends.goal, term, params)?;
    let d = descend(&sg, &field, ends.start)?;
    let mut report = d.report();
    let status = match d.end {
        DescentEnd::Reached => PlanStatus::Found,
        DescentEnd::LocalMinimum { cell, .. } => {
            if mf.world() {
                report.push_str(&format!(" (the minimum is at {})", mf.describe(cell)));
            }
            PlanStatus::LocalMinimum
        }
        DescentEnd::Unreachable => {
            return Ok(unreachable(
                format!(
                    "no path from the start at {} to the goal at {}: {report}",
                    mf.describe(ends.start),
                    mf.describe(ends.goal)
                ),
                sg,
            ));
        }
    };
    let cost_cells = (status == PlanStatus::Found).then(|| polyline_length(&d.cells));
    Ok(Found {
        status,
        report,
        cells: d.cells,
        headings: None,
        cost_cells,
        expanded: 0,
        cspace: sg,
        dstar: None,
    })
}

/// Smooths and times the path.
fn finish(
    mf: &MapFrame<'_>,
    req: &PlanRequest,
    ends: Ends,
    f: Found,
    map: MapProducts,
) -> Result<Plan> {
    let (smoothed, waypoints, trajectory, curve) = if f.status == PlanStatus::Unreachable {
        (Vec::new(), Vec::new(), Vec::new(), None)
    } else {
        let smoothed = if !req.smooth || f.headings.is_some() {
            compress(&f.cells)
        } else {
            smooth(&f.cspace, &f.cells)
        };
        let waypoints: Vec<[f64; 2]> = smoothed
            .iter()
            .map(|c| mf.grid.cell_to_world(c.0 as f64, c.1 as f64))
            .collect();
        let (trajectory, curve) = match &req.timing {
            Some(Timing::StopAndTurn { limits, dt }) => (
                time_parameterize(&waypoints, req.start_yaw, limits, *dt)?,
                None,
            ),
            // a descent stuck short of the goal has no path to the goal pose to time
            Some(Timing::Curvature { .. }) if f.status != PlanStatus::Found => (Vec::new(), None),
            Some(Timing::Curvature { timing }) => {
                let start = [req.start[0], req.start[1], req.start_yaw.unwrap_or(0.0)];
                let goal = [req.goal[0], req.goal[1], req.goal_yaw.unwrap_or(0.0)];
                let curve =
                    time_cells_curved(mf.grid, &f.cspace, &f.cells, start, 0.0, goal, timing)?;
                let points = curve
                    .samples
                    .iter()
                    .map(|p| TrajectoryPoint {
                        t: p.t,
                        x: p.x,
                        y: p.y,
                        theta: p.theta,
                        v: p.v,
                        omega: p.omega,
                    })
                    .collect();
                (points, Some(curve))
            }
            None => (Vec::new(), None),
        };
        (smoothed, waypoints, trajectory, curve)
    };
    let mut path_check = map.path_check;
    let colliding = match path_check.as_mut() {
        Some(check) => check.colliding_cells(
            mf.grid,
            &map.occupied,
            trajectory.iter().map(|p| [p.x, p.y, p.theta]),
        ),
        None => Vec::new(),
    };
    if let (Some(check), Some(pc), Some(first), Some(last)) = (
        path_check.as_mut(),
        &req.polygon_check,
        trajectory.first(),
        trajectory.last(),
    ) {
        let fields = req.fields;
        if req.start_yaw.is_none() {
            check_end(
                mf,
                check,
                pc,
                &map.occupied,
                fields.start,
                req.start,
                (first.theta, true),
            )?;
        }
        // a descent stuck short of the goal does not arrive there
        if req.goal_yaw.is_none() && f.status == PlanStatus::Found {
            check_end(
                mf,
                check,
                pc,
                &map.occupied,
                fields.goal,
                req.goal,
                (last.theta, true),
            )?;
        }
    }
    Ok(Plan {
        start_cell: ends.start,
        goal_cell: ends.goal,
        occupied: map.occupied,
        distance: map.distance,
        reach_cells: map.reach_cells,
        cspace: f.cspace,
        dstar: f.dstar,
        search_s: map.search_s,
        status: f.status,
        report: f.report,
        cells: f.cells,
        headings: f.headings,
        cost_cells: f.cost_cells,
        expanded: f.expanded,
        smoothed,
        waypoints,
        trajectory,
        curve,
        path_check,
        colliding,
    })
}

/// Refuses the end `what` (the request's start or goal `point`, map units) where the
/// polygon of `pc` collides at the heading `yaw.0` (`yaw.1`: the heading the timed path
/// has there, the request giving none) with `occupied` (the plan's obstacle cells).
fn check_end(
    mf: &MapFrame<'_>,
    check: &mut PathCheck,
    pc: &PolygonCheck,
    occupied: &[bool],
    what: &str,
    point: [f64; 2],
    yaw: (f64, bool),
) -> Result<()> {
    let (yaw, from_path) = yaw;
    if !check.collides(mf.grid, occupied, [point[0], point[1], yaw]) {
        return Ok(());
    }
    // the polygon's origin, `ahead` of the planned point
    let (s, c) = yaw.sin_cos();
    let origin = [point[0] + pc.ahead * c, point[1] + pc.ahead * s];
    let which = if from_path {
        ", the heading the timed path has there (none was given)"
    } else {
        ""
    };
    Err(Error::Planning(format!(
        "{what}: the footprint polygon with its origin at ({:.3}, {:.3}) {u} and heading \
         {yaw:.3} rad{which} overlaps an obstacle cell or comes closer to one than the \
         padding ({} {u})",
        origin[0],
        origin[1],
        short(pc.padding),
        u = mf.units()
    )))
}

/// Keeps only the cells where the direction changes (and repeated cells, i.e. turns).
fn compress(cells: &[(usize, usize)]) -> Vec<(usize, usize)> {
    let mut out: Vec<(usize, usize)> = Vec::new();
    for (i, &c) in cells.iter().enumerate() {
        if i == 0 || i == cells.len() - 1 {
            out.push(c);
            continue;
        }
        let (p, n) = (cells[i - 1], cells[i + 1]);
        let d1 = (c.0 as i64 - p.0 as i64, c.1 as i64 - p.1 as i64);
        let d2 = (n.0 as i64 - c.0 as i64, n.1 as i64 - c.1 as i64);
        if d1 != d2 && out.last() != Some(&c) {
            out.push(c);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::planning::grid::OCCUPIED;

    /// A 30 x 12 Moving AI map with one obstacle cell at (15, 7), two rows above the
    /// straight path along row 5 from (3, 5) to (27, 5).
    fn one_obstacle() -> OccupancyGrid {
        let mut g = OccupancyGrid::new_free(30, 12, MapKind::MovingAi).unwrap();
        g.cells[7 * 30 + 15] = OCCUPIED;
        g
    }

    fn request(check: Option<PolygonCheck>) -> PlanRequest {
        PlanRequest {
            start: [3.0, 5.0],
            start_yaw: None,
            goal: [27.0, 5.0],
            goal_yaw: None,
            frame: Frame::Map,
            unknown_is_obstacle: true,
            footprint: RobotFootprint::Disk(0.5),
            axle_offset: 0.0,
            fields: PlanFields::default(),
            search: Search::Astar,
            turn_cost: 1.0,
            smooth: true,
            timing: Some(Timing::StopAndTurn {
                limits: DiffDriveLimits {
                    v_max: 1.0,
                    omega_max: 1.0,
                    a_max: 1.0,
                    alpha_max: 1.0,
                },
                dt: 0.1,
            }),
            polygon_check: check,
        }
    }

    /// A rectangle `long` along the heading and `wide` across it (cells).
    fn rectangle(long: f64, wide: f64, padding: f64) -> PolygonCheck {
        let (a, b) = (long / 2.0, wide / 2.0);
        PolygonCheck {
            polygon: Footprint::new(vec![[-a, -b], [a, -b], [a, b], [-a, b]]).unwrap(),
            padding,
            ahead: 0.0,
        }
    }

    /// The disk C-space passes the straight path; the polygon check finds where a chassis
    /// wide across the path meets the obstacle (its centre within a cell of it), and
    /// passes the same chassis driven lengthwise, unless the padding asks for more room.
    #[test]
    fn the_timed_path_is_checked_with_the_polygon_at_its_heading() {
        let g = one_obstacle();
        let plain = plan(&g, &request(None)).unwrap();
        assert_eq!(plain.status, PlanStatus::Found);
        assert!(plain.cells.iter().all(|c| c.1 == 5));
        assert!(plain.path_check.is_none() && plain.colliding.is_empty());
        // 2 cells along the heading, 5 across: reaches from y = 3 to 8 over row 5
        let across = plan(&g, &request(Some(rectangle(2.0, 5.0, 0.0)))).unwrap();
        assert_eq!(across.cells, plain.cells, "the same search");
        assert_eq!(across.colliding, [(14, 5), (15, 5), (16, 5)]);
        assert!(across.path_check.is_some());
        // turned lengthwise (5 along, 2 across): its side passes 0.5 cells below the
        // obstacle's square
        let along = plan(&g, &request(Some(rectangle(5.0, 2.0, 0.0)))).unwrap();
        assert!(along.colliding.is_empty());
        let padded = plan(&g, &request(Some(rectangle(5.0, 2.0, 0.6)))).unwrap();
        assert!(!padded.colliding.is_empty());
        // without a timing the check is handed over, nothing is checked
        let mut untimed = request(Some(rectangle(2.0, 5.0, 0.0)));
        untimed.timing = None;
        let untimed = plan(&g, &untimed).unwrap();
        assert!(untimed.colliding.is_empty());
        let mut check = untimed.path_check.unwrap();
        assert!(check.collides(&g, &untimed.occupied, [15.0, 5.0, 0.0]));
        assert!(!check.collides(
            &g,
            &untimed.occupied,
            [15.0, 5.0, std::f64::consts::FRAC_PI_2]
        ));
    }

    /// The start and goal poses are checked with the polygon: at the heading the request
    /// gives, before the search, or else at the heading the timed path has there; each
    /// refusal names the request's field. (15, 5) lies two cells below the obstacle: the
    /// disk fits there, the chassis 5 cells wide across its heading does not at heading 0.
    #[test]
    fn the_ends_are_checked_with_the_polygon_naming_the_field() {
        let g = one_obstacle();
        let fields = PlanFields {
            start: "start.pose",
            goal: "goal.pose",
            radius: "radius",
        };
        let across = || {
            let mut r = request(Some(rectangle(2.0, 5.0, 0.0)));
            r.fields = fields;
            r
        };
        // the request's heading: refused before the search
        let mut req = across();
        req.start = [15.0, 5.0];
        req.start_yaw = Some(0.0);
        let e = plan(&g, &req).unwrap_err().to_string();
        assert!(
            e.contains("start.pose: the footprint polygon with its origin at (15.000, 5.000) cells and heading 0.000 rad overlaps"),
            "{e}"
        );
        // turned a quarter turn it fits; the turn in place towards the goal then
        // collides along the path, which is the path check's verdict, not an error
        req.start_yaw = Some(std::f64::consts::FRAC_PI_2);
        let p = plan(&g, &req).unwrap();
        assert_eq!(p.colliding.first(), Some(&(15, 5)));
        // no heading given: the one the timed path leaves with (along row 5)
        req.start_yaw = None;
        let e = plan(&g, &req).unwrap_err().to_string();
        assert!(
            e.contains("start.pose") && e.contains("none was given"),
            "{e}"
        );
        // the goal, arrived at along row 5
        let mut req = across();
        req.goal = [15.0, 5.0];
        let e = plan(&g, &req).unwrap_err().to_string();
        assert!(
            e.contains("goal.pose") && e.contains("none was given"),
            "{e}"
        );
        // with a goal heading (untimed: the stop-and-turn timing takes none)
        req.timing = None;
        req.goal_yaw = Some(0.0);
        let e = plan(&g, &req).unwrap_err().to_string();
        assert!(
            e.contains("goal.pose") && e.contains("heading 0.000 rad overlaps"),
            "{e}"
        );
        req.goal_yaw = Some(std::f64::consts::FRAC_PI_2);
        assert_eq!(plan(&g, &req).unwrap().status, PlanStatus::Found);
        // the padding counts: lengthwise the chassis passes 0.5 cells below the obstacle
        let mut req = request(Some(rectangle(5.0, 2.0, 0.6)));
        req.start = [15.0, 5.0];
        req.start_yaw = Some(0.0);
        let e = plan(&g, &req).unwrap_err().to_string();
        assert!(
            e.contains("start: ") && e.contains("padding (0.6 cells)"),
            "{e}"
        );
        req.start_yaw = Some(f64::NAN);
        let e = plan(&g, &req).unwrap_err().to_string();
        assert!(e.contains("start heading"), "{e}");
        // without the check the ends are the disk's alone
        let mut req = request(None);
        req.start = [15.0, 5.0];
        req.start_yaw = Some(0.0);
        assert_eq!(plan(&g, &req).unwrap().status, PlanStatus::Found);
    }

    #[test]
    fn the_stop_and_turn_timing_takes_no_goal_heading() {
        let mut req = request(None);
        req.goal_yaw = Some(0.0);
        let e = plan(&one_obstacle(), &req).unwrap_err().to_string();
        assert!(e.contains("timing") && e.contains("goal heading"), "{e}");
    }

    #[test]
    fn the_polygon_check_needs_a_point_or_disk_footprint_and_a_convex_polygon() {
        let g = one_obstacle();
        let mut req = request(Some(rectangle(2.0, 2.0, 0.0)));
        req.footprint = RobotFootprint::Polygon(rectangle(2.0, 2.0, 0.0).polygon);
        let e = plan(&g, &req).unwrap_err().to_string();
        assert!(e.contains("polygon check"), "{e}");
        let concave = Footprint::new(vec![
            [-1.0, -1.0],
            [1.0, -1.0],
            [0.2, 0.0],
            [1.0, 1.0],
            [-1.0, 1.0],
        ])
        .unwrap();
        let req = request(Some(PolygonCheck {
            polygon: concave,
            padding: 0.0,
            ahead: 0.0,
        }));
        let e = plan(&g, &req).unwrap_err().to_string();
        assert!(e.contains("convex"), "{e}");
        let mut negative = rectangle(2.0, 2.0, 0.0);
        negative.padding = -0.1;
        let e = plan(&g, &request(Some(negative))).unwrap_err().to_string();
        assert!(e.contains("padding"), "{e}");
    }
}

//! The planning pipeline of `moma plan` and the Python `plan`: a map, a footprint, start
//! and goal, a search and limits in; the configuration space, the cell path, the
//! smoothed path and the timed reference out.
//!
//! Coordinates and lengths are in the map's own units ([`MapFrame`]): world metres on a
//! ROS map, cells on a Moving AI map. The footprint is a point, a disk (the obstacles
//! dilated by its radius, one distance transform) or a polygon in the robot frame. A
//! polygon is searched over (x, y, heading) on the 8-heading lattice of
//! [`costmap::footprint_cspace`] (each heading's C-space exact at cell centres: blocked
//! within the inscribed radius, free beyond the circumscribed radius, the polygon tested
//! against the obstacle cells in the band between; turns in place checked on the swept
//! footprint), so the path's every pose and turn is collision-free at the heading it is
//! driven with, which nav2's Smac planners also do on their heading lattices.

use super::costmap::{self, Footprint, InflationParams};
use super::dstar_lite::DStarLite;
use super::potential::{DescentEnd, GoalTerm, PotentialParams, descend, potential_field};
use super::smooth::{polyline_length, smooth};
use super::trajectory::{DiffDriveLimits, TrajectoryPoint, time_parameterize};
use super::{MapKind, OccupancyGrid, SearchGrid, astar};
use crate::{Error, Result};

/// A map with the frame its user's coordinates are in.
#[derive(Debug, Clone, Copy)]
pub struct MapFrame<'a> {
    /// The map.
    pub grid: &'a OccupancyGrid,
}

impl<'a> MapFrame<'a> {
    /// The frame of `grid`.
    #[must_use]
    pub fn new(grid: &'a OccupancyGrid) -> Self {
        Self { grid }
    }

    /// `true` on a ROS map (world metres), `false` on a Moving AI map (cells).
    #[must_use]
    pub fn world(&self) -> bool {
        self.grid.kind == MapKind::Ros
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

/// What to plan.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanRequest {
    /// Start `[x, y]` in map units.
    pub start: [f64; 2],
    /// Start heading (rad, world frame); `None` faces the first segment.
    pub start_yaw: Option<f64>,
    /// Goal `[x, y]` in map units.
    pub goal: [f64; 2],
    /// Unknown cells are obstacles (else free).
    pub unknown_is_obstacle: bool,
    /// The robot's shape.
    pub footprint: RobotFootprint,
    /// The search.
    pub search: Search,
    /// Turn cost per 45° of the polygon search (cells of travel).
    pub turn_cost: f64,
    /// Shortcut smoothing of the cell path (the polygon's path is never shortcut: its
    /// headings hold only along the cells searched).
    pub smooth: bool,
    /// The stop-and-turn timing; `None` plans the path alone.
    pub timing: Option<Timing>,
}

/// Limits and sampling of the stop-and-turn timing
/// ([`super::trajectory::time_parameterize`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Timing {
    /// Platform limits.
    pub limits: DiffDriveLimits,
    /// Sampling period (s).
    pub dt: f64,
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
#[derive(Debug, Clone, PartialEq)]
pub struct Plan {
    /// Start cell.
    pub start_cell: (usize, usize),
    /// Goal cell.
    pub goal_cell: (usize, usize),
    /// The C-space the path lives on (`true` = free); for a polygon, the cells free at
    /// every heading.
    pub cspace: SearchGrid,
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
    /// The stop-and-turn timed reference (empty without [`PlanRequest::timing`]).
    pub trajectory: Vec<TrajectoryPoint>,
}

/// Runs the pipeline on `grid` (see the module documentation).
///
/// # Errors
/// Start or goal off the map, in an obstacle or unknown cell, or inside the C-space
/// obstacle; invalid footprint, search or timing parameters; an oversized map or
/// footprint C-space. An unreachable goal is not an error ([`PlanStatus::Unreachable`]).
pub fn plan(grid: &OccupancyGrid, req: &PlanRequest) -> Result<Plan> {
    let mf = MapFrame::new(grid);
    let (w, h) = (grid.width, grid.height);
    let obst = grid.obstacle_mask(100, req.unknown_is_obstacle);
    // validates the map size for the searches before anything else is built
    SearchGrid::from_obstacles(&obst, w, h)?;
    let start = mf.cell_of("start", req.start[0], req.start[1])?;
    let goal = mf.cell_of("goal", req.goal[0], req.goal[1])?;
    for (what, c) in [("start", start), ("goal", goal)] {
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
            "radius",
            format!("must be a finite non-negative number, got {radius}"),
        ));
    }
    let cspace = SearchGrid::from_obstacles(
        &costmap::inflate(&obst, w, h, mf.units_to_cells(radius))?,
        w,
        h,
    )?;
    for (what, c) in [("start", start), ("goal", goal)] {
        if !cspace.is_free(c.0 as i64, c.1 as i64) {
            return Err(Error::Planning(format!(
                "{what} at {} is closer than the robot radius {} {} to an obstacle (inside \
                 the configuration-space obstacle)",
                mf.describe(c),
                short(radius),
                mf.units()
            )));
        }
    }
    let ends = Ends { start, goal };
    let found = match (&req.footprint, &req.search) {
        (RobotFootprint::Polygon(fp), Search::Astar) => search_polygon(&mf, &obst, &ends, req, fp)?,
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
    finish(&mf, req, ends, found)
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
    }
}

/// A* over (x, y, 8 headings) for a polygon.
fn search_polygon(
    mf: &MapFrame<'_>,
    obst: &[bool],
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
    let cs = costmap::footprint_cspace(obst, w, h, 1.0, &fp_cells, 8)?;
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
    let (path, expanded) = if matches!(req.search, Search::DStarLite) {
        let mut d = DStarLite::new(&sg, start, goal)?;
        let c = d.compute();
        (c.and_then(|c| d.path().map(|p| (p, c))), d.expanded())
    } else {
        let p = astar(&sg, start, goal)?;
        let e = p.as_ref().map_or(0, |p| p.expanded);
        (p.map(|p| (p.cells, p.cost)), e)
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
        return Ok(unreachable(
            format!(
                "no path: the goal at {} is not reachable from the start at {} {why}",
                mf.describe(goal),
                mf.describe(start)
            ),
            sg,
        ));
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
    })
}

/// Smooths and times the path.
fn finish(mf: &MapFrame<'_>, req: &PlanRequest, ends: Ends, f: Found) -> Result<Plan> {
    let (smoothed, waypoints, trajectory) = if f.status == PlanStatus::Unreachable {
        (Vec::new(), Vec::new(), Vec::new())
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
        let trajectory = match &req.timing {
            Some(t) => time_parameterize(&waypoints, req.start_yaw, &t.limits, t.dt)?,
            None => Vec::new(),
        };
        (smoothed, waypoints, trajectory)
    };
    Ok(Plan {
        start_cell: ends.start,
        goal_cell: ends.goal,
        cspace: f.cspace,
        status: f.status,
        report: f.report,
        cells: f.cells,
        headings: f.headings,
        cost_cells: f.cost_cells,
        expanded: f.expanded,
        smoothed,
        waypoints,
        trajectory,
    })
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

//! The mission's planner: the configuration space of the map, D* Lite from the robot's
//! cell to the goal's cell, and the turn from a cell path into a timed reference.

use std::time::Instant;

use super::footprint::MissionFootprint;
use super::scenario::Mission;
use crate::error::{Error, Result};
use crate::planning::costmap;
use crate::planning::dstar_lite::DStarLite;
use crate::planning::footprint_clearance::PathCheck;
use crate::planning::pipeline::{
    self, Frame, PlanFields, PlanRequest, PlanStatus, PolygonCheck, RobotFootprint, Search,
};
use crate::planning::{OccupancyGrid, SearchGrid, distance_transform};

/// Per-cell state of the world the robot knows: obstacles of the map plus the obstacles
/// that have appeared, their distance transform, and the D* Lite planner on the
/// configuration space (the obstacles dilated by the footprint).
pub(crate) struct Planner {
    pub width: usize,
    pub height: usize,
    /// `true` = occupied cell (map or appeared obstacle).
    pub occupied: Vec<bool>,
    /// Distance (cells) from each cell centre to the nearest occupied cell centre.
    pub dist: Vec<f32>,
    /// How many times obstacles that appeared changed `occupied` and `dist`.
    pub map_changes: usize,
    /// The centre-to-centre distance (cells) within which an occupied cell blocks a
    /// configuration-space cell: footprint radius + |d| + ½ cell
    /// ([`costmap::disk_reach`]).
    pub r_cells: f64,
    pub dstar: DStarLite,
    pub goal_cell: (usize, usize),
    /// The pipeline's check of the paths with the footprint polygon
    /// (`robot.footprint = "robot"`, the base frame `d` ahead of the planned axle
    /// midpoint), `None` for a disk.
    pub polygon: Option<PathCheck>,
}

/// A path of cells `(x, y)`, start to goal.
pub(crate) type CellPath = Vec<(usize, usize)>;

/// One D* Lite query's figures.
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct SearchTiming {
    /// Wall time of the incremental search (s): `move_start`, `set_blocked`, `compute`
    /// and the path extraction.
    pub search_s: f64,
    /// Cells expanded by `compute`.
    pub expanded: usize,
}

impl Planner {
    /// Builds the configuration space and plans once through [`pipeline::plan`] on
    /// `request` (the mission's: [`first_plan_request`], D* Lite between the driven-axle
    /// midpoints, with or without a polygon check), keeping its D* Lite state for the
    /// re-plans and its check of the paths with the footprint polygon.
    ///
    /// # Errors
    /// [`pipeline::plan`]'s: start or goal outside the map, in an obstacle, or where the
    /// footprint does not fit (the start's message says when it fits nowhere) or where
    /// the request's footprint polygon collides at the pose's heading; a polygon that is
    /// not convex. An unreachable goal is not an error: the returned path is
    /// `None`.
    pub fn new(
        grid: &OccupancyGrid,
        request: &PlanRequest,
    ) -> Result<(Self, Option<CellPath>, SearchTiming)> {
        let plan = pipeline::plan(grid, request)?;
        let Some(dstar) = plan.dstar else {
            return Err(Error::Planning(
                "the planning pipeline gave no D* Lite state for a D* Lite search".into(),
            ));
        };
        let timing = SearchTiming {
            search_s: plan.search_s,
            expanded: dstar.expanded(),
        };
        let path = (plan.status == PlanStatus::Found).then_some(plan.cells);
        Ok((
            Self {
                width: grid.width,
                height: grid.height,
                occupied: plan.occupied,
                dist: plan.distance,
                map_changes: 0,
                r_cells: plan.reach_cells,
                dstar,
                goal_cell: plan.goal_cell,
                polygon: plan.path_check,
            },
            path,
            timing,
        ))
    }

    /// Marks a disk obstacle (centre in continuous cell coordinates, radius in cells)
    /// occupied, refreshes the distance transform, and blocks its dilated cells in the
    /// planner (after moving the planner's start to `robot_cell`). Returns the newly
    /// blocked configuration-space cells and the search time spent.
    pub fn add_disk(
        &mut self,
        center: [f64; 2],
        radius: f64,
        robot_cell: (usize, usize),
    ) -> Result<(Vec<(usize, usize)>, f64)> {
        let (w, h) = (self.width as i64, self.height as i64);
        let reach = radius + self.r_cells;
        let x0 = ((center[0] - reach).floor() as i64).clamp(0, w - 1);
        let x1 = ((center[0] + reach).ceil() as i64).clamp(0, w - 1);
        let y0 = ((center[1] - reach).floor() as i64).clamp(0, h - 1);
        let y1 = ((center[1] + reach).ceil() as i64).clamp(0, h - 1);
        let mut newly = Vec::new();
        let mut changed = false;
        for y in y0..=y1 {
            for x in x0..=x1 {
                let d = (x as f64 + 0.5 - center[0]).hypot(y as f64 + 0.5 - center[1]);
                let i = (y * w + x) as usize;
                if d <= radius && !self.occupied[i] {
                    self.occupied[i] = true;
                    changed = true;
                }
                if d <= reach {
                    newly.push((x as usize, y as usize));
                }
            }
        }
        if changed {
            self.dist = distance_transform(&self.occupied, self.width, self.height);
            self.map_changes += 1;
        }
        let clock = Instant::now();
        self.move_start(robot_cell)?;
        newly.retain(|&c| self.dstar.grid().is_free(c.0 as i64, c.1 as i64));
        // D* Lite keeps its goal cell free; a disk over the goal is reported by the
        // caller (the goal's cell in the returned list) instead.
        for &c in newly.iter().filter(|&&c| c != self.goal_cell) {
            self.dstar.set_blocked(c, true)?;
        }
        Ok((newly, clock.elapsed().as_secs_f64()))
    }

    /// `true` when the footprint with the axle midpoint at the world pose `axle`
    /// collides: the polygon at the pose's heading comes closer than its padding to an
    /// occupied cell; without a polygon, the axle midpoint's C-space cell is blocked.
    pub fn axle_collides(&mut self, grid: &OccupancyGrid, axle: [f64; 3]) -> bool {
        let Some(pc) = self.polygon.as_mut() else {
            let [fx, fy, _] = PathCheck::pose_in_cells(grid, axle);
            return self.blocked_at(fx, fy);
        };
        pc.collides(grid, &self.occupied, axle)
    }

    /// The cells of the axle midpoints among `poses` (world, in order) where the
    /// footprint polygon collides ([`PathCheck::colliding_cells`]), each once; none
    /// without the polygon.
    pub fn colliding_cells(
        &mut self,
        grid: &OccupancyGrid,
        poses: impl IntoIterator<Item = [f64; 3]>,
    ) -> Vec<(usize, usize)> {
        match self.polygon.as_mut() {
            Some(pc) => pc.colliding_cells(grid, &self.occupied, poses),
            None => Vec::new(),
        }
    }

    /// The clearance (m) of the footprint with the base frame at the world pose `base`:
    /// the polygon's signed distance to the nearest occupied cell less the padding, exact
    /// within `exact` m of the polygon; without a polygon, the distance from the disk of
    /// radius `r_foot` about the base frame origin ([`Planner::obstacle_distance`]).
    /// Beyond the exact range a lower bound from the distance transform; infinite on a
    /// map without occupied cells.
    pub fn clearance(
        &mut self,
        grid: &OccupancyGrid,
        base: [f64; 3],
        r_foot: f64,
        exact: f64,
    ) -> f64 {
        let res = grid.resolution;
        let [fx, fy, th] = PathCheck::pose_in_cells(grid, base);
        let Some(pc) = self.polygon.as_mut() else {
            return self
                .obstacle_distance(fx, fy, (r_foot + exact) / res)
                .map_or(f64::INFINITY, |d| d * res - r_foot);
        };
        let near = pc.clearance(
            &self.occupied,
            self.width,
            self.height,
            [fx, fy, th],
            exact / res,
        );
        let (circ, pad) = (pc.footprint().circumscribed(), pc.padding());
        let cells = match near {
            Some(d) => Some(d),
            // the disk about the base that holds the polygon bounds it from below
            None => self
                .obstacle_distance(fx, fy, 0.0)
                .map(|d| (d - circ).max(exact / res)),
        };
        cells.map_or(f64::INFINITY, |d| (d - pad) * res)
    }

    /// Blocks `cell` in the C-space (a pose there collided at the heading it was driven
    /// with); the goal's cell stays free. `false` when it is the goal's.
    ///
    /// The block holds at every heading, stricter than the collision found: D* Lite
    /// searches the (x, y) cells only, and the heading a path has in a cell is not the
    /// search's but the smoothing's (the tangent of the curvature-bounded path through
    /// the cells, known only after the search). A (cell, heading) block needs a search
    /// over (x, y, θ), as `planning::costmap::astar_footprint` does for `moma plan`, at
    /// the number of headings times the states and without D* Lite's incremental
    /// repair. What the cell block costs: a cell the polygon passes at another heading
    /// is lost to every later path of the mission, so a passage entered at a wrong angle
    /// may be closed for good; the search then goes round, or after `POLYGON_REPAIRS`
    /// falls back to the circumscribed disk (`docs/mission.md`).
    pub fn block(&mut self, cell: (usize, usize)) -> Result<bool> {
        if cell == self.goal_cell {
            return Ok(false);
        }
        self.dstar.set_blocked(cell, true)?;
        Ok(true)
    }

    /// Replaces the C-space by the obstacles dilated by `radius` (m, about the axle
    /// midpoint), the appeared obstacles included, with the search's start at `start`
    /// and no polygon check: the fallback when the polygon's lower bound gives no path
    /// the polygon passes. `false` when the goal's cell is blocked there.
    pub fn use_disk(
        &mut self,
        radius: f64,
        resolution: f64,
        start: (usize, usize),
    ) -> Result<bool> {
        self.r_cells = costmap::disk_reach(radius / resolution);
        let blocked = costmap::dilate_disk(&self.dist, radius / resolution);
        self.polygon = None;
        if blocked[self.goal_cell.1 * self.width + self.goal_cell.0] {
            return Ok(false);
        }
        let sgrid = SearchGrid::from_obstacles(&blocked, self.width, self.height)?;
        self.dstar = DStarLite::new(&sgrid, start, self.goal_cell)?;
        self.move_start(start)?;
        Ok(true)
    }

    /// Moves the planner's start to `cell`, or to the nearest free cell within two cells
    /// if the robot stands in the configuration-space obstacle.
    pub fn move_start(&mut self, cell: (usize, usize)) -> Result<()> {
        let c = self.nearest_free(cell).unwrap_or(cell);
        self.dstar.move_start(c)
    }

    fn nearest_free(&self, cell: (usize, usize)) -> Option<(usize, usize)> {
        let g = self.dstar.grid();
        let (cx, cy) = (cell.0 as i64, cell.1 as i64);
        let mut best: Option<((usize, usize), i64)> = None;
        for dy in -2i64..=2 {
            for dx in -2i64..=2 {
                if g.is_free(cx + dx, cy + dy) {
                    let d2 = dx * dx + dy * dy;
                    if best.is_none_or(|(_, b)| d2 < b) {
                        best = Some((((cx + dx) as usize, (cy + dy) as usize), d2));
                    }
                }
            }
        }
        best.map(|b| b.0)
    }

    /// Re-plans from the planner's current start: the cell path, or `None` when the goal
    /// is cut off.
    pub fn replan(&mut self) -> (Option<Vec<(usize, usize)>>, SearchTiming) {
        let clock = Instant::now();
        let path = self.dstar.compute().and_then(|_| self.dstar.path());
        (
            path,
            SearchTiming {
                search_s: clock.elapsed().as_secs_f64(),
                expanded: self.dstar.expanded(),
            },
        )
    }

    /// `true` if the configuration-space cell containing continuous cell coordinates
    /// `(fx, fy)` is blocked (or outside the map).
    pub fn blocked_at(&self, fx: f64, fy: f64) -> bool {
        !self
            .dstar
            .grid()
            .is_free(fx.floor() as i64, fy.floor() as i64)
    }

    /// Distance (cells) from a point (continuous cell coordinates) to the boundary of
    /// the nearest occupied cell: exact within `exact_cells` of the point, beyond it the
    /// distance transform's value at the point's cell minus one cell diagonal (a lower
    /// bound within 1.5 cells). `None` on a map without occupied cells.
    pub fn obstacle_distance(&self, fx: f64, fy: f64, exact_cells: f64) -> Option<f64> {
        let (w, h) = (self.width as i64, self.height as i64);
        let cx = (fx.floor() as i64).clamp(0, w - 1);
        let cy = (fy.floor() as i64).clamp(0, h - 1);
        let dc = f64::from(self.dist[(cy * w + cx) as usize]);
        if !dc.is_finite() {
            return None;
        }
        if dc > exact_cells {
            return Some((dc - std::f64::consts::SQRT_2).max(0.0));
        }
        let r = (dc + 2.2).ceil() as i64;
        let mut best = f64::INFINITY;
        for y in (cy - r).max(0)..=(cy + r).min(h - 1) {
            let row = (y * w) as usize;
            let ddy = if fy < y as f64 {
                y as f64 - fy
            } else if fy > (y + 1) as f64 {
                fy - (y + 1) as f64
            } else {
                0.0
            };
            if ddy >= best {
                continue;
            }
            for x in (cx - r).max(0)..=(cx + r).min(w - 1) {
                if self.occupied[row + x as usize] {
                    let ddx = if fx < x as f64 {
                        x as f64 - fx
                    } else if fx > (x + 1) as f64 {
                        fx - (x + 1) as f64
                    } else {
                        0.0
                    };
                    let d = ddx.hypot(ddy);
                    if d < best {
                        best = d;
                    }
                }
            }
        }
        // Off-window obstacles lie farther than the window's reach (see above), so a miss
        // means the map's border-less outside: fall back to the transform.
        Some(if best.is_finite() {
            best
        } else {
            (dc - std::f64::consts::SQRT_2).max(0.0)
        })
    }
}

/// The pipeline's request of the mission's first plan: D* Lite on the disk C-space of
/// `footprint_radius` about a base frame `axle_offset` ahead of the planned axle
/// midpoint, unsmoothed and untimed (the mission smooths and times the cell path from
/// the robot's pose and speed when it adopts it, `mission::reference`).
pub(crate) fn first_plan_request(
    unknown_is_obstacle: bool,
    fields: PlanFields,
    footprint_radius: f64,
    axle_offset: f64,
    start: [f64; 2],
    goal: [f64; 2],
) -> PlanRequest {
    PlanRequest {
        start,
        start_yaw: None,
        goal_yaw: None,
        goal,
        frame: Frame::World,
        unknown_is_obstacle,
        footprint: RobotFootprint::Disk(footprint_radius),
        axle_offset,
        fields,
        search: Search::DStarLite,
        turn_cost: 1.0,
        smooth: false,
        timing: None,
        polygon_check: None,
    }
}

/// The mission's planner on `grid` (the mission's map, or a `[task]`'s drive on's) between
/// two axle-midpoint poses for `footprint` (the mission's, or a `[task]`'s while
/// carrying). With the robot's footprint polygon: searched on the largest disk about the
/// axle midpoint inside it (padded), and every path it gives checked with the polygon at
/// each heading; with a disk: the map dilated by it (and `|d|`).
pub(super) fn mission_planner(
    m: &Mission,
    grid: &OccupancyGrid,
    footprint: &MissionFootprint,
    from: [f64; 3],
    to: [f64; 3],
) -> Result<(Planner, Option<CellPath>, SearchTiming)> {
    let d = m.robot.base.drive.d;
    let polygon = footprint.planning_polygon(d);
    let (field, radius, offset) = match &polygon {
        Some((_, inscribed)) => ("robot.footprint", inscribed + footprint.padding(), 0.0),
        None if m.file.robot.footprint.is_some() => ("robot.footprint", footprint.radius, d),
        None => ("robot.footprint_radius", footprint.radius, d),
    };
    let check = polygon.map(|(polygon, _)| PolygonCheck {
        polygon,
        padding: footprint.padding(),
        ahead: d,
    });
    let fields = PlanFields {
        start: "start.pose",
        goal: "goal.pose",
        radius: field,
    };
    let mut request = first_plan_request(
        m.file.map.unknown_is_obstacle,
        fields,
        radius,
        offset,
        [from[0], from[1]],
        [to[0], to[1]],
    );
    // the poses' headings: the polygon check refuses a start or goal where it collides
    request.start_yaw = Some(from[2]);
    request.goal_yaw = Some(to[2]);
    request.polygon_check = check;
    Planner::new(grid, &request)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mission::reference::axle_pose;

    /// The mission's first plan is `moma plan`'s D* Lite plan for a disk of the
    /// footprint radius + |d| from the axle midpoint to the goal's: the same C-space, the
    /// same cells and the same D* Lite state to re-plan from (`mission_offset.toml`: a
    /// base frame 0.12 m ahead of the axle).
    #[test]
    fn first_plan_is_the_pipelines() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scenarios/mission_offset.toml");
        let m = crate::mission::load(&path).unwrap();
        let d = m.robot.base.drive.d;
        assert!(
            d != 0.0 && m.footprint.source == crate::mission::footprint::FootprintSource::Radius
        );
        let (s0, g0) = (
            axle_pose(m.file.start.pose, d),
            axle_pose(m.goal().unwrap().pose, d),
        );
        let (planner, cells, search) =
            mission_planner(&m, &m.map.grid, &m.footprint, s0, g0).unwrap();
        let cells = cells.expect("the goal is reachable");
        let mut as_moma_plan = first_plan_request(
            m.file.map.unknown_is_obstacle,
            PlanFields::default(),
            m.footprint.radius + d.abs(),
            0.0,
            [s0[0], s0[1]],
            [g0[0], g0[1]],
        );
        as_moma_plan.frame = Frame::Map;
        let plan = pipeline::plan(&m.map.grid, &as_moma_plan).unwrap();
        assert_eq!(plan.status, PlanStatus::Found);
        assert_eq!(planner.dstar.grid(), &plan.cspace, "the C-space");
        assert_eq!(cells, plan.cells);
        assert_eq!(search.expanded, plan.expanded);
        assert_eq!(planner.r_cells, plan.reach_cells);
        assert_eq!(planner.occupied, plan.occupied);
        // the handed-over state re-plans as the mission's does
        let mut theirs = plan.dstar.unwrap();
        let mut ours = planner.dstar;
        let mid = cells[cells.len() / 2];
        for p in [&mut theirs, &mut ours] {
            p.move_start(cells[3]).unwrap();
            p.set_blocked(mid, true).unwrap();
        }
        let replanned = ours.compute().and_then(|_| ours.path());
        assert!(replanned.as_ref().is_some_and(|p| !p.contains(&mid)));
        assert_eq!(replanned, theirs.compute().and_then(|_| theirs.path()));
    }
}

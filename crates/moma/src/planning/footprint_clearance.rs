//! The heading-aware check of a convex footprint at a continuous pose: its signed
//! distance to the occupied cells of a grid, each cell taken as the unit square it
//! covers.
//!
//! nav2's controllers and smoothers check a path this way (the footprint at each pose's
//! heading against the costmap); the lattice of [`super::costmap::footprint_cspace`]
//! checks cell centres at eight headings instead. A convex polygon and a square are
//! apart when one of their edge normals separates them (the separating-axis theorem):
//! then their distance is the smallest vertex-to-edge distance of either; when no axis
//! separates them, the smallest overlap over those axes is the depth of penetration (the
//! shortest translation that parts them), reported as a negative distance.
//!
//! [`PathCheck`] checks a planned path so, pose by pose: the planning pipeline's check of
//! a disk C-space's timed path with the robot's polygon ([`super::pipeline::PlanRequest::polygon_check`]),
//! which the mission keeps for the paths it re-times and re-plans.

use super::costmap::Footprint;
use super::{MapKind, OccupancyGrid};
use crate::{Error, Result};

/// A convex footprint in cells, ready to be placed: its vertices counter-clockwise and
/// their outward edge normals.
#[derive(Debug, Clone, PartialEq)]
pub struct ConvexFootprint {
    /// Vertices in the robot frame (cells), counter-clockwise.
    vertices: Vec<[f64; 2]>,
    /// Radius (cells) of the disk about the robot's origin that holds the polygon.
    circumscribed: f64,
}

impl ConvexFootprint {
    /// The footprint `fp` (metres in the robot frame) on cells of `resolution` m.
    ///
    /// # Errors
    /// A polygon that is not convex (its vertices must turn one way) or a resolution
    /// that is not positive and finite.
    pub fn new(fp: &Footprint, resolution: f64) -> Result<Self> {
        if !(resolution.is_finite() && resolution > 0.0) {
            return Err(Error::invalid(
                "resolution",
                format!("must be a positive finite length, got {resolution}"),
            ));
        }
        let mut v: Vec<[f64; 2]> = fp
            .vertices
            .iter()
            .map(|p| [p[0] / resolution, p[1] / resolution])
            .collect();
        let n = v.len();
        let turn = |i: usize| {
            let (a, b, c) = (v[i], v[(i + 1) % n], v[(i + 2) % n]);
            (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0])
        };
        let turns: Vec<f64> = (0..n).map(turn).collect();
        let (left, right) = (
            turns.iter().any(|&t| t > 0.0),
            turns.iter().any(|&t| t < 0.0),
        );
        if left && right {
            return Err(Error::invalid(
                "footprint",
                "the polygon must be convex for the heading-aware check",
            ));
        }
        if right {
            v.reverse();
        }
        let circumscribed = v.iter().map(|p| p[0].hypot(p[1])).fold(0.0, f64::max);
        Ok(Self {
            vertices: v,
            circumscribed,
        })
    }

    /// Radius (cells) of the disk about the robot's origin that holds the polygon.
    #[must_use]
    pub fn circumscribed(&self) -> f64 {
        self.circumscribed
    }

    /// The signed distance (cells) from the footprint placed at `pose` = `[x, y, θ]`
    /// (continuous cell coordinates: cell `(i, j)` covers `[i, i + 1] × [j, j + 1]`;
    /// θ in the grid frame) to the nearest `occupied` cell of the `width` × `height`
    /// grid (row-major), negative by the depth of penetration when they overlap. Only
    /// cells whose squares come within `reach` cells of the placed polygon's bounding
    /// box are looked at: `None` when none of them is occupied (cells off the grid are
    /// free). `placed` is a scratch buffer.
    ///
    /// # Panics
    /// If `occupied` does not hold `width · height` cells.
    #[must_use]
    pub fn clearance(
        &self,
        occupied: &[bool],
        width: usize,
        height: usize,
        pose: [f64; 3],
        reach: f64,
        placed: &mut Vec<[f64; 2]>,
    ) -> Option<f64> {
        assert_eq!(occupied.len(), width * height, "occupied mask size");
        let (s, c) = pose[2].sin_cos();
        placed.clear();
        placed.extend(
            self.vertices
                .iter()
                .map(|p| [pose[0] + c * p[0] - s * p[1], pose[1] + s * p[0] + c * p[1]]),
        );
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in placed.iter() {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        let reach = reach.max(0.0);
        // the cells whose squares come within `reach` of the box (none off the grid)
        let range = |a: f64, b: f64, n: usize| {
            let first = (a - reach - 1.0).floor().max(0.0);
            let last = (b + reach).floor().min(n as f64 - 1.0);
            (first <= last).then_some((first as usize, last as usize))
        };
        let (Some((x0, x1)), Some((y0, y1))) =
            (range(lo[0], hi[0], width), range(lo[1], hi[1], height))
        else {
            return None;
        };
        // A lower bound per cell: the gap between the square and the polygon's bounding
        // box, or between the square and the circumscribed disk. The cell of the least
        // bound gives a first distance; only the cells whose bound is below it (all
        // overlapping ones when it is a penetration) are then measured.
        let r = self.circumscribed;
        let lower = |x: usize, y: usize| {
            let (xf, yf) = (x as f64, y as f64);
            let gx = (xf - hi[0]).max(lo[0] - (xf + 1.0)).max(0.0);
            let gy = (yf - hi[1]).max(lo[1] - (yf + 1.0)).max(0.0);
            let cx = (xf - pose[0]).max(pose[0] - (xf + 1.0)).max(0.0);
            let cy = (yf - pose[1]).max(pose[1] - (yf + 1.0)).max(0.0);
            gx.hypot(gy).max(cx.hypot(cy) - r)
        };
        let cells = || (y0..=y1).flat_map(move |y| (x0..=x1).map(move |x| (x, y)));
        let (first, _) = cells()
            .filter(|&(x, y)| occupied[y * width + x])
            .map(|(x, y)| ((x, y), lower(x, y)))
            .filter(|&(_, b)| b <= reach)
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        let mut best = polygon_square_distance(placed, [first.0 as f64, first.1 as f64]);
        for (x, y) in cells() {
            if !occupied[y * width + x] || (x, y) == first {
                continue;
            }
            let b = lower(x, y);
            let worth = if best > 0.0 { b < best } else { b <= 0.0 };
            if worth && b <= reach {
                best = best.min(polygon_square_distance(placed, [x as f64, y as f64]));
            }
        }
        Some(best)
    }
}

/// The heading-aware check of a path of planned points with a convex footprint polygon
/// whose origin lies a fixed distance ahead of the planned point along the heading (the
/// base frame ahead of the driven-axle midpoint): a pose collides when the polygon at the
/// pose's heading comes closer than the padding to an occupied cell (nav2's check of a
/// path against a polygon footprint). Poses are world poses on an [`OccupancyGrid`];
/// the occupied cells are the caller's (the map's, or the map's and the obstacles that
/// appeared since).
#[derive(Debug, Clone)]
pub struct PathCheck {
    /// The polygon about its origin, in cells.
    footprint: ConvexFootprint,
    /// The padding the polygon keeps from the occupied cells (cells).
    padding: f64,
    /// The polygon's origin ahead of the planned point (cells).
    ahead: f64,
    /// Scratch of the placed vertices.
    placed: Vec<[f64; 2]>,
}

impl PathCheck {
    /// The check of the convex `polygon` with `padding`, its origin `ahead` of the
    /// planned point, all lengths in units of which a cell is `cell` (the map's
    /// resolution for metres, 1 for cells).
    ///
    /// # Errors
    /// A polygon that is not convex; a padding that is negative or not finite, an offset
    /// or cell size that is not finite (or a cell size that is not positive).
    pub fn new(polygon: &Footprint, padding: f64, ahead: f64, cell: f64) -> Result<Self> {
        if !(padding.is_finite() && padding >= 0.0) {
            return Err(Error::invalid(
                "footprint padding",
                format!("must be a finite non-negative length, got {padding}"),
            ));
        }
        if !ahead.is_finite() {
            return Err(Error::NonFinite {
                field: "footprint offset".into(),
            });
        }
        Ok(Self {
            footprint: ConvexFootprint::new(polygon, cell)?,
            padding: padding / cell,
            ahead: ahead / cell,
            placed: Vec::new(),
        })
    }

    /// The polygon about its origin (cells).
    #[must_use]
    pub fn footprint(&self) -> &ConvexFootprint {
        &self.footprint
    }

    /// The padding (cells).
    #[must_use]
    pub fn padding(&self) -> f64 {
        self.padding
    }

    /// The world pose `[x, y, θ]` in `grid`'s continuous cell coordinates and frame.
    #[must_use]
    pub fn pose_in_cells(grid: &OccupancyGrid, pose: [f64; 3]) -> [f64; 3] {
        let [fx, fy] = grid.world_to_cell_f(pose[0], pose[1]);
        let yaw0 = if grid.kind == MapKind::Ros {
            grid.origin[2]
        } else {
            0.0
        };
        [fx, fy, pose[2] - yaw0]
    }

    /// `true` when the polygon with the planned point at the world pose `planned` comes
    /// closer than the padding to an `occupied` cell of `grid` (its cells' mask).
    ///
    /// # Panics
    /// If `occupied` does not hold one flag per cell of `grid`.
    pub fn collides(&mut self, grid: &OccupancyGrid, occupied: &[bool], planned: [f64; 3]) -> bool {
        let [fx, fy, th] = Self::pose_in_cells(grid, planned);
        let (s, c) = th.sin_cos();
        let origin = [fx + self.ahead * c, fy + self.ahead * s, th];
        self.clearance(occupied, grid.width, grid.height, origin, self.padding)
            .is_some_and(|d| d < self.padding)
    }

    /// The cells of the planned points among `poses` (world poses, in order) where the
    /// polygon collides ([`PathCheck::collides`]), each once, in the order met (a point
    /// off the map in its nearest cell).
    pub fn colliding_cells(
        &mut self,
        grid: &OccupancyGrid,
        occupied: &[bool],
        poses: impl IntoIterator<Item = [f64; 3]>,
    ) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for p in poses {
            if self.collides(grid, occupied, p) {
                let [fx, fy] = grid.world_to_cell_f(p[0], p[1]);
                let c = (
                    (fx.floor().max(0.0) as usize).min(grid.width - 1),
                    (fy.floor().max(0.0) as usize).min(grid.height - 1),
                );
                if !out.contains(&c) {
                    out.push(c);
                }
            }
        }
        out
    }

    /// [`ConvexFootprint::clearance`] of the polygon with its origin at `origin`
    /// (continuous cell coordinates and grid-frame heading), the padding not subtracted.
    ///
    /// # Panics
    /// If `occupied` does not hold `width · height` cells.
    pub fn clearance(
        &mut self,
        occupied: &[bool],
        width: usize,
        height: usize,
        origin: [f64; 3],
        reach: f64,
    ) -> Option<f64> {
        self.footprint
            .clearance(occupied, width, height, origin, reach, &mut self.placed)
    }
}

/// Signed distance between the convex counter-clockwise polygon `p` and the unit square
/// with lower-left corner `q` (negative: penetration depth).
fn polygon_square_distance(p: &[[f64; 2]], q: [f64; 2]) -> f64 {
    let n = p.len();
    let centre = [q[0] + 0.5, q[1] + 0.5];
    // the square's axes
    let (mut px0, mut px1, mut py0, mut py1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for v in p {
        px0 = px0.min(v[0]);
        px1 = px1.max(v[0]);
        py0 = py0.min(v[1]);
        py1 = py1.max(v[1]);
    }
    let mut sep = (q[0] - px1)
        .max(px0 - (q[0] + 1.0))
        .max(q[1] - py1)
        .max(py0 - (q[1] + 1.0));
    // the polygon's edge normals: the polygon's support along its own outward normal is
    // the edge itself, the square's lowest point along it its centre less half the
    // normal's L1 norm
    for i in 0..n {
        let (a, b) = (p[i], p[(i + 1) % n]);
        let (ex, ey) = (b[0] - a[0], b[1] - a[1]);
        let len = ex.hypot(ey);
        if len == 0.0 {
            continue;
        }
        let (nx, ny) = (ey / len, -ex / len);
        let square_min = nx * centre[0] + ny * centre[1] - 0.5 * (nx.abs() + ny.abs());
        sep = sep.max(square_min - (nx * a[0] + ny * a[1]));
    }
    if sep <= 0.0 {
        return sep;
    }
    // apart: the nearest pair is a vertex of one against an edge of the other
    let corners = [
        q,
        [q[0] + 1.0, q[1]],
        [q[0] + 1.0, q[1] + 1.0],
        [q[0], q[1] + 1.0],
    ];
    let mut d = f64::INFINITY;
    for v in p {
        let dx = (q[0] - v[0]).max(v[0] - (q[0] + 1.0)).max(0.0);
        let dy = (q[1] - v[1]).max(v[1] - (q[1] + 1.0)).max(0.0);
        d = d.min(dx.hypot(dy));
    }
    for c in corners {
        for i in 0..n {
            d = d.min(point_segment(c, p[i], p[(i + 1) % n]));
        }
    }
    d
}

fn point_segment(c: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (abx, aby) = (b[0] - a[0], b[1] - a[1]);
    let len2 = abx * abx + aby * aby;
    let t = if len2 > 0.0 {
        (((c[0] - a[0]) * abx + (c[1] - a[1]) * aby) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (c[0] - a[0] - t * abx).hypot(c[1] - a[1] - t * aby)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rect(l: f64, w: f64) -> ConvexFootprint {
        let fp = Footprint::new(vec![
            [-l / 2.0, -w / 2.0],
            [l / 2.0, -w / 2.0],
            [l / 2.0, w / 2.0],
            [-l / 2.0, w / 2.0],
        ])
        .unwrap();
        ConvexFootprint::new(&fp, 1.0).unwrap()
    }

    /// One occupied cell (5, 5) on a 12 × 12 grid.
    fn one_cell() -> Vec<bool> {
        let mut m = vec![false; 144];
        m[5 * 12 + 5] = true;
        m
    }

    #[test]
    fn distance_apart_is_the_gap_to_the_nearest_square() {
        let fp = rect(4.0, 2.0);
        let m = one_cell();
        let mut buf = Vec::new();
        // the rectangle's right edge at x = 3.5, the square from x = 5: 1.5 apart
        let d = fp.clearance(&m, 12, 12, [1.5, 5.5, 0.0], 10.0, &mut buf);
        assert!((d.unwrap() - 1.5).abs() < 1e-12, "{d:?}");
        // corner to corner: the rectangle's corner (3.5, 3.5) to the square's (5, 5)
        let d = fp.clearance(&m, 12, 12, [1.5, 2.5, 0.0], 10.0, &mut buf);
        assert!((d.unwrap() - 1.5 * 2f64.sqrt()).abs() < 1e-12, "{d:?}");
        // beyond reach: nothing looked at
        assert_eq!(
            fp.clearance(&m, 12, 12, [1.5, 5.5, 0.0], 1.0, &mut buf),
            None
        );
    }

    #[test]
    fn overlap_is_the_depth_of_penetration() {
        let fp = rect(4.0, 2.0);
        let m = one_cell();
        let mut buf = Vec::new();
        // right edge at x = 5.25: the square is entered by 0.25
        let d = fp.clearance(&m, 12, 12, [3.25, 5.5, 0.0], 0.0, &mut buf);
        assert!((d.unwrap() + 0.25).abs() < 1e-12, "{d:?}");
    }

    #[test]
    fn the_heading_decides_whether_a_long_footprint_collides() {
        let fp = rect(4.0, 1.0);
        let m = one_cell();
        let mut buf = Vec::new();
        // centred 2 cells below the square's centre: lengthwise along x it passes 1 cell
        // from the square, turned along y it runs into it
        let along = fp.clearance(&m, 12, 12, [5.5, 3.5, 0.0], 0.0, &mut buf);
        let across = fp.clearance(
            &m,
            12,
            12,
            [5.5, 3.5, std::f64::consts::FRAC_PI_2],
            0.0,
            &mut buf,
        );
        assert_eq!(along, None);
        assert!(across.unwrap() < 0.0, "{across:?}");
        let along = fp.clearance(&m, 12, 12, [5.5, 3.5, 0.0], 5.0, &mut buf);
        assert!((along.unwrap() - 1.0).abs() < 1e-12, "{along:?}");
    }

    #[test]
    fn a_concave_polygon_is_refused() {
        let fp = Footprint::new(vec![
            [-1.0, -1.0],
            [1.0, -1.0],
            [0.2, 0.0],
            [1.0, 1.0],
            [-1.0, 1.0],
        ])
        .unwrap();
        assert!(ConvexFootprint::new(&fp, 0.05).is_err());
    }
}

//! The occupancy grid every planner works on, and conversions between world and cell
//! coordinates.

use crate::{Error, Result};

// Cost values of a cost layer, as nav2 defines them (`nav2_costmap_2d/cost_values.hpp`).

/// nav2 `FREE_SPACE`.
pub const FREE_SPACE: u8 = 0;
/// nav2 `MAX_NON_OBSTACLE`: the highest cost a robot centre may occupy.
pub const MAX_NON_OBSTACLE: u8 = 252;
/// nav2 `INSCRIBED_INFLATED_OBSTACLE`: the robot centre here means a collision.
pub const INSCRIBED: u8 = 253;
/// nav2 `LETHAL_OBSTACLE`: an obstacle cell.
pub const LETHAL: u8 = 254;
/// nav2 `NO_INFORMATION`: unknown cell.
pub const NO_INFORMATION: u8 = 255;

/// Cell value of an occupied cell (ROS `nav_msgs/OccupancyGrid` convention).
pub const OCCUPIED: i8 = 100;
/// Cell value of a free cell.
pub const FREE: i8 = 0;
/// Cell value of an unknown cell.
pub const UNKNOWN: i8 = -1;

/// Where an [`OccupancyGrid`] came from; decides how cell rows map to the world.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MapKind {
    /// A ROS `map_server` map (YAML + image, or a bare image with the legacy defaults):
    /// row 0 is the **bottom** image row, world = origin pose ∘ (cell centre × resolution).
    Ros,
    /// A Moving AI `.map`: row 0 is the **top** row of the file, world coordinates are
    /// the cell coordinates themselves (x = column, y = row, resolution 1, origin 0).
    MovingAi,
}

/// A 2-D occupancy grid: `cells[y * width + x]` holds 100 (occupied), 0 (free), −1
/// (unknown) or, for `scale`/`raw` ROS maps, an intermediate occupancy in 1..=99.
///
/// For ROS maps row `y = 0` is the bottom row of the image (the `nav_msgs/OccupancyGrid`
/// layout, the loader flips the image); for Moving AI maps row 0 is the file's first row.
#[derive(Debug, Clone, PartialEq)]
pub struct OccupancyGrid {
    /// Number of columns.
    pub width: usize,
    /// Number of rows.
    pub height: usize,
    /// Edge length of one cell (m/cell); 1 for Moving AI maps.
    pub resolution: f64,
    /// Pose `[x, y, yaw]` of the lower-left corner of cell (0, 0) in the world frame
    /// (ROS `origin`; yaw counter-clockwise in radians).
    pub origin: [f64; 3],
    /// Row-major cell values, `width * height` of them.
    pub cells: Vec<i8>,
    /// How rows relate to the world frame.
    pub kind: MapKind,
}

/// Occupied, free and unknown cell counts of a grid.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct CellCounts {
    /// Cells with value ≥ the lethal threshold (100).
    pub occupied: usize,
    /// Cells with value 0.
    pub free: usize,
    /// Cells with value −1.
    pub unknown: usize,
    /// Cells with an intermediate value 1..=99 (`scale` / `raw` maps only).
    pub intermediate: usize,
}

impl OccupancyGrid {
    /// An all-free grid of `width × height` cells with resolution 1 and origin 0.
    pub fn new_free(width: usize, height: usize, kind: MapKind) -> Result<Self> {
        check_size(width, height)?;
        Ok(Self {
            width,
            height,
            resolution: 1.0,
            origin: [0.0; 3],
            cells: vec![FREE; width * height],
            kind,
        })
    }

    /// Builds a grid from a row-major passability mask (`true` = free).
    pub fn from_free_mask(
        width: usize,
        height: usize,
        free: &[bool],
        kind: MapKind,
    ) -> Result<Self> {
        check_size(width, height)?;
        crate::error::ensure_len("free mask", width * height, free.len())?;
        Ok(Self {
            width,
            height,
            resolution: 1.0,
            origin: [0.0; 3],
            cells: free
                .iter()
                .map(|&f| if f { FREE } else { OCCUPIED })
                .collect(),
            kind,
        })
    }

    /// Number of cells.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// `true` for a grid without cells (never produced by the loaders).
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// Row-major index of cell `(x, y)`.
    #[inline]
    pub fn index(&self, x: usize, y: usize) -> usize {
        y * self.width + x
    }

    /// Value of cell `(x, y)`, `None` outside the grid.
    pub fn get(&self, x: i64, y: i64) -> Option<i8> {
        if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height {
            None
        } else {
            Some(self.cells[self.index(x as usize, y as usize)])
        }
    }

    /// Counts occupied (≥ 100), free (0), unknown (−1) and intermediate cells.
    pub fn counts(&self) -> CellCounts {
        let mut c = CellCounts::default();
        for &v in &self.cells {
            match v {
                v if v < 0 => c.unknown += 1,
                0 => c.free += 1,
                v if v >= OCCUPIED => c.occupied += 1,
                _ => c.intermediate += 1,
            }
        }
        c
    }

    /// The obstacle mask used for planning: `true` where the cell is an obstacle, i.e.
    /// its value is ≥ `lethal_threshold` (nav2's static layer uses 100), or it is unknown
    /// and `unknown_is_obstacle` is set.
    pub fn obstacle_mask(&self, lethal_threshold: i8, unknown_is_obstacle: bool) -> Vec<bool> {
        self.cells
            .iter()
            .map(|&v| {
                if v < 0 {
                    unknown_is_obstacle
                } else {
                    v >= lethal_threshold
                }
            })
            .collect()
    }

    /// World coordinates of the centre of cell `(x, y)`.
    ///
    /// ROS maps: `origin ∘ ((x + ½) r, (y + ½) r)` (rotation by the origin's yaw);
    /// Moving AI maps: `(x, y)` itself.
    pub fn cell_to_world(&self, x: f64, y: f64) -> [f64; 2] {
        match self.kind {
            MapKind::MovingAi => [x, y],
            MapKind::Ros => {
                let (s, c) = self.origin[2].sin_cos();
                let lx = (x + 0.5) * self.resolution;
                let ly = (y + 0.5) * self.resolution;
                [
                    self.origin[0] + c * lx - s * ly,
                    self.origin[1] + s * lx + c * ly,
                ]
            }
        }
    }

    /// Continuous cell coordinates of a world point (cell `(i, j)` spans `[i, i+1) ×
    /// [j, j+1)` for ROS maps; for Moving AI maps cell centres sit on integers).
    pub fn world_to_cell_f(&self, wx: f64, wy: f64) -> [f64; 2] {
        match self.kind {
            MapKind::MovingAi => [wx + 0.5, wy + 0.5],
            MapKind::Ros => {
                let (s, c) = self.origin[2].sin_cos();
                let dx = wx - self.origin[0];
                let dy = wy - self.origin[1];
                [
                    (c * dx + s * dy) / self.resolution,
                    (-s * dx + c * dy) / self.resolution,
                ]
            }
        }
    }

    /// The cell containing a world point, or an error naming `what` if it lies outside
    /// the grid or is not finite.
    pub fn world_to_cell(&self, what: &str, wx: f64, wy: f64) -> Result<(usize, usize)> {
        if !wx.is_finite() || !wy.is_finite() {
            return Err(Error::NonFinite {
                field: what.to_string(),
            });
        }
        let [fx, fy] = self.world_to_cell_f(wx, wy);
        let (ix, iy) = (fx.floor(), fy.floor());
        if ix < 0.0 || iy < 0.0 || ix >= self.width as f64 || iy >= self.height as f64 {
            return Err(Error::Planning(format!(
                "{what} ({wx}, {wy}) lies outside the map (cell ({ix}, {iy}); the map has {} x {} cells)",
                self.width, self.height
            )));
        }
        Ok((ix as usize, iy as usize))
    }
}

pub(crate) fn check_size(width: usize, height: usize) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(Error::invalid(
            "map size",
            format!("{width} x {height}: a map needs at least one cell"),
        ));
    }
    if width >= u16::MAX as usize - 2
        || height >= u16::MAX as usize - 2
        || width * height >= (u32::MAX / 2) as usize
    {
        return Err(Error::invalid(
            "map size",
            format!("{width} x {height}: at most 65,532 cells per side and 2^31 cells in all"),
        ));
    }
    Ok(())
}

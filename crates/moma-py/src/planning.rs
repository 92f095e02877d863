//! Maps and grid planning: `moma.load_map`, `moma.Map`, `moma.plan`.

use crate::err;
use moma::planning::costmap;
use moma::planning::smooth::smooth;
use moma::planning::{MapKind, OccupancyGrid, SearchGrid, astar, load_map as load};
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use std::path::PathBuf;

/// An occupancy grid: a ROS map (coordinates in world metres) or a Moving AI map
/// (coordinates in cells).
#[pyclass(module = "moma", name = "Map", frozen)]
pub struct PyMap {
    grid: OccupancyGrid,
    source: String,
}

impl PyMap {
    fn world(&self) -> bool {
        self.grid.kind == MapKind::Ros
    }

    /// `(x, y) m (cell (i, j))` on a ROS map, `cell (i, j)` on a Moving AI map.
    fn describe(&self, c: (usize, usize)) -> String {
        if self.world() {
            let [x, y] = self.grid.cell_to_world(c.0 as f64, c.1 as f64);
            format!("({x:.3}, {y:.3}) m (cell ({}, {}))", c.0, c.1)
        } else {
            format!("cell ({}, {})", c.0, c.1)
        }
    }

    /// The cell of a point in the map's frame.
    fn cell_of(&self, what: &str, p: [f64; 2]) -> PyResult<(usize, usize)> {
        let g = &self.grid;
        let [x, y] = p;
        if self.world() {
            return g.world_to_cell(what, x, y).map_err(err);
        }
        if x < 0.0
            || y < 0.0
            || x.fract() != 0.0
            || y.fract() != 0.0
            || x >= g.width as f64
            || y >= g.height as f64
        {
            return Err(err(format!(
                "{what} ({x}, {y}) must be a cell of the {} x {} map (integers from 0)",
                g.width, g.height
            )));
        }
        Ok((x as usize, y as usize))
    }
}

#[pymethods]
impl PyMap {
    /// Number of columns.
    #[getter]
    fn width(&self) -> usize {
        self.grid.width
    }

    /// Number of rows.
    #[getter]
    fn height(&self) -> usize {
        self.grid.height
    }

    /// Cell size (m/cell; 1 on Moving AI maps).
    #[getter]
    fn resolution(&self) -> f64 {
        self.grid.resolution
    }

    /// Pose `[x, y, yaw]` of the corner of cell (0, 0) in the world (ROS `origin`).
    #[getter]
    fn origin(&self) -> [f64; 3] {
        self.grid.origin
    }

    /// "ros" (world metres) or "movingai" (cells).
    #[getter]
    fn kind(&self) -> &'static str {
        if self.world() { "ros" } else { "movingai" }
    }

    /// The cell values (height × width, int8: 0 free … 100 occupied, −1 unknown), row
    /// `j` holding cells `(i, j)`.
    #[getter]
    fn cells<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<i8>>> {
        PyArray1::from_slice(py, &self.grid.cells).reshape([self.grid.height, self.grid.width])
    }

    fn __repr__(&self) -> String {
        format!(
            "moma.Map('{}', kind='{}', {} x {} cells, resolution {})",
            self.source,
            self.kind(),
            self.grid.width,
            self.grid.height,
            self.grid.resolution
        )
    }
}

/// Loads a map by extension: ROS map_server YAML (`.yaml`), Moving AI (`.map`), or a
/// bare PGM/PNG image with `resolution` (m/cell, default 0.05).
#[pyfunction]
#[pyo3(signature = (path, resolution = None))]
fn load_map(py: Python<'_>, path: PathBuf, resolution: Option<f64>) -> PyResult<PyMap> {
    let loaded = py.detach(|| load(&path, resolution)).map_err(err)?;
    Ok(PyMap {
        grid: loaded.grid,
        source: path.display().to_string(),
    })
}

/// Plans a path from `start` to `goal` (`[x, y]`: world metres on ROS maps, cells on
/// Moving AI maps) for a disk robot of `radius` (same units): A* (octile, no corner
/// cutting) on the map's obstacles dilated by the disk, then shortcut smoothing
/// (`smooth=False` returns every cell of the A* path). Returns the waypoints as an
/// (n, 2) array in the map's frame (cell centres), or None when the goal cannot be
/// reached. Unknown cells are obstacles unless `unknown="free"`. The GIL is released.
///
/// Raises MomaError when start or goal lies outside the map, in an obstacle or closer
/// than `radius` to one.
#[pyfunction]
#[pyo3(signature = (grid, start, goal, radius = 0.0, unknown = "obstacle", smooth = true))]
fn plan<'py>(
    py: Python<'py>,
    grid: PyRef<'py, PyMap>,
    start: [f64; 2],
    goal: [f64; 2],
    radius: f64,
    unknown: &str,
    smooth: bool,
) -> PyResult<Option<Bound<'py, PyArray2<f64>>>> {
    let unknown_is_obstacle = match unknown {
        "obstacle" => true,
        "free" => false,
        other => {
            return Err(err(format!(
                "unknown: '{other}' is not one of obstacle, free"
            )));
        }
    };
    if !(radius.is_finite() && radius >= 0.0) {
        return Err(err(format!(
            "radius must be a finite non-negative number, got {radius}"
        )));
    }
    let mf = &*grid;
    let (w, h) = (mf.grid.width, mf.grid.height);
    let s = mf.cell_of("start", start)?;
    let g = mf.cell_of("goal", goal)?;
    let obst = mf.grid.obstacle_mask(100, unknown_is_obstacle);
    for (what, c) in [("start", s), ("goal", g)] {
        if obst[c.1 * w + c.0] {
            let kind = if mf.grid.cells[c.1 * w + c.0] < 0 {
                "an unknown cell (use unknown=\"free\" to allow)"
            } else {
                "an obstacle"
            };
            return Err(err(format!("{what} at {} lies in {kind}", mf.describe(c))));
        }
    }
    let radius_cells = if mf.world() {
        radius / mf.grid.resolution
    } else {
        radius
    };
    let units = if mf.world() { "m" } else { "cells" };
    let found = py.detach(|| -> PyResult<Option<Vec<[f64; 2]>>> {
        let cspace = costmap::inflate(&obst, w, h, radius_cells).map_err(err)?;
        let sg = SearchGrid::from_obstacles(&cspace, w, h).map_err(err)?;
        for (what, c) in [("start", s), ("goal", g)] {
            if !sg.is_free(c.0 as i64, c.1 as i64) {
                return Err(err(format!(
                    "{what} at {} is closer than the robot radius {radius} {units} to an obstacle (inside the configuration-space obstacle)",
                    mf.describe(c)
                )));
            }
        }
        let Some(path) = astar(&sg, s, g).map_err(err)? else {
            return Ok(None);
        };
        let cells = if smooth {
            smooth_cells(&sg, &path.cells)
        } else {
            path.cells
        };
        Ok(Some(
            cells
                .iter()
                .map(|c| mf.grid.cell_to_world(c.0 as f64, c.1 as f64))
                .collect(),
        ))
    })?;
    match found {
        None => Ok(None),
        Some(pts) => {
            let n = pts.len();
            let flat: Vec<f64> = pts.into_iter().flatten().collect();
            Ok(Some(PyArray1::from_vec(py, flat).reshape([n, 2])?))
        }
    }
}

fn smooth_cells(sg: &SearchGrid, cells: &[(usize, usize)]) -> Vec<(usize, usize)> {
    smooth(sg, cells)
}

/// Registers the class and functions.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMap>()?;
    m.add_function(wrap_pyfunction!(load_map, m)?)?;
    m.add_function(wrap_pyfunction!(plan, m)?)?;
    Ok(())
}

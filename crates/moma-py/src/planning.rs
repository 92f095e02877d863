//! Maps and grid planning: `moma.load_map`, `moma.Map`, `moma.plan`.

use crate::{err, json_to_py};
use moma::planning::pipeline::{
    self, Frame, PLAN_DT, PLAN_LIMITS, PlanFields, PlanRequest, PlanStatus, PolygonCheck,
    RobotFootprint, Search, Timing,
};
use moma::planning::{MapKind, OccupancyGrid, load_map as load};
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
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
/// Moving AI maps) for a disk robot of `radius` (same units) through the library's
/// planning pipeline, as `moma plan`: A* (octile, no corner cutting) on the map's
/// obstacles dilated by the disk, then shortcut smoothing
/// (`smooth=False` returns every cell of the A* path). Returns the waypoints as an
/// (n, 2) array in the map's frame (cell centres), or None when the goal cannot be
/// reached. Unknown cells are obstacles unless `unknown="free"`. The GIL is released.
///
/// With `check_footprint` (a convex polygon `[[x, y], ...]` about the planned point, map
/// units) the path is checked as `moma plan --check-footprint` checks it: timed
/// stop-and-turn with `moma plan`'s default limits, every pose checked with the polygon at
/// its heading, keeping `check_padding` (≥ 0) from the obstacle cells; the start and goal
/// are checked at the heading the path leaves and arrives with. The result is then a dict:
/// `status` ("found", or "colliding" when a pose collides), `waypoints` and `check` (kind,
/// vertices, padding, colliding: the cells of the colliding poses), as `moma plan` writes
/// them in path.json (`status`, `waypoints`, `robot.check`); None when unreachable.
///
/// Raises MomaError when start or goal lies outside the map, in an obstacle or closer
/// than `radius` to one, or where the `check_footprint` polygon collides; for a polygon
/// that is not convex (naming `check_footprint`) and a negative or non-finite
/// `check_padding`, or one given without `check_footprint`.
#[pyfunction]
#[pyo3(signature = (
    grid, start, goal, radius = 0.0, unknown = "obstacle", smooth = true,
    check_footprint = None, check_padding = None
))]
#[allow(clippy::too_many_arguments)]
fn plan<'py>(
    py: Python<'py>,
    grid: PyRef<'py, PyMap>,
    start: [f64; 2],
    goal: [f64; 2],
    radius: f64,
    unknown: &str,
    smooth: bool,
    check_footprint: Option<Vec<[f64; 2]>>,
    check_padding: Option<f64>,
) -> PyResult<Option<Bound<'py, PyAny>>> {
    let unknown_is_obstacle = match unknown {
        "obstacle" => true,
        "free" => false,
        other => {
            return Err(err(format!(
                "unknown: '{other}' is not one of obstacle, free"
            )));
        }
    };
    let polygon_check = match check_footprint {
        None if check_padding.is_some() => {
            return Err(err(
                "check_padding: read only with check_footprint (the polygon it pads)",
            ));
        }
        None => None,
        Some(vertices) => Some(
            PolygonCheck::new(
                vertices,
                check_padding.unwrap_or(0.0),
                0.0,
                ["check_footprint", "check_padding"],
            )
            .map_err(err)?,
        ),
    };
    // the check is of the timed path, timed as `moma plan` times it by default
    let timing = polygon_check.as_ref().map(|_| Timing::StopAndTurn {
        limits: PLAN_LIMITS,
        dt: PLAN_DT,
    });
    let request = PlanRequest {
        start,
        start_yaw: None,
        goal,
        goal_yaw: None,
        frame: Frame::Map,
        unknown_is_obstacle,
        footprint: RobotFootprint::Disk(radius),
        axle_offset: 0.0,
        fields: PlanFields::default(),
        search: Search::Astar,
        turn_cost: 1.0,
        smooth,
        timing,
        polygon_check,
    };
    let grid = &grid.grid;
    let found = py.detach(|| pipeline::plan(grid, &request)).map_err(err)?;
    if found.status == PlanStatus::Unreachable {
        return Ok(None);
    }
    let cells = if smooth {
        &found.smoothed
    } else {
        &found.cells
    };
    let n = cells.len();
    let flat: Vec<f64> = cells
        .iter()
        .flat_map(|c| grid.cell_to_world(c.0 as f64, c.1 as f64))
        .collect();
    let waypoints = PyArray1::from_vec(py, flat).reshape([n, 2])?.into_any();
    let Some(report) = found.check_report(&request) else {
        return Ok(Some(waypoints));
    };
    let report = serde_json::to_value(report).map_err(err)?;
    let out = PyDict::new(py);
    out.set_item("status", found.outcome())?;
    out.set_item("waypoints", waypoints)?;
    out.set_item("check", json_to_py(py, &report)?)?;
    Ok(Some(out.into_any()))
}

/// Registers the class and functions.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMap>()?;
    m.add_function(wrap_pyfunction!(load_map, m)?)?;
    m.add_function(wrap_pyfunction!(plan, m)?)?;
    Ok(())
}

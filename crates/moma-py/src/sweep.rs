//! Sweeps (`moma.Sweep`, `moma.Table`, used by the `moma.sweep` Python module) and
//! missions (`moma.run_mission`).

use crate::{chain, err, json_to_py};
use moma::sweep::{Sweep, Table, Value, merge};
use pyo3::IntoPyObjectExt;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyFloat, PyInt, PyString};
use std::path::PathBuf;

/// A sweep file loaded and validated (moma's `sweep::Sweep`): its points, columns and
/// evaluation on a rayon pool. `moma.sweep.run` drives it locally or on Ray.
#[pyclass(module = "moma", name = "Sweep", frozen)]
pub struct PySweep {
    inner: Sweep,
}

#[pymethods]
impl PySweep {
    /// Loads and validates a sweep TOML file (paths inside resolve against its folder).
    #[staticmethod]
    fn from_file(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let inner = py.detach(|| Sweep::from_file(&path)).map_err(err)?;
        Ok(Self { inner })
    }

    /// The study: "stability" or "placement".
    #[getter]
    fn study(&self) -> String {
        self.inner.study().to_string()
    }

    /// Number of points.
    fn __len__(&self) -> usize {
        self.inner.len() as usize
    }

    /// The table's column names (index, parameters, results, `*_time_s` timing last).
    #[getter]
    fn columns(&self) -> Vec<String> {
        self.inner.columns()
    }

    /// Evaluates the points `indices` (all points when None) on `threads` threads (0: all
    /// cores), GIL released, into a table sorted by index.
    #[pyo3(signature = (indices = None, threads = 0))]
    fn run(&self, py: Python<'_>, indices: Option<Vec<u64>>, threads: usize) -> PyResult<PyTable> {
        let idx = indices.unwrap_or_else(|| (0..self.inner.len()).collect());
        let t = py.detach(|| self.inner.run(&idx, threads)).map_err(err)?;
        Ok(PyTable { inner: t })
    }

    /// The indices of shard `k` of `n` (1 ≤ k ≤ n): `i` with `i mod n = k − 1`.
    fn shard_indices(&self, k: u64, n: u64) -> PyResult<Vec<u64>> {
        moma::sweep::shard_indices(self.inner.len(), k, n).map_err(err)
    }
}

/// A sweep's results table (moma's `sweep::Table`): columns and rows, CSV as
/// `moma sweep` writes it.
#[pyclass(module = "moma", name = "Table", frozen)]
pub struct PyTable {
    inner: Table,
}

fn cell_to_py<'py>(py: Python<'py>, v: &Value) -> PyResult<Bound<'py, PyAny>> {
    match v {
        Value::Int(i) => i.into_bound_py_any(py),
        Value::Float(f) => f.into_bound_py_any(py),
        Value::Bool(b) => b.into_bound_py_any(py),
        Value::Text(s) => s.as_str().into_bound_py_any(py),
        Value::Missing => Ok(py.None().into_bound(py)),
    }
}

fn cell_from_py(x: &Bound<'_, PyAny>) -> PyResult<Value> {
    if x.is_none() {
        Ok(Value::Missing)
    } else if x.is_instance_of::<PyBool>() {
        Ok(Value::Bool(x.extract()?))
    } else if x.is_instance_of::<PyInt>() {
        Ok(Value::Int(x.extract()?))
    } else if x.is_instance_of::<PyFloat>() {
        Ok(Value::Float(x.extract()?))
    } else if x.is_instance_of::<PyString>() {
        Ok(Value::Text(x.extract()?))
    } else {
        Err(err(format!(
            "table cell: expected int, float, bool, str or None, got {}",
            x.get_type().name()?
        )))
    }
}

#[pymethods]
impl PyTable {
    /// A table from column names and rows of int, float, bool, str or None cells (the
    /// form `rows` returns; how Ray tasks send their rows back).
    #[new]
    fn new(columns: Vec<String>, rows: Vec<Vec<Bound<'_, PyAny>>>) -> PyResult<Self> {
        let mut out = Vec::with_capacity(rows.len());
        for (k, r) in rows.iter().enumerate() {
            if r.len() != columns.len() {
                return Err(err(format!(
                    "table row {k}: {} cells for {} columns",
                    r.len(),
                    columns.len()
                )));
            }
            out.push(r.iter().map(cell_from_py).collect::<PyResult<Vec<_>>>()?);
        }
        Ok(Self {
            inner: Table { columns, rows: out },
        })
    }

    /// Reads a table written by `moma sweep` or `write_csv` (cells come back as text).
    #[staticmethod]
    fn read_csv(path: PathBuf) -> PyResult<Self> {
        Ok(Self {
            inner: Table::read_csv(&path).map_err(err)?,
        })
    }

    /// Joins shard tables (equal headers, disjoint indices covering 0..n).
    #[staticmethod]
    fn merge(tables: Vec<PyRef<'_, PyTable>>) -> PyResult<Self> {
        let names: Vec<String> = (0..tables.len()).map(|k| format!("table {k}")).collect();
        let ts = tables.iter().map(|t| t.inner.clone()).collect();
        Ok(Self {
            inner: merge(ts, &names).map_err(err)?,
        })
    }

    /// Column names.
    #[getter]
    fn columns(&self) -> Vec<String> {
        self.inner.columns.clone()
    }

    /// The rows as lists of int, float, bool, str or None (None: undefined measure).
    #[getter]
    fn rows<'py>(&self, py: Python<'py>) -> PyResult<Vec<Vec<Bound<'py, PyAny>>>> {
        self.inner
            .rows
            .iter()
            .map(|r| r.iter().map(|v| cell_to_py(py, v)).collect())
            .collect()
    }

    /// The point index of every row.
    fn indices(&self) -> Vec<u64> {
        self.inner.indices()
    }

    /// The table without its `*_time_s` timing columns (identical whatever the backend,
    /// shards and threads).
    fn without_timing(&self) -> Self {
        Self {
            inner: self.inner.without_timing(),
        }
    }

    /// The CSV text, as `moma sweep` writes it.
    fn to_csv(&self) -> String {
        self.inner.to_csv()
    }

    /// Writes the CSV atomically.
    fn write_csv(&self, path: PathBuf) -> PyResult<()> {
        self.inner.write_csv(&path).map_err(err)
    }

    fn __len__(&self) -> usize {
        self.inner.rows.len()
    }

    fn __eq__(&self, other: PyRef<'_, PyTable>) -> bool {
        self.inner == other.inner
    }

    fn __repr__(&self) -> String {
        format!(
            "moma.Table({} rows x {} columns)",
            self.inner.rows.len(),
            self.inner.columns.len()
        )
    }
}

/// Runs a mission file end to end (plan, timed reference, closed-loop simulation with
/// re-planning, end-effector reach, monitors), GIL released, and returns its summary
/// dict (the keys of `moma mission`'s summary.json that do not concern files or the
/// report: `mission`, `reached`, `reason`, `time_to_goal`, `simulated_time`, `replans`,
/// the stability, clearance, tracking and slip extremes, `final_pose_error`,
/// `end_effector_error`, saturation counts, energies, `tip_over_limits`, `samples`, and
/// the wall times: `wall_time_s` (load and run) and `wall_time` with `planning_s`,
/// `smoothing_timing_s`, `simulation_s`). Writes no file. A mission that runs but does
/// not reach its goal returns `reached=False` with the reason; invalid input raises
/// MomaError, its message naming the file once, with the OS reason of a file that cannot
/// be read.
#[pyfunction]
fn run_mission<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyAny>> {
    let clock = std::time::Instant::now();
    let (m, r) = py
        .detach(|| -> moma::Result<_> {
            let m = moma::mission::load(&path)?;
            let r = moma::mission::run(&m)?;
            Ok((m, r))
        })
        .map_err(|e| {
            let text = chain(&e);
            let file = path.display().to_string();
            if text.contains(&file) {
                err(text)
            } else {
                err(format!("{file}: {text}"))
            }
        })?;
    let wall = clock.elapsed().as_secs_f64();
    let mut doc = moma::mission::summary(&m, &r);
    doc.insert("wall_time_s".into(), serde_json::json!(wall));
    doc.insert(
        "wall_time".into(),
        serde_json::json!({
            "planning_s": r.wall.planning_s,
            "smoothing_timing_s": r.wall.smoothing_timing_s,
            "simulation_s": r.wall.simulation_s,
        }),
    );
    json_to_py(py, &serde_json::Value::Object(doc))
}

/// Registers the classes and functions.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PySweep>()?;
    m.add_class::<PyTable>()?;
    m.add_function(wrap_pyfunction!(run_mission, m)?)?;
    Ok(())
}

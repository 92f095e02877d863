//! The `moma` Python package: the library's Model / Data / free-function API with numpy
//! arrays in and out (built by maturin from `pyproject.toml`; Python tests in `tests/`).
//!
//! Conventions, for every function:
//! * inputs are anything numpy turns into float64 arrays; their lengths are checked
//!   against the model and a wrong length or a non-finite value raises
//!   [`MomaError`] with the library's message naming the function and argument;
//! * a `Data` belongs to the `Model` that created it (another model's `Data` is an
//!   error, not a crash);
//! * single-state calls keep the GIL (they take well under a microsecond to a few
//!   microseconds, less than releasing and re-taking it costs); the `*_batch` forms,
//!   `plan` and every call that reads a file release it while Rust works;
//! * the per-state dictionaries of `stability`, `space` and `osc` are the objects of the
//!   command line's JSON (`states[i]`), built by the same library structs.

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use pyo3::{IntoPyObjectExt, create_exception};

mod analysis;
mod chapter;
mod collision;
mod dynamics;
mod layout;
mod model;
mod motion;
mod place;
mod planning;
mod simulate;
mod sweep;

create_exception!(
    moma,
    MomaError,
    pyo3::exceptions::PyException,
    "Raised for invalid input and failing solvers; the message is the moma library's."
);

/// A library error as a Python `MomaError`.
pub(crate) fn err(e: impl std::fmt::Display) -> PyErr {
    MomaError::new_err(e.to_string())
}

/// An error and its causes joined by `": "`, as the command line prints it.
pub(crate) fn chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        text = format!("{text}: {c}");
        cause = c.source();
    }
    text
}

/// A JSON value (of a serialised library report) as Python objects: objects become
/// dicts (in field order), arrays lists, integers int, other numbers float, null None.
pub(crate) fn json_to_py<'py>(
    py: Python<'py>,
    v: &serde_json::Value,
) -> PyResult<Bound<'py, PyAny>> {
    use serde_json::Value;
    match v {
        Value::Null => Ok(py.None().into_bound(py)),
        Value::Bool(b) => b.into_bound_py_any(py),
        Value::Number(n) => {
            if let Some(i) = n.as_u64() {
                i.into_bound_py_any(py)
            } else if let Some(i) = n.as_i64() {
                i.into_bound_py_any(py)
            } else {
                n.as_f64().unwrap_or(f64::NAN).into_bound_py_any(py)
            }
        }
        Value::String(s) => s.as_str().into_bound_py_any(py),
        Value::Array(a) => {
            let items = a
                .iter()
                .map(|x| json_to_py(py, x))
                .collect::<PyResult<Vec<_>>>()?;
            Ok(PyList::new(py, items)?.into_any())
        }
        Value::Object(o) => {
            let d = PyDict::new(py);
            for (k, x) in o {
                d.set_item(k, json_to_py(py, x)?)?;
            }
            Ok(d.into_any())
        }
    }
}

/// A serialisable library report as Python objects.
pub(crate) fn to_py<'py, T: serde::Serialize>(
    py: Python<'py>,
    x: &T,
) -> PyResult<Bound<'py, PyAny>> {
    let v = serde_json::to_value(x).map_err(err)?;
    json_to_py(py, &v)
}

/// Kinematics, dynamics, tip-over stability, control and planning of wheeled mobile
/// manipulators and free-floating space manipulators (the moma Rust library).
#[pymodule]
fn _moma(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("MomaError", m.py().get_type::<MomaError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    model::register(m)?;
    dynamics::register(m)?;
    layout::register(m)?;
    analysis::register(m)?;
    chapter::register(m)?;
    collision::register(m)?;
    planning::register(m)?;
    motion::register(m)?;
    place::register(m)?;
    sweep::register(m)?;
    simulate::register(m)?;
    Ok(())
}

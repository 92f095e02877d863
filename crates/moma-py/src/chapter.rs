//! The chapter's closed-form models from Python: `moma.eval_cases` (the document that
//! `moma eval` writes) and `moma.eval_case` (one case of one model), through the library's
//! one registry (`moma::closed_form::registry`) and case evaluator
//! (`moma::closed_form::cases`).

use crate::{err, json_to_py};
use moma::closed_form::cases::{
    DEFAULT_TOLERANCE, MAX_TOLERANCE, MIN_TOLERANCE, UNICYCLE_CONTROL, evaluate_case,
    evaluate_document,
};
use moma::closed_form::registry::{ChapterModel, MODEL_NAMES};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use serde_json::{Map, Number, Value};
use std::path::PathBuf;

/// Deepest nesting of a Python document accepted (a case file is four levels deep).
const MAX_DEPTH: usize = 64;

/// A Python document (dicts with string keys, lists, tuples, numbers, strings, bools,
/// None; numpy arrays and scalars through their `tolist`) as JSON; `path` names the
/// offending entry in errors.
fn py_to_json(x: &Bound<'_, PyAny>, path: &str, depth: usize) -> PyResult<Value> {
    if depth > MAX_DEPTH {
        return Err(err(format!(
            "{path}: nested deeper than {MAX_DEPTH} levels"
        )));
    }
    if x.is_none() {
        return Ok(Value::Null);
    }
    if let Ok(b) = x.cast::<PyBool>() {
        return Ok(Value::Bool(b.is_true()));
    }
    if x.is_instance_of::<PyInt>() {
        if let Ok(i) = x.extract::<i64>() {
            return Ok(Value::from(i));
        }
        if let Ok(u) = x.extract::<u64>() {
            return Ok(Value::from(u));
        }
        return Err(err(format!("{path}: integer out of the 64-bit range")));
    }
    if x.is_instance_of::<PyFloat>() {
        let f: f64 = x.extract()?;
        return Number::from_f64(f)
            .map(Value::Number)
            .ok_or_else(|| err(format!("{path}: non-finite number {f}")));
    }
    if let Ok(s) = x.cast::<PyString>() {
        return Ok(Value::String(s.to_str()?.to_owned()));
    }
    if let Ok(d) = x.cast::<PyDict>() {
        let mut m = Map::new();
        for (k, v) in d.iter() {
            let key: String = k
                .extract()
                .map_err(|_| err(format!("{path}: dict keys must be strings, got {k}")))?;
            let sub = format!("{path}.{key}");
            m.insert(key, py_to_json(&v, &sub, depth + 1)?);
        }
        return Ok(Value::Object(m));
    }
    let seq = |items: Vec<Bound<'_, PyAny>>| -> PyResult<Value> {
        items
            .iter()
            .enumerate()
            .map(|(i, v)| py_to_json(v, &format!("{path}[{i}]"), depth + 1))
            .collect::<PyResult<Vec<_>>>()
            .map(Value::Array)
    };
    if let Ok(l) = x.cast::<PyList>() {
        return seq(l.iter().collect());
    }
    if let Ok(t) = x.cast::<PyTuple>() {
        return seq(t.iter().collect());
    }
    if x.hasattr("tolist")? {
        return py_to_json(&x.call_method0("tolist")?, path, depth);
    }
    Err(err(format!(
        "{path}: cannot be written as JSON (a {})",
        x.get_type().name()?
    )))
}

/// Checks `tol` against the command line's range.
fn check_tol(tol: f64) -> PyResult<()> {
    if (MIN_TOLERANCE..=MAX_TOLERANCE).contains(&tol) {
        Ok(())
    } else {
        Err(err(format!(
            "tol must be in [{MIN_TOLERANCE:e}, {MAX_TOLERANCE}] (the integrator cannot meet a \
             relative tolerance below f64's resolution), got {tol}"
        )))
    }
}

/// Evaluates the chapter's closed-form models (m1–m6, and the closed-loop
/// `unicycle_control` schema) on a case document, as `moma eval CASES.json --tol TOL`:
/// the same document with every case's `outputs` (and `trajectory`, `control`, … where the
/// case asks for them) filled in; every other field is kept.
///
/// `doc` is the path of a JSON case file or the document itself (a dict, as `json.load`
/// gives). `tol` is the integration tolerance (rtol = atol) of trajectories, in
/// [1e-15, 0.1]. The GIL is released while the cases run.
///
/// Raises MomaError naming the file (for a path), the case id and the field at fault.
#[pyfunction]
#[pyo3(signature = (doc, tol = DEFAULT_TOLERANCE))]
fn eval_cases<'py>(
    py: Python<'py>,
    doc: &Bound<'py, PyAny>,
    tol: f64,
) -> PyResult<Bound<'py, PyAny>> {
    check_tol(tol)?;
    let out = if doc.is_instance_of::<PyDict>() {
        let v = py_to_json(doc, "doc", 0)?;
        py.detach(|| evaluate_document(&v, tol)).map_err(err)?
    } else {
        let path: PathBuf = doc.extract().map_err(|_| {
            err("doc: expected the path of a case file or a dict (the parsed document)")
        })?;
        py.detach(|| -> Result<Value, String> {
            let text = std::fs::read_to_string(&path)
                .map_err(|e| format!("{}: cannot read case file: {e}", path.display()))?;
            let v: Value = serde_json::from_str(&text)
                .map_err(|e| format!("{}: malformed JSON: {e}", path.display()))?;
            evaluate_document(&v, tol).map_err(|e| format!("{}: {e}", path.display()))
        })
        .map_err(err)?
    };
    json_to_py(py, &out)
}

/// One case of one chapter model: `model` is a canonical name (`m1_unicycle`,
/// `m2_platform_planar_arm`, `m3_diffdrive_kinematics`, `m4_cart_two_link`,
/// `m5_mobile_manipulator_3d`, `m6_space_manipulator`) or an alias (`m1` … `m6`); `case`
/// a dict with `params`, `state`, `inputs` and optionally `trajectory.t` (the schema of
/// the case files). Returns the case with `outputs` (and `trajectory`, …) filled in,
/// exactly as `eval_cases` fills it inside a document.
///
/// Raises MomaError for an unknown model or a bad case (naming the case id and field).
#[pyfunction]
#[pyo3(signature = (model, case, tol = DEFAULT_TOLERANCE))]
fn eval_case<'py>(
    py: Python<'py>,
    model: &str,
    case: &Bound<'py, PyAny>,
    tol: f64,
) -> PyResult<Bound<'py, PyAny>> {
    check_tol(tol)?;
    let v = py_to_json(case, "case", 0)?;
    let out = if model == UNICYCLE_CONTROL {
        let doc = serde_json::json!({ "model": model, "cases": [v] });
        let mut d = py.detach(|| evaluate_document(&doc, tol)).map_err(err)?;
        d["cases"][0].take()
    } else {
        let m = ChapterModel::from_name(model).map_err(err)?;
        py.detach(|| evaluate_case(m, &v, 0, tol)).map_err(err)?
    };
    json_to_py(py, &out)
}

/// The chapter models' canonical names (as in the case files), with `unicycle_control`.
#[pyfunction]
fn chapter_models() -> Vec<&'static str> {
    MODEL_NAMES
        .iter()
        .map(|(c, _, _)| *c)
        .chain([UNICYCLE_CONTROL])
        .collect()
}

/// Registers the functions.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(eval_cases, m)?)?;
    m.add_function(wrap_pyfunction!(eval_case, m)?)?;
    m.add_function(wrap_pyfunction!(chapter_models, m)?)?;
    Ok(())
}

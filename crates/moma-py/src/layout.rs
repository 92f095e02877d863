//! Pinocchio interop: `moma.to_pinocchio` and `moma.from_pinocchio` (the library's
//! `io::pinocchio_layout`).

use crate::err;
use crate::model::{PyModel, Vec1, check_state, vector};
use moma::Error;
use moma::io::pinocchio_layout::PinocchioLayout;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::PyDict;

fn need_v(src: &str, a: bool, v: bool) -> PyResult<()> {
    if a && !v {
        return Err(err(format!(
            "{src}: converting a needs v (the acceleration picks up the base's rotation rate)"
        )));
    }
    Ok(())
}

/// moma's state in Pinocchio's layout: a dict with `q` (Pinocchio's nq: planar base
/// `[x, y, cos θ, sin θ]`, continuous joints as cos/sin pairs) and, for those given,
/// `v` and `tau` (base-frame velocity / force: `T x`) and `a` (`T (a − ω S v)`, needs v).
/// Every input is in moma's layout; the others coordinates are copied.
#[pyfunction]
#[pyo3(signature = (model, q, v = None, a = None, tau = None))]
fn to_pinocchio<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    q: Vec1<'py>,
    v: Option<Vec1<'py>>,
    a: Option<Vec1<'py>>,
    tau: Option<Vec1<'py>>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = &model.inner;
    let src = "to_pinocchio";
    need_v(src, a.is_some(), v.is_some())?;
    let lay = PinocchioLayout::new(m);
    let qm = vector(src, "q", q.as_array(), m.nq)?;
    let vm = v
        .map(|x| vector(src, "v", x.as_array(), m.nv))
        .transpose()?;
    let am = a
        .map(|x| vector(src, "a", x.as_array(), m.nv))
        .transpose()?;
    let tm = tau
        .map(|x| vector(src, "tau", x.as_array(), m.nv))
        .transpose()?;
    check_state(
        m,
        || src.into(),
        qm.as_slice(),
        vm.as_ref().map(|x| x.as_slice()),
        am.as_ref().map(|x| x.as_slice()),
        tm.as_ref().map(|x| x.as_slice()),
    )?;
    let d = PyDict::new(py);
    let mut qp = vec![0.0; lay.nq()];
    lay.q_to_pinocchio(qm.as_slice(), &mut qp);
    d.set_item("q", PyArray1::from_vec(py, qp))?;
    let mut out = vec![0.0; m.nv];
    if let Some(vm) = &vm {
        lay.v_to_pinocchio(qm.as_slice(), vm.as_slice(), &mut out);
        d.set_item("v", PyArray1::from_slice(py, &out))?;
        if let Some(am) = &am {
            lay.a_to_pinocchio(qm.as_slice(), vm.as_slice(), am.as_slice(), &mut out);
            d.set_item("a", PyArray1::from_slice(py, &out))?;
        }
    }
    if let Some(tm) = &tm {
        lay.tau_to_pinocchio(qm.as_slice(), tm.as_slice(), &mut out);
        d.set_item("tau", PyArray1::from_slice(py, &out))?;
    }
    Ok(d)
}

/// A Pinocchio state in moma's layout: the inverse of `to_pinocchio`. Inputs are in
/// Pinocchio's layout (`q` of Pinocchio's nq, its cos/sin pairs unit); the dict holds
/// `q` (moma's nq) and the converted `v`, `a` (needs v) and `tau` that were given.
#[pyfunction]
#[pyo3(signature = (model, q, v = None, a = None, tau = None))]
fn from_pinocchio<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    q: Vec1<'py>,
    v: Option<Vec1<'py>>,
    a: Option<Vec1<'py>>,
    tau: Option<Vec1<'py>>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = &model.inner;
    let src = "from_pinocchio";
    need_v(src, a.is_some(), v.is_some())?;
    let lay = PinocchioLayout::new(m);
    let qp: Vec<f64> = q.as_array().iter().copied().collect();
    let mut qm = vec![0.0; m.nq];
    lay.q_from_pinocchio(&qp, &mut qm)
        .map_err(|e| err(format!("{src}: {e}")))?;
    let vp = v
        .map(|x| vector(src, "v", x.as_array(), m.nv))
        .transpose()?;
    let ap = a
        .map(|x| vector(src, "a", x.as_array(), m.nv))
        .transpose()?;
    let tp = tau
        .map(|x| vector(src, "tau", x.as_array(), m.nv))
        .transpose()?;
    for (name, x) in [("v", &vp), ("a", &ap), ("tau", &tp)] {
        if let Some(x) = x
            && let Some(k) = x.iter().position(|y| !y.is_finite())
        {
            return Err(err(Error::NonFinite {
                field: format!("{src} {name}[{k}]"),
            }));
        }
    }
    let d = PyDict::new(py);
    let mut vm = vec![0.0; m.nv];
    let mut out = vec![0.0; m.nv];
    if let Some(vp) = &vp {
        lay.v_from_pinocchio(&qm, vp.as_slice(), &mut vm);
        d.set_item("v", PyArray1::from_slice(py, &vm))?;
        if let Some(ap) = &ap {
            lay.a_from_pinocchio(&qm, &vm, ap.as_slice(), &mut out);
            d.set_item("a", PyArray1::from_slice(py, &out))?;
        }
    }
    if let Some(tp) = &tp {
        lay.tau_from_pinocchio(&qm, tp.as_slice(), &mut out);
        d.set_item("tau", PyArray1::from_slice(py, &out))?;
    }
    d.set_item("q", PyArray1::from_vec(py, qm))?;
    Ok(d)
}

/// Registers the functions.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(to_pinocchio, m)?)?;
    m.add_function(wrap_pyfunction!(from_pinocchio, m)?)?;
    Ok(())
}

//! Pinocchio interop: `moma.to_pinocchio` and `moma.from_pinocchio` (the library's
//! `io::pinocchio_layout`), one implementation for both directions.

use crate::err;
use crate::model::{Mat2, PyModel, Vec1, check_state, vector};
use moma::Error;
use moma::io::pinocchio_layout::PinocchioLayout;
use nalgebra::DMatrix;
use numpy::{PyArray1, ToPyArray};
use pyo3::prelude::*;
use pyo3::types::PyDict;

/// The direction of a conversion.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Dir {
    /// moma's layout into Pinocchio's.
    To,
    /// Pinocchio's layout into moma's.
    From,
}

impl Dir {
    fn src(self) -> &'static str {
        match self {
            Dir::To => "to_pinocchio",
            Dir::From => "from_pinocchio",
        }
    }
}

/// The inputs of one conversion, each in the source layout.
struct Inputs<'py> {
    q: Vec1<'py>,
    v: Option<Vec1<'py>>,
    a: Option<Vec1<'py>>,
    tau: Option<Vec1<'py>>,
    mass_matrix: Option<Mat2<'py>>,
    jacobian: Option<Mat2<'py>>,
}

/// A matrix input of `rows` × nv (`rows` = None: any number of rows), finite.
fn matrix(
    src: &str,
    name: &str,
    x: Option<&Mat2<'_>>,
    rows: Option<usize>,
    nv: usize,
) -> PyResult<Option<DMatrix<f64>>> {
    let Some(x) = x else { return Ok(None) };
    let x = x.as_array();
    let (r, c) = x.dim();
    if c != nv || rows.is_some_and(|n| n != r) {
        let want = rows.map_or_else(|| "(m, nv)".to_string(), |n| format!("({n}, {nv})"));
        return Err(err(format!(
            "{src} {name}: expected shape {want} with nv = {nv}, got ({r}, {c})"
        )));
    }
    if let Some(k) = x.iter().position(|y| !y.is_finite()) {
        return Err(err(Error::NonFinite {
            field: format!("{src} {name}[{}, {}]", k / c, k % c),
        }));
    }
    Ok(Some(DMatrix::from_fn(r, c, |i, j| x[(i, j)])))
}

/// One conversion in direction `dir`; the dict holds `q` and every other given input,
/// converted.
fn convert<'py>(
    py: Python<'py>,
    m: &moma::multibody::Model,
    dir: Dir,
    x: Inputs<'py>,
) -> PyResult<Bound<'py, PyDict>> {
    let src = dir.src();
    if x.a.is_some() && x.v.is_none() {
        return Err(err(format!(
            "{src}: converting a needs v (the acceleration picks up the base's rotation rate)"
        )));
    }
    let lay = PinocchioLayout::new(m);
    let nv = m.nv;
    let read = |name: &str, y: &Option<Vec1<'py>>| {
        y.as_ref()
            .map(|y| vector(src, name, y.as_array(), nv))
            .transpose()
    };
    let (v_in, a_in, tau_in) = (read("v", &x.v)?, read("a", &x.a)?, read("tau", &x.tau)?);
    // moma's q (the conversions are evaluated at it) and the output q.
    let (qm, q_out) = match dir {
        Dir::To => {
            let qm = vector(src, "q", x.q.as_array(), m.nq)?;
            check_state(
                m,
                || src.into(),
                qm.as_slice(),
                v_in.as_ref().map(|y| y.as_slice()),
                a_in.as_ref().map(|y| y.as_slice()),
                tau_in.as_ref().map(|y| y.as_slice()),
            )?;
            let mut qp = vec![0.0; lay.nq()];
            lay.q_to_pinocchio(qm.as_slice(), &mut qp);
            (qm.as_slice().to_vec(), qp)
        }
        Dir::From => {
            let qp: Vec<f64> = x.q.as_array().iter().copied().collect();
            let mut qm = vec![0.0; m.nq];
            lay.q_from_pinocchio(&qp, &mut qm)
                .map_err(|e| err(format!("{src}: {e}")))?;
            for (name, y) in [("v", &v_in), ("a", &a_in), ("tau", &tau_in)] {
                if let Some(y) = y
                    && let Some(k) = y.iter().position(|z| !z.is_finite())
                {
                    return Err(err(Error::NonFinite {
                        field: format!("{src} {name}[{k}]"),
                    }));
                }
            }
            (qm.clone(), qm)
        }
    };
    let mass = matrix(src, "mass_matrix", x.mass_matrix.as_ref(), Some(nv), nv)?;
    let jac = matrix(src, "jacobian", x.jacobian.as_ref(), None, nv)?;
    let d = PyDict::new(py);
    d.set_item("q", PyArray1::from_vec(py, q_out))?;
    if let Some(vi) = &v_in {
        let mut vo = vec![0.0; nv];
        match dir {
            Dir::To => lay.v_to_pinocchio(&qm, vi.as_slice(), &mut vo),
            Dir::From => lay.v_from_pinocchio(&qm, vi.as_slice(), &mut vo),
        }
        if let Some(ai) = &a_in {
            let mut ao = vec![0.0; nv];
            match dir {
                Dir::To => lay.a_to_pinocchio(&qm, vi.as_slice(), ai.as_slice(), &mut ao),
                Dir::From => lay.a_from_pinocchio(&qm, &vo, ai.as_slice(), &mut ao),
            }
            d.set_item("a", PyArray1::from_vec(py, ao))?;
        }
        d.set_item("v", PyArray1::from_vec(py, vo))?;
    }
    if let Some(ti) = &tau_in {
        let mut to = vec![0.0; nv];
        match dir {
            Dir::To => lay.tau_to_pinocchio(&qm, ti.as_slice(), &mut to),
            Dir::From => lay.tau_from_pinocchio(&qm, ti.as_slice(), &mut to),
        }
        d.set_item("tau", PyArray1::from_vec(py, to))?;
    }
    if let Some(h) = &mass {
        let mut out = DMatrix::zeros(nv, nv);
        match dir {
            Dir::To => lay.matrix_to_pinocchio(&qm, h, &mut out),
            Dir::From => lay.matrix_from_pinocchio(&qm, h, &mut out),
        }
        d.set_item("mass_matrix", out.to_pyarray(py))?;
    }
    if let Some(j) = &jac {
        let mut out = DMatrix::zeros(j.nrows(), nv);
        match dir {
            Dir::To => lay.jacobian_to_pinocchio(&qm, j, &mut out),
            Dir::From => lay.jacobian_from_pinocchio(&qm, j, &mut out),
        }
        d.set_item("jacobian", out.to_pyarray(py))?;
    }
    Ok(d)
}

/// moma's state in Pinocchio's layout: a dict with `q` (Pinocchio's nq: planar base
/// `[x, y, cos θ, sin θ]`, continuous joints as cos/sin pairs) and, for those given,
/// `v` and `tau` (base-frame velocity / force: `T x`), `a` (`T (a − ω S v)`, needs v),
/// `mass_matrix` (nv × nv, by congruence: `T H Tᵀ`) and `jacobian` (m × nv, by its
/// columns: `J Tᵀ`). Every input is in moma's layout; the other coordinates are copied.
#[pyfunction]
#[pyo3(signature = (model, q, v = None, a = None, tau = None, *, mass_matrix = None, jacobian = None))]
#[allow(clippy::too_many_arguments)]
fn to_pinocchio<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    q: Vec1<'py>,
    v: Option<Vec1<'py>>,
    a: Option<Vec1<'py>>,
    tau: Option<Vec1<'py>>,
    mass_matrix: Option<Mat2<'py>>,
    jacobian: Option<Mat2<'py>>,
) -> PyResult<Bound<'py, PyDict>> {
    let x = Inputs {
        q,
        v,
        a,
        tau,
        mass_matrix,
        jacobian,
    };
    convert(py, &model.inner, Dir::To, x)
}

/// A Pinocchio state in moma's layout: the inverse of `to_pinocchio`. Inputs are in
/// Pinocchio's layout (`q` of Pinocchio's nq, its cos/sin pairs unit); the dict holds
/// `q` (moma's nq) and the converted `v`, `a` (needs v), `tau`, `mass_matrix`
/// (`Tᵀ H_P T`) and `jacobian` (`J_P T`) that were given.
#[pyfunction]
#[pyo3(signature = (model, q, v = None, a = None, tau = None, *, mass_matrix = None, jacobian = None))]
#[allow(clippy::too_many_arguments)]
fn from_pinocchio<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    q: Vec1<'py>,
    v: Option<Vec1<'py>>,
    a: Option<Vec1<'py>>,
    tau: Option<Vec1<'py>>,
    mass_matrix: Option<Mat2<'py>>,
    jacobian: Option<Mat2<'py>>,
) -> PyResult<Bound<'py, PyDict>> {
    let x = Inputs {
        q,
        v,
        a,
        tau,
        mass_matrix,
        jacobian,
    };
    convert(py, &model.inner, Dir::From, x)
}

/// Registers the functions.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(to_pinocchio, m)?)?;
    m.add_function(wrap_pyfunction!(from_pinocchio, m)?)?;
    Ok(())
}

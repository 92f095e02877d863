//! `moma.Model` and `moma.Data`, and the array readers every function uses.

use crate::err;
use moma::Error;
use moma::io::urdf::{model_from_urdf_file, model_from_urdf_str};
use moma::multibody::{Data, FrameIndex, Model, RootJoint, neutral};
use nalgebra::{DVector, Matrix6xX};
use numpy::ndarray::{ArrayView1, ArrayView2};
use numpy::{
    AllowTypeChange, IxDyn, PyArray1, PyArray2, PyArrayDyn, PyArrayLike1, PyArrayLike2,
    PyArrayMethods, ToPyArray,
};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::atomic::{AtomicU64, Ordering};

/// A 1-D input: anything numpy converts to a float64 vector.
pub(crate) type Vec1<'py> = PyArrayLike1<'py, f64, AllowTypeChange>;
/// A 2-D input: anything numpy converts to a float64 matrix (one state per row).
pub(crate) type Mat2<'py> = PyArrayLike2<'py, f64, AllowTypeChange>;

static NEXT_MODEL_ID: AtomicU64 = AtomicU64::new(1);

/// A robot model: the immutable kinematic tree with inertias, frames, limits and
/// gravity (moma's `multibody::Model`).
///
/// State layout: `q` has `nq` entries, `v`, `a` and `tau` have `nv`. The planar root is
/// `[x, y, θ]`, the free flyer `[x, y, z, qx, qy, qz, qw]` with the base twist in the
/// base frame (as Pinocchio), a continuous joint one angle.
#[pyclass(module = "moma", name = "Model", frozen)]
pub struct PyModel {
    pub(crate) inner: Model,
    pub(crate) id: u64,
}

impl PyModel {
    fn wrap(inner: Model) -> Self {
        Self {
            inner,
            id: NEXT_MODEL_ID.fetch_add(1, Ordering::Relaxed),
        }
    }

    /// The frame called `name`.
    pub(crate) fn frame(&self, name: &str) -> PyResult<FrameIndex> {
        self.inner.frame_id(name).map_err(err)
    }

    /// Checks that `data` was created by this model.
    pub(crate) fn check_data(&self, data: &PyData) -> PyResult<()> {
        if data.model_id == self.id {
            Ok(())
        } else {
            Err(err(format!(
                "data was created by another model (use model.create_data() of model '{}')",
                self.inner.name
            )))
        }
    }
}

fn parse_root(root: &str) -> PyResult<RootJoint> {
    root.parse::<RootJoint>().map_err(err)
}

#[pymethods]
impl PyModel {
    /// Loads a URDF file. `root` is "fixed" (an arm), "planar" (a mobile base: x, y, θ)
    /// or "free-flyer" (a floating base).
    ///
    /// Raises MomaError naming the file, link or joint at fault.
    #[staticmethod]
    #[pyo3(signature = (path, root = "fixed"))]
    fn from_urdf(py: Python<'_>, path: PathBuf, root: &str) -> PyResult<Self> {
        let root = parse_root(root)?;
        let model = py
            .detach(|| model_from_urdf_file(&path, root))
            .map_err(err)?;
        Ok(Self::wrap(model))
    }

    /// Builds a model from URDF text; `source` names it in error messages.
    #[staticmethod]
    #[pyo3(signature = (text, root = "fixed", source = "<string>"))]
    fn from_urdf_string(text: &str, root: &str, source: &str) -> PyResult<Self> {
        let root = parse_root(root)?;
        Ok(Self::wrap(
            model_from_urdf_str(text, root, source).map_err(err)?,
        ))
    }

    /// A new workspace for this model's algorithms.
    fn create_data(&self) -> PyData {
        PyData::new(self)
    }

    /// Robot name.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }

    /// The root joint: "fixed", "planar" or "free-flyer".
    #[getter]
    fn root(&self) -> String {
        self.inner.root.to_string()
    }

    /// Number of configuration coordinates.
    #[getter]
    fn nq(&self) -> usize {
        self.inner.nq
    }

    /// Number of velocity coordinates.
    #[getter]
    fn nv(&self) -> usize {
        self.inner.nv
    }

    /// Number of joints, the universe (joint 0) included.
    #[getter]
    fn njoints(&self) -> usize {
        self.inner.njoints
    }

    /// Joint names in state order (joint 0 is the universe).
    #[getter]
    fn joint_names(&self) -> Vec<String> {
        self.inner.names.clone()
    }

    /// Frame names (bodies, joints, fixed links).
    #[getter]
    fn frame_names(&self) -> Vec<String> {
        self.inner.frames.iter().map(|f| f.name.clone()).collect()
    }

    /// Gravity (m/s², world axes).
    #[getter]
    fn gravity<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.gravity.as_slice())
    }

    /// Lower position limits (nq).
    #[getter]
    fn lower_position_limit<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.lower_position_limit.as_slice())
    }

    /// Upper position limits (nq).
    #[getter]
    fn upper_position_limit<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.upper_position_limit.as_slice())
    }

    /// The neutral configuration (zero angles, identity base).
    fn neutral<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, neutral(&self.inner).as_slice())
    }

    fn __repr__(&self) -> String {
        format!(
            "moma.Model(name='{}', root='{}', nq={}, nv={})",
            self.inner.name, self.inner.root, self.inner.nq, self.inner.nv
        )
    }
}

/// The workspace of a Model's algorithms (moma's `multibody::Data`): create it once with
/// `model.create_data()` and pass it to every call on that model.
#[pyclass(module = "moma", name = "Data")]
pub struct PyData {
    pub(crate) inner: Data,
    pub(crate) model_id: u64,
    pub(crate) q: DVector<f64>,
    pub(crate) v: DVector<f64>,
    pub(crate) a: DVector<f64>,
    pub(crate) jac: Matrix6xX<f64>,
    /// The workspace of `rnea_derivatives` / `aba_derivatives`, made on their first call.
    pub(crate) derivatives: Option<Box<moma::dynamics::DerivativeData>>,
}

impl PyData {
    fn new(model: &PyModel) -> Self {
        let m = &model.inner;
        Self {
            inner: Data::new(m),
            model_id: model.id,
            q: DVector::zeros(m.nq),
            v: DVector::zeros(m.nv),
            a: DVector::zeros(m.nv),
            jac: Matrix6xX::zeros(m.nv),
            derivatives: None,
        }
    }
}

#[pymethods]
impl PyData {
    /// The joint torques of the last `rnea` (nv).
    #[getter]
    fn tau<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.tau.as_slice())
    }

    /// The accelerations of the last `aba` (nv).
    #[getter]
    fn ddq<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        PyArray1::from_slice(py, self.inner.ddq.as_slice())
    }

    /// The joint-space inertia matrix of the last `crba` (nv × nv).
    #[getter]
    fn mass_matrix<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        self.inner.mass_matrix.to_pyarray(py)
    }
}

/// Copies a 1-D input of the expected length into `out`.
pub(crate) fn load(
    src: &str,
    name: &str,
    x: ArrayView1<'_, f64>,
    out: &mut DVector<f64>,
) -> PyResult<()> {
    if x.len() != out.len() {
        return Err(err(Error::WrongLength {
            field: format!("{src} {name}"),
            expected: out.len(),
            got: x.len(),
        }));
    }
    for (o, v) in out.iter_mut().zip(x.iter()) {
        *o = *v;
    }
    Ok(())
}

/// A 1-D input of the expected length as a new vector.
pub(crate) fn vector(
    src: &str,
    name: &str,
    x: ArrayView1<'_, f64>,
    n: usize,
) -> PyResult<DVector<f64>> {
    let mut out = DVector::zeros(n);
    load(src, name, x, &mut out)?;
    Ok(out)
}

/// Checks a batch input's shape `(n, width)` (n = `rows` when given) and returns n.
pub(crate) fn batch_rows(
    src: &str,
    name: &str,
    x: &ArrayView2<'_, f64>,
    width: usize,
    rows: Option<usize>,
) -> PyResult<usize> {
    let (n, w) = x.dim();
    if w != width {
        return Err(err(format!(
            "{src} {name}: expected shape (n, {width}), got ({n}, {w})"
        )));
    }
    if let Some(r) = rows
        && r != n
    {
        return Err(err(format!(
            "{src} {name}: expected {r} rows (as q), got {n}"
        )));
    }
    Ok(n)
}

/// Row `k` of a batch input into `out` (shapes checked by [`batch_rows`]): one slice copy
/// for a C-contiguous array, element by element otherwise.
pub(crate) fn load_row(x: &ArrayView2<'_, f64>, k: usize, out: &mut DVector<f64>) {
    let w = out.len();
    match x.as_slice() {
        Some(s) => out.as_mut_slice().copy_from_slice(&s[k * w..(k + 1) * w]),
        None => {
            for (o, v) in out.iter_mut().zip(x.row(k).iter()) {
                *o = *v;
            }
        }
    }
}

/// Registers the classes.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyModel>()?;
    m.add_class::<PyData>()?;
    Ok(())
}

/// The library's state check (finite values, unit base quaternion) with its message,
/// without formatting anything on the common path; `src` names the call in errors.
pub(crate) fn check_state(
    m: &Model,
    src: impl FnOnce() -> String,
    q: &[f64],
    v: Option<&[f64]>,
    a: Option<&[f64]>,
    tau: Option<&[f64]>,
) -> PyResult<()> {
    let finite = q
        .iter()
        .chain(v.unwrap_or(&[]))
        .chain(a.unwrap_or(&[]))
        .chain(tau.unwrap_or(&[]))
        .all(|x| x.is_finite());
    if finite && m.root != RootJoint::FreeFlyer {
        return Ok(());
    }
    moma::kinematics::check_state(m, &src(), Some(q), v, a, tau).map_err(err)
}

/// One worker's buffers for the batch forms.
pub(crate) struct Scratch {
    pub(crate) data: Data,
    pub(crate) q: DVector<f64>,
    pub(crate) v: DVector<f64>,
    pub(crate) a: DVector<f64>,
    pub(crate) jac: Matrix6xX<f64>,
}

impl Scratch {
    pub(crate) fn new(m: &Model) -> Self {
        Self {
            data: Data::new(m),
            q: DVector::zeros(m.nq),
            v: DVector::zeros(m.nv),
            a: DVector::zeros(m.nv),
            jac: Matrix6xX::zeros(m.nv),
        }
    }
}

/// States per parallel task of the batch forms.
const CHUNK: usize = 64;

/// Evaluates `f(scratch, k, out_row)` for every row `k` of the row-major `out` (rows of
/// `width`), in place: on one thread with one [`Scratch`] when the batch is small or the
/// pool has one thread, else on all cores (rayon, tasks of [`CHUNK`] rows, one
/// [`Scratch`] per worker split). Each row depends only on its own inputs, so the result
/// does not depend on the thread count.
pub(crate) fn par_rows(
    m: &Model,
    width: usize,
    out: &mut [f64],
    f: impl Fn(&mut Scratch, usize, &mut [f64]) + Sync,
) {
    use rayon::prelude::*;
    if width == 0 {
        return;
    }
    let n = out.len() / width;
    if n <= CHUNK || rayon::current_num_threads() == 1 {
        let mut s = Scratch::new(m);
        for (k, row) in out.chunks_mut(width).enumerate() {
            f(&mut s, k, row);
        }
        return;
    }
    out.par_chunks_mut(width * CHUNK).enumerate().for_each_init(
        || Scratch::new(m),
        |s, (c, block)| {
            for (j, row) in block.chunks_mut(width).enumerate() {
                f(s, c * CHUNK + j, row);
            }
        },
    );
}

/// The state inputs of a batch form, one state per row: `q` (n, nq) and, when given, `v`
/// and a second velocity-sized input (`a`, or `tau` when `second_is_tau`), both (n, nv).
/// Rows fill a [`Scratch`]'s `q`, `v` and `a`; an input not given stays zero there.
pub(crate) struct BatchInputs<'a> {
    pub(crate) src: &'static str,
    pub(crate) q: ArrayView2<'a, f64>,
    pub(crate) v: Option<ArrayView2<'a, f64>>,
    pub(crate) a: Option<ArrayView2<'a, f64>>,
    pub(crate) second_is_tau: bool,
}

impl BatchInputs<'_> {
    /// Checks the shapes and returns the number of states.
    pub(crate) fn rows(&self, m: &Model) -> PyResult<usize> {
        let n = batch_rows(self.src, "q", &self.q, m.nq, None)?;
        if let Some(x) = &self.v {
            batch_rows(self.src, "v", x, m.nv, Some(n))?;
        }
        if let Some(x) = &self.a {
            let name = if self.second_is_tau { "tau" } else { "a" };
            batch_rows(self.src, name, x, m.nv, Some(n))?;
        }
        Ok(n)
    }

    /// The library's state check on every row (the error names the first bad row).
    pub(crate) fn check(&self, m: &Model, n: usize) -> PyResult<()> {
        let (a, tau) = if self.second_is_tau {
            (None, self.a.as_ref())
        } else {
            (self.a.as_ref(), None)
        };
        check_rows(m, self.src, n, &self.q, self.v.as_ref(), a, tau)
    }

    /// Row `k` into `s.q`, `s.v` and `s.a`.
    pub(crate) fn load(&self, k: usize, s: &mut Scratch) {
        load_row(&self.q, k, &mut s.q);
        if let Some(x) = &self.v {
            load_row(x, k, &mut s.v);
        }
        if let Some(x) = &self.a {
            load_row(x, k, &mut s.a);
        }
    }
}

/// The one shape of the batch forms: checks `data` and the inputs' shapes, makes the
/// output array `(n, *row_shape)`, then, with the GIL released, checks every row and
/// evaluates `f(scratch, out_row)` on each (after loading the row into the scratch)
/// straight into the array, on all cores ([`par_rows`]).
pub(crate) fn run_batch<'py>(
    py: Python<'py>,
    model: &PyModel,
    data: &PyData,
    inputs: &BatchInputs<'_>,
    row_shape: &[usize],
    f: impl Fn(&mut Scratch, &mut [f64]) + Sync,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let m = &model.inner;
    model.check_data(data)?;
    let n = inputs.rows(m)?;
    let mut shape = Vec::with_capacity(row_shape.len() + 1);
    shape.push(n);
    shape.extend_from_slice(row_shape);
    let width = row_shape.iter().product();
    let out = PyArrayDyn::<f64>::zeros(py, IxDyn(&shape), false);
    {
        let mut rw = out.readwrite();
        let buf = rw.as_slice_mut().map_err(err)?;
        py.detach(|| -> PyResult<()> {
            inputs.check(m, n)?;
            par_rows(m, width, buf, |s, k, row| {
                inputs.load(k, s);
                f(s, row);
            });
            Ok(())
        })?;
    }
    Ok(out)
}

/// True when every value of `x` is finite. On a contiguous array, blocks of 64 values
/// are tested without an early exit inside the block, so the test is vectorised (it is
/// a serial pass before the parallel one: at 1 ns a value it cost about a tenth of a
/// Panda RNEA per state).
fn all_finite(x: &ArrayView2<'_, f64>) -> bool {
    match x.as_slice_memory_order() {
        Some(s) => slice_finite(s),
        None => x.iter().all(|y| y.is_finite()),
    }
}

/// Whether every value of `s` is finite (chunks without early exit, which vectorise).
pub(crate) fn slice_finite(s: &[f64]) -> bool {
    s.chunks(64)
        .all(|c| c.iter().fold(true, |ok, y| ok & y.is_finite()))
}

/// Checks every row of a batch (finite values, unit base quaternion) before the parallel
/// pass, so the error names the first bad row. Without a free-flyer root, one pass over
/// the arrays proves them finite and the per-row check runs only to name a bad row.
pub(crate) fn check_rows(
    m: &Model,
    src: &str,
    n: usize,
    q: &ArrayView2<'_, f64>,
    v: Option<&ArrayView2<'_, f64>>,
    a: Option<&ArrayView2<'_, f64>>,
    tau: Option<&ArrayView2<'_, f64>>,
) -> PyResult<()> {
    let finite = |x: Option<&ArrayView2<'_, f64>>| x.is_none_or(all_finite);
    if m.root != RootJoint::FreeFlyer && finite(Some(q)) && finite(v) && finite(a) && finite(tau) {
        return Ok(());
    }
    let mut s = (
        DVector::zeros(m.nq),
        DVector::zeros(m.nv),
        DVector::zeros(m.nv),
        DVector::zeros(m.nv),
    );
    for k in 0..n {
        load_row(q, k, &mut s.0);
        if let Some(x) = v {
            load_row(x, k, &mut s.1);
        }
        if let Some(x) = a {
            load_row(x, k, &mut s.2);
        }
        if let Some(x) = tau {
            load_row(x, k, &mut s.3);
        }
        check_state(
            m,
            || format!("{src} row {k}"),
            s.0.as_slice(),
            v.map(|_| s.1.as_slice()),
            a.map(|_| s.2.as_slice()),
            tau.map(|_| s.3.as_slice()),
        )?;
    }
    Ok(())
}

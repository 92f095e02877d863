//! Rigid-body algorithms: RNEA, CRBA, ABA, their derivatives, frame Jacobians, one state
//! or a batch.

use crate::model::{BatchInputs, Mat2, PyData, PyModel, Vec1, check_state, load, run_batch};
use moma::dynamics;
use moma::kinematics::{self, ReferenceFrame};
use numpy::{PyArray1, PyArray2, PyArrayDyn, PyArrayMethods, PyUntypedArrayMethods, ToPyArray};
use pyo3::prelude::*;

/// Inverse dynamics (recursive Newton-Euler): the joint torques
/// `tau = M(q) a + C(q, v) v + g(q)` (nv), also left in `data.tau`.
///
/// Raises MomaError on a wrong length, a non-finite value or another model's data.
#[pyfunction]
pub(crate) fn rnea<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: Vec1<'py>,
    v: Vec1<'py>,
    a: Vec1<'py>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let m = &model.inner;
    model.check_data(&data)?;
    let d = &mut *data;
    load("rnea", "q", q.as_array(), &mut d.q)?;
    load("rnea", "v", v.as_array(), &mut d.v)?;
    load("rnea", "a", a.as_array(), &mut d.a)?;
    check_state(
        m,
        || "rnea".into(),
        d.q.as_slice(),
        Some(d.v.as_slice()),
        Some(d.a.as_slice()),
        None,
    )?;
    let tau = dynamics::rnea(m, &mut d.inner, &d.q, &d.v, &d.a);
    Ok(PyArray1::from_slice(py, tau.as_slice()))
}

/// The joint-space inertia matrix M(q) (nv × nv, composite rigid-body algorithm), also
/// left in `data.mass_matrix`.
#[pyfunction]
pub(crate) fn crba<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: Vec1<'py>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let m = &model.inner;
    model.check_data(&data)?;
    let d = &mut *data;
    load("crba", "q", q.as_array(), &mut d.q)?;
    check_state(m, || "crba".into(), d.q.as_slice(), None, None, None)?;
    Ok(dynamics::crba(m, &mut d.inner, &d.q).to_pyarray(py))
}

/// Forward dynamics (articulated-body algorithm): the accelerations
/// `ddq = M(q)⁻¹ (tau − C(q, v) v − g(q))` (nv), also left in `data.ddq`.
#[pyfunction]
pub(crate) fn aba<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: Vec1<'py>,
    v: Vec1<'py>,
    tau: Vec1<'py>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let m = &model.inner;
    model.check_data(&data)?;
    let d = &mut *data;
    load("aba", "q", q.as_array(), &mut d.q)?;
    load("aba", "v", v.as_array(), &mut d.v)?;
    load("aba", "tau", tau.as_array(), &mut d.a)?;
    check_state(
        m,
        || "aba".into(),
        d.q.as_slice(),
        Some(d.v.as_slice()),
        None,
        Some(d.a.as_slice()),
    )?;
    let ddq = dynamics::aba(m, &mut d.inner, &d.q, &d.v, &d.a);
    Ok(PyArray1::from_slice(py, ddq.as_slice()))
}

/// Three nv × nv matrices.
type Matrices3<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
);

/// The analytical derivatives of inverse dynamics tau = RNEA(q, v, a):
/// `(dtau_dq, dtau_dv, dtau_da)`, nv × nv each (`dtau_da` = M(q)); q is perturbed along
/// the tangent `q ⊕ dq` (moma's layout: planar root in world axes).
///
/// Raises MomaError on a wrong length, a non-finite value or another model's data.
#[pyfunction]
pub(crate) fn rnea_derivatives<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: Vec1<'py>,
    v: Vec1<'py>,
    a: Vec1<'py>,
) -> PyResult<Matrices3<'py>> {
    let m = &model.inner;
    model.check_data(&data)?;
    let d = &mut *data;
    let src = "rnea_derivatives";
    load(src, "q", q.as_array(), &mut d.q)?;
    load(src, "v", v.as_array(), &mut d.v)?;
    load(src, "a", a.as_array(), &mut d.a)?;
    check_state(
        m,
        || src.into(),
        d.q.as_slice(),
        Some(d.v.as_slice()),
        Some(d.a.as_slice()),
        None,
    )?;
    let dd = d
        .derivatives
        .get_or_insert_with(|| Box::new(dynamics::DerivativeData::new(m)));
    dynamics::rnea_derivatives(m, dd, &d.q, &d.v, &d.a);
    Ok((
        dd.drnea_dq.to_pyarray(py),
        dd.drnea_dv.to_pyarray(py),
        dd.drnea_da.to_pyarray(py),
    ))
}

/// The analytical derivatives of forward dynamics ddq = ABA(q, v, tau):
/// `(dddq_dq, dddq_dv, dddq_dtau)`, nv × nv each (`dddq_dtau` = M(q)⁻¹).
///
/// Raises MomaError on a wrong length, a non-finite value, another model's data or a
/// mass matrix that is not positive definite.
#[pyfunction]
pub(crate) fn aba_derivatives<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: Vec1<'py>,
    v: Vec1<'py>,
    tau: Vec1<'py>,
) -> PyResult<Matrices3<'py>> {
    let m = &model.inner;
    model.check_data(&data)?;
    let d = &mut *data;
    let src = "aba_derivatives";
    load(src, "q", q.as_array(), &mut d.q)?;
    load(src, "v", v.as_array(), &mut d.v)?;
    load(src, "tau", tau.as_array(), &mut d.a)?;
    check_state(
        m,
        || src.into(),
        d.q.as_slice(),
        Some(d.v.as_slice()),
        None,
        Some(d.a.as_slice()),
    )?;
    let dd = d
        .derivatives
        .get_or_insert_with(|| Box::new(dynamics::DerivativeData::new(m)));
    dynamics::aba_derivatives(m, dd, &d.q, &d.v, &d.a).map_err(crate::err)?;
    Ok((
        dd.daba_dq.to_pyarray(py),
        dd.daba_dv.to_pyarray(py),
        dd.daba_dtau.to_pyarray(py),
    ))
}

/// The Jacobian of frame `frame` (6 × nv, rows `[ṗ; ω]` of the frame origin in world
/// axes: Pinocchio's LOCAL_WORLD_ALIGNED).
#[pyfunction]
pub(crate) fn frame_jacobian<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: Vec1<'py>,
    frame: &str,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let m = &model.inner;
    model.check_data(&data)?;
    let fid = model.frame(frame)?;
    let d = &mut *data;
    load("frame_jacobian", "q", q.as_array(), &mut d.q)?;
    check_state(
        m,
        || "frame_jacobian".into(),
        d.q.as_slice(),
        None,
        None,
        None,
    )?;
    kinematics::frame_jacobian(
        m,
        &mut d.inner,
        &d.q,
        fid,
        ReferenceFrame::LocalWorldAligned,
        &mut d.jac,
    );
    Ok(d.jac.to_pyarray(py))
}

/// `rnea` on every row: q (n, nq), v and a (n, nv) → tau (n, nv). Loops in Rust with
/// the GIL released, on all cores, with the library's multi-state kernel
/// (`moma::dynamics::rnea_batch`, eight states per pass) over each worker's rows, writing
/// straight into the returned array; bit-for-bit the single calls' torques. `out`, when
/// given, is a writeable C-contiguous float64 array of shape (n, nv), distinct from the
/// inputs, that receives the torques and is returned (reusing it across calls saves the
/// allocation and the first touch of fresh pages); after an error it holds NaN.
#[pyfunction]
#[pyo3(signature = (model, data, q, v, a, out = None))]
pub(crate) fn rnea_batch<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    data: PyRef<'py, PyData>,
    q: Mat2<'py>,
    v: Mat2<'py>,
    a: Mat2<'py>,
    out: Option<Bound<'py, PyArrayDyn<f64>>>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let m = &model.inner;
    let inputs = BatchInputs {
        src: "rnea_batch",
        q: q.as_array(),
        v: Some(v.as_array()),
        a: Some(a.as_array()),
        second_is_tau: false,
    };
    model.check_data(&data)?;
    let n = inputs.rows(m)?;
    let given = out.is_some();
    let out = match out {
        Some(o) => {
            if o.shape() != [n, m.nv] {
                return Err(crate::err(format!(
                    "rnea_batch out: expected shape ({n}, {}), got {:?}",
                    m.nv,
                    o.shape()
                )));
            }
            if !o.is_c_contiguous() {
                return Err(crate::err("rnea_batch out: expected a C-contiguous array"));
            }
            o
        }
        None => PyArrayDyn::<f64>::zeros(py, numpy::ndarray::IxDyn(&[n, m.nv]), false),
    };
    {
        let mut rw = out.try_readwrite().map_err(|e| {
            crate::err(format!(
                "rnea_batch out: not writeable, or shares memory with an input ({e})"
            ))
        })?;
        let buf = rw.as_slice_mut().map_err(crate::err)?;
        let result = py.detach(|| -> PyResult<()> {
            // a free-flyer's quaternions are checked row by row first; otherwise each block
            // checks its own rows are finite just before computing them (while they are in
            // cache, and on all cores), and a bad block sends the batch to the row-by-row
            // check, which names the first bad row
            let per_block = m.root != moma::multibody::RootJoint::FreeFlyer;
            if !per_block {
                inputs.check(m, n)?;
            }
            let bad = std::sync::atomic::AtomicBool::new(false);
            // the kernel reads row-major slices: C-contiguous inputs as they are, others
            // copied once (their size is the caller's own array's)
            let (qa, va, aa) = (inputs.q, inputs.v.unwrap(), inputs.a.unwrap());
            let owned = |x: &numpy::ndarray::ArrayView2<'_, f64>| {
                if x.as_slice().is_some() {
                    None
                } else {
                    Some(x.as_standard_layout().into_owned())
                }
            };
            let (qo, vo, ao) = (owned(&qa), owned(&va), owned(&aa));
            let (qs, vs, as_) = (
                rows_slice(&qo, &qa),
                rows_slice(&vo, &va),
                rows_slice(&ao, &aa),
            );
            par_blocks(m, buf, |bd, first, block| {
                let rows = block.len() / m.nv;
                let (q0, v0) = (first * m.nq, first * m.nv);
                let (q, v, a) = (
                    &qs[q0..q0 + rows * m.nq],
                    &vs[v0..v0 + rows * m.nv],
                    &as_[v0..v0 + rows * m.nv],
                );
                if per_block
                    && !(crate::model::slice_finite(q)
                        && crate::model::slice_finite(v)
                        && crate::model::slice_finite(a))
                {
                    bad.store(true, std::sync::atomic::Ordering::Relaxed);
                    return;
                }
                dynamics::rnea_batch(m, bd, q, v, a, block);
            });
            if bad.into_inner() {
                inputs.check(m, n)?;
                return Err(crate::err("rnea_batch: a state has a non-finite value"));
            }
            Ok(())
        });
        if result.is_err() && given {
            buf.fill(f64::NAN);
        }
        result?;
    }
    Ok(out)
}

/// The row-major values of `x`, or of its contiguous copy `o` when it has one.
fn rows_slice<'s>(
    o: &'s Option<numpy::ndarray::Array2<f64>>,
    x: &'s numpy::ndarray::ArrayView2<'_, f64>,
) -> &'s [f64] {
    match o {
        Some(a) => a.as_slice().unwrap_or(&[]),
        None => x.as_slice().unwrap_or(&[]),
    }
}

/// Rows per claim of [`par_blocks`] (a multiple of the kernel's eight lanes): about 10 µs
/// of Panda RNEA, so the thread that takes the last block keeps the other waiting little.
const BLOCK: usize = 64;

/// Batches below this many rows run on the calling thread alone: waking an idle worker
/// can cost a millisecond on a virtual machine, more than such a batch takes.
const PAR_MIN_ROWS: usize = 2048;

/// Counts one block of [`par_blocks`] as finished when dropped, also when `f` unwinds, so
/// the caller's wait for running blocks always ends (the scope then re-raises the panic).
struct Finished<'a>(&'a std::sync::atomic::AtomicUsize);

impl Drop for Finished<'_> {
    fn drop(&mut self) {
        self.0.fetch_add(1, std::sync::atomic::Ordering::Release);
    }
}

/// Runs `f(workspace, first_row, out_rows)` over blocks of [`BLOCK`] rows of the
/// row-major `out` (rows of nv). The calling thread starts on the first block at once
/// and the pool's other workers join as they wake, each claiming the next unclaimed block
/// until none is left, with one workspace per thread; small batches, or a pool of one
/// thread, run on the caller alone. Each row depends only on its own inputs, so the result
/// does not depend on which thread computed it.
fn par_blocks(
    m: &moma::multibody::Model,
    out: &mut [f64],
    f: impl Fn(&mut dynamics::BatchData, usize, &mut [f64]) + Sync,
) {
    use std::sync::Mutex;
    use std::sync::atomic::{AtomicUsize, Ordering};
    if m.nv == 0 || out.is_empty() {
        return;
    }
    let n = out.len() / m.nv;
    let threads = rayon::current_num_threads();
    if n < PAR_MIN_ROWS || threads == 1 {
        f(&mut dynamics::BatchData::new(m), 0, out);
        return;
    }
    let nblocks = n.div_ceil(BLOCK);
    let blocks = Mutex::new(out.chunks_mut(m.nv * BLOCK).enumerate());
    let finished = AtomicUsize::new(0);
    let work = || {
        let mut bd = None;
        loop {
            // a panic in `f` poisons nothing this loop relies on: the iterator is intact
            let next = blocks.lock().unwrap_or_else(|e| e.into_inner()).next();
            let Some((c, block)) = next else { break };
            let _done = Finished(&finished);
            f(
                bd.get_or_insert_with(|| dynamics::BatchData::new(m)),
                c * BLOCK,
                block,
            );
        }
    };
    rayon::in_place_scope(|s| {
        for _ in 1..threads {
            s.spawn(|_| work());
        }
        work();
        // every block is claimed; wait for the ones still running without going to sleep
        // (a sleeping caller is woken late), at most one block's time
        while finished.load(Ordering::Acquire) < nblocks {
            std::hint::spin_loop();
        }
    });
}

/// `aba` on every row: q (n, nq), v and tau (n, nv) → ddq (n, nv), on all cores with the GIL released.
#[pyfunction]
pub(crate) fn aba_batch<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    data: PyRef<'py, PyData>,
    q: Mat2<'py>,
    v: Mat2<'py>,
    tau: Mat2<'py>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let m = &model.inner;
    let inputs = BatchInputs {
        src: "aba_batch",
        q: q.as_array(),
        v: Some(v.as_array()),
        a: Some(tau.as_array()),
        second_is_tau: true,
    };
    run_batch(py, &model, &data, &inputs, &[m.nv], |s, row| {
        row.copy_from_slice(dynamics::aba(m, &mut s.data, &s.q, &s.v, &s.a).as_slice());
    })
}

/// Copies the first `out.len() / ncols` rows of `x` into the row-major `out`.
fn rows_into(x: &nalgebra::DMatrix<f64>, out: &mut [f64]) {
    let nc = x.ncols();
    for (r, row) in out.chunks_mut(nc).enumerate() {
        for (c, o) in row.iter_mut().enumerate() {
            *o = x[(r, c)];
        }
    }
}

/// `crba` on every row: q (n, nq) → M (n, nv, nv), on all cores with the GIL released.
#[pyfunction]
pub(crate) fn crba_batch<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    data: PyRef<'py, PyData>,
    q: Mat2<'py>,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let m = &model.inner;
    let inputs = BatchInputs {
        src: "crba_batch",
        q: q.as_array(),
        v: None,
        a: None,
        second_is_tau: false,
    };
    run_batch(py, &model, &data, &inputs, &[m.nv, m.nv], |s, blk| {
        rows_into(dynamics::crba(m, &mut s.data, &s.q), blk);
    })
}

/// `frame_jacobian` on every row: q (n, nq) → J (n, 6, nv), on all cores with the GIL released.
#[pyfunction]
pub(crate) fn frame_jacobian_batch<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    data: PyRef<'py, PyData>,
    q: Mat2<'py>,
    frame: &str,
) -> PyResult<Bound<'py, PyArrayDyn<f64>>> {
    let m = &model.inner;
    let fid = model.frame(frame)?;
    let inputs = BatchInputs {
        src: "frame_jacobian_batch",
        q: q.as_array(),
        v: None,
        a: None,
        second_is_tau: false,
    };
    run_batch(py, &model, &data, &inputs, &[6, m.nv], |s, blk| {
        kinematics::frame_jacobian(
            m,
            &mut s.data,
            &s.q,
            fid,
            ReferenceFrame::LocalWorldAligned,
            &mut s.jac,
        );
        let nv = m.nv;
        for (r, row) in blk.chunks_mut(nv).enumerate() {
            for (c, o) in row.iter_mut().enumerate() {
                *o = s.jac[(r, c)];
            }
        }
    })
}

/// Registers the functions.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(rnea, m)?)?;
    m.add_function(wrap_pyfunction!(crba, m)?)?;
    m.add_function(wrap_pyfunction!(aba, m)?)?;
    m.add_function(wrap_pyfunction!(rnea_derivatives, m)?)?;
    m.add_function(wrap_pyfunction!(aba_derivatives, m)?)?;
    m.add_function(wrap_pyfunction!(frame_jacobian, m)?)?;
    m.add_function(wrap_pyfunction!(rnea_batch, m)?)?;
    m.add_function(wrap_pyfunction!(aba_batch, m)?)?;
    m.add_function(wrap_pyfunction!(crba_batch, m)?)?;
    m.add_function(wrap_pyfunction!(frame_jacobian_batch, m)?)?;
    Ok(())
}

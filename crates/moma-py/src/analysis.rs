//! Tip-over stability, free-floating space manipulators and operational-space control:
//! the per-state documents of `moma stability`, `moma space` and `moma osc`.

use crate::model::{BatchInputs, Mat2, PyData, PyModel, Vec1, check_state, load, par_rows, vector};
use crate::{err, to_py};
use moma::control::osc::{
    MIN_TASK_CONDITIONING, OscData, OscStateReport, osc_fixed_base, osc_to_pinocchio_layout,
    task_conditioning,
};
use moma::ik::tasks::TaskRows;
use moma::io::pinocchio_layout::PinocchioLayout;
use moma::multibody::Model;
use moma::space::{SpaceData, state_report};
use moma::spatial::Force;
use moma::stability::{
    BodySet, ExternalLoads, PointForce, StabilityData, StabilityModel, StateReport,
    SupportAttachment, SupportPolygon, evaluate,
};
use nalgebra::{DVector, Vector2, Vector3};
use numpy::ndarray::ArrayView1;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::collections::HashMap;

/// The stability set-up of the command line: support points in the base frame, the
/// Moment-Height body set, gravity (default the model's).
fn stability_model(
    m: &Model,
    support: &[[f64; 2]],
    mhs_bodies: &str,
    gravity: Option<[f64; 3]>,
) -> PyResult<StabilityModel> {
    let pts: Vec<Vector2<f64>> = support.iter().map(|p| Vector2::new(p[0], p[1])).collect();
    let poly = SupportPolygon::from_points(&pts).map_err(|e| err(format!("support: {e}")))?;
    let set: BodySet = mhs_bodies
        .parse()
        .map_err(|e| err(format!("mhs_bodies: {e}")))?;
    let g = gravity.map_or(m.gravity, |g| Vector3::new(g[0], g[1], g[2]));
    StabilityModel::new(m, poly, SupportAttachment::Base, &set)
        .map_err(|e| err(format!("mhs_bodies: {e}")))?
        .with_gravity(g)
        .map_err(err)
}

/// External point loads `[{"point": [x, y, z], "force": [fx, fy, fz]}, ...]` (world).
fn external_loads(ext: Option<Vec<HashMap<String, Vec<f64>>>>) -> PyResult<Vec<PointForce>> {
    let mut out = Vec::new();
    for (k, e) in ext.unwrap_or_default().iter().enumerate() {
        let get = |key: &str| -> PyResult<Vector3<f64>> {
            let x = e
                .get(key)
                .ok_or_else(|| err(format!("external[{k}]: missing field \"{key}\"")))?;
            if x.len() != 3 {
                return Err(err(format!(
                    "external[{k}].{key}: expected length 3, got {}",
                    x.len()
                )));
            }
            if x.iter().any(|y| !y.is_finite()) {
                return Err(err(format!("external[{k}].{key}: non-finite value")));
            }
            Ok(Vector3::new(x[0], x[1], x[2]))
        };
        out.push(PointForce {
            point: get("point")?,
            force: get("force")?,
        });
    }
    Ok(out)
}

/// Tip-over measures of one state (ZMP, Force-Angle, Moment-Height) on the support
/// polygon `support` (points `[x, y]` in the base frame on the ground), as the dict of
/// `moma stability`'s `states[i]` (keys `total_mass`, `com`, `giw`, `support`, `zmp`,
/// `zmp_margin`, `zmp_critical_edge`, `edges`, `force_angle_min`, `force_angle_alpha`,
/// `force_angle_beta_min`, `mhs_min`, `acceleration_limits` (at rest only), `stable`).
///
/// `v` and `a` default to zero; `mhs_bodies` is "all", "subtree:JOINT" or
/// "links:A,B,..."; `gravity` defaults to the model's; `external` is a list of
/// `{"point": [x, y, z], "force": [fx, fy, fz]}` (world).
#[pyfunction]
#[pyo3(signature = (model, data, q, v = None, a = None, *, support, mhs_bodies = "all", gravity = None, external = None))]
pub(crate) fn stability<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: Vec1<'py>,
    v: Option<Vec1<'py>>,
    a: Option<Vec1<'py>>,
    support: Vec<[f64; 2]>,
    mhs_bodies: &str,
    gravity: Option<[f64; 3]>,
    external: Option<Vec<HashMap<String, Vec<f64>>>>,
) -> PyResult<Bound<'py, PyAny>> {
    let m = &model.inner;
    model.check_data(&data)?;
    let sm = stability_model(m, &support, mhs_bodies, gravity)?;
    let ext = external_loads(external)?;
    let d = &mut *data;
    let src = "stability";
    load(src, "q", q.as_array(), &mut d.q)?;
    d.v.fill(0.0);
    d.a.fill(0.0);
    if let Some(v) = &v {
        load(src, "v", v.as_array(), &mut d.v)?;
    }
    if let Some(a) = &a {
        load(src, "a", a.as_array(), &mut d.a)?;
    }
    check_state(
        m,
        || src.into(),
        d.q.as_slice(),
        Some(d.v.as_slice()),
        Some(d.a.as_slice()),
        None,
    )?;
    let mut sd = StabilityData::new(&sm);
    let loads = ExternalLoads {
        forces: &ext,
        moments: &[],
    };
    evaluate(m, &mut d.inner, &sm, &mut sd, &d.q, &d.v, &d.a, &loads);
    let at_rest = d.v.iter().chain(d.a.iter()).all(|x| *x == 0.0) && ext.is_empty();
    to_py(py, &StateReport::new(&sm, &sd, at_rest))
}

/// `stability` on every row of q (n, nq) (v and a (n, nv), zero when omitted), on all
/// cores with the GIL released (one workspace per worker; `data` is only checked). Returns a dict of arrays, one entry per state: `total_mass` (n),
/// `com` (n, 3), `zmp` (n, 3), `zmp_margin`, `force_angle_min`, `force_angle_alpha`,
/// `force_angle_beta_min`, `mhs_min` (n; NaN where the measure is undefined),
/// `zmp_critical_edge` (n, int; -1 where undefined) and `stable` (n, bool).
#[pyfunction]
#[pyo3(signature = (model, data, q, v = None, a = None, *, support, mhs_bodies = "all", gravity = None))]
pub(crate) fn stability_batch<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    data: PyRef<'py, PyData>,
    q: Mat2<'py>,
    v: Option<Mat2<'py>>,
    a: Option<Mat2<'py>>,
    support: Vec<[f64; 2]>,
    mhs_bodies: &str,
    gravity: Option<[f64; 3]>,
) -> PyResult<Bound<'py, PyDict>> {
    let m = &model.inner;
    model.check_data(&data)?;
    let sm = stability_model(m, &support, mhs_bodies, gravity)?;
    let inputs = BatchInputs {
        src: "stability_batch",
        q: q.as_array(),
        v: v.as_ref().map(|x| x.as_array()),
        a: a.as_ref().map(|x| x.as_array()),
        second_is_tau: false,
    };
    let n = inputs.rows(m)?;
    let nan = f64::NAN;
    // per row: mass, com (3), zmp (3), margin, critical edge, FA min, FA alpha, FA beta, MHS, stable
    const W: usize = 14;
    let mut flat = vec![0.0; n * W];
    py.detach(|| -> PyResult<()> {
        inputs.check(m, n)?;
        let sd0 = StabilityData::new(&sm);
        par_rows(m, W, &mut flat, |s, k, row| {
            inputs.load(k, s);
            let mut sd = sd0.clone();
            evaluate(
                m,
                &mut s.data,
                &sm,
                &mut sd,
                &s.q,
                &s.v,
                &s.a,
                &ExternalLoads::default(),
            );
            let (w, r) = (&sd.wrench, &sd.report);
            row[0] = w.mass;
            row[1..4].copy_from_slice(w.com.as_slice());
            match &r.zmp {
                Some(z) => row[4..7].copy_from_slice(z.as_slice()),
                None => row[4..7].fill(nan),
            }
            row[7] = r.zmp_margin.unwrap_or(nan);
            row[8] = r.zmp_critical_edge.map_or(-1.0, |e| e as f64);
            row[9] = r.force_angle_min.unwrap_or(nan);
            row[10] = r.force_angle_alpha.unwrap_or(nan);
            row[11] = r.force_angle_beta_min.unwrap_or(nan);
            row[12] = r.mhs_min.unwrap_or(nan);
            row[13] = if r.stable { 1.0 } else { 0.0 };
        });
        Ok(())
    })?;
    let mut out = BatchOut::new(n);
    for (k, row) in flat.chunks(W).enumerate() {
        out.total_mass[k] = row[0];
        out.com[3 * k..3 * k + 3].copy_from_slice(&row[1..4]);
        out.zmp[3 * k..3 * k + 3].copy_from_slice(&row[4..7]);
        out.zmp_margin[k] = row[7];
        out.zmp_critical_edge[k] = row[8] as i64;
        out.force_angle_min[k] = row[9];
        out.force_angle_alpha[k] = row[10];
        out.force_angle_beta_min[k] = row[11];
        out.mhs_min[k] = row[12];
        out.stable[k] = row[13] == 1.0;
    }
    let dict = PyDict::new(py);
    dict.set_item("total_mass", PyArray1::from_vec(py, out.total_mass))?;
    dict.set_item("com", PyArray1::from_vec(py, out.com).reshape([n, 3])?)?;
    dict.set_item("zmp", PyArray1::from_vec(py, out.zmp).reshape([n, 3])?)?;
    dict.set_item("zmp_margin", PyArray1::from_vec(py, out.zmp_margin))?;
    dict.set_item(
        "zmp_critical_edge",
        PyArray1::from_vec(py, out.zmp_critical_edge),
    )?;
    dict.set_item(
        "force_angle_min",
        PyArray1::from_vec(py, out.force_angle_min),
    )?;
    dict.set_item(
        "force_angle_alpha",
        PyArray1::from_vec(py, out.force_angle_alpha),
    )?;
    dict.set_item(
        "force_angle_beta_min",
        PyArray1::from_vec(py, out.force_angle_beta_min),
    )?;
    dict.set_item("mhs_min", PyArray1::from_vec(py, out.mhs_min))?;
    dict.set_item("stable", PyArray1::from_vec(py, out.stable))?;
    Ok(dict)
}

/// The columns of `stability_batch`.
struct BatchOut {
    total_mass: Vec<f64>,
    com: Vec<f64>,
    zmp: Vec<f64>,
    zmp_margin: Vec<f64>,
    zmp_critical_edge: Vec<i64>,
    force_angle_min: Vec<f64>,
    force_angle_alpha: Vec<f64>,
    force_angle_beta_min: Vec<f64>,
    mhs_min: Vec<f64>,
    stable: Vec<bool>,
}

impl BatchOut {
    fn new(n: usize) -> Self {
        Self {
            total_mass: vec![0.0; n],
            com: vec![0.0; 3 * n],
            zmp: vec![0.0; 3 * n],
            zmp_margin: vec![0.0; n],
            zmp_critical_edge: vec![0; n],
            force_angle_min: vec![0.0; n],
            force_angle_alpha: vec![0.0; n],
            force_angle_beta_min: vec![0.0; n],
            mhs_min: vec![0.0; n],
            stable: vec![false; n],
        }
    }
}

/// The free-floating quantities of one state of a free-flyer-rooted model, as the dict of
/// `moma space`'s `states[i]`: `total_mass`, `com`, `base_velocity` (the base twist the
/// joint rates induce under momentum conservation, base frame), `v` (the whole
/// generalized velocity), `generalized_jacobian` J* (6 × n rows), `generalized_inertia`
/// H* (n × n rows) and `frame_velocity` (`[ṗ; ω]` of `frame`, world axes).
///
/// `qdot_joints` has nv − 6 entries; `momentum` is `{"linear": [3],
/// "angular_about_com": [3]}` (world axes, angular part about the system CoM; zero when
/// omitted). Gravity plays no part.
#[pyfunction]
#[pyo3(name = "space", signature = (model, data, q, qdot_joints, frame, momentum = None))]
pub(crate) fn space_state<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: Vec1<'py>,
    qdot_joints: Vec1<'py>,
    frame: &str,
    momentum: Option<HashMap<String, Vec<f64>>>,
) -> PyResult<Bound<'py, PyAny>> {
    let m = &model.inner;
    model.check_data(&data)?;
    let fid = model.frame(frame)?;
    let mut sd = SpaceData::new(m).map_err(err)?;
    let src = "space";
    let d = &mut *data;
    load(src, "q", q.as_array(), &mut d.q)?;
    check_state(m, || src.into(), d.q.as_slice(), None, None, None)?;
    let qd = vector(src, "qdot_joints", qdot_joints.as_array(), sd.n)?;
    if let Some(i) = qd.iter().position(|y| !y.is_finite()) {
        return Err(err(format!("{src} qdot_joints[{i}]: not finite")));
    }
    let h = match &momentum {
        None => Force::zero(),
        Some(mm) => {
            let get = |key: &str| -> PyResult<Vector3<f64>> {
                let x = mm
                    .get(key)
                    .ok_or_else(|| err(format!("{src} momentum: missing field \"{key}\"")))?;
                if x.len() != 3 {
                    return Err(err(format!(
                        "{src} momentum.{key}: expected 3 numbers, got {}",
                        x.len()
                    )));
                }
                if let Some(k) = x.iter().position(|y| !y.is_finite()) {
                    return Err(err(format!("{src} momentum.{key}[{k}]: not finite")));
                }
                Ok(Vector3::new(x[0], x[1], x[2]))
            };
            if let Some(k) = mm
                .keys()
                .find(|k| *k != "linear" && *k != "angular_about_com")
            {
                return Err(err(format!("{src} momentum: unknown field \"{k}\"")));
            }
            Force::new(get("linear")?, get("angular_about_com")?)
        }
    };
    let st = state_report(m, &mut d.inner, &mut sd, &d.q, qd.as_slice(), &h, fid)
        .map_err(|e| err(format!("{src}: {e}")))?;
    if !st.is_finite() {
        return Err(err(format!(
            "{src}: non-finite result (degenerate mass distribution?)"
        )));
    }
    to_py(py, &st)
}

/// The `layout` argument of `osc`: `None` for moma's own, the converter for Pinocchio's.
fn osc_layout(m: &Model, layout: &str) -> PyResult<Option<PinocchioLayout>> {
    match layout {
        "moma" => Ok(None),
        "pinocchio" => Ok(Some(PinocchioLayout::new(m))),
        other => Err(err(format!(
            "osc layout: expected \"moma\" or \"pinocchio\", got \"{other}\""
        ))),
    }
}

/// Loads `osc`'s q and v (zero when not given) into `d` in moma's layout, converting
/// from Pinocchio's when `pin` is given, and checks the state.
fn load_osc_state(
    m: &Model,
    d: &mut PyData,
    pin: Option<&PinocchioLayout>,
    q: &Vec1<'_>,
    v: Option<&Vec1<'_>>,
) -> PyResult<()> {
    let src = "osc";
    match pin {
        None => load(src, "q", q.as_array(), &mut d.q)?,
        Some(l) => {
            let qp: Vec<f64> = q.as_array().iter().copied().collect();
            l.q_from_pinocchio(&qp, d.q.as_mut_slice())
                .map_err(|e| err(format!("{src}: {e}")))?;
        }
    }
    d.v.fill(0.0);
    if let Some(v) = v {
        load(src, "v", v.as_array(), &mut d.v)?;
        if let Some(l) = pin {
            d.a.copy_from(&d.v);
            l.v_from_pinocchio(d.q.as_slice(), d.a.as_slice(), d.v.as_mut_slice());
        }
    }
    check_state(
        m,
        || src.into(),
        d.q.as_slice(),
        Some(d.v.as_slice()),
        None,
        None,
    )
}

/// `osc`'s desired task acceleration on the selected `rows`: given as 6 values (`[ẍ; ω̇]`)
/// or one per selected row.
fn osc_task_acceleration(ta: ArrayView1<'_, f64>, rows: &[usize]) -> PyResult<DVector<f64>> {
    let src = "osc";
    let nr = rows.len();
    let a_des = if ta.len() == nr {
        DVector::from_iterator(nr, ta.iter().copied())
    } else if ta.len() == 6 {
        DVector::from_iterator(nr, rows.iter().map(|&r| ta[r]))
    } else {
        return Err(err(format!(
            "{src} task_acceleration: expected 6 values (or {nr}, one per selected row), got {}",
            ta.len()
        )));
    };
    if let Some(i) = a_des.iter().position(|x| !x.is_finite()) {
        return Err(err(format!("{src} task_acceleration[{i}]: not finite")));
    }
    Ok(a_des)
}

/// `osc`'s null-space torque τ₀ in moma's layout (zero when not given).
fn osc_null_torque(
    d: &PyData,
    pin: Option<&PinocchioLayout>,
    null_torque: Option<&Vec1<'_>>,
    nv: usize,
) -> PyResult<DVector<f64>> {
    let src = "osc";
    let Some(t) = null_torque else {
        return Ok(DVector::zeros(nv));
    };
    let t = vector(src, "null_torque", t.as_array(), nv)?;
    if let Some(i) = t.iter().position(|x| !x.is_finite()) {
        return Err(err(format!("{src} null_torque[{i}]: not finite")));
    }
    Ok(match pin {
        None => t,
        Some(l) => {
            let mut tm = DVector::zeros(nv);
            l.tau_from_pinocchio(d.q.as_slice(), t.as_slice(), tm.as_mut_slice());
            tm
        }
    })
}

/// Khatib's operational-space quantities of `frame` at one state (fixed base), as the
/// dict of `moma osc`'s `states[i]`: `task_inertia` Λ, `dynamically_consistent_inverse`
/// J̄, `nullspace_projector` N (lists of rows), `acceleration_bias` J̇v, `task_force` F,
/// `torque` τ = Jᵀ F + Nᵀ τ₀ and `task_conditioning` (σ_min/σ_max of J).
///
/// `task_acceleration` has 6 entries (`[ẍ; ω̇]`, world axes) or one per selected row;
/// `null_torque` (nv) defaults to zero; `rows` is "position", "orientation", "full" or
/// "rows:i,j,...". A task Jacobian with σ_min/σ_max below 1e-6 raises MomaError.
///
/// `layout="pinocchio"` takes q, v and `null_torque` in Pinocchio's layout (planar base
/// `[x, y, cos θ, sin θ]` with base-frame velocity, continuous joints as cos/sin pairs)
/// and gives J̄ (`T J̄`), N (`T N Tᵀ`), τ (`T τ`) and J̇v (Pinocchio's, at its zero
/// acceleration) in it too, as `moma osc --layout pinocchio`; Λ and F are the same in
/// both layouts.
#[pyfunction]
#[pyo3(signature = (model, data, q, v, frame, task_acceleration, null_torque = None, rows = "full", *, layout = "moma"))]
pub(crate) fn osc<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    mut data: PyRefMut<'py, PyData>,
    q: Vec1<'py>,
    v: Option<Vec1<'py>>,
    frame: &str,
    task_acceleration: Vec1<'py>,
    null_torque: Option<Vec1<'py>>,
    rows: &str,
    layout: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let m = &model.inner;
    model.check_data(&data)?;
    let fid = model.frame(frame)?;
    let task_rows: TaskRows = rows.parse().map_err(|e| err(format!("rows: {e}")))?;
    task_rows
        .validate()
        .map_err(|e| err(format!("rows: {e}")))?;
    let rows = task_rows.indices();
    let nv = m.nv;
    let src = "osc";
    let pin = osc_layout(m, layout)?;
    let d = &mut *data;
    load_osc_state(m, d, pin.as_ref(), &q, v.as_ref())?;
    let a_des = osc_task_acceleration(task_acceleration.as_array(), &rows)?;
    let tau0 = osc_null_torque(d, pin.as_ref(), null_torque.as_ref(), nv)?;
    let mut od = OscData::new(nv, &rows);
    let res = osc_fixed_base(m, &mut d.inner, &mut od, fid, &d.q, &d.v, &a_des, &tau0);
    let cond = task_conditioning(&od);
    if cond < MIN_TASK_CONDITIONING {
        return Err(err(format!(
            "{src}: task Jacobian of frame '{frame}' is singular: sigma_min/sigma_max = {cond:e} < {MIN_TASK_CONDITIONING:e}"
        )));
    }
    res.map_err(|e| err(format!("{src}: {e}")))?;
    if let Some(l) = &pin {
        osc_to_pinocchio_layout(l, d.q.as_slice(), d.v.as_slice(), &mut od);
    }
    to_py(py, &OscStateReport::new(&od, cond))
}

/// Registers the functions.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(stability, m)?)?;
    m.add_function(wrap_pyfunction!(stability_batch, m)?)?;
    m.add_function(wrap_pyfunction!(space_state, m)?)?;
    m.add_function(wrap_pyfunction!(osc, m)?)?;
    Ok(())
}

//! Where to stand for a grasp: `moma.place`, the library's `place_base` as `moma place`
//! runs it (drive and support polygon from the URDF's wheels and the casters, the grasp
//! from a pose or a MotionBenchMaker query), returning the ranked candidates as arrays.

use crate::collision::{PyGeometryModel, PyScene};
use crate::err;
use crate::model::{PyModel, Vec1};
use moma::ik::tasks::target_from_slice;
use moma::mobile::{Caster, read_casters, wheeled_base_from_urdf};
use moma::motion::placement::{
    Candidate, Payload, PlacementOptions, PlacementProblem, ScoreWeights, place_base,
};
use moma::motion::{GoalPose, JointGroup, grasp_query::read_grasp_query};
use moma::stability::SupportPolygon;
use nalgebra::Vector3;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

fn invalid(field: &str, msg: impl Into<String>) -> PyErr {
    err(moma::Error::invalid(format!("place: {field}"), msg))
}

/// A library error, its message prefixed with the function's name.
fn lib(e: moma::Error) -> PyErr {
    err(format!("place: {e}"))
}

/// Exactly `n` finite numbers.
fn fixed<const N: usize>(field: &str, v: &[f64]) -> PyResult<[f64; N]> {
    let a: [f64; N] = v
        .try_into()
        .map_err(|_| invalid(field, format!("expected {N} numbers, got {}", v.len())))?;
    if let Some(i) = a.iter().position(|x| !x.is_finite()) {
        return Err(invalid(
            field,
            format!("element {i} ({}) is not finite", a[i]),
        ));
    }
    Ok(a)
}

/// The casters: a casters file (as `moma place --casters`) or a sequence of `[x, y]`
/// contact points in the base frame.
fn caster_list(v: Option<&Bound<'_, PyAny>>) -> PyResult<Vec<Caster>> {
    let Some(v) = v else { return Ok(Vec::new()) };
    if let Ok(path) = v.extract::<PathBuf>() {
        return read_casters(&path).map_err(lib);
    }
    let points: Vec<Vec<f64>> = v.extract().map_err(|_| {
        invalid(
            "casters",
            "expected a casters file or a sequence of [x, y] points",
        )
    })?;
    points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            Ok(Caster {
                name: format!("caster{i}"),
                position: fixed::<2>(&format!("casters[{i}]"), p)?,
            })
        })
        .collect()
}

/// Candidates' rows as an (n, cols) array (an empty (0, cols) array for none).
fn rows<'py>(
    py: Python<'py>,
    r: Vec<Vec<f64>>,
    cols: usize,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    if r.is_empty() {
        return Ok(PyArray2::zeros(py, [0, cols], false));
    }
    PyArray2::from_vec2(py, &r).map_err(err)
}

/// Ranks the base poses `(x, y, θ)` from which the joint `group` of a robot on a planar
/// root reaches a grasp collision-free and without tipping over with the payload, as
/// `moma place` does (`docs/placement.md`). The grasp is `grasp_pose` (`[x, y, z]` or
/// `[x, y, z, qx, qy, qz, qw]`, world) of the model frame `frame` within
/// `position_tolerance` m and `orientation_tolerance` rad, or goal query `query_index`
/// of the MotionBenchMaker query file `query` (an offset from a scene object, its own
/// tolerances; the payload's centre then defaults to the object's origin). `wheels` are
/// the `[left, right]` driven wheel joints (drive read from the URDF); `casters` a
/// casters file or a sequence of `[x, y]` points (base frame); `payload` the object's
/// mass (kg) at `payload_offset` (grasp frame, m); `posture` a full configuration fixing
/// the joints outside the group and seeding IK (default: neutral). The other options are
/// the command's: `area` `[x0, y0, x1, y1]`, `step`, `headings`, `ik_attempts`, `seed`,
/// `margin`, `weights` `(manipulability, clearance, tip-over)`, `max_samples`,
/// `candidates`. The GIL is released while searching.
///
/// Returns a dict: `found`, `reason` (None when found, else why no pose works, counted
/// per stage), `candidates` (best first: `base` (n, 3), `q` (n, nq), `manipulability`,
/// `clearance`, `tip_over_margin`, `score` (n,), `grasp_error` (n, 2), `closest` (pairs
/// of names)), `counts` (poses stopped at each stage), `reach` (centre, radius),
/// `best_position_error`, `grid`, `grasp` (`frame`, `pose` (7,), tolerances, `object`),
/// `payload_offset` (3,), `support` (m, 2). No candidate is not an error.
///
/// Raises MomaError for bad input: a model without a planar root, an unknown group
/// joint, wheel joint or frame, both or neither of `grasp_pose` and `query`, an
/// unreadable query or casters file, a negative payload, bad weights, margin or grid
/// options, a posture of the wrong length.
#[pyfunction]
#[pyo3(name = "place", signature = (
    model, geom, scene, group, wheels, grasp_pose = None, frame = None, query = None,
    query_index = 0, position_tolerance = 0.01, orientation_tolerance = 0.01,
    casters = None, payload = 0.0, payload_offset = None, posture = None, area = None,
    step = 0.1, headings = 16, ik_attempts = 8, seed = 0, margin = 0.005,
    weights = (1.0, 1.0, 1.0), max_samples = 200_000, candidates = 20
))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn place_py<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    geom: PyRef<'py, PyGeometryModel>,
    scene: PyRef<'py, PyScene>,
    group: Vec<String>,
    wheels: (String, String),
    grasp_pose: Option<Vec1<'py>>,
    frame: Option<&str>,
    query: Option<PathBuf>,
    query_index: usize,
    position_tolerance: f64,
    orientation_tolerance: f64,
    casters: Option<Bound<'py, PyAny>>,
    payload: f64,
    payload_offset: Option<Vec1<'py>>,
    posture: Option<Vec1<'py>>,
    area: Option<Vec1<'py>>,
    step: f64,
    headings: usize,
    ik_attempts: usize,
    seed: u64,
    margin: f64,
    weights: (f64, f64, f64),
    max_samples: usize,
    candidates: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let m = &model.inner;
    let gm = &geom.inner;
    let scene = &scene.inner;
    let group = JointGroup::new(m, &group).map_err(lib)?;
    let frame_name = frame.ok_or_else(|| invalid("frame", "the grasp needs the frame"))?;
    let frame_id = m.frame_id(frame_name).map_err(lib)?;
    let (grasp, object, query_offset) = match (grasp_pose, &query) {
        (Some(p), None) => {
            let target = target_from_slice(&p.as_array().to_vec()).map_err(lib)?;
            for (name, v) in [
                ("position_tolerance", position_tolerance),
                ("orientation_tolerance", orientation_tolerance),
            ] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(invalid(name, format!("{v} is not positive")));
                }
            }
            let g = GoalPose {
                frame: frame_id,
                target,
                position_tolerance,
                orientation_tolerance,
            };
            (g, None, None)
        }
        (None, Some(path)) => {
            let q = read_grasp_query(path, query_index, scene).map_err(lib)?;
            let g = GoalPose {
                frame: frame_id,
                target: q.target,
                position_tolerance: q.position_tolerance,
                orientation_tolerance: q.orientation_tolerance,
            };
            (g, Some(q.object), Some(q.object_in_grasp))
        }
        (Some(_), Some(_)) => {
            return Err(invalid("grasp", "give grasp_pose or query, not both"));
        }
        (None, None) => return Err(invalid("grasp", "give grasp_pose or query")),
    };
    let base = wheeled_base_from_urdf(
        m,
        gm,
        [&wheels.0, &wheels.1],
        caster_list(casters.as_ref())?,
    )
    .map_err(lib)?;
    let support = SupportPolygon::from_wheeled_base(&base).map_err(lib)?;
    let offset = match payload_offset {
        Some(v) => Vector3::from(fixed::<3>("payload_offset", &v.as_array().to_vec())?),
        None => query_offset.unwrap_or_else(Vector3::zeros),
    };
    let posture: Vec<f64> = match posture {
        Some(v) => v.as_array().to_vec(),
        None => moma::multibody::neutral(m).as_slice().to_vec(),
    };
    let area = match area {
        Some(v) => Some(fixed::<4>("area", &v.as_array().to_vec())?),
        None => None,
    };
    let options = PlacementOptions {
        area,
        step,
        headings,
        ik_attempts,
        seed,
        margin,
        weights: ScoreWeights {
            manipulability: weights.0,
            clearance: weights.1,
            tip_over: weights.2,
        },
        max_samples,
        max_candidates: candidates,
        ..PlacementOptions::default()
    };
    let problem = PlacementProblem {
        model: m,
        geometry: gm,
        scene,
        group: &group,
        posture: &posture,
        support: &support,
        grasp: &grasp,
        payload: Payload {
            mass: payload,
            offset,
        },
    };
    let placement = py.detach(|| place_base(&problem, &options)).map_err(lib)?;

    let c = &placement.candidates;
    let cand = PyDict::new(py);
    cand.set_item(
        "base",
        rows(py, c.iter().map(|c| c.base.to_vec()).collect(), 3)?,
    )?;
    cand.set_item(
        "q",
        rows(py, c.iter().map(|c| c.q.clone()).collect(), m.nq)?,
    )?;
    let column = |f: fn(&Candidate) -> f64| PyArray1::from_vec(py, c.iter().map(f).collect());
    cand.set_item("manipulability", column(|c| c.manipulability))?;
    cand.set_item("clearance", column(|c| c.clearance))?;
    cand.set_item("tip_over_margin", column(|c| c.tip_over_margin))?;
    cand.set_item("score", column(|c| c.score))?;
    cand.set_item(
        "grasp_error",
        rows(py, c.iter().map(|c| c.grasp_error.to_vec()).collect(), 2)?,
    )?;
    cand.set_item(
        "closest",
        c.iter()
            .map(|c| (c.closest[0].clone(), c.closest[1].clone()))
            .collect::<Vec<_>>(),
    )?;
    let t = grasp.target;
    let r = t.rotation.coords;
    let g = PyDict::new(py);
    g.set_item("frame", frame_name)?;
    g.set_item(
        "pose",
        PyArray1::from_vec(
            py,
            vec![
                t.translation.x,
                t.translation.y,
                t.translation.z,
                r.x,
                r.y,
                r.z,
                r.w,
            ],
        ),
    )?;
    g.set_item("position_tolerance", grasp.position_tolerance)?;
    g.set_item("orientation_tolerance", grasp.orientation_tolerance)?;
    g.set_item("object", object)?;

    let out = PyDict::new(py);
    out.set_item("found", !c.is_empty())?;
    out.set_item("reason", placement.failure())?;
    out.set_item("candidates", cand)?;
    out.set_item("counts", crate::to_py(py, &placement.counts)?)?;
    out.set_item("reach", crate::to_py(py, &placement.reach)?)?;
    out.set_item("best_position_error", placement.best_position_error)?;
    out.set_item("grid", crate::to_py(py, &placement.grid)?)?;
    out.set_item("grasp", g)?;
    out.set_item("payload_kg", payload)?;
    out.set_item(
        "payload_offset",
        PyArray1::from_slice(py, offset.as_slice()),
    )?;
    out.set_item(
        "support",
        rows(
            py,
            support
                .vertices_xy()
                .iter()
                .map(|v| vec![v.x, v.y])
                .collect(),
            2,
        )?,
    )?;
    Ok(out)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(place_py, m)?)?;
    Ok(())
}

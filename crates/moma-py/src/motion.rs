//! Arm motion planning among obstacles: `moma.plan_motion`, the library's `plan_motion`
//! as `moma motion` runs it (concave links in contact at the start or goal state swapped for their
//! mesh surfaces first), returning the command's output fields.

use crate::collision::{PyGeometryModel, PyScene};
use crate::err;
use crate::model::{PyModel, Vec1};
use moma::collision::Scene;
use moma::ik::tasks::target_from_slice;
use moma::motion::{
    GoalPose, JointGroup, MotionGoal, MotionOptions, MotionProblem, plan_motion,
    surface_links_for_states,
};
use moma::multibody::RootJoint;
use numpy::{PyArray1, PyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::time::Duration;

fn invalid(field: &str, msg: impl Into<String>) -> PyErr {
    err(moma::Error::invalid(format!("plan_motion: {field}"), msg))
}

/// A library error, its message prefixed with the function's name.
fn lib(e: moma::Error) -> PyErr {
    err(format!("plan_motion: {e}"))
}

/// One value for every joint, or one per joint.
fn per_joint(field: &str, v: &Bound<'_, PyAny>, dim: usize) -> PyResult<Vec<f64>> {
    let values = match v.extract::<f64>() {
        Ok(x) => vec![x; dim],
        Err(_) => v.extract::<Vec<f64>>().map_err(|_| {
            invalid(
                field,
                "expected a number or a sequence of numbers (one per joint)",
            )
        })?,
    };
    if values.len() != dim {
        return Err(invalid(
            field,
            format!(
                "{} values for a group of {dim} joints (give 1 or {dim})",
                values.len()
            ),
        ));
    }
    if let Some(i) = values.iter().position(|a| !(a.is_finite() && *a > 0.0)) {
        return Err(invalid(
            field,
            format!("element {i} ({}) is not positive", values[i]),
        ));
    }
    Ok(values)
}

/// Rows as an (n, cols) array (an empty (0, cols) array for no row).
fn rows<'py>(py: Python<'py>, r: &[Vec<f64>], cols: usize) -> PyResult<Bound<'py, PyArray2<f64>>> {
    if r.is_empty() {
        return Ok(PyArray2::zeros(py, [0, cols], false));
    }
    PyArray2::from_vec2(py, r).map_err(err)
}

/// Plans a collision-free, time-optimal motion of the joint `group` (names, e.g. Fetch's
/// torso lift and 7 arm joints) among the `scene`'s objects, as `moma motion` does: from
/// `start` (a full configuration, model order) to `goal_state` (a full configuration
/// whose joints outside the group equal the start's) or to `goal_pose`
/// (`[x, y, z]` or `[x, y, z, qx, qy, qz, qw]` of the model frame `frame`, in the world
/// frame, reached within `position_tolerance` m and `orientation_tolerance` rad by IK
/// over the group). `time_limit` (s) bounds IK, search, shortcutting and timing
/// together; `seed` fixes every random choice (the same seed gives the same path);
/// `margin` (m) is the clearance every checked state keeps; `max_acceleration` is one
/// limit for every group joint or one per joint (rad/s², m/s²); `mesh` is how the
/// scene's meshes enter the distances, as `moma motion --mesh`: `"convex"` (each as its
/// convex hull, the default) or `"exact"` (each as its triangles: a concave mesh, such
/// as a shelf unit, then has no inside). Needs a model with a fixed root. The GIL is
/// released while planning.
///
/// Returns a dict with the fields of `moma motion`'s JSON: `solved`, `reason` (None when
/// solved, else why not: time limit, goal pose unreachable, goal pose only reachable in
/// collision), `planning_time_s`, `path` (n, nq), `trajectory` (`t` (m,), `q` (m, nq)),
/// `duration_s`, `min_distance`, `closest_pair`, `min_distance_states` (the states the
/// minimum covers: the path's waypoints then the trajectory's samples, a prefix when the
/// time limit left no room for all), `checks`, `iterations`, `ik_attempts`,
/// `ik_solutions`, `goal_state` ((nq,) or None), `group`, `seed`, `margin`,
/// `velocity_limits`, `acceleration_limits`, `mesh_surface_links`. A query not solved
/// returns `solved=False` with the reason; it does not raise.
///
/// Raises MomaError for bad input: an unknown group joint (listing the model's joints),
/// a start or goal of the wrong length, outside the joint limits or in contact (naming
/// the link and the scene object or other link), both or neither of `goal_state` and
/// `goal_pose`, an unknown frame, non-positive tolerances, time limit or accelerations;
/// ValueError for a `mesh` other than `"convex"` or `"exact"`.
#[pyfunction]
#[pyo3(name = "plan_motion", signature = (
    model, geom, scene, group, start, goal_state = None, goal_pose = None, frame = None,
    position_tolerance = 0.01, orientation_tolerance = 0.01, time_limit = 1.0, seed = 0,
    margin = 0.002, max_acceleration = None, mesh = "convex"
))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn plan_motion_py<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    geom: PyRef<'py, PyGeometryModel>,
    scene: Option<PyRef<'py, PyScene>>,
    group: Vec<String>,
    start: Vec1<'py>,
    goal_state: Option<Vec1<'py>>,
    goal_pose: Option<Vec1<'py>>,
    frame: Option<&str>,
    position_tolerance: f64,
    orientation_tolerance: f64,
    time_limit: f64,
    seed: u64,
    margin: f64,
    max_acceleration: Option<Bound<'py, PyAny>>,
    mesh: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let exact = match mesh {
        "convex" => false,
        "exact" => true,
        other => {
            return Err(PyValueError::new_err(format!(
                "plan_motion: mesh: '{other}' is not 'convex' or 'exact'"
            )));
        }
    };
    let m = &model.inner;
    if m.root != RootJoint::Fixed {
        return Err(invalid(
            "model",
            format!(
                "motion plans a fixed-base group; the model's root is {}",
                m.root
            ),
        ));
    }
    let group = JointGroup::new(m, &group).map_err(lib)?;
    let dim = group.dim();
    let start: Vec<f64> = start.as_array().to_vec();
    let goal = match (goal_state, goal_pose) {
        (Some(q), None) => {
            if frame.is_some() {
                return Err(invalid("frame", "only with goal_pose"));
            }
            MotionGoal::State(q.as_array().to_vec())
        }
        (None, Some(p)) => {
            let frame = frame.ok_or_else(|| invalid("frame", "goal_pose needs the frame"))?;
            let frame = m.frame_id(frame).map_err(lib)?;
            let values = p.as_array().to_vec();
            let target = target_from_slice(&values).map_err(lib)?;
            for (name, v) in [
                ("position_tolerance", position_tolerance),
                ("orientation_tolerance", orientation_tolerance),
            ] {
                if !(v.is_finite() && v > 0.0) {
                    return Err(invalid(name, format!("{v} is not positive")));
                }
            }
            MotionGoal::Pose(GoalPose {
                frame,
                target,
                position_tolerance,
                orientation_tolerance,
            })
        }
        (Some(_), Some(_)) => {
            return Err(invalid("goal", "give goal_state or goal_pose, not both"));
        }
        (None, None) => return Err(invalid("goal", "give goal_state or goal_pose")),
    };
    if !(time_limit.is_finite() && time_limit > 0.0 && time_limit <= 86_400.0) {
        return Err(invalid(
            "time_limit",
            format!("{time_limit} is not a positive number of seconds (at most a day)"),
        ));
    }
    if !(margin.is_finite() && (0.0..=1.0).contains(&margin)) {
        return Err(invalid(
            "margin",
            format!("{margin} is not a length in [0, 1] m"),
        ));
    }
    let acceleration = match &max_acceleration {
        Some(a) => per_joint("max_acceleration", a, dim)?,
        None => vec![1.0; dim],
    };
    let mut options = MotionOptions::new(dim);
    options.time_limit = Duration::from_secs_f64(time_limit);
    options.seed = seed;
    options.margin = margin;
    options.acceleration = acceleration;

    let empty = Scene::default();
    let scene = scene.as_ref().map_or(&empty, |s| &s.inner);
    let triangles;
    let scene = if exact {
        triangles = scene.with_mesh_triangles().map_err(lib)?;
        &triangles
    } else {
        scene
    };
    let gm = &geom.inner;
    let source = &geom.source;
    let (r, swapped) = py
        .detach(|| -> moma::Result<_> {
            moma::error::ensure_len("start", m.nq, start.len())?;
            let states: Vec<&[f64]> = std::iter::once(start.as_slice())
                .chain(goal.state())
                .collect();
            let (geometry, swapped) =
                surface_links_for_states(m, gm, scene, &group, &states, options.margin, source)?;
            let problem = MotionProblem {
                model: m,
                geometry: &geometry,
                scene,
                group: &group,
            };
            Ok((plan_motion(&problem, &start, &goal, &options)?, swapped))
        })
        .map_err(lib)?;

    let nq = m.nq;
    let out = PyDict::new(py);
    out.set_item("solved", r.not_solved.is_none())?;
    out.set_item("reason", r.not_solved.as_ref().map(ToString::to_string))?;
    out.set_item("planning_time_s", r.planning_time.as_secs_f64())?;
    out.set_item("path", rows(py, &r.path, nq)?)?;
    let traj = PyDict::new(py);
    let (t, q) = r
        .trajectory
        .as_ref()
        .map_or((Vec::new(), Vec::new()), |t| (t.t.clone(), t.q.clone()));
    traj.set_item("t", PyArray1::from_vec(py, t))?;
    traj.set_item("q", rows(py, &q, nq)?)?;
    out.set_item("trajectory", traj)?;
    out.set_item("duration_s", r.trajectory.as_ref().map(|t| t.duration))?;
    out.set_item("min_distance", r.closest.as_ref().map(|c| c.distance))?;
    out.set_item("min_distance_states", r.closest_states)?;
    out.set_item(
        "closest_pair",
        r.closest
            .as_ref()
            .map(|c| (c.link.clone(), c.other.clone())),
    )?;
    out.set_item("checks", r.checks)?;
    out.set_item("iterations", r.iterations)?;
    out.set_item("ik_attempts", r.ik_attempts)?;
    out.set_item("ik_solutions", r.ik_solutions)?;
    out.set_item(
        "goal_state",
        r.goal_state.as_ref().map(|g| PyArray1::from_slice(py, g)),
    )?;
    out.set_item("group", group.names.clone())?;
    out.set_item("seed", seed)?;
    out.set_item("margin", r.margin)?;
    out.set_item("velocity_limits", group.velocity.clone())?;
    out.set_item("acceleration_limits", options.acceleration.clone())?;
    out.set_item("mesh_surface_links", swapped)?;
    Ok(out)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(plan_motion_py, m)?)?;
    Ok(())
}

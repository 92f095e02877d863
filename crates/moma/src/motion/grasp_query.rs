//! A grasp from a MotionBenchMaker goal query: the query names a scene object and gives
//! the grasp frame's pose as an offset from the object's pose, with per-axis tolerances.
//!
//! ```yaml
//! goal_queries:
//!   - objects: ["Can1"]
//!     offset:
//!       position: [-0.2, 0.0, 0.025]
//!       orientation: [0, 0, 0, 1]          # x, y, z, w
//!       position_tol: [0.0001, 0.0001, 0.0001]
//!       orientation_tol: [0.003, 0.003, 0.003]
//! ```
//!
//! The object's pose is the pose of its one shape in the scene (MotionBenchMaker's
//! objects are one primitive each); the grasp is `object ∘ offset`. A per-axis box
//! tolerance becomes the largest ball inside it: the smallest of the three values. The
//! object's centre in the grasp frame is `offset⁻¹`'s translation (the payload's place).

use crate::collision::Scene;
use crate::{Error, Result};
use nalgebra::{Isometry3, Quaternion, Translation3, UnitQuaternion, Vector3};
use std::path::Path;

/// The grasp a query asks for.
#[derive(Clone, Debug, PartialEq)]
pub struct GraspQuery {
    /// The object grasped (its scene id).
    pub object: String,
    /// The grasp frame's pose (world).
    pub target: Isometry3<f64>,
    /// Position tolerance (m): the smallest per-axis value.
    pub position_tolerance: f64,
    /// Orientation tolerance (rad): the smallest per-axis value.
    pub orientation_tolerance: f64,
    /// The object's origin in the grasp frame (m).
    pub object_in_grasp: Vector3<f64>,
}

#[derive(serde::Deserialize)]
struct RawFile {
    goal_queries: Option<Vec<RawQuery>>,
}

#[derive(serde::Deserialize)]
struct RawQuery {
    objects: Vec<String>,
    offset: RawOffset,
}

#[derive(serde::Deserialize)]
struct RawOffset {
    position: Vec<f64>,
    orientation: Vec<f64>,
    position_tol: Option<Vec<f64>>,
    orientation_tol: Option<Vec<f64>>,
}

/// Reads goal query `index` of the query file `path` against `scene`.
///
/// # Errors
/// [`Error::Io`]; [`Error::Parse`] naming the file and the field: malformed YAML, no
/// `goal_queries`, an index past the list, no object, an object the scene lacks, vectors
/// of the wrong length or not finite, a zero quaternion, tolerances that are not positive.
pub fn read_grasp_query(path: &Path, index: usize, scene: &Scene) -> Result<GraspQuery> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    grasp_query_from_str(&text, path, index, scene)
}

/// [`read_grasp_query`] on the text of the file `path`.
///
/// # Errors
/// As [`read_grasp_query`].
pub fn grasp_query_from_str(
    text: &str,
    path: &Path,
    index: usize,
    scene: &Scene,
) -> Result<GraspQuery> {
    let raw: RawFile = serde_saphyr::from_str(text)
        .map_err(|e| Error::parse(path, format!("malformed query YAML: {e}")))?;
    let queries = raw
        .goal_queries
        .ok_or_else(|| Error::parse(path, "goal_queries: missing"))?;
    let q = queries.get(index).ok_or_else(|| {
        Error::parse(
            path,
            format!(
                "goal_queries[{index}]: the file holds {} goal queries",
                queries.len()
            ),
        )
    })?;
    let at =
        |field: &str, m: String| Error::parse(path, format!("goal_queries[{index}].{field}: {m}"));
    let object = q
        .objects
        .first()
        .ok_or_else(|| at("objects", "names no object".into()))?;
    let obj = scene
        .objects
        .iter()
        .find(|o| &o.id == object)
        .ok_or_else(|| {
            let ids: Vec<&str> = scene.objects.iter().map(|o| o.id.as_str()).collect();
            at(
                "objects",
                format!(
                    "'{object}' is not in the scene (its objects: {})",
                    ids.join(", ")
                ),
            )
        })?;
    let [shape] = obj.shapes.as_slice() else {
        return Err(at(
            "objects",
            format!(
                "'{object}' has {} shapes; its pose is that of its one shape",
                obj.shapes.len()
            ),
        ));
    };
    let vec3 = |field: &str, v: &[f64]| -> Result<Vector3<f64>> {
        if v.len() != 3 || !v.iter().all(|x| x.is_finite()) {
            return Err(at(field, format!("expected 3 finite numbers, got {v:?}")));
        }
        Ok(Vector3::new(v[0], v[1], v[2]))
    };
    let o = &q.offset;
    let p = vec3("offset.position", &o.position)?;
    if o.orientation.len() != 4 || !o.orientation.iter().all(|x| x.is_finite()) {
        return Err(at(
            "offset.orientation",
            format!(
                "expected x, y, z, w (4 finite numbers), got {:?}",
                o.orientation
            ),
        ));
    }
    let quat = Quaternion::new(
        o.orientation[3],
        o.orientation[0],
        o.orientation[1],
        o.orientation[2],
    );
    if quat.norm() < 1e-9 {
        return Err(at("offset.orientation", "a zero quaternion".into()));
    }
    let offset =
        Isometry3::from_parts(Translation3::from(p), UnitQuaternion::from_quaternion(quat));
    let tol = |field: &str, v: &Option<Vec<f64>>, default: f64| -> Result<f64> {
        match v {
            None => Ok(default),
            Some(v) => {
                let t = vec3(field, v)?;
                let m = t.min();
                if m > 0.0 {
                    Ok(m)
                } else {
                    Err(at(field, format!("{v:?} is not positive")))
                }
            }
        }
    };
    let object_pose = shape.pose.to_isometry();
    Ok(GraspQuery {
        object: object.clone(),
        target: object_pose * offset,
        position_tolerance: tol("offset.position_tol", &o.position_tol, 0.01)?,
        orientation_tolerance: tol("offset.orientation_tol", &o.orientation_tol, 0.01)?,
        object_in_grasp: offset.inverse().translation.vector,
    })
}

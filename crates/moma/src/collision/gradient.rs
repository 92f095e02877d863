//! The derivative of the robot's minimum distance (over its self pairs and the scene)
//! with respect to the velocity coordinates: the closest pair's distance derivative.

use super::geometry_data::{GeometryData, pair_derivative};
use super::geometry_model::GeometryModel;
use super::scene::{Scene, SceneData};
use crate::multibody::{Data, Model};
use nalgebra::DVector;

/// The pair behind a minimum distance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ClosestPair {
    /// A link pair: index into `GeometryModel::pairs`.
    SelfPair(usize),
    /// A link (index into `GeometryModel::links`) and a scene object (index into
    /// `Scene::objects`).
    Scene {
        /// The link.
        link: usize,
        /// The object.
        object: usize,
    },
}

impl ClosestPair {
    /// The (link, object) pair of entry `k` of `SceneData::results` in a scene of
    /// `objects` objects (the results are link-major).
    #[must_use]
    pub fn scene_result(k: usize, objects: usize) -> Self {
        ClosestPair::Scene {
            link: k / objects,
            object: k % objects,
        }
    }
}

/// The closest pair of the last `compute_distances` and `compute_scene_distances` (a
/// self pair wins a tie) and its signed distance; `None` if neither visited a pair.
#[must_use]
pub fn closest_pair(
    gd: &GeometryData,
    scene: &Scene,
    sd: &SceneData,
) -> Option<(ClosestPair, f64)> {
    let own = gd
        .closest
        .map(|p| (ClosestPair::SelfPair(p), gd.results[p].distance));
    let no = scene.objects.len();
    let other = sd
        .closest
        .filter(|_| no > 0)
        .map(|k| (ClosestPair::scene_result(k, no), sd.results[k].distance));
    match (own, other) {
        (Some(a), Some(b)) => Some(if b.1 < a.1 { b } else { a }),
        (a, b) => a.or(b),
    }
}

/// Derivative of the distance between link `link` and scene object `object` (as last
/// computed by `compute_scene_distances`) with respect to the velocity coordinates:
/// the object is fixed, so `out[k] = −n · ∂witness_a/∂v_k` (see
/// [`distance_derivative`](super::geometry_data::distance_derivative); run
/// `kinematics::compute_joint_jacobians` first).
///
/// # Panics
/// If `out` does not have length `model.nv` or the indices are out of range.
#[allow(clippy::too_many_arguments)]
pub fn scene_distance_derivative(
    model: &Model,
    data: &Data,
    gm: &GeometryModel,
    scene: &Scene,
    sd: &SceneData,
    link: usize,
    object: usize,
    out: &mut DVector<f64>,
) {
    assert!(object < scene.objects.len(), "scene object out of range");
    let r = &sd.results[link * scene.objects.len() + object];
    pair_derivative(model, data, Some(gm.links[link].joint), None, r, out);
}

/// The minimum signed distance over the pairs the last `compute_distances` and
/// `compute_scene_distances` visited, and into `out` its derivative with respect to the
/// velocity coordinates (the derivative of the closest pair's distance: where the
/// closest pair is unique and its closest features are too, this is the gradient of the
/// minimum; for a fixed or planar root in moma's layout it is ∂d/∂q). Needs the joint
/// Jacobians of the same configuration (`kinematics::compute_joint_jacobians`).
/// Returns `None` (and leaves `out` alone) if no pair was visited.
///
/// # Panics
/// If `out` does not have length `model.nv`.
#[allow(clippy::too_many_arguments)]
pub fn min_distance_gradient(
    model: &Model,
    data: &Data,
    gm: &GeometryModel,
    gd: &GeometryData,
    scene: &Scene,
    sd: &SceneData,
    out: &mut DVector<f64>,
) -> Option<(ClosestPair, f64)> {
    let best = closest_pair(gd, scene, sd)?;
    pair_distance_derivative(model, data, gm, gd, scene, sd, best.0, out);
    Some(best)
}

/// Derivative of the distance of `pair` (as last computed by `compute_distances` or
/// `compute_scene_distances`) with respect to the velocity coordinates, into `out`:
/// [`distance_derivative`](super::geometry_data::distance_derivative) for a self pair,
/// [`scene_distance_derivative`] for a link and a scene object (run
/// `kinematics::compute_joint_jacobians` first).
///
/// # Panics
/// If `out` does not have length `model.nv` or the pair's indices are out of range.
#[allow(clippy::too_many_arguments)]
pub fn pair_distance_derivative(
    model: &Model,
    data: &Data,
    gm: &GeometryModel,
    gd: &GeometryData,
    scene: &Scene,
    sd: &SceneData,
    pair: ClosestPair,
    out: &mut DVector<f64>,
) {
    match pair {
        ClosestPair::SelfPair(p) => {
            super::geometry_data::distance_derivative(model, data, gm, gd, p, out);
        }
        ClosestPair::Scene { link, object } => {
            scene_distance_derivative(model, data, gm, scene, sd, link, object, out);
        }
    }
}

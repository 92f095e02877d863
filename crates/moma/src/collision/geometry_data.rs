//! `GeometryData`: world placements, per-pair results and warm starts; the self-distance
//! queries (all allocation-free once the data exists).

use super::geometry_model::GeometryModel;
use super::gjk::{EpaWorkspace, PairDistance, WarmStart, overlaps, signed_distance};
use crate::multibody::{Data, JointIndex, Model};
use crate::spatial::SE3;
use nalgebra::{DVector, Vector3};

/// Which link pairs a query visits.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum PairSelection {
    /// The enabled pairs ([`GeometryModel::enabled`]).
    #[default]
    Enabled,
    /// Every pair of links with geometry.
    All,
}

/// The workspace of the geometry queries.
#[derive(Clone, Debug)]
pub struct GeometryData {
    /// World placement of each object of the model (`update_geometry_placements`).
    pub placements: Vec<SE3>,
    /// Result per link pair of the model (aligned with `GeometryModel::pairs`); entries of
    /// pairs the last query did not visit keep older values.
    pub results: Vec<PairDistance>,
    /// Index (into `GeometryModel::pairs`) of the closest pair of the last
    /// `compute_distances`, `None` if it visited no pair.
    pub closest: Option<usize>,
    /// Warm start per object pair, `pair_offsets[p]..pair_offsets[p + 1]` for link pair p.
    warm: Vec<WarmStart>,
    pair_offsets: Vec<usize>,
    pub(super) epa: EpaWorkspace,
}

impl GeometryData {
    /// A workspace for `gm`.
    #[must_use]
    pub fn new(gm: &GeometryModel) -> Self {
        let mut pair_offsets = vec![0];
        for &[a, b] in &gm.pairs {
            let n = gm.links[a].count * gm.links[b].count;
            pair_offsets.push(pair_offsets.last().copied().unwrap_or(0) + n);
        }
        let nwarm = pair_offsets.last().copied().unwrap_or(0);
        let none = PairDistance {
            distance: f64::INFINITY,
            witness_a: Vector3::zeros(),
            witness_b: Vector3::zeros(),
            normal: Vector3::z(),
        };
        GeometryData {
            placements: gm.objects.iter().map(|o| o.placement).collect(),
            results: vec![none; gm.pairs.len()],
            closest: None,
            warm: vec![WarmStart::default(); nwarm],
            pair_offsets,
            epa: EpaWorkspace::default(),
        }
    }

    /// Forgets the warm starts, so the next queries' results depend only on the state
    /// (a warm start can move a distance in its last bits).
    pub fn reset_warm_starts(&mut self) {
        self.warm.fill(WarmStart::default());
    }
}

/// World placements of the geometry from the joint placements in `data` (run
/// `kinematics::forward_kinematics` first).
pub fn update_geometry_placements(gm: &GeometryModel, data: &Data, gd: &mut GeometryData) {
    for (p, o) in gd.placements.iter_mut().zip(&gm.objects) {
        *p = data.world_from_joint[o.joint.0] * o.placement;
    }
}

/// Signed distance of link pair `p` (minimum over its objects' pairs), into
/// `gd.results[p]`.
fn pair_distance(gm: &GeometryModel, gd: &mut GeometryData, p: usize) -> f64 {
    let [la, lb] = gm.pairs[p];
    let (a, b) = (&gm.links[la], &gm.links[lb]);
    let mut best = PairDistance {
        distance: f64::INFINITY,
        witness_a: Vector3::zeros(),
        witness_b: Vector3::zeros(),
        normal: Vector3::z(),
    };
    let mut k = gd.pair_offsets[p];
    for i in a.first..a.first + a.count {
        for j in b.first..b.first + b.count {
            let r = signed_distance(
                &gm.objects[i].shape,
                &gd.placements[i],
                &gm.objects[j].shape,
                &gd.placements[j],
                &mut gd.warm[k],
                &mut gd.epa,
            );
            if r.distance < best.distance {
                best = r;
            }
            k += 1;
        }
    }
    gd.results[p] = best;
    best.distance
}

/// Signed distances of the selected link pairs (after `update_geometry_placements`), into
/// `gd.results`; returns the minimum (`+∞` with no pair) and sets `gd.closest`.
pub fn compute_distances(gm: &GeometryModel, gd: &mut GeometryData, which: PairSelection) -> f64 {
    let mut min = f64::INFINITY;
    gd.closest = None;
    for p in 0..gm.pairs.len() {
        if which == PairSelection::Enabled && !gm.enabled[p] {
            continue;
        }
        let d = pair_distance(gm, gd, p);
        if d < min || gd.closest.is_none() {
            min = min.min(d);
            gd.closest = Some(p);
        }
    }
    min
}

/// Whether some enabled pair overlaps (signed distance < 0), stopping at the first one:
/// pairs whose bounding balls are apart are skipped, and each GJK stops as soon as it has
/// a separating plane. Returns the index of the first overlapping pair.
pub fn compute_collision(gm: &GeometryModel, gd: &mut GeometryData) -> Option<usize> {
    for p in 0..gm.pairs.len() {
        if !gm.enabled[p] {
            continue;
        }
        let [la, lb] = gm.pairs[p];
        let (a, b) = (&gm.links[la], &gm.links[lb]);
        let mut k = gd.pair_offsets[p];
        for i in a.first..a.first + a.count {
            for j in b.first..b.first + b.count {
                let (oa, ob) = (&gm.objects[i], &gm.objects[j]);
                let ca = gd.placements[i].act_point(&oa.bounding_centre);
                let cb = gd.placements[j].act_point(&ob.bounding_centre);
                let far = (ca - cb).norm() >= oa.bounding_radius + ob.bounding_radius;
                if !far
                    && overlaps(
                        &oa.shape,
                        &gd.placements[i],
                        &ob.shape,
                        &gd.placements[j],
                        &mut gd.warm[k],
                    )
                {
                    return Some(p);
                }
                k += 1;
            }
        }
    }
    None
}

/// Derivative of pair `p`'s signed distance (as last computed) with respect to the
/// velocity coordinates: `out[k] = n · (∂witness_b/∂v_k − ∂witness_a/∂v_k)`, the
/// witness points moving with their links (world-frame joint Jacobians in
/// `data.joint_jacobians`: run `kinematics::compute_joint_jacobians` first). For a fixed
/// base and revolute/prismatic joints this is ∂d/∂q. Exact where the closest features
/// are unique (vertex–face, edge–edge); at parallel faces d is not differentiable.
///
/// # Panics
/// If `out` does not have length `model.nv`.
pub fn distance_derivative(
    model: &Model,
    data: &Data,
    gm: &GeometryModel,
    gd: &GeometryData,
    p: usize,
    out: &mut DVector<f64>,
) {
    assert_eq!(
        out.len(),
        model.nv,
        "distance_derivative: out must have length nv"
    );
    let [la, lb] = gm.pairs[p];
    pair_derivative(
        model,
        data,
        Some(gm.links[la].joint),
        Some(gm.links[lb].joint),
        &gd.results[p],
        out,
    );
}

/// Derivative of a signed distance `r` between a shape carried by joint `joint_a` and one
/// carried by `joint_b` (`None`: fixed in the world, as a scene object) with respect to
/// the velocity coordinates: `out[k] = n · (∂witness_b/∂v_k − ∂witness_a/∂v_k)`, from the
/// world-frame joint Jacobians in `data.joint_jacobians` (run
/// `kinematics::compute_joint_jacobians` first). See [`distance_derivative`].
///
/// # Panics
/// If `out` does not have length `model.nv`.
pub fn pair_derivative(
    model: &Model,
    data: &Data,
    joint_a: Option<JointIndex>,
    joint_b: Option<JointIndex>,
    r: &PairDistance,
    out: &mut DVector<f64>,
) {
    assert_eq!(
        out.len(),
        model.nv,
        "pair_derivative: out must have length nv"
    );
    for k in 0..model.nv {
        let jk = model.joint_of_dof[k];
        let col = data.joint_jacobians.column(k);
        let lin = Vector3::new(col[0], col[1], col[2]);
        let ang = Vector3::new(col[3], col[4], col[5]);
        let mut g = 0.0;
        if joint_b.is_some_and(|jb| model.is_ancestor(jk, jb)) {
            g += r.normal.dot(&(lin + ang.cross(&r.witness_b)));
        }
        if joint_a.is_some_and(|ja| model.is_ancestor(jk, ja)) {
            g -= r.normal.dot(&(lin + ang.cross(&r.witness_a)));
        }
        out[k] = g;
    }
}

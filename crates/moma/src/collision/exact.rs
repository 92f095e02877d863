//! Exact distances between the links' triangle meshes (the `--mesh exact` option), with
//! `parry3d-f64`'s triangle-mesh queries: a mesh element is its triangles (not its convex
//! hull), a primitive is parry's shape of the same size. As coal's distance between
//! BVH models, the result is the surface distance: `0` when triangles touch or cross,
//! and positive for a mesh entirely inside another one without a crossing. parry's
//! types (glam) are converted at this file's boundary.

use super::convex::Convex;
use super::geometry_data::{GeometryData, PairSelection};
use super::geometry_model::GeometryModel;
use super::gjk::PairDistance;
use crate::spatial::SE3;
use crate::{Error, Result};
use nalgebra::{Rotation3, UnitQuaternion, Vector3};
use parry3d_f64::math::{Pose, Rot3, Vector as GVec};
use parry3d_f64::query::{ClosestPoints, closest_points};
use parry3d_f64::shape::{Ball, Capsule, Cuboid, Cylinder, SharedShape, TriMesh};

/// The exact shapes of a [`GeometryModel`]'s objects (aligned with `objects`).
#[derive(Clone)]
pub struct ExactGeometry {
    shapes: Vec<SharedShape>,
    /// `object_from_shape`: parry's cylinders run along y, ours along z.
    offsets: Vec<SE3>,
}

impl std::fmt::Debug for ExactGeometry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ExactGeometry({} shapes)", self.shapes.len())
    }
}

fn g(v: &Vector3<f64>) -> GVec {
    GVec::new(v.x, v.y, v.z)
}

fn pose(m: &SE3) -> Pose {
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(m.rotation));
    Pose::from_parts(
        g(&m.translation),
        Rot3::from_xyzw(q.i, q.j, q.k, q.w).normalize(),
    )
}

impl ExactGeometry {
    /// Builds the exact shapes: each mesh element's triangles as a parry `TriMesh`, each
    /// primitive as parry's.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the link of a mesh parry refuses (no triangle).
    pub fn new(gm: &GeometryModel) -> Result<Self> {
        let mut shapes = Vec::with_capacity(gm.objects.len());
        let mut offsets = Vec::with_capacity(gm.objects.len());
        for o in &gm.objects {
            let mut offset = SE3::identity();
            let shape = match (&o.mesh, &o.shape) {
                (Some(mesh), _) => {
                    let tri = TriMesh::new(
                        mesh.vertices.iter().map(g).collect(),
                        mesh.triangles.clone(),
                    )
                    .map_err(|e| {
                        Error::invalid(
                            format!("link '{}' mesh", gm.links[o.link].name),
                            format!("no exact triangle mesh: {e}"),
                        )
                    })?;
                    SharedShape::new(tri)
                }
                (None, Convex::Box { half }) => SharedShape::new(Cuboid::new(g(half))),
                (None, Convex::Sphere { radius }) => SharedShape::new(Ball::new(*radius)),
                (
                    None,
                    Convex::Capsule {
                        radius,
                        half_length,
                    },
                ) => SharedShape::new(Capsule::new_z(*half_length, *radius)),
                (
                    None,
                    Convex::Cylinder {
                        radius,
                        half_height,
                    },
                ) => {
                    // parry's y axis onto ours z: a quarter turn about x.
                    offset.rotation = *Rotation3::from_axis_angle(
                        &Vector3::x_axis(),
                        std::f64::consts::FRAC_PI_2,
                    )
                    .matrix();
                    SharedShape::new(Cylinder::new(*half_height, *radius))
                }
                (None, Convex::Hull { .. }) => {
                    return Err(Error::invalid(
                        format!("link '{}'", gm.links[o.link].name),
                        "a hull without its mesh has no exact shape",
                    ));
                }
            };
            shapes.push(shape);
            offsets.push(offset);
        }
        Ok(ExactGeometry { shapes, offsets })
    }
}

/// Exact distance between objects `i` and `j` at the placements of `gd`.
fn object_distance(ex: &ExactGeometry, gd: &GeometryData, i: usize, j: usize) -> PairDistance {
    let pa = gd.placements[i] * ex.offsets[i];
    let pb = gd.placements[j] * ex.offsets[j];
    let (ga, gb) = (pose(&pa), pose(&pb));
    let touching = PairDistance {
        distance: 0.0,
        witness_a: pa.translation,
        witness_b: pa.translation,
        normal: Vector3::zeros(),
    };
    match closest_points(&ga, &*ex.shapes[i].0, &gb, &*ex.shapes[j].0, f64::MAX) {
        Ok(ClosestPoints::WithinMargin(a, b)) => {
            let (wa, wb) = (Vector3::new(a.x, a.y, a.z), Vector3::new(b.x, b.y, b.z));
            let d = (wb - wa).norm();
            if d > 0.0 {
                PairDistance {
                    distance: d,
                    witness_a: wa,
                    witness_b: wb,
                    normal: (wb - wa) / d,
                }
            } else {
                PairDistance {
                    witness_a: wa,
                    witness_b: wb,
                    ..touching
                }
            }
        }
        // Intersecting (or a pair parry cannot answer, which none of the shapes built
        // above is): touching.
        _ => touching,
    }
}

/// Exact distances of the selected link pairs (after `update_geometry_placements`), into
/// `gd.results` as [`compute_distances`](super::geometry_data::compute_distances) does
/// for the hulls: each link pair's minimum over its objects, the world closest points,
/// `normal` = (witness_b − witness_a) / distance (zero when touching). Returns the
/// minimum and sets `gd.closest`. Allocates (parry's traversal), unlike the hull queries.
pub fn compute_exact_distances(
    gm: &GeometryModel,
    ex: &ExactGeometry,
    gd: &mut GeometryData,
    which: PairSelection,
) -> f64 {
    let mut min = f64::INFINITY;
    gd.closest = None;
    for p in 0..gm.pairs.len() {
        if which == PairSelection::Enabled && !gm.enabled[p] {
            continue;
        }
        let [la, lb] = gm.pairs[p];
        let (a, b) = (&gm.links[la], &gm.links[lb]);
        let mut best: Option<PairDistance> = None;
        for i in a.first..a.first + a.count {
            for j in b.first..b.first + b.count {
                let r = object_distance(ex, gd, i, j);
                if best.is_none_or(|b| r.distance < b.distance) {
                    best = Some(r);
                }
            }
        }
        if let Some(r) = best {
            gd.results[p] = r;
            if r.distance < min || gd.closest.is_none() {
                min = min.min(r.distance);
                gd.closest = Some(p);
            }
        }
    }
    min
}

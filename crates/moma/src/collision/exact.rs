//! Exact distances with the triangle meshes (the `--mesh exact` option): a mesh element is
//! its triangles (not its convex hull), a primitive is itself, for the link pairs
//! ([`compute_exact_distances`]) and the (link, scene object) pairs
//! ([`compute_exact_scene_distances`], scene meshes as their triangles, primitives and
//! voxels as themselves). Mesh against mesh is `parry3d-f64`'s triangle-mesh query (glam
//! converted at this file's boundary); mesh against primitive is the nearest triangle by
//! this module's GJK. As coal's distance between BVH models, the result is the surface
//! distance: `0` when triangles touch or cross, and positive for a mesh entirely inside
//! another one without a crossing; a primitive is solid, so a mesh inside a box is at
//! `0`, a box inside a mesh (no triangle reaching it) at its distance to the nearest
//! triangle.

use super::convex::Convex;
use super::geometry_data::{GeometryData, PairSelection};
use super::geometry_model::GeometryModel;
use super::gjk::{EpaWorkspace, PairDistance, WarmStart, signed_distance};
use super::mesh::TriangleMesh;
use super::scene::{Scene, SceneData, nearest_in_scene, world_aabb};
use crate::spatial::SE3;
use crate::{Error, Result};
use nalgebra::{Rotation3, UnitQuaternion, Vector3};
use parry3d_f64::math::{Pose, Rot3, Vector as GVec};
use parry3d_f64::query::{ClosestPoints, closest_points};
use parry3d_f64::shape::{SharedShape, TriMesh};
use std::sync::Arc;

/// One exact shape: a mesh's triangles, or a convex primitive as itself.
#[derive(Clone)]
enum Exact {
    /// The triangles, as parry's `TriMesh` (for mesh–mesh queries) and as read (for
    /// triangle–primitive queries with this module's GJK).
    Mesh(SharedShape, Arc<TriangleMesh>),
    /// A primitive (box, cylinder, sphere, capsule), measured with this module's GJK.
    Solid(Convex),
}

/// The exact shapes of a [`GeometryModel`]'s objects (aligned with `objects`).
#[derive(Clone)]
pub struct ExactGeometry {
    shapes: Vec<Exact>,
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

/// The exact shape of `shape` (with its mesh's triangles when it is a mesh's hull);
/// `what` names it in the error.
fn exact_shape(
    shape: &Convex,
    mesh: Option<&Arc<TriangleMesh>>,
    what: &dyn Fn() -> String,
) -> Result<Exact> {
    match (mesh, shape) {
        (Some(mesh), _) => {
            let tri = TriMesh::new(
                mesh.vertices.iter().map(g).collect(),
                mesh.triangles.clone(),
            )
            .map_err(|e| Error::invalid(what(), format!("no exact triangle mesh: {e}")))?;
            Ok(Exact::Mesh(SharedShape::new(tri), Arc::clone(mesh)))
        }
        (None, Convex::Hull { .. }) => Err(Error::invalid(
            what(),
            "a hull without its mesh has no exact shape",
        )),
        (None, primitive) => Ok(Exact::Solid(primitive.clone())),
    }
}

impl ExactGeometry {
    /// Builds the exact shapes: each mesh element's triangles as a parry `TriMesh`, each
    /// primitive as parry's.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the link of a mesh parry refuses (no triangle).
    pub fn new(gm: &GeometryModel) -> Result<Self> {
        let shapes = gm
            .objects
            .iter()
            .map(|o| {
                let what = || format!("link '{}' mesh", gm.links[o.link].name);
                exact_shape(&o.shape, o.mesh.as_ref(), &what)
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(ExactGeometry { shapes })
    }
}

/// The exact shapes of a [`Scene`]'s objects: per object, per shape (aligned with
/// `SceneObject::shapes`) the mesh's triangles for a mesh, the primitive itself
/// otherwise (a voxel is its box).
#[derive(Clone)]
pub struct ExactScene {
    /// `objects[o][s]`: the exact shape.
    objects: Vec<Vec<Exact>>,
}

impl std::fmt::Debug for ExactScene {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "ExactScene({} objects)", self.objects.len())
    }
}

impl ExactScene {
    /// Builds the exact shapes of `scene`'s objects.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the scene object of a mesh parry refuses, or of a
    /// hull given without its mesh.
    pub fn new(scene: &Scene) -> Result<Self> {
        let objects = scene
            .objects
            .iter()
            .map(|o| {
                let what = || format!("scene object '{}'", o.id);
                o.shapes
                    .iter()
                    .map(|s| exact_shape(&s.shape, s.mesh.as_ref(), &what))
                    .collect::<Result<Vec<_>>>()
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(ExactScene { objects })
    }
}

/// Exact distance between `a` at `pose_a` and `b` at `pose_b` (world placements): the
/// surface distance with the world closest points, `0` when they touch or cross. Two
/// meshes: parry's triangle-mesh query. A mesh and a primitive: the nearest triangle to
/// the solid primitive by this module's GJK (parry's triangle–cuboid closest points come
/// from separating axes and can miss an edge–vertex distance by millimetres). Two
/// primitives: their GJK distance, `0` when they overlap.
fn exact_distance(
    a: &Exact,
    pose_a: &SE3,
    b: &Exact,
    pose_b: &SE3,
    epa: &mut EpaWorkspace,
) -> PairDistance {
    match (a, b) {
        (Exact::Mesh(ta, _), Exact::Mesh(tb, _)) => mesh_mesh(ta, pose_a, tb, pose_b),
        (Exact::Mesh(_, m), Exact::Solid(c)) => mesh_solid(m, pose_a, c, pose_b, epa),
        (Exact::Solid(c), Exact::Mesh(_, m)) => {
            let r = mesh_solid(m, pose_b, c, pose_a, epa);
            PairDistance {
                witness_a: r.witness_b,
                witness_b: r.witness_a,
                normal: -r.normal,
                ..r
            }
        }
        (Exact::Solid(ca), Exact::Solid(cb)) => {
            let r = signed_distance(ca, pose_a, cb, pose_b, &mut WarmStart::default(), epa);
            clamp_touching(r)
        }
    }
}

/// A GJK/EPA result as a surface distance: overlapping is touching (distance 0, no
/// normal).
fn clamp_touching(r: PairDistance) -> PairDistance {
    if r.distance > 0.0 {
        r
    } else {
        PairDistance {
            distance: 0.0,
            normal: Vector3::zeros(),
            ..r
        }
    }
}

/// The nearest of `mesh`'s triangles (at `pose_m`) to the solid `c` (at `pose_c`):
/// triangles in the order of the gap between their bounding box and `c`'s, each a
/// three-vertex hull measured by GJK, until the gap reaches the best distance; `0` at
/// the first triangle that touches or enters `c`.
fn mesh_solid(
    mesh: &TriangleMesh,
    pose_m: &SE3,
    c: &Convex,
    pose_c: &SE3,
    epa: &mut EpaWorkspace,
) -> PairDistance {
    let (lo, hi) = world_aabb(c, pose_c);
    let mut order: Vec<(f64, usize)> = mesh
        .triangles
        .iter()
        .enumerate()
        .map(|(k, t)| {
            let w = t.map(|i| pose_m.act_point(&mesh.vertices[i as usize]));
            let tlo = w[0].inf(&w[1]).inf(&w[2]);
            let thi = w[0].sup(&w[1]).sup(&w[2]);
            let gap = (tlo - hi).sup(&(lo - thi)).sup(&Vector3::zeros()).norm();
            (gap, k)
        })
        .collect();
    order.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut best = PairDistance {
        distance: f64::INFINITY,
        witness_a: pose_m.translation,
        witness_b: pose_c.translation,
        normal: Vector3::zeros(),
    };
    for (gap, k) in order {
        if gap >= best.distance {
            break;
        }
        let tri = Convex::Hull {
            vertices: mesh.triangles[k]
                .iter()
                .map(|&i| mesh.vertices[i as usize])
                .collect(),
            neighbours: Vec::new(),
        };
        let r = signed_distance(&tri, pose_m, c, pose_c, &mut WarmStart::default(), epa);
        if r.distance <= 0.0 {
            return clamp_touching(r);
        }
        if r.distance < best.distance {
            best = r;
        }
    }
    best
}

/// Exact distance between two triangle meshes (parry), `0` when they touch or cross.
fn mesh_mesh(a: &SharedShape, pose_a: &SE3, b: &SharedShape, pose_b: &SE3) -> PairDistance {
    let touching = PairDistance {
        distance: 0.0,
        witness_a: pose_a.translation,
        witness_b: pose_a.translation,
        normal: Vector3::zeros(),
    };
    match closest_points(&pose(pose_a), &*a.0, &pose(pose_b), &*b.0, f64::MAX) {
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
        // Intersecting: touching.
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
                let r = exact_distance(
                    &ex.shapes[i],
                    &gd.placements[i],
                    &ex.shapes[j],
                    &gd.placements[j],
                    &mut gd.epa,
                );
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

/// Exact distances between every link and every scene object (after
/// `update_geometry_placements`), into `sd.results` as
/// [`compute_scene_distances`](super::scene::compute_scene_distances) does for the convex
/// shapes, by the same nearest search in each object's tree (its bounds, taken from the
/// convex hulls, are lower bounds on the meshes' distances): a link mesh against a
/// primitive or a voxel is the distance from its triangles to the solid primitive (`0`
/// when a triangle touches or enters it), against a scene mesh the distance between the
/// two triangle sets. Returns the minimum and sets `sd.closest`. Allocates (parry's
/// traversal), unlike the convex queries.
pub fn compute_exact_scene_distances(
    gm: &GeometryModel,
    ex: &ExactGeometry,
    gd: &mut GeometryData,
    scene: &Scene,
    exs: &ExactScene,
    sd: &mut SceneData,
) -> f64 {
    nearest_in_scene(gm, gd, scene, sd, f64::INFINITY, |q| {
        exact_distance(
            &ex.shapes[q.object],
            q.pose,
            &exs.objects[q.scene_object][q.shape],
            &scene.objects[q.scene_object].shapes[q.shape].pose,
            q.epa,
        )
    })
}

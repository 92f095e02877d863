//! Exact distances with the triangle meshes (the `--mesh exact` option): a mesh element is
//! its triangles (not its convex hull), a primitive is itself, for the link pairs
//! ([`compute_exact_distances`]) and the (link, scene object) pairs
//! ([`compute_exact_scene_distances`], scene meshes as their triangles, primitives and
//! voxels as themselves). Each mesh keeps a bounding-volume tree over its triangles (in
//! its own frame, built once); a query descends the two trees (or the one tree against
//! the primitive's box) nearest first, skipping the node pairs whose boxes are no nearer
//! than the best distance so far, and measures the triangles left with this module's GJK
//! ([`gap_distance`]: triangles are flat convex shapes). As coal's distance between BVH
//! models, the result is the surface distance: `0` when triangles touch or cross, and
//! positive for a mesh entirely inside another one without a crossing; a primitive is
//! solid, so a mesh inside a box is at `0`, a box inside a mesh (no triangle reaching
//! it) at its distance to the nearest triangle. A query allocates nothing: the descent
//! is recursive, its depth that of the trees (about 2 log2 of the triangles per leaf).

use super::bvh::{BvhNode, box_gap, build_bvh};
use super::convex::{Convex, Triangle};
use super::geometry_data::{GeometryData, PairSelection};
use super::geometry_model::GeometryModel;
use super::gjk::{PairDistance, WarmStart, gap_distance};
use super::mesh::TriangleMesh;
use super::scene::{Scene, SceneData, nearest_in_scene};
use crate::spatial::SE3;
use crate::{Error, Result};
use nalgebra::Vector3;
use std::sync::Arc;

/// Triangles per leaf of a mesh's tree.
const TRIANGLES_PER_LEAF: usize = 4;

/// A mesh's triangles in its own frame, in the leaf order of their tree.
#[derive(Debug)]
struct MeshTree {
    triangles: Vec<Triangle>,
    nodes: Vec<BvhNode>,
}

impl MeshTree {
    fn new(mesh: &TriangleMesh) -> Self {
        let mut triangles: Vec<Triangle> = mesh
            .triangles
            .iter()
            .map(|t| Triangle(t.map(|i| mesh.vertices[i as usize])))
            .collect();
        let nodes = build_bvh(&mut triangles, TRIANGLES_PER_LEAF, Triangle::aabb);
        MeshTree { triangles, nodes }
    }
}

/// One exact shape: a mesh's triangles, or a convex primitive as itself.
#[derive(Clone, Debug)]
enum Exact {
    /// The triangles with their tree.
    Mesh(Arc<MeshTree>),
    /// A primitive (box, cylinder, sphere, capsule).
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

/// The exact shape of `shape` (with its mesh's triangles when it is a mesh's hull);
/// `what` names it in the error.
fn exact_shape(
    shape: &Convex,
    mesh: Option<&Arc<TriangleMesh>>,
    what: &dyn Fn() -> String,
) -> Result<Exact> {
    match (mesh, shape) {
        (Some(mesh), _) if mesh.triangles.is_empty() => Err(Error::invalid(
            what(),
            "no exact triangle mesh: no triangle",
        )),
        (Some(mesh), _) => Ok(Exact::Mesh(Arc::new(MeshTree::new(mesh)))),
        (None, Convex::Hull { .. }) => Err(Error::invalid(
            what(),
            "a hull without its mesh has no exact shape",
        )),
        (None, primitive) => Ok(Exact::Solid(primitive.clone())),
    }
}

impl ExactGeometry {
    /// Builds the exact shapes: each mesh element's triangles with their tree, each
    /// primitive as itself.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the link of a mesh without triangles.
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
    /// [`Error::InvalidInput`] naming the scene object of a mesh without triangles, or
    /// of a hull given without its mesh.
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
/// meshes: the nearest pair of triangles; a mesh and a primitive: the nearest triangle
/// to the solid primitive; two primitives: their distance, `0` when they overlap.
fn exact_distance(a: &Exact, pose_a: &SE3, b: &Exact, pose_b: &SE3) -> PairDistance {
    let mut search = Nearest::new(pose_a, pose_b);
    match (a, b) {
        (Exact::Mesh(ta), Exact::Mesh(tb)) => search.mesh_mesh(ta, 0, tb, 0),
        (Exact::Mesh(t), Exact::Solid(c)) => {
            let (lo, hi) = box_in(&search.b_in_a, c);
            search.mesh_solid(t, 0, c, &lo, &hi);
        }
        (Exact::Solid(c), Exact::Mesh(t)) => {
            let mut swapped = Nearest::new(pose_b, pose_a);
            let (lo, hi) = box_in(&swapped.b_in_a, c);
            swapped.mesh_solid(t, 0, c, &lo, &hi);
            let r = swapped.best;
            return PairDistance {
                witness_a: r.witness_b,
                witness_b: r.witness_a,
                normal: -r.normal,
                ..r
            };
        }
        (Exact::Solid(ca), Exact::Solid(cb)) => {
            search.best = gap_distance(ca, pose_a, cb, pose_b, &mut WarmStart::default());
        }
    }
    search.best
}

/// The box (min, max) in the mesh's frame of the primitive `c`, `to` mapping the
/// primitive's frame to the mesh's: its own box turned and enclosed.
fn box_in(to: &SE3, c: &Convex) -> (Vector3<f64>, Vector3<f64>) {
    let (centre, half) = c.local_aabb();
    let m = to.act_point(&centre);
    let r = to.rotation.abs() * half;
    (m - r, m + r)
}

/// The nearest-pair search between a mesh (A, its tree's boxes in its own frame) and a
/// mesh or primitive (B), with the best pair so far.
///
/// Two lower bounds skip a pair of boxes (or of triangles): the gap between A's box and
/// B's box turned into A's frame and enclosed, and the gap along the best pair's normal
/// `n` (from A to B), `min over B of n·x − max over A of n·x`, which holds for any unit
/// `n` and is tight near the closest features, where the boxes overlap.
struct Nearest<'a> {
    pose_a: &'a SE3,
    pose_b: &'a SE3,
    /// B's frame to A's.
    b_in_a: SE3,
    best: PairDistance,
    /// The best pair's normal in A's frame and in B's (zero before the first pair apart),
    /// and `n · (B's origin − A's origin)` in the world.
    axis_a: Vector3<f64>,
    axis_b: Vector3<f64>,
    offset: f64,
}

impl<'a> Nearest<'a> {
    fn new(pose_a: &'a SE3, pose_b: &'a SE3) -> Self {
        Nearest {
            pose_a,
            pose_b,
            b_in_a: pose_a.inverse_compose(pose_b),
            best: PairDistance {
                distance: f64::INFINITY,
                witness_a: pose_a.translation,
                witness_b: pose_b.translation,
                normal: Vector3::zeros(),
            },
            axis_a: Vector3::zeros(),
            axis_b: Vector3::zeros(),
            offset: 0.0,
        }
    }

    /// Measures one pair of shapes and keeps it when nearer (its normal the new axis).
    fn measure<B: super::convex::Support>(&mut self, t: &Triangle, b: &B) {
        let r = gap_distance(t, self.pose_a, b, self.pose_b, &mut WarmStart::default());
        if r.distance < self.best.distance {
            self.best = r;
            let n = r.normal;
            self.axis_a = self.pose_a.rotation.tr_mul(&n);
            self.axis_b = self.pose_b.rotation.tr_mul(&n);
            self.offset = n.dot(&(self.pose_b.translation - self.pose_a.translation));
        }
    }

    /// The gap along the axis between A's points whose largest `axis_a` projection is
    /// `a_max` and B's whose smallest `axis_b` projection is `b_min` (each in its frame).
    fn axis_gap(&self, a_max: f64, b_min: f64) -> f64 {
        b_min + self.offset - a_max
    }

    /// Whether a triangle of A and one of B are no nearer than the best along the axis.
    fn triangles_apart(&self, ta: &Triangle, tb: &Triangle) -> bool {
        let a_max =
            ta.0.iter()
                .map(|v| v.dot(&self.axis_a))
                .fold(f64::MIN, f64::max);
        let b_min =
            tb.0.iter()
                .map(|v| v.dot(&self.axis_b))
                .fold(f64::MAX, f64::min);
        self.axis_gap(a_max, b_min) >= self.best.distance
    }

    /// Node `na` of tree `a` against node `nb` of tree `b`: leaves' triangles pairwise,
    /// otherwise the larger node's children, the nearer (by box gap) first, each only
    /// while its gap is below the best distance.
    fn mesh_mesh(&mut self, a: &MeshTree, na: usize, b: &MeshTree, nb: usize) {
        let (x, y) = (&a.nodes[na], &b.nodes[nb]);
        match (x.leaf, y.leaf) {
            (Some((fa, ca)), Some((fb, cb))) => {
                for ta in &a.triangles[fa..fa + ca] {
                    for tb in &b.triangles[fb..fb + cb] {
                        if self.best.distance <= 0.0 {
                            return;
                        }
                        if !self.triangles_apart(ta, tb) {
                            self.measure(ta, tb);
                        }
                    }
                }
            }
            _ => {
                let split_a = y.leaf.is_some()
                    || (x.leaf.is_none() && (x.hi - x.lo).norm() >= (y.hi - y.lo).norm());
                let children = |n: &BvhNode| [n.child, n.child + 1];
                let gaps = if split_a {
                    children(x).map(|c| (self.gap(&a.nodes[c], y), c, nb))
                } else {
                    children(y).map(|c| (self.gap(x, &b.nodes[c]), na, c))
                };
                let [first, second] = if gaps[0].0 <= gaps[1].0 {
                    gaps
                } else {
                    [gaps[1], gaps[0]]
                };
                for (gap, ia, ib) in [first, second] {
                    // The axis may have changed since: the bound again.
                    if gap < self.best.distance
                        && self.gap(&a.nodes[ia], &b.nodes[ib]) < self.best.distance
                    {
                        self.mesh_mesh(a, ia, b, ib);
                    }
                }
            }
        }
    }

    /// A lower bound on the distance between a node of A's tree and a node of B's.
    fn gap(&self, x: &BvhNode, y: &BvhNode) -> f64 {
        let (cy, hy) = ((y.lo + y.hi) / 2.0, (y.hi - y.lo) / 2.0);
        let centre = self.b_in_a.act_point(&cy);
        let half = self.b_in_a.rotation.abs() * hy;
        let boxes = box_gap(&x.lo, &x.hi, &(centre - half), &(centre + half));
        let (cx, hx) = ((x.lo + x.hi) / 2.0, (x.hi - x.lo) / 2.0);
        let a_max = cx.dot(&self.axis_a) + hx.dot(&self.axis_a.abs());
        let b_min = cy.dot(&self.axis_b) - hy.dot(&self.axis_b.abs());
        boxes.max(self.axis_gap(a_max, b_min))
    }

    /// Node `n` of the mesh's tree against the primitive `c` (its box `lo`, `hi` in the
    /// mesh's frame), nearer child first.
    fn mesh_solid(
        &mut self,
        t: &MeshTree,
        n: usize,
        c: &Convex,
        lo: &Vector3<f64>,
        hi: &Vector3<f64>,
    ) {
        let node = &t.nodes[n];
        match node.leaf {
            Some((first, count)) => {
                for tri in &t.triangles[first..first + count] {
                    if self.best.distance <= 0.0 {
                        return;
                    }
                    self.measure(tri, c);
                }
            }
            None => {
                let gap = |k: usize| box_gap(&t.nodes[k].lo, &t.nodes[k].hi, lo, hi);
                let (l, r) = (node.child, node.child + 1);
                let (gl, gr) = (gap(l), gap(r));
                let order = if gl <= gr {
                    [(gl, l), (gr, r)]
                } else {
                    [(gr, r), (gl, l)]
                };
                for (g, k) in order {
                    if g < self.best.distance {
                        self.mesh_solid(t, k, c, lo, hi);
                    }
                }
            }
        }
    }
}

/// Exact distances of the selected link pairs (after `update_geometry_placements`), into
/// `gd.results` as [`compute_distances`](super::geometry_data::compute_distances) does
/// for the hulls: each link pair's minimum over its objects, the world closest points,
/// `normal` = (witness_b − witness_a) / distance (zero when touching). Returns the
/// minimum and sets `gd.closest`. Allocates nothing.
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
/// two triangle sets. Returns the minimum and sets `sd.closest`. Allocates nothing.
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
        )
    })
}

//! The robot's world: MoveIt planning-scene YAML (MotionBenchMaker's schema), 3-D
//! occupancy grids and point clouds binned into voxels, as named scene objects with a
//! bounding-volume tree each; and the link–object distance queries.

use super::bvh::{BvhNode, build_bvh};
use super::convex::Convex;
use super::geometry_data::GeometryData;
use super::geometry_model::GeometryModel;
use super::gjk::{EpaWorkspace, PairDistance, WarmStart, overlaps, signed_distance};
use super::mesh::{TriangleMesh, convex_hull_vertices, read_mesh};
use super::separating_plane::support_value;
use super::urdf_geometry::resolve_uri;
use crate::planning::grid3::Grid3;
use crate::spatial::SE3;
use crate::{Error, Result};
use nalgebra::{Quaternion, UnitQuaternion, Vector3};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// One shape of a scene object, placed in the world.
#[derive(Clone, Debug)]
pub struct SceneShape {
    /// World placement.
    pub pose: SE3,
    /// The shape.
    pub shape: Convex,
    /// World-axis-aligned bounding box (min, max).
    pub aabb: (Vector3<f64>, Vector3<f64>),
    /// For a mesh (whose `shape` is its convex hull), its triangles in the shape's frame,
    /// for exact distances ([`super::exact`]); `None` for primitives and voxels.
    pub mesh: Option<Arc<TriangleMesh>>,
}

/// A named scene object: its shapes and a bounding-volume tree over them.
#[derive(Clone, Debug)]
pub struct SceneObject {
    /// The object's `id`.
    pub id: String,
    /// Its shapes, in the tree's leaf order.
    pub shapes: Vec<SceneShape>,
    /// Robot links allowed to touch it (MoveIt's allowed-collision entries for this
    /// object): their distances to it are neither computed nor checked. Empty from
    /// [`SceneObject::new`].
    pub touch_links: Vec<String>,
    /// The tree: node `k` has box `nodes[k]`; leaves hold a range of `shapes`.
    nodes: Vec<BvhNode>,
}

/// Most shapes one scene object may hold (about 0.8 GB): bounds the memory a voxel grid
/// or point cloud can claim.
pub const MAX_SCENE_SHAPES: usize = 4_000_000;

/// Largest size and largest position coordinate (m) of a scene primitive: the distance
/// queries' fixed tolerances hold to about 1e12 m and fail beyond (a box of 1e15 m around
/// the robot reads as clear of some links), so a planning scene is bounded well inside.
pub const MAX_SCENE_LENGTH: f64 = 1e6;

/// Shapes per BVH leaf.
const LEAF_SIZE: usize = 4;

impl SceneObject {
    /// An object from world-placed shapes (builds its tree).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the object when it has no shape.
    pub fn new(id: impl Into<String>, shapes: Vec<(SE3, Convex)>) -> Result<Self> {
        Self::with_meshes(id, shapes.into_iter().map(|(p, s)| (p, s, None)).collect())
    }

    /// An object from world-placed shapes, each a mesh's convex hull with the mesh's
    /// triangles or a shape without a mesh (builds its tree).
    ///
    /// # Errors
    /// As [`SceneObject::new`].
    pub fn with_meshes(
        id: impl Into<String>,
        shapes: Vec<(SE3, Convex, Option<Arc<TriangleMesh>>)>,
    ) -> Result<Self> {
        let id = id.into();
        if shapes.is_empty() {
            return Err(Error::invalid(
                format!("scene object '{id}'"),
                "has no shape",
            ));
        }
        if shapes.len() > MAX_SCENE_SHAPES {
            return Err(Error::invalid(
                format!("scene object '{id}'"),
                format!("{} shapes, more than {MAX_SCENE_SHAPES}", shapes.len()),
            ));
        }
        let mut shapes: Vec<SceneShape> = shapes
            .into_iter()
            .map(|(pose, shape, mesh)| SceneShape {
                aabb: world_aabb(&shape, &pose),
                pose,
                shape,
                mesh,
            })
            .collect();
        let nodes = build_bvh(&mut shapes, LEAF_SIZE, |s| s.aabb);
        Ok(SceneObject {
            id,
            shapes,
            touch_links: Vec::new(),
            nodes,
        })
    }

    /// Whether the link named `link` may touch this object ([`SceneObject::touch_links`]).
    #[must_use]
    pub fn allows(&self, link: &str) -> bool {
        self.touch_links.iter().any(|l| l == link)
    }

    /// World bounding box of the whole object.
    #[must_use]
    pub fn aabb(&self) -> (Vector3<f64>, Vector3<f64>) {
        (self.nodes[0].lo, self.nodes[0].hi)
    }

    /// The shapes that may lie within `within` of the ball at `centre` of `radius`: into
    /// `near`, ranges `(first, end)` of [`SceneObject::shapes`] in increasing order
    /// (adjacent ranges joined), those of the tree's leaves whose boxes, and whose
    /// ancestors' boxes, are no farther than `within` from the ball. Every shape outside
    /// the ranges is farther than `within` from anything in the ball. `stack` is scratch.
    pub fn shapes_near(
        &self,
        centre: &Vector3<f64>,
        radius: f64,
        within: f64,
        stack: &mut Vec<usize>,
        near: &mut Vec<(usize, usize)>,
    ) {
        near.clear();
        stack.clear();
        stack.push(0);
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            if ball_box_gap(centre, radius, &node.lo, &node.hi) > within {
                continue;
            }
            match node.leaf {
                Some((first, count)) => match near.last_mut() {
                    Some(last) if last.1 == first => last.1 = first + count,
                    _ => near.push((first, first + count)),
                },
                // The first child holds the earlier shapes: popped first.
                None => stack.extend([node.child + 1, node.child]),
            }
        }
    }
}

/// World-axis-aligned bounding box (min, max) of `shape` placed at `pose`.
pub(super) fn world_aabb(shape: &Convex, pose: &SE3) -> (Vector3<f64>, Vector3<f64>) {
    let (c, h) = shape.local_aabb();
    let centre = pose.act_point(&c);
    let r = pose.rotation.abs() * h;
    (centre - r, centre + r)
}

/// Distance from a ball to a box (0 inside), a lower bound on any shape in the box.
fn ball_box_gap(c: &Vector3<f64>, r: f64, lo: &Vector3<f64>, hi: &Vector3<f64>) -> f64 {
    let d = (lo - c).sup(&(c - hi)).sup(&Vector3::zeros());
    d.norm() - r
}

/// The robot's world: scene objects.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// The objects, in file order.
    pub objects: Vec<SceneObject>,
}

impl Scene {
    /// The scene moved by `by`: every shape at `by ∘ pose`, each object keeping its
    /// shapes, their meshes and its touch links (trees rebuilt).
    ///
    /// # Errors
    /// As [`SceneObject::with_meshes`] (not for the objects of a scene built by them).
    pub fn placed(&self, by: &SE3) -> Result<Scene> {
        self.map_objects(|o| {
            o.shapes
                .iter()
                .map(|s| (by.compose(&s.pose), s.shape.clone(), s.mesh.clone()))
                .collect()
        })
    }

    /// The scene with every mesh as its triangles, each a flat convex shape at the
    /// mesh's pose (primitives and voxels kept): the convex queries then measure the
    /// meshes' surfaces, as [`super::exact`] does (`moma collision --mesh exact`),
    /// instead of their hulls. A triangle's distance is GJK's on its three vertices; the
    /// surface distance is the smallest over the triangles, and the object's tree prunes
    /// the far ones. A surface has no inside: a shape wholly inside a closed mesh is apart
    /// from it.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming an object whose triangles exceed
    /// [`MAX_SCENE_SHAPES`].
    pub fn with_mesh_triangles(&self) -> Result<Scene> {
        self.map_objects(|o| {
            let mut shapes = Vec::new();
            for s in &o.shapes {
                match &s.mesh {
                    Some(mesh) => shapes.extend(mesh.triangles.iter().map(|t| {
                        let triangle = Convex::Hull {
                            vertices: t.iter().map(|&i| mesh.vertices[i as usize]).collect(),
                            neighbours: Vec::new(),
                        };
                        (s.pose, triangle, None)
                    })),
                    None => shapes.push((s.pose, s.shape.clone(), None)),
                }
            }
            shapes
        })
    }

    /// The scene with each object's shapes replaced by `shapes(object)`, its id and touch
    /// links kept.
    fn map_objects(
        &self,
        shapes: impl Fn(&SceneObject) -> Vec<(SE3, Convex, Option<Arc<TriangleMesh>>)>,
    ) -> Result<Scene> {
        let objects = self
            .objects
            .iter()
            .map(|o| {
                let mut placed = SceneObject::with_meshes(o.id.clone(), shapes(o))?;
                placed.touch_links.clone_from(&o.touch_links);
                Ok(placed)
            })
            .collect::<Result<Vec<_>>>()?;
        Ok(Scene { objects })
    }
}

/// Workspace of the scene queries: results per (link, object) pair and warm starts.
#[derive(Clone, Debug)]
pub struct SceneData {
    /// Result per (link, object): `results[link * n_objects + object]`.
    pub results: Vec<PairDistance>,
    /// Index into `results` of the closest pair of the last `compute_scene_distances`.
    pub closest: Option<usize>,
    warm: Vec<WarmStart>,
    /// Branch-and-bound stack.
    stack: Vec<usize>,
}

impl SceneData {
    /// A workspace for `gm` against `scene`.
    #[must_use]
    pub fn new(gm: &GeometryModel, scene: &Scene) -> Self {
        let n = gm.links.len() * scene.objects.len();
        let depth = scene
            .objects
            .iter()
            .map(|o| o.nodes.len())
            .max()
            .unwrap_or(1);
        SceneData {
            results: vec![
                PairDistance {
                    distance: f64::INFINITY,
                    witness_a: Vector3::zeros(),
                    witness_b: Vector3::zeros(),
                    normal: Vector3::z(),
                };
                n
            ],
            closest: None,
            warm: vec![WarmStart::default(); n],
            stack: Vec::with_capacity(depth),
        }
    }

    /// Forgets the warm starts, so the next queries' results depend only on the state
    /// (a warm start can move a distance in its last bits).
    pub fn reset_warm_starts(&mut self) {
        self.warm.fill(WarmStart::default());
    }
}

/// Signed distances between every link and every scene object (after
/// `update_geometry_placements`), into `sd.results`; returns the minimum. A pair the
/// object allows ([`SceneObject::touch_links`]) gets `+∞`. Each
/// link–object distance is a nearest search in the object's tree: a subtree is skipped
/// when a lower bound on its distance is not below the best found so far (less
/// [`PRUNE_TOLERANCE`]). The bound is the larger of the gap between the shape's bounding
/// ball and the subtree's box, and the separating-axis gap along the normal of the
/// current best (at first the previous query's): `min over the box of n·x` minus the
/// shape's support value along n — tight for a wall or floor of voxels, where every
/// voxel of a layer is equally far along the normal.
pub fn compute_scene_distances(
    gm: &GeometryModel,
    gd: &mut GeometryData,
    scene: &Scene,
    sd: &mut SceneData,
) -> f64 {
    compute_scene_distances_below(gm, gd, scene, sd, f64::INFINITY)
}

/// [`compute_scene_distances`] for the link–object pairs closer than `cutoff` (m): the
/// search starts with `cutoff` as its best distance, so a link whose bounding balls are
/// at least `cutoff` from an object costs one ball–box test and no distance query. A
/// pair at `cutoff` or farther gets a distance of `+∞` (it is not the closest); the
/// others get the same distance as with no cutoff.
pub fn compute_scene_distances_below(
    gm: &GeometryModel,
    gd: &mut GeometryData,
    scene: &Scene,
    sd: &mut SceneData,
    cutoff: f64,
) -> f64 {
    nearest_in_scene(gm, gd, scene, sd, cutoff, |q| {
        let s = &scene.objects[q.scene_object].shapes[q.shape];
        signed_distance(
            &gm.objects[q.object].shape,
            q.pose,
            &s.shape,
            &s.pose,
            q.warm,
            q.epa,
        )
    })
}

/// One distance query of [`nearest_in_scene`]: robot object `object` (index into
/// `GeometryModel::objects`) at `pose` against shape `shape` of scene object
/// `scene_object`, with that link–object pair's warm start and the EPA buffers.
pub(super) struct LeafQuery<'a> {
    pub object: usize,
    pub pose: &'a SE3,
    pub scene_object: usize,
    pub shape: usize,
    pub warm: &'a mut WarmStart,
    pub epa: &'a mut EpaWorkspace,
}

/// The branch-and-bound nearest search of [`compute_scene_distances_below`] with the
/// distance of one robot object to one scene shape given by `leaf` (GJK/EPA on the
/// convex shapes, or the exact triangle-mesh distance of [`super::exact`]). The bounds
/// are those of the robot object's convex shape (its bounding ball, its support value
/// along an axis), lower bounds on the distance of anything inside it, so `leaf` may
/// measure any shape that lies within the convex one.
pub(super) fn nearest_in_scene(
    gm: &GeometryModel,
    gd: &mut GeometryData,
    scene: &Scene,
    sd: &mut SceneData,
    cutoff: f64,
    mut leaf: impl FnMut(LeafQuery<'_>) -> PairDistance,
) -> f64 {
    let no = scene.objects.len();
    let mut min = f64::INFINITY;
    sd.closest = None;
    for (l, link) in gm.links.iter().enumerate() {
        for (o, obj) in scene.objects.iter().enumerate() {
            let k = l * no + o;
            if obj.allows(&link.name) {
                sd.results[k].distance = f64::INFINITY;
                continue;
            }
            let mut best = PairDistance {
                distance: cutoff,
                witness_a: Vector3::zeros(),
                witness_b: Vector3::zeros(),
                normal: Vector3::z(),
            };
            // The axis of the separating-axis bound: the last query's normal to start
            // (only worth a support climb when the object has several shapes to skip).
            let many = obj.shapes.len() > 1;
            let mut axis = sd.results[k].normal;
            if !(many && axis.iter().all(|x| x.is_finite()) && (axis.norm() - 1.0).abs() < 1e-9) {
                axis = Vector3::zeros();
            }
            for i in link.first..link.first + link.count {
                let go = &gm.objects[i];
                let pose = gd.placements[i];
                let c = pose.act_point(&go.bounding_centre);
                let mut hint = sd.warm[k].hint_a;
                // No axis: a bound of −∞.
                let mut reach = if axis == Vector3::zeros() {
                    f64::INFINITY
                } else {
                    support_value(&go.shape, &pose, &axis, &mut hint)
                };
                let bound =
                    |axis: &Vector3<f64>, reach: f64, lo: &Vector3<f64>, hi: &Vector3<f64>| {
                        ball_box_gap(&c, go.bounding_radius, lo, hi)
                            .max(box_min_along(axis, lo, hi) - reach)
                    };
                sd.stack.clear();
                sd.stack.push(0);
                while let Some(n) = sd.stack.pop() {
                    let node = &obj.nodes[n];
                    if bound(&axis, reach, &node.lo, &node.hi) >= best.distance - PRUNE_TOLERANCE {
                        continue;
                    }
                    match node.leaf {
                        Some((first, count)) => {
                            for (si, s) in obj.shapes[first..first + count].iter().enumerate() {
                                if bound(&axis, reach, &s.aabb.0, &s.aabb.1)
                                    >= best.distance - PRUNE_TOLERANCE
                                {
                                    continue;
                                }
                                let r = leaf(LeafQuery {
                                    object: i,
                                    pose: &pose,
                                    scene_object: o,
                                    shape: first + si,
                                    warm: &mut sd.warm[k],
                                    epa: &mut gd.epa,
                                });
                                if r.distance < best.distance {
                                    best = r;
                                    // Apart, the normal separates the robot object
                                    // from the shapes beyond the best one's distance.
                                    if many && r.distance > 0.0 {
                                        axis = r.normal;
                                        reach = support_value(&go.shape, &pose, &axis, &mut hint);
                                    }
                                }
                            }
                        }
                        None => {
                            // Nearer child last, so it is searched first.
                            let (a, b) = (node.child, node.child + 1);
                            let ga = ball_box_gap(&c, 0.0, &obj.nodes[a].lo, &obj.nodes[a].hi);
                            let gb = ball_box_gap(&c, 0.0, &obj.nodes[b].lo, &obj.nodes[b].hi);
                            if ga < gb {
                                sd.stack.extend([b, a]);
                            } else {
                                sd.stack.extend([a, b]);
                            }
                        }
                    }
                }
            }
            if best.distance >= cutoff {
                best.distance = f64::INFINITY;
            }
            sd.results[k] = best;
            if best.distance < min {
                min = best.distance;
                sd.closest = Some(k);
            }
        }
    }
    min
}

/// How much a skipped subtree may undercut the best distance of
/// [`compute_scene_distances`] (m): the reported minimum is within this of the exact one
/// (ties between the voxels of a flat layer are skipped instead of all visited).
pub const PRUNE_TOLERANCE: f64 = 1e-12;

/// `min over the box [lo, hi] of n·x`.
fn box_min_along(n: &Vector3<f64>, lo: &Vector3<f64>, hi: &Vector3<f64>) -> f64 {
    (0..3)
        .map(|k| n[k] * if n[k] >= 0.0 { lo[k] } else { hi[k] })
        .sum()
}

/// Whether some link overlaps some scene object, stopping at the first overlap: the
/// `(link, object)` indices. Pairs the object allows ([`SceneObject::touch_links`]) are
/// skipped.
pub fn scene_collision(
    gm: &GeometryModel,
    gd: &GeometryData,
    scene: &Scene,
    sd: &mut SceneData,
) -> Option<(usize, usize)> {
    let no = scene.objects.len();
    for (l, link) in gm.links.iter().enumerate() {
        for (o, obj) in scene.objects.iter().enumerate() {
            let k = l * no + o;
            if obj.allows(&link.name) {
                continue;
            }
            // A separating axis to start with: the last distance query's normal.
            let mut axis = sd.results[k].normal;
            if !(axis.iter().all(|x| x.is_finite()) && (axis.norm() - 1.0).abs() < 1e-9) {
                axis = Vector3::z();
            }
            for i in link.first..link.first + link.count {
                let go = &gm.objects[i];
                let pose = gd.placements[i];
                let c = pose.act_point(&go.bounding_centre);
                let mut hint = sd.warm[k].hint_a;
                let reach = support_value(&go.shape, &pose, &axis, &mut hint);
                let apart = |lo: &Vector3<f64>, hi: &Vector3<f64>| {
                    ball_box_gap(&c, go.bounding_radius, lo, hi) > 0.0
                        || box_min_along(&axis, lo, hi) - reach > 0.0
                };
                sd.stack.clear();
                sd.stack.push(0);
                while let Some(n) = sd.stack.pop() {
                    let node = &obj.nodes[n];
                    if apart(&node.lo, &node.hi) {
                        continue;
                    }
                    match node.leaf {
                        Some((first, count)) => {
                            for s in &obj.shapes[first..first + count] {
                                if !apart(&s.aabb.0, &s.aabb.1)
                                    && overlaps(
                                        &go.shape,
                                        &pose,
                                        &s.shape,
                                        &s.pose,
                                        &mut sd.warm[k],
                                    )
                                {
                                    return Some((l, o));
                                }
                            }
                        }
                        None => sd.stack.extend([node.child, node.child + 1]),
                    }
                }
            }
        }
    }
    None
}

// ---- MoveIt planning-scene YAML ------------------------------------------------------

#[derive(Deserialize)]
struct RawScene {
    world: Option<RawWorld>,
}

#[derive(Deserialize)]
struct RawWorld {
    #[serde(default)]
    collision_objects: Vec<RawObject>,
}

#[derive(Deserialize)]
struct RawHeader {
    frame_id: Option<String>,
}

#[derive(Deserialize)]
struct RawPose {
    position: Vec<f64>,
    orientation: Vec<f64>,
}

#[derive(Deserialize)]
struct RawPrimitive {
    #[serde(rename = "type")]
    kind: String,
    dimensions: Vec<f64>,
}

#[derive(Deserialize)]
struct RawMesh {
    resource: String,
}

#[derive(Deserialize)]
struct RawObject {
    header: Option<RawHeader>,
    id: String,
    #[serde(default)]
    primitives: Vec<RawPrimitive>,
    #[serde(default)]
    primitive_poses: Vec<RawPose>,
    #[serde(default)]
    meshes: Vec<RawMesh>,
    #[serde(default)]
    mesh_poses: Vec<RawPose>,
}

/// Where scene poses may be expressed: frame names that mean the world.
#[derive(Clone, Debug)]
pub struct SceneOptions {
    /// Frame names taken as the world frame (the robot's root link with a fixed base,
    /// `world`, `map`...). A pose in any other frame is an error naming it.
    pub world_frames: Vec<String>,
    /// Folders against which `package://` mesh URIs resolve.
    pub package_dirs: Vec<PathBuf>,
}

/// Reads a MoveIt planning-scene YAML file (MotionBenchMaker's `scene_*.yaml`).
///
/// # Errors
/// [`Error::Io`] if unreadable; [`Error::Parse`] naming the file and the object (by its
/// `id` and position) for malformed YAML, an unknown primitive type, a wrong number or a
/// non-positive dimension, a malformed pose, an unknown frame, or a mesh that does not
/// resolve or load.
pub fn read_scene(path: &Path, opts: &SceneOptions) -> Result<Scene> {
    let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    scene_from_str(&text, path, opts)
}

/// Parses planning-scene YAML text; `path` names it in errors and anchors relative mesh
/// URIs.
///
/// # Errors
/// As [`read_scene`].
pub fn scene_from_str(text: &str, path: &Path, opts: &SceneOptions) -> Result<Scene> {
    // An XML file (MotionBenchMaker's kitchen and table_bars scenes are URDFs) is no YAML:
    // say what it is rather than quote the YAML parser's first complaint.
    if text.trim_start().starts_with('<') {
        let what = if text.contains("<robot") {
            "a URDF"
        } else {
            "XML"
        };
        return Err(Error::parse(
            path,
            format!(
                "is {what}, not a planning-scene YAML: give a URDF scene's links as \
                 collision_objects with meshes and mesh_poses (the links' poses at the \
                 scene's joint values)"
            ),
        ));
    }
    let raw: RawScene = serde_saphyr::from_str(text)
        .map_err(|e| Error::parse(path, format!("malformed planning-scene YAML: {e}")))?;
    let mut scene = Scene::default();
    let dir = path.parent().unwrap_or(Path::new("."));
    for (k, o) in raw
        .world
        .map(|w| w.collision_objects)
        .unwrap_or_default()
        .iter()
        .enumerate()
    {
        let at = |m: String| {
            Error::parse(
                path,
                format!("world.collision_objects[{k}] (id '{}'): {m}", o.id),
            )
        };
        let frame = o
            .header
            .as_ref()
            .and_then(|h| h.frame_id.clone())
            .unwrap_or_else(|| "world".into());
        if !opts.world_frames.contains(&frame) {
            return Err(at(format!(
                "unknown frame '{frame}' (known: {})",
                opts.world_frames.join(", ")
            )));
        }
        if o.primitives.len() != o.primitive_poses.len() {
            return Err(at(format!(
                "{} primitives but {} primitive_poses",
                o.primitives.len(),
                o.primitive_poses.len()
            )));
        }
        if o.meshes.len() != o.mesh_poses.len() {
            return Err(at(format!(
                "{} meshes but {} mesh_poses",
                o.meshes.len(),
                o.mesh_poses.len()
            )));
        }
        let mut shapes = Vec::new();
        for (i, (p, pose)) in o.primitives.iter().zip(&o.primitive_poses).enumerate() {
            let pose = parse_pose(pose).map_err(|m| at(format!("primitive_poses[{i}]: {m}")))?;
            let shape = primitive(p).map_err(|m| at(format!("primitives[{i}]: {m}")))?;
            shapes.push((pose, shape, None));
        }
        for (i, (m, pose)) in o.meshes.iter().zip(&o.mesh_poses).enumerate() {
            let pose = parse_pose(pose).map_err(|e| at(format!("mesh_poses[{i}]: {e}")))?;
            let file = resolve_uri(&m.resource, dir, &opts.package_dirs)
                .map_err(|e| at(format!("meshes[{i}]: {e}")))?;
            let mesh = read_mesh(&file, [1.0; 3]).map_err(|e| at(format!("meshes[{i}]: {e}")))?;
            let hull = convex_hull_vertices(&mesh.vertices);
            shapes.push((
                pose,
                Convex::Hull {
                    vertices: hull.vertices,
                    neighbours: hull.neighbours,
                },
                Some(Arc::new(mesh)),
            ));
        }
        if shapes.is_empty() {
            return Err(at("has no primitive and no mesh".into()));
        }
        scene
            .objects
            .push(SceneObject::with_meshes(o.id.clone(), shapes)?);
    }
    Ok(scene)
}

fn parse_pose(p: &RawPose) -> std::result::Result<SE3, String> {
    let (Ok(t), Ok(q)) = (
        <[f64; 3]>::try_from(p.position.as_slice()),
        <[f64; 4]>::try_from(p.orientation.as_slice()),
    ) else {
        return Err("position must be [x, y, z] and orientation [x, y, z, w]".into());
    };
    if t.iter().chain(&q).any(|x| !x.is_finite()) {
        return Err("pose is not finite".into());
    }
    if let Some(x) = t.iter().find(|x| x.abs() > MAX_SCENE_LENGTH) {
        return Err(format!(
            "position coordinate {x:e} m is beyond ±{MAX_SCENE_LENGTH:e} m"
        ));
    }
    let norm = q.iter().map(|x| x * x).sum::<f64>().sqrt();
    if (norm - 1.0).abs() > 1e-3 {
        return Err(format!(
            "orientation {q:?} is not a unit quaternion (norm {norm})"
        ));
    }
    let r = UnitQuaternion::from_quaternion(Quaternion::new(q[3], q[0], q[1], q[2]));
    Ok(SE3::new(
        r.to_rotation_matrix().into_inner(),
        Vector3::from(t),
    ))
}

fn primitive(p: &RawPrimitive) -> std::result::Result<Convex, String> {
    let d = &p.dimensions;
    let need = |n: usize| {
        if d.len() != n {
            return Err(format!("{} needs {n} dimensions, got {}", p.kind, d.len()));
        }
        if let Some(x) = d.iter().find(|x| !(x.is_finite() && **x > 0.0)) {
            return Err(format!("{} dimension {x} must be finite and > 0", p.kind));
        }
        if let Some(x) = d.iter().find(|x| **x > MAX_SCENE_LENGTH) {
            return Err(format!(
                "{} dimension {x:e} m is larger than {MAX_SCENE_LENGTH:e} m",
                p.kind
            ));
        }
        Ok(())
    };
    Ok(match p.kind.as_str() {
        "box" => {
            need(3)?;
            Convex::Box {
                half: Vector3::new(d[0], d[1], d[2]) / 2.0,
            }
        }
        "cylinder" => {
            need(2)?;
            Convex::Cylinder {
                radius: d[1],
                half_height: d[0] / 2.0,
            }
        }
        "sphere" => {
            need(1)?;
            Convex::Sphere { radius: d[0] }
        }
        other => {
            return Err(format!(
                "unsupported primitive type '{other}' (box, cylinder, sphere)"
            ));
        }
    })
}

// ---- voxels ----------------------------------------------------------------------------

/// A scene object of the blocked cells of a 3-D occupancy grid: one box per cell, cell
/// `(x, y, z)` centred at `origin + (x + ½, y + ½, z + ½)·resolution`.
///
/// # Errors
/// [`Error::InvalidInput`] for a non-positive or non-finite resolution, a non-finite
/// origin, or a grid with no blocked cell.
pub fn voxel_object(
    id: &str,
    grid: &Grid3,
    resolution: f64,
    origin: Vector3<f64>,
) -> Result<SceneObject> {
    if !(resolution.is_finite() && resolution > 0.0) || origin.iter().any(|x| !x.is_finite()) {
        return Err(Error::invalid(
            format!("scene object '{id}'"),
            format!("resolution {resolution} must be > 0 and the origin finite"),
        ));
    }
    if grid.blocked_count() > MAX_SCENE_SHAPES {
        return Err(Error::invalid(
            format!("scene object '{id}'"),
            format!(
                "{} blocked voxels, more than {MAX_SCENE_SHAPES}",
                grid.blocked_count()
            ),
        ));
    }
    let half = Vector3::repeat(resolution / 2.0);
    let mut shapes = Vec::with_capacity(grid.blocked_count());
    for z in 0..grid.nz {
        for y in 0..grid.ny {
            for x in 0..grid.nx {
                if grid.is_blocked(x as i64, y as i64, z as i64) {
                    let c = origin
                        + Vector3::new(x as f64 + 0.5, y as f64 + 0.5, z as f64 + 0.5) * resolution;
                    shapes.push((SE3::from_translation(c), Convex::Box { half }));
                }
            }
        }
    }
    SceneObject::new(id, shapes)
}

/// A scene object of the voxels (edge `resolution`, on the grid anchored at the world
/// origin) that hold at least one of `points` (a point cloud binned into voxels).
///
/// # Errors
/// [`Error::InvalidInput`] for a non-positive resolution, a non-finite point (naming its
/// index) or no point.
pub fn point_cloud_object(
    id: &str,
    points: &[Vector3<f64>],
    resolution: f64,
) -> Result<SceneObject> {
    if !(resolution.is_finite() && resolution > 0.0) {
        return Err(Error::invalid(
            format!("scene object '{id}'"),
            format!("resolution {resolution} must be > 0"),
        ));
    }
    if let Some(i) = points.iter().position(|p| p.iter().any(|x| !x.is_finite())) {
        return Err(Error::invalid(
            format!("scene object '{id}' point {i}"),
            "not finite",
        ));
    }
    let mut cells: Vec<[i64; 3]> = points
        .iter()
        .map(|p| [0, 1, 2].map(|k| (p[k] / resolution).floor() as i64))
        .collect();
    cells.sort_unstable();
    cells.dedup();
    let half = Vector3::repeat(resolution / 2.0);
    let shapes = cells
        .iter()
        .map(|c| {
            let centre =
                Vector3::new(c[0] as f64 + 0.5, c[1] as f64 + 0.5, c[2] as f64 + 0.5) * resolution;
            (SE3::from_translation(centre), Convex::Box { half })
        })
        .collect();
    SceneObject::new(id, shapes)
}

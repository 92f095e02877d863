//! The pick task of a mission (`[task]`): a MoveIt scene placed on the map, the object to
//! pick with its grasp and mass, and what the run needs of them.
//!
//! At load ([`load_task`]): the scene is read (poses in its own frame, `world` or the
//! robot's root link) and placed on the map at `task.pose` ([`Scene::placed`], meshes
//! kept), its meshes as their triangles with `task.mesh = "exact"`
//! ([`Scene::with_mesh_triangles`]: the one scene of the placement, the planner and the
//! monitor); the grasp comes from a
//! MotionBenchMaker goal query or an offset from the object; the robot's collision
//! geometry is read with the SRDF's disabled pairs; the joint group is the end effector's
//! arm chain; the robot with the object as a point mass on the grasp frame's body is
//! built for after the grasp. The outline on the ground of each scene object the robot
//! cannot pass under at its transport posture blocks the map cells it covers
//! ([`super::heights::block_by_height`]: a table top the robot clears is left off), and
//! such an object where the footprint stands at the start is an input error naming it.
//!
//! The object is attached to the end effector's geometry once ([`Task::carried`]): the
//! transport posture is checked with it at load, the lift and the retreat are planned
//! with it, the distance monitor measures with it after the grasp, and the drive on's
//! footprint holds its outline at the transport posture ([`Task::carrying_footprint`]).
//!
//! In the run (`run.rs`): [`Task::placements`] ranks the base poses
//! ([`crate::motion::placement::place_base`]), the run drives to the best one its planner
//! reaches, plans and tracks the arm motions, attaches the payload, and monitors the
//! distances of the executed motion at every control step ([`DistanceMonitor`]; during
//! the lift the held object against its support by the lift rule, [`LiftStart`]).

use std::path::{Path, PathBuf};

use nalgebra::{DVector, Isometry3, Quaternion, Translation3, UnitQuaternion, Vector2, Vector3};
use serde::{Deserialize, Serialize};

use super::arm_scene::{polygon_distance, scene_with};
use crate::collision::footprint::hull_2d;
use crate::collision::gjk::{EpaWorkspace, WarmStart, signed_distance};
use crate::collision::{
    GeometryData, GeometryModel, GeometryOptions, PairSelection, Scene, SceneData, SceneObject,
    SceneOptions, compute_distances, compute_scene_distances, outline_points, read_scene,
    update_geometry_placements,
};
use crate::error::{Error, Result};
use crate::mobile::WheeledModel;
use crate::motion::grasp_query::read_grasp_query;
use crate::motion::placement::{
    Payload, Placement, PlacementOptions, PlacementProblem, place_base,
};
use crate::motion::{GoalPose, JointGroup, MeshSource, surface_links_for_states};
use crate::multibody::{Data, FrameIndex, FrameKind, JointType};
use crate::spatial::{Inertia, SE3};
use crate::stability::SupportPolygon;

/// `[task]` as written.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TaskSpec {
    /// MoveIt planning-scene YAML (MotionBenchMaker's schema), relative to the mission
    /// file; poses in `world` or the robot's root link, both meaning the scene's frame.
    pub scene: PathBuf,
    /// The scene's frame on the map `[x, y, yaw]` (m, rad).
    pub pose: [f64; 3],
    /// The object to pick: a scene object's id (one shape).
    pub object: String,
    /// A MotionBenchMaker query file whose goal query `query_index` is the grasp of the
    /// end effector (relative to the mission file); or `grasp`.
    #[serde(default)]
    pub query: Option<PathBuf>,
    /// Which goal query of `query` (from 0).
    #[serde(default)]
    pub query_index: usize,
    /// The grasp as the end effector's pose in the object's frame
    /// `[x, y, z, qx, qy, qz, qw]` (tolerances 0.01 m, 0.01 rad); or `query`.
    #[serde(default)]
    pub grasp: Option<[f64; 7]>,
    /// The object's mass (kg).
    pub mass: f64,
    /// SRDF whose disabled pairs the arm's collision checks skip (relative to the mission
    /// file).
    #[serde(default)]
    pub srdf: Option<PathBuf>,
    /// Base positions the placement searches `[x0, y0, x1, y1]` (map frame, m); default:
    /// the square around the grasp as wide as the arm's reach.
    #[serde(default)]
    pub area: Option<[f64; 4]>,
    /// Placement grid step (m).
    #[serde(default = "default_step")]
    pub step: f64,
    /// Placement headings per grid cell.
    #[serde(default = "default_headings")]
    pub headings: usize,
    /// The pre-grasp: the grasp moved back this far along the end effector's x axis (m).
    #[serde(default = "default_approach")]
    pub approach: f64,
    /// The lift: the grasp moved up this far (world z, m), the object's support allowed
    /// to touch it on the way.
    #[serde(default = "default_lift")]
    pub lift: f64,
    /// Longest planning time of each arm motion (s).
    #[serde(default = "default_planning_time")]
    pub planning_time: f64,
    /// Seed of the placement's IK seeds and of the arm planner.
    #[serde(default)]
    pub seed: u64,
    /// How the scene's meshes enter the pick's distances (the placement's, the arm
    /// planner's and the distance monitor's), as `moma collision --mesh`: `"convex"`
    /// (default), each mesh as its convex hull; `"exact"`, each mesh as its triangles
    /// ([`Scene::with_mesh_triangles`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<String>,
}

fn default_step() -> f64 {
    0.1
}
fn default_headings() -> usize {
    16
}
fn default_approach() -> f64 {
    0.1
}
fn default_lift() -> f64 {
    0.05
}
fn default_planning_time() -> f64 {
    5.0
}

/// The tolerances of a `grasp` offset (m, rad): those of a query without its own.
const GRASP_TOLERANCE: [f64; 2] = [0.01, 0.01];
/// The clearance every arm-plan state keeps from the scene and between links (m).
pub const ARM_MARGIN: f64 = 0.005;

/// A validated task, ready for the run.
#[derive(Debug, Clone)]
pub struct Task {
    /// The scene placed on the map (world frame).
    pub scene: Scene,
    /// The scene without the picked object (the object travels with the gripper): the
    /// retreat's.
    pub scene_after_grasp: Scene,
    /// The same with the object's support ([`Task::support`]) allowed to touch the held
    /// object: the lift's.
    pub scene_lifting: Scene,
    /// The scene objects the picked object rests on or in at its scene pose: those within
    /// the grasp's position tolerance of it (the held object may sit that far off its
    /// scene pose once grasped). During the lift their pairs with the held object are left
    /// out of the scene check (MoveIt's support surface of a pick) and checked by the lift
    /// rule instead ([`LiftStart`]).
    pub support: Vec<String>,
    /// The map's boxes (`[[map.boxes]]`, named `map.boxes[k]`, world frame) the robot can
    /// reach from a placement ([`super::arm_scene::boxes_near_pick`]): the placement
    /// search, the arm planner and the arm phases' distance monitor measure them after
    /// the scene's objects. Set by the mission's load (empty from [`load_task`]).
    pub boxes: Vec<SceneObject>,
    /// The scene as read, in its own frame (for the report).
    pub scene_pose: [f64; 3],
    /// Per object of `scene` (in its order), the 3-D check of its height range against
    /// the robot at the transport posture; the blocked ones are on the map
    /// ([`super::heights::block_by_height`]).
    pub heights: Vec<super::heights::BoxVerdict>,
    /// The picked object's id.
    pub object: String,
    /// The grasp of the end effector (world).
    pub grasp: GoalPose,
    /// The pre-grasp: the grasp moved back along the end effector's x axis.
    pub pre_grasp: GoalPose,
    /// The lift: the grasp moved up (world z).
    pub lift: GoalPose,
    /// The object's centre in the grasp frame (m).
    pub object_in_grasp: Vector3<f64>,
    /// The object's mass (kg).
    pub mass: f64,
    /// The robot's collision geometry (with the SRDF's disabled pairs), the links whose
    /// hulls touch at the transport posture swapped for their mesh surfaces: the arm
    /// planner's and the distance monitor's.
    pub geometry: GeometryModel,
    /// The same with convex hulls only: the placement search's (a grasping posture clear
    /// of the hulls is clear of the meshes inside them).
    pub hull_geometry: GeometryModel,
    /// `geometry` with the picked object as one more link (the last), fixed to the end
    /// effector's body at the grasp (`carried_geometry`): what the lift and the retreat
    /// are planned with and the distance monitor measures once the object is grasped.
    pub carried: GeometryModel,
    /// The drive on's footprint: the mission's with the held object at the transport
    /// posture ([`super::footprint::MissionFootprint::carrying`]).
    pub carrying_footprint: super::footprint::MissionFootprint,
    /// The joints that reach: the end effector's arm chain.
    pub group: JointGroup,
    /// The robot with the object as a point mass on the grasp frame's body.
    pub payload_robot: WheeledModel,
    /// The placement search's options.
    pub placement: PlacementOptions,
    /// Longest planning time per arm motion (s).
    pub planning_time: f64,
    /// The arm planner's seed.
    pub seed: u64,
}

fn field_err(path: &Path, field: &str, msg: impl std::fmt::Display) -> Error {
    Error::parse(path, format!("{field}: {msg}"))
}

/// Loads `[task]`: the scene on the map, the grasp, the geometry, the group and the
/// payload robot (module docs). `transport` is the transport posture (one angle per arm
/// dof): links whose convex hulls touch there are swapped for their mesh surfaces
/// ([`crate::motion::surface_links_for_states`], as `moma motion` does at its start), so
/// the posture the arm leaves from and returns to is clear. The robot's geometry carrying
/// the object is built once, checked at the transport posture, and `footprint` (the
/// mission's) grown by the object's outline there for the drive on.
///
/// # Errors
/// Naming the file and the `task.*` field: an unreadable scene, query or SRDF, an
/// unknown object (listing the scene's), both or neither of `query` and `grasp`, a query
/// for another object, a non-finite pose or grasp, a mass that is not ≥ 0, a step,
/// heading count, approach, lift or planning time out of range, an area of the wrong shape, a
/// scene object where the footprint stands at the start, a `mesh` other than `"convex"`
/// and `"exact"`.
#[allow(clippy::too_many_arguments)]
pub fn load_task(
    spec: &TaskSpec,
    path: &Path,
    base: &Path,
    robot: &WheeledModel,
    ee_frame: FrameIndex,
    transport: &[f64],
    urdf: &Path,
    package_dirs: &[PathBuf],
    geometry: GeometryModel,
    footprint: &super::footprint::MissionFootprint,
) -> Result<Task> {
    check_numbers(spec, path)?;
    let exact = exact_meshes(spec, path)?;
    let model = &robot.model;
    let mut world_frames = vec!["world".to_string()];
    if let Some(f) = model.frames.iter().find(|f| f.kind == FrameKind::Body) {
        world_frames.push(f.name.clone());
    }
    let local = read_scene(
        &base.join(&spec.scene),
        &SceneOptions {
            world_frames,
            package_dirs: package_dirs.to_vec(),
        },
    )
    .map_err(|e| field_err(path, "task.scene", e))?;
    let on_map = SE3::from_xyz_rpy([spec.pose[0], spec.pose[1], 0.0], [0.0, 0.0, spec.pose[2]]);
    let scene = local
        .placed(&on_map)
        .map_err(|e| field_err(path, "task.scene", e))?;
    let scene = if exact {
        scene
            .with_mesh_triangles()
            .map_err(|e| field_err(path, "task.mesh", e))?
    } else {
        scene
    };
    let Some(obj) = scene.objects.iter().find(|o| o.id == spec.object) else {
        let ids: Vec<&str> = scene.objects.iter().map(|o| o.id.as_str()).collect();
        return Err(field_err(
            path,
            "task.object",
            format!(
                "'{}' is not in the scene (its objects: {})",
                spec.object,
                ids.join(", ")
            ),
        ));
    };
    let (target, tolerance, object_in_grasp) = match (&spec.query, &spec.grasp) {
        (Some(_), Some(_)) | (None, None) => {
            return Err(field_err(
                path,
                "task.query",
                "give the grasp either as a query file (task.query) or as task.grasp, one of them",
            ));
        }
        (Some(q), None) => {
            let g = read_grasp_query(&base.join(q), spec.query_index, &scene)
                .map_err(|e| field_err(path, "task.query", e))?;
            if g.object != spec.object {
                return Err(field_err(
                    path,
                    "task.query",
                    format!(
                        "goal query {} grasps '{}', not task.object '{}'",
                        spec.query_index, g.object, spec.object
                    ),
                ));
            }
            (
                g.target,
                [g.position_tolerance, g.orientation_tolerance],
                g.object_in_grasp,
            )
        }
        (None, Some(g)) => {
            let [shape] = obj.shapes.as_slice() else {
                return Err(field_err(
                    path,
                    "task.object",
                    format!(
                        "'{}' has {} shapes; a grasp offset is taken from the pose of its one shape",
                        spec.object,
                        obj.shapes.len()
                    ),
                ));
            };
            let quat = Quaternion::new(g[6], g[3], g[4], g[5]);
            if quat.norm() < 1e-9 {
                return Err(field_err(path, "task.grasp", "a zero quaternion"));
            }
            let offset = Isometry3::from_parts(
                Translation3::new(g[0], g[1], g[2]),
                UnitQuaternion::from_quaternion(quat),
            );
            (
                shape.pose.to_isometry() * offset,
                GRASP_TOLERANCE,
                offset.inverse().translation.vector,
            )
        }
    };
    let grasp = GoalPose {
        frame: ee_frame,
        target,
        position_tolerance: tolerance[0],
        orientation_tolerance: tolerance[1],
    };
    let pre_grasp = GoalPose {
        target: target * Translation3::new(-spec.approach, 0.0, 0.0),
        ..grasp.clone()
    };
    let lift = GoalPose {
        target: Translation3::new(0.0, 0.0, spec.lift) * target,
        ..grasp.clone()
    };
    let group = JointGroup::new(
        model,
        &arm_chain(robot, ee_frame)
            .iter()
            .map(|&j| model.names[j].as_str())
            .collect::<Vec<_>>(),
    )
    .map_err(|e| field_err(path, "robot.end_effector", e))?;
    let posture = super::plant::start_configuration(robot, [0.0; 3], transport);
    let hull_geometry = geometry;
    let (geometry, _) = surface_links_for_states(
        model,
        &hull_geometry,
        &Scene::default(),
        &group,
        &[&posture],
        ARM_MARGIN,
        &MeshSource {
            urdf: urdf.to_path_buf(),
            package_dirs: package_dirs.to_vec(),
        },
    )
    .map_err(|e| field_err(path, "robot.transport_posture (mesh surfaces)", e))?;
    let grasp_pose = SE3::from_isometry(&target);
    let carried = carried_geometry(model, &geometry, ee_frame, obj, &grasp_pose)
        .map_err(|e| field_err(path, "task.object", e))?;
    if let Some((link, depth)) = carried_object_touch(model, &carried, &posture) {
        return Err(field_err(
            path,
            "robot.transport_posture",
            format!(
                "with '{}' held at its grasp (task.object, task.grasp) the object enters \
                 '{link}' by {:.1} mm at this posture: choose a transport posture (or a \
                 grasp) that holds it clear of the robot",
                obj.id,
                depth * 1e3
            ),
        ));
    }
    let payload_robot = with_payload(robot, ee_frame, spec.mass, &object_in_grasp);
    let support = support_of(&scene, obj, tolerance[0]);
    let mut scene_after_grasp = scene.clone();
    scene_after_grasp.objects.retain(|o| o.id != spec.object);
    let mut scene_lifting = scene_after_grasp.clone();
    for o in &mut scene_lifting.objects {
        if support.contains(&o.id) {
            o.touch_links.push(obj.id.clone());
        }
    }
    let carrying_footprint = footprint.carrying(robot, &carried, transport);
    Ok(Task {
        scene,
        scene_after_grasp,
        scene_lifting,
        support,
        boxes: Vec::new(),
        scene_pose: spec.pose,
        heights: Vec::new(),
        object: spec.object.clone(),
        grasp,
        pre_grasp,
        lift,
        object_in_grasp,
        mass: spec.mass,
        geometry,
        hull_geometry,
        carried,
        carrying_footprint,
        group,
        payload_robot,
        placement: PlacementOptions {
            area: spec.area,
            step: spec.step,
            headings: spec.headings,
            seed: spec.seed,
            ..PlacementOptions::default()
        },
        planning_time: spec.planning_time,
        seed: spec.seed,
    })
}

/// The collision geometry `[task]` plans with: the URDF's, with the SRDF's disabled pairs.
pub(super) fn task_geometry_options(
    spec: &TaskSpec,
    base: &Path,
    package_dirs: &[PathBuf],
) -> GeometryOptions {
    GeometryOptions {
        package_dirs: package_dirs.to_vec(),
        srdf: spec.srdf.as_ref().map(|s| base.join(s)),
    }
}

fn check_numbers(spec: &TaskSpec, path: &Path) -> Result<()> {
    let finite = |field: &str, xs: &[f64]| match crate::error::first_non_finite(xs) {
        Some(i) => Err(field_err(
            path,
            field,
            format!("entry {i} is not a finite number"),
        )),
        None => Ok(()),
    };
    finite("task.pose", &spec.pose)?;
    if let Some(g) = &spec.grasp {
        finite("task.grasp", g)?;
    }
    if !(spec.mass.is_finite() && spec.mass >= 0.0) {
        return Err(field_err(
            path,
            "task.mass",
            format!("{} is not a mass in kg (≥ 0)", spec.mass),
        ));
    }
    for (field, v) in [
        ("task.step", spec.step),
        ("task.planning_time", spec.planning_time),
        ("task.lift", spec.lift),
    ] {
        if let Some(problem) = crate::error::not_positive_finite(v) {
            return Err(field_err(path, field, problem));
        }
    }
    if !(spec.approach.is_finite() && spec.approach >= 0.0) {
        return Err(field_err(
            path,
            "task.approach",
            format!("{} is not a distance ≥ 0", spec.approach),
        ));
    }
    if spec.headings == 0 {
        return Err(field_err(path, "task.headings", "must be at least 1"));
    }
    if let Some(a) = &spec.area {
        finite("task.area", a)?;
        if a[2] <= a[0] || a[3] <= a[1] {
            return Err(field_err(
                path,
                "task.area",
                format!("expected [x0, y0, x1, y1] with x0 < x1 and y0 < y1, got {a:?}"),
            ));
        }
    }
    Ok(())
}

/// Whether `task.mesh` asks for the meshes' triangles (`"exact"`) rather than their hulls
/// (`"convex"`, the default).
fn exact_meshes(spec: &TaskSpec, path: &Path) -> Result<bool> {
    match spec.mesh.as_deref() {
        None | Some("convex") => Ok(false),
        Some("exact") => Ok(true),
        Some(other) => Err(field_err(
            path,
            "task.mesh",
            format!("'{other}' is not a mesh mode (\"convex\" or \"exact\")"),
        )),
    }
}

/// The joints of the chain from the base to the end effector that the mission's arm
/// holds (the torso and arm; not the planar root), root side first.
pub(super) fn arm_chain(robot: &WheeledModel, ee_frame: FrameIndex) -> Vec<usize> {
    let model = &robot.model;
    let mut j = model.frames[ee_frame.0].parent_joint.0;
    let mut chain = Vec::new();
    while j != 0 {
        if model.joint_types[j] != JointType::Planar && robot.arm_dofs().contains(&model.idx_v[j]) {
            chain.push(j);
        }
        j = model.parents[j].0;
    }
    chain.reverse();
    chain
}

/// The robot's geometry `geometry` with the picked object `object` attached as one more
/// link, fixed to the body of the end effector `ee_frame` at its grasp: the object's
/// shapes (world, scene as placed) seen from the end effector at `grasp` (its world pose
/// at the grasp). The links it may touch: those on the end effector's body and on the
/// bodies below it (the gripper and its fingers, which hold it) and the object's own
/// `touch_links`.
///
/// # Errors
/// As [`GeometryModel::with_attached`].
fn carried_geometry(
    model: &crate::multibody::Model,
    geometry: &GeometryModel,
    ee_frame: FrameIndex,
    object: &SceneObject,
    grasp: &SE3,
) -> Result<GeometryModel> {
    let fr = &model.frames[ee_frame.0];
    let joint = fr.parent_joint;
    let shapes: Vec<_> = object
        .shapes
        .iter()
        .map(|s| {
            (
                fr.placement.compose(&grasp.inverse_compose(&s.pose)),
                s.shape.clone(),
            )
        })
        .collect();
    let below_ee = |mut j: usize| loop {
        if j == joint.0 {
            return true;
        }
        if j == 0 {
            return false;
        }
        j = model.parents[j].0;
    };
    let touch: Vec<usize> = geometry
        .links
        .iter()
        .enumerate()
        .filter(|(_, l)| below_ee(l.joint.0) || object.touch_links.contains(&l.name))
        .map(|(k, _)| k)
        .collect();
    geometry.with_attached(&object.id, joint, &shapes, &touch)
}

/// The link the held object (the last link of `carried`, [`carried_geometry`]) enters
/// at the configuration `posture`, and how deep (m): the deepest of its enabled pairs by
/// the collision module's signed distances (hulls, and the mesh surfaces of the swapped
/// links); `None` when it touches nothing.
fn carried_object_touch(
    model: &crate::multibody::Model,
    carried: &GeometryModel,
    posture: &[f64],
) -> Option<(String, f64)> {
    let mut data = Data::new(model);
    crate::kinematics::forward_kinematics(model, &mut data, &DVector::from_column_slice(posture));
    let mut gd = GeometryData::new(carried);
    update_geometry_placements(carried, &data, &mut gd);
    compute_distances(carried, &mut gd, PairSelection::Enabled);
    let held = carried.links.len() - 1;
    carried
        .pairs
        .iter()
        .enumerate()
        .filter(|&(p, pair)| carried.enabled[p] && pair[1] == held)
        .map(|(p, pair)| (gd.results[p].distance, pair[0]))
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .filter(|&(d, _)| d <= 0.0)
        .map(|(d, link)| (carried.links[link].name.clone(), -d))
}

/// The ids of the scene objects (other than `object`) that come within `tolerance` (m)
/// of `object`'s shapes as the scene places them (signed distances of the collision
/// module): what it rests on or in.
fn support_of(scene: &Scene, object: &SceneObject, tolerance: f64) -> Vec<String> {
    let (mut warm, mut epa) = (WarmStart::default(), EpaWorkspace::default());
    scene
        .objects
        .iter()
        .filter(|o| o.id != object.id)
        .filter(|o| {
            o.shapes.iter().any(|s| {
                object.shapes.iter().any(|h| {
                    warm = WarmStart::default();
                    signed_distance(&h.shape, &h.pose, &s.shape, &s.pose, &mut warm, &mut epa)
                        .distance
                        <= tolerance
                })
            })
        })
        .map(|o| o.id.clone())
        .collect()
}

/// `robot` with a point mass `mass` at `offset` in the frame `frame` added to the frame's
/// body.
fn with_payload(
    robot: &WheeledModel,
    frame: FrameIndex,
    mass: f64,
    offset: &Vector3<f64>,
) -> WheeledModel {
    let mut out = robot.clone();
    let fr = &robot.model.frames[frame.0];
    let at = fr.placement.act_point(offset);
    let j = fr.parent_joint.0;
    out.model.inertias[j] = robot.model.inertias[j] + Inertia::point_mass(mass, at);
    out
}

/// The outlines of the scene's shapes on the ground: one convex polygon per shape
/// (counter-clockwise, world frame), with the id of its object.
pub fn scene_outlines(scene: &Scene) -> Vec<(String, Vec<Vector2<f64>>)> {
    let mut out = Vec::new();
    let mut points = Vec::new();
    for o in &scene.objects {
        for s in &o.shapes {
            points.clear();
            outline_points(&s.shape, &s.pose, &mut points);
            out.push((o.id.clone(), hull_2d(points.iter().map(|p| p.xy()))));
        }
    }
    out
}

/// The first scene object whose outline comes within `radius` of `at` (world), with the
/// distance: where the footprint would stand in it.
pub fn object_under_footprint(
    outlines: &[(String, Vec<Vector2<f64>>)],
    at: [f64; 2],
    radius: f64,
) -> Option<(String, f64)> {
    let p = Vector2::new(at[0], at[1]);
    outlines.iter().find_map(|(id, poly)| {
        let d = polygon_distance(poly, &p);
        (d <= radius).then(|| (id.clone(), d))
    })
}

impl Task {
    /// Ranks the base poses from which the group reaches the grasp
    /// ([`crate::motion::placement::place_base`]), the arm's other joints at `posture`
    /// (a full configuration), with the payload, clear of the scene and of the map's
    /// boxes near the pick ([`Task::boxes`]): a grasping posture that touches either is
    /// refused.
    ///
    /// # Errors
    /// As [`crate::motion::placement::place_base`].
    pub fn placements(&self, robot: &WheeledModel, posture: &[f64]) -> Result<Placement> {
        let support = SupportPolygon::from_wheeled_base(&robot.base)?;
        place_base(
            &PlacementProblem {
                model: &robot.model,
                geometry: &self.hull_geometry,
                scene: &scene_with(&self.scene, &self.boxes),
                group: &self.group,
                posture,
                support: &support,
                grasp: &self.grasp,
                payload: Payload {
                    mass: self.mass,
                    offset: self.object_in_grasp,
                },
            },
            &self.placement,
        )
    }
}

/// The smallest distances of the executed arm motion to the scene, to the map's boxes
/// near the pick ([`Task::boxes`]) and between the robot's enabled link pairs (the
/// collision module's signed distances on the convex hulls and the swapped links' mesh
/// surfaces), with the pair of each: before the grasp with the robot's geometry against
/// the whole scene, after it with the geometry carrying the object ([`Task::carried`])
/// against the scene without it ([`Holding`]). The drives' monitor
/// ([`DistanceMonitor::scene_only`]) measures against the task's scene and all the map's
/// boxes.
///
/// During the lift the held object's pairs with its support ([`Task::support`]) are left
/// out of the scene distance and checked by the lift rule instead ([`LiftStart`]): the
/// object may touch its support only while it rises off it.
#[derive(Debug, Clone)]
pub struct DistanceMonitor {
    /// The task's scenes it measures against, per [`Holding`]: [`Task::scene`],
    /// [`Task::scene_lifting`], [`Task::scene_after_grasp`].
    scenes: [Scene; 3],
    /// The map's boxes it measures against besides, whatever the robot holds.
    boxes: Scene,
    data: Data,
    gd: GeometryData,
    gd_carried: GeometryData,
    sd: SceneData,
    sd_after: SceneData,
    sd_boxes: SceneData,
    sd_boxes_carried: SceneData,
    q: DVector<f64>,
    /// The last sample: its scene, box and self distances, what it held, and the closest
    /// (link, object) and link pair.
    last: LastSample,
    /// Where the held object stood against its support at the lift's first sample.
    lift_start: Option<LiftStart>,
    /// The world placements of the geometry's objects at the last sample (what
    /// [`DistanceMonitor::step`] measures the motion since against).
    anchor: Vec<SE3>,
    /// Control steps that [`DistanceMonitor::step`] showed could not come closer than
    /// the minima so far, so it measured no distance there.
    pub skipped: usize,
    /// Smallest robot–scene distance so far, the map's boxes included (m), and its link
    /// (or the held object) and scene object or box.
    pub min_scene: Option<(f64, [String; 2])>,
    /// Smallest robot–box distance so far (m) and its link (or the held object) and box
    /// (`map.boxes[k]`); `None` without boxes.
    pub min_box: Option<(f64, [String; 2])>,
    /// Smallest distance between enabled link pairs so far (m) and the links (the held
    /// object as the second one of its pairs).
    pub min_self: Option<(f64, [String; 2])>,
    /// Whether the distances between links are measured (`false`:
    /// [`DistanceMonitor::scene_only`], and `min_self` stays `None`).
    with_self: bool,
}

impl DistanceMonitor {
    /// The monitor of `task` on `robot` (the arm motions'): the robot against the task's
    /// scene and the map's boxes near the pick ([`Task::boxes`]), its links against each
    /// other.
    #[must_use]
    pub fn new(task: &Task, robot: &WheeledModel) -> Self {
        Self::against(task, robot, &task.boxes)
    }

    /// The monitor of `task` on `robot` against the task's scenes and `boxes`.
    fn against(task: &Task, robot: &WheeledModel, boxes: &[SceneObject]) -> Self {
        let boxes = Scene {
            objects: boxes.to_vec(),
        };
        Self {
            data: Data::new(&robot.model),
            gd: GeometryData::new(&task.geometry),
            gd_carried: GeometryData::new(&task.carried),
            sd: SceneData::new(&task.geometry, &task.scene),
            sd_after: SceneData::new(&task.carried, &task.scene_after_grasp),
            sd_boxes: SceneData::new(&task.geometry, &boxes),
            sd_boxes_carried: SceneData::new(&task.carried, &boxes),
            scenes: [
                task.scene.clone(),
                task.scene_lifting.clone(),
                task.scene_after_grasp.clone(),
            ],
            boxes,
            q: DVector::zeros(robot.model.nq),
            last: LastSample::default(),
            lift_start: None,
            anchor: Vec::new(),
            skipped: 0,
            min_scene: None,
            min_box: None,
            min_self: None,
            with_self: true,
        }
    }

    /// The monitor of `task` on `robot` that measures the robot against the task's scene
    /// and `boxes` (all the map's boxes, `Mission::box_objects`: a table top or beam the
    /// base passes under), not its links against each other (the drives': the arm holds
    /// its transport posture there, whose self distances the load checks, holding the
    /// object too).
    #[must_use]
    pub fn scene_only(task: &Task, robot: &WheeledModel, boxes: &[SceneObject]) -> Self {
        Self {
            with_self: false,
            ..Self::against(task, robot, boxes)
        }
    }

    /// The monitor at one control step: [`DistanceMonitor::sample`] unless the motion
    /// since the last sample shows that no distance can have fallen to the minima so far.
    /// Every point of an object moves by at most `|Δc| + ‖ΔR‖_F ρ` (c and ρ its bounding
    /// ball's world centre and radius, R its world rotation; the Frobenius norm bounds the
    /// rotation's), so with `m` the largest such motion a scene or box distance is at
    /// least the last one minus `m` and a distance between two links at least the last
    /// one minus `2 m`. When all stay above the minima, the step changes no minimum and
    /// touches nothing (the minima are above zero while the run goes on): the minima are
    /// those of a sample at every step (up to GJK's tolerance, as its warm starts then come
    /// from other states). The lift is sampled at every step (its rule reads
    /// the support distance and height each time), and so is the first step after a
    /// change of what the robot holds.
    pub fn step(&mut self, task: &Task, robot: &WheeledModel, q: &[f64], holding: Holding) {
        self.place(task, robot, q, holding);
        if self.cannot_reach_the_minima(task, holding) {
            self.skipped += 1;
        } else {
            self.measure(task, holding);
        }
    }

    /// Whether the placements just computed ([`DistanceMonitor::place`]) lie too close
    /// to the last sample's for any distance to reach the minima (the bound of
    /// [`DistanceMonitor::step`]); `false` while lifting, after a change of what the robot
    /// holds, or before the first sample.
    fn cannot_reach_the_minima(&self, task: &Task, holding: Holding) -> bool {
        let Some(min_scene) = &self.min_scene else {
            return false;
        };
        let min_self = match &self.min_self {
            Some((d, _)) => *d,
            None if self.with_self => return false,
            None => f64::NEG_INFINITY,
        };
        let min_box = match &self.min_box {
            Some((d, _)) => *d,
            None if !self.boxes.objects.is_empty() => return false,
            None => f64::NEG_INFINITY,
        };
        if holding == Holding::Lifting || holding != self.last.holding || self.anchor.is_empty() {
            return false;
        }
        let (gm, gd) = if holding == Holding::Nothing {
            (&task.geometry, &self.gd)
        } else {
            (&task.carried, &self.gd_carried)
        };
        let moved = gm
            .objects
            .iter()
            .zip(&gd.placements)
            .zip(&self.anchor)
            .map(|((o, now), then)| {
                let centre = now.act_point(&o.bounding_centre) - then.act_point(&o.bounding_centre);
                centre.norm() + (now.rotation - then.rotation).norm() * o.bounding_radius
            })
            .fold(0.0, f64::max);
        self.last.scene_distance - moved > min_scene.0
            && self.last.box_distance - moved > min_box
            && (!self.with_self || self.last.self_distance - 2.0 * moved > min_self)
    }

    /// Forward kinematics at `q` (full configuration) and the placements of the geometry
    /// the robot has holding `holding`.
    fn place(&mut self, task: &Task, robot: &WheeledModel, q: &[f64], holding: Holding) {
        let (gm, gd) = if holding == Holding::Nothing {
            (&task.geometry, &mut self.gd)
        } else {
            (&task.carried, &mut self.gd_carried)
        };
        self.q.copy_from_slice(q);
        crate::kinematics::forward_kinematics(&robot.model, &mut self.data, &self.q);
        update_geometry_placements(gm, &self.data, gd);
    }

    /// The smallest robot–scene distance and its pair, once the monitor has measured a
    /// state.
    #[must_use]
    pub fn scene_minimum(&self) -> Option<SceneMinimum> {
        let (d, pair) = self.min_scene.clone()?;
        Some(SceneMinimum {
            min_scene_distance: d,
            closest_scene_pair: pair,
        })
    }

    /// What the last [`DistanceMonitor::sample`] touched (a distance ≤ 0), as the run's
    /// reason states it: the scene and the boxes before the links, the held object named
    /// as such (`held object 'Can2' touches scene object '<id>' (<distance> m)`, a map box
    /// as `link 'upperarm_roll_link' touches map box 'map.boxes[0]' ...`); `None` when it
    /// touched nothing.
    /// A lift that breaks the rule of [`LiftStart`] is named as the held object entering
    /// its support (`held object 'Can2' enters its support '<id>' ...`) or staying on it
    /// after rising (`held object 'Can2' is 0.0021 m from its support '<id>' after
    /// rising ...`).
    #[must_use]
    pub fn touch(&self, task: &Task) -> Option<String> {
        let l = &self.last;
        if let Some(v) = &l.lift_violation {
            return Some(v.clone());
        }
        let grasped = l.holding != Holding::Nothing;
        let gm = if grasped {
            &task.carried
        } else {
            &task.geometry
        };
        let held = gm.links.len() - 1;
        let link = |k: usize| {
            if grasped && k == held {
                format!("held object '{}'", gm.links[k].name)
            } else {
                format!("link '{}'", gm.links[k].name)
            }
        };
        if l.scene_distance <= 0.0
            && let Some((k, object)) = l.scene_pair
        {
            let source = match object {
                Measured::Scene(_) => "scene object",
                Measured::Box(_) => "map box",
            };
            return Some(format!(
                "{} touches {source} '{}' ({:.4} m)",
                link(k),
                object.name(&self.scenes[l.holding.index()], &self.boxes),
                l.scene_distance
            ));
        }
        if l.self_distance <= 0.0
            && let Some(i) = l.self_pair
        {
            let [a, b] = gm.pairs[i];
            return Some(format!(
                "{} touches {} ({:.4} m)",
                link(a),
                link(b),
                l.self_distance
            ));
        }
        None
    }

    /// The distances at `q` (full configuration) to the scene (the boxes included) and
    /// between links, holding `holding`; updates the minima and returns both (m).
    pub fn sample(
        &mut self,
        task: &Task,
        robot: &WheeledModel,
        q: &[f64],
        holding: Holding,
    ) -> (f64, f64) {
        self.place(task, robot, q, holding);
        self.measure(task, holding)
    }

    /// The distances of the placements [`DistanceMonitor::place`] computed: as
    /// [`DistanceMonitor::sample`].
    fn measure(&mut self, task: &Task, holding: Holding) -> (f64, f64) {
        let scene = &self.scenes[holding.index()];
        let (gm, gd, sd, sd_boxes) = if holding == Holding::Nothing {
            (
                &task.geometry,
                &mut self.gd,
                &mut self.sd,
                &mut self.sd_boxes,
            )
        } else {
            (
                &task.carried,
                &mut self.gd_carried,
                &mut self.sd_after,
                &mut self.sd_boxes_carried,
            )
        };
        let d_self = if self.with_self {
            compute_distances(gm, gd, PairSelection::Enabled)
        } else {
            f64::INFINITY
        };
        let d_task = compute_scene_distances(gm, gd, scene, sd);
        let (no, nb) = (scene.objects.len(), self.boxes.objects.len());
        let task_pair = sd.closest.map(|k| (k / no, Measured::Scene(k % no)));
        let (d_box, box_pair) = if nb == 0 {
            (f64::INFINITY, None)
        } else {
            let d = compute_scene_distances(gm, gd, &self.boxes, sd_boxes);
            (d, sd_boxes.closest.map(|k| (k / nb, Measured::Box(k % nb))))
        };
        let (d_scene, scene_pair) = if d_box < d_task {
            (d_box, box_pair)
        } else {
            (d_task, task_pair)
        };
        let lift_violation = if holding == Holding::Lifting {
            let held = gm.links.len() - 1;
            let (d, support) = support_distance(task, gm, gd, held);
            let z = gd.placements[gm.links[held].first].translation.z;
            let start = *self.lift_start.get_or_insert(LiftStart {
                z,
                depth: (-d).max(0.0),
            });
            support.and_then(|o| {
                start
                    .violation(z, d, &task.scene.objects[o].id)
                    .map(|why| format!("held object '{}' {why}", gm.links[held].name))
            })
        } else {
            None
        };
        let self_pair = gd.closest;
        self.anchor.clone_from(&gd.placements);
        self.last = LastSample {
            scene_distance: d_scene,
            box_distance: d_box,
            self_distance: d_self,
            holding,
            scene_pair,
            self_pair,
            lift_violation,
        };
        let links = &gm.links;
        let boxes = &self.boxes;
        let named = |(k, object): (usize, Measured)| {
            [links[k].name.clone(), object.name(scene, boxes).to_string()]
        };
        if self.min_scene.as_ref().is_none_or(|m| d_scene < m.0)
            && let Some(pair) = scene_pair
        {
            self.min_scene = Some((d_scene, named(pair)));
        }
        if self.min_box.as_ref().is_none_or(|m| d_box < m.0)
            && let Some(pair) = box_pair
        {
            self.min_box = Some((d_box, named(pair)));
        }
        if self.with_self
            && self.min_self.as_ref().is_none_or(|m| d_self < m.0)
            && let Some(i) = self_pair
        {
            let [a, b] = gm.pairs[i];
            self.min_self = Some((d_self, [links[a].name.clone(), links[b].name.clone()]));
        }
        (d_scene, d_self)
    }
}

/// The held object's smallest signed distance (m) to its support at the placements in
/// `gd` (`held` its link in `gm`, the carrying geometry), with the support object's index
/// in [`Task::scene`]; `+∞` and `None` without a support.
fn support_distance(
    task: &Task,
    gm: &GeometryModel,
    gd: &GeometryData,
    held: usize,
) -> (f64, Option<usize>) {
    let mut epa = EpaWorkspace::default();
    let link = &gm.links[held];
    let mut best = (f64::INFINITY, None);
    for (o, obj) in task.scene.objects.iter().enumerate() {
        if !task.support.contains(&obj.id) {
            continue;
        }
        for s in &obj.shapes {
            for k in link.first..link.first + link.count {
                let d = signed_distance(
                    &gm.objects[k].shape,
                    &gd.placements[k],
                    &s.shape,
                    &s.pose,
                    &mut WarmStart::default(),
                    &mut epa,
                )
                .distance;
                if d < best.0 {
                    best = (d, Some(o));
                }
            }
        }
    }
    best
}

/// The lift rule: the held object's state against its support ([`Task::support`]) at the
/// lift's first sample (the grasp, where the payload was attached), and what every later
/// sample of the lift must keep. With `depth` how far the object then stood in its support
/// (0 if clear) and [`ARM_MARGIN`] the arm planner's clearance:
/// 1. it never enters its support deeper than it stood at the grasp by more than the
///    margin: signed distance ≥ −(`depth` + margin);
/// 2. once its centre has risen above its height at the grasp by more than `depth` + 2 ×
///    margin (lifted straight off a level support it would then be a margin clear of it,
///    plus a margin for the tracking), it is clear of its support by more than the margin.
///
/// The first catches an object pushed into its support, the second one dragged along it
/// (or not lifted off it at all) while the lift rises.
#[derive(Debug, Clone, Copy)]
pub struct LiftStart {
    /// Height of the held object's centre (world z, m).
    pub z: f64,
    /// Its depth in its support (m, ≥ 0).
    pub depth: f64,
}

impl LiftStart {
    /// How a lift sample at height `z` (m) with support distance `d` (m) to the support
    /// `support` breaks the rule, as the reason's words after the held object's name;
    /// `None` when it keeps it.
    #[must_use]
    pub fn violation(&self, z: f64, d: f64, support: &str) -> Option<String> {
        let risen = z - self.z;
        let clear_above = self.depth + 2.0 * ARM_MARGIN;
        if d < -(self.depth + ARM_MARGIN) {
            Some(format!(
                "enters its support '{support}' ({d:.4} m; it stood {:.4} m in it at the \
                 grasp, the lift allows {ARM_MARGIN} m deeper)",
                self.depth
            ))
        } else if risen > clear_above && d <= ARM_MARGIN {
            Some(format!(
                "is still on its support '{support}' ({d:.4} m) after rising {risen:.4} m (it \
                 stood {:.4} m in it at the grasp; once risen {clear_above:.4} m the lift asks \
                 for more than {ARM_MARGIN} m clear)",
                self.depth
            ))
        } else {
            None
        }
    }
}

/// What the gripper holds at a state the [`DistanceMonitor`] samples.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Holding {
    /// Nothing yet: the robot against the whole scene.
    Nothing,
    /// The object, lifting it: the carrying geometry against [`Task::scene_lifting`]
    /// (its support may touch it).
    Lifting,
    /// The object: the carrying geometry against [`Task::scene_after_grasp`].
    Carrying,
}

impl Holding {
    /// The index of the scene a [`DistanceMonitor`] checks while holding this: of
    /// [`Task::scene`], [`Task::scene_lifting`], [`Task::scene_after_grasp`].
    fn index(self) -> usize {
        match self {
            Holding::Nothing => 0,
            Holding::Lifting => 1,
            Holding::Carrying => 2,
        }
    }
}

/// What a [`DistanceMonitor`] measured a distance to: an object of the task's scene
/// measured (its index there) or a map box (its index among the monitor's boxes).
#[derive(Debug, Clone, Copy)]
enum Measured {
    Scene(usize),
    Box(usize),
}

impl Measured {
    /// Its id: of an object of `scene` (the task's scene measured) or of `boxes`.
    fn name<'a>(self, scene: &'a Scene, boxes: &'a Scene) -> &'a str {
        match self {
            Measured::Scene(o) => &scene.objects[o].id,
            Measured::Box(o) => &boxes.objects[o].id,
        }
    }
}

/// The distances of a [`DistanceMonitor`]'s last sample.
#[derive(Debug, Clone)]
struct LastSample {
    /// To the scene and the boxes.
    scene_distance: f64,
    /// To the boxes (`+∞` without).
    box_distance: f64,
    self_distance: f64,
    holding: Holding,
    /// The link (index into the geometry's links) and object of the closest link–scene
    /// or link–box pair.
    scene_pair: Option<(usize, Measured)>,
    /// The closest enabled link pair (index into the geometry's pairs).
    self_pair: Option<usize>,
    /// During the lift, how the held object broke the lift rule ([`LiftStart`]).
    lift_violation: Option<String>,
}

impl Default for LastSample {
    fn default() -> Self {
        Self {
            scene_distance: f64::INFINITY,
            box_distance: f64::INFINITY,
            self_distance: f64::INFINITY,
            holding: Holding::Nothing,
            scene_pair: None,
            self_pair: None,
            lift_violation: None,
        }
    }
}

/// The placement the run drove to.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PlacementChoice {
    /// Base pose `[x, y, θ]` (world).
    pub base: [f64; 3],
    /// Its rank among the candidates (0: the best): the better-ranked ones the base could
    /// not reach on the map (the footprint does not fit there, or no path leads there),
    /// or, with a `[goal]`, the drive on could not leave holding the object (its footprint
    /// does not fit there on the drive on's map).
    pub rank: usize,
    /// Candidates ranked.
    pub candidates: usize,
    /// Its score, manipulability, clearance (m) and tip-over margin with the payload (m).
    pub score: f64,
    /// Yoshikawa's manipulability of the grasping posture.
    pub manipulability: f64,
    /// Clearance of the grasping posture (m).
    pub clearance: f64,
    /// ZMP margin of the grasping posture at rest with the payload (m).
    pub tip_over_margin: f64,
    /// Per-stage counts of the search.
    pub counts: crate::motion::placement::PlacementCounts,
    /// Wall time of the search (s).
    pub time_s: f64,
}

/// One arm motion of the pick.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ArmPlanRecord {
    /// `approach` (to the pre-grasp), `grasp`, `lift` (up off the support) or `retreat`
    /// (to the transport posture).
    pub stage: String,
    /// Mission time it was planned at (s).
    pub t: f64,
    /// Whether it was solved.
    pub solved: bool,
    /// Why not.
    pub reason: Option<String>,
    /// Planning wall time (s).
    pub planning_time_s: f64,
    /// States checked for collision.
    pub checks: u64,
    /// Duration of the timed trajectory (s).
    pub duration: Option<f64>,
    /// The planner's smallest distance along the plan (m), over the first
    /// `min_distance_states` of its states (the start, the waypoints, then the trajectory's
    /// samples: those measured within the planning time, `MotionResult::closest_states`).
    pub min_distance: Option<f64>,
    /// How many of the plan's states `min_distance` covers.
    pub min_distance_states: usize,
}

/// The payload attached at the grasp.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PayloadRecord {
    /// Mission time (s).
    pub t: f64,
    /// Mass (kg).
    pub mass: f64,
    /// The ZMP margin at that state without and with the payload (m).
    pub zmp_margin_without: Option<f64>,
    /// With the payload (m).
    pub zmp_margin_with: Option<f64>,
}

/// The smallest robot–scene distance a scene-only [`DistanceMonitor`] measured.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct SceneMinimum {
    /// Smallest robot–scene distance (m).
    pub min_scene_distance: f64,
    /// Link (or the held object) and scene object at it.
    pub closest_scene_pair: [String; 2],
}

/// What the pick did.
#[derive(Debug, Clone, serde::Serialize)]
pub struct TaskResult {
    /// The object.
    pub object: String,
    /// The scene's pose on the map `[x, y, yaw]`.
    pub scene_pose: [f64; 3],
    /// The placement driven to (`None`: none found or reachable).
    pub placement: Option<PlacementChoice>,
    /// The arm motions planned.
    pub arm_plans: Vec<ArmPlanRecord>,
    /// The payload attach.
    pub payload: Option<PayloadRecord>,
    /// Smallest robot–scene distance (the map's boxes near the pick included) over every
    /// control step of the executed arm motions (m; during the lift without the held object's pairs with its support, which
    /// [`LiftStart`]'s rule checks).
    pub min_scene_distance: Option<f64>,
    /// Link and scene object (or map box) at it.
    pub closest_scene_pair: Option<[String; 2]>,
    /// Smallest distance to the map's boxes near the pick ([`Task::boxes`]) over every
    /// control step of the executed arm motions (m; absent without such boxes).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub min_box_distance: Option<f64>,
    /// Link (or the held object) and box (`map.boxes[k]`) at it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub closest_box_pair: Option<[String; 2]>,
    /// Smallest distance between enabled link pairs over every control step of the
    /// executed arm motions (m).
    pub min_self_distance: Option<f64>,
    /// Links at it.
    pub closest_self_pair: Option<[String; 2]>,
    /// Smallest robot–scene distance over every control step of the drives, to the
    /// placement and on from it (the task's scene, the held object counted after the
    /// grasp; `None` without a drive).
    pub driving: Option<SceneMinimum>,
    /// The scene objects the held object may touch ([`Task::support`]).
    pub support: Vec<String>,
    /// The radius of the drive on's footprint, with the held object (m; `None` without
    /// a drive on).
    pub drive_on_footprint_radius: Option<f64>,
}

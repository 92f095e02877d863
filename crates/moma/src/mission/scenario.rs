//! The mission file (TOML) and its validation into a ready-to-run [`Mission`]: the map,
//! the robot, the footprint, the postures, a `[task]`, the contact plant, the
//! `[uncertainty]` draw and law `mpc`'s MPC loaded and checked.
//!
//! The schema (documented for users in `docs/mission.md`) and the checks that need only
//! the file are `schema`'s, its items re-exported here. Relative paths (`map.file`,
//! `robot.urdf`, `output.dir`) resolve against the folder of the mission file.

use std::path::{Path, PathBuf};

use super::arm_scene::{boxes_near_pick, robot_reach};
use super::footprint::MissionFootprint;
use super::heights::{
    BoxVerdict, DriveOnMap, block_by_height, block_by_height_holding, place_boxes,
};
use super::plant::{MissionContact, start_configuration};
use super::task::{Task, load_task, object_under_footprint, scene_outlines, task_geometry_options};
use crate::collision::{GeometryModel, GeometryOptions, Scene, SceneObject};
use crate::contact::PlantKind;
use crate::control::mpc::WholeBodyMpc;
use crate::error::{Error, Result};
use crate::mobile::{Caster, DiffDrive, WheeledBase, WheeledModel};
use crate::multibody::{FrameIndex, RootJoint};
use crate::planning::LoadedMap;
use crate::sim::model_mismatch::ModelPerturbation;
use crate::sim::mpc_table::build_mpc;
use crate::sim::sensor_noise::SensorNoise;
use crate::sim::uncertainty::{Draw, perturb, sensor_noise};

pub use super::schema::{
    ControlSpec, DriveSource, DriveSpec, FootprintSpec, GoalSpec, LimitsSpec, MAX_OBSTACLES,
    MAX_SAMPLES, MAX_STEPS, MapSpec, MissionFile, MissionLaw, ObstacleSpec, OutputSpec, RobotSpec,
    SimulationSpec, StartSpec, parse_file,
};
use super::schema::{
    check_goal_and_task, check_limits_and_gains, check_obstacles_and_robot, check_simulation,
    field_err, finite, positive,
};

/// A validated mission, ready for [`super::run`].
#[derive(Debug, Clone)]
pub struct Mission {
    /// Title.
    pub name: String,
    /// The mission file (for messages).
    pub path: PathBuf,
    /// The file as written.
    pub file: MissionFile,
    /// The map.
    pub map: LoadedMap,
    /// The robot on its wheels.
    pub robot: WheeledModel,
    /// The end-effector frame.
    pub ee_frame: FrameIndex,
    /// Arm joint angles of the transport posture (one per arm dof).
    pub transport: Vec<f64>,
    /// Initial arm joint angles.
    pub q_arm0: Vec<f64>,
    /// Output folder, resolved against the mission file's folder.
    pub output_dir: PathBuf,
    /// The footprint the configuration space and the clearance use.
    pub footprint: MissionFootprint,
    /// The verdict of each of `map.boxes` (in file order); the blocked ones are
    /// occupied cells of [`Mission::map`].
    pub boxes: Vec<BoxVerdict>,
    /// `map.boxes` as scene objects (named `map.boxes[k]`, in file order): what a
    /// `[task]`'s drives are monitored against in 3-D, with the task's scene.
    pub box_objects: Vec<SceneObject>,
    /// `robot.package_dirs`, resolved against the mission file's folder.
    pub package_dirs: Vec<PathBuf>,
    /// The contact plant, built and checked (`simulation.plant = "contact"`).
    pub contact: Option<MissionContact>,
    /// The rolling plant's robot with the `[uncertainty]` draw applied (`None` without
    /// the table, or when it leaves the model as it is: the plant is [`Mission::robot`]). The planner, reference, law and
    /// computed torque keep [`Mission::robot`].
    pub plant_robot: Option<WheeledModel>,
    /// The `[uncertainty]` noise on the state the law measures (`None` without a positive
    /// deviation), at the start of its sequence.
    pub sensor_noise: Option<SensorNoise>,
    /// The pick of `[task]`, loaded (its scene's outline already blocks [`Mission::map`]).
    pub task: Option<Task>,
    /// With a `[task]`: the map its drive on plans on, holding the object.
    pub drive_on_map: Option<DriveOnMap>,
    /// Law `mpc`: the whole-body MPC built from `[control.mpc]`, its posture the start
    /// configuration, and its solve period in control steps.
    pub mpc: Option<(WholeBodyMpc, usize)>,
}

impl Mission {
    /// The file's `[goal]` (always present without `[task]`).
    #[must_use]
    pub fn goal(&self) -> Option<&GoalSpec> {
        self.file.goal.as_ref()
    }
}

/// Reads and validates a mission file.
///
/// # Errors
/// A file that cannot be read or parsed (naming the file, and the key for unknown or
/// missing keys), an invalid value (naming the field), a map or URDF that does not load.
pub fn load(path: &Path) -> Result<Mission> {
    load_with(path, &FileSystem)
}

/// As [`load`], with the map and robot read through `files`.
///
/// # Errors
/// As [`load`].
pub fn load_with(path: &Path, files: &dyn Loader) -> Result<Mission> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    let file = parse_file(&text, path)?;
    let base = path.parent().unwrap_or(Path::new("."));
    from_file_with(file, path, base, files)
}

/// Where the map and robot files a mission (or a sweep) names are parsed from: the
/// normal path reads them from the file system ([`FileSystem`], what [`load`],
/// [`from_file`] and `Sweep::from_toml_str` use). A caller that loads the same few
/// files over and over (a fuzzer feeding thousands of variants of one mission) may hand
/// in files it parsed once, provided it returns exactly what [`FileSystem`] would for
/// the same path and arguments.
pub trait Loader {
    /// The map at `path` ([`crate::planning::load_map`]).
    ///
    /// # Errors
    /// As [`crate::planning::load_map`].
    fn map(&self, path: &Path, resolution: Option<f64>) -> Result<LoadedMap>;
    /// The robot at `path` ([`crate::io::urdf::model_from_urdf_file`]).
    ///
    /// # Errors
    /// As [`crate::io::urdf::model_from_urdf_file`].
    fn urdf(&self, path: &Path, root: RootJoint) -> Result<crate::multibody::Model>;
    /// The collision geometry of `model`, loaded from the URDF at `path`
    /// ([`GeometryModel::from_urdf`]; read only for `drive = "urdf"`, `map.boxes` and
    /// `footprint = "robot"`).
    ///
    /// # Errors
    /// As [`GeometryModel::from_urdf`].
    fn geometry(
        &self,
        model: &crate::multibody::Model,
        path: &Path,
        options: &GeometryOptions,
    ) -> Result<GeometryModel> {
        GeometryModel::from_urdf(model, path, options)
    }
}

/// The file system: every call parses the file anew.
#[derive(Debug, Clone, Copy, Default)]
pub struct FileSystem;

impl Loader for FileSystem {
    fn map(&self, path: &Path, resolution: Option<f64>) -> Result<LoadedMap> {
        crate::planning::load_map(path, resolution)
    }
    fn urdf(&self, path: &Path, root: RootJoint) -> Result<crate::multibody::Model> {
        crate::io::urdf::model_from_urdf_file(path, root)
    }
}

/// Validates a parsed mission file; `base` resolves relative paths.
///
/// # Errors
/// As [`load`].
pub fn from_file(file: MissionFile, path: &Path, base: &Path) -> Result<Mission> {
    from_file_with(file, path, base, &FileSystem)
}

/// As [`from_file`], with the map and robot read through `files`.
///
/// # Errors
/// As [`load`].
pub fn from_file_with(
    file: MissionFile,
    path: &Path,
    base: &Path,
    files: &dyn Loader,
) -> Result<Mission> {
    check_limits_and_gains(&file, path)?;
    check_simulation(&file, path)?;
    check_obstacles_and_robot(&file, path)?;
    check_goal_and_task(&file, path)?;
    let mut map = load_mission_map(&file, path, base, files)?;
    let package_dirs = package_dirs(&file, path, base)?;
    let (robot, ee_frame, geometry) = load_robot(&file, path, base, &package_dirs, files)?;
    let (transport, q_arm0) = arm_postures(&file, &robot, path)?;
    let footprint = mission_footprint(&file, path, &map, &robot, geometry.as_ref(), &transport)?;
    let (box_objects, boxes) = match &geometry {
        Some(gm) => place_boxes(
            &mut map.grid,
            &file.map.boxes,
            &robot,
            gm,
            &transport,
            footprint.padding(),
        )
        .map_err(|e| match e {
            Error::InvalidInput { field, message } => field_err(path, &field, message),
            other => other,
        })?,
        None => (Vec::new(), Vec::new()),
    };
    let draw = uncertainty_draw(&file, path)?;
    let contact = contact_plant(&file, path, base, &robot, &q_arm0, draw.as_ref(), files)?;
    let plant_robot = match (&draw, file.simulation.plant) {
        (Some(d), PlantKind::Rolling) if d.perturbation != ModelPerturbation::default() => {
            Some(perturbed_robot(d, path, &robot)?)
        }
        _ => None,
    };
    let sensor_noise = match &file.uncertainty {
        Some(spec) => sensor_noise(spec, (&robot.q_names(), &robot.v_names()), path)?,
        None => None,
    };
    let (task, drive_on_map) = match &file.task {
        None => (None, None),
        Some(spec) => {
            let options = task_geometry_options(spec, base, &package_dirs);
            let gm = files
                .geometry(&robot.model, &base.join(&file.robot.urdf), &options)
                .map_err(|e| field_err(path, "task.srdf (collision geometry)", e))?;
            let urdf = base.join(&file.robot.urdf);
            let mut task = load_task(
                spec,
                path,
                base,
                &robot,
                ee_frame,
                &transport,
                &urdf,
                &package_dirs,
                gm,
                &footprint,
            )?;
            let reach = robot_reach(&robot.model, &task.carried, ee_frame);
            let g = task.grasp.target.translation.vector;
            task.boxes = boxes_near_pick(&box_objects, [g.x, g.y], reach);
            place_scene_on_map(
                &mut task,
                &file,
                path,
                &mut map,
                (&robot, transport.as_slice()),
                &footprint,
            )?;
            let held = (&robot, transport.as_slice());
            let drive_on = drive_on_map(&task, (&box_objects, &boxes), &map, held, &footprint);
            (Some(task), Some(drive_on))
        }
    };
    let mpc = whole_body_mpc(&file, path, base, &robot, ee_frame, &q_arm0)?;
    let name = file.name.clone().unwrap_or_else(|| {
        path.file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_else(|| "mission".into())
    });
    let output_dir = lexical_clean(&base.join(&file.output.dir));
    Ok(Mission {
        name,
        path: path.to_path_buf(),
        file,
        map,
        robot,
        ee_frame,
        transport,
        q_arm0,
        output_dir,
        footprint,
        boxes,
        box_objects,
        package_dirs,
        contact,
        plant_robot,
        sensor_noise,
        task,
        drive_on_map,
        mpc,
    })
}

/// Law `mpc`: the whole-body MPC of `[control.mpc]` (checked as `moma simulate` checks
/// `[controller.mpc]`, errors naming `control.mpc.*`) on the mission's robot, its end
/// effector `robot.end_effector`, from the start configuration; and its solve period in
/// control steps. `None` for the default law, which takes none of the MPC's keys. What
/// law `mpc` does not run is refused, naming the field: a `[task]`, the contact plant,
/// `[uncertainty]`.
fn whole_body_mpc(
    file: &MissionFile,
    path: &Path,
    base: &Path,
    robot: &WheeledModel,
    ee_frame: FrameIndex,
    q_arm0: &[f64],
) -> Result<Option<(WholeBodyMpc, usize)>> {
    let c = &file.control;
    if c.law == MissionLaw::DriveThenReach {
        for (field, given) in [
            ("control.mpc", c.mpc.is_some()),
            ("control.period", c.period.is_some()),
            ("control.reach_radius", c.reach_radius.is_some()),
        ] {
            if given {
                return Err(field_err(
                    path,
                    field,
                    "read only with control.law = \"mpc\"",
                ));
            }
        }
        return Ok(None);
    }
    let refused = [
        ("task", file.task.is_some(), "law mpc runs no [task] pick"),
        (
            "simulation.plant",
            file.simulation.plant == PlantKind::Contact,
            "law mpc runs on the rolling plant (\"rolling\")",
        ),
        (
            "uncertainty",
            file.uncertainty.is_some(),
            "law mpc takes no [uncertainty]",
        ),
    ];
    if let Some((field, _, why)) = refused.iter().find(|r| r.1) {
        return Err(field_err(path, field, why));
    }
    let spec = c.mpc.as_ref().ok_or_else(|| {
        field_err(
            path,
            "control.mpc",
            "missing: law mpc needs its table (at least its joints)",
        )
    })?;
    let frame = &robot.model.frames[ee_frame.0].name;
    let q0 = start_configuration(robot, file.start.pose, q_arm0);
    let mpc = build_mpc(
        spec,
        "control.mpc",
        frame,
        "robot.end_effector",
        robot,
        &base.join(&file.robot.urdf),
        q0.as_slice(),
        base,
    )
    .map_err(|e| Error::parse(path, crate::error::chain(&e)))?;
    let dt = file.simulation.dt;
    let period = c.period.unwrap_or(mpc.problem.settings.dt);
    positive(path, "control.period", period)?;
    let steps = (period / dt).round();
    if steps < 1.0 || (steps * dt - period).abs() > 1e-9 * period {
        return Err(field_err(
            path,
            "control.period",
            format!("must be a whole number of simulation.dt = {dt} s, got {period}"),
        ));
    }
    if let Some(r) = c.reach_radius {
        positive(path, "control.reach_radius", r)?;
    }
    Ok(Some((mpc, steps as usize)))
}

/// Blocks the map cells under the outline of the task scene's objects that the robot
/// cannot pass under at its transport posture ([`block_by_height`], the verdicts into
/// `task.heights`); such an object where the footprint stands at the start is an error
/// naming the object.
fn place_scene_on_map(
    task: &mut Task,
    file: &MissionFile,
    path: &Path,
    map: &mut LoadedMap,
    (robot, transport): (&WheeledModel, &[f64]),
    footprint: &MissionFootprint,
) -> Result<()> {
    let footprint_radius = footprint.radius;
    let mut grid = map.grid.clone();
    task.heights = block_by_height(
        &mut grid,
        &task.scene.objects,
        robot,
        &task.hull_geometry,
        transport,
        footprint.padding(),
    );
    let blocking = Scene {
        objects: task
            .scene
            .objects
            .iter()
            .zip(&task.heights)
            .filter(|(_, v)| v.blocked)
            .map(|(o, _)| o.clone())
            .collect(),
    };
    let outlines = scene_outlines(&blocking);
    let s = file.start.pose;
    if let Some((id, d)) = object_under_footprint(&outlines, [s[0], s[1]], footprint_radius) {
        return Err(field_err(
            path,
            "task.pose",
            format!(
                "scene object '{id}' overlaps the start pose: its outline lies {d:.3} m from \
                 ({}, {}), within the footprint radius {footprint_radius} m",
                s[0], s[1]
            ),
        ));
    }
    map.grid = grid;
    Ok(())
}

/// The map of `task`'s drive on: `map` (the mission's, the scene placed on it) with the
/// obstacles with heights, the `boxes` (with their verdicts) and the scene's objects but
/// the picked one, checked again with the object held ([`block_by_height_holding`] on
/// [`Task::carried`]); those the robot passed under bare and does not holding it are
/// blocked.
fn drive_on_map(
    task: &Task,
    (box_objects, box_verdicts): (&[SceneObject], &[BoxVerdict]),
    map: &LoadedMap,
    (robot, transport): (&WheeledModel, &[f64]),
    footprint: &MissionFootprint,
) -> DriveOnMap {
    let (mut objects, mut bare) = (box_objects.to_vec(), box_verdicts.to_vec());
    for (o, v) in task.scene.objects.iter().zip(&task.heights) {
        if o.id != task.object {
            objects.push(o.clone());
            bare.push(*v);
        }
    }
    let mut grid = map.grid.clone();
    let blocks = block_by_height_holding(
        &mut grid,
        &objects,
        &bare,
        robot,
        &task.carried,
        transport,
        footprint.padding(),
    );
    DriveOnMap { grid, blocks }
}

/// The file's `[uncertainty]` draw, checked (`None` without the table); `mu` is refused
/// on the rolling plant, naming the field.
fn uncertainty_draw(file: &MissionFile, path: &Path) -> Result<Option<Draw>> {
    let Some(spec) = &file.uncertainty else {
        return Ok(None);
    };
    spec.check()
        .map_err(|e| Error::parse(path, crate::error::chain(&e)))?;
    if spec.mu.is_some() && file.simulation.plant == PlantKind::Rolling {
        return Err(field_err(
            path,
            "uncertainty.mu",
            "the wheels' friction is drawn for the contact plant only",
        ));
    }
    Ok(Some(spec.draw()))
}

/// The rolling plant's robot under the draw `draw`.
fn perturbed_robot(draw: &Draw, path: &Path, robot: &WheeledModel) -> Result<WheeledModel> {
    let mut plant = robot.clone();
    perturb(draw, &mut plant.model, path)?;
    Ok(plant)
}

/// The contact plant of `simulation.plant = "contact"` (the robot description loaded
/// again on a free-flyer root, the `[contact]` table), its model and μ under the
/// `[uncertainty]` draw `draw`, started at the start pose and arm posture and checked
/// there; `None` for the rolling plant, which takes no `[contact]`.
fn contact_plant(
    file: &MissionFile,
    path: &Path,
    base: &Path,
    robot: &WheeledModel,
    q_arm0: &[f64],
    draw: Option<&Draw>,
    files: &dyn Loader,
) -> Result<Option<MissionContact>> {
    let spec = match (file.simulation.plant, &file.contact) {
        (PlantKind::Rolling, None) => return Ok(None),
        (PlantKind::Rolling, Some(_)) => {
            return Err(field_err(
                path,
                "contact",
                "the [contact] table is read only with simulation.plant = \"contact\"",
            ));
        }
        (PlantKind::Contact, None) => {
            return Err(field_err(
                path,
                "simulation.plant",
                "\"contact\" needs a [contact] table (at least its casters)",
            ));
        }
        (PlantKind::Contact, Some(spec)) => spec,
    };
    let mut model = files
        .urdf(&base.join(&file.robot.urdf), RootJoint::FreeFlyer)
        .map_err(|e| field_err(path, "robot.urdf", e))?;
    model.gravity = robot.model.gravity;
    let mut spec = spec.clone();
    if let Some(d) = draw {
        perturb(d, &mut model, path)?;
        spec.mu = d.mu.or(spec.mu);
    }
    let q0 = start_configuration(robot, file.start.pose, q_arm0);
    MissionContact::new(robot, model, &spec, &q0, file.simulation.dt)
        .map(Some)
        .map_err(|e| Error::parse(path, e.to_string()))
}

/// Loads the map (`map.file`, `map.resolution`).
fn load_mission_map(
    file: &MissionFile,
    path: &Path,
    base: &Path,
    files: &dyn Loader,
) -> Result<LoadedMap> {
    let map_path = base.join(&file.map.file);
    if let Some(r) = file.map.resolution {
        positive(path, "map.resolution", r)?;
    }
    let map = files
        .map(&map_path, file.map.resolution)
        .map_err(|e| field_err(path, "map.file", e))?;
    Ok(map)
}

/// `robot.package_dirs` resolved against the mission file's folder; each must be a folder.
fn package_dirs(file: &MissionFile, path: &Path, base: &Path) -> Result<Vec<PathBuf>> {
    let mut out = Vec::with_capacity(file.robot.package_dirs.len());
    for (k, d) in file.robot.package_dirs.iter().enumerate() {
        let dir = lexical_clean(&base.join(d));
        if !dir.is_dir() {
            return Err(field_err(
                path,
                &format!("robot.package_dirs[{k}]"),
                format!("{} is not a folder", dir.display()),
            ));
        }
        out.push(dir);
    }
    Ok(out)
}

/// The casters: `robot.casters`, `robot.casters_file` (read here), or none.
fn mission_casters(file: &MissionFile, path: &Path, base: &Path) -> Result<Vec<Caster>> {
    match (&file.robot.casters, &file.robot.casters_file) {
        (Some(_), Some(_)) => Err(field_err(
            path,
            "robot.casters_file",
            "give the casters either in robot.casters or in a casters file, not both",
        )),
        (Some(list), None) => Ok(list.clone()),
        (None, Some(f)) => crate::mobile::read_casters(&base.join(f))
            .map_err(|e| field_err(path, "robot.casters_file", e)),
        (None, None) => Ok(Vec::new()),
    }
}

/// Loads the robot (URDF with a planar root, drive, casters, support polygon) and finds
/// its end-effector frame; the collision geometry too when the drive or the footprint
/// come from it (`package_dirs` resolve its meshes).
fn load_robot(
    file: &MissionFile,
    path: &Path,
    base: &Path,
    package_dirs: &[PathBuf],
    files: &dyn Loader,
) -> Result<(WheeledModel, FrameIndex, Option<GeometryModel>)> {
    let urdf_path = base.join(&file.robot.urdf);
    let mut model = files
        .urdf(&urdf_path, RootJoint::Planar)
        .map_err(|e| field_err(path, "robot.urdf", e))?;
    model.gravity = nalgebra::Vector3::new(0.0, 0.0, -file.robot.gravity.unwrap_or(9.81));
    let casters = mission_casters(file, path, base)?;
    let geometry = if file.robot.drive == DriveSource::Urdf
        || file.robot.footprint.is_some()
        || !file.map.boxes.is_empty()
    {
        let options = GeometryOptions {
            package_dirs: package_dirs.to_vec(),
            srdf: None,
        };
        Some(
            files
                .geometry(&model, &urdf_path, &options)
                .map_err(|e| field_err(path, "robot.urdf (collision geometry)", e))?,
        )
    } else {
        None
    };
    let wbase = match (&file.robot.drive, &geometry) {
        (DriveSource::Given(d), _) => WheeledBase {
            drive: DiffDrive::new(d.r_w, d.b, d.d)
                .map_err(|e| field_err(path, "robot.drive", e))?,
            casters,
            wheel_joints: file.robot.wheel_joints.clone(),
        },
        (DriveSource::Urdf, Some(gm)) => {
            let [left, right] = file.robot.wheel_joints.as_ref().ok_or_else(|| {
                field_err(
                    path,
                    "robot.wheel_joints",
                    "drive = \"urdf\" reads the drive from the wheel joints: name them \
                     ([left, right])",
                )
            })?;
            crate::mobile::wheeled_base_from_urdf(&model, gm, [left, right], casters)
                .map_err(|e| field_err(path, "robot.wheel_joints", e))?
        }
        (DriveSource::Urdf, None) => unreachable!("the geometry is loaded for drive = \"urdf\""),
    };
    let robot = WheeledModel::new(model, wbase).map_err(|e| field_err(path, "robot", e))?;
    let casters_field = if file.robot.casters_file.is_some() {
        "robot.casters_file"
    } else {
        "robot.casters"
    };
    crate::stability::SupportPolygon::from_wheeled_base(&robot.base)
        .map_err(|e| field_err(path, casters_field, format!("support polygon: {e}")))?;
    let ee_frame = match &file.robot.end_effector {
        Some(n) => robot
            .model
            .frame_id(n)
            .map_err(|e| field_err(path, "robot.end_effector", e))?,
        None => robot.model.last_link_frame(),
    };
    Ok((robot, ee_frame, geometry))
}

/// The footprint disk: `robot.footprint_radius` or the robot's footprint at the
/// transport posture (exactly one of `footprint_radius` and `footprint`), and no larger
/// than the whole map.
fn mission_footprint(
    file: &MissionFile,
    path: &Path,
    map: &LoadedMap,
    robot: &WheeledModel,
    geometry: Option<&GeometryModel>,
    transport: &[f64],
) -> Result<MissionFootprint> {
    let (fp, field) = match (file.robot.footprint_radius, &file.robot.footprint, geometry) {
        (Some(_), Some(_), _) => {
            return Err(field_err(
                path,
                "robot.footprint",
                "give either robot.footprint_radius or robot.footprint, not both",
            ));
        }
        (None, None, _) => {
            return Err(field_err(
                path,
                "robot.footprint_radius",
                "missing: give the radius (m) or robot.footprint = \"robot\"",
            ));
        }
        (Some(r), None, _) => (MissionFootprint::given(r), "robot.footprint_radius"),
        (None, Some(spec), Some(gm)) => {
            if !(spec.padding.is_finite() && spec.padding >= 0.0) {
                return Err(field_err(
                    path,
                    "robot.footprint.padding",
                    format!("must be a finite distance >= 0, got {}", spec.padding),
                ));
            }
            (
                MissionFootprint::from_robot(robot, gm, transport, spec.padding),
                "robot.footprint",
            )
        }
        (None, Some(_), None) => unreachable!("the geometry is loaded for footprint = \"robot\""),
    };
    if !(fp.radius.is_finite() && fp.radius > 0.0) {
        return Err(field_err(
            path,
            field,
            format!(
                "the robot's collision geometry gives a footprint of radius {} m",
                fp.radius
            ),
        ));
    }
    // A footprint larger than the map itself fits nowhere.
    let grid = &map.grid;
    let extent = grid.width.max(grid.height) as f64 * grid.resolution;
    if fp.radius > extent {
        return Err(field_err(
            path,
            field,
            format!(
                "{} m is larger than the whole map ({extent} m): it fits nowhere",
                fp.radius
            ),
        ));
    }
    Ok(fp)
}

/// The transport posture and the start arm posture, one angle per arm joint (each checked
/// against the arm's size and joint limits; defaults: each other, else zero). With
/// `robot.arm_joints` the file lists the named joints only and the others stay at zero.
fn arm_postures(
    file: &MissionFile,
    robot: &WheeledModel,
    path: &Path,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let m = &robot.model;
    let arm = robot.arm_dofs();
    // the arm slots (indices into arm_dofs) the file's lists fill
    let slots: Vec<usize> = match &file.robot.arm_joints {
        None => (0..arm.len()).collect(),
        Some(names) => arm_joint_slots(names, robot, path)?,
    };
    let na = slots.len();
    let name_of = |k: usize| m.names[m.joint_of_dof[arm[k]].0].clone();
    let check_arm = |field: &str, q: &[f64]| -> Result<()> {
        if q.len() != na {
            return Err(field_err(
                path,
                field,
                format!("expected {na} arm joint angles, got {}", q.len()),
            ));
        }
        finite(path, field, q)?;
        for (k, &slot) in slots.iter().enumerate() {
            let i = arm[slot];
            let (lo, hi) = (m.lower_position_limit[i], m.upper_position_limit[i]);
            if q[k] < lo || q[k] > hi {
                return Err(field_err(
                    path,
                    field,
                    format!(
                        "entry {k} ({}) = {} lies outside the joint limits [{lo}, {hi}]",
                        name_of(slot),
                        q[k]
                    ),
                ));
            }
        }
        Ok(())
    };
    if let Some(q) = &file.robot.transport_posture {
        check_arm("robot.transport_posture", q)?;
    }
    if let Some(q) = &file.start.q_arm {
        check_arm("start.q_arm", q)?;
    }
    let transport = file
        .robot
        .transport_posture
        .clone()
        .or_else(|| file.start.q_arm.clone())
        .unwrap_or_else(|| vec![0.0; na]);
    let q_arm0 = file
        .start
        .q_arm
        .clone()
        .unwrap_or_else(|| transport.clone());
    // every arm joint: the listed ones from the file, the others at zero
    let full = |listed: &[f64]| {
        let mut q = vec![0.0; arm.len()];
        for (&slot, &x) in slots.iter().zip(listed) {
            q[slot] = x;
        }
        q
    };
    Ok((full(&transport), full(&q_arm0)))
}

/// The arm slots of the joints `robot.arm_joints` names: each an arm joint (not the
/// platform or a tracked wheel), named once; the arm joints left out must admit 0.
fn arm_joint_slots(names: &[String], robot: &WheeledModel, path: &Path) -> Result<Vec<usize>> {
    let m = &robot.model;
    let arm = robot.arm_dofs();
    let mut slots = Vec::with_capacity(names.len());
    for (k, n) in names.iter().enumerate() {
        let field = format!("robot.arm_joints[{k}]");
        let j = m.joint_id(n).map_err(|e| field_err(path, &field, e))?;
        let slot = arm
            .iter()
            .position(|&i| m.joint_of_dof[i] == j)
            .ok_or_else(|| {
                field_err(
                    path,
                    &field,
                    format!("'{n}' is not an arm joint (the platform, a wheel or a fixed joint)"),
                )
            })?;
        if slots.contains(&slot) {
            return Err(field_err(path, &field, format!("'{n}' is named twice")));
        }
        slots.push(slot);
    }
    for (slot, &i) in arm.iter().enumerate() {
        let (lo, hi) = (m.lower_position_limit[i], m.upper_position_limit[i]);
        if !slots.contains(&slot) && (lo > 0.0 || hi < 0.0) {
            return Err(field_err(
                path,
                "robot.arm_joints",
                format!(
                    "'{}' is not named, so it stays at 0, outside its joint limits [{lo}, {hi}]",
                    m.names[m.joint_of_dof[i].0]
                ),
            ));
        }
    }
    Ok(slots)
}

/// `path` with `.` components dropped and each `..` cancelling the component before it
/// (lexically, without following symbolic links), so `scenarios/../out` is `out`.
fn lexical_clean(path: &Path) -> PathBuf {
    use std::path::Component;
    let mut out: Vec<Component<'_>> = Vec::new();
    for c in path.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => match out.last() {
                Some(Component::Normal(_)) => {
                    out.pop();
                }
                Some(Component::RootDir | Component::Prefix(_)) => {}
                _ => out.push(c),
            },
            other => out.push(other),
        }
    }
    if out.is_empty() {
        PathBuf::from(".")
    } else {
        out.iter().collect()
    }
}

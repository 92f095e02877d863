//! The mission file (TOML) and its validation into a ready-to-run [`Mission`].
//!
//! Schema (documented for users in `docs/mission.md`); every table rejects unknown keys,
//! naming the key and the file. Relative paths (`map.file`, `robot.urdf`, `output.dir`)
//! resolve against the folder of the mission file.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::footprint::MissionFootprint;
use super::heights::{BoxSpec, BoxVerdict, block_by_height, place_boxes};
use super::plant::{MissionContact, start_configuration};
use super::task::{
    Task, TaskSpec, load_task, object_under_footprint, scene_outlines, task_geometry_options,
};
use crate::collision::{GeometryModel, GeometryOptions, Scene};
use crate::contact::{ContactSpec, PlantKind};
use crate::control::mpc::WholeBodyMpc;
use crate::error::{Error, Result};
use crate::mobile::{Caster, DiffDrive, WheeledBase, WheeledModel};
use crate::multibody::{FrameIndex, RootJoint};
use crate::planning::LoadedMap;
use crate::sim::model_mismatch::{ModelPerturbation, SensorNoise};
use crate::sim::mpc_table::{MpcSpec, build_mpc};
use crate::sim::uncertainty::{Draw, UncertaintySpec, perturb, sensor_noise};

/// The mission file as written.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MissionFile {
    /// Free-text title (default: the file name).
    #[serde(default)]
    pub name: Option<String>,
    /// The map.
    pub map: MapSpec,
    /// The robot.
    pub robot: RobotSpec,
    /// Start state.
    pub start: StartSpec,
    /// Goal (required without `[task]`; with it, not taken: the base goal is the placement).
    #[serde(default)]
    pub goal: Option<GoalSpec>,
    /// Platform limits (the mission's own table).
    pub limits: LimitsSpec,
    /// Obstacles that appear during the run.
    #[serde(default)]
    pub obstacles: Vec<ObstacleSpec>,
    /// Controller gains (optional).
    #[serde(default)]
    pub control: ControlSpec,
    /// Simulation settings (optional).
    #[serde(default)]
    pub simulation: SimulationSpec,
    /// The contact plant's law, step and casters (`simulation.plant = "contact"`; the
    /// `[contact]` table of `moma simulate`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactSpec>,
    /// How the plant differs from the model the controller keeps and the noise on what it
    /// measures (the `[uncertainty]` table of `moma simulate`; `mu` on the contact plant
    /// only).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uncertainty: Option<UncertaintySpec>,
    /// A pick: a scene placed on the map, the object, its grasp and mass (`[task]`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub task: Option<TaskSpec>,
    /// Outputs.
    #[serde(default)]
    pub output: OutputSpec,
}

/// `[map]`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MapSpec {
    /// ROS `map_server` YAML, Moving AI `.map`, or a bare PGM/PNG image.
    pub file: PathBuf,
    /// Resolution (m/cell) of a bare image (not allowed for YAML or `.map`).
    #[serde(default)]
    pub resolution: Option<f64>,
    /// Treat unknown cells as obstacles (default `true`).
    #[serde(default = "yes")]
    pub unknown_is_obstacle: bool,
    /// `[[map.boxes]]`: obstacles with heights, checked in 3-D against the robot at its
    /// transport posture ([`super::heights`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub boxes: Vec<BoxSpec>,
}

/// `[robot]`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct RobotSpec {
    /// URDF file; its root link is the base frame.
    pub urdf: PathBuf,
    /// Differential drive: `{ r_w, b, d }` (m), or `"urdf"` to read it from the URDF's
    /// wheel joints (`wheel_joints`) and wheel links.
    pub drive: DriveSource,
    /// `[left, right]` wheel joints of the URDF (optional, as in `moma simulate`;
    /// required with `drive = "urdf"`).
    #[serde(default)]
    pub wheel_joints: Option<[String; 2]>,
    /// Passive casters, as in `moma simulate` (at least one when given).
    #[serde(default)]
    pub casters: Option<Vec<CasterSpec>>,
    /// Radius (m) of the disk that covers the base, for the configuration space (or
    /// `footprint`).
    #[serde(default)]
    pub footprint_radius: Option<f64>,
    /// The end-effector frame (default: the URDF's last link).
    #[serde(default)]
    pub end_effector: Option<String>,
    /// Arm joint angles of the transport posture (default: `start.q_arm`, else zeros).
    #[serde(default)]
    pub transport_posture: Option<Vec<f64>>,
    /// Gravity magnitude (m/s², default 9.81).
    #[serde(default)]
    pub gravity: Option<f64>,
    // --- a robot described by its URDF package (drive, casters, footprint, arm joints) ---
    /// Folders against which `package://PKG/...` mesh URIs resolve (relative to the
    /// mission file), as `moma collision --package-dir`.
    #[serde(default)]
    pub package_dirs: Vec<PathBuf>,
    /// A casters file (`[[casters]]` tables, [`crate::mobile::read_casters`]; relative to
    /// the mission file) instead of `casters`.
    #[serde(default)]
    pub casters_file: Option<PathBuf>,
    /// The footprint from the robot: `"robot"` or `{ from = "robot", padding = m }`
    /// instead of `footprint_radius`.
    #[serde(default)]
    pub footprint: Option<FootprintSpec>,
    /// The joints `transport_posture` and `start.q_arm` give angles for, in that order
    /// (default: every arm joint in model order); the arm joints not named stay at 0.
    #[serde(default)]
    pub arm_joints: Option<Vec<String>>,
}

/// `robot.drive`: given, or read from the URDF.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DriveSource {
    /// `drive = "urdf"`: [`crate::mobile::wheeled_base_from_urdf`] on `wheel_joints`.
    Urdf,
    /// `drive = { r_w, b, d }`.
    Given(DriveSpec),
}

impl<'de> Deserialize<'de> for DriveSource {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        match toml::Value::deserialize(d)? {
            toml::Value::String(s) if s == "urdf" => Ok(Self::Urdf),
            toml::Value::String(s) => Err(D::Error::custom(format!(
                "expected \"urdf\" or a table {{ r_w, b, d }}, got \"{s}\""
            ))),
            other => DriveSpec::deserialize(other)
                .map(Self::Given)
                .map_err(|e| D::Error::custom(e.message())),
        }
    }
}

impl Serialize for DriveSource {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            Self::Urdf => s.serialize_str("urdf"),
            Self::Given(d) => d.serialize(s),
        }
    }
}

/// `robot.footprint`: `"robot"` or `{ from = "robot", padding = m }`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FootprintSpec {
    /// Added to the radius of the robot's footprint (m, default 0).
    pub padding: f64,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FootprintTable {
    from: String,
    #[serde(default)]
    padding: f64,
}

impl<'de> Deserialize<'de> for FootprintSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error as _;
        let from_robot = |from: &str| {
            if from == "robot" {
                Ok(())
            } else {
                Err(D::Error::custom(format!(
                    "the footprint comes \"from\" = \"robot\" (or give robot.footprint_radius), got \"{from}\""
                )))
            }
        };
        match toml::Value::deserialize(d)? {
            toml::Value::String(s) => from_robot(&s).map(|()| Self { padding: 0.0 }),
            other => {
                let t = FootprintTable::deserialize(other)
                    .map_err(|e| D::Error::custom(e.message()))?;
                from_robot(&t.from).map(|()| Self { padding: t.padding })
            }
        }
    }
}

impl Serialize for FootprintSpec {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        use serde::ser::SerializeStruct as _;
        let mut t = s.serialize_struct("FootprintSpec", 2)?;
        t.serialize_field("from", "robot")?;
        t.serialize_field("padding", &self.padding)?;
        t.end()
    }
}

/// Differential-drive geometry.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct DriveSpec {
    /// Wheel radius (m).
    pub r_w: f64,
    /// Half track (m).
    pub b: f64,
    /// Base frame origin ahead of the driven-axle midpoint along the heading (m; any
    /// finite value, negative behind it). The mission plans and tracks the axle midpoint
    /// (the unicycle point); see [`super::reference::Reference`].
    pub d: f64,
}

/// A passive caster (support point in the base frame).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CasterSpec {
    /// Name.
    pub name: String,
    /// Contact point `[x, y]` in the base frame (m).
    pub position: [f64; 2],
}

/// `[start]`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct StartSpec {
    /// Base pose `[x, y, θ]` in the world (m, rad).
    pub pose: [f64; 3],
    /// Initial arm joint angles (default: the transport posture).
    #[serde(default)]
    pub q_arm: Option<Vec<f64>>,
}

/// `[goal]`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct GoalSpec {
    /// Base pose `[x, y, θ]` (m, rad).
    pub pose: [f64; 3],
    /// End-effector target `[x, y, z]` in the world (m), reached at the goal.
    #[serde(default)]
    pub end_effector: Option<[f64; 3]>,
    /// Position tolerance of the base at the goal (m, default 0.10).
    #[serde(default = "default_pos_tol")]
    pub position_tolerance: f64,
    /// Heading tolerance at the goal (rad, default 0.10).
    #[serde(default = "default_heading_tol")]
    pub heading_tolerance: f64,
    /// End-effector tolerance (m, default 0.02).
    #[serde(default = "default_ee_tol")]
    pub end_effector_tolerance: f64,
}

impl GoalSpec {
    /// A base pose to reach with the given tolerances, without an end-effector target.
    #[must_use]
    pub fn base_pose(pose: [f64; 3], position_tolerance: f64, heading_tolerance: f64) -> Self {
        Self {
            pose,
            end_effector: None,
            position_tolerance,
            heading_tolerance,
            end_effector_tolerance: default_ee_tol(),
        }
    }
}

/// `[limits]`.
#[derive(Debug, Clone, Copy, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct LimitsSpec {
    /// Largest forward speed (m/s).
    pub v_max: f64,
    /// Largest yaw rate (rad/s).
    pub omega_max: f64,
    /// Largest linear acceleration (m/s²).
    pub a_max: f64,
    /// Largest angular acceleration (rad/s²).
    pub alpha_max: f64,
    /// Tyre-ground friction coefficient (slip monitor).
    pub mu: f64,
    /// Largest path curvature (1/m) of the smoothed path (default 2: turns of at least
    /// 0.5 m radius).
    #[serde(default = "default_kappa_max")]
    pub kappa_max: f64,
    /// Fraction of the tip-over acceleration limits the timing may use (default 0.8).
    #[serde(default = "default_tip_fraction")]
    pub tip_fraction: f64,
}

/// `[[obstacles]]`: a disk that appears at time `t`.
#[derive(Debug, Clone, Copy, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleSpec {
    /// Appearance time (s).
    pub t: f64,
    /// Centre `[x, y]` (m, world).
    pub center: [f64; 2],
    /// Radius (m).
    pub radius: f64,
}

/// `control.law`: how the mission drives and reaches.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Deserialize, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum MissionLaw {
    /// Kanayama's law on the timed reference with computed torque, Aicardi's to arrive,
    /// then the task-space reach with the platform held (the gains below).
    #[default]
    DriveThenReach,
    /// The whole-body MPC of `[control.mpc]` (the table of `moma simulate`'s
    /// `[controller.mpc]`): the base reference and the end-effector target at once.
    Mpc,
}

/// `[control]`: the law and its gains (all optional).
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct ControlSpec {
    /// The law (default `drive_then_reach`).
    pub law: MissionLaw,
    /// Kanayama K_x (1/s).
    pub kx: f64,
    /// Kanayama K_y (1/m²).
    pub ky: f64,
    /// Kanayama K_θ (1/m).
    pub kth: f64,
    /// Inner speed loop bandwidth on [v, ω] (1/s).
    pub speed_gain: f64,
    /// Arm joint PD natural frequency (rad/s).
    pub arm_frequency: f64,
    /// End-effector task natural frequency (rad/s).
    pub task_frequency: f64,
    /// Law `mpc`: time between solves (s, default `control.mpc.dt`), a whole number of
    /// `simulation.dt`; the torques are held in between.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub period: Option<f64>,
    /// Law `mpc`: the end-effector target is set at the horizon's knots whose base
    /// reference lies within this horizontal distance of it (m, default 1).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub reach_radius: Option<f64>,
    /// Law `mpc`: the MPC's settings.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mpc: Option<MpcSpec>,
}

impl Default for ControlSpec {
    fn default() -> Self {
        Self {
            kx: 2.0,
            ky: 6.0,
            kth: 3.0,
            speed_gain: 20.0,
            arm_frequency: 12.0,
            task_frequency: 6.0,
            law: MissionLaw::DriveThenReach,
            period: None,
            reach_radius: None,
            mpc: None,
        }
    }
}

/// `[simulation]`.
#[derive(Debug, Clone, Copy, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct SimulationSpec {
    /// Fixed RK4 step and control period (s).
    pub dt: f64,
    /// Recording interval (s).
    pub record_interval: f64,
    /// Give up after this mission time (s); default: 3 × the first plan's duration + 30 s.
    pub time_limit: Option<f64>,
    /// The plant the law drives: `rolling` (the reduced model, RK4 at `dt`; default) or
    /// `contact` (the contact plant of the `[contact]` table, `docs/contact.md`).
    pub plant: PlantKind,
}

impl Default for SimulationSpec {
    fn default() -> Self {
        Self {
            dt: 0.002,
            record_interval: 0.02,
            time_limit: None,
            plant: PlantKind::Rolling,
        }
    }
}

/// `[output]`.
#[derive(Debug, Clone, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Output folder (relative to the mission file).
    #[serde(default = "default_dir")]
    pub dir: PathBuf,
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self { dir: default_dir() }
    }
}

fn yes() -> bool {
    true
}
fn default_pos_tol() -> f64 {
    0.10
}
fn default_heading_tol() -> f64 {
    0.10
}
fn default_ee_tol() -> f64 {
    0.02
}
fn default_kappa_max() -> f64 {
    2.0
}
fn default_tip_fraction() -> f64 {
    0.8
}
fn default_dir() -> PathBuf {
    PathBuf::from("mission-output")
}

/// Most obstacles a mission may list.
pub const MAX_OBSTACLES: usize = 10_000;
/// Most recorded samples a run may produce (time limit / record interval).
pub const MAX_SAMPLES: f64 = 2_000_000.0;
/// Most control steps a run may take (time limit / dt).
pub const MAX_STEPS: f64 = 50_000_000.0;

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

/// Parses the text of a mission file (`path` names it in errors) without validating it
/// or loading its map and robot: [`from_file`] does that.
///
/// # Errors
/// Malformed TOML, an unknown or missing key, a value of the wrong type: one line
/// naming the file, the line and column, and the key.
pub fn parse_file(text: &str, path: &Path) -> Result<MissionFile> {
    toml::from_str(text).map_err(|e| {
        // one line: where, then what (toml's own message, without its source excerpt)
        let at = e.span().map_or_else(String::new, |sp| {
            let before = &text[..sp.start.min(text.len())];
            let line = before.matches('\n').count() + 1;
            let col = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
            format!("line {line}, column {col}: ")
        });
        Error::parse(
            path,
            format!("{at}{}", e.message().trim().replace('\n', "; ")),
        )
    })
}

fn field_err(path: &Path, field: &str, msg: impl std::fmt::Display) -> Error {
    Error::parse(path, format!("{field}: {msg}"))
}

fn finite(path: &Path, field: &str, xs: &[f64]) -> Result<()> {
    if let Some(i) = crate::error::first_non_finite(xs) {
        return Err(field_err(
            path,
            field,
            format!("entry {i} is not a finite number"),
        ));
    }
    Ok(())
}

fn positive(path: &Path, field: &str, x: f64) -> Result<()> {
    match crate::error::not_positive_finite(x) {
        Some(problem) => Err(field_err(path, field, problem)),
        None => Ok(()),
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
    let boxes = match &geometry {
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
        None => Vec::new(),
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
    let task = match &file.task {
        None => None,
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
            )?;
            place_scene_on_map(
                &mut task,
                &file,
                path,
                &mut map,
                (&robot, transport.as_slice()),
                &footprint,
            )?;
            Some(task)
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
        package_dirs,
        contact,
        plant_robot,
        sensor_noise,
        task,
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

/// `[goal]` is required without `[task]`; with it, the goal is optional (the base drives
/// on to it after the pick) and takes no end-effector target, and `[uncertainty]` is not
/// offered (the payload is attached to the mission's own model and, on the contact plant,
/// to the contact plant's).
fn check_goal_and_task(file: &MissionFile, path: &Path) -> Result<()> {
    match (&file.goal, &file.task) {
        (None, None) => Err(field_err(
            path,
            "goal",
            "missing: give [goal] (or a [task] to pick)",
        )),
        (Some(g), Some(_)) if g.end_effector.is_some() => Err(field_err(
            path,
            "goal.end_effector",
            "a mission with [task] drives on to the goal pose after the pick; it takes no \
             end-effector target",
        )),
        (_, Some(_)) if file.uncertainty.is_some() => Err(field_err(
            path,
            "uncertainty",
            "a [task] takes no [uncertainty] (its payload is the model's own)",
        )),
        _ => Ok(()),
    }
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

/// The limits, the control gains and the start and goal poses are positive or finite as
/// each must be.
fn check_limits_and_gains(file: &MissionFile, path: &Path) -> Result<()> {
    let l = &file.limits;
    for (n, x) in [
        ("limits.v_max", l.v_max),
        ("limits.omega_max", l.omega_max),
        ("limits.a_max", l.a_max),
        ("limits.alpha_max", l.alpha_max),
        ("limits.mu", l.mu),
        ("limits.kappa_max", l.kappa_max),
        ("simulation.dt", file.simulation.dt),
        (
            "simulation.record_interval",
            file.simulation.record_interval,
        ),
    ] {
        positive(path, n, x)?;
    }
    if let Some(r) = file.robot.footprint_radius {
        positive(path, "robot.footprint_radius", r)?;
    }
    if let DriveSource::Given(d) = &file.robot.drive {
        positive(path, "robot.drive.r_w", d.r_w)?;
        positive(path, "robot.drive.b", d.b)?;
    }
    if !(l.tip_fraction > 0.0 && l.tip_fraction <= 1.0) {
        return Err(field_err(
            path,
            "limits.tip_fraction",
            format!("must lie in (0, 1], got {}", l.tip_fraction),
        ));
    }
    let c = &file.control;
    for (n, x) in [
        ("control.kx", c.kx),
        ("control.ky", c.ky),
        ("control.kth", c.kth),
        ("control.speed_gain", c.speed_gain),
        ("control.arm_frequency", c.arm_frequency),
        ("control.task_frequency", c.task_frequency),
    ] {
        positive(path, n, x)?;
    }
    finite(path, "start.pose", &file.start.pose)?;
    if let Some(g) = &file.goal {
        for (n, x) in [
            ("goal.position_tolerance", g.position_tolerance),
            ("goal.heading_tolerance", g.heading_tolerance),
            ("goal.end_effector_tolerance", g.end_effector_tolerance),
        ] {
            positive(path, n, x)?;
        }
        finite(path, "goal.pose", &g.pose)?;
        if let Some(ee) = &g.end_effector {
            finite(path, "goal.end_effector", ee)?;
        }
    }
    Ok(())
}

/// The simulation's step, record interval and time limit, and the step and sample counts
/// they imply, are bounded.
fn check_simulation(file: &MissionFile, path: &Path) -> Result<()> {
    if let Some(tl) = file.simulation.time_limit {
        positive(path, "simulation.time_limit", tl)?;
        if tl / file.simulation.dt > MAX_STEPS {
            return Err(field_err(
                path,
                "simulation.time_limit",
                format!(
                    "{tl} s at dt = {} s is more than {MAX_STEPS:e} steps",
                    file.simulation.dt
                ),
            ));
        }
        if tl / file.simulation.record_interval > MAX_SAMPLES {
            return Err(field_err(
                path,
                "simulation.time_limit",
                format!(
                    "{tl} s at record_interval = {} s is more than {MAX_SAMPLES:e} samples",
                    file.simulation.record_interval
                ),
            ));
        }
    }
    if file.simulation.record_interval < file.simulation.dt {
        return Err(field_err(
            path,
            "simulation.record_interval",
            format!(
                "must be at least simulation.dt = {} s, got {}",
                file.simulation.dt, file.simulation.record_interval
            ),
        ));
    }
    if file.simulation.dt > 0.05 {
        return Err(field_err(
            path,
            "simulation.dt",
            format!(
                "at most 0.05 s (the control period), got {}",
                file.simulation.dt
            ),
        ));
    }
    Ok(())
}

/// The obstacles (count, centres, times, radii), the caster positions and the gravity.
fn check_obstacles_and_robot(file: &MissionFile, path: &Path) -> Result<()> {
    if file.obstacles.len() > MAX_OBSTACLES {
        return Err(field_err(
            path,
            "obstacles",
            format!(
                "at most {MAX_OBSTACLES} obstacles, got {}",
                file.obstacles.len()
            ),
        ));
    }
    for (k, o) in file.obstacles.iter().enumerate() {
        let f = format!("obstacles[{k}]");
        finite(path, &format!("{f}.center"), &o.center)?;
        if !(o.t.is_finite() && o.t >= 0.0) {
            return Err(field_err(
                path,
                &format!("{f}.t"),
                format!("must be a finite time >= 0, got {}", o.t),
            ));
        }
        positive(path, &format!("{f}.radius"), o.radius)?;
    }
    if let Some(list) = &file.robot.casters
        && let Some(problem) = crate::mobile::caster_list_problem(&casters_of(list))
    {
        return Err(Error::parse(path, format!("robot.casters{problem}")));
    }
    if let Some(g) = file.robot.gravity {
        positive(path, "robot.gravity", g)?;
    }
    Ok(())
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

/// `robot.casters` as the mobile module's casters.
fn casters_of(list: &[CasterSpec]) -> Vec<Caster> {
    list.iter()
        .map(|c| Caster {
            name: c.name.clone(),
            position: c.position,
        })
        .collect()
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
        (Some(list), None) => Ok(casters_of(list)),
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

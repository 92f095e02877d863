//! The mission file as written: its tables (serde, every table refusing unknown keys,
//! naming the key and the file), the bounds on its counts, [`parse_file`], and the
//! checks that need nothing but the file (goal and task, limits and gains, simulation,
//! obstacles and robot). Loading the map, the robot and the rest into a
//! [`super::scenario::Mission`] is `scenario`'s.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::heights::BoxSpec;
use super::task::TaskSpec;
use crate::contact::{ContactSpec, PlantKind};
use crate::error::{Error, Result};
use crate::mobile::Caster;
use crate::planning::trajectory::DiffDriveLimits;
use crate::sim::mpc_table::MpcSpec;
use crate::sim::uncertainty::UncertaintySpec;

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
    pub casters: Option<Vec<Caster>>,
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

impl LimitsSpec {
    /// The platform limits the timing and the law hold the base to.
    #[must_use]
    pub fn platform(&self) -> DiffDriveLimits {
        DiffDriveLimits {
            v_max: self.v_max,
            omega_max: self.omega_max,
            a_max: self.a_max,
            alpha_max: self.alpha_max,
        }
    }
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

pub(super) fn field_err(path: &Path, field: &str, msg: impl std::fmt::Display) -> Error {
    Error::parse(path, format!("{field}: {msg}"))
}

pub(super) fn finite(path: &Path, field: &str, xs: &[f64]) -> Result<()> {
    if let Some(i) = crate::error::first_non_finite(xs) {
        return Err(field_err(
            path,
            field,
            format!("entry {i} is not a finite number"),
        ));
    }
    Ok(())
}

pub(super) fn positive(path: &Path, field: &str, x: f64) -> Result<()> {
    match crate::error::not_positive_finite(x) {
        Some(problem) => Err(field_err(path, field, problem)),
        None => Ok(()),
    }
}

/// `[goal]` is required without `[task]`; with it, the goal is optional (the base drives
/// on to it after the pick) and takes no end-effector target, and `[uncertainty]` is not
/// offered (the payload is attached to the mission's own model and, on the contact plant,
/// to the contact plant's).
pub(super) fn check_goal_and_task(file: &MissionFile, path: &Path) -> Result<()> {
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

/// The limits, the control gains and the start and goal poses are positive or finite as
/// each must be.
pub(super) fn check_limits_and_gains(file: &MissionFile, path: &Path) -> Result<()> {
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
pub(super) fn check_simulation(file: &MissionFile, path: &Path) -> Result<()> {
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
pub(super) fn check_obstacles_and_robot(file: &MissionFile, path: &Path) -> Result<()> {
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
        && let Some(problem) = crate::mobile::caster_list_problem(list)
    {
        return Err(Error::parse(path, format!("robot.casters{problem}")));
    }
    if let Some(g) = file.robot.gravity {
        positive(path, "robot.gravity", g)?;
    }
    Ok(())
}

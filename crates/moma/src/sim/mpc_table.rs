//! The whole-body MPC's settings table, one schema for both files that run it:
//! `[controller.mpc]` of `moma simulate` (`crate::sim_config::mpc`) and `[control.mpc]` of
//! `moma mission` (`crate::mission`). [`build_mpc`] checks every value given (the defaults
//! are [`MpcSettings`]'), loads the collision model and scene of the clearance constraint
//! and builds the [`WholeBodyMpc`]; every error is an [`Error::Scenario`] naming the
//! table's field (the table's name is the caller's) or the robot's.

use std::path::{Path, PathBuf};

use nalgebra::DVector;
use serde::{Deserialize, Serialize};

use crate::collision::{GeometryModel, GeometryOptions, Scene, SceneOptions, read_scene};
use crate::control::mpc::{Clearance, MpcRobot, MpcSettings, WholeBodyMpc};
use crate::error::{Error, Result, chain, not_positive_finite};
use crate::mobile::WheeledModel;
use crate::stability::{BodySet, StabilityModel, SupportAttachment, SupportPolygon};

/// An [`Error::Scenario`] with a formatted message.
macro_rules! bail {
    ($($t:tt)*) => {
        return Err(Error::Scenario(format!($($t)*)))
    };
}

/// Most joints the MPC may move (each adds two states and one input).
const MAX_MOVED_JOINTS: usize = 64;

/// Most stages of the horizon.
const MAX_STAGES: i64 = 10_000;

fn err(message: String) -> Error {
    Error::Scenario(message)
}

/// `Err` naming `field[i]` unless every value is finite.
fn finite(field: &str, xs: &[f64]) -> Result<()> {
    if let Some(i) = crate::error::first_non_finite(xs) {
        bail!("{field}[{i}] is not a finite number");
    }
    Ok(())
}

/// The `weights` table of the MPC's table: any of [`crate::control::mpc::CostWeights`].
#[derive(Clone, Debug, Default, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct WeightsSpec {
    /// Base position error (1/m²).
    pub base_position: Option<f64>,
    /// Base heading error (1/rad²).
    pub base_yaw: Option<f64>,
    /// End-effector position error (1/m²).
    pub ee_position: Option<f64>,
    /// End-effector orientation error to the world axes (1/rad²).
    pub ee_orientation: Option<f64>,
    /// Platform velocities.
    pub platform_velocity: Option<f64>,
    /// Joint velocities.
    pub joint_velocity: Option<f64>,
    /// Platform accelerations.
    pub platform_acceleration: Option<f64>,
    /// Joint accelerations.
    pub joint_acceleration: Option<f64>,
    /// Distance of the moved joints to the posture (the initial configuration).
    pub posture: Option<f64>,
    /// Factor of the state costs at the last knot.
    pub terminal: Option<f64>,
}

/// The MPC's table (`[controller.mpc]` of `moma simulate`, `[control.mpc]` of `moma mission`).
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct MpcSpec {
    /// The joints the MPC moves (URDF names; arm joints of the platform). The others are
    /// held where the initial configuration puts them.
    pub joints: Vec<String>,
    /// Stages N of the horizon (default 20).
    #[serde(default)]
    pub stages: Option<i64>,
    /// Stage length (s, default 0.05); the horizon is `stages · dt`.
    #[serde(default)]
    pub dt: Option<f64>,
    /// Bound on `|v̇|` (m/s², default 3).
    #[serde(default)]
    pub max_linear_acceleration: Option<f64>,
    /// Bound on `|ω̇|` (rad/s², default 6).
    #[serde(default)]
    pub max_angular_acceleration: Option<f64>,
    /// Bound on each moved joint's `|q̈|` (default 6).
    #[serde(default)]
    pub max_joint_acceleration: Option<f64>,
    /// Cost weights.
    #[serde(default)]
    pub weights: WeightsSpec,
    /// Smallest ZMP margin (m, default 0.05); `false`: no tip-over constraint.
    #[serde(default)]
    pub zmp_margin: Option<toml::Value>,
    /// Smallest distance between enabled link pairs and to the scene (m, default 0.03);
    /// `false`: no clearance constraint (and no collision model).
    #[serde(default)]
    pub clearance: Option<toml::Value>,
    /// Smallest clearance (m, finite, ≥ 0) of the base footprint (`moma mission`: the
    /// disk of `robot.footprint_radius` about the base frame origin) to the map's
    /// obstacles, on the mission planner's distance transform; absent: no map-clearance
    /// constraint. Only `moma mission` has a map: `moma simulate` refuses it.
    #[serde(default)]
    pub map_clearance: Option<f64>,
    /// Self pairs farther apart than this at the start of a solve are skipped in it (m,
    /// default 0.25; `inf`: every enabled pair).
    #[serde(default)]
    pub activation_distance: Option<f64>,
    /// Clearance rows per knot: one for each of the nearest this many pairs (1 to 64,
    /// default 4).
    #[serde(default)]
    pub clearance_pairs: Option<i64>,
    /// Band above the clearance's set value within which an inactive clearance row still
    /// gives the step's model its curvature (m, finite, ≥ 0, default 0.003; 0: none).
    #[serde(default)]
    pub clearance_band: Option<f64>,
    /// Distance kept from the joint position limits (default 0.02).
    #[serde(default)]
    pub position_margin: Option<f64>,
    /// Fraction of the torque limits the MPC plans with, in (0, 1] (default 1).
    #[serde(default)]
    pub torque_fraction: Option<f64>,
    /// Augmented-Lagrangian penalty (default 1000).
    #[serde(default)]
    pub penalty: Option<f64>,
    /// Largest augmented-Lagrangian multiplier (default 1000).
    #[serde(default)]
    pub max_multiplier: Option<f64>,
    /// Length scaling the ZMP and clearance constraints (m, default 0.02).
    #[serde(default)]
    pub length_scale: Option<f64>,
    /// Solver iterations per solve at most (default 4).
    #[serde(default)]
    pub max_iterations: Option<i64>,
    /// Solver tolerance on the predicted decrease (default 1e-6).
    #[serde(default)]
    pub tolerance: Option<f64>,
    /// MoveIt planning-scene YAML of the obstacles (as `moma collision --scene`), relative
    /// to the scenario; poses in `world` (or `map`, `odom`).
    #[serde(default)]
    pub scene: Option<PathBuf>,
    /// Folders against which `package://` URIs of the URDF and the scene resolve.
    #[serde(default)]
    pub package_dirs: Vec<PathBuf>,
    /// SRDF whose `<disable_collisions>` pairs are not checked.
    #[serde(default)]
    pub srdf: Option<PathBuf>,
}

/// `Some(x)` for a positive finite `x`, else the error naming `{table}.{name}`.
fn positive(table: &str, name: &str, x: Option<f64>) -> Result<Option<f64>> {
    if let Some(problem) = x.and_then(not_positive_finite) {
        bail!("{table}.{name} {problem}");
    }
    Ok(x)
}

/// `Some(x)` for a finite `x ≥ 0`, else the error naming `{table}.{name}`.
fn non_negative(table: &str, name: &str, x: Option<f64>) -> Result<Option<f64>> {
    if let Some(x) = x {
        finite(&format!("{table}.{name}"), &[x])?;
        if x < 0.0 {
            bail!("{table}.{name} must not be negative, got {x}");
        }
    }
    Ok(x)
}

/// A count of at least 1 and at most `max`.
fn count(table: &str, name: &str, x: Option<i64>, max: i64) -> Result<Option<usize>> {
    match x {
        Some(n) if !(1..=max).contains(&n) => {
            bail!("{table}.{name} must be between 1 and {max}, got {n}")
        }
        _ => Ok(x.map(|n| n as usize)),
    }
}

/// A constraint's set value: a finite number, or `false` (off); absent: `default`.
fn set_value(
    table: &str,
    name: &str,
    v: Option<&toml::Value>,
    default: Option<f64>,
) -> Result<Option<f64>> {
    match v {
        None => Ok(default),
        Some(toml::Value::Boolean(false)) => Ok(None),
        Some(toml::Value::Float(x)) => {
            finite(&format!("{table}.{name}"), &[*x])?;
            Ok(Some(*x))
        }
        Some(toml::Value::Integer(i)) => Ok(Some(*i as f64)),
        Some(other) => bail!(
            "{table}.{name} must be a number (m) or false, got {}",
            other.type_str()
        ),
    }
}

/// The MPC's settings: the defaults overridden by the table `table`, every value checked.
fn settings(spec: &MpcSpec, table: &str) -> Result<MpcSettings> {
    let mut s = MpcSettings::default();
    if let Some(n) = count(table, "stages", spec.stages, MAX_STAGES)? {
        s.stages = n;
    }
    for (name, x, field) in [
        ("dt", spec.dt, &mut s.dt),
        (
            "max_linear_acceleration",
            spec.max_linear_acceleration,
            &mut s.max_linear_acceleration,
        ),
        (
            "max_angular_acceleration",
            spec.max_angular_acceleration,
            &mut s.max_angular_acceleration,
        ),
        (
            "max_joint_acceleration",
            spec.max_joint_acceleration,
            &mut s.max_joint_acceleration,
        ),
        ("penalty", spec.penalty, &mut s.constraints.penalty),
        (
            "max_multiplier",
            spec.max_multiplier,
            &mut s.constraints.max_multiplier,
        ),
        (
            "length_scale",
            spec.length_scale,
            &mut s.constraints.length_scale,
        ),
        ("tolerance", spec.tolerance, &mut s.solver.tolerance),
        (
            "torque_fraction",
            spec.torque_fraction,
            &mut s.constraints.torque_fraction,
        ),
    ] {
        if let Some(x) = positive(table, name, x)? {
            *field = x;
        }
    }
    if s.constraints.torque_fraction > 1.0 {
        bail!(
            "{table}.torque_fraction must be at most 1, got {}",
            s.constraints.torque_fraction
        );
    }
    if let Some(n) = count(table, "max_iterations", spec.max_iterations, 1000)? {
        s.solver.max_iterations = n;
    }
    if let Some(n) = count(table, "clearance_pairs", spec.clearance_pairs, 64)? {
        s.constraints.clearance_pairs = n;
    }
    if let Some(b) = non_negative(table, "clearance_band", spec.clearance_band)? {
        s.constraints.clearance_band = b;
    }
    if let Some(m) = non_negative(table, "position_margin", spec.position_margin)? {
        s.constraints.position_margin = m;
    }
    if let Some(a) = spec.activation_distance {
        if a.is_nan() || a <= 0.0 {
            bail!("{table}.activation_distance must be positive (or inf), got {a}");
        }
        s.constraints.activation_distance = a;
    }
    s.constraints.zmp_margin = set_value(
        table,
        "zmp_margin",
        spec.zmp_margin.as_ref(),
        s.constraints.zmp_margin,
    )?;
    s.constraints.clearance = set_value(
        table,
        "clearance",
        spec.clearance.as_ref(),
        s.constraints.clearance,
    )?;
    if let Some(m) = non_negative(table, "map_clearance", spec.map_clearance)? {
        s.constraints.map_clearance = Some(m);
    }
    let w = &spec.weights;
    let cw = &mut s.weights;
    for (name, x, field) in [
        ("base_position", w.base_position, &mut cw.base_position),
        ("base_yaw", w.base_yaw, &mut cw.base_yaw),
        ("ee_position", w.ee_position, &mut cw.ee_position),
        ("ee_orientation", w.ee_orientation, &mut cw.ee_orientation),
        (
            "platform_velocity",
            w.platform_velocity,
            &mut cw.platform_velocity,
        ),
        ("joint_velocity", w.joint_velocity, &mut cw.joint_velocity),
        (
            "platform_acceleration",
            w.platform_acceleration,
            &mut cw.platform_acceleration,
        ),
        (
            "joint_acceleration",
            w.joint_acceleration,
            &mut cw.joint_acceleration,
        ),
        ("posture", w.posture, &mut cw.posture),
        ("terminal", w.terminal, &mut cw.terminal),
    ] {
        if let Some(x) = non_negative(table, &format!("weights.{name}"), x)? {
            *field = x;
        }
    }
    Ok(s)
}

/// The collision model and scene of the clearance constraint; `base_dir` resolves the
/// table's paths and `urdf` (the robot's file).
fn clearance(
    spec: &MpcSpec,
    table: &str,
    wm: &WheeledModel,
    urdf: &Path,
    base_dir: &Path,
) -> Result<Clearance> {
    let package_dirs: Vec<PathBuf> = spec.package_dirs.iter().map(|d| base_dir.join(d)).collect();
    let options = GeometryOptions {
        package_dirs: package_dirs.clone(),
        srdf: spec.srdf.as_ref().map(|s| base_dir.join(s)),
    };
    let geometry = GeometryModel::from_urdf(&wm.model, urdf, &options).map_err(|e| {
        err(format!(
            "{table} (the robot's collision model: package_dirs, srdf): {}",
            chain(&e)
        ))
    })?;
    let scene = match &spec.scene {
        None => Scene::default(),
        Some(p) => read_scene(
            &base_dir.join(p),
            &SceneOptions {
                world_frames: vec!["world".into(), "map".into(), "odom".into()],
                package_dirs,
            },
        )
        .map_err(|e| err(format!("{table}.scene {}: {}", p.display(), chain(&e))))?,
    };
    Ok(Clearance { geometry, scene })
}

/// The whole-body MPC of `spec` (the table named `table` in its file) on `wm` (loaded
/// from `urdf`), its end effector the frame `frame` (set by the file's field
/// `frame_field`), its posture and held joints at the configuration `q0`; `base_dir`
/// resolves the table's paths.
///
/// # Errors
/// [`Error::Scenario`] naming the `{table}.*` field, the frame, a joint, or the robot's
/// wheel joints and casters.
#[allow(clippy::too_many_arguments)]
pub fn build_mpc(
    spec: &MpcSpec,
    table: &str,
    frame: &str,
    frame_field: &str,
    wm: &WheeledModel,
    urdf: &Path,
    q0: &[f64],
    base_dir: &Path,
) -> Result<WholeBodyMpc> {
    let settings = settings(spec, table)?;
    if spec.joints.is_empty() || spec.joints.len() > MAX_MOVED_JOINTS {
        bail!(
            "{table}.joints: give 1 to {MAX_MOVED_JOINTS} arm joints to move, got {}",
            spec.joints.len()
        );
    }
    if wm.wheel_dofs().is_none() {
        bail!(
            "robot.wheel_joints: law mpc needs the tracked wheel joints (their torque and \
             speed limits)"
        );
    }
    let support = SupportPolygon::from_wheeled_model(wm)
        .map_err(|e| err(format!("robot.casters: {}", chain(&e))))?;
    let stability = StabilityModel::new(&wm.model, support, SupportAttachment::Base, &BodySet::All)
        .map_err(|e| err(format!("robot: {}", chain(&e))))?;
    let clear = match settings.constraints.clearance {
        Some(_) => Some(clearance(spec, table, wm, urdf, base_dir)?),
        None => {
            if spec.scene.is_some() {
                bail!("{table}.scene needs the clearance constraint (clearance = false)");
            }
            None
        }
    };
    let moved: Vec<&str> = spec.joints.iter().map(String::as_str).collect();
    let robot = MpcRobot::new(wm.clone(), stability, clear, &moved, frame)
        .map_err(|e| err(format!("{table}.joints / {frame_field}: {}", chain(&e))))?;
    let q_start = DVector::from_column_slice(q0);
    WholeBodyMpc::new(robot, settings, &q_start).map_err(|e| err(format!("{table}: {}", chain(&e))))
}

//! The robot of a `moma simulate` scenario: a chapter model, a URDF robot on a
//! differential drive, or a fixed-base URDF arm, with the checks of `[robot]` and the
//! top-level `gravity`.

use std::path::Path;

use super::{Context, bail, finite};
use crate::closed_form::ChapterModel;
use crate::error::Result;
use crate::mobile::Caster;
use crate::sim::chapter_models::chapter_system;
use crate::sim::reduced_system::ReducedSystem;
use crate::sim_config::schema::{DriveSpec, RobotSpec};

/// Builds the robot of a scenario and the name the summary gives it; `base_dir` resolves
/// relative URDF paths. A free-floating robot is refused (the space run builds it).
///
/// # Errors
/// [`crate::Error::Scenario`] naming the `robot.*` field or the URDF at fault.
pub fn build_robot(
    spec: &RobotSpec,
    gravity: Option<f64>,
    base_dir: &Path,
) -> Result<(Box<dyn ReducedSystem>, String)> {
    match spec {
        RobotSpec::Chapter { model, params } => {
            check_params(params)?;
            let is_m5 = matches!(
                ChapterModel::from_name(model),
                Ok(ChapterModel::M5MobileManipulator)
            );
            if let Some(g) = gravity
                && !is_m5
            {
                bail!(
                    "gravity = {g}: chapter model {model} has no gravity term (it moves in \
                     the horizontal plane or in free space); remove the top-level `gravity` \
                     (only m5 uses it)"
                );
            }
            let json = chapter_params_json(params, gravity, is_m5)?;
            let sys = chapter_system(model, &json).ctx("robot")?;
            Ok((sys, format!("chapter model {model}")))
        }
        RobotSpec::Urdf {
            urdf,
            drive,
            wheel_joints,
            casters,
        } => {
            let path = base_dir.join(urdf);
            let wm = build_wheeled_model(&path, drive, wheel_joints.clone(), casters, gravity)?;
            let sys = crate::sim::wheeled_system::WheeledSystem::new(wm);
            Ok((Box::new(sys), format!("URDF {}", urdf.display())))
        }
        RobotSpec::FixedBase { urdf } => {
            let model = fixed_base_model(&base_dir.join(urdf), gravity)?;
            let sys = crate::sim::fixed_base::FixedBaseSystem::new(model)
                .with_ctx(|| format!("{}", urdf.display()))?;
            Ok((
                Box::new(sys),
                format!("URDF {} (fixed base)", urdf.display()),
            ))
        }
        RobotSpec::FreeFloating { .. } => {
            bail!("a free-floating robot is run by the space simulation")
        }
    }
}

/// Every chapter parameter must be a finite number.
fn check_params(params: &toml::Table) -> Result<()> {
    for (k, v) in params {
        match v {
            toml::Value::Float(x) if !x.is_finite() => {
                bail!("robot.params.{k} is not a finite number ({x})")
            }
            toml::Value::Float(_) | toml::Value::Integer(_) => {}
            other => bail!(
                "robot.params.{k} must be a number, got {}",
                other.type_str()
            ),
        }
    }
    Ok(())
}

/// The gravity vector of magnitude `g` (default 9.81) along −z.
fn gravity_vector(gravity: Option<f64>) -> Result<nalgebra::Vector3<f64>> {
    let g = gravity.unwrap_or(9.81);
    if !g.is_finite() {
        bail!("gravity is not a finite number");
    }
    Ok(nalgebra::Vector3::new(0.0, 0.0, -g))
}

/// A fixed-base URDF model under gravity `g` (default 9.81) along −z.
///
/// # Errors
/// [`crate::Error`] of the URDF loader, or a non-finite gravity.
pub fn fixed_base_model(path: &Path, gravity: Option<f64>) -> Result<crate::multibody::Model> {
    let mut model =
        crate::io::urdf::model_from_urdf_file(path, crate::multibody::RootJoint::Fixed)?;
    model.gravity = gravity_vector(gravity)?;
    Ok(model)
}

/// The chapter parameters as JSON, with the top-level gravity moved into `g` for m5.
///
/// # Errors
/// [`crate::Error::Scenario`] when gravity is given twice.
pub fn chapter_params_json(
    params: &toml::Table,
    gravity: Option<f64>,
    is_m5: bool,
) -> Result<serde_json::Value> {
    let mut json = serde_json::to_value(params).ctx("robot.params")?;
    if let (Some(g), true) = (gravity, is_m5)
        && let Some(obj) = json.as_object_mut()
    {
        if obj.contains_key("g") {
            bail!("gravity is given twice: top-level `gravity` and robot.params.g");
        }
        obj.insert("g".into(), serde_json::json!(g));
    }
    Ok(json)
}

/// The wheeled model of a URDF robot on a differential drive (also read by the stability
/// monitor).
///
/// # Errors
/// [`crate::Error`] naming `robot.drive`, a caster, the URDF or the gravity.
pub fn build_wheeled_model(
    path: &Path,
    drive: &DriveSpec,
    wheel_joints: Option<[String; 2]>,
    casters: &[Caster],
    gravity: Option<f64>,
) -> Result<crate::mobile::WheeledModel> {
    use crate::mobile::{DiffDrive, WheeledBase, WheeledModel};
    let dd = DiffDrive::new(drive.r_w, drive.b, drive.d).ctx("robot.drive")?;
    for c in casters {
        finite(&format!("robot.casters '{}' position", c.name), &c.position)?;
    }
    let base = WheeledBase {
        drive: dd,
        casters: casters.to_vec(),
        wheel_joints,
    };
    let mut model =
        crate::io::urdf::model_from_urdf_file(path, crate::multibody::RootJoint::Planar)?;
    model.gravity = gravity_vector(gravity)?;
    WheeledModel::new(model, base).with_ctx(|| format!("{}", path.display()))
}

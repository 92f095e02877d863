//! The rolling plant of a closed-loop scenario with `[uncertainty]`: the wheeled URDF
//! robot rebuilt with the draw applied, and the closed loop given that plant and the
//! noise on its measurement (the law keeps the nominal model). Separate from `uncertainty`
//! (the table and its draws) so that the file schema, which holds the table, and this
//! builder, which reads the schema, do not import each other.

use std::path::Path;

use super::{at, bail, chain};
use crate::error::{Error, Result};
use crate::sim::uncertainty::{UncertaintySpec, perturb, sensor_noise};

/// A wheeled URDF robot's table: the URDF, its drive, wheel joints and casters.
type WheeledUrdf<'a> = (
    &'a Path,
    &'a super::schema::DriveSpec,
    &'a Option<[String; 2]>,
    &'a [crate::mobile::Caster],
);

/// The robot of a scenario with `[uncertainty]`, which must be a URDF robot on a wheeled
/// base (errors name the file).
fn wheeled_robot<'a>(sc: &'a super::Scenario, path: &Path) -> Result<WheeledUrdf<'a>> {
    match &sc.robot {
        super::schema::RobotSpec::Urdf {
            urdf,
            drive,
            wheel_joints,
            casters,
        } => Ok((urdf, drive, wheel_joints, casters)),
        _ => bail!(
            "{}",
            at(
                path,
                "[uncertainty] perturbs a URDF robot on a wheeled base (robot.kind = \"urdf\")"
            )
        ),
    }
}

/// The rolling plant's model of a scenario: its wheeled URDF robot with the
/// `[uncertainty]` draw applied (the nominal robot without the table). What the plant of
/// a closed loop is built from, and what its `[stability]` replay evaluates.
///
/// # Errors
/// [`Error::Scenario`] naming the file and field.
pub fn rolling_plant_model(
    sc: &super::Scenario,
    path: &Path,
) -> Result<crate::mobile::WheeledModel> {
    let base_dir = path.parent().unwrap_or(Path::new("."));
    let (urdf, drive, wheel_joints, casters) = wheeled_robot(sc, path)?;
    let mut wm = super::build_wheeled_model(
        &base_dir.join(urdf),
        drive,
        wheel_joints.clone(),
        casters,
        sc.gravity,
    )
    .map_err(|e| Error::Scenario(at(path, &format!("robot: {}", chain(&e)))))?;
    if let Some(spec) = &sc.uncertainty {
        perturb(&spec.draw(), &mut wm.model, path)?;
    }
    Ok(wm)
}

/// Applies the scenario's `[uncertainty]` to (and returns) a closed loop on the rolling plant: the
/// plant rebuilt from [`rolling_plant_model`], the sensor noise on what the law (built on
/// the nominal model) measures, drawn by the loop ([`super::ClosedLoop::noise`]). Refuses `uncertainty.mu` (the rolling plant has no friction) and
/// sensor noise without `controller.period` (the noise is drawn once per control tick).
///
/// # Errors
/// [`Error::Scenario`] naming the file and field.
pub fn apply_to_rolling(
    spec: &UncertaintySpec,
    mut cl: super::ClosedLoop,
    sc: &super::Scenario,
    path: &Path,
) -> Result<super::ClosedLoop> {
    spec.check()
        .map_err(|e| Error::Scenario(at(path, &chain(&e))))?;
    if spec.mu.is_some() {
        bail!(
            "{}",
            at(
                path,
                "uncertainty.mu: the rolling plant's wheels cannot slip, so it has no friction \
                 to perturb: use plant = \"contact\" or remove uncertainty.mu"
            )
        );
    }
    if spec.has_noise() && cl.options.control_period.is_none() {
        bail!(
            "{}",
            at(
                path,
                "uncertainty.sensor_noise: the noise is drawn once per control tick; give \
                 controller.period"
            )
        );
    }
    let wm = rolling_plant_model(sc, path)?;
    let system = crate::sim::wheeled_system::WheeledSystem::new(wm);
    let names = (
        crate::sim::reduced_system::ReducedSystem::q_names(&system),
        crate::sim::reduced_system::ReducedSystem::v_names(&system),
    );
    cl.noise = sensor_noise(spec, (&names.0, &names.1), path)?;
    cl.system = Box::new(system);
    Ok(cl)
}

//! A scenario with `plant = "contact"`: the same robot, inputs or law as with the rolling
//! plant, run on the contact plant ([`crate::sim::contact_run`]).

use std::path::Path;

use crate::contact::{ContactState, PlantKind};
use crate::error::Error;
use crate::error::Result;
use crate::sim::contact_run::{ContactDriver, ContactRun, contact_plant_of};
use crate::sim_config::schema::RobotSpec;
use crate::sim_config::{Scenario, at, bail, build_wheeled_model, chain, closed_loop, open_loop};

/// Builds the contact run of a scenario with `plant = "contact"`: the contact plant of the
/// URDF robot on a free-flyer root (its `wheel_joints` as disks of radius `drive.r_w`, the
/// `[contact]` casters), started on the ground at `initial.q`/`initial.v` mapped from the
/// reduced coordinates, driven by the scenario's `[[inputs]]` or `[controller]`. Every
/// check of the contact plant is made here, before a run: `contact.mu` ≤ 0, a stiffness
/// whose step is unstable at `contact.dt` (the bound in the message), a caster below the
/// ground at the start.
///
/// # Errors
/// [`Error::Scenario`] naming the file and the field at fault.
pub fn prepare_contact(sc: &Scenario, path: &Path) -> Result<ContactRun> {
    let base_dir = path.parent().unwrap_or(Path::new("."));
    let ctx = |what: &str| at(path, what);
    let named = |e: Error| Error::Scenario(format!("{}: {}", path.display(), chain(&e)));
    if sc.plant != PlantKind::Contact {
        bail!("{}", ctx("prepare_contact needs plant = \"contact\""));
    }
    let RobotSpec::Urdf {
        urdf,
        drive,
        wheel_joints,
        casters,
    } = &sc.robot
    else {
        bail!(
            "{}",
            ctx(
                "plant = \"contact\" is for a URDF robot on a wheeled base (robot.kind = \"urdf\")"
            )
        );
    };
    let Some(wheel_joints) = wheel_joints else {
        bail!(
            "{}",
            ctx("plant = \"contact\" drives the wheel joints: name them in robot.wheel_joints")
        );
    };
    let Some(spec) = &sc.contact else {
        bail!(
            "{}",
            ctx("plant = \"contact\" needs a [contact] table (at least its casters)")
        );
    };
    if sc.stability.is_some() {
        bail!(
            "{}",
            ctx(
                "[stability] monitors the rolling plant; with plant = \"contact\" the contact \
                 forces, lift-off and slip are recorded instead: remove [stability]"
            )
        );
    }
    let robot = build_wheeled_model(
        &base_dir.join(urdf),
        drive,
        Some(wheel_joints.clone()),
        casters,
        sc.gravity,
    )
    .map_err(|e| Error::Scenario(format!("{}: robot: {}", path.display(), chain(&e))))?;
    let mut model = crate::io::urdf::model_from_urdf_file(
        base_dir.join(urdf),
        crate::multibody::RootJoint::FreeFlyer,
    )
    .map_err(|e| Error::Scenario(format!("{}: robot: {}", path.display(), chain(&e))))?;
    model.gravity = robot.model.gravity;
    // [uncertainty]: the plant's model and μ perturbed, the noise on what the law
    // measures (the run's loop draws it); the law keeps the nominal (rolling) model.
    let mut params = spec.params();
    if let Some(draw) = crate::sim_config::uncertainty::contact_draw(sc, path)? {
        crate::sim::uncertainty::perturb(&draw, &mut model, path)?;
        params.mu = draw.mu.unwrap_or(params.mu);
    }
    let noise = match &sc.uncertainty {
        Some(u) => {
            crate::sim::uncertainty::sensor_noise(u, (&robot.q_names(), &robot.v_names()), path)?
        }
        None => None,
    };
    let (plant, mut map) = contact_plant_of(robot, model, spec, params).map_err(named)?;
    let (q0, v0, driver, record_interval) = if sc.controller.is_some() || sc.reference.is_some() {
        let cl = closed_loop(sc, path, base_dir)?;
        let driver = ContactDriver::Law {
            law: cl.law,
            period: cl.options.control_period,
        };
        (cl.q0, cl.v0, driver, cl.options.record_interval)
    } else {
        let ol = open_loop(sc, path, base_dir)?;
        (
            ol.q0,
            ol.v0,
            ContactDriver::Profile(ol.input),
            ol.options.record_interval,
        )
    };
    let (qc, vc) = map.to_contact(&q0, &v0);
    let start = ContactState::new(&plant, &qc, &vc).map_err(named)?;
    Ok(ContactRun {
        plant,
        map,
        q0,
        v0,
        driver,
        duration: sc.duration,
        record_interval,
        start,
        noise,
    })
}

/// The check of a run on the rolling plant: `plant` is `rolling` and there is no
/// `[contact]` table (`has_contact`), which only the contact plant reads.
///
/// # Errors
/// [`Error::InvalidInput`] naming `plant` or `contact`.
pub fn check_rolling(plant: PlantKind, has_contact: bool) -> Result<()> {
    if plant == PlantKind::Contact {
        return Err(Error::invalid(
            "plant",
            "\"contact\" runs through sim_config::contact::prepare_contact (moma simulate does)",
        ));
    }
    if has_contact {
        return Err(Error::invalid(
            "contact",
            "the [contact] table is read only with plant = \"contact\"",
        ));
    }
    Ok(())
}

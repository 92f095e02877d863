//! The `[stability]` table of `moma simulate` scenarios: tip-over measures, wheel–ground
//! loads and slip along a wheeled URDF run (schema and outputs in docs/simulate.md).

use serde::Deserialize;

use super::{Context, bail};
use crate::error::Result;
use crate::mobile::WheeledModel;
use crate::sim::recorder::Recorder;
use crate::sim::stability_monitor::{StabilityMonitor, StabilitySettings};
use crate::sim_config::schema::RobotSpec;
use crate::stability::BodySet;

/// The `[stability]` table.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StabilitySpec {
    /// Coulomb friction coefficient of the driven wheels (optional: no slip check).
    #[serde(default)]
    pub mu: Option<f64>,
    /// Moment-Height body set: `all`, `subtree:JOINT` or `links:A,B,…` (default all).
    #[serde(default)]
    pub bodies: Option<String>,
    /// Ground height in the base frame (m); default from the tracked wheels, else 0.
    #[serde(default)]
    pub ground_z: Option<f64>,
    /// End the run at the first sample that tips over.
    #[serde(default)]
    pub stop_at_tip: bool,
    /// Declare "stays stable" a goal of the scenario: a tip-over gives exit status 3.
    #[serde(default)]
    pub require_stable: bool,
}

/// Builds the monitor of `spec` for `wm`.
///
/// # Errors
/// [`crate::Error::Scenario`] naming the `stability.*` field.
pub fn monitor(spec: &StabilitySpec, wm: &WheeledModel) -> Result<StabilityMonitor> {
    let bodies: BodySet = match &spec.bodies {
        None => BodySet::All,
        Some(s) => s.parse().ctx("stability.bodies")?,
    };
    if let Some(problem) = spec.mu.and_then(crate::error::not_positive_finite) {
        bail!("stability.mu {problem}");
    }
    if let Some(z) = spec.ground_z
        && !z.is_finite()
    {
        bail!("stability.ground_z is not a finite number");
    }
    let settings = StabilitySettings {
        mu: spec.mu,
        bodies,
        ground_z: spec.ground_z,
        stop_at_tip: spec.stop_at_tip,
    };
    StabilityMonitor::new(wm, settings).ctx("stability")
}

/// Evaluates every recorded sample of a finished run (closed-loop runs, whose loop has no
/// sample observer): the robot must be a URDF on a wheeled base; `base_dir` resolves its
/// path.
///
/// # Errors
/// [`crate::Error::Scenario`] naming the field, or the sample whose evaluation failed.
pub fn replay(
    spec: &StabilitySpec,
    robot: &RobotSpec,
    gravity: Option<f64>,
    base_dir: &std::path::Path,
    rec: &Recorder,
) -> Result<StabilityMonitor> {
    let RobotSpec::Urdf {
        urdf,
        drive,
        wheel_joints,
        casters,
    } = robot
    else {
        bail!("[stability] needs a URDF robot on a wheeled base (robot.kind = \"urdf\")");
    };
    let wm = super::build_wheeled_model(
        &base_dir.join(urdf),
        drive,
        wheel_joints.clone(),
        casters,
        gravity,
    )?;
    replay_on(spec, &wm, rec)
}

/// [`replay`] on the plant a closed-loop scenario ran: with `[uncertainty]`, the perturbed
/// model ([`crate::sim_config::rolling_plant::rolling_plant_model`]), so the tip-over
/// measures are those of the robot that moved, not of the controller's nominal model.
///
/// # Errors
/// As [`replay`]; errors of the robot name the file `path`.
pub fn replay_scenario(
    spec: &StabilitySpec,
    sc: &crate::sim_config::Scenario,
    path: &std::path::Path,
    rec: &Recorder,
) -> Result<StabilityMonitor> {
    let wm = crate::sim_config::rolling_plant::rolling_plant_model(sc, path)?;
    replay_on(spec, &wm, rec)
}

fn replay_on(spec: &StabilitySpec, wm: &WheeledModel, rec: &Recorder) -> Result<StabilityMonitor> {
    let mut mon = monitor(spec, wm)?;
    for i in 0..rec.len() {
        mon.sample(rec.times[i], rec.q_row(i), rec.v_row(i), rec.u_row(i))
            .with_ctx(|| format!("sample at t = {}", rec.times[i]))?;
    }
    Ok(mon)
}

//! The lift-off study: over arm postures and payloads, the tip-over limit that
//! `stability::acceleration_limit` predicts beside the smallest steady acceleration at
//! which the contact plant lifts a contact (`sim::lift_off`).
//!
//! Each point is one posture (the `[lift_off].posture` joints, then the point's `q.JOINT`
//! values) with a point-mass payload of `payload` kg at the origin of `payload_frame`:
//! the predicted limit along `direction`, then the bisection between `bracket[0]` and
//! `bracket[1]` times the prediction to the relative `tolerance`, the arm joints held by
//! the PD gains `joint_gains` (`[kp, kd]` on every joint; by default each joint's from its
//! own inertia, `sim::lift_off::DEFAULT_JOINT_GAINS`). Gains unstable at the plant's step
//! fail the point before it runs, naming `lift_off.joint_gains` and the joint. The search
//! looks for `event`: the first contact to lift (`first_lift`, the default) or the
//! tip-over (`tip_over`: every contact off one edge unloaded); the `contact` table's
//! `caster_friction = true` gives the casters the wheels' friction
//! (`ContactPlant::with_caster_friction`); `static_torque = true` adds the static torque
//! of the posture to the joints' PD law (`LiftOffProblem::with_static_torque`).

use std::path::{Path, PathBuf};

use nalgebra::{DVector, Vector2, Vector3};
use serde::Deserialize;

use super::{
    Parameter, Value, file_error, joint_parameter, num, require_non_negative, require_numbers,
    study_section,
};
use super::{resolve, set_joints};
use crate::contact::{ContactPlant, ContactSpec, WheelSpec};
use crate::error::{Error, Result};
use crate::mission::scenario::Loader;
use crate::multibody::{RootJoint, neutral};
use crate::sim::lift_off::{JointGains, LiftOffEvent, LiftOffProblem, LiftOffSettings};
use crate::sim::model_mismatch::{ModelPerturbation, Payload};
use crate::sim::uncertainty::MAX_PAYLOAD_MASS;

/// Result columns of the lift-off study.
pub(super) const RESULTS: &[&str] = &[
    "predicted_limit",
    "simulated_limit",
    "ratio",
    "lifted_contact",
    "bisection_runs",
];

/// Largest factor of the predicted limit the search may start from: a bracket of 1e300
/// drove the plant to non-finite accelerations, naming no field.
const MAX_BRACKET: f64 = 10.0;

/// The parameters this study reads.
const NAMES: &str = "payload, q.JOINT";

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Spec {
    robot: String,
    wheels: Vec<WheelSpec>,
    contact: ContactSpec,
    #[serde(default)]
    posture: toml::Table,
    payload_frame: Option<String>,
    direction: Option<String>,
    bracket: Option<[f64; 2]>,
    tolerance: Option<f64>,
    max_iterations: Option<usize>,
    joint_gains: Option<[f64; 2]>,
    event: Option<String>,
    static_torque: Option<bool>,
}

#[derive(Clone, Copy, Debug)]
enum Slot {
    Payload,
    /// A one-coordinate joint's q index.
    Joint(usize),
}

/// The prepared study.
pub(super) struct LiftOffStudy {
    /// The sweep file, for the errors of a point's checks.
    path: PathBuf,
    plant: ContactPlant,
    posture: DVector<f64>,
    payload_link: String,
    direction: Vector2<f64>,
    bracket: [f64; 2],
    settings: LiftOffSettings,
    event: LiftOffEvent,
    static_torque: bool,
    slots: Vec<Slot>,
}

/// Per-worker workspace: the point's configuration.
pub(super) struct Workspace {
    q: DVector<f64>,
}

/// An error of building the contact plant, its field placed in the study's section.
fn plant_error(path: &Path, e: Error) -> Error {
    match e {
        Error::InvalidInput { field, message } => {
            let field = match field.strip_prefix("contact.wheels") {
                Some(rest) => format!("lift_off.wheels{rest}"),
                None => format!("lift_off.{field}"),
            };
            file_error(path, &field, message)
        }
        // A robot whose joints the plant cannot take (a joint of more than one dof).
        Error::Model(_) => file_error(path, "lift_off.robot", e),
        // A wheel joint the model lacks.
        other => file_error(path, "lift_off.wheels", other),
    }
}

/// The study slot of every sweep parameter, its values checked (numbers; a payload not
/// negative).
fn parameter_slots(
    path: &Path,
    model: &crate::multibody::Model,
    params: &[Parameter],
) -> Result<Vec<Slot>> {
    let mut slots = Vec::with_capacity(params.len());
    for p in params {
        let slot = match p.name.as_str() {
            "payload" => Slot::Payload,
            n if n.starts_with("q.") => Slot::Joint(joint_parameter(model, path, n)?),
            n => {
                return Err(file_error(
                    path,
                    &format!("parameters.{n}"),
                    format!("unknown parameter of the lift_off study (expected {NAMES})"),
                ));
            }
        };
        require_numbers(path, p)?;
        if matches!(slot, Slot::Payload) {
            require_non_negative(path, p, " kg (0: no payload)")?;
            let hi = match &p.values {
                super::Values::Linspace { lo, hi, .. } => lo.max(*hi),
                super::Values::List(v) => v.iter().map(num).fold(f64::NEG_INFINITY, f64::max),
            };
            if hi > MAX_PAYLOAD_MASS {
                return Err(file_error(
                    path,
                    &format!("parameters.{}", p.name),
                    format!("must be at most {MAX_PAYLOAD_MASS:e} kg, got {hi:e}"),
                ));
            }
        }
        slots.push(slot);
    }
    Ok(slots)
}

/// The search settings of the section, checked, fields named.
fn settings(path: &Path, spec: &Spec) -> Result<([f64; 2], LiftOffSettings)> {
    let d = LiftOffSettings::default();
    let settings = LiftOffSettings {
        tolerance: spec.tolerance.unwrap_or(d.tolerance),
        max_iterations: spec.max_iterations.unwrap_or(d.max_iterations),
        joint_gains: spec.joint_gains.map_or(d.joint_gains, JointGains::Fixed),
        ..d
    };
    settings.validate().map_err(|e| match e {
        Error::InvalidInput { field, message } => {
            file_error(path, &format!("lift_off.{field}"), message)
        }
        other => other,
    })?;
    let bracket = spec.bracket.unwrap_or([0.8, 1.2]);
    if !(bracket[0].is_finite() && bracket[1].is_finite() && 0.0 <= bracket[0])
        || bracket[0] >= bracket[1]
        || bracket[1] > MAX_BRACKET
    {
        return Err(file_error(
            path,
            "lift_off.bracket",
            format!(
                "needs 0 <= lo < hi <= {MAX_BRACKET} (factors of the predicted limit), got \
                 [{:e}, {:e}]",
                bracket[0], bracket[1]
            ),
        ));
    }
    Ok((bracket, settings))
}

impl LiftOffStudy {
    pub(super) fn new(
        path: &Path,
        dir: &Path,
        section: toml::Value,
        params: &[Parameter],
        files: &dyn Loader,
    ) -> Result<Self> {
        let spec: Spec = study_section(path, "lift_off", section)?;
        let model = files.urdf(&resolve(dir, &spec.robot), RootJoint::FreeFlyer)?;
        let mut posture = neutral(&model);
        set_joints(
            path,
            &model,
            "lift_off.posture",
            &spec.posture,
            &mut posture,
        )?;
        let payload_link = match &spec.payload_frame {
            Some(f) => f.clone(),
            None => model.frames[model.last_link_frame().0].name.clone(),
        };
        // The payload's link is checked once here (a zero mass changes nothing).
        ModelPerturbation {
            mass_scale: 1.0,
            payload: Some(Payload {
                link: payload_link.clone(),
                mass: 0.0,
                position: Vector3::zeros(),
            }),
        }
        .apply(&mut model.clone())
        .map_err(|e| file_error(path, "lift_off.payload_frame", e))?;
        let direction = match spec.direction.as_deref().unwrap_or("forward") {
            "forward" => Vector2::new(1.0, 0.0),
            "backward" => Vector2::new(-1.0, 0.0),
            "left" => Vector2::new(0.0, 1.0),
            "right" => Vector2::new(0.0, -1.0),
            other => {
                return Err(file_error(
                    path,
                    "lift_off.direction",
                    format!(
                        "unknown direction '{other}' (expected forward, backward, left or right)"
                    ),
                ));
            }
        };
        let event = match spec.event.as_deref().unwrap_or("first_lift") {
            "first_lift" => LiftOffEvent::FirstLift,
            "tip_over" => LiftOffEvent::TipOver,
            other => {
                return Err(file_error(
                    path,
                    "lift_off.event",
                    format!("unknown event '{other}' (expected first_lift or tip_over)"),
                ));
            }
        };
        let (bracket, settings) = settings(path, &spec)?;
        let slots = parameter_slots(path, &model, params)?;
        let plant = spec
            .contact
            .plant(model, &spec.wheels, spec.contact.params())
            .map_err(|e| plant_error(path, e))?;
        Ok(Self {
            path: path.to_path_buf(),
            plant,
            posture,
            payload_link,
            direction,
            bracket,
            settings,
            event,
            static_torque: spec.static_torque == Some(true),
            slots,
        })
    }

    pub(super) fn workspace(&self) -> Workspace {
        Workspace {
            q: self.posture.clone(),
        }
    }

    pub(super) fn evaluate(
        &self,
        ws: &mut Workspace,
        point: &[Value],
        row: &mut Vec<Value>,
    ) -> Result<()> {
        ws.q.copy_from(&self.posture);
        let mut payload = 0.0;
        for (s, v) in self.slots.iter().zip(point) {
            match s {
                Slot::Payload => payload = num(v),
                Slot::Joint(iq) => ws.q[*iq] = num(v),
            }
        }
        let tool = Payload {
            link: self.payload_link.clone(),
            mass: payload,
            position: Vector3::zeros(),
        };
        let mut problem = LiftOffProblem::new(
            &self.plant,
            &ws.q.as_slice()[7..],
            (payload > 0.0).then_some(&tool),
            self.direction,
        )?
        .with_event(self.event);
        if self.static_torque {
            problem = problem.with_static_torque();
        }
        let predicted = problem.predicted_limit()?.ok_or_else(|| {
            Error::invalid(
                "predicted_limit",
                "no tip-over limit in this direction (the robot tips at rest, or no support \
                 edge limits the direction)",
            )
        })?;
        // The gains' stable step depends on the point's posture and payload: checked here,
        // before the point runs, and named in the file.
        problem.joint_gains(&self.settings).map_err(|e| match e {
            Error::InvalidInput { field, message } => {
                let field = if field == "wheel_gains" {
                    "lift_off.wheels".to_string()
                } else {
                    format!("lift_off.{field}")
                };
                file_error(&self.path, &field, message)
            }
            other => other,
        })?;
        let found = problem.search(
            self.bracket[0] * predicted,
            self.bracket[1] * predicted,
            &self.settings,
        )?;
        row.push(Value::Float(predicted));
        row.push(Value::Float(found.acceleration));
        row.push(Value::Float(found.acceleration / predicted));
        row.push(Value::Text(
            self.plant.contact_name(found.contact).to_string(),
        ));
        row.push(Value::Int(found.iterations as i64));
        Ok(())
    }
}

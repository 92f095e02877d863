//! The `[space]` table of a free-floating scenario (`robot.kind = "free_floating"`): a
//! URDF as a free flyer in zero gravity, torque-driven (with an optional capture of a
//! target body) or under resolved-rate control through the generalized Jacobian.
//! Schema: `docs/space.md`.

use std::path::Path;

use nalgebra::{DVector, Matrix3, Vector3};
use serde::Deserialize;

use super::{Context, Scenario, at, bail, err, finite};
use crate::error::Result;
use crate::multibody::{Data, Model, RootJoint};
use crate::sim::free_floating::{CaptureEvent, FloatingSettings, ResolvedRateControl, TargetBody};
use crate::space::{self, SpaceData};
use crate::spatial::Force;

/// The `[space]` table of a free-floating scenario.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpaceSpec {
    /// Initial momentum `{ linear = [3], angular_about_com = [3] }` (world; default zero).
    #[serde(default)]
    pub momentum: Option<MomentumSpec>,
    /// Viscous joint damping (N·m·s/rad).
    #[serde(default)]
    pub joint_damping: f64,
    /// Resolved-rate control of the frame position.
    #[serde(default)]
    pub control: Option<ControlSpec>,
    /// Capture of a target body.
    #[serde(default)]
    pub capture: Option<CaptureSpec>,
}

/// Initial momentum.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MomentumSpec {
    /// Linear momentum (N·s).
    pub linear: [f64; 3],
    /// Angular momentum about the system CoM (N·m·s).
    pub angular_about_com: [f64; 3],
}

/// Resolved-rate control settings.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlSpec {
    /// Goal of the frame position (world, m).
    pub target: [f64; 3],
    /// Gain (1/s).
    pub gain: f64,
    /// Damped least squares λ.
    #[serde(default)]
    pub damping: f64,
    /// Cancel the momentum drift with the measured attitude (5.145).
    #[serde(default)]
    pub drift_compensation: bool,
    /// Reaction-null-space term (redundant arms).
    #[serde(default)]
    pub reaction_null_space: bool,
}

/// A target captured at the frame.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaptureSpec {
    /// Capture time (s).
    pub time: f64,
    /// Mass (kg).
    pub mass: f64,
    /// CoM in the grasp frame (m).
    pub com_in_frame: [f64; 3],
    /// Principal moments about its CoM, grasp-frame axes (kg·m²).
    pub inertia_diagonal: [f64; 3],
    /// CoM velocity before capture (world, m/s).
    pub linear_velocity: [f64; 3],
    /// Angular velocity before capture (world, rad/s).
    pub angular_velocity: [f64; 3],
}

/// The inputs of a free-floating run ([`crate::sim::free_floating::run`]).
pub struct SpaceRun {
    /// The robot as a free flyer in zero gravity.
    pub model: Model,
    /// Initial configuration.
    pub q0: DVector<f64>,
    /// Initial velocity (the base twist from the joint rates and the initial momentum).
    pub v0: DVector<f64>,
    /// Frame, duration, integrator, torques or control, capture.
    pub settings: FloatingSettings,
}

/// Builds the free-floating run of a scenario whose robot is the URDF `urdf` (relative
/// to `base_dir`) with the recorded `frame`; `path` is the scenario file named in errors.
///
/// # Errors
/// [`crate::Error::Scenario`] naming the file and the field at fault.
pub fn space_run(
    sc: &Scenario,
    path: &Path,
    base_dir: &Path,
    urdf: &Path,
    frame: &str,
) -> Result<SpaceRun> {
    let ctx = |what: &str| at(path, what);
    if sc.gravity.is_some_and(|g| g != 0.0) {
        bail!(
            "{}",
            ctx("gravity: a free-floating robot is simulated in zero gravity")
        );
    }
    let mut model =
        crate::io::urdf::model_from_urdf_file(base_dir.join(urdf), RootJoint::FreeFlyer)
            .with_ctx(|| ctx("robot.urdf"))?;
    model.gravity = Vector3::zeros();
    let fid = model.frame_id(frame).with_ctx(|| ctx("robot.frame"))?;
    let spec = sc.space.as_ref();
    let (q0, v0) = initial_state(sc, &model, path)?;
    let control = resolved_rate(spec, path)?;
    let capture = capture(spec, path)?;
    if control.is_some() && sc.inputs.is_some() {
        bail!(
            "{}",
            ctx("inputs: a controlled run commands joint rates; torques are not used")
        );
    }
    let settings = FloatingSettings {
        frame: fid,
        duration: sc.duration,
        record_interval: sc.output.record_interval,
        integrator: sc.integrator,
        torque: sc.inputs.clone().unwrap_or_default(),
        joint_damping: spec.map_or(0.0, |s| s.joint_damping),
        control,
        capture,
    };
    Ok(SpaceRun {
        model,
        q0,
        v0,
        settings,
    })
}

/// The initial configuration and velocity: the joint rates and the momentum give the
/// base twist.
fn initial_state(
    sc: &Scenario,
    model: &Model,
    path: &Path,
) -> Result<(DVector<f64>, DVector<f64>)> {
    let ctx = |what: &str| at(path, what);
    let n = model.nv - 6;
    let q0 = match &sc.initial.q {
        Some(q) => q.clone(),
        None => crate::kinematics::neutral(model).as_slice().to_vec(),
    };
    let qd0 = sc.initial.v.clone().unwrap_or_else(|| vec![0.0; n]);
    crate::kinematics::check_state(model, &ctx("initial"), Some(&q0), None, None, None)
        .map_err(|e| err!("{}", super::chain(&e)))?;
    if qd0.len() != n {
        bail!(
            "{}",
            ctx(&format!(
                "initial.v: expected the {n} joint rates (nv − 6), got {}",
                qd0.len()
            ))
        );
    }
    finite(&ctx("initial.v"), &qd0)?;
    let h0 = match sc.space.as_ref().and_then(|s| s.momentum.as_ref()) {
        Some(m) => {
            finite(&ctx("space.momentum.linear"), &m.linear)?;
            finite(
                &ctx("space.momentum.angular_about_com"),
                &m.angular_about_com,
            )?;
            Force::new(Vector3::from(m.linear), Vector3::from(m.angular_about_com))
        }
        None => Force::zero(),
    };
    let q0 = DVector::from_vec(q0);
    let mut data = Data::new(model);
    let mut sd = SpaceData::new(model).with_ctx(|| ctx("robot"))?;
    space::base_velocity(model, &mut data, &mut sd, &q0, &qd0, &h0)
        .with_ctx(|| ctx("initial state"))?;
    Ok((q0, sd.v.clone()))
}

/// The resolved-rate control of `[space.control]`.
fn resolved_rate(spec: Option<&SpaceSpec>, path: &Path) -> Result<Option<ResolvedRateControl>> {
    let Some(c) = spec.and_then(|s| s.control.as_ref()) else {
        return Ok(None);
    };
    finite(&at(path, "space.control.target"), &c.target)?;
    Ok(Some(ResolvedRateControl {
        target: Vector3::from(c.target),
        gain: c.gain,
        damping: c.damping,
        drift_compensation: c.drift_compensation,
        reaction_null_space: c.reaction_null_space,
    }))
}

/// The capture event of `[space.capture]`.
fn capture(spec: Option<&SpaceSpec>, path: &Path) -> Result<Option<CaptureEvent>> {
    let Some(c) = spec.and_then(|s| s.capture.as_ref()) else {
        return Ok(None);
    };
    for (name, x) in [
        ("com_in_frame", &c.com_in_frame),
        ("inertia_diagonal", &c.inertia_diagonal),
        ("linear_velocity", &c.linear_velocity),
        ("angular_velocity", &c.angular_velocity),
    ] {
        finite(&at(path, &format!("space.capture.{name}")), x)?;
    }
    if c.inertia_diagonal.iter().any(|&i| i < 0.0) {
        bail!(
            "{}",
            at(path, "space.capture.inertia_diagonal must not be negative")
        );
    }
    Ok(Some(CaptureEvent {
        time: c.time,
        target: TargetBody {
            mass: c.mass,
            com_in_frame: Vector3::from(c.com_in_frame),
            inertia_com: Matrix3::from_diagonal(&Vector3::from(c.inertia_diagonal)),
            linear_velocity: Vector3::from(c.linear_velocity),
            angular_velocity: Vector3::from(c.angular_velocity),
        },
    }))
}

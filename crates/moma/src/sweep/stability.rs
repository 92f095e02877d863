//! The stability study: tip-over measures of a wheeled manipulator (planar root, a
//! differential-drive base) over arm postures, platform motions and payloads.
//!
//! Each point is one state: the base at the origin with heading 0 (the support moves with
//! the base, so the pose does not matter), the arm at rest in the chosen posture, and the
//! platform moving with forward speed `speed` and acceleration `accel` (m/s, m/s² along
//! the base x axis, at the driven-axle midpoint), yaw rate `yaw_rate` and yaw acceleration
//! `yaw_accel` (rad/s, rad/s²). With the base origin `d` ahead of the axle, the base
//! velocity in base axes is `[speed, d·ω, ω]` and its acceleration
//! `[accel − d·ω², d·ω̇ + speed·ω, ω̇]`. A payload of `payload` kg is a point mass at the
//! origin of `payload_frame`, added to the inertia of the body that frame belongs to (so
//! it enters the mass, the centre of mass, the d'Alembert forces and the Moment-Height
//! inertia).

use std::path::Path;

use nalgebra::{DVector, Vector2, Vector3};
use serde::Deserialize;

use super::{
    Parameter, Value, file_error, joint_parameter, num, require_names, require_non_negative,
    require_numbers, resolve, set_joints, study_section,
};
use crate::error::Result;
use crate::mission::scenario::Loader;
use crate::mobile::{Caster, DiffDrive, WheeledBase};
use crate::multibody::{Data, FrameIndex, JointIndex, Model, RootJoint, neutral};
use crate::spatial::Inertia;
use crate::stability::{
    BodySet, ExternalLoads, StabilityData, StabilityModel, SupportAttachment, SupportPolygon,
    evaluate,
};

/// Result columns of the stability study.
pub(super) const RESULTS: &[&str] = &[
    "stable",
    "zmp_margin",
    "zmp_critical_edge",
    "zmp_x",
    "zmp_y",
    "fa_alpha",
    "fa_min",
    "fa_beta",
    "mhs_min",
    "mass",
    "com_x",
    "com_y",
    "com_z",
];

/// The parameters this study reads.
const NAMES: &str = "posture, accel, speed, yaw_rate, yaw_accel, payload, q.JOINT";

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Spec {
    robot: String,
    base: BaseSpec,
    support: Option<Vec<[f64; 2]>>,
    mhs_bodies: Option<String>,
    payload_frame: Option<String>,
    gravity: Option<[f64; 3]>,
    #[serde(default)]
    postures: Vec<PostureSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct BaseSpec {
    r_w: f64,
    b: f64,
    #[serde(default)]
    d: f64,
    #[serde(default)]
    casters: Vec<[f64; 2]>,
    /// The drive wheels' joints in the URDF `[left, right]`: the ground lies `r_w` below
    /// their axis (as `WheeledModel::ground_z`). Without them the ground is the base
    /// origin's plane, z = 0.
    wheel_joints: Option<[String; 2]>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PostureSpec {
    name: String,
    q: toml::Table,
}

#[derive(Clone, Copy, Debug)]
enum Slot {
    Posture,
    Accel,
    Speed,
    YawRate,
    YawAccel,
    Payload,
    /// A one-coordinate joint's q index.
    Joint(usize),
}

/// The prepared study.
pub(super) struct StabilityStudy {
    model: Model,
    sm: StabilityModel,
    d: f64,
    posture_names: Vec<String>,
    postures: Vec<DVector<f64>>,
    slots: Vec<Slot>,
    payload_joint: JointIndex,
    payload_at: Vector3<f64>,
}

/// Per-worker workspace.
pub(super) struct Workspace {
    model: Model,
    data: Data,
    sd: StabilityData,
    q: DVector<f64>,
    v: DVector<f64>,
    a: DVector<f64>,
}

/// The height of the ground in the base frame (m): the mean height of the wheel joints'
/// origins in the neutral configuration, base at the origin, minus the wheel radius (so a
/// URDF rooted at axle height stands on the ground under its wheels, as in
/// `WheeledModel::ground_z`); 0 without `base.wheel_joints`.
fn ground_height(path: &Path, model: &Model, spec: &Spec) -> Result<f64> {
    let Some(names) = &spec.base.wheel_joints else {
        return Ok(0.0);
    };
    let mut data = Data::new(model);
    crate::kinematics::forward_kinematics(model, &mut data, &neutral(model));
    let mut z = 0.0;
    for name in names {
        let j = model
            .joint_id(name)
            .map_err(|e| file_error(path, "stability.base.wheel_joints", e))?;
        if j.0 <= 1 {
            return Err(file_error(
                path,
                "stability.base.wheel_joints",
                format!("joint '{name}' is the base's root, not a wheel"),
            ));
        }
        z += 0.5 * data.world_from_joint[j.0].translation.z;
    }
    Ok(z - spec.base.r_w)
}

/// The support polygon on the ground `ground_z`: the listed `support` points, or else the
/// wheel contacts of the drive and the casters.
fn support_polygon(
    path: &Path,
    spec: &Spec,
    drive: DiffDrive,
    ground_z: f64,
) -> Result<SupportPolygon> {
    let points: Vec<Vector2<f64>> = match &spec.support {
        Some(s) => s.iter().map(|p| Vector2::new(p[0], p[1])).collect(),
        None => {
            let mut wb = WheeledBase::new(drive);
            for (k, c) in spec.base.casters.iter().enumerate() {
                wb.casters.push(Caster {
                    name: format!("caster{k}"),
                    position: *c,
                });
            }
            wb.support_points()
        }
    };
    let field = if spec.support.is_some() {
        "stability.support"
    } else {
        "stability.base"
    };
    SupportPolygon::from_points_at_height(&points, ground_z).map_err(|e| file_error(path, field, e))
}

/// Where the payload sits: the joint of the body that `payload_frame` (default the last
/// link's frame) belongs to, and the frame's origin in that joint's frame.
fn payload_attachment(
    path: &Path,
    model: &Model,
    payload_frame: Option<&str>,
) -> Result<(JointIndex, Vector3<f64>)> {
    let frame: FrameIndex = match payload_frame {
        Some(n) => model
            .frame_id(n)
            .map_err(|e| file_error(path, "stability.payload_frame", e))?,
        None => model.last_link_frame(),
    };
    let fr = &model.frames[frame.0];
    if fr.parent_joint.0 == 0 {
        return Err(file_error(
            path,
            "stability.payload_frame",
            format!("frame '{}' is not on a moving body", fr.name),
        ));
    }
    Ok((fr.parent_joint, fr.placement.translation))
}

/// The named postures: the neutral configuration with the listed joints set.
fn parse_postures(
    path: &Path,
    model: &Model,
    specs: &[PostureSpec],
) -> Result<(Vec<String>, Vec<DVector<f64>>)> {
    let mut posture_names = Vec::with_capacity(specs.len());
    let mut postures = Vec::with_capacity(specs.len());
    for (k, p) in specs.iter().enumerate() {
        let at = format!("stability.postures[{k}]");
        if posture_names.contains(&p.name) {
            return Err(file_error(
                path,
                &at,
                format!("posture '{}' named twice", p.name),
            ));
        }
        let mut q = neutral(model);
        set_joints(path, model, &format!("{at}.q"), &p.q, &mut q)?;
        posture_names.push(p.name.clone());
        postures.push(q);
    }
    Ok((posture_names, postures))
}

/// The study slot of every sweep parameter, with its values checked (names of the
/// file's `posture_names`, numbers otherwise, a payload not negative).
fn parameter_slots(
    path: &Path,
    model: &Model,
    params: &[Parameter],
    posture_names: &[String],
) -> Result<Vec<Slot>> {
    let mut slots = Vec::with_capacity(params.len());
    for p in params {
        let slot = match p.name.as_str() {
            "posture" => {
                if posture_names.is_empty() {
                    return Err(file_error(
                        path,
                        "parameters.posture",
                        "needs [[stability.postures]] entries",
                    ));
                }
                require_names(path, p, posture_names)?;
                Slot::Posture
            }
            "accel" => Slot::Accel,
            "speed" => Slot::Speed,
            "yaw_rate" => Slot::YawRate,
            "yaw_accel" => Slot::YawAccel,
            "payload" => Slot::Payload,
            n if n.starts_with("q.") => Slot::Joint(joint_parameter(model, path, n)?),
            n => {
                return Err(file_error(
                    path,
                    &format!("parameters.{n}"),
                    format!("unknown parameter of the stability study (expected {NAMES})"),
                ));
            }
        };
        if !matches!(slot, Slot::Posture) {
            require_numbers(path, p)?;
        }
        if matches!(slot, Slot::Payload) {
            require_non_negative(path, p, " kg")?;
        }
        slots.push(slot);
    }
    Ok(slots)
}

impl StabilityStudy {
    pub(super) fn new(
        path: &Path,
        dir: &Path,
        section: toml::Value,
        params: &[Parameter],
        files: &dyn Loader,
    ) -> Result<Self> {
        let spec: Spec = study_section(path, "stability", section)?;
        let robot = resolve(dir, &spec.robot);
        let mut model = files.urdf(&robot, RootJoint::Planar)?;
        if let Some(g) = spec.gravity {
            crate::error::ensure_finite("stability.gravity", &g)
                .map_err(|e| file_error(path, "stability.gravity", e))?;
            model.gravity = Vector3::from(g);
        }
        let drive = DiffDrive::new(spec.base.r_w, spec.base.b, spec.base.d)
            .map_err(|e| file_error(path, "stability.base", e))?;
        let ground_z = ground_height(path, &model, &spec)?;
        let poly = support_polygon(path, &spec, drive, ground_z)?;
        let bodies: BodySet = spec
            .mhs_bodies
            .as_deref()
            .unwrap_or("all")
            .parse()
            .map_err(|e| file_error(path, "stability.mhs_bodies", e))?;
        let sm = StabilityModel::new(&model, poly, SupportAttachment::Base, &bodies)
            .map_err(|e| file_error(path, "stability.mhs_bodies", e))?;
        let (payload_joint, payload_at) =
            payload_attachment(path, &model, spec.payload_frame.as_deref())?;
        let (mut posture_names, mut postures) = parse_postures(path, &model, &spec.postures)?;
        let slots = parameter_slots(path, &model, params, &posture_names)?;
        if postures.is_empty() {
            postures.push(neutral(&model));
            posture_names.push("neutral".into());
        }
        Ok(Self {
            model,
            sm,
            d: drive.d,
            posture_names,
            postures,
            slots,
            payload_joint,
            payload_at,
        })
    }

    pub(super) fn workspace(&self) -> Workspace {
        let model = self.model.clone();
        let data = Data::new(&model);
        Workspace {
            data,
            sd: StabilityData::new(&self.sm),
            q: DVector::zeros(model.nq),
            v: DVector::zeros(model.nv),
            a: DVector::zeros(model.nv),
            model,
        }
    }

    pub(super) fn evaluate(
        &self,
        ws: &mut Workspace,
        point: &[Value],
        row: &mut Vec<Value>,
    ) -> Result<()> {
        let (mut speed, mut accel, mut w, mut dw, mut payload) = (0.0, 0.0, 0.0, 0.0, 0.0);
        let posture = self
            .slots
            .iter()
            .zip(point)
            .find_map(|(s, v)| match (s, v) {
                (Slot::Posture, Value::Text(n)) => self.posture_names.iter().position(|p| p == n),
                _ => None,
            })
            .unwrap_or(0);
        ws.q.copy_from(&self.postures[posture]);
        for (s, v) in self.slots.iter().zip(point) {
            match s {
                Slot::Posture => {}
                Slot::Accel => accel = num(v),
                Slot::Speed => speed = num(v),
                Slot::YawRate => w = num(v),
                Slot::YawAccel => dw = num(v),
                Slot::Payload => payload = num(v),
                Slot::Joint(iq) => ws.q[*iq] = num(v),
            }
        }
        // Base at the origin, heading 0: base axes are world axes.
        ws.q[0] = 0.0;
        ws.q[1] = 0.0;
        ws.q[2] = 0.0;
        ws.v.fill(0.0);
        ws.a.fill(0.0);
        let d = self.d;
        ws.v[0] = speed;
        ws.v[1] = d * w;
        ws.v[2] = w;
        ws.a[0] = accel - d * w * w;
        ws.a[1] = d * dw + speed * w;
        ws.a[2] = dw;
        let j = self.payload_joint.0;
        ws.model.inertias[j] =
            self.model.inertias[j] + Inertia::point_mass(payload, self.payload_at);
        let r = evaluate(
            &ws.model,
            &mut ws.data,
            &self.sm,
            &mut ws.sd,
            &ws.q,
            &ws.v,
            &ws.a,
            &ExternalLoads::NONE,
        );
        row.push(Value::Bool(r.stable));
        row.push(Value::opt(r.zmp_margin));
        row.push(
            r.zmp_critical_edge
                .map_or(Value::Missing, |e| Value::Int(e as i64)),
        );
        row.push(Value::opt(r.zmp.map(|p| p.x)));
        row.push(Value::opt(r.zmp.map(|p| p.y)));
        row.push(Value::opt(r.force_angle_alpha));
        row.push(Value::opt(r.force_angle_min));
        row.push(Value::opt(r.force_angle_beta_min));
        row.push(Value::opt(r.mhs_min));
        let wr = &ws.sd.wrench;
        row.push(Value::Float(wr.mass));
        row.push(Value::Float(wr.com.x));
        row.push(Value::Float(wr.com.y));
        row.push(Value::Float(wr.com.z));
        Ok(())
    }
}

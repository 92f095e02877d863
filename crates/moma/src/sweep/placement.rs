//! The placement study: can the arm reach a target from a base pose, and how well (a
//! manipulability measure at the IK solution)? Each point is one (target, base pose) pair,
//! solved by [`ArmReachEvaluator`] as `moma reach-map` solves each pose (from the seed,
//! then the same restart configurations at every pose), so a point's result depends on
//! the point alone.

use std::path::Path;
use std::sync::Arc;

use nalgebra::{DVector, Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::Deserialize;

use super::{
    Parameter, Value, file_error, num, require_names, require_numbers, resolve, study_section,
};
use crate::error::Result;
use crate::ik::IkOptions;
use crate::ik::model::ModelFrame;
use crate::ik::placement::{
    ArmReachEvaluator, ArmReachWorkspace, MeasureScope, PlacementEvaluator,
};
use crate::ik::tasks::{TaskRows, target_from_slice};
use crate::manipulability::Measure;
use crate::mission::scenario::Loader;
use crate::multibody::{RootJoint, neutral};

/// Result columns of the placement study.
pub(super) const RESULTS: &[&str] = &["reachable", "measure", "residual", "ik_iterations"];

const NAMES: &str = "target, base_x, base_y, base_yaw";

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Spec {
    robot: String,
    frame: Option<String>,
    mount: Option<Vec<f64>>,
    rows: Option<String>,
    measure: Option<String>,
    q0: Option<Vec<f64>>,
    tol: Option<f64>,
    max_iters: Option<usize>,
    restarts: Option<usize>,
    targets: Vec<TargetSpec>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct TargetSpec {
    name: String,
    pose: Vec<f64>,
}

#[derive(Clone, Copy)]
enum Slot {
    Target,
    X,
    Y,
    Yaw,
}

/// The prepared study.
pub(super) struct PlacementStudy {
    names: Vec<String>,
    evaluators: Vec<ArmReachEvaluator<ModelFrame>>,
    slots: Vec<Slot>,
}

/// Per-worker workspace: one IK workspace per target (their task rows may differ), made
/// when the target is first met.
pub(super) type Workspace = Vec<Option<ArmReachWorkspace<ModelFrame>>>;

/// The arm's mount on the base: `[x, y, z]` or `[x, y, z, yaw]` (identity when absent).
fn parse_mount(path: &Path, mount: Option<&[f64]>) -> Result<Isometry3<f64>> {
    match mount {
        None => Ok(Isometry3::identity()),
        Some(m) if m.len() == 3 || m.len() == 4 => {
            crate::error::ensure_finite("placement.mount", m)
                .map_err(|e| file_error(path, "placement.mount", e))?;
            Ok(Isometry3::from_parts(
                Translation3::new(m[0], m[1], m[2]),
                UnitQuaternion::from_axis_angle(&Vector3::z_axis(), *m.get(3).unwrap_or(&0.0)),
            ))
        }
        Some(m) => Err(file_error(
            path,
            "placement.mount",
            format!(
                "expected [x, y, z] or [x, y, z, yaw], got {} values",
                m.len()
            ),
        )),
    }
}

/// The IK settings of every point: tolerance, iteration limit and restarts.
struct SolverSettings {
    tol: f64,
    max_iters: usize,
    restarts: usize,
}

impl SolverSettings {
    /// The settings of `spec` (defaults 1e-6, 100, 2), each checked in range.
    fn from_spec(path: &Path, spec: &Spec) -> Result<Self> {
        let tol = spec.tol.unwrap_or(1e-6);
        if !(tol.is_finite() && tol > 0.0) {
            return Err(file_error(
                path,
                "placement.tol",
                format!("must be > 0, got {tol}"),
            ));
        }
        let max_iters = spec.max_iters.unwrap_or(100);
        if max_iters == 0 || max_iters > 100_000 {
            return Err(file_error(
                path,
                "placement.max_iters",
                "must be from 1 to 100000",
            ));
        }
        let restarts = spec.restarts.unwrap_or(2);
        if restarts > 1000 {
            return Err(file_error(path, "placement.restarts", "at most 1000"));
        }
        Ok(Self {
            tol,
            max_iters,
            restarts,
        })
    }
}

/// The task rows of target `t` (field `at`): the study's `rows`, or by default position
/// for a 3-value pose and the full pose otherwise; checked against the pose and the
/// directional measure's length.
fn target_rows(
    path: &Path,
    at: &str,
    t: &TargetSpec,
    rows: Option<&TaskRows>,
    measure: &Measure,
) -> Result<TaskRows> {
    let task_rows = rows.cloned().unwrap_or(if t.pose.len() == 3 {
        TaskRows::Position
    } else {
        TaskRows::Full
    });
    if t.pose.len() == 3 && task_rows.indices().iter().any(|&r| r >= 3) {
        return Err(file_error(
            path,
            &format!("{at}.pose"),
            "orientation rows need a 7-value pose x,y,z,qx,qy,qz,qw",
        ));
    }
    if let Measure::Directional(u) = measure
        && u.len() != task_rows.indices().len()
    {
        return Err(file_error(
            path,
            "placement.measure",
            format!(
                "directional: expected {} components, got {}",
                task_rows.indices().len(),
                u.len()
            ),
        ));
    }
    Ok(task_rows)
}

/// The study slot of every sweep parameter (a target name, or a number for the base
/// pose).
fn parameter_slots(path: &Path, params: &[Parameter], names: &[String]) -> Result<Vec<Slot>> {
    let mut slots = Vec::with_capacity(params.len());
    for p in params {
        let slot = match p.name.as_str() {
            "target" => {
                require_names(path, p, names)?;
                Slot::Target
            }
            "base_x" => Slot::X,
            "base_y" => Slot::Y,
            "base_yaw" => Slot::Yaw,
            n => {
                return Err(file_error(
                    path,
                    &format!("parameters.{n}"),
                    format!("unknown parameter of the placement study (expected {NAMES})"),
                ));
            }
        };
        if !matches!(slot, Slot::Target) {
            require_numbers(path, p)?;
        }
        slots.push(slot);
    }
    Ok(slots)
}

impl PlacementStudy {
    pub(super) fn new(
        path: &Path,
        dir: &Path,
        section: toml::Value,
        params: &[Parameter],
        files: &dyn Loader,
    ) -> Result<Self> {
        let spec: Spec = study_section(path, "placement", section)?;
        let model = Arc::new(files.urdf(&resolve(dir, &spec.robot), RootJoint::Fixed)?);
        let frame = match &spec.frame {
            Some(n) => model
                .frame_id(n)
                .map_err(|e| file_error(path, "placement.frame", e))?,
            None => model.last_link_frame(),
        };
        let arm = ModelFrame::new(model.clone(), frame)?;
        let mount = parse_mount(path, spec.mount.as_deref())?;
        let rows: Option<TaskRows> = spec
            .rows
            .as_deref()
            .map(str::parse)
            .transpose()
            .map_err(|e| file_error(path, "placement.rows", e))?;
        let measure: Measure = spec
            .measure
            .as_deref()
            .unwrap_or("yoshikawa")
            .parse()
            .map_err(|e| file_error(path, "placement.measure", e))?;
        let seed = match &spec.q0 {
            Some(q) => DVector::from_vec(q.clone()),
            None => neutral(&model),
        };
        let solver = SolverSettings::from_spec(path, &spec)?;
        if spec.targets.is_empty() {
            return Err(file_error(
                path,
                "placement.targets",
                "needs at least one target",
            ));
        }
        let mut names = Vec::with_capacity(spec.targets.len());
        let mut evaluators = Vec::with_capacity(spec.targets.len());
        for (k, t) in spec.targets.iter().enumerate() {
            let at = format!("placement.targets[{k}]");
            if names.contains(&t.name) {
                return Err(file_error(
                    path,
                    &at,
                    format!("target '{}' named twice", t.name),
                ));
            }
            let target = target_from_slice(&t.pose)
                .map_err(|e| file_error(path, &format!("{at}.pose"), e))?;
            let task_rows = target_rows(path, &at, t, rows.as_ref(), &measure)?;
            let ev = ArmReachEvaluator {
                arm: arm.clone(),
                mount,
                target,
                rows: task_rows,
                options: IkOptions {
                    tolerance: solver.tol,
                    max_iterations: solver.max_iters,
                    ..IkOptions::default()
                },
                seed: seed.clone(),
                restarts: solver.restarts,
                measure: measure.clone(),
                scope: MeasureScope::Arm,
            };
            ev.validate().map_err(|e| file_error(path, &at, e))?;
            names.push(t.name.clone());
            evaluators.push(ev);
        }
        let slots = parameter_slots(path, params, &names)?;
        Ok(Self {
            names,
            evaluators,
            slots,
        })
    }

    pub(super) fn workspace(&self) -> Workspace {
        self.evaluators.iter().map(|_| None).collect()
    }

    pub(super) fn evaluate(
        &self,
        ws: &mut Workspace,
        point: &[Value],
        row: &mut Vec<Value>,
    ) -> Result<()> {
        let mut base = [0.0; 3];
        let mut target = 0;
        for (s, v) in self.slots.iter().zip(point) {
            match s {
                Slot::Target => {
                    if let Value::Text(n) = v {
                        target = self.names.iter().position(|t| t == n).unwrap_or(0);
                    }
                }
                Slot::X => base[0] = num(v),
                Slot::Y => base[1] = num(v),
                Slot::Yaw => base[2] = num(v),
            }
        }
        let ev = &self.evaluators[target];
        let w = ws[target].get_or_insert_with(|| ev.workspace());
        let sample = ev.evaluate(w, base)?;
        row.push(Value::Bool(sample.reachable));
        row.push(Value::opt(sample.measure));
        row.push(Value::Float(sample.residual));
        row.push(Value::Int(sample.iterations as i64));
        Ok(())
    }
}

//! Evaluating the chapter's models on case files (the schema of the reference vectors).
//!
//! A case file is a JSON object with a `model` name and a list of `cases`; each case has
//! `id`, `params`, `state`, `inputs` and optionally `trajectory.t`. [`evaluate_document`]
//! returns the same document with every case's `outputs` and `trajectory` filled in (all
//! other fields preserved). Nothing is returned unless every case succeeds.

use super::m1_unicycle::{Unicycle, UnicycleParams};
use super::m2_platform_arm::{PlatformArm, PlatformArmParams};
use super::m3_diffdrive::{DiffDriveKinematics, DiffDriveKinematicsParams};
use super::m4_cart_two_link::{CartTwoLink, CartTwoLinkParams};
use super::m5_mobile_manipulator::{MobileManipulator, MobileManipulatorParams, TaskController};
use super::m6_space_manipulator::{SpaceManipulator, SpaceManipulatorParams};
use super::{MAX_CASE_TIME, check_horizon, fixed_vector};
use crate::error::{Error, Result};
use nalgebra::{SMatrix, SVector};
use serde::Serialize;
use serde_json::{Map, Value, json};

pub use super::registry::{ChapterModel, MODEL_NAMES};

fn field<'a>(case: &'a Value, path: &[&str]) -> Result<&'a Value> {
    let mut v = case;
    for (i, key) in path.iter().enumerate() {
        v = v
            .get(key)
            .ok_or_else(|| Error::invalid(path[..=i].join("."), "missing"))?;
    }
    Ok(v)
}

fn numbers(case: &Value, path: &[&str]) -> Result<Vec<f64>> {
    let name = path.join(".");
    let arr = field(case, path)?
        .as_array()
        .ok_or_else(|| Error::invalid(&name, "expected a list of numbers"))?;
    arr.iter()
        .enumerate()
        .map(|(i, x)| {
            x.as_f64()
                .ok_or_else(|| Error::invalid(format!("{name}[{i}]"), "expected a number"))
        })
        .collect()
}

fn vector<const K: usize>(case: &Value, path: &[&str]) -> Result<SVector<f64, K>> {
    fixed_vector(&path.join("."), &numbers(case, path)?)
}

fn params<P: super::ChapterParams>(case: &Value) -> Result<P> {
    let p = field(case, &["params"])?;
    if let Some(obj) = p.as_object() {
        for (k, v) in obj {
            if !v.is_number() {
                return Err(Error::invalid(format!("params.{k}"), "expected a number"));
            }
        }
    }
    super::parse_params("params", p)
}

fn times(case: &Value) -> Result<Option<Vec<f64>>> {
    match case.get("trajectory").and_then(|t| t.get("t")) {
        None => Ok(None),
        Some(_) => {
            let t = numbers(case, &["trajectory", "t"])?;
            crate::error::ensure_finite("trajectory.t", &t)?;
            for (i, w) in t.windows(2).enumerate() {
                if w[1] < w[0] {
                    return Err(Error::invalid(
                        format!("trajectory.t[{}]", i + 1),
                        "times must be non-decreasing",
                    ));
                }
            }
            if let Some(&t0) = t.first()
                && t0 < 0.0
            {
                return Err(Error::invalid(
                    "trajectory.t[0]",
                    "times start at 0 and must not be negative",
                ));
            }
            check_horizon("trajectory.t", &t)?;
            Ok(Some(t))
        }
    }
}

fn to_value<T: Serialize>(x: &T) -> Result<Value> {
    serde_json::to_value(x).map_err(|e| Error::invalid("outputs", e.to_string()))
}

fn rows<const K: usize>(xs: impl Iterator<Item = SVector<f64, K>>) -> Value {
    Value::Array(xs.map(|x| json!(x.as_slice())).collect())
}

fn all_finite(v: &Value) -> bool {
    match v {
        Value::Number(n) => n.as_f64().is_some_and(f64::is_finite),
        Value::Null => false,
        Value::Array(a) => a.iter().all(all_finite),
        Value::Object(o) => o.values().all(all_finite),
        _ => true,
    }
}

/// A trajectory object: `t` plus the two state parts of each sample, as rows.
fn trajectory<const A: usize, const B: usize>(
    names: [&str; 2],
    samples: &[(SVector<f64, A>, SVector<f64, B>)],
    t: &[f64],
) -> Value {
    let mut m = Map::new();
    m.insert("t".into(), json!(t));
    m.insert(names[0].into(), rows(samples.iter().map(|x| x.0)));
    m.insert(names[1].into(), rows(samples.iter().map(|x| x.1)));
    Value::Object(m)
}

/// Outputs, trajectory and extra top-level keys of one case.
type CaseParts = (Value, Option<Value>, Option<Value>);

/// The trajectory object of a case with `trajectory.t` (`t`), run by `simulate`; `None`
/// without one.
fn trajectory_if<const A: usize, const B: usize>(
    t: Option<&[f64]>,
    names: [&str; 2],
    simulate: impl FnOnce(&[f64]) -> Result<Vec<(SVector<f64, A>, SVector<f64, B>)>>,
) -> Result<Option<Value>> {
    match t {
        Some(t) => Ok(Some(trajectory(names, &simulate(t)?, t))),
        None => Ok(None),
    }
}

/// Outputs and trajectory (keys `t` plus the state names) of one case.
fn evaluate_inner(model: ChapterModel, case: &Value, tol: f64) -> Result<CaseParts> {
    let t = times(case)?;
    let t = t.as_deref();
    match model {
        ChapterModel::M1Unicycle => m1_case(case, t, tol),
        ChapterModel::M2PlatformArm => m2_case(case, t, tol),
        ChapterModel::M3DiffDrive => m3_case(case, t, tol),
        ChapterModel::M4CartTwoLink => m4_case(case, t, tol),
        ChapterModel::M5MobileManipulator => m5_case(case, t, tol),
        ChapterModel::M6SpaceManipulator => {
            let (out, extras) = m6_case(case, tol)?;
            Ok((out, None, Some(extras)))
        }
    }
}

/// m1: outputs and trajectory.
fn m1_case(case: &Value, t: Option<&[f64]>, tol: f64) -> Result<CaseParts> {
    let sys = Unicycle::new(params::<UnicycleParams>(case)?)?;
    let q = vector::<3>(case, &["state", "q"])?;
    let v = vector::<2>(case, &["state", "v"])?;
    let u = vector::<2>(case, &["inputs", "u"])?;
    let out = to_value(&sys.evaluate(&q, &v, &u)?)?;
    let tr = trajectory_if(t, ["q", "v"], |t| sys.simulate(&q, &v, &u, t, tol))?;
    Ok((out, tr, None))
}

/// m2: outputs and trajectory.
fn m2_case(case: &Value, t: Option<&[f64]>, tol: f64) -> Result<CaseParts> {
    let sys = PlatformArm::new(params::<PlatformArmParams>(case)?)?;
    let q = vector::<5>(case, &["state", "q"])?;
    let v = vector::<4>(case, &["state", "v"])?;
    let u = vector::<4>(case, &["inputs", "u"])?;
    let out = to_value(&sys.evaluate(&q, &v, &u)?)?;
    let tr = trajectory_if(t, ["q", "v"], |t| sys.simulate(&q, &v, &u, t, tol))?;
    Ok((out, tr, None))
}

/// m3: outputs and trajectory.
fn m3_case(case: &Value, t: Option<&[f64]>, tol: f64) -> Result<CaseParts> {
    let sys = DiffDriveKinematics::new(params::<DiffDriveKinematicsParams>(case)?)?;
    let q = vector::<6>(case, &["state", "q"])?;
    let v = vector::<5>(case, &["inputs", "v"])?;
    let out = to_value(&sys.evaluate(&q, &v)?)?;
    let tr = trajectory_if(t, ["q", "X"], |t| sys.simulate(&q, &v, t, tol))?;
    Ok((out, tr, None))
}

/// m4: outputs and trajectory, after checking a case marked `balanced`.
fn m4_case(case: &Value, t: Option<&[f64]>, tol: f64) -> Result<CaseParts> {
    let sys = CartTwoLink::new(params::<CartTwoLinkParams>(case)?)?;
    let q = vector::<3>(case, &["state", "q"])?;
    let qd = vector::<3>(case, &["state", "qdot"])?;
    let u = vector::<3>(case, &["inputs", "u"])?;
    check_balanced(case, &sys)?;
    let out = to_value(&sys.evaluate(&q, &qd, &u)?)?;
    let tr = trajectory_if(t, ["q", "qdot"], |t| sys.simulate(&q, &qd, &u, t, tol))?;
    Ok((out, tr, None))
}

/// A case's optional `balanced: true` must hold for its parameters (Γ1 = Γ2 = 0).
fn check_balanced(case: &Value, sys: &CartTwoLink) -> Result<()> {
    let Some(b) = case.get("balanced") else {
        return Ok(());
    };
    let b = b
        .as_bool()
        .ok_or_else(|| Error::invalid("balanced", "expected true or false"))?;
    let p = &sys.params;
    let scale = p.arm_mass() * (p.L1 + p.L2);
    if b && !sys.is_balanced(1e-6 * scale.max(1.0)) {
        return Err(Error::invalid(
            "balanced",
            format!(
                "marked balanced but Γ1 = {:e}, Γ2 = {:e} (need L1cm = −(m2+M1+M2) L1/m1, L2cm = −M2 L2/m2)",
                p.gamma1(),
                p.gamma2()
            ),
        ));
    }
    Ok(())
}

/// m5: outputs, trajectory and the optional `control` block.
fn m5_case(case: &Value, t: Option<&[f64]>, tol: f64) -> Result<CaseParts> {
    let sys = MobileManipulator::new(params::<MobileManipulatorParams>(case)?)?;
    let q = vector::<6>(case, &["state", "q"])?;
    let v = vector::<5>(case, &["state", "v"])?;
    let u = vector::<5>(case, &["inputs", "u"])?;
    let out = to_value(&sys.evaluate(&q, &v, &u)?)?;
    let tr = trajectory_if(t, ["q", "v"], |t| sys.simulate(&q, &v, &u, t, tol))?;
    let control = match case.get("control") {
        Some(_) => Some(control_block(&sys, case, tol)?),
        None => None,
    };
    Ok((out, tr, control))
}

/// m6: outputs, plus the `trajectories` runs and the `joint_loop` (returned as one object
/// of top-level keys to set).
fn m6_case(case: &Value, tol: f64) -> Result<(Value, Value)> {
    let sys = SpaceManipulator::new(params::<SpaceManipulatorParams>(case)?)?;
    let q = vector::<5>(case, &["state", "q"])?;
    let th = vector::<2>(case, &["state", "theta_dot"])?;
    let qz = vector::<5>(case, &["state", "qdot_zero_momentum"])?;
    let qn = vector::<5>(case, &["state", "qdot_nonzero_momentum"])?;
    let tau = vector::<2>(case, &["inputs", "torque"])?;
    let out = to_value(&sys.evaluate(&q, &th, &qz, &qn, &tau)?)?;
    let mut extras = Map::new();
    if let Some(runs) = case.get("trajectories") {
        let runs = runs
            .as_object()
            .ok_or_else(|| Error::invalid("trajectories", "expected an object of runs"))?;
        let mut filled = Map::new();
        for (name, run) in runs {
            let path = ["trajectories", name.as_str()];
            let t = numbers(case, &[path[0], path[1], "t"])?;
            crate::error::ensure_finite(&format!("trajectories.{name}.t"), &t)?;
            if t.first().is_some_and(|&t0| t0 < 0.0) || t.windows(2).any(|w| w[1] < w[0]) {
                return Err(Error::invalid(
                    format!("trajectories.{name}.t"),
                    "times must be non-negative and non-decreasing",
                ));
            }
            check_horizon(&format!("trajectories.{name}.t"), &t)?;
            let torque = vector::<2>(case, &[path[0], path[1], "torque"])?;
            let qdot0 = vector::<5>(case, &[path[0], path[1], "qdot0"])?;
            let samples = sys.simulate(&q, &qdot0, &torque, &t, tol)?;
            let mut r = run.as_object().cloned().unwrap_or_default();
            r.insert("q".into(), rows(samples.iter().map(|s| s.q)));
            r.insert("qdot".into(), rows(samples.iter().map(|s| s.qdot)));
            r.insert("P".into(), rows(samples.iter().map(|s| s.p)));
            r.insert(
                "L_O".into(),
                json!(samples.iter().map(|s| s.l_o).collect::<Vec<_>>()),
            );
            r.insert(
                "psi_from_omega_exact".into(),
                json!(samples.iter().map(|s| s.psi_exact).collect::<Vec<_>>()),
            );
            r.insert(
                "psi_from_omega_chapter".into(),
                json!(samples.iter().map(|s| s.psi_chapter).collect::<Vec<_>>()),
            );
            filled.insert(name.clone(), Value::Object(r));
        }
        extras.insert("trajectories".into(), Value::Object(filled));
    }
    if let Some(jl) = case.get("joint_loop") {
        let a = vector::<2>(case, &["joint_loop", "amplitude"])?;
        let period = field(case, &["joint_loop", "period"])?
            .as_f64()
            .ok_or_else(|| Error::invalid("joint_loop.period", "expected a number"))?;
        if period > MAX_CASE_TIME {
            return Err(Error::invalid(
                "joint_loop.period",
                format!("{period} s is past the longest case horizon, {MAX_CASE_TIME} s"),
            ));
        }
        let theta0 = nalgebra::Vector2::new(q[3], q[4]);
        let d = sys.joint_loop_rotation(&theta0, &a, period, tol)?;
        let mut m = jl.as_object().cloned().unwrap_or_default();
        m.insert("delta_psi".into(), json!(d));
        extras.insert("joint_loop".into(), Value::Object(m));
    }
    Ok((out, Value::Object(extras)))
}

/// Fills `outputs` (and `trajectory`, if the case has `trajectory.t`) of one case.
/// Errors name the case id and the field.
pub fn evaluate_case(model: ChapterModel, case: &Value, index: usize, tol: f64) -> Result<Value> {
    let wrap = |e: Error| name_case(case, index, e);
    if !case.is_object() {
        return Err(wrap(Error::invalid("case", "expected an object")));
    }
    let (outputs, traj, control) = evaluate_inner(model, case, tol).map_err(wrap)?;
    if !all_finite(&outputs)
        || !traj.as_ref().is_none_or(all_finite)
        || !control.as_ref().is_none_or(all_finite)
    {
        return Err(wrap(Error::Numerical {
            t: 0.0,
            message: "non-finite output".into(),
        }));
    }
    let mut out = case.clone();
    let obj = out.as_object_mut().expect("checked object");
    obj.insert("outputs".into(), outputs);
    if let Some(tr) = traj {
        let mut merged = case
            .get("trajectory")
            .and_then(|t| t.as_object())
            .cloned()
            .unwrap_or_default();
        for (k, v) in tr.as_object().expect("object").clone() {
            merged.insert(k, v);
        }
        obj.insert("trajectory".into(), Value::Object(merged));
    }
    if let Some(c) = control {
        if model == ChapterModel::M6SpaceManipulator {
            for (k, v) in c.as_object().expect("object").clone() {
                obj.insert(k, v);
            }
        } else {
            obj.insert("control".into(), c);
        }
    }
    Ok(out)
}

/// Prefixes the field of an error with the case id (or its index).
fn name_case(case: &Value, index: usize, e: Error) -> Error {
    let id = match case.get("id") {
        Some(Value::String(s)) => s.clone(),
        Some(v) => v.to_string(),
        None => format!("#{index}"),
    };
    match e {
        Error::InvalidInput { field, message } => Error::InvalidInput {
            field: format!("case {id}: {field}"),
            message,
        },
        Error::NonFinite { field } => Error::NonFinite {
            field: format!("case {id}: {field}"),
        },
        Error::WrongLength {
            field,
            expected,
            got,
        } => Error::WrongLength {
            field: format!("case {id}: {field}"),
            expected,
            got,
        },
        other => Error::invalid(format!("case {id}"), other.to_string()),
    }
}

/// The model name of the closed-loop unicycle case schema
/// ([`super::control_cases`]).
pub const UNICYCLE_CONTROL: &str = "unicycle_control";

/// Default integration tolerance (`rtol = atol`) for trajectories.
pub const DEFAULT_TOLERANCE: f64 = 1e-12;

/// Smallest integration tolerance accepted from a user (`moma eval --tol`, the Python
/// package's `eval_cases`): a few units of f64's relative resolution (2.2e-16).
pub const MIN_TOLERANCE: f64 = 1e-15;

/// Largest integration tolerance accepted from a user: beyond it a trajectory carries
/// no digit.
pub const MAX_TOLERANCE: f64 = 0.1;

/// Evaluates a whole case document (`model`, `cases`, …); every other top-level field is
/// preserved.
pub fn evaluate_document(doc: &Value, tol: f64) -> Result<Value> {
    let name = doc
        .get("model")
        .ok_or_else(|| Error::invalid("model", "missing (expected e.g. \"m1_unicycle\")"))?
        .as_str()
        .ok_or_else(|| Error::invalid("model", "expected a string"))?;
    let cases = doc
        .get("cases")
        .ok_or_else(|| Error::invalid("cases", "missing"))?
        .as_array()
        .ok_or_else(|| Error::invalid("cases", "expected a list"))?;
    let filled = if name == UNICYCLE_CONTROL {
        cases
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let out = super::control_cases::evaluate_unicycle_case(c, tol)
                    .map_err(|e| name_case(c, i, e))?;
                if !out.get("trajectory").is_none_or(all_finite) {
                    return Err(name_case(
                        c,
                        i,
                        Error::Numerical {
                            t: 0.0,
                            message: "non-finite output".into(),
                        },
                    ));
                }
                Ok(out)
            })
            .collect::<Result<Vec<_>>>()?
    } else {
        let model = ChapterModel::from_name(name)?;
        cases
            .iter()
            .enumerate()
            .map(|(i, c)| evaluate_case(model, c, i, tol))
            .collect::<Result<Vec<_>>>()?
    };
    let mut out = doc.clone();
    out.as_object_mut()
        .ok_or_else(|| Error::invalid("document", "expected a JSON object"))?
        .insert("cases".into(), Value::Array(filled));
    Ok(out)
}

fn matrix5(case: &Value, path: &[&str]) -> Result<SMatrix<f64, 5, 5>> {
    let name = path.join(".");
    let rows = field(case, path)?
        .as_array()
        .ok_or_else(|| Error::invalid(&name, "expected a 5×5 matrix (list of rows)"))?;
    crate::error::ensure_len(&name, 5, rows.len())?;
    let mut m = SMatrix::<f64, 5, 5>::zeros();
    for (i, r) in rows.iter().enumerate() {
        let row_name = format!("{name}[{i}]");
        let r = r
            .as_array()
            .ok_or_else(|| Error::invalid(&row_name, "expected a row"))?;
        crate::error::ensure_len(&row_name, 5, r.len())?;
        for (j, x) in r.iter().enumerate() {
            let x = x
                .as_f64()
                .ok_or_else(|| Error::invalid(format!("{row_name}[{j}]"), "expected a number"))?;
            if !x.is_finite() {
                return Err(Error::NonFinite {
                    field: format!("{row_name}[{j}]"),
                });
            }
            m[(i, j)] = x;
        }
    }
    Ok(m)
}

/// The m5 `control` block: set-up preserved, controller outputs at t = 0 and the closed
/// loop at `control.closed_loop.t` filled in.
fn control_block(sys: &MobileManipulator, case: &Value, tol: f64) -> Result<Value> {
    let ctl = TaskController {
        x_ref: vector::<5>(case, &["control", "x_ref"])?,
        amp: vector::<5>(case, &["control", "amp"])?,
        omega: vector::<5>(case, &["control", "omega"])?,
        kp: matrix5(case, &["control", "Kp"])?,
        kd: matrix5(case, &["control", "Kd"])?,
    };
    ctl.validate()?;
    let q0 = vector::<6>(case, &["control", "q0"])?;
    let v0 = vector::<5>(case, &["control", "v0"])?;
    let c0 = ctl.control(sys, 0.0, &q0, &v0)?;
    let mut out = case["control"].as_object().cloned().unwrap_or_default();
    for (k, v) in [
        ("x_d0", json!(c0.x_d.as_slice())),
        ("xdot_d0", json!(c0.xdot_d.as_slice())),
        ("xddot_d0", json!(c0.xddot_d.as_slice())),
        ("tau_x0", json!(c0.tau_x.as_slice())),
        ("u0", json!(c0.u.as_slice())),
        ("e0", json!(c0.e.as_slice())),
        ("edot0", json!(c0.edot.as_slice())),
        ("W0", json!(c0.w)),
    ] {
        out.insert(k.into(), v);
    }
    if case["control"]
        .get("closed_loop")
        .and_then(|c| c.get("t"))
        .is_some()
    {
        let t = numbers(case, &["control", "closed_loop", "t"])?;
        crate::error::ensure_finite("control.closed_loop.t", &t)?;
        let samples = ctl.simulate(sys, &q0, &v0, &t, tol)?;
        let mut cl = case["control"]["closed_loop"]
            .as_object()
            .cloned()
            .unwrap_or_default();
        cl.insert("t".into(), json!(t));
        cl.insert("q".into(), rows(samples.iter().map(|s| s.q)));
        cl.insert("v".into(), rows(samples.iter().map(|s| s.v)));
        cl.insert("e".into(), rows(samples.iter().map(|s| s.e)));
        cl.insert(
            "W".into(),
            json!(samples.iter().map(|s| s.w).collect::<Vec<_>>()),
        );
        cl.insert(
            "dissipated".into(),
            json!(samples.iter().map(|s| s.dissipated).collect::<Vec<_>>()),
        );
        out.insert("closed_loop".into(), Value::Object(cl));
    }
    Ok(Value::Object(out))
}

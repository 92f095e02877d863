//! `moma manipulability`: manipulability measures of an arm, or of the whole mobile
//! manipulator on a differential-drive base, on a list of states.
//!
//! Also holds the small helpers shared by `ik` and `reach-map` (model loading, number
//! lists, targets).

use crate::output::{print_json, write_json};
use anyhow::{Context, Result, anyhow, bail};
use moma::ik::model::ModelFrame;
use moma::ik::tasks::{FrameKinematics, TaskRows};
use moma::io::urdf::model_from_urdf_file;
use moma::manipulability::{ManipulabilityReport, Measure, evaluate, report};
use moma::mobile::DiffDrive;
use moma::mobile::whole_body::{
    BaseInputs, bias_acceleration, inputs_to_velocity, whole_body_jacobian,
};
use moma::multibody::{Model, RootJoint};
use nalgebra::{DMatrix, DVector, Isometry3};
use serde::Serialize;
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Arguments of `moma manipulability`.
#[derive(clap::Args)]
pub struct Args {
    /// Robot model (URDF). Without --base its root is fixed; with --base it is mounted on
    /// a planar root q = [x, y, θ] and the states include the base pose.
    pub robot: PathBuf,
    /// Differential-drive platform: `diff-drive:r_w=R,b=B,d=D` (wheel radius, half
    /// track, base origin ahead of the axle). Enables the whole-body measures.
    #[arg(long)]
    pub base: Option<String>,
    /// States: JSON `{"states": [{"q": [...], "u": [...]}, ...]}`, or a list of such
    /// objects, or a list of q arrays. `u` (whole-body inputs, optional) adds J̄̇·u.
    #[arg(long)]
    pub states: PathBuf,
    /// Measure: yoshikawa, det-jtj, inverse-condition, condition, min-singular-value,
    /// geometric-mean, eccentricity, directional:u1,u2,...
    #[arg(long, default_value = "yoshikawa")]
    pub measure: String,
    /// End-effector frame (default: the deepest link).
    #[arg(long)]
    pub frame: Option<String>,
    /// Task rows: position, orientation, full, or rows:i,j,... of [vx,vy,vz,wx,wy,wz].
    #[arg(long, default_value = "full")]
    pub rows: String,
    /// Base inputs of the whole-body Jacobian: platform (v, ω) or wheels (φ̇_L, φ̇_R).
    #[arg(long, default_value = "platform")]
    pub inputs: String,
    /// Task direction for the directional quantities, e.g. 1,0,0.
    #[arg(long)]
    pub direction: Option<String>,
    /// Print JSON on standard output (default: a table).
    #[arg(long)]
    pub json: bool,
    /// Also write the JSON result to this file.
    #[arg(long, short)]
    pub output: Option<PathBuf>,
}

/// Parses a comma-separated list of numbers for option `field`.
pub(crate) fn parse_list(field: &str, text: &str) -> Result<Vec<f64>> {
    let mut out = Vec::new();
    for (i, part) in text.split(',').enumerate() {
        let p = part.trim();
        let x: f64 = p
            .parse()
            .map_err(|_| anyhow!("{field}: element {i} '{p}' is not a number"))?;
        if !x.is_finite() {
            bail!("{field}: element {i} is not finite");
        }
        out.push(x);
    }
    Ok(out)
}

/// Loads a URDF with the given root.
pub(crate) fn load_model(path: &Path, root: RootJoint) -> Result<Arc<Model>> {
    let model = model_from_urdf_file(path, root)
        .with_context(|| format!("loading robot model {}", path.display()))?;
    Ok(Arc::new(model))
}

/// The end-effector frame (by name, or the model's deepest link).
pub(crate) fn frame_of(model: &Arc<Model>, name: Option<&str>, path: &Path) -> Result<ModelFrame> {
    let frame = match name {
        Some(n) => model
            .frame_id(n)
            .map_err(|e| anyhow!("{}: --frame: {e}", path.display()))?,
        None => model.last_link_frame(),
    };
    Ok(ModelFrame::new(model.clone(), frame)?)
}

/// Parses `--base`.
pub(crate) fn parse_base(spec: &str) -> Result<DiffDrive> {
    if !spec.trim_start().starts_with("diff-drive") {
        bail!("--base: unknown platform '{spec}'; expected diff-drive:r_w=R,b=B,d=D");
    }
    spec.parse::<DiffDrive>()
        .map_err(|e| anyhow!("--base: {e}"))
}

/// Parses `--rows` (default: position for a 3-value target, full for a 7-value one) and
/// checks that orientation rows come with an orientation in the target `tvals`.
pub(crate) fn parse_task_rows(rows: Option<&str>, tvals: &[f64]) -> Result<TaskRows> {
    let rows: TaskRows = match rows {
        Some(r) => r.parse().map_err(|e| anyhow!("--rows: {e}"))?,
        None if tvals.len() == 3 => TaskRows::Position,
        None => TaskRows::Full,
    };
    if tvals.len() == 3 && rows.indices().iter().any(|&r| r >= 3) {
        bail!("--rows: orientation rows need a 7-value target x,y,z,qx,qy,qz,qw");
    }
    Ok(rows)
}

/// Checks the IK budget options `--tol` (> 0) and `--max-iters` (>= 1).
pub(crate) fn check_ik_budget(tol: f64, max_iters: usize) -> Result<()> {
    if !(tol.is_finite() && tol > 0.0) {
        bail!("--tol: must be > 0, got {tol}");
    }
    if max_iters == 0 {
        bail!("--max-iters: must be at least 1");
    }
    Ok(())
}

/// A frame name for output.
pub(crate) fn frame_name(kin: &ModelFrame) -> String {
    kin.model().frames[kin.frame().0].name.clone()
}

struct State {
    q: DVector<f64>,
    u: Option<DVector<f64>>,
}

fn number_array(v: &Value, field: &str, path: &Path) -> Result<DVector<f64>> {
    let arr = v
        .as_array()
        .ok_or_else(|| anyhow!("{}: {field}: expected an array of numbers", path.display()))?;
    let mut out = Vec::with_capacity(arr.len());
    for (i, x) in arr.iter().enumerate() {
        let f = x.as_f64().ok_or_else(|| {
            anyhow!(
                "{}: {field}[{i}]: expected a number, got {x}",
                path.display()
            )
        })?;
        out.push(f);
    }
    Ok(DVector::from_vec(out))
}

fn read_states(path: &Path) -> Result<Vec<State>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read states file", path.display()))?;
    let v: Value =
        serde_json::from_str(&text).with_context(|| format!("{}: invalid JSON", path.display()))?;
    let list = match &v {
        Value::Array(a) => a.clone(),
        Value::Object(o) => o
            .get("states")
            .and_then(|s| s.as_array())
            .cloned()
            .ok_or_else(|| anyhow!("{}: expected a \"states\" array", path.display()))?,
        _ => bail!("{}: expected a JSON object or array", path.display()),
    };
    if list.is_empty() {
        bail!("{}: states: empty list", path.display());
    }
    let mut out = Vec::with_capacity(list.len());
    for (i, s) in list.iter().enumerate() {
        let st = match s {
            Value::Array(_) => State {
                q: number_array(s, &format!("states[{i}]"), path)?,
                u: None,
            },
            Value::Object(o) => {
                let q = o.get("q").ok_or_else(|| {
                    anyhow!("{}: states[{i}]: missing field \"q\"", path.display())
                })?;
                State {
                    q: number_array(q, &format!("states[{i}].q"), path)?,
                    u: match o.get("u") {
                        Some(u) => Some(number_array(u, &format!("states[{i}].u"), path)?),
                        None => None,
                    },
                }
            }
            _ => bail!(
                "{}: states[{i}]: expected an object with \"q\" or an array",
                path.display()
            ),
        };
        out.push(st);
    }
    Ok(out)
}

#[derive(Serialize)]
struct StateOut {
    index: usize,
    q: Vec<f64>,
    /// The chosen measure on the arm's Jacobian (null when undefined for its shape or singular).
    arm_value: Option<f64>,
    /// The chosen measure on the whole-body Jacobian.
    #[serde(skip_serializing_if = "Option::is_none")]
    whole_body_value: Option<Option<f64>>,
    arm: ManipulabilityReport,
    #[serde(skip_serializing_if = "Option::is_none")]
    whole_body: Option<ManipulabilityReport>,
    /// Whole-body Jacobian J̄ (selected rows × inputs), row-major.
    #[serde(skip_serializing_if = "Option::is_none")]
    whole_body_jacobian: Option<Vec<Vec<f64>>>,
    /// J̄̇·u (selected rows), when the state gives u.
    #[serde(skip_serializing_if = "Option::is_none")]
    jdot_u: Option<Vec<f64>>,
    /// Why the chosen measure is undefined, if it is.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    notes: Vec<String>,
}

#[derive(Serialize)]
struct Output {
    robot: String,
    frame: String,
    rows: Vec<usize>,
    measure: String,
    #[serde(skip_serializing_if = "Option::is_none")]
    base: Option<DiffDrive>,
    #[serde(skip_serializing_if = "Option::is_none")]
    inputs: Option<BaseInputs>,
    states: Vec<StateOut>,
}

fn rows_of(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    (0..m.nrows())
        .map(|i| m.row(i).iter().copied().collect())
        .collect()
}

/// Runs `moma manipulability`.
pub fn run(args: Args) -> Result<()> {
    let measure: Measure = args
        .measure
        .parse()
        .map_err(|e| anyhow!("--measure: {e}"))?;
    let rows: TaskRows = args.rows.parse().map_err(|e| anyhow!("--rows: {e}"))?;
    let idx = rows.indices();
    let inputs: BaseInputs = args.inputs.parse().map_err(|e| anyhow!("--inputs: {e}"))?;
    let drive = args.base.as_deref().map(parse_base).transpose()?;
    let direction = args
        .direction
        .as_deref()
        .map(|d| parse_list("--direction", d))
        .transpose()?;
    if let Some(d) = &direction
        && d.len() != idx.len()
    {
        bail!(
            "--direction: expected {} components (one per task row), got {}",
            idx.len(),
            d.len()
        );
    }
    if let Measure::Directional(u) = &measure
        && u.len() != idx.len()
    {
        bail!(
            "--measure directional: expected {} components (one per task row), got {}",
            idx.len(),
            u.len()
        );
    }
    let root = if drive.is_some() {
        RootJoint::Planar
    } else {
        RootJoint::Fixed
    };
    let model = load_model(&args.robot, root)?;
    let mut kin = frame_of(&model, args.frame.as_deref(), &args.robot)?;
    let states = read_states(&args.states)?;
    let nv = kin.nv();
    let arm_start = if drive.is_some() { 3 } else { 0 };
    let mut j6 = DMatrix::zeros(6, nv);
    let mut pose = Isometry3::identity();
    let mut out_states = Vec::with_capacity(states.len());
    for (i, st) in states.iter().enumerate() {
        let field = format!("{}: states[{i}].q", args.states.display());
        kin.check_q(&field, &st.q)?;
        kin.pose_and_jacobian(&st.q, &mut pose, &mut j6)?;
        let j_rows = j6.select_rows(&idx);
        let j_arm = j_rows.columns(arm_start, nv - arm_start).into_owned();
        let mut notes = Vec::new();
        let arm_report = report(&j_arm, direction.as_deref())
            .with_context(|| format!("state {i}: arm Jacobian"))?;
        let arm_value = match evaluate(&measure, &j_arm) {
            Ok(v) => Some(v),
            Err(e) => {
                notes.push(format!("arm: {e}"));
                None
            }
        };
        let (mut wb_value, mut wb_report, mut wb_j, mut jdot_u) = (None, None, None, None);
        if let Some(drive) = &drive {
            let jbar_full = whole_body_jacobian(drive, inputs, st.q[2], &j6)?;
            let jbar = jbar_full.select_rows(&idx);
            wb_value = Some(match evaluate(&measure, &jbar) {
                Ok(v) => Some(v),
                Err(e) => {
                    notes.push(format!("whole body: {e}"));
                    None
                }
            });
            wb_report = Some(
                report(&jbar, direction.as_deref())
                    .with_context(|| format!("state {i}: whole-body Jacobian"))?,
            );
            wb_j = Some(rows_of(&jbar));
            if let Some(u) = &st.u {
                moma::error::ensure_len(
                    &format!("{}: states[{i}].u", args.states.display()),
                    nv - 1,
                    u.len(),
                )?;
                moma::error::ensure_finite(
                    &format!("{}: states[{i}].u", args.states.display()),
                    u.iter(),
                )?;
                let v = inputs_to_velocity(drive, inputs, st.q[2], u);
                let jdqd = kin.jdot_qdot(&st.q, &v);
                let b = bias_acceleration(drive, inputs, st.q[2], &j6, &jdqd, u)?;
                jdot_u = Some(idx.iter().map(|&r| b[r]).collect());
            }
        } else if st.u.is_some() {
            bail!(
                "{}: states[{i}].u: whole-body inputs need --base",
                args.states.display()
            );
        }
        out_states.push(StateOut {
            index: i,
            q: st.q.iter().copied().collect(),
            arm_value,
            whole_body_value: wb_value,
            arm: arm_report,
            whole_body: wb_report,
            whole_body_jacobian: wb_j,
            jdot_u,
            notes,
        });
    }
    let out = Output {
        robot: args.robot.display().to_string(),
        frame: frame_name(&kin),
        rows: idx.clone(),
        measure: measure.to_string(),
        base: drive,
        inputs: drive.map(|_| inputs),
        states: out_states,
    };
    if let Some(path) = &args.output {
        write_json(path, &out)?;
    }
    if args.json {
        print_json(&out)?;
    } else {
        let fmt = |v: Option<f64>| v.map_or("undefined".to_string(), |x| format!("{x:.6e}"));
        println!(
            "{} frame '{}', rows {:?}, measure {}",
            out.robot, out.frame, out.rows, out.measure
        );
        for s in &out.states {
            match s.whole_body_value {
                Some(w) => println!(
                    "state {:>3}: arm {}  whole-body {}  (σ_min arm {:.4e}, whole-body {:.4e})",
                    s.index,
                    fmt(s.arm_value),
                    fmt(w),
                    s.arm.min_singular_value,
                    s.whole_body.as_ref().map_or(0.0, |r| r.min_singular_value)
                ),
                None => println!(
                    "state {:>3}: arm {}  (σ_min {:.4e})",
                    s.index,
                    fmt(s.arm_value),
                    s.arm.min_singular_value
                ),
            }
            for n in &s.notes {
                println!("           note: {n}");
            }
        }
    }
    Ok(())
}

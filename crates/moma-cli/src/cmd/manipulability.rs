//! `moma manipulability`: manipulability measures of an arm, or of the whole mobile
//! manipulator on a differential-drive base, on a list of states.

use super::common::{frame_name, frame_of, load_model, parse_base, parse_list, read_states};
use crate::output::{print_json, write_json};
use anyhow::{Context, Result, anyhow, bail};
use moma::ik::model::ModelFrame;
use moma::ik::tasks::{FrameKinematics, TaskRows};
use moma::manipulability::{ManipulabilityReport, Measure, evaluate, report};
use moma::mobile::DiffDrive;
use moma::mobile::whole_body::{
    BaseInputs, bias_acceleration, inputs_to_velocity, whole_body_jacobian,
};
use moma::multibody::RootJoint;
use nalgebra::{DMatrix, DVector, Isometry3};
use serde::Serialize;
use std::path::PathBuf;
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
    /// State layout of the states file's q and of the output q: moma or pinocchio (planar
    /// root [x, y, cos θ, sin θ]; continuous joints as cos, sin).
    #[arg(long, value_enum, default_value_t = super::common::Layout::Moma)]
    pub layout: super::common::Layout,
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

/// The parsed options that every state shares.
struct Setup {
    measure: Measure,
    idx: Vec<usize>,
    inputs: BaseInputs,
    drive: Option<DiffDrive>,
    direction: Option<Vec<f64>>,
}

fn parse_setup(args: &Args) -> Result<Setup> {
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
    Ok(Setup {
        measure,
        idx,
        inputs,
        drive,
        direction,
    })
}

/// The measure's value, or `None` with a note saying why it is undefined.
fn value_or_note(
    measure: &Measure,
    j: &DMatrix<f64>,
    who: &str,
    notes: &mut Vec<String>,
) -> Option<f64> {
    match evaluate(measure, j) {
        Ok(v) => Some(v),
        Err(e) => {
            notes.push(format!("{who}: {e}"));
            None
        }
    }
}

/// Evaluates one state; `src` names it in errors (`FILE: states[i]`).
fn evaluate_state(
    setup: &Setup,
    kin: &mut ModelFrame,
    index: usize,
    q: DVector<f64>,
    u: Option<DVector<f64>>,
    src: &str,
) -> Result<StateOut> {
    let nv = kin.nv();
    let arm_start = if setup.drive.is_some() { 3 } else { 0 };
    let mut j6 = DMatrix::zeros(6, nv);
    let mut pose = Isometry3::identity();
    kin.check_q(&format!("{src}.q"), &q)?;
    kin.pose_and_jacobian(&q, &mut pose, &mut j6)?;
    let j_rows = j6.select_rows(&setup.idx);
    let j_arm = j_rows.columns(arm_start, nv - arm_start).into_owned();
    let mut notes = Vec::new();
    let direction = setup.direction.as_deref();
    let arm = report(&j_arm, direction).with_context(|| format!("state {index}: arm Jacobian"))?;
    let arm_value = value_or_note(&setup.measure, &j_arm, "arm", &mut notes);
    let mut out = StateOut {
        index,
        q: q.iter().copied().collect(),
        arm_value,
        whole_body_value: None,
        arm,
        whole_body: None,
        whole_body_jacobian: None,
        jdot_u: None,
        notes,
    };
    let Some(drive) = &setup.drive else {
        if u.is_some() {
            bail!("{src}.u: whole-body inputs need --base");
        }
        return Ok(out);
    };
    let jbar = whole_body_jacobian(drive, setup.inputs, q[2], &j6)?.select_rows(&setup.idx);
    out.whole_body_value = Some(value_or_note(
        &setup.measure,
        &jbar,
        "whole body",
        &mut out.notes,
    ));
    out.whole_body = Some(
        report(&jbar, direction).with_context(|| format!("state {index}: whole-body Jacobian"))?,
    );
    out.whole_body_jacobian = Some(rows_of(&jbar));
    if let Some(u) = &u {
        let field = format!("{src}.u");
        moma::error::ensure_len(&field, nv - 1, u.len())?;
        moma::error::ensure_finite(&field, u.iter())?;
        let v = inputs_to_velocity(drive, setup.inputs, q[2], u);
        let jdqd = kin.jdot_qdot(&q, &v);
        let b = bias_acceleration(drive, setup.inputs, q[2], &j6, &jdqd, u)?;
        out.jdot_u = Some(setup.idx.iter().map(|&r| b[r]).collect());
    }
    Ok(out)
}

/// Runs `moma manipulability`.
pub fn run(args: Args) -> Result<()> {
    let setup = parse_setup(&args)?;
    let root = if setup.drive.is_some() {
        RootJoint::Planar
    } else {
        RootJoint::Fixed
    };
    let model = Arc::new(load_model(&args.robot, root)?);
    let mut kin = frame_of(&model, args.frame.as_deref(), &args.robot)?;
    let states = read_states(&args.states, &["q", "u"])?;
    let conv = super::common::LayoutConv::new(&model, args.layout);
    let mut out_states = Vec::with_capacity(states.len());
    for (i, st) in states.into_iter().enumerate() {
        let src = format!("{}: states[{i}]", args.states.display());
        let q = DVector::from_vec(conv.q_in(st.q, &format!("{src}.q"))?);
        let u = st.u.map(DVector::from_vec);
        let mut s = evaluate_state(&setup, &mut kin, i, q, u, &src)?;
        if s.q.len() == model.nq {
            s.q = conv.q_out(&s.q);
        }
        out_states.push(s);
    }
    let out = Output {
        robot: args.robot.display().to_string(),
        frame: frame_name(&kin),
        rows: setup.idx.clone(),
        measure: setup.measure.to_string(),
        base: setup.drive,
        inputs: setup.drive.map(|_| setup.inputs),
        states: out_states,
    };
    if let Some(path) = &args.output {
        write_json(path, &out)?;
    }
    if args.json {
        print_json(&out)
    } else {
        print_table(&out);
        Ok(())
    }
}

fn print_table(out: &Output) {
    let fmt = |v: Option<f64>| v.map_or("undefined".to_string(), |x| format!("{x:.6e}"));
    outln!(
        "{} frame '{}', rows {:?}, measure {}",
        out.robot,
        out.frame,
        out.rows,
        out.measure
    );
    for s in &out.states {
        match s.whole_body_value {
            Some(w) => outln!(
                "state {:>3}: arm {}  whole-body {}  (σ_min arm {:.4e}, whole-body {:.4e})",
                s.index,
                fmt(s.arm_value),
                fmt(w),
                s.arm.min_singular_value,
                s.whole_body.as_ref().map_or(0.0, |r| r.min_singular_value)
            ),
            None => outln!(
                "state {:>3}: arm {}  (σ_min {:.4e})",
                s.index,
                fmt(s.arm_value),
                s.arm.min_singular_value
            ),
        }
        for n in &s.notes {
            outln!("           note: {n}");
        }
    }
}

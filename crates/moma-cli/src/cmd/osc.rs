//! `moma osc ROBOT.urdf --root fixed --frame NAME --states STATES.json [--rows ROWS]
//! [--output OUT.json]`: Khatib's operational-space quantities of one frame for each
//! state (Λ, J̄, N, J̇q̇, F, τ). Schema: `docs/cli.md`.

use super::common::{load_model, parse_root};
use crate::output::{print_json, write_json};
use anyhow::{Context, Result, anyhow, bail};
use moma::control::osc::{MIN_TASK_CONDITIONING, OscData, osc_fixed_base, task_conditioning};
use moma::ik::tasks::TaskRows;
use moma::kinematics;
use moma::multibody::{Data, RootJoint};
use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};
use std::path::PathBuf;

/// Arguments of `moma osc`.
#[derive(clap::Args)]
pub struct Args {
    /// The robot description (URDF).
    pub urdf: PathBuf,
    /// Root joint: fixed (an arm), planar or free-flyer.
    #[arg(long, value_parser = parse_root)]
    pub root: RootJoint,
    /// The task frame (its [ṗ; ω] in world axes is the task).
    #[arg(long)]
    pub frame: String,
    /// States file: `{"states": [{"q": [..], "v": [..], "task_acceleration": [6],
    /// "null_torque": [nv]}, ..]}` (`v` and `null_torque` default to zero).
    #[arg(long)]
    pub states: PathBuf,
    /// Task rows: position, orientation, full, or rows:i,j,... of [vx,vy,vz,wx,wy,wz].
    #[arg(long, default_value = "full")]
    pub rows: String,
    /// Write the JSON here (atomically) instead of standard output.
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    /// Layout of the states' q (and v): moma or pinocchio (continuous joints as cos, sin;
    /// the free-flyer is the same in both).
    #[arg(long, value_enum, default_value_t = super::common::Layout::Moma)]
    pub layout: super::common::Layout,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StateIn {
    q: Vec<f64>,
    #[serde(default)]
    v: Option<Vec<f64>>,
    task_acceleration: Vec<f64>,
    #[serde(default)]
    null_torque: Option<Vec<f64>>,
}

#[derive(Deserialize)]
struct StatesIn {
    states: Vec<StateIn>,
}

#[derive(Serialize)]
struct StateOut {
    task_inertia: Vec<Vec<f64>>,
    dynamically_consistent_inverse: Vec<Vec<f64>>,
    nullspace_projector: Vec<Vec<f64>>,
    acceleration_bias: Vec<f64>,
    task_force: Vec<f64>,
    torque: Vec<f64>,
    task_conditioning: f64,
}

#[derive(Serialize)]
struct Output {
    robot: String,
    source: String,
    root: String,
    nq: usize,
    nv: usize,
    frame: String,
    rows: Vec<usize>,
    min_task_conditioning: f64,
    states: Vec<StateOut>,
}

fn rows_of(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    m.row_iter().map(|r| r.iter().copied().collect()).collect()
}

/// Runs `moma osc`.
pub fn run(args: Args) -> Result<()> {
    let model = load_model(&args.urdf, args.root)?;
    let fid = model
        .frame_id(&args.frame)
        .with_context(|| format!("{}: --frame", args.urdf.display()))?;
    let task_rows: TaskRows = args.rows.parse().map_err(|e| anyhow!("--rows: {e}"))?;
    task_rows.validate().map_err(|e| anyhow!("--rows: {e}"))?;
    let rows = task_rows.indices();
    let m = rows.len();
    let text = std::fs::read_to_string(&args.states)
        .with_context(|| format!("{}: cannot read states file", args.states.display()))?;
    let states: StatesIn = serde_json::from_str(&text).map_err(|e| {
        anyhow!(
            "{}: invalid states file (expected {{\"states\": [{{\"q\": [..], \"v\": [..], \"task_acceleration\": [6], \"null_torque\": [nv]}}]}}): {e}",
            args.states.display()
        )
    })?;
    if states.states.is_empty() {
        bail!("{}: 'states' is empty", args.states.display());
    }
    let nv = model.nv;
    let conv = super::common::LayoutConv::new(&model, args.layout);
    if conv.moves_velocities() {
        bail!(
            "--layout pinocchio: not supported by osc on a planar root (the task bias and \
             torques depend on the layout's velocity frame); use --layout moma"
        );
    }
    let mut data = Data::new(&model);
    let mut od = OscData::new(nv, &rows);
    let mut out = Vec::with_capacity(states.states.len());
    for (k, s) in states.states.iter().enumerate() {
        let src = format!("{}: states[{k}]", args.states.display());
        let q_in = conv.q_in(s.q.clone(), &format!("{src}.q"))?;
        kinematics::check_state(&model, &src, Some(&q_in), s.v.as_deref(), None, None)?;
        let a = &s.task_acceleration;
        let a_des = if a.len() == m {
            DVector::from_column_slice(a)
        } else if a.len() == 6 {
            DVector::from_iterator(m, rows.iter().map(|&r| a[r]))
        } else {
            bail!(
                "{src}.task_acceleration: expected 6 values (or {m}, one per selected row), got {}",
                a.len()
            );
        };
        if let Some(i) = a_des.iter().position(|x| !x.is_finite()) {
            bail!("{src}.task_acceleration[{i}]: not finite");
        }
        let tau0 = match &s.null_torque {
            Some(t) => {
                if t.len() != nv {
                    bail!(
                        "{src}.null_torque: expected {nv} values (nv), got {}",
                        t.len()
                    );
                }
                if let Some(i) = t.iter().position(|x| !x.is_finite()) {
                    bail!("{src}.null_torque[{i}]: not finite");
                }
                DVector::from_column_slice(t)
            }
            None => DVector::zeros(nv),
        };
        let q = DVector::from_column_slice(&q_in);
        let v =
            s.v.as_ref()
                .map_or_else(|| DVector::zeros(nv), |x| DVector::from_column_slice(x));
        let res = osc_fixed_base(&model, &mut data, &mut od, fid, &q, &v, &a_des, &tau0);
        // The conditioning is judged on J, filled before any factorisation can fail.
        let cond = task_conditioning(&od);
        if cond < MIN_TASK_CONDITIONING {
            bail!(
                "{src}: task Jacobian of frame '{}' is singular: sigma_min/sigma_max = {cond:e} < {MIN_TASK_CONDITIONING:e}",
                args.frame
            );
        }
        res.map_err(|e| anyhow!("{src}: {e}"))?;
        out.push(StateOut {
            task_inertia: rows_of(&od.task_inertia),
            dynamically_consistent_inverse: rows_of(&od.dynamically_consistent_inverse),
            nullspace_projector: rows_of(&od.nullspace_projector),
            acceleration_bias: od.acceleration_bias.as_slice().to_vec(),
            task_force: od.task_force.as_slice().to_vec(),
            torque: od.torque.as_slice().to_vec(),
            task_conditioning: cond,
        });
    }
    let output = Output {
        robot: model.name.clone(),
        source: args.urdf.display().to_string(),
        root: args.root.to_string(),
        nq: model.nq,
        nv,
        frame: args.frame.clone(),
        rows,
        min_task_conditioning: MIN_TASK_CONDITIONING,
        states: out,
    };
    match &args.output {
        Some(p) => write_json(p, &output),
        None => print_json(&output),
    }
}

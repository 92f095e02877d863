//! `moma osc ROBOT.urdf --root fixed --frame NAME --states STATES.json [--rows ROWS]
//! [--output OUT.json]`: Khatib's operational-space quantities of one frame for each
//! state (Λ, J̄, N, J̇q̇, F, τ). Schema: `docs/cli.md`.

use super::common::{load_model, parse_root};
use crate::output::{print_json, write_json};
use anyhow::{Context, Result, anyhow, bail};
use moma::control::osc::{
    MIN_TASK_CONDITIONING, OscData, OscStateReport, osc_fixed_base, osc_to_pinocchio_layout,
    task_conditioning,
};
use moma::ik::tasks::TaskRows;
use moma::kinematics;
use moma::multibody::{Data, RootJoint};
use nalgebra::DVector;
use serde::Serialize;
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
    /// Layout of the states' q, v and null_torque and of the joint-space results (J̄, N, τ)
    /// and the bias J̇v: moma or pinocchio (continuous joints as cos, sin; a planar root as
    /// [x, y, cos θ, sin θ] with base-frame velocity; the free-flyer is the same in both).
    #[arg(long, value_enum, default_value_t = super::common::Layout::Moma)]
    pub layout: super::common::Layout,
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
    states: Vec<OscStateReport>,
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
    let text = super::common::read_states_text(&args.states)?;
    let states = moma::io::states::parse_osc_states(&text, &args.states)?;
    let nv = model.nv;
    let conv = super::common::LayoutConv::new(&model, args.layout);
    // On a planar root, Pinocchio's velocities are in the base frame: the states' v and
    // null_torque come in through Tᵀ and the joint-space results go out through T.
    let pin = conv
        .moves_velocities()
        .then(|| moma::io::pinocchio_layout::PinocchioLayout::new(&model));
    let mut data = Data::new(&model);
    let mut od = OscData::new(nv, &rows);
    let mut out = Vec::with_capacity(states.len());
    for (k, s) in states.iter().enumerate() {
        let src = format!("{}: states[{k}]", args.states.display());
        let q_in = conv.q_in(s.q.clone(), &format!("{src}.q"))?;
        kinematics::check_state(&model, &src, Some(&q_in), s.v.as_deref(), None, None)?;
        let (a_des, tau0) = s.task_inputs(&rows, nv, k, &args.states)?;
        let a_des = DVector::from_vec(a_des);
        let tau0 = DVector::from_vec(conv.v_in(&q_in, tau0));
        let q = DVector::from_column_slice(&q_in);
        let v = s.v.as_ref().map_or_else(
            || DVector::zeros(nv),
            |x| DVector::from_vec(conv.v_in(&q_in, x.clone())),
        );
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
        if let Some(p) = &pin {
            osc_to_pinocchio_layout(p, q.as_slice(), v.as_slice(), &mut od);
        }
        out.push(OscStateReport::new(&od, cond));
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

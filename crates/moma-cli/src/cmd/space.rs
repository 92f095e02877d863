//! `moma space ROBOT.urdf --frame NAME --states STATES.json [--output OUT.json]`: the robot
//! as a free-floating system (free-flyer root, zero gravity). Per state: total mass, CoM,
//! the base twist that the joint rates induce under momentum conservation, the whole
//! generalized velocity, the generalized Jacobian J* of the frame, the generalized inertia
//! H* and the frame's velocity (with the momentum drift). Schema: `docs/cli.md`.

use super::common::load_model;
use anyhow::{Context, Result, bail};
use moma::multibody::{Data, RootJoint};
use moma::space::{self, SpaceData, SpaceStateReport};
use moma::spatial::Force;
use nalgebra::{DVector, Vector3};
use serde::Serialize;
use std::path::PathBuf;

/// Arguments of `moma space`.
#[derive(clap::Args)]
pub struct Args {
    /// The robot description (URDF); its root link becomes a free-flying base.
    pub urdf: PathBuf,
    /// Frame whose generalized Jacobian and velocity are reported.
    #[arg(long)]
    pub frame: String,
    /// States file: `{"states": [{"q": [nq], "qdot_joints": [nv − 6],
    /// "momentum": {"linear": [3], "angular_about_com": [3]}}]}` (momentum optional, zero
    /// by default; world axes, angular part about the system CoM).
    #[arg(long)]
    pub states: PathBuf,
    /// Write the JSON here (atomically) instead of standard output.
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// Layout of the states' q (and v): moma or pinocchio (continuous joints as cos, sin;
    /// the free-flyer is the same in both).
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
    states: Vec<SpaceStateReport>,
}

/// Runs `moma space`.
pub fn run(args: Args) -> Result<()> {
    let mut model = load_model(&args.urdf, RootJoint::FreeFlyer)?;
    model.gravity = Vector3::zeros();
    let fid = model
        .frame_id(&args.frame)
        .with_context(|| format!("{}: --frame", args.urdf.display()))?;
    let mut sd = SpaceData::new(&model).with_context(|| args.urdf.display().to_string())?;
    let text = super::common::read_states_text(&args.states)?;
    let states = moma::io::states::parse_space_states(&text, &args.states)?;
    let conv = super::common::LayoutConv::new(&model, args.layout);
    let n = sd.n;
    let mut data = Data::new(&model);
    let mut out_states = Vec::with_capacity(states.len());
    for (k, s) in states.iter().enumerate() {
        let src = format!("{}: states[{k}]", args.states.display());
        let q_in = conv.q_in(s.q.clone(), &format!("{src}.q"))?;
        moma::kinematics::check_state(&model, &src, Some(&q_in), None, None, None)?;
        let h = s.check(n, model.nv, k, &args.states)?;
        let h = Force::new(
            Vector3::new(h[0], h[1], h[2]),
            Vector3::new(h[3], h[4], h[5]),
        );
        let q = DVector::from_column_slice(&q_in);
        let st = space::state_report(&model, &mut data, &mut sd, &q, &s.qdot_joints, &h, fid)
            .with_context(|| src.clone())?;
        if !st.is_finite() {
            bail!("{src}: non-finite result (degenerate mass distribution?)");
        }
        out_states.push(st);
    }
    let out = Output {
        robot: model.name.clone(),
        source: args.urdf.display().to_string(),
        root: model.root.to_string(),
        nq: model.nq,
        nv: model.nv,
        frame: model.frames[fid.0].name.clone(),
        states: out_states,
    };
    match &args.output {
        Some(p) => crate::output::write_json(p, &out),
        None => crate::output::print_json(&out),
    }
}

//! `moma space ROBOT.urdf --frame NAME --states STATES.json [--output OUT.json]`: the robot
//! as a free-floating system (free-flyer root, zero gravity). Per state: total mass, CoM,
//! the base twist that the joint rates induce under momentum conservation, the whole
//! generalized velocity, the generalized Jacobian J* of the frame, the generalized inertia
//! H* and the frame's velocity (with the momentum drift). Schema: `docs/cli.md`.

use super::common::load_model;
use anyhow::{Context, Result, bail};
use moma::multibody::{Data, RootJoint};
use moma::space::{self, SpaceData};
use moma::spatial::Force;
use nalgebra::{DVector, Vector3};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

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

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MomentumIn {
    linear: Vec<f64>,
    angular_about_com: Vec<f64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StateIn {
    q: Vec<f64>,
    qdot_joints: Vec<f64>,
    #[serde(default)]
    momentum: Option<MomentumIn>,
}

#[derive(Deserialize)]
struct StatesIn {
    states: Vec<StateIn>,
}

#[derive(Serialize)]
struct StateOut {
    total_mass: f64,
    com: [f64; 3],
    base_velocity: [f64; 6],
    v: Vec<f64>,
    generalized_jacobian: Vec<Vec<f64>>,
    generalized_inertia: Vec<Vec<f64>>,
    frame_velocity: [f64; 6],
}

#[derive(Serialize)]
struct Output {
    robot: String,
    source: String,
    root: String,
    nq: usize,
    nv: usize,
    frame: String,
    states: Vec<StateOut>,
}

fn read_states(path: &Path) -> Result<StatesIn> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read states file", path.display()))?;
    serde_json::from_str(&text).map_err(|e| {
        anyhow::anyhow!(
            "{}: invalid states file (expected {{\"states\": [{{\"q\": [..], \"qdot_joints\": [..], \"momentum\": {{\"linear\": [3], \"angular_about_com\": [3]}}}}]}}): {e}",
            path.display()
        )
    })
}

fn vec3(src: &str, name: &str, x: &[f64]) -> Result<Vector3<f64>> {
    if x.len() != 3 {
        bail!("{src} {name}: expected 3 numbers, got {}", x.len());
    }
    if let Some(k) = x.iter().position(|y| !y.is_finite()) {
        bail!("{src} {name}[{k}]: not finite");
    }
    Ok(Vector3::new(x[0], x[1], x[2]))
}

/// Runs `moma space`.
pub fn run(args: Args) -> Result<()> {
    let mut model = load_model(&args.urdf, RootJoint::FreeFlyer)?;
    model.gravity = Vector3::zeros();
    let fid = model
        .frame_id(&args.frame)
        .with_context(|| format!("{}: --frame", args.urdf.display()))?;
    let mut sd = SpaceData::new(&model).with_context(|| args.urdf.display().to_string())?;
    let states = read_states(&args.states)?;
    let conv = super::common::LayoutConv::new(&model, args.layout);
    if states.states.is_empty() {
        bail!("{}: 'states' is empty", args.states.display());
    }
    let n = sd.n;
    let mut data = Data::new(&model);
    let mut out_states = Vec::with_capacity(states.states.len());
    for (k, s) in states.states.iter().enumerate() {
        let src = format!("{}: states[{k}]", args.states.display());
        let q_in = conv.q_in(s.q.clone(), &format!("{src}.q"))?;
        moma::kinematics::check_state(&model, &src, Some(&q_in), None, None, None)?;
        if s.qdot_joints.len() != n {
            bail!(
                "{src} qdot_joints: expected {n} numbers (nv − 6 = {} − 6), got {}",
                model.nv,
                s.qdot_joints.len()
            );
        }
        if let Some(i) = s.qdot_joints.iter().position(|y| !y.is_finite()) {
            bail!("{src} qdot_joints[{i}]: not finite");
        }
        let h = match &s.momentum {
            Some(m) => Force::new(
                vec3(&src, "momentum.linear", &m.linear)?,
                vec3(&src, "momentum.angular_about_com", &m.angular_about_com)?,
            ),
            None => Force::zero(),
        };
        let q = DVector::from_column_slice(&q_in);
        let vb = space::base_velocity(&model, &mut data, &mut sd, &q, &s.qdot_joints, &h)
            .with_context(|| src.clone())?;
        let v = sd.v.as_slice().to_vec();
        space::generalized_jacobian(&model, &mut data, &mut sd, &q, fid)
            .with_context(|| src.clone())?;
        let xf = space::frame_velocity(&sd, &s.qdot_joints, &h);
        let gj = sd
            .generalized_jacobian
            .row_iter()
            .map(|r| r.iter().copied().collect())
            .collect();
        let hs = space::generalized_inertia(&model, &mut data, &mut sd, &q)
            .with_context(|| src.clone())?
            .row_iter()
            .map(|r| r.iter().copied().collect())
            .collect();
        let st = StateOut {
            total_mass: sd.total_mass,
            com: [sd.com.x, sd.com.y, sd.com.z],
            base_velocity: vb.to_vector().into(),
            v,
            generalized_jacobian: gj,
            generalized_inertia: hs,
            frame_velocity: xf.into(),
        };
        let finite =
            st.v.iter()
                .chain(st.frame_velocity.iter())
                .all(|x| x.is_finite());
        if !finite {
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

//! `moma dynamics ROBOT.urdf --root R --states STATES.json [--frame NAME]
//! [--gravity GX,GY,GZ] [--output OUT.json]`: RNEA, CRBA, ABA, nonlinear effects, gravity,
//! CoM, centroidal map and one frame's placement and Jacobian for each state. Schema:
//! `docs/cli.md`.

use super::common::{
    Layout, LayoutConv, State, load_model, parse_root, read_states, rows, state_vectors,
};
use anyhow::{Context, Result, bail};
use moma::dynamics;
use moma::kinematics::{self, ReferenceFrame};
use moma::multibody::{Data, FrameIndex, Model, RootJoint};
use nalgebra::{DMatrix, DVector, Matrix6xX, Vector3};
use serde::Serialize;
use std::path::PathBuf;

/// Arguments of `moma dynamics`.
#[derive(clap::Args)]
pub struct Args {
    /// The robot description (URDF).
    pub urdf: PathBuf,
    /// Root joint: fixed, planar (q = [x, y, θ], v world axes) or free-flyer.
    #[arg(long, value_parser = parse_root)]
    pub root: RootJoint,
    /// States file: `{"states": [{"q": [..], "v": [..], "a": [..], "tau": [..]}, ..]}`.
    #[arg(long)]
    pub states: PathBuf,
    /// Frame for the placement and Jacobian outputs (default: the last link).
    #[arg(long)]
    pub frame: Option<String>,
    /// Gravity in world axes, m/s² (default 0,0,-9.81).
    #[arg(long, value_parser = parse_gravity, allow_hyphen_values = true)]
    pub gravity: Option<Vector3<f64>>,
    /// Write the JSON here (atomically) instead of standard output.
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// State layout of the states file and of the outputs: moma (planar root [x, y, θ],
    /// world-axes velocity; continuous joints as one angle) or pinocchio ([x, y, cos θ,
    /// sin θ], base-frame velocity; continuous joints as cos, sin).
    #[arg(long, value_enum, default_value_t = Layout::Moma)]
    pub layout: Layout,
}

fn parse_gravity(s: &str) -> Result<Vector3<f64>, String> {
    let parts: Vec<&str> = s.split(',').collect();
    if parts.len() != 3 {
        return Err(format!(
            "expected GX,GY,GZ (three comma-separated numbers), got '{s}'"
        ));
    }
    let mut g = [0.0; 3];
    for (k, p) in parts.iter().enumerate() {
        let x: f64 = p
            .trim()
            .parse()
            .map_err(|_| format!("component {k} '{p}' is not a number"))?;
        if !x.is_finite() {
            return Err(format!("component {k} '{p}' is not finite"));
        }
        g[k] = x;
    }
    Ok(Vector3::from(g))
}

#[derive(Serialize)]
struct StateOut {
    rnea_tau: Vec<f64>,
    #[serde(rename = "crba_M")]
    crba_m: Vec<Vec<f64>>,
    aba_ddq: Vec<f64>,
    nle: Vec<f64>,
    gravity_torque: Vec<f64>,
    com: [f64; 3],
    #[serde(rename = "centroidal_map_Ag")]
    centroidal_map_ag: Vec<Vec<f64>>,
    kinetic_energy: f64,
    potential_energy: f64,
    position: [f64; 3],
    rotation: [[f64; 3]; 3],
    quaternion_xyzw: [f64; 4],
    jacobian_local_world_aligned: Vec<Vec<f64>>,
}

#[derive(Serialize)]
struct Output {
    robot: String,
    source: String,
    root: String,
    nq: usize,
    nv: usize,
    layout: &'static str,
    gravity: [f64; 3],
    frame: String,
    states: Vec<StateOut>,
}

/// Runs `moma dynamics`.
pub fn run(args: Args) -> Result<()> {
    let mut model = load_model(&args.urdf, args.root)?;
    if let Some(g) = args.gravity {
        model.gravity = g;
    }
    let fid = match &args.frame {
        Some(name) => model
            .frame_id(name)
            .with_context(|| format!("{}: --frame", args.urdf.display()))?,
        None => model.last_link_frame(),
    };
    let mut states = read_states(&args.states, &["q", "v", "a", "tau"])?;
    let conv = LayoutConv::new(&model, args.layout);
    let mut data = Data::new(&model);
    let out_states = states
        .iter_mut()
        .enumerate()
        .map(|(k, s)| {
            let src = format!("{}: states[{k}]", args.states.display());
            conv.state_in(s, &src)?;
            evaluate_state(&model, &mut data, fid, s, &src, &conv)
        })
        .collect::<Result<Vec<_>>>()?;
    let out = Output {
        robot: model.name.clone(),
        source: args.urdf.display().to_string(),
        root: model.root.to_string(),
        nq: match args.layout {
            Layout::Moma => model.nq,
            Layout::Pinocchio => moma::io::pinocchio_layout::PinocchioLayout::new(&model).nq(),
        },
        nv: model.nv,
        layout: match args.layout {
            Layout::Moma => "moma",
            Layout::Pinocchio => "pinocchio",
        },
        gravity: [model.gravity.x, model.gravity.y, model.gravity.z],
        frame: model.frames[fid.0].name.clone(),
        states: out_states,
    };
    match &args.output {
        Some(p) => crate::output::write_json(p, &out),
        None => crate::output::print_json(&out),
    }
}

/// Every output of one state (in moma's layout), written in `conv`'s layout; `src` names
/// the state in errors.
fn evaluate_state(
    model: &Model,
    data: &mut Data,
    fid: FrameIndex,
    s: &State,
    src: &str,
    conv: &LayoutConv,
) -> Result<StateOut> {
    let nv = model.nv;
    let [q, v, a, tau] = state_vectors(model, s, src)?;
    let qs = q.as_slice();
    let rnea_tau = conv.v_out(qs, dynamics::rnea(model, data, &q, &v, &a).as_slice());
    let crba_m = rows(&conv.matrix_out(qs, dynamics::crba(model, data, &q)));
    let aba = dynamics::aba(model, data, &q, &v, &tau).clone();
    let aba_ddq = conv.a_out(qs, v.as_slice(), aba.as_slice());
    if let Some(i) = aba_ddq.iter().position(|x| !x.is_finite()) {
        bail!(
            "{src}: forward dynamics gave a non-finite acceleration at v[{i}] (singular mass matrix: massless subtree? or inputs v, tau, --gravity beyond f64's range)"
        );
    }
    if let Some(i) = rnea_tau.iter().position(|x| !x.is_finite()) {
        bail!(
            "{src}: inverse dynamics gave a non-finite torque at tau[{i}] (inputs v, a, --gravity beyond f64's range)"
        );
    }
    // The bias is RNEA at zero acceleration *in the output layout* (for a planar root in
    // Pinocchio's layout that is not a = 0, see moma::io::pinocchio_layout).
    let nle = if conv.moves_velocities() {
        let a0 = DVector::from_vec(conv.zero_acceleration(qs, v.as_slice()));
        conv.v_out(qs, dynamics::rnea(model, data, &q, &v, &a0).as_slice())
    } else {
        dynamics::nonlinear_effects(model, data, &q, &v)
            .as_slice()
            .to_vec()
    };
    let gravity_torque = conv.v_out(qs, dynamics::gravity_torque(model, data, &q).as_slice());
    let ag_m = dynamics::centroidal_momentum_matrix(model, data, &q).clone();
    let ag = rows(&conv.jacobian_out(qs, &DMatrix::from_column_slice(6, nv, ag_m.as_slice())));
    let com = data.com;
    let kinetic_energy = dynamics::kinetic_energy(model, data, &q, &v);
    let potential_energy = dynamics::potential_energy(model, data, &q);
    let mut jac = Matrix6xX::zeros(nv);
    kinematics::frame_jacobian(
        model,
        data,
        &q,
        fid,
        ReferenceFrame::LocalWorldAligned,
        &mut jac,
    );
    let m = data.world_from_frame[fid.0];
    let r = m.rotation;
    let c = m.quaternion().as_ref().coords;
    Ok(StateOut {
        rnea_tau,
        crba_m,
        aba_ddq,
        nle,
        gravity_torque,
        com: [com.x, com.y, com.z],
        centroidal_map_ag: ag,
        kinetic_energy,
        potential_energy,
        position: [m.translation.x, m.translation.y, m.translation.z],
        rotation: [
            [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
            [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
            [r[(2, 0)], r[(2, 1)], r[(2, 2)]],
        ],
        quaternion_xyzw: [c[0], c[1], c[2], c[3]],
        jacobian_local_world_aligned: rows(
            &conv.jacobian_out(qs, &DMatrix::from_column_slice(6, nv, jac.as_slice())),
        ),
    })
}

//! `moma derivatives ROBOT.urdf --root R --states STATES.json [--layout moma|pinocchio]
//! [--frame NAME] [--output OUT.json]`: the analytical derivatives of inverse dynamics
//! (∂τ/∂q, ∂τ/∂v, ∂τ/∂a = M) and of forward dynamics (∂q̈/∂q, ∂q̈/∂v, ∂q̈/∂τ = M⁻¹) for
//! each state, and with `--frame` those of the frame's placement, velocity and
//! acceleration. Schema: `docs/cli.md`.

use super::common::{
    Layout, LayoutConv, State, load_model, parse_root, read_states, rows, state_vectors,
};
use anyhow::{Context, Result, anyhow, bail};
use moma::dynamics::{self, DerivativeData, FrameDerivativeData};
use moma::kinematics::ReferenceFrame;
use moma::multibody::{FrameIndex, Model, RootJoint};
use nalgebra::{DVector, Matrix6xX};
use serde::Serialize;
use std::path::PathBuf;

/// Arguments of `moma derivatives`.
#[derive(clap::Args)]
pub struct Args {
    /// The robot description (URDF).
    pub urdf: PathBuf,
    /// Root joint: fixed, planar (q = [x, y, θ], v world axes) or free-flyer.
    #[arg(long, value_parser = parse_root)]
    pub root: RootJoint,
    /// States file: `{"states": [{"q": [..], "v": [..], "a": [..], "tau": [..]}, ..]}`
    /// (v, a, tau default to zeros). RNEA's derivatives are taken at (q, v, a), ABA's at
    /// (q, v, tau).
    #[arg(long)]
    pub states: PathBuf,
    /// Write the JSON here (atomically) instead of standard output.
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// State layout of the states file and of the outputs: moma (planar root [x, y, θ],
    /// world-axes velocity; continuous joints as one angle) or pinocchio ([x, y, cos θ,
    /// sin θ], base-frame velocity; continuous joints as cos, sin). With pinocchio the
    /// outputs are Pinocchio's computeRNEADerivatives / computeABADerivatives.
    #[arg(long, value_enum, default_value_t = Layout::Moma)]
    pub layout: Layout,
    /// Also the derivatives of this frame's placement, velocity and acceleration at
    /// (q, v, a), in the LOCAL, WORLD and LOCAL_WORLD_ALIGNED frames (field `frame` of
    /// each state).
    #[arg(long)]
    pub frame: Option<String>,
}

#[derive(Serialize)]
struct StateOut {
    drnea_dq: Vec<Vec<f64>>,
    drnea_dv: Vec<Vec<f64>>,
    drnea_da: Vec<Vec<f64>>,
    daba_dq: Vec<Vec<f64>>,
    daba_dv: Vec<Vec<f64>>,
    daba_dtau: Vec<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    frame: Option<FrameOut>,
}

/// One frame's motion and derivatives at one state.
#[derive(Serialize)]
struct FrameOut {
    name: String,
    placement: Placement,
    local: FrameDerivativesOut,
    world: FrameDerivativesOut,
    local_world_aligned: FrameDerivativesOut,
}

#[derive(Serialize)]
struct Placement {
    translation: [f64; 3],
    rotation: [[f64; 3]; 3],
}

/// The frame's twist and acceleration in one reference frame and their derivatives
/// (6 × nv row lists).
#[derive(Serialize)]
struct FrameDerivativesOut {
    velocity: [f64; 6],
    acceleration: [f64; 6],
    jacobian: Vec<Vec<f64>>,
    dv_dq: Vec<Vec<f64>>,
    da_dq: Vec<Vec<f64>>,
    da_dv: Vec<Vec<f64>>,
}

/// The frame part of `moma derivatives`: its index, workspace and four 6 × nv buffers.
struct FrameWork {
    name: String,
    frame: FrameIndex,
    fd: FrameDerivativeData,
    m: [Matrix6xX<f64>; 4],
}

#[derive(Serialize)]
struct Output {
    robot: String,
    source: String,
    root: String,
    nv: usize,
    layout: &'static str,
    states: Vec<StateOut>,
}

/// Runs `moma derivatives`.
pub fn run(args: Args) -> Result<()> {
    let model = load_model(&args.urdf, args.root)?;
    let mut states = read_states(&args.states, &["q", "v", "a", "tau"])?;
    let conv = LayoutConv::new(&model, args.layout);
    let mut dd = DerivativeData::new(&model);
    let mut frame = match &args.frame {
        Some(name) => Some(FrameWork {
            name: name.clone(),
            frame: model
                .frame_id(name)
                .with_context(|| format!("{}: --frame", args.urdf.display()))?,
            fd: FrameDerivativeData::new(&model),
            m: [(); 4].map(|()| Matrix6xX::zeros(model.nv)),
        }),
        None => None,
    };
    let out_states = states
        .iter_mut()
        .enumerate()
        .map(|(k, s)| {
            let src = format!("{}: states[{k}]", args.states.display());
            conv.state_in(s, &src)?;
            evaluate_state(&model, &mut dd, frame.as_mut(), s, &src, &conv)
        })
        .collect::<Result<Vec<_>>>()?;
    let out = Output {
        robot: model.name.clone(),
        source: args.urdf.display().to_string(),
        root: model.root.to_string(),
        nv: model.nv,
        layout: match args.layout {
            Layout::Moma => "moma",
            Layout::Pinocchio => "pinocchio",
        },
        states: out_states,
    };
    match &args.output {
        Some(p) => crate::output::write_json(p, &out),
        None => crate::output::print_json(&out),
    }
}

/// The six matrices of one state (computed in moma's layout), in `conv`'s layout; `src`
/// names the state in errors.
fn evaluate_state(
    model: &Model,
    dd: &mut DerivativeData,
    frame: Option<&mut FrameWork>,
    s: &State,
    src: &str,
    conv: &LayoutConv,
) -> Result<StateOut> {
    let nv = model.nv;
    let [q, v, a, tau] = state_vectors(model, s, src)?;
    let (qs, vs) = (q.as_slice(), v.as_slice());
    dynamics::rnea_derivatives(model, dd, &q, &v, &a);
    let mut rnea = [
        dd.drnea_dq.clone(),
        dd.drnea_dv.clone(),
        dd.drnea_da.clone(),
    ];
    conv.rnea_derivatives_out(qs, vs, a.as_slice(), dd.tau.as_slice(), &mut rnea);
    dynamics::aba_derivatives(model, dd, &q, &v, &tau).map_err(|e| anyhow!("{src}: {e}"))?;
    let mut aba = [dd.daba_dq.clone(), dd.daba_dv.clone(), dd.daba_dtau.clone()];
    conv.aba_derivatives_out(qs, vs, tau.as_slice(), dd.ddq.as_slice(), &mut aba);
    for (name, m) in ["drnea_dq", "drnea_dv", "drnea_da"]
        .iter()
        .zip(&rnea)
        .chain(["daba_dq", "daba_dv", "daba_dtau"].iter().zip(&aba))
    {
        if let Some(k) = m.iter().position(|x| !x.is_finite()) {
            bail!(
                "{src}: {name} has a non-finite entry at [{}][{}] (inputs v, a, tau beyond f64's range?)",
                k % nv,
                k / nv
            );
        }
    }
    let frame = frame
        .map(|fw| evaluate_frame(model, fw, &q, &v, &a, src, conv))
        .transpose()?;
    let [dq, dv, da] = rnea;
    let [bq, bv, bt] = aba;
    Ok(StateOut {
        drnea_dq: rows(&dq),
        drnea_dv: rows(&dv),
        drnea_da: rows(&da),
        daba_dq: rows(&bq),
        daba_dv: rows(&bv),
        daba_dtau: rows(&bt),
        frame,
    })
}

/// The frame's placement, motion and derivatives at `(q, v, a)` (moma's layout) in the
/// three reference frames, written in `conv`'s layout.
fn evaluate_frame(
    model: &Model,
    fw: &mut FrameWork,
    q: &DVector<f64>,
    v: &DVector<f64>,
    a: &DVector<f64>,
    src: &str,
    conv: &LayoutConv,
) -> Result<FrameOut> {
    dynamics::forward_kinematics_derivatives(model, &mut fw.fd, q, v, a);
    let (qs, vs, as_) = (q.as_slice(), v.as_slice(), a.as_slice());
    let mut one = |rf: ReferenceFrame| -> Result<FrameDerivativesOut> {
        let [vq, aq, av, aa] = &mut fw.m;
        dynamics::frame_acceleration_derivatives(model, &fw.fd, fw.frame, rf, vq, aq, av, aa);
        conv.frame_derivatives_out(qs, vs, as_, [vq, aq, av, aa]);
        let (_, vel, acc) = dynamics::frame_motion(model, &fw.fd, fw.frame, rf);
        let six = |m: &moma::spatial::Motion| {
            let x = m.to_vector();
            [x[0], x[1], x[2], x[3], x[4], x[5]]
        };
        for (name, m) in [("dv_dq", &*vq), ("da_dq", &*aq), ("da_dv", &*av)] {
            if let Some(k) = m.iter().position(|x| !x.is_finite()) {
                bail!(
                    "{src}: frame {name} has a non-finite entry at [{}][{}] (inputs v, a beyond f64's range?)",
                    k % 6,
                    k / 6
                );
            }
        }
        let rows6 = |m: &Matrix6xX<f64>| -> Vec<Vec<f64>> {
            m.row_iter().map(|r| r.iter().copied().collect()).collect()
        };
        Ok(FrameDerivativesOut {
            velocity: six(&vel),
            acceleration: six(&acc),
            jacobian: rows6(aa),
            dv_dq: rows6(vq),
            da_dq: rows6(aq),
            da_dv: rows6(av),
        })
    };
    let (local, world, local_world_aligned) = (
        one(ReferenceFrame::Local)?,
        one(ReferenceFrame::World)?,
        one(ReferenceFrame::LocalWorldAligned)?,
    );
    let (m, _, _) = dynamics::frame_motion(model, &fw.fd, fw.frame, ReferenceFrame::World);
    let r = m.rotation;
    Ok(FrameOut {
        name: fw.name.clone(),
        placement: Placement {
            translation: [m.translation.x, m.translation.y, m.translation.z],
            rotation: [0, 1, 2].map(|i| [r[(i, 0)], r[(i, 1)], r[(i, 2)]]),
        },
        local,
        world,
        local_world_aligned,
    })
}

//! `moma derivatives ROBOT.urdf --root R --states STATES.json [--layout moma|pinocchio]
//! [--output OUT.json]`: the analytical derivatives of inverse dynamics (∂τ/∂q, ∂τ/∂v,
//! ∂τ/∂a = M) and of forward dynamics (∂q̈/∂q, ∂q̈/∂v, ∂q̈/∂τ = M⁻¹) for each state.
//! Schema: `docs/cli.md`.

use super::common::{Layout, LayoutConv, State, load_model, parse_root, read_states};
use anyhow::{Result, anyhow, bail};
use moma::dynamics::{self, DerivativeData};
use moma::kinematics;
use moma::multibody::{Model, RootJoint};
use nalgebra::{DMatrix, DVector};
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
}

#[derive(Serialize)]
struct StateOut {
    drnea_dq: Vec<Vec<f64>>,
    drnea_dv: Vec<Vec<f64>>,
    drnea_da: Vec<Vec<f64>>,
    daba_dq: Vec<Vec<f64>>,
    daba_dv: Vec<Vec<f64>>,
    daba_dtau: Vec<Vec<f64>>,
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

fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    m.row_iter().map(|r| r.iter().copied().collect()).collect()
}

/// Runs `moma derivatives`.
pub fn run(args: Args) -> Result<()> {
    let model = load_model(&args.urdf, args.root)?;
    let mut states = read_states(&args.states, &["q", "v", "a", "tau"])?;
    let conv = LayoutConv::new(&model, args.layout);
    let mut dd = DerivativeData::new(&model);
    let out_states = states
        .iter_mut()
        .enumerate()
        .map(|(k, s)| {
            let src = format!("{}: states[{k}]", args.states.display());
            conv.state_in(s, &src)?;
            evaluate_state(&model, &mut dd, s, &src, &conv)
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
    s: &State,
    src: &str,
    conv: &LayoutConv,
) -> Result<StateOut> {
    let nv = model.nv;
    kinematics::check_state(
        model,
        src,
        Some(&s.q),
        s.v.as_deref(),
        s.a.as_deref(),
        s.tau.as_deref(),
    )?;
    let q = DVector::from_column_slice(&s.q);
    let get = |x: &Option<Vec<f64>>| {
        x.as_ref()
            .map_or_else(|| DVector::zeros(nv), |x| DVector::from_column_slice(x))
    };
    let (v, a, tau) = (get(&s.v), get(&s.a), get(&s.tau));
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
    let [dq, dv, da] = rnea;
    let [bq, bv, bt] = aba;
    Ok(StateOut {
        drnea_dq: rows(&dq),
        drnea_dv: rows(&dv),
        drnea_da: rows(&da),
        daba_dq: rows(&bq),
        daba_dv: rows(&bv),
        daba_dtau: rows(&bt),
    })
}

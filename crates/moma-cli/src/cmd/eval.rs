//! `moma eval CASES.json [--output OUT.json]`: evaluates the chapter's closed-form models
//! (m1–m6) on a case file in the schema of the reference vectors and writes the same
//! document with every case's `outputs` and `trajectory` filled in. The
//! `unicycle_control` schema runs the non-holonomic feedback laws in closed loop and fills
//! `trajectory.state`, `v`, `w` and `V`.

use crate::output::{print_json, write_json};
use anyhow::{Context, Result, anyhow};
use moma::closed_form::cases::{
    DEFAULT_TOLERANCE, MAX_TOLERANCE as MAX_TOL, MIN_TOLERANCE as MIN_TOL, evaluate_document,
};
use std::path::PathBuf;

/// Arguments of `moma eval`.
#[derive(clap::Args)]
pub struct Args {
    /// Case file (JSON): `model` (m1_unicycle, m2_platform_planar_arm,
    /// m3_diffdrive_kinematics, m4_cart_two_link, m5_mobile_manipulator_3d) and `cases`
    /// with `params`, `state`, `inputs` and optionally `trajectory.t`; or `model`
    /// unicycle_control with cases `law`, `gains`, `reference`, `initial_state`,
    /// `trajectory.t`.
    pub cases: PathBuf,
    /// Output file (JSON); standard output if omitted. Written only if every case succeeds.
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    /// Integration tolerance (rtol = atol) for trajectories, in [1e-15, 0.1].
    #[arg(long, default_value_t = DEFAULT_TOLERANCE)]
    pub tol: f64,
}

/// Runs `moma eval`.
pub fn run(args: Args) -> Result<()> {
    if !(MIN_TOL..=MAX_TOL).contains(&args.tol) {
        return Err(anyhow!(
            "--tol must be in [{MIN_TOL:e}, {MAX_TOL}] (the integrator cannot meet a relative \
             tolerance below f64's resolution), got {}",
            args.tol
        ));
    }
    let path = &args.cases;
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read case file", path.display()))?;
    let doc: serde_json::Value = serde_json::from_str(&text)
        .map_err(|e| anyhow!("{}: malformed JSON: {e}", path.display()))?;
    let out = evaluate_document(&doc, args.tol).map_err(|e| {
        let hint = if e.to_string().contains("step size underflow") {
            format!(" (--tol {:e} may be too tight for this case)", args.tol)
        } else {
            String::new()
        };
        anyhow!("{}: {e}{hint}", path.display())
    })?;
    if let Some(cases) = out.get("cases").and_then(|c| c.as_array()) {
        for c in cases {
            if let Some(ws) = c.get("warnings").and_then(|w| w.as_array()) {
                let id = c.get("id").map_or_else(String::new, ToString::to_string);
                for w in ws {
                    eprintln!(
                        "warning: {}: case {id}: {}",
                        path.display(),
                        w.as_str().unwrap_or_default()
                    );
                }
            }
        }
    }
    match &args.output {
        Some(o) => write_json(o, &out),
        None => print_json(&out),
    }
}

//! `moma simulate [SCENARIO.toml]`: run a constrained (wheeled) simulation in reduced
//! coordinates and write a CSV trajectory, a JSON summary and SVG plots.
//!
//! Without an argument the bundled `scenarios/default.toml` runs (looked up in the
//! current directory, then next to the source tree this binary was built from). The
//! scenario schema is documented in `docs/simulate.md`.

use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use moma::sim::settings::IntegratorSettings;
use moma::sim::wheeled::SimulationResult;
use moma::sim_config::{OpenLoop, Run};
use serde::Serialize;

pub use super::simulate_common::Args;
use super::simulate_common::{
    RobotSpec, Scenario, arm_plots, balance_plots, motion_plots, progress_bar,
};
use crate::output::write_dir;

/// The summary written as `summary.json`.
#[derive(Debug, Serialize)]
struct Summary {
    scenario: String,
    robot: String,
    duration: f64,
    samples: usize,
    q_names: Vec<String>,
    v_names: Vec<String>,
    final_q: Vec<f64>,
    final_v: Vec<f64>,
    initial_energy: f64,
    final_energy: f64,
    input_work: f64,
    max_energy_error: f64,
    relative_energy_error: f64,
    max_constraint_residual: f64,
    integrator: IntegratorSettings,
    accepted_steps: usize,
    rejected_steps: usize,
    rhs_evaluations: usize,
    wall_time_s: f64,
    steps_per_second: f64,
    files: Vec<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    stability: Option<super::simulate_stability::StabilitySummary>,
}

/// Finds the scenario: the argument, else `scenarios/default.toml` in the current
/// directory, else the one in the source tree.
fn resolve_scenario(arg: Option<PathBuf>) -> Result<PathBuf> {
    if let Some(p) = arg {
        return Ok(p);
    }
    let local = PathBuf::from("scenarios/default.toml");
    if local.is_file() {
        return Ok(local);
    }
    let bundled = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/default.toml");
    if bundled.is_file() {
        return Ok(bundled);
    }
    bail!(
        "no scenario given and no scenarios/default.toml found in the current directory or at {}",
        bundled.display()
    )
}

/// Parses a scenario file, with errors naming the file and the line/field.
pub fn load_scenario(path: &Path) -> Result<Scenario> {
    Ok(moma::sim_config::load(path)?)
}

/// Builds every output file in memory.
fn render(
    fixed_base: bool,
    wheels: &[String],
    result: &SimulationResult,
    summary: &mut Summary,
    plots: bool,
    stability: Option<&moma::sim::stability_monitor::StabilityMonitor>,
) -> Result<Vec<(String, Vec<u8>)>> {
    let rec = &result.recorder;
    let mut files = vec![("trajectory.csv".to_string(), rec.to_csv().into_bytes())];
    if let Some(mon) = stability {
        files.push((
            "stability.csv".to_string(),
            super::simulate_stability::csv(mon).into_bytes(),
        ));
    }
    if plots {
        if fixed_base {
            arm_plots(rec, &mut files);
        } else {
            motion_plots(wheels, rec, &mut files);
        }
        balance_plots(rec, &mut files);
        if let Some(mon) = stability {
            super::simulate_stability::plots(mon, &mut files);
        }
    }
    super::simulate_common::push_summary(&mut files, summary, |s, names| s.files = names)?;
    Ok(files)
}

/// Runs `moma simulate`.
pub fn run(args: Args) -> Result<()> {
    let path = resolve_scenario(args.scenario.clone())?;
    let sc = load_scenario(&path)?;
    sc.check_header(&path)?;
    if sc.plant == moma::contact::PlantKind::Contact {
        return super::simulate_contact::run(&path, &sc, &args);
    }
    match moma::sim_config::prepare(&sc, &path)? {
        Run::Closed(cl) => super::simulate_control::run(&path, &sc, *cl, &args),
        Run::Space(sr) => super::simulate_space::run(&path, &sc, *sr, &args),
        Run::Open(ol) => run_open_loop(&path, &sc, *ol, &args),
    }
}

/// Simulates an open-loop run with a progress bar on a terminal.
fn simulate_with_progress(ol: &mut OpenLoop) -> moma::Result<SimulationResult> {
    let bar = progress_bar(ol.options.duration);
    let result = ol.run(&mut |t| {
        if let Some(pb) = &bar {
            pb.set_position((t * 1000.0).round() as u64);
        }
    });
    if let Some(pb) = &bar {
        pb.finish_and_clear();
    }
    result
}

/// The summary of a finished open-loop run (its file list is filled by [`render`]).
fn summary(
    path: &Path,
    sc: &Scenario,
    robot: String,
    result: &SimulationResult,
    wall: f64,
) -> Summary {
    let rec = &result.recorder;
    let last = rec.len() - 1;
    let steps = result.stats.accepted;
    Summary {
        scenario: sc
            .name
            .clone()
            .unwrap_or_else(|| path.display().to_string()),
        robot,
        duration: sc.duration,
        samples: rec.len(),
        q_names: rec.q_names.clone(),
        v_names: rec.v_names.clone(),
        final_q: rec.q_row(last).to_vec(),
        final_v: rec.v_row(last).to_vec(),
        initial_energy: rec.kinetic[0] + rec.potential[0],
        final_energy: rec.kinetic[last] + rec.potential[last],
        input_work: rec.work[last],
        max_energy_error: result.monitor.max_energy_error,
        relative_energy_error: result.monitor.relative_energy_error(),
        max_constraint_residual: result.monitor.max_residual,
        integrator: sc.integrator,
        accepted_steps: steps,
        rejected_steps: result.stats.rejected,
        rhs_evaluations: result.stats.rhs_evals,
        wall_time_s: wall,
        steps_per_second: if wall > 0.0 { steps as f64 / wall } else { 0.0 },
        files: Vec::new(),
        stability: None,
    }
}

/// Runs an open-loop scenario and writes its files.
fn run_open_loop(path: &Path, sc: &Scenario, mut ol: OpenLoop, args: &Args) -> Result<()> {
    let dir = args.output.clone().unwrap_or_else(|| sc.output.dir.clone());
    let start = Instant::now();
    let result = simulate_with_progress(&mut ol)
        .with_context(|| format!("{}: simulation failed", path.display()))?;
    let wall = start.elapsed().as_secs_f64();
    let monitor = ol.monitor;
    let mut summary = summary(path, sc, ol.robot_name, &result, wall);
    if let (Some(spec), Some(mon)) = (&sc.stability, &monitor) {
        summary.stability = Some(super::simulate_stability::summary(
            spec,
            mon,
            result.stopped_at,
        ));
    }
    let fixed = matches!(sc.robot, RobotSpec::FixedBase { .. });
    let files = render(
        fixed,
        &moma::sim_config::wheel_joints(sc),
        &result,
        &mut summary,
        sc.output.plots,
        monitor.as_ref(),
    )?;
    write_dir(&dir, &files)?;
    if !args.quiet {
        crate::output::print_json(&summary)?;
    }
    if let (Some(spec), Some(mon)) = (&sc.stability, &monitor)
        && spec.require_stable
        && mon.tipped()
    {
        return super::common::goal_not_reached(super::simulate_stability::tip_message(mon));
    }
    Ok(())
}

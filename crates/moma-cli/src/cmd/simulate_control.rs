//! `moma simulate` in closed loop: a scenario with a `[controller]` table (the law and its
//! gains) and a `[reference]` table (what it tracks). The unicycle laws and regulated pure
//! pursuit drive a wheeled URDF robot through an inner computed-torque loop (their
//! reference may be a path planned on a map); `coordinated` coordinates the platform
//! with two arm joints so the end effector tracks its reference; `osc` drives
//! an end-effector point of a wheeled URDF robot through the reduced model; `mpc` is the
//! whole-body MPC (its solves summarised in the summary's `mpc` object); `pd_plus`,
//! `computed_torque` and the `decoupled_*` laws run on the chapter's model m5. Writes the
//! open-loop files plus `control.csv`, `tracking_error.svg` and `lyapunov.svg`, and a
//! summary with the Lyapunov monitor and the saturation report. Schema:
//! `docs/simulate.md`.

use super::simulate_common::{
    Args, RobotSpec, Scenario, arm_plots, balance_plots, motion_plots, progress_bar, series,
};
use crate::output::write_dir;
use crate::svg_plots::line_chart;
use anyhow::{Context, Result, anyhow};
use moma::sim::closed_loop::ClosedLoopResult;
use moma::sim::mpc_run::MpcRunSummary;
use moma::sim::settings::IntegratorSettings;
use moma::sim::stability_monitor::StabilityMonitor;
use moma::sim_config::{ClosedLoop, ControllerSpec};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

#[derive(Debug, Serialize)]
struct ViolationOut {
    t: f64,
    increase: f64,
}

#[derive(Debug, Serialize)]
struct LyapunovOut {
    v_first: f64,
    v_last: f64,
    monotone: bool,
    violations: usize,
    first_violations: Vec<ViolationOut>,
    max_integral_error: Option<f64>,
    max_rate_error: Option<f64>,
    tolerance: f64,
}

#[derive(Debug, Serialize)]
struct SaturationOut {
    evaluations: usize,
    speed_limited: usize,
    torque_limited: usize,
    first_speed_limited_t: Option<f64>,
    first_torque_limited_t: Option<f64>,
}

#[derive(Debug, Serialize)]
struct ControlSummary {
    scenario: String,
    robot: String,
    law: String,
    reference: String,
    duration: f64,
    control_period: Option<f64>,
    control_ticks: usize,
    samples: usize,
    q_names: Vec<String>,
    v_names: Vec<String>,
    final_q: Vec<f64>,
    final_v: Vec<f64>,
    error_names: Vec<String>,
    initial_error: Vec<f64>,
    final_error: Vec<f64>,
    final_error_norm: f64,
    max_abs_error: Vec<f64>,
    goal_tolerance: Option<f64>,
    goal_reached: Option<bool>,
    lyapunov: Option<LyapunovOut>,
    saturation: SaturationOut,
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
    #[serde(skip_serializing_if = "Option::is_none")]
    mpc: Option<MpcRunSummary>,
}

/// The `mpc` section of a run whose law is the MPC.
fn mpc_out(cl: &ClosedLoop) -> Option<MpcRunSummary> {
    Some(cl.law.mpc_run()?.summary.clone())
}

/// `t, errors…, V, V̇_analytic` per sample.
fn control_csv(res: &ClosedLoopResult) -> String {
    let mut s = String::from("t [s]");
    for n in &res.error_names {
        s.push(',');
        s.push_str(n);
    }
    let has_v = !res.lyapunov.is_empty();
    if has_v {
        s.push_str(",V,V_rate_analytic [1/s]");
    }
    for n in &res.signal_names {
        s.push(',');
        s.push_str(n);
    }
    s.push('\n');
    for (i, t) in res.recorder.times.iter().enumerate() {
        s.push_str(&format!("{t:.17e}"));
        for e in res.error_row(i) {
            s.push_str(&format!(",{e:.17e}"));
        }
        if has_v {
            s.push_str(&format!(
                ",{:.17e},{:.17e}",
                res.lyapunov[i], res.lyapunov_rate[i]
            ));
        }
        for x in res.signal_row(i) {
            s.push_str(&format!(",{x:.17e}"));
        }
        s.push('\n');
    }
    s
}

fn control_plots(res: &ClosedLoopResult, files: &mut Vec<(String, Vec<u8>)>) {
    let t = &res.recorder.times;
    let errs: Vec<_> = res
        .error_names
        .iter()
        .enumerate()
        .map(|(k, n)| series(t, n, (0..t.len()).map(|i| res.error_row(i)[k]).collect()))
        .collect();
    files.push((
        "tracking_error.svg".to_string(),
        line_chart("Tracking error", "t [s]", "error [m], [rad]", &errs).into_bytes(),
    ));
    if !res.lyapunov.is_empty() {
        // V₀ + ∫ V̇_analytic (trapezoidal) beside the recorded V
        let mut integral = Vec::with_capacity(t.len());
        let mut acc = res.lyapunov[0];
        integral.push(acc);
        for i in 1..t.len() {
            acc += 0.5 * (t[i] - t[i - 1]) * (res.lyapunov_rate[i] + res.lyapunov_rate[i - 1]);
            integral.push(acc);
        }
        let s = vec![
            series(t, "V (recorded)", res.lyapunov.clone()),
            series(t, "V₀ + ∫ V̇ analytic", integral),
        ];
        files.push((
            "lyapunov.svg".to_string(),
            line_chart("Lyapunov function", "t [s]", "V", &s).into_bytes(),
        ));
    }
    // one plot per further signal of the law, named by the signal (e.g. manipulability.svg)
    for (k, n) in res.signal_names.iter().enumerate() {
        let stem: String = n
            .split([' ', '['])
            .next()
            .unwrap_or("signal")
            .chars()
            .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
            .collect();
        let s = vec![series(
            t,
            n,
            (0..t.len()).map(|i| res.signal_row(i)[k]).collect(),
        )];
        files.push((
            format!("{stem}.svg"),
            line_chart(&stem, "t [s]", n, &s).into_bytes(),
        ));
    }
}

/// Simulates the closed loop with a progress bar on a terminal.
fn simulate_with_progress(cl: &mut ClosedLoop) -> moma::Result<ClosedLoopResult> {
    let bar = progress_bar(cl.options.duration);
    let result = cl.run(&mut |t| {
        if let Some(pb) = &bar {
            pb.set_position((t * 1000.0).round() as u64);
        }
    });
    if let Some(pb) = &bar {
        pb.finish_and_clear();
    }
    result
}

/// The Lyapunov section of the summary.
fn lyapunov_out(res: &ClosedLoopResult, tol: f64) -> Option<LyapunovOut> {
    res.lyapunov_report.as_ref().map(|r| LyapunovOut {
        v_first: r.v_first,
        v_last: r.v_last,
        monotone: r.monotone(),
        violations: r.violations.len(),
        first_violations: r
            .violations
            .iter()
            .take(20)
            .map(|v| ViolationOut {
                t: v.t,
                increase: v.increase,
            })
            .collect(),
        max_integral_error: r.max_integral_error,
        max_rate_error: r.max_rate_error,
        tolerance: tol,
    })
}

/// The summary of a finished closed-loop run (its file list is filled by [`files`]).
fn control_summary(
    path: &Path,
    sc: &Scenario,
    c: &ControllerSpec,
    cl: &ClosedLoop,
    res: &ClosedLoopResult,
    wall: f64,
) -> ControlSummary {
    let rec = &res.recorder;
    let last = rec.len() - 1;
    let ne = res.error_names.len();
    let final_error = res.error_row(last).to_vec();
    let final_norm = final_error.iter().map(|e| e * e).sum::<f64>().sqrt();
    let max_abs_error = (0..ne)
        .map(|k| {
            (0..rec.len())
                .map(|i| res.error_row(i)[k].abs())
                .fold(0.0, f64::max)
        })
        .collect();
    let s = res.saturation;
    let steps = res.stats.accepted;
    ControlSummary {
        scenario: sc
            .name
            .clone()
            .unwrap_or_else(|| path.display().to_string()),
        robot: cl.robot_name.clone(),
        law: c.law.clone(),
        reference: sc.reference.as_ref().map_or("", |r| r.kind()).to_string(),
        duration: sc.duration,
        control_period: res.control_period,
        control_ticks: res.control_ticks,
        samples: rec.len(),
        q_names: rec.q_names.clone(),
        v_names: rec.v_names.clone(),
        final_q: rec.q_row(last).to_vec(),
        final_v: rec.v_row(last).to_vec(),
        error_names: res.error_names.clone(),
        initial_error: res.error_row(0).to_vec(),
        final_error,
        final_error_norm: final_norm,
        max_abs_error,
        goal_tolerance: c.goal_tolerance,
        goal_reached: c.goal_tolerance.map(|g| final_norm <= g),
        lyapunov: lyapunov_out(res, cl.options.lyapunov_tolerance),
        saturation: SaturationOut {
            evaluations: s.evaluations,
            speed_limited: s.speed,
            torque_limited: s.torque,
            first_speed_limited_t: s.first_speed,
            first_torque_limited_t: s.first_torque,
        },
        max_energy_error: res.monitor.max_energy_error,
        relative_energy_error: res.monitor.relative_energy_error(),
        max_constraint_residual: res.monitor.max_residual,
        integrator: sc.integrator,
        accepted_steps: steps,
        rejected_steps: res.stats.rejected,
        rhs_evaluations: res.stats.rhs_evals,
        wall_time_s: wall,
        steps_per_second: if wall > 0.0 { steps as f64 / wall } else { 0.0 },
        files: Vec::new(),
        stability: None,
        mpc: mpc_out(cl),
    }
}

/// Every output file in memory, `summary.json` last (its file list filled here).
fn files(
    sc: &Scenario,
    res: &ClosedLoopResult,
    monitor: Option<&StabilityMonitor>,
    summary: &mut ControlSummary,
) -> Result<Vec<(String, Vec<u8>)>> {
    let rec = &res.recorder;
    let mut files = vec![
        ("trajectory.csv".to_string(), rec.to_csv().into_bytes()),
        ("control.csv".to_string(), control_csv(res).into_bytes()),
    ];
    if let Some(mon) = monitor {
        files.push((
            "stability.csv".to_string(),
            super::simulate_stability::csv(mon).into_bytes(),
        ));
    }
    if sc.output.plots {
        if matches!(sc.robot, RobotSpec::FixedBase { .. }) {
            arm_plots(rec, &mut files);
        } else {
            motion_plots(&moma::sim_config::wheel_joints(sc), rec, &mut files);
        }
        balance_plots(rec, &mut files);
        control_plots(res, &mut files);
        if let Some(mon) = monitor {
            super::simulate_stability::plots(mon, &mut files);
        }
    }
    super::simulate_common::push_summary(&mut files, summary, |s, names| s.files = names)?;
    Ok(files)
}

/// Runs a closed-loop scenario built by `moma::sim_config::closed_loop` and writes its
/// files; exit status 3 when it tips over under `require_stable` or misses
/// `controller.goal_tolerance`.
pub fn run(path: &Path, sc: &Scenario, mut cl: ClosedLoop, args: &Args) -> Result<()> {
    let Some(c) = &sc.controller else {
        return Err(anyhow!(
            "{}: [reference] needs a [controller] table",
            path.display()
        ));
    };
    for w in &cl.warnings {
        eprintln!("warning: {w}");
    }
    let dir = args.output.clone().unwrap_or_else(|| sc.output.dir.clone());
    let start = Instant::now();
    let res = simulate_with_progress(&mut cl)
        .map_err(|e| anyhow!("{}: closed-loop simulation failed: {e}", path.display()))?;
    let wall = start.elapsed().as_secs_f64();
    let mut summary = control_summary(path, sc, c, &cl, &res, wall);
    let monitor = match &sc.stability {
        None => None,
        Some(spec) => {
            // On the plant that ran (perturbed under [uncertainty]).
            let mon = moma::sim_config::replay_scenario(spec, sc, path, &res.recorder)
                .with_context(|| format!("{}: stability", path.display()))?;
            summary.stability = Some(super::simulate_stability::summary(spec, &mon, None));
            Some(mon)
        }
    };
    let files = files(sc, &res, monitor.as_ref(), &mut summary)?;
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
    if summary.goal_reached == Some(false) {
        return super::common::goal_not_reached(format!(
            "{}: final tracking error {:e} exceeds controller.goal_tolerance = {}",
            path.display(),
            summary.final_error_norm,
            c.goal_tolerance.unwrap_or_default()
        ));
    }
    Ok(())
}

//! `moma mission [MISSION.toml]`: plan on a map, time the path under the tip-over limits,
//! track it in closed-loop dynamic simulation, re-plan when obstacles appear, reach an
//! end-effector target at the goal, and write the whole output set at once.
//!
//! Without an argument `scenarios/mission.toml` runs (looked up in the current
//! directory, then next to the source tree this binary was built from). The schema and
//! the outputs are documented in `docs/mission.md`. Exit status: 0 reached, 1 input error
//! (nothing written), 3 the mission ran but did not reach its goal (every output written,
//! `reached: false` and a `reason` in `summary.json`).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Result, anyhow, bail};
use moma::mission::{Mission, MissionResult};
use serde_json::{Value, json};

use crate::output::write_dir;

/// Arguments of `moma mission`.
#[derive(clap::Args)]
pub struct Args {
    /// Mission file (TOML). Default: scenarios/mission.toml.
    pub scenario: Option<PathBuf>,
    /// Output directory (overrides the mission's `output.dir`; relative to the current
    /// directory).
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    /// Do not print the summary on standard output.
    #[arg(long)]
    pub quiet: bool,
}

fn resolve_scenario(arg: Option<PathBuf>) -> Result<PathBuf> {
    if let Some(p) = arg {
        return Ok(p);
    }
    let local = PathBuf::from("scenarios/mission.toml");
    if local.is_file() {
        return Ok(local);
    }
    let bundled = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/mission.toml");
    if bundled.is_file() {
        return Ok(bundled);
    }
    bail!(
        "no mission given and no scenarios/mission.toml found in the current directory or at {}",
        bundled.display()
    )
}

fn opt(x: Option<f64>) -> Value {
    x.filter(|v| v.is_finite())
        .map_or(Value::Null, |v| json!(v))
}

/// The summary object (`summary.json`).
fn summary(m: &Mission, r: &MissionResult, wall_total: f64, report_s: f64) -> Value {
    let f = &m.file;
    let last = r.samples.t.len().saturating_sub(1);
    let final_pose = r.samples.q.get(last).map(|q| [q[0], q[1], q[2]]);
    let final_pose_error = final_pose.map(|p| {
        let g = f.goal.pose;
        json!([
            (p[0] - g[0]).hypot(p[1] - g[1]),
            moma::control::wrap_angle(g[2] - p[2]).abs()
        ])
    });
    let ee_error = f.goal.end_effector.and_then(|target| {
        r.samples.ee.get(last).map(|e| {
            ((e[0] - target[0]).powi(2) + (e[1] - target[1]).powi(2) + (e[2] - target[2]).powi(2))
                .sqrt()
        })
    });
    let replan_search: Vec<Value> = r
        .plans
        .iter()
        .skip(1)
        .map(|p| {
            json!({
                "t": p.t,
                "trigger": p.trigger,
                "dstar_lite_ms": p.search.search_s * 1e3,
                "expanded": p.search.expanded,
                "smoothing_timing_ms": p.smoothing_timing_s * 1e3,
                "v_start": p.v_start,
                "duration": p.duration,
            })
        })
        .collect();
    let sim_time = r.duration;
    json!({
        "mission": m.name,
        "reached": r.reached,
        "reason": r.reason,
        "time_to_goal": opt(r.time_to_goal),
        "simulated_time": sim_time,
        "replans": r.replans(),
        "min_zmp_margin": opt(r.min_zmp_margin()),
        "min_force_angle": opt(r.min_force_angle()),
        "min_moment_height": opt(r.min_mhs()),
        "min_clearance": opt(r.min_clearance()),
        "max_tracking_error": opt(r.max_tracking_error()),
        "final_pose_error": final_pose_error,
        "end_effector_error": opt(ee_error),
        "max_slip_ratio": opt(r.max_slip_ratio()),
        "torque_saturated_steps": r.torque_saturated_steps,
        "speed_saturated_steps": r.speed_saturated_steps,
        "control_steps": r.steps,
        "actuator_energy": r.samples.energy.last().copied().unwrap_or(0.0),
        "input_work": r.input_work,
        "tip_over_limits": {
            "forward": opt(r.tip_limits.forward),
            "backward": opt(r.tip_limits.backward),
            "left": opt(r.tip_limits.left),
            "right": opt(r.tip_limits.right),
        },
        "timing_acceleration": r.timing_acceleration,
        "replan_timing": replan_search,
        "wall_time_s": wall_total,
        "wall_time": {
            "planning_s": r.wall.planning_s,
            "smoothing_timing_s": r.wall.smoothing_timing_s,
            "simulation_s": r.wall.simulation_s,
            "report_s": report_s,
        },
        "real_time_factor": if wall_total > 0.0 { json!(sim_time / wall_total) } else { Value::Null },
        "samples": r.samples.t.len(),
        "files": ["summary.json", "trajectory.csv", "events.json", "top_view.svg", "speeds.svg", "margins.svg"],
    })
}

fn num(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        String::new()
    }
}

fn opt_num(x: Option<f64>) -> String {
    x.map_or_else(String::new, num)
}

/// `trajectory.csv`: one row per recorded sample.
fn trajectory_csv(r: &MissionResult) -> String {
    let s = &r.samples;
    let mut out = String::new();
    out.push_str("t,x,y,theta,v,omega,v_ref,omega_ref,x_ref,y_ref,zmp_margin,force_angle_min,moment_height_min,clearance,tracking_error,slip_ratio,ee_x,ee_y,ee_z,energy,phase");
    for n in &r.arm_names {
        let _ = write!(out, ",q_{n}");
    }
    for n in &r.u_names {
        let _ = write!(out, ",u_{n}");
    }
    out.push('\n');
    let arm: Vec<usize> = r
        .arm_names
        .iter()
        .filter_map(|n| r.q_names.iter().position(|q| q == n))
        .collect();
    for i in 0..s.t.len() {
        let q = &s.q[i];
        let _ = write!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            num(s.t[i]),
            num(q[0]),
            num(q[1]),
            num(q[2]),
            num(s.v[i]),
            num(s.omega[i]),
            num(s.v_ref[i]),
            num(s.omega_ref[i]),
            num(s.ref_xy[i][0]),
            num(s.ref_xy[i][1]),
            opt_num(s.zmp_margin[i]),
            opt_num(s.force_angle_min[i]),
            opt_num(s.mhs_min[i]),
            num(s.clearance[i]),
            num(s.tracking_error[i]),
            opt_num(s.slip_ratio[i]),
            num(s.ee[i][0]),
            num(s.ee[i][1]),
            num(s.ee[i][2]),
            num(s.energy[i]),
            s.phase[i]
        );
        for &j in &arm {
            let _ = write!(out, ",{}", num(q[j]));
        }
        for u in &s.u[i] {
            let _ = write!(out, ",{}", num(*u));
        }
        out.push('\n');
    }
    out
}

fn svgs(m: &Mission, r: &MissionResult) -> Result<Vec<(String, Vec<u8>)>> {
    use crate::svg_plots::{Series, line_chart};
    let grid = &m.map.grid;
    let cell = |p: [f64; 2]| -> (usize, usize) {
        let [fx, fy] = grid.world_to_cell_f(p[0], p[1]);
        (
            (fx.floor().max(0.0) as usize).min(grid.width - 1),
            (fy.floor().max(0.0) as usize).min(grid.height - 1),
        )
    };
    let f = &m.file;
    let start = cell([f.start.pose[0], f.start.pose[1]]);
    let goal = cell([f.goal.pose[0], f.goal.pose[1]]);
    let executed: Vec<(usize, usize)> = r.samples.q.iter().map(|q| cell([q[0], q[1]])).collect();
    let planned: Vec<(usize, usize)> = r
        .plans
        .last()
        .map(|p| p.path.iter().map(|&w| cell(w)).collect())
        .unwrap_or_default();
    let cspace = vec![false; grid.len()];
    let scene = crate::svg_map::Scene {
        grid,
        cspace: &cspace,
        path: &executed,
        smooth: &planned,
        start,
        goal,
        title: format!("{}: executed path and last plan", m.name),
    };
    let top = crate::svg_map::render(&scene)?;
    let t = &r.samples.t;
    let speeds = line_chart(
        "speeds",
        "t (s)",
        "m/s, rad/s",
        &[
            Series {
                name: "v",
                x: t,
                y: r.samples.v.clone(),
            },
            Series {
                name: "v_ref",
                x: t,
                y: r.samples.v_ref.clone(),
            },
            Series {
                name: "omega",
                x: t,
                y: r.samples.omega.clone(),
            },
            Series {
                name: "omega_ref",
                x: t,
                y: r.samples.omega_ref.clone(),
            },
        ],
    );
    let margins = line_chart(
        "margins",
        "t (s)",
        "m",
        &[
            Series {
                name: "ZMP margin",
                x: t,
                y: r.samples
                    .zmp_margin
                    .iter()
                    .map(|z| z.unwrap_or(f64::NAN))
                    .collect(),
            },
            Series {
                name: "clearance",
                x: t,
                y: r.samples.clearance.iter().map(|c| c.min(2.0)).collect(),
            },
            Series {
                name: "tracking error",
                x: t,
                y: r.samples.tracking_error.clone(),
            },
        ],
    );
    Ok(vec![
        ("top_view.svg".into(), top.into_bytes()),
        ("speeds.svg".into(), speeds.into_bytes()),
        ("margins.svg".into(), margins.into_bytes()),
    ])
}

/// Runs `moma mission`.
pub fn run(args: Args) -> Result<()> {
    let clock = Instant::now();
    let path = resolve_scenario(args.scenario)?;
    let m = moma::mission::load(&path).map_err(|e| anyhow!("{e}"))?;
    let result = moma::mission::run(&m).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    let report_clock = Instant::now();
    let mut files = svgs(&m, &result)?;
    let events = serde_json::to_vec_pretty(&json!({
        "events": result.events,
        "plans": result.plans.iter().map(|p| json!({
            "t": p.t, "trigger": p.trigger, "path": p.path, "duration": p.duration,
        })).collect::<Vec<_>>(),
    }))?;
    files.push(("events.json".into(), events));
    files.push((
        "trajectory.csv".into(),
        trajectory_csv(&result).into_bytes(),
    ));
    let report_s = report_clock.elapsed().as_secs_f64();
    let wall = clock.elapsed().as_secs_f64();
    let sum = summary(&m, &result, wall, report_s);
    let mut sum_text = serde_json::to_vec_pretty(&sum)?;
    sum_text.push(b'\n');
    files.push(("summary.json".into(), sum_text));
    let dir = args.output.unwrap_or_else(|| m.output_dir.clone());
    write_dir(&dir, &files)?;
    if !args.quiet {
        crate::output::print_json(&sum)?;
    }
    if !result.reached {
        return crate::cmd::common::goal_not_reached(format!(
            "{}: {} (outputs in {})",
            path.display(),
            result.reason.as_deref().unwrap_or("not reached"),
            dir.display()
        ));
    }
    Ok(())
}

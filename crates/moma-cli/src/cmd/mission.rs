//! `moma mission [MISSION.toml]`: plan on a map, time the path under the tip-over limits,
//! track it in closed-loop dynamic simulation, re-plan when obstacles appear, reach an
//! end-effector target at the goal, and write the whole output set at once.
//!
//! Without an argument `scenarios/mission.toml` runs (looked up in the current
//! directory, then next to the source tree this binary was built from; that built-in
//! default writes to `mission-output/` in the current directory, never into the source
//! tree). The schema and
//! the outputs are documented in `docs/mission.md`; the page and its figures come from
//! [`crate::report`]. Exit status: 0 reached, 1 input error
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
    /// Mission file (TOML). Default: scenarios/mission.toml in the current directory, else
    /// the one shipped with the source tree (its outputs then go to mission-output/ in the
    /// current directory).
    pub scenario: Option<PathBuf>,
    /// Output directory (overrides the mission's `output.dir`, which is relative to the
    /// mission file; this one is relative to the current directory). The folder and the
    /// report's path are printed on standard error.
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    /// Do not print the summary on standard output.
    #[arg(long)]
    pub quiet: bool,
}

/// The mission file to run, and whether it is the built-in default found next to the
/// source tree (whose outputs then go to the current directory, not into that tree).
fn resolve_scenario(arg: Option<PathBuf>) -> Result<(PathBuf, bool)> {
    if let Some(p) = arg {
        return Ok((p, false));
    }
    let local = PathBuf::from("scenarios/mission.toml");
    if local.is_file() {
        return Ok((local, false));
    }
    let bundled = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/mission.toml");
    if bundled.is_file() {
        return Ok((bundled, true));
    }
    bail!(
        "no mission given and no scenarios/mission.toml found in the current directory or at {}",
        bundled.display()
    )
}

/// Where the outputs go: `--output` (relative to the current directory), else the
/// mission's `output.dir` (relative to the mission file), except for the built-in
/// default run from elsewhere: `mission-output/` in the current directory.
fn output_dir(arg: Option<PathBuf>, m: &Mission, bundled: bool) -> PathBuf {
    match arg {
        Some(d) => d,
        None if bundled => PathBuf::from("mission-output"),
        None => m.output_dir.clone(),
    }
}

/// The summary object (`summary.json`).
fn summary(
    m: &Mission,
    r: &MissionResult,
    wall_total: f64,
    report_s: f64,
    files: &[String],
) -> Value {
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
    let mut doc = moma::mission::summary(m, r);
    doc.insert("footprint".into(), m.footprint.to_json());
    doc.insert("replan_timing".into(), json!(replan_search));
    doc.insert("wall_time_s".into(), json!(wall_total));
    doc.insert(
        "wall_time".into(),
        json!({
            "planning_s": r.wall.planning_s,
            "smoothing_timing_s": r.wall.smoothing_timing_s,
            "simulation_s": r.wall.simulation_s,
            "report_s": report_s,
        }),
    );
    doc.insert(
        "real_time_factor".into(),
        if wall_total > 0.0 {
            json!(r.duration / wall_total)
        } else {
            Value::Null
        },
    );
    doc.insert("files".into(), json!(files));
    Value::Object(doc)
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
    out.push_str(
        "t [s],x [m],y [m],theta [rad],v [m/s],omega [rad/s],v_ref [m/s],omega_ref [rad/s],\
         x_ref [m],y_ref [m],zmp_margin [m],force_angle_min [rad],moment_height_min,\
         clearance [m],tracking_error [m],slip_ratio,ee_x [m],ee_y [m],ee_z [m],energy [J],phase",
    );
    for n in &r.arm_names {
        let _ = write!(out, ",q_{n} [rad]");
    }
    for n in &r.u_names {
        let _ = write!(out, ",{n} [N m]");
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

/// Runs `moma mission`.
pub fn run(args: Args) -> Result<()> {
    let clock = Instant::now();
    let (path, bundled) = resolve_scenario(args.scenario)?;
    // the error keeps its causes (the OS reason a file cannot be read)
    let m = moma::mission::load(&path)?;
    let result = moma::mission::run(&m).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    // everything but the page and the figures, with the summary as of now (the page's
    // summary table shows the wall times up to the report)
    let mut files: Vec<(String, Vec<u8>)> = Vec::new();
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
    // The page shows summary.json as it is written: the report is rendered once to time
    // it and to list its figures, then the page again with the final summary (its own
    // second rendering is the only time summary.json does not count).
    let report_clock = Instant::now();
    let pre = summary(&m, &result, clock.elapsed().as_secs_f64(), 0.0, &[]);
    let mut report = mission_report(&m, &result, &pre)?;
    report
        .check()
        .map_err(|e| anyhow!("{}: the report data is malformed: {e}", path.display()))?;
    let _ = crate::report::render_html(&report);
    let figures = crate::report::render_svgs(&report);
    let report_s = report_clock.elapsed().as_secs_f64();
    let mut names: Vec<String> = [
        "summary.json",
        "trajectory.csv",
        "events.json",
        "report.html",
    ]
    .iter()
    .map(|s| (*s).to_string())
    .collect();
    names.extend(figures.iter().map(|(n, _)| n.clone()));
    let wall = clock.elapsed().as_secs_f64();
    let sum = summary(&m, &result, wall, report_s, &names);
    report.summary = sum.clone();
    files.push((
        "report.html".into(),
        crate::report::render_html(&report).into_bytes(),
    ));
    for (n, svg) in figures {
        files.push((n, svg.into_bytes()));
    }
    let mut sum_text = serde_json::to_vec_pretty(&sum)?;
    sum_text.push(b'\n');
    files.push(("summary.json".into(), sum_text));
    let dir = output_dir(args.output, &m, bundled);
    write_dir(&dir, &files)?;
    if !args.quiet {
        crate::output::print_json(&sum)?;
        eprintln!(
            "wrote {} files to {}; report: {}",
            files.len(),
            dir.display(),
            dir.join("report.html").display()
        );
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

/// The report's data from a run (the interface of `crate::report`).
///
/// The 3-D view draws the robot's URDF shapes (read again here, relative to the mission
/// file as the mission reads it) at the recorded configurations.
fn mission_report(
    m: &Mission,
    r: &MissionResult,
    summary: &Value,
) -> Result<crate::report::MissionReport> {
    use crate::report::{
        MAX_FRAMES, MissionReport, ReportEvent, ReportMap, ReportObstacle, ReportPlan,
        ReportSamples, RobotShapes, scene_shapes,
    };
    let urdf = m
        .path
        .parent()
        .unwrap_or(Path::new("."))
        .join(&m.file.robot.urdf);
    let model = &m.robot.model;
    let view3d = RobotShapes::from_urdf(&urdf, model, &m.package_dirs)
        .and_then(|shapes| {
            // a [task]'s scene at its place on the map
            let scene = m
                .task
                .as_ref()
                .map_or_else(Vec::new, |t| scene_shapes(&t.scene));
            shapes.view(model, &r.samples.t, &r.samples.q, MAX_FRAMES, scene)
        })
        .map_err(|e| anyhow!("{}: the 3-D view: {e}", m.path.display()))?;
    let g = &m.map.grid;
    let cells = g
        .cells
        .iter()
        .map(|&c| match c {
            c if c < 0 => 2,
            c if c >= 100 => 1,
            _ => 0,
        })
        .collect();
    // the lower-left corner of cell (0, 0) in the world (ROS maps; a rotated origin is
    // drawn unrotated, Moving AI cells are centred on integers)
    let origin = match g.kind {
        moma::planning::MapKind::Ros => [g.origin[0], g.origin[1]],
        moma::planning::MapKind::MovingAi => [-0.5, -0.5],
    };
    let f = &m.file;
    let s = &r.samples;
    let col = |k: usize| s.q.iter().map(|q| q[k]).collect::<Vec<f64>>();
    let nu = r.u_names.len();
    Ok(MissionReport {
        title: m.name.clone(),
        map: ReportMap {
            width: g.width,
            height: g.height,
            resolution: g.resolution,
            origin,
            cells,
        },
        footprint_radius: m.footprint.radius,
        start: f.start.pose,
        goal: r.goal_pose,
        end_effector_target: m.goal().and_then(|g| g.end_effector),
        plans: r
            .plans
            .iter()
            .map(|p| ReportPlan {
                t: p.t,
                points: p.path.clone(),
            })
            .collect(),
        obstacles: f
            .obstacles
            .iter()
            .map(|o| ReportObstacle {
                t: o.t,
                center: o.center,
                radius: o.radius,
            })
            .collect(),
        samples: ReportSamples {
            t: s.t.clone(),
            x: col(0),
            y: col(1),
            theta: col(2),
            v: s.v.clone(),
            omega: s.omega.clone(),
            v_ref: s.v_ref.clone(),
            omega_ref: s.omega_ref.clone(),
            zmp_margin: s.zmp_margin.clone(),
            force_angle_min: s.force_angle_min.clone(),
            clearance: s.clearance.iter().map(|c| c.min(1e3)).collect(),
            tracking_error: s.tracking_error.clone(),
            torque_names: r.u_names.clone(),
            torques: (0..nu)
                .map(|j| s.u.iter().map(|u| u[j]).collect())
                .collect(),
            arm_side: s.arm_side.clone(),
        },
        events: r
            .events
            .iter()
            .map(|e| ReportEvent {
                t: e.t,
                kind: e.kind.clone(),
                text: e.text.clone(),
            })
            .collect(),
        summary: summary.clone(),
        view3d: Some(view3d),
    })
}

//! `moma simulate` for a free-floating robot (`robot.kind = "free_floating"`): a URDF as a
//! free flyer in zero gravity, torque-driven (with an optional capture of a target body)
//! or under resolved-rate control through the generalized Jacobian. Writes
//! `trajectory.csv`, `summary.json` and plots of the base attitude, the momentum and the
//! end-effector path. Schema: `docs/space.md`.

use super::simulate_common::{Args, Scenario};
use crate::output::write_all_atomic;
use crate::svg_plots::{Series, line_chart, path_chart};
use anyhow::{Context, Result};
use moma::sim::free_floating;
use moma::sim_config::SpaceRun;
use moma::spatial::{Force, rpy_from_rotation};
use serde::Serialize;
use std::path::Path;
use std::time::Instant;

#[derive(Serialize)]
struct PhaseDrift {
    linear: f64,
    angular: f64,
    com: f64,
}

#[derive(Serialize)]
struct CaptureSummary {
    time: f64,
    momentum_before: [f64; 6],
    momentum_after: [f64; 6],
    max_difference: f64,
    total_mass_after: f64,
}

#[derive(Serialize)]
struct Summary {
    scenario: String,
    robot: String,
    frame: String,
    mode: String,
    duration: f64,
    samples: usize,
    initial_momentum: [f64; 6],
    final_momentum: [f64; 6],
    momentum_drift: Vec<PhaseDrift>,
    final_q: Vec<f64>,
    final_v: Vec<f64>,
    final_frame_position: [f64; 3],
    capture: Option<CaptureSummary>,
    accepted_steps: usize,
    rhs_evaluations: usize,
    wall_time_s: f64,
    files: Vec<String>,
}

/// Runs a free-floating scenario built by `moma::sim_config::space_run` and writes its
/// files.
pub fn run(path: &Path, sc: &Scenario, sr: SpaceRun, args: &Args) -> Result<()> {
    let start = Instant::now();
    let run = free_floating::run(&sr.model, &sr.q0, &sr.v0, &sr.settings)
        .with_context(|| format!("{}: simulation failed", path.display()))?;
    let wall = start.elapsed().as_secs_f64();
    let dir = args.output.clone().unwrap_or_else(|| sc.output.dir.clone());
    let frame = match &sc.robot {
        moma::sim_config::schema::RobotSpec::FreeFloating { frame, .. } => frame.as_str(),
        _ => sr.model.frames[sr.settings.frame.0].name.as_str(),
    };
    let files = render(
        &dir,
        sc,
        path,
        &sr.model.name,
        frame,
        &run,
        wall,
        sc.output.plots,
    )?;
    std::fs::create_dir_all(&dir)
        .with_context(|| format!("{}: cannot create output directory", dir.display()))?;
    write_all_atomic(&files.0)?;
    if !args.quiet {
        crate::output::print_json(&files.1)?;
    }
    Ok(())
}

/// Output files in memory: (path, bytes).
type OutputFiles = Vec<(std::path::PathBuf, Vec<u8>)>;

fn v6(f: &Force) -> [f64; 6] {
    f.to_vector().into()
}

#[allow(clippy::too_many_arguments)]
fn render(
    dir: &Path,
    sc: &Scenario,
    path: &Path,
    robot: &str,
    frame: &str,
    run: &free_floating::FloatingRun,
    wall: f64,
    plots: bool,
) -> Result<(OutputFiles, serde_json::Value)> {
    let (csv, rpy) = trajectory_csv(run);
    let mut files = vec![(dir.join("trajectory.csv"), csv.into_bytes())];
    if plots {
        push_plots(dir, frame, run, &rpy, &mut files);
    }
    let s = &run.samples;
    let last = s.len() - 1;
    let fp = run.frame_positions[last];
    let mode = if sc.space.as_ref().is_some_and(|x| x.control.is_some()) {
        "resolved_rate"
    } else if run.capture.is_some() {
        "torque_capture"
    } else {
        "torque"
    };
    let mut summary = Summary {
        scenario: sc
            .name
            .clone()
            .unwrap_or_else(|| path.display().to_string()),
        robot: robot.to_string(),
        frame: frame.to_string(),
        mode: mode.to_string(),
        duration: sc.duration,
        samples: s.len(),
        initial_momentum: v6(&s[0].momentum),
        final_momentum: v6(&s[last].momentum),
        momentum_drift: run
            .drift
            .iter()
            .map(|d| PhaseDrift {
                linear: d.linear,
                angular: d.angular,
                com: d.com,
            })
            .collect(),
        final_q: s[last].q.as_slice().to_vec(),
        final_v: s[last].v.as_slice().to_vec(),
        final_frame_position: [fp.x, fp.y, fp.z],
        capture: run.capture.as_ref().map(|c| CaptureSummary {
            time: c.time,
            momentum_before: v6(&c.momentum_before),
            momentum_after: v6(&c.momentum_after),
            max_difference: (c.momentum_before.to_vector() - c.momentum_after.to_vector()).amax(),
            total_mass_after: c.model.total_mass(),
        }),
        accepted_steps: run.steps,
        rhs_evaluations: run.rhs_evals,
        wall_time_s: wall,
        files: Vec::new(),
    };
    summary.files = files
        .iter()
        .map(|(p, _)| {
            p.file_name()
                .unwrap_or_default()
                .to_string_lossy()
                .into_owned()
        })
        .chain(std::iter::once("summary.json".to_string()))
        .collect();
    let value = serde_json::to_value(&summary).context("serialising the summary")?;
    let mut json = serde_json::to_string_pretty(&summary).context("serialising the summary")?;
    json.push('\n');
    files.push((dir.join("summary.json"), json.into_bytes()));
    Ok((files, value))
}

/// `trajectory.csv` and the base attitude (roll, pitch, yaw) of every sample.
fn trajectory_csv(run: &free_floating::FloatingRun) -> (String, Vec<[f64; 3]>) {
    let s = &run.samples;
    let nq = s[0].q.len();
    let nv = s[0].v.len();
    let mut csv = String::from("t");
    for i in 0..nq {
        csv.push_str(&format!(",q{i}"));
    }
    for i in 0..nv {
        csv.push_str(&format!(",v{i}"));
    }
    csv.push_str(",P_x,P_y,P_z,L_x,L_y,L_z,com_x,com_y,com_z,roll,pitch,yaw,ee_x,ee_y,ee_z\n");
    let mut rpy = Vec::with_capacity(s.len());
    for (k, x) in s.iter().enumerate() {
        let r = free_floating::base_attitude(&x.q)
            .to_rotation_matrix()
            .into_inner();
        let a = rpy_from_rotation(&r);
        rpy.push(a);
        let p = run.frame_positions[k];
        let row: Vec<String> = std::iter::once(x.t)
            .chain(x.q.iter().copied())
            .chain(x.v.iter().copied())
            .chain(x.momentum.linear.iter().copied())
            .chain(x.momentum.angular.iter().copied())
            .chain(x.com.iter().copied())
            .chain(a.iter().copied())
            .chain(p.iter().copied())
            .map(|v| format!("{v:e}"))
            .collect();
        csv.push_str(&row.join(","));
        csv.push('\n');
    }
    (csv, rpy)
}

/// The attitude, momentum and frame-path plots.
fn push_plots(
    dir: &Path,
    frame: &str,
    run: &free_floating::FloatingRun,
    rpy: &[[f64; 3]],
    files: &mut OutputFiles,
) {
    let s = &run.samples;
    let t: Vec<f64> = s.iter().map(|x| x.t).collect();
    let ser = |name: &'static str, y: Vec<f64>| Series { name, x: &t, y };
    let att = vec![
        ser("roll", rpy.iter().map(|a| a[0]).collect()),
        ser("pitch", rpy.iter().map(|a| a[1]).collect()),
        ser("yaw", rpy.iter().map(|a| a[2]).collect()),
    ];
    files.push((
        dir.join("base_attitude.svg"),
        line_chart(
            "Base attitude (roll, pitch, yaw)",
            "t (s)",
            "angle (rad)",
            &att,
        )
        .into_bytes(),
    ));
    let h0 = s[0].momentum;
    let mom = vec![
        ser(
            "|P − P₀| (N·s)",
            s.iter()
                .map(|x| (x.momentum.linear - h0.linear).norm())
                .collect(),
        ),
        ser(
            "|L_c − L_c₀| (N·m·s)",
            s.iter()
                .map(|x| (x.momentum.angular - h0.angular).norm())
                .collect(),
        ),
    ];
    files.push((
        dir.join("momentum_drift.svg"),
        line_chart("Momentum drift", "t (s)", "drift", &mom).into_bytes(),
    ));
    let comp = vec![
        ser("P_x", s.iter().map(|x| x.momentum.linear.x).collect()),
        ser("P_y", s.iter().map(|x| x.momentum.linear.y).collect()),
        ser("P_z", s.iter().map(|x| x.momentum.linear.z).collect()),
        ser("L_x", s.iter().map(|x| x.momentum.angular.x).collect()),
        ser("L_y", s.iter().map(|x| x.momentum.angular.y).collect()),
        ser("L_z", s.iter().map(|x| x.momentum.angular.z).collect()),
    ];
    files.push((
        dir.join("momentum.svg"),
        line_chart(
            "Momentum (world; angular about the CoM)",
            "t (s)",
            "N·s, N·m·s",
            &comp,
        )
        .into_bytes(),
    ));
    let ex: Vec<f64> = run.frame_positions.iter().map(|p| p.x).collect();
    let ey: Vec<f64> = run.frame_positions.iter().map(|p| p.y).collect();
    files.push((
        dir.join("ee_path.svg"),
        path_chart(&format!("{frame} path (world x–y)"), &ex, &ey).into_bytes(),
    ));
}

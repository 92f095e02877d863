//! `moma simulate` with `plant = "contact"`: the scenario's inputs or law on the contact
//! plant; writes the trajectory with the contact forces, a summary with the lift-off and
//! slip events, and SVG plots.

use std::path::Path;
use std::time::Instant;

use anyhow::{Context, Result};
use moma::contact::ContactParams;
use moma::sim::contact_run::{ContactEvent, ContactResult, ContactTotals, SETTLE_TIME};
use serde::Serialize;

use super::simulate_common::{Args, Scenario, progress_bar, series};
use crate::output::write_dir;
use crate::svg_plots::{Series, line_chart, path_chart};

/// The summary written as `summary.json`.
#[derive(Debug, Serialize)]
struct Summary {
    scenario: String,
    plant: &'static str,
    robot: String,
    contact: ContactParams,
    duration: f64,
    samples: usize,
    contact_steps: usize,
    control_evaluations: usize,
    steps_per_control: usize,
    q_names: Vec<String>,
    v_names: Vec<String>,
    final_q: Vec<f64>,
    final_v: Vec<f64>,
    events_after_s: f64,
    first_lift_off: Option<ContactEvent>,
    first_slip: Option<ContactEvent>,
    contacts: Vec<ContactTotals>,
    max_tilt_rad: f64,
    wall_time_s: f64,
    steps_per_second: f64,
    files: Vec<String>,
}

/// The trajectory as CSV: `t [s]` then [`ContactResult::column_names`].
fn csv(res: &ContactResult) -> String {
    let mut s = String::from("t [s]");
    for c in res.column_names() {
        s.push(',');
        s.push_str(&c);
    }
    s.push('\n');
    for (t, row) in res.times.iter().zip(&res.rows) {
        s.push_str(&format!("{t}"));
        for x in row {
            s.push_str(&format!(",{x}"));
        }
        s.push('\n');
    }
    s
}

/// Path, normal forces and slip speeds.
fn plots(res: &ContactResult, files: &mut Vec<(String, Vec<u8>)>) {
    let t = &res.times;
    let col = |j: usize| res.rows.iter().map(|r| r[j]).collect::<Vec<f64>>();
    files.push((
        "path.svg".into(),
        path_chart("Platform path (contact plant)", &col(0), &col(1)).into_bytes(),
    ));
    let first = res.q_names.len() + res.v_names.len() + res.u_names.len() + 5;
    let normal: Vec<Series> = res
        .contact_names
        .iter()
        .enumerate()
        .map(|(k, n)| series(t, n, col(first + 4 * k)))
        .collect();
    files.push((
        "normal_forces.svg".into(),
        line_chart("Contact normal forces", "t [s]", "N [N]", &normal).into_bytes(),
    ));
    let slip: Vec<Series> = res
        .contact_names
        .iter()
        .enumerate()
        .map(|(k, n)| series(t, n, col(first + 4 * k + 1)))
        .collect();
    files.push((
        "slip.svg".into(),
        line_chart(
            "Slip speed of each contact point",
            "t [s]",
            "|v_t| [m/s]",
            &slip,
        )
        .into_bytes(),
    ));
    let nq = res.q_names.len();
    let tilt = [
        series(
            t,
            "roll",
            col(nq + res.v_names.len() + res.u_names.len() + 1),
        ),
        series(
            t,
            "pitch",
            col(nq + res.v_names.len() + res.u_names.len() + 2),
        ),
    ];
    files.push((
        "tilt.svg".into(),
        line_chart("Base roll and pitch", "t [s]", "angle [rad]", &tilt).into_bytes(),
    ));
}

/// Runs a `plant = "contact"` scenario and writes its files.
pub fn run(path: &Path, sc: &Scenario, args: &Args) -> Result<()> {
    let mut run = moma::sim_config::contact::prepare_contact(sc, path)?;
    let dir = args.output.clone().unwrap_or_else(|| sc.output.dir.clone());
    let bar = progress_bar(sc.duration);
    let start = Instant::now();
    let res = run.run(&mut |t| {
        if let Some(pb) = &bar {
            pb.set_position((t * 1000.0).round() as u64);
        }
    });
    if let Some(pb) = &bar {
        pb.finish_and_clear();
    }
    let res = res.with_context(|| format!("{}: simulation failed", path.display()))?;
    let wall = start.elapsed().as_secs_f64();
    let last = res.rows.len() - 1;
    let (nq, nv) = (res.q_names.len(), res.v_names.len());
    let mut summary = Summary {
        scenario: sc
            .name
            .clone()
            .unwrap_or_else(|| path.display().to_string()),
        plant: "contact",
        robot: match &sc.robot {
            moma::sim_config::schema::RobotSpec::Urdf { urdf, .. } => {
                format!("URDF {} on a free-flyer root", urdf.display())
            }
            _ => String::new(),
        },
        contact: run.plant.params,
        duration: sc.duration,
        samples: res.rows.len(),
        contact_steps: res.steps,
        control_evaluations: res.control_evaluations,
        steps_per_control: res.steps_per_control,
        q_names: res.q_names.clone(),
        v_names: res.v_names.clone(),
        final_q: res.rows[last][..nq].to_vec(),
        final_v: res.rows[last][nq..nq + nv].to_vec(),
        events_after_s: SETTLE_TIME,
        first_lift_off: res.first_lift_off.clone(),
        first_slip: res.first_slip.clone(),
        contacts: res.totals.clone(),
        max_tilt_rad: res.max_tilt,
        wall_time_s: wall,
        steps_per_second: if wall > 0.0 {
            res.steps as f64 / wall
        } else {
            0.0
        },
        files: Vec::new(),
    };
    let mut files = vec![("trajectory.csv".to_string(), csv(&res).into_bytes())];
    if sc.output.plots {
        plots(&res, &mut files);
    }
    super::simulate_common::push_summary(&mut files, &mut summary, |s, names| s.files = names)?;
    write_dir(&dir, &files)?;
    if !args.quiet {
        crate::output::print_json(&summary)?;
    }
    Ok(())
}

//! What the three runs of `moma simulate` (open loop in `simulate`, closed loop in
//! `simulate_control`, free-floating in `simulate_space`) share: the command's arguments,
//! the scenario type, the progress bar and the plots of a recorded wheeled or fixed-base
//! run.

use std::io::IsTerminal;
use std::path::PathBuf;

use anyhow::{Context, Result};
use moma::sim::recorder::Recorder;
use serde::Serialize;

use crate::svg_plots::{Series, line_chart, path_chart};

/// Arguments of `moma simulate`.
#[derive(clap::Args)]
pub struct Args {
    /// Scenario file (TOML). Default: the bundled scenarios/default.toml.
    pub scenario: Option<PathBuf>,
    /// Output directory (overrides the scenario's `output.dir`).
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    /// Do not print the summary on standard output.
    #[arg(long)]
    pub quiet: bool,
}

pub use moma::sim_config::schema::RobotSpec;

/// A scenario file: the library's schema with this command's `[space]`, `[stability]`,
/// `[controller]` and `[reference]` tables ([`moma::sim_config::Scenario`]).
pub use moma::sim_config::Scenario;

/// One named curve over the times `t`.
pub(super) fn series<'a>(t: &'a [f64], name: &'a str, y: Vec<f64>) -> Series<'a> {
    Series { name, x: t, y }
}

/// The column `row(i)` of every recorded sample.
fn column(rec: &Recorder, row: &dyn Fn(usize) -> f64) -> Vec<f64> {
    (0..rec.len()).map(row).collect()
}

/// A fixed-base arm: every joint coordinate and the input torques against time.
pub(super) fn arm_plots(rec: &Recorder, files: &mut Vec<(String, Vec<u8>)>) {
    let t = &rec.times;
    let col = |row: &dyn Fn(usize) -> f64| column(rec, row);
    let joints: Vec<Series> = rec
        .q_names
        .iter()
        .enumerate()
        .map(|(k, n)| series(t, n, col(&|i| rec.q_row(i)[k])))
        .collect();
    files.push((
        "joints.svg".to_string(),
        line_chart(
            "Joints",
            "t [s]",
            "angle [rad] (prismatic joints: [m])",
            &joints,
        )
        .into_bytes(),
    ));
    let inputs: Vec<Series> = rec
        .u_names
        .iter()
        .enumerate()
        .map(|(k, n)| series(t, n, col(&|i| rec.u_row(i)[k])))
        .collect();
    files.push((
        "inputs.svg".to_string(),
        line_chart(
            "Inputs (joint torques)",
            "t [s]",
            "torque [N m] (prismatic joints: force [N])",
            &inputs,
        )
        .into_bytes(),
    ));
}

/// Platform path, heading and arm joints, wheel angles (when tracked) and inputs.
pub(super) fn motion_plots(wheels: &[String], rec: &Recorder, files: &mut Vec<(String, Vec<u8>)>) {
    let t = &rec.times;
    let col = |row: &dyn Fn(usize) -> f64| column(rec, row);
    let x = col(&|i| rec.q_row(i)[0]);
    let y = col(&|i| rec.q_row(i)[1]);
    files.push((
        "path.svg".to_string(),
        path_chart("Platform path", &x, &y).into_bytes(),
    ));
    let angle_series = |keep: &dyn Fn(&str) -> bool| -> Vec<Series> {
        rec.q_names
            .iter()
            .enumerate()
            .skip(2)
            .filter(|(_, n)| keep(n))
            .map(|(k, n)| series(t, n, col(&|i| rec.q_row(i)[k])))
            .collect()
    };
    let is_wheel = |n: &str| wheels.iter().any(|w| w == n);
    files.push((
        "joints.svg".to_string(),
        line_chart(
            "Heading and arm joints",
            "t [s]",
            if rec.units[0].iter().skip(3).any(|u| *u == "m") {
                "angle [rad] (prismatic joints: [m])"
            } else {
                "angle [rad]"
            },
            &angle_series(&|n| !is_wheel(n)),
        )
        .into_bytes(),
    ));
    if !wheels.is_empty() {
        files.push((
            "wheels.svg".to_string(),
            line_chart(
                "Wheel angles",
                "t [s]",
                "angle [rad]",
                &angle_series(&is_wheel),
            )
            .into_bytes(),
        ));
    }
    let inputs: Vec<Series> = rec
        .u_names
        .iter()
        .enumerate()
        .map(|(k, n)| series(t, n, col(&|i| rec.u_row(i)[k])))
        .collect();
    files.push((
        "inputs.svg".to_string(),
        line_chart(
            "Inputs (wheel and joint torques)",
            "t [s]",
            if rec.units[2].iter().any(|u| *u == "N") {
                "torque [N m] (prismatic joints: force [N])"
            } else {
                "torque [N m]"
            },
            &inputs,
        )
        .into_bytes(),
    ));
}

/// Energy balance and its error, the constraint multipliers and the residual.
pub(super) fn balance_plots(rec: &Recorder, files: &mut Vec<(String, Vec<u8>)>) {
    let t = &rec.times;
    let col = |row: &dyn Fn(usize) -> f64| column(rec, row);
    let energy = vec![
        series(t, "kinetic T", rec.kinetic.clone()),
        series(t, "potential V", rec.potential.clone()),
        series(t, "input work W", rec.work.clone()),
        series(
            t,
            "T + V − W",
            col(&|i| rec.kinetic[i] + rec.potential[i] - rec.work[i]),
        ),
    ];
    files.push((
        "energy.svg".to_string(),
        line_chart("Energy balance", "t [s]", "energy [J]", &energy).into_bytes(),
    ));
    let drift = vec![series(
        t,
        "(T+V) − (T₀+V₀) − W",
        col(&|i| rec.energy_error(i)),
    )];
    files.push((
        "energy_error.svg".to_string(),
        line_chart("Energy balance error", "t [s]", "energy [J]", &drift).into_bytes(),
    ));
    if !rec.lambda_names.is_empty() {
        let k = rec.lambda_names.len();
        const LABELS: [&str; 3] = ["λ0 no side slip", "λ1 left rolling", "λ2 right rolling"];
        let forces: Vec<Series> = rec
            .lambda_names
            .iter()
            .enumerate()
            .map(|(j, name)| {
                let label = LABELS.get(j).copied().unwrap_or(name.as_str());
                series(t, label, col(&|i| rec.lambda[i * k + j]))
            })
            .collect();
        let title = if k == 3 {
            "Constraint multipliers: λ0 no side slip (−λ0 = lateral ground force on the axle),\nλ1, λ2 rolling of the left and right wheel"
        } else {
            "Multiplier λ0 of the no-side-slip constraint (−λ0 = lateral ground force on the axle)"
        };
        files.push((
            "multipliers.svg".to_string(),
            line_chart(title, "t [s]", "λ [N]", &forces).into_bytes(),
        ));
    }
    let res = vec![series(
        t,
        "log10 |C q̇|",
        col(&|i| rec.residual[i].max(1e-20).log10()),
    )];
    files.push((
        "residual.svg".to_string(),
        line_chart("Constraint residual", "t [s]", "log10 (|C q̇| [m/s])", &res).into_bytes(),
    ));
}

/// A progress bar on standard error when it is a terminal.
pub(super) fn progress_bar(duration: f64) -> Option<indicatif::ProgressBar> {
    if std::io::stderr().is_terminal() {
        let pb = indicatif::ProgressBar::new((duration * 1000.0).round() as u64);
        pb.set_style(
            indicatif::ProgressStyle::with_template(
                "{spinner} simulating [{bar:40}] {pos}/{len} ms  {elapsed_precise}",
            )
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
            .progress_chars("=> "),
        );
        Some(pb)
    } else {
        None
    }
}

/// Ends a run's output: `set_files` receives the name of every file in `files` and of
/// `summary.json` (so the summary lists itself), then the summary, pretty JSON, is appended
/// as `summary.json`.
pub fn push_summary<S: Serialize>(
    files: &mut Vec<(String, Vec<u8>)>,
    summary: &mut S,
    set_files: impl FnOnce(&mut S, Vec<String>),
) -> Result<()> {
    let names = files
        .iter()
        .map(|(name, _)| name.clone())
        .chain(std::iter::once("summary.json".to_string()))
        .collect();
    set_files(summary, names);
    let mut json = serde_json::to_string_pretty(summary).context("serialising the summary")?;
    json.push('\n');
    files.push(("summary.json".to_string(), json.into_bytes()));
    Ok(())
}

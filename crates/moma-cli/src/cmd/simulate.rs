//! `moma simulate [SCENARIO.toml]`: run a constrained (wheeled) simulation in reduced
//! coordinates and write a CSV trajectory, a JSON summary and SVG plots.
//!
//! Without an argument the bundled `scenarios/default.toml` runs (looked up in the
//! current directory, then next to the source tree this binary was built from). The
//! scenario schema is documented in `docs/simulate.md`.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result, anyhow, bail};
use moma::closed_form::ChapterModel;
use moma::sim::chapter_models::chapter_system;
use moma::sim::recorder::Recorder;
pub use moma::sim::scenario::{CasterSpec, DriveSpec, RobotSpec};
use moma::sim::scenario::{InputProfile, IntegratorSettings};
use moma::sim::wheeled::{ReducedSystem, SimulationOptions, SimulationResult, simulate_observed};
use serde::Serialize;

use crate::output::write_dir;
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

/// A scenario file: the library's schema ([`moma::sim::scenario::Scenario`]) with this
/// command's `[space]`, `[stability]`, `[controller]` and `[reference]` tables.
pub type Scenario = moma::sim::scenario::Scenario<
    super::simulate_space::SpaceSpec,
    super::simulate_stability::StabilitySpec,
    super::simulate_control::ControllerSpec,
    super::simulate_control::ReferenceSpec,
>;

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
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read scenario file", path.display()))?;
    Ok(moma::sim::scenario::parse_scenario(&text, path)?)
}

pub(super) fn ensure_finite(field: &str, xs: &[f64]) -> Result<()> {
    if let Some(i) = xs.iter().position(|x| !x.is_finite()) {
        bail!("{field}[{i}] is not a finite number");
    }
    Ok(())
}

/// Builds the robot of a scenario; `base_dir` resolves relative URDF paths.
pub(super) fn build_robot(
    spec: &RobotSpec,
    gravity: Option<f64>,
    base_dir: &Path,
) -> Result<(Box<dyn ReducedSystem>, String)> {
    match spec {
        RobotSpec::Chapter { model, params } => {
            for (k, v) in params {
                match v {
                    toml::Value::Float(x) if !x.is_finite() => {
                        bail!("robot.params.{k} is not a finite number ({x})")
                    }
                    toml::Value::Float(_) | toml::Value::Integer(_) => {}
                    other => bail!(
                        "robot.params.{k} must be a number, got {}",
                        other.type_str()
                    ),
                }
            }
            let is_m5 = matches!(
                ChapterModel::from_name(model),
                Ok(ChapterModel::M5MobileManipulator)
            );
            if let Some(g) = gravity
                && !is_m5
            {
                bail!(
                    "gravity = {g}: chapter model {model} has no gravity term (it moves in \
                     the horizontal plane or in free space); remove the top-level `gravity` \
                     (only m5 uses it)"
                );
            }
            let json = chapter_params_json(params, gravity, is_m5)?;
            let sys = chapter_system(model, &json).context("robot")?;
            Ok((sys, format!("chapter model {model}")))
        }
        RobotSpec::Urdf {
            urdf,
            drive,
            wheel_joints,
            casters,
        } => {
            let path = base_dir.join(urdf);
            let sys = build_urdf_robot(&path, drive, wheel_joints.clone(), casters, gravity)?;
            Ok((sys, format!("URDF {}", urdf.display())))
        }
        RobotSpec::FixedBase { urdf } => {
            let model = fixed_base_model(&base_dir.join(urdf), gravity)?;
            let sys = moma::sim::fixed_base::FixedBaseSystem::new(model)
                .with_context(|| format!("{}", urdf.display()))?;
            Ok((
                Box::new(sys),
                format!("URDF {} (fixed base)", urdf.display()),
            ))
        }
        RobotSpec::FreeFloating { .. } => {
            bail!("a free-floating robot is run by the space simulation")
        }
    }
}

/// A fixed-base URDF model under gravity `g` (default 9.81) along −z.
pub(super) fn fixed_base_model(
    path: &Path,
    gravity: Option<f64>,
) -> Result<moma::multibody::Model> {
    let mut model = moma::io::urdf::model_from_urdf_file(path, moma::multibody::RootJoint::Fixed)?;
    let g = gravity.unwrap_or(9.81);
    if !g.is_finite() {
        bail!("gravity is not a finite number");
    }
    model.gravity = nalgebra::Vector3::new(0.0, 0.0, -g);
    Ok(model)
}

/// The chapter parameters as JSON, with the top-level gravity moved into `g` for m5.
pub(super) fn chapter_params_json(
    params: &toml::Table,
    gravity: Option<f64>,
    is_m5: bool,
) -> Result<serde_json::Value> {
    let mut json = serde_json::to_value(params).context("robot.params")?;
    if let (Some(g), true) = (gravity, is_m5)
        && let Some(obj) = json.as_object_mut()
    {
        if obj.contains_key("g") {
            bail!("gravity is given twice: top-level `gravity` and robot.params.g");
        }
        obj.insert("g".into(), serde_json::json!(g));
    }
    Ok(json)
}

fn build_urdf_robot(
    path: &Path,
    drive: &DriveSpec,
    wheel_joints: Option<[String; 2]>,
    casters: &[CasterSpec],
    gravity: Option<f64>,
) -> Result<Box<dyn ReducedSystem>> {
    let wm = build_wheeled_model(path, drive, wheel_joints, casters, gravity)?;
    Ok(Box::new(moma::sim::wheeled_system::WheeledSystem::new(wm)))
}

/// The wheeled model of a URDF robot on a differential drive (also read by the stability
/// monitor).
pub(super) fn build_wheeled_model(
    path: &Path,
    drive: &DriveSpec,
    wheel_joints: Option<[String; 2]>,
    casters: &[CasterSpec],
    gravity: Option<f64>,
) -> Result<moma::mobile::WheeledModel> {
    use moma::mobile::{Caster, DiffDrive, WheeledBase, WheeledModel};
    let dd = DiffDrive::new(drive.r_w, drive.b, drive.d).context("robot.drive")?;
    for c in casters {
        ensure_finite(&format!("robot.casters '{}' position", c.name), &c.position)?;
    }
    let base = WheeledBase {
        drive: dd,
        casters: casters
            .iter()
            .map(|c| Caster {
                name: c.name.clone(),
                position: c.position,
            })
            .collect(),
        wheel_joints,
    };
    let mut model = moma::io::urdf::model_from_urdf_file(path, moma::multibody::RootJoint::Planar)?;
    let g = gravity.unwrap_or(9.81);
    if !g.is_finite() {
        bail!("gravity is not a finite number");
    }
    model.gravity = nalgebra::Vector3::new(0.0, 0.0, -g);
    WheeledModel::new(model, base).with_context(|| format!("{}", path.display()))
}

pub(super) fn series<'a>(t: &'a [f64], name: &'a str, y: Vec<f64>) -> Series<'a> {
    Series { name, x: t, y }
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
    summary.files = files
        .iter()
        .map(|(name, _)| name.clone())
        .chain(std::iter::once("summary.json".to_string()))
        .collect();
    let mut json = serde_json::to_string_pretty(summary).context("serialising the summary")?;
    json.push('\n');
    files.push(("summary.json".to_string(), json.into_bytes()));
    Ok(files)
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

/// The initial configuration, reduced velocity and input profile of a scenario, checked
/// against the system's sizes (errors name the field and the expected channels).
pub(super) fn initial_state(
    sc: &Scenario,
    system: &dyn ReducedSystem,
    ctx: &dyn Fn(&str) -> String,
) -> Result<(Vec<f64>, Vec<f64>, InputProfile)> {
    sc.initial_state(system, Path::new(""))
        .map_err(|e| match e {
            moma::Error::Parse { message, .. } => anyhow!("{}", ctx(&message)),
            e => e.into(),
        })
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

/// Runs `moma simulate`.
pub fn run(args: Args) -> Result<()> {
    let path = resolve_scenario(args.scenario.clone())?;
    let sc = load_scenario(&path)?;
    let ctx = |what: &str| format!("{}: {what}", path.display());
    sc.check_header(&path)?;
    let base_dir = path.parent().unwrap_or(Path::new("."));
    if sc.controller.is_some() || sc.reference.is_some() {
        if sc.stability.as_ref().is_some_and(|s| s.stop_at_tip) {
            bail!(
                "{}",
                ctx(
                    "stability.stop_at_tip is not available in closed-loop runs (their samples are evaluated after the run): remove it"
                )
            );
        }
        if sc.stability.is_some() && !matches!(sc.robot, RobotSpec::Urdf { .. }) {
            bail!(
                "{}",
                ctx("[stability] needs a URDF robot on a wheeled base (robot.kind = \"urdf\")")
            );
        }
        return super::simulate_control::run(&path, &sc, base_dir, &args);
    }
    if let RobotSpec::FreeFloating { urdf, frame } = &sc.robot {
        if sc.stability.is_some() {
            bail!(
                "{}",
                ctx("[stability] needs a URDF robot on a wheeled base (robot.kind = \"urdf\")")
            );
        }
        return super::simulate_space::run(&path, &sc, base_dir, urdf, frame, &args);
    }
    if sc.space.is_some() {
        bail!(
            "{}",
            ctx("[space] is only for robot.kind = \"free_floating\"")
        );
    }
    let (mut system, robot_name) =
        build_robot(&sc.robot, sc.gravity, base_dir).with_context(|| ctx("robot"))?;
    let mut monitor = match (&sc.stability, &sc.robot) {
        (None, _) => None,
        (
            Some(spec),
            RobotSpec::Urdf {
                urdf,
                drive,
                wheel_joints,
                casters,
            },
        ) => {
            let wm = build_wheeled_model(
                &base_dir.join(urdf),
                drive,
                wheel_joints.clone(),
                casters,
                sc.gravity,
            )
            .with_context(|| ctx("robot"))?;
            Some(super::simulate_stability::monitor(spec, &wm).with_context(|| ctx("stability"))?)
        }
        (Some(_), _) => bail!(
            "{}",
            ctx("[stability] needs a URDF robot on a wheeled base (robot.kind = \"urdf\")")
        ),
    };
    let (q0, v0, input) = initial_state(&sc, system.as_ref(), &ctx)?;
    sc.integrator
        .validate()
        .with_context(|| ctx("integrator"))?;
    let options = SimulationOptions {
        duration: sc.duration,
        integrator: sc.integrator,
        record_interval: sc.output.record_interval,
        limits: sc.limits.unwrap_or_default(),
    };
    let dir = args.output.clone().unwrap_or_else(|| sc.output.dir.clone());
    let bar = progress_bar(sc.duration);
    let start = Instant::now();
    let observer = monitor
        .as_mut()
        .map(|m| m as &mut dyn moma::sim::wheeled::SampleObserver);
    let result = simulate_observed(
        system.as_mut(),
        &input,
        &q0,
        &v0,
        &options,
        &mut |t| {
            if let Some(pb) = &bar {
                pb.set_position((t * 1000.0).round() as u64);
            }
        },
        observer,
    );
    if let Some(pb) = &bar {
        pb.finish_and_clear();
    }
    let result = result.with_context(|| ctx("simulation failed"))?;
    let wall = start.elapsed().as_secs_f64();
    let rec = &result.recorder;
    let last = rec.len() - 1;
    let steps = result.stats.accepted;
    let mut summary = Summary {
        scenario: sc
            .name
            .clone()
            .unwrap_or_else(|| path.display().to_string()),
        robot: robot_name,
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
    };
    if let (Some(spec), Some(mon)) = (&sc.stability, &monitor) {
        summary.stability = Some(super::simulate_stability::summary(
            spec,
            mon,
            result.stopped_at,
        ));
    }
    let wheels = match &sc.robot {
        RobotSpec::Urdf {
            wheel_joints: Some(w),
            ..
        } => w.to_vec(),
        _ => Vec::new(),
    };
    let fixed = matches!(sc.robot, RobotSpec::FixedBase { .. });
    let files = render(
        fixed,
        &wheels,
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

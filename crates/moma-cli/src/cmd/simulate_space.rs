//! `moma simulate` for a free-floating robot (`robot.kind = "free_floating"`): a URDF as a
//! free flyer in zero gravity, torque-driven (with an optional capture of a target body)
//! or under resolved-rate control through the generalized Jacobian. Writes
//! `trajectory.csv`, `summary.json` and plots of the base attitude, the momentum and the
//! end-effector path. Schema: `docs/space.md`.

use super::simulate::{Args, Scenario};
use crate::output::write_all_atomic;
use crate::svg_plots::{Series, line_chart, path_chart};
use anyhow::{Context, Result, bail};
use moma::multibody::{Data, RootJoint};
use moma::sim::free_floating::{
    self, CaptureEvent, FloatingSettings, ResolvedRateControl, TargetBody,
};
use moma::space::{self, SpaceData};
use moma::spatial::{Force, rpy_from_rotation};
use nalgebra::{DVector, Matrix3, Vector3};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

/// The `[space]` table of a free-floating scenario.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpaceSpec {
    /// Initial momentum `{ linear = [3], angular_about_com = [3] }` (world; default zero).
    #[serde(default)]
    pub momentum: Option<MomentumSpec>,
    /// Viscous joint damping (N·m·s/rad).
    #[serde(default)]
    pub joint_damping: f64,
    /// Resolved-rate control of the frame position.
    #[serde(default)]
    pub control: Option<ControlSpec>,
    /// Capture of a target body.
    #[serde(default)]
    pub capture: Option<CaptureSpec>,
}

/// Initial momentum.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MomentumSpec {
    /// Linear momentum (N·s).
    pub linear: [f64; 3],
    /// Angular momentum about the system CoM (N·m·s).
    pub angular_about_com: [f64; 3],
}

/// Resolved-rate control settings.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControlSpec {
    /// Goal of the frame position (world, m).
    pub target: [f64; 3],
    /// Gain (1/s).
    pub gain: f64,
    /// Damped least squares λ.
    #[serde(default)]
    pub damping: f64,
    /// Cancel the momentum drift with the measured attitude (5.145).
    #[serde(default)]
    pub drift_compensation: bool,
    /// Reaction-null-space term (redundant arms).
    #[serde(default)]
    pub reaction_null_space: bool,
}

/// A target captured at the frame.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CaptureSpec {
    /// Capture time (s).
    pub time: f64,
    /// Mass (kg).
    pub mass: f64,
    /// CoM in the grasp frame (m).
    pub com_in_frame: [f64; 3],
    /// Principal moments about its CoM, grasp-frame axes (kg·m²).
    pub inertia_diagonal: [f64; 3],
    /// CoM velocity before capture (world, m/s).
    pub linear_velocity: [f64; 3],
    /// Angular velocity before capture (world, rad/s).
    pub angular_velocity: [f64; 3],
}

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

fn finite(field: &str, x: &[f64]) -> Result<()> {
    if let Some(i) = x.iter().position(|v| !v.is_finite()) {
        bail!("{field}[{i}] is not a finite number");
    }
    Ok(())
}

/// Runs a free-floating scenario.
pub fn run(
    path: &Path,
    sc: &Scenario,
    base_dir: &Path,
    urdf: &Path,
    frame: &str,
    args: &Args,
) -> Result<()> {
    let ctx = |what: &str| format!("{}: {what}", path.display());
    if sc.gravity.is_some_and(|g| g != 0.0) {
        bail!(
            "{}",
            ctx("gravity: a free-floating robot is simulated in zero gravity")
        );
    }
    let urdf_path = base_dir.join(urdf);
    let mut model = moma::io::urdf::model_from_urdf_file(&urdf_path, RootJoint::FreeFlyer)
        .with_context(|| ctx("robot.urdf"))?;
    model.gravity = Vector3::zeros();
    let fid = model.frame_id(frame).with_context(|| ctx("robot.frame"))?;
    let spec = sc.space.as_ref();
    let n = model.nv - 6;
    let q0 = match &sc.initial.q {
        Some(q) => q.clone(),
        None => moma::kinematics::neutral(&model).as_slice().to_vec(),
    };
    let qd0 = sc.initial.v.clone().unwrap_or_else(|| vec![0.0; n]);
    moma::kinematics::check_state(&model, &ctx("initial"), Some(&q0), None, None, None)?;
    if qd0.len() != n {
        bail!(
            "{}",
            ctx(&format!(
                "initial.v: expected the {n} joint rates (nv − 6), got {}",
                qd0.len()
            ))
        );
    }
    finite(&ctx("initial.v"), &qd0)?;
    let h0 = match spec.and_then(|s| s.momentum.as_ref()) {
        Some(m) => {
            finite(&ctx("space.momentum.linear"), &m.linear)?;
            finite(
                &ctx("space.momentum.angular_about_com"),
                &m.angular_about_com,
            )?;
            Force::new(Vector3::from(m.linear), Vector3::from(m.angular_about_com))
        }
        None => Force::zero(),
    };
    let q0 = DVector::from_vec(q0);
    let mut data = Data::new(&model);
    let mut sd = SpaceData::new(&model).with_context(|| ctx("robot"))?;
    space::base_velocity(&model, &mut data, &mut sd, &q0, &qd0, &h0)
        .with_context(|| ctx("initial state"))?;
    let v0 = sd.v.clone();
    let control = spec
        .and_then(|s| s.control.as_ref())
        .map(|c| ResolvedRateControl {
            target: Vector3::from(c.target),
            gain: c.gain,
            damping: c.damping,
            drift_compensation: c.drift_compensation,
            reaction_null_space: c.reaction_null_space,
        });
    if let Some(c) = spec.and_then(|s| s.control.as_ref()) {
        finite(&ctx("space.control.target"), &c.target)?;
    }
    let capture = match spec.and_then(|s| s.capture.as_ref()) {
        Some(c) => {
            for (name, x) in [
                ("com_in_frame", &c.com_in_frame),
                ("inertia_diagonal", &c.inertia_diagonal),
                ("linear_velocity", &c.linear_velocity),
                ("angular_velocity", &c.angular_velocity),
            ] {
                finite(&ctx(&format!("space.capture.{name}")), x)?;
            }
            if c.inertia_diagonal.iter().any(|&i| i < 0.0) {
                bail!(
                    "{}",
                    ctx("space.capture.inertia_diagonal must not be negative")
                );
            }
            Some(CaptureEvent {
                time: c.time,
                target: TargetBody {
                    mass: c.mass,
                    com_in_frame: Vector3::from(c.com_in_frame),
                    inertia_com: Matrix3::from_diagonal(&Vector3::from(c.inertia_diagonal)),
                    linear_velocity: Vector3::from(c.linear_velocity),
                    angular_velocity: Vector3::from(c.angular_velocity),
                },
            })
        }
        None => None,
    };
    if control.is_some() && sc.inputs.is_some() {
        bail!(
            "{}",
            ctx("inputs: a controlled run commands joint rates; torques are not used")
        );
    }
    let settings = FloatingSettings {
        frame: fid,
        duration: sc.duration,
        record_interval: sc.output.record_interval,
        integrator: sc.integrator,
        torque: sc.inputs.clone().unwrap_or_default(),
        joint_damping: spec.map_or(0.0, |s| s.joint_damping),
        control,
        capture,
    };
    let start = Instant::now();
    let run = free_floating::run(&model, &q0, &v0, &settings)
        .with_context(|| ctx("simulation failed"))?;
    let wall = start.elapsed().as_secs_f64();
    let dir = args.output.clone().unwrap_or_else(|| sc.output.dir.clone());
    let files = render(
        &dir,
        sc,
        path,
        &model.name,
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
    let mut files = vec![(dir.join("trajectory.csv"), csv.into_bytes())];
    if plots {
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

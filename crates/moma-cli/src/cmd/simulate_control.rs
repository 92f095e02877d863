//! `moma simulate` in closed loop: a scenario with a `[controller]` table (the law and its
//! gains) and a `[reference]` table (what it tracks). The unicycle laws and regulated pure
//! pursuit drive a wheeled URDF robot through an inner computed-torque loop (their
//! reference may be a path planned on a map); `coordinated` coordinates the platform
//! with two arm joints so the end effector tracks its reference; `osc` drives
//! an end-effector point of a wheeled URDF robot through the reduced model; `pd_plus`,
//! `computed_torque` and the `decoupled_*` laws run on the chapter's model m5. Writes the
//! open-loop files plus `control.csv`, `tracking_error.svg` and `lyapunov.svg`, and a
//! summary with the Lyapunov monitor and the saturation report. Schema:
//! `docs/simulate.md`.

use super::simulate::{
    Args, RobotSpec, Scenario, arm_plots, balance_plots, build_wheeled_model, chapter_params_json,
    fixed_base_model, initial_state, motion_plots, progress_bar, series,
};
use crate::output::write_dir;
use crate::svg_plots::line_chart;
use anyhow::{Context, Result, anyhow, bail};
use moma::closed_form::ChapterModel;
use moma::closed_form::m5_mobile_manipulator::{MobileManipulator, MobileManipulatorParams};
use moma::control::pursuit::{PurePursuit, PurePursuitParams};
use moma::control::task::Coupling;
use moma::control::unicycle::{Aicardi, Astolfi, ConstantInputReference, Kanayama, Samson};
use moma::mission::planned::{PlannedPath, PlannedPathRequest, plan_platform_reference};
use moma::planning::load_map;
use moma::planning::trajectory::{DiffDriveLimits, time_parameterize};
use moma::sim::closed_loop::{
    ClosedLoopOptions, ClosedLoopResult, FeedbackLaw, simulate_closed_loop,
};
use moma::sim::coordinated::{CoordinatedController, CoordinatedGains};
use moma::sim::feedback::{
    FixedOscController, M5TaskController, OscController, OscGains, PlatformController, PlatformLaw,
    PointReference, SampledTrajectory, TaskLaw, TrackingReference, VelocityServo,
};
use moma::sim::fixed_base::FixedBaseSystem;
use moma::sim::scenario::IntegratorSettings;
use moma::sim::wheeled::ReducedSystem;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::Instant;

/// Most waypoints a reference may list.
const MAX_WAYPOINTS: usize = 100_000;

/// The `[controller]` table.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ControllerSpec {
    /// `kanayama`, `samson`, `astolfi`, `aicardi`, `pure_pursuit`, `osc`, `pd_plus`,
    /// `computed_torque`, `decoupled_naive`, `decoupled_feedforward`,
    /// `decoupled_compensated`.
    pub law: String,
    /// Control period of the zero-order hold (s); absent: continuous feedback.
    #[serde(default)]
    pub period: Option<f64>,
    /// The law's gains (names per law, docs/simulate.md).
    #[serde(default)]
    pub gains: toml::Table,
    /// Inner velocity loop gain k_v (1/s) of the platform laws (default 20).
    #[serde(default)]
    pub velocity_gain: Option<f64>,
    /// Arm posture stiffness of the platform laws' inner loop (1/s², default 100).
    #[serde(default)]
    pub arm_kp: Option<f64>,
    /// Arm posture damping of the inner loop (1/s, default 20).
    #[serde(default)]
    pub arm_kd: Option<f64>,
    /// Wheel-speed limit (rad/s), applied through the wheel map.
    #[serde(default)]
    pub max_wheel_speed: Option<f64>,
    /// Wheel-torque limit (N·m).
    #[serde(default)]
    pub max_wheel_torque: Option<f64>,
    /// Limit on every actuator input (`osc` and the m5 laws).
    #[serde(default)]
    pub max_torque: Option<f64>,
    /// The controlled frame (`osc`, `coordinated`).
    #[serde(default)]
    pub frame: Option<String>,
    /// The two arm joints coordinated with the platform (`coordinated`).
    #[serde(default)]
    pub joints: Option<[String; 2]>,
    /// Null-space posture of the arm joints (`osc`), preferred posture (`coordinated`);
    /// default: the initial configuration.
    #[serde(default)]
    pub posture: Option<Vec<f64>>,
    /// Increase of V between samples tolerated as round-off (default 1e-9).
    #[serde(default)]
    pub lyapunov_tolerance: Option<f64>,
    /// Largest final tracking-error norm counted as success (exit status 3 otherwise).
    #[serde(default)]
    pub goal_tolerance: Option<f64>,
}

/// Differential-drive limits of a time parameterisation.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TimingSpec {
    /// Largest speed (m/s).
    pub v_max: f64,
    /// Largest turn rate (rad/s).
    pub omega_max: f64,
    /// Largest acceleration (m/s²).
    pub a_max: f64,
    /// Largest angular acceleration (rad/s²).
    pub alpha_max: f64,
    /// Sampling step (s, default 0.01).
    #[serde(default)]
    pub dt: Option<f64>,
}

/// The `[reference]` table.
#[derive(Debug, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum ReferenceSpec {
    /// Kanayama: the circle of constant `(v_r, ω_r)` from the origin heading +x.
    Circle {
        /// v_r (m/s).
        vr: f64,
        /// ω_r (rad/s).
        wr: f64,
    },
    /// Kanayama: the line `x = v_r t` along +x.
    Line {
        /// v_r (m/s).
        vr: f64,
    },
    /// Samson, Astolfi, Aicardi: the goal pose.
    Pose {
        /// `[x, y, θ]` of the axle midpoint.
        goal: [f64; 3],
    },
    /// Pure pursuit: the polyline; Kanayama: the polyline time-parameterised under
    /// `timing` (turn in place, then drive each segment, trapezoidal profiles).
    Waypoints {
        /// `[[x, y], …]` (m).
        points: Vec<[f64; 2]>,
        /// Limits of the time parameterisation (Kanayama).
        #[serde(default)]
        timing: Option<TimingSpec>,
    },
    /// `osc`: a straight end-effector line, quintic time scaling.
    EeLine {
        /// Start (m, world).
        from: [f64; 3],
        /// End (m, world).
        to: [f64; 3],
        /// Duration (s).
        duration: f64,
    },
    /// `osc`: a horizontal end-effector circle.
    EeCircle {
        /// Centre (m, world).
        center: [f64; 3],
        /// Radius (m).
        radius: f64,
        /// Period (s).
        period: f64,
        /// Phase at t = 0 (rad).
        #[serde(default)]
        phase: f64,
    },
    /// `osc`: end-effector waypoints at given times.
    EeWaypoints {
        /// `[[x, y, z], …]` (m, world).
        points: Vec<[f64; 3]>,
        /// Times (s), strictly increasing.
        times: Vec<f64>,
    },
    /// Kanayama, pure pursuit: a path planned on a map from `start` to `goal` for a disk
    /// footprint (D* Lite on the configuration space, curvature-bounded smoothing, timing
    /// under `timing`), as `moma mission` plans.
    Planned {
        /// The map (ROS YAML, Moving AI `.map` or image), relative to the scenario.
        map: std::path::PathBuf,
        /// Start pose `[x, y, θ]` of the axle midpoint (world).
        start: [f64; 3],
        /// Goal pose.
        goal: [f64; 3],
        /// Radius of the disk covering the footprint (m).
        footprint_radius: f64,
        /// Unknown cells are obstacles (default true).
        #[serde(default)]
        unknown_is_obstacle: Option<bool>,
        /// Curvature bound of the smoothing (1/m, default 2).
        #[serde(default)]
        kappa_max: Option<f64>,
        /// Platform limits of the timing.
        timing: TimingSpec,
    },
    /// m5 laws: `x_d(t) = x_ref + amplitude ⊙ sin(omega ⊙ t)` in the task coordinates.
    TaskSinusoid {
        /// x_ref.
        x_ref: [f64; 5],
        /// Amplitudes.
        amplitude: [f64; 5],
        /// Angular frequencies (rad/s).
        omega: [f64; 5],
    },
}

impl ReferenceSpec {
    fn kind(&self) -> &'static str {
        match self {
            Self::Circle { .. } => "circle",
            Self::Line { .. } => "line",
            Self::Pose { .. } => "pose",
            Self::Waypoints { .. } => "waypoints",
            Self::Planned { .. } => "planned",
            Self::EeLine { .. } => "ee_line",
            Self::EeCircle { .. } => "ee_circle",
            Self::EeWaypoints { .. } => "ee_waypoints",
            Self::TaskSinusoid { .. } => "task_sinusoid",
        }
    }
}

/// Checks that `gains` holds only `allowed` keys.
fn check_keys(law: &str, gains: &toml::Table, allowed: &[&str]) -> Result<()> {
    if let Some(k) = gains.keys().find(|k| !allowed.contains(&k.as_str())) {
        bail!(
            "controller.gains.{k}: unknown gain for law {law} (expected {})",
            allowed.join(", ")
        );
    }
    Ok(())
}

fn number(v: &toml::Value, field: &str) -> Result<f64> {
    let x = match v {
        toml::Value::Float(x) => *x,
        toml::Value::Integer(i) => *i as f64,
        other => bail!("{field} must be a number, got {}", other.type_str()),
    };
    if !x.is_finite() {
        bail!("{field} is not a finite number ({x})");
    }
    Ok(x)
}

/// A required scalar gain.
fn gain(law: &str, gains: &toml::Table, name: &str, all: &[&str]) -> Result<f64> {
    let v = gains.get(name).ok_or_else(|| {
        anyhow!(
            "controller.gains.{name}: missing (law {law} needs {})",
            all.join(", ")
        )
    })?;
    number(v, &format!("controller.gains.{name}"))
}

/// An optional scalar gain.
fn opt_gain(gains: &toml::Table, name: &str) -> Result<Option<f64>> {
    gains
        .get(name)
        .map(|v| number(v, &format!("controller.gains.{name}")))
        .transpose()
}

/// A required 5-vector gain (m5 laws).
fn gain5(law: &str, gains: &toml::Table, name: &str) -> Result<[f64; 5]> {
    let field = format!("controller.gains.{name}");
    let v = gains
        .get(name)
        .ok_or_else(|| anyhow!("{field}: missing (law {law} needs Kp and Kd, 5 values each)"))?;
    let arr = v
        .as_array()
        .ok_or_else(|| anyhow!("{field} must be an array of 5 numbers"))?;
    if arr.len() != 5 {
        bail!("{field}: expected 5 values, got {}", arr.len());
    }
    let mut out = [0.0; 5];
    for (i, x) in arr.iter().enumerate() {
        out[i] = number(x, &format!("{field}[{i}]"))?;
    }
    Ok(out)
}

fn wrong_reference(law: &str, r: &ReferenceSpec, want: &str) -> anyhow::Error {
    anyhow!(
        "reference.kind = \"{}\" does not fit law {law} (expected {want})",
        r.kind()
    )
}

fn bounded_points<T>(points: &[T]) -> Result<()> {
    if points.is_empty() {
        bail!("reference.points: need at least one point");
    }
    if points.len() > MAX_WAYPOINTS {
        bail!(
            "reference.points: {} points exceed the limit of {MAX_WAYPOINTS}",
            points.len()
        );
    }
    Ok(())
}

/// Kanayama's reference.
fn tracking_reference(law: &str, r: &ReferenceSpec, base_dir: &Path) -> Result<TrackingReference> {
    match r {
        ReferenceSpec::Circle { vr, wr } => {
            super::simulate::ensure_finite("reference (vr, wr)", &[*vr, *wr])?;
            Ok(TrackingReference::Constant(ConstantInputReference {
                vr: *vr,
                wr: *wr,
            }))
        }
        ReferenceSpec::Line { vr } => {
            super::simulate::ensure_finite("reference.vr", &[*vr])?;
            Ok(TrackingReference::Constant(ConstantInputReference {
                vr: *vr,
                wr: 0.0,
            }))
        }
        ReferenceSpec::Waypoints { points, timing } => {
            bounded_points(points)?;
            let Some(tm) = timing else {
                bail!(
                    "reference.timing: law {law} tracks a time-parameterised path; give \
                     timing = {{ v_max, omega_max, a_max, alpha_max }}"
                );
            };
            let limits = DiffDriveLimits {
                v_max: tm.v_max,
                omega_max: tm.omega_max,
                a_max: tm.a_max,
                alpha_max: tm.alpha_max,
            };
            let traj = time_parameterize(points, None, &limits, tm.dt.unwrap_or(0.01))
                .context("reference.timing")?;
            Ok(TrackingReference::Sampled(SampledTrajectory::new(traj)?))
        }
        ReferenceSpec::Planned { .. } => Ok(TrackingReference::Sampled(
            planned_reference(r, base_dir)?.trajectory,
        )),
        other => Err(wrong_reference(
            law,
            other,
            "circle, line, waypoints or planned",
        )),
    }
}

/// Plans the `planned` reference on its map (the library's planner, as `moma mission`).
fn planned_reference(r: &ReferenceSpec, base_dir: &Path) -> Result<PlannedPath> {
    let ReferenceSpec::Planned {
        map,
        start,
        goal,
        footprint_radius,
        unknown_is_obstacle,
        kappa_max,
        timing,
    } = r
    else {
        unreachable!("planned_reference called for {}", r.kind());
    };
    let grid = load_map(&base_dir.join(map), None)
        .with_context(|| format!("reference.map {}", map.display()))?
        .grid;
    let request = PlannedPathRequest {
        start: *start,
        goal: *goal,
        footprint_radius: *footprint_radius,
        unknown_is_obstacle: unknown_is_obstacle.unwrap_or(true),
        limits: DiffDriveLimits {
            v_max: timing.v_max,
            omega_max: timing.omega_max,
            a_max: timing.a_max,
            alpha_max: timing.alpha_max,
        },
        kappa_max: kappa_max.unwrap_or(2.0),
        dt: timing.dt.unwrap_or(0.02),
    };
    Ok(plan_platform_reference(&grid, &request)?)
}

fn goal_pose(law: &str, r: &ReferenceSpec) -> Result<[f64; 3]> {
    match r {
        ReferenceSpec::Pose { goal } => {
            super::simulate::ensure_finite("reference.goal", goal)?;
            Ok(*goal)
        }
        other => Err(wrong_reference(law, other, "pose")),
    }
}

/// The platform law with its gains and reference.
fn platform_law(
    law: &str,
    gains: &toml::Table,
    r: &ReferenceSpec,
    base_dir: &Path,
) -> Result<PlatformLaw> {
    let named = |all: &[&str]| -> Result<Vec<f64>> {
        check_keys(law, gains, all)?;
        all.iter().map(|n| gain(law, gains, n, all)).collect()
    };
    Ok(match law {
        "kanayama" => {
            let g = named(&["Kx", "Ky", "Kth"])?;
            PlatformLaw::Kanayama(
                Kanayama::new(g[0], g[1], g[2])?,
                tracking_reference(law, r, base_dir)?,
            )
        }
        "samson" => {
            let g = named(&["k1", "k2", "k3"])?;
            PlatformLaw::Samson(Samson::new(g[0], g[1], g[2])?, goal_pose(law, r)?)
        }
        "astolfi" => {
            let g = named(&["k_rho", "k_alpha", "k_beta"])?;
            let a = Astolfi::new(g[0], g[1], g[2])?;
            if let Some(w) = a.warning() {
                eprintln!("warning: {w}");
            }
            PlatformLaw::Astolfi(a, goal_pose(law, r)?)
        }
        "aicardi" => {
            let g = named(&["gamma", "k", "h"])?;
            PlatformLaw::Aicardi(Aicardi::new(g[0], g[1], g[2])?, goal_pose(law, r)?)
        }
        "pure_pursuit" => {
            const NAMES: [&str; 8] = [
                "desired_speed",
                "lookahead_time",
                "min_lookahead",
                "max_lookahead",
                "regulation_min_radius",
                "approach_distance",
                "min_approach_speed",
                "goal_tolerance",
            ];
            check_keys(law, gains, &NAMES)?;
            let mut p = PurePursuitParams::default();
            let fields: [&mut f64; 8] = [
                &mut p.desired_speed,
                &mut p.lookahead_time,
                &mut p.min_lookahead,
                &mut p.max_lookahead,
                &mut p.regulation_min_radius,
                &mut p.approach_distance,
                &mut p.min_approach_speed,
                &mut p.goal_tolerance,
            ];
            for (name, f) in NAMES.iter().zip(fields) {
                if let Some(x) = opt_gain(gains, name)? {
                    *f = x;
                }
            }
            if let ReferenceSpec::Planned { .. } = r {
                let path = planned_reference(r, base_dir)?.path;
                return Ok(PlatformLaw::PurePursuit(
                    Box::new(PurePursuit::new(p).context("controller.gains")?),
                    path,
                ));
            }
            let ReferenceSpec::Waypoints { points, timing } = r else {
                return Err(wrong_reference(law, r, "waypoints or planned"));
            };
            if timing.is_some() {
                bail!("reference.timing: pure pursuit follows the path itself (remove timing)");
            }
            bounded_points(points)?;
            for (i, p) in points.iter().enumerate() {
                super::simulate::ensure_finite(&format!("reference.points[{i}]"), p)?;
            }
            PlatformLaw::PurePursuit(
                Box::new(PurePursuit::new(p).context("controller.gains")?),
                points.clone(),
            )
        }
        _ => unreachable!("platform_law called for {law}"),
    })
}

fn point_reference(law: &str, r: &ReferenceSpec) -> Result<PointReference> {
    let p = match r {
        ReferenceSpec::EeLine { from, to, duration } => PointReference::Line {
            from: *from,
            to: *to,
            duration: *duration,
        },
        ReferenceSpec::EeCircle {
            center,
            radius,
            period,
            phase,
        } => PointReference::Circle {
            center: *center,
            radius: *radius,
            period: *period,
            phase: *phase,
        },
        ReferenceSpec::EeWaypoints { points, times } => {
            bounded_points(points)?;
            PointReference::Waypoints {
                points: points.clone(),
                times: times.clone(),
            }
        }
        other => {
            return Err(wrong_reference(
                law,
                other,
                "ee_line, ee_circle or ee_waypoints",
            ));
        }
    };
    p.validate()?;
    Ok(p)
}

fn osc_gains(law: &str, gains: &toml::Table) -> Result<OscGains> {
    let all = ["kp", "kv", "posture_kp", "posture_kd"];
    check_keys(law, gains, &all)?;
    Ok(OscGains {
        kp: gain(law, gains, "kp", &all)?,
        kv: gain(law, gains, "kv", &all)?,
        posture_kp: opt_gain(gains, "posture_kp")?.unwrap_or(0.0),
        posture_kd: opt_gain(gains, "posture_kd")?.unwrap_or(0.0),
    })
}

const PLATFORM_LAWS: [&str; 5] = ["kanayama", "samson", "astolfi", "aicardi", "pure_pursuit"];
const M5_LAWS: [&str; 5] = [
    "pd_plus",
    "computed_torque",
    "decoupled_naive",
    "decoupled_feedforward",
    "decoupled_compensated",
];

/// The plant and the law of a closed-loop scenario.
type Loop = (Box<dyn ReducedSystem>, Box<dyn FeedbackLaw>, String);

fn only_for(law: &str, fields: &[(&str, bool)]) -> Result<()> {
    for (name, present) in fields {
        if *present {
            bail!("controller.{name} does not apply to law {law}");
        }
    }
    Ok(())
}

/// The `[controller]` keys of the platform servo that OSC (fixed base or on the platform)
/// does not take, with whether the scenario gives them.
fn not_for_osc(c: &ControllerSpec) -> [(&'static str, bool); 6] {
    [
        ("joints", c.joints.is_some()),
        ("velocity_gain", c.velocity_gain.is_some()),
        ("arm_kp", c.arm_kp.is_some()),
        ("arm_kd", c.arm_kd.is_some()),
        ("max_wheel_speed", c.max_wheel_speed.is_some()),
        ("max_wheel_torque", c.max_wheel_torque.is_some()),
    ]
}

fn build_loop(sc: &Scenario, base_dir: &Path, c: &ControllerSpec) -> Result<Loop> {
    let law = c.law.as_str();
    let Some(r) = &sc.reference else {
        bail!("[reference] is missing: law {law} needs one");
    };
    let nonneg = |name: &str, x: Option<f64>| -> Result<()> {
        if let Some(x) = x
            && !(x.is_finite() && x > 0.0)
        {
            bail!("controller.{name} must be a positive finite number, got {x}");
        }
        Ok(())
    };
    nonneg("max_wheel_speed", c.max_wheel_speed)?;
    nonneg("max_wheel_torque", c.max_wheel_torque)?;
    nonneg("max_torque", c.max_torque)?;
    if law == "osc"
        && let RobotSpec::FixedBase { urdf } = &sc.robot
    {
        only_for(law, &not_for_osc(c))?;
        let model = fixed_base_model(&base_dir.join(urdf), sc.gravity).context("robot")?;
        let q0 = sc.initial.q.clone().unwrap_or_else(|| vec![0.0; model.nq]);
        if q0.len() != model.nq {
            bail!("initial.q: expected {} values, got {}", model.nq, q0.len());
        }
        let gains = osc_gains(law, &c.gains)?;
        let frame = c
            .frame
            .as_deref()
            .ok_or_else(|| anyhow!("controller.frame: missing (law osc needs the frame)"))?;
        let posture = c.posture.clone().unwrap_or(q0);
        if posture.len() != model.nv {
            bail!(
                "controller.posture: expected {} values (the joints), got {}",
                model.nv,
                posture.len()
            );
        }
        let ctl = FixedOscController::new(
            model.clone(),
            frame,
            point_reference(law, r)?,
            gains,
            posture,
            c.max_torque,
        )?;
        let sys = FixedBaseSystem::new(model).context("robot")?;
        return Ok((
            Box::new(sys),
            Box::new(ctl),
            format!("URDF {} (fixed base)", urdf.display()),
        ));
    }
    if PLATFORM_LAWS.contains(&law) || law == "osc" || law == "coordinated" {
        let RobotSpec::Urdf {
            urdf,
            drive,
            wheel_joints,
            casters,
        } = &sc.robot
        else {
            bail!(
                "law {law} drives a URDF robot on a differential drive (robot.kind = \"urdf\"{})",
                if law == "osc" {
                    ", or \"fixed_base\""
                } else {
                    ""
                }
            );
        };
        let path = base_dir.join(urdf);
        let wm = build_wheeled_model(&path, drive, wheel_joints.clone(), casters, sc.gravity)
            .context("robot")?;
        let nr = wm.nr();
        let q0 = sc
            .initial
            .q
            .clone()
            .unwrap_or_else(|| vec![0.0; wm.model.nq]);
        if q0.len() != wm.model.nq {
            bail!(
                "initial.q: expected {} values ({}), got {}",
                wm.model.nq,
                wm.q_names().join(", "),
                q0.len()
            );
        }
        let arm0: Vec<f64> = wm.arm_dofs().iter().map(|&d| q0[d]).collect();
        let name = format!("URDF {}", urdf.display());
        if law == "coordinated" {
            only_for(law, &[("max_torque", c.max_torque.is_some())])?;
            let all = ["K_E", "K_Y"];
            check_keys(law, &c.gains, &all)?;
            let gains = CoordinatedGains {
                k_e: gain(law, &c.gains, "K_E", &all)?,
                k_y: gain(law, &c.gains, "K_Y", &all)?,
            };
            let frame = c.frame.as_deref().ok_or_else(|| {
                anyhow!("controller.frame: missing (law coordinated needs the end-effector frame)")
            })?;
            let joints = c.joints.as_ref().ok_or_else(|| {
                anyhow!(
                    "controller.joints: missing (law coordinated needs the two arm joints that \
                     move the end effector in the horizontal plane)"
                )
            })?;
            let posture = c.posture.clone().unwrap_or(arm0);
            if posture.len() != nr - 2 {
                bail!(
                    "controller.posture: expected {} values (the arm joints), got {}",
                    nr - 2,
                    posture.len()
                );
            }
            let servo = VelocityServo {
                gain: c.velocity_gain.unwrap_or(20.0),
                arm_kp: c.arm_kp.unwrap_or(100.0),
                arm_kd: c.arm_kd.unwrap_or(20.0),
            };
            let ctl = CoordinatedController::new(
                wm.clone(),
                frame,
                [joints[0].as_str(), joints[1].as_str()],
                point_reference(law, r)?,
                gains,
                posture,
                servo,
                c.max_wheel_speed,
                c.max_wheel_torque,
            )?;
            return Ok((
                Box::new(moma::sim::wheeled_system::WheeledSystem::new(wm)),
                Box::new(ctl),
                name,
            ));
        }
        if law == "osc" {
            only_for(law, &not_for_osc(c))?;
            let gains = osc_gains(law, &c.gains)?;
            let frame = c
                .frame
                .as_deref()
                .ok_or_else(|| anyhow!("controller.frame: missing (law osc needs the frame)"))?;
            let posture = c.posture.clone().unwrap_or(arm0);
            if posture.len() != nr - 2 {
                bail!(
                    "controller.posture: expected {} values (the arm joints), got {}",
                    nr - 2,
                    posture.len()
                );
            }
            let law_obj = OscController::new(
                wm.clone(),
                frame,
                point_reference(law, r)?,
                gains,
                posture,
                c.max_torque,
            )?;
            return Ok((
                Box::new(moma::sim::wheeled_system::WheeledSystem::new(wm)),
                Box::new(law_obj),
                name,
            ));
        }
        only_for(
            law,
            &[
                ("max_torque", c.max_torque.is_some()),
                ("frame", c.frame.is_some()),
                ("joints", c.joints.is_some()),
                ("posture", c.posture.is_some()),
            ],
        )?;
        let servo = VelocityServo {
            gain: c.velocity_gain.unwrap_or(20.0),
            arm_kp: c.arm_kp.unwrap_or(100.0),
            arm_kd: c.arm_kd.unwrap_or(20.0),
        };
        let pl = platform_law(law, &c.gains, r, base_dir)?;
        let ctl = PlatformController::new(
            wm.clone(),
            pl,
            servo,
            arm0,
            c.max_wheel_speed,
            c.max_wheel_torque,
        )?;
        return Ok((
            Box::new(moma::sim::wheeled_system::WheeledSystem::new(wm)),
            Box::new(ctl),
            name,
        ));
    }
    if M5_LAWS.contains(&law) {
        only_for(
            law,
            &[
                ("velocity_gain", c.velocity_gain.is_some()),
                ("arm_kp", c.arm_kp.is_some()),
                ("arm_kd", c.arm_kd.is_some()),
                ("max_wheel_speed", c.max_wheel_speed.is_some()),
                ("max_wheel_torque", c.max_wheel_torque.is_some()),
                ("frame", c.frame.is_some()),
                ("joints", c.joints.is_some()),
                ("posture", c.posture.is_some()),
            ],
        )?;
        let RobotSpec::Chapter { model, params } = &sc.robot else {
            bail!("law {law} runs on the chapter model m5 (robot.kind = \"chapter\")");
        };
        if !matches!(
            ChapterModel::from_name(model),
            Ok(ChapterModel::M5MobileManipulator)
        ) {
            bail!("law {law} runs on the chapter model m5, not {model}");
        }
        let json = chapter_params_json(params, sc.gravity, true)?;
        let p: MobileManipulatorParams =
            moma::closed_form::parse_params("robot.params", &json).context("robot")?;
        let mm = MobileManipulator::new(p).context("robot.params")?;
        let sys = moma::sim::chapter_models::chapter_system(model, &json).context("robot")?;
        check_keys(law, &c.gains, &["Kp", "Kd"])?;
        let kp = gain5(law, &c.gains, "Kp")?;
        let kd = gain5(law, &c.gains, "Kd")?;
        let ReferenceSpec::TaskSinusoid {
            x_ref,
            amplitude,
            omega,
        } = r
        else {
            return Err(wrong_reference(law, r, "task_sinusoid"));
        };
        let tl = match law {
            "pd_plus" => TaskLaw::PdPlus,
            "computed_torque" => TaskLaw::ComputedTorque,
            "decoupled_naive" => TaskLaw::Decoupled(Coupling::Naive),
            "decoupled_feedforward" => TaskLaw::Decoupled(Coupling::DesiredAcceleration),
            _ => TaskLaw::Decoupled(Coupling::Compensated),
        };
        let ctl = M5TaskController::new(mm, tl, *x_ref, *amplitude, *omega, kp, kd, c.max_torque)?;
        return Ok((sys, Box::new(ctl), format!("chapter model {model}")));
    }
    bail!(
        "controller.law = \"{law}\": unknown law (expected one of {}, osc, coordinated, {})",
        PLATFORM_LAWS.join(", "),
        M5_LAWS.join(", ")
    )
}

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

/// Runs a closed-loop scenario.
pub fn run(path: &Path, sc: &Scenario, base_dir: &Path, args: &Args) -> Result<()> {
    let ctx = |what: &str| format!("{}: {what}", path.display());
    let Some(c) = &sc.controller else {
        bail!("{}", ctx("[reference] needs a [controller] table"));
    };
    if matches!(sc.robot, RobotSpec::FreeFloating { .. }) {
        bail!(
            "{}",
            ctx(
                "[controller] is for wheeled robots and m5; free-floating control is [space.control]"
            )
        );
    }
    if sc.inputs.is_some() {
        bail!(
            "{}",
            ctx("[[inputs]] and [controller] exclude each other: the controller writes the inputs")
        );
    }
    if sc.space.is_some() {
        bail!(
            "{}",
            ctx("[space] is only for robot.kind = \"free_floating\"")
        );
    }
    let (mut system, mut law, robot_name) =
        build_loop(sc, base_dir, c).map_err(|e| anyhow!("{}: {e:#}", path.display()))?;
    let (q0, v0, _) = initial_state(sc, system.as_ref(), &ctx)?;
    sc.integrator
        .validate()
        .with_context(|| ctx("integrator"))?;
    let tol = c.lyapunov_tolerance.unwrap_or(1e-9);
    if let Some(g) = c.goal_tolerance
        && !(g.is_finite() && g >= 0.0)
    {
        bail!(
            "{}",
            ctx(&format!(
                "controller.goal_tolerance must be >= 0 and finite, got {g}"
            ))
        );
    }
    let options = ClosedLoopOptions {
        duration: sc.duration,
        integrator: sc.integrator,
        control_period: c.period,
        record_interval: sc.output.record_interval,
        limits: sc.limits.unwrap_or_default(),
        lyapunov_tolerance: tol,
    };
    let dir = args.output.clone().unwrap_or_else(|| sc.output.dir.clone());
    let bar = progress_bar(sc.duration);
    let start = Instant::now();
    let result = simulate_closed_loop(
        system.as_mut(),
        law.as_mut(),
        &q0,
        &v0,
        &options,
        &mut |t| {
            if let Some(pb) = &bar {
                pb.set_position((t * 1000.0).round() as u64);
            }
        },
    );
    if let Some(pb) = &bar {
        pb.finish_and_clear();
    }
    let res =
        result.map_err(|e| anyhow!("{}: closed-loop simulation failed: {e}", path.display()))?;
    let wall = start.elapsed().as_secs_f64();
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
    let lyapunov = res.lyapunov_report.as_ref().map(|r| LyapunovOut {
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
    });
    let s = res.saturation;
    let steps = res.stats.accepted;
    let goal_reached = c.goal_tolerance.map(|g| final_norm <= g);
    let mut summary = ControlSummary {
        scenario: sc
            .name
            .clone()
            .unwrap_or_else(|| path.display().to_string()),
        robot: robot_name,
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
        goal_reached,
        lyapunov,
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
    };
    let monitor = match &sc.stability {
        None => None,
        Some(spec) => {
            let mon = super::simulate_stability::replay(spec, &sc.robot, sc.gravity, base_dir, rec)
                .with_context(|| ctx("stability"))?;
            summary.stability = Some(super::simulate_stability::summary(spec, &mon, None));
            Some(mon)
        }
    };
    let wheels = match &sc.robot {
        RobotSpec::Urdf {
            wheel_joints: Some(w),
            ..
        } => w.to_vec(),
        _ => Vec::new(),
    };
    let mut files = vec![
        ("trajectory.csv".to_string(), rec.to_csv().into_bytes()),
        ("control.csv".to_string(), control_csv(&res).into_bytes()),
    ];
    if let Some(mon) = &monitor {
        files.push((
            "stability.csv".to_string(),
            super::simulate_stability::csv(mon).into_bytes(),
        ));
    }
    if sc.output.plots {
        if matches!(sc.robot, RobotSpec::FixedBase { .. }) {
            arm_plots(rec, &mut files);
        } else {
            motion_plots(&wheels, rec, &mut files);
        }
        balance_plots(rec, &mut files);
        control_plots(&res, &mut files);
        if let Some(mon) = &monitor {
            super::simulate_stability::plots(mon, &mut files);
        }
    }
    summary.files = files
        .iter()
        .map(|(n, _)| n.clone())
        .chain(std::iter::once("summary.json".to_string()))
        .collect();
    let mut json = serde_json::to_string_pretty(&summary).context("serialising the summary")?;
    json.push('\n');
    files.push(("summary.json".to_string(), json.into_bytes()));
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
    if goal_reached == Some(false) {
        return super::common::goal_not_reached(format!(
            "{}: final tracking error {final_norm:e} exceeds controller.goal_tolerance = {}",
            path.display(),
            c.goal_tolerance.unwrap_or_default()
        ));
    }
    Ok(())
}

//! The `[controller]` and `[reference]` tables of closed-loop `moma simulate` scenarios
//! and the closed loop they make: the unicycle laws and regulated pure pursuit drive a
//! wheeled URDF robot through an inner computed-torque loop (their reference may be a
//! path planned on a map, `mission::planned`); `coordinated` coordinates the platform
//! with two arm joints; `osc` drives an end-effector point of a wheeled URDF robot
//! through the reduced model, or of a fixed-base arm; `mpc` is the whole-body MPC
//! (its table in [`crate::sim_config::mpc`]); `pd_plus`, `computed_torque` and
//! the `decoupled_*` laws run on the chapter's model m5. Schema: `docs/simulate.md`.

use std::path::Path;

use serde::Deserialize;

use super::{
    Context, Scenario, at, bail, build_wheeled_model, chapter_params_json, err, finite,
    fixed_base_model,
};
use crate::closed_form::ChapterModel;
use crate::closed_form::m5_mobile_manipulator::{MobileManipulator, MobileManipulatorParams};
use crate::control::pursuit::{PurePursuit, PurePursuitParams};
use crate::control::task::Coupling;
use crate::control::unicycle::{Aicardi, Astolfi, ConstantInputReference, Kanayama, Samson};
use crate::error::{Error, Result};
use crate::mission::planned::{PlannedPath, PlannedPathRequest, plan_platform_reference};
use crate::planning::load_map;
use crate::planning::trajectory::{DiffDriveLimits, time_parameterize};
use crate::sim::closed_loop::{
    ClosedLoopOptions, ClosedLoopResult, FeedbackLaw, simulate_closed_loop,
};
use crate::sim::coordinated::{CoordinatedController, CoordinatedGains};
use crate::sim::feedback::{
    FixedOscController, M5TaskController, OscController, OscGains, PlatformController, PlatformLaw,
    PointReference, SampledTrajectory, TaskLaw, TrackingReference, VelocityServo,
};
use crate::sim::fixed_base::FixedBaseSystem;
use crate::sim::reduced_system::ReducedSystem;
use crate::sim::sensor_noise::SensorNoise;
use crate::sim_config::mpc::{LineReach, MpcSpec, mpc_law};
use crate::sim_config::schema::RobotSpec;

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
    /// The whole-body MPC's settings (`mpc`).
    #[serde(default)]
    pub mpc: Option<MpcSpec>,
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
    /// `mpc`: the base along +x at `vr` (as `line`) and, from `target_from` on, the end
    /// effector at `target`.
    LineReach {
        /// Base speed (m/s).
        vr: f64,
        /// End-effector target (m, world).
        target: [f64; 3],
        /// Time the target becomes active (s, default 0).
        #[serde(default)]
        target_from: f64,
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
    pub fn kind(&self) -> &'static str {
        match self {
            Self::Circle { .. } => "circle",
            Self::Line { .. } => "line",
            Self::Pose { .. } => "pose",
            Self::Waypoints { .. } => "waypoints",
            Self::Planned { .. } => "planned",
            Self::EeLine { .. } => "ee_line",
            Self::EeCircle { .. } => "ee_circle",
            Self::EeWaypoints { .. } => "ee_waypoints",
            Self::LineReach { .. } => "line_reach",
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
        err!(
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
        .ok_or_else(|| err!("{field}: missing (law {law} needs Kp and Kd, 5 values each)"))?;
    let arr = v
        .as_array()
        .ok_or_else(|| err!("{field} must be an array of 5 numbers"))?;
    if arr.len() != 5 {
        bail!("{field}: expected 5 values, got {}", arr.len());
    }
    let mut out = [0.0; 5];
    for (i, x) in arr.iter().enumerate() {
        out[i] = number(x, &format!("{field}[{i}]"))?;
    }
    Ok(out)
}

fn wrong_reference(law: &str, r: &ReferenceSpec, want: &str) -> Error {
    err!(
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
            finite("reference (vr, wr)", &[*vr, *wr])?;
            Ok(TrackingReference::Constant(ConstantInputReference {
                vr: *vr,
                wr: *wr,
            }))
        }
        ReferenceSpec::Line { vr } => {
            finite("reference.vr", &[*vr])?;
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
                .ctx("reference.timing")?;
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
        .with_ctx(|| format!("reference.map {}", map.display()))?
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
    plan_platform_reference(&grid, &request)
}

fn goal_pose(law: &str, r: &ReferenceSpec) -> Result<[f64; 3]> {
    match r {
        ReferenceSpec::Pose { goal } => {
            finite("reference.goal", goal)?;
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
    warnings: &mut Vec<String>,
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
                warnings.push(w);
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
                    Box::new(PurePursuit::new(p).ctx("controller.gains")?),
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
                finite(&format!("reference.points[{i}]"), p)?;
            }
            PlatformLaw::PurePursuit(
                Box::new(PurePursuit::new(p).ctx("controller.gains")?),
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

/// The plant, the law and the robot's name of a closed-loop scenario.
type Loop = (Box<dyn ReducedSystem>, Box<dyn FeedbackLaw>, String);

/// A closed-loop run: the plant, the feedback law, the initial state and the options of
/// [`crate::sim::closed_loop::simulate_closed_loop`].
pub struct ClosedLoop {
    /// The plant.
    pub system: Box<dyn ReducedSystem>,
    /// The feedback law.
    pub law: Box<dyn FeedbackLaw>,
    /// How the summary names the robot.
    pub robot_name: String,
    /// Warnings about the law's gains (e.g. Astolfi's strong condition), for the user.
    pub warnings: Vec<String>,
    /// Initial configuration.
    pub q0: Vec<f64>,
    /// Initial reduced velocity.
    pub v0: Vec<f64>,
    /// Duration, integrator, control period, recording, limits, Lyapunov tolerance.
    pub options: ClosedLoopOptions,
    /// The noise on the state the law measures (`[uncertainty]`'s sensor noise), drawn
    /// by the loop at every control tick; `None`: the law measures the plant's state.
    pub noise: Option<SensorNoise>,
}

impl ClosedLoop {
    /// Runs the loop from its initial state; `progress` gets the simulated time as it
    /// advances.
    ///
    /// # Errors
    /// As [`simulate_closed_loop`].
    pub fn run(&mut self, progress: &mut dyn FnMut(f64)) -> Result<ClosedLoopResult> {
        simulate_closed_loop(
            self.system.as_mut(),
            self.law.as_mut(),
            &self.q0,
            &self.v0,
            &self.options,
            self.noise.as_mut(),
            progress,
        )
    }
}

/// Builds the closed loop of a scenario with `[controller]` (and `[reference]`); `path`
/// is the scenario file named in every error, `base_dir` resolves relative paths.
///
/// # Errors
/// [`Error::Scenario`] naming the file and the field at fault.
pub fn closed_loop(sc: &Scenario, path: &Path, base_dir: &Path) -> Result<ClosedLoop> {
    let ctx = |what: &str| at(path, what);
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
    let mut warnings = Vec::new();
    let (system, law, robot_name) = build_loop(sc, base_dir, c, &mut warnings)
        .map_err(|e| err!("{}: {}", path.display(), super::chain(&e)))?;
    let (q0, v0, _) = super::initial_state(sc, system.as_ref(), path)?;
    sc.integrator.validate().with_ctx(|| ctx("integrator"))?;
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
        lyapunov_tolerance: c.lyapunov_tolerance.unwrap_or(1e-9),
    };
    Ok(ClosedLoop {
        system,
        law,
        robot_name,
        warnings,
        q0,
        v0,
        options,
        noise: None,
    })
}

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

/// The actuator limits, when given, are positive finite numbers.
fn check_limits(c: &ControllerSpec) -> Result<()> {
    for (name, x) in [
        ("max_wheel_speed", c.max_wheel_speed),
        ("max_wheel_torque", c.max_wheel_torque),
        ("max_torque", c.max_torque),
    ] {
        if let Some(problem) = x.and_then(crate::error::not_positive_finite) {
            bail!("controller.{name} {problem}");
        }
    }
    Ok(())
}

/// The inner velocity loop of the platform laws and `coordinated`.
fn servo(c: &ControllerSpec) -> VelocityServo {
    VelocityServo {
        gain: c.velocity_gain.unwrap_or(20.0),
        arm_kp: c.arm_kp.unwrap_or(100.0),
        arm_kd: c.arm_kd.unwrap_or(20.0),
    }
}

fn build_loop(
    sc: &Scenario,
    base_dir: &Path,
    c: &ControllerSpec,
    warnings: &mut Vec<String>,
) -> Result<Loop> {
    let law = c.law.as_str();
    let Some(r) = &sc.reference else {
        bail!("[reference] is missing: law {law} needs one");
    };
    check_limits(c)?;
    if c.mpc.is_some() && law != "mpc" {
        bail!("controller.mpc does not apply to law {law} (only to law mpc)");
    }
    if law == "osc"
        && let RobotSpec::FixedBase { urdf } = &sc.robot
    {
        return fixed_osc_loop(sc, base_dir, c, r, urdf);
    }
    if PLATFORM_LAWS.contains(&law) || ["osc", "coordinated", "mpc"].contains(&law) {
        return wheeled_loop(sc, base_dir, c, r, warnings);
    }
    if M5_LAWS.contains(&law) {
        return m5_loop(sc, c, r);
    }
    bail!(
        "controller.law = \"{law}\": unknown law (expected one of {}, osc, coordinated, mpc, {})",
        PLATFORM_LAWS.join(", "),
        M5_LAWS.join(", ")
    )
}

/// `osc` on a fixed-base arm.
fn fixed_osc_loop(
    sc: &Scenario,
    base_dir: &Path,
    c: &ControllerSpec,
    r: &ReferenceSpec,
    urdf: &Path,
) -> Result<Loop> {
    let law = c.law.as_str();
    only_for(law, &not_for_osc(c))?;
    let model = fixed_base_model(&base_dir.join(urdf), sc.gravity).ctx("robot")?;
    let q0 = sc.initial.q.clone().unwrap_or_else(|| vec![0.0; model.nq]);
    if q0.len() != model.nq {
        bail!("initial.q: expected {} values, got {}", model.nq, q0.len());
    }
    let gains = osc_gains(law, &c.gains)?;
    let frame = c
        .frame
        .as_deref()
        .ok_or_else(|| err!("controller.frame: missing (law osc needs the frame)"))?;
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
    let sys = FixedBaseSystem::new(model).ctx("robot")?;
    Ok((
        Box::new(sys),
        Box::new(ctl),
        format!("URDF {} (fixed base)", urdf.display()),
    ))
}

/// The platform laws, `coordinated` and `osc` on a URDF robot on a differential drive.
fn wheeled_loop(
    sc: &Scenario,
    base_dir: &Path,
    c: &ControllerSpec,
    r: &ReferenceSpec,
    warnings: &mut Vec<String>,
) -> Result<Loop> {
    let law = c.law.as_str();
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
        .ctx("robot")?;
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
    let ctl: Box<dyn FeedbackLaw> = match law {
        "mpc" => whole_body_mpc(&wm, c, r, &path, &q0, base_dir)?,
        "coordinated" => coordinated_law(&wm, c, r, arm0)?,
        "osc" => osc_law(&wm, c, r, arm0)?,
        _ => {
            only_for(
                law,
                &[
                    ("max_torque", c.max_torque.is_some()),
                    ("frame", c.frame.is_some()),
                    ("joints", c.joints.is_some()),
                    ("posture", c.posture.is_some()),
                ],
            )?;
            let pl = platform_law(law, &c.gains, r, base_dir, warnings)?;
            Box::new(PlatformController::new(
                wm.clone(),
                pl,
                servo(c),
                arm0,
                c.max_wheel_speed,
                c.max_wheel_torque,
            )?)
        }
    };
    Ok((
        Box::new(crate::sim::wheeled_system::WheeledSystem::new(wm)),
        ctl,
        format!("URDF {}", urdf.display()),
    ))
}

/// `mpc`: the whole-body MPC, solved once per control period.
fn whole_body_mpc(
    wm: &crate::mobile::WheeledModel,
    c: &ControllerSpec,
    r: &ReferenceSpec,
    urdf: &Path,
    q0: &[f64],
    base_dir: &Path,
) -> Result<Box<dyn FeedbackLaw>> {
    let law = c.law.as_str();
    let mut not_taken = not_for_osc(c).to_vec();
    not_taken.extend([
        ("max_torque", c.max_torque.is_some()),
        ("posture", c.posture.is_some()),
        ("gains", !c.gains.is_empty()),
    ]);
    only_for(law, &not_taken)?;
    if c.period.is_none() {
        bail!("controller.period: missing (law mpc solves once per control period)");
    }
    let spec = c
        .mpc
        .as_ref()
        .ok_or_else(|| err!("[controller.mpc]: missing (law mpc needs at least its joints)"))?;
    let frame = c
        .frame
        .as_deref()
        .ok_or_else(|| err!("controller.frame: missing (law mpc needs the end-effector frame)"))?;
    let ReferenceSpec::LineReach {
        vr,
        target,
        target_from,
    } = r
    else {
        return Err(wrong_reference(law, r, "line_reach"));
    };
    finite("reference.vr", &[*vr])?;
    finite("reference.target", target)?;
    if !(target_from.is_finite() && *target_from >= 0.0) {
        bail!("reference.target_from must be a finite number >= 0, got {target_from}");
    }
    let reference = LineReach {
        vr: *vr,
        target: *target,
        target_from: *target_from,
    };
    mpc_law(spec, frame, wm, urdf, q0, reference, base_dir)
}

/// The arm posture a law holds: `controller.posture`, else the initial arm joints.
fn arm_posture(c: &ControllerSpec, arm0: Vec<f64>, n_arm: usize) -> Result<Vec<f64>> {
    let posture = c.posture.clone().unwrap_or(arm0);
    if posture.len() != n_arm {
        bail!(
            "controller.posture: expected {n_arm} values (the arm joints), got {}",
            posture.len()
        );
    }
    Ok(posture)
}

/// `coordinated`: platform and two arm joints move the end effector.
fn coordinated_law(
    wm: &crate::mobile::WheeledModel,
    c: &ControllerSpec,
    r: &ReferenceSpec,
    arm0: Vec<f64>,
) -> Result<Box<dyn FeedbackLaw>> {
    let law = c.law.as_str();
    only_for(law, &[("max_torque", c.max_torque.is_some())])?;
    let all = ["K_E", "K_Y"];
    check_keys(law, &c.gains, &all)?;
    let gains = CoordinatedGains {
        k_e: gain(law, &c.gains, "K_E", &all)?,
        k_y: gain(law, &c.gains, "K_Y", &all)?,
    };
    let frame = c.frame.as_deref().ok_or_else(|| {
        err!("controller.frame: missing (law coordinated needs the end-effector frame)")
    })?;
    let joints = c.joints.as_ref().ok_or_else(|| {
        err!(
            "controller.joints: missing (law coordinated needs the two arm joints that \
             move the end effector in the horizontal plane)"
        )
    })?;
    let posture = arm_posture(c, arm0, wm.nr() - 2)?;
    Ok(Box::new(CoordinatedController::new(
        wm.clone(),
        frame,
        [joints[0].as_str(), joints[1].as_str()],
        point_reference(law, r)?,
        gains,
        posture,
        servo(c),
        c.max_wheel_speed,
        c.max_wheel_torque,
    )?))
}

/// `osc` on the reduced model of a wheeled robot.
fn osc_law(
    wm: &crate::mobile::WheeledModel,
    c: &ControllerSpec,
    r: &ReferenceSpec,
    arm0: Vec<f64>,
) -> Result<Box<dyn FeedbackLaw>> {
    let law = c.law.as_str();
    only_for(law, &not_for_osc(c))?;
    let gains = osc_gains(law, &c.gains)?;
    let frame = c
        .frame
        .as_deref()
        .ok_or_else(|| err!("controller.frame: missing (law osc needs the frame)"))?;
    let posture = arm_posture(c, arm0, wm.nr() - 2)?;
    Ok(Box::new(OscController::new(
        wm.clone(),
        frame,
        point_reference(law, r)?,
        gains,
        posture,
        c.max_torque,
    )?))
}

/// The task-space laws on the chapter's m5.
fn m5_loop(sc: &Scenario, c: &ControllerSpec, r: &ReferenceSpec) -> Result<Loop> {
    let law = c.law.as_str();
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
        crate::closed_form::parse_params("robot.params", &json).ctx("robot")?;
    let mm = MobileManipulator::new(p).ctx("robot.params")?;
    let sys = crate::sim::chapter_models::chapter_system(model, &json).ctx("robot")?;
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
    Ok((sys, Box::new(ctl), format!("chapter model {model}")))
}

//! The feedback laws of [`crate::control`] as [`FeedbackLaw`]s of the closed-loop
//! simulator, with the references they track.
//!
//! * [`PlatformController`]: a unicycle law (Kanayama, Samson, Astolfi, Aicardi) or
//!   regulated pure pursuit drives a wheeled URDF robot **dynamically**. The law's
//!   `(v, ω)` command (for the axle midpoint) is limited in wheel speed through the wheel
//!   map of the drive, then tracked by an inner computed-torque loop on the reduced
//!   dynamics: `Qr = Mr a + (cr + Gr)` with `a = [k_v (v_c − v), k_v (ω_c − ω),
//!   k_p (q*_arm − q_arm) − k_d q̇_arm]` (the arm holds its initial posture), the actuator
//!   inputs from `N_Cᵀ S u = Qr`, wheel torques clipped to their limit. V and V̇ are the
//!   law's own (kinematic) Lyapunov function and rate at the actual pose, so the
//!   monitor shows what the inner loop's lag and the limits do to them.
//! * [`OscController`]: operational-space control of an end-effector point on a wheeled
//!   robot through the reduced model ([`crate::control::osc::osc_reduced`]), with
//!   `a_des = ẍ_d + k_v (ẋ_d − ẋ) + k_p (x_d − x)` and a null-space posture torque;
//!   `V = ½|ė|² + ½ k_p |e|²`, `V̇ = −k_v |ė|²` (exact for continuous, unsaturated
//!   feedback on the exact model).
//! * [`M5TaskController`]: the chapter's task-space laws on model m5 ([`crate::control::task`]):
//!   PD+ (5.122 corrected), task-space computed torque, and the decoupled control
//!   (5.129–5.133) naive, with desired-acceleration feed-forward, or compensated.

use crate::closed_form::m5_mobile_manipulator::MobileManipulator;
use crate::control::Controller;
use crate::control::osc::{ReducedOscData, osc_reduced};
use crate::control::pursuit::PurePursuit;
use crate::control::task::{Coupling, computed_torque, decoupled, pd_plus};
use crate::control::unicycle::{
    Aicardi, Astolfi, ConstantInputReference, Kanayama, Pose, ReferenceSample, Samson, WheelLimits,
    pose_in_goal_frame,
};
use crate::control::wrap_angle;
use crate::error::{Error, Result};
use crate::mobile::wheeled::reduced_forward_dynamics_crba;
use crate::mobile::{WheeledData, WheeledModel};
use crate::multibody::FrameIndex;
use crate::planning::trajectory::TrajectoryPoint;
use crate::sim::closed_loop::{FeedbackLaw, Observation, SaturationFlags};
use crate::sim::computed_torque::ComputedTorque;
use nalgebra::{DMatrix, DVector, SMatrix, SVector};

/// A time-sampled platform trajectory (from [`crate::planning::trajectory`]),
/// interpolated linearly between samples (the heading along the shorter arc) and held
/// at rest at its last sample.
#[derive(Clone, Debug)]
pub struct SampledTrajectory {
    points: Vec<TrajectoryPoint>,
}

impl SampledTrajectory {
    /// Wraps samples with strictly increasing times.
    ///
    /// # Errors
    /// No sample, or times not strictly increasing.
    pub fn new(points: Vec<TrajectoryPoint>) -> Result<Self> {
        if points.is_empty() {
            return Err(Error::invalid("trajectory", "no samples"));
        }
        if points.windows(2).any(|w| w[1].t <= w[0].t) {
            return Err(Error::invalid(
                "trajectory",
                "sample times must be strictly increasing",
            ));
        }
        Ok(Self { points })
    }

    /// The samples.
    #[must_use]
    pub fn points(&self) -> &[TrajectoryPoint] {
        &self.points
    }

    /// The reference sample at time t.
    #[must_use]
    pub fn at(&self, t: f64) -> ReferenceSample {
        let p = &self.points;
        let last = p[p.len() - 1];
        if t >= last.t {
            return ReferenceSample {
                pose: [last.x, last.y, last.theta],
                v: 0.0,
                w: 0.0,
            };
        }
        let i = p.partition_point(|s| s.t <= t);
        if i == 0 {
            let f = p[0];
            return ReferenceSample {
                pose: [f.x, f.y, f.theta],
                v: f.v,
                w: f.omega,
            };
        }
        let (a, b) = (p[i - 1], p[i]);
        let s = (t - a.t) / (b.t - a.t);
        let lerp = |x: f64, y: f64| x + s * (y - x);
        ReferenceSample {
            pose: [
                lerp(a.x, b.x),
                lerp(a.y, b.y),
                a.theta + s * wrap_angle(b.theta - a.theta),
            ],
            v: lerp(a.v, b.v),
            w: lerp(a.omega, b.omega),
        }
    }
}

/// What Kanayama's law tracks.
#[derive(Clone, Debug)]
pub enum TrackingReference {
    /// Constant `(v_r, ω_r)` from the origin: the circle of radius `v_r/ω_r`, or a line.
    Constant(ConstantInputReference),
    /// A time-parameterised planned path.
    Sampled(SampledTrajectory),
}

impl TrackingReference {
    /// The sample at time t.
    #[must_use]
    pub fn at(&self, t: f64) -> ReferenceSample {
        match self {
            Self::Constant(c) => c.at(t),
            Self::Sampled(s) => s.at(t),
        }
    }
}

/// The platform law and its reference.
#[derive(Clone, Debug)]
pub enum PlatformLaw {
    /// Kanayama tracking.
    Kanayama(Kanayama, TrackingReference),
    /// Samson's time-varying stabiliser to a goal pose.
    Samson(Samson, Pose),
    /// Astolfi's polar stabiliser.
    Astolfi(Astolfi, Pose),
    /// Aicardi's Lyapunov polar stabiliser.
    Aicardi(Aicardi, Pose),
    /// Regulated pure pursuit of a polyline.
    PurePursuit(Box<PurePursuit>, Vec<[f64; 2]>),
}

/// The inner velocity loop of [`PlatformController`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VelocityServo {
    /// Gain k_v (1/s) of `a = k_v (v_c − v)` on v and ω.
    pub gain: f64,
    /// Arm posture stiffness k_p (1/s²).
    pub arm_kp: f64,
    /// Arm posture damping k_d (1/s).
    pub arm_kd: f64,
}

impl VelocityServo {
    pub(crate) fn validate(&self) -> Result<()> {
        for (n, x) in [
            ("controller.velocity_gain", self.gain),
            ("controller.arm_kp", self.arm_kp),
            ("controller.arm_kd", self.arm_kd),
        ] {
            crate::error::ensure_positive(n, x)?;
        }
        Ok(())
    }
}

fn clip(u: &mut [f64], limit: f64) -> bool {
    let mut hit = false;
    for x in u.iter_mut() {
        if x.abs() > limit {
            *x = x.signum() * limit;
            hit = true;
        }
    }
    hit
}

/// A unicycle law or pure pursuit driving a wheeled URDF robot through an inner
/// computed-torque velocity loop (see the module documentation).
#[derive(Clone, Debug)]
pub struct PlatformController {
    wm: WheeledModel,
    inner: InnerLoop,
    /// The law and its reference.
    pub law: PlatformLaw,
    /// The inner loop.
    pub servo: VelocityServo,
    limits: WheelLimits,
    arm_target: Vec<f64>,
}

/// The inner computed-torque loop on the reduced dynamics shared by the platform laws
/// and the coordinated law: the reduced dynamics of the state, then
/// [`ComputedTorque::inputs`] for a commanded reduced acceleration `a`, wheel torques
/// clipped.
#[derive(Clone, Debug)]
pub(crate) struct InnerLoop {
    wm: WheeledModel,
    wd: WheeledData,
    torque: ComputedTorque,
    q: DVector<f64>,
    v: DVector<f64>,
    acc: DVector<f64>,
    zero_u: Vec<f64>,
}

impl InnerLoop {
    pub(crate) fn new(wm: &WheeledModel, max_wheel_torque: f64) -> Result<Self> {
        let (nq, nr, nu) = (wm.model.nq, wm.nr(), wm.nu());
        let mut bounds = vec![f64::INFINITY; nu];
        bounds[..2].fill(max_wheel_torque);
        Ok(Self {
            wd: WheeledData::new(wm),
            torque: ComputedTorque::new(wm, bounds)?,
            q: DVector::zeros(nq),
            v: DVector::zeros(nr),
            acc: DVector::zeros(nr),
            zero_u: vec![0.0; nu],
            wm: wm.clone(),
        })
    }

    /// Writes the inputs `u` at `(q, v)` for the reduced acceleration
    /// `a_i = accel(i, q_i, v_i)` (`q_i` the configuration of reduced coordinate i for
    /// the arm, 0 for the two platform rates); true when a wheel torque was clipped.
    pub(crate) fn inputs(
        &mut self,
        q: &[f64],
        v: &[f64],
        u: &mut [f64],
        accel: impl Fn(usize, f64, f64) -> f64,
    ) -> Result<bool> {
        self.q.copy_from_slice(q);
        self.v.copy_from_slice(v);
        reduced_forward_dynamics_crba(&self.wm, &mut self.wd, &self.q, &self.v, &self.zero_u)?;
        self.acc[0] = accel(0, 0.0, v[0]);
        self.acc[1] = accel(1, 0.0, v[1]);
        for (j, &dof) in self.wm.arm_dofs().iter().enumerate() {
            self.acc[2 + j] = accel(2 + j, q[dof], v[2 + j]);
        }
        Ok(self.torque.inputs(&self.wd.reduced, &self.acc, u))
    }
}

impl PlatformController {
    /// A controller for `wm`; the arm holds `arm_target` (one value per arm joint);
    /// `max_wheel_speed` (rad/s) and `max_wheel_torque` (N·m) are optional limits.
    ///
    /// # Errors
    /// Non-positive gains or limits, a wrong number of arm targets.
    pub fn new(
        wm: WheeledModel,
        law: PlatformLaw,
        servo: VelocityServo,
        arm_target: Vec<f64>,
        max_wheel_speed: Option<f64>,
        max_wheel_torque: Option<f64>,
    ) -> Result<Self> {
        servo.validate()?;
        crate::error::ensure_len("arm target", wm.nr() - 2, arm_target.len())?;
        crate::error::ensure_finite("arm target", &arm_target)?;
        let limits = WheelLimits::new(
            wm.base.drive,
            max_wheel_speed.unwrap_or(f64::INFINITY),
            max_wheel_torque.unwrap_or(f64::INFINITY),
        )?;
        Ok(Self {
            inner: InnerLoop::new(&wm, limits.max_wheel_torque)?,
            law,
            servo,
            limits,
            arm_target,
            wm,
        })
    }

    /// The axle-midpoint pose `[x, y, θ]` of configuration q (the base origin sits `d`
    /// ahead of it).
    #[must_use]
    pub fn pose(&self, q: &[f64]) -> Pose {
        let d = self.wm.base.drive.d;
        let (s, c) = q[2].sin_cos();
        [q[0] - d * c, q[1] - d * s, q[2]]
    }

    /// The law's `(v, ω)` command at `(t, pose)` (before limits).
    ///
    /// # Errors
    /// As the law.
    pub fn command(&mut self, t: f64, pose: &Pose) -> Result<[f64; 2]> {
        let mut out = [0.0; 2];
        match &mut self.law {
            PlatformLaw::Kanayama(l, r) => l.actuation(t, pose, &r.at(t), &mut out)?,
            PlatformLaw::Samson(l, g) => l.actuation(t, pose, g, &mut out)?,
            PlatformLaw::Astolfi(l, g) => l.actuation(t, pose, g, &mut out)?,
            PlatformLaw::Aicardi(l, g) => l.actuation(t, pose, g, &mut out)?,
            PlatformLaw::PurePursuit(l, p) => l.actuation(t, pose, p, &mut out)?,
        }
        Ok(out)
    }
}

fn dist_to_polyline(p: [f64; 2], path: &[[f64; 2]]) -> f64 {
    let d = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    if path.len() == 1 {
        return d(p, path[0]);
    }
    path.windows(2)
        .map(|w| {
            let (a, b) = (w[0], w[1]);
            let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
            let l2 = dx * dx + dy * dy;
            let s = if l2 > 0.0 {
                (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            d(p, [a[0] + s * dx, a[1] + s * dy])
        })
        .fold(f64::INFINITY, f64::min)
}

impl FeedbackLaw for PlatformController {
    fn nu(&self) -> usize {
        self.wm.nu()
    }

    fn error_names(&self) -> Vec<String> {
        let names: &[&str] = match self.law {
            PlatformLaw::Kanayama(..) => &["e_x [m]", "e_y [m]", "e_theta [rad]"],
            PlatformLaw::PurePursuit(..) => &["cross_track [m]", "goal_distance [m]"],
            _ => &["x_goal [m]", "y_goal [m]", "theta_goal [rad]"],
        };
        names.iter().map(|s| (*s).to_string()).collect()
    }

    fn has_lyapunov(&self) -> bool {
        matches!(
            self.law,
            PlatformLaw::Kanayama(..) | PlatformLaw::Samson(..) | PlatformLaw::Aicardi(..)
        )
    }

    fn control(&mut self, t: f64, q: &[f64], v: &[f64], u: &mut [f64]) -> Result<SaturationFlags> {
        let pose = self.pose(q);
        let mut cmd = self.command(t, &pose)?;
        let speed = self.limits.limit_inputs(&mut cmd).speed;
        let servo = self.servo;
        let target = &self.arm_target;
        let torque = self.inner.inputs(q, v, u, |j, qj, vj| {
            if j < 2 {
                servo.gain * (cmd[j] - vj)
            } else {
                servo.arm_kp * (target[j - 2] - qj) - servo.arm_kd * vj
            }
        })?;
        Ok(SaturationFlags { speed, torque })
    }

    fn observe(&mut self, t: f64, q: &[f64], _v: &[f64], e: &mut [f64]) -> Result<Observation> {
        let pose = self.pose(q);
        let (mut lyapunov, mut lyapunov_rate) = (None, None);
        match &self.law {
            PlatformLaw::Kanayama(l, r) => {
                let s = r.at(t);
                e.copy_from_slice(&Kanayama::error(&pose, &s));
                lyapunov = l.lyapunov(t, &pose, &s);
                lyapunov_rate = l.lyapunov_rate(t, &pose, &s);
            }
            PlatformLaw::Samson(l, g) => {
                goal_error(&pose, g, e);
                lyapunov = l.lyapunov(t, &pose, g);
                lyapunov_rate = l.lyapunov_rate(t, &pose, g);
            }
            PlatformLaw::Astolfi(_, g) => goal_error(&pose, g, e),
            PlatformLaw::Aicardi(l, g) => {
                goal_error(&pose, g, e);
                lyapunov = l.lyapunov(t, &pose, g);
                lyapunov_rate = l.lyapunov_rate(t, &pose, g);
            }
            PlatformLaw::PurePursuit(_, p) => {
                let xy = [pose[0], pose[1]];
                let end = p[p.len() - 1];
                e[0] = dist_to_polyline(xy, p);
                e[1] = (xy[0] - end[0]).hypot(xy[1] - end[1]);
            }
        }
        Ok(Observation {
            lyapunov,
            lyapunov_rate,
        })
    }
}

fn goal_error(pose: &Pose, goal: &Pose, e: &mut [f64]) {
    let p = pose_in_goal_frame(pose, goal);
    e[0] = p[0];
    e[1] = p[1];
    e[2] = wrap_angle(p[2]);
}

/// A 3-D end-effector reference: position, velocity and acceleration at time t.
#[derive(Clone, Debug, PartialEq)]
pub enum PointReference {
    /// From `from` to `to` in `duration` with a quintic (rest-to-rest) time scaling,
    /// then held.
    Line {
        /// Start (m).
        from: [f64; 3],
        /// End (m).
        to: [f64; 3],
        /// Duration (s), > 0.
        duration: f64,
    },
    /// The horizontal circle `c + r (cos φ, sin φ, 0)`, `φ = φ₀ + 2π t / period`.
    Circle {
        /// Centre (m).
        center: [f64; 3],
        /// Radius (m), > 0.
        radius: f64,
        /// Period (s), > 0.
        period: f64,
        /// Phase φ₀ (rad).
        phase: f64,
    },
    /// Through `points` at `times` (strictly increasing, the first ≥ 0), each leg a
    /// quintic rest-to-rest motion; the first point is held before `times[0]`, the last
    /// after the last time.
    Waypoints {
        /// Points (m).
        points: Vec<[f64; 3]>,
        /// Their times (s).
        times: Vec<f64>,
    },
}

/// The quintic rest-to-rest scaling `s(τ) = 10τ³ − 15τ⁴ + 6τ⁵` and its first two
/// derivatives in τ.
fn quintic(tau: f64) -> (f64, f64, f64) {
    let t = tau.clamp(0.0, 1.0);
    let (t2, t3) = (t * t, t * t * t);
    (
        t3 * (10.0 - 15.0 * t + 6.0 * t2),
        30.0 * t2 * (1.0 - 2.0 * t + t2),
        60.0 * t * (1.0 - 3.0 * t + 2.0 * t2),
    )
}

impl PointReference {
    /// Checks finiteness, positive durations and increasing times (field names in errors).
    ///
    /// # Errors
    /// The first bad field.
    pub fn validate(&self) -> Result<()> {
        let pos = crate::error::ensure_positive;
        match self {
            Self::Line { from, to, duration } => {
                crate::error::ensure_finite("reference.from", from)?;
                crate::error::ensure_finite("reference.to", to)?;
                pos("reference.duration", *duration)
            }
            Self::Circle {
                center,
                radius,
                period,
                phase,
            } => {
                crate::error::ensure_finite("reference.center", center)?;
                crate::error::ensure_finite("reference.phase", [phase])?;
                pos("reference.radius", *radius)?;
                pos("reference.period", *period)
            }
            Self::Waypoints { points, times } => {
                if points.is_empty() {
                    return Err(Error::invalid(
                        "reference.points",
                        "need at least one point",
                    ));
                }
                crate::error::ensure_len("reference.times", points.len(), times.len())?;
                for p in points {
                    crate::error::ensure_finite("reference.points", p)?;
                }
                crate::error::ensure_finite("reference.times", times)?;
                if times[0] < 0.0 || times.windows(2).any(|w| w[1] <= w[0]) {
                    return Err(Error::invalid(
                        "reference.times",
                        "must start at >= 0 and be strictly increasing",
                    ));
                }
                Ok(())
            }
        }
    }

    /// `(x_d, ẋ_d, ẍ_d)` at time t.
    #[must_use]
    pub fn at(&self, t: f64) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let leg = |a: &[f64; 3], b: &[f64; 3], t0: f64, dur: f64| {
            let (s, sd, sdd) = quintic((t - t0) / dur);
            let (mut x, mut v, mut acc) = ([0.0; 3], [0.0; 3], [0.0; 3]);
            for k in 0..3 {
                let d = b[k] - a[k];
                x[k] = a[k] + s * d;
                v[k] = sd * d / dur;
                acc[k] = sdd * d / (dur * dur);
            }
            (x, v, acc)
        };
        match self {
            Self::Line { from, to, duration } => leg(from, to, 0.0, *duration),
            Self::Circle {
                center,
                radius,
                period,
                phase,
            } => {
                let w = std::f64::consts::TAU / period;
                let (s, c) = (phase + w * t).sin_cos();
                (
                    [center[0] + radius * c, center[1] + radius * s, center[2]],
                    [-radius * w * s, radius * w * c, 0.0],
                    [-radius * w * w * c, -radius * w * w * s, 0.0],
                )
            }
            Self::Waypoints { points, times } => {
                let n = points.len();
                if n == 1 || t <= times[0] {
                    return (points[0], [0.0; 3], [0.0; 3]);
                }
                if t >= times[n - 1] {
                    return (points[n - 1], [0.0; 3], [0.0; 3]);
                }
                let i = times.partition_point(|&s| s <= t);
                leg(
                    &points[i - 1],
                    &points[i],
                    times[i - 1],
                    times[i] - times[i - 1],
                )
            }
        }
    }
}

/// Gains of [`OscController`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OscGains {
    /// Task stiffness k_p (1/s²).
    pub kp: f64,
    /// Task damping k_v (1/s).
    pub kv: f64,
    /// Null-space posture stiffness on the arm joints (N·m/rad).
    pub posture_kp: f64,
    /// Null-space damping on every reduced velocity (N·m·s/rad).
    pub posture_kd: f64,
}

/// Operational-space control of a frame's position on a wheeled robot, through the
/// reduced model (see the module documentation).
#[derive(Clone, Debug)]
pub struct OscController {
    wm: WheeledModel,
    rod: ReducedOscData,
    frame: FrameIndex,
    /// The end-effector reference.
    pub reference: PointReference,
    /// Gains.
    pub gains: OscGains,
    torque: ComputedTorque,
    posture: Vec<f64>,
    q: DVector<f64>,
    v: DVector<f64>,
    zero_a: DVector<f64>,
    tau0: DVector<f64>,
    tau_r: DVector<f64>,
}

impl OscController {
    /// OSC of the position of `frame` (named) of `wm`; the null space holds the arm at
    /// `posture` (one value per arm joint); `max_torque` clips every input.
    ///
    /// # Errors
    /// An unknown frame, bad gains, reference or posture.
    pub fn new(
        wm: WheeledModel,
        frame: &str,
        reference: PointReference,
        gains: OscGains,
        posture: Vec<f64>,
        max_torque: Option<f64>,
    ) -> Result<Self> {
        let fid = wm.model.frame_id(frame)?;
        reference.validate()?;
        check_osc_gains(&gains, max_torque)?;
        crate::error::ensure_len("posture", wm.nr() - 2, posture.len())?;
        crate::error::ensure_finite("posture", &posture)?;
        let (nq, nr, nu) = (wm.model.nq, wm.nr(), wm.nu());
        Ok(Self {
            rod: ReducedOscData::new(&wm, &[0, 1, 2]),
            frame: fid,
            reference,
            gains,
            torque: ComputedTorque::new(&wm, vec![max_torque.unwrap_or(f64::INFINITY); nu])?,
            posture,
            q: DVector::zeros(nq),
            v: DVector::zeros(nr),
            zero_a: DVector::zeros(3),
            tau0: DVector::zeros(nr),
            tau_r: DVector::zeros(nr),
            wm,
        })
    }

    /// OSC update at `(q, v)` with a zero task acceleration; returns the frame position
    /// and its velocity `J_r v_r`.
    fn update(&mut self, q: &[f64], v: &[f64]) -> Result<([f64; 3], [f64; 3])> {
        self.q.copy_from_slice(q);
        self.v.copy_from_slice(v);
        let g = self.gains;
        self.tau0[0] = -g.posture_kd * v[0];
        self.tau0[1] = -g.posture_kd * v[1];
        for (j, &dof) in self.wm.arm_dofs().iter().enumerate() {
            self.tau0[2 + j] = g.posture_kp * (self.posture[j] - q[dof]) - g.posture_kd * v[2 + j];
        }
        osc_reduced(
            &self.wm,
            &mut self.rod,
            self.frame,
            &self.q,
            &self.v,
            &self.zero_a,
            &self.tau0,
        )?;
        let p = self.rod.wheeled.data.world_from_frame[self.frame.0].translation;
        Ok(([p[0], p[1], p[2]], task_velocity(&self.rod.osc.jacobian, v)))
    }
}

impl FeedbackLaw for OscController {
    fn nu(&self) -> usize {
        self.wm.nu()
    }

    fn error_names(&self) -> Vec<String> {
        position_error_names()
    }

    fn has_lyapunov(&self) -> bool {
        true
    }

    fn control(&mut self, t: f64, q: &[f64], v: &[f64], u: &mut [f64]) -> Result<SaturationFlags> {
        let (x, xdot) = self.update(q, v)?;
        osc_torque(
            &self.rod.osc,
            &self.gains,
            &self.reference,
            t,
            x,
            xdot,
            self.tau_r.as_mut_slice(),
        );
        let torque = self
            .torque
            .inputs_from_reduced_force(self.tau_r.as_slice(), u);
        Ok(SaturationFlags {
            speed: false,
            torque,
        })
    }

    fn observe(&mut self, t: f64, q: &[f64], v: &[f64], e: &mut [f64]) -> Result<Observation> {
        let (x, xdot) = self.update(q, v)?;
        Ok(osc_observation(&self.gains, &self.reference, t, x, xdot, e))
    }
}

/// The task-space law of [`M5TaskController`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TaskLaw {
    /// PD+ (chapter 5.122 corrected).
    PdPlus,
    /// Task-space computed torque.
    ComputedTorque,
    /// The chapter's decoupled control (platform block `[x_B, y_B]`, arm block the
    /// other three coordinates) with the given treatment of the cross terms.
    Decoupled(Coupling),
}

/// The chapter's task-space laws on m5, tracking `x_d(t) = x_ref + amp ⊙ sin(ω ⊙ t)` in
/// the task coordinates `x = [x_B, y_B, x_E − x_B, y_E − y_B, z_E]`.
///
/// V: PD+ reports `W = ½ ėᵀ Hx ė + ½ eᵀ Kp e` with `Ẇ = −ėᵀ Kd ė`; the computed-torque
/// and decoupled laws report `V = ½ |ė|² + ½ eᵀ Kp e` with the rate `−ėᵀ Kd ė` of the
/// linear error equation `ë + Kd ė + Kp e = 0` they aim at (exact for computed torque
/// and compensated decoupling; for the naive and feed-forward variants the gap between V
/// and `V₀ + ∫ V̇` shows the neglected coupling).
#[derive(Clone, Debug)]
pub struct M5TaskController {
    model: MobileManipulator,
    /// The law.
    pub law: TaskLaw,
    /// `x_ref`.
    pub x_ref: SVector<f64, 5>,
    /// Amplitudes.
    pub amp: SVector<f64, 5>,
    /// Angular frequencies (rad/s).
    pub omega: SVector<f64, 5>,
    /// Kp (diagonal).
    pub kp: SMatrix<f64, 5, 5>,
    /// Kd (diagonal; K_v of computed torque).
    pub kd: SMatrix<f64, 5, 5>,
    max_torque: Option<f64>,
}

impl M5TaskController {
    /// Diagonal gains `kp`, `kd` (each > 0) and the sinusoidal reference.
    ///
    /// # Errors
    /// Non-positive or non-finite gains, non-finite reference values, a bad torque limit.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        model: MobileManipulator,
        law: TaskLaw,
        x_ref: [f64; 5],
        amp: [f64; 5],
        omega: [f64; 5],
        kp: [f64; 5],
        kd: [f64; 5],
        max_torque: Option<f64>,
    ) -> Result<Self> {
        crate::error::ensure_finite("reference.x_ref", &x_ref)?;
        crate::error::ensure_finite("reference.amplitude", &amp)?;
        crate::error::ensure_finite("reference.omega", &omega)?;
        for (n, g) in [("controller.kp", kp), ("controller.kd", kd)] {
            for (i, &x) in g.iter().enumerate() {
                crate::error::ensure_positive(&format!("{n}[{i}]"), x)?;
            }
        }
        if let Some(m) = max_torque {
            crate::error::ensure_positive("controller.max_torque", m)?;
        }
        Ok(Self {
            model,
            law,
            x_ref: SVector::from(x_ref),
            amp: SVector::from(amp),
            omega: SVector::from(omega),
            kp: SMatrix::from_diagonal(&SVector::from(kp)),
            kd: SMatrix::from_diagonal(&SVector::from(kd)),
            max_torque,
        })
    }

    /// `(x_d, ẋ_d, ẍ_d)` at time t.
    #[must_use]
    pub fn desired(&self, t: f64) -> (SVector<f64, 5>, SVector<f64, 5>, SVector<f64, 5>) {
        let s = self.omega.map(|w| (w * t).sin());
        let c = self.omega.map(|w| (w * t).cos());
        let aw = self.amp.component_mul(&self.omega);
        (
            self.x_ref + self.amp.component_mul(&s),
            aw.component_mul(&c),
            -aw.component_mul(&self.omega).component_mul(&s),
        )
    }

    fn state(q: &[f64], v: &[f64]) -> (SVector<f64, 6>, SVector<f64, 5>) {
        (SVector::from_column_slice(q), SVector::from_column_slice(v))
    }
}

impl FeedbackLaw for M5TaskController {
    fn nu(&self) -> usize {
        5
    }

    fn error_names(&self) -> Vec<String> {
        ["e_xB [m]", "e_yB [m]", "e_dxE [m]", "e_dyE [m]", "e_zE [m]"]
            .iter()
            .map(|s| (*s).to_string())
            .collect()
    }

    fn has_lyapunov(&self) -> bool {
        true
    }

    fn control(&mut self, t: f64, q: &[f64], v: &[f64], u: &mut [f64]) -> Result<SaturationFlags> {
        let (q, v) = Self::state(q, v);
        let tt = self.model.task_terms(&q, &v)?;
        let (xd, vd, ad) = self.desired(t);
        let f = match self.law {
            TaskLaw::PdPlus => {
                pd_plus(
                    &tt.hx,
                    &tt.bv,
                    &tt.bg,
                    &(tt.x - xd),
                    &(tt.xdot - vd),
                    &vd,
                    &ad,
                    &self.kp,
                    &self.kd,
                )
                .0
            }
            TaskLaw::ComputedTorque => computed_torque(
                &tt.hx,
                &(tt.bv * tt.xdot),
                &tt.bg,
                &(xd - tt.x),
                &(vd - tt.xdot),
                &ad,
                &self.kp,
                &self.kd,
            ),
            TaskLaw::Decoupled(c) => decoupled::<5, 2>(
                &tt.hx,
                &tt.bv,
                &tt.bg,
                &tt.xdot,
                &(xd - tt.x),
                &(vd - tt.xdot),
                &ad,
                &self.kp,
                &self.kd,
                c,
            ),
        };
        let sol = tt
            .actuation
            .lu()
            .solve(&(tt.a.transpose() * f))
            .ok_or_else(|| Error::Singular {
                what: "actuator map N_Cᵀ S".into(),
                detail: None,
            })?;
        u.copy_from_slice(sol.as_slice());
        let torque = self.max_torque.is_some_and(|m| clip(u, m));
        Ok(SaturationFlags {
            speed: false,
            torque,
        })
    }

    fn observe(&mut self, t: f64, q: &[f64], v: &[f64], e: &mut [f64]) -> Result<Observation> {
        let (q, v) = Self::state(q, v);
        let tt = self.model.task_terms(&q, &v)?;
        let (xd, vd, _) = self.desired(t);
        let err = tt.x - xd;
        let ed = tt.xdot - vd;
        e.copy_from_slice(err.as_slice());
        let pot = 0.5 * err.dot(&(self.kp * err));
        let kin = match self.law {
            TaskLaw::PdPlus => 0.5 * ed.dot(&(tt.hx * ed)),
            _ => 0.5 * ed.dot(&ed),
        };
        Ok(Observation {
            lyapunov: Some(kin + pot),
            lyapunov_rate: Some(-ed.dot(&(self.kd * ed))),
        })
    }
}

/// Operational-space control of a frame's position on a fixed-base arm
/// ([`crate::control::osc::osc_fixed_base`]), plant [`crate::sim::fixed_base::FixedBaseSystem`]:
/// `a_des = ẍ_d + k_v (ẋ_d − ẋ) + k_p (x_d − x)`, null-space posture
/// `τ₀ = posture_kp (q* − q) − posture_kd q̇`; V as [`OscController`].
#[derive(Clone, Debug)]
pub struct FixedOscController {
    model: crate::multibody::Model,
    data: crate::multibody::Data,
    od: crate::control::osc::OscData,
    frame: FrameIndex,
    /// The end-effector reference.
    pub reference: PointReference,
    /// Gains.
    pub gains: OscGains,
    max_torque: Option<f64>,
    posture: Vec<f64>,
    q: DVector<f64>,
    v: DVector<f64>,
    zero_a: DVector<f64>,
    tau0: DVector<f64>,
}

impl FixedOscController {
    /// OSC of the position of `frame` (named) of `model`; the null space holds `posture`
    /// (one value per joint); `max_torque` clips every input.
    ///
    /// # Errors
    /// An unknown frame, bad gains, reference or posture.
    pub fn new(
        model: crate::multibody::Model,
        frame: &str,
        reference: PointReference,
        gains: OscGains,
        posture: Vec<f64>,
        max_torque: Option<f64>,
    ) -> Result<Self> {
        let fid = model.frame_id(frame)?;
        reference.validate()?;
        check_osc_gains(&gains, max_torque)?;
        crate::error::ensure_len("posture", model.nv, posture.len())?;
        crate::error::ensure_finite("posture", &posture)?;
        let (nq, nv) = (model.nq, model.nv);
        Ok(Self {
            data: crate::multibody::Data::new(&model),
            od: crate::control::osc::OscData::new(nv, &[0, 1, 2]),
            frame: fid,
            reference,
            gains,
            max_torque,
            posture,
            q: DVector::zeros(nq),
            v: DVector::zeros(nv),
            zero_a: DVector::zeros(3),
            tau0: DVector::zeros(nv),
            model,
        })
    }

    fn update(&mut self, q: &[f64], v: &[f64]) -> Result<([f64; 3], [f64; 3])> {
        self.q.copy_from_slice(q);
        self.v.copy_from_slice(v);
        let g = self.gains;
        for i in 0..self.model.nv {
            self.tau0[i] = g.posture_kp * (self.posture[i] - q[i]) - g.posture_kd * v[i];
        }
        crate::control::osc::osc_fixed_base(
            &self.model,
            &mut self.data,
            &mut self.od,
            self.frame,
            &self.q,
            &self.v,
            &self.zero_a,
            &self.tau0,
        )?;
        let p = self.data.world_from_frame[self.frame.0].translation;
        Ok(([p[0], p[1], p[2]], task_velocity(&self.od.jacobian, v)))
    }
}

/// `J v` for the three position rows of a task Jacobian.
fn task_velocity(j: &DMatrix<f64>, v: &[f64]) -> [f64; 3] {
    let mut xd = [0.0; 3];
    for (k, x) in xd.iter_mut().enumerate() {
        *x = (0..j.ncols()).map(|c| j[(k, c)] * v[c]).sum();
    }
    xd
}

/// The error names of a frame-position task.
fn position_error_names() -> Vec<String> {
    ["e_x [m]", "e_y [m]", "e_z [m]"]
        .iter()
        .map(|s| (*s).to_string())
        .collect()
}

fn check_osc_gains(gains: &OscGains, max_torque: Option<f64>) -> Result<()> {
    for (n, x) in [
        ("controller.kp", gains.kp),
        ("controller.kv", gains.kv),
        ("controller.posture_kp", gains.posture_kp),
        ("controller.posture_kd", gains.posture_kd),
    ] {
        if !(x.is_finite() && x >= 0.0) {
            return Err(Error::invalid(
                n,
                format!("must be >= 0 and finite, got {x}"),
            ));
        }
    }
    if let Some(m) = max_torque {
        crate::error::ensure_positive("controller.max_torque", m)?;
    }
    Ok(())
}

/// `a = ẍ_d + k_v (ẋ_d − ẋ) + k_p (x_d − x)`, then `τ = τ(a = 0) + Jᵀ Λ a` into `u`.
fn osc_torque(
    od: &crate::control::osc::OscData,
    gains: &OscGains,
    reference: &PointReference,
    t: f64,
    x: [f64; 3],
    xdot: [f64; 3],
    u: &mut [f64],
) {
    let (xd, vd, ad) = reference.at(t);
    let mut a = [0.0; 3];
    for k in 0..3 {
        a[k] = ad[k] + gains.kv * (vd[k] - xdot[k]) + gains.kp * (xd[k] - x[k]);
    }
    let mut la = [0.0; 3];
    for (i, l) in la.iter_mut().enumerate() {
        *l = (0..3).map(|k| od.task_inertia[(i, k)] * a[k]).sum();
    }
    for (c, uc) in u.iter_mut().enumerate() {
        *uc = od.torque[c] + (0..3).map(|k| od.jacobian[(k, c)] * la[k]).sum::<f64>();
    }
}

fn osc_observation(
    gains: &OscGains,
    reference: &PointReference,
    t: f64,
    x: [f64; 3],
    xdot: [f64; 3],
    e: &mut [f64],
) -> Observation {
    let (xd, vd, _) = reference.at(t);
    let (mut ee, mut ed) = (0.0, 0.0);
    for k in 0..3 {
        e[k] = xd[k] - x[k];
        let d = vd[k] - xdot[k];
        ee += e[k] * e[k];
        ed += d * d;
    }
    Observation {
        lyapunov: Some(0.5 * ed + 0.5 * gains.kp * ee),
        lyapunov_rate: Some(-gains.kv * ed),
    }
}

impl FeedbackLaw for FixedOscController {
    fn nu(&self) -> usize {
        self.model.nv
    }

    fn error_names(&self) -> Vec<String> {
        position_error_names()
    }

    fn has_lyapunov(&self) -> bool {
        true
    }

    fn control(&mut self, t: f64, q: &[f64], v: &[f64], u: &mut [f64]) -> Result<SaturationFlags> {
        let (x, xdot) = self.update(q, v)?;
        osc_torque(&self.od, &self.gains, &self.reference, t, x, xdot, u);
        let torque = self.max_torque.is_some_and(|m| clip(u, m));
        Ok(SaturationFlags {
            speed: false,
            torque,
        })
    }

    fn observe(&mut self, t: f64, q: &[f64], v: &[f64], e: &mut [f64]) -> Result<Observation> {
        let (x, xdot) = self.update(q, v)?;
        Ok(osc_observation(&self.gains, &self.reference, t, x, xdot, e))
    }
}

//! [`PlatformController`]: a unicycle law (Kanayama, Samson, Astolfi, Aicardi) or
//! regulated pure pursuit driving a wheeled URDF robot through an inner computed-torque
//! velocity loop on the reduced dynamics ([`InnerLoop`], shared with the coordinated law).

use super::references::TrackingReference;
use crate::control::Controller;
use crate::control::pursuit::PurePursuit;
use crate::control::unicycle::{
    Aicardi, Astolfi, Kanayama, Pose, Samson, WheelLimits, pose_in_goal_frame,
};
use crate::control::wrap_angle;
use crate::error::Result;
use crate::mobile::wheeled::reduced_forward_dynamics_crba;
use crate::mobile::{WheeledData, WheeledModel};
use crate::sim::closed_loop::{FeedbackLaw, Observation, SaturationFlags};
use crate::sim::computed_torque::ComputedTorque;
use nalgebra::DVector;

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

//! Coordinated base/arm control ([`crate::control::coordinated`], theory section 2.6) of a
//! wheeled URDF robot in closed loop.
//!
//! Two arm joints that move the end effector in the horizontal plane (a turret and an
//! elbow, say) are coordinated with the platform: the end effector tracks its reference
//! in the horizontal plane, `(p_E,d − p_E)' = −K_E (p_E,d − p_E)`, while the platform
//! keeps the end effector's position relative to the axle midpoint at its value `y*` in
//! the preferred arm posture, `(y* − y)' = −K_Y (y* − y)`
//! ([`crate::control::coordinated::coordinated_rates`], on the measured state: the frame's
//! position and its reduced Jacobian `J N_C`). The other arm joints hold the preferred
//! posture. The law's rates `[v, ω, q̇_a, q̇_b]` (wheel speeds limited through the wheel
//! map) are tracked by the inner computed-torque loop of
//! [`crate::sim::feedback::PlatformController`]: `Qr = Mr a + (cr + Gr)`,
//! `a = k_v (u_cmd − u)` on the four coordinated rates, `k_p (q* − q) − k_d q̇` on the
//! other arm joints, wheel torques clipped.
//!
//! Reported: the errors `p_E,d − p_E` (x, y) and `y* − y`; the law's own
//! `V = ½|p_E,d − p_E|² + ½|y* − y|²` with its rate `V̇ = −K_E|p_E,d − p_E|² − K_Y|y* − y|²`
//! (exact for the kinematic law; the inner loop's lag shows as the gap); and the signal
//! `manipulability`, `|det|` of the 2 × 2 horizontal Jacobian of the two coordinated
//! joints (the planar 2R's `l1 l2 |sin q2|`). The end effector's height is not
//! controlled: it follows from the arm joints.

use crate::control::coordinated::{
    MeasuredPlanarArm, PointReference as PlanarReference, coordinated_rates,
};
use crate::control::unicycle::WheelLimits;
use crate::error::{Error, Result};
use crate::kinematics::{ReferenceFrame, frame_jacobian};
use crate::mobile::wheeled::admissible_velocity_basis;
use crate::mobile::{WheeledData, WheeledModel};
use crate::multibody::FrameIndex;
use crate::sim::closed_loop::{FeedbackLaw, Observation, SaturationFlags};
use crate::sim::feedback::{InnerLoop, PointReference, VelocityServo};
use nalgebra::DVector;

/// Gains of the coordinated law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoordinatedGains {
    /// End-effector gain K_E (1/s), > 0.
    pub k_e: f64,
    /// Relative-output gain K_Y (1/s), > 0.
    pub k_y: f64,
}

/// The coordinated base/arm law on a wheeled URDF robot (see the module documentation).
#[derive(Clone, Debug)]
pub struct CoordinatedController {
    wm: WheeledModel,
    wd: WheeledData,
    frame: FrameIndex,
    /// Positions of the two coordinated joints among the arm joints.
    joints: [usize; 2],
    /// The end-effector reference (its horizontal part is tracked).
    pub reference: PointReference,
    /// Gains.
    pub gains: CoordinatedGains,
    /// The inner loop.
    pub servo: VelocityServo,
    limits: WheelLimits,
    posture: Vec<f64>,
    y_star: [f64; 2],
    w_star: f64,
    inner: InnerLoop,
    q: DVector<f64>,
}

impl CoordinatedController {
    /// Coordinates the platform of `wm` with the arm joints `joints` (names) so that
    /// `frame` tracks `reference` in the horizontal plane; `posture` (one value per arm
    /// joint) is the preferred arm posture, which defines `y*` and is held by the other
    /// arm joints; `max_wheel_speed` (rad/s) and `max_wheel_torque` (N·m) are optional.
    ///
    /// # Errors
    /// An unknown frame or joint, a joint that is not an arm joint, the same joint twice,
    /// non-positive gains or limits, a bad reference or posture, a preferred posture where
    /// the law is singular (the end effector over the axle line, or the two joints unable
    /// to move it in the plane).
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        wm: WheeledModel,
        frame: &str,
        joints: [&str; 2],
        reference: PointReference,
        gains: CoordinatedGains,
        posture: Vec<f64>,
        servo: VelocityServo,
        max_wheel_speed: Option<f64>,
        max_wheel_torque: Option<f64>,
    ) -> Result<Self> {
        let fid = wm.model.frame_id(frame)?;
        reference.validate()?;
        servo.validate()?;
        for (n, x) in [
            ("controller.gains.K_E", gains.k_e),
            ("controller.gains.K_Y", gains.k_y),
        ] {
            crate::error::ensure_positive(n, x)?;
        }
        let mut idx = [0usize; 2];
        for (k, name) in joints.iter().enumerate() {
            let j = wm.model.joint_id(name)?;
            let dof = wm.model.idx_v[j.0];
            idx[k] = wm
                .arm_dofs()
                .iter()
                .position(|&d| d == dof && wm.model.nvs[j.0] == 1)
                .ok_or_else(|| {
                    Error::invalid(
                        "controller.joints",
                        format!("{name} is not a one-degree-of-freedom arm joint"),
                    )
                })?;
        }
        if idx[0] == idx[1] {
            return Err(Error::invalid(
                "controller.joints",
                "name two different arm joints",
            ));
        }
        crate::error::ensure_len("controller.posture", wm.nr() - 2, posture.len())?;
        crate::error::ensure_finite("controller.posture", &posture)?;
        let limits = WheelLimits::new(
            wm.base.drive,
            max_wheel_speed.unwrap_or(f64::INFINITY),
            max_wheel_torque.unwrap_or(f64::INFINITY),
        )?;
        let nq = wm.model.nq;
        let mut me = Self {
            inner: InnerLoop::new(&wm, limits.max_wheel_torque)?,
            wd: WheeledData::new(&wm),
            frame: fid,
            joints: idx,
            reference,
            gains,
            servo,
            limits,
            posture,
            y_star: [0.0; 2],
            w_star: 0.0,
            q: DVector::zeros(nq),
            wm,
        };
        // y* from the preferred posture (y does not depend on the platform pose)
        let mut q_star = vec![0.0; nq];
        for (k, &d) in me.wm.arm_dofs().iter().enumerate() {
            q_star[d] = me.posture[k];
        }
        let (m, w) = me.measure(&q_star);
        me.y_star = m.y;
        me.w_star = w;
        let probe = PlanarReference {
            p: m.p_e,
            v: [0.0; 2],
        };
        coordinated_rates(&m, me.y_star, &probe, gains.k_e, gains.k_y).map_err(|e| {
            Error::invalid(
                "controller.posture",
                format!("the preferred posture is singular for the coordinated law: {e}"),
            )
        })?;
        Ok(me)
    }

    /// `y*`: the end effector relative to the axle midpoint (platform frame) in the
    /// preferred posture.
    #[must_use]
    pub fn y_star(&self) -> [f64; 2] {
        self.y_star
    }

    /// The manipulability signal in the preferred posture.
    #[must_use]
    pub fn preferred_manipulability(&self) -> f64 {
        self.w_star
    }

    /// The measured state the law needs at configuration `q`, and the manipulability
    /// `|det|` of the two coordinated joints' horizontal Jacobian.
    fn measure(&mut self, q: &[f64]) -> (MeasuredPlanarArm, f64) {
        self.q.copy_from_slice(q);
        let wd = &mut self.wd;
        frame_jacobian(
            &self.wm.model,
            &mut wd.data,
            &self.q,
            self.frame,
            ReferenceFrame::LocalWorldAligned,
            &mut wd.jacobian,
        );
        admissible_velocity_basis(&self.wm, &self.q, &mut wd.basis);
        let p = wd.data.world_from_frame[self.frame.0].translation;
        let (jac, basis) = (&wd.jacobian, &wd.basis);
        let arm = self.wm.arm_dofs();
        let mut j = [[0.0; 4]; 2];
        for (k, row) in j.iter_mut().enumerate() {
            for c in 0..2 {
                row[c] = (0..self.wm.nv()).map(|i| jac[(k, i)] * basis[(i, c)]).sum();
            }
            row[2] = jac[(k, arm[self.joints[0]])];
            row[3] = jac[(k, arm[self.joints[1]])];
        }
        let d = self.wm.base.drive.d;
        let (sn, c) = q[2].sin_cos();
        let pa = [q[0] - d * c, q[1] - d * sn];
        let rel = [p[0] - pa[0], p[1] - pa[1]];
        let y = [c * rel[0] + sn * rel[1], -sn * rel[0] + c * rel[1]];
        let w = (j[0][2] * j[1][3] - j[0][3] * j[1][2]).abs();
        (
            MeasuredPlanarArm {
                heading: q[2],
                p_e: [p[0], p[1]],
                y,
                jacobian: j,
            },
            w,
        )
    }

    fn planar_reference(&self, t: f64) -> PlanarReference {
        let (p, v, _) = self.reference.at(t);
        PlanarReference {
            p: [p[0], p[1]],
            v: [v[0], v[1]],
        }
    }

    fn errors(&self, m: &MeasuredPlanarArm, r: &PlanarReference) -> [f64; 4] {
        [
            r.p[0] - m.p_e[0],
            r.p[1] - m.p_e[1],
            self.y_star[0] - m.y[0],
            self.y_star[1] - m.y[1],
        ]
    }
}

impl FeedbackLaw for CoordinatedController {
    fn nu(&self) -> usize {
        self.wm.nu()
    }

    fn error_names(&self) -> Vec<String> {
        [
            "e_x [m]",
            "e_y [m]",
            "y_star_x - y_x [m]",
            "y_star_y - y_y [m]",
        ]
        .iter()
        .map(|s| (*s).to_string())
        .collect()
    }

    fn has_lyapunov(&self) -> bool {
        true
    }

    fn control(&mut self, t: f64, q: &[f64], v: &[f64], u: &mut [f64]) -> Result<SaturationFlags> {
        let (m, _) = self.measure(q);
        let r = self.planar_reference(t);
        let rates = coordinated_rates(&m, self.y_star, &r, self.gains.k_e, self.gains.k_y)
            .map_err(|e| e.singular_at_time(t))?;
        let mut cmd = [rates[0], rates[1]];
        let speed = self.limits.limit_inputs(&mut cmd).speed;
        let (servo, joints, posture) = (self.servo, self.joints, &self.posture);
        let torque = self.inner.inputs(q, v, u, |i, qi, vi| {
            if i < 2 {
                servo.gain * (cmd[i] - vi)
            } else if i - 2 == joints[0] {
                servo.gain * (rates[2] - vi)
            } else if i - 2 == joints[1] {
                servo.gain * (rates[3] - vi)
            } else {
                servo.arm_kp * (posture[i - 2] - qi) - servo.arm_kd * vi
            }
        })?;
        Ok(SaturationFlags { speed, torque })
    }

    fn observe(&mut self, t: f64, q: &[f64], _v: &[f64], e: &mut [f64]) -> Result<Observation> {
        let (m, _) = self.measure(q);
        let r = self.planar_reference(t);
        let err = self.errors(&m, &r);
        e.copy_from_slice(&err);
        let ee = err[0] * err[0] + err[1] * err[1];
        let ey = err[2] * err[2] + err[3] * err[3];
        Ok(Observation {
            lyapunov: Some(0.5 * (ee + ey)),
            lyapunov_rate: Some(-self.gains.k_e * ee - self.gains.k_y * ey),
        })
    }

    fn signal_names(&self) -> Vec<String> {
        vec!["manipulability [m^2]".to_string()]
    }

    fn signals(&mut self, _t: f64, q: &[f64], _v: &[f64], out: &mut [f64]) -> Result<()> {
        out[0] = self.measure(q).1;
        Ok(())
    }
}

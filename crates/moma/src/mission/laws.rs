//! The mission's control laws on the measured state, writing the desired reduced
//! accelerations that the computed torque turns into torques: the platform's (Kanayama
//! tracking on drive, the arrive law onto the goal), the reach's (the end effector on its
//! minimum-jerk segment) and the pick's arm law, with their gains and guards
//! ([`RunSettings`]); the goal test and the end-effector kinematics they read.

use nalgebra::{DVector, Matrix3, Vector2, Vector3};

use super::arm_motion::EeTrajectory;
use super::reference::{RefSample, axle_pose, base_reference};
use super::scenario::{GoalSpec, Mission};
use super::workspace::{Actuators, Workspace};
use crate::control::unicycle::{Aicardi, Kanayama, ReferenceSample};
use crate::control::wrap_angle;
use crate::error::Result;
use crate::kinematics::{ReferenceFrame, frame_acceleration_bias, frame_jacobian_from_kinematics};
use crate::mobile::WheeledModel;
use crate::mobile::wheeled::admissible_velocity_basis_dot;
use crate::stability::AccelerationLimits;

/// The run's settings (not a control law: the laws are Kanayama, Aicardi and the computed
/// torque it holds): sizes, the goal, the gains and guards of the laws, the actuators, the
/// obstacle schedule; fixed for the run but the time limit, which a pick's drive on
/// extends.
pub(super) struct RunSettings {
    pub(super) nq: usize,
    pub(super) nr: usize,
    pub(super) na: usize,
    pub(super) h: f64,
    pub(super) time_limit: f64,
    pub(super) rec_every: usize,
    pub(super) r_foot: f64,
    /// The base frame's goal pose.
    pub(super) goal: [f64; 3],
    /// The unicycle point the platform is planned and tracked by: the driven-axle
    /// midpoint, `d` behind the base frame origin.
    pub(super) d: f64,
    pub(super) goal_axle: [f64; 3],
    pub(super) arm: Vec<usize>,
    /// The transport posture as a full configuration.
    pub(super) q_t: DVector<f64>,
    pub(super) kan: Kanayama,
    /// The arrive phase's posture law onto the axle's goal pose.
    pub(super) arrive: Aicardi,
    /// The goal's position tolerance (m).
    pub(super) pos_tol: f64,
    pub(super) kx: f64,
    pub(super) ks: f64,
    pub(super) wn: f64,
    pub(super) wt: f64,
    pub(super) v_max: f64,
    pub(super) omega_max: f64,
    pub(super) a_guard_f: f64,
    pub(super) a_guard_b: f64,
    pub(super) alpha_guard: f64,
    pub(super) act: Actuators,
    pub(super) chain: Vec<usize>,
    /// (index, time) of the obstacles in the order they appear.
    pub(super) obstacles: Vec<(usize, f64)>,
    /// A `[task]`'s group joints as arm slots (indices into `arm`).
    pub(super) group_slots: Vec<usize>,
}

impl RunSettings {
    #[allow(clippy::too_many_arguments)]
    pub(super) fn new(
        m: &Mission,
        wm: &WheeledModel,
        goal: &GoalSpec,
        tip: &AccelerationLimits,
        act: Actuators,
        time_limit: f64,
        rec_every: usize,
    ) -> Result<Self> {
        let f = &m.file;
        let model = &wm.model;
        let arm = wm.arm_dofs().to_vec();
        let mut q_t = DVector::zeros(model.nq);
        for (k, &i) in arm.iter().enumerate() {
            q_t[i] = m.transport[k];
        }
        let c = &f.control;
        let kan = Kanayama::new(c.kx, c.ky, c.kth)?;
        let (tip_f, tip_b) = match (tip.forward, tip.backward) {
            (Some(a), Some(b)) => (a, b),
            _ => (0.0, 0.0),
        };
        let mut obstacles: Vec<(usize, f64)> = f
            .obstacles
            .iter()
            .enumerate()
            .map(|(k, o)| (k, o.t))
            .collect();
        obstacles.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        let d = wm.base.drive.d;
        let group_slots = m.task.as_ref().map_or_else(Vec::new, |t| {
            t.group
                .q_index
                .iter()
                .map(|i| {
                    arm.iter()
                        .position(|a| a == i)
                        .expect("the group is the arm chain")
                })
                .collect()
        });
        Ok(Self {
            nq: model.nq,
            nr: wm.nr(),
            na: arm.len(),
            h: f.simulation.dt,
            time_limit,
            rec_every,
            r_foot: m.footprint.radius,
            goal: goal.pose,
            d,
            goal_axle: axle_pose(goal.pose, d),
            arm,
            q_t,
            kan,
            arrive: Aicardi::new(c.kx, 2.0, 1.0)?,
            pos_tol: goal.position_tolerance,
            kx: c.kx,
            ks: c.speed_gain,
            wn: c.arm_frequency,
            wt: c.task_frequency,
            v_max: f.limits.v_max,
            omega_max: f.limits.omega_max,
            a_guard_f: (2.0 * f.limits.a_max).min(0.95 * tip_f),
            a_guard_b: (2.0 * f.limits.a_max).min(0.95 * tip_b),
            alpha_guard: 2.0 * f.limits.alpha_max,
            act,
            chain: super::task::arm_chain(&m.robot, m.ee_frame),
            obstacles,
            group_slots,
        })
    }

    /// Drives on to `goal` with the tip-over guards of `tip` (a `[task]`'s drive on).
    pub(super) fn retarget(&mut self, goal: &GoalSpec, tip: &AccelerationLimits) {
        self.goal = goal.pose;
        self.goal_axle = axle_pose(goal.pose, self.d);
        self.pos_tol = goal.position_tolerance;
        let (tip_f, tip_b) = match (tip.forward, tip.backward) {
            (Some(a), Some(b)) => (a, b),
            _ => (0.0, 0.0),
        };
        self.a_guard_f = self.a_guard_f.min(0.95 * tip_f);
        self.a_guard_b = self.a_guard_b.min(0.95 * tip_b);
    }

    /// A `[task]`'s arm motion: the platform's speeds to zero, each group joint onto the
    /// reference in the workspace (q̈ = q̈_r + 2ωₙ (q̇_r − q̇) + ωₙ² (q_r − q)), the other
    /// arm joints held at the transport posture. Writes the desired accelerations.
    pub(super) fn arm_law(&self, ws: &mut Workspace, v: f64, w: f64) {
        let (ks, wn) = (self.ks, self.wn);
        let a_des = &mut ws.a_des;
        a_des[0] = -ks * v;
        a_des[1] = -ks * w;
        for (k2, &i) in self.arm.iter().enumerate() {
            a_des[2 + k2] = wn * wn * (self.q_t[i] - ws.q_now[i]) - 2.0 * wn * ws.v_now[2 + k2];
        }
        for (j, &k2) in self.group_slots.iter().enumerate() {
            let i = self.arm[k2];
            a_des[2 + k2] = ws.qdd_ref[j]
                + 2.0 * wn * (ws.qd_ref[j] - ws.v_now[2 + k2])
                + wn * wn * (ws.q_ref[i] - ws.q_now[i]);
        }
    }

    /// The reference sample of the goal pose at rest.
    pub(super) fn goal_sample(&self, t: f64) -> RefSample {
        RefSample {
            t,
            x: self.goal[0],
            y: self.goal[1],
            theta: self.goal[2],
            v: 0.0,
            omega: 0.0,
            a: 0.0,
            alpha: 0.0,
        }
    }

    /// Drive and arrive: Kanayama tracking of the axle reference sample `reference`
    /// (arrive: `None`, a proportional law onto the goal), speed commands clipped at the
    /// limits, accelerations within the tip-over guards, the arm held at the transport
    /// posture. Writes the desired accelerations; returns the base frame's reference and
    /// whether a speed command was clipped.
    pub(super) fn platform_law(
        &self,
        reference: Option<RefSample>,
        t: f64,
        axle: [f64; 3],
        v: f64,
        w: f64,
        ws: &mut Workspace,
    ) -> (RefSample, bool) {
        let (mut cmd, r) = match reference {
            Some(r) => {
                let rs = ReferenceSample {
                    pose: [r.x, r.y, r.theta],
                    v: r.v,
                    w: r.omega,
                };
                (self.kan.inputs(&axle, &rs), base_reference(r, self.d))
            }
            None => (
                arrive_command(&self.arrive, self.kx, self.pos_tol, axle, self.goal_axle),
                self.goal_sample(t),
            ),
        };
        let mut speed_clip = false;
        if cmd[0].abs() > self.v_max {
            cmd[0] = self.v_max.copysign(cmd[0]);
            speed_clip = true;
        }
        if cmd[1].abs() > self.omega_max {
            cmd[1] = self.omega_max.copysign(cmd[1]);
            speed_clip = true;
        }
        let wr = self.act.w_inv * Vector2::new(cmd[0], cmd[1]);
        let peak = wr.amax();
        if peak > self.act.wheel_speed {
            let s = self.act.wheel_speed / peak;
            cmd[0] *= s;
            cmd[1] *= s;
            speed_clip = true;
        }
        let (ks, wn) = (self.ks, self.wn);
        let a_des = &mut ws.a_des;
        a_des[0] = (r.a + ks * (cmd[0] - v)).clamp(-self.a_guard_b, self.a_guard_f);
        a_des[1] = (r.alpha + ks * (cmd[1] - w)).clamp(-self.alpha_guard, self.alpha_guard);
        for (k2, &i) in self.arm.iter().enumerate() {
            a_des[2 + k2] = wn * wn * (self.q_t[i] - ws.q_now[i]) - 2.0 * wn * ws.v_now[2 + k2];
        }
        (r, speed_clip)
    }

    /// Reach: the platform's speeds to zero, the end effector on `traj` by damped least
    /// squares on the arm block, the joint rates damped in its null space. Writes the
    /// desired accelerations; `false` if the arm block is singular.
    pub(super) fn reach_law(
        &self,
        traj: &EeTrajectory,
        ee: &EeState,
        t: f64,
        v: f64,
        w: f64,
        ws: &mut Workspace,
    ) -> bool {
        let (nr, na, wn, wt) = (self.nr, self.na, self.wn, self.wt);
        let (ee_jacobian, v_now, a_des) = (&ws.ee_jacobian, &ws.v_now, &mut ws.a_des);
        // platform holds: speeds to zero
        a_des[0] = -self.ks * v;
        a_des[1] = -self.ks * w;
        let (xd, dxd, ddxd) = traj.at(t);
        let mut rhs = ddxd + (dxd - ee.dp) * (2.0 * wt) + (xd - ee.p) * (wt * wt) - ee.bias;
        for r in 0..3 {
            rhs[r] -= ee_jacobian[(r, 0)] * a_des[0] + ee_jacobian[(r, 1)] * a_des[1];
        }
        // damped least squares on the arm block, null-space damping
        let mut jjt = Matrix3::zeros();
        for r in 0..3 {
            for s in 0..3 {
                let mut acc = 0.0;
                for j in 2..nr {
                    acc += ee_jacobian[(r, j)] * ee_jacobian[(s, j)];
                }
                jjt[(r, s)] = acc;
            }
            jjt[(r, r)] += 1e-6;
        }
        let Some(jinv) = jjt.try_inverse() else {
            return false;
        };
        let y = jinv * rhs;
        // null-space motion: damp the joint rates
        let mut q0 = vec![0.0; na];
        for (k2, q0k) in q0.iter_mut().enumerate() {
            *q0k = -2.0 * wn * v_now[2 + k2];
        }
        // J q0
        let mut jq0 = Vector3::zeros();
        for r in 0..3 {
            for (k2, q0k) in q0.iter().enumerate() {
                jq0[r] += ee_jacobian[(r, 2 + k2)] * q0k;
            }
        }
        let z = jinv * jq0;
        for k2 in 0..na {
            let mut acc = q0[k2];
            for r in 0..3 {
                acc += ee_jacobian[(r, 2 + k2)] * (y[r] - z[r]);
            }
            a_des[2 + k2] = acc;
        }
        true
    }
}

/// The base's distance and heading error (m, rad) to the base frame's goal pose `goal`,
/// and whether it rests there within `g`'s tolerances.
pub(super) fn at_goal(
    goal: [f64; 3],
    g: &GoalSpec,
    pose: [f64; 3],
    v: f64,
    w: f64,
) -> (f64, f64, bool) {
    let pe = (pose[0] - goal[0]).hypot(pose[1] - goal[1]);
    let he = wrap_angle(goal[2] - pose[2]).abs();
    let settled = v.abs() < 0.02 && w.abs() < 0.05;
    let arrived = pe <= g.position_tolerance && he <= g.heading_tolerance && settled;
    (pe, he, arrived)
}

/// The arrive phase's speed commands `[v, ω]` for the axle pose `axle` onto its goal pose
/// `goal`: while the position is more than `position_tolerance` off, Aicardi's polar law
/// `law` (it closes a lateral offset too, which no smooth law of the pose error alone
/// can, by Brockett's condition); within it, `[kx·eₓ, 2·e_θ]`, a turn onto the goal
/// heading.
pub(super) fn arrive_command(
    law: &Aicardi,
    kx: f64,
    position_tolerance: f64,
    axle: [f64; 3],
    goal: [f64; 3],
) -> [f64; 2] {
    if (axle[0] - goal[0]).hypot(axle[1] - goal[1]) > position_tolerance {
        return law.inputs(&axle, &goal);
    }
    let rs = ReferenceSample {
        pose: goal,
        v: 0.0,
        w: 0.0,
    };
    let [ex, _, eth] = Kanayama::error(&axle, &rs);
    [kx * ex, 2.0 * eth]
}

/// End-effector position, velocity and acceleration bias in reduced coordinates.
#[derive(Clone, Copy, Default)]
pub(super) struct EeState {
    pub(super) p: Vector3<f64>,
    pub(super) dp: Vector3<f64>,
    pub(super) bias: Vector3<f64>,
}

/// The end effector's position, velocity and acceleration bias at the workspace's state,
/// with its reduced position Jacobian in `ws.ee_jacobian` (needs the controller's reduced
/// dynamics at the state).
pub(super) fn end_effector_kinematics(m: &Mission, ws: &mut Workspace) -> EeState {
    let (wm, ee_frame) = (&m.robot, m.ee_frame);
    let model = &wm.model;
    let nr = wm.nr();
    let qd = &ws.control_dynamics.qdot;
    let acc = frame_acceleration_bias(
        model,
        &mut ws.data,
        &ws.q_now,
        qd,
        ee_frame,
        ReferenceFrame::LocalWorldAligned,
    );
    let mut ee = EeState {
        p: ws.data.world_from_frame[ee_frame.0].translation,
        ..EeState::default()
    };
    frame_jacobian_from_kinematics(
        model,
        &mut ws.data,
        ee_frame,
        ReferenceFrame::LocalWorldAligned,
        &mut ws.jac,
    );
    admissible_velocity_basis_dot(wm, &ws.q_now, qd[2], &mut ws.ndot);
    ws.ndot.mul_to(&ws.v_now, &mut ws.ndot_v);
    let (jac, ee_jacobian, v_now) = (&ws.jac, &mut ws.ee_jacobian, &ws.v_now);
    for r in 0..3 {
        let mut b = acc.linear[r];
        for cc in 0..model.nv {
            b += jac[(r, cc)] * ws.ndot_v[cc];
        }
        ee.bias[r] = b;
        for j in 0..nr {
            let mut s = 0.0;
            for l in 0..model.nv {
                s += jac[(r, l)] * ws.control_dynamics.basis[(l, j)];
            }
            ee_jacobian[(r, j)] = s;
        }
        let mut s = 0.0;
        for j in 0..nr {
            s += ee_jacobian[(r, j)] * v_now[j];
        }
        ee.dp[r] = s;
    }
    ee
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The arrive law on the kinematic unicycle with the mission's speed limits, from
    /// `start` onto the origin: the pose error after 8 s (the arrive phase's time-out).
    fn arrive_from(start: [f64; 3]) -> (f64, f64) {
        let law = Aicardi::new(2.0, 2.0, 1.0).unwrap();
        let (mut p, h) = (start, 1e-3);
        for _ in 0..8000 {
            let [v, w] = arrive_command(&law, 2.0, 0.1, p, [0.0; 3]);
            let (v, w) = (v.clamp(-1.0, 1.0), w.clamp(-1.0, 1.0));
            p = [
                p[0] + h * v * p[2].cos(),
                p[1] + h * v * p[2].sin(),
                p[2] + h * w,
            ];
        }
        (p[0].hypot(p[1]), wrap_angle(p[2]).abs())
    }

    #[test]
    fn arrive_closes_a_sideways_offset_within_its_time_out() {
        for start in [
            [0.0, 0.3, 0.0],
            [0.0, -0.5, 0.0],
            [-0.2, 0.25, 0.1],
            [0.4, 0.0, 0.0],
        ] {
            let (pe, he) = arrive_from(start);
            assert!(
                pe <= 0.1 && he <= 0.1,
                "from {start:?}: {pe} m, {he} rad off"
            );
        }
    }

    #[test]
    fn the_heading_law_alone_never_closes_a_sideways_offset() {
        // the law the arrive phase had before: [kx·eₓ, 2·e_θ] everywhere
        let law = Aicardi::new(2.0, 2.0, 1.0).unwrap();
        let [v, w] = arrive_command(&law, 2.0, f64::INFINITY, [0.0, 0.3, 0.0], [0.0; 3]);
        assert_eq!([v, w], [0.0, 0.0]);
    }
}

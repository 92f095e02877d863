//! The phases' ends: drive → arrive at the end of the reference, arrive → reach (or the
//! pick, or done) once the base rests on the goal pose; the reach phase; law `mpc`'s
//! whole-body step with its own goal test; the time limit.

use nalgebra::Vector3;

use super::arm_motion::{ArmStage, EeTrajectory};
use super::laws::{EeState, RunSettings, at_goal};
use super::reference::base_reference;
use super::run::{LoopState, Phase, Runner};
use super::whole_body::WholeBodyLaw;
use super::workspace::Workspace;

/// Time allowed after the reference ends to settle on the goal pose (s).
const ARRIVE_TIMEOUT: f64 = 8.0;

/// Time allowed after the end-effector trajectory ends to settle on the target (s).
const REACH_SETTLE: f64 = 5.0;

impl Runner<'_> {
    /// Drive → arrive at the end of the reference; arrive → reach (or done) once the
    /// base settles on the goal pose, or failure after the arrival timeout; the time
    /// limit.
    pub(super) fn phase_transitions(
        &mut self,
        c: &RunSettings,
        st: &mut LoopState,
        t: f64,
        pose: [f64; 3],
        v: f64,
        w: f64,
    ) {
        let g = self.goal.clone();
        if st.phase == Phase::Drive {
            let r = self.reference.as_ref().expect("drive has a reference");
            if t >= r.t_end() {
                st.phase = Phase::Arrive;
                st.phase_t0 = t;
            }
        }
        if st.phase == Phase::Arrive {
            let (pe, he, arrived) = at_goal(c.goal, &g, pose, v, w);
            if arrived {
                self.event(
                    t,
                    "arrived",
                    format!("base at the goal: {pe:.3} m, {he:.3} rad off"),
                );
                if g.end_effector.is_some() {
                    st.phase = Phase::Reach;
                    st.phase_t0 = t;
                } else if self.m.task.is_some() && !st.picked {
                    st.phase = Phase::Arm(ArmStage::Approach);
                    st.phase_t0 = t;
                } else {
                    st.time_to_goal = Some(t);
                    st.phase = Phase::Done;
                }
            } else if t - st.phase_t0 > ARRIVE_TIMEOUT {
                self.fail(
                    t,
                    format!(
                        "the base stopped {pe:.3} m and {he:.3} rad from the goal pose \
                         (tolerances {} m, {} rad)",
                        g.position_tolerance, g.heading_tolerance
                    ),
                );
                st.phase = Phase::Done;
            }
        }
        if t >= c.time_limit && st.phase != Phase::Done {
            self.fail(t, format!("time limit of {:.1} s reached", c.time_limit));
            st.phase = Phase::Done;
        }
    }

    /// The reach phase: the platform holds, the arm tracks a minimum-jerk segment to the
    /// target; reached or failed once it ends. `false` when the arm is singular (the run
    /// ends).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn reach(
        &mut self,
        c: &RunSettings,
        st: &mut LoopState,
        ws: &mut Workspace,
        ee: &EeState,
        t: f64,
        v: f64,
        w: f64,
    ) -> bool {
        let g = self.goal.clone();
        let target = Vector3::from(g.end_effector.expect("reach has a target"));
        let traj = *st.ee_traj.get_or_insert_with(|| {
            let dist = (target - ee.p).norm();
            EeTrajectory {
                t0: t,
                duration: (1.875 * dist / 0.25).max(1.5),
                from: ee.p,
                to: target,
            }
        });
        st.cur_ref = c.goal_sample(t);
        if !c.reach_law(&traj, ee, t, v, w, ws) {
            self.fail(t, "the arm is singular at the goal".to_string());
            st.phase = Phase::Done;
            return false;
        }
        let err = (target - ee.p).norm();
        if t >= traj.t0 + traj.duration && err <= g.end_effector_tolerance && ee.dp.norm() < 0.01 {
            self.event(
                t,
                "reached",
                format!("end effector at its target: {:.4} m off", err),
            );
            st.time_to_goal = Some(t);
            st.phase = Phase::Done;
        } else if t > traj.t0 + traj.duration + REACH_SETTLE {
            self.fail(
                t,
                format!(
                    "the end effector stopped {err:.3} m from its target \
                     (tolerance {} m)",
                    g.end_effector_tolerance
                ),
            );
            st.phase = Phase::Done;
        }
        true
    }

    /// Law `mpc`, one control step: the MPC tracks the current plan (a re-plan's from
    /// its next solve on) and reaches for the target, its torques in `ws.u`; the run is
    /// done once the end effector has been within its tolerance of the target and the
    /// base rests at the goal pose after the reference has ended. It fails when that has
    /// not happened [`ARRIVE_TIMEOUT`] + [`REACH_SETTLE`] after the reference's end, or
    /// when the MPC fails (`false`: the run ends).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn whole_body_step(
        &mut self,
        c: &RunSettings,
        st: &mut LoopState,
        ws: &mut Workspace,
        t: f64,
        pose: [f64; 3],
        v: f64,
        w: f64,
    ) -> bool {
        let (Some(reference), Some(law)) = (self.reference.as_ref(), self.whole_body.as_mut())
        else {
            self.fail(t, "law mpc has no reference to track".to_string());
            st.phase = Phase::Done;
            return false;
        };
        law.track(reference, self.plans.len(), &self.planner, &self.m.map.grid);
        st.cur_ref = base_reference(reference.at(t), c.d);
        let t_end = reference.t_end();
        let (q, v_r) = (ws.q_now.as_slice(), ws.v_now.as_slice());
        let tick = match law.tick(st.k, t, q, v_r, &mut ws.u) {
            Ok(tick) => tick,
            Err(e) => {
                self.fail(t, format!("the MPC failed: {e}"));
                st.phase = Phase::Done;
                return false;
            }
        };
        let reached = law.reached();
        self.saturation_events(st, t, tick.torque_clipped, false);
        if let Some(e) = tick.touched {
            self.event(
                t,
                "reached",
                format!("end effector at its target: {e:.4} m off, the base at {v:.2} m/s"),
            );
        }
        let (pe, he, arrived) = at_goal(c.goal, &self.goal, pose, v, w);
        if t >= t_end && arrived && reached {
            self.event(
                t,
                "arrived",
                format!("base at the goal: {pe:.3} m, {he:.3} rad off"),
            );
            st.time_to_goal = Some(t);
            st.phase = Phase::Done;
        } else if t > t_end + ARRIVE_TIMEOUT + REACH_SETTLE {
            let g = &self.goal;
            let why = if !reached {
                let min_error = self
                    .whole_body
                    .as_ref()
                    .map_or(f64::INFINITY, WholeBodyLaw::min_ee_error);
                format!(
                    "the end effector came no closer than {min_error:.3} m to its target \
                     (tolerance {} m)",
                    g.end_effector_tolerance
                )
            } else {
                format!(
                    "the base stopped {pe:.3} m and {he:.3} rad from the goal pose \
                     (tolerances {} m, {} rad)",
                    g.position_tolerance, g.heading_tolerance
                )
            };
            self.fail(t, why);
            st.phase = Phase::Done;
        }
        true
    }
}

//! A `[task]`'s pick in the loop: each arm motion planned on entry from the measured
//! state and tracked while the platform holds, the payload attached after the grasp, the
//! object lifted off its support and carried back to the transport posture, and the
//! drive on to `[goal]` with the footprint that holds it.

use std::time::Instant;

use super::arm_motion::{ArmMotion, ArmStage};
use super::footprint::MissionFootprint;
use super::heights::HeldObjectBlocks;
use super::laws::RunSettings;
use super::plan::mission_planner;
use super::reference::{TimingStart, axle_pose};
use super::run::{LoopState, Phase, Runner};
use super::scenario::GoalSpec;
use super::task::{ARM_MARGIN, ArmPlanRecord, PayloadRecord, Task};
use super::tip_over::{timing_acceleration, tip_limits_of};
use super::workspace::Workspace;

/// Time allowed after an arm trajectory ends to settle on its last state (s).
const ARM_SETTLE: f64 = 3.0;

/// An arm motion has ended when every group joint is this close to its last state (rad
/// or m) and moves slower than [`ARM_SETTLED_RATE`].
const ARM_SETTLED: f64 = 0.01;

/// Joint rate (rad/s or m/s) below which a settled arm joint counts as at rest.
const ARM_SETTLED_RATE: f64 = 0.02;

impl<'m> Runner<'m> {
    /// A `[task]`'s arm motion: the state's distances checked (every control step), the
    /// motion planned on entry from the measured state, tracked in joint space by computed
    /// torque while the platform holds; once it settles, the next motion (the payload
    /// attached after the grasp). `false` when the run ends here (a touch, a motion not
    /// planned or not settled).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn arm_step(
        &mut self,
        c: &mut RunSettings,
        st: &mut LoopState,
        ws: &mut Workspace,
        stage: ArmStage,
        t: f64,
        axle: [f64; 3],
        v: f64,
        w: f64,
    ) -> bool {
        if !self.check_task_distances(ws, st, t) {
            return false;
        }
        let m = self.m;
        let task = m.task.as_ref().expect("arm phases have a task");
        st.cur_ref = c.goal_sample(t);
        if st.arm.is_none() {
            let clock = Instant::now();
            let planned = self.plan_arm(task, stage, t, ws.q_now.as_slice());
            st.excluded += clock.elapsed().as_secs_f64();
            match planned {
                Ok(motion) => st.arm = Some(motion),
                Err(reason) => {
                    self.fail(t, reason);
                    st.phase = Phase::Done;
                    return false;
                }
            }
        }
        let g = &task.group;
        let (end, settled) = {
            let motion = st.arm.as_ref().expect("planned above");
            motion.at(t, g, &mut ws.q_ref, &mut ws.qd_ref, &mut ws.qdd_ref);
            let last = motion.last();
            let settled = g.q_index.iter().zip(&c.group_slots).all(|(&i, &k2)| {
                (ws.q_now[i] - last[i]).abs() <= ARM_SETTLED
                    && ws.v_now[2 + k2].abs() <= ARM_SETTLED_RATE
            });
            (motion.t0 + motion.trajectory.duration, settled)
        };
        c.arm_law(ws, v, w);
        if t < end {
            return true;
        }
        let name = Phase::Arm(stage).name();
        if settled {
            st.arm = None;
            self.event(t, "arm", format!("{name} motion done"));
            match stage {
                ArmStage::Approach => st.phase = Phase::Arm(ArmStage::Grasp),
                ArmStage::Grasp => {
                    self.attach_payload(task, ws, st, t);
                    st.phase = Phase::Arm(ArmStage::Lift);
                }
                ArmStage::Lift => st.phase = Phase::Arm(ArmStage::Retreat),
                ArmStage::Retreat => {
                    st.picked = true;
                    let text = format!(
                        "picked '{}', arm back in the transport posture",
                        task.object
                    );
                    match self.drive_on.take() {
                        Some(goal) => {
                            self.event(t, "picked", text);
                            if !self.drive_on_to(c, st, t, axle, goal) {
                                st.phase = Phase::Done;
                                return false;
                            }
                        }
                        None => {
                            self.event(t, "reached", text);
                            st.time_to_goal = Some(t);
                            st.phase = Phase::Done;
                        }
                    }
                }
            }
            st.phase_t0 = t;
        } else if t > end + ARM_SETTLE {
            self.fail(
                t,
                format!(
                    "the arm did not settle at the end of its {name} motion within {ARM_SETTLE} s \
                     (each joint within {ARM_SETTLED} of its last state)"
                ),
            );
            st.phase = Phase::Done;
            return false;
        }
        true
    }

    /// After the pick: plans from where the base stands (or the placement) to `goal`
    /// with the footprint that holds the object (the map with the obstacles that have
    /// appeared), times the path from the robot's pose at rest under the
    /// tip-over limits of the transport posture with the payload, and drives on. `false`
    /// (with the reason) when no path leads there or it cannot be timed.
    pub(super) fn drive_on_to(
        &mut self,
        c: &mut RunSettings,
        st: &mut LoopState,
        t: f64,
        axle: [f64; 3],
        goal: GoalSpec,
    ) -> bool {
        let m = self.m;
        let f = &m.file;
        let d = self.wm.base.drive.d;
        let clock = Instant::now();
        // the search leaves from where the base stands, or, when that cell is not free on
        // the configuration space, from the placement's cell (free: the base was planned
        // there); the timing from where the base stands
        let to = axle_pose(goal.pose, d);
        let task = m.task.as_ref().expect("the drive on follows a pick");
        let footprint = &task.carrying_footprint;
        let map = m
            .drive_on_map
            .as_ref()
            .expect("a pick has its drive on's map");
        let held = holding_text(task, &map.blocks);
        if let Some(text) = &held {
            self.event(t, "heights", text.clone());
        }
        // the failures' reasons name what the object held blocks
        let why = held.map_or(String::new(), |text| format!(" ({text})"));
        let grid = &map.grid;
        let (from, planned) = match mission_planner(m, grid, footprint, axle, to) {
            Ok(p) => (axle, Ok(p)),
            Err(_) => {
                let placement = axle_pose(self.goal.pose, d);
                (
                    placement,
                    mission_planner(m, grid, footprint, placement, to),
                )
            }
        };
        let (mut planner, mut path, search) = match planned {
            Ok(p) => p,
            Err(e) => {
                self.fail(t, format!("driving on to the goal: {e}{why}"));
                return false;
            }
        };
        // the obstacles that have appeared so far
        let [fx, fy] = grid.world_to_cell_f(from[0], from[1]);
        let cell = (
            (fx.floor().max(0.0) as usize).min(grid.width - 1),
            (fy.floor().max(0.0) as usize).min(grid.height - 1),
        );
        if st.next_obstacle > 0 {
            for &(oi, _) in &c.obstacles[..st.next_obstacle] {
                let o = f.obstacles[oi];
                let centre = grid.world_to_cell_f(o.center[0], o.center[1]);
                if let Err(e) = planner.add_disk(centre, o.radius / grid.resolution, cell) {
                    self.fail(t, format!("driving on to the goal: {e}"));
                    return false;
                }
            }
            path = planner.replan().0;
        }
        let s = clock.elapsed().as_secs_f64();
        self.wall.planning_s += s;
        st.excluded += s;
        let Some(cells) = path else {
            self.fail(
                t,
                format!(
                    "the goal is unreachable from the placement: no collision-free path on \
                     the configuration space{why}"
                ),
            );
            return false;
        };
        self.planner = planner;
        self.footprint = footprint;
        c.r_foot = footprint.radius;
        self.event(t, "footprint", carrying_text(task, &m.footprint));
        if let Some(tr) = &mut self.task {
            tr.drive_on_footprint_radius = Some(footprint.radius);
        }
        self.goal = goal;
        match tip_limits_of(m, self.wm) {
            Ok(tip) => self.tip = tip,
            Err(e) => {
                self.fail(t, format!("driving on to the goal: {e}"));
                return false;
            }
        }
        self.timing_accel = timing_acceleration(&self.tip, f.limits.tip_fraction);
        if self.timing_accel.is_none() {
            self.fail(
                t,
                "the transport posture with the payload leaves no acceleration that keeps \
                 the ZMP inside the support"
                    .to_string(),
            );
            return false;
        }
        c.retarget(&self.goal, &self.tip);
        let start = TimingStart {
            t0: t,
            pose: axle,
            v: 0.0,
        };
        if !self.make_reference(cells, start, "drive on", search) {
            return false;
        }
        let dur = self.plans.last().map_or(0.0, |p| p.duration);
        if f.simulation.time_limit.is_none() {
            c.time_limit = c.time_limit.max(t + 3.0 * dur + 30.0);
        }
        self.event(t, "plan", format!("drive on to the goal: {dur:.2} s"));
        st.phase = Phase::Drive;
        true
    }

    /// Plans the arm motion of `stage` from `q` (the measured state, its group joints
    /// clamped into the joint box) among the task's scene and the map's boxes near the
    /// pick ([`Task::boxes`]); the lift and the retreat carrying the object, among the
    /// scene without it (the lift's support allowed to touch it); records the plan.
    pub(super) fn plan_arm(
        &mut self,
        task: &Task,
        stage: ArmStage,
        t: f64,
        q: &[f64],
    ) -> std::result::Result<ArmMotion, String> {
        use crate::motion::{MotionGoal, MotionOptions, MotionProblem, plan_motion};
        let m = self.m;
        let g = &task.group;
        let mut start = q.to_vec();
        for (j, &i) in g.q_index.iter().enumerate() {
            start[i] = start[i].clamp(g.lower[j], g.upper[j]);
        }
        let (geometry, scene, goal) = match stage {
            ArmStage::Approach => (
                &task.geometry,
                &task.scene,
                MotionGoal::Pose(task.pre_grasp.clone()),
            ),
            ArmStage::Grasp => (
                &task.geometry,
                &task.scene,
                MotionGoal::Pose(task.grasp.clone()),
            ),
            ArmStage::Lift => (
                &task.carried,
                &task.scene_lifting,
                MotionGoal::Pose(task.lift.clone()),
            ),
            ArmStage::Retreat => {
                let mut goal = start.clone();
                for (k, &i) in m.robot.arm_dofs().iter().enumerate() {
                    if g.q_index.contains(&i) {
                        goal[i] = m.transport[k];
                    }
                }
                (
                    &task.carried,
                    &task.scene_after_grasp,
                    MotionGoal::State(goal),
                )
            }
        };
        let mut options = MotionOptions::new(g.dim());
        options.time_limit = std::time::Duration::from_secs_f64(task.planning_time);
        options.seed = task.seed;
        options.margin = ARM_MARGIN;
        // the map's boxes near the pick after the task's objects
        let scene = &super::arm_scene::scene_with(scene, &task.boxes);
        let problem = MotionProblem {
            model: &m.robot.model,
            geometry,
            scene,
            group: g,
        };
        let name = Phase::Arm(stage).name();
        let mut record = ArmPlanRecord {
            stage: name.to_string(),
            t,
            solved: false,
            reason: None,
            planning_time_s: 0.0,
            checks: 0,
            duration: None,
            min_distance: None,
            min_distance_states: 0,
        };
        let out = match plan_motion(&problem, &start, &goal, &options) {
            Err(e) => Err(format!("the {name} motion could not be planned: {e}")),
            Ok(r) => {
                record.planning_time_s = r.planning_time.as_secs_f64();
                record.checks = r.checks;
                record.duration = r.trajectory.as_ref().map(|tr| tr.duration);
                record.min_distance = r.closest.as_ref().map(|c| c.distance);
                record.min_distance_states = r.closest_states;
                match (r.not_solved, r.trajectory) {
                    (None, Some(trajectory)) => Ok(ArmMotion { t0: t, trajectory }),
                    (Some(why), _) => Err(format!("the {name} motion was not solved: {why}")),
                    (None, None) => Err(format!("the {name} motion has no trajectory")),
                }
            }
        };
        record.solved = out.is_ok();
        record.reason = out.as_ref().err().cloned();
        if let Ok(a) = &out {
            self.wall.planning_s += record.planning_time_s;
            self.event(
                t,
                "arm_plan",
                format!(
                    "{name} motion planned in {:.3} s ({} checks): {:.2} s",
                    record.planning_time_s, record.checks, a.trajectory.duration
                ),
            );
        }
        if let Some(tr) = &mut self.task {
            tr.arm_plans.push(record);
        }
        out
    }

    /// Attaches the picked object: the law, the plant and the monitors take the robot
    /// with the payload from now on; the ZMP margin at this state without and with it is
    /// recorded.
    pub(super) fn attach_payload(
        &mut self,
        task: &'m Task,
        ws: &mut Workspace,
        st: &mut LoopState,
        t: f64,
    ) {
        let zmp = |ws: &mut Workspace| {
            ws.monitor
                .sample(t, ws.q_now.as_slice(), ws.v_now.as_slice(), &ws.u)
                .ok()?;
            ws.monitor.trace.zmp_margin.last().copied().flatten()
        };
        let without = zmp(ws);
        self.wm = &task.payload_robot;
        let attached = ws.attach(self.wm, self.m.file.limits.mu);
        let with = attached.ok().and_then(|()| zmp(ws));
        st.grasped = true;
        let fmt = |z: Option<f64>| z.map_or("undefined".to_string(), |z| format!("{z:.4} m"));
        let support = if task.support.is_empty() {
            String::new()
        } else {
            format!(
                "; it may touch its support ({}) until lifted",
                task.support
                    .iter()
                    .map(|s| format!("'{s}'"))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        };
        self.event(
            t,
            "payload",
            format!(
                "'{}' attached ({} kg): ZMP margin {} without it, {} with it{support}",
                task.object,
                task.mass,
                fmt(without),
                fmt(with)
            ),
        );
        if let Some(tr) = &mut self.task {
            tr.payload = Some(PayloadRecord {
                t,
                mass: task.mass,
                zmp_margin_without: without,
                zmp_margin_with: with,
            });
        }
    }
}

/// The drive on's `heights` event: the obstacles with heights that the robot passes
/// under bare and not holding the object, which its map blocks; `None` when there are
/// none.
fn holding_text(task: &Task, blocks: &[HeldObjectBlocks]) -> Option<String> {
    if blocks.is_empty() {
        return None;
    }
    let each: Vec<String> = blocks
        .iter()
        .map(|b| {
            format!(
                "'{}' (clearance {:.4} m bare, {:.4} m holding it)",
                b.name, b.bare.clearance, b.holding.clearance
            )
        })
        .collect();
    Some(format!(
        "holding '{}' at the transport posture the robot no longer passes under {}: the \
         drive on's map blocks {}",
        task.object,
        each.join(", "),
        if blocks.len() == 1 { "it" } else { "them" }
    ))
}

/// The drive on's `footprint` event: the footprint with the held object against the
/// mission's `bare` one.
fn carrying_text(task: &Task, bare: &MissionFootprint) -> String {
    let fp = &task.carrying_footprint;
    if fp == bare {
        format!(
            "driving on with '{}': it lies inside the robot's footprint at the transport \
             posture, the footprint is unchanged (radius {:.4} m)",
            task.object, bare.radius
        )
    } else {
        format!(
            "driving on with '{}': the footprint holds it at the transport posture, radius \
             {:.4} m ({:.4} m without it)",
            task.object, fp.radius, bare.radius
        )
    }
}

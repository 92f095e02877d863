//! The closed loop of a mission: [`run`] prepares the [`Runner`] (the goal, the planner,
//! the tip-over limits, law `mpc`), then has the held-input loop
//! ([`crate::sim::held_loop::run_held_loop`]) run it as a law with phases on the mission's
//! plant ([`MissionPlant`]): at each control tick [`Runner::step`] takes the measured
//! state, the obstacles due, the phase, the control law, the torques, the record; the
//! loop then advances the plant. [`Runner::finish`] turns what it gathered into the
//! [`MissionResult`]. The step's parts live beside it: `replan` (planning in the loop),
//! `arrival` (the phases' ends), `pick` (a `[task]`'s arm motions), `recording` (samples,
//! monitors, events), `laws` and `workspace`.

use std::time::Instant;

use super::arm_motion::{ArmMotion, ArmStage, EeTrajectory};
use super::footprint::MissionFootprint;
use super::laws::{EeState, RunSettings, end_effector_kinematics};
use super::placement::choose_placement;
use super::plan::{Planner, SearchTiming, mission_planner};
use super::plant::{ContactLoop, MissionPlant};
use super::reference::{RefSample, Reference, TimingStart, axle_pose};
use super::result::{Event, MissionResult, PlanRecord, Samples, WallTimes};
use super::scenario::{GoalSpec, MAX_SAMPLES, MAX_STEPS, Mission};
use super::task::{DistanceMonitor, TaskResult};
use super::tip_over::{timing_acceleration, transport_tip_limits};
use super::whole_body::WholeBodyLaw;
use super::workspace::{Actuators, Workspace, initial_state};
use crate::error::{Error, Result};
use crate::mobile::WheeledModel;
use crate::mobile::wheeled::{
    reduced_forward_dynamics_crba, reduced_forward_dynamics_under_inputs,
};
use crate::planning::trajectory::{DiffDriveLimits, TipOverAcceleration};
use crate::sim::held_loop::{Tick, TickEnd, TickLaw, run_held_loop};
use crate::sim::monitor::MonitorLimits;
use crate::sim::rolling_plant::RollingPlant;
use crate::sim::settings::{IntegratorSettings, MAX_STEP_BUDGET};
use crate::sim::stepping::Grid;
use crate::sim::wheeled_system::WheeledSystem;
use crate::stability::{AccelerationLimits, BodySet};

/// What the loop does at a step (recorded by [`Phase::name`] in `Samples::phase`).
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum Phase {
    /// The base tracks the timed reference.
    Drive,
    /// The reference has ended: the base settles on the goal pose.
    Arrive,
    /// The platform holds, the end effector moves to its target.
    Reach,
    /// A `[task]`'s arm motion.
    Arm(ArmStage),
    /// Law `mpc`: drive and reach at once, up to the goal.
    WholeBody,
    /// The run has ended (reached or failed): the last sample is recorded.
    Done,
}

impl Phase {
    /// The base follows the timed reference (which a blocking obstacle re-plans): `drive`,
    /// and law `mpc`'s `whole_body`.
    pub(super) fn follows_reference(self) -> bool {
        matches!(self, Phase::Drive | Phase::WholeBody)
    }

    /// The phase's name in the record.
    pub(super) fn name(self) -> &'static str {
        match self {
            Phase::Drive => "drive",
            Phase::Arrive => "arrive",
            Phase::Reach => "reach",
            Phase::Arm(stage) => stage.name(),
            Phase::WholeBody => "whole_body",
            Phase::Done => "done",
        }
    }
}

/// Runs a mission.
///
/// # Errors
/// Input errors found while preparing the run (start or goal outside the map or where the
/// footprint does not fit, a footprint that fits nowhere, an inconsistent robot). A run
/// that starts but does not reach the goal is not an error: it returns `reached: false`
/// with a `reason`.
pub fn run(m: &Mission) -> Result<MissionResult> {
    Runner::new(m)?.run()
}

/// A mission being run: its goal, the planner with the reference being tracked, the
/// tip-over limits and timing accelerations, and the plans, events and samples gathered
/// so far. Its methods are the loop's parts, one file per concept (see the file's head).
pub(super) struct Runner<'m> {
    pub(super) m: &'m Mission,
    /// The law's robot: the mission's, with a `[task]`'s payload once grasped.
    pub(super) wm: &'m WheeledModel,
    /// The footprint planned and monitored with: the mission's, a `[task]`'s carrying one
    /// on the drive on.
    pub(super) footprint: &'m MissionFootprint,
    /// The base goal: `[goal]`, or a `[task]`'s placement.
    pub(super) goal: GoalSpec,
    /// A `[task]`'s record so far.
    pub(super) task: Option<TaskResult>,
    /// A `[task]`'s `[goal]`, driven on to after the pick.
    pub(super) drive_on: Option<GoalSpec>,
    pub(super) planner: Planner,
    pub(super) first_path: Option<Vec<(usize, usize)>>,
    pub(super) first_search: SearchTiming,
    pub(super) wall: WallTimes,
    pub(super) tip: AccelerationLimits,
    pub(super) limits: DiffDriveLimits,
    pub(super) timing_accel: Option<TipOverAcceleration>,
    pub(super) plans: Vec<PlanRecord>,
    pub(super) events: Vec<Event>,
    pub(super) samples: Samples,
    pub(super) reference: Option<Reference>,
    pub(super) failure: Option<String>,
    /// Law `mpc`.
    pub(super) whole_body: Option<WholeBodyLaw>,
}

impl<'m> Runner<'m> {
    pub(super) fn new(m: &'m Mission) -> Result<Self> {
        let f = &m.file;
        let clock = Instant::now();
        let d = m.robot.base.drive.d;
        let (goal, task, failure) = match &m.task {
            None => (
                m.goal()
                    .cloned()
                    .ok_or_else(|| Error::parse(&m.path, "goal: missing"))?,
                None,
                None,
            ),
            Some(task) => choose_placement(m, task)?,
        };
        let (s0, g0) = (axle_pose(f.start.pose, d), axle_pose(goal.pose, d));
        // the pipeline refuses a start or goal pose where the footprint polygon collides
        let (planner, first_path, first_search) =
            mission_planner(m, &m.map.grid, &m.footprint, s0, g0)?;
        let planning_s = clock.elapsed().as_secs_f64();
        let tip = transport_tip_limits(m)?;
        let l = &f.limits;
        let limits = l.platform();
        let timing_accel = timing_acceleration(&tip, l.tip_fraction);
        let whole_body = m.mpc.as_ref().map(|(mpc, every)| {
            WholeBodyLaw::new(
                mpc.clone(),
                *every,
                d,
                goal.end_effector,
                f.control.reach_radius.unwrap_or(1.0),
                goal.end_effector_tolerance,
                m.footprint.radius,
            )
        });
        Ok(Self {
            m,
            wm: &m.robot,
            footprint: &m.footprint,
            goal,
            task,
            drive_on: m.task.as_ref().and(m.goal().cloned()),
            planner,
            first_path,
            first_search,
            wall: WallTimes {
                planning_s,
                ..Default::default()
            },
            tip,
            limits,
            timing_accel,
            plans: Vec::new(),
            events: Vec::new(),
            samples: Samples::default(),
            reference: None,
            failure,
            whole_body,
        })
    }

    pub(super) fn event(&mut self, t: f64, kind: &str, text: impl Into<String>) {
        self.events.push(Event {
            t,
            kind: kind.to_string(),
            text: text.into(),
        });
    }

    pub(super) fn fail(&mut self, t: f64, reason: String) {
        self.event(t, "failed", reason.clone());
        self.failure = Some(reason);
    }

    pub(super) fn run(mut self) -> Result<MissionResult> {
        self.first_plan();
        let (time_limit, rec_every) = self.run_length()?;
        let sim = &self.m.file.simulation;
        let h = sim.dt;
        let plant_robot = self.m.plant_robot.as_ref().unwrap_or(self.wm);
        // the rolling plant: one RK4 step per control period (the run's length is bounded
        // by `run_length`, below the step budget)
        let mut rolling = WheeledSystem::new(plant_robot.clone());
        let end = |k: usize| (k + 1) as f64 * h;
        let one_step = |_: usize| 1;
        let mut plant = match &self.m.contact {
            Some(c) => MissionPlant::Contact(ContactLoop::new(
                c,
                self.wm,
                h,
                self.m.file.start.pose[2],
                &BodySet::All,
            )?),
            None => MissionPlant::Rolling(RollingPlant::new(
                &mut rolling,
                initial_state(self.m),
                IntegratorSettings::Rk4 {
                    dt: h,
                    max_steps: Some(MAX_STEP_BUDGET),
                },
                &MonitorLimits::default(),
                Grid {
                    n: (time_limit / h).ceil() as usize + 1,
                    end: &end,
                    rk4: Some((h, &one_step)),
                    switches: false,
                    max_step_cap: h,
                },
            )?),
        };
        let mut noise = self.m.sensor_noise.clone();
        let ws = Workspace::new(
            self.wm,
            plant_robot,
            self.m.file.limits.mu,
            noise.is_some(),
            self.m.task.as_ref(),
            &self.m.box_objects,
        )?;
        let act = Actuators::new(self.wm)?;
        let c = RunSettings::new(
            self.m, self.wm, &self.goal, &self.tip, act, time_limit, rec_every,
        )?;
        let st = LoopState::new(&self);
        let sim_clock = Instant::now();
        let mut tick = MissionTick {
            runner: &mut self,
            c,
            ws,
            st,
        };
        run_held_loop(&mut plant, &mut tick, noise.as_mut())?;
        let MissionTick { mut ws, st, .. } = tick;
        self.wall.simulation_s = (sim_clock.elapsed().as_secs_f64() - st.excluded).max(0.0);
        let distances = [ws.distances.take(), ws.drive_distances.take()];
        let edges = (0..ws.monitor.edges().len())
            .map(|i| ws.monitor.edge_label(i))
            .collect();
        Ok(self.finish(&st, plant, distances, edges))
    }

    /// The plan at t = 0 (or the reason there is none: a posture that tips at rest, an
    /// unreachable goal, a path that cannot be timed).
    pub(super) fn first_plan(&mut self) {
        if let Some(reason) = &self.failure {
            let reason = reason.clone();
            self.event(0.0, "failed", reason);
            return;
        }
        if self.timing_accel.is_none() {
            let why = if self.tip.forward.is_none() || self.tip.backward.is_none() {
                "the transport posture tips the robot at rest (its ZMP lies outside the support \
                 polygon), so every motion would tip it"
            } else {
                "the transport posture leaves no acceleration that keeps the ZMP inside the \
                 support, so every motion would tip the robot"
            };
            self.fail(0.0, why.to_string());
            return;
        }
        match self.first_path.take() {
            None => self.fail(
                0.0,
                "the goal is unreachable: no collision-free path from the start on the \
                 configuration space"
                    .to_string(),
            ),
            Some(cells) => {
                let start = TimingStart {
                    t0: 0.0,
                    pose: axle_pose(self.m.file.start.pose, self.wm.base.drive.d),
                    v: 0.0,
                };
                let search = self.first_search;
                if self.make_reference(cells, start, "start", search) {
                    let d = self.plans[0].duration;
                    self.event(0.0, "plan", format!("first plan: {d:.2} s"));
                }
            }
        }
    }

    /// The simulated time limit (s) and the record interval in control steps. A run too
    /// long is an error naming the field the user set: `simulation.time_limit` when given,
    /// else `simulation.dt` (steps) or `simulation.record_interval` (samples) against the
    /// default time limit.
    pub(super) fn run_length(&self) -> Result<(f64, usize)> {
        let sim = &self.m.file.simulation;
        let (h, ri) = (sim.dt, sim.record_interval);
        let planned = self.plans.first().map(|p| p.duration);
        let time_limit = sim
            .time_limit
            .unwrap_or_else(|| planned.map_or(10.0, |p| 3.0 * p + 30.0));
        let default_limit = || match planned {
            Some(p) => format!(
                "the default time limit of {time_limit} s (3 × the first plan's {p} s + 30 s)"
            ),
            None => format!("the default time limit of {time_limit} s"),
        };
        let too_long =
            |field: &str, what: String| Err(Error::parse(&self.m.path, format!("{field}: {what}")));
        let (steps, samples) = (time_limit / h, time_limit / ri);
        if steps > MAX_STEPS {
            return match sim.time_limit {
                Some(_) => too_long(
                    "simulation.time_limit",
                    format!(
                        "{time_limit} s at simulation.dt = {h} s is {steps:e} steps, more than {MAX_STEPS:e}"
                    ),
                ),
                None => too_long(
                    "simulation.dt",
                    format!(
                        "{h} s over {} is {steps:e} steps, more than {MAX_STEPS:e}: raise simulation.dt or set a shorter simulation.time_limit",
                        default_limit()
                    ),
                ),
            };
        }
        if samples > MAX_SAMPLES {
            return match sim.time_limit {
                Some(_) => too_long(
                    "simulation.time_limit",
                    format!(
                        "{time_limit} s at simulation.record_interval = {ri} s is {samples:e} samples, more than {MAX_SAMPLES:e}"
                    ),
                ),
                None => too_long(
                    "simulation.record_interval",
                    format!(
                        "{ri} s over {} is {samples:e} samples, more than {MAX_SAMPLES:e}: raise simulation.record_interval or set a shorter simulation.time_limit",
                        default_limit()
                    ),
                ),
            };
        }
        let rec_every = ((ri / h).round() as usize).max(1);
        Ok((time_limit, rec_every))
    }

    /// One control step, the loop's tick: obstacle arrivals (and re-plans), the phase, the
    /// control law, the torques, the record with its monitors; the loop then advances
    /// `plant` with the torques held.
    pub(super) fn step(
        &mut self,
        c: &mut RunSettings,
        ws: &mut Workspace,
        st: &mut LoopState,
        plant: &mut MissionPlant<'_>,
        now: &Tick<'_>,
    ) -> Flow {
        let (nq, nr) = (c.nq, c.nr);
        let t = now.t;
        st.t = t;
        st.k = now.k;
        ws.first_stage_known = false;
        // what the contact plant did over the last period
        if let Some(cl) = plant.contact() {
            for n in cl.news() {
                self.event(n.t, n.kind, n.text);
            }
        }
        // the plant's state and what the law measures (through the sensor noise if any;
        // the record, the monitors and the energy keep the plant's own)
        ws.q_plant.copy_from_slice(now.q_plant);
        ws.v_plant.copy_from_slice(now.v_plant);
        ws.q_now.copy_from_slice(now.q);
        ws.v_now.copy_from_slice(now.v);
        let pose = [ws.q_now[0], ws.q_now[1], ws.q_now[2]];
        let axle = axle_pose(pose, c.d);
        let (v, w) = (ws.v_now[0], ws.v_now[1]);

        self.obstacle_arrivals(c, st, t, axle, v);

        // the reduced dynamics of the state, evaluated once: the law's model (Mr, cr + Gr,
        // N_C, Ṅ_C v under zero input), then below the plant's response to the torques
        // (v̇, q̈, λ) for the monitors and the integrator's first stage
        let evaluated = match reduced_forward_dynamics_crba(
            self.wm,
            &mut ws.control_dynamics,
            &ws.q_now,
            &ws.v_now,
            &ws.zero_u,
        ) {
            Ok(_) => true,
            Err(e) => {
                self.fail(t, format!("the dynamics became singular: {e}"));
                st.phase = Phase::Done;
                false
            }
        };

        self.phase_transitions(c, st, t, pose, v, w);

        // end-effector kinematics in reduced coordinates (for the reach phase and the
        // record)
        let need_ee =
            matches!(st.phase, Phase::Reach | Phase::WholeBody) || st.k.is_multiple_of(c.rec_every);
        let ee = if need_ee {
            end_effector_kinematics(self.m, ws)
        } else {
            EeState::default()
        };

        // control law: desired reduced accelerations
        let speed_clip = match st.phase {
            Phase::Drive | Phase::Arrive => {
                if !self.check_task_distances(ws, st, t) {
                    return Flow::Retry;
                }
                let reference = if st.phase == Phase::Drive {
                    Some(
                        self.reference
                            .as_ref()
                            .expect("drive has a reference")
                            .at(t),
                    )
                } else {
                    None
                };
                let (r, clip) = c.platform_law(reference, t, axle, v, w, ws);
                st.cur_ref = r;
                clip
            }
            Phase::Reach => {
                if !self.reach(c, st, ws, &ee, t, v, w) {
                    // record the state on the next pass, in phase `done`
                    return Flow::Retry;
                }
                false
            }
            Phase::Arm(stage) => {
                if !self.arm_step(c, st, ws, stage, t, axle, v, w) {
                    return Flow::Retry;
                }
                false
            }
            Phase::WholeBody => {
                if !self.whole_body_step(c, st, ws, t, pose, v, w) {
                    return Flow::Retry;
                }
                false
            }
            // the run ends at this sample: no step follows, so no torque is computed and
            // the record shows the input the plant last had (zero at t = 0)
            Phase::Done => false,
        };

        let last = st.phase == Phase::Done;
        // (law mpc wrote its own torques)
        if !last && st.phase != Phase::WholeBody {
            let torque_clip =
                c.act
                    .torque
                    .inputs(&ws.control_dynamics.reduced, &ws.a_des, &mut ws.u);
            self.saturation_events(st, t, torque_clip, speed_clip);
        }
        let evaluated = evaluated
            && reduced_forward_dynamics_under_inputs(
                self.wm,
                &mut ws.control_dynamics,
                &ws.q_now,
                &ws.u,
            )
            .is_ok();
        // a payload attached in this step: the plant takes it before the record
        if std::mem::take(&mut ws.attach_pending) {
            plant.attach(self.wm);
        }
        if st.k.is_multiple_of(c.rec_every) || last {
            self.record_and_check(c, ws, st, plant, t, ee.p, evaluated);
        }
        if last {
            return Flow::Finished;
        }

        // actuator energy over the step (rates at its start)
        let v_plant = &ws.v_plant;
        st.energy += c.act.absolute_power(&ws.u, v_plant, v_plant[0], v_plant[1]) * c.h;

        // the rolling plant's first RK4 stage is the state's evaluation under the torques
        // just formed (on the law's model, which is the plant's unless [uncertainty]
        // perturbs it or the law measured a noisy state)
        if evaluated
            && self.m.plant_robot.is_none()
            && !ws.noisy
            && matches!(plant, MissionPlant::Rolling(_))
        {
            let cd = &ws.control_dynamics;
            ws.first_stage[..nq].copy_from_slice(cd.qdot.as_slice());
            ws.first_stage[nq..nq + nr].copy_from_slice(cd.reduced.vdot.as_slice());
            ws.first_stage[nq + nr] = cd.force.dot(&cd.qdot);
            ws.first_stage_known = true;
        }
        Flow::Next
    }

    /// The result of the finished loop.
    pub(super) fn finish(
        mut self,
        st: &LoopState,
        plant: MissionPlant<'_>,
        [arm, drives]: [Option<DistanceMonitor>; 2],
        support_edges: Vec<String>,
    ) -> MissionResult {
        if let Some(tr) = &mut self.task {
            if let Some(dm) = arm {
                if let Some((d, pair)) = dm.min_scene {
                    tr.min_scene_distance = Some(d);
                    tr.closest_scene_pair = Some(pair);
                }
                if let Some((d, pair)) = dm.min_box {
                    tr.min_box_distance = Some(d);
                    tr.closest_box_pair = Some(pair);
                }
                if let Some((d, pair)) = dm.min_self {
                    tr.min_self_distance = Some(d);
                    tr.closest_self_pair = Some(pair);
                }
            }
            tr.driving = drives.and_then(|dm| dm.scene_minimum());
        }
        self.min_zmp_event();
        self.events.sort_by(|a, b| a.t.total_cmp(&b.t));
        let reached = self.failure.is_none() && st.time_to_goal.is_some();
        let reason = if reached {
            None
        } else {
            Some(
                self.failure
                    .clone()
                    .unwrap_or_else(|| "the mission ended before the goal".into()),
            )
        };
        let wm = self.wm;
        let model = &wm.model;
        let arm_names = wm
            .arm_dofs()
            .iter()
            .map(|&i| model.names[model.joint_of_dof[i].0].clone())
            .collect();
        MissionResult {
            reached,
            reason,
            time_to_goal: if reached { st.time_to_goal } else { None },
            duration: st.t,
            tip_limits: self.tip,
            timing_acceleration: self.timing_accel.map(|a| [a.forward, a.backward]),
            plans: self.plans,
            events: self.events,
            samples: self.samples,
            q_names: wm.q_names(),
            u_names: wm.u_names(),
            arm_names,
            torque_saturated_steps: st.torque_sat,
            speed_saturated_steps: st.speed_sat,
            steps: st.k,
            input_work: plant.input_work(),
            wall: self.wall,
            contact: match plant {
                MissionPlant::Rolling(_) => None,
                MissionPlant::Contact(cl) => Some(cl.tally().clone().finish()),
            },
            goal_pose: self.goal.pose,
            task: self.task,
            support_edges,
            mpc: self.whole_body.as_ref().and_then(WholeBodyLaw::summary),
        }
    }
}

/// The mission as the held-input loop's law: the runner with the run's settings,
/// workspaces and loop state; its tick is [`Runner::step`].
struct MissionTick<'r, 'm> {
    runner: &'r mut Runner<'m>,
    c: RunSettings,
    ws: Workspace,
    st: LoopState,
}

impl<'s> TickLaw<MissionPlant<'s>> for MissionTick<'_, '_> {
    fn tick(&mut self, plant: &mut MissionPlant<'s>, now: &mut Tick<'_>) -> Result<TickEnd> {
        let flow = self
            .runner
            .step(&mut self.c, &mut self.ws, &mut self.st, plant, now);
        now.u.copy_from_slice(&self.ws.u);
        Ok(match flow {
            Flow::Next => TickEnd::Hold,
            Flow::Retry => TickEnd::Again,
            Flow::Finished => TickEnd::Stop,
        })
    }

    fn first_stage(&self) -> Option<&[f64]> {
        self.ws
            .first_stage_known
            .then_some(self.ws.first_stage.as_slice())
    }

    /// The run ends, its last sample recorded in this tick.
    fn measurement_failed(&mut self, t: f64, e: Error) -> Result<()> {
        self.runner.fail(t, format!("the measurement failed: {e}"));
        self.st.phase = Phase::Done;
        Ok(())
    }

    /// The run ends at the state reached before the failure, recorded in a repeated tick.
    fn advance_failed(&mut self, plant: &mut MissionPlant<'s>, t: f64, e: Error) -> Result<()> {
        if let Some(cl) = plant.contact() {
            for n in cl.news() {
                self.runner.event(n.t, n.kind, n.text);
            }
        }
        self.runner.fail(t, format!("the simulation failed: {e}"));
        self.st.phase = Phase::Done;
        Ok(())
    }
}

/// How a control step ends.
pub(super) enum Flow {
    /// The step was taken.
    Next,
    /// The run just ended: the same step is taken again in phase `done` (recorded).
    Retry,
    /// The last sample is recorded.
    Finished,
}

/// The state the loop carries from step to step (besides the plant state).
pub(super) struct LoopState {
    pub(super) k: usize,
    pub(super) t: f64,
    pub(super) phase: Phase,
    pub(super) phase_t0: f64,
    pub(super) ee_traj: Option<EeTrajectory>,
    pub(super) energy: f64,
    pub(super) torque_sat: usize,
    pub(super) speed_sat: usize,
    pub(super) first_torque_sat: bool,
    pub(super) first_speed_sat: bool,
    pub(super) first_slip: bool,
    pub(super) first_contact: bool,
    pub(super) time_to_goal: Option<f64>,
    pub(super) cur_ref: RefSample,
    /// Planning wall time spent inside the loop (s).
    pub(super) excluded: f64,
    pub(super) next_obstacle: usize,
    /// A `[task]`'s arm motion being tracked.
    pub(super) arm: Option<ArmMotion>,
    /// The picked object is attached.
    pub(super) grasped: bool,
    /// The pick is done (the arm back in the transport posture).
    pub(super) picked: bool,
}

impl LoopState {
    pub(super) fn new(r: &Runner<'_>) -> Self {
        let start = r.m.file.start.pose;
        Self {
            k: 0,
            t: 0.0,
            phase: if r.failure.is_some() {
                Phase::Done
            } else if r.whole_body.is_some() {
                Phase::WholeBody
            } else {
                Phase::Drive
            },
            phase_t0: 0.0,
            ee_traj: None,
            energy: 0.0,
            torque_sat: 0,
            speed_sat: 0,
            first_torque_sat: true,
            first_speed_sat: true,
            first_slip: true,
            first_contact: true,
            time_to_goal: None,
            cur_ref: RefSample {
                t: 0.0,
                x: start[0],
                y: start[1],
                theta: start[2],
                v: 0.0,
                omega: 0.0,
                a: 0.0,
                alpha: 0.0,
            },
            excluded: 0.0,
            next_obstacle: 0,
            arm: None,
            grasped: false,
            picked: false,
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::mission::plan::first_plan_request;
    use crate::mission::reference::axle_pose;
    use crate::planning::pipeline::{self, PlanFields};

    /// The pipeline's curvature-limited timing of the mission's first plan is the
    /// reference the mission tracks first (`mission.toml`: its recorded path and
    /// duration); the timing needs the start heading.
    #[test]
    fn curvature_timing_is_the_missions_first_reference() {
        use crate::planning::curve_timing::CurvatureTiming;
        use crate::planning::pipeline::Timing;
        let path =
            std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/mission.toml");
        let m = crate::mission::load(&path).unwrap();
        let run = crate::mission::run(&m).unwrap();
        let first = &run.plans[0];
        let (f, d) = (&m.file, m.robot.base.drive.d);
        let (s0, g0) = (
            axle_pose(f.start.pose, d),
            axle_pose(m.goal().unwrap().pose, d),
        );
        let tip = super::super::tip_over::timing_acceleration(
            &super::super::tip_over::transport_tip_limits(&m).unwrap(),
            f.limits.tip_fraction,
        )
        .unwrap();
        let l = &f.limits;
        let fields = PlanFields {
            start: "start.pose",
            goal: "goal.pose",
            radius: "robot.footprint_radius",
        };
        let mut req = first_plan_request(
            f.map.unknown_is_obstacle,
            fields,
            m.footprint.radius,
            d,
            [s0[0], s0[1]],
            [g0[0], g0[1]],
        );
        req.start_yaw = Some(s0[2]);
        req.goal_yaw = Some(g0[2]);
        req.timing = Some(Timing::Curvature {
            timing: CurvatureTiming {
                limits: l.platform(),
                tip,
                kappa_max: l.kappa_max,
                dt: 0.02,
            },
        });
        let plan = pipeline::plan(&m.map.grid, &req).unwrap();
        assert_eq!(plan.cells, first.cells);
        let curve = plan.curve.clone().unwrap();
        assert_eq!(plan.trajectory.len(), curve.samples.len());
        let reference = super::super::reference::reference_of_curve(curve, first.t, d);
        assert_eq!(reference.path, first.path);
        assert_eq!(reference.t_end() - first.t, first.duration);
        req.start_yaw = None;
        let e = pipeline::plan(&m.map.grid, &req).unwrap_err().to_string();
        assert!(e.contains("timing") && e.contains("start heading"), "{e}");
    }
}

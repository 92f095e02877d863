//! The closed loop of a mission: plan, time, track, monitor, re-plan, reach.

use std::time::Instant;

use nalgebra::{DMatrix, DVector, Matrix2, Matrix3, Matrix6xX, Vector2, Vector3};

use super::plan::{Planner, PolygonCheck, SearchTiming};
use super::plant::{ContactLoop, Monitors, start_configuration};
use super::reference::{
    RefSample, Reference, TimingStart, base_reference, brake_along, build_reference,
};
use super::scenario::{GoalSpec, MAX_SAMPLES, MAX_STEPS, Mission};
use super::task::{
    ARM_MARGIN, ArmPlanRecord, DistanceMonitor, PayloadRecord, PlacementChoice, Task, TaskResult,
};
use super::whole_body::WholeBodyLaw;
use crate::control::unicycle::{Aicardi, Kanayama, ReferenceSample};
use crate::control::wrap_angle;
use crate::error::{Error, Result};
use crate::kinematics::{ReferenceFrame, frame_acceleration_bias, frame_jacobian_from_kinematics};
use crate::mobile::wheeled::{
    admissible_velocity_basis_dot, lagrange_multipliers, reduced_forward_dynamics_crba,
    reduced_forward_dynamics_under_inputs,
};
use crate::mobile::{WheeledData, WheeledModel};
use crate::multibody::Data;
use crate::ode::{OdeSystem, Rk4};
use crate::planning::footprint_clearance::ConvexFootprint;
use crate::planning::trajectory::{DiffDriveLimits, TipOverAcceleration};
use crate::sim::computed_torque::ComputedTorque;
use crate::sim::contact_run::ContactTally;
use crate::sim::model_mismatch::SensorNoise;
use crate::sim::mpc_run::MpcRunSummary;
use crate::sim::reduced_system::ReducedSystem;
use crate::sim::stability_monitor::{StabilityMonitor, StabilitySettings};
use crate::sim::wheeled_system::WheeledSystem;
use crate::stability::{AccelerationLimits, BodySet, SupportPolygon};

/// Spacing of the reference samples (s).
const REF_DT: f64 = 0.02;
/// Time allowed after the reference ends to settle on the goal pose (s).
const ARRIVE_TIMEOUT: f64 = 8.0;
/// Time allowed after the end-effector trajectory ends to settle on the target (s).
const REACH_SETTLE: f64 = 5.0;
/// Distance (m) beyond the footprint within which the clearance is exact.
const EXACT_CLEARANCE: f64 = 1.0;
/// Re-plans with the colliding cells blocked before the footprint polygon's search
/// falls back to the circumscribed disk.
const POLYGON_REPAIRS: usize = 10;
/// Time allowed after an arm trajectory ends to settle on its last state (s).
const ARM_SETTLE: f64 = 3.0;
/// An arm motion has ended when every group joint is this close to its last state (rad
/// or m) and moves slower than [`ARM_SETTLED_RATE`].
const ARM_SETTLED: f64 = 0.01;
/// Joint rate (rad/s or m/s) below which a settled arm joint counts as at rest.
const ARM_SETTLED_RATE: f64 = 0.02;
/// Tolerances of the base at a task's placement (m, rad).
const PLACEMENT_TOLERANCE: [f64; 2] = [0.05, 0.05];

/// A path the footprint passes: its cells, its timed reference and the wall time (s) of
/// its smoothing, timing and checks.
struct CheckedPath {
    cells: Vec<(usize, usize)>,
    reference: Reference,
    smoothing_s: f64,
}

/// One re-plan (or the first plan) of a run.
#[derive(Debug, Clone, serde::Serialize)]
pub struct PlanRecord {
    /// Mission time when it was made (s).
    pub t: f64,
    /// What triggered it.
    pub trigger: String,
    /// The D* Lite cell path, start to goal.
    pub cells: Vec<(usize, usize)>,
    /// The smoothed path (world, m).
    pub path: Vec<[f64; 2]>,
    /// Duration of its timed reference (s).
    pub duration: f64,
    /// D* Lite wall time (s) and expanded cells.
    pub search: SearchTiming,
    /// Smoothing + time parameterisation (+ the footprint polygon's check) wall time (s).
    pub smoothing_timing_s: f64,
    /// Forward speed the timing started from (m/s).
    pub v_start: f64,
}

/// Something that happened during the run.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Event {
    /// Mission time (s).
    pub t: f64,
    /// Kind: `plan`, `obstacle`, `replan`, `torque_limit`, `speed_limit`, `slip`,
    /// `lift_off` (contact plant), `contact`, `min_zmp_margin`, `arrived`, `reached`,
    /// `failed`.
    pub kind: String,
    /// Human-readable detail.
    pub text: String,
}

/// The recorded run, one entry per sample in every column.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct Samples {
    /// Time (s).
    pub t: Vec<f64>,
    /// Full configuration q per sample (the model's order).
    pub q: Vec<Vec<f64>>,
    /// Executed forward speed of the driven-axle midpoint (m/s).
    pub v: Vec<f64>,
    /// Executed yaw rate (rad/s).
    pub omega: Vec<f64>,
    /// Reference speed and yaw rate.
    pub v_ref: Vec<f64>,
    /// Reference yaw rate.
    pub omega_ref: Vec<f64>,
    /// Reference position of the base frame origin (the axle midpoint's reference moved
    /// `d` ahead along the reference heading).
    pub ref_xy: Vec<[f64; 2]>,
    /// ZMP margin (m); `None` where the ZMP is undefined (tipping). On the contact plant:
    /// the centre of pressure of its normal forces inside the support, `None` while no
    /// contact is loaded.
    pub zmp_margin: Vec<Option<f64>>,
    /// The support edge of that margin, an index into [`MissionResult::support_edges`]
    /// (on the contact plant the edge nearest the centre of pressure); `None` where the
    /// margin is.
    pub zmp_critical_edge: Vec<Option<usize>>,
    /// Smallest Force-Angle measure (rad).
    pub force_angle_min: Vec<Option<f64>>,
    /// Smallest Moment-Height measure.
    pub mhs_min: Vec<Option<f64>>,
    /// Footprint edge to the nearest occupied cell's boundary (m).
    pub clearance: Vec<f64>,
    /// Distance of the base frame origin from its reference position (m).
    pub tracking_error: Vec<f64>,
    /// Larger drive-wheel slip ratio |(F_long, F_lat)| / (μ N) (`stability::loads`: the
    /// lateral axle force −λ₀ shared in proportion to the normal loads); `None` if a wheel
    /// carries no load. On the contact plant: each wheel's friction force over μ N, μ of
    /// `[contact]` (1 while it slides).
    pub slip_ratio: Vec<Option<f64>>,
    /// Actuator torques per sample (`u`, the model's input order).
    pub u: Vec<Vec<f64>>,
    /// End-effector position (world, m).
    pub ee: Vec<[f64; 3]>,
    /// Arm chain (joint origins, then the end effector) in the base x–z plane (m).
    pub arm_side: Vec<Vec<[f64; 2]>>,
    /// Actuator energy so far ∫ Σ |u_j · rate_j| dt (J).
    pub energy: Vec<f64>,
    /// Mission phase: `drive`, `arrive`, `reach`, with a `[task]` `approach`, `grasp`,
    /// `retreat`; `done`.
    pub phase: Vec<&'static str>,
    /// On the contact plant: each contact's normal force (N; the wheels, then the
    /// casters, as [`ContactTally::totals`]); empty on the rolling plant.
    pub contact_normal: Vec<Vec<f64>>,
}

/// Wall times of the run's parts (s).
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct WallTimes {
    /// Map → C-space → first search, plus every re-plan's search.
    pub planning_s: f64,
    /// Every smoothing and time parameterisation, with the footprint polygon's checks.
    pub smoothing_timing_s: f64,
    /// The closed-loop simulation with its monitors (planning excluded).
    pub simulation_s: f64,
}

/// The outcome of a mission.
#[derive(Debug, Clone, serde::Serialize)]
pub struct MissionResult {
    /// `true` when the base reached the goal pose (and the end effector its target).
    pub reached: bool,
    /// Why not (`None` when reached).
    pub reason: Option<String>,
    /// Mission time when the goal was reached (s).
    pub time_to_goal: Option<f64>,
    /// Simulated time (s).
    pub duration: f64,
    /// Tip-over acceleration limits of the transport posture at rest (base axes, m/s²).
    pub tip_limits: AccelerationLimits,
    /// The accelerations the timing used (m/s²): `[forward, backward]`.
    pub timing_acceleration: Option<[f64; 2]>,
    /// Plans, the first at t = 0.
    pub plans: Vec<PlanRecord>,
    /// Events in time order.
    pub events: Vec<Event>,
    /// Recorded samples.
    pub samples: Samples,
    /// Names of q, of the inputs u, and of the arm joints.
    pub q_names: Vec<String>,
    /// Input names.
    pub u_names: Vec<String>,
    /// Arm joint names (model order).
    pub arm_names: Vec<String>,
    /// Control steps whose torques were clipped at a limit.
    pub torque_saturated_steps: usize,
    /// Control steps whose speed commands were clipped at a limit.
    pub speed_saturated_steps: usize,
    /// Control steps.
    pub steps: usize,
    /// Net work of the actuators ∫ Qᵀ q̇ dt (J).
    pub input_work: f64,
    /// Wall times.
    pub wall: WallTimes,
    /// On the contact plant (`simulation.plant = "contact"`): the first lift-off and the
    /// first slip, per-contact totals and the largest tilt; `None` on the rolling plant.
    pub contact: Option<ContactTally>,
    /// The base pose the run drove to: `[goal]`'s, or with `[task]` the placement (the
    /// start pose when none was found).
    pub goal_pose: [f64; 3],
    /// With `[task]`: the placement, the arm plans, the payload and the distances.
    pub task: Option<TaskResult>,
    /// The support polygon's edges (numbered in the base frame, as the stability
    /// monitor's), each named `edge A-B` by its two contacts (wheel joints, casters).
    pub support_edges: Vec<String>,
    /// Law `mpc`: the MPC's summary (solve times, iterations, violations), as `moma
    /// simulate`'s.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mpc: Option<MpcRunSummary>,
}

impl MissionResult {
    /// Number of re-plans (plans after the first).
    pub fn replans(&self) -> usize {
        self.plans.len().saturating_sub(1)
    }
}

fn min_opt(xs: &[Option<f64>]) -> Option<f64> {
    xs.iter().flatten().copied().reduce(f64::min)
}

impl MissionResult {
    /// Smallest ZMP margin of the run (m); `None` if never defined.
    pub fn min_zmp_margin(&self) -> Option<f64> {
        min_opt(&self.samples.zmp_margin)
    }
    /// Smallest Force-Angle measure.
    pub fn min_force_angle(&self) -> Option<f64> {
        min_opt(&self.samples.force_angle_min)
    }
    /// Smallest Moment-Height measure.
    pub fn min_mhs(&self) -> Option<f64> {
        min_opt(&self.samples.mhs_min)
    }
    /// Smallest clearance (m).
    pub fn min_clearance(&self) -> Option<f64> {
        self.samples.clearance.iter().copied().reduce(f64::min)
    }
    /// Largest tracking error (m).
    pub fn max_tracking_error(&self) -> Option<f64> {
        self.samples.tracking_error.iter().copied().reduce(f64::max)
    }
    /// Largest slip ratio.
    pub fn max_slip_ratio(&self) -> Option<f64> {
        self.samples
            .slip_ratio
            .iter()
            .flatten()
            .copied()
            .reduce(f64::max)
    }
}

/// The plant under a zero-order-hold input.
struct Plant<'a> {
    sys: &'a mut WheeledSystem,
    u: &'a [f64],
    nq: usize,
    nr: usize,
}

impl OdeSystem for Plant<'_> {
    fn dim(&self) -> usize {
        self.nq + self.nr + 1
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<()> {
        let (q, rest) = x.split_at(self.nq);
        let v = &rest[..self.nr];
        let (qd, rest_d) = dx.split_at_mut(self.nq);
        let (vd, wd) = rest_d.split_at_mut(self.nr);
        self.sys.dynamics(q, v, self.u, qd, vd)?;
        wd[0] = self.sys.input_power(q, v, self.u)?;
        Ok(())
    }
}

#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Phase {
    Drive,
    Arrive,
    Reach,
    /// A `[task]`'s arm motion.
    Arm(ArmStage),
    /// Law `mpc`: drive and reach at once, up to the goal.
    WholeBody,
    Done,
}

/// The arm motions of a pick, in order.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum ArmStage {
    /// To the pre-grasp.
    Approach,
    /// From the pre-grasp to the grasp.
    Grasp,
    /// With the object, back to the transport posture.
    Retreat,
}

impl Phase {
    /// The base follows the timed reference (which a blocking obstacle re-plans): `drive`,
    /// and law `mpc`'s `whole_body`.
    fn follows_reference(self) -> bool {
        matches!(self, Phase::Drive | Phase::WholeBody)
    }

    fn name(self) -> &'static str {
        match self {
            Phase::Drive => "drive",
            Phase::Arrive => "arrive",
            Phase::Reach => "reach",
            Phase::Arm(ArmStage::Approach) => "approach",
            Phase::Arm(ArmStage::Grasp) => "grasp",
            Phase::Arm(ArmStage::Retreat) => "retreat",
            Phase::WholeBody => "whole_body",
            Phase::Done => "done",
        }
    }
}

/// An arm motion being tracked: its trajectory from `t0` and its last state.
struct ArmMotion {
    t0: f64,
    trajectory: crate::motion::MotionTrajectory,
}

impl ArmMotion {
    /// The group's reference (q, q̇, q̈) at mission time `t` (linear between samples;
    /// q̈ the difference of the bracketing rates), written into `q` (full configuration),
    /// `qd` and `qdd` (group order).
    fn at(
        &self,
        t: f64,
        group: &crate::motion::JointGroup,
        q: &mut [f64],
        qd: &mut [f64],
        qdd: &mut [f64],
    ) {
        let tr = &self.trajectory;
        let s = (t - self.t0).clamp(0.0, tr.duration);
        let n = tr.t.len();
        if n < 2 {
            q.copy_from_slice(&tr.q[0]);
            qd.fill(0.0);
            qdd.fill(0.0);
            return;
        }
        let k = tr.t.partition_point(|&ti| ti <= s).clamp(1, n - 1);
        let (a, b) = (k - 1, k);
        let h = (tr.t[b] - tr.t[a]).max(f64::MIN_POSITIVE);
        let w = ((s - tr.t[a]) / h).clamp(0.0, 1.0);
        q.copy_from_slice(&tr.q[a]);
        for (j, &i) in group.q_index.iter().enumerate() {
            q[i] = tr.q[a][i] + w * (tr.q[b][i] - tr.q[a][i]);
            let (va, vb) = (tr.qd[a][j], tr.qd[b][j]);
            if t - self.t0 >= tr.duration {
                qd[j] = 0.0;
                qdd[j] = 0.0;
            } else {
                qd[j] = va + w * (vb - va);
                qdd[j] = (vb - va) / h;
            }
        }
    }

    /// The last state of the trajectory (full configuration).
    fn last(&self) -> &[f64] {
        self.trajectory.q.last().expect("a trajectory has samples")
    }
}

/// Minimum-jerk point-to-point segment of the end effector.
#[derive(Clone, Copy, Debug)]
struct EeTrajectory {
    t0: f64,
    duration: f64,
    from: Vector3<f64>,
    to: Vector3<f64>,
}

impl EeTrajectory {
    fn at(&self, t: f64) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        let s = ((t - self.t0) / self.duration).clamp(0.0, 1.0);
        let d = self.to - self.from;
        let (p, dp, ddp) = if t - self.t0 >= self.duration {
            (1.0, 0.0, 0.0)
        } else {
            (
                s * s * s * (10.0 - 15.0 * s + 6.0 * s * s),
                30.0 * s * s * (1.0 - s) * (1.0 - s) / self.duration,
                60.0 * s * (1.0 - 3.0 * s + 2.0 * s * s) / (self.duration * self.duration),
            )
        };
        (self.from + d * p, d * dp, d * ddp)
    }
}

/// Length of a polyline (m).
fn path_length(p: &[[f64; 2]]) -> f64 {
    p.windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum()
}

/// The pose of the driven-axle midpoint P0 (the unicycle point) of a base pose
/// `[x, y, θ]` whose origin lies `d` ahead of it: `[x − d cos θ, y − d sin θ, θ]`.
/// The mission's planner between two axle-midpoint poses. With the robot's footprint
/// polygon: searched on the largest disk about the axle midpoint inside it (padded), and
/// every path it gives checked with the polygon at each heading; with a disk: the map
/// dilated by it (and `|d|`).
fn mission_planner(
    m: &Mission,
    from: [f64; 3],
    to: [f64; 3],
) -> Result<(Planner, Option<super::plan::CellPath>, SearchTiming)> {
    let d = m.robot.base.drive.d;
    let grid = &m.map.grid;
    let polygon = m.footprint.planning_polygon(d);
    let (field, radius, offset) = match &polygon {
        Some((_, inscribed)) => ("robot.footprint", inscribed + m.footprint.padding(), 0.0),
        None if m.file.robot.footprint.is_some() => ("robot.footprint", m.footprint.radius, d),
        None => ("robot.footprint_radius", m.footprint.radius, d),
    };
    let (mut planner, path, search) = Planner::new(
        grid,
        m.file.map.unknown_is_obstacle,
        field,
        radius,
        offset,
        [from[0], from[1]],
        [to[0], to[1]],
    )?;
    if let Some((fp, _)) = polygon {
        let res = grid.resolution;
        planner.polygon = Some(PolygonCheck::new(
            ConvexFootprint::new(&fp, res)?,
            m.footprint.padding() / res,
            d / res,
        ));
    }
    Ok((planner, path, search))
}

fn axle_pose(base: [f64; 3], d: f64) -> [f64; 3] {
    if d == 0.0 {
        return base;
    }
    let (s, c) = base[2].sin_cos();
    [base[0] - d * c, base[1] - d * s, base[2]]
}

/// The tip-over limits the timing may use (`tip_fraction` of them): a side no edge limits
/// is unbounded; a posture that tips at rest (or has no room to accelerate) cannot be
/// timed (`None`).
fn timing_acceleration(tip: &AccelerationLimits, tip_fraction: f64) -> Option<TipOverAcceleration> {
    match (tip.forward, tip.backward) {
        (Some(fw), Some(bw)) if fw > 0.0 && bw > 0.0 => {
            let side = |x: Option<f64>| x.map_or(f64::INFINITY, |a| tip_fraction * a);
            Some(TipOverAcceleration {
                forward: tip_fraction * fw,
                backward: tip_fraction * bw,
                left: side(tip.left),
                right: side(tip.right),
            })
            .filter(|t| t.left > 0.0 && t.right > 0.0)
        }
        _ => None,
    }
}

/// The tip-over acceleration limits of the robot in its transport posture, at rest, in
/// base axes.
pub fn transport_tip_limits(m: &Mission) -> Result<AccelerationLimits> {
    tip_limits_of(m, &m.robot)
}

/// [`transport_tip_limits`] of `robot` (the mission's, or with a `[task]`'s payload).
fn tip_limits_of(m: &Mission, robot: &WheeledModel) -> Result<AccelerationLimits> {
    let model = &robot.model;
    let mut q = DVector::zeros(model.nq);
    for (k, &i) in m.robot.arm_dofs().iter().enumerate() {
        q[i] = m.transport[k];
    }
    let mut data = Data::new(model);
    let com = crate::dynamics::center_of_mass(model, &mut data, &q);
    let support = SupportPolygon::from_wheeled_model(robot)?;
    Ok(crate::stability::acceleration_limits(
        model.total_mass(),
        &com,
        &model.gravity,
        &support,
        0.0,
    ))
}

/// The joints of the arm chain that ends at the end-effector frame (root side first).
fn arm_chain(m: &Mission) -> Vec<usize> {
    super::task::arm_chain(&m.robot, m.ee_frame)
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

struct Runner<'m> {
    m: &'m Mission,
    /// The law's robot: the mission's, with a `[task]`'s payload once grasped.
    wm: &'m WheeledModel,
    /// The base goal: `[goal]`, or a `[task]`'s placement.
    goal: GoalSpec,
    /// A `[task]`'s record so far.
    task: Option<TaskResult>,
    /// A `[task]`'s `[goal]`, driven on to after the pick.
    drive_on: Option<GoalSpec>,
    planner: Planner,
    first_path: Option<Vec<(usize, usize)>>,
    first_search: SearchTiming,
    wall: WallTimes,
    tip: AccelerationLimits,
    limits: DiffDriveLimits,
    timing_accel: Option<TipOverAcceleration>,
    plans: Vec<PlanRecord>,
    events: Vec<Event>,
    samples: Samples,
    reference: Option<Reference>,
    failure: Option<String>,
    /// Law `mpc`.
    whole_body: Option<WholeBodyLaw>,
}

impl<'m> Runner<'m> {
    fn new(m: &'m Mission) -> Result<Self> {
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
        let grid = &m.map.grid;
        let (mut planner, first_path, first_search) = mission_planner(m, s0, g0)?;
        if planner.polygon.is_some() {
            for (what, pose, axle) in [
                ("start.pose", f.start.pose, s0),
                ("goal.pose", goal.pose, g0),
            ] {
                if planner.axle_collides(grid, axle) {
                    return Err(Error::invalid(
                        what,
                        format!(
                            "the robot's footprint polygon at ({}, {}, {} rad) overlaps an \
                             obstacle or comes closer to one than the padding ({} m)",
                            pose[0],
                            pose[1],
                            pose[2],
                            m.footprint.padding()
                        ),
                    ));
                }
            }
        }
        let planning_s = clock.elapsed().as_secs_f64();
        let tip = transport_tip_limits(m)?;
        let l = &f.limits;
        let limits = DiffDriveLimits {
            v_max: l.v_max,
            omega_max: l.omega_max,
            a_max: l.a_max,
            alpha_max: l.alpha_max,
        };
        let timing_accel = timing_acceleration(&tip, l.tip_fraction);
        let whole_body = m.mpc.as_ref().map(|(mpc, every)| {
            WholeBodyLaw::new(
                mpc.clone(),
                *every,
                d,
                goal.end_effector,
                f.control.reach_radius.unwrap_or(1.0),
                goal.end_effector_tolerance,
            )
        });
        Ok(Self {
            m,
            wm: &m.robot,
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

    fn event(&mut self, t: f64, kind: &str, text: impl Into<String>) {
        self.events.push(Event {
            t,
            kind: kind.to_string(),
            text: text.into(),
        });
    }

    fn fail(&mut self, t: f64, reason: String) {
        self.event(t, "failed", reason.clone());
        self.failure = Some(reason);
    }

    /// Smooths and times `cells` from `start`; records the plan. `false` on failure.
    fn make_reference(
        &mut self,
        cells: Vec<(usize, usize)>,
        start: TimingStart,
        trigger: &str,
        mut search: SearchTiming,
    ) -> bool {
        match self.checked_reference(cells, &start, &mut search) {
            Some(Ok(p)) => {
                self.adopt(
                    p.cells,
                    p.reference,
                    start.t0,
                    start.v,
                    trigger,
                    search,
                    p.smoothing_s,
                );
                true
            }
            Some(Err(reason)) => {
                self.fail(start.t0, reason);
                false
            }
            None => false,
        }
    }

    /// Smooths and times `cells` from `start` ([`Runner::time_cells`]) and, with the
    /// robot's footprint polygon, checks every sample with the polygon at its heading:
    /// the axle cells of the samples that collide are blocked and D* Lite re-plans, up to
    /// [`POLYGON_REPAIRS`] times; then the search falls back to the circumscribed disk
    /// (`MissionFootprint::radius` about the base frame, `+ |d|` about the axle). The
    /// cells, reference and smoothing wall time it ends with, or the reason there is
    /// none (`None`: no timing accelerations, already reported).
    fn checked_reference(
        &mut self,
        mut cells: Vec<(usize, usize)>,
        start: &TimingStart,
        search: &mut SearchTiming,
    ) -> Option<std::result::Result<CheckedPath, String>> {
        let mut smoothing_s = 0.0;
        let mut repaired = 0;
        let mut polygon = self.planner.polygon.is_some();
        loop {
            let (r, st) = match self.time_cells(&cells, start)? {
                Ok(x) => x,
                Err(e) => return Some(Err(format!("the path could not be timed: {e}"))),
            };
            let clock = Instant::now();
            let bad = if polygon {
                self.colliding_cells(&r)
            } else {
                Vec::new()
            };
            let check_s = clock.elapsed().as_secs_f64();
            self.wall.smoothing_timing_s += check_s;
            smoothing_s += st + check_s;
            if bad.is_empty() {
                // after the fallback to the disk its own event has said how it ended
                if repaired > 0 && polygon {
                    let text = format!(
                        "the footprint polygon collided along the path: {repaired} re-plan(s) \
                         with the colliding cells blocked"
                    );
                    self.event(start.t0, "footprint", text);
                }
                return Some(Ok(CheckedPath {
                    cells,
                    reference: r,
                    smoothing_s,
                }));
            }
            let clock = Instant::now();
            let mut blocked = false;
            if repaired < POLYGON_REPAIRS {
                let robot = self.planner.dstar.start();
                for c in bad.into_iter().filter(|&c| c != robot) {
                    blocked |= self.planner.block(c).unwrap_or(false);
                }
            }
            let (path, timing) = if blocked {
                repaired += 1;
                self.planner.replan()
            } else {
                // the polygon's lower bound gives no path it passes: the circumscribed disk
                polygon = false;
                let grid = &self.m.map.grid;
                let radius = self.m.footprint.radius + self.wm.base.drive.d.abs();
                let sc = self.cell_of(start.pose);
                let text = format!(
                    "the footprint polygon collides along every path found ({repaired} \
                     re-plan(s)): planning on the circumscribed disk of radius {:.3} m",
                    self.m.footprint.radius
                );
                self.event(start.t0, "footprint", text);
                match self.planner.use_disk(radius, grid.resolution, sc) {
                    Ok(true) => self.planner.replan(),
                    _ => (None, SearchTiming::default()),
                }
            };
            let dt = clock.elapsed().as_secs_f64();
            search.search_s += dt;
            search.expanded += timing.expanded;
            self.wall.planning_s += dt;
            match path {
                Some(p) => cells = p,
                None => {
                    return Some(Err(
                        "the goal is unreachable: no path on the configuration space that the \
                         robot's footprint polygon passes at the headings it is driven with"
                            .to_string(),
                    ));
                }
            }
        }
    }

    /// The cell of a world point (clamped to the map).
    fn cell_of(&self, p: [f64; 3]) -> (usize, usize) {
        let grid = &self.m.map.grid;
        let [fx, fy] = grid.world_to_cell_f(p[0], p[1]);
        (
            (fx.floor().max(0.0) as usize).min(grid.width - 1),
            (fy.floor().max(0.0) as usize).min(grid.height - 1),
        )
    }

    /// The axle cells of the samples of `r` where the footprint collides
    /// ([`Planner::axle_collides`]), each once.
    fn colliding_cells(&mut self, r: &Reference) -> Vec<(usize, usize)> {
        let mut out = Vec::new();
        for s in &r.samples {
            let p = [s.x, s.y, s.theta];
            if self.planner.axle_collides(&self.m.map.grid, p) {
                let c = self.cell_of(p);
                if !out.contains(&c) {
                    out.push(c);
                }
            }
        }
        out
    }

    /// Smooths and times `cells` from `start` (`None` without timing accelerations),
    /// with the wall time it took.
    fn time_cells(
        &mut self,
        cells: &[(usize, usize)],
        start: &TimingStart,
    ) -> Option<Result<(Reference, f64)>> {
        let accel = self.timing_accel?;
        let clock = Instant::now();
        let r = build_reference(
            &self.m.map.grid,
            self.planner.dstar.grid(),
            cells,
            start,
            axle_pose(self.goal.pose, self.wm.base.drive.d),
            self.wm.base.drive.d,
            &self.limits,
            &accel,
            self.m.file.limits.kappa_max,
            REF_DT,
        );
        let st = clock.elapsed().as_secs_f64();
        self.wall.smoothing_timing_s += st;
        Some(r.map(|r| (r, st)))
    }

    /// Makes `r` (timed from `t0` at speed `v_start`, from `cells`) the reference to
    /// track and records it as a plan.
    #[allow(clippy::too_many_arguments)]
    fn adopt(
        &mut self,
        cells: Vec<(usize, usize)>,
        r: Reference,
        t0: f64,
        v_start: f64,
        trigger: &str,
        search: SearchTiming,
        smoothing_timing_s: f64,
    ) {
        if r.kappa_max != self.m.file.limits.kappa_max || r.turn_at_goal {
            let text = format!(
                "smoothing with kappa_max = {} 1/m{}",
                r.kappa_max,
                if r.turn_at_goal {
                    "; no smooth path ends at the goal heading: the path ends with its \
                     arrival heading and the base turns in place at the goal"
                } else {
                    ""
                }
            );
            self.event(t0, "smoothing", text);
        }
        self.plans.push(PlanRecord {
            t: t0,
            trigger: trigger.to_string(),
            cells,
            path: r.path.clone(),
            duration: r.t_end() - t0,
            search,
            smoothing_timing_s,
            v_start,
        });
        self.reference = Some(r);
    }

    /// A `[task]`'s arm motion: planned on entry from the measured state, tracked in
    /// joint space by computed torque while the platform holds; once it settles, the next
    /// motion (the payload attached after the grasp). `false` when the run ends here.
    #[allow(clippy::too_many_arguments)]
    fn arm_step(
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
                    st.phase = Phase::Arm(ArmStage::Retreat);
                }
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

    /// After the pick: plans from the placement to `goal` (the map with the obstacles
    /// that have appeared), times the path from the robot's pose at rest under the
    /// tip-over limits of the transport posture with the payload, and drives on. `false`
    /// (with the reason) when no path leads there or it cannot be timed.
    fn drive_on_to(
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
        // the search leaves from the placement's cell (free on the configuration space:
        // the base was planned there), the timing from where the base stands
        let from = axle_pose(self.goal.pose, d);
        let to = axle_pose(goal.pose, d);
        let planned = mission_planner(m, from, to);
        let (mut planner, mut path, search) = match planned {
            Ok(p) => p,
            Err(e) => {
                self.fail(t, format!("driving on to the goal: {e}"));
                return false;
            }
        };
        // the obstacles that have appeared so far
        let grid = &m.map.grid;
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
                "the goal is unreachable from the placement: no collision-free path on the \
                 configuration space"
                    .to_string(),
            );
            return false;
        };
        self.planner = planner;
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
    /// clamped into the joint box) among the task's scene; records the plan.
    fn plan_arm(
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
        let (scene, goal) = match stage {
            ArmStage::Approach => (&task.scene, MotionGoal::Pose(task.pre_grasp.clone())),
            ArmStage::Grasp => (&task.scene, MotionGoal::Pose(task.grasp.clone())),
            ArmStage::Retreat => {
                let mut goal = start.clone();
                for (k, &i) in m.robot.arm_dofs().iter().enumerate() {
                    if g.q_index.contains(&i) {
                        goal[i] = m.transport[k];
                    }
                }
                (&task.scene_after_grasp, MotionGoal::State(goal))
            }
        };
        let mut options = MotionOptions::new(g.dim());
        options.time_limit = std::time::Duration::from_secs_f64(task.planning_time);
        options.seed = task.seed;
        options.margin = ARM_MARGIN;
        let problem = MotionProblem {
            model: &m.robot.model,
            geometry: &task.geometry,
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
        };
        let out = match plan_motion(&problem, &start, &goal, &options) {
            Err(e) => Err(format!("the {name} motion could not be planned: {e}")),
            Ok(r) => {
                record.planning_time_s = r.planning_time.as_secs_f64();
                record.checks = r.checks;
                record.duration = r.trajectory.as_ref().map(|tr| tr.duration);
                record.min_distance = r.closest.as_ref().map(|c| c.distance);
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
    fn attach_payload(&mut self, task: &'m Task, ws: &mut Workspace, st: &mut LoopState, t: f64) {
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
        self.event(
            t,
            "payload",
            format!(
                "'{}' attached ({} kg): ZMP margin {} without it, {} with it",
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

    fn run(mut self) -> Result<MissionResult> {
        let mut x = initial_state(self.m);
        self.first_plan();
        let (time_limit, rec_every) = self.run_length()?;
        let contact = self
            .m
            .contact
            .as_ref()
            .map(|c| {
                let sim = &self.m.file.simulation;
                ContactLoop::new(c, self.wm, sim.dt, self.m.file.start.pose[2], &BodySet::All)
            })
            .transpose()?;
        let plant = self.m.plant_robot.as_ref().unwrap_or(self.wm);
        let noise = self.m.sensor_noise.clone();
        let mut ws = Workspace::new(
            self.wm,
            plant,
            self.m.file.limits.mu,
            contact,
            noise,
            self.m.task.as_ref(),
        )?;
        let act = Actuators::new(self.wm)?;
        let mut c = RunSettings::new(&self, act, time_limit, rec_every)?;
        let mut st = LoopState::new(&self);
        let sim_clock = Instant::now();
        while let Flow::Next | Flow::Retry = self.step(&mut c, &mut ws, &mut st, &mut x) {}
        self.wall.simulation_s = (sim_clock.elapsed().as_secs_f64() - st.excluded).max(0.0);
        let distances = ws.distances.take();
        let edges = (0..ws.monitor.edges().len())
            .map(|i| ws.monitor.edge_label(i))
            .collect();
        Ok(self.finish(&st, &x, ws.contact.take(), distances, edges))
    }

    /// The plan at t = 0 (or the reason there is none: a posture that tips at rest, an
    /// unreachable goal, a path that cannot be timed).
    fn first_plan(&mut self) {
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
    fn run_length(&self) -> Result<(f64, usize)> {
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

    /// One control step: obstacle arrivals (and re-plans), the phase, the control law,
    /// the torques, the record with its monitors, one integration step.
    fn step(
        &mut self,
        c: &mut RunSettings,
        ws: &mut Workspace,
        st: &mut LoopState,
        x: &mut [f64],
    ) -> Flow {
        let (nq, nr) = (c.nq, c.nr);
        let t = st.k as f64 * c.h;
        st.t = t;
        match &mut ws.contact {
            Some(cl) => cl.measure(&mut ws.q_plant, &mut ws.v_plant),
            None => {
                ws.q_plant.copy_from_slice(&x[..nq]);
                ws.v_plant.copy_from_slice(&x[nq..nq + nr]);
            }
        }
        // what the law measures: the plant's state, through the sensor noise if any (the
        // record, the monitors and the energy keep the plant's own)
        match &mut ws.noise {
            Some(noise) => {
                let (q, v) = (ws.q_plant.as_slice(), ws.v_plant.as_slice());
                let (qm, vm) = (ws.q_now.as_mut_slice(), ws.v_now.as_mut_slice());
                if let Err(e) = noise.measure(q, v, qm, vm) {
                    self.fail(t, format!("the measurement failed: {e}"));
                    st.phase = Phase::Done;
                }
            }
            None => {
                ws.q_now.copy_from(&ws.q_plant);
                ws.v_now.copy_from(&ws.v_plant);
            }
        }
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
        if st.k.is_multiple_of(c.rec_every) || last {
            self.record_and_check(c, ws, st, t, ee.p, evaluated);
        }
        if last {
            return Flow::Finished;
        }

        // actuator energy over the step (rates at its start)
        let v_plant = &ws.v_plant;
        st.energy += c.act.absolute_power(&ws.u, v_plant, v_plant[0], v_plant[1]) * c.h;

        // the contact plant: the torques held over the control period
        if let Some(cl) = &mut ws.contact {
            let advanced = cl.advance(&ws.u);
            for n in cl.news() {
                self.event(n.t, n.kind, n.text);
            }
            if let Err(e) = advanced {
                self.fail(t, format!("the simulation failed: {e}"));
                st.phase = Phase::Done;
                return Flow::Retry;
            }
            st.k += 1;
            return Flow::Next;
        }

        // integrate one step
        let mut plant = Plant {
            sys: &mut ws.sys,
            u: &ws.u,
            nq,
            nr,
        };
        let stepped = if evaluated && self.m.plant_robot.is_none() && ws.noise.is_none() {
            // the first stage is the state's evaluation under the torques just formed (on
            // the law's model, which is the plant's unless [uncertainty] perturbs it)
            let cd = &ws.control_dynamics;
            ws.first_stage[..nq].copy_from_slice(cd.qdot.as_slice());
            ws.first_stage[nq..nq + nr].copy_from_slice(cd.reduced.vdot.as_slice());
            ws.first_stage[nq + nr] = cd.force.dot(&cd.qdot);
            ws.rk
                .step_from_derivative(&mut plant, t, x, &ws.first_stage, c.h)
        } else {
            ws.rk.step(&mut plant, t, x, c.h)
        };
        if let Err(e) = stepped {
            self.fail(t, format!("the simulation failed: {e}"));
            st.phase = Phase::Done;
            // record the state reached before the failure on the next pass
            return Flow::Retry;
        }
        st.k += 1;
        Flow::Next
    }

    /// The obstacles whose time has come appear in the map, each re-planning the drive
    /// if it blocks the rest of the reference.
    fn obstacle_arrivals(
        &mut self,
        c: &RunSettings,
        st: &mut LoopState,
        t: f64,
        axle: [f64; 3],
        v: f64,
    ) {
        while st.phase != Phase::Done
            && st.next_obstacle < c.obstacles.len()
            && c.obstacles[st.next_obstacle].1 <= t + 1e-12
        {
            let (oi, ot) = c.obstacles[st.next_obstacle];
            st.next_obstacle += 1;
            if !self.obstacle_appears(st, oi, ot, t, axle, v) {
                break;
            }
        }
    }

    /// Adds obstacle `oi` (due at `ot`) to the planner at time `t`; `false` when the run
    /// ends with it.
    fn obstacle_appears(
        &mut self,
        st: &mut LoopState,
        oi: usize,
        ot: f64,
        t: f64,
        axle: [f64; 3],
        v: f64,
    ) -> bool {
        let m = self.m;
        let grid = &m.map.grid;
        let o = m.file.obstacles[oi];
        let clock = Instant::now();
        let c = grid.world_to_cell_f(o.center[0], o.center[1]);
        let [fx, fy] = grid.world_to_cell_f(axle[0], axle[1]);
        let rc = (
            (fx.floor().max(0.0) as usize).min(grid.width - 1),
            (fy.floor().max(0.0) as usize).min(grid.height - 1),
        );
        let added = self.planner.add_disk(c, o.radius / grid.resolution, rc);
        self.event(
            ot,
            "obstacle",
            format!(
                "obstacle {oi} appears at ({:.2}, {:.2}), radius {:.2} m",
                o.center[0], o.center[1], o.radius
            ),
        );
        let (newly, s_time) = match added {
            Ok(a) => a,
            Err(e) => {
                self.fail(t, format!("re-planning failed: {e}"));
                st.phase = Phase::Done;
                return false;
            }
        };
        if newly.contains(&self.planner.goal_cell) && st.phase.follows_reference() {
            self.wall.planning_s += s_time;
            st.excluded += clock.elapsed().as_secs_f64();
            self.fail(
                t,
                format!(
                    "obstacle {oi} (t = {ot} s) seals the goal: the footprint no \
                     longer fits at the goal pose"
                ),
            );
            st.phase = Phase::Done;
            return false;
        }
        let planner = &mut self.planner;
        let affected = st.phase.follows_reference()
            && self.reference.as_ref().is_some_and(|r| {
                r.samples
                    .iter()
                    .filter(|s| s.t >= t)
                    .any(|s| planner.axle_collides(grid, [s.x, s.y, s.theta]))
            });
        if affected {
            self.replan_after_obstacle(st, oi, ot, t, axle, v, s_time);
        } else {
            self.wall.planning_s += s_time;
        }
        st.excluded += clock.elapsed().as_secs_f64();
        true
    }

    /// Re-plans from the current axle pose and speed after obstacle `oi` blocked the
    /// reference (`s_time`: the wall time its map update took).
    #[allow(clippy::too_many_arguments)]
    fn replan_after_obstacle(
        &mut self,
        st: &mut LoopState,
        oi: usize,
        ot: f64,
        t: f64,
        axle: [f64; 3],
        v: f64,
        s_time: f64,
    ) {
        let (path, mut timing) = self.planner.replan();
        timing.search_s += s_time;
        self.wall.planning_s += timing.search_s;
        let Some(cells) = path else {
            self.fail(
                t,
                format!(
                    "obstacle {oi} (t = {ot} s) seals the goal: no \
                     collision-free path remains"
                ),
            );
            st.phase = Phase::Done;
            return;
        };
        let start = TimingStart {
            t0: t,
            pose: axle,
            v,
        };
        let trigger = format!("obstacle {oi}");
        let old = self.reference.take();
        let (cells, r, st_s, stop) = match self.checked_reference(cells, &start, &mut timing) {
            Some(Ok(CheckedPath {
                cells,
                reference: r,
                smoothing_s: st_s,
            })) => {
                // a new path that does not admit the current speed at its start would be
                // braked onto past its limits (ω_max): stop along the old path instead,
                // then follow a path planned from there
                let brake = match (&old, r.overspeed_until) {
                    (Some(o), Some(_)) if v > 0.0 => self.brake_then_replan(o, t, v, &mut timing),
                    _ => None,
                };
                match brake {
                    Some(b) => (b.cells, b.reference, st_s + b.smoothing_s, Some(b.t_stop)),
                    None => (cells, r, st_s, None),
                }
            }
            Some(Err(reason)) => {
                self.fail(t, reason);
                st.phase = Phase::Done;
                return;
            }
            None => {
                st.phase = Phase::Done;
                return;
            }
        };
        self.adopt(cells, r, t, v, &trigger, timing, st_s);
        let p = self.plans.last().expect("just pushed");
        let stop_text = stop.map_or(String::new(), |ts| {
            format!(
                "; the new path does not admit {v:.2} m/s at its start, so the base brakes \
                 to rest along the old path first ({:.2} s)",
                ts - t
            )
        });
        let text = format!(
            "re-plan after obstacle {oi}: D* Lite expanded {} cells, \
             new path {:.2} m, {:.2} s to go from {:.2} m/s{stop_text}",
            p.search.expanded,
            path_length(&p.path),
            p.duration,
            p.v_start
        );
        self.event(t, "replan", text);
    }

    /// The stop of a re-plan at speed: brakes from `v` to rest along the path of `old`
    /// from where it is at `t`, then plans and times a new path from that stop at rest.
    /// `None` when the stop
    /// cannot be made (it runs into a blocked cell, it cannot be timed, no path leaves
    /// it), the caller then keeps the path planned from where the base is.
    fn brake_then_replan(
        &mut self,
        old: &Reference,
        t: f64,
        v: f64,
        timing: &mut SearchTiming,
    ) -> Option<StopAndGo> {
        let accel = self.timing_accel?;
        let clock = Instant::now();
        let mut samples = brake_along(old, t, v, &self.limits, &accel, REF_DT).ok()?;
        self.wall.smoothing_timing_s += clock.elapsed().as_secs_f64();
        let grid = &self.m.map.grid;
        if samples
            .iter()
            .any(|p| self.planner.axle_collides(grid, [p.x, p.y, p.theta]))
        {
            return None;
        }
        let stop = *samples.last().expect("a timed stop has samples");
        let [fx, fy] = grid.world_to_cell_f(stop.x, stop.y);
        let cell = (
            (fx.floor().max(0.0) as usize).min(grid.width - 1),
            (fy.floor().max(0.0) as usize).min(grid.height - 1),
        );
        let search_clock = Instant::now();
        self.planner.move_start(cell).ok()?;
        let (path, second) = self.planner.replan();
        let search_s = search_clock.elapsed().as_secs_f64().max(second.search_s);
        timing.search_s += search_s;
        timing.expanded += second.expanded;
        self.wall.planning_s += search_s;
        let cells = path?;
        let from_stop = TimingStart {
            t0: stop.t,
            pose: [stop.x, stop.y, stop.theta],
            v: 0.0,
        };
        let CheckedPath {
            cells,
            reference: mut r,
            smoothing_s: st,
        } = self.checked_reference(cells, &from_stop, timing)?.ok()?;
        samples.pop();
        samples.append(&mut r.samples);
        r.samples = samples;
        // the joined reference's arc lengths: the new path's from the stop; the stretch
        // before it is not on that geometry (NaN: a re-plan during the stop cannot stop
        // along it again, and falls back to braking onto its new path)
        let n_brake = r.samples.len() - r.arc.len();
        let mut arc = vec![f64::NAN; n_brake];
        arc.append(&mut r.arc);
        r.arc = arc;
        let d = self.wm.base.drive.d;
        let mut drawn: Vec<[f64; 2]> = r.samples[..n_brake]
            .iter()
            .map(|p| {
                let (sn, cs) = p.theta.sin_cos();
                [p.x + d * cs, p.y + d * sn]
            })
            .collect();
        drawn.append(&mut r.path);
        r.path = drawn;
        Some(StopAndGo {
            cells,
            reference: r,
            smoothing_s: st,
            t_stop: stop.t,
        })
    }

    /// Drive → arrive at the end of the reference; arrive → reach (or done) once the
    /// base settles on the goal pose, or failure after the arrival timeout; the time
    /// limit.
    fn phase_transitions(
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
    fn reach(
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
    fn whole_body_step(
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
        law.track(reference, self.plans.len());
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

    /// Counts the clipped steps; an event at the first of each kind.
    fn saturation_events(&mut self, st: &mut LoopState, t: f64, torque: bool, speed: bool) {
        if torque {
            st.torque_sat += 1;
            if st.first_torque_sat {
                st.first_torque_sat = false;
                self.event(t, "torque_limit", "first torque saturation");
            }
        }
        if speed {
            st.speed_sat += 1;
            if st.first_speed_sat {
                st.first_speed_sat = false;
                self.event(t, "speed_limit", "first speed-command saturation");
            }
        }
    }

    /// Records a sample, then the first slip and the first contact as events (a contact
    /// ends the run as a collision).
    fn record_and_check(
        &mut self,
        c: &RunSettings,
        ws: &mut Workspace,
        st: &mut LoopState,
        t: f64,
        ee: Vector3<f64>,
        evaluated: bool,
    ) {
        self.check_arm_distances(ws, st, t);
        let Some((slip, clear)) = self.record(c, ws, st, t, ee, evaluated) else {
            return;
        };
        // (on the contact plant the plant's own slip flag makes the event, in `step`)
        if ws.contact.is_none() && st.first_slip && slip.is_some_and(|s| s > 1.0) {
            st.first_slip = false;
            self.event(t, "slip", "lateral wheel force exceeds μ N");
        }
        if st.first_contact && clear < 0.0 {
            st.first_contact = false;
            self.event(
                t,
                "contact",
                format!("footprint overlaps an obstacle by {:.3} m", -clear),
            );
            if st.phase != Phase::Done {
                self.fail(
                    t,
                    format!(
                        "collision: the footprint overlaps an obstacle by {:.3} m",
                        -clear
                    ),
                );
                st.phase = Phase::Done;
            }
        }
    }

    /// During a `[task]`'s arm motions: the distances of the state to the scene (without
    /// the object once grasped) and between the robot's links; a distance ≤ 0 is a touch
    /// and ends the run.
    fn check_arm_distances(&mut self, ws: &mut Workspace, st: &mut LoopState, t: f64) {
        let (Phase::Arm(_), Some(task), Some(dm)) =
            (st.phase, self.m.task.as_ref(), ws.distances.as_mut())
        else {
            return;
        };
        let (d_scene, d_self) = dm.sample(task, &self.m.robot, ws.q_now.as_slice(), st.grasped);
        let touch = if d_scene <= 0.0 {
            dm.min_scene
                .as_ref()
                .map(|(d, [l, o])| format!("link '{l}' touches scene object '{o}' ({d:.4} m)"))
        } else if d_self <= 0.0 {
            dm.min_self
                .as_ref()
                .map(|(d, [a, b])| format!("link '{a}' touches link '{b}' ({d:.4} m)"))
        } else {
            None
        };
        if let Some(what) = touch {
            self.event(t, "contact", what.clone());
            self.fail(t, format!("collision: {what}"));
            st.phase = Phase::Done;
        }
    }

    /// The smallest ZMP margin of the recorded samples as an event.
    fn min_zmp_event(&mut self) {
        if let Some((i, mz)) = self
            .samples
            .zmp_margin
            .iter()
            .enumerate()
            .filter_map(|(i, z)| z.map(|z| (i, z)))
            .min_by(|a, b| a.1.total_cmp(&b.1))
        {
            let ti = self.samples.t[i];
            self.event(
                ti,
                "min_zmp_margin",
                format!("smallest ZMP margin {mz:.4} m"),
            );
        }
    }

    /// The result of the finished loop.
    fn finish(
        mut self,
        st: &LoopState,
        x: &[f64],
        contact: Option<ContactLoop>,
        distances: Option<DistanceMonitor>,
        support_edges: Vec<String>,
    ) -> MissionResult {
        if let (Some(tr), Some(dm)) = (&mut self.task, distances) {
            if let Some((d, pair)) = dm.min_scene {
                tr.min_scene_distance = Some(d);
                tr.closest_scene_pair = Some(pair);
            }
            if let Some((d, pair)) = dm.min_self {
                tr.min_self_distance = Some(d);
                tr.closest_self_pair = Some(pair);
            }
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
            input_work: contact
                .as_ref()
                .map_or(x[model.nq + wm.nr()], |c| c.input_work),
            wall: self.wall,
            contact: contact.map(|c| c.tally.finish()),
            goal_pose: self.goal.pose,
            task: self.task,
            support_edges,
            mpc: self.whole_body.as_ref().and_then(WholeBodyLaw::summary),
        }
    }

    /// Records one sample; returns (slip ratio, clearance) for the event checks, `None`
    /// if the monitors could not be evaluated (the sample is still recorded). `evaluated`:
    /// the step's dynamics under the applied torques are in the workspace.
    fn record(
        &mut self,
        c: &RunSettings,
        ws: &mut Workspace,
        st: &LoopState,
        t: f64,
        ee: Vector3<f64>,
        evaluated: bool,
    ) -> Option<(Option<f64>, f64)> {
        let pose = [ws.q_plant[0], ws.q_plant[1], ws.q_plant[2]];
        let mon = match &mut ws.contact {
            Some(cl) => Some(cl.monitors(pose)),
            None if evaluated => monitors(self.wm, self.m.plant_robot.is_some(), ws, t),
            None => None,
        };
        let (q, v) = (&ws.q_plant, &ws.v_plant);
        let side = arm_side(&self.wm.model, &mut ws.data, q, &c.chain, ee);
        let r = &st.cur_ref;
        let clearance = self.planner.clearance(
            &self.m.map.grid,
            [q[0], q[1], q[2]],
            c.r_foot,
            EXACT_CLEARANCE,
        );
        let te = (q[0] - r.x).hypot(q[1] - r.y);
        let m = mon.unwrap_or_default();
        let s = &mut self.samples;
        s.t.push(t);
        s.q.push(q.as_slice().to_vec());
        s.v.push(v[0]);
        s.omega.push(v[1]);
        s.v_ref.push(r.v);
        s.omega_ref.push(r.omega);
        s.ref_xy.push([r.x, r.y]);
        s.zmp_margin.push(m.zmp);
        s.zmp_critical_edge.push(m.zmp_edge);
        s.force_angle_min.push(m.force_angle);
        s.mhs_min.push(m.mhs);
        s.clearance.push(clearance);
        s.tracking_error.push(te);
        s.slip_ratio.push(m.slip);
        s.u.push(ws.u.clone());
        s.ee.push([ee.x, ee.y, ee.z]);
        s.arm_side.push(side);
        s.energy.push(st.energy);
        s.phase.push(st.phase.name());
        if let Some(cl) = &ws.contact {
            s.contact_normal.push(cl.normal_loads());
        }
        mon.map(|m| (m.slip, clearance))
    }
}

/// The stability and slip monitors (the one set of [`StabilityMonitor`], on the plant's
/// robot) at the step's state, from the dynamics the step evaluated under the applied
/// torques, or, when `[uncertainty]` perturbs the plant (`perturbed`) or the law measured
/// a noisy state, from the plant's own dynamics at its state; `None` if the multipliers
/// or the loads cannot be formed.
fn monitors(wm: &WheeledModel, perturbed: bool, ws: &mut Workspace, t: f64) -> Option<Monitors> {
    let q = ws.q_plant.as_slice();
    if perturbed || ws.noise.is_some() {
        ws.monitor.sample(t, q, ws.v_plant.as_slice(), &ws.u).ok()?;
    } else {
        lagrange_multipliers(wm, &mut ws.control_dynamics, &ws.q_now).ok()?;
        ws.monitor
            .sample_evaluated(t, q, &mut ws.control_dynamics, &ws.u)
            .ok()?;
    }
    let tr = &ws.monitor.trace;
    let last = |xs: &[Option<f64>]| xs.last().copied().flatten();
    Some(Monitors {
        zmp: last(&tr.zmp_margin),
        zmp_edge: tr.critical_edge.last().copied().flatten(),
        force_angle: last(&tr.force_angle_min),
        mhs: last(&tr.mhs_min),
        slip: tr.wheels.last().and_then(|w| {
            w.iter()
                .map(|f| f.slip_ratio.unwrap_or(f64::INFINITY))
                .reduce(f64::max)
                .filter(|x| x.is_finite())
        }),
    })
}

/// A re-plan that stops along the old path first.
struct StopAndGo {
    /// The cell path from the stop.
    cells: Vec<(usize, usize)>,
    /// The stop, then the new path.
    reference: Reference,
    /// Smoothing and timing wall time of the new path (s).
    smoothing_s: f64,
    /// Mission time of the stop (s).
    t_stop: f64,
}

/// How a control step ends.
enum Flow {
    /// The step was taken.
    Next,
    /// The run just ended: the same step is taken again in phase `done` (recorded).
    Retry,
    /// The last sample is recorded.
    Finished,
}

/// The state the loop carries from step to step (besides the plant state).
struct LoopState {
    k: usize,
    t: f64,
    phase: Phase,
    phase_t0: f64,
    ee_traj: Option<EeTrajectory>,
    energy: f64,
    torque_sat: usize,
    speed_sat: usize,
    first_torque_sat: bool,
    first_speed_sat: bool,
    first_slip: bool,
    first_contact: bool,
    time_to_goal: Option<f64>,
    cur_ref: RefSample,
    /// Planning wall time spent inside the loop (s).
    excluded: f64,
    next_obstacle: usize,
    /// A `[task]`'s arm motion being tracked.
    arm: Option<ArmMotion>,
    /// The picked object is attached.
    grasped: bool,
    /// The pick is done (the arm back in the transport posture).
    picked: bool,
}

impl LoopState {
    fn new(r: &Runner<'_>) -> Self {
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

/// A `[task]`'s base goal: the best-ranked placement
/// ([`crate::motion::placement::place_base`], the arm at the transport posture) that the
/// base's planner reaches from the start (the footprint fits there and a path leads
/// there), with the task's record; or the start pose and the reason there is none.
fn choose_placement(
    m: &Mission,
    task: &Task,
) -> Result<(GoalSpec, Option<TaskResult>, Option<String>)> {
    let clock = Instant::now();
    let f = &m.file;
    let posture = start_configuration(&m.robot, [0.0; 3], &m.transport);
    let placement = task.placements(&m.robot, &posture)?;
    let time_s = clock.elapsed().as_secs_f64();
    let goal_at =
        |pose: [f64; 3]| GoalSpec::base_pose(pose, PLACEMENT_TOLERANCE[0], PLACEMENT_TOLERANCE[1]);
    let mut result = TaskResult {
        object: task.object.clone(),
        scene_pose: task.scene_pose,
        placement: None,
        arm_plans: Vec::new(),
        payload: None,
        min_scene_distance: None,
        closest_scene_pair: None,
        min_self_distance: None,
        closest_self_pair: None,
    };
    if let Some(reason) = placement.failure() {
        return Ok((
            goal_at(f.start.pose),
            Some(result),
            Some(format!("no placement for the pick: {reason}")),
        ));
    }
    let d = m.robot.base.drive.d;
    let s0 = axle_pose(f.start.pose, d);
    for (rank, c) in placement.candidates.iter().enumerate() {
        let g0 = axle_pose(c.base, d);
        let reached = mission_planner(m, s0, g0);
        if let Ok((_, Some(_), _)) = reached {
            result.placement = Some(PlacementChoice {
                base: c.base,
                rank,
                candidates: placement.candidates.len(),
                score: c.score,
                manipulability: c.manipulability,
                clearance: c.clearance,
                tip_over_margin: c.tip_over_margin,
                counts: placement.counts,
                time_s,
            });
            return Ok((goal_at(c.base), Some(result), None));
        }
    }
    let n = placement.candidates.len();
    Ok((
        goal_at(f.start.pose),
        Some(result),
        Some(format!(
            "none of the {n} best placements that reach the grasp can be reached by the base: \
             the footprint does not fit there or no path leads there"
        )),
    ))
}

/// The plant state at the start: the start pose, the start arm posture, at rest (the
/// last entry integrates the input work).
fn initial_state(m: &Mission) -> Vec<f64> {
    let mut x = start_configuration(&m.robot, m.file.start.pose, &m.q_arm0);
    x.resize(m.robot.model.nq + m.robot.nr() + 1, 0.0);
    x
}

/// The workspaces of the loop, allocated once before it.
struct Workspace {
    /// The plant.
    sys: WheeledSystem,
    /// The control law's reduced dynamics (Mr, cr + Gr, N_C) at the step's state, under
    /// zero input.
    control_dynamics: WheeledData,
    /// Kinematics workspace (end effector, arm side view).
    data: Data,
    /// The stability, load and slip monitors of the recorded samples.
    monitor: StabilityMonitor,
    rk: Rk4,
    /// The integrator's first stage `[q̇, v̇, Qᵀq̇]` at the step's state.
    first_stage: Vec<f64>,
    /// The configuration q the law measured at the step (the plant's, with sensor noise
    /// if any).
    q_now: DVector<f64>,
    /// The reduced velocity v = [v, ω, q̇_arm] the law measured at the step.
    v_now: DVector<f64>,
    /// The actuator inputs (wheel torques, then arm torques), held over the step.
    u: Vec<f64>,
    zero_u: Vec<f64>,
    /// The law's desired reduced accelerations.
    a_des: DVector<f64>,
    /// The contact plant, when the mission runs on it (else the plant is `sys`).
    contact: Option<ContactLoop>,
    /// The `[uncertainty]` sensor noise between the plant's state and what the law
    /// measures (`q_now`, `v_now`).
    noise: Option<SensorNoise>,
    /// The plant's configuration (reduced coordinates) at the step.
    q_plant: DVector<f64>,
    /// The plant's reduced velocity at the step.
    v_plant: DVector<f64>,
    /// The end effector's frame Jacobian (full velocity coordinates).
    jac: Matrix6xX<f64>,
    /// Ṅ_C.
    ndot: DMatrix<f64>,
    /// Ṅ_C v.
    ndot_v: DVector<f64>,
    /// The end effector's reduced position Jacobian J N_C (3 × nr).
    ee_jacobian: DMatrix<f64>,
    /// A `[task]`'s distance monitor of the arm motions.
    distances: Option<DistanceMonitor>,
    /// The arm motion's reference: configuration (full), group rates and accelerations.
    q_ref: Vec<f64>,
    /// Group joint rates of the reference.
    qd_ref: Vec<f64>,
    /// Group joint accelerations of the reference.
    qdd_ref: Vec<f64>,
}

impl Workspace {
    fn new(
        wm: &WheeledModel,
        plant: &WheeledModel,
        mu: f64,
        contact: Option<ContactLoop>,
        noise: Option<SensorNoise>,
        task: Option<&Task>,
    ) -> Result<Self> {
        let model = &wm.model;
        let (nq, nr, nu) = (model.nq, wm.nr(), wm.nu());
        let dim = task.map_or(0, |t| t.group.dim());
        Ok(Self {
            sys: WheeledSystem::new(plant.clone()),
            control_dynamics: WheeledData::new(wm),
            data: Data::new(model),
            monitor: StabilityMonitor::new(plant, monitor_settings(mu))?,
            rk: Rk4::new(nq + nr + 1),
            first_stage: vec![0.0; nq + nr + 1],
            q_now: DVector::zeros(nq),
            v_now: DVector::zeros(nr),
            u: vec![0.0; nu],
            zero_u: vec![0.0; nu],
            a_des: DVector::zeros(nr),
            contact,
            noise,
            q_plant: DVector::zeros(nq),
            v_plant: DVector::zeros(nr),
            jac: Matrix6xX::zeros(model.nv),
            ndot: DMatrix::zeros(model.nv, nr),
            ndot_v: DVector::zeros(model.nv),
            ee_jacobian: DMatrix::zeros(3, nr),
            distances: task.map(|t| DistanceMonitor::new(t, wm)),
            q_ref: vec![0.0; nq],
            qd_ref: vec![0.0; dim],
            qdd_ref: vec![0.0; dim],
        })
    }

    /// The plant (the contact plant too) and the monitors take `robot` (the same joints,
    /// other inertias: the payload attached).
    fn attach(&mut self, robot: &WheeledModel, mu: f64) -> Result<()> {
        self.sys = WheeledSystem::new(robot.clone());
        if let Some(cl) = &mut self.contact {
            cl.attach(robot);
        }
        self.monitor = StabilityMonitor::new(robot, monitor_settings(mu))?;
        Ok(())
    }
}

/// The settings of the mission's stability and slip monitor.
fn monitor_settings(mu: f64) -> StabilitySettings {
    StabilitySettings {
        mu: Some(mu),
        bodies: BodySet::All,
        ground_z: None,
        stop_at_tip: false,
    }
}

/// The actuators: the computed-torque map with the torque limits, the wheel-speed limit.
struct Actuators {
    /// Computed torque on the reduced model, clipped at the joints' effort limits.
    torque: ComputedTorque,
    wheel_speed: f64,
    /// Number of arm inputs.
    na: usize,
    /// Platform speeds (v, ω) to wheel rates.
    w_inv: Matrix2<f64>,
}

impl Actuators {
    /// The actuators of `wm` with the limits of its URDF (a missing or non-positive
    /// limit is none).
    fn new(wm: &WheeledModel) -> Result<Self> {
        let model = &wm.model;
        let lim = |i: usize, v: &DVector<f64>| {
            let x = v[i];
            if x.is_finite() && x > 0.0 {
                x
            } else {
                f64::INFINITY
            }
        };
        let (wheel_tau, wheel_speed) = match wm.wheel_dofs() {
            Some(w) => (
                [
                    lim(w[0], &model.effort_limit),
                    lim(w[1], &model.effort_limit),
                ],
                lim(w[0], &model.velocity_limit).min(lim(w[1], &model.velocity_limit)),
            ),
            None => ([f64::INFINITY; 2], f64::INFINITY),
        };
        let bounds = wheel_tau
            .into_iter()
            .chain(wm.arm_dofs().iter().map(|&i| lim(i, &model.effort_limit)))
            .collect();
        Ok(Self {
            torque: ComputedTorque::new(wm, bounds)?,
            wheel_speed,
            na: wm.arm_dofs().len(),
            w_inv: wm.base.drive.platform_to_wheel(),
        })
    }

    /// The actuators' absolute power Σ |u_j · rate_j| at the inputs `u`, the reduced
    /// velocities `v_now` and the platform speeds (`v`, `w`).
    fn absolute_power(&self, u: &[f64], v_now: &DVector<f64>, v: f64, w: f64) -> f64 {
        let wrates = self.w_inv * Vector2::new(v, w);
        let mut p_abs = (u[0] * wrates[0]).abs() + (u[1] * wrates[1]).abs();
        for k2 in 0..self.na {
            p_abs += (u[2 + k2] * v_now[2 + k2]).abs();
        }
        p_abs
    }
}

/// The run's settings (not a control law: the laws are Kanayama, Aicardi and the computed
/// torque it holds): sizes, the goal, the gains and guards of the laws, the actuators, the
/// obstacle schedule; fixed for the run but the time limit, which a pick's drive on
/// extends.
struct RunSettings {
    nq: usize,
    nr: usize,
    na: usize,
    h: f64,
    time_limit: f64,
    rec_every: usize,
    r_foot: f64,
    /// The base frame's goal pose.
    goal: [f64; 3],
    /// The unicycle point the platform is planned and tracked by: the driven-axle
    /// midpoint, `d` behind the base frame origin.
    d: f64,
    goal_axle: [f64; 3],
    arm: Vec<usize>,
    /// The transport posture as a full configuration.
    q_t: DVector<f64>,
    kan: Kanayama,
    /// The arrive phase's posture law onto the axle's goal pose.
    arrive: Aicardi,
    /// The goal's position tolerance (m).
    pos_tol: f64,
    kx: f64,
    ks: f64,
    wn: f64,
    wt: f64,
    v_max: f64,
    omega_max: f64,
    a_guard_f: f64,
    a_guard_b: f64,
    alpha_guard: f64,
    act: Actuators,
    chain: Vec<usize>,
    /// (index, time) of the obstacles in the order they appear.
    obstacles: Vec<(usize, f64)>,
    /// A `[task]`'s group joints as arm slots (indices into `arm`).
    group_slots: Vec<usize>,
}

impl RunSettings {
    fn new(r: &Runner<'_>, act: Actuators, time_limit: f64, rec_every: usize) -> Result<Self> {
        let (m, wm, f) = (r.m, r.wm, &r.m.file);
        let model = &wm.model;
        let arm = wm.arm_dofs().to_vec();
        let mut q_t = DVector::zeros(model.nq);
        for (k, &i) in arm.iter().enumerate() {
            q_t[i] = m.transport[k];
        }
        let c = &f.control;
        let kan = Kanayama::new(c.kx, c.ky, c.kth)?;
        let (tip_f, tip_b) = match (r.tip.forward, r.tip.backward) {
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
            goal: r.goal.pose,
            d,
            goal_axle: axle_pose(r.goal.pose, d),
            arm,
            q_t,
            kan,
            arrive: Aicardi::new(c.kx, 2.0, 1.0)?,
            pos_tol: r.goal.position_tolerance,
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
            chain: arm_chain(m),
            obstacles,
            group_slots,
        })
    }

    /// Drives on to `goal` with the tip-over guards of `tip` (a `[task]`'s drive on).
    fn retarget(&mut self, goal: &GoalSpec, tip: &AccelerationLimits) {
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
    fn arm_law(&self, ws: &mut Workspace, v: f64, w: f64) {
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
    fn goal_sample(&self, t: f64) -> RefSample {
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
    fn platform_law(
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
    fn reach_law(
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
fn at_goal(goal: [f64; 3], g: &GoalSpec, pose: [f64; 3], v: f64, w: f64) -> (f64, f64, bool) {
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
fn arrive_command(
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
struct EeState {
    p: Vector3<f64>,
    dp: Vector3<f64>,
    bias: Vector3<f64>,
}

/// The end effector's position, velocity and acceleration bias at the workspace's state,
/// with its reduced position Jacobian in `ws.ee_jacobian` (needs the controller's reduced
/// dynamics at the state).
fn end_effector_kinematics(m: &Mission, ws: &mut Workspace) -> EeState {
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

/// The arm chain (joint origins, then the end effector `ee`) in the base x–z plane, from
/// the forward kinematics at the configuration `q` (`data` its workspace).
fn arm_side(
    model: &crate::multibody::Model,
    data: &mut Data,
    q: &DVector<f64>,
    chain: &[usize],
    ee: Vector3<f64>,
) -> Vec<[f64; 2]> {
    crate::kinematics::forward_kinematics(model, data, q);
    let (sn, cs) = q[2].sin_cos();
    let to_base = |p: &Vector3<f64>| {
        let dx = p.x - q[0];
        let dy = p.y - q[1];
        [cs * dx + sn * dy, p.z]
    };
    let mut side: Vec<[f64; 2]> = chain
        .iter()
        .map(|&j| to_base(&data.world_from_joint[j].translation))
        .collect();
    side.push(to_base(&ee));
    side
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

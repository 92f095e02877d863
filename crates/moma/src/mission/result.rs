//! What a mission run returns: the plans, the events, the recorded samples (plain
//! columns, one entry per sample), the wall times of its parts and the outcome with its
//! extremes ([`MissionResult`]), which the CLI turns into CSV, JSON, SVGs and the report.

use super::plan::SearchTiming;
use super::task::TaskResult;
use crate::sim::contact_run::ContactTally;
use crate::sim::mpc_run::MpcRunSummary;
use crate::stability::AccelerationLimits;

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
    /// The driven-axle midpoint's pose `[x, y, θ]` the path was smoothed from: where the
    /// base stood, or the stop along the old path when a re-plan brakes to rest first.
    pub smoothed_from: [f64; 3],
}

/// Something that happened during the run.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Event {
    /// Mission time (s).
    pub t: f64,
    /// Kind: `plan`, `obstacle`, `replan`, `torque_limit`, `speed_limit`, `slip`,
    /// `lift_off` (contact plant), `contact`, `min_zmp_margin`, `arrived`, `reached`,
    /// `failed`; with a `[task]` also `arm_plan`, `arm`, `payload`, `picked`, `footprint`
    /// and `heights` (the drive on's).
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
    /// `lift`, `retreat`; `done`.
    pub phase: Vec<&'static str>,
    /// On the contact plant: each contact's normal force (N; the wheels, then the
    /// casters, as [`ContactTally::totals`]); empty on the rolling plant.
    pub contact_normal: Vec<Vec<f64>>,
    /// On the contact plant: each contact's friction force on the robot `[x, y]` (world,
    /// N; same order; zero for a caster), applied over the step that ends at the sample;
    /// empty on the rolling plant.
    pub contact_friction: Vec<Vec<[f64; 2]>>,
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

pub(super) fn min_opt(xs: &[Option<f64>]) -> Option<f64> {
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

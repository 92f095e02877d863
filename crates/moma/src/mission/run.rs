//! The closed loop of a mission: plan, time, track, monitor, re-plan, reach.

use std::time::Instant;

use nalgebra::{DMatrix, DVector, Matrix2, Matrix3, Matrix6xX, Vector2, Vector3};

use super::plan::{Planner, SearchTiming};
use super::reference::{RefSample, Reference, TimingStart, build_reference};
use super::scenario::{MAX_SAMPLES, MAX_STEPS, Mission};
use crate::control::unicycle::{Kanayama, ReferenceSample};
use crate::control::wrap_angle;
use crate::error::{Error, Result};
use crate::kinematics::{ReferenceFrame, frame_acceleration_bias, frame_jacobian_from_kinematics};
use crate::mobile::wheeled::{
    actuation_matrix, admissible_velocity_basis, admissible_velocity_basis_dot,
    lagrange_multipliers, reduced_forward_dynamics_crba,
};
use crate::mobile::{WheeledData, WheeledModel, reduced_forward_dynamics};
use crate::multibody::{Data, JointType};
use crate::ode::{OdeSystem, Rk4};
use crate::planning::trajectory::{DiffDriveLimits, TipOverAcceleration};
use crate::sim::wheeled::ReducedSystem;
use crate::sim::wheeled_system::WheeledSystem;
use crate::stability::{
    AccelerationLimits, BodySet, ExternalLoads, StabilityData, StabilityModel, SupportAttachment,
    SupportPolygon, contact_normal_loads, driven_wheel_friction,
};

/// Spacing of the reference samples (s).
const REF_DT: f64 = 0.02;
/// Time allowed after the reference ends to settle on the goal pose (s).
const ARRIVE_TIMEOUT: f64 = 8.0;
/// Time allowed after the end-effector trajectory ends to settle on the target (s).
const REACH_SETTLE: f64 = 5.0;
/// Distance (m) beyond the footprint within which the clearance is exact.
const EXACT_CLEARANCE: f64 = 1.0;

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
    /// Smoothing + time parameterisation wall time (s).
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
    /// `contact`, `min_zmp_margin`, `arrived`, `reached`, `failed`.
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
    /// ZMP margin (m); `None` where the ZMP is undefined (tipping).
    pub zmp_margin: Vec<Option<f64>>,
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
    /// carries no load.
    pub slip_ratio: Vec<Option<f64>>,
    /// Actuator torques per sample (`u`, the model's input order).
    pub u: Vec<Vec<f64>>,
    /// End-effector position (world, m).
    pub ee: Vec<[f64; 3]>,
    /// Arm chain (joint origins, then the end effector) in the base x–z plane (m).
    pub arm_side: Vec<Vec<[f64; 2]>>,
    /// Actuator energy so far ∫ Σ |u_j · rate_j| dt (J).
    pub energy: Vec<f64>,
    /// Mission phase: `drive`, `arrive`, `reach`, `done`.
    pub phase: Vec<&'static str>,
}

/// Wall times of the run's parts (s).
#[derive(Debug, Clone, Copy, Default, serde::Serialize)]
pub struct WallTimes {
    /// Map → C-space → first search, plus every re-plan's search.
    pub planning_s: f64,
    /// Every smoothing and time parameterisation.
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
    Done,
}

impl Phase {
    fn name(self) -> &'static str {
        match self {
            Phase::Drive => "drive",
            Phase::Arrive => "arrive",
            Phase::Reach => "reach",
            Phase::Done => "done",
        }
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
fn axle_pose(base: [f64; 3], d: f64) -> [f64; 3] {
    if d == 0.0 {
        return base;
    }
    let (s, c) = base[2].sin_cos();
    [base[0] - d * c, base[1] - d * s, base[2]]
}

/// The reference of the base frame origin for a reference sample of the axle midpoint
/// (position moved `d` ahead along the reference heading; speeds as they are).
fn base_reference(mut r: RefSample, d: f64) -> RefSample {
    if d != 0.0 {
        let (s, c) = r.theta.sin_cos();
        r.x += d * c;
        r.y += d * s;
    }
    r
}

/// The tip-over acceleration limits of the robot in its transport posture, at rest, in
/// base axes.
pub fn transport_tip_limits(m: &Mission) -> Result<AccelerationLimits> {
    let model = &m.robot.model;
    let mut q = DVector::zeros(model.nq);
    for (k, &i) in m.robot.arm_dofs().iter().enumerate() {
        q[i] = m.transport[k];
    }
    let mut data = Data::new(model);
    let com = crate::dynamics::center_of_mass(model, &mut data, &q);
    let support = SupportPolygon::from_wheeled_base(&m.robot.base)?;
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
    let model = &m.robot.model;
    let mut j = model.frames[m.ee_frame.0].parent_joint.0;
    let mut chain = Vec::new();
    while j != 0 {
        if model.joint_types[j] != JointType::Planar && m.robot.arm_dofs().contains(&model.idx_v[j])
        {
            chain.push(j);
        }
        j = model.parents[j].0;
    }
    chain.reverse();
    chain
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
    wm: &'m WheeledModel,
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
}

impl<'m> Runner<'m> {
    fn new(m: &'m Mission) -> Result<Self> {
        let f = &m.file;
        let clock = Instant::now();
        let d = m.robot.base.drive.d;
        let (s0, g0) = (axle_pose(f.start.pose, d), axle_pose(f.goal.pose, d));
        let (planner, first_path, first_search) = Planner::new(
            &m.map.grid,
            f.map.unknown_is_obstacle,
            f.robot.footprint_radius,
            d,
            [s0[0], s0[1]],
            [g0[0], g0[1]],
        )?;
        let planning_s = clock.elapsed().as_secs_f64();
        let tip = transport_tip_limits(m)?;
        let l = &f.limits;
        let limits = DiffDriveLimits {
            v_max: l.v_max,
            omega_max: l.omega_max,
            a_max: l.a_max,
            alpha_max: l.alpha_max,
        };
        // the tip-over limits the timing may use: a side no edge limits is unbounded; a
        // posture that tips at rest (or has no room to accelerate) cannot be timed
        let timing_accel = match (tip.forward, tip.backward) {
            (Some(fw), Some(bw)) if fw > 0.0 && bw > 0.0 => {
                let side = |x: Option<f64>| x.map_or(f64::INFINITY, |a| l.tip_fraction * a);
                Some(TipOverAcceleration {
                    forward: l.tip_fraction * fw,
                    backward: l.tip_fraction * bw,
                    left: side(tip.left),
                    right: side(tip.right),
                })
                .filter(|t| t.left > 0.0 && t.right > 0.0)
            }
            _ => None,
        };
        Ok(Self {
            m,
            wm: &m.robot,
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
            failure: None,
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
        search: SearchTiming,
    ) -> bool {
        let Some(accel) = self.timing_accel else {
            return false;
        };
        let clock = Instant::now();
        let r = build_reference(
            &self.m.map.grid,
            self.planner.dstar.grid(),
            &cells,
            &start,
            axle_pose(self.m.file.goal.pose, self.wm.base.drive.d),
            self.wm.base.drive.d,
            &self.limits,
            &accel,
            self.m.file.limits.kappa_max,
            REF_DT,
        );
        let st = clock.elapsed().as_secs_f64();
        self.wall.smoothing_timing_s += st;
        match r {
            Ok(r) => {
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
                    self.event(start.t0, "smoothing", text);
                }
                self.plans.push(PlanRecord {
                    t: start.t0,
                    trigger: trigger.to_string(),
                    cells,
                    path: r.path.clone(),
                    duration: r.t_end() - r.t_start(),
                    search,
                    smoothing_timing_s: st,
                    v_start: start.v,
                });
                self.reference = Some(r);
                true
            }
            Err(e) => {
                self.fail(start.t0, format!("the path could not be timed: {e}"));
                false
            }
        }
    }

    #[allow(clippy::too_many_lines)]
    fn run(mut self) -> Result<MissionResult> {
        let m = self.m;
        let f = &m.file;
        let wm = self.wm;
        let model = &wm.model;
        let (nq, nr, nu) = (model.nq, wm.nr(), wm.nu());
        let arm = wm.arm_dofs().to_vec();
        let na = arm.len();
        let grid = &m.map.grid;
        let res = grid.resolution;
        let r_foot = f.robot.footprint_radius;
        let goal = f.goal.pose;
        // the unicycle point the platform is planned and tracked by: the driven-axle
        // midpoint, `d` behind the base frame origin
        let d = wm.base.drive.d;
        let goal_axle = axle_pose(goal, d);

        // initial state
        let mut x = vec![0.0; nq + nr + 1];
        x[..3].copy_from_slice(&f.start.pose);
        for (k, &i) in arm.iter().enumerate() {
            x[i] = m.q_arm0[k];
        }
        let mut q_t = DVector::zeros(nq);
        for (k, &i) in arm.iter().enumerate() {
            q_t[i] = m.transport[k];
        }

        // the first plan
        if self.timing_accel.is_none() {
            let why = if self.tip.forward.is_none() || self.tip.backward.is_none() {
                "the transport posture tips the robot at rest (its ZMP lies outside the support \
                 polygon), so every motion would tip it"
            } else {
                "the transport posture leaves no acceleration that keeps the ZMP inside the \
                 support, so every motion would tip the robot"
            };
            self.fail(0.0, why.to_string());
        } else {
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
                        pose: axle_pose(f.start.pose, d),
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

        let h = f.simulation.dt;
        let time_limit = f
            .simulation
            .time_limit
            .unwrap_or_else(|| self.plans.first().map_or(10.0, |p| 3.0 * p.duration + 30.0));
        if time_limit / h > MAX_STEPS || time_limit / f.simulation.record_interval > MAX_SAMPLES {
            return Err(Error::invalid(
                "simulation.time_limit",
                format!("a run of {time_limit} s needs too many steps or samples"),
            ));
        }
        let rec_every = ((f.simulation.record_interval / h).round() as usize).max(1);

        // workspaces
        let mut sys = WheeledSystem::new(wm.clone());
        let mut cwd = WheeledData::new(wm);
        let mut mwd = WheeledData::new(wm);
        let mut data = Data::new(model);
        let support = SupportPolygon::from_wheeled_base(&wm.base)?;
        let sm = StabilityModel::new(model, support, SupportAttachment::Base, &BodySet::All)?;
        let mut sd = StabilityData::new(&sm);
        let support_pts = wm.base.support_points();
        let mut contacts = support_pts.clone();
        let mut loads = vec![0.0; support_pts.len()];
        let mut rk = Rk4::new(nq + nr + 1);
        let mut qv = DVector::zeros(nq);
        let mut vv = DVector::zeros(nr);
        let mut u = vec![0.0; nu];
        let zero_u = vec![0.0; nu];
        let mut a_des = DVector::zeros(nr);
        let mut smat = DMatrix::zeros(model.nv, nu);
        let mut jac = Matrix6xX::zeros(model.nv);
        let mut ndot = DMatrix::zeros(model.nv, nr);
        let mut ndv = DVector::zeros(model.nv);
        let mut jr = DMatrix::zeros(3, nr);

        // the platform block of N_Cᵀ S: Qr[0..2] = B u[0..2]
        qv.copy_from_slice(&x[..nq]);
        admissible_velocity_basis(wm, &qv, &mut cwd.basis);
        actuation_matrix(wm, &qv, &mut smat);
        let b_full = cwd.basis.transpose() * &smat;
        let b_pp = Matrix2::new(
            b_full[(0, 0)],
            b_full[(0, 1)],
            b_full[(1, 0)],
            b_full[(1, 1)],
        );
        let b_inv = b_pp.try_inverse().ok_or_else(|| Error::Singular {
            what: "wheel actuation map".into(),
            detail: None,
        })?;

        // limits of the actuators
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
        let arm_tau: Vec<f64> = arm.iter().map(|&i| lim(i, &model.effort_limit)).collect();
        let w_inv = wm.base.drive.platform_to_wheel();

        let c = &f.control;
        let kan = Kanayama::new(c.kx, c.ky, c.kth)?;
        let ks = c.speed_gain;
        let wn = c.arm_frequency;
        let wt = c.task_frequency;
        let (tip_f, tip_b) = match (self.tip.forward, self.tip.backward) {
            (Some(a), Some(b)) => (a, b),
            _ => (0.0, 0.0),
        };
        let a_guard_f = (2.0 * f.limits.a_max).min(0.95 * tip_f);
        let a_guard_b = (2.0 * f.limits.a_max).min(0.95 * tip_b);
        let alpha_guard = 2.0 * f.limits.alpha_max;
        let chain = arm_chain(m);

        let mut obstacles: Vec<(usize, f64)> = f
            .obstacles
            .iter()
            .enumerate()
            .map(|(k, o)| (k, o.t))
            .collect();
        obstacles.sort_by(|a, b| a.1.total_cmp(&b.1).then(a.0.cmp(&b.0)));
        let mut next_obstacle = 0usize;

        let mut phase = if self.failure.is_some() {
            Phase::Done
        } else {
            Phase::Drive
        };
        let mut phase_t0 = 0.0;
        let mut ee_traj: Option<EeTrajectory> = None;
        let mut energy = 0.0;
        let mut torque_sat = 0usize;
        let mut speed_sat = 0usize;
        let mut first_torque_sat = true;
        let mut first_speed_sat = true;
        let mut first_slip = true;
        let mut first_contact = true;
        let mut time_to_goal = None;
        let mut cur_ref = RefSample {
            t: 0.0,
            x: f.start.pose[0],
            y: f.start.pose[1],
            theta: f.start.pose[2],
            v: 0.0,
            omega: 0.0,
            a: 0.0,
            alpha: 0.0,
        };
        let sim_clock = Instant::now();
        let mut excluded = 0.0; // planning time spent inside the loop
        let mut k = 0usize;
        let mut t;
        loop {
            t = k as f64 * h;
            qv.copy_from_slice(&x[..nq]);
            vv.copy_from_slice(&x[nq..nq + nr]);
            let pose = [x[0], x[1], x[2]];
            let axle = axle_pose(pose, d);
            let (v, w) = (x[nq], x[nq + 1]);

            // obstacles that appear now
            while phase != Phase::Done
                && next_obstacle < obstacles.len()
                && obstacles[next_obstacle].1 <= t + 1e-12
            {
                let (oi, ot) = obstacles[next_obstacle];
                next_obstacle += 1;
                let o = f.obstacles[oi];
                let clock = Instant::now();
                let c = grid.world_to_cell_f(o.center[0], o.center[1]);
                let [fx, fy] = grid.world_to_cell_f(axle[0], axle[1]);
                let rc = (
                    (fx.floor().max(0.0) as usize).min(grid.width - 1),
                    (fy.floor().max(0.0) as usize).min(grid.height - 1),
                );
                let added = self.planner.add_disk(c, o.radius / res, rc);
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
                        phase = Phase::Done;
                        break;
                    }
                };
                if newly.contains(&self.planner.goal_cell) && phase == Phase::Drive {
                    self.wall.planning_s += s_time;
                    excluded += clock.elapsed().as_secs_f64();
                    self.fail(
                        t,
                        format!(
                            "obstacle {oi} (t = {ot} s) seals the goal: the footprint no \
                             longer fits at the goal pose"
                        ),
                    );
                    phase = Phase::Done;
                    break;
                }
                let affected = phase == Phase::Drive
                    && self.reference.as_ref().is_some_and(|r| {
                        r.samples.iter().filter(|s| s.t >= t).any(|s| {
                            let [cx, cy] = grid.world_to_cell_f(s.x, s.y);
                            self.planner.blocked_at(cx, cy)
                        })
                    });
                if affected {
                    let (path, mut timing) = self.planner.replan();
                    timing.search_s += s_time;
                    self.wall.planning_s += timing.search_s;
                    match path {
                        None => {
                            self.fail(
                                t,
                                format!(
                                    "obstacle {oi} (t = {ot} s) seals the goal: no \
                                     collision-free path remains"
                                ),
                            );
                            phase = Phase::Done;
                        }
                        Some(cells) => {
                            let start = TimingStart {
                                t0: t,
                                pose: axle,
                                v,
                            };
                            if self.make_reference(cells, start, &format!("obstacle {oi}"), timing)
                            {
                                let p = self.plans.last().expect("just pushed");
                                let text = format!(
                                    "re-plan after obstacle {oi}: D* Lite expanded {} cells, \
                                     new path {:.2} m, {:.2} s to go from {:.2} m/s",
                                    p.search.expanded,
                                    path_length(&p.path),
                                    p.duration,
                                    p.v_start
                                );
                                self.event(t, "replan", text);
                            } else {
                                phase = Phase::Done;
                            }
                        }
                    }
                } else {
                    self.wall.planning_s += s_time;
                }
                excluded += clock.elapsed().as_secs_f64();
            }

            // reduced dynamics at the state (controller's model)
            let step_ok = reduced_forward_dynamics_crba(wm, &mut cwd, &qv, &vv, &zero_u);
            if let Err(e) = step_ok {
                self.fail(t, format!("the dynamics became singular: {e}"));
                phase = Phase::Done;
            }

            // phase transitions
            if phase == Phase::Drive {
                let r = self.reference.as_ref().expect("drive has a reference");
                if t >= r.t_end() {
                    phase = Phase::Arrive;
                    phase_t0 = t;
                }
            }
            if phase == Phase::Arrive {
                let pe = (pose[0] - goal[0]).hypot(pose[1] - goal[1]);
                let he = wrap_angle(goal[2] - pose[2]).abs();
                let settled = v.abs() < 0.02 && w.abs() < 0.05;
                if pe <= f.goal.position_tolerance && he <= f.goal.heading_tolerance && settled {
                    self.event(
                        t,
                        "arrived",
                        format!("base at the goal: {pe:.3} m, {he:.3} rad off"),
                    );
                    if f.goal.end_effector.is_some() {
                        phase = Phase::Reach;
                        phase_t0 = t;
                    } else {
                        time_to_goal = Some(t);
                        phase = Phase::Done;
                    }
                } else if t - phase_t0 > ARRIVE_TIMEOUT {
                    self.fail(
                        t,
                        format!(
                            "the base stopped {pe:.3} m and {he:.3} rad from the goal pose \
                             (tolerances {} m, {} rad)",
                            f.goal.position_tolerance, f.goal.heading_tolerance
                        ),
                    );
                    phase = Phase::Done;
                }
            }
            if t >= time_limit && phase != Phase::Done {
                self.fail(t, format!("time limit of {time_limit:.1} s reached"));
                phase = Phase::Done;
            }

            // end-effector kinematics in reduced coordinates (for the reach phase and the
            // record)
            let mut ee_p = Vector3::zeros();
            let mut ee_dp = Vector3::zeros();
            let mut ee_bias = Vector3::zeros();
            let need_ee = phase == Phase::Reach || k.is_multiple_of(rec_every);
            if need_ee {
                let qd = &cwd.qdot;
                let acc = frame_acceleration_bias(
                    model,
                    &mut data,
                    &qv,
                    qd,
                    m.ee_frame,
                    ReferenceFrame::LocalWorldAligned,
                );
                ee_p = data.world_from_frame[m.ee_frame.0].translation;
                frame_jacobian_from_kinematics(
                    model,
                    &mut data,
                    m.ee_frame,
                    ReferenceFrame::LocalWorldAligned,
                    &mut jac,
                );
                admissible_velocity_basis_dot(wm, &qv, qd[2], &mut ndot);
                ndot.mul_to(&vv, &mut ndv);
                for r in 0..3 {
                    let mut b = acc.linear[r];
                    for cc in 0..model.nv {
                        b += jac[(r, cc)] * ndv[cc];
                    }
                    ee_bias[r] = b;
                    for j in 0..nr {
                        let mut s = 0.0;
                        for l in 0..model.nv {
                            s += jac[(r, l)] * cwd.basis[(l, j)];
                        }
                        jr[(r, j)] = s;
                    }
                    let mut s = 0.0;
                    for j in 0..nr {
                        s += jr[(r, j)] * vv[j];
                    }
                    ee_dp[r] = s;
                }
            }

            // control law: desired reduced accelerations
            let mut speed_clip = false;
            match phase {
                Phase::Drive | Phase::Arrive => {
                    let (mut cmd, r) = if phase == Phase::Drive {
                        let r = self
                            .reference
                            .as_ref()
                            .expect("drive has a reference")
                            .at(t);
                        let rs = ReferenceSample {
                            pose: [r.x, r.y, r.theta],
                            v: r.v,
                            w: r.omega,
                        };
                        (kan.inputs(&axle, &rs), base_reference(r, d))
                    } else {
                        let rs = ReferenceSample {
                            pose: goal_axle,
                            v: 0.0,
                            w: 0.0,
                        };
                        let [ex, _, eth] = Kanayama::error(&axle, &rs);
                        let r = RefSample {
                            t,
                            x: goal[0],
                            y: goal[1],
                            theta: goal[2],
                            v: 0.0,
                            omega: 0.0,
                            a: 0.0,
                            alpha: 0.0,
                        };
                        ([c.kx * ex, 2.0 * eth], r)
                    };
                    cur_ref = r;
                    if cmd[0].abs() > f.limits.v_max {
                        cmd[0] = f.limits.v_max.copysign(cmd[0]);
                        speed_clip = true;
                    }
                    if cmd[1].abs() > f.limits.omega_max {
                        cmd[1] = f.limits.omega_max.copysign(cmd[1]);
                        speed_clip = true;
                    }
                    let wr = w_inv * Vector2::new(cmd[0], cmd[1]);
                    let peak = wr.amax();
                    if peak > wheel_speed {
                        let s = wheel_speed / peak;
                        cmd[0] *= s;
                        cmd[1] *= s;
                        speed_clip = true;
                    }
                    a_des[0] = (r.a + ks * (cmd[0] - v)).clamp(-a_guard_b, a_guard_f);
                    a_des[1] = (r.alpha + ks * (cmd[1] - w)).clamp(-alpha_guard, alpha_guard);
                    for (k2, &i) in arm.iter().enumerate() {
                        a_des[2 + k2] = wn * wn * (q_t[i] - qv[i]) - 2.0 * wn * vv[2 + k2];
                    }
                }
                Phase::Reach => {
                    let target = Vector3::from(f.goal.end_effector.expect("reach has a target"));
                    let traj = *ee_traj.get_or_insert_with(|| {
                        let dist = (target - ee_p).norm();
                        EeTrajectory {
                            t0: t,
                            duration: (1.875 * dist / 0.25).max(1.5),
                            from: ee_p,
                            to: target,
                        }
                    });
                    cur_ref = RefSample {
                        t,
                        x: goal[0],
                        y: goal[1],
                        theta: goal[2],
                        v: 0.0,
                        omega: 0.0,
                        a: 0.0,
                        alpha: 0.0,
                    };
                    // platform holds: speeds to zero
                    a_des[0] = -ks * v;
                    a_des[1] = -ks * w;
                    let (xd, dxd, ddxd) = traj.at(t);
                    let mut rhs =
                        ddxd + (dxd - ee_dp) * (2.0 * wt) + (xd - ee_p) * (wt * wt) - ee_bias;
                    for r in 0..3 {
                        rhs[r] -= jr[(r, 0)] * a_des[0] + jr[(r, 1)] * a_des[1];
                    }
                    // damped least squares on the arm block, null-space damping
                    let mut jjt = Matrix3::zeros();
                    for r in 0..3 {
                        for s in 0..3 {
                            let mut acc = 0.0;
                            for j in 2..nr {
                                acc += jr[(r, j)] * jr[(s, j)];
                            }
                            jjt[(r, s)] = acc;
                        }
                        jjt[(r, r)] += 1e-6;
                    }
                    let Some(jinv) = jjt.try_inverse() else {
                        self.fail(t, "the arm is singular at the goal".to_string());
                        phase = Phase::Done;
                        continue;
                    };
                    let y = jinv * rhs;
                    // null-space motion: damp the joint rates
                    let mut q0 = vec![0.0; na];
                    for (k2, q0k) in q0.iter_mut().enumerate() {
                        *q0k = -2.0 * wn * vv[2 + k2];
                    }
                    // J q0
                    let mut jq0 = Vector3::zeros();
                    for r in 0..3 {
                        for (k2, q0k) in q0.iter().enumerate() {
                            jq0[r] += jr[(r, 2 + k2)] * q0k;
                        }
                    }
                    let z = jinv * jq0;
                    for k2 in 0..na {
                        let mut acc = q0[k2];
                        for r in 0..3 {
                            acc += jr[(r, 2 + k2)] * (y[r] - z[r]);
                        }
                        a_des[2 + k2] = acc;
                    }
                    let err = (target - ee_p).norm();
                    if t >= traj.t0 + traj.duration
                        && err <= f.goal.end_effector_tolerance
                        && ee_dp.norm() < 0.01
                    {
                        self.event(
                            t,
                            "reached",
                            format!("end effector at its target: {:.4} m off", err),
                        );
                        time_to_goal = Some(t);
                        phase = Phase::Done;
                    } else if t > traj.t0 + traj.duration + REACH_SETTLE {
                        self.fail(
                            t,
                            format!(
                                "the end effector stopped {err:.3} m from its target \
                                 (tolerance {} m)",
                                f.goal.end_effector_tolerance
                            ),
                        );
                        phase = Phase::Done;
                    }
                }
                Phase::Done => {
                    a_des[0] = -ks * v;
                    a_des[1] = -ks * w;
                    for k2 in 0..na {
                        a_des[2 + k2] = -2.0 * wn * vv[2 + k2];
                    }
                }
            }

            // computed torque through the reduced model: Qr = Mr a + (cr + Gr)
            let mr = &cwd.reduced.mass_matrix;
            let bias = &cwd.reduced.velocity_terms;
            let mut qr = [0.0f64; 2];
            for (i, qri) in qr.iter_mut().enumerate() {
                let mut s = bias[i];
                for j in 0..nr {
                    s += mr[(i, j)] * a_des[j];
                }
                *qri = s;
            }
            let up = b_inv * Vector2::new(qr[0], qr[1]);
            let mut torque_clip = false;
            for s in 0..2 {
                let tau = up[s];
                u[s] = if tau.abs() > wheel_tau[s] {
                    torque_clip = true;
                    wheel_tau[s].copysign(tau)
                } else {
                    tau
                };
            }
            for k2 in 0..na {
                let i = 2 + k2;
                let mut s = bias[i];
                for j in 0..nr {
                    s += mr[(i, j)] * a_des[j];
                }
                u[i] = if s.abs() > arm_tau[k2] {
                    torque_clip = true;
                    arm_tau[k2].copysign(s)
                } else {
                    s
                };
            }
            if torque_clip {
                torque_sat += 1;
                if first_torque_sat {
                    first_torque_sat = false;
                    self.event(t, "torque_limit", "first torque saturation");
                }
            }
            if speed_clip {
                speed_sat += 1;
                if first_speed_sat {
                    first_speed_sat = false;
                    self.event(t, "speed_limit", "first speed-command saturation");
                }
            }

            // record
            let last = phase == Phase::Done;
            if k.is_multiple_of(rec_every) || last {
                let rec = self.record(
                    &mut RecordCtx {
                        mwd: &mut mwd,
                        data: &mut data,
                        sm: &sm,
                        sd: &mut sd,
                        support_pts: &support_pts,
                        contacts: &mut contacts,
                        loads: &mut loads,
                        chain: &chain,
                    },
                    t,
                    &qv,
                    &vv,
                    &u,
                    &cur_ref,
                    ee_p,
                    energy,
                    phase,
                    res,
                    r_foot,
                );
                if let Some((slip, clear)) = rec {
                    if first_slip && slip.is_some_and(|s| s > 1.0) {
                        first_slip = false;
                        self.event(t, "slip", "lateral wheel force exceeds μ N");
                    }
                    if first_contact && clear < 0.0 {
                        first_contact = false;
                        self.event(
                            t,
                            "contact",
                            format!("footprint overlaps an obstacle by {:.3} m", -clear),
                        );
                        if phase != Phase::Done {
                            self.fail(
                                t,
                                format!(
                                    "collision: the footprint overlaps an obstacle by {:.3} m",
                                    -clear
                                ),
                            );
                            phase = Phase::Done;
                        }
                    }
                }
            }
            if last {
                break;
            }

            // actuator energy over the step (rates at its start)
            let wrates = w_inv * Vector2::new(v, w);
            let mut p_abs = (u[0] * wrates[0]).abs() + (u[1] * wrates[1]).abs();
            for k2 in 0..na {
                p_abs += (u[2 + k2] * vv[2 + k2]).abs();
            }
            energy += p_abs * h;

            // integrate one step
            let mut plant = Plant {
                sys: &mut sys,
                u: &u,
                nq,
                nr,
            };
            if let Err(e) = rk.step(&mut plant, t, &mut x, h) {
                self.fail(t, format!("the simulation failed: {e}"));
                phase = Phase::Done;
                // record the state reached before the failure on the next pass
                continue;
            }
            k += 1;
        }
        self.wall.simulation_s = (sim_clock.elapsed().as_secs_f64() - excluded).max(0.0);

        // the minimum ZMP margin as an event
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
        self.events.sort_by(|a, b| a.t.total_cmp(&b.t));
        let reached = self.failure.is_none() && time_to_goal.is_some();
        let reason = if reached {
            None
        } else {
            Some(
                self.failure
                    .clone()
                    .unwrap_or_else(|| "the mission ended before the goal".into()),
            )
        };
        let arm_names = arm
            .iter()
            .map(|&i| model.names[model.joint_of_dof[i].0].clone())
            .collect();
        Ok(MissionResult {
            reached,
            reason,
            time_to_goal: if reached { time_to_goal } else { None },
            duration: t,
            tip_limits: self.tip,
            timing_acceleration: self.timing_accel.map(|a| [a.forward, a.backward]),
            plans: self.plans,
            events: self.events,
            samples: self.samples,
            q_names: wm.q_names(),
            u_names: wm.u_names(),
            arm_names,
            torque_saturated_steps: torque_sat,
            speed_saturated_steps: speed_sat,
            steps: k,
            input_work: x[nq + nr],
            wall: self.wall,
        })
    }

    /// Records one sample; returns (slip ratio, clearance) for the event checks, `None`
    /// if the monitors could not be evaluated (the sample is still recorded).
    #[allow(clippy::too_many_arguments)]
    fn record(
        &mut self,
        ctx: &mut RecordCtx<'_>,
        t: f64,
        q: &DVector<f64>,
        v: &DVector<f64>,
        u: &[f64],
        r: &RefSample,
        ee: Vector3<f64>,
        energy: f64,
        phase: Phase,
        res: f64,
        r_foot: f64,
    ) -> Option<(Option<f64>, f64)> {
        let wm = self.wm;
        let model = &wm.model;
        let grid = &self.m.map.grid;
        let s = &mut self.samples;
        let ok = reduced_forward_dynamics(wm, ctx.mwd, q, v, u).is_ok();
        let (mut zmp, mut fa, mut mhs, mut slip) = (None, None, None, None);
        if ok {
            let lam = lagrange_multipliers(wm, ctx.mwd, q).ok().map(|l| {
                let at = |i: usize| l.get(i).copied().unwrap_or(0.0);
                ([at(0), at(1), at(2)], l.len())
            });
            let rep = crate::stability::evaluate(
                model,
                ctx.data,
                ctx.sm,
                ctx.sd,
                q,
                &ctx.mwd.qdot,
                &ctx.mwd.reduced.qddot,
                &ExternalLoads::default(),
            );
            zmp = rep.zmp_margin;
            fa = rep.force_angle_min;
            mhs = rep.mhs_min;
            if let Some((lam, nk)) = lam {
                // contacts in the world, loads from the wrench (stability::loads)
                let (sn, cs) = q[2].sin_cos();
                for (w, p) in ctx.contacts.iter_mut().zip(ctx.support_pts) {
                    *w = Vector2::new(q[0] + cs * p.x - sn * p.y, q[1] + sn * p.x + cs * p.y);
                }
                let ground = ctx.sm.support.ground_z();
                if contact_normal_loads(ctx.contacts, ground, &ctx.sd.wrench, ctx.loads).is_ok() {
                    // longitudinal wheel forces: the rolling multipliers of tracked wheels,
                    // else the wheel torques over the radius
                    let long = if nk == 3 {
                        [lam[1], lam[2]]
                    } else {
                        let r = wm.base.drive.wheel_radius;
                        [u[0] / r, u[1] / r]
                    };
                    if let Ok(fr) = driven_wheel_friction(
                        -lam[0],
                        long,
                        [ctx.loads[0], ctx.loads[1]],
                        self.m.file.limits.mu,
                    ) {
                        slip = fr
                            .iter()
                            .map(|w| w.slip_ratio.unwrap_or(f64::INFINITY))
                            .reduce(f64::max)
                            .filter(|x| x.is_finite());
                    }
                }
            }
        }
        // arm chain in the base x–z plane
        crate::kinematics::forward_kinematics(model, ctx.data, q);
        let (sn, cs) = q[2].sin_cos();
        let to_base = |p: &Vector3<f64>| {
            let dx = p.x - q[0];
            let dy = p.y - q[1];
            [cs * dx + sn * dy, p.z]
        };
        let mut side: Vec<[f64; 2]> = ctx
            .chain
            .iter()
            .map(|&j| to_base(&ctx.data.world_from_joint[j].translation))
            .collect();
        side.push(to_base(&ee));
        let [fx, fy] = grid.world_to_cell_f(q[0], q[1]);
        let clearance = self
            .planner
            .obstacle_distance(fx, fy, (r_foot + EXACT_CLEARANCE) / res)
            .map_or(f64::INFINITY, |d| d * res - r_foot);
        let te = (q[0] - r.x).hypot(q[1] - r.y);
        s.t.push(t);
        s.q.push(q.as_slice().to_vec());
        s.v.push(v[0]);
        s.omega.push(v[1]);
        s.v_ref.push(r.v);
        s.omega_ref.push(r.omega);
        s.ref_xy.push([r.x, r.y]);
        s.zmp_margin.push(zmp);
        s.force_angle_min.push(fa);
        s.mhs_min.push(mhs);
        s.clearance.push(clearance);
        s.tracking_error.push(te);
        s.slip_ratio.push(slip);
        s.u.push(u.to_vec());
        s.ee.push([ee.x, ee.y, ee.z]);
        s.arm_side.push(side);
        s.energy.push(energy);
        s.phase.push(phase.name());
        ok.then_some((slip, clearance))
    }
}

struct RecordCtx<'a> {
    mwd: &'a mut WheeledData,
    data: &'a mut Data,
    sm: &'a StabilityModel,
    sd: &'a mut StabilityData,
    support_pts: &'a [Vector2<f64>],
    contacts: &'a mut [Vector2<f64>],
    loads: &'a mut [f64],
    chain: &'a [usize],
}

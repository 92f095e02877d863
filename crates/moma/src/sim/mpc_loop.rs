//! The whole-body MPC ([`crate::control::mpc::WholeBodyMpc`]) in closed loop on the
//! reduced-model plant of a wheeled URDF robot ([`WheeledSystem`]): every control period
//! the MPC solves from the measured state, the torques that realise its first input
//! (inverse dynamics, clipped to the actuator limits) are held for the period, and RK4
//! integrates the plant. Each period records the solve report and what the plant did:
//! ZMP margin of the true state (its real acceleration), clearance (every enabled self
//! pair and the scene), torque beyond the limits before clipping, end-effector error.

use nalgebra::DVector;

use crate::collision::{
    GeometryData, PairSelection, SceneData, compute_distances, compute_scene_distances,
    update_geometry_placements,
};
use crate::control::mpc::{KnotReference, SolveReport, Violations, WholeBodyMpc};
use crate::error::{Error, Result};
use crate::ode::{OdeSystem, Rk4};
use crate::sim::reduced_system::ReducedSystem;
use crate::sim::wheeled_system::WheeledSystem;
use crate::stability::{ExternalLoads, StabilityData, evaluate};

/// Settings of a closed-loop run.
#[derive(Clone, Copy, Debug)]
pub struct MpcLoopSettings {
    /// Duration (s).
    pub duration: f64,
    /// Control period (s): one solve per period, torques held over it.
    pub period: f64,
    /// RK4 steps per period.
    pub substeps: usize,
}

/// One control period.
#[derive(Clone, Debug)]
pub struct MpcSample {
    /// Time at the start of the period (s).
    pub t: f64,
    /// Configuration at that time.
    pub q: Vec<f64>,
    /// Reduced velocity.
    pub v: Vec<f64>,
    /// Torques applied over the period.
    pub torque: Vec<f64>,
    /// The solve.
    pub solve: SolveReport,
    /// ZMP margin of the plant's state and acceleration (m); `None` at lift-off.
    pub zmp_margin: Option<f64>,
    /// Smallest distance over the enabled self pairs and the scene (m; `∞` without
    /// geometry).
    pub clearance: f64,
    /// Largest torque beyond its limit that the MPC asked for (clipped before applying).
    pub torque_excess: f64,
    /// End-effector position error to the reference at `t`, if it has a target (m).
    pub ee_error: Option<f64>,
}

/// Percentiles of the solve times and the closed loop's extremes.
#[derive(Clone, Debug, PartialEq)]
pub struct MpcRunSummary {
    /// Number of solves.
    pub solves: usize,
    /// Solve time percentiles (s): 50th, 90th, 99th, and the largest.
    pub solve_time_p50: f64,
    /// 90th percentile.
    pub solve_time_p90: f64,
    /// 99th percentile.
    pub solve_time_p99: f64,
    /// Largest.
    pub solve_time_max: f64,
    /// Mean and largest iterations per solve.
    pub iterations_mean: f64,
    /// Largest.
    pub iterations_max: usize,
    /// Largest violation per kind over every planned horizon.
    pub planned_violations: Violations,
    /// Smallest ZMP margin of the plant (m).
    pub min_zmp_margin: f64,
    /// Smallest clearance of the plant (m).
    pub min_clearance: f64,
    /// Largest torque excess asked for (clipped).
    pub max_torque_excess: f64,
    /// Largest wheel rate beyond its limit in the plant (rad/s).
    pub wheel_speed_excess: f64,
    /// Largest joint speed beyond its limit in the plant.
    pub joint_speed_excess: f64,
    /// Largest joint position beyond its limit in the plant.
    pub joint_position_excess: f64,
    /// Smallest end-effector error over the run (m), if a target was set.
    pub min_ee_error: Option<f64>,
    /// First time the end-effector error fell below 2 cm (s).
    pub ee_reached_at: Option<f64>,
    /// Platform speed `|v|` at that time (m/s): non-zero when the arm reached on the move.
    pub base_speed_at_reach: Option<f64>,
}

/// A closed-loop run: samples and summary; `q`, `v` end at the final state.
#[derive(Clone, Debug)]
pub struct MpcRun {
    /// One sample per period.
    pub samples: Vec<MpcSample>,
    /// Summary.
    pub summary: MpcRunSummary,
}

/// The plant under held torques, state `[q, v]`.
struct HeldTorques<'a> {
    plant: &'a mut WheeledSystem,
    torque: &'a [f64],
}

impl OdeSystem for HeldTorques<'_> {
    fn dim(&self) -> usize {
        self.plant.nq() + self.plant.nv()
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<()> {
        let nq = self.plant.nq();
        let (q, v) = x.split_at(nq);
        let (qd, vd) = dx.split_at_mut(nq);
        self.plant
            .dynamics(q, v, self.torque, qd, vd)
            .map_err(|e| e.singular_at_time(t))
    }
}

/// The `p`-th percentile (nearest rank) of sorted values.
fn percentile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let rank = ((p / 100.0) * sorted.len() as f64).ceil() as usize;
    sorted[rank.clamp(1, sorted.len()) - 1]
}

/// Runs `mpc` in closed loop on `plant` (the same robot) from `(q0, v0)`; `reference(t)`
/// gives the knot reference at time `t`.
///
/// # Errors
/// [`Error::Invalid`] for a non-positive duration or period, zero substeps or states of
/// the wrong length; what the solver or the plant report.
pub fn run_mpc_loop(
    mpc: &mut WholeBodyMpc,
    plant: &mut WheeledSystem,
    q0: &[f64],
    v0: &[f64],
    settings: &MpcLoopSettings,
    mut reference: impl FnMut(f64) -> KnotReference,
) -> Result<MpcRun> {
    for (field, v) in [("duration", settings.duration), ("period", settings.period)] {
        if !(v > 0.0 && v.is_finite()) {
            return Err(Error::invalid(field, format!("must be positive, got {v}")));
        }
    }
    if settings.substeps == 0 {
        return Err(Error::invalid("substeps", "must be at least 1"));
    }
    let (nq, nv) = (plant.nq(), plant.nv());
    crate::error::ensure_len("q0", nq, q0.len())?;
    crate::error::ensure_len("v0", nv, v0.len())?;
    let robot = mpc.problem.robot.clone();
    let model = &robot.wheeled.model;
    let mut data = crate::multibody::Data::new(model);
    let mut sd = StabilityData::new(&robot.stability);
    let mut geo = robot.clearance.as_ref().map(|c| {
        (
            GeometryData::new(&c.geometry),
            SceneData::new(&c.geometry, &c.scene),
        )
    });
    let mut x = q0.to_vec();
    x.extend_from_slice(v0);
    let mut dx = vec![0.0; nq + nv];
    let mut torque = vec![0.0; plant.nu()];
    let mut raw = vec![0.0; plant.nu()];
    let mut rk4 = Rk4::new(nq + nv);
    let steps = (settings.duration / settings.period).round() as usize;
    let h = settings.period / settings.substeps as f64;
    let mut samples = Vec::with_capacity(steps);
    let mut qv = DVector::zeros(nq);
    for step in 0..steps {
        let t = step as f64 * settings.period;
        mpc.set_reference(t, &mut reference);
        let (q, v) = x.split_at(nq);
        let solve = mpc.solve(q, v)?;
        mpc.first_torques(&mut raw, false)?;
        let mut excess: f64 = 0.0;
        for i in 0..raw.len() {
            let lim = robot.torque_limit[i];
            excess = excess.max(raw[i].abs() - lim);
            torque[i] = raw[i].clamp(-lim, lim);
        }
        // What the plant does under these torques: its acceleration, hence its ZMP.
        {
            let (q, v) = x.split_at(nq);
            let (qd, vd) = dx.split_at_mut(nq);
            plant.dynamics(q, v, &torque, qd, vd)?;
        }
        qv.copy_from_slice(&x[..nq]);
        let wd = &plant.data;
        let report = evaluate(
            model,
            &mut data,
            &robot.stability,
            &mut sd,
            &qv,
            &wd.qdot,
            &wd.reduced.qddot,
            &ExternalLoads::NONE,
        );
        let zmp_margin = report.zmp_margin;
        let mut clearance = f64::INFINITY;
        if let (Some(c), Some((gd, scd))) = (&robot.clearance, &mut geo) {
            update_geometry_placements(&c.geometry, &data, gd);
            let own = compute_distances(&c.geometry, gd, PairSelection::Enabled);
            let other = compute_scene_distances(&c.geometry, gd, &c.scene, scd);
            clearance = own.min(other);
        }
        let ee_error = reference(t).end_effector.map(|(p, _)| {
            crate::kinematics::forward_kinematics(model, &mut data, &qv);
            let m = crate::kinematics::update_frame_placement(model, &mut data, robot.end_effector);
            (m.translation - p).norm()
        });
        samples.push(MpcSample {
            t,
            q: x[..nq].to_vec(),
            v: x[nq..].to_vec(),
            torque: torque.clone(),
            solve,
            zmp_margin,
            clearance,
            torque_excess: excess.max(0.0),
            ee_error,
        });
        let mut ode = HeldTorques {
            plant,
            torque: &torque,
        };
        rk4.step_from_derivative(&mut ode, t, &mut x, &dx, h)?;
        for k in 1..settings.substeps {
            rk4.step(&mut ode, t + k as f64 * h, &mut x, h)?;
        }
    }
    let summary = summarize(&robot, &samples);
    Ok(MpcRun { samples, summary })
}

/// The summary of a run's samples.
fn summarize(robot: &crate::control::mpc::MpcRobot, samples: &[MpcSample]) -> MpcRunSummary {
    let mut times: Vec<f64> = samples.iter().map(|s| s.solve.time.as_secs_f64()).collect();
    times.sort_by(f64::total_cmp);
    let n = samples.len().max(1) as f64;
    let mut planned = Violations::default();
    let (mut wheel, mut speed, mut pos): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for s in samples {
        planned = planned.max(&s.solve.violations);
        let mut xs = DVector::zeros(robot.nx());
        robot.state_from_plant(&s.q, &s.v, &mut xs);
        let nc = robot.n_moved();
        let rates = robot.wheel_map * nalgebra::Vector2::new(xs[3 + nc], xs[4 + nc]);
        wheel = wheel.max(rates.amax() - robot.wheel_rate_limit);
        for i in 0..nc {
            speed = speed.max(xs[5 + nc + i].abs() - robot.speed_limit[i]);
            pos = pos
                .max(xs[3 + i] - robot.upper[i])
                .max(robot.lower[i] - xs[3 + i]);
        }
    }
    let reached = samples
        .iter()
        .find(|s| s.ee_error.is_some_and(|e| e < 0.02));
    MpcRunSummary {
        solves: samples.len(),
        solve_time_p50: percentile(&times, 50.0),
        solve_time_p90: percentile(&times, 90.0),
        solve_time_p99: percentile(&times, 99.0),
        solve_time_max: times.last().copied().unwrap_or(f64::NAN),
        iterations_mean: samples
            .iter()
            .map(|s| s.solve.iterations as f64)
            .sum::<f64>()
            / n,
        iterations_max: samples
            .iter()
            .map(|s| s.solve.iterations)
            .max()
            .unwrap_or(0),
        planned_violations: planned,
        min_zmp_margin: samples
            .iter()
            .map(|s| s.zmp_margin.unwrap_or(f64::NEG_INFINITY))
            .fold(f64::INFINITY, f64::min),
        min_clearance: samples
            .iter()
            .map(|s| s.clearance)
            .fold(f64::INFINITY, f64::min),
        max_torque_excess: samples.iter().map(|s| s.torque_excess).fold(0.0, f64::max),
        wheel_speed_excess: wheel.max(0.0),
        joint_speed_excess: speed.max(0.0),
        joint_position_excess: pos.max(0.0),
        min_ee_error: samples.iter().filter_map(|s| s.ee_error).reduce(f64::min),
        ee_reached_at: reached.map(|s| s.t),
        base_speed_at_reach: reached.map(|s| s.v[0].abs()),
    }
}

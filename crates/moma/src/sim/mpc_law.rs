//! The whole-body MPC ([`WholeBodyMpc`]) as a [`FeedbackLaw`], so that the one stepping
//! loop ([`crate::sim::closed_loop::simulate_closed_loop`]) runs it under a zero-order
//! hold at the control period, as it runs every other law.
//!
//! At each control tick the law sets the MPC's reference over the horizon from
//! `reference(t)`, solves from the measured `(q, v)` (warm-started from the previous
//! solution), and realises the first planned input `[v̇, ω̇, q̈_c]` as actuator torques
//! by [`WholeBodyMpc::first_input_torques_at`]: the MPC's own computed torque on the
//! reduced model, `(N_Cᵀ S)⁻¹ (Mr a + cr + Gr)` at the state the MPC solved from (the
//! joints it does not move held: zero velocity and acceleration), the very torques its
//! torque constraint bounds; they are clipped to the robot's torque limits. It then
//! records one [`MpcSample`]: the solve report, the torques, the largest torque beyond its
//! limit before clipping, the ZMP margin of the acceleration those torques give on the
//! MPC's model of the robot at the measured state, the clearance (enabled self pairs and
//! the scene) and the end-effector error.
//!
//! A caller that applies torques more often than it solves (`moma mission`'s law `mpc`)
//! calls [`MpcLaw::hold_input`] in between: the same inverse dynamics of the same planned
//! input at the measured state, so it holds the planned acceleration, not the torques.
//!
//! Tracking errors: end-effector position error (NaN while no target is set) and the
//! base pose error to the reference. Signals: solve time, iterations and planned ZMP
//! margin of the last solve, and the clearance of the sampled configuration (when the
//! robot has a collision model).

use nalgebra::DVector;

use crate::collision::{
    GeometryData, PairSelection, SceneData, compute_distances, compute_scene_distances,
    update_geometry_placements,
};
use crate::control::mpc::{KnotReference, MapClearance, MpcRobot, WholeBodyMpc};
use crate::error::Result;
use crate::kinematics::{forward_kinematics, update_frame_placement, wrap_angle};
use crate::mobile::wheeled::{WheeledData, reduced_forward_dynamics_crba};
use crate::multibody::Data;
use crate::sim::closed_loop::{FeedbackLaw, Observation, SaturationFlags};
use crate::sim::mpc_run::{MpcRun, MpcSample, summarize};
use crate::stability::{ExternalLoads, StabilityData, evaluate};

/// The MPC law: the MPC, its reference `reference(t)`, the workspaces that evaluate
/// what its torques do, and the per-tick log.
pub struct MpcLaw<R> {
    mpc: WholeBodyMpc,
    reference: R,
    nu: usize,
    wd: WheeledData,
    sd: StabilityData,
    geometry: Option<(GeometryData, SceneData)>,
    q: DVector<f64>,
    v: DVector<f64>,
    samples: Vec<MpcSample>,
}

impl<R: FnMut(f64) -> KnotReference> MpcLaw<R> {
    /// The law of `mpc` tracking `reference` (the knot reference at a time); torques are
    /// clipped to `mpc.problem.robot.torque_limit`.
    #[must_use]
    pub fn new(mpc: WholeBodyMpc, reference: R) -> Self {
        let robot = &mpc.problem.robot;
        let wm = &robot.wheeled;
        let geometry = robot.clearance.as_ref().map(|c| {
            (
                GeometryData::new(&c.geometry),
                SceneData::new(&c.geometry, &c.scene),
            )
        });
        Self {
            nu: wm.nu(),
            wd: WheeledData::new(wm),
            sd: StabilityData::new(&robot.stability),
            geometry,
            q: DVector::zeros(wm.model.nq),
            v: DVector::zeros(wm.nr()),
            samples: Vec::new(),
            mpc,
            reference,
        }
    }

    /// Tracks `reference` from the next tick on (a re-planned path, a target set or
    /// dropped), warm-started from the last solution as every tick is.
    pub fn set_reference(&mut self, reference: R) {
        self.reference = reference;
    }

    /// Keeps the base footprint clear of `map` (the MPC's map-clearance constraint, set
    /// value `constraints.map_clearance`) from the next solve on: the caller's map as it
    /// is now, replaced when its obstacles change.
    pub fn set_map(&mut self, map: MapClearance) {
        self.mpc.problem.map = Some(map);
    }

    /// Between solves: the torques that realise the last solve's first planned input
    /// `[v̇, ω̇, q̈_c]` at the measured `(q, v)`
    /// ([`WholeBodyMpc::first_input_torques_at`]), clipped to the limits as at a solve;
    /// whether they were clipped. A caller that solves less often than it applies
    /// torques holds the planned acceleration this way, the input the MPC's model holds
    /// over a stage, instead of the solve's torques, which drift from it as the state
    /// moves. Records no sample.
    ///
    /// # Errors
    /// What the MPC reports (states of the wrong length).
    pub fn hold_input(&mut self, q: &[f64], v: &[f64], u: &mut [f64]) -> Result<bool> {
        Ok(self.first_input_torques(q, v, u)? > 0.0)
    }

    /// The torques of the first planned input at `(q, v)`, clipped to the limits, into
    /// `u`; the largest excess over a limit before clipping (≤ 0: none clipped).
    fn first_input_torques(&mut self, q: &[f64], v: &[f64], u: &mut [f64]) -> Result<f64> {
        self.mpc.first_input_torques_at(q, v, u, false)?;
        let mut excess = f64::NEG_INFINITY;
        for (ui, &lim) in u.iter_mut().zip(self.mpc.problem.robot.torque_limit.iter()) {
            excess = excess.max(ui.abs() - lim);
            *ui = ui.clamp(-lim, lim);
        }
        Ok(excess)
    }

    /// One sample per control tick so far.
    #[must_use]
    pub fn samples(&self) -> &[MpcSample] {
        &self.samples
    }

    /// The MPC and the run: samples and summary.
    #[must_use]
    pub fn finish(self) -> (WholeBodyMpc, MpcRun) {
        let summary = summarize(&self.mpc.problem.robot, &self.samples);
        (
            self.mpc,
            MpcRun {
                samples: self.samples,
                summary,
            },
        )
    }

    /// The end-effector error to `reference(t)`'s target at `self.q` (`None`: no target).
    fn ee_error(&mut self, t: f64) -> Option<f64> {
        let robot = &self.mpc.problem.robot;
        let model = &robot.wheeled.model;
        (self.reference)(t).end_effector.map(|(p, _)| {
            forward_kinematics(model, &mut self.wd.data, &self.q);
            let m = update_frame_placement(model, &mut self.wd.data, robot.end_effector);
            (m.translation - p).norm()
        })
    }
}

/// The smallest distance over the enabled self pairs and the scene at the placements of
/// `data` (`∞` without a collision model).
fn clearance(
    robot: &MpcRobot,
    data: &Data,
    geometry: &mut Option<(GeometryData, SceneData)>,
) -> f64 {
    match (&robot.clearance, geometry) {
        (Some(c), Some((gd, scd))) => {
            update_geometry_placements(&c.geometry, data, gd);
            let own = compute_distances(&c.geometry, gd, PairSelection::Enabled);
            own.min(compute_scene_distances(&c.geometry, gd, &c.scene, scd))
        }
        _ => f64::INFINITY,
    }
}

impl<R: FnMut(f64) -> KnotReference> FeedbackLaw for MpcLaw<R> {
    fn nu(&self) -> usize {
        self.nu
    }

    fn error_names(&self) -> Vec<String> {
        [
            "ee_position [m]",
            "base_x [m]",
            "base_y [m]",
            "base_heading [rad]",
        ]
        .map(String::from)
        .to_vec()
    }

    fn has_lyapunov(&self) -> bool {
        false
    }

    fn control(&mut self, t: f64, q: &[f64], v: &[f64], u: &mut [f64]) -> Result<SaturationFlags> {
        self.mpc.set_reference(t, &mut self.reference);
        let solve = self.mpc.solve(q, v)?;
        // The torques of the first planned input: the MPC's own inverse dynamics of the
        // reduced model (those its torque constraint bounds), clipped to the limits.
        let excess = self.first_input_torques(q, v, u)?;
        let robot = &self.mpc.problem.robot;
        // What these torques do: the acceleration, hence the ZMP, on the MPC's model.
        self.q.copy_from_slice(q);
        self.v.copy_from_slice(v);
        let wm = &robot.wheeled;
        reduced_forward_dynamics_crba(wm, &mut self.wd, &self.q, &self.v, u)?;
        let zmp_margin = evaluate(
            &wm.model,
            &mut self.wd.data,
            &robot.stability,
            &mut self.sd,
            &self.q,
            &self.wd.qdot,
            &self.wd.reduced.qddot,
            &ExternalLoads::NONE,
        )
        .zmp_margin;
        let clearance = clearance(robot, &self.wd.data, &mut self.geometry);
        let ee_error = self.ee_error(t);
        self.samples.push(MpcSample {
            t,
            q: q.to_vec(),
            v: v.to_vec(),
            torque: u.to_vec(),
            solve,
            zmp_margin,
            clearance,
            torque_excess: excess.max(0.0),
            ee_error,
        });
        Ok(SaturationFlags {
            speed: false,
            torque: excess > 0.0,
        })
    }

    fn observe(&mut self, t: f64, q: &[f64], _v: &[f64], error: &mut [f64]) -> Result<Observation> {
        self.q.copy_from_slice(q);
        let base = (self.reference)(t).base;
        error[0] = self.ee_error(t).unwrap_or(f64::NAN);
        error[1] = q[0] - base[0];
        error[2] = q[1] - base[1];
        error[3] = wrap_angle(q[2] - base[2]);
        Ok(Observation::default())
    }

    fn signal_names(&self) -> Vec<String> {
        let mut names = vec![
            "solve_time [s]".to_string(),
            "iterations [1]".to_string(),
            "planned_zmp_margin [m]".to_string(),
        ];
        if self.geometry.is_some() {
            names.push("clearance [m]".to_string());
        }
        names
    }

    /// Solve time, iterations and planned ZMP margin of the last solve at or before `t`;
    /// the clearance at `q`.
    fn signals(&mut self, _t: f64, q: &[f64], _v: &[f64], out: &mut [f64]) -> Result<()> {
        let last = self.samples.last().map(|s| s.solve).unwrap_or_default();
        out[0] = last.time.as_secs_f64();
        out[1] = last.iterations as f64;
        out[2] = last.min_zmp_margin;
        if self.geometry.is_some() {
            self.q.copy_from_slice(q);
            let robot = &self.mpc.problem.robot;
            forward_kinematics(&robot.wheeled.model, &mut self.wd.data, &self.q);
            out[3] = clearance(robot, &self.wd.data, &mut self.geometry);
        }
        Ok(())
    }

    fn mpc_run(&self) -> Option<MpcRun> {
        Some(MpcRun {
            samples: self.samples.clone(),
            summary: summarize(&self.mpc.problem.robot, &self.samples),
        })
    }
}

//! The loop's workspaces, allocated once before it ([`Workspace`]: the law's reduced
//! dynamics, the monitors, the measured and the plant's state, the inputs), the
//! actuators with their limits ([`Actuators`]) and the plant's start state.

use nalgebra::{DMatrix, DVector, Matrix2, Matrix6xX, Vector2};

use super::plant::start_configuration;
use super::scenario::Mission;
use super::task::{DistanceMonitor, Task};
use crate::collision::SceneObject;
use crate::error::Result;
use crate::mobile::{WheeledData, WheeledModel};
use crate::multibody::Data;
use crate::sim::computed_torque::ComputedTorque;
use crate::sim::stability_monitor::{StabilityMonitor, StabilitySettings};
use crate::stability::BodySet;

/// The plant state at the start: the start pose, the start arm posture, at rest (the
/// last entry integrates the input work).
pub(super) fn initial_state(m: &Mission) -> Vec<f64> {
    let mut x = start_configuration(&m.robot, m.file.start.pose, &m.q_arm0);
    x.resize(m.robot.model.nq + m.robot.nr() + 1, 0.0);
    x
}

/// The workspaces of the loop, allocated once before it.
pub(super) struct Workspace {
    /// The control law's reduced dynamics (Mr, cr + Gr, N_C) at the step's state, under
    /// zero input.
    pub(super) control_dynamics: WheeledData,
    /// Kinematics workspace (end effector, arm side view).
    pub(super) data: Data,
    /// The stability, load and slip monitors of the recorded samples.
    pub(super) monitor: StabilityMonitor,
    /// The plant's first integration stage `[q̇, v̇, Qᵀq̇]` at the step's state under the
    /// step's torques, when the step evaluated it exactly (`first_stage_known`).
    pub(super) first_stage: Vec<f64>,
    pub(super) first_stage_known: bool,
    /// The configuration q the law measured at the step (the plant's, with sensor noise
    /// if any).
    pub(super) q_now: DVector<f64>,
    /// The reduced velocity v = [v, ω, q̇_arm] the law measured at the step.
    pub(super) v_now: DVector<f64>,
    /// The actuator inputs (wheel torques, then arm torques), held over the step.
    pub(super) u: Vec<f64>,
    pub(super) zero_u: Vec<f64>,
    /// The law's desired reduced accelerations.
    pub(super) a_des: DVector<f64>,
    /// The law measures the plant's state through the `[uncertainty]` sensor noise.
    pub(super) noisy: bool,
    /// A `[task]`'s payload was attached in this step: the plant takes it before the
    /// record.
    pub(super) attach_pending: bool,
    /// The plant's configuration (reduced coordinates) at the step.
    pub(super) q_plant: DVector<f64>,
    /// The plant's reduced velocity at the step.
    pub(super) v_plant: DVector<f64>,
    /// The end effector's frame Jacobian (full velocity coordinates).
    pub(super) jac: Matrix6xX<f64>,
    /// Ṅ_C.
    pub(super) ndot: DMatrix<f64>,
    /// Ṅ_C v.
    pub(super) ndot_v: DVector<f64>,
    /// The end effector's reduced position Jacobian J N_C (3 × nr).
    pub(super) ee_jacobian: DMatrix<f64>,
    /// A `[task]`'s distance monitor of the arm motions.
    pub(super) distances: Option<DistanceMonitor>,
    /// A `[task]`'s distance monitor of the drives (to the placement and on from it):
    /// the robot against the task's scene and the map's boxes, not its links.
    pub(super) drive_distances: Option<DistanceMonitor>,
    /// The arm motion's reference: configuration (full), group rates and accelerations.
    pub(super) q_ref: Vec<f64>,
    /// Group joint rates of the reference.
    pub(super) qd_ref: Vec<f64>,
    /// Group joint accelerations of the reference.
    pub(super) qdd_ref: Vec<f64>,
}

impl Workspace {
    pub(super) fn new(
        wm: &WheeledModel,
        plant: &WheeledModel,
        mu: f64,
        noisy: bool,
        task: Option<&Task>,
        boxes: &[SceneObject],
    ) -> Result<Self> {
        let model = &wm.model;
        let (nq, nr, nu) = (model.nq, wm.nr(), wm.nu());
        let dim = task.map_or(0, |t| t.group.dim());
        Ok(Self {
            control_dynamics: WheeledData::new(wm),
            data: Data::new(model),
            monitor: StabilityMonitor::new(plant, monitor_settings(mu))?,
            first_stage: vec![0.0; nq + nr + 1],
            first_stage_known: false,
            q_now: DVector::zeros(nq),
            v_now: DVector::zeros(nr),
            u: vec![0.0; nu],
            zero_u: vec![0.0; nu],
            a_des: DVector::zeros(nr),
            noisy,
            attach_pending: false,
            q_plant: DVector::zeros(nq),
            v_plant: DVector::zeros(nr),
            jac: Matrix6xX::zeros(model.nv),
            ndot: DMatrix::zeros(model.nv, nr),
            ndot_v: DVector::zeros(model.nv),
            ee_jacobian: DMatrix::zeros(3, nr),
            distances: task.map(|t| DistanceMonitor::new(t, wm)),
            drive_distances: task.map(|t| DistanceMonitor::scene_only(t, wm, boxes)),
            q_ref: vec![0.0; nq],
            qd_ref: vec![0.0; dim],
            qdd_ref: vec![0.0; dim],
        })
    }

    /// The monitors take `robot` (the same joints, other inertias: the payload
    /// attached), and the plant (the contact plant too) before the step's record.
    pub(super) fn attach(&mut self, robot: &WheeledModel, mu: f64) -> Result<()> {
        self.attach_pending = true;
        self.monitor = StabilityMonitor::new(robot, monitor_settings(mu))?;
        Ok(())
    }
}

/// The settings of the mission's stability and slip monitor.
pub(super) fn monitor_settings(mu: f64) -> StabilitySettings {
    StabilitySettings {
        mu: Some(mu),
        bodies: BodySet::All,
        ground_z: None,
        stop_at_tip: false,
    }
}

/// The actuators: the computed-torque map with the torque limits, the wheel-speed limit.
pub(super) struct Actuators {
    /// Computed torque on the reduced model, clipped at the joints' effort limits.
    pub(super) torque: ComputedTorque,
    pub(super) wheel_speed: f64,
    /// Number of arm inputs.
    pub(super) na: usize,
    /// Platform speeds (v, ω) to wheel rates.
    pub(super) w_inv: Matrix2<f64>,
}

impl Actuators {
    /// The actuators of `wm` with the limits of its URDF (a missing or non-positive
    /// limit is none).
    pub(super) fn new(wm: &WheeledModel) -> Result<Self> {
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
    pub(super) fn absolute_power(&self, u: &[f64], v_now: &DVector<f64>, v: f64, w: f64) -> f64 {
        let wrates = self.w_inv * Vector2::new(v, w);
        let mut p_abs = (u[0] * wrates[0]).abs() + (u[1] * wrates[1]).abs();
        for k2 in 0..self.na {
            p_abs += (u[2 + k2] * v_now[2 + k2]).abs();
        }
        p_abs
    }
}

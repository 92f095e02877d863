//! The record of the loop: one sample of every column with its monitors (stability,
//! slip, clearance, tracking error, energy, the arm's side view), the events they raise
//! (first slip, contact, saturation) and the smallest ZMP margin; and a pick's distance
//! check, at every control step of its arm motions.

use nalgebra::{DVector, Vector3};

use super::arm_motion::ArmStage;
use super::laws::RunSettings;
use super::plant::{ContactLoop, MissionPlant, Monitors};
use super::run::{LoopState, Phase, Runner};
use super::task::Holding;
use super::workspace::Workspace;
use crate::mobile::WheeledModel;
use crate::mobile::wheeled::lagrange_multipliers;
use crate::multibody::Data;

/// Distance (m) beyond the footprint within which the clearance is exact.
const EXACT_CLEARANCE: f64 = 1.0;

impl Runner<'_> {
    /// Counts the clipped steps; an event at the first of each kind.
    pub(super) fn saturation_events(
        &mut self,
        st: &mut LoopState,
        t: f64,
        torque: bool,
        speed: bool,
    ) {
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
    pub(super) fn record_and_check(
        &mut self,
        c: &RunSettings,
        ws: &mut Workspace,
        st: &mut LoopState,
        plant: &mut MissionPlant<'_>,
        t: f64,
        ee: Vector3<f64>,
        evaluated: bool,
    ) {
        let on_contact = plant.contact().is_some();
        let Some((slip, clear)) = self.record(c, ws, st, plant.contact(), t, ee, evaluated) else {
            return;
        };
        // (on the contact plant the plant's own slip flag makes the event, in `step`)
        if !on_contact && st.first_slip && slip.is_some_and(|s| s > 1.0) {
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

    /// With a `[task]`, at every control step (not only the recorded ones) of its arm
    /// motions and of the drives before and after them (each its own monitor, so the
    /// result has the minima of both): the distances of the plant's
    /// state to the task's scene and between the robot's links (once grasped, carrying
    /// the object, the scene without it; during the lift its support under the lift rule,
    /// [`super::task::LiftStart`]); a distance ≤ 0 or a broken lift rule is a touch and
    /// ends the run (`false`).
    pub(super) fn check_task_distances(
        &mut self,
        ws: &mut Workspace,
        st: &mut LoopState,
        t: f64,
    ) -> bool {
        let monitor = match st.phase {
            Phase::Arm(_) => ws.distances.as_mut(),
            Phase::Drive | Phase::Arrive => ws.drive_distances.as_mut(),
            _ => None,
        };
        let (Some(task), Some(dm)) = (self.m.task.as_ref(), monitor) else {
            return true;
        };
        let holding = match st.phase {
            _ if !st.grasped => Holding::Nothing,
            Phase::Arm(ArmStage::Lift) => Holding::Lifting,
            _ => Holding::Carrying,
        };
        dm.step(task, &self.m.robot, ws.q_plant.as_slice(), holding);
        if let Some(what) = dm.touch(task) {
            self.event(t, "contact", what.clone());
            self.fail(t, format!("collision: {what}"));
            st.phase = Phase::Done;
            return false;
        }
        true
    }

    /// The smallest ZMP margin of the recorded samples as an event.
    pub(super) fn min_zmp_event(&mut self) {
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

    /// Records one sample; returns (slip ratio, clearance) for the event checks, `None`
    /// if the monitors could not be evaluated (the sample is still recorded). `evaluated`:
    /// the step's dynamics under the applied torques are in the workspace.
    pub(super) fn record(
        &mut self,
        c: &RunSettings,
        ws: &mut Workspace,
        st: &LoopState,
        mut contact: Option<&mut ContactLoop>,
        t: f64,
        ee: Vector3<f64>,
        evaluated: bool,
    ) -> Option<(Option<f64>, f64)> {
        let pose = [ws.q_plant[0], ws.q_plant[1], ws.q_plant[2]];
        let mon = match contact.as_deref_mut() {
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
        if let Some(cl) = contact {
            s.contact_normal.push(cl.normal_loads());
            s.contact_friction.push(cl.friction_forces());
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
    if perturbed || ws.noisy {
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

//! The contact plant of a mission with `simulation.plant = "contact"`: built and checked
//! when the file is loaded ([`MissionContact`]), stepped by the held-input loop
//! ([`ContactLoop`]) in place of the reduced (rolling) model's RK4 step; the plant the
//! mission's loop steps is either ([`MissionPlant`]).
//!
//! The law is the mission's own, on its rolling model. What it measures is the contact
//! plant's free-flyer state mapped to the reduced coordinates
//! ([`ReducedMap::to_reduced`], as `moma simulate` does); its torques are held over the
//! control period `simulation.dt` while the contact plant takes `simulation.dt /
//! contact.dt` steps. The monitors report what the contact plant did: the ZMP is the
//! centre of pressure of its normal forces (on flat ground the two coincide), the
//! Force-Angle and Moment-Height measures those of [`crate::stability::evaluate`] on the
//! plant's own model and state (free-flyer configuration, velocity and the last step's
//! acceleration, the support carried with its base on the ground z = 0), the slip ratio
//! each wheel's friction over μ N, lift-off and slip the plant's own flags
//! ([`ContactTally`]).

use nalgebra::Vector2;

use crate::contact::{ContactPlant, ContactSpec, ContactState};
use crate::control::wrap_angle;
use crate::error::{Error, Result};
use crate::mobile::WheeledModel;
use crate::multibody::{Data, Model};
use crate::sim::contact_run::{ContactTally, HeldContactPlant, ReducedMap, contact_plant_of};
use crate::sim::held_loop::HeldPlant;
use crate::sim::rolling_plant::RollingPlant;
use crate::sim::wheeled_system::WheeledSystem;
use crate::stability::{
    BodySet, ExternalLoads, StabilityData, StabilityModel, SupportAttachment, SupportPolygon,
    evaluate,
};

/// The contact plant of a mission, checked before the run: the plant, the map between
/// its free-flyer state and the mission's reduced coordinates, and its start state (on
/// the ground at the start pose and arm posture, at rest; nothing below the ground, a
/// stable step).
#[derive(Clone, Debug)]
pub struct MissionContact {
    /// The plant.
    pub plant: ContactPlant,
    /// Reduced ↔ contact coordinates (holds a copy of the mission's rolling model).
    pub map: ReducedMap,
    /// The checked start state.
    pub start: ContactState,
}

impl MissionContact {
    /// The contact plant of `robot` (its tracked wheel joints, disks of radius
    /// `drive.r_w`, and `spec`'s casters) on `model`, the same description on a
    /// free-flyer root, started at the reduced configuration `q0` at rest; `control_dt`
    /// (the mission's control period) must hold a whole number of contact steps.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the field: `contact.mu` (≤ 0 and the other
    /// parameters, [`crate::contact::ContactParams::validate`]), `contact.stiffness` (a
    /// step the spring-damper is unstable at), `contact.slip_velocity`, `contact.dt`,
    /// `contact.casters[k].frame`, `robot.wheel_joints`.
    pub fn new(
        robot: &WheeledModel,
        model: Model,
        spec: &ContactSpec,
        q0: &[f64],
        control_dt: f64,
    ) -> Result<Self> {
        let params = spec.params();
        params.validate()?;
        let ratio = control_dt / params.dt;
        if ratio.round() < 1.0 || (ratio - ratio.round()).abs() > 1e-6 * ratio {
            return Err(Error::invalid(
                "contact.dt",
                format!(
                    "{} s must divide the control period simulation.dt = {control_dt} s into \
                     a whole number of contact steps",
                    params.dt
                ),
            ));
        }
        let (plant, mut map) = contact_plant_of(robot.clone(), model, spec, params)?;
        let (qc, vc) = map.to_contact(q0, &vec![0.0; robot.nr()]);
        let start = ContactState::new(&plant, &qc, &vc)?;
        Ok(Self { plant, map, start })
    }

    /// Contact steps per control period `control_dt` (checked whole by
    /// [`MissionContact::new`]).
    #[must_use]
    pub fn steps_per_control(&self, control_dt: f64) -> usize {
        (control_dt / self.plant.params.dt).round() as usize
    }
}

/// The reduced configuration at the start: the base at `pose`, the arm joints at `q_arm`
/// (one per arm dof), the wheels at 0.
#[must_use]
pub(super) fn start_configuration(robot: &WheeledModel, pose: [f64; 3], q_arm: &[f64]) -> Vec<f64> {
    let mut q = vec![0.0; robot.model.nq];
    q[..3].copy_from_slice(&pose);
    for (&i, &x) in robot.arm_dofs().iter().zip(q_arm) {
        q[i] = x;
    }
    q
}

/// A contact lift-off or slip, first of its kind, for the mission's events.
pub(super) struct ContactNews {
    /// `lift_off` or `slip`.
    pub kind: &'static str,
    /// When (s).
    pub t: f64,
    /// What happened.
    pub text: String,
}

/// A mission run's contact plant: the contact plant under the held torques
/// ([`HeldContactPlant`], with what it did), the measured heading, the support and
/// stability monitors, and the control ticks taken (its time is the mission's, `k ×
/// simulation.dt`).
pub(super) struct ContactLoop {
    held: HeldContactPlant,
    control_dt: f64,
    ticks: usize,
    /// The measured heading, continued across ±π as the rolling model's is.
    heading: f64,
    /// The support polygon in base axes and placed at the measured pose.
    support: SupportPolygon,
    placed: SupportPolygon,
    news_lift: bool,
    news_slip: bool,
    /// The stability measures on the plant's model: the support in base axes on z = 0,
    /// their workspace and the kinematics workspace.
    stability: StabilityModel,
    stability_data: StabilityData,
    data: Data,
}

/// The stability and slip monitors of one sample (of either plant).
#[derive(Clone, Copy, Default)]
pub(super) struct Monitors {
    /// ZMP margin (m); on the contact plant the centre of pressure against the support.
    pub zmp: Option<f64>,
    /// The support edge of that margin (the stability monitor's base-frame numbering).
    pub zmp_edge: Option<usize>,
    /// Force-Angle minimum (rad).
    pub force_angle: Option<f64>,
    /// Moment-Height minimum.
    pub mhs: Option<f64>,
    /// Larger drive-wheel slip ratio.
    pub slip: Option<f64>,
}

impl ContactLoop {
    /// The run of `setup` under the control period `control_dt`, on the support of
    /// `robot`, its heading measured on from the start pose's `heading` (any angle, as
    /// the rolling model's θ); the Moment-Height measure over `bodies`.
    pub fn new(
        setup: &MissionContact,
        robot: &WheeledModel,
        control_dt: f64,
        heading: f64,
        bodies: &BodySet,
    ) -> Result<Self> {
        let support = SupportPolygon::from_wheeled_model(robot)?;
        let on_ground = SupportPolygon::from_points_at_height(support.vertices_xy(), 0.0)?;
        let model = &setup.plant.model;
        let stability = StabilityModel::new(model, on_ground, SupportAttachment::Base, bodies)?;
        let held = HeldContactPlant::new(
            setup.plant.clone(),
            setup.map.clone(),
            setup.start.clone(),
            setup.steps_per_control(control_dt),
        );
        Ok(Self {
            stability_data: StabilityData::new(&stability),
            stability,
            data: Data::new(model),
            held,
            control_dt,
            ticks: 0,
            heading,
            placed: support.clone(),
            support,
            news_lift: false,
            news_slip: false,
        })
    }

    /// What the contacts did so far.
    pub fn tally(&self) -> &ContactTally {
        &self.held.tally
    }

    /// Net work of the actuators (J).
    pub fn input_work(&self) -> f64 {
        self.held.input_work
    }

    /// The normal force of each contact (N; the wheels, then the casters, in the order of
    /// [`ContactPlant::contact_name`]) at the present state.
    pub fn normal_loads(&self) -> Vec<f64> {
        self.held.state.contacts.iter().map(|r| r.normal).collect()
    }

    /// The friction force `[x, y]` of each contact on the robot (world, N; the order of
    /// [`ContactLoop::normal_loads`]) applied over the last step.
    pub fn friction_forces(&self) -> Vec<[f64; 2]> {
        let reports = &self.held.state.contacts;
        reports
            .iter()
            .map(|r| [r.friction.x, r.friction.y])
            .collect()
    }

    /// The plant takes the bodies' inertias of `robot` (the mission's robot with other
    /// inertias, the joints the same: a `[task]`'s payload attached at the grasp). The
    /// root body (the planar joint's there, the free flyer's here) is the same link.
    pub fn attach(&mut self, robot: &WheeledModel) {
        let model = &mut self.held.plant.model;
        model.inertias.clone_from(&robot.model.inertias);
    }

    /// The first lift-off and the first slip, each once, when they have happened.
    pub fn news(&mut self) -> Vec<ContactNews> {
        let mut out = Vec::new();
        if !self.news_lift
            && let Some(e) = &self.held.tally.first_lift_off
        {
            self.news_lift = true;
            out.push(ContactNews {
                kind: "lift_off",
                t: e.t,
                text: format!("'{}' loses its contact with the ground", e.contact),
            });
        }
        if !self.news_slip
            && let Some(e) = &self.held.tally.first_slip
        {
            self.news_slip = true;
            out.push(ContactNews {
                kind: "slip",
                t: e.t,
                text: format!("'{}' slides: its friction reaches μ N", e.contact),
            });
        }
        out
    }

    /// The monitors of the present state: the ZMP margin (the centre of pressure of the
    /// normal forces against the support polygon placed at the measured pose `(x, y,
    /// θ)`; `None` when nothing touches the ground) and its edge (the nearest, the lowest
    /// index among equal distances), the Force-Angle and Moment-Height
    /// minima of [`evaluate`] on the plant's state with the last step's accelerations
    /// (`None` before the first step), and the larger drive-wheel slip ratio |F_t| / (μ
    /// N) (`None` when a wheel carries no load). Does not allocate.
    pub fn monitors(&mut self, pose: [f64; 3]) -> Monitors {
        let (force_angle, mhs) = if self.held.state.t > 0.0 {
            let st = &self.held.state;
            let r = evaluate(
                &self.held.plant.model,
                &mut self.data,
                &self.stability,
                &mut self.stability_data,
                &st.q,
                &st.v,
                st.acceleration(),
                &ExternalLoads::NONE,
            );
            (r.force_angle_min, r.mhs_min)
        } else {
            (None, None)
        };
        let reports = &self.held.state.contacts;
        let total: f64 = reports.iter().map(|r| r.normal).sum();
        let nearest = (total > 0.0).then(|| {
            let cop = reports
                .iter()
                .fold(Vector2::zeros(), |a, r| a + r.point.xy() * r.normal)
                / total;
            self.support
                .place_into(pose[0], pose[1], pose[2], &mut self.placed);
            (0..self.placed.len())
                .map(|i| {
                    let e = self.placed.edge(i);
                    (i, e.inward.xy().dot(&(cop - e.from.xy())))
                })
                .fold((0, f64::INFINITY), |a, b| if b.1 < a.1 { b } else { a })
        });
        let mu = self.held.plant.params.mu;
        let wheels = self.held.plant.wheel_dofs().len();
        let slip = reports[..wheels]
            .iter()
            .map(|r| (r.normal > 0.0).then(|| r.friction.norm() / (mu * r.normal)))
            .try_fold(0.0f64, |a, s| s.map(|s| a.max(s)));
        Monitors {
            zmp: nearest.map(|(_, m)| m),
            zmp_edge: nearest.map(|(i, _)| i),
            force_angle,
            mhs,
            slip,
        }
    }
}

impl HeldPlant for ContactLoop {
    fn nq(&self) -> usize {
        self.held.nq()
    }

    fn nv(&self) -> usize {
        self.held.nv()
    }

    fn nu(&self) -> usize {
        self.held.nu()
    }

    /// The mission's time of the present tick, `k × simulation.dt`.
    fn time(&self) -> f64 {
        self.ticks as f64 * self.control_dt
    }

    /// The reduced state the law measures, the heading continued across ±π. Does not
    /// allocate.
    fn state(&mut self, q: &mut [f64], v: &mut [f64]) {
        self.held.state(q, v);
        self.heading += wrap_angle(q[2] - self.heading);
        q[2] = self.heading;
    }

    /// The torques `u` held over one control period.
    fn advance(&mut self, u: &[f64], first_stage: Option<&[f64]>) -> Result<()> {
        self.held.advance(u, first_stage)?;
        self.ticks += 1;
        Ok(())
    }
}

/// The plant a mission's loop steps: the rolling model (RK4 at the control period) or the
/// contact plant.
// one plant per run, built once: its size does not matter
#[allow(clippy::large_enum_variant)]
pub(super) enum MissionPlant<'s> {
    /// The reduced (rolling) model.
    Rolling(RollingPlant<'s, WheeledSystem>),
    /// The contact plant.
    Contact(ContactLoop),
}

impl MissionPlant<'_> {
    /// The contact plant, when the mission runs on it.
    pub(super) fn contact(&mut self) -> Option<&mut ContactLoop> {
        match self {
            MissionPlant::Rolling(_) => None,
            MissionPlant::Contact(cl) => Some(cl),
        }
    }

    /// The plant takes the bodies' inertias of `robot` (a `[task]`'s payload attached).
    pub(super) fn attach(&mut self, robot: &WheeledModel) {
        match self {
            MissionPlant::Rolling(p) => *p.system = WheeledSystem::new(robot.clone()),
            MissionPlant::Contact(cl) => cl.attach(robot),
        }
    }

    /// Net work of the actuators (J): the integrated `W` of the rolling state, the contact
    /// plant's per-step sum.
    pub(super) fn input_work(&self) -> f64 {
        match self {
            MissionPlant::Rolling(p) => p.x[p.x.len() - 1],
            MissionPlant::Contact(cl) => cl.input_work(),
        }
    }
}

impl HeldPlant for MissionPlant<'_> {
    fn nq(&self) -> usize {
        match self {
            MissionPlant::Rolling(p) => p.nq(),
            MissionPlant::Contact(cl) => cl.nq(),
        }
    }

    fn nv(&self) -> usize {
        match self {
            MissionPlant::Rolling(p) => p.nv(),
            MissionPlant::Contact(cl) => cl.nv(),
        }
    }

    fn nu(&self) -> usize {
        match self {
            MissionPlant::Rolling(p) => p.nu(),
            MissionPlant::Contact(cl) => cl.nu(),
        }
    }

    fn time(&self) -> f64 {
        match self {
            MissionPlant::Rolling(p) => p.time(),
            MissionPlant::Contact(cl) => cl.time(),
        }
    }

    fn state(&mut self, q: &mut [f64], v: &mut [f64]) {
        match self {
            MissionPlant::Rolling(p) => p.state(q, v),
            MissionPlant::Contact(cl) => cl.state(q, v),
        }
    }

    fn advance(&mut self, u: &[f64], first_stage: Option<&[f64]>) -> Result<()> {
        match self {
            MissionPlant::Rolling(p) => p.advance(u, first_stage),
            MissionPlant::Contact(cl) => cl.advance(u, first_stage),
        }
    }
}

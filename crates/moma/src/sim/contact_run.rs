//! A wheeled robot run on the contact plant ([`crate::contact`]) instead of the reduced
//! (rolling) model: the same input profile or the same feedback law, the contact plant
//! stepped at its own `dt`, and what it did recorded at the recording interval.
//!
//! The law keeps its nominal (rolling) model. What it measures is the contact plant's
//! free-flyer state mapped to the reduced coordinates ([`ReducedMap`]): `x, y` of the base
//! origin, `θ` its heading (the yaw of the base x axis in the ground plane), the joints as
//! they are; `v` the base origin's world velocity along the heading, `ω` the world yaw
//! rate, the arm's joint rates. Its inputs `[τ_L, τ_R, τ_arm…]` go to the same joints of
//! the contact plant. Under a control period the law's output is held over the period
//! (zero-order hold); without one it is evaluated at every contact step. The run is the
//! held-input loop ([`run_held_loop`]) on [`HeldContactPlant`] (the contact plant under
//! held inputs, which the mission's contact plant steps too), one contact step per tick;
//! with sensor noise the loop measures through it at every tick the law is evaluated
//! (the recorded rows and tracking errors keep the plant's own state).

use nalgebra::{DMatrix, DVector, Vector3};

use crate::contact::{ContactParams, ContactPlant, ContactSpec, ContactState, WheelSpec};
use crate::error::{Error, Result};
use crate::mobile::WheeledModel;
use crate::mobile::wheeled::admissible_velocity_basis;
use crate::multibody::Model;
use crate::sim::closed_loop::FeedbackLaw;
use crate::sim::held_loop::{HeldPlant, Tick, TickEnd, TickLaw, run_held_loop};
use crate::sim::sensor_noise::SensorNoise;
use crate::sim::settings::InputProfile;

/// Largest number of contact steps a run accepts (`duration / contact.dt`).
pub const MAX_CONTACT_STEPS: f64 = 100_000_000.0;

/// Between the reduced coordinates of a [`WheeledModel`] (planar root, tracked wheels)
/// and the free-flyer coordinates of a [`ContactPlant`] of the same robot.
#[derive(Clone, Debug)]
pub struct ReducedMap {
    /// The nominal (rolling) model.
    pub robot: WheeledModel,
    /// Base height above the ground at which the wheels touch it (m): `−ground_z`.
    pub base_height: f64,
    basis: DMatrix<f64>,
    q: DVector<f64>,
    /// Contact-plant input index of each reduced input.
    input_index: Vec<usize>,
}

impl ReducedMap {
    /// The map for `robot` (tracked wheel joints required) and `plant` (built from the
    /// same robot description on a free-flyer root).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] if the robot tracks no wheel joints or the two models'
    /// joints differ.
    pub fn new(robot: WheeledModel, plant: &ContactPlant) -> Result<Self> {
        let Some(wheels) = robot.wheel_dofs() else {
            return Err(Error::invalid(
                "robot.wheel_joints",
                "the contact plant drives the wheel joints: name them",
            ));
        };
        let (m, c) = (&robot.model, &plant.model);
        if m.nv != c.nv - 3 || m.nq != m.nv {
            return Err(Error::invalid(
                "robot.urdf",
                "the rolling and contact models of the robot have different joints",
            ));
        }
        for i in 3..m.nv {
            let (a, b) = (
                &m.names[m.joint_of_dof[i].0],
                &c.names[c.joint_of_dof[i + 3].0],
            );
            if a != b {
                return Err(Error::invalid(
                    "robot.urdf",
                    format!("joint order differs between the two models: '{a}' vs '{b}'"),
                ));
            }
        }
        let mut input_index = vec![wheels[0] - 3, wheels[1] - 3];
        input_index.extend(robot.arm_dofs().iter().map(|&i| i - 3));
        Ok(Self {
            base_height: -robot.ground_z(),
            basis: DMatrix::zeros(robot.nv(), robot.nr()),
            q: DVector::zeros(robot.model.nq),
            robot,
            input_index,
        })
    }

    /// The contact plant's start `(q, v)` for the reduced `(q_r, v_r)`: the base on the
    /// ground (at [`ReducedMap::base_height`]), level, at `(x, y, θ)`; its twist and the
    /// joint rates from `q̇ = N_C(q_r) v_r`.
    #[must_use]
    pub fn to_contact(&mut self, q_r: &[f64], v_r: &[f64]) -> (Vec<f64>, Vec<f64>) {
        self.q.copy_from_slice(q_r);
        admissible_velocity_basis(&self.robot, &self.q, &mut self.basis);
        let qdot = &self.basis * DVector::from_column_slice(v_r);
        let (s, c) = q_r[2].sin_cos();
        let (h, half) = (self.base_height, q_r[2] / 2.0);
        let mut q = vec![q_r[0], q_r[1], h, 0.0, 0.0, half.sin(), half.cos()];
        q.extend_from_slice(&q_r[3..]);
        // Base twist in the base frame: the world velocity turned by −θ.
        let mut v = vec![
            c * qdot[0] + s * qdot[1],
            -s * qdot[0] + c * qdot[1],
            0.0,
            0.0,
            0.0,
            qdot[2],
        ];
        v.extend(qdot.iter().skip(3));
        (q, v)
    }

    /// The reduced `(q_r, v_r)` the law measures on the contact plant's `state`
    /// (module docs). Does not allocate.
    pub fn to_reduced(&self, state: &ContactState, q_r: &mut [f64], v_r: &mut [f64]) {
        let rot = state.base_orientation();
        let yaw = state.yaw();
        q_r[0] = state.q[0];
        q_r[1] = state.q[1];
        q_r[2] = yaw;
        q_r[3..].copy_from_slice(state.joint_positions());
        let lin = rot * Vector3::new(state.v[0], state.v[1], state.v[2]);
        let ang = rot * Vector3::new(state.v[3], state.v[4], state.v[5]);
        let (s, c) = yaw.sin_cos();
        v_r[0] = c * lin.x + s * lin.y;
        v_r[1] = ang.z;
        for (k, &i) in self.robot.arm_dofs().iter().enumerate() {
            v_r[2 + k] = state.v[i + 3];
        }
    }

    /// Writes the contact plant's inputs `u_c` (one per joint) from the reduced inputs
    /// `u_r = [τ_L, τ_R, τ_arm…]`.
    pub fn to_contact_inputs(&self, u_r: &[f64], u_c: &mut [f64]) {
        u_c.fill(0.0);
        for (&i, &u) in self.input_index.iter().zip(u_r) {
            u_c[i] = u;
        }
    }
}

/// The contact plant of `robot` and the map to its reduced coordinates: `model` is the
/// same robot description on a free-flyer root, the drive wheels are the robot's
/// tracked `wheel_joints` as disks of radius `drive.r_w`, the casters those of the
/// `[contact]` table `spec` ([`ContactSpec::plant`]), the law `params`.
///
/// # Errors
/// [`Error::InvalidInput`] naming the field at fault (`robot.wheel_joints`,
/// `contact.mu`, `contact.casters[k].frame`, …); [`Error::Model`] for a wrong root.
pub fn contact_plant_of(
    robot: WheeledModel,
    model: Model,
    spec: &ContactSpec,
    params: ContactParams,
) -> Result<(ContactPlant, ReducedMap)> {
    let Some(joints) = robot.base.wheel_joints.clone() else {
        return Err(Error::invalid(
            "robot.wheel_joints",
            "the contact plant drives the wheel joints: name them",
        ));
    };
    let radius = robot.base.drive.wheel_radius;
    let wheels = joints.map(|joint| WheelSpec { joint, radius });
    let plant = spec.plant(model, &wheels, params)?;
    let map = ReducedMap::new(robot, &plant)?;
    Ok((plant, map))
}

/// The contact plant under held inputs.
#[derive(Clone, Debug)]
pub struct HeldContactPlant {
    /// The plant.
    pub plant: ContactPlant,
    /// Reduced ↔ contact coordinates (holds the law's rolling model).
    pub map: ReducedMap,
    /// The plant's state.
    pub state: ContactState,
    /// The plant's inputs (one per joint below the free flyer).
    u_c: Vec<f64>,
    /// Contact steps per control period.
    steps: usize,
    /// First lift-off and slip, totals, tilt.
    pub tally: ContactTally,
    /// Net work of the actuators ∫ uᵀ q̇ dt (J), per contact step (the rates at its start).
    pub input_work: f64,
}

impl HeldContactPlant {
    /// `plant` started at `start`, `steps` contact steps per control period.
    #[must_use]
    pub fn new(plant: ContactPlant, map: ReducedMap, start: ContactState, steps: usize) -> Self {
        Self {
            tally: ContactTally::new(&plant),
            u_c: vec![0.0; plant.nu()],
            plant,
            map,
            state: start,
            steps,
            input_work: 0.0,
        }
    }
}

impl HeldPlant for HeldContactPlant {
    fn nq(&self) -> usize {
        self.map.robot.model.nq
    }

    fn nv(&self) -> usize {
        self.map.robot.nr()
    }

    fn nu(&self) -> usize {
        self.map.robot.nu()
    }

    /// The plant's own time (the sum of its steps).
    fn time(&self) -> f64 {
        self.state.t
    }

    fn state(&mut self, q: &mut [f64], v: &mut [f64]) {
        self.map.to_reduced(&self.state, q, v);
    }

    /// # Errors
    /// [`crate::Error::Numerical`] if the plant's accelerations stop being finite.
    fn advance(&mut self, u: &[f64], _first_stage: Option<&[f64]>) -> Result<()> {
        self.map.to_contact_inputs(u, &mut self.u_c);
        let dt = self.plant.params.dt;
        for _ in 0..self.steps {
            let power: f64 = self
                .u_c
                .iter()
                .zip(self.state.v.iter().skip(6))
                .map(|(u, v)| u * v)
                .sum();
            self.plant.step(&mut self.state, &self.u_c)?;
            self.input_work += power * dt;
            self.tally.observe(&self.state, dt);
        }
        Ok(())
    }
}

/// What drives the contact plant.
pub enum ContactDriver {
    /// Open loop: the reduced inputs `u(t)`, evaluated at every contact step.
    Profile(InputProfile),
    /// Closed loop: a feedback law on the measured reduced state.
    Law {
        /// The law (on its nominal, rolling model).
        law: Box<dyn FeedbackLaw>,
        /// Control period (s) of the zero-order hold; `None`: every contact step.
        period: Option<f64>,
    },
}

/// A run of the contact plant.
pub struct ContactRun {
    /// The plant.
    pub plant: ContactPlant,
    /// Reduced ↔ contact coordinates (holds the nominal model).
    pub map: ReducedMap,
    /// Initial reduced configuration and velocity.
    pub q0: Vec<f64>,
    /// Initial reduced velocity.
    pub v0: Vec<f64>,
    /// The inputs.
    pub driver: ContactDriver,
    /// Duration (s).
    pub duration: f64,
    /// Recording interval (s), rounded to a whole number of contact steps.
    pub record_interval: f64,
    /// The start state (checked: nothing below the ground, a stable step).
    pub start: ContactState,
    /// The noise on the state a law measures (`None`: the plant's own; an input
    /// profile measures nothing).
    pub noise: Option<SensorNoise>,
}

/// The first time something happened to a contact.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ContactEvent {
    /// Time (s).
    pub t: f64,
    /// The contact (wheel joint or caster frame).
    pub contact: String,
}

/// Per contact over a run.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct ContactTotals {
    /// The contact (wheel joint or caster frame).
    pub contact: String,
    /// Smallest and largest normal force (N) after the settling time.
    pub min_normal: f64,
    /// Largest normal force (N).
    pub max_normal: f64,
    /// Time (s) without normal force after the settling time.
    pub lifted_time: f64,
    /// Time (s) sliding (friction at μ N) after the settling time.
    pub slipping_time: f64,
    /// Largest slip speed (m/s) while loaded.
    pub max_slip_speed: f64,
}

/// Events are counted after this settling time (s), in which the robot, started with
/// no penetration, sinks onto its compliant contacts.
pub const SETTLE_TIME: f64 = 0.05;

/// What the contacts did over a run, gathered step by step from the plant's reports
/// ([`ContactTally::observe`]): the first lift-off and the first slip after
/// [`SETTLE_TIME`], the per-contact totals and the largest tilt of the base.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct ContactTally {
    /// First contact to lose its load after [`SETTLE_TIME`].
    pub first_lift_off: Option<ContactEvent>,
    /// First wheel to slide (friction at μ N) after [`SETTLE_TIME`].
    pub first_slip: Option<ContactEvent>,
    /// Per-contact totals (a contact never loaded after the settling time has
    /// `min_normal` 0 once [`ContactTally::finish`]ed).
    pub totals: Vec<ContactTotals>,
    /// Largest tilt of the base (rad): the angle between its z axis and the vertical.
    pub max_tilt: f64,
}

impl ContactTally {
    /// Nothing seen yet, one total per contact of `plant`.
    #[must_use]
    pub fn new(plant: &ContactPlant) -> Self {
        Self {
            first_lift_off: None,
            first_slip: None,
            totals: (0..plant.ncontacts())
                .map(|k| ContactTotals {
                    contact: plant.contact_name(k).to_string(),
                    min_normal: f64::INFINITY,
                    ..ContactTotals::default()
                })
                .collect(),
            max_tilt: 0.0,
        }
    }

    /// Adds the reports of the step of length `dt` that ended in `st` (at `st.t`).
    /// Does not allocate, except to name the first lift-off and the first slip.
    pub fn observe(&mut self, st: &ContactState, dt: f64) {
        let t = st.t;
        let tilt = (st.base_orientation() * Vector3::z())
            .z
            .clamp(-1.0, 1.0)
            .acos();
        self.max_tilt = self.max_tilt.max(tilt);
        if t <= SETTLE_TIME {
            return;
        }
        for (c, r) in st.contacts.iter().enumerate() {
            let tot = &mut self.totals[c];
            tot.min_normal = tot.min_normal.min(r.normal);
            tot.max_normal = tot.max_normal.max(r.normal);
            if r.lifted {
                tot.lifted_time += dt;
                self.first_lift_off.get_or_insert_with(|| ContactEvent {
                    t,
                    contact: tot.contact.clone(),
                });
            } else {
                tot.max_slip_speed = tot.max_slip_speed.max(r.slip.norm());
            }
            if r.slipping {
                tot.slipping_time += dt;
                self.first_slip.get_or_insert_with(|| ContactEvent {
                    t,
                    contact: tot.contact.clone(),
                });
            }
        }
    }

    /// The tally of a finished run: a contact never loaded after the settling time
    /// reports `min_normal` 0.
    #[must_use]
    pub fn finish(mut self) -> Self {
        for tot in &mut self.totals {
            if !tot.min_normal.is_finite() {
                tot.min_normal = 0.0;
            }
        }
        self
    }
}

/// A recorded contact run.
#[derive(Clone, Debug)]
pub struct ContactResult {
    /// Sample times (s).
    pub times: Vec<f64>,
    /// Names of the reduced coordinates, velocities, inputs and contacts.
    pub q_names: Vec<String>,
    /// Names of the reduced velocities.
    pub v_names: Vec<String>,
    /// Names of the reduced inputs.
    pub u_names: Vec<String>,
    /// Names of the contacts (wheels, then casters).
    pub contact_names: Vec<String>,
    /// Names of the law's tracking-error components (closed loop).
    pub error_names: Vec<String>,
    /// Rows of `[q_r, v_r, u_r, z, roll, pitch, wheel speeds (2), per contact: normal,
    /// slip speed, lifted (0/1), slipping (0/1), tracking errors]`.
    pub rows: Vec<Vec<f64>>,
    /// First contact to lose its load after [`SETTLE_TIME`].
    pub first_lift_off: Option<ContactEvent>,
    /// First wheel to slide (friction at μ N) after [`SETTLE_TIME`].
    pub first_slip: Option<ContactEvent>,
    /// Per-contact totals.
    pub totals: Vec<ContactTotals>,
    /// Largest tilt of the base (rad): the angle between its z axis and the vertical.
    pub max_tilt: f64,
    /// Contact steps taken.
    pub steps: usize,
    /// Evaluations of the law (closed loop) or of the input profile.
    pub control_evaluations: usize,
    /// Steps per control evaluation (closed loop with a period), else 1.
    pub steps_per_control: usize,
}

impl ContactResult {
    /// Column names of [`ContactResult::rows`], with units in brackets.
    #[must_use]
    pub fn column_names(&self) -> Vec<String> {
        let mut c: Vec<String> = Vec::new();
        c.extend(self.q_names.iter().map(|n| n.to_string()));
        c.extend(self.v_names.iter().map(|n| n.to_string()));
        c.extend(self.u_names.iter().map(|n| n.to_string()));
        c.extend(
            ["z [m]", "roll [rad]", "pitch [rad]"]
                .iter()
                .map(|s| (*s).to_string()),
        );
        c.push("wheel_speed_left [rad/s]".into());
        c.push("wheel_speed_right [rad/s]".into());
        for n in &self.contact_names {
            c.push(format!("normal_{n} [N]"));
            c.push(format!("slip_speed_{n} [m/s]"));
            c.push(format!("lifted_{n}"));
            c.push(format!("slipping_{n}"));
        }
        c.extend(self.error_names.iter().cloned());
        c
    }
}

impl ContactRun {
    /// Runs to the end; `progress(t)` is called at every recorded sample.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a run longer than [`MAX_CONTACT_STEPS`]; the law's
    /// error; [`Error::Numerical`] if the plant's accelerations stop being finite.
    pub fn run(&mut self, progress: &mut dyn FnMut(f64)) -> Result<ContactResult> {
        let dt = self.plant.params.dt;
        let nsteps = (self.duration / dt).round();
        if nsteps > MAX_CONTACT_STEPS {
            return Err(Error::invalid(
                "contact.dt",
                format!(
                    "duration / contact.dt = {nsteps:e} steps, more than {MAX_CONTACT_STEPS:e}"
                ),
            ));
        }
        let nsteps = nsteps as usize;
        let every = ((self.record_interval / dt).round() as usize).max(1);
        let hold = match &self.driver {
            ContactDriver::Law {
                period: Some(p), ..
            } => ((p / dt).round() as usize).max(1),
            _ => 1,
        };
        let robot = &self.map.robot;
        let error_names = match &self.driver {
            ContactDriver::Law { law, .. } => law.error_names(),
            ContactDriver::Profile(_) => Vec::new(),
        };
        let nc = self.plant.ncontacts();
        let mut res = ContactResult {
            times: Vec::new(),
            q_names: with_units(robot.q_names(), robot, true),
            v_names: with_units(robot.v_names(), robot, false),
            u_names: robot
                .u_names()
                .into_iter()
                .enumerate()
                .map(|(k, n)| {
                    let lin = k >= 2 && is_prismatic(robot, robot.arm_dofs()[k - 2]);
                    format!("{n} [{}]", if lin { "N" } else { "N m" })
                })
                .collect(),
            contact_names: (0..nc)
                .map(|k| self.plant.contact_name(k).to_string())
                .collect(),
            error_names,
            rows: Vec::new(),
            first_lift_off: None,
            first_slip: None,
            totals: Vec::new(),
            max_tilt: 0.0,
            steps: 0,
            control_evaluations: 0,
            steps_per_control: hold,
        };
        let n_errors = res.error_names.len();
        let mut held =
            HeldContactPlant::new(self.plant.clone(), self.map.clone(), self.start.clone(), 1);
        let mut tick = ContactTick {
            driver: &mut self.driver,
            res: &mut res,
            err: vec![0.0; n_errors],
            nsteps,
            hold,
            every,
            progress,
        };
        res.steps = run_held_loop(&mut held, &mut tick, self.noise.as_mut())?;
        let tally = held.tally.finish();
        res.first_lift_off = tally.first_lift_off;
        res.first_slip = tally.first_slip;
        res.totals = tally.totals;
        res.max_tilt = tally.max_tilt;
        Ok(res)
    }
}

/// The tick of a contact run, one per contact step: the driver evaluated every `hold`
/// steps on the measured state (its inputs held in between), a row of the plant's own
/// state recorded every `every` steps, the run stopped after `nsteps` steps.
struct ContactTick<'a> {
    driver: &'a mut ContactDriver,
    res: &'a mut ContactResult,
    err: Vec<f64>,
    nsteps: usize,
    hold: usize,
    every: usize,
    progress: &'a mut dyn FnMut(f64),
}

impl TickLaw<HeldContactPlant> for ContactTick<'_> {
    fn tick(&mut self, held: &mut HeldContactPlant, now: &mut Tick<'_>) -> Result<TickEnd> {
        let (k, t) = (now.k, now.t);
        if k.is_multiple_of(self.hold) {
            match &mut *self.driver {
                ContactDriver::Profile(p) => p.eval(t, now.u),
                ContactDriver::Law { law, .. } => {
                    law.control(t, now.q, now.v, now.u)?;
                }
            }
            self.res.control_evaluations += 1;
        }
        if k.is_multiple_of(self.every) {
            let (st, plant) = (&held.state, &held.plant);
            let nc = st.contacts.len();
            let mut row = Vec::with_capacity(
                now.q.len() + now.v.len() + now.u.len() + 5 + 4 * nc + self.err.len(),
            );
            row.extend_from_slice(now.q_plant);
            row.extend_from_slice(now.v_plant);
            row.extend_from_slice(now.u);
            let (roll, pitch, _) = st.base_orientation().euler_angles();
            row.extend([st.q[2], roll, pitch]);
            let nwheels = plant.wheel_dofs().len();
            row.extend(plant.wheel_speeds(st).take(nwheels.min(2)));
            for r in &st.contacts {
                row.extend([
                    r.normal,
                    r.slip.norm(),
                    f64::from(u8::from(r.lifted)),
                    f64::from(u8::from(r.slipping)),
                ]);
            }
            if let ContactDriver::Law { law, .. } = &mut *self.driver {
                law.observe(t, now.q_plant, now.v_plant, &mut self.err)?;
                row.extend_from_slice(&self.err);
            }
            self.res.times.push(t);
            self.res.rows.push(row);
            (self.progress)(t);
        }
        Ok(if k < self.nsteps {
            TickEnd::Hold
        } else {
            TickEnd::Stop
        })
    }

    /// The law reads the measurement at the steps it is evaluated at.
    fn measures(&self, k: usize) -> bool {
        k.is_multiple_of(self.hold)
    }
}

fn is_prismatic(robot: &WheeledModel, dof: usize) -> bool {
    let m = &robot.model;
    m.joint_types[m.joint_of_dof[dof].0].is_prismatic()
}

/// `name [unit]` for the reduced coordinates (`q`) or velocities.
fn with_units(names: Vec<String>, robot: &WheeledModel, q: bool) -> Vec<String> {
    names
        .into_iter()
        .enumerate()
        .map(|(k, n)| {
            let unit = if q {
                match k {
                    0 | 1 => "m",
                    2 => "rad",
                    _ if is_prismatic(robot, k) => "m",
                    _ => "rad",
                }
            } else {
                match k {
                    0 => "m/s",
                    1 => "rad/s",
                    _ if is_prismatic(robot, robot.arm_dofs()[k - 2]) => "m/s",
                    _ => "rad/s",
                }
            };
            format!("{n} [{unit}]")
        })
        .collect()
}

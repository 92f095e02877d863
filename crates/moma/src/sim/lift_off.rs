//! The smallest steady acceleration at which the contact plant ([`crate::contact`]) lifts
//! a contact, found by simulation, beside the tip-over limit that
//! [`crate::stability::acceleration_limit`] predicts for the same posture.
//!
//! How the acceleration is imposed: by d'Alembert's principle, a robot whose every body
//! accelerates at `a u` with its joints held (the motion the limit is defined for) feels
//! the same contact forces as the robot at rest under gravity `g − a u`. A run
//! ([`LiftOffProblem::lifted_contact`]) starts the robot at rest, level, heading +x, its
//! lowest contact on the ground, lets it settle for [`LiftOffSettings::settle`], ramps the
//! plant's gravity from `g` to `g − a u` over [`LiftOffSettings::ramp`] along a smooth step
//! (`3τ² − 2τ³` of the elapsed fraction τ: no jump in the rate of the imposed acceleration
//! at either end, so the hold does not start with a jolt) and holds it for
//! [`LiftOffSettings::hold`], with every joint (wheels included) held at its start
//! position by a PD law (the arm's gains by default from each joint's own inertia,
//! [`JointGains`]); the wheels' friction carries the horizontal load. The run ends
//! at the problem's [`LiftOffEvent`] after the settling time: by default the first
//! contact that carries no normal force; or the tip-over, when the contacts still loaded
//! lie on one line (every contact off that edge has lost its load).
//! [`LiftOffProblem::run`] shows each step to an observer.
//!
//! [`LiftOffProblem::search`] bisects on `a` between an acceleration at which nothing
//! lifts and one at which a contact lifts, until the bracket is narrower than
//! [`LiftOffSettings::tolerance`] times its upper end, in at most
//! [`LiftOffSettings::max_iterations`] runs after the two that check the bracket.
//!
//! What this measures: the steady acceleration of the prediction, on a plant whose
//! contacts are compliant and whose joints are PD-held (so as a contact unloads the base
//! pitches and the arm deflects); not the transients of a real start or stop.

use nalgebra::{DVector, Vector2, Vector3};

use crate::contact::{ContactPlant, ContactReport, ContactState, spring_damper_step_bound};
use crate::dynamics::center_of_mass;
use crate::error::{Error, Result};
use crate::multibody::Data;
use crate::sim::contact_run::MAX_CONTACT_STEPS;
use crate::sim::model_mismatch::{ModelPerturbation, Payload};
use crate::stability::{SupportPolygon, acceleration_limit};

/// How the PD law `u = kp (q₀ − q) − kd q̇` holding the joints other than the wheels is
/// tuned.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointGains {
    /// Per joint from its effective inertia `I` at the start posture
    /// ([`ContactPlant::joint_inertias`], the payload included): `kp = I ω²`,
    /// `kd = 2 ζ ω I`, so that each joint on its own is a spring-damper of natural
    /// frequency `frequency` ω (rad/s, > 0) and damping ratio `damping_ratio` ζ (≥ 0),
    /// whatever its inertia (a light wrist as a heavy shoulder).
    Inertial {
        /// ω (rad/s).
        frequency: f64,
        /// ζ.
        damping_ratio: f64,
    },
    /// The same `[kp (N·m/rad), kd (N·m·s/rad)]` on every joint.
    Fixed([f64; 2]),
}

/// The default [`JointGains`]: ω = 100 rad/s, ζ = 1 (critically damped). Each joint's
/// stable step is then `0.828 / ω` = 8.3 ms, 83 times the plant's default step.
pub const DEFAULT_JOINT_GAINS: JointGains = JointGains::Inertial {
    frequency: 100.0,
    damping_ratio: 1.0,
};

/// How a lift-off run imposes the acceleration and how the search ends.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LiftOffSettings {
    /// Time at rest before the ramp (s, ≥ 0); lift-off is looked for only after it.
    pub settle: f64,
    /// Duration of the ramp of the acceleration from 0 to `a` (s, > 0), a smooth step.
    pub ramp: f64,
    /// Time `a` is held after the ramp (s, ≥ 0).
    pub hold: f64,
    /// PD gains `[kp (N·m/rad), kd (N·m·s/rad)]` holding the wheel joints.
    pub wheel_gains: [f64; 2],
    /// The PD gains holding every other joint.
    pub joint_gains: JointGains,
    /// The search ends when the bracket `[lo, hi]` has `hi − lo ≤ tolerance · hi` (> 0).
    pub tolerance: f64,
    /// Largest number of bisection runs (≥ 1).
    pub max_iterations: usize,
}

impl Default for LiftOffSettings {
    fn default() -> Self {
        Self {
            settle: 0.3,
            ramp: 1.0,
            hold: 0.7,
            wheel_gains: [500.0, 20.0],
            joint_gains: DEFAULT_JOINT_GAINS,
            tolerance: 0.005,
            max_iterations: 20,
        }
    }
}

impl LiftOffSettings {
    /// Checks every field on its own (the gains' stable step, which depends on the robot,
    /// is [`LiftOffProblem::joint_gains`]).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming the field (`settle`, `ramp`, `hold`, `wheel_gains`,
    /// `joint_gains`, `tolerance`, `max_iterations`).
    pub fn validate(&self) -> Result<()> {
        let nonneg = |name: &str, x: f64| {
            if x.is_finite() && x >= 0.0 {
                Ok(())
            } else {
                Err(Error::invalid(
                    name,
                    format!("must be a finite number >= 0, got {x}"),
                ))
            }
        };
        nonneg("settle", self.settle)?;
        nonneg("hold", self.hold)?;
        crate::error::ensure_positive("ramp", self.ramp)?;
        nonneg("wheel_gains", self.wheel_gains[0])?;
        nonneg("wheel_gains", self.wheel_gains[1])?;
        match self.joint_gains {
            JointGains::Fixed([kp, kd]) => {
                nonneg("joint_gains", kp)?;
                nonneg("joint_gains", kd)?;
            }
            JointGains::Inertial {
                frequency,
                damping_ratio,
            } => {
                crate::error::ensure_positive("joint_gains", frequency)?;
                nonneg("joint_gains", damping_ratio)?;
            }
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0 && self.tolerance < 1.0) {
            return Err(Error::invalid(
                "tolerance",
                format!("must be in (0, 1), got {}", self.tolerance),
            ));
        }
        if self.max_iterations == 0 {
            return Err(Error::invalid("max_iterations", "must be at least 1"));
        }
        Ok(())
    }
}

/// What a run looks for after the settling time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LiftOffEvent {
    /// The first contact that carries no normal force (the default).
    #[default]
    FirstLift,
    /// The tip-over: a contact has lifted and the contacts still carrying normal force lie
    /// on one line (within [`EDGE_TOLERANCE`], or one contact or none), so every contact
    /// off that edge has lost its load.
    TipOver,
}

/// Largest distance (m) of a loaded contact from the line through the two loaded
/// contacts farthest apart for the loaded contacts to count as one edge
/// ([`LiftOffEvent::TipOver`]).
pub const EDGE_TOLERANCE: f64 = 1e-3;

/// Do the contacts that carry normal force lie on one line (within [`EDGE_TOLERANCE`], in
/// the ground plane)? True for one loaded contact or none.
fn loaded_on_one_line(contacts: &[ContactReport]) -> bool {
    let loaded = || contacts.iter().filter(|r| !r.lifted).map(|r| r.point.xy());
    let mut ends = None;
    let mut widest = 0.0;
    for (i, a) in loaded().enumerate() {
        for b in loaded().skip(i + 1) {
            let d = (b - a).norm();
            if d > widest {
                widest = d;
                ends = Some((a, b));
            }
        }
    }
    let Some((a, b)) = ends.filter(|_| widest > EDGE_TOLERANCE) else {
        return true;
    };
    let along = (b - a) / widest;
    loaded().all(|p| {
        let r = p - a;
        (r.x * along.y - r.y * along.x).abs() <= EDGE_TOLERANCE
    })
}

/// The fraction of the acceleration imposed at time `t` (s) of a run: 0 until the end of
/// the settling, then the smooth step `3τ² − 2τ³` of the ramp's elapsed fraction τ, then 1.
/// Its rate is zero at both ends of the ramp: a linear ramp's jump in rate where the hold
/// begins set the base rocking on its contacts, and a held run read the overshoot as a
/// lower threshold (Fetch's tip-over, `docs/contact.md`: 0.964 × the prediction, 0.980 ×
/// with this step).
fn ramp_fraction(t: f64, settings: &LiftOffSettings) -> f64 {
    let tau = ((t - settings.settle) / settings.ramp).clamp(0.0, 1.0);
    tau * tau * (3.0 - 2.0 * tau)
}

/// One step of a run as [`LiftOffProblem::run`] shows it: the state the step started
/// from, the gravity it ran under, and the contact forces and accelerations computed
/// there (so `q`, `v`, `acceleration` and `contacts` satisfy the plant's equations of
/// motion together).
#[derive(Clone, Copy, Debug)]
pub struct RunStep<'a> {
    /// Time at the end of the step (s).
    pub time: f64,
    /// The plant's gravity over the step (world, m/s²): `g − a s u`, s the ramp's fraction
    /// (a smooth step from 0 to 1).
    pub gravity: Vector3<f64>,
    /// Configuration at the start of the step.
    pub q: &'a DVector<f64>,
    /// Velocity at the start of the step.
    pub v: &'a DVector<f64>,
    /// The step's accelerations `v̇`.
    pub acceleration: &'a DVector<f64>,
    /// The step's contact reports (forces at the start of the step).
    pub contacts: &'a [ContactReport],
}

/// The result of a search: the smallest acceleration that lifted a contact, to the
/// tolerance.
#[derive(Clone, Debug, PartialEq)]
pub struct LiftOff {
    /// The bracket's midpoint `(lo + hi) / 2` (m/s²).
    pub acceleration: f64,
    /// The largest acceleration tried at which nothing lifted (m/s²).
    pub lo: f64,
    /// The smallest acceleration tried at which a contact lifted (m/s²).
    pub hi: f64,
    /// The contact that lifted at `hi` (index in the plant's contact order: wheels, then
    /// casters); for [`LiftOffEvent::TipOver`] the one whose loss of load completed the
    /// tip-over.
    pub contact: usize,
    /// Bisection runs made (besides the two that check the bracket).
    pub iterations: usize,
}

/// A robot in a posture at rest on the ground, to be accelerated along a direction.
#[derive(Clone, Debug)]
pub struct LiftOffProblem {
    plant: ContactPlant,
    q0: Vec<f64>,
    direction: Vector3<f64>,
    event: LiftOffEvent,
    static_torque: bool,
}

impl LiftOffProblem {
    /// The plant (with the payload added to its model, if any) in the posture `joints`
    /// (every joint below the free-flyer root, wheels included, in model order), at rest,
    /// level, heading +x, at the height where its lowest contact touches the ground;
    /// accelerated along the horizontal `direction` (base axes = world axes at the start;
    /// `[1, 0]` speeds up forwards).
    ///
    /// # Errors
    /// [`Error::WrongLength`] / [`Error::NonFinite`] for `joints`;
    /// [`Error::InvalidInput`] for a `direction` of zero length or not finite, and the
    /// payload's errors (`payload.link`, `payload.mass`, `payload.position`, as
    /// [`ModelPerturbation::apply`]).
    pub fn new(
        plant: &ContactPlant,
        joints: &[f64],
        payload: Option<&Payload>,
        direction: Vector2<f64>,
    ) -> Result<Self> {
        let mut plant = plant.clone();
        let n = plant.model.nq - 7;
        crate::error::ensure_len("posture joints", n, joints.len())?;
        crate::error::ensure_finite("posture joints", joints.iter())?;
        let norm = direction.norm();
        if !(norm.is_finite() && norm > 0.0) {
            return Err(Error::invalid(
                "direction",
                "must be a finite, non-zero horizontal vector",
            ));
        }
        ModelPerturbation {
            mass_scale: 1.0,
            payload: payload.cloned(),
        }
        .apply(&mut plant.model)?;
        let mut q0 = vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0];
        q0.extend_from_slice(joints);
        let lowest = plant
            .contact_points(&q0)?
            .iter()
            .map(|p| p.z)
            .fold(f64::INFINITY, f64::min);
        q0[2] = -lowest;
        Ok(Self {
            plant,
            q0,
            direction: Vector3::new(direction.x / norm, direction.y / norm, 0.0),
            event: LiftOffEvent::FirstLift,
            static_torque: false,
        })
    }

    /// The same problem, its runs looking for `event` ([`LiftOffEvent::FirstLift`] unless
    /// set).
    #[must_use]
    pub fn with_event(mut self, event: LiftOffEvent) -> Self {
        self.event = event;
        self
    }

    /// The same problem, its runs adding to the PD law of every joint but the wheels the
    /// static torque that holds the start posture under the gravity of the moment: the
    /// joint rows of the generalised gravity `g(q0)` for the tilted gravity `g − a s u`
    /// (linear in it). Without it a joint sags until its PD law carries the load (by
    /// `load / kp`: with soft gains, as a light wrist needs, a heavy prismatic torso
    /// sinks by centimetres and bounces, lightly damped), and the centre of mass moves
    /// from where the prediction puts it. The wheels keep the PD law alone: their static
    /// torque is the ground friction's, not gravity's.
    #[must_use]
    pub fn with_static_torque(mut self) -> Self {
        self.static_torque = true;
        self
    }

    /// The plant the runs step (the payload included).
    #[must_use]
    pub fn plant(&self) -> &ContactPlant {
        &self.plant
    }

    /// The unit horizontal direction of the acceleration (world).
    #[must_use]
    pub fn direction(&self) -> Vector3<f64> {
        self.direction
    }

    /// The start configuration (free-flyer `q`).
    #[must_use]
    pub fn start(&self) -> &[f64] {
        &self.q0
    }

    /// The predicted limit (m/s²): [`acceleration_limit`] of the robot's mass and centre
    /// of mass at the start, under the plant's gravity, on the support polygon of the
    /// contacts that touch the ground at the start (within
    /// `params.start_penetration_tol`). `None` as [`acceleration_limit`] (e.g. the robot
    /// already tips at rest).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when fewer than three touching contacts span a polygon.
    pub fn predicted_limit(&self) -> Result<Option<f64>> {
        let m = &self.plant.model;
        let tol = self.plant.params.start_penetration_tol;
        let support: Vec<Vector2<f64>> = self
            .plant
            .contact_points(&self.q0)?
            .iter()
            .filter(|p| p.z <= tol)
            .map(|p| Vector2::new(p.x, p.y))
            .collect();
        let support = SupportPolygon::from_points(&support)?;
        let mut data = Data::new(m);
        let com = center_of_mass(m, &mut data, &DVector::from_column_slice(&self.q0));
        Ok(acceleration_limit(
            m.total_mass(),
            &com,
            &m.gravity,
            &support,
            &self.direction,
        ))
    }

    /// One run at the steady acceleration `a` (m/s², ≥ 0) until the problem's event
    /// after the settling time: for [`LiftOffEvent::FirstLift`] the first contact (plant
    /// order) that lifted, for [`LiftOffEvent::TipOver`] the first (plant order) of the
    /// contacts whose loss of load completed the tip-over; `None` if the event did not
    /// happen.
    ///
    /// # Errors
    /// As [`LiftOffProblem::run`].
    pub fn lifted_contact(&self, a: f64, settings: &LiftOffSettings) -> Result<Option<usize>> {
        let mut was_lifted = vec![false; self.plant.ncontacts()];
        let mut found = None;
        self.run(a, settings, |s| {
            if s.time > settings.settle {
                let lifted = |r: &ContactReport| r.lifted;
                found = match self.event {
                    LiftOffEvent::FirstLift => s.contacts.iter().position(lifted),
                    LiftOffEvent::TipOver if loaded_on_one_line(s.contacts) => s
                        .contacts
                        .iter()
                        .zip(&was_lifted)
                        .position(|(r, was)| r.lifted && !was)
                        .or_else(|| s.contacts.iter().position(lifted)),
                    LiftOffEvent::TipOver => None,
                };
            }
            for (was, r) in was_lifted.iter_mut().zip(s.contacts) {
                *was = r.lifted;
            }
            found.is_some()
        })?;
        Ok(found)
    }

    /// The PD gains `[kp, kd]` of every joint below the root (model order, wheels
    /// included) under `settings`, each checked against the plant's step: semi-implicit
    /// Euler on the joint alone, a spring-damper on its effective inertia `I`
    /// ([`ContactPlant::joint_inertias`] at the start posture), is stable for
    /// `dt < 4 I / (kd + √(kd² + 4 kp I))` ([`spring_damper_step_bound`]; `2 I / kd`
    /// without stiffness).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming `joint_gains` (or `wheel_gains`), the first joint
    /// whose gains break the bound, its inertia and the bound; `settings` invalid.
    pub fn joint_gains(&self, settings: &LiftOffSettings) -> Result<Vec<[f64; 2]>> {
        settings.validate()?;
        let p = &self.plant;
        let inertias = p.joint_inertias(&DVector::from_column_slice(&self.q0))?;
        let dt = p.params.dt;
        let names = p.input_names();
        let mut gains = Vec::with_capacity(inertias.len());
        for (k, &inertia) in inertias.iter().enumerate() {
            let wheel = p.wheel_dofs().contains(&(6 + k));
            let [kp, kd] = match (wheel, settings.joint_gains) {
                (true, _) => settings.wheel_gains,
                (false, JointGains::Fixed(g)) => g,
                (
                    false,
                    JointGains::Inertial {
                        frequency: w,
                        damping_ratio: z,
                    },
                ) => [inertia * w * w, 2.0 * z * w * inertia],
            };
            let bound = spring_damper_step_bound(kp, kd, inertia);
            if dt >= bound {
                return Err(Error::invalid(
                    if wheel { "wheel_gains" } else { "joint_gains" },
                    format!(
                        "kp = {kp} N·m/rad, kd = {kd} N·m·s/rad on '{}' (effective inertia \
                         {inertia:.4e} kg·m² at the start posture) need dt < \
                         4 I/(kd + √(kd² + 4 kp I)) = {bound:.3e} s, but contact.dt = {dt} s: \
                         lower the gains{}",
                        names[k],
                        if wheel {
                            ""
                        } else {
                            " (or leave them unset: gains from each joint's own inertia)"
                        }
                    ),
                ));
            }
            gains.push([kp, kd]);
        }
        Ok(gains)
    }

    /// One run at the steady acceleration `a` (m/s², ≥ 0), showing every step to
    /// `observe` (the first step's `time` is one contact step), until `observe` returns
    /// true or the run ends.
    ///
    /// # Errors
    /// `settings` invalid ([`LiftOffSettings::validate`]), `a` negative or not finite
    /// (`acceleration`), a run longer than [`MAX_CONTACT_STEPS`] steps, the start's checks
    /// ([`ContactState::new`]), gains unstable at the step
    /// ([`LiftOffProblem::joint_gains`]) and a step's numerical failure.
    pub fn run(
        &self,
        a: f64,
        settings: &LiftOffSettings,
        mut observe: impl FnMut(&RunStep<'_>) -> bool,
    ) -> Result<()> {
        settings.validate()?;
        if !(a.is_finite() && a >= 0.0) {
            return Err(Error::invalid(
                "acceleration",
                format!("must be a finite number >= 0, got {a}"),
            ));
        }
        let mut p = self.plant.clone();
        let g = p.model.gravity;
        let duration = settings.settle + settings.ramp + settings.hold;
        let steps = (duration / p.params.dt).round();
        if steps > MAX_CONTACT_STEPS {
            return Err(Error::invalid(
                "settle",
                format!(
                    "settle + ramp + hold = {duration} s is more than {MAX_CONTACT_STEPS} contact steps"
                ),
            ));
        }
        let gains = self.joint_gains(settings)?;
        let nv = p.model.nv;
        let mut st = ContactState::new(&p, &self.q0, &vec![0.0; nv])?;
        // The joint rows of g(q0) per unit of gravity along world x, y, z (zero without
        // the static torque, and for the wheels).
        let mut hold = [vec![0.0; nv - 6], vec![0.0; nv - 6], vec![0.0; nv - 6]];
        if self.static_torque {
            let mut m = p.model.clone();
            let mut data = Data::new(&m);
            let q0 = DVector::from_column_slice(&self.q0);
            for (axis, column) in hold.iter_mut().enumerate() {
                m.gravity = Vector3::ith(axis, 1.0);
                let tau = crate::dynamics::gravity_torque(&m, &mut data, &q0);
                for (k, c) in column.iter_mut().enumerate() {
                    if !p.wheel_dofs().contains(&(6 + k)) {
                        *c = tau[6 + k];
                    }
                }
            }
        }
        let mut u = vec![0.0; nv - 6];
        let (mut q, mut v) = (st.q.clone(), st.v.clone());
        for _ in 0..steps as usize {
            p.model.gravity = g - self.direction * (a * ramp_fraction(st.t, settings));
            let gravity = p.model.gravity;
            for (k, (uk, [kp, kd])) in u.iter_mut().zip(&gains).enumerate() {
                // Joint k below the root: q index 7 + k, v index 6 + k (one-dof joints).
                *uk = kp * (self.q0[7 + k] - st.q[7 + k]) - kd * st.v[6 + k];
                *uk += hold[0][k] * gravity.x + hold[1][k] * gravity.y + hold[2][k] * gravity.z;
            }
            q.copy_from(&st.q);
            v.copy_from(&st.v);
            p.step(&mut st, &u)?;
            let step = RunStep {
                time: st.t,
                gravity: p.model.gravity,
                q: &q,
                v: &v,
                acceleration: st.acceleration(),
                contacts: &st.contacts,
            };
            if observe(&step) {
                break;
            }
        }
        Ok(())
    }

    /// The smallest acceleration in `[lo, hi]` (m/s², `0 ≤ lo < hi`) at which the
    /// problem's event happens (a contact lifts, or the robot tips over), by bisection:
    /// checks that it does not happen at `lo` and does at `hi`, then halves the bracket
    /// until `hi − lo ≤ tolerance · hi`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming `bracket` when it is not `0 ≤ lo < hi` (finite), the
    /// event already happens at `lo` or does not at `hi`; naming `max_iterations` when
    /// the tolerance is not reached within it; the errors of
    /// [`LiftOffProblem::lifted_contact`].
    pub fn search(&self, lo: f64, hi: f64, settings: &LiftOffSettings) -> Result<LiftOff> {
        settings.validate()?;
        if !(lo.is_finite() && hi.is_finite() && lo >= 0.0 && lo < hi) {
            return Err(Error::invalid(
                "bracket",
                format!("needs 0 <= lo < hi, got [{lo}, {hi}]"),
            ));
        }
        let (happens, none) = match self.event {
            LiftOffEvent::FirstLift => ("lifts", "no contact lifts"),
            LiftOffEvent::TipOver => (
                "lifts, tipping the robot over,",
                "the robot does not tip over",
            ),
        };
        if let Some(k) = self.lifted_contact(lo, settings)? {
            return Err(Error::invalid(
                "bracket",
                format!(
                    "contact '{}' already {happens} at the lower end {lo} m/s²",
                    self.plant.contact_name(k)
                ),
            ));
        }
        let Some(mut contact) = self.lifted_contact(hi, settings)? else {
            return Err(Error::invalid(
                "bracket",
                format!("{none} at the upper end {hi} m/s²"),
            ));
        };
        let (mut lo, mut hi) = (lo, hi);
        let mut iterations = 0;
        while hi - lo > settings.tolerance * hi {
            if iterations == settings.max_iterations {
                return Err(Error::invalid(
                    "max_iterations",
                    format!(
                        "{iterations} bisection runs leave [{lo}, {hi}] m/s², wider than the tolerance {}",
                        settings.tolerance
                    ),
                ));
            }
            let mid = 0.5 * (lo + hi);
            match self.lifted_contact(mid, settings)? {
                Some(k) => {
                    hi = mid;
                    contact = k;
                }
                None => lo = mid,
            }
            iterations += 1;
        }
        Ok(LiftOff {
            acceleration: 0.5 * (lo + hi),
            lo,
            hi,
            contact,
            iterations,
        })
    }
}

/// The smallest steady acceleration along `direction` at which `plant` in the posture
/// `joints` (with `payload`, if any) lifts a contact, searched in `bracket` (m/s²): the
/// one-call form of [`LiftOffProblem::new`] and [`LiftOffProblem::search`].
///
/// # Errors
/// As [`LiftOffProblem::new`] and [`LiftOffProblem::search`].
pub fn lift_off_acceleration(
    plant: &ContactPlant,
    joints: &[f64],
    payload: Option<&Payload>,
    direction: Vector2<f64>,
    bracket: [f64; 2],
    settings: &LiftOffSettings,
) -> Result<LiftOff> {
    LiftOffProblem::new(plant, joints, payload, direction)?.search(bracket[0], bracket[1], settings)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_loaded_contacts_form_one_edge_only_when_on_one_line_within_the_tolerance() {
        let at = |x: f64, y: f64, lifted: bool| ContactReport {
            point: Vector3::new(x, y, -0.001),
            normal: if lifted { 0.0 } else { 100.0 },
            lifted,
            ..ContactReport::default()
        };
        // Wheels at x = 0, casters at x = ±0.24: the rear casters alone carry the load.
        let mut c = [
            at(0.0, 0.25, true),
            at(0.0, -0.25, true),
            at(0.24, 0.16, true),
            at(0.24, -0.16, true),
            at(-0.24, 0.16, false),
            at(-0.24, -0.16, false),
        ];
        assert!(loaded_on_one_line(&c));
        // A wheel still loaded: three loaded contacts span a triangle.
        c[0] = at(0.0, 0.25, false);
        assert!(!loaded_on_one_line(&c));
        // A loaded contact 0.9 mm off the edge's line counts as on it, 1.1 mm does not.
        c[0] = at(-0.2391, 0.0, false);
        assert!(loaded_on_one_line(&c));
        c[0] = at(-0.2389, 0.0, false);
        assert!(!loaded_on_one_line(&c));
        // One loaded contact, or none: on a point.
        let one = [at(0.0, 0.0, false), at(1.0, 0.0, true), at(0.0, 1.0, true)];
        assert!(loaded_on_one_line(&one));
        assert!(loaded_on_one_line(&[
            at(0.0, 0.0, true),
            at(1.0, 0.0, true)
        ]));
    }

    #[test]
    fn the_ramp_rises_from_0_to_1_without_a_jump_in_rate_at_either_end() {
        let s = LiftOffSettings {
            settle: 0.3,
            ramp: 2.0,
            ..LiftOffSettings::default()
        };
        let f = |t: f64| ramp_fraction(t, &s);
        assert_eq!(f(0.0), 0.0);
        assert_eq!(f(0.3), 0.0);
        assert_eq!(f(2.3), 1.0);
        assert_eq!(f(5.0), 1.0);
        // Half-way in time, half-way in acceleration; rising throughout.
        assert!((f(1.3) - 0.5).abs() < 1e-15);
        let mut last = 0.0;
        for k in 1..=200 {
            let x = f(0.3 + 2.0 * f64::from(k) / 200.0);
            assert!(x > last, "{k}");
            last = x;
        }
        // The rate (per second) just inside either end is ~0, as it is outside: a
        // linear ramp's would be 1/ramp = 0.5 there.
        let h = 1e-6;
        for end in [0.3, 2.3] {
            for t in [end - h, end + h] {
                let rate = (f(t + h) - f(t - h)) / (2.0 * h);
                assert!(rate.abs() < 1e-5, "rate {rate} at {t}");
            }
        }
        // Steepest half-way: 1.5 / ramp.
        let rate = (f(1.3 + h) - f(1.3 - h)) / (2.0 * h);
        assert!((rate - 0.75).abs() < 1e-6, "{rate}");
    }

    #[test]
    fn bad_settings_name_their_field() {
        let ok = LiftOffSettings::default();
        assert!(ok.validate().is_ok());
        for (s, field) in [
            (
                LiftOffSettings {
                    tolerance: 0.0,
                    ..ok
                },
                "tolerance",
            ),
            (
                LiftOffSettings {
                    tolerance: f64::NAN,
                    ..ok
                },
                "tolerance",
            ),
            (LiftOffSettings { ramp: 0.0, ..ok }, "ramp"),
            (LiftOffSettings { hold: -1.0, ..ok }, "hold"),
            (
                LiftOffSettings {
                    joint_gains: JointGains::Fixed([-1.0, 0.0]),
                    ..ok
                },
                "joint_gains",
            ),
            (
                LiftOffSettings {
                    max_iterations: 0,
                    ..ok
                },
                "max_iterations",
            ),
        ] {
            let e = s.validate().unwrap_err().to_string();
            assert!(e.contains(field), "{e}");
        }
    }
}

//! The smallest steady acceleration at which the contact plant ([`crate::contact`]) lifts
//! a contact, found by simulation, beside the tip-over limit that
//! [`crate::stability::acceleration_limit`] predicts for the same posture.
//!
//! How the acceleration is imposed: by d'Alembert's principle, a robot whose every body
//! accelerates at `a u` with its joints held (the motion the limit is defined for) feels
//! the same contact forces as the robot at rest under gravity `g − a u`. A run
//! ([`LiftOffProblem::lifted_contact`]) starts the robot at rest, level, heading +x, its
//! lowest contact on the ground, lets it settle for [`LiftOffSettings::settle`], ramps the
//! plant's gravity linearly from `g` to `g − a u` over [`LiftOffSettings::ramp`] and holds
//! it for [`LiftOffSettings::hold`], with every joint (wheels included) held at its start
//! position by a PD law (the arm's gains by default from each joint's own inertia,
//! [`JointGains`]); the wheels' friction carries the horizontal load. The first
//! contact that carries no normal force after the settling time has lifted.
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

use crate::contact::{ContactPlant, ContactState, spring_damper_step_bound};
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
    /// Duration of the linear ramp of the acceleration from 0 to `a` (s, > 0).
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
    /// casters).
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
        })
    }

    /// The plant the runs step (the payload included).
    #[must_use]
    pub fn plant(&self) -> &ContactPlant {
        &self.plant
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

    /// One run at the steady acceleration `a` (m/s², ≥ 0): the first contact (plant
    /// order) that lifted after the settling time, or `None`.
    ///
    /// # Errors
    /// `settings` invalid ([`LiftOffSettings::validate`]), `a` negative or not finite
    /// (`acceleration`), a run longer than [`MAX_CONTACT_STEPS`] steps, the start's checks
    /// ([`ContactState::new`]), gains unstable at the step
    /// ([`LiftOffProblem::joint_gains`]) and a step's numerical failure.
    pub fn lifted_contact(&self, a: f64, settings: &LiftOffSettings) -> Result<Option<usize>> {
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
        let mut u = vec![0.0; nv - 6];
        for _ in 0..steps as usize {
            let s = ((st.t - settings.settle) / settings.ramp).clamp(0.0, 1.0);
            p.model.gravity = g - self.direction * (a * s);
            for (k, (uk, [kp, kd])) in u.iter_mut().zip(&gains).enumerate() {
                // Joint k below the root: q index 7 + k, v index 6 + k (one-dof joints).
                *uk = kp * (self.q0[7 + k] - st.q[7 + k]) - kd * st.v[6 + k];
            }
            p.step(&mut st, &u)?;
            if st.t > settings.settle
                && let Some(k) = st.contacts.iter().position(|r| r.lifted)
            {
                return Ok(Some(k));
            }
        }
        Ok(None)
    }

    /// The smallest acceleration in `[lo, hi]` (m/s², `0 ≤ lo < hi`) that lifts a
    /// contact, by bisection: checks that nothing lifts at `lo` and a contact lifts at
    /// `hi`, then halves the bracket until `hi − lo ≤ tolerance · hi`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming `bracket` when it is not `0 ≤ lo < hi` (finite), a
    /// contact already lifts at `lo` or none lifts at `hi`; naming `max_iterations` when
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
        if let Some(k) = self.lifted_contact(lo, settings)? {
            return Err(Error::invalid(
                "bracket",
                format!(
                    "contact '{}' already lifts at the lower end {lo} m/s²",
                    self.plant.contact_name(k)
                ),
            ));
        }
        let Some(mut contact) = self.lifted_contact(hi, settings)? else {
            return Err(Error::invalid(
                "bracket",
                format!("no contact lifts at the upper end {hi} m/s²"),
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

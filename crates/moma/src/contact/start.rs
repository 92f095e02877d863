//! Starting a run: the initial state's checks (lengths, a unit quaternion, nothing deeper
//! in the ground than the tolerance) and the stable-step bounds at that configuration.

use nalgebra::{DVector, Vector3};

use super::params::{friction_step_bound, spring_damper_step_bound};
use super::plant::{ContactPlant, ContactState, Shape};
use super::report::ContactReport;
use super::step::evaluate_contacts;
use crate::error::{Error, Result};
use crate::multibody::Data;

impl ContactPlant {
    /// The stable-step checks of `docs/contact.md` at the state's configuration: for every
    /// contact the normal spring-damper on its normal effective mass, and for every
    /// frictional contact the viscous friction branch on its longitudinal and lateral
    /// effective masses (a wheel's rolling and axle directions; a frictional caster's world
    /// x and y) with the normal force taken as the robot's whole weight.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming `contact.stiffness` or `contact.slip_velocity`,
    /// with the bound and the contact.
    pub fn check_step(&self, state: &ContactState) -> Result<()> {
        let p = &self.params;
        let weight = self.model.total_mass() * self.model.gravity.norm();
        for k in 0..self.contacts.len() {
            let c = &self.contacts[k];
            let m_n = self.effective_mass(state, k, &Vector3::z())?;
            let bound = spring_damper_step_bound(p.stiffness, p.damping, m_n);
            if p.dt >= bound {
                return Err(Error::invalid(
                    "contact.stiffness",
                    format!(
                        "k = {} N/m, c = {} N·s/m on '{}' (normal effective mass {m_n:.4} kg) \
                         need dt < 2(√(1+ζ²) − ζ)/ω_n = {bound:.3e} s, but contact.dt = {}: \
                         lower the stiffness or the step",
                        p.stiffness, p.damping, c.name, p.dt
                    ),
                ));
            }
            if !c.frictional {
                continue;
            }
            let (fwd, lat) = match c.shape {
                Shape::Disk { axis } => self.wheel_directions(state, k, &axis),
                Shape::Sphere { .. } => (Vector3::x(), Vector3::y()),
            };
            for (what, dir) in [("longitudinal", fwd), ("lateral", lat)] {
                let m_t = self.effective_mass(state, k, &dir)?;
                let bound = friction_step_bound(p.mu, weight, p.slip_velocity, m_t);
                if p.dt >= bound {
                    return Err(Error::invalid(
                        "contact.slip_velocity",
                        format!(
                            "v_ε = {} m/s with μ = {} on '{}' ({what} effective mass {m_t:.4} kg, \
                             normal force up to the weight {weight:.1} N) needs dt < 2 m v_ε/(μ N) \
                             = {bound:.3e} s, but contact.dt = {}: raise v_ε or lower the step",
                            p.slip_velocity, p.mu, c.name, p.dt
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// World rolling direction and lateral (axle) direction of wheel `k` in the ground
    /// plane.
    fn wheel_directions(
        &self,
        state: &ContactState,
        k: usize,
        axis: &Vector3<f64>,
    ) -> (Vector3<f64>, Vector3<f64>) {
        let c = &self.contacts[k];
        let mut data = Data::new(&self.model);
        crate::kinematics::forward_kinematics(&self.model, &mut data, &state.q);
        let a = data.world_from_joint[c.body].rotation * axis;
        let lat = Vector3::new(a.x, a.y, 0.0);
        let lat = if lat.norm() > 1e-9 {
            lat.normalize()
        } else {
            Vector3::y()
        };
        (lat.cross(&Vector3::z()), lat)
    }
}

impl ContactState {
    /// A run starting at `q0`, `v0` (t = 0): checks the state (lengths, finite values, a
    /// unit quaternion), that no wheel or caster starts deeper in the ground than
    /// `contact.start_penetration_tol`, and the stable step ([`ContactPlant::check_step`]).
    ///
    /// # Errors
    /// [`Error::WrongLength`] / [`Error::NonFinite`] for `initial q` / `initial v`;
    /// [`Error::InvalidInput`] naming the contact below the ground
    /// (`contact.wheels[0] 'left_wheel_joint'`, `contact.casters[0] 'caster'`), or the parameter of an unstable step.
    pub fn new(plant: &ContactPlant, q0: &[f64], v0: &[f64]) -> Result<Self> {
        let model = &plant.model;
        crate::kinematics::check_state(model, "initial", Some(q0), Some(v0), None, None)?;
        let qn = (q0[3] * q0[3] + q0[4] * q0[4] + q0[5] * q0[5] + q0[6] * q0[6]).sqrt();
        if (qn - 1.0).abs() > 1e-6 {
            return Err(Error::invalid(
                "initial q[3..7]",
                format!("the base quaternion [qx, qy, qz, qw] must have unit norm, has {qn}"),
            ));
        }
        let nc = plant.contacts.len();
        let mut st = Self {
            t: 0.0,
            q: DVector::from_column_slice(q0),
            v: DVector::from_column_slice(v0),
            contacts: vec![ContactReport::default(); nc],
            data: Data::new(model),
            tau: DVector::zeros(model.nv),
            dq: DVector::zeros(model.nv),
            q_next: DVector::zeros(model.nq),
        };
        evaluate_contacts(plant, &mut st);
        for (k, r) in st.contacts.iter().enumerate() {
            if r.depth > plant.params.start_penetration_tol {
                let c = &plant.contacts[k];
                let nw = plant.wheel_dofs().len();
                return Err(Error::invalid(
                    if k < nw {
                        format!("contact.wheels[{k}] '{}'", c.name)
                    } else {
                        format!("contact.casters[{}] '{}'", k - nw, c.name)
                    },
                    format!(
                        "starts {:.6} m below the ground, beyond contact.start_penetration_tol = {} m",
                        r.depth, plant.params.start_penetration_tol
                    ),
                ));
            }
        }
        plant.check_step(&st)?;
        Ok(st)
    }
}

//! One step of the contact plant: contact forces from the compliant law, their
//! generalised forces, the articulated-body algorithm, semi-implicit Euler.

use nalgebra::{Vector2, Vector3};

use super::law::{friction_force, normal_force};
use super::plant::{ContactPlant, ContactState};
use super::point_force::add_point_force;
use crate::error::{Error, Result};

/// Fills `state.contacts` and adds the contact forces' generalised force to `state.tau`
/// at the state's `(q, v)`; runs forward kinematics with velocities first.
pub(crate) fn evaluate_contacts(plant: &ContactPlant, st: &mut ContactState) {
    let model = &plant.model;
    let p = &plant.params;
    crate::kinematics::forward_kinematics_second_order_impl(
        model,
        &mut st.data,
        st.q.as_slice(),
        st.v.as_slice(),
        None,
    );
    for (k, c) in plant.contacts.iter().enumerate() {
        let x = &st.data.world_from_joint[c.body];
        let point = c.lowest_point(x);
        // Velocity of the body's material point at the contact (world).
        let tw = &st.data.v[c.body];
        let w = x.rotation * tw.angular;
        let vel = x.rotation * tw.linear + w.cross(&(point - x.translation));
        let depth = -point.z;
        let normal = normal_force(p.stiffness, p.damping, depth, -vel.z);
        let slip = Vector2::new(vel.x, vel.y);
        let friction = if c.frictional && normal > 0.0 {
            friction_force(p.mu, normal, p.slip_velocity, &slip)
        } else {
            Vector2::zeros()
        };
        let r = &mut st.contacts[k];
        r.point = point;
        r.depth = depth;
        r.normal = normal;
        r.slip = slip;
        r.friction = friction;
        r.lifted = normal <= 0.0;
        r.slipping = c.frictional && normal > 0.0 && slip.norm() >= p.slip_velocity;
        if normal > 0.0 {
            let f = Vector3::new(friction.x, friction.y, normal);
            add_point_force(
                model,
                &st.data,
                c.body,
                &point,
                &f,
                st.q.as_slice(),
                st.tau.as_mut_slice(),
            );
        }
    }
}

impl ContactPlant {
    /// Advances `state` by one step `contact.dt` under joint torques `u` (one per joint
    /// below the free flyer, [`ContactPlant::input_names`]): contact forces at the start
    /// of the step, accelerations by the articulated-body algorithm, then semi-implicit
    /// (symplectic) Euler `v ← v + dt v̇`, `q ← q ⊕ dt v`. Fills `state.contacts` with the
    /// forces applied. Does not allocate.
    ///
    /// # Errors
    /// [`Error::WrongLength`] / [`Error::NonFinite`] for `u`; [`Error::Numerical`] if
    /// the accelerations are not finite (the state has then not been changed).
    pub fn step(&self, st: &mut ContactState, u: &[f64]) -> Result<()> {
        let model = &self.model;
        crate::error::ensure_len("contact input u", self.nu(), u.len())?;
        if !u.iter().all(|x| x.is_finite()) {
            return Err(Error::NonFinite {
                field: "contact input u".into(),
            });
        }
        st.tau.fill(0.0);
        st.tau.as_mut_slice()[6..].copy_from_slice(u);
        evaluate_contacts(self, st);
        let ddq = crate::dynamics::aba(model, &mut st.data, &st.q, &st.v, &st.tau);
        if !ddq.iter().all(|x| x.is_finite()) {
            return Err(Error::Numerical {
                t: st.t,
                message: "contact plant accelerations are not finite".into(),
            });
        }
        let dt = self.params.dt;
        st.v.axpy(dt, ddq, 1.0);
        st.dq.copy_from(&st.v);
        st.dq *= dt;
        crate::kinematics::integrate(model, &st.q, &st.dq, &mut st.q_next);
        std::mem::swap(&mut st.q, &mut st.q_next);
        st.t += dt;
        Ok(())
    }
}

//! The contact plant's set-up: the robot on a free-flyer root with its wheels and casters
//! resolved, and a run's state with the checks made before it starts.

use nalgebra::{DVector, UnitQuaternion, Vector3};

use super::geometry::{disk_lowest_point, sphere_lowest_point};
use super::params::ContactParams;
use super::point_force::add_point_force;
use super::report::ContactReport;
use super::spec::{CasterSpec, WheelSpec};
use crate::error::{Error, Result};
use crate::multibody::{Data, JointType, Model, RootJoint};
use crate::spatial::SE3;

/// The kind and geometry of one resolved ground contact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Shape {
    /// A wheel disk: axle along `axis` (joint frame), centred on the joint origin.
    Disk { axis: Vector3<f64> },
    /// A ball caster: sphere centred at `centre` (joint frame of its body).
    Sphere { centre: Vector3<f64> },
}

/// One resolved ground contact.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Contact {
    pub name: String,
    /// The joint whose body carries the contact.
    pub body: usize,
    pub shape: Shape,
    pub radius: f64,
    /// Frictional (wheels; casters only by [`ContactPlant::with_caster_friction`]).
    pub frictional: bool,
}

impl Contact {
    /// The contact's point (the lowest point of its disk or sphere), world, with its
    /// body at `x` (world from the body's joint frame).
    #[inline]
    pub(crate) fn lowest_point(&self, x: &SE3) -> Vector3<f64> {
        match self.shape {
            Shape::Disk { axis } => {
                disk_lowest_point(&x.translation, &(x.rotation * axis), self.radius)
            }
            Shape::Sphere { centre } => sphere_lowest_point(&x.act_point(&centre), self.radius),
        }
    }
}

/// The robot on a free-flyer root, its drive wheels and ball casters in compliant
/// contact with the ground plane z = 0, and the contact parameters (`docs/contact.md`).
/// Immutable; a run's state is a [`ContactState`].
#[derive(Clone, Debug)]
pub struct ContactPlant {
    /// The rigid-body model (free-flyer root).
    pub model: Model,
    /// Contact law and step.
    pub params: ContactParams,
    pub(crate) contacts: Vec<Contact>,
    wheel_dofs: Vec<usize>,
}

impl ContactPlant {
    /// Resolves `wheels` (revolute joints) and `casters` (frames, or positions in links'
    /// frames) on `model`, whose root must be a free flyer and every other joint one-dof,
    /// and checks `params`.
    ///
    /// # Errors
    /// [`Error::Model`] for a wrong root; [`Error::InvalidInput`] naming the field
    /// (`contact.wheels[k].joint`, `contact.wheels[k].radius`,
    /// `contact.casters[k].frame`, `contact.casters[k].link`, `contact.casters[k].position`,
    /// `contact.casters[k].radius`, `contact.mu`, …);
    /// [`Error::Unknown`] for a joint or frame the model lacks.
    pub fn new(
        model: Model,
        wheels: &[WheelSpec],
        casters: &[CasterSpec],
        params: ContactParams,
    ) -> Result<Self> {
        params.validate()?;
        if model.root != RootJoint::FreeFlyer
            || model.joint_types.get(1) != Some(&JointType::FreeFlyer)
        {
            return Err(Error::Model(format!(
                "the contact plant needs a free-flyer root, '{}' has a {} root",
                model.name, model.root
            )));
        }
        if let Some(j) = (2..model.njoints).find(|&j| model.nvs[j] != 1 || model.nqs[j] != 1) {
            return Err(Error::Model(format!(
                "contact plant '{}': joint '{}' is not one-dof; only one-dof joints may sit \
                 on the free-flyer base",
                model.name, model.names[j]
            )));
        }
        if wheels.is_empty() && casters.is_empty() {
            return Err(Error::invalid("contact.wheels", "no wheel and no caster"));
        }
        let mut contacts = Vec::with_capacity(wheels.len() + casters.len());
        let mut wheel_dofs = Vec::with_capacity(wheels.len());
        for (k, w) in wheels.iter().enumerate() {
            let j = model.joint_id(&w.joint)?.0;
            let axis = model.joint_types[j]
                .axis()
                .filter(|_| model.joint_types[j].is_revolute())
                .ok_or_else(|| {
                    Error::invalid(
                        format!("contact.wheels[{k}].joint"),
                        format!("'{}' must be a revolute (continuous) joint", w.joint),
                    )
                })?;
            check_radius(&format!("contact.wheels[{k}].radius"), w.radius, false)?;
            if wheel_dofs.contains(&model.idx_v[j]) {
                return Err(Error::invalid(
                    format!("contact.wheels[{k}].joint"),
                    format!("'{}' is named twice", w.joint),
                ));
            }
            wheel_dofs.push(model.idx_v[j]);
            contacts.push(Contact {
                name: w.joint.clone(),
                body: j,
                shape: Shape::Disk { axis },
                radius: w.radius,
                frictional: true,
            });
        }
        for (k, c) in casters.iter().enumerate() {
            let place = c.place(k, &model)?;
            check_radius(&format!("contact.casters[{k}].radius"), c.radius, true)?;
            contacts.push(Contact {
                name: place.name,
                body: place.joint,
                shape: Shape::Sphere {
                    centre: place.centre,
                },
                radius: c.radius,
                frictional: false,
            });
        }
        Ok(Self {
            model,
            params,
            contacts,
            wheel_dofs,
        })
    }

    /// The same plant with Coulomb friction (μ, `v_ε` of its parameters, as a wheel's) at
    /// every caster: a caster that carries horizontal force, as a braked or locked caster
    /// does. The shipped casters are frictionless ([`CasterSpec`]); this is for studies
    /// that need horizontal force at the casters, such as tipping a robot over an edge
    /// between two casters (`sim::lift_off`), where frictionless casters leave the
    /// unloaded drive wheels as the only frictional contacts.
    #[must_use]
    pub fn with_caster_friction(mut self) -> Self {
        for c in &mut self.contacts {
            c.frictional = true;
        }
        self
    }

    /// Number of ground contacts: the wheels, then the casters, in the order given.
    #[must_use]
    pub fn ncontacts(&self) -> usize {
        self.contacts.len()
    }

    /// Each contact's point (the lowest point of its wheel disk or caster sphere, world)
    /// at the configuration `q`, in contact order; for setting a run up (allocates).
    ///
    /// # Errors
    /// [`Error::WrongLength`] / [`Error::NonFinite`] for `q` (named `q`).
    pub fn contact_points(&self, q: &[f64]) -> Result<Vec<Vector3<f64>>> {
        crate::kinematics::check_state(&self.model, "contact_points", Some(q), None, None, None)?;
        let mut data = Data::new(&self.model);
        crate::kinematics::forward_kinematics(
            &self.model,
            &mut data,
            &nalgebra::DVector::from_column_slice(q),
        );
        Ok(self
            .contacts
            .iter()
            .map(|c| c.lowest_point(&data.world_from_joint[c.body]))
            .collect())
    }

    /// Name of contact `k` (the wheel joint; the caster's frame, or `link [x y z]`).
    #[must_use]
    pub fn contact_name(&self, k: usize) -> &str {
        &self.contacts[k].name
    }

    /// Number of inputs: one torque per joint below the free flyer (`nv − 6`), in model
    /// velocity order ([`ContactPlant::input_names`]).
    #[must_use]
    pub fn nu(&self) -> usize {
        self.model.nv - 6
    }

    /// The joint of each input, in order.
    #[must_use]
    pub fn input_names(&self) -> Vec<String> {
        (6..self.model.nv)
            .map(|i| self.model.names[self.model.joint_of_dof[i].0].clone())
            .collect()
    }

    /// Velocity index of each wheel, in the order given.
    #[must_use]
    pub fn wheel_dofs(&self) -> &[usize] {
        &self.wheel_dofs
    }

    /// Effective mass (kg) of contact `k` along the world direction `dir` at the state's
    /// configuration: `1 / (gᵀ H⁻¹ g)` with `g = Jᵀ dir` the generalised force of a unit
    /// force at the contact point. Allocates (set-up and checks only).
    ///
    /// # Errors
    /// [`Error::Singular`] if the mass matrix is not positive definite.
    pub fn effective_mass(
        &self,
        state: &ContactState,
        k: usize,
        dir: &Vector3<f64>,
    ) -> Result<f64> {
        let mut data = Data::new(&self.model);
        crate::kinematics::forward_kinematics(&self.model, &mut data, &state.q);
        let mut g = DVector::zeros(self.model.nv);
        add_point_force(
            &self.model,
            &data,
            self.contacts[k].body,
            &state.contacts[k].point,
            dir,
            state.q.as_slice(),
            g.as_mut_slice(),
        );
        Ok(self.effective_inertias(&state.q, &[g])?[0])
    }

    /// Effective inertia (kg·m² for a revolute joint) of each joint below the free flyer at
    /// the configuration `q`, in input order: `1 / (H⁻¹)ᵢᵢ`, the inertia the joint's own
    /// torque moves with the base and every other joint free (what a PD law on that joint
    /// acts on over one step). Allocates (set-up and checks only).
    ///
    /// # Errors
    /// [`Error::Singular`] if the mass matrix is not positive definite.
    pub fn joint_inertias(&self, q: &DVector<f64>) -> Result<Vec<f64>> {
        let nv = self.model.nv;
        let units: Vec<DVector<f64>> = (6..nv)
            .map(|i| DVector::from_fn(nv, |r, _| if r == i { 1.0 } else { 0.0 }))
            .collect();
        self.effective_inertias(q, &units)
    }

    /// `1 / (gᵀ H⁻¹ g)` at `q` for each generalised force `g`.
    fn effective_inertias(&self, q: &DVector<f64>, forces: &[DVector<f64>]) -> Result<Vec<f64>> {
        let mut data = Data::new(&self.model);
        crate::dynamics::crba(&self.model, &mut data, q);
        let chol = data
            .mass_matrix
            .clone()
            .cholesky()
            .ok_or_else(|| Error::Singular {
                what: "contact plant mass matrix".into(),
                detail: None,
            })?;
        Ok(forces.iter().map(|g| 1.0 / g.dot(&chol.solve(g))).collect())
    }

    /// Wheel speeds (rad/s, joint velocities) of `state`, in the order the wheels were given.
    pub fn wheel_speeds<'a>(&'a self, state: &'a ContactState) -> impl Iterator<Item = f64> + 'a {
        self.wheel_dofs.iter().map(move |&i| state.v[i])
    }
}

fn check_radius(field: &str, r: f64, zero_ok: bool) -> Result<()> {
    if !r.is_finite() {
        return Err(Error::NonFinite {
            field: field.into(),
        });
    }
    if r < 0.0 || (!zero_ok && r == 0.0) {
        return Err(Error::invalid(field, format!("must be > 0, got {r}")));
    }
    Ok(())
}

/// A run of the contact plant: time, state, the contact reports of the last step and every
/// buffer a step needs (allocated once by [`ContactState::new`]).
#[derive(Clone, Debug)]
pub struct ContactState {
    /// Time (s).
    pub t: f64,
    /// Configuration `[x, y, z, qx, qy, qz, qw, joints…]` (base pose in world, then the
    /// joints in model order).
    pub q: DVector<f64>,
    /// Velocity `[base twist in the base frame (linear, angular), joint rates…]`.
    pub v: DVector<f64>,
    /// One report per contact (wheels, then casters).
    pub contacts: Vec<ContactReport>,
    pub(crate) data: Data,
    pub(crate) tau: DVector<f64>,
    pub(crate) dq: DVector<f64>,
    pub(crate) q_next: DVector<f64>,
}

impl ContactState {
    /// Base position (world, m).
    #[must_use]
    pub fn base_position(&self) -> Vector3<f64> {
        Vector3::new(self.q[0], self.q[1], self.q[2])
    }

    /// Base orientation (world from base).
    #[must_use]
    pub fn base_orientation(&self) -> UnitQuaternion<f64> {
        UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
            self.q[6], self.q[3], self.q[4], self.q[5],
        ))
    }

    /// Heading: the yaw of the base x axis in the ground plane (rad).
    #[must_use]
    pub fn yaw(&self) -> f64 {
        let x = self.base_orientation() * Vector3::x();
        x.y.atan2(x.x)
    }

    /// Joint positions below the free flyer, in model order (`q[7..]`).
    #[must_use]
    pub fn joint_positions(&self) -> &[f64] {
        &self.q.as_slice()[7..]
    }

    /// Joint velocities below the free flyer, in model order (`v[6..]`).
    #[must_use]
    pub fn joint_velocities(&self) -> &[f64] {
        &self.v.as_slice()[6..]
    }

    /// The accelerations `v̇` of the last step (at its start, under the contact forces of
    /// [`ContactState::contacts`]); zero before the first step.
    #[must_use]
    pub fn acceleration(&self) -> &DVector<f64> {
        &self.data.ddq
    }
}

//! The `plant` choice and the `[contact]` table as a file writes them: one schema for the
//! `moma simulate` scenario (`docs/simulate.md`) and the `moma mission` file
//! (`docs/mission.md`); the model in `docs/contact.md`.

use serde::{Deserialize, Serialize};

use super::params::ContactParams;
use super::plant::ContactPlant;
use super::spec::{CasterSpec, WheelSpec};
use crate::Result;
use crate::multibody::Model;

/// Which plant a wheeled scenario runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlantKind {
    /// The reduced (rolling) model: planar base, wheels that roll without slipping.
    #[default]
    Rolling,
    /// The contact plant: free-flyer base, wheels and casters in frictional, unilateral
    /// contact with the ground (`docs/contact.md`).
    Contact,
}

/// The `[contact]` table: the contact law's parameters (each optional, defaults of
/// [`ContactParams`], checked by [`ContactParams::validate`] when the plant is built) and
/// the casters. The drive wheels are the robot's `wheel_joints`, disks of radius
/// `drive.r_w`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Coulomb friction coefficient μ of the wheels (> 0).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mu: Option<f64>,
    /// Normal stiffness k (N/m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness: Option<f64>,
    /// Normal damping c (N·s/m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub damping: Option<f64>,
    /// Friction regularisation velocity v_ε (m/s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub slip_velocity: Option<f64>,
    /// Contact step (s).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub dt: Option<f64>,
    /// Largest penetration allowed at the start (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub start_penetration_tol: Option<f64>,
    /// The casters: a sphere of `radius` on a `frame` of the robot description, or at
    /// `position` in the frame of `link` ([`CasterSpec`]).
    pub casters: Vec<CasterSpec>,
    /// `true` gives every caster the wheels' Coulomb friction (μ, `v_ε`), as a braked or
    /// locked caster has ([`ContactPlant::with_caster_friction`]); default `false`:
    /// frictionless casters.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub caster_friction: Option<bool>,
}

impl ContactSpec {
    /// The contact plant of `model` (a free-flyer root) with the drive `wheels`, the
    /// table's casters (with the wheels' friction when `caster_friction = true`) and the
    /// law `params` (the table's, [`ContactSpec::params`], or a perturbed draw of them).
    ///
    /// # Errors
    /// [`ContactPlant::new`]'s, naming the field at fault.
    pub fn plant(
        &self,
        model: Model,
        wheels: &[WheelSpec],
        params: ContactParams,
    ) -> Result<ContactPlant> {
        let plant = ContactPlant::new(model, wheels, &self.casters, params)?;
        Ok(if self.caster_friction == Some(true) {
            plant.with_caster_friction()
        } else {
            plant
        })
    }

    /// The law's parameters: the table's values over the defaults.
    #[must_use]
    pub fn params(&self) -> ContactParams {
        let d = ContactParams::default();
        ContactParams {
            stiffness: self.stiffness.unwrap_or(d.stiffness),
            damping: self.damping.unwrap_or(d.damping),
            mu: self.mu.unwrap_or(d.mu),
            slip_velocity: self.slip_velocity.unwrap_or(d.slip_velocity),
            dt: self.dt.unwrap_or(d.dt),
            start_penetration_tol: self
                .start_penetration_tol
                .unwrap_or(d.start_penetration_tol),
        }
    }
}

//! A planning group: the joints of a rigid-body model that move (e.g. Fetch's
//! `arm_with_torso`, torso lift and seven arm joints), their planning box and limits, and
//! the map between a group state and the full configuration.
//!
//! **Box.** A revolute or prismatic joint is planned within its URDF position limits. A
//! continuous joint has none; it is planned as a real coordinate in the bounded range
//! `[-π, π]`, not wrapped around (so a motion never crosses ±π; a start or goal of a
//! continuous joint outside that range is an error naming the joint).

use crate::multibody::{JointIndex, Model};
use crate::{Error, Result};
use std::f64::consts::PI;

/// The joints a planner moves; every other joint stays where the start state puts it.
#[derive(Clone, Debug, PartialEq)]
pub struct JointGroup {
    /// The group's joints in the caller's order.
    pub joints: Vec<JointIndex>,
    /// Their names.
    pub names: Vec<String>,
    /// Index of each joint's coordinate in the full configuration `q` (and velocity).
    pub q_index: Vec<usize>,
    /// Whether each joint is prismatic (its coordinate is in metres).
    pub prismatic: Vec<bool>,
    /// Whether each joint is continuous (no URDF position limits).
    pub continuous: Vec<bool>,
    /// Lower end of the planning box per joint.
    pub lower: Vec<f64>,
    /// Upper end of the planning box per joint.
    pub upper: Vec<f64>,
    /// URDF velocity limit per joint (m/s or rad/s).
    pub velocity: Vec<f64>,
}

impl JointGroup {
    /// The group of the named joints of `model`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming `group` when the list is empty, names a joint twice,
    /// names a joint the model lacks (listing the model's joints), or a joint that is not
    /// a one-coordinate revolute, continuous or prismatic joint, or one without a finite
    /// positive velocity limit.
    pub fn new(model: &Model, names: &[impl AsRef<str>]) -> Result<Self> {
        if names.is_empty() {
            return Err(Error::invalid("group", "names no joint"));
        }
        let mut g = JointGroup {
            joints: Vec::new(),
            names: Vec::new(),
            q_index: Vec::new(),
            prismatic: Vec::new(),
            continuous: Vec::new(),
            lower: Vec::new(),
            upper: Vec::new(),
            velocity: Vec::new(),
        };
        for name in names {
            let name = name.as_ref();
            let Some(j) = (1..model.njoints).find(|&j| model.names[j] == name) else {
                let known: Vec<&str> = model.names[1..].iter().map(String::as_str).collect();
                return Err(Error::invalid(
                    "group",
                    format!(
                        "unknown joint '{name}'; the model's joints are {}",
                        known.join(", ")
                    ),
                ));
            };
            if g.names.iter().any(|n| n == name) {
                return Err(Error::invalid(
                    "group",
                    format!("joint '{name}' is named twice"),
                ));
            }
            let jt = model.joint_types[j];
            if !(jt.is_revolute() || jt.is_prismatic()) || model.nqs[j] != 1 || model.nvs[j] != 1 {
                return Err(Error::invalid(
                    "group",
                    format!(
                        "joint '{name}' is a {} joint; a group holds revolute, continuous and prismatic joints",
                        jt.name()
                    ),
                ));
            }
            let (iq, iv) = (model.idx_q[j], model.idx_v[j]);
            if iq != iv && model.nq == model.nv {
                return Err(Error::invalid(
                    "group",
                    format!("joint '{name}': its position and velocity indices differ"),
                ));
            }
            let (lo, hi) = (
                model.lower_position_limit[iq],
                model.upper_position_limit[iq],
            );
            let continuous = !(lo.is_finite() && hi.is_finite());
            let vel = model.velocity_limit[iv];
            if !(vel.is_finite() && vel > 0.0) {
                return Err(Error::invalid(
                    "group",
                    format!("joint '{name}' has no finite positive velocity limit ({vel})"),
                ));
            }
            g.joints.push(JointIndex(j));
            g.names.push(name.to_string());
            g.q_index.push(iq);
            g.prismatic.push(jt.is_prismatic());
            g.continuous.push(continuous);
            g.lower.push(if continuous { -PI } else { lo });
            g.upper.push(if continuous { PI } else { hi });
            g.velocity.push(vel);
        }
        Ok(g)
    }

    /// The number of joints.
    #[must_use]
    pub fn dim(&self) -> usize {
        self.joints.len()
    }

    /// The group's coordinates of a full configuration, into `out`.
    pub fn extract(&self, q: &[f64], out: &mut [f64]) {
        for (o, &i) in out.iter_mut().zip(&self.q_index) {
            *o = q[i];
        }
    }

    /// Writes a group state into a full configuration.
    pub fn embed(&self, x: &[f64], q: &mut [f64]) {
        for (v, &i) in x.iter().zip(&self.q_index) {
            q[i] = *v;
        }
    }

    /// Checks that the group coordinates of the full state `q` lie in the planning box;
    /// `field` names the state.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] naming `field` and the joint.
    pub fn check_in_box(&self, field: &str, q: &[f64]) -> Result<()> {
        for k in 0..self.dim() {
            let x = q[self.q_index[k]];
            if !(self.lower[k] <= x && x <= self.upper[k]) {
                let what = if self.continuous[k] {
                    "the planning range of a continuous joint (give the angle in [-π, π])"
                } else {
                    "the URDF position limits"
                };
                return Err(Error::invalid(
                    format!("{field}: joint '{}'", self.names[k]),
                    format!(
                        "{x} is outside {what} [{}, {}]",
                        self.lower[k], self.upper[k]
                    ),
                ));
            }
        }
        Ok(())
    }
}

//! Tip-over stability of a mobile manipulator (chapter 5.3.2): the support polygon, the
//! gravito-inertial wrench of any state `(q, v, a)`, and the three measures built on it —
//! the Zero-Moment Point and its margin, the Force-Angle measure of Papadopoulos & Rey
//! (1996, 2000) and the Moment-Height measure of Moosavian & Alipour — plus the
//! acceleration limits of a posture at rest.
//!
//! # Conventions
//!
//! * Ground plane horizontal, normal +z, at the height of the support
//!   ([`SupportPolygon::ground_z`]).
//! * Support vertices clockwise seen from above, starting at the smallest x (ties:
//!   smallest y); edge (tip-over axis) i runs from vertex i to vertex i + 1, its inward
//!   normal is `a_i × ẑ`. A critical edge is the lowest index among equal values.
//! * The wrench is everything but the ground reactions: `f_gi = M g − ṗ + Σ f_j`,
//!   `M_gi(p_c) = −L̇_c + Σ (s_j − p_c) × f_j + Σ n_j`.
//! * Signs: positive = stable for every measure (`s_i`, `θ_i`, `β_i`, `M_i`, `M_i/I_i`).
//! * Undefined values are `None` (never NaN): the ZMP when `n · f_gi ≥ 0`, `θ_i` when the
//!   effective force vanishes, `M_i / I_i` when `I_i = 0`.
//!
//! # Data flow
//!
//! [`StabilityModel`] (support, gravity, Moment-Height body set; immutable) and a
//! [`StabilityData`] workspace allocated once; [`evaluate`] fills the workspace from one
//! forward pass over the rigid-body [`Data`](crate::multibody::Data) and does not
//! allocate.
//!
//! ```
//! # use moma::{io::urdf::model_from_urdf_str, multibody::{Data, RootJoint}};
//! # use moma::stability::{BodySet, StabilityData, StabilityModel, SupportAttachment, SupportPolygon, evaluate};
//! # use nalgebra::{DVector, Vector2};
//! # let urdf = r#"<robot name="r"><link name="base"><inertial><mass value="10"/>
//! #   <origin xyz="0 0 0.3"/><inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>"#;
//! let model = model_from_urdf_str(urdf, RootJoint::Planar, "r.urdf")?;
//! let support = SupportPolygon::from_points(&[
//!     Vector2::new(0.5, 0.3), Vector2::new(0.5, -0.3),
//!     Vector2::new(-0.5, -0.3), Vector2::new(-0.5, 0.3)])?;
//! let sm = StabilityModel::new(&model, support, SupportAttachment::Base, &BodySet::All)?;
//! let mut data = Data::new(&model);
//! let mut sd = StabilityData::new(&sm);
//! let z = DVector::zeros(3);
//! let r = evaluate(&model, &mut data, &sm, &mut sd, &z, &z, &z, &Default::default());
//! assert!((r.zmp_margin.unwrap() - 0.3).abs() < 1e-12);
//! # Ok::<(), moma::Error>(())
//! ```
//!
//! # References
//! * E. G. Papadopoulos, D. A. Rey, "A new measure of tipover stability margin for
//!   mobile manipulators", ICRA 1996; "The force-angle measure of tipover stability
//!   margin for mobile manipulators", Vehicle System Dynamics 33(1), 2000.
//! * S. A. A. Moosavian, K. Alipour, "Moment-height tip-over measure for stability
//!   analysis of mobile robotic systems", IROS 2006.
//! * Q. Huang, S. Sugano, I. Kato, "Stability control for a mobile manipulator using a
//!   potential method", IROS 1994 (ZMP on mobile manipulators).

mod limits;
pub mod loads;
mod measures;
mod polygon;
mod state_report;
mod wrench;

pub use limits::{AccelerationLimits, acceleration_limit, acceleration_limits};
pub use loads::{
    LoadRule, WheelFriction, contact_normal_loads, driven_wheel_friction, load_equilibrium_residual,
};
pub use measures::{
    EdgeMeasures, StabilityReport, evaluate_measures, inertia_about_axis, zero_moment_point,
};
pub use polygon::{Edge, SupportKind, SupportPolygon};
pub use state_report::{EdgeState, StateReport, WrenchState};
pub use wrench::{
    ExternalLoads, GravitoInertialWrench, PointForce, gravito_inertial_wrench,
    gravito_inertial_wrench_per_body, gravito_inertial_wrench_with_set,
};

use nalgebra::{DVector, Vector3};

use crate::error::{Error, Result};
use crate::multibody::{Data, FrameIndex, FrameKind, JointIndex, Model};
use crate::spatial::Inertia;

/// The bodies whose inertia enters the Moment-Height measure `I_i`.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub enum BodySet {
    /// Every moving body (the default).
    #[default]
    All,
    /// The bodies of a joint's subtree (the joint's own body and all below it).
    Subtree(String),
    /// The bodies carrying the named links. A link merged into a body by a fixed joint
    /// names that whole body; a body named twice counts once.
    Links(Vec<String>),
}

impl std::str::FromStr for BodySet {
    type Err = Error;

    /// `all`, `subtree:JOINT` or `links:A,B,…`.
    fn from_str(s: &str) -> Result<Self> {
        let s = s.trim();
        if s == "all" {
            return Ok(BodySet::All);
        }
        if let Some(j) = s.strip_prefix("subtree:") {
            let j = j.trim();
            if j.is_empty() {
                return Err(Error::invalid("body set", "subtree: needs a joint name"));
            }
            return Ok(BodySet::Subtree(j.to_string()));
        }
        if let Some(l) = s.strip_prefix("links:") {
            let names: Vec<String> = l
                .split(',')
                .map(|x| x.trim().to_string())
                .filter(|x| !x.is_empty())
                .collect();
            if names.is_empty() {
                return Err(Error::invalid("body set", "links: needs at least one link"));
            }
            return Ok(BodySet::Links(names));
        }
        Err(Error::invalid(
            "body set",
            format!("'{s}' is not one of all, subtree:JOINT, links:A,B,..."),
        ))
    }
}

impl BodySet {
    /// One flag per joint of `model`: does the body of joint i belong to the set?
    ///
    /// # Errors
    /// [`Error::Unknown`] for a joint or link the model does not have;
    /// [`Error::InvalidInput`] for the universe or a link fixed to the world.
    pub fn mask(&self, model: &Model) -> Result<Vec<bool>> {
        let n = model.njoints;
        let mut mask = vec![false; n];
        match self {
            BodySet::All => mask[1..].iter_mut().for_each(|m| *m = true),
            BodySet::Subtree(name) => {
                let j = model.joint_id(name)?;
                if j.0 == 0 {
                    return Err(Error::invalid(
                        "body set",
                        "subtree: name a moving joint, not the universe",
                    ));
                }
                for (i, m) in mask.iter_mut().enumerate().skip(1) {
                    *m = model.is_ancestor(j, JointIndex(i));
                }
            }
            BodySet::Links(names) => {
                for name in names {
                    let f = model
                        .frames
                        .iter()
                        .find(|f| f.name == *name && f.kind == FrameKind::Body)
                        .ok_or_else(|| Error::Unknown {
                            kind: "link",
                            name: name.clone(),
                        })?;
                    if f.parent_joint.0 == 0 {
                        return Err(Error::invalid(
                            format!("body set link '{name}'"),
                            "is fixed to the world (not a moving body)",
                        ));
                    }
                    mask[f.parent_joint.0] = true;
                }
            }
        }
        Ok(mask)
    }
}

/// Where the support polygon is given.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SupportAttachment {
    /// Fixed in world coordinates.
    World,
    /// In the frame of the root link (the mobile base): it moves with the base's position
    /// on the ground and its heading.
    Base,
}

/// The immutable part of a stability evaluation: support, gravity and body set.
#[derive(Clone, Debug)]
pub struct StabilityModel {
    /// Support polygon (in the base frame or the world, see `attachment`).
    pub support: SupportPolygon,
    /// Where `support` is given.
    pub attachment: SupportAttachment,
    /// Gravity (world, m/s²); the model's gravity unless changed.
    pub gravity: Vector3<f64>,
    /// Moment-Height body flags, one per joint.
    pub body_mask: Vec<bool>,
    /// The root-link frame (the base frame of the support).
    pub base_frame: FrameIndex,
}

impl StabilityModel {
    /// Builds the evaluation set-up for `model`; gravity is `model.gravity`.
    ///
    /// # Errors
    /// From [`BodySet::mask`].
    pub fn new(
        model: &Model,
        support: SupportPolygon,
        attachment: SupportAttachment,
        bodies: &BodySet,
    ) -> Result<Self> {
        let base_frame = model
            .frames
            .iter()
            .position(|f| f.kind == FrameKind::Body)
            .map_or(FrameIndex(0), FrameIndex);
        Ok(Self {
            support,
            attachment,
            gravity: model.gravity,
            body_mask: bodies.mask(model)?,
            base_frame,
        })
    }

    /// The same set-up under another gravity vector.
    ///
    /// # Errors
    /// [`Error::NonFinite`] for a non-finite component.
    pub fn with_gravity(mut self, gravity: Vector3<f64>) -> Result<Self> {
        crate::error::ensure_finite("gravity", gravity.iter())?;
        self.gravity = gravity;
        Ok(self)
    }
}

/// Workspace and results of [`evaluate`], allocated once by [`StabilityData::new`].
#[derive(Clone, Debug)]
pub struct StabilityData {
    /// The gravito-inertial wrench of the last state.
    pub wrench: GravitoInertialWrench,
    /// The support in world coordinates for the last state.
    pub support: SupportPolygon,
    /// World spatial inertia of the Moment-Height body set.
    pub set_inertia: Inertia,
    /// Base pose on the ground `(x, y, yaw)` of the last state.
    pub base_pose: [f64; 3],
    /// The measures.
    pub report: StabilityReport,
}

impl StabilityData {
    /// Allocates every buffer for `sm`.
    #[must_use]
    pub fn new(sm: &StabilityModel) -> Self {
        Self {
            wrench: GravitoInertialWrench::zero(),
            support: sm.support.clone(),
            set_inertia: Inertia::zero(),
            base_pose: [0.0; 3],
            report: StabilityReport::with_capacity(sm.support.len()),
        }
    }

    /// The acceleration limits (base axes) of the last state, read as a posture at rest
    /// (its velocities, accelerations and external loads are ignored).
    #[must_use]
    pub fn acceleration_limits(&self, sm: &StabilityModel) -> AccelerationLimits {
        acceleration_limits(
            self.wrench.mass,
            &self.wrench.com,
            &sm.gravity,
            &self.support,
            self.base_pose[2],
        )
    }
}

/// Evaluates the wrench, the support in world coordinates and every measure of state
/// `(q, v, a)` with `external` loads, into `sd` (returns `&sd.report`). Does not
/// allocate.
///
/// # Panics
/// On wrong vector lengths, or if `sd` / `data` were not made for `sm` / `model`.
#[allow(clippy::too_many_arguments)]
pub fn evaluate<'s>(
    model: &Model,
    data: &mut Data,
    sm: &StabilityModel,
    sd: &'s mut StabilityData,
    q: &DVector<f64>,
    v: &DVector<f64>,
    a: &DVector<f64>,
    external: &ExternalLoads<'_>,
) -> &'s StabilityReport {
    sd.wrench = gravito_inertial_wrench_with_set(
        model,
        data,
        q,
        v,
        a,
        &sm.gravity,
        external,
        Some((&sm.body_mask, &mut sd.set_inertia)),
    );
    let fr = &model.frames[sm.base_frame.0];
    let base = data.world_from_joint[fr.parent_joint.0].compose(&fr.placement);
    let r = &base.rotation;
    sd.base_pose = [
        base.translation.x,
        base.translation.y,
        r[(1, 0)].atan2(r[(0, 0)]),
    ];
    match sm.attachment {
        SupportAttachment::Base => sm.support.place_into(
            sd.base_pose[0],
            sd.base_pose[1],
            sd.base_pose[2],
            &mut sd.support,
        ),
        SupportAttachment::World => sm.support.place_into(0.0, 0.0, 0.0, &mut sd.support),
    }
    evaluate_measures(&sd.wrench, &sd.support, &sd.set_inertia, &mut sd.report);
    &sd.report
}

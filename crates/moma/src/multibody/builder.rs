//! Programmatic construction of a [`Model`].

use super::{Frame, FrameIndex, FrameKind, JointIndex, JointType, Model, RootJoint};
use crate::spatial::{Inertia, SE3};
use crate::{Error, Result};
use nalgebra::{DVector, Matrix3, Vector3};

/// Position, velocity and effort limits of one joint.
///
/// Empty vectors mean "unlimited"; otherwise `lower`/`upper` have the joint's nq entries
/// and `velocity`/`effort` its nv entries.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct JointLimits {
    /// Lower position limits (nq, or empty).
    pub lower: Vec<f64>,
    /// Upper position limits (nq, or empty).
    pub upper: Vec<f64>,
    /// Velocity limits (nv, or empty).
    pub velocity: Vec<f64>,
    /// Effort limits (nv, or empty).
    pub effort: Vec<f64>,
}

impl JointLimits {
    /// No limits.
    #[must_use]
    pub fn unlimited() -> Self {
        Self::default()
    }

    /// Limits of a one-degree-of-freedom joint.
    #[must_use]
    pub fn scalar(lower: f64, upper: f64, velocity: f64, effort: f64) -> Self {
        Self {
            lower: vec![lower],
            upper: vec![upper],
            velocity: vec![velocity],
            effort: vec![effort],
        }
    }
}

#[derive(Clone, Debug)]
struct JointSpec {
    name: String,
    parent: JointIndex,
    jtype: JointType,
    placement: SE3,
    limits: JointLimits,
    inertia: Inertia,
}

/// Builds a [`Model`] joint by joint, validating every input.
///
/// Joint 0 (the universe) and frame 0 (`"universe"`) exist from the start; each joint
/// must be added after its parent, so `parents[i] < i` holds.
///
/// # Examples
/// ```
/// use moma::multibody::{JointIndex, JointLimits, JointType, ModelBuilder};
/// use moma::spatial::{Inertia, SE3};
/// use nalgebra::{Matrix3, Vector3};
///
/// let mut b = ModelBuilder::new("arm2");
/// let link = Inertia::new(1.0, Vector3::new(0.5, 0.0, 0.0), Matrix3::identity() * 0.01);
/// let j1 = b.add_joint(JointIndex(0), "shoulder", JointType::RevoluteZ, SE3::identity(),
///                      JointLimits::unlimited()).unwrap();
/// b.append_body_inertia(j1, &link, &SE3::identity()).unwrap();
/// let j2 = b.add_joint(j1, "elbow", JointType::RevoluteZ,
///                      SE3::from_translation(Vector3::new(1.0, 0.0, 0.0)),
///                      JointLimits::unlimited()).unwrap();
/// b.append_body_inertia(j2, &link, &SE3::identity()).unwrap();
/// let model = b.build().unwrap();
/// assert_eq!((model.nq, model.nv, model.njoints), (2, 2, 3));
/// assert_eq!(model.total_mass(), 2.0);
/// ```
#[derive(Clone, Debug)]
pub struct ModelBuilder {
    name: String,
    joints: Vec<JointSpec>,
    frames: Vec<Frame>,
    gravity: Vector3<f64>,
    root: RootJoint,
}

fn check_se3(field: &str, m: &SE3) -> Result<()> {
    crate::error::ensure_finite(field, m.rotation.iter().chain(m.translation.iter()))?;
    let should_be_identity = m.rotation.transpose() * m.rotation - Matrix3::identity();
    if should_be_identity.norm() > 1e-9 || m.rotation.determinant() < 0.0 {
        return Err(Error::invalid(
            field,
            "rotation is not a proper rotation matrix",
        ));
    }
    Ok(())
}

impl ModelBuilder {
    /// A new builder holding only the universe.
    #[must_use]
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            joints: vec![JointSpec {
                name: "universe".into(),
                parent: JointIndex(0),
                jtype: JointType::RevoluteZ,
                placement: SE3::identity(),
                limits: JointLimits::unlimited(),
                inertia: Inertia::zero(),
            }],
            frames: vec![Frame {
                name: "universe".into(),
                parent_joint: JointIndex(0),
                parent_frame: FrameIndex(0),
                placement: SE3::identity(),
                kind: FrameKind::Universe,
            }],
            gravity: Vector3::new(0.0, 0.0, -9.81),
            root: RootJoint::Fixed,
        }
    }

    /// Sets gravity (world axes, m/s²).
    pub fn set_gravity(&mut self, g: Vector3<f64>) -> &mut Self {
        self.gravity = g;
        self
    }

    /// Records which root the model was built with (reported by `Model::root`).
    pub fn set_root(&mut self, root: RootJoint) -> &mut Self {
        self.root = root;
        self
    }

    /// Number of frames so far (including the universe).
    #[must_use]
    pub fn nframes(&self) -> usize {
        self.frames.len()
    }

    /// Number of joints so far (including the universe).
    #[must_use]
    pub fn njoints(&self) -> usize {
        self.joints.len()
    }

    /// Adds a joint under `parent`, placed at `placement` (`parent_from_joint` at q = 0),
    /// and its joint frame (same name). Returns the new joint's index.
    ///
    /// # Errors
    /// Unknown parent, duplicate joint name, non-finite or non-rigid placement, limit
    /// vectors of the wrong length, NaN limits or lower > upper.
    pub fn add_joint(
        &mut self,
        parent: JointIndex,
        name: &str,
        jtype: JointType,
        placement: SE3,
        limits: JointLimits,
    ) -> Result<JointIndex> {
        if parent.0 >= self.joints.len() {
            return Err(Error::invalid(
                format!("joint '{name}' parent"),
                format!("joint index {} does not exist", parent.0),
            ));
        }
        if name.is_empty() {
            return Err(Error::invalid("joint name", "must not be empty"));
        }
        if self.joints.iter().any(|j| j.name == name) {
            return Err(Error::invalid(
                format!("joint '{name}'"),
                "a joint with this name already exists",
            ));
        }
        if let Some(axis) = jtype.axis() {
            crate::error::ensure_finite(&format!("joint '{name}' axis"), axis.iter())?;
        }
        check_se3(&format!("joint '{name}' placement"), &placement)?;
        let (nq, nv) = (jtype.nq(), jtype.nv());
        for (field, v, n) in [
            ("lower", &limits.lower, nq),
            ("upper", &limits.upper, nq),
            ("velocity", &limits.velocity, nv),
            ("effort", &limits.effort, nv),
        ] {
            if !v.is_empty() {
                crate::error::ensure_len(&format!("joint '{name}' limits.{field}"), n, v.len())?;
                if v.iter().any(|x| x.is_nan()) {
                    return Err(Error::NonFinite {
                        field: format!("joint '{name}' limits.{field}"),
                    });
                }
            }
        }
        if !limits.lower.is_empty() && !limits.upper.is_empty() {
            for (lo, hi) in limits.lower.iter().zip(&limits.upper) {
                if lo > hi {
                    return Err(Error::invalid(
                        format!("joint '{name}' limits"),
                        format!("lower limit {lo} exceeds upper limit {hi}"),
                    ));
                }
            }
        }
        let id = JointIndex(self.joints.len());
        self.joints.push(JointSpec {
            name: name.to_string(),
            parent,
            jtype,
            placement,
            limits,
            inertia: Inertia::zero(),
        });
        let parent_frame = self.joint_frame_of(parent);
        self.frames.push(Frame {
            name: name.to_string(),
            parent_joint: id,
            parent_frame,
            placement: SE3::identity(),
            kind: FrameKind::Joint,
        });
        Ok(id)
    }

    fn joint_frame_of(&self, joint: JointIndex) -> FrameIndex {
        self.frames
            .iter()
            .position(|f| {
                f.parent_joint == joint && matches!(f.kind, FrameKind::Joint | FrameKind::Universe)
            })
            .map_or(FrameIndex(0), FrameIndex)
    }

    /// Adds `inertia`, given in a frame placed at `placement` in `joint`'s frame, to the
    /// body carried by `joint` (this is how fixed joints merge links into their parent).
    ///
    /// # Errors
    /// Unknown joint, non-finite inertia or placement, negative mass.
    pub fn append_body_inertia(
        &mut self,
        joint: JointIndex,
        inertia: &Inertia,
        placement: &SE3,
    ) -> Result<()> {
        let Some(spec) = self.joints.get(joint.0) else {
            return Err(Error::invalid(
                "body inertia joint",
                format!("joint index {} does not exist", joint.0),
            ));
        };
        let field = format!("body inertia of joint '{}'", spec.name);
        if !inertia.is_finite() {
            return Err(Error::NonFinite { field });
        }
        if inertia.mass() < 0.0 {
            return Err(Error::invalid(field, "negative mass"));
        }
        check_se3(&field, placement)?;
        self.joints[joint.0].inertia += inertia.transformed(placement);
        Ok(())
    }

    /// Adds a frame attached to `parent_joint` at `placement` (`joint_from_frame`);
    /// `parent_frame` records the frame it hangs from in the source tree.
    ///
    /// # Errors
    /// Unknown joint or parent frame, a frame of the same kind and name already exists,
    /// non-finite placement.
    pub fn add_frame(
        &mut self,
        name: &str,
        parent_joint: JointIndex,
        parent_frame: FrameIndex,
        placement: SE3,
        kind: FrameKind,
    ) -> Result<FrameIndex> {
        if parent_joint.0 >= self.joints.len() {
            return Err(Error::invalid(
                format!("frame '{name}' parent joint"),
                format!("joint index {} does not exist", parent_joint.0),
            ));
        }
        if parent_frame.0 >= self.frames.len() {
            return Err(Error::invalid(
                format!("frame '{name}' parent frame"),
                format!("frame index {} does not exist", parent_frame.0),
            ));
        }
        if self.frames.iter().any(|f| f.name == name && f.kind == kind) {
            return Err(Error::invalid(
                format!("frame '{name}'"),
                format!("a {} frame with this name already exists", kind.name()),
            ));
        }
        check_se3(&format!("frame '{name}' placement"), &placement)?;
        self.frames.push(Frame {
            name: name.to_string(),
            parent_joint,
            parent_frame,
            placement,
            kind,
        });
        Ok(FrameIndex(self.frames.len() - 1))
    }

    /// Validates and returns the model.
    ///
    /// # Errors
    /// Non-finite gravity; a body (the merged inertia of everything rigidly attached to
    /// one joint) whose spatial inertia is not positive semidefinite: its rotational
    /// inertia about its centre of mass has an eigenvalue below
    /// −[`MERGED_INERTIA_REL_TOL`] · trace (round-off only). The algorithms need every
    /// body inertia positive semidefinite for the joint-space inertia matrix to be
    /// positive definite.
    pub fn build(self) -> Result<Model> {
        crate::error::ensure_finite("gravity", self.gravity.iter())?;
        for j in self.joints.iter().skip(1) {
            check_body_inertia(&j.name, &j.inertia)?;
        }
        let njoints = self.joints.len();
        let mut idx_q = vec![0; njoints];
        let mut idx_v = vec![0; njoints];
        let mut nqs = vec![0; njoints];
        let mut nvs = vec![0; njoints];
        let (mut nq, mut nv) = (0, 0);
        for (i, j) in self.joints.iter().enumerate().skip(1) {
            idx_q[i] = nq;
            idx_v[i] = nv;
            nqs[i] = j.jtype.nq();
            nvs[i] = j.jtype.nv();
            nq += nqs[i];
            nv += nvs[i];
        }
        let mut lower = DVector::from_element(nq, f64::NEG_INFINITY);
        let mut upper = DVector::from_element(nq, f64::INFINITY);
        let mut vel = DVector::from_element(nv, f64::INFINITY);
        let mut eff = DVector::from_element(nv, f64::INFINITY);
        let mut joint_of_dof = vec![JointIndex(0); nv];
        for (i, j) in self.joints.iter().enumerate().skip(1) {
            for k in 0..nqs[i] {
                if !j.limits.lower.is_empty() {
                    lower[idx_q[i] + k] = j.limits.lower[k];
                }
                if !j.limits.upper.is_empty() {
                    upper[idx_q[i] + k] = j.limits.upper[k];
                }
            }
            for k in 0..nvs[i] {
                if !j.limits.velocity.is_empty() {
                    vel[idx_v[i] + k] = j.limits.velocity[k];
                }
                if !j.limits.effort.is_empty() {
                    eff[idx_v[i] + k] = j.limits.effort[k];
                }
                joint_of_dof[idx_v[i] + k] = JointIndex(i);
            }
        }
        let last_link = last_body_frame(&self.frames);
        Ok(Model {
            last_link,
            name: self.name,
            nq,
            nv,
            njoints,
            names: self.joints.iter().map(|j| j.name.clone()).collect(),
            parents: self.joints.iter().map(|j| j.parent).collect(),
            joint_types: self.joints.iter().map(|j| j.jtype).collect(),
            idx_q,
            idx_v,
            nqs,
            nvs,
            joint_placements: self.joints.iter().map(|j| j.placement).collect(),
            inertias: self.joints.iter().map(|j| j.inertia).collect(),
            frames: self.frames,
            gravity: self.gravity,
            lower_position_limit: lower,
            upper_position_limit: upper,
            velocity_limit: vel,
            effort_limit: eff,
            joint_of_dof,
            root: self.root,
        })
    }
}

/// Relative round-off tolerated in a merged body's rotational inertia about its centre
/// of mass (relative to the trace of its inertia about the joint origin).
pub const MERGED_INERTIA_REL_TOL: f64 = 1e-9;

/// The body of joint `name` has a positive semidefinite spatial inertia (mass ≥ 0 is
/// checked where inertias are added).
fn check_body_inertia(name: &str, inertia: &Inertia) -> Result<()> {
    let ic = inertia.inertia_about_com();
    let scale = inertia.inertia_about_origin().trace().abs();
    let e = ic.symmetric_eigenvalues();
    if e.min() < -MERGED_INERTIA_REL_TOL * scale || (scale == 0.0 && e.min() < 0.0) {
        return Err(Error::invalid(
            format!("body inertia of joint '{name}'"),
            format!(
                "the merged rigid body is not positive semidefinite (eigenvalues about its \
                 centre of mass {:.3e}, {:.3e}, {:.3e} kg·m²): the joint-space inertia \
                 matrix would not be positive definite",
                e[0], e[1], e[2]
            ),
        ));
    }
    Ok(())
}

fn last_body_frame(frames: &[Frame]) -> FrameIndex {
    frames
        .iter()
        .rposition(|f| f.kind == FrameKind::Body)
        .map_or(FrameIndex(frames.len().saturating_sub(1)), FrameIndex)
}

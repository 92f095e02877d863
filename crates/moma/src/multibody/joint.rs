//! Joint types and their per-joint kernels (transform, motion subspace, bias).

use crate::spatial::{Force, Motion, SE3};
use crate::{Error, Result};
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

/// Index of a joint in a [`Model`](super::Model) (joint 0 is the universe).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct JointIndex(pub usize);

/// Index of a frame in a [`Model`](super::Model) (frame 0 is the universe).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct FrameIndex(pub usize);

/// The kind of a joint (a closed set, dispatched by `match`).
///
/// Revolute and prismatic joints about an axis that is exactly a unit axis of the joint
/// frame get their own variant (`RevoluteZ`, ...), whose kernels exploit the sparsity of
/// the motion subspace; [`JointType::revolute`] and [`JointType::prismatic`] pick them.
/// Fixed joints are not joints of the model: they merge their child link into the parent
/// body and add a frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum JointType {
    /// Revolute about the joint frame's x axis; `q = [θ]`, `v = [θ̇]`.
    RevoluteX,
    /// Revolute about the joint frame's y axis.
    RevoluteY,
    /// Revolute about the joint frame's z axis.
    RevoluteZ,
    /// Revolute about a unit `axis` of the joint frame.
    RevoluteUnaligned {
        /// Unit rotation axis in the joint frame.
        axis: Vector3<f64>,
    },
    /// Prismatic along the joint frame's x axis; `q = [d]` (m), `v = [ḋ]`.
    PrismaticX,
    /// Prismatic along the joint frame's y axis.
    PrismaticY,
    /// Prismatic along the joint frame's z axis.
    PrismaticZ,
    /// Prismatic along a unit `axis` of the joint frame.
    PrismaticUnaligned {
        /// Unit translation axis in the joint frame.
        axis: Vector3<f64>,
    },
    /// Planar mobile base moving in the parent's x–y plane: q = [x, y, θ],
    /// v = [ẋ, ẏ, θ̇] in the PARENT (world) axes; nq = nv = 3.
    Planar,
    /// Free-flying base: q = [x, y, z, qx, qy, qz, qw] (position in the parent frame, unit
    /// quaternion), v = [v; ω], the base twist in the BASE frame (as Pinocchio); nq = 7,
    /// nv = 6.
    FreeFlyer,
}

fn unit_axis(axis: Vector3<f64>, what: &str) -> Result<Vector3<f64>> {
    let n = axis.norm();
    if !n.is_finite() || n < 1e-12 {
        return Err(Error::invalid(
            format!("{what} axis"),
            format!(
                "must be a finite non-zero vector, got [{}, {}, {}]",
                axis.x, axis.y, axis.z
            ),
        ));
    }
    Ok(axis / n)
}

const AXIS_TOL: f64 = 1e-12;

impl JointType {
    /// A revolute joint about `axis` (normalised); aligned axes give the specialised
    /// variants.
    ///
    /// # Errors
    /// If the axis is zero or not finite.
    pub fn revolute(axis: Vector3<f64>) -> Result<Self> {
        let a = unit_axis(axis, "revolute joint")?;
        Ok(if (a - Vector3::x()).norm() < AXIS_TOL {
            JointType::RevoluteX
        } else if (a - Vector3::y()).norm() < AXIS_TOL {
            JointType::RevoluteY
        } else if (a - Vector3::z()).norm() < AXIS_TOL {
            JointType::RevoluteZ
        } else {
            JointType::RevoluteUnaligned { axis: a }
        })
    }

    /// A prismatic joint along `axis` (normalised).
    ///
    /// # Errors
    /// If the axis is zero or not finite.
    pub fn prismatic(axis: Vector3<f64>) -> Result<Self> {
        let a = unit_axis(axis, "prismatic joint")?;
        Ok(if (a - Vector3::x()).norm() < AXIS_TOL {
            JointType::PrismaticX
        } else if (a - Vector3::y()).norm() < AXIS_TOL {
            JointType::PrismaticY
        } else if (a - Vector3::z()).norm() < AXIS_TOL {
            JointType::PrismaticZ
        } else {
            JointType::PrismaticUnaligned { axis: a }
        })
    }

    /// Number of configuration coordinates nq of this joint.
    #[must_use]
    pub fn nq(&self) -> usize {
        match self {
            JointType::Planar => 3,
            JointType::FreeFlyer => 7,
            _ => 1,
        }
    }

    /// Number of velocity coordinates nv of this joint.
    #[must_use]
    pub fn nv(&self) -> usize {
        match self {
            JointType::Planar => 3,
            JointType::FreeFlyer => 6,
            _ => 1,
        }
    }

    /// Stable short name (`revolute_z`, `prismatic_unaligned`, `planar`, `free_flyer`...).
    #[must_use]
    pub fn name(&self) -> &'static str {
        match self {
            JointType::RevoluteX => "revolute_x",
            JointType::RevoluteY => "revolute_y",
            JointType::RevoluteZ => "revolute_z",
            JointType::RevoluteUnaligned { .. } => "revolute_unaligned",
            JointType::PrismaticX => "prismatic_x",
            JointType::PrismaticY => "prismatic_y",
            JointType::PrismaticZ => "prismatic_z",
            JointType::PrismaticUnaligned { .. } => "prismatic_unaligned",
            JointType::Planar => "planar",
            JointType::FreeFlyer => "free_flyer",
        }
    }

    /// True for revolute joints (any axis).
    #[must_use]
    pub fn is_revolute(&self) -> bool {
        matches!(
            self,
            JointType::RevoluteX
                | JointType::RevoluteY
                | JointType::RevoluteZ
                | JointType::RevoluteUnaligned { .. }
        )
    }

    /// True for prismatic joints (any axis).
    #[must_use]
    pub fn is_prismatic(&self) -> bool {
        matches!(
            self,
            JointType::PrismaticX
                | JointType::PrismaticY
                | JointType::PrismaticZ
                | JointType::PrismaticUnaligned { .. }
        )
    }

    /// The unit axis of a revolute or prismatic joint (in the joint frame).
    #[must_use]
    pub fn axis(&self) -> Option<Vector3<f64>> {
        match self {
            JointType::RevoluteX | JointType::PrismaticX => Some(Vector3::x()),
            JointType::RevoluteY | JointType::PrismaticY => Some(Vector3::y()),
            JointType::RevoluteZ | JointType::PrismaticZ => Some(Vector3::z()),
            JointType::RevoluteUnaligned { axis } | JointType::PrismaticUnaligned { axis } => {
                Some(*axis)
            }
            _ => None,
        }
    }

    /// The one coordinate of a twist `[v; ω]` (0–2 linear, 3–5 angular) that the motion
    /// subspace of an axis-aligned prismatic or revolute joint spans; `None` for the other
    /// kinds. RNEA (one state or many) adds and crosses such a joint's twist `q̇·e_k` by
    /// that coordinate alone: the values of the full products, except that exactly-zero
    /// terms are not added (at most the sign of a zero result differs).
    #[inline]
    #[must_use]
    pub fn axis_slot(&self) -> Option<usize> {
        match self {
            JointType::PrismaticX => Some(0),
            JointType::PrismaticY => Some(1),
            JointType::PrismaticZ => Some(2),
            JointType::RevoluteX => Some(3),
            JointType::RevoluteY => Some(4),
            JointType::RevoluteZ => Some(5),
            _ => None,
        }
    }

    /// `parent_from_joint = placement · J(q)`: the joint placement (in its parent joint's
    /// frame) composed with the joint's own motion for configuration `q` (its nq entries).
    #[inline]
    #[must_use]
    pub fn parent_from_joint(&self, placement: &SE3, q: &[f64]) -> SE3 {
        let r = &placement.rotation;
        match *self {
            JointType::RevoluteX => {
                let (s, c) = crate::spatial::trig::sin_cos(q[0]);
                let c1 = r.column(1) * c + r.column(2) * s;
                let c2 = r.column(2) * c - r.column(1) * s;
                SE3::new(
                    Matrix3::from_columns(&[r.column(0).into(), c1, c2]),
                    placement.translation,
                )
            }
            JointType::RevoluteY => {
                let (s, c) = crate::spatial::trig::sin_cos(q[0]);
                let c0 = r.column(0) * c - r.column(2) * s;
                let c2 = r.column(0) * s + r.column(2) * c;
                SE3::new(
                    Matrix3::from_columns(&[c0, r.column(1).into(), c2]),
                    placement.translation,
                )
            }
            JointType::RevoluteZ => {
                let (s, c) = crate::spatial::trig::sin_cos(q[0]);
                let c0 = r.column(0) * c + r.column(1) * s;
                let c1 = r.column(1) * c - r.column(0) * s;
                SE3::new(
                    Matrix3::from_columns(&[c0, c1, r.column(2).into()]),
                    placement.translation,
                )
            }
            JointType::RevoluteUnaligned { axis } => {
                SE3::new(r * axis_rotation(&axis, q[0]), placement.translation)
            }
            JointType::PrismaticX => SE3::new(*r, placement.translation + r.column(0) * q[0]),
            JointType::PrismaticY => SE3::new(*r, placement.translation + r.column(1) * q[0]),
            JointType::PrismaticZ => SE3::new(*r, placement.translation + r.column(2) * q[0]),
            JointType::PrismaticUnaligned { axis } => {
                SE3::new(*r, placement.translation + r * (axis * q[0]))
            }
            JointType::Planar => {
                let (s, c) = crate::spatial::trig::sin_cos(q[2]);
                let rz = Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
                placement.compose(&SE3::new(rz, Vector3::new(q[0], q[1], 0.0)))
            }
            JointType::FreeFlyer => placement.compose(&free_flyer_transform(q)),
        }
    }

    /// Joint velocity `S(q)·v` in the joint frame (`v`: its nv entries).
    #[inline]
    #[must_use]
    pub fn motion(&self, q: &[f64], v: &[f64]) -> Motion {
        let z = Vector3::zeros();
        match *self {
            JointType::RevoluteX => Motion::new(z, Vector3::new(v[0], 0.0, 0.0)),
            JointType::RevoluteY => Motion::new(z, Vector3::new(0.0, v[0], 0.0)),
            JointType::RevoluteZ => Motion::new(z, Vector3::new(0.0, 0.0, v[0])),
            JointType::RevoluteUnaligned { axis } => Motion::new(z, axis * v[0]),
            JointType::PrismaticX => Motion::new(Vector3::new(v[0], 0.0, 0.0), z),
            JointType::PrismaticY => Motion::new(Vector3::new(0.0, v[0], 0.0), z),
            JointType::PrismaticZ => Motion::new(Vector3::new(0.0, 0.0, v[0]), z),
            JointType::PrismaticUnaligned { axis } => Motion::new(axis * v[0], z),
            JointType::Planar => {
                let (s, c) = crate::spatial::trig::sin_cos(q[2]);
                Motion::new(
                    Vector3::new(c * v[0] + s * v[1], -s * v[0] + c * v[1], 0.0),
                    Vector3::new(0.0, 0.0, v[2]),
                )
            }
            JointType::FreeFlyer => Motion::new(
                Vector3::new(v[0], v[1], v[2]),
                Vector3::new(v[3], v[4], v[5]),
            ),
        }
    }

    /// Joint bias acceleration `c_J = Ṡ(q)·v` in the joint frame (zero except for the
    /// planar base, whose velocity is expressed in world axes).
    #[inline]
    #[must_use]
    pub fn bias(&self, q: &[f64], v: &[f64]) -> Motion {
        match *self {
            JointType::Planar => {
                let (s, c) = crate::spatial::trig::sin_cos(q[2]);
                let vx = c * v[0] + s * v[1];
                let vy = -s * v[0] + c * v[1];
                // −ω × v_local with ω = θ̇ ẑ
                Motion::new(Vector3::new(v[2] * vy, -v[2] * vx, 0.0), Vector3::zeros())
            }
            _ => Motion::zero(),
        }
    }

    /// True when `c_J` can be non-zero.
    #[inline]
    #[must_use]
    pub fn has_bias(&self) -> bool {
        matches!(self, JointType::Planar)
    }

    /// Column `k` of the motion subspace S(q) (the joint-frame twist of unit velocity k).
    #[inline]
    #[must_use]
    pub fn subspace_column(&self, q: &[f64], k: usize) -> Motion {
        match *self {
            JointType::Planar => {
                let (s, c) = crate::spatial::trig::sin_cos(q[2]);
                match k {
                    0 => Motion::new(Vector3::new(c, -s, 0.0), Vector3::zeros()),
                    1 => Motion::new(Vector3::new(s, c, 0.0), Vector3::zeros()),
                    _ => Motion::new(Vector3::zeros(), Vector3::z()),
                }
            }
            JointType::FreeFlyer => {
                let mut m = Motion::zero();
                if k < 3 {
                    m.linear[k] = 1.0;
                } else {
                    m.angular[k - 3] = 1.0;
                }
                m
            }
            _ => self.motion(q, &[1.0]),
        }
    }

    /// `Sᵀ f` for a one-degree-of-freedom joint (revolute or prismatic).
    #[inline]
    #[must_use]
    pub fn project_force_1dof(&self, f: &Force) -> f64 {
        match *self {
            JointType::RevoluteX => f.angular.x,
            JointType::RevoluteY => f.angular.y,
            JointType::RevoluteZ => f.angular.z,
            JointType::RevoluteUnaligned { axis } => axis.dot(&f.angular),
            JointType::PrismaticX => f.linear.x,
            JointType::PrismaticY => f.linear.y,
            JointType::PrismaticZ => f.linear.z,
            JointType::PrismaticUnaligned { axis } => axis.dot(&f.linear),
            _ => f64::NAN,
        }
    }

    /// `Sᵀ f` written into `out` (nv entries).
    #[inline]
    pub fn project_force(&self, q: &[f64], f: &Force, out: &mut [f64]) {
        match *self {
            JointType::Planar => {
                let (s, c) = crate::spatial::trig::sin_cos(q[2]);
                out[0] = c * f.linear.x - s * f.linear.y;
                out[1] = s * f.linear.x + c * f.linear.y;
                out[2] = f.angular.z;
            }
            JointType::FreeFlyer => {
                out[0] = f.linear.x;
                out[1] = f.linear.y;
                out[2] = f.linear.z;
                out[3] = f.angular.x;
                out[4] = f.angular.y;
                out[5] = f.angular.z;
            }
            _ => out[0] = self.project_force_1dof(f),
        }
    }
}

/// Rotation of angle `theta` about the unit `axis` (Rodrigues).
#[must_use]
pub fn axis_rotation(axis: &Vector3<f64>, theta: f64) -> Matrix3<f64> {
    let (s, c) = crate::spatial::trig::sin_cos(theta);
    let k = crate::spatial::skew(axis);
    Matrix3::identity() + k * s + k * k * (1.0 - c)
}

/// Base pose of a free-flyer configuration `[x, y, z, qx, qy, qz, qw]` (the quaternion is
/// normalised).
#[must_use]
pub fn free_flyer_transform(q: &[f64]) -> SE3 {
    let quat = UnitQuaternion::from_quaternion(Quaternion::new(q[6], q[3], q[4], q[5]));
    SE3::new(
        *quat.to_rotation_matrix().matrix(),
        Vector3::new(q[0], q[1], q[2]),
    )
}

//! Rigid transforms stored as a rotation matrix and a translation.

use super::{Force, Inertia, Motion};
use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// A rigid transform `a_from_b` (an element of SE(3)): `p_a = rotation · p_b + translation`.
///
/// Stored as a 3 × 3 rotation matrix and a translation (the layout Pinocchio uses), which
/// makes the spatial actions on [`Motion`], [`Force`] and [`Inertia`] cheap. Convert to and
/// from nalgebra's [`Isometry3`] with [`SE3::to_isometry`] and [`SE3::from_isometry`].
#[doc(alias = "Isometry")]
#[doc(alias = "Transform")]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SE3 {
    /// Rotation matrix R (orientation of frame `b` in frame `a`).
    pub rotation: Matrix3<f64>,
    /// Translation p (origin of frame `b` in frame `a`), metres.
    pub translation: Vector3<f64>,
}

impl Default for SE3 {
    fn default() -> Self {
        Self::identity()
    }
}

impl SE3 {
    /// The identity transform.
    #[must_use]
    pub fn identity() -> Self {
        Self {
            rotation: Matrix3::identity(),
            translation: Vector3::zeros(),
        }
    }

    /// A transform from a rotation matrix and a translation (the matrix is trusted to be
    /// a rotation).
    #[must_use]
    pub fn new(rotation: Matrix3<f64>, translation: Vector3<f64>) -> Self {
        Self {
            rotation,
            translation,
        }
    }

    /// A pure translation.
    #[must_use]
    pub fn from_translation(translation: Vector3<f64>) -> Self {
        Self {
            rotation: Matrix3::identity(),
            translation,
        }
    }

    /// The URDF `<origin xyz rpy>` transform: rotation `Rz(yaw)·Ry(pitch)·Rx(roll)`.
    #[must_use]
    pub fn from_xyz_rpy(xyz: [f64; 3], rpy: [f64; 3]) -> Self {
        Self {
            rotation: rotation_from_rpy(rpy[0], rpy[1], rpy[2]),
            translation: Vector3::from(xyz),
        }
    }

    /// Converts from an nalgebra isometry.
    #[must_use]
    pub fn from_isometry(iso: &Isometry3<f64>) -> Self {
        Self {
            rotation: *iso.rotation.to_rotation_matrix().matrix(),
            translation: iso.translation.vector,
        }
    }

    /// Converts to an nalgebra isometry (the rotation is re-orthonormalised through a
    /// quaternion).
    #[must_use]
    pub fn to_isometry(&self) -> Isometry3<f64> {
        let rot = Rotation3::from_matrix_unchecked(self.rotation);
        Isometry3::from_parts(
            Translation3::from(self.translation),
            UnitQuaternion::from_rotation_matrix(&rot),
        )
    }

    /// Unit quaternion of the rotation.
    #[must_use]
    pub fn quaternion(&self) -> UnitQuaternion<f64> {
        UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(self.rotation))
    }

    /// The inverse transform `b_from_a`.
    #[must_use]
    pub fn inverse(&self) -> Self {
        let rt = self.rotation.transpose();
        Self {
            rotation: rt,
            translation: -(rt * self.translation),
        }
    }

    /// Composition `self · other` (`a_from_b · b_from_c = a_from_c`).
    #[inline]
    #[must_use]
    pub fn compose(&self, other: &SE3) -> SE3 {
        SE3 {
            rotation: self.rotation * other.rotation,
            translation: self.rotation * other.translation + self.translation,
        }
    }

    /// `self⁻¹ · other` without forming the inverse (`b_from_a⁻¹ · ...`).
    #[inline]
    #[must_use]
    pub fn inverse_compose(&self, other: &SE3) -> SE3 {
        let rt = self.rotation.transpose();
        SE3 {
            rotation: rt * other.rotation,
            translation: rt * (other.translation - self.translation),
        }
    }

    /// Maps a point of frame `b` into frame `a`.
    #[inline]
    #[must_use]
    pub fn act_point(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rotation * p + self.translation
    }

    /// Maps a point of frame `a` into frame `b`.
    #[inline]
    #[must_use]
    pub fn inverse_act_point(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.rotation.tr_mul(&(p - self.translation))
    }

    /// Expresses in frame `a` a twist given in frame `b` (the adjoint action `Ad_M v`).
    #[doc(alias = "Ad")]
    #[inline]
    #[must_use]
    pub fn act_motion(&self, m: &Motion) -> Motion {
        let angular = self.rotation * m.angular;
        Motion {
            linear: self.rotation * m.linear + self.translation.cross(&angular),
            angular,
        }
    }

    /// Expresses in frame `b` a twist given in frame `a` (`Ad_M⁻¹ v`).
    #[inline]
    #[must_use]
    pub fn inverse_act_motion(&self, m: &Motion) -> Motion {
        Motion {
            linear: self
                .rotation
                .tr_mul(&(m.linear - self.translation.cross(&m.angular))),
            angular: self.rotation.tr_mul(&m.angular),
        }
    }

    /// Expresses in frame `a` a wrench given in frame `b` (the dual action `Ad_M⁻ᵀ f`).
    #[inline]
    #[must_use]
    pub fn act_force(&self, f: &Force) -> Force {
        let linear = self.rotation * f.linear;
        Force {
            angular: self.rotation * f.angular + self.translation.cross(&linear),
            linear,
        }
    }

    /// Expresses in frame `b` a wrench given in frame `a`.
    #[inline]
    #[must_use]
    pub fn inverse_act_force(&self, f: &Force) -> Force {
        Force {
            linear: self.rotation.tr_mul(&f.linear),
            angular: self
                .rotation
                .tr_mul(&(f.angular - self.translation.cross(&f.linear))),
        }
    }

    /// Expresses in frame `a` a spatial inertia given in frame `b`.
    #[inline]
    #[must_use]
    pub fn act_inertia(&self, inertia: &Inertia) -> Inertia {
        inertia.transformed(self)
    }
}

impl std::ops::Mul for SE3 {
    type Output = SE3;
    fn mul(self, rhs: SE3) -> SE3 {
        self.compose(&rhs)
    }
}

impl std::ops::Mul<&SE3> for &SE3 {
    type Output = SE3;
    fn mul(self, rhs: &SE3) -> SE3 {
        self.compose(rhs)
    }
}

/// Rotation matrix of URDF roll-pitch-yaw angles: `Rz(yaw)·Ry(pitch)·Rx(roll)`.
#[must_use]
pub fn rotation_from_rpy(roll: f64, pitch: f64, yaw: f64) -> Matrix3<f64> {
    let (sr, cr) = roll.sin_cos();
    let (sp, cp) = pitch.sin_cos();
    let (sy, cy) = yaw.sin_cos();
    Matrix3::new(
        cy * cp,
        cy * sp * sr - sy * cr,
        cy * sp * cr + sy * sr,
        sy * cp,
        sy * sp * sr + cy * cr,
        sy * sp * cr - cy * sr,
        -sp,
        cp * sr,
        cp * cr,
    )
}

/// Roll-pitch-yaw angles of a rotation matrix (inverse of [`rotation_from_rpy`]; pitch in
/// [−π/2, π/2]).
#[must_use]
pub fn rpy_from_rotation(r: &Matrix3<f64>) -> [f64; 3] {
    let pitch = (-r[(2, 0)]).atan2((r[(0, 0)].powi(2) + r[(1, 0)].powi(2)).sqrt());
    let roll = r[(2, 1)].atan2(r[(2, 2)]);
    let yaw = r[(1, 0)].atan2(r[(0, 0)]);
    [roll, pitch, yaw]
}

const SMALL_ANGLE: f64 = 1e-4;

/// Rotation matrix `exp([ω]×)` of a rotation vector ω (Rodrigues).
#[must_use]
pub fn exp3(w: &Vector3<f64>) -> Matrix3<f64> {
    let t2 = w.norm_squared();
    let t = t2.sqrt();
    let (a, b) = if t < SMALL_ANGLE {
        (1.0 - t2 / 6.0, 0.5 - t2 / 24.0)
    } else {
        (t.sin() / t, (1.0 - t.cos()) / t2)
    };
    let k = super::skew(w);
    Matrix3::identity() + k * a + k * k * b
}

/// Rotation vector ω = log(R) of a rotation matrix, with |ω| ∈ [0, π].
#[must_use]
pub fn log3(r: &Matrix3<f64>) -> Vector3<f64> {
    let tr = r.trace();
    let cos_t = ((tr - 1.0) * 0.5).clamp(-1.0, 1.0);
    let t = cos_t.acos();
    let vee = Vector3::new(
        r[(2, 1)] - r[(1, 2)],
        r[(0, 2)] - r[(2, 0)],
        r[(1, 0)] - r[(0, 1)],
    );
    if t < SMALL_ANGLE {
        vee * (0.5 * (1.0 + t * t / 6.0))
    } else if t > std::f64::consts::PI - 1e-3 {
        // Near π: axis from the symmetric part R ≈ 2aaᵀ − I (plus a cos θ correction).
        let d = 1.0 - cos_t;
        let mut a = Vector3::new(
            ((r[(0, 0)] - cos_t) / d).max(0.0).sqrt(),
            ((r[(1, 1)] - cos_t) / d).max(0.0).sqrt(),
            ((r[(2, 2)] - cos_t) / d).max(0.0).sqrt(),
        );
        let k = a.imax();
        for j in 0..3 {
            if j != k {
                let sym = r[(k, j)] + r[(j, k)];
                if sym < 0.0 {
                    a[j] = -a[j];
                }
            }
        }
        if a.dot(&vee) < 0.0 {
            a = -a;
        }
        a.normalize() * t
    } else {
        vee * (t / (2.0 * t.sin()))
    }
}

/// Exponential map of SE(3): the transform reached by following the constant body twist
/// `v` for one unit of time (`[linear; angular]`).
#[must_use]
pub fn exp6(v: &Motion) -> SE3 {
    let w = &v.angular;
    let t2 = w.norm_squared();
    let t = t2.sqrt();
    let (b, c) = if t < SMALL_ANGLE {
        (0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0)
    } else {
        ((1.0 - t.cos()) / t2, (t - t.sin()) / (t2 * t))
    };
    let k = super::skew(w);
    let vmat = Matrix3::identity() + k * b + k * k * c;
    SE3::new(exp3(w), vmat * v.linear)
}

/// Logarithm of SE(3): the body twist `v` with `exp6(v) = m`.
#[must_use]
pub fn log6(m: &SE3) -> Motion {
    let w = log3(&m.rotation);
    let t2 = w.norm_squared();
    let t = t2.sqrt();
    let coef = if t < SMALL_ANGLE {
        1.0 / 12.0 + t2 / 720.0
    } else {
        (1.0 - t * t.sin() / (2.0 * (1.0 - t.cos()))) / t2
    };
    let k = super::skew(&w);
    let vinv = Matrix3::identity() - k * 0.5 + k * k * coef;
    Motion::new(vinv * m.translation, w)
}

//! Spatial inertia of a rigid body.

use super::{Force, Motion, SE3, skew};
use nalgebra::{Matrix3, Matrix6, Vector3};

/// Spatial inertia of a rigid body, expressed in some frame.
///
/// Stored as the mass m, the first mass moment h = m·c (c: centre of mass in the frame)
/// and the rotational inertia about the frame origin I_o = I_c − m [c]×² (kg·m²). This
/// makes sums of inertias (composite bodies) component-wise and their action on a twist
/// cheap. Build it from the usual (mass, centre of mass, inertia about the centre of mass)
/// with [`Inertia::new`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Inertia {
    mass: f64,
    first_moment: Vector3<f64>,
    inertia_origin: Matrix3<f64>,
}

impl Default for Inertia {
    fn default() -> Self {
        Self::zero()
    }
}

impl Inertia {
    /// The zero inertia (massless body).
    #[must_use]
    pub fn zero() -> Self {
        Self {
            mass: 0.0,
            first_moment: Vector3::zeros(),
            inertia_origin: Matrix3::zeros(),
        }
    }

    /// From mass m (kg), centre of mass c (m) and rotational inertia about the centre of
    /// mass I_c (kg·m², symmetric; the upper triangle is used).
    #[must_use]
    pub fn new(mass: f64, com: Vector3<f64>, inertia_com: Matrix3<f64>) -> Self {
        let ic = symmetrize(&inertia_com);
        let cx = skew(&com);
        Self {
            mass,
            first_moment: com * mass,
            inertia_origin: ic - cx * cx * mass,
        }
    }

    /// A point mass at `com`.
    #[must_use]
    pub fn point_mass(mass: f64, com: Vector3<f64>) -> Self {
        Self::new(mass, com, Matrix3::zeros())
    }

    /// Mass m (kg).
    #[must_use]
    pub fn mass(&self) -> f64 {
        self.mass
    }

    /// First mass moment h = m·c (kg·m).
    #[must_use]
    pub fn first_moment(&self) -> Vector3<f64> {
        self.first_moment
    }

    /// Centre of mass c (m); the origin for a massless body.
    #[must_use]
    pub fn com(&self) -> Vector3<f64> {
        if self.mass > 0.0 {
            self.first_moment / self.mass
        } else {
            Vector3::zeros()
        }
    }

    /// Rotational inertia about the frame origin I_o (kg·m²).
    #[must_use]
    pub fn inertia_about_origin(&self) -> Matrix3<f64> {
        self.inertia_origin
    }

    /// Rotational inertia about the centre of mass I_c (kg·m²).
    #[must_use]
    pub fn inertia_about_com(&self) -> Matrix3<f64> {
        if self.mass > 0.0 {
            let cx = skew(&self.com());
            self.inertia_origin + cx * cx * self.mass
        } else {
            self.inertia_origin
        }
    }

    /// The spatial momentum `I·v` of a twist `v` (both in this inertia's frame).
    #[inline]
    #[must_use]
    pub fn mul_motion(&self, v: &Motion) -> Force {
        Force {
            linear: v.linear * self.mass - self.first_moment.cross(&v.angular),
            angular: self.inertia_origin * v.angular + self.first_moment.cross(&v.linear),
        }
    }

    /// The inertia expressed in frame `a`, given `a_from_b` and this inertia in `b`.
    #[inline]
    #[must_use]
    pub fn transformed(&self, a_from_b: &SE3) -> Inertia {
        let r = &a_from_b.rotation;
        let p = &a_from_b.translation;
        let rh = r * self.first_moment;
        let rir = r * self.inertia_origin * r.transpose();
        // I_o' = R I_o Rᵀ − [Rh]×[p]× − [p]×[Rh]× − m [p]×²
        let px = skew(p);
        let rhx = skew(&rh);
        let cross = rhx * px;
        Inertia {
            mass: self.mass,
            first_moment: rh + p * self.mass,
            inertia_origin: rir - cross - cross.transpose() - px * px * self.mass,
        }
    }

    /// Kinetic energy ½ vᵀ I v of a twist (J).
    #[must_use]
    pub fn kinetic_energy(&self, v: &Motion) -> f64 {
        0.5 * v.dot(&self.mul_motion(v))
    }

    /// The 6 × 6 matrix `[m·1, −[h]×; [h]×, I_o]` acting on `[linear; angular]` twists.
    #[must_use]
    pub fn to_matrix(&self) -> Matrix6<f64> {
        let mut out = Matrix6::zeros();
        let hx = skew(&self.first_moment);
        out.fixed_view_mut::<3, 3>(0, 0)
            .copy_from(&(Matrix3::identity() * self.mass));
        out.fixed_view_mut::<3, 3>(0, 3).copy_from(&(-hx));
        out.fixed_view_mut::<3, 3>(3, 0).copy_from(&hx);
        out.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&self.inertia_origin);
        out
    }

    /// True when every component is finite.
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.mass.is_finite()
            && self.first_moment.iter().all(|x| x.is_finite())
            && self.inertia_origin.iter().all(|x| x.is_finite())
    }
}

impl std::ops::Add for Inertia {
    type Output = Inertia;
    #[inline]
    fn add(self, o: Inertia) -> Inertia {
        Inertia {
            mass: self.mass + o.mass,
            first_moment: self.first_moment + o.first_moment,
            inertia_origin: self.inertia_origin + o.inertia_origin,
        }
    }
}

impl std::ops::AddAssign for Inertia {
    #[inline]
    fn add_assign(&mut self, o: Inertia) {
        self.mass += o.mass;
        self.first_moment += o.first_moment;
        self.inertia_origin += o.inertia_origin;
    }
}

fn symmetrize(m: &Matrix3<f64>) -> Matrix3<f64> {
    Matrix3::new(
        m[(0, 0)],
        m[(0, 1)],
        m[(0, 2)],
        m[(0, 1)],
        m[(1, 1)],
        m[(1, 2)],
        m[(0, 2)],
        m[(1, 2)],
        m[(2, 2)],
    )
}

impl Force {
    /// Shorthand for `inertia.mul_motion(v)`.
    #[must_use]
    pub fn momentum(inertia: &Inertia, v: &Motion) -> Force {
        inertia.mul_motion(v)
    }
}

//! Spatial inertia of a rigid body.

use super::{Force, Motion, SE3, skew};
use nalgebra::{Matrix3, Matrix6, Vector3};

/// Spatial inertia of a rigid body, expressed in some frame.
///
/// Stored as the mass m, the first mass moment h = m·c (c: centre of mass in the frame)
/// and the rotational inertia about the frame origin `I_o = I_c − m [c]×²` (kg·m²). This
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
    #[inline(always)]
    #[must_use]
    pub fn transformed(&self, a_from_b: &SE3) -> Inertia {
        let r = &a_from_b.rotation;
        let p = &a_from_b.translation;
        let rh = r * self.first_moment;
        let m = self.mass;
        let mp = p * m;
        // I_o' = R I_o Rᵀ − ([Rh]×[p]× + [p]×[Rh]×) − m [p]×², with [a]×[b]× = b aᵀ − (a·b) 1:
        //      = R I_o Rᵀ − (p gᵀ + g pᵀ) + 2 (g·p) 1, with g = Rh + m p / 2.
        let g = rh + mp * 0.5;
        let s = &self.inertia_origin;
        let (d0, d1, d2, d3, d4, d5) = (
            s[(0, 0)],
            s[(0, 1)],
            s[(1, 1)],
            s[(0, 2)],
            s[(1, 2)],
            s[(2, 2)],
        );
        // R S Rᵀ in 30 products (the scheme of Pinocchio's Symmetric3::rotate): write
        // S = d5·1 + (S − d5·1), whose last diagonal entry is zero, and use RᵀR = 1.
        let (l00, l11, l20, l21) = (d0 - d5, d2 - d5, 2.0 * d3, 2.0 * d4);
        let y00 = r[(1, 0)] * l00 + r[(1, 1)] * d1 + r[(1, 2)] * l20;
        let y01 = r[(1, 0)] * d1 + r[(1, 1)] * l11 + r[(1, 2)] * l21;
        let y10 = r[(2, 0)] * l00 + r[(2, 1)] * d1 + r[(2, 2)] * l20;
        let y11 = r[(2, 0)] * d1 + r[(2, 1)] * l11 + r[(2, 2)] * l21;
        let o11 = y00 * r[(1, 0)] + y01 * r[(1, 1)];
        let o22 = y10 * r[(2, 0)] + y11 * r[(2, 1)];
        let w0 = -r[(0, 0)] * d4 + r[(0, 1)] * d3;
        let w1 = -r[(1, 0)] * d4 + r[(1, 1)] * d3;
        let w2 = -r[(2, 0)] * d4 + r[(2, 1)] * d3;
        let rs00 = l00 + l11 - o11 - o22 + d5;
        let rs01 = y00 * r[(0, 0)] + y01 * r[(0, 1)] + w2;
        let rs11 = o11 + d5;
        let rs02 = y10 * r[(0, 0)] + y11 * r[(0, 1)] - w1;
        let rs12 = y10 * r[(1, 0)] + y11 * r[(1, 1)] + w0;
        let rs22 = o22 + d5;
        let diag = 2.0 * g.dot(p);
        let e = |i: usize, j: usize| p[i] * g[j] + g[i] * p[j];
        let a00 = rs00 - e(0, 0) + diag;
        let a01 = rs01 - e(0, 1);
        let a02 = rs02 - e(0, 2);
        let a11 = rs11 - e(1, 1) + diag;
        let a12 = rs12 - e(1, 2);
        let a22 = rs22 - e(2, 2) + diag;
        Inertia {
            mass: m,
            first_moment: rh + mp,
            inertia_origin: Matrix3::new(a00, a01, a02, a01, a11, a12, a02, a12, a22),
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

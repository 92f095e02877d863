//! Spatial motion (twist) and force (wrench) vectors.

use nalgebra::{Vector3, Vector6};
use std::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

/// A spatial motion vector (twist, or spatial acceleration) `[linear; angular]`.
///
/// `linear` is the velocity of the point at the expressing frame's origin, `angular` the
/// angular velocity, both in that frame's axes.
#[doc(alias = "Twist")]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Motion {
    /// Linear part v (m/s, or m/s² for accelerations).
    pub linear: Vector3<f64>,
    /// Angular part ω (rad/s, or rad/s²).
    pub angular: Vector3<f64>,
}

/// A spatial force vector (wrench, or momentum) `[linear; angular]`: force and moment
/// about the expressing frame's origin.
#[doc(alias = "Wrench")]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Force {
    /// Linear part f (N).
    pub linear: Vector3<f64>,
    /// Angular part n, the moment about the frame origin (N·m).
    pub angular: Vector3<f64>,
}

macro_rules! spatial_ops {
    ($t:ident) => {
        impl $t {
            /// The zero vector.
            #[inline]
            #[must_use]
            pub fn zero() -> Self {
                Self {
                    linear: Vector3::zeros(),
                    angular: Vector3::zeros(),
                }
            }

            /// Builds from its linear and angular parts.
            #[inline]
            #[must_use]
            pub fn new(linear: Vector3<f64>, angular: Vector3<f64>) -> Self {
                Self { linear, angular }
            }

            /// Builds from a 6-vector `[linear; angular]`.
            #[must_use]
            pub fn from_vector(v: &Vector6<f64>) -> Self {
                Self {
                    linear: Vector3::new(v[0], v[1], v[2]),
                    angular: Vector3::new(v[3], v[4], v[5]),
                }
            }

            /// The 6-vector `[linear; angular]`.
            #[must_use]
            pub fn to_vector(&self) -> Vector6<f64> {
                Vector6::new(
                    self.linear.x,
                    self.linear.y,
                    self.linear.z,
                    self.angular.x,
                    self.angular.y,
                    self.angular.z,
                )
            }

            /// Component `k` of `[linear; angular]` (0..6).
            ///
            /// # Panics
            /// If `k >= 6`.
            #[inline]
            #[must_use]
            pub fn component(&self, k: usize) -> f64 {
                if k < 3 {
                    self.linear[k]
                } else {
                    self.angular[k - 3]
                }
            }
        }

        impl Add for $t {
            type Output = $t;
            #[inline]
            fn add(self, o: $t) -> $t {
                $t {
                    linear: self.linear + o.linear,
                    angular: self.angular + o.angular,
                }
            }
        }
        impl Sub for $t {
            type Output = $t;
            #[inline]
            fn sub(self, o: $t) -> $t {
                $t {
                    linear: self.linear - o.linear,
                    angular: self.angular - o.angular,
                }
            }
        }
        impl AddAssign for $t {
            #[inline]
            fn add_assign(&mut self, o: $t) {
                self.linear += o.linear;
                self.angular += o.angular;
            }
        }
        impl SubAssign for $t {
            #[inline]
            fn sub_assign(&mut self, o: $t) {
                self.linear -= o.linear;
                self.angular -= o.angular;
            }
        }
        impl Neg for $t {
            type Output = $t;
            #[inline]
            fn neg(self) -> $t {
                $t {
                    linear: -self.linear,
                    angular: -self.angular,
                }
            }
        }
        impl Mul<f64> for $t {
            type Output = $t;
            #[inline]
            fn mul(self, s: f64) -> $t {
                $t {
                    linear: self.linear * s,
                    angular: self.angular * s,
                }
            }
        }
    };
}

spatial_ops!(Motion);
spatial_ops!(Force);

impl Motion {
    /// Spatial cross product of motions `self × m` (the `ad_v m` operator):
    /// `[ω × m_v + v × m_ω; ω × m_ω]`.
    #[doc(alias = "crm")]
    #[inline]
    #[must_use]
    pub fn cross_motion(&self, m: &Motion) -> Motion {
        Motion {
            linear: self.angular.cross(&m.linear) + self.linear.cross(&m.angular),
            angular: self.angular.cross(&m.angular),
        }
    }

    /// Dual cross product `self ×* f` (the `-ad_vᵀ f` operator):
    /// `[ω × f; ω × n + v × f]`.
    #[doc(alias = "crf")]
    #[inline]
    #[must_use]
    pub fn cross_force(&self, f: &Force) -> Force {
        Force {
            linear: self.angular.cross(&f.linear),
            angular: self.angular.cross(&f.angular) + self.linear.cross(&f.linear),
        }
    }

    /// Power pairing `⟨self, f⟩ = v·f + ω·n`.
    #[inline]
    #[must_use]
    pub fn dot(&self, f: &Force) -> f64 {
        self.linear.dot(&f.linear) + self.angular.dot(&f.angular)
    }
}

impl Force {
    /// Power pairing `⟨m, self⟩`.
    #[inline]
    #[must_use]
    pub fn dot(&self, m: &Motion) -> f64 {
        m.dot(self)
    }
}

//! The differential-drive platform: two driven wheels on one axle, passive casters for
//! support, no side slip.
//!
//! # Coordinates
//!
//! The platform is the planar root of a model: `q = [x, y, θ]` is the position of the
//! base frame origin and its heading (angle of the base x axis from world +x towards
//! +y); `q̇ = [ẋ, ẏ, θ̇]` in world axes. The base origin lies a distance `d` **ahead**
//! of the driven-axle midpoint `P0` along the base x axis (the chapter's `d`; `d` may be
//! zero or negative):
//!
//! ```text
//! P0 = (x, y) − d·e(θ),   e(θ) = (cos θ, sin θ),   e_lat(θ) = (−sin θ, cos θ)
//! ```
//!
//! The left wheel touches the ground at `P0 + b·e_lat`, the right wheel at `P0 − b·e_lat`
//! (`b` is the half track). Wheel quantities are always ordered **[left, right]**, as the
//! chapter orders its inputs `u = [τ_L, τ_R]`.
//!
//! # The constraint and its basis
//!
//! No side slip of the axle midpoint gives one Pfaffian row
//! `C(q) = [−sin θ, cos θ, −d]` with `C q̇ = 0`. The admissible velocities are
//! `q̇ = N_C(q) u` with the platform inputs `u = [v, ω]` (forward speed of the axle
//! midpoint and yaw rate):
//!
//! ```text
//!         ⎡ cos θ   −d sin θ ⎤
//! N_C  =  ⎢ sin θ    d cos θ ⎥        C N_C = 0 for every d, including d = 0.
//!         ⎣   0         1    ⎦
//! ```
//!
//! Wheel rates map to `u` by `v = r_w (φ̇_L + φ̇_R)/2`, `ω = r_w (φ̇_R − φ̇_L)/(2b)`.

use std::str::FromStr;

use nalgebra::{Matrix2, Matrix3x2, RowVector3, Vector2, Vector3};

use crate::error::{Error, Result};

/// A differential-drive platform: wheel radius `r_w`, half track `b`, and the offset `d`
/// of the base frame origin ahead of the driven-axle midpoint.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DiffDrive {
    /// Wheel radius r_w (m), > 0.
    pub wheel_radius: f64,
    /// Half the distance between the two driven wheels, b (m), > 0.
    pub half_track: f64,
    /// Distance d (m) of the base frame origin ahead of the axle midpoint along the base x
    /// axis; any finite value.
    pub d: f64,
}

impl DiffDrive {
    /// A validated differential drive: `r_w > 0`, `b > 0`, `d` finite.
    pub fn new(wheel_radius: f64, half_track: f64, d: f64) -> Result<Self> {
        for (field, value) in [("r_w", wheel_radius), ("b", half_track), ("d", d)] {
            if !value.is_finite() {
                return Err(Error::NonFinite {
                    field: format!("diff-drive {field}"),
                });
            }
        }
        if wheel_radius <= 0.0 {
            return Err(Error::invalid(
                "diff-drive r_w",
                format!("wheel radius must be > 0, got {wheel_radius}"),
            ));
        }
        if half_track <= 0.0 {
            return Err(Error::invalid(
                "diff-drive b",
                format!("half track must be > 0, got {half_track}"),
            ));
        }
        Ok(Self {
            wheel_radius,
            half_track,
            d,
        })
    }

    /// Pfaffian no-side-slip row C(q) = [−sin θ, cos θ, −d] (1×3), `C q̇ = 0`.
    #[doc(alias = "C")]
    pub fn constraint_row(&self, theta: f64) -> RowVector3<f64> {
        let (s, c) = theta.sin_cos();
        RowVector3::new(-s, c, -self.d)
    }

    /// Time derivative Ċ(q, q̇) = [−cos θ θ̇, −sin θ θ̇, 0].
    pub fn constraint_row_dot(&self, theta: f64, theta_dot: f64) -> RowVector3<f64> {
        let (s, c) = theta.sin_cos();
        RowVector3::new(-c * theta_dot, -s * theta_dot, 0.0)
    }

    /// Admissible-velocity basis N_C(q) (3×2) mapping `u = [v, ω]` to `q̇ = [ẋ, ẏ, θ̇]`.
    #[doc(alias = "N_C")]
    pub fn basis(&self, theta: f64) -> Matrix3x2<f64> {
        let (s, c) = theta.sin_cos();
        let d = self.d;
        Matrix3x2::new(c, -d * s, s, d * c, 0.0, 1.0)
    }

    /// Time derivative Ṅ_C(q, q̇) (3×2) of [`DiffDrive::basis`] for heading rate `θ̇`.
    #[doc(alias = "Ndot_C")]
    pub fn basis_dot(&self, theta: f64, theta_dot: f64) -> Matrix3x2<f64> {
        let (s, c) = theta.sin_cos();
        let d = self.d;
        Matrix3x2::new(-s, -d * c, c, -d * s, 0.0, 0.0) * theta_dot
    }

    /// Base velocity `q̇ = N_C(θ) [v, ω]` in world axes.
    pub fn base_velocity(&self, theta: f64, v: f64, omega: f64) -> Vector3<f64> {
        self.basis(theta) * Vector2::new(v, omega)
    }

    /// The platform inputs `[v, ω]` of an admissible base velocity `q̇` (the left inverse
    /// of N_C: `v = ẋ cos θ + ẏ sin θ`, `ω = θ̇`). The side-slip part of `q̇`, if any, is
    /// what [`DiffDrive::constraint_row`] measures.
    pub fn platform_inputs(&self, theta: f64, qdot: &Vector3<f64>) -> Vector2<f64> {
        let (s, c) = theta.sin_cos();
        Vector2::new(qdot[0] * c + qdot[1] * s, qdot[2])
    }

    /// Matrix W (2×2) with `[v, ω] = W [φ̇_L, φ̇_R]`.
    pub fn wheel_to_platform(&self) -> Matrix2<f64> {
        let r = self.wheel_radius;
        let b = self.half_track;
        Matrix2::new(r / 2.0, r / 2.0, -r / (2.0 * b), r / (2.0 * b))
    }

    /// Matrix W⁻¹ (2×2) with `[φ̇_L, φ̇_R] = W⁻¹ [v, ω]`.
    pub fn platform_to_wheel(&self) -> Matrix2<f64> {
        let r = self.wheel_radius;
        let b = self.half_track;
        Matrix2::new(1.0 / r, -b / r, 1.0 / r, b / r)
    }

    /// Admissible-velocity basis in wheel rates (3×2): `q̇ = N_C(θ) W [φ̇_L, φ̇_R]`.
    pub fn wheel_basis(&self, theta: f64) -> Matrix3x2<f64> {
        self.basis(theta) * self.wheel_to_platform()
    }

    /// Actuation map S(q) (3×2): generalised force on `[x, y, θ]` from wheel torques
    /// `[τ_L, τ_R]`, each wheel pushing with `τ/r_w` along the heading at its contact point.
    #[doc(alias = "S")]
    pub fn actuation_map(&self, theta: f64) -> Matrix3x2<f64> {
        let (s, c) = theta.sin_cos();
        let r = self.wheel_radius;
        let b = self.half_track;
        Matrix3x2::new(c / r, c / r, s / r, s / r, -b / r, b / r)
    }

    /// Position of the driven-axle midpoint P0 for base pose `[x, y, θ]`.
    pub fn axle_midpoint(&self, q: &Vector3<f64>) -> Vector2<f64> {
        let (s, c) = q[2].sin_cos();
        Vector2::new(q[0] - self.d * c, q[1] - self.d * s)
    }

    /// Ground contact points of the `[left, right]` wheels for base pose `[x, y, θ]`.
    pub fn wheel_contacts(&self, q: &Vector3<f64>) -> [Vector2<f64>; 2] {
        let p0 = self.axle_midpoint(q);
        let (s, c) = q[2].sin_cos();
        let lat = Vector2::new(-s, c) * self.half_track;
        [p0 + lat, p0 - lat]
    }

    /// Rolling constraints (2×5) when wheel angles are tracked: for the extended
    /// coordinates `[x, y, θ, φ_L, φ_R]`, each wheel's contact point moves forward at
    /// `r_w φ̇`. The forward velocity of the left contact is `ẋ cos θ + ẏ sin θ − b θ̇`
    /// (the offset `d` has no forward component), so the rows are
    /// `[cos θ, sin θ, −b, −r_w, 0]` and `[cos θ, sin θ, b, 0, −r_w]`.
    pub fn rolling_rows(&self, theta: f64) -> nalgebra::Matrix2x5<f64> {
        let (s, c) = theta.sin_cos();
        let r = self.wheel_radius;
        let b = self.half_track;
        nalgebra::Matrix2x5::new(c, s, -b, -r, 0.0, c, s, b, 0.0, -r)
    }
}

impl FromStr for DiffDrive {
    type Err = Error;

    /// Parses `r_w=0.1,b=0.25,d=0.0` (any order; all three keys required), optionally
    /// prefixed by `diff-drive:`.
    fn from_str(spec: &str) -> Result<Self> {
        let body = spec.strip_prefix("diff-drive:").unwrap_or(spec);
        let (mut r, mut b, mut d) = (None, None, None);
        for item in body.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            let (key, value) = item.split_once('=').ok_or_else(|| {
                Error::invalid(
                    "diff-drive spec",
                    format!("expected key=value, got '{item}'"),
                )
            })?;
            let value: f64 = value.trim().parse().map_err(|_| {
                Error::invalid(
                    format!("diff-drive {}", key.trim()),
                    format!("'{}' is not a number", value.trim()),
                )
            })?;
            match key.trim() {
                "r_w" | "r" => r = Some(value),
                "b" => b = Some(value),
                "d" => d = Some(value),
                other => {
                    return Err(Error::invalid(
                        "diff-drive spec",
                        format!("unknown key '{other}' (expected r_w, b, d)"),
                    ));
                }
            }
        }
        let need = |v: Option<f64>, k: &str| {
            v.ok_or_else(|| Error::invalid("diff-drive spec", format!("missing key '{k}'")))
        };
        DiffDrive::new(need(r, "r_w")?, need(b, "b")?, need(d, "d")?)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> DiffDrive {
        DiffDrive::new(
            0.048_381_849_769_459_57,
            0.176_305_268_444_718_75,
            -0.134_460_309_596_868_36,
        )
        .unwrap()
    }

    #[test]
    fn basis_spans_the_null_space_of_the_constraint() {
        for &d in &[0.0, 0.3, -0.2] {
            let dd = DiffDrive::new(0.1, 0.25, d).unwrap();
            for k in 0..16 {
                let th = -3.0 + 0.4 * k as f64;
                let cn = dd.constraint_row(th) * dd.basis(th);
                assert!(cn.norm() < 1e-15, "C N_C = {cn}");
                assert_eq!(dd.basis(th).rank(1e-12), 2);
            }
        }
    }

    #[test]
    fn basis_dot_matches_finite_difference() {
        let dd = sample();
        let (th, thd, h) = (0.7, -1.3, 1e-6);
        let fd = (dd.basis(th + h * thd) - dd.basis(th - h * thd)) / (2.0 * h);
        assert!((fd - dd.basis_dot(th, thd)).norm() < 1e-8);
        let fd_c = (dd.constraint_row(th + h * thd) - dd.constraint_row(th - h * thd)) / (2.0 * h);
        assert!((fd_c - dd.constraint_row_dot(th, thd)).norm() < 1e-8);
    }

    #[test]
    fn wheel_maps_are_inverse() {
        let dd = sample();
        let id = dd.wheel_to_platform() * dd.platform_to_wheel();
        assert!((id - Matrix2::identity()).norm() < 1e-12);
        // Equal wheel rates drive straight, opposite rates spin in place.
        let u = dd.wheel_to_platform() * Vector2::new(2.0, 2.0);
        assert!((u[0] - 2.0 * dd.wheel_radius).abs() < 1e-15 && u[1].abs() < 1e-15);
        let u = dd.wheel_to_platform() * Vector2::new(-1.0, 1.0);
        assert!(u[0].abs() < 1e-15 && u[1] > 0.0);
    }

    #[test]
    fn actuation_map_matches_the_chapter_m1_reference() {
        // Case 0 of the chapter's m1 reference vectors (sympy derivation): S at φ = -2.18526...
        let dd = sample();
        let s = dd.actuation_map(-2.185_264_175_482_659_6);
        let expected = Matrix3x2::new(
            -11.916_117_227_813_45,
            -11.916_117_227_813_45,
            -16.888_158_769_569_092,
            -16.888_158_769_569_092,
            -3.644_037_367_004_707_5,
            3.644_037_367_004_707_5,
        );
        assert!((s - expected).norm() < 1e-9 * expected.norm());
    }

    #[test]
    fn actuation_is_power_consistent_with_wheel_rates() {
        // Power through the wheels equals power on the platform: Sᵀ N_C W = diag(1, 1).
        let dd = sample();
        let th = 1.1;
        let p = dd.actuation_map(th).transpose() * dd.wheel_basis(th);
        assert!((p - Matrix2::identity()).norm() < 1e-12, "{p}");
    }

    #[test]
    fn rolling_rows_hold_along_admissible_motion() {
        let dd = sample();
        let th = 0.4;
        let wheel_rates = Vector2::new(0.7, -0.2);
        let qd = dd.wheel_basis(th) * wheel_rates;
        let ext = nalgebra::Vector5::new(qd[0], qd[1], qd[2], wheel_rates[0], wheel_rates[1]);
        assert!((dd.rolling_rows(th) * ext).norm() < 1e-12);
        // Slipping wheels violate them.
        let slipping =
            nalgebra::Vector5::new(qd[0], qd[1], qd[2], wheel_rates[0] + 0.1, wheel_rates[1]);
        assert!((dd.rolling_rows(th) * slipping).norm() > 1e-3);
    }

    #[test]
    fn parses_specs_and_rejects_bad_ones() {
        let dd: DiffDrive = "diff-drive:r_w=0.1,b=0.3,d=0".parse().unwrap();
        assert_eq!(dd, DiffDrive::new(0.1, 0.3, 0.0).unwrap());
        assert!("r_w=0.1,b=0.3".parse::<DiffDrive>().is_err());
        assert!("r_w=0.1,b=-0.3,d=0".parse::<DiffDrive>().is_err());
        assert!("r_w=x,b=0.3,d=0".parse::<DiffDrive>().is_err());
        assert!("r_w=0.1,b=0.3,d=0,z=1".parse::<DiffDrive>().is_err());
        assert!("r_w=NaN,b=0.3,d=0".parse::<DiffDrive>().is_err());
    }
}

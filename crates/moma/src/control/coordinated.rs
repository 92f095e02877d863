//! Coordinated base/arm control of a differential drive carrying a planar 2R arm
//! (Yamamoto & Yun; the kinematic form of the project's theory notes, section 2.6).
//!
//! State `[x, y, φ, q1, q2]`: axle midpoint, heading, arm angles; the arm base B sits `L`
//! ahead of the axle, the arm's forward kinematics in the platform frame is
//! `y = f(q) = (l1 cos q1 + l2 cos(q1+q2), l1 sin q1 + l2 sin(q1+q2))`. The platform keeps
//! the arm at its preferred, high-manipulability configuration `q*` (its end-effector
//! offset `y* = f(q*)`), while the arm tracks the end-effector path `p_E,d(t)`:
//!
//! ```text
//! ṗ_E,cmd = ṗ_E,d + K_E (p_E,d − p_E)
//! [v; ω]  = A(y)⁻¹ (K_Y (y* − y) − Rᵀ ṗ_E,cmd),     A(y) = [[−1, y2], [0, −(y1 + L)]]
//! q̇       = J_arm⁻¹ (Rᵀ (ṗ_E,cmd − ṗ_B) − ω (−y2, y1))
//! ```
//!
//! so that `(p_E,d − p_E)' = −K_E (p_E,d − p_E)` and `(y* − y)' = −K_Y (y* − y)` exactly.
//! The reported Lyapunov function is `V = ½|p_E,d − p_E|² + ½|y* − y|²` with
//! `V̇ = −K_E |p_E,d − p_E|² − K_Y |y* − y|²`. The heading is the zero dynamics,
//! `φ̇ = −V_path sin φ/(y1* + L)` on a straight path: stable forward, unstable backwards.

use super::Controller;
use crate::error::{Error, Result};

/// Geometry and gains.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coordinated {
    /// Distance axle → arm base L.
    pub l: f64,
    /// Link lengths.
    pub l1: f64,
    /// Link 2.
    pub l2: f64,
    /// Preferred arm configuration q*.
    pub q_star: [f64; 2],
    /// End-effector gain K_E > 0.
    pub k_e: f64,
    /// Relative-output gain K_Y > 0.
    pub k_y: f64,
}

/// End-effector reference sample: position and velocity (world).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointReference {
    /// p_E,d.
    pub p: [f64; 2],
    /// ṗ_E,d.
    pub v: [f64; 2],
}

/// Smallest |y1 + L| and |det J_arm| the law accepts.
pub const SINGULARITY_GUARD: f64 = 1e-9;

impl Coordinated {
    /// Arm forward kinematics in the platform frame, from B.
    #[must_use]
    pub fn arm(&self, q: [f64; 2]) -> [f64; 2] {
        let a = q[0] + q[1];
        [
            self.l1 * q[0].cos() + self.l2 * a.cos(),
            self.l1 * q[0].sin() + self.l2 * a.sin(),
        ]
    }

    /// The end-effector position (world).
    #[must_use]
    pub fn end_effector(&self, s: &[f64; 5]) -> [f64; 2] {
        let y = self.arm([s[3], s[4]]);
        let (sn, c) = s[2].sin_cos();
        [
            s[0] + self.l * c + c * y[0] - sn * y[1],
            s[1] + self.l * sn + sn * y[0] + c * y[1],
        ]
    }

    /// Arm manipulability `l1 l2 |sin q2|`.
    #[must_use]
    pub fn manipulability(&self, s: &[f64; 5]) -> f64 {
        self.l1 * self.l2 * s[4].sin().abs()
    }

    /// The errors `(p_E,d − p_E, y* − y)`.
    #[must_use]
    pub fn errors(&self, s: &[f64; 5], r: &PointReference) -> ([f64; 2], [f64; 2]) {
        let pe = self.end_effector(s);
        let y = self.arm([s[3], s[4]]);
        let ys = self.arm(self.q_star);
        (
            [r.p[0] - pe[0], r.p[1] - pe[1]],
            [ys[0] - y[0], ys[1] - y[1]],
        )
    }

    /// The rates `[v, ω, q̇1, q̇2]`.
    ///
    /// # Errors
    /// [`Error::Singular`] when `|y1 + L|` or `|det J_arm|` is below [`SINGULARITY_GUARD`].
    pub fn rates(&self, s: &[f64; 5], r: &PointReference) -> Result<[f64; 4]> {
        let (ee, ey) = self.errors(s, r);
        let y = self.arm([s[3], s[4]]);
        let (sn, c) = s[2].sin_cos();
        let pc = [r.v[0] + self.k_e * ee[0], r.v[1] + self.k_e * ee[1]];
        // Rᵀ ṗ_E,cmd
        let rp = [c * pc[0] + sn * pc[1], -sn * pc[0] + c * pc[1]];
        let a22 = -(y[0] + self.l);
        if a22.abs() < SINGULARITY_GUARD {
            return Err(Error::Singular {
                what: "coordinated control: platform output map A(y)".into(),
                detail: Some(format!("y1 + L = {}", -a22)),
            });
        }
        let rhs = [self.k_y * ey[0] - rp[0], self.k_y * ey[1] - rp[1]];
        // A = [[−1, y2], [0, a22]]
        let w = rhs[1] / a22;
        let v = -(rhs[0] - y[1] * w);
        // Rᵀ ṗ_B = (v, L ω)
        let t = [rp[0] - v + w * y[1], rp[1] - self.l * w - w * y[0]];
        let a = s[3] + s[4];
        let j11 = -self.l1 * s[3].sin() - self.l2 * a.sin();
        let j12 = -self.l2 * a.sin();
        let j21 = self.l1 * s[3].cos() + self.l2 * a.cos();
        let j22 = self.l2 * a.cos();
        let det = j11 * j22 - j12 * j21;
        if det.abs() < SINGULARITY_GUARD {
            return Err(Error::Singular {
                what: "coordinated control: arm Jacobian".into(),
                detail: Some(format!("det J_arm = {det}")),
            });
        }
        let qd1 = (j22 * t[0] - j12 * t[1]) / det;
        let qd2 = (-j21 * t[0] + j11 * t[1]) / det;
        Ok([v, w, qd1, qd2])
    }

    /// The closed-loop state derivative for rates `u = [v, ω, q̇1, q̇2]`.
    #[must_use]
    pub fn state_rate(s: &[f64; 5], u: &[f64; 4]) -> [f64; 5] {
        let (sn, c) = s[2].sin_cos();
        [u[0] * c, u[0] * sn, u[1], u[2], u[3]]
    }
}

/// What [`coordinated_rates`] needs of a measured state: the platform heading, the end
/// effector's world position, its position relative to the **axle midpoint** in the
/// platform frame `y = Rᵀ(p_E − p_A)`, and the horizontal rows of its reduced Jacobian
/// `ṗ_E = J u` for `u = [v, ω, q̇_a, q̇_b]` (the platform's speed and turn rate and the two
/// arm joints that move the end effector in the horizontal plane).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeasuredPlanarArm {
    /// Heading φ of the platform.
    pub heading: f64,
    /// p_E (world, horizontal).
    pub p_e: [f64; 2],
    /// y = Rᵀ(p_E − p_A), p_A the axle midpoint.
    pub y: [f64; 2],
    /// Rows x, y of the world velocity of the end effector in `u`.
    pub jacobian: [[f64; 4]; 2],
}

/// The coordinated law on a measured state (any arm whose two chosen joints move the end
/// effector in the horizontal plane, e.g. a URDF arm on the platform): solves
///
/// ```text
/// ṗ_E = J u                          = ṗ_E,d + K_E (p_E,d − p_E)
/// ẏ   = Rᵀ J u + A(y) [v; ω]        = K_Y (y* − y),      A(y) = [[−1, y2], [0, −y1]]
/// ```
///
/// for `u = [v, ω, q̇_a, q̇_b]` (y measured from the axle midpoint, so `A` has no `L`:
/// [`Coordinated::rates`] is the special case of a planar 2R arm L ahead of the axle).
/// Returns `u` and `|det|` of the 4 × 4 output map.
///
/// # Errors
/// [`Error::Singular`] when the output map is singular (`|det| <` [`SINGULARITY_GUARD`]
/// relative to the product of its row norms): the end effector over the axle line
/// (`y1 = 0`) or an arm singularity of the two joints.
pub fn coordinated_rates(
    m: &MeasuredPlanarArm,
    y_star: [f64; 2],
    r: &PointReference,
    k_e: f64,
    k_y: f64,
) -> Result<[f64; 4]> {
    let (sn, c) = m.heading.sin_cos();
    let j = &m.jacobian;
    let mut a = nalgebra::Matrix4::<f64>::zeros();
    for k in 0..4 {
        a[(0, k)] = j[0][k];
        a[(1, k)] = j[1][k];
        a[(2, k)] = c * j[0][k] + sn * j[1][k];
        a[(3, k)] = -sn * j[0][k] + c * j[1][k];
    }
    a[(2, 0)] -= 1.0;
    a[(2, 1)] += m.y[1];
    a[(3, 1)] -= m.y[0];
    let rhs = nalgebra::Vector4::new(
        r.v[0] + k_e * (r.p[0] - m.p_e[0]),
        r.v[1] + k_e * (r.p[1] - m.p_e[1]),
        k_y * (y_star[0] - m.y[0]),
        k_y * (y_star[1] - m.y[1]),
    );
    let scale: f64 = (0..4).map(|i| a.row(i).norm()).product();
    let lu = a.lu();
    let det = lu.determinant();
    if !(det.is_finite() && scale > 0.0 && det.abs() >= SINGULARITY_GUARD * scale) {
        return Err(Error::Singular {
            what: "coordinated control: output map [p_E; y]".into(),
            detail: Some(format!(
                "det = {det:e} (y1 = {:.4} m from the axle)",
                m.y[0]
            )),
        });
    }
    let u = lu.solve(&rhs).ok_or_else(|| Error::Singular {
        what: "coordinated control: output map [p_E; y]".into(),
        detail: None,
    })?;
    Ok([u[0], u[1], u[2], u[3]])
}

impl Controller for Coordinated {
    type State = [f64; 5];
    type Reference = PointReference;
    type Actuation = [f64; 4];

    fn actuation(
        &mut self,
        _t: f64,
        s: &[f64; 5],
        r: &PointReference,
        out: &mut [f64; 4],
    ) -> Result<()> {
        *out = self.rates(s, r)?;
        Ok(())
    }

    fn lyapunov(&self, _t: f64, s: &[f64; 5], r: &PointReference) -> Option<f64> {
        let (ee, ey) = self.errors(s, r);
        Some(0.5 * (ee[0] * ee[0] + ee[1] * ee[1] + ey[0] * ey[0] + ey[1] * ey[1]))
    }

    fn lyapunov_rate(&self, _t: f64, s: &[f64; 5], r: &PointReference) -> Option<f64> {
        let (ee, ey) = self.errors(s, r);
        Some(
            -self.k_e * (ee[0] * ee[0] + ee[1] * ee[1])
                - self.k_y * (ey[0] * ey[0] + ey[1] * ey[1]),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The measured-state form on the planar 2R equals the closed form of the theory
    /// notes (y shifted by L to the axle, the Jacobian of ṗ_E in u written out).
    #[test]
    fn measured_form_equals_the_closed_form_on_the_planar_2r() {
        let law = Coordinated {
            l: 0.3,
            l1: 0.6,
            l2: 0.5,
            q_star: [-0.6, std::f64::consts::FRAC_PI_2],
            k_e: 2.0,
            k_y: 1.0,
        };
        for (s, r) in [
            (
                [0.0, 0.0, 0.2, 0.0, 1.2],
                PointReference {
                    p: [1.0, 0.5],
                    v: [0.2, 0.03],
                },
            ),
            (
                [0.4, -0.3, -1.1, 0.7, -0.9],
                PointReference {
                    p: [1.2, -0.1],
                    v: [-0.1, 0.25],
                },
            ),
        ] {
            let want = law.rates(&s, &r).unwrap();
            let (sn, c) = s[2].sin_cos();
            let yb = law.arm([s[3], s[4]]);
            let y = [yb[0] + law.l, yb[1]];
            // ṗ_E = R(v, 0) + ω ẑ×(R y) + R J_arm q̇
            let a = s[3] + s[4];
            let ja = [
                [-law.l1 * s[3].sin() - law.l2 * a.sin(), -law.l2 * a.sin()],
                [law.l1 * s[3].cos() + law.l2 * a.cos(), law.l2 * a.cos()],
            ];
            let ry = [c * y[0] - sn * y[1], sn * y[0] + c * y[1]];
            let jacobian = [
                [
                    c,
                    -ry[1],
                    c * ja[0][0] - sn * ja[1][0],
                    c * ja[0][1] - sn * ja[1][1],
                ],
                [
                    sn,
                    ry[0],
                    sn * ja[0][0] + c * ja[1][0],
                    sn * ja[0][1] + c * ja[1][1],
                ],
            ];
            let m = MeasuredPlanarArm {
                heading: s[2],
                p_e: law.end_effector(&s),
                y,
                jacobian,
            };
            let ys = law.arm(law.q_star);
            let got = coordinated_rates(&m, [ys[0] + law.l, ys[1]], &r, law.k_e, law.k_y).unwrap();
            for k in 0..4 {
                assert!((got[k] - want[k]).abs() < 1e-12, "{k}: {got:?} vs {want:?}");
            }
        }
    }

    #[test]
    fn measured_form_refuses_the_end_effector_over_the_axle() {
        let m = MeasuredPlanarArm {
            heading: 0.0,
            p_e: [0.0, 0.5],
            y: [0.0, 0.5],
            // base rotation moves the point along −x; arm joints only along y
            jacobian: [[1.0, -0.5, 0.0, 0.0], [0.0, 0.0, 1.0, 0.5]],
        };
        let r = PointReference {
            p: [0.0, 0.5],
            v: [0.0, 0.0],
        };
        let e = coordinated_rates(&m, [0.5, 0.0], &r, 1.0, 1.0).unwrap_err();
        assert!(e.to_string().contains("output map"), "{e}");
    }
}

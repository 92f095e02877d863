//! Feedback laws for the unicycle / differential drive `ẋ = v cos θ, ẏ = v sin θ, θ̇ = ω`
//! (state `[x, y, θ]` of the axle midpoint, inputs `[v, ω]`).
//!
//! Brockett's condition (1983) rules out any smooth time-invariant law that stabilises a
//! pose: the image of `(x, u) ↦ f(x, u)` near the goal misses the sideways directions
//! (see the `brockett_*` tests). The laws here escape it in the three classic ways:
//!
//! * [`Kanayama`] *tracks* a moving reference (not blocked by Brockett), with
//!   `V = (e_x² + e_y²)/2 + (1 − cos e_θ)/K_y`, `V̇ = −K_x e_x² − (v_r K_θ/K_y) sin² e_θ`;
//! * [`Samson`] is smooth but **time-varying**:
//!   `u1 = −k1 z1 + (z2² + z3²) sin t` (t the absolute time), `u2 = −k2 u1 z3 − k3 z2`,
//!   `ω = u1`, `v = u2 + z3 u1` in the chained coordinates
//!   `z1 = θ, z2 = x cos θ + y sin θ, z3 = x sin θ − y cos θ`;
//!   `V = (z2² + k2 z3²)/2`, `V̇ = −k3 z2²` exactly;
//! * [`Astolfi`] and [`Aicardi`] are smooth in polar coordinates and therefore
//!   **discontinuous** in Cartesian ones at the goal.
//!
//! The stabilisers take the goal pose as reference and work with the robot pose
//! expressed in the goal frame. The error coordinates are exactly those of the project's
//! theory notes (section 2): Astolfi's `ρ = |p|`, `α = wrap(−θ + atan2(−y, −x))`,
//! `β = wrap(−θ − α)`; Aicardi's `e = |p|`, `ϑ = atan2(−y, −x)`, `α = wrap(ϑ − θ)`.
//!
//! [`WheelLimits`] applies wheel-speed and wheel-torque limits through the wheel map of a
//! [`DiffDrive`] and reports what saturated.

use super::{Controller, wrap_angle};
use crate::error::{Error, Result};
use crate::mobile::DiffDrive;
use nalgebra::Vector2;

/// A unicycle pose `[x, y, θ]`.
pub type Pose = [f64; 3];

/// Right-hand side of the unicycle `[v cos θ, v sin θ, ω]`.
#[must_use]
pub fn unicycle_rhs(state: &Pose, input: &[f64; 2]) -> Pose {
    let (s, c) = state[2].sin_cos();
    [input[0] * c, input[0] * s, input[1]]
}

/// The robot pose expressed in the frame of `goal` (heading not wrapped).
#[must_use]
pub fn pose_in_goal_frame(state: &Pose, goal: &Pose) -> Pose {
    let (s, c) = goal[2].sin_cos();
    let dx = state[0] - goal[0];
    let dy = state[1] - goal[1];
    [c * dx + s * dy, -s * dx + c * dy, state[2] - goal[2]]
}

fn check_gain(name: &str, value: f64) -> Result<()> {
    if !value.is_finite() {
        return Err(Error::NonFinite {
            field: format!("gains.{name}"),
        });
    }
    if value <= 0.0 {
        return Err(Error::invalid(
            format!("gains.{name}"),
            format!("must be > 0, got {value}"),
        ));
    }
    Ok(())
}

/// A reference sample of a tracking law: pose and feed-forward inputs `(v_r, ω_r)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReferenceSample {
    /// Reference pose `[x_r, y_r, θ_r]`.
    pub pose: Pose,
    /// Reference forward speed v_r.
    pub v: f64,
    /// Reference yaw rate ω_r.
    pub w: f64,
}

/// The constant-input reference of theory.md 2.3: starting at the origin heading +x with
/// constant `(v_r, ω_r)`, i.e. the circle `x_r = v_r/ω_r sin(ω_r t)`,
/// `y_r = v_r/ω_r (1 − cos ω_r t)`, `θ_r = ω_r t`, and for `ω_r = 0` the line
/// `x_r = v_r t`, `y_r = 0`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConstantInputReference {
    /// v_r.
    pub vr: f64,
    /// ω_r.
    pub wr: f64,
}

impl ConstantInputReference {
    /// The reference sample at time t (the `ω_r → 0` limit is exact, not a division).
    #[must_use]
    pub fn at(&self, t: f64) -> ReferenceSample {
        let a = self.wr * t;
        // sin(a)/ω_r and (1 − cos a)/ω_r = 2 sin²(a/2)/ω_r, written without cancellation.
        let (x, y) = if self.wr == 0.0 {
            (self.vr * t, 0.0)
        } else {
            let h = (0.5 * a).sin();
            (self.vr * a.sin() / self.wr, 2.0 * self.vr * h * h / self.wr)
        };
        ReferenceSample {
            pose: [x, y, a],
            v: self.vr,
            w: self.wr,
        }
    }
}

/// Kanayama et al. (1990) tracking law:
/// `[e_x; e_y] = R(θ)ᵀ [x_r − x; y_r − y]`, `e_θ = wrap(θ_r − θ)`,
/// `v = v_r cos e_θ + K_x e_x`, `ω = ω_r + v_r (K_y e_y + K_θ sin e_θ)`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Kanayama {
    /// K_x (1/s), > 0.
    pub kx: f64,
    /// K_y (1/m²), > 0.
    pub ky: f64,
    /// K_θ (1/m), > 0.
    pub kth: f64,
}

impl Kanayama {
    /// Validated gains (all > 0).
    ///
    /// # Errors
    /// A gain that is not positive and finite, naming it.
    pub fn new(kx: f64, ky: f64, kth: f64) -> Result<Self> {
        check_gain("Kx", kx)?;
        check_gain("Ky", ky)?;
        check_gain("Kth", kth)?;
        Ok(Self { kx, ky, kth })
    }

    /// The tracking error `[e_x, e_y, e_θ]` in the robot frame.
    #[must_use]
    pub fn error(state: &Pose, r: &ReferenceSample) -> [f64; 3] {
        let (s, c) = state[2].sin_cos();
        let dx = r.pose[0] - state[0];
        let dy = r.pose[1] - state[1];
        [
            c * dx + s * dy,
            -s * dx + c * dy,
            wrap_angle(r.pose[2] - state[2]),
        ]
    }

    /// The inputs `[v, ω]`.
    #[must_use]
    pub fn inputs(&self, state: &Pose, r: &ReferenceSample) -> [f64; 2] {
        let [ex, ey, eth] = Self::error(state, r);
        [
            r.v * eth.cos() + self.kx * ex,
            r.w + r.v * (self.ky * ey + self.kth * eth.sin()),
        ]
    }

    /// Linearisation of the error dynamics about e = 0 for constant `(v_r, ω_r)`:
    /// `[[−K_x, ω_r, 0], [−ω_r, 0, v_r], [0, −v_r K_y, −v_r K_θ]]`.
    #[must_use]
    pub fn linearisation(&self, vr: f64, wr: f64) -> nalgebra::Matrix3<f64> {
        nalgebra::Matrix3::new(
            -self.kx,
            wr,
            0.0,
            -wr,
            0.0,
            vr,
            0.0,
            -vr * self.ky,
            -vr * self.kth,
        )
    }
}

impl Controller for Kanayama {
    type State = Pose;
    type Reference = ReferenceSample;
    type Actuation = [f64; 2];

    fn actuation(
        &mut self,
        _t: f64,
        s: &Pose,
        r: &ReferenceSample,
        out: &mut [f64; 2],
    ) -> Result<()> {
        *out = self.inputs(s, r);
        Ok(())
    }

    fn lyapunov(&self, _t: f64, s: &Pose, r: &ReferenceSample) -> Option<f64> {
        let [ex, ey, eth] = Self::error(s, r);
        Some(0.5 * (ex * ex + ey * ey) + (1.0 - eth.cos()) / self.ky)
    }

    fn lyapunov_rate(&self, _t: f64, s: &Pose, r: &ReferenceSample) -> Option<f64> {
        let [ex, _, eth] = Self::error(s, r);
        let se = eth.sin();
        Some(-self.kx * ex * ex - r.v * self.kth / self.ky * se * se)
    }
}

/// Samson-type smooth time-varying point stabiliser (goal = reference pose):
/// chained coordinates `z1 = θ, z2 = x cos θ + y sin θ, z3 = x sin θ − y cos θ` of the
/// pose in the goal frame, `u1 = −k1 z1 + (z2² + z3²) sin t` with t the absolute time,
/// `u2 = −k2 u1 z3 − k3 z2`, `ω = u1`, `v = u2 + z3 u1`. Convergence is slow (not
/// exponential); `V̇ = −k3 z2²` is exact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Samson {
    /// k1 > 0.
    pub k1: f64,
    /// k2 > 0.
    pub k2: f64,
    /// k3 > 0.
    pub k3: f64,
}

impl Samson {
    /// Validated gains (all > 0).
    ///
    /// # Errors
    /// A gain that is not positive and finite, naming it.
    pub fn new(k1: f64, k2: f64, k3: f64) -> Result<Self> {
        check_gain("k1", k1)?;
        check_gain("k2", k2)?;
        check_gain("k3", k3)?;
        Ok(Self { k1, k2, k3 })
    }

    /// Chained coordinates `[z1, z2, z3]` of the pose in the goal frame.
    #[must_use]
    pub fn chained(state: &Pose, goal: &Pose) -> [f64; 3] {
        let [x, y, th] = pose_in_goal_frame(state, goal);
        let (s, c) = th.sin_cos();
        [th, x * c + y * s, x * s - y * c]
    }

    /// The chained inputs `[u1, u2]` at time t.
    #[must_use]
    pub fn chained_inputs(&self, t: f64, z: &[f64; 3]) -> [f64; 2] {
        let u1 = -self.k1 * z[0] + (z[1] * z[1] + z[2] * z[2]) * t.sin();
        [u1, -self.k2 * u1 * z[2] - self.k3 * z[1]]
    }

    /// The inputs `[v, ω]` at time t.
    #[must_use]
    pub fn inputs(&self, t: f64, state: &Pose, goal: &Pose) -> [f64; 2] {
        let z = Self::chained(state, goal);
        let [u1, u2] = self.chained_inputs(t, &z);
        [u2 + z[2] * u1, u1]
    }
}

impl Controller for Samson {
    type State = Pose;
    type Reference = Pose;
    type Actuation = [f64; 2];

    fn actuation(&mut self, t: f64, s: &Pose, goal: &Pose, out: &mut [f64; 2]) -> Result<()> {
        *out = self.inputs(t, s, goal);
        Ok(())
    }

    fn lyapunov(&self, _t: f64, s: &Pose, goal: &Pose) -> Option<f64> {
        let z = Self::chained(s, goal);
        Some(0.5 * (z[1] * z[1] + self.k2 * z[2] * z[2]))
    }

    fn lyapunov_rate(&self, _t: f64, s: &Pose, goal: &Pose) -> Option<f64> {
        let z = Self::chained(s, goal);
        Some(-self.k3 * z[1] * z[1])
    }
}

/// Astolfi's polar-coordinate stabiliser (goal = reference pose):
/// `ρ = |p|`, `α = wrap(−θ + atan2(−y, −x))`, `β = wrap(−θ − α)` of the pose in the goal
/// frame, `v = k_ρ ρ`, `ω = k_α α + k_β β`. No Lyapunov function is reported.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Astolfi {
    /// k_ρ > 0.
    pub k_rho: f64,
    /// k_α > k_ρ.
    pub k_alpha: f64,
    /// k_β < 0.
    pub k_beta: f64,
}

impl Astolfi {
    /// Gains checked against the local exponential stability conditions
    /// `k_ρ > 0`, `k_β < 0`, `k_α − k_ρ > 0`.
    ///
    /// # Errors
    /// The first violated condition, named (e.g. "k_beta < 0 violated: k_beta = 0.5").
    pub fn new(k_rho: f64, k_alpha: f64, k_beta: f64) -> Result<Self> {
        for (n, v) in [("k_rho", k_rho), ("k_alpha", k_alpha), ("k_beta", k_beta)] {
            if !v.is_finite() {
                return Err(Error::NonFinite {
                    field: format!("gains.{n}"),
                });
            }
        }
        if k_rho <= 0.0 {
            return Err(Error::invalid(
                "gains",
                format!("Astolfi condition k_rho > 0 violated: k_rho = {k_rho}"),
            ));
        }
        if k_beta >= 0.0 {
            return Err(Error::invalid(
                "gains",
                format!("Astolfi condition k_beta < 0 violated: k_beta = {k_beta}"),
            ));
        }
        if k_alpha - k_rho <= 0.0 {
            return Err(Error::invalid(
                "gains",
                format!(
                    "Astolfi condition k_alpha > k_rho violated: k_alpha = {k_alpha}, k_rho = {k_rho}"
                ),
            ));
        }
        Ok(Self {
            k_rho,
            k_alpha,
            k_beta,
        })
    }

    /// Whether the strong condition `k_α + (5/3) k_β − (2/π) k_ρ > 0` (α stays in
    /// (−π/2, π/2] for all time) holds.
    #[must_use]
    pub fn strong_condition(&self) -> bool {
        self.k_alpha + 5.0 / 3.0 * self.k_beta - 2.0 / std::f64::consts::PI * self.k_rho > 0.0
    }

    /// A warning text when the strong condition fails, `None` otherwise.
    #[must_use]
    pub fn warning(&self) -> Option<String> {
        (!self.strong_condition()).then(|| {
            format!(
                "Astolfi strong condition k_alpha + 5/3 k_beta - 2/pi k_rho > 0 fails \
                 ({} <= 0): alpha may leave (-pi/2, pi/2]",
                self.k_alpha + 5.0 / 3.0 * self.k_beta - 2.0 / std::f64::consts::PI * self.k_rho
            )
        })
    }

    /// Polar coordinates `[ρ, α, β]` of the pose in the goal frame.
    #[must_use]
    pub fn polar(state: &Pose, goal: &Pose) -> [f64; 3] {
        let [x, y, th] = pose_in_goal_frame(state, goal);
        let rho = x.hypot(y);
        let alpha = wrap_angle(-th + (-y).atan2(-x));
        [rho, alpha, wrap_angle(-th - alpha)]
    }

    /// The inputs `[v, ω]`.
    #[must_use]
    pub fn inputs(&self, state: &Pose, goal: &Pose) -> [f64; 2] {
        let [rho, alpha, beta] = Self::polar(state, goal);
        [self.k_rho * rho, self.k_alpha * alpha + self.k_beta * beta]
    }

    /// The linearised `(α, β)` dynamics `[[−(k_α − k_ρ), −k_β], [−k_ρ, 0]]`.
    #[must_use]
    pub fn linearisation(&self) -> nalgebra::Matrix2<f64> {
        nalgebra::Matrix2::new(-(self.k_alpha - self.k_rho), -self.k_beta, -self.k_rho, 0.0)
    }
}

impl Controller for Astolfi {
    type State = Pose;
    type Reference = Pose;
    type Actuation = [f64; 2];

    fn actuation(&mut self, _t: f64, s: &Pose, goal: &Pose, out: &mut [f64; 2]) -> Result<()> {
        *out = self.inputs(s, goal);
        Ok(())
    }
}

/// Aicardi, Casalino, Bicchi and Balestrino (1995) Lyapunov polar law (goal = reference
/// pose): `e = |p|`, `ϑ = atan2(−y, −x)`, `α = wrap(ϑ − θ)` of the pose in the goal
/// frame, `v = γ e cos α`, `ω = k α + γ (cos α sin α / α)(α + h ϑ)`;
/// `V = (λ e² + α² + h ϑ²)/2`, `V̇ = −λ γ e² cos² α − k α²` (λ = 1 here: the law does not
/// depend on λ, only the reported V does).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aicardi {
    /// γ > 0.
    pub gamma: f64,
    /// k > 0.
    pub k: f64,
    /// h > 0.
    pub h: f64,
    /// λ > 0, the weight of e² in V (1 by default).
    pub lambda: f64,
}

impl Aicardi {
    /// Validated gains (all > 0), λ = 1.
    ///
    /// # Errors
    /// A gain that is not positive and finite, naming it.
    pub fn new(gamma: f64, k: f64, h: f64) -> Result<Self> {
        check_gain("gamma", gamma)?;
        check_gain("k", k)?;
        check_gain("h", h)?;
        Ok(Self {
            gamma,
            k,
            h,
            lambda: 1.0,
        })
    }

    /// `[e, ϑ, α]` of the pose in the goal frame.
    #[must_use]
    pub fn polar(state: &Pose, goal: &Pose) -> [f64; 3] {
        let [x, y, th] = pose_in_goal_frame(state, goal);
        let theta = (-y).atan2(-x);
        [x.hypot(y), theta, wrap_angle(theta - th)]
    }

    /// The inputs `[v, ω]`.
    #[must_use]
    pub fn inputs(&self, state: &Pose, goal: &Pose) -> [f64; 2] {
        let [e, theta, alpha] = Self::polar(state, goal);
        let (sa, ca) = alpha.sin_cos();
        // sin α / α, continuous at α = 0.
        let sinc = if alpha.abs() < 1e-8 {
            1.0 - alpha * alpha / 6.0
        } else {
            sa / alpha
        };
        [
            self.gamma * e * ca,
            self.k * alpha + self.gamma * ca * sinc * (alpha + self.h * theta),
        ]
    }
}

impl Controller for Aicardi {
    type State = Pose;
    type Reference = Pose;
    type Actuation = [f64; 2];

    fn actuation(&mut self, _t: f64, s: &Pose, goal: &Pose, out: &mut [f64; 2]) -> Result<()> {
        *out = self.inputs(s, goal);
        Ok(())
    }

    fn lyapunov(&self, _t: f64, s: &Pose, goal: &Pose) -> Option<f64> {
        let [e, theta, alpha] = Self::polar(s, goal);
        Some(0.5 * (self.lambda * e * e + alpha * alpha + self.h * theta * theta))
    }

    fn lyapunov_rate(&self, _t: f64, s: &Pose, goal: &Pose) -> Option<f64> {
        let [e, _, alpha] = Self::polar(s, goal);
        let ca = alpha.cos();
        Some(-self.lambda * self.gamma * e * e * ca * ca - self.k * alpha * alpha)
    }
}

/// What [`WheelLimits`] changed.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Saturation {
    /// Whether any wheel exceeded its speed limit.
    pub speed: bool,
    /// Whether any wheel exceeded its torque limit.
    pub torque: bool,
    /// The factor (≤ 1) the wheel rates were scaled by (1 when not saturated).
    pub speed_scale: f64,
}

/// Wheel-speed and wheel-torque limits of a differential drive, applied through its wheel
/// map `[φ̇_L, φ̇_R] = W⁻¹ [v, ω]`.
///
/// Speed limits scale both wheel rates by the same factor, so the commanded path
/// curvature `ω/v` is kept and only the speed along it drops; torque limits clip each
/// wheel torque on its own (a torque command has no geometric meaning to preserve).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WheelLimits {
    /// The platform.
    pub drive: DiffDrive,
    /// Largest wheel rate |φ̇| (rad/s), > 0 (infinity: none).
    pub max_wheel_speed: f64,
    /// Largest wheel torque |τ| (N·m), > 0 (infinity: none).
    pub max_wheel_torque: f64,
}

impl WheelLimits {
    /// Validated limits.
    ///
    /// # Errors
    /// A limit that is not positive (NaN included).
    pub fn new(drive: DiffDrive, max_wheel_speed: f64, max_wheel_torque: f64) -> Result<Self> {
        for (n, v) in [
            ("max_wheel_speed", max_wheel_speed),
            ("max_wheel_torque", max_wheel_torque),
        ] {
            if v.is_nan() || v <= 0.0 {
                return Err(Error::invalid(n, format!("must be > 0, got {v}")));
            }
        }
        Ok(Self {
            drive,
            max_wheel_speed,
            max_wheel_torque,
        })
    }

    /// Limits platform inputs `[v, ω]` in place; returns what saturated.
    pub fn limit_inputs(&self, input: &mut [f64; 2]) -> Saturation {
        let wheels = self.drive.platform_to_wheel() * Vector2::new(input[0], input[1]);
        let peak = wheels.amax();
        let mut sat = Saturation {
            speed_scale: 1.0,
            ..Default::default()
        };
        if peak > self.max_wheel_speed {
            let s = self.max_wheel_speed / peak;
            input[0] *= s;
            input[1] *= s;
            sat.speed = true;
            sat.speed_scale = s;
        }
        sat
    }

    /// Clips wheel torques `[τ_L, τ_R]` in place; returns what saturated.
    pub fn limit_torques(&self, tau: &mut [f64; 2]) -> Saturation {
        let mut sat = Saturation {
            speed_scale: 1.0,
            ..Default::default()
        };
        for t in tau.iter_mut() {
            if t.abs() > self.max_wheel_torque {
                *t = t.signum() * self.max_wheel_torque;
                sat.torque = true;
            }
        }
        sat
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rng_state(i: u32) -> Pose {
        let f = |k: u32| ((f64::from(i * 7 + k) * 0.618_033_988_7).fract() - 0.5) * 4.0;
        [f(1), f(2), f(3)]
    }

    /// V̇ of each law equals the directional derivative of V along its own closed-loop
    /// field (central differences in state and time).
    #[test]
    fn lyapunov_rates_match_numerical_derivatives() {
        let kan = Kanayama::new(1.0, 4.0, 4.0).unwrap();
        let sam = Samson::new(1.3, 0.7, 1.9).unwrap();
        let aic = Aicardi::new(1.0, 3.0, 2.0).unwrap();
        let goal = [0.3, -0.2, 0.4];
        let reference = ConstantInputReference { vr: 0.5, wr: 0.2 };
        for i in 0..40 {
            let s = rng_state(i);
            let t = 0.37 * f64::from(i);
            let hstep = 1e-6;
            let along = |u: [f64; 2]| {
                let f = unicycle_rhs(&s, &u);
                let p = [
                    s[0] + hstep * f[0],
                    s[1] + hstep * f[1],
                    s[2] + hstep * f[2],
                ];
                let m = [
                    s[0] - hstep * f[0],
                    s[1] - hstep * f[1],
                    s[2] - hstep * f[2],
                ];
                (p, m)
            };
            // Kanayama: the reference moves too.
            let r = reference.at(t);
            let (p, m) = along(kan.inputs(&s, &r));
            let num = (kan.lyapunov(0.0, &p, &reference.at(t + hstep)).unwrap()
                - kan.lyapunov(0.0, &m, &reference.at(t - hstep)).unwrap())
                / (2.0 * hstep);
            let ana = kan.lyapunov_rate(t, &s, &r).unwrap();
            assert!(
                (num - ana).abs() < 1e-6 * (1.0 + ana.abs()),
                "kanayama {i}: {num} vs {ana}"
            );
            let (p, m) = along(sam.inputs(t, &s, &goal));
            let num = (sam.lyapunov(t, &p, &goal).unwrap() - sam.lyapunov(t, &m, &goal).unwrap())
                / (2.0 * hstep);
            let ana = sam.lyapunov_rate(t, &s, &goal).unwrap();
            assert!(
                (num - ana).abs() < 1e-6 * (1.0 + ana.abs()),
                "samson {i}: {num} vs {ana}"
            );
            let (p, m) = along(aic.inputs(&s, &goal));
            let num = (aic.lyapunov(t, &p, &goal).unwrap() - aic.lyapunov(t, &m, &goal).unwrap())
                / (2.0 * hstep);
            let ana = aic.lyapunov_rate(t, &s, &goal).unwrap();
            // α and ϑ jump where the robot crosses the goal's +x axis behind it; skip those.
            let pol = Aicardi::polar(&s, &goal);
            if pol[1].abs() < 3.0 && pol[2].abs() < 3.0 {
                assert!(
                    (num - ana).abs() < 1e-5 * (1.0 + ana.abs()),
                    "aicardi {i}: {num} vs {ana}"
                );
            }
        }
    }

    /// The chained transform satisfies z' = (u1, u2, z2 u1) for random states and inputs.
    #[test]
    fn samson_chained_form() {
        let goal = [0.0; 3];
        for i in 0..30 {
            let s = rng_state(i);
            let z = Samson::chained(&s, &goal);
            let (u1, u2) = (0.3 * f64::from(i) - 4.0, 1.1 - 0.05 * f64::from(i));
            let input = [u2 + z[2] * u1, u1];
            let f = unicycle_rhs(&s, &input);
            let h = 1e-6;
            let zp = Samson::chained(&[s[0] + h * f[0], s[1] + h * f[1], s[2] + h * f[2]], &goal);
            let zm = Samson::chained(&[s[0] - h * f[0], s[1] - h * f[1], s[2] - h * f[2]], &goal);
            let dz: Vec<f64> = (0..3).map(|k| (zp[k] - zm[k]) / (2.0 * h)).collect();
            assert!((dz[0] - u1).abs() < 1e-6);
            assert!((dz[1] - u2).abs() < 1e-6);
            assert!((dz[2] - z[1] * u1).abs() < 1e-6);
        }
    }

    /// theory.md 2.7 item 3: eigenvalues of the linearisation for the reference gains, and
    /// critical damping of the heading loop at K_y = K_θ²/4.
    #[test]
    fn kanayama_linearisation() {
        let k = Kanayama::new(1.0, 4.0, 4.0).unwrap();
        let ev = k.linearisation(0.5, 0.2).complex_eigenvalues();
        let mut got: Vec<(f64, f64)> = ev.iter().map(|c| (c.re, c.im)).collect();
        got.sort_by(|a, b| a.1.partial_cmp(&b.1).unwrap());
        let want = [
            (-0.848402, -0.330070),
            (-1.303196, 0.0),
            (-0.848402, 0.330070),
        ];
        for (g, w) in got.iter().zip(want) {
            assert!(
                (g.0 - w.0).abs() < 1e-6 && (g.1 - w.1).abs() < 1e-6,
                "{got:?}"
            );
        }
        // The linearisation is the Jacobian of the closed loop's error dynamics at zero
        // error, taken here by central differences of the law's own inputs on the
        // unicycle and the moving reference.
        for (kan, vr, wr) in [
            (k, 0.5, 0.2),
            (Kanayama::new(2.0, 2.25, 3.0).unwrap(), 0.7, 0.0),
        ] {
            let numeric = error_jacobian(&kan, vr, wr);
            let diff = (numeric - kan.linearisation(vr, wr)).amax();
            assert!(diff < 1e-4, "{diff}: {numeric}");
        }
        // On a straight reference the heading loop is e'' + v K_θ e' + v² K_y e = 0: at
        // K_y = K_θ²/4 a double real root −v K_θ / 2 (critical damping), a complex pair
        // above, two distinct real roots below; read from the numerical Jacobian.
        let (vr, kth) = (0.7, 3.0);
        for (ky, kind) in [(2.25, "critical"), (2.5, "complex"), (2.0, "real")] {
            // K_x = 3 keeps the along-track root −K_x apart from the heading roots
            let kan = Kanayama::new(3.0, ky, kth).unwrap();
            let ev = error_jacobian(&kan, vr, 0.0).complex_eigenvalues();
            let heading: Vec<_> = ev.iter().filter(|c| (c.re + 3.0).abs() > 0.1).collect();
            assert_eq!(heading.len(), 2, "{kind}: {ev:?}");
            let (a, b) = (heading[0], heading[1]);
            match kind {
                // a double root splits by about √(finite-difference error)
                "critical" => assert!(
                    (a.re + vr * kth / 2.0).abs() < 1e-2
                        && (b.re + vr * kth / 2.0).abs() < 1e-2
                        && a.im.abs() < 1e-2,
                    "{ev:?}"
                ),
                "complex" => assert!(a.im.abs() > 0.1, "{ev:?}"),
                _ => assert!(a.im.abs() < 1e-9 && (a.re - b.re).abs() > 0.1, "{ev:?}"),
            }
        }
    }

    /// The Jacobian of Kanayama's closed-loop error dynamics `ė(e)` at `e = 0` on the
    /// constant-input reference `(v_r, ω_r)`, by central differences: the robot starts at
    /// the error `e` (reference frame) from the reference pose at t = 1 s, both move for a
    /// step `h` (the robot with the law's inputs) and the error is read again.
    fn error_jacobian(kan: &Kanayama, vr: f64, wr: f64) -> nalgebra::Matrix3<f64> {
        let reference = ConstantInputReference { vr, wr };
        let error = |s: &Pose, r: &Pose| {
            let (sn, cs) = s[2].sin_cos();
            let (dx, dy) = (r[0] - s[0], r[1] - s[1]);
            [
                cs * dx + sn * dy,
                -sn * dx + cs * dy,
                crate::control::wrap_angle(r[2] - s[2]),
            ]
        };
        let rate = |e: [f64; 3]| {
            let t = 1.0;
            let r = reference.at(t);
            // the robot pose with error e: s = r − R(θ_s) e_xy, θ_s = θ_r − e_θ
            let th = r.pose[2] - e[2];
            let (sn, cs) = th.sin_cos();
            let s = [
                r.pose[0] - (cs * e[0] - sn * e[1]),
                r.pose[1] - (sn * e[0] + cs * e[1]),
                th,
            ];
            let f = unicycle_rhs(&s, &kan.inputs(&s, &r));
            let h = 1e-6;
            let sp = [s[0] + h * f[0], s[1] + h * f[1], s[2] + h * f[2]];
            let sm = [s[0] - h * f[0], s[1] - h * f[1], s[2] - h * f[2]];
            let (ep, em) = (
                error(&sp, &reference.at(t + h).pose),
                error(&sm, &reference.at(t - h).pose),
            );
            nalgebra::Vector3::from_fn(|i, _| (ep[i] - em[i]) / (2.0 * h))
        };
        let d = 1e-5;
        nalgebra::Matrix3::from_fn(|i, j| {
            let (mut p, mut m) = ([0.0; 3], [0.0; 3]);
            p[j] = d;
            m[j] = -d;
            (rate(p)[i] - rate(m)[i]) / (2.0 * d)
        })
    }

    #[test]
    fn astolfi_gain_conditions() {
        let a = Astolfi::new(3.0, 8.0, -1.5).unwrap();
        assert!(a.strong_condition() && a.warning().is_none());
        let e = Astolfi::new(3.0, 8.0, 0.5).unwrap_err().to_string();
        assert!(e.contains("k_beta < 0"), "{e}");
        let e = Astolfi::new(3.0, 3.0, -1.0).unwrap_err().to_string();
        assert!(e.contains("k_alpha > k_rho"), "{e}");
        let e = Astolfi::new(-1.0, 3.0, -1.0).unwrap_err().to_string();
        assert!(e.contains("k_rho > 0"), "{e}");
        let weak = Astolfi::new(1.0, 1.5, -1.0).unwrap();
        assert!(weak.warning().unwrap().contains("strong condition"));
        for ev in a.linearisation().complex_eigenvalues().iter() {
            assert!(ev.re < 0.0);
        }
        // theory.md 2.5: polar coordinates at the reference start.
        let p = Astolfi::polar(&[-1.0, -0.5, 0.3], &[0.0; 3]);
        for (g, w) in p
            .iter()
            .zip([1.118033988749895, 0.16364760900080633, -0.46364760900080615])
        {
            assert!((g - w).abs() < 1e-14);
        }
    }

    #[test]
    fn wheel_limits_keep_curvature_and_clip_torque() {
        let drive = DiffDrive::new(0.1, 0.25, 0.0).unwrap();
        let lim = WheelLimits::new(drive, 10.0, 2.0).unwrap();
        let mut u = [2.0, 1.0];
        let sat = lim.limit_inputs(&mut u);
        assert!(sat.speed);
        let w = drive.platform_to_wheel() * Vector2::new(u[0], u[1]);
        assert!((w.amax() - 10.0).abs() < 1e-12);
        assert!((u[1] / u[0] - 0.5).abs() < 1e-15);
        let mut small = [0.1, 0.1];
        assert!(!lim.limit_inputs(&mut small).speed);
        assert_eq!(small, [0.1, 0.1]);
        let mut tau = [3.0, -1.0];
        assert!(lim.limit_torques(&mut tau).torque);
        assert_eq!(tau, [2.0, -1.0]);
        assert!(WheelLimits::new(drive, 0.0, 1.0).is_err());
    }

    /// Brockett's condition 3 fails for the unicycle (theory.md 2.2): over |θ| ≤ θ_max and
    /// any (v, ω), the image of the crate's unicycle field `unicycle_rhs` stays a distance
    /// ε cos θ_max away from (0, ε, 0), so no neighbourhood of 0 is covered and no smooth
    /// time-invariant law stabilises a pose. Searched over a grid of θ, v and ω (the
    /// bound is attained at θ = ±θ_max, v = ε sin θ, ω = 0, which the grid holds).
    #[test]
    fn brockett_image_misses_sideways_direction() {
        let eps = 1e-2;
        for th_max in [0.3, 0.8, 1.2] {
            let mut best = f64::INFINITY;
            for k in 0..=200 {
                let th = -th_max + 2.0 * th_max * f64::from(k) / 200.0;
                for j in -100..=100 {
                    let v = eps * th_max.sin() * f64::from(j) / 100.0;
                    for w in [-0.01, 0.0, 0.01] {
                        let f = unicycle_rhs(&[0.3, -0.2, th], &[v, w]);
                        best =
                            best.min((f[0].powi(2) + (f[1] - eps).powi(2) + f[2].powi(2)).sqrt());
                    }
                }
            }
            // never below the bound, and the grid reaches it
            assert!(best >= eps * th_max.cos() - 1e-15, "{best}");
            assert!((best - eps * th_max.cos()).abs() < 1e-12, "{best}");
        }
    }
}

//! Conversions between moma's state layout and Pinocchio's, so states, torques, mass
//! matrices and Jacobians can be exchanged with Pinocchio as they are.
//!
//! The two layouts differ in two joint kinds only (every other joint, the free-flyer
//! included, has the same coordinates, and the URDF loader orders joints as urdfdom does):
//!
//! | joint | moma | Pinocchio |
//! | --- | --- | --- |
//! | planar root | `q = [x, y, θ]`, `v = [ẋ, ẏ, θ̇]` in world axes | `q = [x, y, cos θ, sin θ]`, `v = [v_x, v_y, ω]` in the base frame |
//! | continuous revolute (unbounded) | `q = [θ]` | `q = [cos θ, sin θ]` |
//!
//! With `R(θ)` the base heading and `T = diag(Rᵀ(θ), 1, I)` (nv × nv, orthogonal), a
//! Pinocchio velocity is `v_P = T v`. Generalised forces transform the same way, since
//! power is invariant and `T⁻¹ = Tᵀ`: `τ_P = T τ`. Hence the mass matrix transforms by
//! congruence, `H_P = T H Tᵀ`, and a Jacobian by its columns, `J_P = J Tᵀ` (rows are task
//! coordinates, unchanged). An acceleration picks up the time derivative of `T`: with
//! `ω = θ̇` and `S = [[0, −1], [1, 0]]` acting on the base's `(x, y)` rows,
//! `a_P = T (a − ω S v)` and `a = Tᵀ a_P + ω S v`, so it needs `q` and `v`.
//!
//! For the same reason the bias forces are not a `τ`-transform: Pinocchio's nonlinear
//! effects are RNEA at `a_P = 0`, i.e. at `a = ω S v` in moma's layout, so
//! `nle_P = T (nle + H ω S v)`; compute them as RNEA at
//! [`PinocchioLayout::a_from_pinocchio`] of a zero acceleration (likewise a Coriolis
//! matrix is not a congruence). Gravity, with no velocity, is.
//!
//! The free-flyer root is Pinocchio's already (`[x, y, z, qx, qy, qz, qw]`, base-frame
//! twist), as is every bounded revolute and prismatic joint, so a model without a planar
//! root and without continuous joints has the identity layout ([`PinocchioLayout::is_identity`]).
//!
//! ```
//! # use moma::{io::urdf::model_from_urdf_str, io::pinocchio_layout::PinocchioLayout};
//! # use moma::multibody::RootJoint;
//! # let urdf = r#"<robot name="r"><link name="base"><inertial><mass value="10"/>
//! #   <inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link></robot>"#;
//! let model = model_from_urdf_str(urdf, RootJoint::Planar, "r.urdf")?;
//! let layout = PinocchioLayout::new(&model);
//! assert_eq!((layout.nq(), layout.nv()), (4, 3));
//! let mut q = [0.0; 3];
//! layout.q_from_pinocchio(&[1.0, 2.0, 0.0, 1.0], &mut q)?;   // θ = π/2
//! assert!((q[2] - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
//! # Ok::<(), moma::Error>(())
//! ```

use nalgebra::{DMatrix, Dim, Dyn, Matrix, Matrix6xX, Storage, StorageMut};

use crate::error::{Error, Result, ensure_finite, ensure_len};
use crate::multibody::{JointType, Model};

/// How far from 1 the norm of a Pinocchio `(cos θ, sin θ)` pair may be.
pub const UNIT_PAIR_TOLERANCE: f64 = 1e-6;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    /// The same `n` coordinates in both layouts.
    Same(usize),
    /// Planar root: moma `[x, y, θ]`, Pinocchio `[x, y, cos θ, sin θ]`.
    Planar,
    /// Continuous revolute joint: moma `[θ]`, Pinocchio `[cos θ, sin θ]`.
    Continuous,
}

#[derive(Clone, Debug)]
struct JointMap {
    /// First coordinate in moma's q.
    iq: usize,
    /// First coordinate in Pinocchio's q.
    iq_pin: usize,
    kind: Kind,
    /// The joint's name (for error messages).
    name: String,
}

/// The map between a model's moma layout and Pinocchio's (see the module docs).
#[derive(Clone, Debug)]
pub struct PinocchioLayout {
    moma_nq: usize,
    pinocchio_nq: usize,
    nv: usize,
    joints: Vec<JointMap>,
    /// `(idx_q, idx_v)` of the planar root, if any.
    planar: Option<(usize, usize)>,
}

impl PinocchioLayout {
    /// The layout map of `model`. A revolute joint is continuous when its position range is
    /// unbounded on both sides (as the URDF loader makes `continuous` joints).
    #[must_use]
    pub fn new(model: &Model) -> Self {
        let mut joints = Vec::with_capacity(model.njoints.saturating_sub(1));
        let mut iq_pin = 0;
        let mut planar = None;
        for i in 1..model.njoints {
            let iq = model.idx_q[i];
            let kind = match model.joint_types[i] {
                JointType::Planar => {
                    planar = Some((iq, model.idx_v[i]));
                    Kind::Planar
                }
                jt if jt.is_revolute()
                    && model.lower_position_limit[iq] == f64::NEG_INFINITY
                    && model.upper_position_limit[iq] == f64::INFINITY =>
                {
                    Kind::Continuous
                }
                _ => Kind::Same(model.nqs[i]),
            };
            joints.push(JointMap {
                iq,
                iq_pin,
                kind,
                name: model.names[i].clone(),
            });
            iq_pin += match kind {
                Kind::Planar => 4,
                Kind::Continuous => 2,
                Kind::Same(n) => n,
            };
        }
        Self {
            moma_nq: model.nq,
            pinocchio_nq: iq_pin,
            nv: model.nv,
            joints,
            planar,
        }
    }

    /// Length of Pinocchio's configuration vector.
    #[must_use]
    pub fn nq(&self) -> usize {
        self.pinocchio_nq
    }

    /// Length of the velocity vector (the same in both layouts).
    #[must_use]
    pub fn nv(&self) -> usize {
        self.nv
    }

    /// True if the model has a planar root: the only joint whose velocities, torques and
    /// matrices differ between the two layouts (continuous joints differ in q only).
    #[must_use]
    pub fn has_planar_root(&self) -> bool {
        self.planar.is_some()
    }

    /// True when both layouts coincide (no planar root, no continuous joint).
    #[must_use]
    pub fn is_identity(&self) -> bool {
        self.planar.is_none() && self.joints.iter().all(|j| matches!(j.kind, Kind::Same(_)))
    }

    /// moma's `q` from Pinocchio's `q_pin` (length [`Self::nq`]) into `out` (the model's
    /// nq). Each `(cos θ, sin θ)` pair must have a norm within [`UNIT_PAIR_TOLERANCE`] of 1.
    ///
    /// # Errors
    /// [`Error::WrongLength`] for a `q_pin` of the wrong length, [`Error::NonFinite`] for a
    /// non-finite entry, [`Error::InvalidInput`] for a pair that is not unit (naming the
    /// joint).
    ///
    /// # Panics
    /// If `out` does not have the model's nq.
    pub fn q_from_pinocchio(&self, q_pin: &[f64], out: &mut [f64]) -> Result<()> {
        assert_eq!(out.len(), self.moma_nq, "out length");
        ensure_len("q (Pinocchio layout)", self.pinocchio_nq, q_pin.len())?;
        ensure_finite("q (Pinocchio layout)", q_pin)?;
        for j in &self.joints {
            let p = j.iq_pin;
            match j.kind {
                Kind::Same(n) => out[j.iq..j.iq + n].copy_from_slice(&q_pin[p..p + n]),
                Kind::Planar => {
                    out[j.iq] = q_pin[p];
                    out[j.iq + 1] = q_pin[p + 1];
                    out[j.iq + 2] = unit_angle(q_pin[p + 2], q_pin[p + 3], &j.name, p + 2)?;
                }
                Kind::Continuous => out[j.iq] = unit_angle(q_pin[p], q_pin[p + 1], &j.name, p)?,
            }
        }
        Ok(())
    }

    /// Pinocchio's `q` (length [`Self::nq`]) from moma's `q`.
    ///
    /// # Panics
    /// On wrong lengths.
    pub fn q_to_pinocchio(&self, q: &[f64], out: &mut [f64]) {
        assert_eq!(q.len(), self.moma_nq, "q length");
        assert_eq!(out.len(), self.pinocchio_nq, "out length");
        for j in &self.joints {
            let p = j.iq_pin;
            match j.kind {
                Kind::Same(n) => out[p..p + n].copy_from_slice(&q[j.iq..j.iq + n]),
                Kind::Planar => {
                    let (s, c) = q[j.iq + 2].sin_cos();
                    out[p] = q[j.iq];
                    out[p + 1] = q[j.iq + 1];
                    out[p + 2] = c;
                    out[p + 3] = s;
                }
                Kind::Continuous => {
                    let (s, c) = q[j.iq].sin_cos();
                    out[p] = c;
                    out[p + 1] = s;
                }
            }
        }
    }

    /// The planar root's `(cos θ, sin θ, idx_v)` at moma configuration `q`: on the base's
    /// `(x, y)` coordinates `T = Rᵀ(θ)`, with `R(θ) = [c −s; s c]`.
    pub(crate) fn heading(&self, q: &[f64]) -> Option<(f64, f64, usize)> {
        assert_eq!(q.len(), self.moma_nq, "q length");
        self.planar.map(|(iq, iv)| {
            let (s, c) = q[iq + 2].sin_cos();
            (c, s, iv)
        })
    }

    /// `out = T x` (a velocity or a generalised force into Pinocchio's layout) at moma
    /// configuration `q`; `x` and `out` have length nv and may not alias.
    ///
    /// # Panics
    /// On wrong lengths.
    pub fn v_to_pinocchio(&self, q: &[f64], x: &[f64], out: &mut [f64]) {
        self.apply(q, x, out, false);
    }

    /// `out = Tᵀ x_P` (a Pinocchio velocity or generalised force into moma's layout) at
    /// moma configuration `q`.
    ///
    /// # Panics
    /// On wrong lengths.
    pub fn v_from_pinocchio(&self, q: &[f64], x_pin: &[f64], out: &mut [f64]) {
        self.apply(q, x_pin, out, true);
    }

    /// `τ_P = T τ`: the same map as [`Self::v_to_pinocchio`] (T is orthogonal).
    ///
    /// # Panics
    /// On wrong lengths.
    pub fn tau_to_pinocchio(&self, q: &[f64], tau: &[f64], out: &mut [f64]) {
        self.apply(q, tau, out, false);
    }

    /// `τ = Tᵀ τ_P`: the same map as [`Self::v_from_pinocchio`].
    ///
    /// # Panics
    /// On wrong lengths.
    pub fn tau_from_pinocchio(&self, q: &[f64], tau_pin: &[f64], out: &mut [f64]) {
        self.apply(q, tau_pin, out, true);
    }

    fn apply(&self, q: &[f64], x: &[f64], out: &mut [f64], transpose: bool) {
        assert_eq!(x.len(), self.nv, "vector length");
        assert_eq!(out.len(), self.nv, "out length");
        out.copy_from_slice(x);
        if let Some((c, s, iv)) = self.heading(q) {
            let (x0, x1) = (x[iv], x[iv + 1]);
            if transpose {
                // R x
                out[iv] = c * x0 - s * x1;
                out[iv + 1] = s * x0 + c * x1;
            } else {
                // Rᵀ x
                out[iv] = c * x0 + s * x1;
                out[iv + 1] = -s * x0 + c * x1;
            }
        }
    }

    /// Pinocchio's acceleration `a_P = T (a − ω S v)` from moma's `(q, v, a)`.
    ///
    /// # Panics
    /// On wrong lengths.
    pub fn a_to_pinocchio(&self, q: &[f64], v: &[f64], a: &[f64], out: &mut [f64]) {
        assert_eq!(v.len(), self.nv, "v length");
        assert_eq!(a.len(), self.nv, "a length");
        assert_eq!(out.len(), self.nv, "out length");
        out.copy_from_slice(a);
        if let Some((c, s, iv)) = self.heading(q) {
            let w = v[iv + 2];
            let a0 = a[iv] + w * v[iv + 1];
            let a1 = a[iv + 1] - w * v[iv];
            out[iv] = c * a0 + s * a1;
            out[iv + 1] = -s * a0 + c * a1;
        }
    }

    /// moma's acceleration `a = Tᵀ a_P + ω S v` from moma's `(q, v)` and Pinocchio's `a_P`.
    ///
    /// # Panics
    /// On wrong lengths.
    pub fn a_from_pinocchio(&self, q: &[f64], v: &[f64], a_pin: &[f64], out: &mut [f64]) {
        assert_eq!(v.len(), self.nv, "v length");
        assert_eq!(a_pin.len(), self.nv, "a length");
        assert_eq!(out.len(), self.nv, "out length");
        out.copy_from_slice(a_pin);
        if let Some((c, s, iv)) = self.heading(q) {
            let w = v[iv + 2];
            let (p0, p1) = (a_pin[iv], a_pin[iv + 1]);
            out[iv] = c * p0 - s * p1 - w * v[iv + 1];
            out[iv + 1] = s * p0 + c * p1 + w * v[iv];
        }
    }

    /// Pinocchio's `H_P = T H Tᵀ` from moma's nv × nv matrix `h` (a mass matrix or any
    /// map from velocities to generalised forces that transforms by congruence).
    ///
    /// # Panics
    /// On wrong sizes.
    pub fn matrix_to_pinocchio(&self, q: &[f64], h: &DMatrix<f64>, out: &mut DMatrix<f64>) {
        self.congruence(q, h, out, false);
    }

    /// moma's `H = Tᵀ H_P T` from Pinocchio's nv × nv matrix `h_pin`.
    ///
    /// # Panics
    /// On wrong sizes.
    pub fn matrix_from_pinocchio(&self, q: &[f64], h_pin: &DMatrix<f64>, out: &mut DMatrix<f64>) {
        self.congruence(q, h_pin, out, true);
    }

    fn congruence(&self, q: &[f64], h: &DMatrix<f64>, out: &mut DMatrix<f64>, transpose: bool) {
        assert_eq!(h.shape(), (self.nv, self.nv), "matrix size");
        assert_eq!(out.shape(), (self.nv, self.nv), "out size");
        out.copy_from(h);
        if let Some((c, s, iv)) = self.heading(q) {
            let s = if transpose { -s } else { s };
            // M = Rᵀ(θ) on the base block (or R(θ) when transposing): rows then columns.
            rotate_rows(out, iv, c, s);
            rotate_cols(out, iv, c, s);
        }
    }

    /// Pinocchio's Jacobian `J_P = J Tᵀ` (any number of rows, nv columns) from moma's `j`.
    ///
    /// # Panics
    /// On wrong sizes.
    pub fn jacobian_to_pinocchio(&self, q: &[f64], j: &DMatrix<f64>, out: &mut DMatrix<f64>) {
        self.columns(q, j, out, false);
    }

    /// moma's Jacobian `J = J_P T` from Pinocchio's `j_pin`.
    ///
    /// # Panics
    /// On wrong sizes.
    pub fn jacobian_from_pinocchio(&self, q: &[f64], j_pin: &DMatrix<f64>, out: &mut DMatrix<f64>) {
        self.columns(q, j_pin, out, true);
    }

    /// `m ← T m` in place, for a matrix whose rows are velocity (or generalised-force)
    /// coordinates and whose columns are not, such as the dynamically consistent inverse
    /// J̄ (nv × m): `J̄_P = T J̄`.
    ///
    /// # Panics
    /// If `m` does not have nv rows or `q` the model's nq.
    pub fn rows_to_pinocchio_in_place(&self, q: &[f64], m: &mut DMatrix<f64>) {
        assert_eq!(m.nrows(), self.nv, "matrix rows");
        if let Some((c, s, iv)) = self.heading(q) {
            rotate_rows(m, iv, c, s);
        }
    }

    /// `m ← m Tᵀ` in place, for a matrix whose columns are velocity coordinates (a
    /// Jacobian); with [`Self::rows_to_pinocchio_in_place`] it makes the congruence
    /// `T m Tᵀ` of an nv × nv matrix (a mass matrix, a null-space projector).
    ///
    /// # Panics
    /// If `m` does not have nv columns or `q` the model's nq.
    pub fn columns_to_pinocchio_in_place(&self, q: &[f64], m: &mut DMatrix<f64>) {
        assert_eq!(m.ncols(), self.nv, "matrix columns");
        if let Some((c, s, iv)) = self.heading(q) {
            rotate_cols(m, iv, c, s);
        }
    }

    /// Pinocchio's derivatives of τ = RNEA(q, v, a), in place, from moma's `dq = ∂τ/∂q`,
    /// `dv = ∂τ/∂v` and `m = ∂τ/∂a = H` at moma's `(q, v, a)` with `tau` = RNEA(q, v, a).
    ///
    /// Pinocchio's τ_P(q_P, v_P, a_P) = T τ(q, Tᵀ v_P, Tᵀ a_P + ω Ŝ Tᵀ v_P) (module
    /// docs), its q perturbation is in the base frame (`dq_moma = Tᵀ δq_P`), and T turns
    /// with θ (`dT/dθ = −T Ŝ`), where Ŝ is the nv × nv matrix with `[[0, −1], [1, 0]]` on
    /// the base's (x, y) block. The chain rule gives
    ///
    /// * `H_P = T H Tᵀ`,
    /// * `∂τ_P/∂v_P = T (∂τ/∂v + H (ω Ŝ + Ŝ v e_ωᵀ)) Tᵀ`,
    /// * `∂τ_P/∂q_P = T (∂τ/∂q + (∂τ/∂v Ŝ v + H Ŝ a − Ŝ τ) e_θᵀ) Tᵀ`,
    ///
    /// with `e_θ = e_ω` the heading's velocity coordinate. Nothing changes without a
    /// planar root. Does not allocate.
    ///
    /// # Panics
    /// On wrong sizes.
    #[allow(clippy::too_many_arguments)]
    pub fn rnea_derivatives_to_pinocchio(
        &self,
        q: &[f64],
        v: &[f64],
        a: &[f64],
        tau: &[f64],
        dq: &mut DMatrix<f64>,
        dv: &mut DMatrix<f64>,
        m: &mut DMatrix<f64>,
    ) {
        self.check_derivative_sizes(&[v, a, tau], &[dq, dv, m]);
        if let Some((c, s, iv)) = self.heading(q) {
            let it = iv + 2;
            for r in 0..self.nv {
                dq[(r, it)] +=
                    skew_mul(dv, r, iv, v) + skew_mul(m, r, iv, a) - skew_vec(tau, r, iv);
            }
            add_heading_rate_terms(dv, m, v, iv, 1.0);
            for x in [dq, dv, m] {
                rotate_rows(x, iv, c, s);
                rotate_cols(x, iv, c, s);
            }
        }
    }

    /// The inverse of [`Self::rnea_derivatives_to_pinocchio`]: moma's `∂τ/∂q`, `∂τ/∂v`
    /// and H, in place, from Pinocchio's, at moma's `(q, v, a)` with moma's `tau` =
    /// RNEA(q, v, a). Does not allocate.
    ///
    /// # Panics
    /// On wrong sizes.
    #[allow(clippy::too_many_arguments)]
    pub fn rnea_derivatives_from_pinocchio(
        &self,
        q: &[f64],
        v: &[f64],
        a: &[f64],
        tau: &[f64],
        dq: &mut DMatrix<f64>,
        dv: &mut DMatrix<f64>,
        m: &mut DMatrix<f64>,
    ) {
        self.check_derivative_sizes(&[v, a, tau], &[dq, dv, m]);
        if let Some((c, s, iv)) = self.heading(q) {
            for x in [&mut *dq, &mut *dv, &mut *m] {
                rotate_rows(x, iv, c, -s);
                rotate_cols(x, iv, c, -s);
            }
            add_heading_rate_terms(dv, m, v, iv, -1.0);
            let it = iv + 2;
            for r in 0..self.nv {
                dq[(r, it)] -=
                    skew_mul(dv, r, iv, v) + skew_mul(m, r, iv, a) - skew_vec(tau, r, iv);
            }
        }
    }

    /// Pinocchio's derivatives of q̈ = ABA(q, v, τ), in place, from moma's `dq = ∂q̈/∂q`,
    /// `dv = ∂q̈/∂v` and `minv = H⁻¹` at moma's `(q, v, τ)` with `ddq` = ABA(q, v, τ).
    ///
    /// With q̈_P = T (q̈ − ω Ŝ v) and the same T, Ŝ as
    /// [`Self::rnea_derivatives_to_pinocchio`]:
    ///
    /// * `H_P⁻¹ = T H⁻¹ Tᵀ`,
    /// * `∂q̈_P/∂v_P = T (∂q̈/∂v − ω Ŝ − Ŝ v e_ωᵀ) Tᵀ`,
    /// * `∂q̈_P/∂q_P = T (∂q̈/∂q + (∂q̈/∂v Ŝ v − Ŝ q̈ + H⁻¹ Ŝ τ) e_θᵀ) Tᵀ`.
    ///
    /// Does not allocate.
    ///
    /// # Panics
    /// On wrong sizes.
    #[allow(clippy::too_many_arguments)]
    pub fn aba_derivatives_to_pinocchio(
        &self,
        q: &[f64],
        v: &[f64],
        tau: &[f64],
        ddq: &[f64],
        dq: &mut DMatrix<f64>,
        dv: &mut DMatrix<f64>,
        minv: &mut DMatrix<f64>,
    ) {
        self.check_derivative_sizes(&[v, tau, ddq], &[dq, dv, minv]);
        if let Some((c, s, iv)) = self.heading(q) {
            let (it, w) = (iv + 2, v[iv + 2]);
            for r in 0..self.nv {
                dq[(r, it)] +=
                    skew_mul(dv, r, iv, v) - skew_vec(ddq, r, iv) + skew_mul(minv, r, iv, tau);
            }
            // − ω Ŝ − Ŝ v e_ωᵀ
            dv[(iv, iv + 1)] += w;
            dv[(iv + 1, iv)] -= w;
            dv[(iv, it)] += v[iv + 1];
            dv[(iv + 1, it)] -= v[iv];
            for x in [dq, dv, minv] {
                rotate_rows(x, iv, c, s);
                rotate_cols(x, iv, c, s);
            }
        }
    }

    /// moma's derivatives of a frame's velocity (6 × nv each, [`crate::dynamics`]'s
    /// `frame_velocity_derivatives`), in place, from the ones with respect to Pinocchio's
    /// tangent `q_P` and velocity `v_P`, at moma's `(q, v)`.
    ///
    /// The frame's twist is a function of the state, `V(q, v) = V_P(q_P, T v)` with
    /// `δq_P = T δq` and `dT/dθ = −T Ŝ` (see [`Self::rnea_derivatives_to_pinocchio`]):
    ///
    /// * `∂V/∂v = ∂V_P/∂v_P T`,
    /// * `∂V/∂q = ∂V_P/∂q_P T − (∂V_P/∂v_P T) Ŝ v e_θᵀ`.
    ///
    /// The rows (the frame's twist, in any reference frame) are untouched. Does not
    /// allocate.
    ///
    /// # Panics
    /// On wrong sizes.
    pub fn frame_velocity_derivatives_from_pinocchio(
        &self,
        q: &[f64],
        v: &[f64],
        dv_dq: &mut Matrix6xX<f64>,
        dv_dv: &mut Matrix6xX<f64>,
    ) {
        self.frame_velocity_chain(q, v, dv_dq, dv_dv, -1.0);
    }

    /// The inverse of [`Self::frame_velocity_derivatives_from_pinocchio`]: Pinocchio's
    /// `getFrameVelocityDerivatives` from moma's, in place. Does not allocate.
    ///
    /// # Panics
    /// On wrong sizes.
    pub fn frame_velocity_derivatives_to_pinocchio(
        &self,
        q: &[f64],
        v: &[f64],
        dv_dq: &mut Matrix6xX<f64>,
        dv_dv: &mut Matrix6xX<f64>,
    ) {
        self.frame_velocity_chain(q, v, dv_dq, dv_dv, 1.0);
    }

    fn frame_velocity_chain(
        &self,
        q: &[f64],
        v: &[f64],
        dq: &mut Matrix6xX<f64>,
        dv: &mut Matrix6xX<f64>,
        sign: f64,
    ) {
        assert_eq!(v.len(), self.nv, "vector length");
        assert_eq!(dq.ncols(), self.nv, "matrix columns");
        assert_eq!(dv.ncols(), self.nv, "matrix columns");
        if let Some((c, s, iv)) = self.heading(q) {
            if sign < 0.0 {
                // from Pinocchio: columns by T, then the heading's column
                rotate_cols(dq, iv, c, -s);
                rotate_cols(dv, iv, c, -s);
            }
            for r in 0..6 {
                dq[(r, iv + 2)] += sign * skew_mul(dv, r, iv, v);
            }
            if sign > 0.0 {
                rotate_cols(dq, iv, c, s);
                rotate_cols(dv, iv, c, s);
            }
        }
    }

    /// moma's derivatives of a frame's twist and acceleration (6 × nv each,
    /// [`crate::dynamics`]'s `frame_acceleration_derivatives`: ∂V/∂q, ∂A/∂q, ∂A/∂v,
    /// ∂A/∂a), in place, from the ones with respect to Pinocchio's `q_P`, `v_P`, `a_P`, at
    /// moma's `(q, v, a)`.
    ///
    /// ∂V/∂q as [`Self::frame_velocity_derivatives_from_pinocchio`] (with
    /// ∂V_P/∂v_P = ∂A_P/∂a_P); with `a_P = T (a − ω Ŝ v)` (module docs):
    ///
    /// * `∂A/∂a = ∂A_P/∂a_P T`,
    /// * `∂A/∂v = ∂A_P/∂v_P T − ∂A/∂a (ω Ŝ + Ŝ v e_ωᵀ)`,
    /// * `∂A/∂q = ∂A_P/∂q_P T − (∂A_P/∂v_P T) Ŝ v e_θᵀ − ∂A/∂a Ŝ (a − ω Ŝ v) e_θᵀ`.
    ///
    /// Does not allocate.
    ///
    /// # Panics
    /// On wrong sizes.
    #[allow(clippy::too_many_arguments)]
    pub fn frame_acceleration_derivatives_from_pinocchio(
        &self,
        q: &[f64],
        v: &[f64],
        a: &[f64],
        dv_dq: &mut Matrix6xX<f64>,
        da_dq: &mut Matrix6xX<f64>,
        da_dv: &mut Matrix6xX<f64>,
        da_da: &mut Matrix6xX<f64>,
    ) {
        self.frame_acceleration_chain(q, v, a, [dv_dq, da_dq, da_dv, da_da], -1.0);
    }

    /// The inverse of [`Self::frame_acceleration_derivatives_from_pinocchio`]: Pinocchio's
    /// `getFrameAccelerationDerivatives` from moma's, in place. Does not allocate.
    ///
    /// # Panics
    /// On wrong sizes.
    #[allow(clippy::too_many_arguments)]
    pub fn frame_acceleration_derivatives_to_pinocchio(
        &self,
        q: &[f64],
        v: &[f64],
        a: &[f64],
        dv_dq: &mut Matrix6xX<f64>,
        da_dq: &mut Matrix6xX<f64>,
        da_dv: &mut Matrix6xX<f64>,
        da_da: &mut Matrix6xX<f64>,
    ) {
        self.frame_acceleration_chain(q, v, a, [dv_dq, da_dq, da_dv, da_da], 1.0);
    }

    fn frame_acceleration_chain(
        &self,
        q: &[f64],
        v: &[f64],
        a: &[f64],
        [vq, dq, dv, da]: [&mut Matrix6xX<f64>; 4],
        sign: f64,
    ) {
        assert_eq!(v.len(), self.nv, "vector length");
        assert_eq!(a.len(), self.nv, "vector length");
        for m in [&*vq, &*dq, &*dv, &*da] {
            assert_eq!(m.ncols(), self.nv, "matrix columns");
        }
        let Some((c, s, iv)) = self.heading(q) else {
            return;
        };
        let w = v[iv + 2];
        if sign < 0.0 {
            for m in [&mut *vq, &mut *dq, &mut *dv, &mut *da] {
                rotate_cols(m, iv, c, -s);
            }
        } else {
            // back to ∂A_P/∂v_P T
            add_heading_rate_terms(dv, &*da, v, iv, 1.0);
        }
        // now dv = ∂A_P/∂v_P T and da = ∂A/∂a = ∂V/∂v, in both directions
        for r in 0..6 {
            let sa =
                skew_mul(&*da, r, iv, a) + w * (da[(r, iv)] * v[iv] + da[(r, iv + 1)] * v[iv + 1]);
            dq[(r, iv + 2)] += sign * (skew_mul(&*dv, r, iv, v) + sa);
            vq[(r, iv + 2)] += sign * skew_mul(&*da, r, iv, v);
        }
        if sign < 0.0 {
            add_heading_rate_terms(dv, &*da, v, iv, -1.0);
        } else {
            for m in [&mut *vq, &mut *dq, &mut *dv, &mut *da] {
                rotate_cols(m, iv, c, s);
            }
        }
    }

    fn check_derivative_sizes(&self, vectors: &[&[f64]], matrices: &[&DMatrix<f64>]) {
        for x in vectors {
            assert_eq!(x.len(), self.nv, "vector length");
        }
        for m in matrices {
            assert_eq!(m.shape(), (self.nv, self.nv), "matrix size");
        }
    }

    fn columns(&self, q: &[f64], j: &DMatrix<f64>, out: &mut DMatrix<f64>, transpose: bool) {
        assert_eq!(j.ncols(), self.nv, "Jacobian columns");
        assert_eq!(out.shape(), j.shape(), "out size");
        out.copy_from(j);
        if let Some((c, s, iv)) = self.heading(q) {
            rotate_cols(out, iv, c, if transpose { -s } else { s });
        }
    }
}

/// Row `r` of `m Ŝ x`, Ŝ acting on the base's (x, y) coordinates `iv, iv + 1`:
/// `−m[r, iv] x[iv + 1] + m[r, iv + 1] x[iv]`.
fn skew_mul<R: Dim, S: Storage<f64, R, Dyn>>(
    m: &Matrix<f64, R, Dyn, S>,
    r: usize,
    iv: usize,
    x: &[f64],
) -> f64 {
    -m[(r, iv)] * x[iv + 1] + m[(r, iv + 1)] * x[iv]
}

/// Entry `r` of `Ŝ x`.
fn skew_vec(x: &[f64], r: usize, iv: usize) -> f64 {
    if r == iv {
        -x[iv + 1]
    } else if r == iv + 1 {
        x[iv]
    } else {
        0.0
    }
}

/// `dv += sign · m (ω Ŝ + Ŝ v e_ωᵀ)` with ω = v[iv + 2]: the terms of ∂τ/∂v that the
/// base-frame velocity adds through the acceleration map.
fn add_heading_rate_terms<R: Dim, S: StorageMut<f64, R, Dyn>, T: Storage<f64, R, Dyn>>(
    dv: &mut Matrix<f64, R, Dyn, S>,
    m: &Matrix<f64, R, Dyn, T>,
    v: &[f64],
    iv: usize,
    sign: f64,
) {
    let w = v[iv + 2];
    for r in 0..m.nrows() {
        let (m0, m1) = (m[(r, iv)], m[(r, iv + 1)]);
        dv[(r, iv)] += sign * w * m1;
        dv[(r, iv + 1)] -= sign * w * m0;
        dv[(r, iv + 2)] += sign * (-m0 * v[iv + 1] + m1 * v[iv]);
    }
}

/// Rows `iv, iv + 1` of `m` replaced by `[c s; −s c]` times them.
fn rotate_rows(m: &mut DMatrix<f64>, iv: usize, c: f64, s: f64) {
    for k in 0..m.ncols() {
        let (a, b) = (m[(iv, k)], m[(iv + 1, k)]);
        m[(iv, k)] = c * a + s * b;
        m[(iv + 1, k)] = -s * a + c * b;
    }
}

/// Columns `iv, iv + 1` of `m` replaced by them times `[c s; −s c]ᵀ`.
fn rotate_cols<R: Dim, S: StorageMut<f64, R, Dyn>>(
    m: &mut Matrix<f64, R, Dyn, S>,
    iv: usize,
    c: f64,
    s: f64,
) {
    for r in 0..m.nrows() {
        let (a, b) = (m[(r, iv)], m[(r, iv + 1)]);
        m[(r, iv)] = c * a + s * b;
        m[(r, iv + 1)] = -s * a + c * b;
    }
}

/// `atan2(s, c)` of a pair whose norm must be 1 (within [`UNIT_PAIR_TOLERANCE`]).
fn unit_angle(c: f64, s: f64, joint: &str, at: usize) -> Result<f64> {
    let n = c.hypot(s);
    if (n - 1.0).abs() > UNIT_PAIR_TOLERANCE {
        return Err(Error::invalid(
            format!("q (Pinocchio layout) [{at}..{}] of joint '{joint}'", at + 2),
            format!("(cos θ, sin θ) must have norm 1 (within {UNIT_PAIR_TOLERANCE:e}), got {n}"),
        ));
    }
    Ok(s.atan2(c))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::io::urdf::model_from_urdf_str;
    use crate::multibody::RootJoint;
    use nalgebra::DVector;

    const URDF: &str = r#"<robot name="r">
      <link name="base"><inertial><mass value="10"/><origin xyz="0.1 0 0.3"/>
        <inertia ixx="1" iyy="1" izz="1" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <link name="l1"><inertial><mass value="1"/><origin xyz="0.2 0 0"/>
        <inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <link name="l2"><inertial><mass value="1"/><origin xyz="0.2 0 0"/>
        <inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="j1" type="continuous"><parent link="base"/><child link="l1"/>
        <origin xyz="0 0 0.5"/><axis xyz="0 0 1"/></joint>
      <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
        <origin xyz="0.4 0 0"/><axis xyz="0 1 0"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>
    </robot>"#;

    fn layout() -> PinocchioLayout {
        PinocchioLayout::new(&model_from_urdf_str(URDF, RootJoint::Planar, "r.urdf").unwrap())
    }

    #[test]
    fn sizes_and_round_trips() {
        let l = layout();
        assert_eq!((l.nq(), l.nv()), (7, 5));
        assert!(!l.is_identity());
        let q = [0.3, -0.2, 2.5, -3.0, 0.7];
        let mut qp = [0.0; 7];
        l.q_to_pinocchio(&q, &mut qp);
        assert_eq!(&qp[..2], &[0.3, -0.2]);
        assert!((qp[2] - 2.5f64.cos()).abs() < 1e-15 && (qp[5] - (-3.0f64).sin()).abs() < 1e-15);
        let mut back = [0.0; 5];
        l.q_from_pinocchio(&qp, &mut back).unwrap();
        for k in 0..5 {
            assert!((back[k] - q[k]).abs() < 1e-14, "{k}");
        }
        let v = [0.4, 0.1, -0.8, 1.0, 2.0];
        let a = [1.5, -0.5, 0.3, 0.2, -0.1];
        let (mut vp, mut vb, mut ap, mut ab) = ([0.0; 5], [0.0; 5], [0.0; 5], [0.0; 5]);
        l.v_to_pinocchio(&q, &v, &mut vp);
        l.v_from_pinocchio(&q, &vp, &mut vb);
        l.a_to_pinocchio(&q, &v, &a, &mut ap);
        l.a_from_pinocchio(&q, &v, &ap, &mut ab);
        for k in 0..5 {
            assert!((vb[k] - v[k]).abs() < 1e-14 && (ab[k] - a[k]).abs() < 1e-14);
        }
        // base-frame speed: |v_P| = |v| on the base block, and the arm is untouched
        assert!((vp[0].hypot(vp[1]) - v[0].hypot(v[1])).abs() < 1e-15);
        assert_eq!(&vp[2..], &v[2..]);
    }

    #[test]
    fn acceleration_is_the_derivative_of_the_base_frame_velocity() {
        // v_P(t) = Rᵀ(θ(t)) v(t): central difference of a smooth motion against a_P.
        let l = layout();
        let state = |t: f64| {
            let q = [0.0, 0.0, 0.4 + 0.9 * t + 0.3 * t * t, 0.0, 0.0];
            let v = [1.0 + 0.5 * t, -0.3 + 0.2 * t * t, 0.9 + 0.6 * t, 0.0, 0.0];
            let a = [0.5, 0.4 * t, 0.6, 0.0, 0.0];
            (q, v, a)
        };
        let (h, t) = (1e-5, 0.7);
        let vp_at = |t| {
            let (q, v, _) = state(t);
            let mut out = [0.0; 5];
            l.v_to_pinocchio(&q, &v, &mut out);
            out
        };
        let (vp1, vp0) = (vp_at(t + h), vp_at(t - h));
        let (q, v, a) = state(t);
        let mut ap = [0.0; 5];
        l.a_to_pinocchio(&q, &v, &a, &mut ap);
        for k in 0..3 {
            let fd = (vp1[k] - vp0[k]) / (2.0 * h);
            assert!((fd - ap[k]).abs() < 1e-8, "{k}: {fd} vs {}", ap[k]);
        }
    }

    #[test]
    fn matrices_follow_the_vectors() {
        let l = layout();
        let q = [0.0, 0.0, 1.1, 0.0, 0.0];
        let h = DMatrix::from_fn(5, 5, |i, j| 1.0 / (1.0 + i as f64 + j as f64));
        let j = DMatrix::from_fn(6, 5, |i, j| (i * 5 + j) as f64 * 0.1 - 1.0);
        let v = DVector::from_vec(vec![0.3, -0.7, 0.2, 1.0, -1.0]);
        let (mut vp, mut hp, mut jp) = (
            DVector::zeros(5),
            DMatrix::zeros(5, 5),
            DMatrix::zeros(6, 5),
        );
        l.v_to_pinocchio(&q, v.as_slice(), vp.as_mut_slice());
        l.matrix_to_pinocchio(&q, &h, &mut hp);
        l.jacobian_to_pinocchio(&q, &j, &mut jp);
        // the same twist and the same power in either layout
        assert!((&j * &v - &jp * &vp).norm() < 1e-13);
        assert!((v.dot(&(&h * &v)) - vp.dot(&(&hp * &vp))).abs() < 1e-13);
        let mut tau_p = DVector::zeros(5);
        l.tau_to_pinocchio(&q, (&h * &v).as_slice(), tau_p.as_mut_slice());
        assert!((&hp * &vp - &tau_p).norm() < 1e-13);
        let (mut hb, mut jb) = (DMatrix::zeros(5, 5), DMatrix::zeros(6, 5));
        l.matrix_from_pinocchio(&q, &hp, &mut hb);
        l.jacobian_from_pinocchio(&q, &jp, &mut jb);
        assert!((hb - h).norm() < 1e-14 && (jb - j).norm() < 1e-14);
    }

    #[test]
    fn in_place_maps_equal_the_copying_ones() {
        let l = layout();
        let q = [0.0, 0.0, -0.7, 0.0, 0.0];
        let h = DMatrix::from_fn(5, 5, |i, j| 1.0 / (1.0 + i as f64 + j as f64));
        let jb = DMatrix::from_fn(5, 3, |i, j| (i * 3 + j) as f64 * 0.1 - 0.4);
        let (mut hp, mut jt) = (DMatrix::zeros(5, 5), DMatrix::zeros(3, 5));
        l.matrix_to_pinocchio(&q, &h, &mut hp);
        l.jacobian_to_pinocchio(&q, &jb.transpose(), &mut jt);
        let mut h2 = h.clone();
        l.rows_to_pinocchio_in_place(&q, &mut h2);
        l.columns_to_pinocchio_in_place(&q, &mut h2);
        assert!((h2 - hp).norm() < 1e-15);
        // T J̄ = (J̄ᵀ Tᵀ)ᵀ
        let mut j2 = jb.clone();
        l.rows_to_pinocchio_in_place(&q, &mut j2);
        assert!((j2 - jt.transpose()).norm() < 1e-15);
        assert!(
            (jb[(0, 0)] - jt[(0, 0)]).abs() > 1e-3,
            "the heading must act"
        );
    }

    #[test]
    fn bad_pinocchio_configurations_are_errors() {
        let l = layout();
        let mut out = [0.0; 5];
        let e = l.q_from_pinocchio(&[0.0; 6], &mut out).unwrap_err();
        assert!(
            matches!(
                e,
                Error::WrongLength {
                    expected: 7,
                    got: 6,
                    ..
                }
            ),
            "{e}"
        );
        let e = l
            .q_from_pinocchio(&[0.0, 0.0, 1.0, 0.0, 0.5, 0.5, 0.0], &mut out)
            .unwrap_err();
        assert!(e.to_string().contains("joint 'j1'"), "{e}");
        let e = l
            .q_from_pinocchio(&[0.0, 0.0, 1.0, f64::NAN, 1.0, 0.0, 0.0], &mut out)
            .unwrap_err();
        assert!(matches!(e, Error::NonFinite { .. }), "{e}");
    }

    #[test]
    fn fixed_arm_without_continuous_joints_is_the_identity() {
        let urdf = URDF.replace(
            r#"type="continuous"><parent link="base"/><child link="l1"/>
        <origin xyz="0 0 0.5"/><axis xyz="0 0 1"/>"#,
            r#"type="revolute"><parent link="base"/><child link="l1"/>
        <origin xyz="0 0 0.5"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/>"#,
        );
        let m = model_from_urdf_str(&urdf, RootJoint::Fixed, "r.urdf").unwrap();
        assert!(PinocchioLayout::new(&m).is_identity());
        let m = model_from_urdf_str(&urdf, RootJoint::FreeFlyer, "r.urdf").unwrap();
        assert!(PinocchioLayout::new(&m).is_identity());
    }
}

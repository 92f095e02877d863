//! The chapter's robots (m1–m6) in their own coordinates, closed form.
//!
//! Each model follows the project's clean specification of the chapter (the printed
//! equations have lost signs and contain several errors; see `docs/chapter.md`):
//!
//! | model | robot | coordinates |
//! | --- | --- | --- |
//! | [`m1_unicycle`] | differential-drive platform | `q = [x, y, φ]`, `v = [v_F, v_T]` |
//! | [`m2_platform_arm`] | platform + horizontal two-link arm | `q = [x, y, φ, θ1, θ2]` |
//! | [`m3_diffdrive`] | wheel-rate kinematics, whole-body Jacobian | `q = [x, y, φ, φ1, θ1, θ2]` |
//! | [`m4_cart_two_link`] | cart + two-link arm in a vertical plane | `q = [d0, θ1, θ2]` |
//! | [`m5_mobile_manipulator`] | 3-D platform + capstan + two-link arm | `q = [x, y, φ, φt, θ1, θ12]` |
//! | [`m6_space_manipulator`] | planar free-floating base + two-link arm | `q = [x0, y0, ψ, θ1, θ2]` |
//!
//! Conventions: `H q̈ + h + G = Q − Cᵀλ`, `C q̇ = 0`, `q̇ = N_C v`, `h = C_cor q̇` with the
//! Christoffel `C_cor`, `G = ∂V/∂q` including gravity. The mass matrix and potential of
//! each model are written once in closed form; their derivatives (Christoffel symbols,
//! G, Ṅ_C, J̇) are exact (forward-mode dual numbers, see [`ad`]).
//!
//! [`multibody_models`] rebuilds m1, m2 and m5 as general multibody models (a planar-rooted
//! [`crate::mobile::WheeledModel`]) for the cross-checks; [`cases`] evaluates case files;
//! [`registry`] holds the models' names and aliases.
//!
//! Each model writes H(q), V(q), C(q), N_C(q) and its task map once, generic over a
//! scalar; [`lagrange`] evaluates them with forward-mode dual numbers ([`ad`]) to get
//! exact Christoffel terms, G, Ṅ_C, Ċq̇ and J̇, then the reduced model and λ. Tests
//! (`tests/chapter_multibody.rs`, `tests/mobile_general_vs_chapter.rs`) hold the closed
//! forms equal to the general multibody model of the same robot.

pub mod ad;
pub mod cases;
pub mod control_cases;
pub mod lagrange;
pub mod m1_unicycle;
pub mod m2_platform_arm;
pub mod m3_diffdrive;
pub mod m4_cart_two_link;
pub mod m5_mobile_manipulator;
pub mod m6_space_manipulator;
pub mod multibody_models;
pub mod registry;

pub use registry::ChapterModel;

use crate::error::{Error, Result};
use crate::manipulability::JacobianSvd;
use crate::ode::OdeSystem;
use ad::Real;
use lagrange::PfaffianSystem;
use nalgebra::{DMatrix, SMatrix, SVector};
use serde::Serialize;

/// The parameter struct of one chapter model (for [`parse_params`]).
pub trait ChapterParams: serde::de::DeserializeOwned {
    /// The model these are the parameters of.
    const MODEL: ChapterModel;
}

impl ChapterParams for m1_unicycle::UnicycleParams {
    const MODEL: ChapterModel = ChapterModel::M1Unicycle;
}
impl ChapterParams for m2_platform_arm::PlatformArmParams {
    const MODEL: ChapterModel = ChapterModel::M2PlatformArm;
}
impl ChapterParams for m3_diffdrive::DiffDriveKinematicsParams {
    const MODEL: ChapterModel = ChapterModel::M3DiffDrive;
}
impl ChapterParams for m4_cart_two_link::CartTwoLinkParams {
    const MODEL: ChapterModel = ChapterModel::M4CartTwoLink;
}
impl ChapterParams for m5_mobile_manipulator::MobileManipulatorParams {
    const MODEL: ChapterModel = ChapterModel::M5MobileManipulator;
}
impl ChapterParams for m6_space_manipulator::SpaceManipulatorParams {
    const MODEL: ChapterModel = ChapterModel::M6SpaceManipulator;
}

/// Reads a chapter model's parameter table (`params` of a case file or of a scenario's
/// `robot.params`) into its parameter struct, which refuses names it does not have: an
/// unknown name is an error on `params.NAME` that names the model and lists its
/// parameters; other deserialization errors (a missing parameter) are reported on
/// `field`.
pub fn parse_params<P: ChapterParams>(field: &str, params: &serde_json::Value) -> Result<P> {
    serde_json::from_value(params.clone()).map_err(|e| {
        let text = e.to_string();
        // serde's message: unknown field `NAME`, expected one of `a`, `b`, … (or
        // "expected `a`" / "expected `a` or `b`").
        if let Some(rest) = text.strip_prefix("unknown field `")
            && let Some((name, tail)) = rest.split_once('`')
        {
            let valid: Vec<&str> = tail.split('`').skip(1).step_by(2).collect();
            return Error::invalid(
                format!("params.{name}"),
                format!(
                    "unknown parameter '{name}' of model {}; its parameters are: {}",
                    P::MODEL.canonical_name(),
                    valid.join(", ")
                ),
            );
        }
        Error::invalid(field, text)
    })
}

/// Smallest |d| (m) for which the lateral-velocity parametrisation `v = [v_F, v_T]` is used
/// automatically; below it [`PlatformVelocity::YawRate`] is chosen.
pub const MIN_AXLE_OFFSET: f64 = 1e-9;

/// How the platform's two admissible velocities are parametrised.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlatformVelocity {
    /// `v = [v_F, v_T]`: forward and lateral velocity of the CM, `v_T = d φ̇`
    /// (the chapter's choice; singular for `d = 0`).
    LateralVelocity,
    /// `v = [v_F, φ̇]`: forward velocity of the CM and yaw rate (valid for every `d`).
    YawRate,
}

impl PlatformVelocity {
    /// The chapter's parametrisation unless `|d| < MIN_AXLE_OFFSET`, then the yaw rate.
    pub fn auto(d: f64) -> Self {
        if d.abs() >= MIN_AXLE_OFFSET {
            PlatformVelocity::LateralVelocity
        } else {
            PlatformVelocity::YawRate
        }
    }

    /// Checks that this parametrisation is usable with the offset `d`.
    pub fn check(self, d: f64) -> Result<()> {
        if self == PlatformVelocity::LateralVelocity && d.abs() < MIN_AXLE_OFFSET {
            return Err(Error::Singular {
                what: "N_C with v = [v_F, v_T]".into(),
                detail: Some(format!(
                    "d = {d} (CM over the axle); use the yaw-rate parametrisation v = [v_F, φ̇]"
                )),
            });
        }
        Ok(())
    }
}

/// The platform block `N11(φ)` (3×2) of the velocity basis, rows `(ẋ, ẏ, φ̇)`.
///
/// Lateral velocity: `[[cos φ, −sin φ], [sin φ, cos φ], [0, 1/d]]`;
/// yaw rate: `[[cos φ, −d sin φ], [sin φ, d cos φ], [0, 1]]`.
pub fn platform_basis<T: Real>(phi: T, d: f64, param: PlatformVelocity) -> [[T; 2]; 3] {
    let (c, s) = (phi.cos(), phi.sin());
    match param {
        PlatformVelocity::LateralVelocity => [[c, -s], [s, c], [T::cst(0.0), T::cst(1.0 / d)]],
        PlatformVelocity::YawRate => [[c, -s * d], [s, c * d], [T::cst(0.0), T::cst(1.0)]],
    }
}

/// Most integration steps (accepted + rejected) one trajectory of a closed-form model
/// may take: the shipped reference cases need at most a few hundred for their second at
/// `tol = 1e-12`. Parameters that make a model stiff or fast (a fuzzed m5 case with a
/// 2.1e11 kg link beside masses of a few kg needed 130,000 steps for one second, 20 s of
/// wall time) are refused with an error saying the step budget ran out, in bounded time.
pub const CASE_MAX_STEPS: usize = 20_000;

/// DOP853 options for a closed-form model's trajectory: `rtol = atol = tol` and the
/// [`CASE_MAX_STEPS`] budget for the whole solve.
pub(crate) fn case_integrator_options(tol: f64) -> crate::ode::AdaptiveOptions {
    crate::ode::AdaptiveOptions {
        max_steps: CASE_MAX_STEPS,
        ..crate::ode::AdaptiveOptions::with_tolerance(tol)
    }
}

/// Rejects a non-finite or non-positive parameter, or one outside [`POSITIVE_RANGE`].
pub(crate) fn positive(name: &str, x: f64) -> Result<()> {
    if !x.is_finite() {
        return Err(Error::NonFinite {
            field: format!("params.{name}"),
        });
    }
    if x <= 0.0 {
        return Err(Error::invalid(
            format!("params.{name}"),
            format!("must be positive, got {x}"),
        ));
    }
    if !(POSITIVE_RANGE.0..=POSITIVE_RANGE.1).contains(&x) {
        return Err(Error::invalid(
            format!("params.{name}"),
            format!(
                "must lie in [{:e}, {:e}] (SI units; beyond, the model's products of \
                 parameters leave f64's range), got {x:e}",
                POSITIVE_RANGE.0, POSITIVE_RANGE.1
            ),
        ));
    }
    Ok(())
}

/// The range of a positive parameter (mass, length, inertia, radius): products of up to
/// six of them stay well inside f64's range.
pub const POSITIVE_RANGE: (f64, f64) = (1e-50, 1e50);

/// Rejects a non-finite or negative parameter.
pub(crate) fn nonnegative(name: &str, x: f64) -> Result<()> {
    if !x.is_finite() {
        return Err(Error::NonFinite {
            field: format!("params.{name}"),
        });
    }
    if x < 0.0 {
        return Err(Error::invalid(
            format!("params.{name}"),
            format!("must not be negative, got {x}"),
        ));
    }
    Ok(())
}

/// Rejects a non-finite parameter.
pub(crate) fn finite(name: &str, x: f64) -> Result<()> {
    if x.is_finite() {
        Ok(())
    } else {
        Err(Error::NonFinite {
            field: format!("params.{name}"),
        })
    }
}

/// Longest simulated time a case may reach (s): the last of `trajectory.t`, of an m6
/// `trajectories.NAME.t`, and m6's `joint_loop.period`. The reference cases span about a
/// second; an unbounded horizon let one number (1e9 s) keep the integrator busy without
/// end (found by fuzzing, first on an m2 case, then on an m6 run).
pub const MAX_CASE_TIME: f64 = 1000.0;

/// Refuses a time list whose last entry is past [`MAX_CASE_TIME`], naming `field[i]`.
pub(crate) fn check_horizon(field: &str, t: &[f64]) -> Result<()> {
    match t.last() {
        Some(&t_end) if t_end > MAX_CASE_TIME => Err(Error::invalid(
            format!("{field}[{}]", t.len() - 1),
            format!(
                "{t_end} s is past the longest case horizon, {MAX_CASE_TIME} s (longer runs belong in `moma simulate`)"
            ),
        )),
        _ => Ok(()),
    }
}

/// Converts a slice of user input into a fixed-size vector, checking length and finiteness.
pub fn fixed_vector<const K: usize>(field: &str, x: &[f64]) -> Result<SVector<f64, K>> {
    crate::error::ensure_len(field, K, x.len())?;
    crate::error::ensure_finite(field, x)?;
    Ok(SVector::from_column_slice(x))
}

/// Manipulability measures of a Jacobian `J` (m×n) with singular values `σ`, in the
/// schema of the chapter's reference vectors (computed by [`crate::manipulability`]).
#[derive(Clone, Debug, Serialize)]
pub struct Manipulability {
    /// `[m, n]`.
    pub shape: [usize; 2],
    /// Singular values of J, descending.
    pub singular_values: Vec<f64>,
    /// The chapter's measure `det(JᵀJ)` (0 for a wide J, where it vanishes identically).
    #[serde(rename = "det_JtJ")]
    pub det_jtj: f64,
    /// Yoshikawa's measure `sqrt(det(J Jᵀ))` (0 for a tall J, where it vanishes identically).
    #[serde(rename = "yoshikawa_sqrt_det_JJt")]
    pub yoshikawa: f64,
    /// `σ_min / σ_max`.
    pub w2_sigma_ratio: f64,
    /// Bayle–Fourquet–Renaud eccentricity `sqrt(1 − (σ_min/σ_max)²)`.
    pub w5_bayle_eccentricity: f64,
}

/// Computes the [`Manipulability`] measures of `j` from one SVD
/// ([`crate::manipulability::JacobianSvd`]). Errors for an empty or non-finite `j`.
#[doc(alias = "Yoshikawa")]
pub fn manipulability(j: &DMatrix<f64>) -> Result<Manipulability> {
    let svd = JacobianSvd::new(j)?;
    Ok(Manipulability {
        shape: [svd.rows, svd.cols],
        singular_values: svd.singular_values.iter().copied().collect(),
        // Both measures are defined for every shape; each is identically zero on the
        // shapes the module refuses (a wide J for det(JᵀJ), a tall J for Yoshikawa).
        det_jtj: if svd.rows < svd.cols {
            0.0
        } else {
            svd.det_jtj()?
        },
        yoshikawa: if svd.rows > svd.cols {
            0.0
        } else {
            svd.yoshikawa()?
        },
        w2_sigma_ratio: svd.inverse_condition(),
        w5_bayle_eccentricity: svd.eccentricity(),
    })
}

/// A state `(q, v)` of a closed-form model: configuration `q` (N) and velocities `v` (NV;
/// `v = q̇` for the unconstrained m4, admissible velocities `q̇ = N_C v` otherwise).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelState<const N: usize, const NV: usize> {
    /// Configuration q.
    pub q: SVector<f64, N>,
    /// Velocities v.
    pub v: SVector<f64, NV>,
}

impl<const N: usize, const NV: usize> ModelState<N, NV> {
    /// A state from slices, checking lengths and finiteness (fields named `state.q`,
    /// `state.v`).
    pub fn from_slices(q: &[f64], v: &[f64]) -> Result<Self> {
        Ok(ModelState {
            q: fixed_vector("state.q", q)?,
            v: fixed_vector("state.v", v)?,
        })
    }

    /// The ODE state vector `[q; v]`.
    pub fn to_ode(&self) -> Vec<f64> {
        self.q.iter().chain(self.v.iter()).copied().collect()
    }

    /// Splits an ODE state vector `[q; v]` (length N + NV).
    pub fn from_ode(x: &[f64]) -> Result<Self> {
        crate::error::ensure_len("ODE state", N + NV, x.len())?;
        Ok(ModelState {
            q: SVector::from_column_slice(&x[..N]),
            v: SVector::from_column_slice(&x[N..]),
        })
    }
}

/// The reduced dynamics of a constrained model under a constant input `u`, as an
/// [`OdeSystem`] on the state `x = [q; v]` (`q̇ = N_C(q) v`, `v̇ = Mr⁻¹(Qr − Cr v − Gr)`).
pub struct ConstantInputOde<'a, S, const N: usize, const NV: usize, const NU: usize> {
    /// The model.
    pub system: &'a S,
    /// The constant input.
    pub input: SVector<f64, NU>,
}

impl<S, const N: usize, const NV: usize, const NU: usize> OdeSystem
    for ConstantInputOde<'_, S, N, NV, NU>
where
    S: PfaffianSystem<N, NV, NU>,
{
    fn dim(&self) -> usize {
        N + NV
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<()> {
        let q = SVector::<f64, N>::from_column_slice(&x[..N]);
        let v = SVector::<f64, NV>::from_column_slice(&x[N..N + NV]);
        let (qd, vd) = lagrange::state_derivative(self.system, &q, &v, &self.input)
            .map_err(|e| e.singular_at_time(t))?;
        dx[..N].copy_from_slice(qd.as_slice());
        dx[N..N + NV].copy_from_slice(vd.as_slice());
        Ok(())
    }
}

/// Integrates a [`ConstantInputOde`] with DOP853 at `rtol = atol = tol` and returns
/// `(q, v)` at each requested time.
#[allow(clippy::type_complexity)]
pub fn simulate_reduced<S, const N: usize, const NV: usize, const NU: usize>(
    system: &S,
    q0: &SVector<f64, N>,
    v0: &SVector<f64, NV>,
    u: &SVector<f64, NU>,
    times: &[f64],
    tol: f64,
) -> Result<Vec<(SVector<f64, N>, SVector<f64, NV>)>>
where
    S: PfaffianSystem<N, NV, NU>,
{
    let mut ode = ConstantInputOde { system, input: *u };
    let mut x0 = vec![0.0; N + NV];
    x0[..N].copy_from_slice(q0.as_slice());
    x0[N..].copy_from_slice(v0.as_slice());
    let mut dp = crate::ode::Dop853::new(N + NV, case_integrator_options(tol))?;
    let rows = dp.solve_at(&mut ode, 0.0, &x0, times)?;
    Ok(rows
        .iter()
        .map(|r| {
            (
                SVector::from_column_slice(&r[..N]),
                SVector::from_column_slice(&r[N..]),
            )
        })
        .collect())
}

/// Serde helpers writing nalgebra matrices as row-major nested lists.
pub mod ser {
    use nalgebra::{SMatrix, SVector};
    use serde::Serializer;
    use serde::ser::SerializeSeq;

    /// A matrix as a list of rows.
    pub fn mat<const R: usize, const C: usize, S: Serializer>(
        m: &SMatrix<f64, R, C>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        let mut seq = s.serialize_seq(Some(R))?;
        for i in 0..R {
            let row: Vec<f64> = (0..C).map(|j| m[(i, j)]).collect();
            seq.serialize_element(&row)?;
        }
        seq.end()
    }

    /// A vector as a flat list.
    pub fn vec<const R: usize, S: Serializer>(
        v: &SVector<f64, R>,
        s: S,
    ) -> Result<S::Ok, S::Error> {
        s.collect_seq(v.iter())
    }

    /// A scalar as a one-element list.
    pub fn one<S: Serializer>(x: &f64, s: S) -> Result<S::Ok, S::Error> {
        s.collect_seq(std::iter::once(x))
    }
}

/// Converts a fixed-size matrix to a dynamically sized one.
pub fn to_dmatrix<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>) -> DMatrix<f64> {
    DMatrix::from_fn(R, C, |i, j| m[(i, j)])
}

/// Rejects a vector with a NaN or infinite entry, naming `field`.
pub fn check_finite<const K: usize>(field: &str, x: &SVector<f64, K>) -> Result<()> {
    crate::error::ensure_finite(field, x.iter())
}

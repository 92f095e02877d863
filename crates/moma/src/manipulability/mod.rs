//! Manipulability measures and ellipsoids of a task Jacobian.
//!
//! Every measure here is a pure function of a Jacobian `J` (m task rows × n input
//! columns) through its singular values `σ₁ ≥ … ≥ σ_r` (r = min(m, n)). Whether the
//! result describes the arm alone or the whole mobile manipulator is only a matter of
//! which Jacobian is passed: the arm's frame Jacobian, or the whole-body Jacobian
//! `J̄ = J·N_C` of [`crate::mobile::whole_body`] (Bayle, Fourquet & Renaud 2003).
//!
//! | [`Measure`] | formula | reference |
//! | --- | --- | --- |
//! | `Yoshikawa` | `w = √det(J Jᵀ) = Π σᵢ` (m ≤ n) | Yoshikawa 1985 |
//! | `DetJtJ` | `det(Jᵀ J) = Π σᵢ²` (m ≥ n; ≡ 0 for wide J) | the chapter's `m` (5.3.1) |
//! | `InverseCondition` | `σ_min / σ_max` ∈ [0, 1] | the chapter's `w2`; Salisbury & Craig 1982 |
//! | `Condition` | `κ = σ_max / σ_min` | Salisbury & Craig 1982 |
//! | `MinSingularValue` | `σ_min` | Klein & Blaho 1987 |
//! | `GeometricMean` | `w^(1/r)` | Bayle et al. 2003 |
//! | `Eccentricity` | `√(1 − (σ_min/σ_max)²)` (smaller is better) | the chapter's `w5`, Bayle et al. 2003 |
//! | `Directional(u)` | `r_v(u) = 1/√(uᵀ (J Jᵀ)⁻¹ u)` | Chiu 1988 (velocity ellipsoid radius along u) |
//!
//! Mixed units (metres and radians in the task, wheel rates and joint rates in the
//! inputs) make all of them scale dependent: scale rows or columns explicitly before
//! calling (e.g. select only the position rows).
//!
//! No function here returns NaN: non-finite input is rejected with
//! [`Error::NonFinite`], and the divisions that blow up at a singularity are reported
//! as [`Error::Singular`] (condition number, force radius) or take their limit
//! (inverse condition number 0, velocity radius 0, eccentricity 1).
//!
//! Maps of these measures over base placements need IK at every sample and live in
//! [`crate::ik::placement`].
//!
//! Every measure comes from one SVD of the Jacobian given, the crate's own one-sided
//! Jacobi on the rows, not nalgebra's: with singular vectors requested, nalgebra 0.35
//! returns wrong values and vectors for some rank-deficient matrices, which are exactly
//! the singular postures the measures are asked about.

use crate::error::{Error, Result, ensure_finite};
use nalgebra::{DMatrix, DVector};
use std::fmt;
use std::str::FromStr;

/// Singular values below `SINGULAR_TOL · σ_max` (or below `f64::MIN_POSITIVE`) count as zero.
pub const SINGULAR_TOL: f64 = 1e-12;

/// A scalar manipulability measure, chosen by name on the command line.
///
/// `FromStr` accepts `yoshikawa` (alias `w`), `det-jtj` (`chapter`), `inverse-condition`
/// (`w2`, `sigma-ratio`), `condition` (`kappa`), `min-singular-value` (`sigma-min`),
/// `geometric-mean`, `eccentricity` (`w5`) and `directional:u1,u2,…`.
#[derive(Clone, Debug, PartialEq)]
pub enum Measure {
    /// Yoshikawa's manipulability `w = √det(J Jᵀ) = Π σᵢ`; needs m ≤ n.
    Yoshikawa,
    /// The chapter's `m = det(Jᵀ J) = Π σᵢ²`; needs m ≥ n (identically zero for a wide J).
    DetJtJ,
    /// Inverse condition number `σ_min / σ_max` (the chapter's `w2`), in [0, 1].
    InverseCondition,
    /// Condition number `κ = σ_max / σ_min` (infinite, hence an error, at a singularity).
    Condition,
    /// Minimum singular value `σ_min`: the worst-direction speed for unit input norm.
    MinSingularValue,
    /// Geometric mean `w^(1/r)` of the singular values.
    GeometricMean,
    /// Bayle's eccentricity `√(1 − (σ_min/σ_max)²)` (the chapter's `w5`): 0 isotropic, → 1 singular.
    Eccentricity,
    /// Velocity-ellipsoid radius along a task direction (normalised on use):
    /// `r_v(u) = 1/√(uᵀ (J Jᵀ)⁻¹ u)`.
    Directional(Vec<f64>),
}

impl Measure {
    /// All measures that need no parameter, in documentation order.
    pub const SCALAR: [Measure; 7] = [
        Measure::Yoshikawa,
        Measure::DetJtJ,
        Measure::InverseCondition,
        Measure::Condition,
        Measure::MinSingularValue,
        Measure::GeometricMean,
        Measure::Eccentricity,
    ];

    /// The canonical name (as accepted by `FromStr`, without parameters).
    pub fn name(&self) -> &'static str {
        match self {
            Measure::Yoshikawa => "yoshikawa",
            Measure::DetJtJ => "det-jtj",
            Measure::InverseCondition => "inverse-condition",
            Measure::Condition => "condition",
            Measure::MinSingularValue => "min-singular-value",
            Measure::GeometricMean => "geometric-mean",
            Measure::Eccentricity => "eccentricity",
            Measure::Directional(_) => "directional",
        }
    }

    /// True when a larger value means a better-conditioned configuration
    /// (false for the condition number and the eccentricity).
    pub fn larger_is_better(&self) -> bool {
        !matches!(self, Measure::Condition | Measure::Eccentricity)
    }

    /// Evaluates the measure on `jacobian`. See [`evaluate`].
    pub fn evaluate(&self, jacobian: &DMatrix<f64>) -> Result<f64> {
        evaluate(self, jacobian)
    }
}

impl fmt::Display for Measure {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Measure::Directional(u) => {
                let parts: Vec<String> = u.iter().map(|x| format!("{x}")).collect();
                write!(f, "directional:{}", parts.join(","))
            }
            m => f.write_str(m.name()),
        }
    }
}

impl FromStr for Measure {
    type Err = Error;

    fn from_str(s: &str) -> Result<Self> {
        let lower = s.trim().to_ascii_lowercase();
        if let Some(rest) = lower.strip_prefix("directional:") {
            let mut u = Vec::new();
            for (i, part) in rest.split(',').enumerate() {
                let x: f64 = part.trim().parse().map_err(|_| {
                    Error::invalid(
                        "measure",
                        format!("directional component {i} '{part}' is not a number"),
                    )
                })?;
                u.push(x);
            }
            ensure_finite("measure directional vector", &u)?;
            if u.iter().map(|x| x * x).sum::<f64>() <= 0.0 {
                return Err(Error::invalid(
                    "measure",
                    "directional vector must be non-zero",
                ));
            }
            return Ok(Measure::Directional(u));
        }
        Ok(match lower.as_str() {
            "yoshikawa" | "w" | "w1" => Measure::Yoshikawa,
            "det-jtj" | "detjtj" | "chapter" => Measure::DetJtJ,
            "inverse-condition" | "w2" | "sigma-ratio" => Measure::InverseCondition,
            "condition" | "kappa" => Measure::Condition,
            "min-singular-value" | "sigma-min" | "w3" => Measure::MinSingularValue,
            "geometric-mean" | "w4" => Measure::GeometricMean,
            "eccentricity" | "w5" => Measure::Eccentricity,
            _ => {
                return Err(Error::invalid(
                    "measure",
                    format!(
                        "unknown measure '{s}'; expected one of yoshikawa, det-jtj, \
                         inverse-condition, condition, min-singular-value, geometric-mean, \
                         eccentricity, directional:u1,u2,..."
                    ),
                ));
            }
        })
    }
}

/// The singular value decomposition of a task Jacobian, with the numerical rank.
///
/// `σ` is sorted in descending order; `u` holds the left singular vectors (the
/// ellipsoid's principal axes, m × r). The right singular vectors are not needed by any
/// measure and are not computed.
#[derive(Clone, Debug)]
pub struct JacobianSvd {
    /// Task rows m.
    pub rows: usize,
    /// Input columns n.
    pub cols: usize,
    /// Singular values σ₁ ≥ … ≥ σ_r, r = min(m, n).
    pub singular_values: DVector<f64>,
    /// Left singular vectors (columns), m × r.
    pub u: DMatrix<f64>,
}

impl JacobianSvd {
    /// Decomposes `jacobian` (m × n, both non-zero, all finite).
    #[doc(alias = "svd")]
    pub fn new(jacobian: &DMatrix<f64>) -> Result<Self> {
        let (m, n) = jacobian.shape();
        if m == 0 || n == 0 {
            return Err(Error::invalid(
                "jacobian",
                format!("empty {m} x {n} Jacobian"),
            ));
        }
        ensure_finite("jacobian", jacobian.iter())?;
        // one-sided Jacobi on the rows (crate::linalg): nalgebra's SVD with vectors is
        // wrong on some rank-deficient matrices, i.e. at singular postures
        let svd = crate::linalg::row_jacobi_svd(jacobian).ok_or_else(|| Error::Numerical {
            t: 0.0,
            message: "singular value decomposition did not converge".into(),
        })?;
        let r = m.min(n);
        Ok(Self {
            rows: m,
            cols: n,
            singular_values: svd.sigma.rows(0, r).into_owned(),
            u: svd.u.columns(0, r).into_owned(),
        })
    }

    /// σ_max.
    pub fn sigma_max(&self) -> f64 {
        self.singular_values[0]
    }

    /// σ_min = σ_r, r = min(m, n).
    pub fn sigma_min(&self) -> f64 {
        self.singular_values[self.singular_values.len() - 1]
    }

    /// The zero threshold for singular values.
    pub fn zero_threshold(&self) -> f64 {
        (SINGULAR_TOL * self.sigma_max()).max(f64::MIN_POSITIVE)
    }

    /// Numerical rank: singular values above [`Self::zero_threshold`].
    pub fn rank(&self) -> usize {
        let t = self.zero_threshold();
        self.singular_values.iter().filter(|&&s| s > t).count()
    }

    /// Product of the singular values.
    fn product(&self) -> f64 {
        self.singular_values.iter().product()
    }

    /// Yoshikawa's `w = √det(J Jᵀ) = Π σᵢ`. Errors for a tall J (m > n), where
    /// `det(J Jᵀ)` is identically zero.
    #[doc(alias = "w")]
    pub fn yoshikawa(&self) -> Result<f64> {
        if self.rows > self.cols {
            return Err(Error::invalid(
                "measure yoshikawa",
                format!(
                    "√det(J Jᵀ) is identically zero for a tall {} x {} Jacobian (m > n); \
                     use det-jtj or the singular-value measures",
                    self.rows, self.cols
                ),
            ));
        }
        Ok(self.product())
    }

    /// The chapter's `m = det(Jᵀ J) = Π σᵢ²`. Errors for a wide J (m < n), where it is
    /// identically zero.
    pub fn det_jtj(&self) -> Result<f64> {
        if self.rows < self.cols {
            return Err(Error::invalid(
                "measure det-jtj",
                format!(
                    "det(Jᵀ J) is identically zero for a wide (redundant) {} x {} Jacobian \
                     (m < n); use yoshikawa = √det(J Jᵀ)",
                    self.rows, self.cols
                ),
            ));
        }
        let p = self.product();
        Ok(p * p)
    }

    /// `σ_min / σ_max` in [0, 1] (0 for a zero Jacobian).
    #[doc(alias = "w2")]
    pub fn inverse_condition(&self) -> f64 {
        if self.sigma_max() <= 0.0 {
            0.0
        } else {
            (self.sigma_min() / self.sigma_max()).clamp(0.0, 1.0)
        }
    }

    /// `κ = σ_max / σ_min`; [`Error::Singular`] when σ_min is (numerically) zero.
    #[doc(alias = "kappa")]
    pub fn condition(&self) -> Result<f64> {
        if self.sigma_min() <= self.zero_threshold() {
            return Err(Error::Singular {
                what: "Jacobian".into(),
                detail: Some(format!(
                    "condition number is infinite (σ_min = {:e}, σ_max = {:e})",
                    self.sigma_min(),
                    self.sigma_max()
                )),
            });
        }
        Ok(self.sigma_max() / self.sigma_min())
    }

    /// Geometric mean of the singular values `(Π σᵢ)^(1/r)`.
    pub fn geometric_mean(&self) -> f64 {
        let r = self.singular_values.len() as f64;
        let mean_ln = self
            .singular_values
            .iter()
            .map(|s| s.max(0.0).ln())
            .sum::<f64>()
            / r;
        mean_ln.exp()
    }

    /// Bayle's eccentricity `√(1 − (σ_min/σ_max)²)` ∈ [0, 1].
    #[doc(alias = "w5")]
    pub fn eccentricity(&self) -> f64 {
        let ratio = self.inverse_condition();
        (1.0 - ratio * ratio).max(0.0).sqrt()
    }

    /// Velocity-ellipsoid radius along the unit task direction `u`:
    /// `r_v(u) = 1/√(uᵀ (J Jᵀ)⁺ u)`, 0 when `u` leaves the reachable subspace.
    pub fn velocity_radius(&self, direction: &[f64]) -> Result<f64> {
        let u = self.unit_direction(direction)?;
        let t = self.zero_threshold();
        let mut sum = 0.0;
        let mut in_range = 0.0;
        for i in 0..self.singular_values.len() {
            let c = self.u.column(i).dot(&u);
            let s = self.singular_values[i];
            if s > t {
                sum += (c / s) * (c / s);
                in_range += c * c;
            }
        }
        // Any component outside the span of the non-zero axes cannot be produced.
        if 1.0 - in_range > 1e-12 || sum <= 0.0 {
            return Ok(0.0);
        }
        Ok(1.0 / sum.sqrt())
    }

    /// Support value of the velocity ellipsoid along `u`: `‖Jᵀ u‖ = √(Σ σᵢ² (u·uᵢ)²)`.
    pub fn velocity_support(&self, direction: &[f64]) -> Result<f64> {
        let u = self.unit_direction(direction)?;
        Ok((0..self.singular_values.len())
            .map(|i| {
                let c = self.u.column(i).dot(&u) * self.singular_values[i];
                c * c
            })
            .sum::<f64>()
            .sqrt())
    }

    /// Force-ellipsoid radius along `u`: `r_f(u) = 1/‖Jᵀ u‖`; [`Error::Singular`] when
    /// `Jᵀ u = 0` (infinite force transmission).
    pub fn force_radius(&self, direction: &[f64]) -> Result<f64> {
        let s = self.velocity_support(direction)?;
        if s <= self.zero_threshold() {
            return Err(Error::Singular {
                what: "Jacobian".into(),
                detail: Some("Jᵀu = 0: force-ellipsoid radius is infinite along u".into()),
            });
        }
        Ok(1.0 / s)
    }

    /// Sum of the semi-axes projected on `u`: `Σ σᵢ |u·uᵢ|`.
    pub fn projection_sum(&self, direction: &[f64]) -> Result<f64> {
        let u = self.unit_direction(direction)?;
        Ok((0..self.singular_values.len())
            .map(|i| self.singular_values[i] * self.u.column(i).dot(&u).abs())
            .sum())
    }

    /// The velocity ellipsoid `{J q̇ : ‖q̇‖ ≤ 1}`.
    pub fn ellipsoid(&self) -> Ellipsoid {
        Ellipsoid {
            axes: self.u.clone(),
            lengths: self.singular_values.clone(),
        }
    }

    fn unit_direction(&self, direction: &[f64]) -> Result<DVector<f64>> {
        crate::error::ensure_len("direction", self.rows, direction.len())?;
        ensure_finite("direction", direction)?;
        let u = DVector::from_column_slice(direction);
        let n = u.norm();
        if n <= 0.0 {
            return Err(Error::invalid("direction", "must be a non-zero vector"));
        }
        Ok(u / n)
    }
}

/// The manipulability (velocity) ellipsoid `{J q̇ : ‖q̇‖ ≤ 1}`: principal axes `uᵢ`
/// (columns of `axes`, unit task vectors) with semi-axis lengths `σᵢ`.
#[derive(Clone, Debug)]
pub struct Ellipsoid {
    /// Principal axes (unit, task space), one per column.
    pub axes: DMatrix<f64>,
    /// Semi-axis lengths σᵢ, descending, matching the columns of `axes`.
    pub lengths: DVector<f64>,
}

/// Singular values of `jacobian`, descending.
#[doc(alias = "sigma")]
pub fn singular_values(jacobian: &DMatrix<f64>) -> Result<DVector<f64>> {
    Ok(JacobianSvd::new(jacobian)?.singular_values)
}

/// Evaluates one [`Measure`] on `jacobian`.
pub fn evaluate(measure: &Measure, jacobian: &DMatrix<f64>) -> Result<f64> {
    let svd = JacobianSvd::new(jacobian)?;
    evaluate_svd(measure, &svd)
}

/// Evaluates one [`Measure`] on an existing decomposition.
pub fn evaluate_svd(measure: &Measure, svd: &JacobianSvd) -> Result<f64> {
    match measure {
        Measure::Yoshikawa => svd.yoshikawa(),
        Measure::DetJtJ => svd.det_jtj(),
        Measure::InverseCondition => Ok(svd.inverse_condition()),
        Measure::Condition => svd.condition(),
        Measure::MinSingularValue => Ok(svd.sigma_min()),
        Measure::GeometricMean => Ok(svd.geometric_mean()),
        Measure::Eccentricity => Ok(svd.eccentricity()),
        Measure::Directional(u) => svd.velocity_radius(u),
    }
}

/// Every measure of a Jacobian at once (the ones that are undefined for its shape or
/// singular there are `None`), plus the ellipsoid.
#[derive(Clone, Debug, serde::Serialize)]
pub struct ManipulabilityReport {
    /// Jacobian shape `[m, n]`.
    pub shape: [usize; 2],
    /// Singular values, descending.
    pub singular_values: Vec<f64>,
    /// Numerical rank.
    pub rank: usize,
    /// `√det(J Jᵀ)`; `None` for a tall J.
    pub yoshikawa: Option<f64>,
    /// `det(Jᵀ J)`; `None` for a wide J (identically zero there).
    pub det_jtj: Option<f64>,
    /// `σ_min / σ_max`.
    pub inverse_condition: f64,
    /// `σ_max / σ_min`; `None` at a singularity.
    pub condition: Option<f64>,
    /// `σ_min`.
    pub min_singular_value: f64,
    /// `(Π σᵢ)^(1/r)`.
    pub geometric_mean: f64,
    /// `√(1 − (σ_min/σ_max)²)`.
    pub eccentricity: f64,
    /// Ellipsoid axes: column i of the left singular vectors, as rows of this list.
    pub ellipsoid_axes: Vec<Vec<f64>>,
    /// Ellipsoid semi-axis lengths (= singular values).
    pub ellipsoid_lengths: Vec<f64>,
    /// Directional quantities, when a direction was given.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub directional: Option<DirectionalReport>,
}

/// Capability along one task direction.
#[derive(Clone, Debug, serde::Serialize)]
pub struct DirectionalReport {
    /// The unit direction used.
    pub direction: Vec<f64>,
    /// `r_v(u) = 1/√(uᵀ (J Jᵀ)⁻¹ u)`.
    pub velocity_radius: f64,
    /// `‖Jᵀ u‖`.
    pub velocity_support: f64,
    /// `1/‖Jᵀ u‖`; `None` when infinite.
    pub force_radius: Option<f64>,
    /// `Σ σᵢ |u·uᵢ|`.
    pub projection_sum: f64,
}

/// Computes every measure of `jacobian` (and the directional ones along `direction`).
pub fn report(jacobian: &DMatrix<f64>, direction: Option<&[f64]>) -> Result<ManipulabilityReport> {
    let svd = JacobianSvd::new(jacobian)?;
    let directional = match direction {
        Some(d) => {
            let u = svd.unit_direction(d)?;
            Some(DirectionalReport {
                direction: u.iter().copied().collect(),
                velocity_radius: svd.velocity_radius(d)?,
                velocity_support: svd.velocity_support(d)?,
                force_radius: svd.force_radius(d).ok(),
                projection_sum: svd.projection_sum(d)?,
            })
        }
        None => None,
    };
    Ok(ManipulabilityReport {
        shape: [svd.rows, svd.cols],
        singular_values: svd.singular_values.iter().copied().collect(),
        rank: svd.rank(),
        yoshikawa: svd.yoshikawa().ok(),
        det_jtj: svd.det_jtj().ok(),
        inverse_condition: svd.inverse_condition(),
        condition: svd.condition().ok(),
        min_singular_value: svd.sigma_min(),
        geometric_mean: svd.geometric_mean(),
        eccentricity: svd.eccentricity(),
        ellipsoid_axes: (0..svd.u.ncols())
            .map(|i| svd.u.column(i).iter().copied().collect())
            .collect(),
        ellipsoid_lengths: svd.singular_values.iter().copied().collect(),
        directional,
    })
}

/// Selects rows of a Jacobian (e.g. `[0, 1, 2]` for the position rows of a 6-D one).
pub fn select_rows(jacobian: &DMatrix<f64>, rows: &[usize]) -> Result<DMatrix<f64>> {
    for (k, &r) in rows.iter().enumerate() {
        if r >= jacobian.nrows() {
            return Err(Error::invalid(
                format!("rows[{k}]"),
                format!(
                    "row {r} out of range for a {}-row Jacobian",
                    jacobian.nrows()
                ),
            ));
        }
    }
    if rows.is_empty() {
        return Err(Error::invalid("rows", "no task rows selected"));
    }
    Ok(jacobian.select_rows(rows))
}

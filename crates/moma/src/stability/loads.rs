//! Wheel–ground loads: the normal load of each ground contact from the gravito-inertial
//! wrench, and the friction demand of the driven wheels against Coulomb's `μ N`.
//!
//! # Normal loads
//!
//! The ground carries everything the gravito-inertial wrench does not balance: with
//! contact `j` at ground point `p_j` carrying the normal load `N_j` (along +z; the
//! tangential forces act in the ground plane and have no moment about horizontal axes
//! through a ground point), equilibrium about horizontal axes through a reference point
//! `c` on the ground (the centroid of the contacts) gives three equations:
//!
//! ```text
//! Σ N_j                 = −f_gi,z
//! Σ N_j (y_j − c_y)     = −M_gi,x(c)
//! Σ N_j (x_j − c_x)     =  M_gi,y(c)
//! ```
//!
//! i.e. `A N = b` with the 3 × n matrix `A = [1; x − c_x; y − c_y]`. The resultant of the
//! loads then acts at the Zero-Moment Point. With **exactly three** non-collinear
//! contacts `A` is square and invertible: the loads are exact (the ZMP's barycentric
//! coordinates times the normal force). With **more than three** the loads are
//! statically indeterminate; the rule used is the **minimum-norm solution**
//! `N = Aᵀ (A Aᵀ)⁻¹ b` (the least-squares distribution: of all load sets in equilibrium,
//! the one with the smallest `Σ N_j²`). Its loads are an affine function of the contact
//! position, `N_j = μ₀ + μ₁ (x_j − c_x) + μ₂ (y_j − c_y)`, so they satisfy the equations
//! exactly (residual at rounding), but unlike real contacts they are not kept
//! non-negative: a negative load means the rule asks that contact to pull, which a wheel
//! cannot (it lifts). With the ZMP outside the support at least one load is negative
//! under either rule. Loads are signed and never NaN.
//!
//! # Driven-wheel friction
//!
//! The no-side-slip constraint holds the axle with one lateral force `F_lat = −λ₀`
//! (see [`crate::mobile`]); two wheels on one axle share it in a way rigid-body
//! mechanics does not fix. The rule used: **in proportion to the wheels' normal loads**
//! (negative loads counted as zero; equal shares if neither wheel is loaded), so both
//! wheels carry the same fraction of their load in lateral force: of all splits, the one
//! that lets the axle alone hold the largest lateral force before either wheel slides.
//! The longitudinal (traction or braking) force of each wheel adds to it: the friction
//! demand is `|(F_long, F_lat,i)|` against the Coulomb limit `μ N_i`, and the slip ratio
//! `|F| / (μ N_i)` exceeds one where the wheel would slide. An unloaded wheel (`N_i` not
//! above a nano-newton) has no ratio (`None`) and slides as soon as a tangential force
//! (above a nano-newton) is asked of it.

use nalgebra::{Matrix3, Vector2, Vector3};

use super::wrench::GravitoInertialWrench;
use crate::error::{Error, Result};

/// Which rule produced a set of normal loads.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LoadRule {
    /// Exactly three contacts: the equilibrium equations have one solution.
    Exact,
    /// More than three contacts: the minimum-norm (least-squares) solution
    /// `N = Aᵀ (A Aᵀ)⁻¹ b`.
    MinimumNorm,
}

impl LoadRule {
    /// A one-line description for reports.
    #[must_use]
    pub fn describe(self) -> &'static str {
        match self {
            LoadRule::Exact => "exact: three contacts, statically determinate",
            LoadRule::MinimumNorm => {
                "minimum-norm (least-squares) solution of the equilibrium equations: more than three contacts, statically indeterminate"
            }
        }
    }
}

/// Reference point (centroid of the contacts) of the equilibrium equations.
fn centroid(contacts: &[Vector2<f64>]) -> Vector2<f64> {
    contacts.iter().sum::<Vector2<f64>>() / contacts.len() as f64
}

/// Right-hand side `b` of the equilibrium equations about the ground point `c`.
fn equilibrium_rhs(w: &GravitoInertialWrench, c: &Vector2<f64>, ground_z: f64) -> Vector3<f64> {
    let m = w.moment_about(&Vector3::new(c.x, c.y, ground_z));
    Vector3::new(-w.force.z, m.y, -m.x)
}

/// The normal load of each ground contact under the gravito-inertial wrench `wrench`,
/// written into `out` (one per contact, N, positive pressing on the ground); returns the
/// rule used (see the module docs). `contacts` are the world ground positions `[x, y]`
/// of every contact (drive-wheel contacts and casters, interior ones included), on the
/// plane `z = ground_z`. Does not allocate.
///
/// # Errors
/// [`Error::InvalidInput`] for fewer than three contacts or contacts on one line (the
/// moments about the line's direction cannot be balanced); [`Error::NonFinite`] for a
/// non-finite contact or wrench.
///
/// # Panics
/// If `out.len() != contacts.len()`.
pub fn contact_normal_loads(
    contacts: &[Vector2<f64>],
    ground_z: f64,
    wrench: &GravitoInertialWrench,
    out: &mut [f64],
) -> Result<LoadRule> {
    assert_eq!(out.len(), contacts.len(), "one load per contact");
    let n = contacts.len();
    if n < 3 {
        return Err(Error::invalid(
            "contact loads",
            format!("need at least three ground contacts, got {n}"),
        ));
    }
    if !contacts.iter().all(|p| p.x.is_finite() && p.y.is_finite()) || !ground_z.is_finite() {
        return Err(Error::NonFinite {
            field: "contact position".into(),
        });
    }
    if !(wrench.force.iter().all(|x| x.is_finite())
        && wrench.moment_about_com.iter().all(|x| x.is_finite())
        && wrench.com.iter().all(|x| x.is_finite()))
    {
        return Err(Error::NonFinite {
            field: "gravito-inertial wrench".into(),
        });
    }
    let c = centroid(contacts);
    // A Aᵀ = Σ a_j a_jᵀ with a_j = [1, x_j − c_x, y_j − c_y].
    let mut aat = Matrix3::<f64>::zeros();
    let mut size = 0.0f64;
    for p in contacts {
        let a = Vector3::new(1.0, p.x - c.x, p.y - c.y);
        aat += a * a.transpose();
        size = size.max((p - c).norm_squared());
    }
    // Collinear contacts make A Aᵀ singular: compare the determinant of its centred 2×2
    // block with the squared size of the contact set.
    let det2 = aat[(1, 1)] * aat[(2, 2)] - aat[(1, 2)] * aat[(2, 1)];
    if det2 <= 1e-12 * (size * n as f64).powi(2) {
        return Err(Error::invalid(
            "contact loads",
            "the ground contacts lie on one line: the moment about that line cannot be carried",
        ));
    }
    let b = equilibrium_rhs(wrench, &c, ground_z);
    let mu = aat
        .cholesky()
        .ok_or_else(|| Error::Singular {
            what: "contact equilibrium A Aᵀ".into(),
            detail: None,
        })?
        .solve(&b);
    for (o, p) in out.iter_mut().zip(contacts) {
        *o = mu[0] + mu[1] * (p.x - c.x) + mu[2] * (p.y - c.y);
    }
    Ok(if n == 3 {
        LoadRule::Exact
    } else {
        LoadRule::MinimumNorm
    })
}

/// Residual `A N − b` of the equilibrium equations for loads `loads` (N, N·m, N·m):
/// vertical force, then the moments about the x and y axes through the contacts'
/// centroid. Zero to rounding for the loads of [`contact_normal_loads`].
///
/// # Panics
/// If the lengths differ or `contacts` is empty.
#[must_use]
pub fn load_equilibrium_residual(
    contacts: &[Vector2<f64>],
    ground_z: f64,
    wrench: &GravitoInertialWrench,
    loads: &[f64],
) -> Vector3<f64> {
    assert_eq!(loads.len(), contacts.len(), "one load per contact");
    assert!(!contacts.is_empty(), "no contact");
    let c = centroid(contacts);
    let mut an = Vector3::zeros();
    for (p, &nj) in contacts.iter().zip(loads) {
        an += Vector3::new(1.0, p.x - c.x, p.y - c.y) * nj;
    }
    an - equilibrium_rhs(wrench, &c, ground_z)
}

/// Forces below this (N) are rounding, not forces: a wheel whose normal load is not above
/// it is unloaded (no slip ratio), and a tangential force not above it asked of an
/// unloaded wheel does not make it slide.
pub const UNLOADED_FORCE_TOL: f64 = 1e-9;

/// The friction demand of one driven wheel.
#[derive(Clone, Copy, Debug, PartialEq, Default, serde::Serialize)]
pub struct WheelFriction {
    /// Normal load N (N), from [`contact_normal_loads`].
    pub normal: f64,
    /// Lateral ground force on the wheel along `(−sin θ, cos θ)` (N): its share of the
    /// axle force.
    pub lateral: f64,
    /// Longitudinal ground force along the heading (N): traction (+) or braking (−).
    pub longitudinal: f64,
    /// `|(F_long, F_lat)| / (μ N)`; `None` when `N ≤` [`UNLOADED_FORCE_TOL`].
    pub slip_ratio: Option<f64>,
    /// True when the wheel would slide: ratio above one, or a tangential force (above
    /// [`UNLOADED_FORCE_TOL`]) asked of an unloaded wheel.
    pub slips: bool,
}

/// The friction demand of the `[left, right]` driven wheels: the axle's lateral force
/// `axle_lateral` (`−λ₀`, N) split in proportion to the normal loads `normal` (see the
/// module docs), the wheels' longitudinal ground forces `longitudinal` (N), against the
/// friction coefficient `mu`.
///
/// # Errors
/// [`Error::InvalidInput`] unless `mu` is positive and finite; [`Error::NonFinite`] for
/// a non-finite force or load.
pub fn driven_wheel_friction(
    axle_lateral: f64,
    longitudinal: [f64; 2],
    normal: [f64; 2],
    mu: f64,
) -> Result<[WheelFriction; 2]> {
    crate::error::ensure_positive("friction coefficient mu", mu)?;
    crate::error::ensure_finite(
        "wheel forces",
        [
            axle_lateral,
            longitudinal[0],
            longitudinal[1],
            normal[0],
            normal[1],
        ]
        .iter(),
    )?;
    let w = [normal[0].max(0.0), normal[1].max(0.0)];
    let total = w[0] + w[1];
    let share = if total > 0.0 {
        [w[0] / total, w[1] / total]
    } else {
        [0.5, 0.5]
    };
    let mut out = [WheelFriction::default(); 2];
    for i in 0..2 {
        let lateral = axle_lateral * share[i];
        let demand = lateral.hypot(longitudinal[i]);
        let (slip_ratio, slips) = if normal[i] > UNLOADED_FORCE_TOL {
            let r = demand / (mu * normal[i]);
            (Some(r), r > 1.0)
        } else {
            (None, demand > UNLOADED_FORCE_TOL)
        };
        out[i] = WheelFriction {
            normal: normal[i],
            lateral,
            longitudinal: longitudinal[i],
            slip_ratio,
            slips,
        };
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wrench of a point mass `m` at `com` with horizontal acceleration `acc` and an
    /// extra moment about the CoM.
    fn wrench(
        m: f64,
        com: Vector3<f64>,
        acc: Vector3<f64>,
        moment: Vector3<f64>,
    ) -> GravitoInertialWrench {
        GravitoInertialWrench {
            mass: m,
            com,
            force: m * (Vector3::new(0.0, 0.0, -9.81) - acc),
            moment_about_com: moment,
        }
    }

    #[test]
    fn three_contacts_are_exact_and_balance_the_wrench() {
        let contacts = [
            Vector2::new(-0.1, 0.25),
            Vector2::new(-0.1, -0.25),
            Vector2::new(0.4, 0.0),
        ];
        let w = wrench(
            30.0,
            Vector3::new(0.05, 0.02, 0.4),
            Vector3::new(-1.5, 0.3, 0.0),
            Vector3::new(0.7, -1.1, 0.2),
        );
        let mut n = [0.0; 3];
        assert_eq!(
            contact_normal_loads(&contacts, 0.0, &w, &mut n).unwrap(),
            LoadRule::Exact
        );
        // sum = normal force, moments about two other points balance as well
        assert!((n.iter().sum::<f64>() + w.force.z).abs() < 1e-10);
        for p0 in [Vector3::zeros(), Vector3::new(1.0, -2.0, 0.0)] {
            let mg = w.moment_about(&p0);
            let mut ml = Vector3::zeros();
            for (c, nj) in contacts.iter().zip(&n) {
                ml += (Vector3::new(c.x, c.y, 0.0) - p0).cross(&Vector3::new(0.0, 0.0, *nj));
            }
            assert!((ml.x + mg.x).abs() < 1e-9 && (ml.y + mg.y).abs() < 1e-9);
        }
        // the loads' centre of pressure is the ZMP
        let zmp = super::super::zero_moment_point(&w, 0.0).unwrap();
        let cop: Vector2<f64> = contacts
            .iter()
            .zip(&n)
            .map(|(c, nj)| c * *nj)
            .sum::<Vector2<f64>>()
            / n.iter().sum::<f64>();
        assert!((cop - zmp.xy()).norm() < 1e-12);
        // an interior contact changes the rule, not the equilibrium
        let four = [
            contacts[0],
            contacts[1],
            contacts[2],
            Vector2::new(0.1, 0.0),
        ];
        let mut n4 = [0.0; 4];
        assert_eq!(
            contact_normal_loads(&four, 0.0, &w, &mut n4).unwrap(),
            LoadRule::MinimumNorm
        );
        assert!(load_equilibrium_residual(&four, 0.0, &w, &n4).norm() < 1e-10);
    }

    #[test]
    fn four_contacts_take_the_minimum_norm_solution() {
        let contacts = [
            Vector2::new(0.5, 0.3),
            Vector2::new(0.5, -0.3),
            Vector2::new(-0.5, -0.3),
            Vector2::new(-0.5, 0.3),
        ];
        // CoM over the centre at rest: equal shares
        let w = wrench(
            40.0,
            Vector3::new(0.0, 0.0, 0.5),
            Vector3::zeros(),
            Vector3::zeros(),
        );
        let mut n = [0.0; 4];
        contact_normal_loads(&contacts, 0.0, &w, &mut n).unwrap();
        for nj in n {
            assert!((nj - 40.0 * 9.81 / 4.0).abs() < 1e-10);
        }
        // braking: the front pair carries more, residual zero, and the minimum norm: any
        // other equilibrium load set (add a null-space vector of A) has a larger norm
        let w = wrench(
            40.0,
            Vector3::new(0.1, 0.05, 0.5),
            Vector3::new(-2.0, 0.0, 0.0),
            Vector3::zeros(),
        );
        contact_normal_loads(&contacts, 0.0, &w, &mut n).unwrap();
        assert!(n[0] > n[3] && n[1] > n[2]);
        assert!(load_equilibrium_residual(&contacts, 0.0, &w, &n).norm() < 1e-10);
        let null = [1.0, -1.0, 1.0, -1.0]; // A · null = 0 for the rectangle
        let norm = |x: &[f64]| x.iter().map(|v| v * v).sum::<f64>();
        for t in [-3.0, -0.1, 0.1, 3.0] {
            let other: Vec<f64> = n.iter().zip(null).map(|(a, b)| a + t * b).collect();
            assert!(load_equilibrium_residual(&contacts, 0.0, &w, &other).norm() < 1e-9);
            assert!(norm(&other) > norm(&n));
        }
    }

    #[test]
    fn zmp_outside_gives_a_negative_load_never_nan() {
        let contacts = [
            Vector2::new(0.0, 0.2),
            Vector2::new(0.0, -0.2),
            Vector2::new(0.4, 0.0),
        ];
        // CoM ahead of the front contact
        let w = wrench(
            10.0,
            Vector3::new(0.6, 0.0, 0.3),
            Vector3::zeros(),
            Vector3::zeros(),
        );
        let mut n = [0.0; 3];
        contact_normal_loads(&contacts, 0.0, &w, &mut n).unwrap();
        assert!(n.iter().all(|x| x.is_finite()));
        assert!(n[0] < 0.0 && n[1] < 0.0 && n[2] > 0.0);
        // free fall: no load at all
        let ff = GravitoInertialWrench {
            mass: 10.0,
            com: Vector3::new(0.1, 0.0, 0.3),
            force: Vector3::zeros(),
            moment_about_com: Vector3::zeros(),
        };
        contact_normal_loads(&contacts, 0.0, &ff, &mut n).unwrap();
        assert!(n.iter().all(|x| x.abs() < 1e-12));
    }

    #[test]
    fn bad_contact_sets_are_errors() {
        let w = wrench(
            10.0,
            Vector3::new(0.0, 0.0, 0.3),
            Vector3::zeros(),
            Vector3::zeros(),
        );
        let two = [Vector2::new(0.0, 0.0), Vector2::new(1.0, 0.0)];
        assert!(contact_normal_loads(&two, 0.0, &w, &mut [0.0; 2]).is_err());
        let line = [
            Vector2::new(0.0, 0.0),
            Vector2::new(1.0, 1.0),
            Vector2::new(2.0, 2.0),
        ];
        let e = contact_normal_loads(&line, 0.0, &w, &mut [0.0; 3]).unwrap_err();
        assert!(e.to_string().contains("one line"), "{e}");
        let nan = [
            Vector2::new(0.0, 0.0),
            Vector2::new(1.0, f64::NAN),
            Vector2::new(0.0, 1.0),
        ];
        assert!(matches!(
            contact_normal_loads(&nan, 0.0, &w, &mut [0.0; 3]),
            Err(Error::NonFinite { .. })
        ));
    }

    #[test]
    fn slip_is_detected_against_mu() {
        // 100 N on each wheel, 30 N braking each, axle lateral 0: ratio 0.3 / μ
        let f = driven_wheel_friction(0.0, [-30.0, -30.0], [100.0, 100.0], 0.5).unwrap();
        for w in f {
            assert!((w.slip_ratio.unwrap() - 0.6).abs() < 1e-15);
            assert!(!w.slips);
        }
        let f = driven_wheel_friction(0.0, [-30.0, -30.0], [100.0, 100.0], 0.25).unwrap();
        assert!(
            f.iter()
                .all(|w| w.slips && (w.slip_ratio.unwrap() - 1.2).abs() < 1e-12)
        );
        // lateral split in proportion to the loads: same ratio on both wheels
        let f = driven_wheel_friction(60.0, [0.0, 0.0], [150.0, 50.0], 0.5).unwrap();
        assert!((f[0].lateral - 45.0).abs() < 1e-12 && (f[1].lateral - 15.0).abs() < 1e-12);
        assert!((f[0].slip_ratio.unwrap() - f[1].slip_ratio.unwrap()).abs() < 1e-15);
        // a lifted wheel: no ratio, slides once a force is asked of it
        let f = driven_wheel_friction(10.0, [5.0, 0.0], [-20.0, 120.0], 0.5).unwrap();
        assert_eq!(f[0].slip_ratio, None);
        assert!(f[0].slips);
        assert_eq!(f[0].lateral, 0.0);
        assert_eq!(f[1].lateral, 10.0);
        let f = driven_wheel_friction(0.0, [0.0, 0.0], [-1.0, -1.0], 0.5).unwrap();
        assert!(f.iter().all(|w| w.slip_ratio.is_none() && !w.slips));
        assert!(driven_wheel_friction(0.0, [0.0, 0.0], [1.0, 1.0], 0.0).is_err());
        assert!(driven_wheel_friction(f64::NAN, [0.0, 0.0], [1.0, 1.0], 0.5).is_err());
    }
}

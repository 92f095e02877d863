//! The gravito-inertial wrench (GIW) of a multibody state: everything acting on the robot
//! except the ground reactions (theory: gravity, d'Alembert forces and moments, external
//! loads).

use nalgebra::{DVector, Vector3};

use crate::kinematics::forward_kinematics_second_order;
use crate::multibody::{Data, Model};
use crate::spatial::{Force, Inertia};

/// An external force `force` (N, world axes) applied at the world point `point` (m).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PointForce {
    /// Application point (world, m).
    pub point: Vector3<f64>,
    /// Force (world, N).
    pub force: Vector3<f64>,
}

/// External loads on the robot besides gravity and the ground: point forces and pure
/// moments (world axes).
#[derive(Clone, Copy, Debug, Default)]
pub struct ExternalLoads<'a> {
    /// Forces at points.
    pub forces: &'a [PointForce],
    /// Pure moments (couples), N·m.
    pub moments: &'a [Vector3<f64>],
}

impl ExternalLoads<'_> {
    /// No external load.
    pub const NONE: ExternalLoads<'static> = ExternalLoads {
        forces: &[],
        moments: &[],
    };

    /// True if there is no force and no moment.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.forces.is_empty() && self.moments.is_empty()
    }
}

/// The gravito-inertial wrench `(f_gi, M_gi(p_c))` of a robot state with its total mass
/// and centre of mass: `f_r = f_gi` and `n_r = M_gi(p_c)` of Papadopoulos & Rey.
#[derive(Clone, Copy, Debug, PartialEq)]
#[doc(alias = "GIW")]
pub struct GravitoInertialWrench {
    /// Total mass M of the moving bodies (kg).
    pub mass: f64,
    /// Centre of mass p_c (world, m); the origin for a massless model.
    pub com: Vector3<f64>,
    /// `f_gi = M g − ṗ + Σ f_j` (N).
    #[doc(alias = "f_r")]
    pub force: Vector3<f64>,
    /// `M_gi(p_c) = −L̇_c + Σ (s_j − p_c) × f_j + Σ n_j` (N·m), about the centre of mass.
    #[doc(alias = "n_r")]
    pub moment_about_com: Vector3<f64>,
}

impl GravitoInertialWrench {
    /// The zero wrench of a massless robot at the origin.
    #[must_use]
    pub fn zero() -> Self {
        Self {
            mass: 0.0,
            com: Vector3::zeros(),
            force: Vector3::zeros(),
            moment_about_com: Vector3::zeros(),
        }
    }

    /// Moment of the wrench about point `p`: `M(p) = M(p_c) + (p_c − p) × f`.
    #[must_use]
    pub fn moment_about(&self, p: &Vector3<f64>) -> Vector3<f64> {
        self.moment_about_com + (self.com - p).cross(&self.force)
    }

    /// Adds external loads (moments taken about the current centre of mass).
    pub fn add_external(&mut self, ext: &ExternalLoads<'_>) {
        for f in ext.forces {
            self.force += f.force;
            self.moment_about_com += (f.point - self.com).cross(&f.force);
        }
        for n in ext.moments {
            self.moment_about_com += n;
        }
    }
}

/// The gravito-inertial wrench of state `(q, v, a)` under `gravity` (world, m/s²) plus
/// `external` loads, from the rate of centroidal momentum (no lumping): one forward
/// pass gives every body's spatial momentum rate `I_k a_k + v_k ×* I_k v_k`, their world
/// sum is `ḣ_O = (ṗ, L̇_O)`, and `f_gi = M g − ṗ`, `M_gi(p_c) = −(L̇_O − p_c × ṗ)`.
///
/// Fills `data.world_from_joint`, `data.v`, `data.a` (no gravity) and `data.com`; does not
/// allocate.
///
/// # Panics
/// On wrong vector lengths.
pub fn gravito_inertial_wrench(
    model: &Model,
    data: &mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    a: &DVector<f64>,
    gravity: &Vector3<f64>,
    external: &ExternalLoads<'_>,
) -> GravitoInertialWrench {
    gravito_inertial_wrench_with_set(model, data, q, v, a, gravity, external, None)
}

/// [`gravito_inertial_wrench`] that also sums, when `set = Some((mask, out))`, the
/// world-frame spatial inertia of the bodies of the joints with `mask[i] == true` into
/// `out` (for the Moment-Height measure), in the same pass.
///
/// # Panics
/// As [`gravito_inertial_wrench`], or if `mask.len() != model.njoints`.
#[allow(clippy::too_many_arguments)]
pub fn gravito_inertial_wrench_with_set(
    model: &Model,
    data: &mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    a: &DVector<f64>,
    gravity: &Vector3<f64>,
    external: &ExternalLoads<'_>,
    set: Option<(&[bool], &mut Inertia)>,
) -> GravitoInertialWrench {
    forward_kinematics_second_order(model, data, q, v, a);
    let mut mass = 0.0;
    let mut first = Vector3::zeros();
    let mut hdot = Force::zero();
    let (mask, mut acc) = match set {
        Some((mask, acc)) => {
            assert_eq!(
                mask.len(),
                model.njoints,
                "body set has {} entries, the model has {} joints",
                mask.len(),
                model.njoints
            );
            *acc = Inertia::zero();
            (Some(mask), Some(acc))
        }
        None => (None, None),
    };
    for i in 1..model.njoints {
        let inertia = &model.inertias[i];
        let m = inertia.mass();
        if m == 0.0 && inertia.inertia_about_origin() == nalgebra::Matrix3::zeros() {
            continue;
        }
        let x = &data.world_from_joint[i];
        let vel = &data.v[i];
        let f = inertia.mul_motion(&data.a[i]) + vel.cross_force(&inertia.mul_motion(vel));
        hdot += x.act_force(&f);
        mass += m;
        first += x.rotation * inertia.first_moment() + x.translation * m;
        if let (Some(mask), Some(acc)) = (mask, acc.as_deref_mut())
            && mask[i]
        {
            *acc += inertia.transformed(x);
        }
    }
    let com = if mass > 0.0 {
        first / mass
    } else {
        Vector3::zeros()
    };
    data.com = com;
    let ldot_c = hdot.angular - com.cross(&hdot.linear);
    let mut w = GravitoInertialWrench {
        mass,
        com,
        force: gravity * mass - hdot.linear,
        moment_about_com: -ldot_c,
    };
    w.add_external(external);
    w
}

/// The same wrench by the per-body sum of the theory (a second, independent
/// implementation for tests): for every body k its CoM acceleration `a_k`, angular
/// velocity and acceleration `ω_k, ω̇_k` and world inertia `I_k` about its CoM give
/// `Ḣ_k = I_k ω̇_k + ω_k × I_k ω_k`, then
/// `f_gi = Σ m_k (g − a_k) + Σ f_j` and
/// `M_gi(O) = Σ [(r_k − O) × m_k (g − a_k) − Ḣ_k] + Σ [(s_j − O) × f_j + n_j]` about the
/// world origin, moved to the centre of mass.
///
/// # Panics
/// On wrong vector lengths.
pub fn gravito_inertial_wrench_per_body(
    model: &Model,
    data: &mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    a: &DVector<f64>,
    gravity: &Vector3<f64>,
    external: &ExternalLoads<'_>,
) -> GravitoInertialWrench {
    crate::kinematics::forward_kinematics_second_order(model, data, q, v, a);
    let mut mass = 0.0;
    let mut first = Vector3::zeros();
    let mut f_gi = Vector3::zeros();
    let mut m_o = Vector3::zeros();
    for i in 1..model.njoints {
        let inertia = &model.inertias[i];
        let m = inertia.mass();
        let x = &data.world_from_joint[i];
        let c = inertia.com();
        let (v_o, w) = (data.v[i].linear, data.v[i].angular);
        let (a_o, wd) = (data.a[i].linear, data.a[i].angular);
        // classical acceleration of the body CoM, body axes
        let v_c = v_o + w.cross(&c);
        let a_c = a_o + wd.cross(&c) + w.cross(&v_c);
        let r_k = x.rotation * c + x.translation;
        let a_k = x.rotation * a_c;
        let w_k = x.rotation * w;
        let wd_k = x.rotation * wd;
        let i_k = x.rotation * inertia.inertia_about_com() * x.rotation.transpose();
        let h_dot = i_k * wd_k + w_k.cross(&(i_k * w_k));
        let load = (gravity - a_k) * m;
        f_gi += load;
        m_o += r_k.cross(&load) - h_dot;
        mass += m;
        first += r_k * m;
    }
    for f in external.forces {
        f_gi += f.force;
        m_o += f.point.cross(&f.force);
    }
    for n in external.moments {
        m_o += n;
    }
    let com = if mass > 0.0 {
        first / mass
    } else {
        Vector3::zeros()
    };
    GravitoInertialWrench {
        mass,
        com,
        force: f_gi,
        // M(p_c) = M(O) − (p_c − O) × f
        moment_about_com: m_o - com.cross(&f_gi),
    }
}

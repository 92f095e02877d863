//! Free-floating space manipulators: momentum, base motion induced by the joints, the
//! generalized Jacobian J* (Umetani & Yoshida), the generalized inertia H* and dynamic
//! singularities (Papadopoulos & Dubowsky).
//!
//! Works on any model whose root is a free flyer (`q = [x, y, z, qx, qy, qz, qw, q_m]`,
//! `v = [v_b; ω_b; q̇_m]` with the base twist in the **base** frame, as Pinocchio), with no
//! external force: gravity is not used by anything here (the free-floating simulation
//! sets it to zero). `n = nv − 6` is the number of joint rates q̇_m.
//!
//! ## The one map everything is built on
//!
//! The system momentum `h = [P; L_c]` (linear; angular about the system CoM c, world
//! axes) is the centroidal momentum `A_g v` of [`dynamics::centroidal_momentum_matrix`],
//! split into base and joint columns, `h = A_b v_b + A_m q̇_m`. Expressed at the CoM the
//! base block is block diagonal: if `(u_c, w)` is the base twist taken at the point c
//! (velocity of the base-fixed point at c, world axes; w the base angular velocity),
//! `A_b v_b = [M u_c; I_c w]`, with M the total mass and I_c the system's rotational
//! inertia about c. Hence, without any 6 × 6 factorisation,
//!
//! ```text
//! w   = I_c⁻¹ (L_c − A_m,ang q̇_m),   u_c = (P − A_m,lin q̇_m) / M
//! ṗ_b = u_c + w × (p_b − c),          v_b = [R_bᵀ ṗ_b; R_bᵀ w]            (base_velocity)
//! ẋ_f = J_f,m q̇_m + [u_c + w × (p_f − c); w]                              (any frame f)
//!     = J* q̇_m + d,   J* = J_f,m − [G_lin + G_ang × (p_f − c); G_ang],
//!     G = [A_m,lin / M; I_c⁻¹ A_m,ang],   d = [P/M + (I_c⁻¹ L_c) × (p_f − c); I_c⁻¹ L_c]
//! ```
//!
//! J* is the generalized Jacobian (zero momentum) and d the momentum drift of the frame
//! (theory item: `ẋ_f − J* q̇_m` is exactly the drift when the momentum is not zero). J* is
//! the same matrix as SpaceDyn's `calc_gj` (`J_m − J_s H_s⁻¹ H_bm`): the frame velocity
//! at zero momentum does not depend on how the base velocity is parametrised.
//!
//! The generalized inertia is the Schur complement of the base block of the CRBA matrix,
//! `H* = H_mm − H_bmᵀ H_bb⁻¹ H_bm` (`H* q̈_m + c* = τ` at zero momentum).
//!
//! Every function writes into a [`SpaceData`] workspace allocated once per model and does
//! not allocate.
//!
//! The simulation is in [`crate::sim::free_floating`]: its ODE keeps the base quaternion in
//! the state and projects it onto the unit sphere; control runs are kinematic (joint-rate
//! servos through J*, the base following from momentum conservation); a capture adds the
//! target's inertia to the grasping body and solves the impulsive momentum balance.
//! `docs/space.md` maps SpaceDyn's functions to these.

use crate::dynamics::{centroidal_momentum_matrix, crba};
use crate::error::{Error, Result};
use crate::kinematics::{ReferenceFrame, frame_jacobian_from_kinematics};
use crate::multibody::{Data, FrameIndex, JointType, Model, RootJoint};
use crate::spatial::{Force, Motion};
use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Matrix6xX, Vector3, Vector6};

/// Workspace and results of the space-manipulator algorithms (one per model).
#[derive(Clone, Debug)]
pub struct SpaceData {
    /// Number of joint rates `n = nv − 6`.
    pub n: usize,
    /// Total mass M (kg).
    pub total_mass: f64,
    /// System centre of mass c (world), m.
    pub com: Vector3<f64>,
    /// Rotational inertia of the whole system about its CoM, world axes, I_c (kg·m²).
    pub centroidal_inertia: Matrix3<f64>,
    /// `G = [A_m,lin / M; I_c⁻¹ A_m,ang]` (6 × n): minus the base twist at the CoM that
    /// each unit joint rate induces at zero momentum.
    pub centroidal_map: Matrix6xX<f64>,
    /// Base twist `[v_b; ω_b]` in the base frame from [`base_velocity`].
    pub base_velocity: Motion,
    /// The whole generalized velocity `v = [v_b; ω_b; q̇_m]` (nv) from [`base_velocity`].
    pub v: DVector<f64>,
    /// The frame Jacobian `[linear; angular]`, world axes at the frame origin (6 × nv), of
    /// the last [`generalized_jacobian`] call.
    pub frame_jacobian: Matrix6xX<f64>,
    /// Position of that frame's origin (world), m.
    pub frame_position: Vector3<f64>,
    /// The generalized Jacobian J* (6 × n) of that frame, rows `[linear; angular]` in
    /// world axes, zero momentum.
    pub generalized_jacobian: Matrix6xX<f64>,
    /// The generalized inertia H* (n × n) from [`generalized_inertia`].
    pub generalized_inertia: DMatrix<f64>,
    ic_inv: Matrix3<f64>,
    /// Scratch 6 × n (`L⁻¹ H_bm` in the Schur complement).
    scratch: Matrix6xX<f64>,
}

impl SpaceData {
    /// Allocates the workspace for a free-flyer-rooted `model`.
    ///
    /// # Errors
    /// [`Error::Model`] unless joint 1 is the model's only free-flyer root and every other
    /// joint keeps `nq = nv` (so that q̇ = v off the base).
    pub fn new(model: &Model) -> Result<Self> {
        check_free_flyer(model)?;
        let n = model.nv - 6;
        Ok(SpaceData {
            n,
            total_mass: 0.0,
            com: Vector3::zeros(),
            centroidal_inertia: Matrix3::zeros(),
            centroidal_map: Matrix6xX::zeros(n),
            base_velocity: Motion::zero(),
            v: DVector::zeros(model.nv),
            frame_jacobian: Matrix6xX::zeros(model.nv),
            frame_position: Vector3::zeros(),
            generalized_jacobian: Matrix6xX::zeros(n),
            generalized_inertia: DMatrix::zeros(n, n),
            ic_inv: Matrix3::zeros(),
            scratch: Matrix6xX::zeros(n),
        })
    }

    /// True if this workspace was sized for `model`.
    #[must_use]
    pub fn fits(&self, model: &Model) -> bool {
        model.nv == self.n + 6
    }
}

/// Checks that `model` is a free-floating system: joint 1 a free flyer at the root, every
/// other joint a descendant of it with `nq = nv`.
///
/// # Errors
/// [`Error::Model`] naming what is wrong.
pub fn check_free_flyer(model: &Model) -> Result<()> {
    if model.root != RootJoint::FreeFlyer
        || model.njoints < 2
        || !matches!(model.joint_types[1], JointType::FreeFlyer)
    {
        return Err(Error::Model(format!(
            "model '{}' is not rooted on a free flyer (load it with the free-flyer root)",
            model.name
        )));
    }
    for i in 2..model.njoints {
        if model.parents[i].0 == 0 {
            return Err(Error::Model(format!(
                "joint '{}' is attached to the world; a free-floating system has one root",
                model.names[i]
            )));
        }
        if model.nqs[i] != model.nvs[i] {
            return Err(Error::Model(format!(
                "joint '{}' has nq = {} ≠ nv = {}; only the base may be a free flyer",
                model.names[i], model.nqs[i], model.nvs[i]
            )));
        }
    }
    Ok(())
}

fn assert_space(model: &Model, sd: &SpaceData) {
    assert!(sd.fits(model), "SpaceData was sized for another model");
}

/// The system momentum `[P; L_c]` at `(q, v)`: linear momentum and angular momentum about
/// the system CoM, world axes (the centroidal momentum of the dynamics module; also in
/// `data.centroidal_momentum`).
///
/// # Panics
/// On wrong vector lengths.
pub fn momentum(model: &Model, data: &mut Data, q: &DVector<f64>, v: &DVector<f64>) -> Force {
    crate::dynamics::centroidal_momentum(model, data, q, v)
}

/// Fills the momentum maps of [`SpaceData`] at q: total mass, CoM, I_c, and the
/// centroidal map G. Runs forward kinematics and the centroidal momentum matrix (A_g is
/// left in `data.centroidal_momentum_matrix`).
///
/// # Errors
/// [`Error::Singular`] if the system has no mass or I_c is not positive definite.
///
/// # Panics
/// On wrong vector lengths or a workspace of another model.
pub fn momentum_maps(
    model: &Model,
    data: &mut Data,
    sd: &mut SpaceData,
    q: &DVector<f64>,
) -> Result<()> {
    assert_space(model, sd);
    centroidal_momentum_matrix(model, data, q);
    let total = data.composite_inertias[0];
    let m = total.mass();
    let ic = total.inertia_about_com();
    let ic_inv = if m > 0.0 {
        ic.cholesky().map(|c| c.inverse())
    } else {
        None
    };
    let Some(ic_inv) = ic_inv else {
        return Err(Error::Singular {
            what: "system inertia about the CoM".into(),
            detail: Some(format!("mass {m} kg, I_c = {:?}", ic.as_slice())),
        });
    };
    sd.total_mass = m;
    sd.com = data.com;
    sd.centroidal_inertia = ic;
    sd.ic_inv = ic_inv;
    let ag = &data.centroidal_momentum_matrix;
    for k in 0..sd.n {
        let a = ag.column(6 + k);
        let lin = Vector3::new(a[0], a[1], a[2]) / m;
        let ang = ic_inv * Vector3::new(a[3], a[4], a[5]);
        let mut g = sd.centroidal_map.column_mut(k);
        g[0] = lin.x;
        g[1] = lin.y;
        g[2] = lin.z;
        g[3] = ang.x;
        g[4] = ang.y;
        g[5] = ang.z;
    }
    Ok(())
}

/// The base twist `[u_c; w]` at the CoM (world axes) for momentum h and joint rates, from
/// the maps already in `sd`.
fn base_twist_at_com(
    sd: &SpaceData,
    qdot_joints: &[f64],
    h: &Force,
) -> (Vector3<f64>, Vector3<f64>) {
    let mut uc = h.linear / sd.total_mass;
    let mut w = sd.ic_inv * h.angular;
    for (k, &qd) in qdot_joints.iter().enumerate() {
        let g = sd.centroidal_map.column(k);
        uc -= Vector3::new(g[0], g[1], g[2]) * qd;
        w -= Vector3::new(g[3], g[4], g[5]) * qd;
    }
    (uc, w)
}

/// The base twist `[v_b; ω_b]` (base frame, the free-flyer convention) that the joint
/// rates `qdot_joints` (n) induce when the system momentum is `h = [P; L_c]` (pass
/// `Force::zero()` for a system at rest). Also writes `sd.base_velocity` and the whole
/// generalized velocity `sd.v`, and the momentum maps.
///
/// # Errors
/// As [`momentum_maps`].
///
/// # Panics
/// On wrong vector lengths.
pub fn base_velocity(
    model: &Model,
    data: &mut Data,
    sd: &mut SpaceData,
    q: &DVector<f64>,
    qdot_joints: &[f64],
    h: &Force,
) -> Result<Motion> {
    assert_eq!(
        qdot_joints.len(),
        sd.n,
        "qdot_joints must have nv − 6 entries"
    );
    momentum_maps(model, data, sd, q)?;
    let (uc, w) = base_twist_at_com(sd, qdot_joints, h);
    let base = &data.world_from_joint[1];
    let pb_dot = uc + w.cross(&(base.translation - sd.com));
    let rt = base.rotation.transpose();
    let vb = Motion::new(rt * pb_dot, rt * w);
    sd.base_velocity = vb;
    let lin = vb.linear;
    let ang = vb.angular;
    for r in 0..3 {
        sd.v[r] = lin[r];
        sd.v[3 + r] = ang[r];
    }
    sd.v.as_mut_slice()[6..].copy_from_slice(qdot_joints);
    Ok(vb)
}

/// The generalized Jacobian J* (6 × n, rows `[linear; angular]` of `frame`'s origin in
/// world axes) at q: `ẋ_f = J* q̇_m` at zero momentum. Stored in
/// `sd.generalized_jacobian`; the ordinary frame Jacobian (6 × nv) is left in
/// `sd.frame_jacobian` (its last n columns are the fixed-base Jacobian).
///
/// # Errors
/// As [`momentum_maps`].
///
/// # Panics
/// On wrong vector lengths.
pub fn generalized_jacobian<'s>(
    model: &Model,
    data: &mut Data,
    sd: &'s mut SpaceData,
    q: &DVector<f64>,
    frame: FrameIndex,
) -> Result<&'s Matrix6xX<f64>> {
    momentum_maps(model, data, sd, q)?;
    frame_jacobian_from_kinematics(
        model,
        data,
        frame,
        ReferenceFrame::LocalWorldAligned,
        &mut sd.frame_jacobian,
    );
    sd.frame_position = data.world_from_frame[frame.0].translation;
    let r = sd.frame_position - sd.com;
    for k in 0..sd.n {
        let g = sd.centroidal_map.column(k);
        let gl = Vector3::new(g[0], g[1], g[2]);
        let ga = Vector3::new(g[3], g[4], g[5]);
        let lin = gl + ga.cross(&r);
        let jf = sd.frame_jacobian.column(6 + k);
        let mut c = sd.generalized_jacobian.column_mut(k);
        for i in 0..3 {
            c[i] = jf[i] - lin[i];
            c[3 + i] = jf[3 + i] - ga[i];
        }
    }
    Ok(&sd.generalized_jacobian)
}

/// The momentum drift of the frame of the last [`generalized_jacobian`] call:
/// `d = [P/M + (I_c⁻¹ L_c) × (p_f − c); I_c⁻¹ L_c]`, so that the frame's velocity
/// `[ṗ_f; ω_f]` (world axes) is `J* q̇_m + d` for momentum `h = [P; L_c]`.
#[must_use]
pub fn momentum_drift(sd: &SpaceData, h: &Force) -> Vector6<f64> {
    let w = sd.ic_inv * h.angular;
    let lin = h.linear / sd.total_mass + w.cross(&(sd.frame_position - sd.com));
    Vector6::new(lin.x, lin.y, lin.z, w.x, w.y, w.z)
}

/// Frame velocity `J* q̇_m + d` (world axes) after [`generalized_jacobian`].
///
/// # Panics
/// If `qdot_joints` does not have n entries.
#[must_use]
pub fn frame_velocity(sd: &SpaceData, qdot_joints: &[f64], h: &Force) -> Vector6<f64> {
    assert_eq!(
        qdot_joints.len(),
        sd.n,
        "qdot_joints must have nv − 6 entries"
    );
    let mut x = momentum_drift(sd, h);
    for (k, &qd) in qdot_joints.iter().enumerate() {
        x += sd.generalized_jacobian.column(k) * qd;
    }
    x
}

/// The generalized inertia `H* = H_mm − H_bmᵀ H_bb⁻¹ H_bm` (n × n, symmetric positive
/// definite) at q, stored in `sd.generalized_inertia`. Runs CRBA (`data.mass_matrix`).
///
/// # Errors
/// [`Error::Singular`] if the base block H_bb is not positive definite.
///
/// # Panics
/// On wrong vector lengths.
pub fn generalized_inertia<'s>(
    model: &Model,
    data: &mut Data,
    sd: &'s mut SpaceData,
    q: &DVector<f64>,
) -> Result<&'s DMatrix<f64>> {
    assert_space(model, sd);
    let h = crba(model, data, q);
    let hbb: Matrix6<f64> = h.fixed_view::<6, 6>(0, 0).into_owned();
    let Some(chol) = hbb.cholesky() else {
        return Err(Error::Singular {
            what: "base block H_bb of the mass matrix".into(),
            detail: None,
        });
    };
    let l = chol.l();
    let n = sd.n;
    // X = L⁻¹ H_bm by forward substitution, column by column.
    for k in 0..n {
        let mut x = [0.0; 6];
        for i in 0..6 {
            let mut s = h[(i, 6 + k)];
            for (j, xj) in x.iter().enumerate().take(i) {
                s -= l[(i, j)] * xj;
            }
            x[i] = s / l[(i, i)];
        }
        sd.scratch.column_mut(k).copy_from_slice(&x);
    }
    for i in 0..n {
        for j in i..n {
            let xi = sd.scratch.column(i);
            let xj = sd.scratch.column(j);
            let v = h[(6 + i, 6 + j)] - xi.dot(&xj);
            sd.generalized_inertia[(i, j)] = v;
            sd.generalized_inertia[(j, i)] = v;
        }
    }
    Ok(&sd.generalized_inertia)
}

/// Dynamic-singularity measures of a frame: the position block (rows ṗ) of J* against
/// the same block of the fixed-base Jacobian `J_f,m`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DynamicSingularity {
    /// Smallest singular value of the position block of J* (of its min(3, n) values).
    pub sigma_min_generalized: f64,
    /// Smallest singular value of the position block of the fixed-base Jacobian.
    pub sigma_min_fixed_base: f64,
    /// det of the position block of J* when it is square (n = 3).
    pub det_generalized: Option<f64>,
    /// det of the position block of the fixed-base Jacobian when square (n = 3).
    pub det_fixed_base: Option<f64>,
}

impl DynamicSingularity {
    /// A dynamic singularity in the sense of Papadopoulos & Dubowsky: J* loses rank
    /// (σ_min ≤ `tol`) where the fixed-base Jacobian does not.
    #[must_use]
    pub fn is_dynamic_singularity(&self, tol: f64) -> bool {
        self.sigma_min_generalized <= tol && self.sigma_min_fixed_base > tol
    }
}

/// Smallest of the min(3, n) singular values of the 3 × n block whose rows are written
/// into `rows` (rows 0..3 of a 6 × n scratch, overwritten). The rows are orthogonalised
/// (modified Gram–Schmidt, `B = L Q` with L 3 × 3 lower triangular), so the singular
/// values come from a 3 × 3 SVD of L: accurate to rounding near zero, no allocation.
fn sigma_min_rows(rows: &mut Matrix6xX<f64>, n: usize) -> f64 {
    if n == 0 {
        return 0.0;
    }
    let mut l = Matrix3::zeros();
    for i in 0..3 {
        for j in 0..i {
            let d = rows.row(i).dot(&rows.row(j));
            l[(i, j)] = d;
            for k in 0..n {
                rows[(i, k)] -= d * rows[(j, k)];
            }
        }
        let nrm = rows.row(i).norm();
        l[(i, i)] = nrm;
        if nrm > 0.0 {
            for k in 0..n {
                rows[(i, k)] /= nrm;
            }
        }
    }
    let mut sv = l.svd(false, false).singular_values;
    sv.as_mut_slice().sort_by(|a, b| b.total_cmp(a));
    sv[n.min(3) - 1]
}

/// Dynamic-singularity measures of `frame` at q (runs [`generalized_jacobian`]).
///
/// # Errors
/// As [`momentum_maps`].
///
/// # Panics
/// On wrong vector lengths.
pub fn dynamic_singularity(
    model: &Model,
    data: &mut Data,
    sd: &mut SpaceData,
    q: &DVector<f64>,
    frame: FrameIndex,
) -> Result<DynamicSingularity> {
    generalized_jacobian(model, data, sd, q, frame)?;
    let n = sd.n;
    let col = |m: &Matrix6xX<f64>, k: usize| Vector3::new(m[(0, k)], m[(1, k)], m[(2, k)]);
    let (det_generalized, det_fixed_base) = if n == 3 {
        let g = &sd.generalized_jacobian;
        let f = &sd.frame_jacobian;
        (
            Some(Matrix3::from_columns(&[col(g, 0), col(g, 1), col(g, 2)]).determinant()),
            Some(Matrix3::from_columns(&[col(f, 6), col(f, 7), col(f, 8)]).determinant()),
        )
    } else {
        (None, None)
    };
    for k in 0..n {
        for r in 0..3 {
            sd.scratch[(r, k)] = sd.generalized_jacobian[(r, k)];
        }
    }
    let sigma_min_generalized = sigma_min_rows(&mut sd.scratch, n);
    for k in 0..n {
        for r in 0..3 {
            sd.scratch[(r, k)] = sd.frame_jacobian[(r, 6 + k)];
        }
    }
    let sigma_min_fixed_base = sigma_min_rows(&mut sd.scratch, n);
    Ok(DynamicSingularity {
        sigma_min_generalized,
        sigma_min_fixed_base,
        det_generalized,
        det_fixed_base,
    })
}

/// The per-state result document of a free-floating evaluation: the `states[i]` object
/// of `moma space` (schema in `docs/cli.md`) and the dictionary of the Python package's
/// `moma.space`. Matrices are lists of rows.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SpaceStateReport {
    /// Total mass (kg).
    pub total_mass: f64,
    /// System centre of mass (world).
    pub com: [f64; 3],
    /// The induced base twist `[v_b; ω_b]` (base frame).
    pub base_velocity: [f64; 6],
    /// The whole generalized velocity (nv).
    pub v: Vec<f64>,
    /// J* (6 × n).
    pub generalized_jacobian: Vec<Vec<f64>>,
    /// H* (n × n).
    pub generalized_inertia: Vec<Vec<f64>>,
    /// The frame's `[ṗ; ω]` (world axes), drift included.
    pub frame_velocity: [f64; 6],
}

impl SpaceStateReport {
    /// True when the velocities are finite (a degenerate mass distribution gives NaN).
    #[must_use]
    pub fn is_finite(&self) -> bool {
        self.v
            .iter()
            .chain(self.frame_velocity.iter())
            .all(|x| x.is_finite())
    }
}

/// Everything `moma space` reports for one state: [`base_velocity`],
/// [`generalized_jacobian`] and [`frame_velocity`] of `frame`, and
/// [`generalized_inertia`], for joint rates `qdot_joints` (n) and momentum `h`.
///
/// # Errors
/// As [`momentum_maps`] and [`generalized_inertia`].
///
/// # Panics
/// On wrong vector lengths.
pub fn state_report(
    model: &Model,
    data: &mut Data,
    sd: &mut SpaceData,
    q: &DVector<f64>,
    qdot_joints: &[f64],
    h: &Force,
    frame: FrameIndex,
) -> Result<SpaceStateReport> {
    let rows = |m: &DMatrix<f64>| -> Vec<Vec<f64>> {
        m.row_iter().map(|r| r.iter().copied().collect()).collect()
    };
    let vb = base_velocity(model, data, sd, q, qdot_joints, h)?;
    let v = sd.v.as_slice().to_vec();
    generalized_jacobian(model, data, sd, q, frame)?;
    let xf = frame_velocity(sd, qdot_joints, h);
    let gj = sd
        .generalized_jacobian
        .row_iter()
        .map(|r| r.iter().copied().collect())
        .collect();
    let hs = rows(generalized_inertia(model, data, sd, q)?);
    Ok(SpaceStateReport {
        total_mass: sd.total_mass,
        com: [sd.com.x, sd.com.y, sd.com.z],
        base_velocity: vb.to_vector().into(),
        v,
        generalized_jacobian: gj,
        generalized_inertia: hs,
        frame_velocity: xf.into(),
    })
}

//! Wheel contacts on any planar-rooted model: the no-side-slip (and, with tracked wheel
//! angles, rolling) Pfaffian constraints `C(q) q̇ = 0`, the analytic admissible-velocity
//! basis `N_C(q)` and its derivative, the actuation map `S(q)`, the reduced dynamics
//! with Lagrange multipliers, and wheel-rate kinematics (chapter 5.1–5.3, eqs 5.20–5.28).
//!
//! # Coordinates
//!
//! The model's root joint is planar: `q = [x, y, θ, q_rest…]`, `q̇ = [ẋ, ẏ, θ̇, q̇_rest…]`
//! in world axes (see [`crate::multibody::RootJoint::Planar`]). The base frame origin is
//! a distance `d` ahead of the driven-axle midpoint ([`DiffDrive`]). If the URDF models
//! the two driven wheels as joints, name them in [`WheeledBase::wheel_joints`]: their
//! angles are then tracked and two rolling rows join the constraint (k = 3); otherwise
//! the wheels are massless traction actuators (k = 1).
//!
//! The reduced velocity is `v_r = [v, ω, q̇_arm…]`: the forward speed of the axle
//! midpoint, the yaw rate, and the rates of every other joint in model order:
//!
//! ```text
//! q̇ = N_C(q) v_r,   N_C = ⎡ N_dd(θ)    0 ⎤  base rows      (3×2, DiffDrive::basis)
//!                         ⎢ s ⊙ W⁻¹    0 ⎥  wheel rows     (only with tracked wheels)
//!                         ⎣   0        I ⎦  arm rows
//! ```
//!
//! The inputs are `u = [τ_L, τ_R, τ_arm…]`: wheel torques then one torque (or force) per
//! arm joint. Untracked wheels push with `τ/r_w` along the heading at their contact
//! points ([`DiffDrive::actuation_map`]); tracked wheels receive `τ` on their joints.

use nalgebra::{DMatrix, DVector, Matrix6xX, Vector2, Vector3};
use serde::{Deserialize, Serialize};

use crate::dynamics::{centroidal_momentum, crba, kinetic_energy, potential_energy, rnea};
use crate::error::{Error, Result};
use crate::kinematics::{ReferenceFrame, frame_jacobian};
use crate::linalg::{cholesky_in_place, cholesky_solve};
use crate::mobile::diff_drive::DiffDrive;
use crate::mobile::reduced::{PIVOT_TOL, ReducedDynamics};
use crate::multibody::{Data, FrameIndex, JointType, Model, RootJoint};

/// A passive caster: a support contact point of the base. It adds no kinematic
/// constraint (a caster swivels freely) but belongs to the support polygon
/// ([`WheeledBase::support_points`]) that tip-over and stability analyses read. It is
/// also the caster table of every file that lists casters (`name`, `position`; unknown
/// keys refused): a casters file ([`crate::mobile::read_casters`]), `moma simulate`'s
/// `robot.casters` and `moma mission`'s; [`crate::mobile::caster_list_problem`] checks a
/// list.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Caster {
    /// A name for reports.
    pub name: String,
    /// Ground contact point in the base frame `[x, y]` (m).
    pub position: [f64; 2],
}

/// The wheel set-up of a planar-rooted model: the differential drive, its passive
/// casters, and optionally the URDF joints of the `[left, right]` driven wheels.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct WheeledBase {
    /// The differential drive (wheel radius, half track, offset d).
    pub drive: DiffDrive,
    /// Passive support casters.
    #[serde(default)]
    pub casters: Vec<Caster>,
    /// Names of the `[left, right]` wheel joints to track, if the model has them.
    #[serde(default)]
    pub wheel_joints: Option<[String; 2]>,
}

impl WheeledBase {
    /// A base with just a differential drive (no casters, wheels not tracked).
    pub fn new(drive: DiffDrive) -> Self {
        Self {
            drive,
            casters: Vec::new(),
            wheel_joints: None,
        }
    }

    /// Ground support points in the base frame: the two wheel contacts (`[left, right]`)
    /// then the casters.
    pub fn support_points(&self) -> Vec<Vector2<f64>> {
        let dd = &self.drive;
        let mut pts = vec![
            Vector2::new(-dd.d, dd.half_track),
            Vector2::new(-dd.d, -dd.half_track),
        ];
        pts.extend(
            self.casters
                .iter()
                .map(|c| Vector2::new(c.position[0], c.position[1])),
        );
        pts
    }
}

/// Casters take part in the model as support points ([`WheeledBase::support_points`],
/// read by stability analyses): each needs a unique, non-empty name and a finite contact
/// point.
fn check_casters(casters: &[Caster]) -> Result<()> {
    for (k, c) in casters.iter().enumerate() {
        if c.name.trim().is_empty() {
            return Err(Error::invalid(
                format!("casters[{k}] name"),
                "a caster needs a name",
            ));
        }
        if casters[..k].iter().any(|o| o.name == c.name) {
            return Err(Error::invalid(
                format!("caster '{}'", c.name),
                "two casters have this name",
            ));
        }
        crate::error::ensure_finite(&format!("caster '{}' position", c.name), &c.position)?;
    }
    Ok(())
}

/// A planar-rooted [`Model`] on a [`WheeledBase`]: the constrained mobile manipulator.
#[derive(Debug, Clone)]
pub struct WheeledModel {
    /// The rigid-body model (planar root).
    pub model: Model,
    /// The wheel set-up.
    pub base: WheeledBase,
    wheel_dofs: Option<[usize; 2]>,
    wheel_signs: [f64; 2],
    arm_dofs: Vec<usize>,
}

impl WheeledModel {
    /// Checks that `model` has a planar root and only one-dof joints besides it, resolves
    /// the tracked wheel joints (children of the base with a lateral axis) and the arm
    /// joints.
    pub fn new(model: Model, base: WheeledBase) -> Result<Self> {
        if model.root != RootJoint::Planar {
            return Err(Error::Model(format!(
                "a wheeled model needs a planar root joint, '{}' has a {} root",
                model.name, model.root
            )));
        }
        if model.nq != model.nv {
            return Err(Error::Model(format!(
                "wheeled model '{}': every joint besides the planar root must have one \
                 coordinate per velocity (nq = {}, nv = {})",
                model.name, model.nq, model.nv
            )));
        }
        if let Some(j) = (2..model.njoints).find(|&j| model.nvs[j] != 1) {
            return Err(Error::Model(format!(
                "wheeled model '{}': joint '{}' has {} velocities; only one-dof joints may sit \
                 on the planar base",
                model.name, model.names[j], model.nvs[j]
            )));
        }
        let root = (1..model.njoints)
            .find(|&j| model.joint_types[j] == JointType::Planar)
            .ok_or_else(|| Error::Model("no planar root joint".into()))?;
        if model.idx_v[root] != 0 {
            return Err(Error::Model(
                "the planar root must own velocities 0..3".into(),
            ));
        }
        check_casters(&base.casters)?;
        let mut wheel_dofs = None;
        let mut wheel_signs = [1.0, 1.0];
        if let Some(names) = &base.wheel_joints {
            let mut dofs = [0usize; 2];
            for (side, name) in names.iter().enumerate() {
                let j = model.joint_id(name)?.0;
                let field = format!("wheel joint '{name}'");
                if model.parents[j].0 != root {
                    return Err(Error::invalid(field, "must be a child of the planar base"));
                }
                let axis = model.joint_types[j]
                    .axis()
                    .filter(|_| model.joint_types[j].is_revolute());
                let axis = axis.ok_or_else(|| {
                    Error::invalid(field.clone(), "must be a revolute (continuous) joint")
                })?;
                let a = model.joint_placements[j].rotation * axis;
                if a.y.abs() < 0.99 {
                    return Err(Error::invalid(
                        field,
                        format!(
                            "axis must point along the base y axis, got [{:.3}, {:.3}, {:.3}]",
                            a.x, a.y, a.z
                        ),
                    ));
                }
                // Rolling forward at speed r φ̇ with the wheel turning about a: v x̂ = φ̇ r (a × ẑ).
                wheel_signs[side] = a.y.signum();
                dofs[side] = model.idx_v[j];
            }
            if dofs[0] == dofs[1] {
                return Err(Error::invalid("wheel joints", "left and right must differ"));
            }
            wheel_dofs = Some(dofs);
        }
        let arm_dofs = (3..model.nv)
            .filter(|i| wheel_dofs.is_none_or(|w| !w.contains(i)))
            .collect();
        Ok(Self {
            model,
            base,
            wheel_dofs,
            wheel_signs,
            arm_dofs,
        })
    }

    /// Number of velocities nv of the full model.
    pub fn nv(&self) -> usize {
        self.model.nv
    }

    /// Number of constraint rows k (1, or 3 with tracked wheels).
    pub fn nk(&self) -> usize {
        if self.wheel_dofs.is_some() { 3 } else { 1 }
    }

    /// Number of reduced velocities `nv − k` (= 2 + number of arm joints).
    pub fn nr(&self) -> usize {
        2 + self.arm_dofs.len()
    }

    /// Number of inputs (2 wheel torques + one per arm joint).
    pub fn nu(&self) -> usize {
        2 + self.arm_dofs.len()
    }

    /// Velocity indices of the arm joints (every joint but the base and tracked wheels).
    pub fn arm_dofs(&self) -> &[usize] {
        &self.arm_dofs
    }

    /// Velocity indices of the tracked `[left, right]` wheel joints.
    pub fn wheel_dofs(&self) -> Option<[usize; 2]> {
        self.wheel_dofs
    }

    /// The ground's height in the root (base) frame (m): the tracked left wheel's axle
    /// height minus the wheel radius, so a root described at axle height puts the ground
    /// at `−r_w`; 0 (the root on the ground) without tracked wheel joints.
    #[must_use]
    pub fn ground_z(&self) -> f64 {
        match self.wheel_dofs {
            Some([left, _]) => {
                let j = self.model.joint_of_dof[left];
                self.model.joint_placements[j.0].translation.z - self.base.drive.wheel_radius
            }
            None => 0.0,
        }
    }

    /// Names of the configuration coordinates `[x, y, theta, <joint names>…]`.
    pub fn q_names(&self) -> Vec<String> {
        let mut names = vec!["x".to_string(), "y".into(), "theta".into()];
        for i in 3..self.model.nv {
            names.push(self.dof_name(i));
        }
        names
    }

    /// Names of the reduced velocities `[v, omega, <arm joint>_dot…]`.
    pub fn v_names(&self) -> Vec<String> {
        let mut names = vec!["v".to_string(), "omega".into()];
        names.extend(
            self.arm_dofs
                .iter()
                .map(|&i| format!("{}_dot", self.dof_name(i))),
        );
        names
    }

    /// Names of the inputs `[tau_left, tau_right, tau_<arm joint>…]`.
    pub fn u_names(&self) -> Vec<String> {
        let mut names = vec!["tau_left".to_string(), "tau_right".into()];
        names.extend(
            self.arm_dofs
                .iter()
                .map(|&i| format!("tau_{}", self.dof_name(i))),
        );
        names
    }

    fn dof_name(&self, i: usize) -> String {
        self.model.names[self.model.joint_of_dof[i].0].clone()
    }
}

/// Workspace of the wheeled-model algorithms (all buffers allocated once).
#[derive(Debug, Clone)]
pub struct WheeledData {
    /// Rigid-body workspace.
    pub data: Data,
    /// Reduced dynamics results: Mr, cr, Gr, Qr, v̇, q̈, λ, −Cᵀλ.
    pub reduced: ReducedDynamics,
    /// Constraint matrix C(q) (k×nv).
    pub constraint: DMatrix<f64>,
    /// Admissible-velocity basis N_C(q) (nv×nr).
    pub basis: DMatrix<f64>,
    /// Its derivative Ṅ_C(q, q̇) (nv×nr).
    pub basis_dot: DMatrix<f64>,
    /// Full velocity q̇ = N_C v_r (nv).
    pub qdot: DVector<f64>,
    /// Applied generalised force Q = S u (nv).
    pub force: DVector<f64>,
    /// Frame Jacobian buffer (6×nv).
    pub jacobian: Matrix6xX<f64>,
    nd_v: DVector<f64>,
    zero: DVector<f64>,
    tmp: DVector<f64>,
    gravity: DVector<f64>,
}

impl WheeledData {
    /// Allocates every buffer for `wm`.
    pub fn new(wm: &WheeledModel) -> Self {
        let (nv, nr, nk) = (wm.nv(), wm.nr(), wm.nk());
        Self {
            data: Data::new(&wm.model),
            reduced: ReducedDynamics::new(nv, nr, nk),
            constraint: DMatrix::zeros(nk, nv),
            basis: DMatrix::zeros(nv, nr),
            basis_dot: DMatrix::zeros(nv, nr),
            qdot: DVector::zeros(nv),
            force: DVector::zeros(nv),
            jacobian: Matrix6xX::zeros(nv),
            nd_v: DVector::zeros(nv),
            zero: DVector::zeros(nv),
            tmp: DVector::zeros(nv),
            gravity: DVector::zeros(nv),
        }
    }
}

/// Pfaffian constraint matrix C(q) (k×nv): the no-side-slip row
/// `[−sin θ, cos θ, −d, 0…]` and, with tracked wheels, the two rolling rows.
#[doc(alias = "C")]
pub fn constraint_matrix(wm: &WheeledModel, q: &DVector<f64>, out: &mut DMatrix<f64>) {
    assert_eq!(out.shape(), (wm.nk(), wm.nv()), "C shape");
    out.fill(0.0);
    let dd = &wm.base.drive;
    let row = dd.constraint_row(q[2]);
    for j in 0..3 {
        out[(0, j)] = row[j];
    }
    if let Some(w) = wm.wheel_dofs {
        let roll = dd.rolling_rows(q[2]);
        for side in 0..2 {
            for j in 0..3 {
                out[(1 + side, j)] = roll[(side, j)];
            }
            // Wheel joint angle ψ = s φ, so −r_w φ̇ = −r_w s ψ̇.
            out[(1 + side, w[side])] = roll[(side, 3 + side)] * wm.wheel_signs[side];
        }
    }
}

/// Admissible-velocity basis N_C(q) (nv×nr) with `C N_C = 0`, for `v_r = [v, ω, q̇_arm…]`.
#[doc(alias = "N_C")]
pub fn admissible_velocity_basis(wm: &WheeledModel, q: &DVector<f64>, out: &mut DMatrix<f64>) {
    assert_eq!(out.shape(), (wm.nv(), wm.nr()), "N_C shape");
    out.fill(0.0);
    let dd = &wm.base.drive;
    let nb = dd.basis(q[2]);
    for i in 0..3 {
        for j in 0..2 {
            out[(i, j)] = nb[(i, j)];
        }
    }
    if let Some(w) = wm.wheel_dofs {
        let winv = dd.platform_to_wheel();
        for side in 0..2 {
            for j in 0..2 {
                out[(w[side], j)] = wm.wheel_signs[side] * winv[(side, j)];
            }
        }
    }
    for (k, &i) in wm.arm_dofs.iter().enumerate() {
        out[(i, 2 + k)] = 1.0;
    }
}

/// Time derivative Ṅ_C(q, q̇) (nv×nr); only the base block depends on q (through θ).
#[doc(alias = "Ndot_C")]
pub fn admissible_velocity_basis_dot(
    wm: &WheeledModel,
    q: &DVector<f64>,
    theta_dot: f64,
    out: &mut DMatrix<f64>,
) {
    assert_eq!(out.shape(), (wm.nv(), wm.nr()), "Ṅ_C shape");
    out.fill(0.0);
    let nd = wm.base.drive.basis_dot(q[2], theta_dot);
    for i in 0..3 {
        for j in 0..2 {
            out[(i, j)] = nd[(i, j)];
        }
    }
}

/// Actuation map S(q) (nv×nu): `Q = S u` for `u = [τ_L, τ_R, τ_arm…]`.
#[doc(alias = "S")]
pub fn actuation_matrix(wm: &WheeledModel, q: &DVector<f64>, out: &mut DMatrix<f64>) {
    assert_eq!(out.shape(), (wm.nv(), wm.nu()), "S shape");
    out.fill(0.0);
    if let Some(w) = wm.wheel_dofs {
        out[(w[0], 0)] = wm.wheel_signs[0];
        out[(w[1], 1)] = wm.wheel_signs[1];
    } else {
        let s = wm.base.drive.actuation_map(q[2]);
        for i in 0..3 {
            for j in 0..2 {
                out[(i, j)] = s[(i, j)];
            }
        }
    }
    for (k, &i) in wm.arm_dofs.iter().enumerate() {
        out[(i, 2 + k)] = 1.0;
    }
}

/// Generalised force `Q = S(q) u` written into `out` without forming S.
pub fn generalized_force(wm: &WheeledModel, q: &DVector<f64>, u: &[f64], out: &mut DVector<f64>) {
    assert_eq!(u.len(), wm.nu(), "u length");
    out.fill(0.0);
    if let Some(w) = wm.wheel_dofs {
        out[w[0]] = wm.wheel_signs[0] * u[0];
        out[w[1]] = wm.wheel_signs[1] * u[1];
    } else {
        let s = wm.base.drive.actuation_map(q[2]);
        for i in 0..3 {
            out[i] = s[(i, 0)] * u[0] + s[(i, 1)] * u[1];
        }
    }
    for (k, &i) in wm.arm_dofs.iter().enumerate() {
        out[i] = u[2 + k];
    }
}

/// `out = N_Cᵀ x` using the block structure of N_C (`x` has nv entries, `out` nr).
fn project(wm: &WheeledModel, basis: &DMatrix<f64>, x: &DVector<f64>, out: &mut DVector<f64>) {
    for j in 0..2 {
        let mut s = 0.0;
        for i in 0..3 {
            s += basis[(i, j)] * x[i];
        }
        if let Some(w) = wm.wheel_dofs {
            s += basis[(w[0], j)] * x[w[0]] + basis[(w[1], j)] * x[w[1]];
        }
        out[j] = s;
    }
    for (k, &i) in wm.arm_dofs.iter().enumerate() {
        out[2 + k] = x[i];
    }
}

pub(crate) fn check_state(wm: &WheeledModel, q: &DVector<f64>, v_r: &DVector<f64>, u: &[f64]) {
    assert_eq!(q.len(), wm.model.nq, "q length");
    assert_eq!(v_r.len(), wm.nr(), "v_r length");
    assert_eq!(u.len(), wm.nu(), "u length");
}

/// Reduced forward dynamics by the joint-space route, for any wheel set-up: v̇_r in
/// `wd.reduced.vdot`, q̈ in `wd.reduced.qddot`, Mr in `wd.reduced.mass_matrix`.
///
/// The terms of [`reduced_dynamics_terms_crba`], then `Mr v̇_r = Qr − (cr + Gr)` by
/// Cholesky. Reports [`Error::Singular`] if Mr is not positive definite. Does not
/// allocate.
///
/// # Panics
/// On wrong vector lengths.
pub fn reduced_forward_dynamics_crba<'d>(
    wm: &WheeledModel,
    wd: &'d mut WheeledData,
    q: &DVector<f64>,
    v_r: &DVector<f64>,
    u: &[f64],
) -> Result<&'d DVector<f64>> {
    reduced_dynamics_terms_crba(wm, wd, q, v_r, u);
    wd.reduced.solve_reduced()?;
    wd.reduced.qddot.copy_from(&wd.nd_v);
    wd.reduced.qddot.gemv(1.0, &wd.basis, &wd.reduced.vdot, 1.0);
    Ok(&wd.reduced.vdot)
}

/// The terms of the reduced dynamics at `(q, v_r)` under `u`, without solving for the
/// acceleration: Mr in `wd.reduced.mass_matrix`, cr + Gr in `wd.reduced.velocity_terms`
/// (`gravity` zero), Qr in `wd.reduced.force`, N_C and Ṅ_C in `wd.basis` and
/// `wd.basis_dot`, q̇ in `wd.qdot` and Ṅ_C v in `wd.nd_v` (`wd.reduced.vdot` and `qddot`
/// are left as they were). For a caller that needs the inverse dynamics
/// `Mr v̇_r + cr + Gr` of its own accelerations, not the forward dynamics.
///
/// One CRBA for H, one RNEA with `a = Ṅ_C v` for `H Ṅ_C v + h + G`, and
/// `Mr = N_Cᵀ H N_C` formed blockwise from the sparsity of N_C (the arm block of Mr is
/// the arm block of H; only the two platform columns are products). Does not allocate.
///
/// # Panics
/// On wrong vector lengths.
pub fn reduced_dynamics_terms_crba(
    wm: &WheeledModel,
    wd: &mut WheeledData,
    q: &DVector<f64>,
    v_r: &DVector<f64>,
    u: &[f64],
) {
    check_state(wm, q, v_r, u);
    let model = &wm.model;
    admissible_velocity_basis(wm, q, &mut wd.basis);
    wd.basis.mul_to(v_r, &mut wd.qdot);
    admissible_velocity_basis_dot(wm, q, wd.qdot[2], &mut wd.basis_dot);
    wd.basis_dot.mul_to(v_r, &mut wd.nd_v);
    generalized_force(wm, q, u, &mut wd.force);
    crba(model, &mut wd.data, q);
    rnea(model, &mut wd.data, q, &wd.qdot, &wd.nd_v);
    let bias = &wd.data.tau; // H Ṅ_C v + h + G
    let h = &wd.data.mass_matrix;
    let basis = &wd.basis;
    let nr = wm.nr();
    let platform: [usize; 5];
    let prows: &[usize] = match wm.wheel_dofs {
        Some(w) => {
            platform = [0, 1, 2, w[0], w[1]];
            &platform
        }
        None => {
            platform = [0, 1, 2, 0, 0];
            &platform[..3]
        }
    };
    {
        let red = &mut wd.reduced;
        let (mr, cr, gr, qr) = red.parts_mut();
        // Platform columns of H N_C restricted to platform rows and arm rows.
        for a in 0..2 {
            for b in a..2 {
                let mut s = 0.0;
                for &i in prows {
                    let mut hi = 0.0;
                    for &j in prows {
                        hi += h[(i, j)] * basis[(j, b)];
                    }
                    s += basis[(i, a)] * hi;
                }
                mr[(a, b)] = s;
                mr[(b, a)] = s;
            }
        }
        for (k, &i) in wm.arm_dofs.iter().enumerate() {
            for a in 0..2 {
                let mut s = 0.0;
                for &j in prows {
                    s += h[(i, j)] * basis[(j, a)];
                }
                mr[(2 + k, a)] = s;
                mr[(a, 2 + k)] = s;
            }
            for (l, &j) in wm.arm_dofs.iter().enumerate().take(k + 1) {
                mr[(2 + k, 2 + l)] = h[(i, j)];
                mr[(2 + l, 2 + k)] = h[(i, j)];
            }
        }
        // cr + Gr together from the RNEA bias: after this fast path
        // `wd.reduced.velocity_terms` holds cr + Gr and `gravity` is zero (use
        // `reduced_dynamics` for the split).
        project(wm, basis, bias, cr);
        gr.fill(0.0);
        project(wm, basis, &wd.force, qr);
        debug_assert_eq!(mr.nrows(), nr);
    }
}

/// The reduced inverse dynamics `Mr v̇_r + cr + Gr` at `(q, v_r)` with the reduced
/// acceleration `a_r`, into `out` (nr), by one RNEA instead of a CRBA: with
/// `q̈ = N_C v̇_r + Ṅ_C v_r` (left in `wd.reduced.qddot`), `N_Cᵀ (H q̈ + h + G)` is the
/// same sum (`Mr = N_Cᵀ H N_C`, `cr + Gr = N_Cᵀ (H Ṅ_C v + h + G)`). N_C, Ṅ_C and q̇ are
/// left in `wd.basis`, `wd.basis_dot` and `wd.qdot`. Does not allocate.
///
/// # Panics
/// On wrong vector lengths.
pub fn reduced_inverse_dynamics(
    wm: &WheeledModel,
    wd: &mut WheeledData,
    q: &DVector<f64>,
    v_r: &DVector<f64>,
    a_r: &DVector<f64>,
    out: &mut DVector<f64>,
) {
    assert_eq!(q.len(), wm.model.nq, "q length");
    assert_eq!(v_r.len(), wm.nr(), "v_r length");
    assert_eq!(a_r.len(), wm.nr(), "a_r length");
    assert_eq!(out.len(), wm.nr(), "out length");
    admissible_velocity_basis(wm, q, &mut wd.basis);
    wd.basis.mul_to(v_r, &mut wd.qdot);
    admissible_velocity_basis_dot(wm, q, wd.qdot[2], &mut wd.basis_dot);
    let qddot = &mut wd.reduced.qddot;
    wd.basis_dot.mul_to(v_r, qddot);
    qddot.gemv(1.0, &wd.basis, a_r, 1.0);
    let tau = rnea(&wm.model, &mut wd.data, q, &wd.qdot, &wd.reduced.qddot);
    project(wm, &wd.basis, tau, out);
}

/// The reduced forward dynamics of the state last evaluated in `wd` by
/// [`reduced_forward_dynamics_crba`] (at `q`, any input) under new inputs `u`: only
/// `Qr`, `v̇_r` and `q̈` change (Mr, cr + Gr, N_C, Ṅ_C v do not depend on the input), so a
/// controller that evaluated the state under zero input to form its torques gets the
/// plant's response to them without a second CRBA and RNEA. The result is the one
/// [`reduced_forward_dynamics_crba`] gives at the same state under `u`.
///
/// # Errors
/// [`Error::Singular`] if Mr is not positive definite.
///
/// # Panics
/// On wrong vector lengths.
pub fn reduced_forward_dynamics_under_inputs<'d>(
    wm: &WheeledModel,
    wd: &'d mut WheeledData,
    q: &DVector<f64>,
    u: &[f64],
) -> Result<&'d DVector<f64>> {
    assert_eq!(q.len(), wm.model.nq, "q length");
    generalized_force(wm, q, u, &mut wd.force);
    {
        let red = &mut wd.reduced;
        let (_, _, _, qr) = red.parts_mut();
        project(wm, &wd.basis, &wd.force, qr);
        red.solve_reduced()?;
    }
    wd.reduced.qddot.copy_from(&wd.nd_v);
    wd.reduced.qddot.gemv(1.0, &wd.basis, &wd.reduced.vdot, 1.0);
    Ok(&wd.reduced.vdot)
}

/// Full reduced dynamics at `(q, v_r)` under `u`: Mr, Cr (from the Christoffel Coriolis
/// matrix), cr, Gr (separately from cr), Qr, v̇, q̈, the multipliers λ and the
/// constraint force −Cᵀλ, all in `wd.reduced`; C, N_C, Ṅ_C in `wd`.
///
/// `coriolis` is the Christoffel-consistent Coriolis matrix C_cor(q, q̇) of the full model
/// at `q̇ = N_C v_r` (nv×nv); pass `None` to skip Cr.
pub fn reduced_dynamics(
    wm: &WheeledModel,
    wd: &mut WheeledData,
    q: &DVector<f64>,
    v_r: &DVector<f64>,
    u: &[f64],
    coriolis: Option<&DMatrix<f64>>,
) -> Result<()> {
    check_state(wm, q, v_r, u);
    let model = &wm.model;
    admissible_velocity_basis(wm, q, &mut wd.basis);
    wd.basis.mul_to(v_r, &mut wd.qdot);
    admissible_velocity_basis_dot(wm, q, wd.qdot[2], &mut wd.basis_dot);
    constraint_matrix(wm, q, &mut wd.constraint);
    generalized_force(wm, q, u, &mut wd.force);
    crba(model, &mut wd.data, q);
    wd.gravity
        .copy_from(crate::dynamics::gravity_torque(model, &mut wd.data, q));
    // h = C_cor q̇ = RNEA(q, q̇, 0) − G.
    rnea(model, &mut wd.data, q, &wd.qdot, &wd.zero);
    wd.tmp.copy_from(&wd.data.tau);
    wd.tmp -= &wd.gravity;
    let terms = crate::mobile::reduced::JointSpaceTerms {
        mass_matrix: &wd.data.mass_matrix,
        velocity_terms: &wd.tmp,
        gravity: &wd.gravity,
        force: &wd.force,
    };
    wd.reduced.compute(&terms, &wd.basis, &wd.basis_dot, v_r)?;
    if let Some(c) = coriolis {
        wd.reduced
            .compute_coriolis(&wd.data.mass_matrix, c, &wd.basis, &wd.basis_dot);
    }
    wd.reduced.compute_multipliers(&terms, &wd.constraint)?;
    Ok(())
}

/// The longitudinal ground forces `[left, right]` on the driven wheels (N, along the
/// heading: traction +, braking −) for the multipliers `lambda` of
/// [`lagrange_multipliers`] and the inputs `u`. With tracked wheels they are the rolling
/// rows' share of the constraint force −Cᵀλ: each rolling row is the contact's forward
/// velocity minus r φ̇, so the ground pushes the base forward by −λ₁ (left) and −λ₂
/// (right); without tracked wheels (massless wheels), the wheel torques over the radius.
#[must_use]
pub fn wheel_longitudinal_forces(wm: &WheeledModel, lambda: &[f64], u: &[f64]) -> [f64; 2] {
    if wm.wheel_dofs().is_some() {
        [-lambda[1], -lambda[2]]
    } else {
        let r = wm.base.drive.wheel_radius;
        [u[0] / r, u[1] / r]
    }
}

/// Lagrange multipliers λ (k) for the state and input of the last
/// [`reduced_forward_dynamics`](crate::mobile::reduced_forward_dynamics) call: `λ = (C Cᵀ)⁻¹ C (Q − RNEA(q, q̇, q̈))`, and the
/// constraint generalised force −Cᵀλ in `wd.reduced.constraint_force`. One extra RNEA.
#[doc(alias = "lambda")]
pub fn lagrange_multipliers<'d>(
    wm: &WheeledModel,
    wd: &'d mut WheeledData,
    q: &DVector<f64>,
) -> Result<&'d DVector<f64>> {
    constraint_matrix(wm, q, &mut wd.constraint);
    rnea(&wm.model, &mut wd.data, q, &wd.qdot, &wd.reduced.qddot);
    wd.tmp.copy_from(&wd.force);
    wd.tmp -= &wd.data.tau;
    let k = wm.nk();
    let c = &wd.constraint;
    let mut cct = nalgebra::Matrix3::<f64>::zeros();
    let mut rhs = nalgebra::Vector3::<f64>::zeros();
    for i in 0..k {
        rhs[i] = c.row(i).iter().zip(wd.tmp.iter()).map(|(a, b)| a * b).sum();
        for j in 0..k {
            cct[(i, j)] = c.row(i).dot(&c.row(j));
        }
    }
    // Solve the k×k system (k ≤ 3).
    let lam = &mut wd.reduced.lambda;
    let sub = cct.fixed_view::<3, 3>(0, 0);
    match k {
        1 => lam[0] = rhs[0] / sub[(0, 0)],
        _ => {
            let m = sub.into_owned();
            let chol = m.cholesky().ok_or_else(|| Error::Singular {
                what: "C Cᵀ".into(),
                detail: None,
            })?;
            let x = chol.solve(&rhs);
            for i in 0..k {
                lam[i] = x[i];
            }
        }
    }
    c.tr_mul_to(lam, &mut wd.reduced.constraint_force);
    wd.reduced.constraint_force.neg_mut();
    Ok(&wd.reduced.lambda)
}

/// Kinetic and potential energy `(T, V)` at `(q, v_r)` (J).
pub fn energy(
    wm: &WheeledModel,
    wd: &mut WheeledData,
    q: &DVector<f64>,
    v_r: &DVector<f64>,
) -> (f64, f64) {
    admissible_velocity_basis(wm, q, &mut wd.basis);
    wd.basis.mul_to(v_r, &mut wd.qdot);
    let t = kinetic_energy(&wm.model, &mut wd.data, q, &wd.qdot);
    let v = potential_energy(&wm.model, &mut wd.data, q);
    (t, v)
}

// ---- wheel-rate kinematics (chapter 5.20–5.28) -------------------------------------------

/// Full velocity `q̇ = N_C(q) v_r` from wheel rates `[φ̇_L, φ̇_R]` and arm rates
/// (chapter 5.21–5.27). Allocates its temporaries; meant for analysis, not hot loops.
pub fn velocity_from_wheel_rates(
    wm: &WheeledModel,
    q: &DVector<f64>,
    wheel_rates: [f64; 2],
    arm_rates: &[f64],
    out: &mut DVector<f64>,
) {
    assert_eq!(arm_rates.len(), wm.arm_dofs.len(), "arm rates length");
    let u = wm.base.drive.wheel_to_platform() * Vector2::new(wheel_rates[0], wheel_rates[1]);
    let mut v_r = DVector::zeros(wm.nr());
    v_r[0] = u[0];
    v_r[1] = u[1];
    for (k, r) in arm_rates.iter().enumerate() {
        v_r[2 + k] = *r;
    }
    let mut n = DMatrix::zeros(wm.nv(), wm.nr());
    admissible_velocity_basis(wm, q, &mut n);
    n.mul_to(&v_r, out);
}

/// Velocity (world axes, m/s) of a point fixed on the platform at base-frame offset
/// `offset = [x, y]`, from wheel rates (chapter 5.20–5.25; `offset = [0, 0]` gives the
/// base origin, `[−d, 0]` the axle midpoint, `[L, 0]` an arm base L ahead).
pub fn platform_point_velocity(
    drive: &DiffDrive,
    theta: f64,
    offset: [f64; 2],
    wheel_rates: [f64; 2],
) -> Vector2<f64> {
    let qd = drive.wheel_basis(theta) * Vector2::new(wheel_rates[0], wheel_rates[1]);
    let (s, c) = theta.sin_cos();
    let r = Vector2::new(c * offset[0] - s * offset[1], s * offset[0] + c * offset[1]);
    Vector2::new(qd[0] - qd[2] * r[1], qd[1] + qd[2] * r[0])
}

/// Velocity of the whole robot's centre of mass (world axes, m/s) at `(q, q̇)`, from the
/// centroidal momentum: `ċ = h_lin / m`.
pub fn center_of_mass_velocity(
    wm: &WheeledModel,
    wd: &mut WheeledData,
    q: &DVector<f64>,
    qdot: &DVector<f64>,
) -> Vector3<f64> {
    let h = centroidal_momentum(&wm.model, &mut wd.data, q, qdot);
    h.linear / wm.model.total_mass()
}

/// Velocity `[ṗ; ω]` (world axes) of a frame (e.g. the arm base or the end effector) at
/// `(q, q̇)`: `J(q) q̇` with the frame Jacobian, so with `q̇ = N_C v_r` this is the
/// whole-body Jacobian `J N_C` applied to the reduced velocity.
pub fn frame_velocity_world(
    wm: &WheeledModel,
    wd: &mut WheeledData,
    q: &DVector<f64>,
    qdot: &DVector<f64>,
    frame: FrameIndex,
) -> nalgebra::Vector6<f64> {
    frame_jacobian(
        &wm.model,
        &mut wd.data,
        q,
        frame,
        ReferenceFrame::LocalWorldAligned,
        &mut wd.jacobian,
    );
    &wd.jacobian * qdot
}

/// Solves `Mr x = b` with the Cholesky factorisation (used by tests and tools that need
/// Mr⁻¹ explicitly). Reports [`Error::Singular`] if Mr is not positive definite.
pub fn solve_reduced_mass(mr: &DMatrix<f64>, b: &mut DVector<f64>) -> Result<()> {
    let mut l = mr.clone();
    cholesky_in_place(&mut l, PIVOT_TOL).map_err(|p| Error::Singular {
        what: "reduced mass matrix Mr".into(),
        detail: Some(format!("pivot {p}")),
    })?;
    cholesky_solve(&l, b);
    Ok(())
}

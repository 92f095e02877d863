//! Reduced forward dynamics of a wheeled model ([`reduced_forward_dynamics`]): the
//! articulated-body algorithm with the no-side-slip constraint applied at the root, or the
//! joint-space route when wheel joints are tracked.
//!
//! When the wheels are massless traction actuators (no tracked wheel joints), the only
//! constraint `C = [C_b, 0]` acts on the planar root's three velocities. The ABA's
//! backward pass condenses the whole arm onto the root: with the root's articulated
//! inertia `IA`, bias `pA`, motion subspace `S_b` and `U = IA S_b`, the root equation is
//!
//! ```text
//! D q̈_b = τ_b − S_bᵀ pA − Uᵀ a₀ − C_bᵀ λ,     D = S_bᵀ IA S_b  (3×3)
//! ```
//!
//! (`a₀` the root's acceleration with `q̈_b = 0`: gravity and velocity-product terms),
//! which is the Schur complement of the arm in `H q̈ + h + G = Q − Cᵀλ` — exact, because
//! λ enters only the root rows. With `q̈_b = N_b v̇_b + Ṅ_b v_b` the constraint force
//! drops out of the 2×2 system `N_bᵀ D N_b v̇_b = N_bᵀ (rhs − D Ṅ_b v_b)`; the forward pass
//! then gives the arm accelerations as in ABA. The cost is one ABA plus a 2×2 solve.
//!
//! Reference for the passes: R. Featherstone, *Rigid Body Dynamics Algorithms*,
//! Springer 2008, §7.3.

use nalgebra::{DVector, Matrix3, Matrix3x2, Vector2, Vector3};

use crate::error::{Error, Result};
use crate::mobile::wheeled::{
    WheeledData, WheeledModel, admissible_velocity_basis, check_state, generalized_force,
    reduced_forward_dynamics_crba,
};
use crate::multibody::{Data, Model};
use crate::spatial::{Force, Motion};

/// Reduced forward dynamics v̇_r (nr) of `Mr v̇ + Cr v + Gr = Qr` for wheel and joint
/// torques `u`, stored in `wd.reduced.vdot` (q̈ in `wd.reduced.qddot`, q̇ in `wd.qdot`).
///
/// Without tracked wheel joints the constraint acts on the root only and the
/// root-constrained articulated-body algorithm is used (one ABA and a 2×2 solve; see
/// the module docs); with tracked wheels,
/// [`reduced_forward_dynamics_crba`]. Only v̇, q̈ and q̇ are guaranteed afterwards; call
/// [`reduced_dynamics`](crate::mobile::wheeled::reduced_dynamics) for Mr, Cr, Gr, Qr. Reports [`Error::Singular`] if Mr is not
/// positive definite. Does not allocate.
///
/// # Panics
/// On wrong vector lengths.
#[doc(alias = "forward_dynamics")]
pub fn reduced_forward_dynamics<'d>(
    wm: &WheeledModel,
    wd: &'d mut WheeledData,
    q: &DVector<f64>,
    v_r: &DVector<f64>,
    u: &[f64],
) -> Result<&'d DVector<f64>> {
    check_state(wm, q, v_r, u);
    if wm.wheel_dofs().is_none() {
        root_constrained_aba(wm, wd, q, v_r, u)?;
        Ok(&wd.reduced.vdot)
    } else {
        reduced_forward_dynamics_crba(wm, wd, q, v_r, u)
    }
}

/// Reduced forward dynamics for a wheeled model without tracked wheel joints, by the
/// root-constrained ABA (see the module docs). Fills `wd.reduced.vdot`,
/// `wd.reduced.qddot`, `wd.qdot`, `wd.force`. Reports [`Error::Singular`] if a joint's
/// articulated inertia or the platform's 2×2 reduced inertia is not positive.
fn root_constrained_aba(
    wm: &WheeledModel,
    wd: &mut WheeledData,
    q: &DVector<f64>,
    v_r: &DVector<f64>,
    u: &[f64],
) -> Result<()> {
    debug_assert!(wm.wheel_dofs().is_none());
    let model = &wm.model;
    admissible_velocity_basis(wm, q, &mut wd.basis);
    wd.basis.mul_to(v_r, &mut wd.qdot);
    generalized_force(wm, q, u, &mut wd.force);
    let data = &mut wd.data;
    let (qs, vs, ts) = (q.as_slice(), wd.qdot.as_slice(), wd.force.as_slice());
    // Forward pass: velocities, bias accelerations, rigid-body inertias and biases.
    crate::dynamics::aba_forward_pass(model, data, qs, vs);
    arm_backward_pass(model, data, ts)?;
    let (dmat, rhs, acc0) = root_articulated_equation(model, data, ts);
    let vb = Vector2::new(v_r[0], v_r[1]);
    let (vdb, qddb) = platform_acceleration(wm, q[2], wd.qdot[2], vb, &dmat, &rhs)?;
    let mut acc = acc0;
    for k in 0..3 {
        data.ddq[k] = qddb[k];
        acc += data.s[k] * qddb[k];
    }
    data.a[ROOT] = acc;
    // Forward pass over the arm.
    for i in ROOT + 1..model.njoints {
        crate::dynamics::accelerate_one_dof(model, data, i);
    }
    let red = &mut wd.reduced;
    red.vdot[0] = vdb[0];
    red.vdot[1] = vdb[1];
    for (k, &i) in wm.arm_dofs().iter().enumerate() {
        red.vdot[2 + k] = data.ddq[i];
    }
    red.qddot.copy_from(&data.ddq);
    Ok(())
}

/// The planar root joint's index.
const ROOT: usize = 1;

/// Backward pass over the arm (all one-dof joints), condensing it onto the root; an error
/// names the first joint that moves no inertia.
#[inline(always)]
fn arm_backward_pass(model: &Model, data: &mut Data, ts: &[f64]) -> Result<()> {
    for i in (ROOT + 1..model.njoints).rev() {
        let iv = model.idx_v[i];
        let uvec = data.ia[i].mul_motion(&data.s[iv]);
        let d = data.s[iv].dot(&uvec);
        if !d.is_finite() || d <= 0.0 {
            return Err(Error::Singular {
                what: "reduced mass matrix Mr (articulated inertia)".into(),
                detail: Some(format!(
                    "joint '{}' moves no inertia (D = {d:e})",
                    model.names[i]
                )),
            });
        }
        crate::dynamics::condense_one_dof(model, data, ts, i, uvec, d);
    }
    Ok(())
}

/// The root's equation `D q̈_b = rhs − C_bᵀ λ` after the arm is condensed onto it:
/// `D = S_bᵀ IA S_b`, `rhs = τ_b − S_bᵀ pA − Uᵀ a₀`, and `a₀` (the root's acceleration
/// with `q̈_b = 0`). Sets `data.a[0]` to −gravity.
#[inline(always)]
fn root_articulated_equation(
    model: &Model,
    data: &mut Data,
    ts: &[f64],
) -> (Matrix3<f64>, Vector3<f64>, Motion) {
    let ia = data.ia[ROOT];
    let pa = data.pa[ROOT];
    let mut uroot = [Force::zero(); 3];
    let mut dmat = Matrix3::zeros();
    for k in 0..3 {
        uroot[k] = ia.mul_motion(&data.s[k]);
    }
    for k in 0..3 {
        for l in 0..3 {
            dmat[(k, l)] = data.s[k].dot(&uroot[l]);
        }
    }
    data.a[0] = Motion::new(-model.gravity, Vector3::zeros());
    let acc0 = data.parent_from_joint[ROOT].inverse_act_motion(&data.a[0]) + data.c[ROOT];
    let mut rhs = Vector3::zeros();
    for k in 0..3 {
        rhs[k] = ts[k] - data.s[k].dot(&pa) - uroot[k].dot(&acc0);
    }
    (dmat, rhs, acc0)
}

/// The platform's reduced accelerations `v̇_b` (2) and root accelerations
/// `q̈_b = N_b v̇_b + Ṅ_b v_b` (3) from the 2×2 system `N_bᵀ D N_b v̇_b = N_bᵀ (rhs − D Ṅ_b
/// v_b)` at heading `theta` and heading rate `theta_dot`; [`Error::Singular`] if that
/// system is not positive definite.
#[inline(always)]
fn platform_acceleration(
    wm: &WheeledModel,
    theta: f64,
    theta_dot: f64,
    vb: Vector2<f64>,
    dmat: &Matrix3<f64>,
    rhs: &Vector3<f64>,
) -> Result<(Vector2<f64>, Vector3<f64>)> {
    let dd = &wm.base.drive;
    let nb: Matrix3x2<f64> = dd.basis(theta);
    let ndv = dd.basis_dot(theta, theta_dot) * vb;
    let m2 = nb.transpose() * dmat * nb;
    let r2 = nb.transpose() * (rhs - dmat * ndv);
    let det = m2[(0, 0)] * m2[(1, 1)] - m2[(0, 1)] * m2[(1, 0)];
    if !det.is_finite()
        || m2[(0, 0)].is_nan()
        || m2[(0, 0)] <= 0.0
        || det <= 1e-14 * m2.norm_squared()
    {
        return Err(Error::Singular {
            what: "reduced mass matrix Mr (platform block)".into(),
            detail: Some(format!("det = {det:e}")),
        });
    }
    let vdb = Vector2::new(
        (m2[(1, 1)] * r2[0] - m2[(0, 1)] * r2[1]) / det,
        (m2[(0, 0)] * r2[1] - m2[(1, 0)] * r2[0]) / det,
    );
    Ok((vdb, nb * vdb + ndv))
}

//! Analytical derivatives of inverse dynamics (RNEA) and forward dynamics (ABA) with
//! respect to q, v and a (or τ), after Carpentier and Mansard (RSS 2018): what Pinocchio's
//! `computeRNEADerivatives` and `computeABADerivatives` compute.
//!
//! Derivatives with respect to q are taken along the tangent perturbation of the
//! configuration, `q ⊕ δq` with [`crate::kinematics::integrate`], so every matrix is
//! nv × nv, for every root and joint kind.
//!
//! # The algorithm
//!
//! Everything is expressed in the world frame. Joint `j`'s motion-subspace columns are
//! `J_j` (its columns of the world Jacobian), body velocities and accelerations (with the
//! fictitious −g) `v_i`, `a_i`, body inertias `I_i`, and `F_i` is the force the subtree of
//! `i` transmits through joint `i`, so `τ_i = J_iᵀ F_i`. Perturbing `q_j` moves the subtree
//! of `j` rigidly, which rotates every world quantity attached to it (`δm = J_j × m` for a
//! motion, `J_j ×* f` for a force) and, on top of that, changes it "intrinsically":
//! `δv_k = v_λ(j) × J_j` and `δa_k = a_λ(j) × J_j + (v_λ(j) × J_j) × (v_k − v_λ(j))` for
//! every body `k` below `j` (λ the parent), and inertias not at all. The rotation cancels in
//! `J_iᵀ F_i` whenever it moves both, i.e. for `j` an ancestor of `i` or `i` itself. With
//! `w_j = v_λ × J_j`, `u_j = a_λ × J_j + v_λ × w_j`, the composite inertia `Ic_i` and the
//! composite of `B_k = v_k×* I_k − I_k v_k× + (· ×* I_k v_k)` (the derivative of
//! `f_k = I_k a_k + v_k ×* I_k v_k` through the velocity that is not in `I_k δa_k`):
//!
//! * `j` ancestor of `i` or `i`: `∂τ_i/∂q_j = (Ic_i J_i)ᵀ u_j + (Bc_iᵀ J_i)ᵀ w_j`,
//!   `∂τ_i/∂v_j = (Ic_i J_i)ᵀ (v_λ + v_j) × J_j + (Bc_iᵀ J_i)ᵀ J_j`, `H_ij = (Ic_i J_i)ᵀ J_j`;
//! * `j` below `i`: `J_iᵀ` of `J_j ×* F_j + Ic_j u_j + Bc_j w_j`, of
//!   `Ic_j (v_λ + v_j) × J_j + Bc_j J_j` and of `Ic_j J_j`.
//!
//! One forward pass computes the per-dof 6-vectors; a backward pass accumulates the
//! composites and writes τ, H and ∂τ/∂v, each row of a joint against its ancestors'
//! columns and each column against its ancestors' rows, and a second one writes ∂τ/∂q
//! the same way from the composites (Pinocchio's one forward and one backward pass with
//! 6 × nv column blocks).
//!
//! The pass runs with a constant joint-frame motion subspace for every joint, which is
//! Pinocchio's planar joint (base-frame velocity); moma's planar root (world-axes velocity)
//! is brought there and back by the chain rule of
//! [`PinocchioLayout::rnea_derivatives_from_pinocchio`]. Continuous joints have the same
//! tangent space in both layouts.
//!
//! Forward dynamics follows from the implicit function theorem: with q̈ = ABA(q, v, τ),
//! `∂q̈/∂x = −H⁻¹ ∂τ/∂x` evaluated at a = q̈, and `∂q̈/∂τ = H⁻¹`. H is factorised as
//! `Lᵀ D L` with the tree's sparsity (Featherstone's LTDL, `Σ depth²` operations); H⁻¹ is
//! solved from it row by row, its upper triangle only, along the tree's ancestor chains
//! (`2 Σ depth` row updates), and `−H⁻¹ ∂τ/∂q`, `−H⁻¹ ∂τ/∂v` are dense products
//! (`dense_product`, Pinocchio's route: about twice the multiply–adds of solving those two
//! right-hand sides through the tree too, but register-blocked, so each load feeds many).
//!
//! q̈ itself comes from the same passes, with no separate ABA: of everything they
//! compute, only the accelerations, `u`, the forces, τ and ∂τ/∂q depend on `a`, and
//! linearly. So they run at a = 0, which gives H and the bias `h = RNEA(q, v, 0)`;
//! `q̈ = H⁻¹ (τ − h)` by the same factorisation; then `δa_i = δa_λ + J_i q̈_i` is added to
//! the accelerations, `δa_λ × J` to `u` and the subtree sums of `I_k δa_k` to the forces,
//! and ∂τ/∂q is written at a = q̈.

use super::dense_product::neg_mul;
use super::motion_pass::{MotionTerms, cross_force, cross_motion, join, split};
use super::tree_ltdl::{
    Rhs, chain_starts, dof_parents, ltdl_in_place, ltdl_solve_rows, subtree_ends,
};
use crate::error::{Error, Result};
use crate::io::pinocchio_layout::PinocchioLayout;
use crate::kinematics::assert_nv;
use crate::multibody::{Data, Model};
use crate::spatial::{Inertia, skew};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3, Vector6};

/// The workspace and the results of [`rnea_derivatives`] and [`aba_derivatives`], sized
/// once for a model by [`DerivativeData::new`]; neither function allocates after that.
///
/// All matrices are nv × nv, entry `(i, j)` = ∂out_i/∂in_j.
#[derive(Clone, Debug)]
pub struct DerivativeData {
    /// ∂τ/∂q of the last [`rnea_derivatives`] (or of RNEA at a = q̈ after
    /// [`aba_derivatives`]).
    pub drnea_dq: DMatrix<f64>,
    /// ∂τ/∂v.
    pub drnea_dv: DMatrix<f64>,
    /// ∂τ/∂a = H(q), the joint-space inertia matrix (full symmetric).
    pub drnea_da: DMatrix<f64>,
    /// τ = RNEA(q, v, a) at the point of the last [`rnea_derivatives`].
    pub tau: DVector<f64>,
    /// ∂q̈/∂q of the last [`aba_derivatives`].
    pub daba_dq: DMatrix<f64>,
    /// ∂q̈/∂v.
    pub daba_dv: DMatrix<f64>,
    /// ∂q̈/∂τ = H(q)⁻¹ (full symmetric).
    pub daba_dtau: DMatrix<f64>,
    /// q̈ = ABA(q, v, τ) of the last [`aba_derivatives`].
    pub ddq: DVector<f64>,
    /// Joint placements and ABA.
    data: Data,
    /// The planar root's chain rule (identity without one).
    layout: PinocchioLayout,
    /// Velocity and acceleration in the pass's convention (planar: base frame).
    v_local: DVector<f64>,
    a_local: DVector<f64>,
    /// The kinematic pass (world frame, root acceleration −g).
    motion: MotionTerms,
    /// Per joint: composite inertia, composite B, subtree force (world frame).
    ic: Vec<Inertia>,
    bc: Vec<VelocityVariation>,
    force: Vec<Vector6<f64>>,
    /// Per joint: the body's own inertia, and the acceleration and force added by
    /// `add_acceleration` (world frame).
    inertia: Vec<Inertia>,
    dacc: Vec<Vector6<f64>>,
    dforce: Vec<Vector6<f64>>,
    /// Per dof: `Ic J` and `Bcᵀ J` with the composites of its joint.
    y1: Vec<Vector6<f64>>,
    y2: Vec<Vector6<f64>>,
    /// Each velocity coordinate's parent in the tree, and one past the last coordinate
    /// of its subtree (see `tree_ltdl`).
    dof_parent: Vec<usize>,
    subtree_end: Vec<usize>,
    /// Per coordinate, the first of the run of consecutive coordinates that ends at it in
    /// its ancestor chain (see `tree_ltdl::chain_starts`).
    chain_start: Vec<usize>,
    /// The tree-sparse `Lᵀ D L` factor of H, H⁻¹ by rows while it is solved (nv blocks of
    /// nv), and one column of scratch.
    fact: DMatrix<f64>,
    rows: DVector<f64>,
    column: DVector<f64>,
}

impl DerivativeData {
    /// Allocates every buffer for `model`.
    #[must_use]
    pub fn new(model: &Model) -> Self {
        let (n, nv) = (model.njoints, model.nv);
        let m = || DMatrix::zeros(nv, nv);
        let dof_parent = dof_parents(model);
        Self {
            drnea_dq: m(),
            drnea_dv: m(),
            drnea_da: m(),
            tau: DVector::zeros(nv),
            daba_dq: m(),
            daba_dv: m(),
            daba_dtau: m(),
            ddq: DVector::zeros(nv),
            data: Data::new(model),
            layout: PinocchioLayout::new(model),
            v_local: DVector::zeros(nv),
            a_local: DVector::zeros(nv),
            motion: MotionTerms::new(model),
            ic: vec![Inertia::zero(); n],
            bc: vec![VelocityVariation::zero(); n],
            force: vec![Vector6::zeros(); n],
            inertia: vec![Inertia::zero(); n],
            dacc: vec![Vector6::zeros(); n],
            dforce: vec![Vector6::zeros(); n],
            y1: vec![Vector6::zeros(); nv],
            y2: vec![Vector6::zeros(); nv],
            subtree_end: subtree_ends(&dof_parent),
            chain_start: chain_starts(&dof_parent),
            dof_parent,
            fact: m(),
            rows: DVector::zeros(nv * nv),
            column: DVector::zeros(nv),
        }
    }

    /// True if this workspace was sized for `model`.
    #[must_use]
    pub fn fits(&self, model: &Model) -> bool {
        self.data.fits(model) && self.motion.jac.len() == model.nv
    }
}

/// Derivatives of inverse dynamics τ = RNEA(q, v, a): writes ∂τ/∂q, ∂τ/∂v and
/// ∂τ/∂a = H(q) into `dd.drnea_dq`, `dd.drnea_dv`, `dd.drnea_da`, and τ into `dd.tau`.
///
/// In moma's layout (planar root: world-axes velocity; see
/// [`crate::io::pinocchio_layout`] for Pinocchio's, and
/// [`PinocchioLayout::rnea_derivatives_to_pinocchio`] to convert).
///
/// # Panics
/// If q, v, a have the wrong length or `dd` was not made for `model`.
///
/// # References
/// J. Carpentier, N. Mansard, "Analytical Derivatives of Rigid Body Dynamics Algorithms",
/// Robotics: Science and Systems, 2018, doi:10.15607/RSS.2018.XIV.038.
pub fn rnea_derivatives(
    model: &Model,
    dd: &mut DerivativeData,
    q: &DVector<f64>,
    v: &DVector<f64>,
    a: &DVector<f64>,
) {
    assert!(dd.fits(model), "DerivativeData was not made for this model");
    assert_eq!(
        q.len(),
        model.nq,
        "q has {} entries, the model nq = {}",
        q.len(),
        model.nq
    );
    assert_nv(model, v, "v");
    assert_nv(model, a, "a");
    rnea_derivatives_impl(model, dd, q.as_slice(), v.as_slice(), a.as_slice());
}

/// [`rnea_derivatives`] on checked slices.
fn rnea_derivatives_impl(
    model: &Model,
    dd: &mut DerivativeData,
    qs: &[f64],
    vs: &[f64],
    as_: &[f64],
) {
    dd.layout.v_to_pinocchio(qs, vs, dd.v_local.as_mut_slice());
    dd.layout
        .a_to_pinocchio(qs, vs, as_, dd.a_local.as_mut_slice());
    forward_pass(model, dd, qs);
    composite_pass(model, dd);
    dq_pass(model, dd);
    // τ computed in the pass's convention → moma's, then the matrices
    dd.column.copy_from(&dd.tau);
    dd.layout
        .tau_from_pinocchio(qs, dd.column.as_slice(), dd.tau.as_mut_slice());
    dd.layout.rnea_derivatives_from_pinocchio(
        qs,
        vs,
        as_,
        dd.tau.as_slice(),
        &mut dd.drnea_dq,
        &mut dd.drnea_dv,
        &mut dd.drnea_da,
    );
}

/// Derivatives of forward dynamics q̈ = ABA(q, v, τ): writes ∂q̈/∂q, ∂q̈/∂v and
/// ∂q̈/∂τ = H(q)⁻¹ into `dd.daba_dq`, `dd.daba_dv`, `dd.daba_dtau`, and q̈ into `dd.ddq`
/// (in moma's layout). `dd.drnea_*` are left holding the RNEA derivatives at a = q̈, and
/// `dd.tau` the given τ.
///
/// # Errors
/// [`Error::Singular`] when H(q) is not positive definite (e.g. a joint that moves only
/// massless links); the outputs are then NaN.
///
/// # Panics
/// If q, v, τ have the wrong length or `dd` was not made for `model`.
pub fn aba_derivatives(
    model: &Model,
    dd: &mut DerivativeData,
    q: &DVector<f64>,
    v: &DVector<f64>,
    tau: &DVector<f64>,
) -> Result<()> {
    assert!(dd.fits(model), "DerivativeData was not made for this model");
    assert_eq!(
        q.len(),
        model.nq,
        "q has {} entries, the model nq = {}",
        q.len(),
        model.nq
    );
    assert_nv(model, v, "v");
    assert_nv(model, tau, "tau");
    let (qs, vs, ts) = (q.as_slice(), v.as_slice(), tau.as_slice());
    // the passes at a = 0 give H, ∂τ/∂v and h = RNEA(q, v, 0) (pass convention)
    dd.layout.v_to_pinocchio(qs, vs, dd.v_local.as_mut_slice());
    dd.a_local.as_mut_slice().fill(0.0);
    forward_pass(model, dd, qs);
    composite_pass(model, dd);
    // q̈ = H⁻¹ (τ − h) in the pass's convention, into a_local
    dd.fact
        .as_mut_slice()
        .copy_from_slice(dd.drnea_da.as_slice());
    if let Err(k) = ltdl_in_place(&mut dd.fact, &dd.dof_parent, &dd.chain_start) {
        return Err(singular(dd, k));
    }
    dd.layout
        .tau_to_pinocchio(qs, ts, dd.a_local.as_mut_slice());
    dd.a_local -= &dd.tau;
    ltdl_solve_rows(
        &dd.fact,
        &dd.dof_parent,
        dd.a_local.as_mut_slice(),
        1,
        Rhs::Dense,
    );
    dd.layout
        .a_from_pinocchio(qs, vs, dd.a_local.as_slice(), dd.ddq.as_mut_slice());
    // everything that depends on the acceleration, at a = q̈: then ∂τ/∂q
    add_acceleration(model, dd);
    dq_pass(model, dd);
    dd.tau.copy_from(tau);
    dd.layout.rnea_derivatives_from_pinocchio(
        qs,
        vs,
        dd.ddq.as_slice(),
        ts,
        &mut dd.drnea_dq,
        &mut dd.drnea_dv,
        &mut dd.drnea_da,
    );
    // H⁻¹ by rows (its upper triangle solved, row r columns r..), then ∂q̈/∂q = −H⁻¹ ∂τ/∂q
    // and ∂q̈/∂v = −H⁻¹ ∂τ/∂v as dense products. With a planar root moma's H is
    // `Tᵀ H_P T` (H_P the pass's, already factorised), so `H⁻¹ = Tᵀ H_P⁻¹ T`: the base's
    // (x, y) rows and columns of H_P⁻¹ turned, instead of a second factorisation
    let nv = model.nv;
    let rows = dd.rows.as_mut_slice();
    for r in 0..nv {
        let row = &mut rows[r * nv..(r + 1) * nv];
        row.fill(0.0);
        row[r] = 1.0;
    }
    ltdl_solve_rows(
        &dd.fact,
        &dd.dof_parent,
        rows,
        nv,
        Rhs::Inverse {
            end: &dd.subtree_end,
        },
    );
    // exactly symmetric: the rows transposed give the upper triangle, then each row r's
    // columns r.. are the lower triangle's column r
    let ot = dd.daba_dtau.as_mut_slice();
    transpose(rows, ot, nv);
    for r in 0..nv {
        ot[r * nv + r..(r + 1) * nv].copy_from_slice(&rows[r * nv + r..(r + 1) * nv]);
    }
    if let Some((c, s, iv)) = dd.layout.heading(qs) {
        // R H_P⁻¹ Rᵀ on its two rows (column-major: entry (r, col) at col nv + r) and
        // two columns
        for col in ot.chunks_exact_mut(nv) {
            let (x, y) = col.split_at_mut(iv + 1);
            rotate_pairs(&mut x[iv..], &mut y[..1], c, s);
        }
        let (x, y) = ot.split_at_mut((iv + 1) * nv);
        rotate_pairs(&mut x[iv * nv..], &mut y[..nv], c, s);
    }
    let ot = dd.daba_dtau.as_slice();
    neg_mul(ot, dd.drnea_dq.as_slice(), dd.daba_dq.as_mut_slice(), nv);
    neg_mul(ot, dd.drnea_dv.as_slice(), dd.daba_dv.as_mut_slice(), nv);
    Ok(())
}

/// `(x_i, y_i) ← (c x_i − s y_i, s x_i + c y_i)` for each `i`: the rotation `R(θ)`, with
/// `(c, s) = (cos θ, sin θ)`, applied to two equally long runs of coordinates.
fn rotate_pairs(x: &mut [f64], y: &mut [f64], c: f64, s: f64) {
    for (a, b) in x.iter_mut().zip(y.iter_mut()) {
        let (x0, y0) = (*a, *b);
        *a = c * x0 - s * y0;
        *b = s * x0 + c * y0;
    }
}

/// `dst[r n + c] = src[c n + r]` for `r, c < n`: the transpose of an `n × n` matrix
/// (column-major into rows, or back). Done by tiles of 8 × 8, each read as 8 contiguous
/// runs and written as 8, instead of one strided access per entry.
fn transpose(src: &[f64], dst: &mut [f64], n: usize) {
    const T: usize = 8;
    let tiled = n / T * T;
    for c0 in (0..tiled).step_by(T) {
        for r0 in (0..tiled).step_by(T) {
            let mut tile = [[0.0; T]; T];
            for (j, t) in tile.iter_mut().enumerate() {
                let at = (c0 + j) * n + r0;
                t.copy_from_slice(&src[at..at + T]);
            }
            for i in 0..T {
                let at = (r0 + i) * n + c0;
                for (d, t) in dst[at..at + T].iter_mut().zip(&tile) {
                    *d = t[i];
                }
            }
        }
    }
    // the edges the tiles leave: rows tiled.. of every column, and columns tiled.. of the
    // tiled rows
    for c in 0..n {
        let r_from = if c < tiled { tiled } else { 0 };
        for r in r_from..n {
            dst[r * n + c] = src[c * n + r];
        }
    }
}

/// Fills the forward-dynamics outputs with NaN and names the failed pivot.
fn singular(dd: &mut DerivativeData, k: usize) -> Error {
    for m in [&mut dd.daba_dq, &mut dd.daba_dv, &mut dd.daba_dtau] {
        m.fill(f64::NAN);
    }
    dd.ddq.fill(f64::NAN);
    Error::Singular {
        what: "joint-space inertia H(q)".into(),
        detail: Some(format!(
            "the pivot of velocity coordinate {k} is not positive"
        )),
    }
}

/// The world placement, twist and acceleration of every joint, the per-dof vectors and
/// each body's inertia, B and force (the composites' starting values).
fn forward_pass(model: &Model, dd: &mut DerivativeData, qs: &[f64]) {
    let gravity = Vector6::new(
        -model.gravity.x,
        -model.gravity.y,
        -model.gravity.z,
        0.0,
        0.0,
        0.0,
    );
    for i in 1..model.njoints {
        dd.motion.step(
            model,
            &mut dd.data,
            i,
            qs,
            dd.v_local.as_slice(),
            dd.a_local.as_slice(),
            &gravity,
        );
        let omi = dd.motion.world_from_joint[i];
        let (vel, acc) = (dd.motion.vel[i], dd.motion.acc[i]);
        let inertia = omi.act_inertia(&model.inertias[i]);
        let h = inertia_mul(&inertia, &vel);
        dd.force[i] = inertia_mul(&inertia, &acc) + cross_force(&vel, &h);
        dd.bc[i] = VelocityVariation::new(&inertia, &vel, &h);
        dd.ic[i] = inertia;
        dd.inertia[i] = inertia;
    }
}

/// Accumulates the composites (inertia, B, force) from the leaves up and writes τ, H and
/// ∂τ/∂v (in the pass's convention), keeping each dof's `Ic J` and `Bcᵀ J` for
/// [`dq_pass`]. Everything here but τ is independent of the acceleration.
fn composite_pass(model: &Model, dd: &mut DerivativeData) {
    let nv = model.nv;
    // a slice's fill is a memset; the matrix's own is an element iterator
    dd.drnea_dv.as_mut_slice().fill(0.0);
    dd.drnea_da.as_mut_slice().fill(0.0);
    // column-major storage: entry (r, c) at c nv + r
    let (dv, da) = (dd.drnea_dv.as_mut_slice(), dd.drnea_da.as_mut_slice());
    for i in (1..model.njoints).rev() {
        let (ic, bc, f) = (dd.ic[i], dd.bc[i], dd.force[i]);
        let iv = model.idx_v[i];
        let p = model.parents[i].0;
        for k in iv..iv + model.nvs[i] {
            let jk = dd.motion.jac[k];
            dd.tau[k] = jk.dot(&f);
            let y1 = inertia_mul(&ic, &jk);
            let y2 = bc.tr_mul(&jk);
            dd.y1[k] = y1;
            dd.y2[k] = y2;
            // row k against the columns of i and of its ancestors; H by symmetry also
            // in column k
            let mut a = i;
            while a > 0 {
                for m in model.idx_v[a]..model.idx_v[a] + model.nvs[a] {
                    dv[m * nv + k] = y1.dot(&dd.motion.dadv[m]) + y2.dot(&dd.motion.jac[m]);
                    let h = y1.dot(&dd.motion.jac[m]);
                    da[m * nv + k] = h;
                    da[k * nv + m] = h;
                }
                a = model.parents[a].0;
            }
            // column k against the rows of the strict ancestors
            let phi_v = inertia_mul(&ic, &dd.motion.dadv[k]) + bc.mul(&jk);
            let mut a = p;
            while a > 0 {
                for r in model.idx_v[a]..model.idx_v[a] + model.nvs[a] {
                    dv[k * nv + r] = dd.motion.jac[r].dot(&phi_v);
                }
                a = model.parents[a].0;
            }
        }
        if p > 0 {
            dd.ic[p] += ic;
            dd.bc[p] += bc;
            dd.force[p] += f;
        }
    }
}

/// ∂τ/∂q from the composites of [`composite_pass`] and the acceleration terms `u` and
/// subtree forces of the current acceleration.
fn dq_pass(model: &Model, dd: &mut DerivativeData) {
    let nv = model.nv;
    let dq = dd.drnea_dq.as_mut_slice();
    dq.fill(0.0);
    for i in (1..model.njoints).rev() {
        let (ic, bc, f) = (&dd.ic[i], &dd.bc[i], &dd.force[i]);
        let iv = model.idx_v[i];
        let p = model.parents[i].0;
        for k in iv..iv + model.nvs[i] {
            let (jk, y1, y2) = (&dd.motion.jac[k], &dd.y1[k], &dd.y2[k]);
            // row k against the columns of i and of its ancestors
            let mut a = i;
            while a > 0 {
                for m in model.idx_v[a]..model.idx_v[a] + model.nvs[a] {
                    dq[m * nv + k] = y1.dot(&dd.motion.u[m]) + y2.dot(&dd.motion.w[m]);
                }
                a = model.parents[a].0;
            }
            // column k against the rows of the strict ancestors
            let phi_q =
                cross_force(jk, f) + inertia_mul(ic, &dd.motion.u[k]) + bc.mul(&dd.motion.w[k]);
            let mut a = p;
            while a > 0 {
                for r in model.idx_v[a]..model.idx_v[a] + model.nvs[a] {
                    dq[k * nv + r] = dd.motion.jac[r].dot(&phi_q);
                }
                a = model.parents[a].0;
            }
        }
    }
}

/// Adds the acceleration `dd.a_local` to a pass run at zero acceleration: everything is
/// linear in it, so each joint's acceleration grows by `δa_i = δa_λ + J_i a_i`, each
/// dof's `u` by `δa_λ × J`, and each subtree force by the subtree's `Σ I_k δa_k`.
fn add_acceleration(model: &Model, dd: &mut DerivativeData) {
    for i in 1..model.njoints {
        let p = model.parents[i].0;
        let da_parent = if p == 0 { Vector6::zeros() } else { dd.dacc[p] };
        let iv = model.idx_v[i];
        let mut da = da_parent;
        for k in iv..iv + model.nvs[i] {
            let jk = dd.motion.jac[k];
            dd.motion.u[k] += cross_motion(&da_parent, &jk);
            da += jk * dd.a_local[k];
        }
        dd.dacc[i] = da;
        dd.motion.acc[i] += da;
        dd.dforce[i] = inertia_mul(&dd.inertia[i], &da);
    }
    for i in (1..model.njoints).rev() {
        let df = dd.dforce[i];
        dd.force[i] += df;
        let p = model.parents[i].0;
        if p > 0 {
            dd.dforce[p] += df;
        }
    }
}

/// `I x` for a spatial inertia in its compact form (`[m x_l − c' × x_ω; c' × x_l + Ī x_ω]`
/// with `c'` the first moment and `Ī` the rotational inertia about the origin).
#[inline]
fn inertia_mul(inertia: &Inertia, x: &Vector6<f64>) -> Vector6<f64> {
    let ((xl, xa), c) = (split(x), inertia.first_moment());
    join(
        xl * inertia.mass() - c.cross(&xa),
        inertia.inertia_about_origin() * xa + c.cross(&xl),
    )
}

/// `B = v×* I − I v× + (x ↦ x ×* h)` with `h = I v`: the derivative of
/// `I a + v ×* I v` through the velocity, beside `I δa`.
///
/// With `I = [m 1, −c'×; c'×, Ī]` and `Y = I (v×)`, `B = −(Y + Yᵀ) − [0, h_l×; h_l×, h_ω×]`;
/// the skew identities `a× b× = b aᵀ − (a·b) 1` and `a bᵀ − b aᵀ = (b × a)×` reduce
/// `Y + Yᵀ` to `[0, k×; −k×, S]` with `k = m v_l − c' × ω`, which is `h_l`, and
/// `S = v_l c'ᵀ + c' v_lᵀ − 2 (c'·v_l) 1 + Ī ω× + (Ī ω×)ᵀ`. So the upper-left and
/// lower-left blocks of B vanish and it is `[0, −2 h_l×; 0, R]`, `R = −S − h_ω×`: two
/// 3-blocks, summed as such over a subtree.
#[derive(Clone, Copy, Debug)]
struct VelocityVariation {
    /// `2 h_l`: the upper-right block is `−(2 h_l)×`.
    hl2: Vector3<f64>,
    /// The lower-right block R.
    r: Matrix3<f64>,
}

impl VelocityVariation {
    fn zero() -> Self {
        Self {
            hl2: Vector3::zeros(),
            r: Matrix3::zeros(),
        }
    }

    #[inline]
    fn new(inertia: &Inertia, v: &Vector6<f64>, h: &Vector6<f64>) -> Self {
        let ((vl, va), (hl, ha)) = (split(v), split(h));
        let c = inertia.first_moment();
        let p = inertia.inertia_about_origin() * skew(&va);
        let cv = c * vl.transpose();
        let mut r = -(cv + cv.transpose() + p + p.transpose()) - skew(&ha);
        let d = 2.0 * c.dot(&vl);
        r[(0, 0)] += d;
        r[(1, 1)] += d;
        r[(2, 2)] += d;
        Self { hl2: hl * 2.0, r }
    }

    /// `B x = [−2 h_l × x_ω; R x_ω]`.
    #[inline]
    fn mul(&self, x: &Vector6<f64>) -> Vector6<f64> {
        let xa = Vector3::new(x[3], x[4], x[5]);
        join(-self.hl2.cross(&xa), self.r * xa)
    }

    /// `Bᵀ x = [0; 2 h_l × x_l + Rᵀ x_ω]`.
    #[inline]
    fn tr_mul(&self, x: &Vector6<f64>) -> Vector6<f64> {
        let (xl, xa) = split(x);
        join(Vector3::zeros(), self.hl2.cross(&xl) + self.r.tr_mul(&xa))
    }
}

impl std::ops::AddAssign for VelocityVariation {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        self.hl2 += o.hl2;
        self.r += o.r;
    }
}

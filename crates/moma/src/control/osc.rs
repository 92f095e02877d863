//! Khatib's operational-space control (1987) with a dynamically consistent null space.
//!
//! For joint-space dynamics `H v̇ + h = τ` (`h = C(q, v) v + g(q)`, the nonlinear effects)
//! and a task `ẋ = J v` (m rows of the frame's `[ṗ; ω]` in world axes, the
//! LOCAL_WORLD_ALIGNED Jacobian):
//!
//! ```text
//! Λ  = (J H⁻¹ Jᵀ)⁻¹                    task inertia (m × m)
//! J̄  = H⁻¹ Jᵀ Λ                        dynamically consistent inverse (n × m)
//! N  = I − J̄ J                         null-space projector; null torque Nᵀ τ₀
//! F  = Λ (a_des − J̇v) + Λ J H⁻¹ h       task force
//! τ  = Jᵀ F + Nᵀ τ₀
//! ```
//!
//! so that the closed loop has `ẍ = a_des` and `J H⁻¹ Nᵀ τ₀ = 0` for every τ₀ (the posture
//! torque does not disturb the task). [`osc_fixed_base`] evaluates it for a fixed-base
//! [`Model`]; [`osc_reduced`] for an arm on a non-holonomic platform through the reduced
//! model (task Jacobian `J N_C`, inertia `N_Cᵀ H N_C`, bias `N_Cᵀ(h + H Ṅ_C v_r)`, task
//! bias `J̇q̇ + J Ṅ_C v_r`), whose torque is the reduced generalised force `N_Cᵀ Q`.
//!
//! **Singularity guard.** [`task_conditioning`] is σ_min/σ_max of the task Jacobian; the
//! command line refuses states where it is below [`MIN_TASK_CONDITIONING`] = 1e-6 (there
//! Λ has a condition number above about 10¹² times that of H, so F and τ carry no
//! correct digit at double precision). The update itself only fails when a Cholesky
//! factorisation (of H or of Λ⁻¹) meets a non-positive pivot.
//!
//! The update allocates nothing: every buffer lives in [`OscData`].

use crate::dynamics::{crba, nonlinear_effects};
use crate::error::{Error, Result};
use crate::io::pinocchio_layout::PinocchioLayout;
use crate::kinematics::{ReferenceFrame, frame_acceleration_bias, frame_jacobian_from_kinematics};
use crate::linalg::{cholesky_in_place, cholesky_solve_columns};
use crate::mobile::{
    WheeledData, WheeledModel, admissible_velocity_basis, admissible_velocity_basis_dot,
};
use crate::multibody::{Data, FrameIndex, Model};
use nalgebra::{DMatrix, DVector, Matrix6xX};

/// Smallest σ_min/σ_max of the task Jacobian the command line accepts.
pub const MIN_TASK_CONDITIONING: f64 = 1e-6;

/// Workspace and results of one operational-space update (n joints, m task rows).
#[derive(Clone, Debug)]
pub struct OscData {
    /// Task rows (indices into `[vx, vy, vz, ωx, ωy, ωz]`).
    pub rows: Vec<usize>,
    /// Task Jacobian J (m × n) of the selected rows.
    pub jacobian: DMatrix<f64>,
    /// J̇v (m) of the selected rows.
    pub acceleration_bias: DVector<f64>,
    /// Λ (m × m).
    pub task_inertia: DMatrix<f64>,
    /// J̄ = H⁻¹ Jᵀ Λ (n × m).
    pub dynamically_consistent_inverse: DMatrix<f64>,
    /// N = I − J̄ J (n × n).
    pub nullspace_projector: DMatrix<f64>,
    /// F (m).
    pub task_force: DVector<f64>,
    /// τ = Jᵀ F + Nᵀ τ₀ (n).
    pub torque: DVector<f64>,
    /// Cholesky factor L of H (lower triangle, n × n).
    chol_h: DMatrix<f64>,
    /// H⁻¹ Jᵀ (n × m).
    hinv_jt: DMatrix<f64>,
    /// Cholesky factor of Λ⁻¹ (m × m).
    chol_l: DMatrix<f64>,
    jac6: Matrix6xX<f64>,
    tmp_m: DVector<f64>,
    tmp_n: DVector<f64>,
    tmp_n2: DVector<f64>,
}

impl OscData {
    /// Buffers for `n` joints and the given task rows.
    ///
    /// # Panics
    /// If `rows` is empty, longer than 6, or holds an index ≥ 6.
    #[must_use]
    pub fn new(n: usize, rows: &[usize]) -> Self {
        assert!(
            !rows.is_empty() && rows.len() <= 6 && rows.iter().all(|&r| r < 6),
            "task rows must be 1..=6 indices below 6"
        );
        let m = rows.len();
        Self {
            rows: rows.to_vec(),
            jacobian: DMatrix::zeros(m, n),
            acceleration_bias: DVector::zeros(m),
            task_inertia: DMatrix::zeros(m, m),
            dynamically_consistent_inverse: DMatrix::zeros(n, m),
            nullspace_projector: DMatrix::zeros(n, n),
            task_force: DVector::zeros(m),
            torque: DVector::zeros(n),
            chol_h: DMatrix::zeros(n, n),
            hinv_jt: DMatrix::zeros(n, m),
            chol_l: DMatrix::zeros(m, m),
            jac6: Matrix6xX::zeros(n),
            tmp_m: DVector::zeros(m),
            tmp_n: DVector::zeros(n),
            tmp_n2: DVector::zeros(n),
        }
    }

    /// Number of task rows m.
    #[must_use]
    pub fn task_dim(&self) -> usize {
        self.rows.len()
    }

    /// Number of joints n.
    #[must_use]
    pub fn dofs(&self) -> usize {
        self.torque.len()
    }

    /// `J H⁻¹ x` for an n-vector x, using the factorisation of the last update
    /// (writes an m-vector into `out`). Used to check dynamic consistency.
    ///
    /// # Panics
    /// On wrong sizes.
    pub fn task_acceleration_of(&self, x: &DVector<f64>, out: &mut DVector<f64>) {
        // J H⁻¹ x = (H⁻¹ Jᵀ)ᵀ x
        self.hinv_jt.tr_mul_to(x, out);
    }
}

/// `out = β out + α A B` (or `Aᵀ B` with `a_transposed`) by loops over contiguous
/// columns: nalgebra's dynamic `gemm`/`mul_to` allocate a packing buffer, and these
/// sizes are small.
fn matmul(
    out: &mut DMatrix<f64>,
    alpha: f64,
    a: &DMatrix<f64>,
    a_transposed: bool,
    b: &DMatrix<f64>,
    beta: f64,
) {
    let (r, k) = if a_transposed {
        (a.ncols(), a.nrows())
    } else {
        (a.nrows(), a.ncols())
    };
    assert_eq!(b.nrows(), k, "inner dimensions");
    assert_eq!(out.shape(), (r, b.ncols()), "output shape");
    let (ad, bd) = (a.as_slice(), b.as_slice());
    let od = out.as_mut_slice();
    for j in 0..b.ncols() {
        let bj = &bd[j * k..(j + 1) * k];
        let oj = &mut od[j * r..(j + 1) * r];
        if a_transposed {
            for (i, o) in oj.iter_mut().enumerate() {
                let ai = &ad[i * k..(i + 1) * k];
                let dot: f64 = ai.iter().zip(bj).map(|(x, y)| x * y).sum();
                *o = beta * *o + alpha * dot;
            }
        } else {
            if beta == 0.0 {
                oj.fill(0.0);
            } else if beta != 1.0 {
                for o in oj.iter_mut() {
                    *o *= beta;
                }
            }
            for (l, &blj) in bj.iter().enumerate() {
                let c = alpha * blj;
                if c != 0.0 {
                    for (o, x) in oj.iter_mut().zip(&ad[l * r..(l + 1) * r]) {
                        *o += c * x;
                    }
                }
            }
        }
    }
}

/// The OSC algebra from given terms: `h_mat` = H (n × n, symmetric positive definite),
/// `bias` = h (n), and `od.jacobian`, `od.acceleration_bias` already filled; `a_des` (m)
/// and `tau0` (n). Fills Λ, J̄, N, F and τ in `od`.
///
/// # Errors
/// [`Error::Singular`] when H or Λ⁻¹ is not positive definite.
///
/// # Panics
/// On wrong sizes.
pub fn osc_from_terms(
    od: &mut OscData,
    h_mat: &DMatrix<f64>,
    bias: &DVector<f64>,
    a_des: &DVector<f64>,
    tau0: &DVector<f64>,
) -> Result<()> {
    let n = od.dofs();
    let m = od.task_dim();
    assert_eq!(h_mat.shape(), (n, n), "H must be n × n");
    assert_eq!(bias.len(), n, "h must have n entries");
    assert_eq!(a_des.len(), m, "a_des must have m entries");
    assert_eq!(tau0.len(), n, "tau0 must have n entries");
    od.chol_h.copy_from(h_mat);
    if cholesky_in_place(&mut od.chol_h, 0.0).is_err() {
        return Err(Error::Singular {
            what: "joint-space inertia H".into(),
            detail: Some("not positive definite".into()),
        });
    }
    // H⁻¹ Jᵀ
    od.jacobian.transpose_to(&mut od.hinv_jt);
    cholesky_solve_columns(&od.chol_h, &mut od.hinv_jt);
    // Λ⁻¹ = J H⁻¹ Jᵀ, factorised; Λ by solving against the identity.
    matmul(&mut od.chol_l, 1.0, &od.jacobian, false, &od.hinv_jt, 0.0);
    if cholesky_in_place(&mut od.chol_l, 0.0).is_err() {
        return Err(Error::Singular {
            what: "task Jacobian".into(),
            detail: Some("J H⁻¹ Jᵀ is not positive definite (rank-deficient task)".into()),
        });
    }
    od.task_inertia.fill_with_identity();
    cholesky_solve_columns(&od.chol_l, &mut od.task_inertia);
    // symmetrise (the two triangles agree to round-off)
    for i in 0..m {
        for j in 0..i {
            let s = 0.5 * (od.task_inertia[(i, j)] + od.task_inertia[(j, i)]);
            od.task_inertia[(i, j)] = s;
            od.task_inertia[(j, i)] = s;
        }
    }
    // J̄ = H⁻¹ Jᵀ Λ
    matmul(
        &mut od.dynamically_consistent_inverse,
        1.0,
        &od.hinv_jt,
        false,
        &od.task_inertia,
        0.0,
    );
    // N = I − J̄ J
    od.nullspace_projector.fill_with_identity();
    matmul(
        &mut od.nullspace_projector,
        -1.0,
        &od.dynamically_consistent_inverse,
        false,
        &od.jacobian,
        1.0,
    );
    // F = Λ (a − J̇v + J H⁻¹ h)
    od.tmp_m.copy_from(a_des);
    od.tmp_m -= &od.acceleration_bias;
    od.tmp_m.gemv_tr(1.0, &od.hinv_jt, bias, 1.0);
    od.task_force.gemv(1.0, &od.task_inertia, &od.tmp_m, 0.0);
    // τ = Jᵀ F + Nᵀ τ₀
    od.torque.gemv_tr(1.0, &od.jacobian, &od.task_force, 0.0);
    od.torque.gemv_tr(1.0, &od.nullspace_projector, tau0, 1.0);
    Ok(())
}

/// One operational-space update for a fixed-base (or any) [`Model`] at `(q, v)` for the
/// frame `frame`: CRBA, nonlinear effects, the LOCAL_WORLD_ALIGNED frame Jacobian and
/// J̇v, then [`osc_from_terms`]. The results are in `od` (H in `data.mass_matrix`, h in
/// `data.nle`).
///
/// # Errors
/// [`Error::Singular`] when H or Λ⁻¹ is not positive definite.
///
/// # Panics
/// On wrong sizes (`od` must be made with `n = model.nv`).
#[allow(clippy::too_many_arguments)]
pub fn osc_fixed_base(
    model: &Model,
    data: &mut Data,
    od: &mut OscData,
    frame: FrameIndex,
    q: &DVector<f64>,
    v: &DVector<f64>,
    a_des: &DVector<f64>,
    tau0: &DVector<f64>,
) -> Result<()> {
    assert_eq!(od.dofs(), model.nv, "OscData made for another model");
    crba(model, data, q);
    nonlinear_effects(model, data, q, v);
    let acc = frame_acceleration_bias(model, data, q, v, frame, ReferenceFrame::LocalWorldAligned);
    frame_jacobian_from_kinematics(
        model,
        data,
        frame,
        ReferenceFrame::LocalWorldAligned,
        &mut od.jac6,
    );
    let acc6 = acc.to_vector();
    for (k, &r) in od.rows.iter().enumerate() {
        od.acceleration_bias[k] = acc6[r];
        for c in 0..model.nv {
            od.jacobian[(k, c)] = od.jac6[(r, c)];
        }
    }
    osc_from_terms(od, &data.mass_matrix, &data.nle, a_des, tau0)
}

/// Moves the results of an update in `od`, computed in moma's layout at `(q, v)` (moma's
/// layout), into Pinocchio's (see [`crate::io::pinocchio_layout`]): with the velocity map
/// `v_P = T v` of a planar root, `J_P = J Tᵀ`, `J̄_P = T J̄`, `N_P = T N Tᵀ` and
/// `τ_P = T τ`, while the task quantities (world axes) Λ and F are unchanged. The bias
/// changes because Pinocchio's J̇v is the task acceleration at `a_P = 0`, which is moma's
/// `a = ω S v`: `(J̇v)_P = J̇v + J ω S v`. Feeding the null-space torque in Pinocchio's
/// layout is the caller's part (`τ₀ = Tᵀ τ₀_P`,
/// [`PinocchioLayout::tau_from_pinocchio`]). A model without a planar root is left as it
/// is. No allocation.
///
/// # Panics
/// If `q`, `v` or `od` do not fit the layout's model.
pub fn osc_to_pinocchio_layout(layout: &PinocchioLayout, q: &[f64], v: &[f64], od: &mut OscData) {
    assert_eq!(od.dofs(), layout.nv(), "OscData made for another model");
    // J ω S v, with moma's J: the moma acceleration of a zero Pinocchio acceleration.
    od.tmp_n2.fill(0.0);
    layout.a_from_pinocchio(q, v, od.tmp_n2.as_slice(), od.tmp_n.as_mut_slice());
    od.acceleration_bias.gemv(1.0, &od.jacobian, &od.tmp_n, 1.0);
    layout.columns_to_pinocchio_in_place(q, &mut od.jacobian);
    layout.rows_to_pinocchio_in_place(q, &mut od.dynamically_consistent_inverse);
    layout.rows_to_pinocchio_in_place(q, &mut od.nullspace_projector);
    layout.columns_to_pinocchio_in_place(q, &mut od.nullspace_projector);
    od.tmp_n.copy_from(&od.torque);
    layout.tau_to_pinocchio(q, od.tmp_n.as_slice(), od.torque.as_mut_slice());
}

/// σ_min/σ_max of the task Jacobian in `od` (filled by an update). Allocates (one SVD):
/// a check for input validation, not for the control loop.
#[must_use]
pub fn task_conditioning(od: &OscData) -> f64 {
    let sv = od.jacobian.clone().singular_values();
    let max = sv.max();
    if max > 0.0 { sv.min() / max } else { 0.0 }
}

/// Workspace of [`osc_reduced`]: the reduced terms and an [`OscData`] of dimension nr.
#[derive(Clone, Debug)]
pub struct ReducedOscData {
    /// Wheeled-model workspace (H, h, N_C, Ṅ_C, q̇).
    pub wheeled: WheeledData,
    /// The OSC results in reduced coordinates (torque = N_Cᵀ Q).
    pub osc: OscData,
    /// Reduced inertia Mr = N_Cᵀ H N_C.
    pub reduced_inertia: DMatrix<f64>,
    /// Reduced bias N_Cᵀ (h + H Ṅ_C v_r).
    pub reduced_bias: DVector<f64>,
    hn: DMatrix<f64>,
    tmp_n: DVector<f64>,
    tmp_n2: DVector<f64>,
    jn: Matrix6xX<f64>,
}

impl ReducedOscData {
    /// Buffers for `wm` and the given task rows.
    ///
    /// # Panics
    /// As [`OscData::new`].
    #[must_use]
    pub fn new(wm: &WheeledModel, rows: &[usize]) -> Self {
        let (nv, nr) = (wm.nv(), wm.nr());
        Self {
            wheeled: WheeledData::new(wm),
            osc: OscData::new(nr, rows),
            reduced_inertia: DMatrix::zeros(nr, nr),
            reduced_bias: DVector::zeros(nr),
            hn: DMatrix::zeros(nv, nr),
            tmp_n: DVector::zeros(nv),
            tmp_n2: DVector::zeros(nv),
            jn: Matrix6xX::zeros(nr),
        }
    }
}

/// Operational-space update of a frame of a wheeled model (non-holonomic platform plus
/// arm) in reduced coordinates `v_r = [v, ω, q̇_arm…]`: `J_r = J N_C`, `H_r = N_Cᵀ H N_C`,
/// `h_r = N_Cᵀ (h(q, q̇) + H Ṅ_C v_r)`, `J̇_r v_r = J̇ q̇ + J Ṅ_C v_r` with `q̇ = N_C v_r`.
/// The torque in `rod.osc.torque` is the reduced generalised force `N_Cᵀ Q` (map it to
/// actuators by solving `N_Cᵀ S u = τ_r`).
///
/// # Errors
/// [`Error::Singular`] when H_r or Λ⁻¹ is not positive definite.
///
/// # Panics
/// On wrong sizes.
#[allow(clippy::too_many_arguments)]
pub fn osc_reduced(
    wm: &WheeledModel,
    rod: &mut ReducedOscData,
    frame: FrameIndex,
    q: &DVector<f64>,
    v_r: &DVector<f64>,
    a_des: &DVector<f64>,
    tau0: &DVector<f64>,
) -> Result<()> {
    let model = &wm.model;
    let wd = &mut rod.wheeled;
    admissible_velocity_basis(wm, q, &mut wd.basis);
    wd.basis.mul_to(v_r, &mut wd.qdot);
    admissible_velocity_basis_dot(wm, q, wd.qdot[2], &mut wd.basis_dot);
    crba(model, &mut wd.data, q);
    nonlinear_effects(model, &mut wd.data, q, &wd.qdot);
    let acc = frame_acceleration_bias(
        model,
        &mut wd.data,
        q,
        &wd.qdot,
        frame,
        ReferenceFrame::LocalWorldAligned,
    );
    frame_jacobian_from_kinematics(
        model,
        &mut wd.data,
        frame,
        ReferenceFrame::LocalWorldAligned,
        &mut wd.jacobian,
    );
    let h = &wd.data.mass_matrix;
    // Mr = Nᵀ H N
    matmul(&mut rod.hn, 1.0, h, false, &wd.basis, 0.0);
    matmul(&mut rod.reduced_inertia, 1.0, &wd.basis, true, &rod.hn, 0.0);
    // hr = Nᵀ (h + H Ṅ v)
    wd.basis_dot.mul_to(v_r, &mut rod.tmp_n);
    rod.tmp_n2.copy_from(&wd.data.nle);
    rod.tmp_n2.gemv(1.0, h, &rod.tmp_n, 1.0);
    wd.basis.tr_mul_to(&rod.tmp_n2, &mut rod.reduced_bias);
    // J N and the task bias J̇q̇ + J Ṅ v
    for j in 0..rod.jn.ncols() {
        for i in 0..6 {
            let mut acc = 0.0;
            for l in 0..model.nv {
                acc += wd.jacobian[(i, l)] * wd.basis[(l, j)];
            }
            rod.jn[(i, j)] = acc;
        }
    }
    let acc6 = acc.to_vector();
    let od = &mut rod.osc;
    for (k, &r) in od.rows.iter().enumerate() {
        let mut b = acc6[r];
        for c in 0..model.nv {
            b += wd.jacobian[(r, c)] * rod.tmp_n[c];
        }
        od.acceleration_bias[k] = b;
        for c in 0..rod.jn.ncols() {
            od.jacobian[(k, c)] = rod.jn[(r, c)];
        }
    }
    osc_from_terms(od, &rod.reduced_inertia, &rod.reduced_bias, a_des, tau0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cholesky_helpers_solve() {
        let a = DMatrix::from_row_slice(3, 3, &[4.0, 2.0, 0.4, 2.0, 3.0, 0.5, 0.4, 0.5, 2.0]);
        let mut l = a.clone();
        assert!(cholesky_in_place(&mut l, 0.0).is_ok());
        let mut b = DMatrix::from_row_slice(3, 2, &[1.0, 0.0, 2.0, 1.0, 3.0, -1.0]);
        let b0 = b.clone();
        cholesky_solve_columns(&l, &mut b);
        assert!((&a * &b - b0).norm() < 1e-13);
        let mut bad = DMatrix::from_row_slice(2, 2, &[1.0, 2.0, 2.0, 1.0]);
        assert!(cholesky_in_place(&mut bad, 0.0).is_err());
    }
}

/// The per-state result document of an operational-space update: the `states[i]` object
/// of `moma osc` (schema in `docs/cli.md`) and the dictionary of the Python package's
/// `moma.osc`. Matrices are lists of rows.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct OscStateReport {
    /// Λ (m × m).
    pub task_inertia: Vec<Vec<f64>>,
    /// J̄ = H⁻¹ Jᵀ Λ (n × m).
    pub dynamically_consistent_inverse: Vec<Vec<f64>>,
    /// N = I − J̄ J (n × n).
    pub nullspace_projector: Vec<Vec<f64>>,
    /// J̇v of the selected rows (m).
    pub acceleration_bias: Vec<f64>,
    /// F (m).
    pub task_force: Vec<f64>,
    /// τ = Jᵀ F + Nᵀ τ₀ (n).
    pub torque: Vec<f64>,
    /// σ_min/σ_max of the task Jacobian ([`task_conditioning`]).
    pub task_conditioning: f64,
}

impl OscStateReport {
    /// The report of the update last written into `od`, with its conditioning.
    #[must_use]
    pub fn new(od: &OscData, task_conditioning: f64) -> Self {
        let rows = |m: &DMatrix<f64>| -> Vec<Vec<f64>> {
            m.row_iter().map(|r| r.iter().copied().collect()).collect()
        };
        Self {
            task_inertia: rows(&od.task_inertia),
            dynamically_consistent_inverse: rows(&od.dynamically_consistent_inverse),
            nullspace_projector: rows(&od.nullspace_projector),
            acceleration_bias: od.acceleration_bias.as_slice().to_vec(),
            task_force: od.task_force.as_slice().to_vec(),
            torque: od.torque.as_slice().to_vec(),
            task_conditioning,
        }
    }
}

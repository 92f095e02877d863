//! The reusable workspace of the algorithms.

use super::Model;
use crate::spatial::{Force, Inertia, Motion, SE3};
use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Matrix6xX, Vector3};

/// Articulated-body inertia `[A B; Bᵀ C]` (6 × 6 symmetric) acting on `[linear; angular]`
/// twists, stored as three 3 × 3 blocks.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ArticulatedInertia {
    /// Linear–linear block A.
    pub a: Matrix3<f64>,
    /// Linear–angular block B.
    pub b: Matrix3<f64>,
    /// Angular–angular block C.
    pub c: Matrix3<f64>,
}

/// Every buffer the algorithms need, sized once from a [`Model`] by [`Data::new`].
///
/// Results are documented by the algorithm that fills them. Per-joint quantities are in
/// the joint's own frame unless the name says `world`.
#[derive(Clone, Debug)]
pub struct Data {
    /// `parent_from_joint[i]` = placement · J(q_i) (position stage).
    pub parent_from_joint: Vec<SE3>,
    /// `world_from_joint[i]`, filled by forward kinematics.
    pub world_from_joint: Vec<SE3>,
    /// `world_from_frame[f]`, filled by `update_frame_placements`.
    pub world_from_frame: Vec<SE3>,
    /// Body twists v_i in joint frames.
    pub v: Vec<Motion>,
    /// Body spatial accelerations a_i in joint frames (RNEA: including −gravity).
    pub a: Vec<Motion>,
    /// Body forces f_i in joint frames (RNEA: transmitted through joint i).
    pub f: Vec<Force>,
    /// Joint torques τ from RNEA (nv).
    pub tau: DVector<f64>,
    /// Joint accelerations q̈ from ABA (nv).
    pub ddq: DVector<f64>,
    /// Joint-space inertia matrix H(q) from CRBA (nv × nv, full symmetric).
    pub mass_matrix: DMatrix<f64>,
    /// Nonlinear effects h(q, v) = C(q, v)v + g(q) (nv).
    pub nle: DVector<f64>,
    /// Generalised gravity g(q) (nv).
    pub gravity_torque: DVector<f64>,
    /// Christoffel-consistent Coriolis matrix C(q, v) (nv × nv).
    pub coriolis: DMatrix<f64>,
    /// Joint Jacobians in the world frame (6 × nv) from `compute_joint_jacobians`.
    pub joint_jacobians: Matrix6xX<f64>,
    /// Centroidal momentum matrix A_g (6 × nv, [linear; angular] about the CoM, world axes).
    pub centroidal_momentum_matrix: Matrix6xX<f64>,
    /// Centroidal momentum h_g = A_g v.
    pub centroidal_momentum: Force,
    /// Centre of mass of the moving bodies (world), m.
    pub com: Vector3<f64>,
    /// Kinetic energy (J).
    pub kinetic_energy: f64,
    /// Potential energy (J).
    pub potential_energy: f64,
    /// Composite rigid-body inertias (CRBA: joint frames; centroidal: world frame).
    pub composite_inertias: Vec<Inertia>,
    /// Motion subspace columns S (local), one per velocity coordinate (nv).
    pub(crate) s: Vec<Motion>,
    /// Scratch: velocity-product accelerations c_i (ABA) per joint.
    pub(crate) c: Vec<Motion>,
    /// Scratch: articulated inertias (ABA).
    pub(crate) ia: Vec<ArticulatedInertia>,
    /// Scratch: articulated bias forces (ABA).
    pub(crate) pa: Vec<Force>,
    /// Scratch: U = IA·S per dof (ABA).
    pub(crate) u: Vec<Force>,
    /// Scratch: D⁻¹ for each joint (ABA).
    pub(crate) dinv: Vec<Matrix6<f64>>,
    /// Scratch: u = τ − Sᵀ pA per dof (ABA).
    pub(crate) uu: DVector<f64>,
    /// Scratch: joint path (support chains).
    pub(crate) path: Vec<usize>,
    /// Scratch: world-frame 6 × 6 matrices per joint (Coriolis).
    pub(crate) mat6: Vec<Matrix6<f64>>,
    /// Scratch: second set of world-frame 6 × 6 matrices per joint (Coriolis).
    pub(crate) mat6b: Vec<Matrix6<f64>>,
    /// Scratch: world twists per joint.
    pub(crate) vworld: Vec<Motion>,
    /// Scratch: d/dt of world Jacobian columns (6 × nv).
    pub(crate) jdot: Matrix6xX<f64>,
    /// CRBA: how the composite force columns are handled for a depth-first model, else
    /// `None` (any other joint order takes the ancestor walk).
    pub(crate) crba_plan: Option<super::crba_plan::CrbaPlan>,
    /// Scratch: CRBA composite-force columns F = I^c S, stored by component (6 rows of nv).
    pub(crate) fcrb: Vec<f64>,
}

impl Data {
    /// Allocates every buffer for `model`.
    #[must_use]
    pub fn new(model: &Model) -> Self {
        let n = model.njoints;
        let nv = model.nv;
        let mut s = vec![Motion::zero(); nv];
        let q0 = super::neutral(model);
        for i in 1..n {
            let q = &q0.as_slice()[model.idx_q[i]..model.idx_q[i] + model.nqs[i]];
            for k in 0..model.nvs[i] {
                s[model.idx_v[i] + k] = model.joint_types[i].subspace_column(q, k);
            }
        }
        Self {
            parent_from_joint: vec![SE3::identity(); n],
            world_from_joint: vec![SE3::identity(); n],
            world_from_frame: vec![SE3::identity(); model.frames.len()],
            v: vec![Motion::zero(); n],
            a: vec![Motion::zero(); n],
            f: vec![Force::zero(); n],
            tau: DVector::zeros(nv),
            ddq: DVector::zeros(nv),
            mass_matrix: DMatrix::zeros(nv, nv),
            nle: DVector::zeros(nv),
            gravity_torque: DVector::zeros(nv),
            coriolis: DMatrix::zeros(nv, nv),
            joint_jacobians: Matrix6xX::zeros(nv),
            centroidal_momentum_matrix: Matrix6xX::zeros(nv),
            centroidal_momentum: Force::zero(),
            com: Vector3::zeros(),
            kinetic_energy: 0.0,
            potential_energy: 0.0,
            composite_inertias: vec![Inertia::zero(); n],
            s,
            c: vec![Motion::zero(); n],
            ia: vec![ArticulatedInertia::default(); n],
            pa: vec![Force::zero(); n],
            u: vec![Force::zero(); nv],
            dinv: vec![Matrix6::zeros(); n],
            uu: DVector::zeros(nv),
            path: Vec::with_capacity(n),
            mat6: vec![Matrix6::zeros(); n],
            mat6b: vec![Matrix6::zeros(); n],
            vworld: vec![Motion::zero(); n],
            jdot: Matrix6xX::zeros(nv),
            crba_plan: super::crba_plan::CrbaPlan::new(model),
            fcrb: vec![0.0; 6 * nv],
        }
    }

    /// True if this workspace was sized for `model`.
    #[must_use]
    pub fn fits(&self, model: &Model) -> bool {
        self.parent_from_joint.len() == model.njoints
            && self.tau.len() == model.nv
            && self.world_from_frame.len() == model.frames.len()
    }
}

//! Pose tasks for [`super::solve`]: an arm frame reaching a target pose, and the same for
//! a manipulator on a differential-drive platform moving its base and arm together.
//!
//! Both are written over [`FrameKinematics`], the forward kinematics of one frame of a
//! model: its world pose and its `LocalWorldAligned` Jacobian (rows `[linear; angular]`).
//! The residual of the pose task is
//!
//! ```text
//! e = [ p(q) − p* ;  log(R(q) R*ᵀ) ]      (world axes; a chosen subset of the 6 rows)
//! ```
//!
//! whose Jacobian with respect to the model velocity is exact: the frame Jacobian for the
//! position rows, and for the angular rows the frame's angular Jacobian `J_ω` (world
//! axes) times the inverse left Jacobian of SO(3) at the error `φ = log(R R*ᵀ)`:
//! a world-axes rotation `δ` changes `R R*ᵀ` into `exp(δ) R R*ᵀ`, whose log is
//! `φ + J_l⁻¹(φ) δ + O(δ²)` with
//!
//! ```text
//! J_l⁻¹(φ) = I − ½ [φ]× + (1/θ² − cot(θ/2) / (2θ)) [φ]×²,   θ = ‖φ‖ < π
//! ```
//!
//! (the inverse of the left Jacobian of SO(3), e.g. Barfoot, *State Estimation for
//! Robotics*, section 7.1). The first-order form `J_ω` alone is wrong for large errors:
//! at θ → π, `J_l⁻¹` scales the components perpendicular to `φ` by π/2 and turns them by
//! 90°, so the plain step points the wrong way there; with `J_l⁻¹` it is the true
//! Gauss–Newton step.

use super::KinematicTask;
use crate::error::{Error, Result, ensure_finite, ensure_len};
use crate::mobile::DiffDrive;
use crate::mobile::whole_body::{BaseInputs, compose_jacobian, integrate_base};
use nalgebra::{DMatrix, DVector, Isometry3, Translation3, UnitQuaternion};
use std::str::FromStr;

/// Forward kinematics of one frame of a model, as the pose tasks need it.
pub trait FrameKinematics {
    /// Configuration dimension nq.
    fn nq(&self) -> usize;
    /// Velocity dimension nv.
    fn nv(&self) -> usize;
    /// World pose of the frame and its 6 × nv `LocalWorldAligned` Jacobian
    /// (rows `[linear; angular]`, linear = velocity of the frame origin).
    fn pose_and_jacobian(
        &mut self,
        q: &DVector<f64>,
        pose: &mut Isometry3<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<()>;
    /// `out = q ⊕ v` (the model's integration for unit time), projected into the joint
    /// limits.
    fn integrate(&self, q: &DVector<f64>, v: &DVector<f64>, out: &mut DVector<f64>);
    /// Marks the velocity coordinates at a limit that `v` pushes further out.
    fn blocked_velocities(&self, q: &DVector<f64>, v: &DVector<f64>, blocked: &mut [bool]);
    /// `out = q1 ⊖ q0` (nv), the velocity that [`FrameKinematics::integrate`] (without
    /// the limit projection) follows for unit time from `q0` to `q1`; angles that wrap
    /// take the shortest way. The default subtracts coordinates (nq = nv, no wrapping).
    fn difference(&self, q0: &DVector<f64>, q1: &DVector<f64>, out: &mut DVector<f64>) {
        for k in 0..out.len() {
            out[k] = q1[k] - q0[k];
        }
    }
    /// A sphere (centre in the model's world frame, radius) that contains every position
    /// the frame can reach, if the model allows a cheap bound (fixed root, revolute and
    /// bounded prismatic joints); used to skip hopeless IK problems.
    fn reach_bound(&self) -> Option<(nalgebra::Vector3<f64>, f64)> {
        None
    }
    /// Writes a random configuration within the joint limits (root coordinates copied
    /// from `current`); false if the model cannot sample one.
    fn random_configuration(
        &self,
        _current: &DVector<f64>,
        _rng: &mut dyn rand::RngCore,
        _out: &mut DVector<f64>,
    ) -> bool {
        false
    }
    /// The same frame with this (fixed-based) chain mounted at `mount` on a planar base:
    /// `q = [x, y, θ, q…]`, `v = [ẋ, ẏ, θ̇, q̇…]` in world axes, and the arm's world frame at
    /// `mount` in the platform frame. Its [`FrameKinematics::pose_and_jacobian`] gives
    /// the whole-body frame Jacobian that the placement maps reduce by the wheel map.
    /// `None` when this kinematics cannot be re-rooted (the default), `Some(Err)` when the
    /// mount is invalid for it.
    fn on_planar_base(&self, _mount: &Isometry3<f64>) -> Option<Result<Self>>
    where
        Self: Sized,
    {
        None
    }
}

/// Which rows of the 6-D pose error/Jacobian `[linear; angular]` a task uses.
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub enum TaskRows {
    /// Position only: rows 0, 1, 2.
    Position,
    /// Orientation only: rows 3, 4, 5.
    Orientation,
    /// Full pose: all six rows.
    #[default]
    Full,
    /// A user-chosen subset of the rows 0..6 (e.g. `[0, 1, 5]` for planar x, y, yaw).
    Rows(Vec<usize>),
}

impl TaskRows {
    /// The row indices into `[vx, vy, vz, ωx, ωy, ωz]`.
    pub fn indices(&self) -> Vec<usize> {
        match self {
            TaskRows::Position => vec![0, 1, 2],
            TaskRows::Orientation => vec![3, 4, 5],
            TaskRows::Full => (0..6).collect(),
            TaskRows::Rows(r) => r.clone(),
        }
    }

    /// Validates a row subset (non-empty, each < 6, no repeats).
    pub fn validate(&self) -> Result<()> {
        let idx = self.indices();
        if idx.is_empty() {
            return Err(Error::invalid("task rows", "no rows selected"));
        }
        for (k, &r) in idx.iter().enumerate() {
            if r >= 6 {
                return Err(Error::invalid(
                    format!("task rows[{k}]"),
                    format!("row {r} out of range 0..6 ([vx, vy, vz, wx, wy, wz])"),
                ));
            }
            if idx[..k].contains(&r) {
                return Err(Error::invalid(
                    format!("task rows[{k}]"),
                    format!("row {r} repeated"),
                ));
            }
        }
        Ok(())
    }
}

impl FromStr for TaskRows {
    type Err = Error;
    /// `position`, `orientation`, `full` (or `pose`), or `rows:0,1,5`.
    fn from_str(s: &str) -> Result<Self> {
        let t = s.trim().to_ascii_lowercase();
        let rows = match t.as_str() {
            "position" | "pos" => TaskRows::Position,
            "orientation" | "rot" => TaskRows::Orientation,
            "full" | "pose" | "6d" => TaskRows::Full,
            _ => {
                let body = t.strip_prefix("rows:").ok_or_else(|| {
                    Error::invalid(
                        "task rows",
                        format!(
                            "unknown '{s}'; expected position, orientation, full or rows:i,j,..."
                        ),
                    )
                })?;
                let mut r = Vec::new();
                for (k, p) in body.split(',').enumerate() {
                    r.push(p.trim().parse::<usize>().map_err(|_| {
                        Error::invalid(
                            format!("task rows[{k}]"),
                            format!("'{p}' is not a row index"),
                        )
                    })?);
                }
                TaskRows::Rows(r)
            }
        };
        rows.validate()?;
        Ok(rows)
    }
}

/// Multiplies the angular rows 3..6 of the 6-row Jacobian `j6` by `J_l⁻¹(φ)`, the inverse
/// left Jacobian of SO(3) at the orientation error `φ = e6[3..6]` (module docs), so that
/// they are the exact derivative of the orientation error.
pub fn apply_log_jacobian(e6: &[f64; 6], j6: &mut DMatrix<f64>) {
    let phi = nalgebra::Vector3::new(e6[3], e6[4], e6[5]);
    let theta = phi.norm();
    if theta == 0.0 {
        return;
    }
    // c(θ) = 1/θ² − cot(θ/2)/(2θ); its series 1/12 + θ²/720 + θ⁴/30240 near 0.
    let c = if theta < 1e-3 {
        let t2 = theta * theta;
        1.0 / 12.0 + t2 / 720.0 + t2 * t2 / 30240.0
    } else {
        let half = 0.5 * theta;
        1.0 / (theta * theta) - half.cos() / (half.sin() * 2.0 * theta)
    };
    for k in 0..j6.ncols() {
        let w = nalgebra::Vector3::new(j6[(3, k)], j6[(4, k)], j6[(5, k)]);
        let pw = phi.cross(&w);
        let out = w - 0.5 * pw + c * phi.cross(&pw);
        j6[(3, k)] = out.x;
        j6[(4, k)] = out.y;
        j6[(5, k)] = out.z;
    }
}

/// The 6-D pose error `[p − p*; log(R R*ᵀ)]` in world axes.
pub fn pose_error(pose: &Isometry3<f64>, target: &Isometry3<f64>) -> [f64; 6] {
    let dp = pose.translation.vector - target.translation.vector;
    let dr = (pose.rotation * target.rotation.inverse()).scaled_axis();
    [dp.x, dp.y, dp.z, dr.x, dr.y, dr.z]
}

/// Builds a target pose from `[x, y, z]` (identity orientation) or
/// `[x, y, z, qx, qy, qz, qw]` (the quaternion is normalised; it must not be zero).
pub fn target_from_slice(values: &[f64]) -> Result<Isometry3<f64>> {
    ensure_finite("target", values)?;
    match values.len() {
        3 => Ok(Isometry3::from_parts(
            Translation3::new(values[0], values[1], values[2]),
            UnitQuaternion::identity(),
        )),
        7 => {
            let q = nalgebra::Quaternion::new(values[6], values[3], values[4], values[5]);
            if q.norm() < 1e-9 {
                return Err(Error::invalid(
                    "target quaternion",
                    "qx, qy, qz, qw must not all be zero",
                ));
            }
            Ok(Isometry3::from_parts(
                Translation3::new(values[0], values[1], values[2]),
                UnitQuaternion::from_quaternion(q),
            ))
        }
        n => Err(Error::invalid(
            "target",
            format!("expected 3 values x,y,z or 7 values x,y,z,qx,qy,qz,qw, got {n}"),
        )),
    }
}

/// Copies the task rows `rows` of the 6-D pose error and of the 6-row Jacobian `j6`
/// into the task residual and Jacobian (one row per selected index).
fn select_rows(
    rows: &[usize],
    e6: &[f64; 6],
    j6: &DMatrix<f64>,
    residual: &mut DVector<f64>,
    jacobian: &mut DMatrix<f64>,
) {
    for (i, &r) in rows.iter().enumerate() {
        residual[i] = e6[r];
        for k in 0..j6.ncols() {
            jacobian[(i, k)] = j6[(r, k)];
        }
    }
}

/// An arm frame reaching a target pose (selected rows): [`KinematicTask`] for
/// [`super::solve`].
pub struct PoseTask<K: FrameKinematics> {
    /// The frame's kinematics.
    pub kinematics: K,
    /// Target pose in world.
    pub target: Isometry3<f64>,
    rows: Vec<usize>,
    preferred: Option<DVector<f64>>,
    pose: Isometry3<f64>,
    j6: DMatrix<f64>,
}

impl<K: FrameKinematics> PoseTask<K> {
    /// A pose task on the given rows.
    pub fn new(kinematics: K, target: Isometry3<f64>, rows: &TaskRows) -> Result<Self> {
        rows.validate()?;
        let nv = kinematics.nv();
        Ok(Self {
            kinematics,
            target,
            rows: rows.indices(),
            preferred: None,
            pose: Isometry3::identity(),
            j6: DMatrix::zeros(6, nv),
        })
    }

    /// Sets a preferred posture (length nq; used by the `Posture` null-space objective).
    pub fn with_preferred_posture(mut self, q: DVector<f64>) -> Result<Self> {
        ensure_len("preferred posture", self.kinematics.nq(), q.len())?;
        ensure_finite("preferred posture", q.iter())?;
        self.preferred = Some(q);
        Ok(self)
    }

    /// The frame pose at the last evaluation.
    pub fn last_pose(&self) -> &Isometry3<f64> {
        &self.pose
    }
}

impl<K: FrameKinematics> KinematicTask for PoseTask<K> {
    fn nq(&self) -> usize {
        self.kinematics.nq()
    }
    fn nv(&self) -> usize {
        self.kinematics.nv()
    }
    fn task_dim(&self) -> usize {
        self.rows.len()
    }
    fn residual_and_jacobian(
        &mut self,
        q: &DVector<f64>,
        residual: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<()> {
        self.kinematics
            .pose_and_jacobian(q, &mut self.pose, &mut self.j6)?;
        let e6 = pose_error(&self.pose, &self.target);
        apply_log_jacobian(&e6, &mut self.j6);
        select_rows(&self.rows, &e6, &self.j6, residual, jacobian);
        Ok(())
    }
    fn integrate(&self, q: &DVector<f64>, delta: &DVector<f64>, out: &mut DVector<f64>) {
        self.kinematics.integrate(q, delta, out);
    }
    fn blocked_inputs(&self, q: &DVector<f64>, delta: &DVector<f64>, blocked: &mut [bool]) {
        self.kinematics.blocked_velocities(q, delta, blocked);
    }
    fn random_configuration(
        &self,
        current: &DVector<f64>,
        rng: &mut dyn rand::RngCore,
        out: &mut DVector<f64>,
    ) -> bool {
        self.kinematics.random_configuration(current, rng, out)
    }
    fn posture_gradient(&self, q: &DVector<f64>, gradient: &mut DVector<f64>) -> bool {
        match &self.preferred {
            // q_pref ⊖ q: the shortest way for wrapping angles, a base twist for a
            // free-flyer root.
            Some(p) => {
                self.kinematics.difference(q, p, gradient);
                true
            }
            None => false,
        }
    }
}

/// A manipulator on a differential-drive platform reaching a target pose with base and
/// arm together (whole-body resolved-rate motion).
///
/// The model's root must be the planar platform joint, `q = [x, y, θ, q_arm…]`,
/// `q̇ = [ẋ, ẏ, θ̇, q̇_arm…]`. The increments are the whole-body inputs
/// `u = [u_base(2), q̇_arm]` ([`BaseInputs`]); the base is integrated exactly along the
/// arc of constant `(v, ω)`, so every iterate is reachable without side slip. Use
/// [`super::IkOptions::weights`] to trade base motion against arm motion.
pub struct WholeBodyTask<K: FrameKinematics> {
    /// The frame's kinematics (planar root first).
    pub kinematics: K,
    /// The platform.
    pub drive: DiffDrive,
    /// Base input parametrisation.
    pub inputs: BaseInputs,
    /// Target pose in world.
    pub target: Isometry3<f64>,
    rows: Vec<usize>,
    preferred: Option<DVector<f64>>,
    pose: Isometry3<f64>,
    j6: DMatrix<f64>,
    jbar: DMatrix<f64>,
    v_model: std::cell::RefCell<DVector<f64>>,
    blocked_model: std::cell::RefCell<Vec<bool>>,
    q_pref_full: std::cell::RefCell<DVector<f64>>,
}

impl<K: FrameKinematics> WholeBodyTask<K> {
    /// A whole-body pose task on the given rows.
    pub fn new(
        kinematics: K,
        drive: DiffDrive,
        inputs: BaseInputs,
        target: Isometry3<f64>,
        rows: &TaskRows,
    ) -> Result<Self> {
        rows.validate()?;
        let (nq, nv) = (kinematics.nq(), kinematics.nv());
        if nv < 3 || nq < 3 {
            return Err(Error::invalid(
                "whole-body model",
                "the model needs a planar root [x, y, θ] (nq, nv >= 3)",
            ));
        }
        Ok(Self {
            kinematics,
            drive,
            inputs,
            target,
            rows: rows.indices(),
            preferred: None,
            pose: Isometry3::identity(),
            j6: DMatrix::zeros(6, nv),
            jbar: DMatrix::zeros(6, nv - 1),
            v_model: std::cell::RefCell::new(DVector::zeros(nv)),
            blocked_model: std::cell::RefCell::new(vec![false; nv]),
            q_pref_full: std::cell::RefCell::new(DVector::zeros(nq)),
        })
    }

    /// Sets a preferred arm posture `q_arm` (length nq − 3) for the `Posture` objective.
    pub fn with_preferred_posture(mut self, q_arm: DVector<f64>) -> Result<Self> {
        ensure_len("preferred posture", self.kinematics.nq() - 3, q_arm.len())?;
        ensure_finite("preferred posture", q_arm.iter())?;
        self.preferred = Some(q_arm);
        Ok(self)
    }

    /// The frame pose at the last evaluation.
    pub fn last_pose(&self) -> &Isometry3<f64> {
        &self.pose
    }

    /// The 6-row whole-body Jacobian `J̄` at the last evaluation.
    pub fn last_whole_body_jacobian(&self) -> &DMatrix<f64> {
        &self.jbar
    }

    /// The model velocity of an increment with the base part zeroed: the arm inputs
    /// `delta[2..]` land at `v[3..]` (written into the reused `v_model` buffer).
    fn arm_velocity(&self, delta: &DVector<f64>) -> std::cell::RefMut<'_, DVector<f64>> {
        let mut v = self.v_model.borrow_mut();
        v.fill(0.0);
        for k in 2..delta.len() {
            v[k + 1] = delta[k];
        }
        v
    }

    /// Forward displacement and heading change of the axle midpoint for base increments.
    fn base_displacement(&self, u0: f64, u1: f64) -> (f64, f64) {
        match self.inputs {
            BaseInputs::Platform => (u0, u1),
            BaseInputs::Wheels => {
                let w = self.drive.wheel_to_platform();
                (
                    w[(0, 0)] * u0 + w[(0, 1)] * u1,
                    w[(1, 0)] * u0 + w[(1, 1)] * u1,
                )
            }
        }
    }
}

impl<K: FrameKinematics> KinematicTask for WholeBodyTask<K> {
    fn nq(&self) -> usize {
        self.kinematics.nq()
    }
    fn nv(&self) -> usize {
        self.kinematics.nv() - 1
    }
    fn task_dim(&self) -> usize {
        self.rows.len()
    }
    fn residual_and_jacobian(
        &mut self,
        q: &DVector<f64>,
        residual: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<()> {
        self.kinematics
            .pose_and_jacobian(q, &mut self.pose, &mut self.j6)?;
        compose_jacobian(&self.drive, self.inputs, q[2], &self.j6, &mut self.jbar)?;
        let e6 = pose_error(&self.pose, &self.target);
        apply_log_jacobian(&e6, &mut self.jbar);
        select_rows(&self.rows, &e6, &self.jbar, residual, jacobian);
        Ok(())
    }
    fn integrate(&self, q: &DVector<f64>, delta: &DVector<f64>, out: &mut DVector<f64>) {
        let v = self.arm_velocity(delta);
        self.kinematics.integrate(q, &v, out);
        let (s, alpha) = self.base_displacement(delta[0], delta[1]);
        let base = integrate_base(&self.drive, [q[0], q[1], q[2]], s, alpha);
        out[0] = base[0];
        out[1] = base[1];
        out[2] = base[2];
    }
    fn blocked_inputs(&self, q: &DVector<f64>, delta: &DVector<f64>, blocked: &mut [bool]) {
        let v = self.arm_velocity(delta);
        let mut b = self.blocked_model.borrow_mut();
        b.iter_mut().for_each(|x| *x = false);
        self.kinematics.blocked_velocities(q, &v, &mut b);
        let n = delta.len();
        blocked[2..n].copy_from_slice(&b[3..n + 1]);
    }
    fn manipulability_columns(&self) -> std::ops::Range<usize> {
        2..self.nv()
    }
    fn random_configuration(
        &self,
        current: &DVector<f64>,
        rng: &mut dyn rand::RngCore,
        out: &mut DVector<f64>,
    ) -> bool {
        if !self.kinematics.random_configuration(current, rng, out) {
            return false;
        }
        // Keep the base where it is: restarts re-seed the arm only.
        out[0] = current[0];
        out[1] = current[1];
        out[2] = current[2];
        true
    }
    fn posture_gradient(&self, q: &DVector<f64>, gradient: &mut DVector<f64>) -> bool {
        let Some(p) = &self.preferred else {
            return false;
        };
        // (q_base, q_arm_pref) ⊖ q, through the model's difference (continuous arm
        // joints take the shortest way); the base inputs get no posture term.
        let mut q_pref = self.q_pref_full.borrow_mut();
        let mut v = self.v_model.borrow_mut();
        q_pref.copy_from(q);
        q_pref.rows_mut(3, p.len()).copy_from(p);
        self.kinematics.difference(q, &q_pref, &mut v);
        gradient[0] = 0.0;
        gradient[1] = 0.0;
        for k in 2..gradient.len() {
            gradient[k] = v[k + 1];
        }
        true
    }
}

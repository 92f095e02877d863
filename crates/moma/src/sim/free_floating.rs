//! Free-floating simulation: a free-flyer model in zero gravity driven only by its joint
//! torques, with the base attitude a unit quaternion, momentum monitors, and the capture
//! of a target body (impulsive, momentum-conserving velocity jump).
//!
//! State `x = [q; v]` (nq + nv): `q = [p_b; quat_xyzw; q_m]`, `v = [v_b; ω_b; q̇_m]` with the
//! base twist in the base frame. The right-hand side is `q̇_pos = R v_b`,
//! `quaṫ = ½ quat ⊗ (ω_b, 0)`, `q̇_m = v_m`, `v̇ = ABA(q, v, [0; τ])`. The quaternion's
//! exact flow keeps its norm; the right-hand side evaluates the kinematics at the
//! normalised quaternion (so the dynamics never see a non-unit attitude) and every
//! reported state is projected back onto the unit sphere. RK4 steps project after each
//! step ([`FreeFloatingOde::rk4_step`]).

use crate::dynamics::aba;
use crate::error::{Error, Result};
use crate::kinematics::{ReferenceFrame, frame_jacobian};
use crate::multibody::{Data, FrameIndex, Model};
use crate::sim::settings::{ChannelProfile, IntegratorSettings};
use crate::sim::stepping::{budget_exhausted, check_rk4_budget};
use crate::sim::{AdaptiveOptions, Dop853, OdeSystem, Rk4, StepBudget};
use crate::space::{self, SpaceData, check_free_flyer};
use crate::spatial::{Force, Inertia, Motion, SE3};
use nalgebra::{DMatrix, DVector, Matrix3, Matrix6xX, UnitQuaternion, Vector3};

/// The free-floating dynamics as an [`OdeSystem`] on `x = [q; v]`.
pub struct FreeFloatingOde<'m> {
    model: &'m Model,
    data: Data,
    q: DVector<f64>,
    v: DVector<f64>,
    tau: DVector<f64>,
    /// Constant joint torques τ (nv − 6).
    pub torque: DVector<f64>,
    /// Time-varying joint torques added to `torque`, one profile per joint (or none).
    pub profiles: Vec<ChannelProfile>,
    /// Viscous joint damping D (N·m·s/rad): adds `−D q̇_m` (internal, keeps the momentum).
    pub joint_damping: f64,
}

/// Projects the base quaternion of `q` (entries 3..7) onto the unit sphere.
pub fn normalize_base_quaternion(q: &mut [f64]) {
    let n = (q[3] * q[3] + q[4] * q[4] + q[5] * q[5] + q[6] * q[6]).sqrt();
    for x in &mut q[3..7] {
        *x /= n;
    }
}

impl<'m> FreeFloatingOde<'m> {
    /// The dynamics of `model` (free-flyer root, zero gravity) with zero joint torques.
    ///
    /// # Errors
    /// [`Error::Model`] if the model is not free floating; [`Error::InvalidInput`] if its
    /// gravity is not zero (momentum would not be conserved).
    pub fn new(model: &'m Model) -> Result<Self> {
        check_free_flyer(model)?;
        if model.gravity.norm() != 0.0 {
            return Err(Error::invalid(
                "gravity",
                format!(
                    "a free-floating system is simulated in zero gravity, got {:?}",
                    model.gravity.as_slice()
                ),
            ));
        }
        Ok(FreeFloatingOde {
            model,
            data: Data::new(model),
            q: DVector::zeros(model.nq),
            v: DVector::zeros(model.nv),
            tau: DVector::zeros(model.nv),
            torque: DVector::zeros(model.nv - 6),
            profiles: Vec::new(),
            joint_damping: 0.0,
        })
    }

    /// The model.
    pub fn model(&self) -> &Model {
        self.model
    }

    /// One classical RK4 step of length h, then the quaternion projection.
    ///
    /// # Errors
    /// As [`Rk4::step`].
    pub fn rk4_step(&mut self, rk: &mut Rk4, t: f64, x: &mut [f64], h: f64) -> Result<()> {
        rk.step(self, t, x, h)?;
        normalize_base_quaternion(x);
        Ok(())
    }
}

impl OdeSystem for FreeFloatingOde<'_> {
    fn dim(&self) -> usize {
        self.model.nq + self.model.nv
    }

    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<()> {
        let (nq, nv) = (self.model.nq, self.model.nv);
        self.q.as_mut_slice().copy_from_slice(&x[..nq]);
        normalize_base_quaternion(self.q.as_mut_slice());
        self.v.as_mut_slice().copy_from_slice(&x[nq..]);
        self.tau.as_mut_slice()[6..].copy_from_slice(self.torque.as_slice());
        for (k, p) in self.profiles.iter().enumerate() {
            self.tau[6 + k] += p.eval(t);
        }
        if self.joint_damping != 0.0 {
            for k in 6..nv {
                self.tau[k] -= self.joint_damping * x[nq + k];
            }
        }
        let ddq = aba(self.model, &mut self.data, &self.q, &self.v, &self.tau);
        dx[nq..].copy_from_slice(ddq.as_slice());
        configuration_rate(&self.q, x, &x[nq..], &mut dx[..nq]);
        Ok(())
    }
}

/// `q̇` of a free-floating configuration from `v`: `ṗ = R v_b`, `quaṫ = ½ quat ⊗ (ω_b, 0)`
/// (on the quaternion `x[3..7]` itself, which keeps its norm; R from the normalised `qn`),
/// `q̇_m = v_m`.
fn configuration_rate(qn: &DVector<f64>, x: &[f64], v: &[f64], dq: &mut [f64]) {
    let rot = base_attitude(qn).to_rotation_matrix().into_inner();
    let vl = Vector3::new(v[0], v[1], v[2]);
    let w = Vector3::new(v[3], v[4], v[5]);
    let pd = rot * vl;
    dq[0] = pd.x;
    dq[1] = pd.y;
    dq[2] = pd.z;
    let (ax, ay, az, aw) = (x[3], x[4], x[5], x[6]);
    dq[3] = 0.5 * (aw * w.x + ay * w.z - az * w.y);
    dq[4] = 0.5 * (aw * w.y + az * w.x - ax * w.z);
    dq[5] = 0.5 * (aw * w.z + ax * w.y - ay * w.x);
    dq[6] = -0.5 * (ax * w.x + ay * w.y + az * w.z);
    let nq = dq.len();
    dq[7..nq].copy_from_slice(&v[6..]);
}

/// One recorded sample of a free-floating run.
#[derive(Clone, Debug)]
pub struct FloatingSample {
    /// Time (s).
    pub t: f64,
    /// Configuration (unit base quaternion).
    pub q: DVector<f64>,
    /// Generalized velocity.
    pub v: DVector<f64>,
    /// System momentum `[P; L_c]` (world; angular about the CoM).
    pub momentum: Force,
    /// System CoM (world), m.
    pub com: Vector3<f64>,
}

/// Momentum monitor of a run: the largest drift of P and of L_c, relative to the initial
/// norm when that is at least 1 (N·s, N·m·s), absolute below (so a system at rest, whose
/// momentum is zero up to rounding, is measured in N·s and N·m·s); and the largest
/// deviation of the CoM from uniform motion.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MomentumDrift {
    /// max |P(t) − P(0)| / max(|P(0)|, 1).
    pub linear: f64,
    /// max |L_c(t) − L_c(0)| / max(|L_c(0)|, 1). With P ≠ 0 the CoM
    /// moves and L_c is still conserved (the moment of P about the moving CoM is zero).
    pub angular: f64,
    /// max |c(t) − c(0) − t P(0)/M| (m): the CoM moves uniformly.
    pub com: f64,
}

/// The drift of a recorded run (see [`MomentumDrift`]).
#[must_use]
pub fn momentum_drift(samples: &[FloatingSample], total_mass: f64) -> MomentumDrift {
    let Some(s0) = samples.first() else {
        return MomentumDrift::default();
    };
    let scale = |x: f64| x.max(1.0);
    let (sp, sl) = (
        scale(s0.momentum.linear.norm()),
        scale(s0.momentum.angular.norm()),
    );
    let mut d = MomentumDrift::default();
    for s in samples {
        d.linear = d
            .linear
            .max((s.momentum.linear - s0.momentum.linear).norm() / sp);
        d.angular = d
            .angular
            .max((s.momentum.angular - s0.momentum.angular).norm() / sl);
        let c = s0.com + s0.momentum.linear * ((s.t - s0.t) / total_mass);
        d.com = d.com.max((s.com - c).norm());
    }
    d
}

/// Simulates the free-floating model from `(q0, v0)` under constant joint torques with
/// DOP853 at `rtol = atol = tol`, recording the state, momentum and CoM at `times`
/// (non-decreasing, from 0). The first recorded sample is `t = 0` when `times[0] = 0`.
///
/// # Errors
/// As [`FreeFloatingOde::new`], wrong lengths, and integration failures.
pub fn simulate(
    model: &Model,
    q0: &DVector<f64>,
    v0: &DVector<f64>,
    torque: &DVector<f64>,
    times: &[f64],
    tol: f64,
) -> Result<Vec<FloatingSample>> {
    let mut ode = FreeFloatingOde::new(model)?;
    crate::error::ensure_len("q0", model.nq, q0.len())?;
    crate::error::ensure_len("v0", model.nv, v0.len())?;
    crate::error::ensure_len("torque", model.nv - 6, torque.len())?;
    crate::error::ensure_finite("q0", q0.iter())?;
    crate::error::ensure_finite("v0", v0.iter())?;
    crate::error::ensure_finite("torque", torque.iter())?;
    ode.torque.copy_from(torque);
    let mut x: Vec<f64> = q0.iter().chain(v0.iter()).copied().collect();
    normalize_base_quaternion(&mut x);
    let mut dp = Dop853::new(x.len(), AdaptiveOptions::with_tolerance(tol))?;
    let mut data = Data::new(model);
    let mut t = 0.0;
    let mut out = Vec::with_capacity(times.len());
    for (i, &te) in times.iter().enumerate() {
        if !te.is_finite() || te < t {
            return Err(Error::invalid(
                format!("t[{i}]"),
                "output times must be finite, non-decreasing and not negative",
            ));
        }
        dp.integrate_to(&mut ode, &mut t, &mut x, te)?;
        out.push(sample(model, &mut data, te, &x));
    }
    Ok(out)
}

/// A sample (projected quaternion, momentum, CoM) from an ODE state.
pub fn sample(model: &Model, data: &mut Data, t: f64, x: &[f64]) -> FloatingSample {
    let mut q = DVector::from_column_slice(&x[..model.nq]);
    normalize_base_quaternion(q.as_mut_slice());
    let v = DVector::from_column_slice(&x[model.nq..]);
    let momentum = space::momentum(model, data, &q, &v);
    FloatingSample {
        t,
        com: data.com,
        q,
        v,
        momentum,
    }
}

/// A free body to be captured: mass, CoM and rotational inertia about its CoM given in
/// the grasp frame's axes at the moment of capture, and its own velocity before capture.
#[derive(Clone, Debug, PartialEq)]
pub struct TargetBody {
    /// Mass (kg, > 0).
    pub mass: f64,
    /// CoM in the grasp frame (m).
    pub com_in_frame: Vector3<f64>,
    /// Rotational inertia about its CoM, grasp-frame axes (kg·m²).
    pub inertia_com: Matrix3<f64>,
    /// Velocity of its CoM before capture (world, m/s).
    pub linear_velocity: Vector3<f64>,
    /// Angular velocity before capture (world, rad/s).
    pub angular_velocity: Vector3<f64>,
}

/// The total momentum at the world origin `[P; L_O]` of a robot state.
fn momentum_at_origin(model: &Model, data: &mut Data, q: &DVector<f64>, v: &DVector<f64>) -> Force {
    let h = space::momentum(model, data, q, v);
    Force::new(h.linear, h.angular + data.com.cross(&h.linear))
}

/// Result of a capture.
#[derive(Clone, Debug)]
pub struct Capture {
    /// The combined model (the target's inertia added to the grasping body).
    pub model: Model,
    /// The generalized velocity just after the capture.
    pub v: DVector<f64>,
    /// Total momentum at the world origin `[P; L_O]` before (robot + target).
    pub momentum_before: Force,
    /// The same after (combined system).
    pub momentum_after: Force,
}

/// Captures `target` rigidly at `frame` at configuration q: the target's inertia joins
/// the frame's body and the velocity jumps impulsively. With no impulsive joint torque,
/// the generalized momentum balance `H'(q) v⁺ = H(q) v⁻ + J_fᵀ p_t` (J_f the world
/// spatial Jacobian of the frame, p_t the target's spatial momentum at the world origin)
/// conserves the total linear and angular momentum exactly.
///
/// # Errors
/// Non-positive or non-finite target data; a singular combined mass matrix.
pub fn capture(
    model: &Model,
    q: &DVector<f64>,
    v: &DVector<f64>,
    frame: FrameIndex,
    target: &TargetBody,
) -> Result<Capture> {
    check_free_flyer(model)?;
    if !(target.mass.is_finite() && target.mass > 0.0) {
        return Err(Error::invalid("target.mass", "must be positive"));
    }
    crate::error::ensure_finite(
        "target",
        target
            .com_in_frame
            .iter()
            .chain(target.inertia_com.iter())
            .chain(target.linear_velocity.iter())
            .chain(target.angular_velocity.iter()),
    )?;
    let mut data = Data::new(model);
    let mut jac = Matrix6xX::zeros(model.nv);
    frame_jacobian(model, &mut data, q, frame, ReferenceFrame::World, &mut jac);
    let world_from_frame: SE3 = data.world_from_frame[frame.0];
    let fr = &model.frames[frame.0];
    let inertia_frame = Inertia::new(target.mass, target.com_in_frame, target.inertia_com);
    // the target's spatial momentum at the world origin
    let inertia_world = inertia_frame.transformed(&world_from_frame);
    let c_world = world_from_frame.act_point(&target.com_in_frame);
    let twist_world = Motion::new(
        target.linear_velocity - target.angular_velocity.cross(&c_world),
        target.angular_velocity,
    );
    let p_t = inertia_world.mul_motion(&twist_world);
    let before_robot = momentum_at_origin(model, &mut data, q, v);
    let momentum_before = Force::new(
        before_robot.linear + p_t.linear,
        before_robot.angular + p_t.angular,
    );
    let mut combined = model.clone();
    let joint = fr.parent_joint.0;
    combined.inertias[joint] += inertia_frame.transformed(&fr.placement);
    combined.name = format!("{}+target", model.name);
    let h_before = crate::dynamics::crba(model, &mut data, q).clone();
    let mut rhs = &h_before * v;
    let pt = nalgebra::Vector6::new(
        p_t.linear.x,
        p_t.linear.y,
        p_t.linear.z,
        p_t.angular.x,
        p_t.angular.y,
        p_t.angular.z,
    );
    rhs += jac.transpose() * pt;
    let mut data_c = Data::new(&combined);
    let h_after: DMatrix<f64> = crate::dynamics::crba(&combined, &mut data_c, q).clone();
    let chol = h_after.cholesky().ok_or_else(|| Error::Singular {
        what: "mass matrix of the combined system".into(),
        detail: None,
    })?;
    let v_after = chol.solve(&rhs);
    let momentum_after = momentum_at_origin(&combined, &mut data_c, q, &v_after);
    Ok(Capture {
        model: combined,
        v: v_after,
        momentum_before,
        momentum_after,
    })
}

/// The base attitude of a configuration as a unit quaternion.
#[must_use]
pub fn base_attitude(q: &DVector<f64>) -> UnitQuaternion<f64> {
    UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(q[6], q[3], q[4], q[5]))
}

/// Joint rates from an end-effector velocity through J* (resolved rate at zero momentum,
/// damped least squares `J*ᵀ (J* J*ᵀ + λ² 1)⁻¹ ẋ` on the selected rows), with the
/// momentum drift subtracted first when h ≠ 0. Allocates (controller use).
///
/// # Errors
/// As [`space::generalized_jacobian`]; a singular damped system.
#[allow(clippy::too_many_arguments)]
pub fn resolved_rate(
    model: &Model,
    data: &mut Data,
    sd: &mut SpaceData,
    q: &DVector<f64>,
    frame: FrameIndex,
    rows: &[usize],
    xdot: &[f64],
    h: &Force,
    damping: f64,
) -> Result<DVector<f64>> {
    space::generalized_jacobian(model, data, sd, q, frame)?;
    let d = space::momentum_drift(sd, h);
    let m = rows.len();
    let j = DMatrix::from_fn(m, sd.n, |i, k| sd.generalized_jacobian[(rows[i], k)]);
    let e = DVector::from_fn(m, |i, _| xdot[i] - d[rows[i]]);
    let a = &j * j.transpose() + DMatrix::identity(m, m) * (damping * damping);
    let y = a.cholesky().ok_or_else(|| Error::Singular {
        what: "J* J*ᵀ + λ² 1".into(),
        detail: None,
    })?;
    Ok(j.transpose() * y.solve(&e))
}

/// End-effector control of a free-floating arm at the velocity level (joint-rate servos,
/// the base floating): `ẋ_d = K (p_target − p_f)` on the frame position, joint rates
/// `q̇_m = J*⁺ (ẋ_d − d)` through the generalized Jacobian.
#[derive(Clone, Debug, PartialEq)]
pub struct ResolvedRateControl {
    /// Frame position goal (world, m).
    pub target: Vector3<f64>,
    /// Gain K (1/s).
    pub gain: f64,
    /// Damped-least-squares λ (0: plain pseudo-inverse).
    pub damping: f64,
    /// Cancel the momentum drift d with the measured attitude (the chapter's
    /// decoupling 5.145): the closed loop then behaves as a fixed-base arm's. Without it
    /// the drift of a non-zero momentum is an unmodelled disturbance.
    pub drift_compensation: bool,
    /// For a redundant arm, choose the null-space motion that makes the base angular
    /// velocity as small as possible (reaction null space):
    /// `q̇ = J*⁺ ẋ + N z`, `z = −(W N)⁺ W J*⁺ ẋ` with W the joint-rate → base-ω map
    /// (the pseudo-inverse damped with μ = 1e-3 so that it stays smooth). Use with
    /// `damping = 0`, so that N is an exact null-space projector.
    pub reaction_null_space: bool,
}

/// The capture of a target body during a run.
#[derive(Clone, Debug, PartialEq)]
pub struct CaptureEvent {
    /// Capture time (s).
    pub time: f64,
    /// The target (its CoM and inertia in the grasp frame at that time).
    pub target: TargetBody,
}

/// Settings of a free-floating run ([`run`]).
#[derive(Clone, Debug)]
pub struct FloatingSettings {
    /// Frame recorded (and controlled / used for the capture).
    pub frame: FrameIndex,
    /// Simulated time (s).
    pub duration: f64,
    /// Recording interval (s).
    pub record_interval: f64,
    /// RK4 with step dt (quaternion projected after each step) or adaptive DOP853
    /// (`rtol`, `atol`).
    pub integrator: IntegratorSettings,
    /// Joint-torque profiles (torque-driven runs; empty: zero torque).
    pub torque: Vec<ChannelProfile>,
    /// Viscous joint damping (N·m·s/rad), e.g. to stabilise after a capture.
    pub joint_damping: f64,
    /// Velocity-level control (a kinematic run: joint rates commanded, the base from
    /// momentum conservation). Excludes torques and capture.
    pub control: Option<ResolvedRateControl>,
    /// A capture during a torque-driven run.
    pub capture: Option<CaptureEvent>,
}

/// Report of a capture in a run.
#[derive(Clone, Debug)]
pub struct CaptureReport {
    /// Capture time (s).
    pub time: f64,
    /// Total momentum at the world origin before (robot + target) and after.
    pub momentum_before: Force,
    /// After.
    pub momentum_after: Force,
    /// The combined model.
    pub model: Model,
}

/// A recorded free-floating run.
#[derive(Clone, Debug)]
pub struct FloatingRun {
    /// Samples (state, momentum, CoM).
    pub samples: Vec<FloatingSample>,
    /// Position of the recorded frame (world) at each sample.
    pub frame_positions: Vec<Vector3<f64>>,
    /// Momentum monitor of each phase (one phase; two with a capture).
    pub drift: Vec<MomentumDrift>,
    /// The capture, if any.
    pub capture: Option<CaptureReport>,
    /// Accepted integration steps.
    pub steps: usize,
    /// Right-hand-side evaluations.
    pub rhs_evals: usize,
}

/// Joint rates of the resolved-rate law at q (see [`ResolvedRateControl`]).
///
/// # Errors
/// As [`space::generalized_jacobian`]; a singular least-squares system.
pub fn control_rates(
    model: &Model,
    data: &mut Data,
    sd: &mut SpaceData,
    q: &DVector<f64>,
    frame: FrameIndex,
    ctl: &ResolvedRateControl,
    h: &Force,
) -> Result<DVector<f64>> {
    space::generalized_jacobian(model, data, sd, q, frame)?;
    // only the joints that move the frame are commanded (e.g. not a gripper's fingers);
    // the others keep a zero rate
    let mut cols = Vec::with_capacity(sd.n);
    let mut j = model.frames[frame.0].parent_joint.0;
    while j > 1 {
        for k in 0..model.nvs[j] {
            cols.push(model.idx_v[j] + k - 6);
        }
        j = model.parents[j].0;
    }
    cols.sort_unstable();
    let n = cols.len();
    let d = if ctl.drift_compensation {
        space::momentum_drift(sd, h)
    } else {
        nalgebra::Vector6::zeros()
    };
    let xd = (ctl.target - sd.frame_position) * ctl.gain;
    let jm = DMatrix::from_fn(3, n, |i, k| sd.generalized_jacobian[(i, cols[k])]);
    let e = nalgebra::DVector::from_fn(3, |i, _| xd[i] - d[i]);
    let pinv = |m: &DMatrix<f64>, lambda: f64| -> Result<DMatrix<f64>> {
        if lambda > 0.0 {
            let r = m.nrows();
            let a = m * m.transpose() + DMatrix::identity(r, r) * (lambda * lambda);
            let c = a.cholesky().ok_or_else(|| Error::Singular {
                what: "damped J* J*ᵀ".into(),
                detail: None,
            })?;
            Ok(m.transpose() * c.inverse())
        } else {
            crate::linalg::pseudo_inverse(m, 1e-12).ok_or_else(|| Error::Singular {
                what: "J* pseudo-inverse".into(),
                detail: Some(
                    "not finite, or its singular value decomposition did not converge".into(),
                ),
            })
        }
    };
    let jp = pinv(&jm, ctl.damping)?;
    let mut qc = &jp * &e;
    if ctl.reaction_null_space && n > 3 {
        // W: base angular velocity per joint rate at zero momentum, −G_ang
        let w = DMatrix::from_fn(3, n, |i, k| -sd.centroidal_map[(3 + i, cols[k])]);
        let nmat = DMatrix::identity(n, n) - &jp * &jm;
        let wn = &w * &nmat;
        // damped (μ = 1e-3) so the term stays smooth where W N loses rank
        let a = &wn * wn.transpose() + DMatrix::identity(3, 3) * 1e-6;
        let c = a.cholesky().ok_or_else(|| Error::Singular {
            what: "reaction null space".into(),
            detail: None,
        })?;
        let z = -(wn.transpose() * c.solve(&(&w * &qc)));
        qc += nmat * z;
    }
    let mut qd = DVector::zeros(sd.n);
    for (k, &c) in cols.iter().enumerate() {
        qd[c] = qc[k];
    }
    Ok(qd)
}

/// The kinematic free-floating system under a resolved-rate law: state q, joint rates
/// from the law, base twist from the (constant) momentum.
struct KinematicOde<'a> {
    model: &'a Model,
    data: Data,
    sd: SpaceData,
    q: DVector<f64>,
    frame: FrameIndex,
    ctl: ResolvedRateControl,
    h: Force,
}

impl OdeSystem for KinematicOde<'_> {
    fn dim(&self) -> usize {
        self.model.nq
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<()> {
        self.q.as_mut_slice().copy_from_slice(x);
        normalize_base_quaternion(self.q.as_mut_slice());
        let qd = control_rates(
            self.model,
            &mut self.data,
            &mut self.sd,
            &self.q,
            self.frame,
            &self.ctl,
            &self.h,
        )
        .map_err(|e| e.singular_at_time(t))?;
        space::base_velocity(
            self.model,
            &mut self.data,
            &mut self.sd,
            &self.q,
            qd.as_slice(),
            &self.h,
        )?;
        configuration_rate(&self.q, x, self.sd.v.as_slice(), dx);
        Ok(())
    }
}

/// The step budget of a whole free-floating run (every phase, every recording
/// interval), with what its error names.
struct RunBudget {
    budget: StepBudget,
    integrator: IntegratorSettings,
    duration: f64,
}

impl RunBudget {
    fn new(settings: &FloatingSettings) -> Self {
        Self {
            budget: StepBudget::new(settings.integrator.step_budget()),
            integrator: settings.integrator,
            duration: settings.duration,
        }
    }

    fn exhausted(&self, t: f64) -> Error {
        let method = match self.integrator {
            IntegratorSettings::Rk4 { .. } => "RK4",
            IntegratorSettings::Adaptive { .. } => "DOP853",
        };
        budget_exhausted(method, &self.integrator, &self.budget, t, self.duration)
    }
}

/// Integrates `sys` from `(t, x)` to `te`: RK4 in equal steps no longer than dt (then
/// the quaternion projection), or DOP853; every step is charged to the run's `budget`.
fn advance<S: OdeSystem>(
    sys: &mut S,
    integ: &mut Integrator,
    t: &mut f64,
    x: &mut [f64],
    te: f64,
    budget: &mut RunBudget,
) -> Result<()> {
    match integ {
        Integrator::Rk4(rk, dt) => {
            let span = te - *t;
            if span <= 0.0 {
                return Ok(());
            }
            // (a float too large for usize saturates, and no budget takes it)
            let steps = (span / *dt - 1e-9).ceil().max(1.0) as usize;
            if !budget.budget.take(steps) {
                return Err(budget.exhausted(*t));
            }
            let h = span / steps as f64;
            for k in 0..steps {
                rk.step(sys, *t + k as f64 * h, x, h)?;
                normalize_base_quaternion(x);
            }
            *t = te;
            Ok(())
        }
        Integrator::Adaptive(dp) => {
            if dp.integrate_to_within(sys, t, x, te, &mut budget.budget)? {
                Ok(())
            } else {
                Err(budget.exhausted(*t))
            }
        }
    }
}

enum Integrator {
    Rk4(Rk4, f64),
    Adaptive(Box<Dop853>),
}

impl Integrator {
    fn new(settings: &IntegratorSettings, n: usize) -> Result<Self> {
        settings.validate()?;
        Ok(match *settings {
            IntegratorSettings::Rk4 { dt, .. } => Integrator::Rk4(Rk4::new(n), dt),
            IntegratorSettings::Adaptive {
                rtol,
                atol,
                max_step,
                ..
            } => {
                let mut o = AdaptiveOptions::with_tolerance(rtol);
                o.atol = atol;
                if let Some(m) = max_step {
                    o.max_step = m;
                }
                Integrator::Adaptive(Box::new(Dop853::new(n, o)?))
            }
        })
    }
    fn stats(&self) -> (usize, usize) {
        match self {
            Integrator::Rk4(rk, _) => (rk.stats.accepted, rk.stats.rhs_evals),
            Integrator::Adaptive(dp) => (dp.stats.accepted, dp.stats.rhs_evals),
        }
    }
}

fn record(
    model: &Model,
    data: &mut Data,
    frame: FrameIndex,
    t: f64,
    x: &[f64],
    run: &mut FloatingRun,
) {
    let s = sample(model, data, t, x);
    crate::kinematics::frames_forward_kinematics(model, data, &s.q);
    run.frame_positions
        .push(data.world_from_frame[frame.0].translation);
    run.samples.push(s);
}

/// Runs a free-floating simulation from `(q0, v0)` (v0: the whole generalized velocity,
/// e.g. from [`space::base_velocity`]).
///
/// # Errors
/// Bad settings (non-positive duration or interval, too many samples, a capture outside
/// the run or together with control), and everything the integration can raise.
pub fn run(
    model: &Model,
    q0: &DVector<f64>,
    v0: &DVector<f64>,
    settings: &FloatingSettings,
) -> Result<FloatingRun> {
    check_free_flyer(model)?;
    check_initial_state(model, q0, v0)?;
    let nrec = check_run_length(settings)?;
    check_drive(model, settings)?;
    let times = record_times(settings, nrec);
    let mut run = FloatingRun {
        samples: Vec::with_capacity(times.len()),
        frame_positions: Vec::with_capacity(times.len()),
        drift: Vec::new(),
        capture: None,
        steps: 0,
        rhs_evals: 0,
    };
    let mut q = q0.clone();
    normalize_base_quaternion(q.as_mut_slice());
    let mut budget = RunBudget::new(settings);
    match &settings.control {
        Some(ctl) => run_controlled(model, &q, v0, ctl, settings, &times, &mut run, &mut budget)?,
        None => run_torque_driven(model, &q, v0, settings, &times, &mut run, &mut budget)?,
    }
    Ok(run)
}

/// The initial state's lengths and finiteness.
fn check_initial_state(model: &Model, q0: &DVector<f64>, v0: &DVector<f64>) -> Result<()> {
    crate::error::ensure_len("initial.q", model.nq, q0.len())?;
    crate::error::ensure_len("initial.v", model.nv, v0.len())?;
    crate::error::ensure_finite("initial.q", q0.iter())?;
    crate::error::ensure_finite("initial.v", v0.iter())
}

/// Checks the duration, the recording interval and the step budget; returns the number
/// of recording intervals, `⌈duration / record_interval⌉`.
fn check_run_length(settings: &FloatingSettings) -> Result<f64> {
    let (dur, dt_rec) = (settings.duration, settings.record_interval);
    if !(dur.is_finite() && dur > 0.0) {
        return Err(Error::invalid("duration", "must be positive and finite"));
    }
    if !(dt_rec.is_finite() && dt_rec > 0.0) {
        return Err(Error::invalid(
            "output.record_interval",
            "must be positive and finite",
        ));
    }
    let nrec = (dur / dt_rec).ceil();
    if nrec > 1e7 {
        return Err(Error::invalid(
            "output.record_interval",
            format!("{nrec} samples exceed 1e7"),
        ));
    }
    if matches!(settings.integrator, IntegratorSettings::Rk4 { dt, .. } if dt > 0.0) {
        check_rk4_budget(&settings.integrator, dur)?;
    }
    Ok(nrec)
}

/// Checks what drives the run: the torque profiles, the joint damping, the capture
/// (inside the run, not with control) and the control gains.
fn check_drive(model: &Model, settings: &FloatingSettings) -> Result<()> {
    let dur = settings.duration;
    if !settings.torque.is_empty() {
        crate::error::ensure_len("inputs", model.nv - 6, settings.torque.len())?;
        for (k, p) in settings.torque.iter().enumerate() {
            p.validate(&format!("inputs[{k}]"))?;
        }
    }
    if !(settings.joint_damping.is_finite() && settings.joint_damping >= 0.0) {
        return Err(Error::invalid(
            "joint_damping",
            "must be finite and not negative",
        ));
    }
    if let Some(c) = &settings.capture {
        if settings.control.is_some() {
            return Err(Error::invalid(
                "capture",
                "a capture runs with torque-driven dynamics, not with control",
            ));
        }
        if !(c.time.is_finite() && c.time > 0.0 && c.time < dur) {
            return Err(Error::invalid(
                "capture.time",
                format!("must lie inside (0, {dur})"),
            ));
        }
    }
    if let Some(c) = &settings.control
        && !(c.gain.is_finite() && c.gain > 0.0 && c.damping.is_finite() && c.damping >= 0.0)
    {
        return Err(Error::invalid(
            "control",
            "gain must be positive, damping not negative",
        ));
    }
    Ok(())
}

/// The recording times `k · record_interval` (k = 0 ..= nrec), the last clamped to the
/// duration.
fn record_times(settings: &FloatingSettings, nrec: f64) -> Vec<f64> {
    (0..=nrec as usize)
        .map(|k| (k as f64 * settings.record_interval).min(settings.duration))
        .collect()
}

/// A kinematic run under resolved-rate control from the normalised `q`: the momentum
/// of `(q, v0)` is kept, and every sample records the commanded velocity.
fn run_controlled(
    model: &Model,
    q: &DVector<f64>,
    v0: &DVector<f64>,
    ctl: &ResolvedRateControl,
    settings: &FloatingSettings,
    times: &[f64],
    run: &mut FloatingRun,
    budget: &mut RunBudget,
) -> Result<()> {
    let mut data = Data::new(model);
    let h = space::momentum(model, &mut data, q, v0);
    let mut ode = KinematicOde {
        model,
        data: Data::new(model),
        sd: SpaceData::new(model)?,
        q: q.clone(),
        frame: settings.frame,
        ctl: ctl.clone(),
        h,
    };
    let mut integ = Integrator::new(&settings.integrator, model.nq)?;
    let mut x: Vec<f64> = q.iter().copied().collect();
    let mut t = 0.0;
    let mut sd = SpaceData::new(model)?;
    for &te in times {
        advance(&mut ode, &mut integ, &mut t, &mut x, te, budget)?;
        // the recorded velocity is the commanded one
        let mut qn = DVector::from_column_slice(&x);
        normalize_base_quaternion(qn.as_mut_slice());
        let qd = control_rates(model, &mut data, &mut sd, &qn, settings.frame, ctl, &h)?;
        space::base_velocity(model, &mut data, &mut sd, &qn, qd.as_slice(), &h)?;
        let xs: Vec<f64> = x.iter().chain(sd.v.iter()).copied().collect();
        record(model, &mut data, settings.frame, te, &xs, run);
    }
    run.drift
        .push(momentum_drift(&run.samples, model.total_mass()));
    (run.steps, run.rhs_evals) = integ.stats();
    Ok(())
}

/// One torque-driven phase of a run (before the capture, or after it with the target
/// joined to the model).
struct Phase {
    /// The model of this phase.
    model: Model,
    /// Index of the phase's first sample in the run.
    first_sample: usize,
}

/// A torque-driven run from the normalised `q`, in one phase, or in two split at the
/// capture.
fn run_torque_driven(
    model: &Model,
    q: &DVector<f64>,
    v0: &DVector<f64>,
    settings: &FloatingSettings,
    times: &[f64],
    run: &mut FloatingRun,
    budget: &mut RunBudget,
) -> Result<()> {
    let mut x: Vec<f64> = q.iter().chain(v0.iter()).copied().collect();
    let mut t = 0.0;
    let split = settings.capture.as_ref().map(|c| c.time);
    let mut phase = Phase {
        model: model.clone(),
        first_sample: 0,
    };
    let mut k = 0usize;
    loop {
        let end = match (split, run.capture.is_none()) {
            (Some(tc), true) => tc,
            _ => settings.duration,
        };
        integrate_phase(
            &phase, settings, times, &mut k, end, &mut t, &mut x, run, budget,
        )?;
        match (&settings.capture, run.capture.is_none()) {
            (Some(c), true) => phase = capture_phase(&phase.model, settings, c, t, &mut x, run)?,
            _ => break,
        }
    }
    Ok(())
}

/// Integrates `phase` from `(t, x)` to `end`, recording at the times `times[*k..]` that
/// are not after `end`, and adds its step counts and momentum drift to `run`.
fn integrate_phase(
    phase: &Phase,
    settings: &FloatingSettings,
    times: &[f64],
    k: &mut usize,
    end: f64,
    t: &mut f64,
    x: &mut [f64],
    run: &mut FloatingRun,
    budget: &mut RunBudget,
) -> Result<()> {
    let mut ode = FreeFloatingOde::new(&phase.model)?;
    ode.profiles = settings.torque.clone();
    ode.joint_damping = settings.joint_damping;
    let mut integ = Integrator::new(&settings.integrator, x.len())?;
    let mut pdata = Data::new(&phase.model);
    while *k < times.len() && times[*k] <= end {
        advance(&mut ode, &mut integ, t, x, times[*k], budget)?;
        record(&phase.model, &mut pdata, settings.frame, times[*k], x, run);
        *k += 1;
    }
    advance(&mut ode, &mut integ, t, x, end, budget)?;
    let (s, r) = integ.stats();
    run.steps += s;
    run.rhs_evals += r;
    run.drift.push(momentum_drift(
        &run.samples[phase.first_sample..],
        phase.model.total_mass(),
    ));
    Ok(())
}

/// The capture `c` at time `t` on the state `x` of a run on `model`: `x` jumps to the
/// post-capture state, which starts the record of the returned second phase, and the
/// capture is reported in `run`.
fn capture_phase(
    model: &Model,
    settings: &FloatingSettings,
    c: &CaptureEvent,
    t: f64,
    x: &mut [f64],
    run: &mut FloatingRun,
) -> Result<Phase> {
    let nq = model.nq;
    let mut qc = DVector::from_column_slice(&x[..nq]);
    normalize_base_quaternion(qc.as_mut_slice());
    let vc = DVector::from_column_slice(&x[nq..]);
    let cap = capture(model, &qc, &vc, settings.frame, &c.target)?;
    x[..nq].copy_from_slice(qc.as_slice());
    x[nq..].copy_from_slice(cap.v.as_slice());
    let phase = Phase {
        model: cap.model.clone(),
        first_sample: run.samples.len(),
    };
    // the state just after the capture starts the second phase's record
    record(
        &phase.model,
        &mut Data::new(&phase.model),
        settings.frame,
        t,
        x,
        run,
    );
    run.capture = Some(CaptureReport {
        time: c.time,
        momentum_before: cap.momentum_before,
        momentum_after: cap.momentum_after,
        model: cap.model,
    });
    Ok(phase)
}

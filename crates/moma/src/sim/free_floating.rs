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
use crate::sim::{AdaptiveOptions, Dop853, OdeSystem, Rk4};
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
    /// Joint torques τ (nv − 6), held constant between changes.
    pub torque: DVector<f64>,
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

    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<()> {
        let (nq, nv) = (self.model.nq, self.model.nv);
        self.q.as_mut_slice().copy_from_slice(&x[..nq]);
        normalize_base_quaternion(self.q.as_mut_slice());
        self.v.as_mut_slice().copy_from_slice(&x[nq..]);
        self.tau.as_mut_slice()[6..].copy_from_slice(self.torque.as_slice());
        let ddq = aba(self.model, &mut self.data, &self.q, &self.v, &self.tau);
        dx[nq..].copy_from_slice(ddq.as_slice());
        let rot = base_attitude(&self.q).to_rotation_matrix().into_inner();
        let vl = Vector3::new(x[nq], x[nq + 1], x[nq + 2]);
        let w = Vector3::new(x[nq + 3], x[nq + 4], x[nq + 5]);
        let pd = rot * vl;
        dx[0] = pd.x;
        dx[1] = pd.y;
        dx[2] = pd.z;
        // ½ quat ⊗ (ω, 0) on the state's own quaternion (keeps its norm)
        let (ax, ay, az, aw) = (x[3], x[4], x[5], x[6]);
        dx[3] = 0.5 * (aw * w.x + ay * w.z - az * w.y);
        dx[4] = 0.5 * (aw * w.y + az * w.x - ax * w.z);
        dx[5] = 0.5 * (aw * w.z + ax * w.y - ay * w.x);
        dx[6] = -0.5 * (ax * w.x + ay * w.y + az * w.z);
        dx[7..nq].copy_from_slice(&x[nq + 6..nq + nv]);
        Ok(())
    }
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

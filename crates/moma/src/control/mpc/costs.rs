//! The MPC's costs: base path tracking, end-effector pose tracking (position and
//! orientation, while the base moves), effort (accelerations, velocities) and a posture
//! regulariser; each a weighted sum of squared residuals `Σ w r²` with the Gauss–Newton
//! gradient `2 w Jᵀ r` and Hessian `2 w Jᵀ J`.

use nalgebra::{DVector, Matrix3, Vector3};

use super::problem::StageModel;
use super::robot::{KnotValues, MpcRobot};
use crate::kinematics::wrap_angle;
use crate::spatial::log3;

/// Weights of the costs (each multiplies a squared residual in SI units).
#[derive(Clone, Debug)]
pub struct CostWeights {
    /// Base position error (1/m²).
    pub base_position: f64,
    /// Base heading error (1/rad²).
    pub base_yaw: f64,
    /// End-effector position error, where a target is set (1/m²).
    pub ee_position: f64,
    /// End-effector orientation error (1/rad²).
    pub ee_orientation: f64,
    /// Platform velocities `(v, ω)`.
    pub platform_velocity: f64,
    /// Joint velocities.
    pub joint_velocity: f64,
    /// Platform accelerations `(v̇, ω̇)` (the effort of the wheels).
    pub platform_acceleration: f64,
    /// Joint accelerations (the effort of the arm).
    pub joint_acceleration: f64,
    /// Moved joints' distance to the posture.
    pub posture: f64,
    /// Factor of the state costs at the last knot.
    pub terminal: f64,
}

impl Default for CostWeights {
    fn default() -> Self {
        Self {
            base_position: 50.0,
            base_yaw: 5.0,
            ee_position: 200.0,
            ee_orientation: 5.0,
            platform_velocity: 0.1,
            joint_velocity: 0.5,
            platform_acceleration: 0.05,
            joint_acceleration: 0.02,
            posture: 0.2,
            terminal: 5.0,
        }
    }
}

/// The reference at one knot.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct KnotReference {
    /// Base pose `[x, y, θ]` on the path.
    pub base: [f64; 3],
    /// End-effector target (position, orientation), if any at this knot.
    pub end_effector: Option<(Vector3<f64>, Matrix3<f64>)>,
}

impl Default for KnotReference {
    fn default() -> Self {
        Self {
            base: [0.0; 3],
            end_effector: None,
        }
    }
}

/// Adds one squared residual `w r²` with gradient row `jx` (over x) and `ju` (over u).
fn add_term(out: &mut StageModel, w: f64, r: f64, jx: &[(usize, f64)], ju: &[(usize, f64)]) -> f64 {
    for &(i, a) in jx {
        out.lx[i] += 2.0 * w * r * a;
        for &(j, b) in jx {
            out.lxx[(i, j)] += 2.0 * w * a * b;
        }
    }
    for &(i, a) in ju {
        out.lu[i] += 2.0 * w * r * a;
        for &(j, b) in ju {
            out.luu[(i, j)] += 2.0 * w * a * b;
        }
        for &(j, b) in jx {
            out.lux[(i, j)] += 2.0 * w * a * b;
        }
    }
    w * r * r
}

/// The cost of knot `(x, u)` (terminal when `u` is `None`) with the knot's evaluated
/// values `vals`; with `out`, also adds its gradient and Gauss–Newton Hessian.
#[allow(clippy::too_many_arguments)]
pub fn knot_cost(
    robot: &MpcRobot,
    w: &CostWeights,
    reference: &KnotReference,
    posture: &DVector<f64>,
    x: &DVector<f64>,
    u: Option<&DVector<f64>>,
    vals: &KnotValues,
    mut out: Option<&mut StageModel>,
) -> f64 {
    let n = robot.n_moved();
    let f = if u.is_none() { w.terminal } else { 1.0 };
    let mut cost = 0.0;
    let mut add = |w: f64, r: f64, jx: &[(usize, f64)], ju: &[(usize, f64)]| {
        if w == 0.0 {
            return;
        }
        cost += match out.as_deref_mut() {
            Some(o) => add_term(o, w, r, jx, ju),
            None => w * r * r,
        };
    };
    // Base path.
    add(
        f * w.base_position,
        x[0] - reference.base[0],
        &[(0, 1.0)],
        &[],
    );
    add(
        f * w.base_position,
        x[1] - reference.base[1],
        &[(1, 1.0)],
        &[],
    );
    add(
        f * w.base_yaw,
        wrap_angle(x[2] - reference.base[2]),
        &[(2, 1.0)],
        &[],
    );
    // End effector: position error and the rotation error R_ref log(R_refᵀ R) (world),
    // whose Jacobian is taken as the angular rows (exact at the target).
    if let Some((p_ref, r_ref)) = &reference.end_effector {
        let ee = &vals.end_effector;
        let ep = ee.translation - p_ref;
        let eo = r_ref * log3(&(r_ref.transpose() * ee.rotation));
        let jac = &vals.end_effector_dx;
        let cols = robot.dofs.len() + 3;
        let mut row = [(0usize, 0.0f64); 32];
        for (a, (e, wgt)) in [
            (ep.x, w.ee_position),
            (ep.y, w.ee_position),
            (ep.z, w.ee_position),
            (eo.x, w.ee_orientation),
            (eo.y, w.ee_orientation),
            (eo.z, w.ee_orientation),
        ]
        .into_iter()
        .enumerate()
        {
            let m = cols.min(row.len());
            for (c, slot) in row.iter_mut().enumerate().take(m) {
                *slot = (c, jac[(a, c)]);
            }
            add(f * wgt, e, &row[..m], &[]);
        }
    }
    // Effort and regularisation.
    add(w.platform_velocity, x[3 + n], &[(3 + n, 1.0)], &[]);
    add(w.platform_velocity, x[4 + n], &[(4 + n, 1.0)], &[]);
    for i in 0..n {
        add(w.joint_velocity, x[5 + n + i], &[(5 + n + i, 1.0)], &[]);
        add(f * w.posture, x[3 + i] - posture[i], &[(3 + i, 1.0)], &[]);
    }
    if let Some(u) = u {
        add(w.platform_acceleration, u[0], &[], &[(0, 1.0)]);
        add(w.platform_acceleration, u[1], &[], &[(1, 1.0)]);
        for i in 0..n {
            add(w.joint_acceleration, u[2 + i], &[], &[(2 + i, 1.0)]);
        }
    }
    cost
}

//! The arm's references in the loop: a `[task]`'s planned joint-space motion
//! ([`ArmMotion`], one per [`ArmStage`] of the pick) and the reach phase's minimum-jerk
//! segment of the end effector ([`EeTrajectory`]).

use nalgebra::Vector3;

/// The arm motions of a pick, in order.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
pub(super) enum ArmStage {
    /// To the pre-grasp.
    Approach,
    /// From the pre-grasp to the grasp.
    Grasp,
    /// With the object, straight up off its support.
    Lift,
    /// With the object, back to the transport posture.
    Retreat,
}

impl ArmStage {
    /// The phase's name in the record: `approach`, `grasp`, `lift`, `retreat`.
    pub(super) fn name(self) -> &'static str {
        match self {
            ArmStage::Approach => "approach",
            ArmStage::Grasp => "grasp",
            ArmStage::Lift => "lift",
            ArmStage::Retreat => "retreat",
        }
    }
}

/// An arm motion being tracked: its trajectory from `t0` and its last state.
pub(super) struct ArmMotion {
    pub(super) t0: f64,
    pub(super) trajectory: crate::motion::MotionTrajectory,
}

impl ArmMotion {
    /// The group's reference (q, q̇, q̈) at mission time `t` (linear between samples;
    /// q̈ the difference of the bracketing rates), written into `q` (full configuration),
    /// `qd` and `qdd` (group order).
    pub(super) fn at(
        &self,
        t: f64,
        group: &crate::motion::JointGroup,
        q: &mut [f64],
        qd: &mut [f64],
        qdd: &mut [f64],
    ) {
        let tr = &self.trajectory;
        let s = (t - self.t0).clamp(0.0, tr.duration);
        let n = tr.t.len();
        if n < 2 {
            q.copy_from_slice(&tr.q[0]);
            qd.fill(0.0);
            qdd.fill(0.0);
            return;
        }
        let k = tr.t.partition_point(|&ti| ti <= s).clamp(1, n - 1);
        let (a, b) = (k - 1, k);
        let h = (tr.t[b] - tr.t[a]).max(f64::MIN_POSITIVE);
        let w = ((s - tr.t[a]) / h).clamp(0.0, 1.0);
        q.copy_from_slice(&tr.q[a]);
        for (j, &i) in group.q_index.iter().enumerate() {
            q[i] = tr.q[a][i] + w * (tr.q[b][i] - tr.q[a][i]);
            let (va, vb) = (tr.qd[a][j], tr.qd[b][j]);
            if t - self.t0 >= tr.duration {
                qd[j] = 0.0;
                qdd[j] = 0.0;
            } else {
                qd[j] = va + w * (vb - va);
                qdd[j] = (vb - va) / h;
            }
        }
    }

    /// The last state of the trajectory (full configuration).
    pub(super) fn last(&self) -> &[f64] {
        self.trajectory.q.last().expect("a trajectory has samples")
    }
}

/// Minimum-jerk point-to-point segment of the end effector.
#[derive(Clone, Copy, Debug)]
pub(super) struct EeTrajectory {
    pub(super) t0: f64,
    pub(super) duration: f64,
    pub(super) from: Vector3<f64>,
    pub(super) to: Vector3<f64>,
}

impl EeTrajectory {
    pub(super) fn at(&self, t: f64) -> (Vector3<f64>, Vector3<f64>, Vector3<f64>) {
        let s = ((t - self.t0) / self.duration).clamp(0.0, 1.0);
        let d = self.to - self.from;
        let (p, dp, ddp) = if t - self.t0 >= self.duration {
            (1.0, 0.0, 0.0)
        } else {
            (
                s * s * s * (10.0 - 15.0 * s + 6.0 * s * s),
                30.0 * s * s * (1.0 - s) * (1.0 - s) / self.duration,
                60.0 * s * (1.0 - 3.0 * s + 2.0 * s * s) / (self.duration * self.duration),
            )
        };
        (self.from + d * p, d * dp, d * ddp)
    }
}

//! Goal states for a goal pose: inverse kinematics of a frame over the group's joints
//! only (the other joints stay at the start), within the planning box, from seeded
//! restarts, each solution kept only if it is collision-free.
//!
//! The solver is [`crate::ik::solve`] (damped least squares, joints clamped to the box)
//! on the full 6-D pose error; a solution counts when its position error is within the
//! position tolerance and its rotation angle error within the orientation tolerance. The
//! first seed is the start state, the next ones are uniform in the box (ChaCha8, seeded).

use super::group::JointGroup;
use crate::ik::tasks::{FrameKinematics, PoseTask, TaskRows, pose_error};
use crate::ik::{IkOptions, IkWorkspace, KinematicTask, solve};
use crate::kinematics::{self, ReferenceFrame};
use crate::multibody::{Data, FrameIndex, Model};
use crate::planning::StateValidity;
use crate::{Error, Result};
use nalgebra::{DMatrix, DVector, Isometry3, Matrix6xX};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// A goal pose of a frame with tolerances.
#[derive(Clone, Debug, PartialEq)]
pub struct GoalPose {
    /// The frame that must reach the pose.
    pub frame: FrameIndex,
    /// The pose in the model's world frame.
    pub target: Isometry3<f64>,
    /// The largest distance of the frame's origin from the target's (m), > 0.
    pub position_tolerance: f64,
    /// The largest rotation angle between the frame and the target (rad), > 0.
    pub orientation_tolerance: f64,
}

impl GoalPose {
    /// The position error (m) and rotation angle error (rad) of `pose`.
    #[must_use]
    pub fn errors(&self, pose: &Isometry3<f64>) -> (f64, f64) {
        let e = pose_error(pose, &self.target);
        (
            (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt(),
            (e[3] * e[3] + e[4] * e[4] + e[5] * e[5]).sqrt(),
        )
    }

    /// Whether `pose` is within both tolerances.
    #[must_use]
    pub fn accepts(&self, pose: &Isometry3<f64>) -> bool {
        let (p, r) = self.errors(pose);
        p <= self.position_tolerance && r <= self.orientation_tolerance
    }
}

/// The kinematics of one frame over the group's joints (the others fixed).
pub struct GroupFrame<'a> {
    model: &'a Model,
    group: &'a JointGroup,
    frame: FrameIndex,
    q: DVector<f64>,
    data: Data,
    j6: Matrix6xX<f64>,
}

impl<'a> GroupFrame<'a> {
    /// The frame's kinematics over `group`, the other joints at `base` (full `q`).
    #[must_use]
    pub fn new(model: &'a Model, group: &'a JointGroup, frame: FrameIndex, base: &[f64]) -> Self {
        GroupFrame {
            model,
            group,
            frame,
            q: DVector::from_column_slice(base),
            data: Data::new(model),
            j6: Matrix6xX::zeros(model.nv),
        }
    }

    /// The frame's world pose at the group state `x`.
    pub fn pose(&mut self, x: &[f64]) -> Isometry3<f64> {
        self.group.embed(x, self.q.as_mut_slice());
        kinematics::forward_kinematics(self.model, &mut self.data, &self.q);
        kinematics::update_frame_placements(self.model, &mut self.data);
        self.data.world_from_frame[self.frame.0].to_isometry()
    }
}

impl FrameKinematics for GroupFrame<'_> {
    fn nq(&self) -> usize {
        self.group.dim()
    }
    fn nv(&self) -> usize {
        self.group.dim()
    }
    fn pose_and_jacobian(
        &mut self,
        x: &DVector<f64>,
        pose: &mut Isometry3<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<()> {
        self.group.embed(x.as_slice(), self.q.as_mut_slice());
        kinematics::frame_jacobian(
            self.model,
            &mut self.data,
            &self.q,
            self.frame,
            ReferenceFrame::LocalWorldAligned,
            &mut self.j6,
        );
        *pose = self.data.world_from_frame[self.frame.0].to_isometry();
        for (k, &iv) in self.group.q_index.iter().enumerate() {
            for r in 0..6 {
                jacobian[(r, k)] = self.j6[(r, iv)];
            }
        }
        Ok(())
    }
    fn integrate(&self, x: &DVector<f64>, v: &DVector<f64>, out: &mut DVector<f64>) {
        for k in 0..out.len() {
            out[k] = (x[k] + v[k]).clamp(self.group.lower[k], self.group.upper[k]);
        }
    }
    fn blocked_velocities(&self, x: &DVector<f64>, v: &DVector<f64>, blocked: &mut [bool]) {
        for k in 0..v.len() {
            blocked[k] = (x[k] <= self.group.lower[k] + 1e-12 && v[k] < 0.0)
                || (x[k] >= self.group.upper[k] - 1e-12 && v[k] > 0.0);
        }
    }
    fn random_configuration(
        &self,
        _current: &DVector<f64>,
        rng: &mut dyn rand::RngCore,
        out: &mut DVector<f64>,
    ) -> bool {
        for k in 0..out.len() {
            out[k] = self.group.lower[k]
                + (self.group.upper[k] - self.group.lower[k]) * rng.random::<f64>();
        }
        true
    }
}

/// What the goal search found.
#[derive(Clone, Debug, PartialEq)]
pub struct IkGoals {
    /// Collision-free solutions within the tolerances, in the order found.
    pub states: Vec<Vec<f64>>,
    /// IK attempts made (seeds solved from).
    pub attempts: usize,
    /// Attempts that met the tolerances (collision-free or not).
    pub reached: usize,
    /// The smallest position error any attempt ended with (m).
    pub best_position_error: f64,
    /// The smallest rotation error any attempt ended with (rad).
    pub best_orientation_error: f64,
}

/// Searches collision-free IK solutions of `goal` over `group` (module docs): up to
/// `attempts` seeds (the first `start`), stopping once `wanted` distinct solutions are
/// found or `deadline` passes. Solutions closer than 1e-3 (max-norm) to a kept one are
/// dropped.
///
/// # Errors
/// [`Error::InvalidInput`] for tolerances that are not positive; errors of the IK solver.
pub fn ik_goals(
    model: &Model,
    group: &JointGroup,
    base: &[f64],
    goal: &GoalPose,
    validity: &mut impl StateValidity,
    attempts: usize,
    wanted: usize,
    seed: u64,
    deadline: std::time::Instant,
) -> Result<IkGoals> {
    for (field, v) in [
        ("position tolerance", goal.position_tolerance),
        ("orientation tolerance", goal.orientation_tolerance),
    ] {
        if !(v.is_finite() && v > 0.0) {
            return Err(Error::invalid(field, format!("{v} is not positive")));
        }
    }
    let dim = group.dim();
    if let Some(gap) = reach_gap(model, group, goal, base)
        && gap > goal.position_tolerance
    {
        // No attempt can end closer than the gap: unreachable without a search.
        return Ok(IkGoals {
            states: Vec::new(),
            attempts: 0,
            reached: 0,
            best_position_error: gap,
            best_orientation_error: f64::INFINITY,
        });
    }
    let kin = GroupFrame::new(model, group, goal.frame, base);
    let mut task = PoseTask::new(kin, goal.target, &TaskRows::Full)?;
    let options = IkOptions {
        tolerance: 0.5 * goal.position_tolerance.min(goal.orientation_tolerance),
        max_iterations: 100,
        ..IkOptions::default()
    };
    let mut ws = IkWorkspace::new(&task);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut seed_x = DVector::zeros(dim);
    group.extract(base, seed_x.as_mut_slice());
    let mut out = IkGoals {
        states: Vec::new(),
        attempts: 0,
        reached: 0,
        best_position_error: f64::INFINITY,
        best_orientation_error: f64::INFINITY,
    };
    for attempt in 0..attempts {
        if out.states.len() >= wanted || (attempt > 0 && std::time::Instant::now() >= deadline) {
            break;
        }
        if attempt > 0 {
            let current = seed_x.clone();
            task.random_configuration(&current, &mut rng, &mut seed_x);
        }
        out.attempts += 1;
        let r = solve(&mut task, &seed_x, &options, &mut ws)?;
        let pose = task.kinematics.pose(r.q.as_slice());
        let (pe, re) = goal.errors(&pose);
        out.best_position_error = out.best_position_error.min(pe);
        out.best_orientation_error = out.best_orientation_error.min(re);
        if !(pe <= goal.position_tolerance && re <= goal.orientation_tolerance) {
            continue;
        }
        out.reached += 1;
        let x = r.q.as_slice();
        let inside = (0..dim).all(|k| group.lower[k] <= x[k] && x[k] <= group.upper[k]);
        let repeat = out
            .states
            .iter()
            .any(|s| s.iter().zip(x).all(|(a, b)| (a - b).abs() < 1e-3));
        if inside && !repeat && validity.is_valid(x) {
            out.states.push(x.to_vec());
        }
    }
    Ok(out)
}

/// How far (m) the goal position lies beyond every position the group's joints can move
/// the frame to from `base`: its distance from the origin of the topmost group joint on
/// the frame's chain (which that joint's own motion does not move) less the chain's
/// length below it (the joint offsets, the frame's offset, each prismatic joint's largest
/// travel: the box for group joints, `base` for the others). `None` when no group joint
/// moves the frame or a joint below it is neither revolute nor prismatic.
fn reach_gap(model: &Model, group: &JointGroup, goal: &GoalPose, base: &[f64]) -> Option<f64> {
    let frame = &model.frames[goal.frame.0];
    let mut chain = Vec::new();
    let mut j = frame.parent_joint.0;
    while j != 0 {
        chain.push(j);
        j = model.parents[j].0;
    }
    let top = chain
        .iter()
        .rposition(|j| group.joints.iter().any(|g| g.0 == *j))?;
    let mut radius = frame.placement.translation.norm();
    for (i, &j) in chain[..=top].iter().enumerate() {
        let jt = &model.joint_types[j];
        if jt.is_prismatic() {
            let iq = model.idx_q[j];
            radius += match group.joints.iter().position(|g| g.0 == j) {
                Some(k) => group.lower[k].abs().max(group.upper[k].abs()),
                None => base[iq].abs(),
            };
        } else if !jt.is_revolute() {
            return None;
        }
        if i < top {
            radius += model.joint_placements[j].translation.norm();
        }
    }
    let mut data = Data::new(model);
    kinematics::forward_kinematics(model, &mut data, &DVector::from_column_slice(base));
    let first = chain[top];
    let origin = data.world_from_joint[model.parents[first].0]
        .act_point(&model.joint_placements[first].translation);
    let gap = (goal.target.translation.vector - origin).norm() - radius;
    gap.is_finite().then_some(gap)
}

//! [`FrameKinematics`] of one frame of a rigid-body [`Model`]: the bridge between the
//! IK/placement algorithms and the rigid-body core (forward kinematics and
//! `LocalWorldAligned` frame Jacobians).

use super::tasks::FrameKinematics;
use crate::error::{Error, Result, ensure_finite, ensure_len};
use crate::kinematics::{self, ReferenceFrame};
use crate::multibody::{Data, FrameIndex, Model, RootJoint, mount_on_root};
use crate::spatial::SE3;
use nalgebra::{DMatrix, DVector, Isometry3, Matrix6xX};
use std::sync::Arc;

/// One frame of a model with its own [`Data`] workspace (clone it per thread).
#[derive(Clone, Debug)]
pub struct ModelFrame {
    model: Arc<Model>,
    data: Data,
    frame: FrameIndex,
    j6: Matrix6xX<f64>,
}

impl ModelFrame {
    /// The frame `frame` of `model`.
    pub fn new(model: Arc<Model>, frame: FrameIndex) -> Result<Self> {
        if frame.0 >= model.frames.len() {
            return Err(Error::Unknown {
                kind: "frame",
                name: format!("#{}", frame.0),
            });
        }
        let data = Data::new(&model);
        let j6 = Matrix6xX::zeros(model.nv);
        Ok(Self {
            model,
            data,
            frame,
            j6,
        })
    }

    /// The frame named `name` of `model`.
    pub fn by_name(model: Arc<Model>, name: &str) -> Result<Self> {
        let frame = model.frame_id(name)?;
        Self::new(model, frame)
    }

    /// The same frame on the model mounted at `mount` on a planar root
    /// ([`crate::multibody::mount_on_root`]): `q = [x, y, θ, q…]`.
    ///
    /// # Errors
    /// As [`crate::multibody::mount_on_root`] (a model that is not fixed-based, a
    /// non-rigid mount).
    pub fn on_planar_base(&self, mount: &Isometry3<f64>) -> Result<Self> {
        let mounted = mount_on_root(&self.model, RootJoint::Planar, &SE3::from_isometry(mount))?;
        // mount_on_root inserts the root joint's frame at index 1 and shifts the others.
        let frame = if self.frame.0 == 0 {
            0
        } else {
            self.frame.0 + 1
        };
        Self::new(Arc::new(mounted), FrameIndex(frame))
    }

    /// The model.
    pub fn model(&self) -> &Model {
        &self.model
    }

    /// The frame index.
    pub fn frame(&self) -> FrameIndex {
        self.frame
    }

    /// Checks a configuration's length and finiteness (for user input).
    pub fn check_q(&self, field: &str, q: &DVector<f64>) -> Result<()> {
        ensure_len(field, self.model.nq, q.len())?;
        ensure_finite(field, q.iter())
    }

    /// `J̇ q̇` of the frame (classical acceleration at zero joint acceleration,
    /// `LocalWorldAligned`, `[linear; angular]`).
    #[doc(alias = "Jdot_qdot")]
    pub fn jdot_qdot(&mut self, q: &DVector<f64>, v: &DVector<f64>) -> DVector<f64> {
        let a = kinematics::frame_acceleration_bias(
            &self.model,
            &mut self.data,
            q,
            v,
            self.frame,
            ReferenceFrame::LocalWorldAligned,
        );
        DVector::from_vec(vec![
            a.linear.x,
            a.linear.y,
            a.linear.z,
            a.angular.x,
            a.angular.y,
            a.angular.z,
        ])
    }

    /// Index in q of velocity coordinate `k` when its joint has one coordinate each in q
    /// and v (revolute, prismatic); `None` otherwise.
    fn scalar_q_index(&self, k: usize) -> Option<usize> {
        let j = self.model.joint_of_dof[k].0;
        if self.model.nqs[j] == self.model.nvs[j] {
            Some(self.model.idx_q[j] + (k - self.model.idx_v[j]))
        } else {
            None
        }
    }

    /// Number of root coordinates in q (0 fixed, 3 planar, 7 free-flyer).
    fn root_nq(&self) -> usize {
        match self.model.root {
            RootJoint::Fixed => 0,
            RootJoint::Planar => 3,
            RootJoint::FreeFlyer => 7,
        }
    }
}

impl FrameKinematics for ModelFrame {
    fn reach_bound(&self) -> Option<(nalgebra::Vector3<f64>, f64)> {
        let m = &*self.model;
        if m.root != RootJoint::Fixed {
            return None;
        }
        let fr = &m.frames[self.frame.0];
        let mut path = Vec::new();
        let mut j = fr.parent_joint.0;
        while j != 0 {
            path.push(j);
            j = m.parents[j].0;
        }
        let Some(&first) = path.last() else {
            // Frame fixed to the world: it reaches exactly one point.
            let p = fr.placement.translation;
            return Some((p, 0.0));
        };
        let mut radius = fr.placement.translation.norm();
        for &j in &path {
            let jt = &m.joint_types[j];
            if jt.is_prismatic() {
                let iq = m.idx_q[j];
                let travel = m.lower_position_limit[iq]
                    .abs()
                    .max(m.upper_position_limit[iq].abs());
                if !travel.is_finite() {
                    return None;
                }
                radius += travel;
            } else if !jt.is_revolute() {
                return None;
            }
            if j != first {
                radius += m.joint_placements[j].translation.norm();
            }
        }
        Some((m.joint_placements[first].translation, radius))
    }

    fn on_planar_base(&self, mount: &Isometry3<f64>) -> Option<Result<Self>> {
        Some(ModelFrame::on_planar_base(self, mount))
    }
    fn nq(&self) -> usize {
        self.model.nq
    }
    fn nv(&self) -> usize {
        self.model.nv
    }
    fn pose_and_jacobian(
        &mut self,
        q: &DVector<f64>,
        pose: &mut Isometry3<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<()> {
        kinematics::frame_jacobian(
            &self.model,
            &mut self.data,
            q,
            self.frame,
            ReferenceFrame::LocalWorldAligned,
            &mut self.j6,
        );
        *pose = self.data.world_from_frame[self.frame.0].to_isometry();
        jacobian.copy_from(&self.j6);
        Ok(())
    }
    fn integrate(&self, q: &DVector<f64>, v: &DVector<f64>, out: &mut DVector<f64>) {
        kinematics::integrate(&self.model, q, v, out);
        let lo = &self.model.lower_position_limit;
        let hi = &self.model.upper_position_limit;
        for k in self.root_nq()..out.len() {
            if out[k] < lo[k] {
                out[k] = lo[k];
            } else if out[k] > hi[k] {
                out[k] = hi[k];
            }
        }
    }
    fn blocked_velocities(&self, q: &DVector<f64>, v: &DVector<f64>, blocked: &mut [bool]) {
        let lo = &self.model.lower_position_limit;
        let hi = &self.model.upper_position_limit;
        for k in 0..v.len() {
            blocked[k] = match self.scalar_q_index(k) {
                Some(i) if i >= self.root_nq() => {
                    (q[i] <= lo[i] + 1e-12 && v[k] < 0.0) || (q[i] >= hi[i] - 1e-12 && v[k] > 0.0)
                }
                _ => false,
            };
        }
    }
    fn difference(&self, q0: &DVector<f64>, q1: &DVector<f64>, out: &mut DVector<f64>) {
        kinematics::difference(&self.model, q0, q1, out);
    }
    fn random_configuration(
        &self,
        current: &DVector<f64>,
        rng: &mut dyn rand::RngCore,
        out: &mut DVector<f64>,
    ) -> bool {
        let q = kinematics::random_configuration(&self.model, rng);
        out.copy_from(&q);
        for k in 0..self.root_nq() {
            out[k] = current[k];
        }
        true
    }
}

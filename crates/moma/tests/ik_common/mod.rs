//! Shared test fixture: an analytic planar chain implementing `FrameKinematics`.
#![allow(dead_code)]

use moma::ik::tasks::FrameKinematics;
use nalgebra::{DMatrix, DVector, Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::Rng;

/// Planar arm of revolute-z joints; with `mobile`, q = [x, y, θ, q_arm], the arm's first
/// joint `mount` ahead of the base origin.
#[derive(Clone)]
pub struct PlanarChain {
    pub mobile: bool,
    pub mount: f64,
    pub lengths: Vec<f64>,
    pub lower: Vec<f64>,
    pub upper: Vec<f64>,
}

impl PlanarChain {
    pub fn arm(lengths: Vec<f64>) -> Self {
        let n = lengths.len();
        Self {
            mobile: false,
            mount: 0.0,
            lengths,
            lower: vec![-3.0; n],
            upper: vec![3.0; n],
        }
    }
    pub fn off(&self) -> usize {
        if self.mobile { 3 } else { 0 }
    }
    pub fn fk(&self, q: &DVector<f64>) -> Isometry3<f64> {
        let o = self.off();
        let (mut x, mut y, mut a) = if self.mobile {
            (
                q[0] + self.mount * q[2].cos(),
                q[1] + self.mount * q[2].sin(),
                q[2],
            )
        } else {
            (0.0, 0.0, 0.0)
        };
        for (i, l) in self.lengths.iter().enumerate() {
            a += q[o + i];
            x += l * a.cos();
            y += l * a.sin();
        }
        Isometry3::from_parts(
            Translation3::new(x, y, 0.0),
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a),
        )
    }
}

impl FrameKinematics for PlanarChain {
    fn on_planar_base(&self, mount: &Isometry3<f64>) -> Option<moma::Result<Self>> {
        // The chain can only sit on the platform's x axis, facing forward.
        let t = mount.translation.vector;
        if self.mobile || t.y != 0.0 || t.z != 0.0 || mount.rotation.angle() != 0.0 {
            return Some(Err(moma::Error::invalid(
                "mount",
                "the planar chain mounts only on the platform's x axis",
            )));
        }
        Some(Ok(Self {
            mobile: true,
            mount: t.x,
            ..self.clone()
        }))
    }
    fn nq(&self) -> usize {
        self.off() + self.lengths.len()
    }
    fn nv(&self) -> usize {
        self.nq()
    }
    fn pose_and_jacobian(
        &mut self,
        q: &DVector<f64>,
        pose: &mut Isometry3<f64>,
        j: &mut DMatrix<f64>,
    ) -> moma::Result<()> {
        *pose = self.fk(q);
        let pe = pose.translation.vector;
        j.fill(0.0);
        let o = self.off();
        let (mut x, mut y, mut a) = (0.0, 0.0, 0.0);
        if self.mobile {
            j[(0, 0)] = 1.0;
            j[(1, 1)] = 1.0;
            j[(0, 2)] = -(pe.y - q[1]);
            j[(1, 2)] = pe.x - q[0];
            j[(5, 2)] = 1.0;
            x = q[0] + self.mount * q[2].cos();
            y = q[1] + self.mount * q[2].sin();
            a = q[2];
        }
        for (i, l) in self.lengths.iter().enumerate() {
            j[(0, o + i)] = -(pe.y - y);
            j[(1, o + i)] = pe.x - x;
            j[(5, o + i)] = 1.0;
            a += q[o + i];
            x += l * a.cos();
            y += l * a.sin();
        }
        Ok(())
    }
    fn integrate(&self, q: &DVector<f64>, v: &DVector<f64>, out: &mut DVector<f64>) {
        let o = self.off();
        for k in 0..q.len() {
            out[k] = q[k] + v[k];
            if k >= o {
                out[k] = out[k].clamp(self.lower[k - o], self.upper[k - o]);
            }
        }
    }
    fn random_configuration(
        &self,
        current: &DVector<f64>,
        rng: &mut dyn rand::RngCore,
        out: &mut DVector<f64>,
    ) -> bool {
        let o = self.off();
        for k in 0..o {
            out[k] = current[k];
        }
        for i in 0..self.lengths.len() {
            out[o + i] = rng.random_range(self.lower[i]..self.upper[i]);
        }
        true
    }
    fn blocked_velocities(&self, q: &DVector<f64>, v: &DVector<f64>, blocked: &mut [bool]) {
        let o = self.off();
        for i in 0..self.lengths.len() {
            let k = o + i;
            blocked[k] = (q[k] <= self.lower[i] + 1e-12 && v[k] < 0.0)
                || (q[k] >= self.upper[i] - 1e-12 && v[k] > 0.0);
        }
    }
}

//! The general wheeled URDF model ([`crate::mobile::WheeledModel`]) as a
//! [`ReducedSystem`] for the simulator.

use crate::error::Result;
use crate::sim::reduced_system::ReducedSystem;

/// A [`crate::mobile::WheeledModel`] with its workspace, simulated in reduced coordinates
/// `v_r = [v, ω, q̇_arm…]` under inputs `u = [τ_L, τ_R, τ_arm…]`.
#[derive(Debug, Clone)]
pub struct WheeledSystem {
    /// The constrained model.
    pub robot: crate::mobile::WheeledModel,
    /// Its workspace.
    pub data: crate::mobile::WheeledData,
    q: nalgebra::DVector<f64>,
    v: nalgebra::DVector<f64>,
}

impl WheeledSystem {
    /// Wraps `robot`, allocating every buffer once.
    pub fn new(robot: crate::mobile::WheeledModel) -> Self {
        let data = crate::mobile::WheeledData::new(&robot);
        let (nq, nr) = (robot.model.nq, robot.nr());
        Self {
            robot,
            data,
            q: nalgebra::DVector::zeros(nq),
            v: nalgebra::DVector::zeros(nr),
        }
    }

    /// `linear` for a prismatic degree of freedom `i`, `angular` otherwise.
    fn dof_unit(&self, i: usize, linear: &'static str, angular: &'static str) -> &'static str {
        let m = &self.robot.model;
        if m.joint_types[m.joint_of_dof[i].0].is_prismatic() {
            linear
        } else {
            angular
        }
    }

    fn load(&mut self, q: &[f64], v: &[f64]) {
        self.q.copy_from_slice(q);
        self.v.copy_from_slice(v);
    }
}

impl ReducedSystem for WheeledSystem {
    fn nq(&self) -> usize {
        self.robot.model.nq
    }
    fn nv(&self) -> usize {
        self.robot.nr()
    }
    fn nu(&self) -> usize {
        self.robot.nu()
    }
    fn q_names(&self) -> Vec<String> {
        self.robot.q_names()
    }
    fn v_names(&self) -> Vec<String> {
        self.robot.v_names()
    }
    fn u_names(&self) -> Vec<String> {
        self.robot.u_names()
    }
    fn q_units(&self) -> Vec<&'static str> {
        let mut u = vec!["m", "m", "rad"];
        u.extend((3..self.robot.model.nv).map(|i| self.dof_unit(i, "m", "rad")));
        u
    }
    fn v_units(&self) -> Vec<&'static str> {
        let mut u = vec!["m/s", "rad/s"];
        u.extend(
            self.robot
                .arm_dofs()
                .iter()
                .map(|&i| self.dof_unit(i, "m/s", "rad/s")),
        );
        u
    }
    fn u_units(&self) -> Vec<&'static str> {
        let mut u = vec!["N m", "N m"];
        u.extend(
            self.robot
                .arm_dofs()
                .iter()
                .map(|&i| self.dof_unit(i, "N", "N m")),
        );
        u
    }
    fn dynamics(
        &mut self,
        q: &[f64],
        v: &[f64],
        u: &[f64],
        qdot: &mut [f64],
        vdot: &mut [f64],
    ) -> Result<()> {
        self.load(q, v);
        crate::mobile::reduced_forward_dynamics(&self.robot, &mut self.data, &self.q, &self.v, u)?;
        qdot.copy_from_slice(self.data.qdot.as_slice());
        vdot.copy_from_slice(self.data.reduced.vdot.as_slice());
        Ok(())
    }
    fn energy(&mut self, q: &[f64], v: &[f64]) -> Result<(f64, f64)> {
        self.load(q, v);
        Ok(crate::mobile::wheeled::energy(
            &self.robot,
            &mut self.data,
            &self.q,
            &self.v,
        ))
    }
    fn input_power(&mut self, q: &[f64], v: &[f64], u: &[f64]) -> Result<f64> {
        self.load(q, v);
        crate::mobile::wheeled::admissible_velocity_basis(
            &self.robot,
            &self.q,
            &mut self.data.basis,
        );
        self.data.basis.mul_to(&self.v, &mut self.data.qdot);
        crate::mobile::wheeled::generalized_force(&self.robot, &self.q, u, &mut self.data.force);
        Ok(self.data.force.dot(&self.data.qdot))
    }
    fn constraint_residual(&mut self, q: &[f64], v: &[f64]) -> Result<f64> {
        self.load(q, v);
        crate::mobile::wheeled::admissible_velocity_basis(
            &self.robot,
            &self.q,
            &mut self.data.basis,
        );
        crate::mobile::wheeled::constraint_matrix(&self.robot, &self.q, &mut self.data.constraint);
        self.data.basis.mul_to(&self.v, &mut self.data.qdot);
        let mut r2 = 0.0;
        for i in 0..self.robot.nk() {
            let ri: f64 = self
                .data
                .constraint
                .row(i)
                .iter()
                .zip(self.data.qdot.iter())
                .map(|(a, b)| a * b)
                .sum();
            r2 += ri * ri;
        }
        Ok(r2.sqrt())
    }
    fn nk(&self) -> usize {
        self.robot.nk()
    }
    fn multipliers(&mut self, q: &[f64], v: &[f64], u: &[f64], out: &mut [f64]) -> Result<()> {
        self.load(q, v);
        crate::mobile::reduced_forward_dynamics(&self.robot, &mut self.data, &self.q, &self.v, u)?;
        let lam =
            crate::mobile::wheeled::lagrange_multipliers(&self.robot, &mut self.data, &self.q)?;
        out.copy_from_slice(lam.as_slice());
        Ok(())
    }
}

//! A fixed-base arm (a [`Model`] with `nq = nv`: revolute, prismatic and continuous
//! joints) as a [`ReducedSystem`]: `q̇ = v`, `v̇ = ABA(q, v, τ)`, every joint actuated,
//! no constraint. Lets the closed-loop simulator run fixed-base laws
//! ([`crate::control::osc::osc_fixed_base`]).

use crate::dynamics::{aba, kinetic_energy, potential_energy};
use crate::error::{Error, Result};
use crate::multibody::{Data, Model};
use crate::sim::reduced_system::ReducedSystem;
use nalgebra::DVector;

/// A fixed-base model with its workspace.
#[derive(Debug, Clone)]
pub struct FixedBaseSystem {
    /// The model.
    pub model: Model,
    data: Data,
    q: DVector<f64>,
    v: DVector<f64>,
    tau: DVector<f64>,
}

impl FixedBaseSystem {
    /// Wraps `model`.
    ///
    /// # Errors
    /// A model whose configuration is not its velocity (`nq ≠ nv`: a free-flyer or
    /// planar root).
    pub fn new(model: Model) -> Result<Self> {
        if model.nq != model.nv {
            return Err(Error::invalid(
                "robot",
                format!(
                    "a fixed-base plant needs nq = nv (got nq = {}, nv = {}): load the URDF with a fixed root",
                    model.nq, model.nv
                ),
            ));
        }
        let n = model.nv;
        Ok(Self {
            data: Data::new(&model),
            q: DVector::zeros(n),
            v: DVector::zeros(n),
            tau: DVector::zeros(n),
            model,
        })
    }

    fn load(&mut self, q: &[f64], v: &[f64]) {
        self.q.copy_from_slice(q);
        self.v.copy_from_slice(v);
    }

    fn dof_names(&self, suffix: &str) -> Vec<String> {
        (0..self.model.nv)
            .map(|i| format!("{}{suffix}", self.model.names[self.model.joint_of_dof[i].0]))
            .collect()
    }

    fn units(&self, linear: &'static str, angular: &'static str) -> Vec<&'static str> {
        (0..self.model.nv)
            .map(|i| {
                if self.model.joint_types[self.model.joint_of_dof[i].0].is_prismatic() {
                    linear
                } else {
                    angular
                }
            })
            .collect()
    }
}

impl ReducedSystem for FixedBaseSystem {
    fn nq(&self) -> usize {
        self.model.nq
    }
    fn nv(&self) -> usize {
        self.model.nv
    }
    fn nu(&self) -> usize {
        self.model.nv
    }
    fn q_names(&self) -> Vec<String> {
        self.dof_names("")
    }
    fn v_names(&self) -> Vec<String> {
        self.dof_names("_dot")
    }
    fn u_names(&self) -> Vec<String> {
        self.dof_names("_tau")
    }
    fn q_units(&self) -> Vec<&'static str> {
        self.units("m", "rad")
    }
    fn v_units(&self) -> Vec<&'static str> {
        self.units("m/s", "rad/s")
    }
    fn u_units(&self) -> Vec<&'static str> {
        self.units("N", "N m")
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
        self.tau.copy_from_slice(u);
        let a = aba(&self.model, &mut self.data, &self.q, &self.v, &self.tau);
        qdot.copy_from_slice(v);
        vdot.copy_from_slice(a.as_slice());
        Ok(())
    }
    fn energy(&mut self, q: &[f64], v: &[f64]) -> Result<(f64, f64)> {
        self.load(q, v);
        let t = kinetic_energy(&self.model, &mut self.data, &self.q, &self.v);
        let p = potential_energy(&self.model, &mut self.data, &self.q);
        Ok((t, p))
    }
    fn input_power(&mut self, _q: &[f64], v: &[f64], u: &[f64]) -> Result<f64> {
        Ok(u.iter().zip(v).map(|(a, b)| a * b).sum())
    }
    fn constraint_residual(&mut self, _q: &[f64], _v: &[f64]) -> Result<f64> {
        Ok(0.0)
    }
    fn nk(&self) -> usize {
        0
    }
    fn multipliers(&mut self, _q: &[f64], _v: &[f64], _u: &[f64], _out: &mut [f64]) -> Result<()> {
        Ok(())
    }
}

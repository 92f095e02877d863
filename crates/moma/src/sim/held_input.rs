//! The plant ODE of a [`ReducedSystem`] under inputs held over the step: the state
//! `[q, v, W]` (configuration, reduced velocity, the inputs' work `W = ∫ Qᵀ q̇ dt`), its
//! derivative `[N_C v, v̇, Qᵀ q̇]` at the inputs `u`. The open-loop run
//! ([`crate::sim::wheeled`]) evaluates its input profile into `u` first, the closed loop
//! ([`crate::sim::closed_loop`]) holds its law's torques (or evaluates the law first when
//! continuous) and `moma mission` holds its torques over the control period.

use crate::error::Result;
use crate::ode::OdeSystem;
use crate::sim::reduced_system::ReducedSystem;

/// The ODE `ẋ = f(x, u)` of `system` with the inputs `u` held, state `[q, v, W]`.
pub struct HeldInputOde<'a, S: ReducedSystem + ?Sized> {
    /// The plant.
    pub system: &'a mut S,
    /// The inputs, one per actuator of `system`.
    pub u: &'a [f64],
}

impl<S: ReducedSystem + ?Sized> OdeSystem for HeldInputOde<'_, S> {
    fn dim(&self) -> usize {
        self.system.nq() + self.system.nv() + 1
    }

    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<()> {
        let (nq, nv) = (self.system.nq(), self.system.nv());
        let (q, rest) = x.split_at(nq);
        let v = &rest[..nv];
        let (qd, rest_d) = dx.split_at_mut(nq);
        let (vd, wd) = rest_d.split_at_mut(nv);
        self.system
            .dynamics(q, v, self.u, qd, vd)
            .map_err(|e| e.singular_at_time(t))?;
        wd[0] = self.system.input_power(q, v, self.u)?;
        Ok(())
    }
}

//! The rolling (reduced) model as a [`HeldPlant`]: a [`ReducedSystem`]'s state `[q, v, W]`
//! integrated under the held inputs ([`HeldInputOde`]) over one segment of its grid per
//! control period, by fixed-step RK4 or the adaptive integrator with the run's one step
//! budget.

use crate::error::Result;
use crate::ode::StepStats;
use crate::sim::held_input::HeldInputOde;
use crate::sim::held_loop::HeldPlant;
use crate::sim::monitor::MonitorLimits;
use crate::sim::reduced_system::ReducedSystem;
use crate::sim::settings::IntegratorSettings;
use crate::sim::stepping::{Grid, GridStepper};

/// A [`ReducedSystem`] integrated over the control periods of a grid.
pub struct RollingPlant<'g, S: ReducedSystem + ?Sized> {
    /// The plant (a payload attached replaces it in place).
    pub system: &'g mut S,
    /// The state `[q, v, W]` (`W` the inputs' work).
    pub x: Vec<f64>,
    stepper: GridStepper<'g>,
}

impl<'g, S: ReducedSystem + ?Sized> RollingPlant<'g, S> {
    /// `system` started at `x0 = [q, v, W]`, integrated by `integrator` over `grid` (one
    /// segment per control period).
    ///
    /// # Errors
    /// The adaptive integrator's options.
    pub(crate) fn new(
        system: &'g mut S,
        x0: Vec<f64>,
        integrator: IntegratorSettings,
        limits: &MonitorLimits,
        grid: Grid<'g>,
    ) -> Result<Self> {
        let stepper = GridStepper::new(x0.len(), integrator, limits, grid)?;
        Ok(Self {
            system,
            x: x0,
            stepper,
        })
    }

    /// The integrator's statistics so far.
    #[must_use]
    pub fn stats(&self) -> StepStats {
        self.stepper.stats()
    }
}

impl<S: ReducedSystem + ?Sized> HeldPlant for RollingPlant<'_, S> {
    fn nq(&self) -> usize {
        self.system.nq()
    }

    fn nv(&self) -> usize {
        self.system.nv()
    }

    fn nu(&self) -> usize {
        self.system.nu()
    }

    fn time(&self) -> f64 {
        self.stepper.time()
    }

    fn state(&mut self, q: &mut [f64], v: &mut [f64]) {
        let nq = q.len();
        q.copy_from_slice(&self.x[..nq]);
        v.copy_from_slice(&self.x[nq..nq + v.len()]);
    }

    fn advance(&mut self, u: &[f64], first_stage: Option<&[f64]>) -> Result<()> {
        let mut ode = HeldInputOde {
            system: &mut *self.system,
            u,
        };
        self.stepper.advance(&mut ode, &mut self.x, first_stage)?;
        Ok(())
    }
}

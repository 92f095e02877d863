//! Integrators, the simulation loop and recorders.

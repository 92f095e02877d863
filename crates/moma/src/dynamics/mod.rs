//! Rigid-body dynamics: RNEA, CRBA, ABA, gravity, nonlinear effects, Coriolis matrix, energy, centre of mass, momentum.

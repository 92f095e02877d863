//! Wheeled platforms: wheel contacts, Pfaffian constraints, admissible-velocity basis, reduced dynamics, whole-body Jacobian.

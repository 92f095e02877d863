//! Forward kinematics, frame Jacobians, configuration-space operations.

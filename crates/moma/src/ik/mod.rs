//! Inverse kinematics: damped least squares / Levenberg–Marquardt for arms, whole-body resolved-rate motion for mobile manipulators.

//! Input and output: the URDF loader, and the map between moma's state layout and
//! Pinocchio's.

pub mod pinocchio_layout;
pub mod urdf;

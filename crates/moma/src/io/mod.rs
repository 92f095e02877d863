//! Input and output: the URDF loader, the JSON states files of the command line, and the
//! map between moma's state layout and Pinocchio's.

pub mod pinocchio_layout;
pub mod states;
pub mod urdf;

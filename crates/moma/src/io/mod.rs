//! Input and output: the URDF loader and the JSON states files of the command line.

pub mod states;
pub mod urdf;

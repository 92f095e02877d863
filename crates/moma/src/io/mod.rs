//! Input and output: the URDF loader.

pub mod urdf;

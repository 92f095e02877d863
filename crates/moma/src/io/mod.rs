//! Input and output: the URDF loader and serde schemas.

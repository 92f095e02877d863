//! 6-D spatial algebra on nalgebra.

//! Motion planning on occupancy grids.

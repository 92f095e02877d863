//! Manipulability measures and ellipsoids.

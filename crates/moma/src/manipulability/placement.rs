//! Base-placement maps (placeholder replaced below).

//! Base-placement maps: reachability and manipulability over a grid of base poses.

//! The files a fuzzed mission or sweep may name. A fuzzed path could name any file on the
//! machine (`/dev/zero` never ends, a directory or a huge file is slow), so the mission
//! and sweep targets keep a path only when it names one of the shipped files below and
//! otherwise swap in one of them, chosen by the path's length: every load still runs, on
//! known files, including a map where a robot belongs and the other way round.

use std::path::{Path, PathBuf};

/// The repository's `scenarios/` folder.
pub fn scenarios() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenarios")
}

/// Maps and robots, relative to `scenarios/` (what a mission file names).
pub const MISSION_FILES: [&str; 7] = [
    "maps/depot.yaml",
    "maps/potential_trap.map",
    "maps/depot.pgm",
    "robots/mobile_manipulator.urdf",
    "robots/diffdrive_arm.urdf",
    "robots/brake_test_robot.urdf",
    "robots/panda.urdf",
];

/// Robots and missions, relative to `scenarios/sweeps/` (what a sweep file names).
pub const SWEEP_FILES: [&str; 6] = [
    "../robots/panda.urdf",
    "../robots/mobile_manipulator.urdf",
    "../robots/diffdrive_arm.urdf",
    "../../crates/moma/tests/data/pinocchio/urdf/tiago.urdf",
    "../mission.toml",
    "../mission_sealed.toml",
];

/// `p` if it is one of `allowed`, else one of them.
pub fn pick<'a>(p: &'a str, allowed: &[&'a str]) -> &'a str {
    if allowed.contains(&p) {
        p
    } else {
        allowed[p.len() % allowed.len()]
    }
}

//! The files a fuzzed mission or sweep may name. A fuzzed path could name any file on the
//! machine (`/dev/zero` never ends, a directory or a huge file is slow), so the mission
//! and sweep targets keep a path only when it names one of the shipped files below and
//! otherwise swap in one of them, chosen by the path's length: every load still runs, on
//! known files, including a map where a robot belongs and the other way round.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, OnceLock};

use moma::mission::scenario::{FileSystem, Loader};
use moma::multibody::{Model, RootJoint};
use moma::planning::LoadedMap;

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

/// The mission and sweep targets' [`Loader`]: each shipped map and robot is parsed from
/// the file system the first time it is asked for (per path, map resolution and root
/// joint, at most [`MAX_KEPT`] of each kind) and handed out as a copy afterwards, so an input pays for the validation and
/// the evaluation it fuzzes, not for re-parsing the same files (the depot map and a URDF
/// took most of each input's time). A file that fails to load is not remembered: the
/// next input loads it again and gets the same error from the same code. The map and
/// URDF parsers themselves are fuzzed by their own targets.
pub struct Cached;

type Memo<K, V> = Mutex<HashMap<K, V>>;

fn maps() -> &'static Memo<(PathBuf, Option<u64>), LoadedMap> {
    static M: OnceLock<Memo<(PathBuf, Option<u64>), LoadedMap>> = OnceLock::new();
    M.get_or_init(Default::default)
}

fn robots() -> &'static Memo<(PathBuf, String), Model> {
    static M: OnceLock<Memo<(PathBuf, String), Model>> = OnceLock::new();
    M.get_or_init(Default::default)
}

/// At most this many loaded files per kind are kept (a fuzzed resolution of an image map
/// is a new key each time, so an unbounded memo would grow with the run).
const MAX_KEPT: usize = 32;

fn remember<K: std::hash::Hash + Eq, V: Clone>(memo: &Memo<K, V>, key: K, v: &V) {
    let mut m = memo.lock().unwrap();
    if m.len() < MAX_KEPT {
        m.insert(key, v.clone());
    }
}

impl Loader for Cached {
    fn map(&self, path: &Path, resolution: Option<f64>) -> moma::Result<LoadedMap> {
        let key = (path.to_path_buf(), resolution.map(f64::to_bits));
        if let Some(m) = maps().lock().unwrap().get(&key) {
            return Ok(m.clone());
        }
        let m = FileSystem.map(path, resolution)?;
        remember(maps(), key, &m);
        Ok(m)
    }

    fn urdf(&self, path: &Path, root: RootJoint) -> moma::Result<Model> {
        let key = (path.to_path_buf(), format!("{root:?}"));
        if let Some(m) = robots().lock().unwrap().get(&key) {
            return Ok(m.clone());
        }
        let m = FileSystem.urdf(path, root)?;
        remember(robots(), key, &m);
        Ok(m)
    }
}

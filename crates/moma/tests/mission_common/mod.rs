//! What the mission tests share: the shipped scenarios, loading and running one, and a
//! shipped file with a text edit, validated as if it were the file.

#![allow(dead_code)] // each test file uses its own part

use std::path::{Path, PathBuf};

use moma::mission::{self, Mission, MissionResult, scenario};

/// The repository's `scenarios/` folder.
pub fn scenarios() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios")
}

/// The shipped mission `name`, loaded.
pub fn load(name: &str) -> Mission {
    mission::load(&scenarios().join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// `m` run to its end.
pub fn run(m: &Mission) -> MissionResult {
    mission::run(m).unwrap_or_else(|e| panic!("{}: {e}", m.name))
}

/// The shipped mission `name` with `table` appended, parsed and validated as if it were
/// the file.
pub fn appended(name: &str, table: &str) -> moma::Result<Mission> {
    let path = scenarios().join(name);
    let text = std::fs::read_to_string(&path).unwrap();
    let file = scenario::parse_file(&format!("{text}\n{table}\n"), &path)?;
    scenario::from_file(file, &path, &scenarios())
}

/// The shipped mission `name` with every `from` replaced by `to` (it must occur), parsed
/// and validated as if it were the file.
pub fn variant(name: &str, from: &str, to: &str) -> moma::Result<Mission> {
    let path = scenarios().join(name);
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(from), "{name} lacks '{from}'");
    let file = scenario::parse_file(&text.replace(from, to), &path)?;
    scenario::from_file(file, &path, &scenarios())
}

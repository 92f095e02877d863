//! Shared by the CLI tests that run the `moma` binary on the shipped scenarios.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The `moma` binary built for these tests.
pub fn moma() -> Command {
    Command::new(env!("CARGO_BIN_EXE_moma"))
}

/// The repository's `scenarios/` folder.
pub fn scenarios() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios")
}

/// A fresh, empty folder under the system's temporary folder, named by the test binary,
/// `tag` and the process id.
pub fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "moma-{}-{tag}-{}",
        env!("CARGO_CRATE_NAME"),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// The `summary.json` a run wrote into `dir`.
pub fn summary(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap()).unwrap()
}

/// `moma simulate --quiet SCENARIO --output OUT`, its output captured.
pub fn simulate(scenario: &Path, out: &Path) -> std::process::Output {
    moma()
        .args(["simulate", "--quiet"])
        .arg(scenario)
        .arg("--output")
        .arg(out)
        .output()
        .unwrap()
}

/// `moma mission --quiet --output OUT MISSION`, its output captured.
pub fn mission(file: &Path, out: &Path) -> std::process::Output {
    moma()
        .args(["mission", "--quiet", "--output"])
        .arg(out)
        .arg(file)
        .output()
        .unwrap()
}

/// A copy of the shipped scenario `name` with `from` (which must occur) replaced by `to`,
/// written beside it (so its relative paths hold) as `STEM_TAG_PID.tmp.toml`; the caller
/// removes it.
pub fn edited_scenario(name: &str, tag: &str, from: &str, to: &str) -> PathBuf {
    let text = std::fs::read_to_string(scenarios().join(name)).unwrap();
    assert!(text.contains(from), "{from}");
    let stem = name.trim_end_matches(".toml");
    let path = scenarios().join(format!("{stem}_{tag}_{}.tmp.toml", std::process::id()));
    std::fs::write(&path, text.replace(from, to)).unwrap();
    path
}

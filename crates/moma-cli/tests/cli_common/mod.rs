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

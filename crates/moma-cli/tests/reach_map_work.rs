//! `moma reach-map` bounds its total work before it runs: a grid fine enough to pass the
//! sample guard, times the restarts and iterations of each solve, is refused at once with
//! an error naming the options (exit status 1, nothing written), and a map just inside the
//! budget still runs.

use std::path::PathBuf;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn panda() -> String {
    concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../moma/tests/data/manipulability/panda.urdf"
    )
    .to_string()
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("moma_reach_map_work_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn reach_map(
    step: &str,
    headings: &str,
    restarts: &str,
    max_iters: &str,
    tag: &str,
) -> (Output, Duration, PathBuf, PathBuf) {
    let svg = tmp(&format!("{tag}.svg"));
    let js = tmp(&format!("{tag}.json"));
    let start = Instant::now();
    let out = Command::new(env!("CARGO_BIN_EXE_moma"))
        .args([
            "reach-map",
            &panda(),
            "--frame",
            "panda_hand_tcp",
            "--target",
            "1.0,0.5,0.5",
            "--area",
            "0,-0.5,2,1.5",
            "--step",
            step,
            "--headings",
            headings,
            "--restarts",
            restarts,
            "--max-iters",
            max_iters,
            "--svg",
            svg.to_str().unwrap(),
            "-o",
            js.to_str().unwrap(),
        ])
        .output()
        .expect("run moma");
    (out, start.elapsed(), svg, js)
}

#[test]
fn total_work_is_bounded_before_running() {
    // 2001 × 2001 × 8 = 32 M samples (under the 50 M sample guard) × 3 attempts × 100
    // iterations = 9.6e9 IK iterations: hours of work, refused at once.
    let (out, took, svg, js) = reach_map("0.001", "8", "2", "100", "fine");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    for words in [
        "--step",
        "--restarts",
        "--max-iters",
        "32032008 samples",
        "9.610e9",
        "budget of 1e8",
    ] {
        assert!(err.contains(words), "missing '{words}' in: {err}");
    }
    assert_eq!(err.lines().count(), 1, "one line: {err}");
    assert!(took < Duration::from_secs(5), "refused after {took:?}");
    assert!(!svg.exists() && !js.exists(), "an output was left behind");
    // Fewer attempts do not help when the grid alone is too fine.
    let (out, _, _, _) = reach_map("0.001", "8", "0", "4", "fine_one");
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("1.281e8"));
}

#[test]
fn a_map_inside_the_budget_runs() {
    // 9 × 9 × 4 = 324 samples × 3 × 100 = 97,200 iterations at most: far inside.
    let (out, _, svg, js) = reach_map("0.25", "4", "2", "100", "coarse");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(svg.exists() && js.exists());
}

//! Failures are clean: malformed or extreme inputs that used to abort, hang, succeed
//! silently or leave a partial output file behind.

use std::path::PathBuf;
use std::process::{Command, Output};
use std::time::{Duration, Instant};

fn moma(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_moma"))
        .args(args)
        .output()
        .expect("run moma")
}

fn root(p: &str) -> String {
    format!("{}/../../{p}", env!("CARGO_MANIFEST_DIR"))
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("moma-review-cli-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A clean failure: exit status 1, one message naming `needle`, no panic or backtrace.
fn assert_clean_error(o: &Output, needle: &str) {
    let err = stderr(o);
    assert_eq!(o.status.code(), Some(1), "stderr: {err}");
    assert!(err.contains(needle), "expected '{needle}' in: {err}");
    assert!(
        !err.contains("panicked") && !err.contains("backtrace"),
        "{err}"
    );
}

fn m1_scenario(name: &str, edit: (&str, &str)) -> PathBuf {
    let text = std::fs::read_to_string(root("scenarios/m1_unicycle.toml")).unwrap();
    assert!(text.contains(edit.0), "scenario template changed");
    let path = tmp(name);
    std::fs::write(&path, text.replace(edit.0, edit.1)).unwrap();
    path
}

#[test]
fn simulate_huge_duration_is_refused_not_an_allocation_abort() {
    let sc = m1_scenario("huge.toml", ("duration = 3.0", "duration = 1e12"));
    let out = tmp("huge-out");
    let o = moma(&[
        "simulate",
        sc.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    // the field the user set, and the bound it breaks
    assert_clean_error(&o, "duration = 1e12 s at output.record_interval");
    assert_clean_error(&o, "more than 1e7");
    assert!(!out.join("summary.json").exists());
}

#[test]
fn simulate_tiny_step_is_refused_not_a_hang() {
    let sc = m1_scenario("tiny.toml", ("dt = 0.001", "dt = 1e-300"));
    let out = tmp("tiny-out");
    let t0 = Instant::now();
    let o = moma(&[
        "simulate",
        sc.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert_clean_error(&o, "integrator.dt");
    assert!(t0.elapsed() < Duration::from_secs(30));
}

fn turtlebot() -> String {
    root("crates/moma/tests/data/planning/rosmaps/turtlebot3/map.yaml")
}

#[test]
fn plan_leaves_no_json_when_the_svg_cannot_be_written() {
    let json = tmp("partial.json");
    let _ = std::fs::remove_file(&json);
    let svg = tmp("no-such-dir").join("sub").join("p.svg");
    let o = moma(&[
        "plan",
        &turtlebot(),
        "--start=-2,-0.5",
        "--goal",
        "1.5,0.5",
        "--output",
        json.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
    ]);
    assert_clean_error(&o, "p.svg");
    assert!(!json.exists(), "partial output left behind");
    // No temporary sibling either.
    let leftovers: Vec<_> = std::fs::read_dir(json.parent().unwrap())
        .unwrap()
        .filter_map(|e| e.ok())
        .filter(|e| e.file_name().to_string_lossy().starts_with(".partial.json"))
        .collect();
    assert!(leftovers.is_empty());
}

#[test]
fn plan_with_a_footprint_larger_than_the_map_is_an_error_not_a_hang_or_a_free_path() {
    for fp in ["[[0,0],[1e10,0],[0,1e10]]", "[[0,0],[1e300,0],[0,1e300]]"] {
        let t0 = Instant::now();
        let o = moma(&[
            "plan",
            &turtlebot(),
            "--start=-2,-0.5",
            "--goal",
            "1.5,0.5",
            "--footprint",
            fp,
        ]);
        assert_clean_error(&o, "footprint");
        assert!(t0.elapsed() < Duration::from_secs(30));
    }
}

#[test]
fn plan_with_a_zero_area_footprint_is_an_error() {
    let o = moma(&[
        "plan",
        &turtlebot(),
        "--start=-2,-0.5",
        "--goal",
        "1.5,0.5",
        "--footprint",
        "0,0;0,0;0,0",
    ]);
    assert_clean_error(&o, "footprint");
}

#[test]
fn scen_with_no_problems_is_an_error_not_a_vacuous_success() {
    let map = tmp("tiny.map");
    std::fs::write(&map, "type octile\nheight 2\nwidth 3\nmap\n...\n...\n").unwrap();
    let scen = tmp("empty.scen");
    std::fs::write(&scen, "").unwrap();
    let out = tmp("empty.csv");
    let o = moma(&[
        "scen",
        map.to_str().unwrap(),
        scen.to_str().unwrap(),
        "--output",
        out.to_str().unwrap(),
    ]);
    assert_clean_error(&o, "empty.scen");
    assert!(!out.exists());
}

#[test]
fn json_to_a_closed_pipe_does_not_panic() {
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_moma"))
        .args([
            "inspect",
            &root("crates/moma/tests/data/pinocchio/urdf/panda.urdf"),
            "--json",
        ])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Close the read end before the child writes.
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    assert!(!stderr(&o).contains("panicked"), "{}", stderr(&o));
}

//! `moma mission` with `[task]`: an object no base placement reaches ends the run with
//! exit 3 and place_base's reason in `summary.json` (the whole output set written); an
//! unknown object exits 1 naming the field, writing nothing.

mod cli_common;

use cli_common::{edited_scenario, mission, summary, temp_dir};

/// Runs the pick mission with `from` replaced by `to` (written next to the original, so
/// its relative paths hold); returns the exit code, standard error and output folder.
fn run_with(tag: &str, from: &str, to: &str) -> (Option<i32>, String, std::path::PathBuf) {
    let path = edited_scenario("mission_fetch_pick.toml", tag, from, to);
    let out = temp_dir(tag).join("out");
    let run = mission(&path, &out);
    let _ = std::fs::remove_file(&path);
    (
        run.status.code(),
        String::from_utf8_lossy(&run.stderr).into_owned(),
        out,
    )
}

#[test]
fn an_object_out_of_every_placements_reach_exits_3_with_the_reason() {
    // the grasp 3 m above the can: beyond the arm's reach from every base pose
    let (code, err, out) = run_with(
        "unreachable",
        "grasp = [-0.2, 0.0, 0.05, 0.0, 0.0, 0.0, 1.0]",
        "grasp = [-0.2, 0.0, 3.0, 0.0, 0.0, 0.0, 1.0]",
    );
    assert_eq!(code, Some(3), "{err}");
    let s = summary(&out);
    assert_eq!(s["reached"], false);
    let reason = s["reason"].as_str().unwrap();
    assert!(
        reason.starts_with("no placement for the pick: no base pose reaches the grasp"),
        "{reason}"
    );
    assert!(reason.contains("out of reach"), "{reason}");
    assert!(s["task"]["placement"].is_null());
    assert!(s["task"]["arm_plans"].as_array().unwrap().is_empty());
    assert!(err.contains(reason), "{err}");
}

#[test]
fn an_unknown_object_exits_1_naming_the_field() {
    let (code, err, out) = run_with("unknown", "object = \"Can2\"", "object = \"Mug\"");
    assert_eq!(code, Some(1), "{err}");
    assert!(
        err.contains("task.object") && err.contains("'Mug'"),
        "{err}"
    );
    assert!(!out.exists(), "no output on an input error");
}

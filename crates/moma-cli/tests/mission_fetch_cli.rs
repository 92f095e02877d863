//! `moma mission scenarios/mission_fetch.toml`: Fetch read from its URDF package runs end
//! to end on nav2's warehouse and reaches its goal with the footprint of its collision
//! geometry; bad robot input (a missing package folder, an unknown wheel joint, a caster
//! list that is empty or not finite) exits 1 naming the file and the field, writing
//! nothing.

mod cli_common;

use cli_common::{edited_scenario, mission, scenarios, temp_dir};

#[test]
fn fetch_mission_reaches_its_goal_with_the_robots_footprint() {
    let out = temp_dir("run").join("out");
    let run = mission(&scenarios().join("mission_fetch.toml"), &out);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["reached"], true, "{}", s["reason"]);
    assert!(s["end_effector_error"].as_f64().unwrap() < 0.02);
    assert!(s["min_zmp_margin"].as_f64().unwrap() > 0.0);
    assert!(s["min_clearance"].as_f64().unwrap() > 0.0);
    let fp = &s["footprint"];
    assert_eq!(fp["source"], "robot");
    assert_eq!(fp["posture"], "transport");
    // Pinocchio's figure (tests/data/robots/fetch/footprint_pinocchio.txt)
    assert!((fp["radius"].as_f64().unwrap() - 0.28771503101378787).abs() < 1e-9);
    assert!(fp["polygon"].as_array().unwrap().len() >= 3);
}

/// The Fetch mission with `from` replaced by `to`, written next to a copy of the paths it
/// names (relative to the scenarios folder, so the copy sits there too).
fn bad(tag: &str, from: &str, to: &str, field: &str) {
    let path = edited_scenario("mission_fetch.toml", tag, from, to);
    let out = temp_dir(tag).join("out");
    let run = mission(&path, &out);
    let _ = std::fs::remove_file(&path);
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{tag}: {err}");
    assert!(run.stdout.is_empty(), "{tag}");
    assert!(!out.exists(), "{tag}: no output on an input error");
    assert!(
        err.contains(&format!("mission_fetch_{tag}")) && err.contains(field),
        "{tag}: {err}"
    );
}

#[test]
fn bad_robot_input_exits_1_naming_file_and_field() {
    bad(
        "pkg",
        "package_dirs = [\"../crates/moma/tests/data/robots/fetch\"]",
        "package_dirs = [\"../crates/moma/tests/data/robots/no_such_package\"]",
        "robot.package_dirs[0]",
    );
    bad(
        "wheel",
        "wheel_joints = [\"l_wheel_joint\", \"r_wheel_joint\"]",
        "wheel_joints = [\"l_wheel_joint\", \"rear_wheel_joint\"]",
        "rear_wheel_joint",
    );
    bad(
        "empty",
        "casters_file = \"../crates/moma/tests/data/robots/fetch/casters.toml\"",
        "casters = []",
        "robot.casters: the list is empty",
    );
    bad(
        "nan",
        "casters_file = \"../crates/moma/tests/data/robots/fetch/casters.toml\"",
        "casters = [{ name = \"a\", position = [0.1, nan] }, { name = \"b\", position = [-0.2, 0.1] }]",
        "robot.casters[0].position",
    );
    bad(
        "nowheels",
        "wheel_joints = [\"l_wheel_joint\", \"r_wheel_joint\"]\n",
        "",
        "robot.wheel_joints",
    );
}

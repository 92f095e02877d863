//! `moma simulate` with `plant = "contact"`: the shipped brake scenario runs, writes its
//! files and reports the casters' lift-off; bad contact parameters fail with the field
//! named and no output.

mod cli_common;

use cli_common::{moma, scenarios, temp_dir};

#[test]
fn the_contact_brake_scenario_reports_the_casters_lift_off() {
    let work = temp_dir("brake");
    let out = work.join("out");
    let r = moma()
        .args(["simulate", "--quiet", "--output"])
        .arg(&out)
        .arg(scenarios().join("contact_brake_arm_extended.toml"))
        .output()
        .unwrap();
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["plant"], "contact");
    let lift = s["first_lift_off"]["t"].as_f64().unwrap();
    // The brake ramps from 0.2 s to 0.3 s; the rolling run's ZMP leaves the support at
    // 0.272 s.
    assert!((0.26..0.29).contains(&lift), "lift-off at {lift} s");
    assert!(
        s["first_lift_off"]["contact"]
            .as_str()
            .unwrap()
            .starts_with("rear_")
    );
    assert!(s["first_slip"].is_null());
    for f in [
        "trajectory.csv",
        "summary.json",
        "path.svg",
        "normal_forces.svg",
        "slip.svg",
        "tilt.svg",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    for col in [
        "t [s]",
        "x [m]",
        "v [m/s]",
        "tau_left [N m]",
        "pitch [rad]",
        "normal_rear_left_caster [N]",
        "lifted_rear_right_caster",
        "slipping_left_wheel_joint",
    ] {
        assert!(
            header.split(',').any(|c| c == col),
            "no column {col}: {header}"
        );
    }
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn bad_contact_parameters_fail_naming_the_field_and_write_nothing() {
    let work = temp_dir("bad");
    let text =
        std::fs::read_to_string(scenarios().join("contact_brake_arm_extended.toml")).unwrap();
    // The robot path is relative to the scenario file: write beside a copy of the robot.
    std::fs::create_dir_all(work.join("robots")).unwrap();
    std::fs::copy(
        scenarios().join("robots/brake_test_robot.urdf"),
        work.join("robots/brake_test_robot.urdf"),
    )
    .unwrap();
    for (from, to, want) in [
        ("mu = 0.9 ", "mu = 0.0 ", "contact.mu"),
        ("mu = 0.9 ", "stiffness = 1e11 ", "contact.stiffness"),
        (
            "radius = 0.0 },\n  { frame = \"rear_right",
            "radius = 0.05 },\n  { frame = \"rear_right",
            "contact.casters[0] 'rear_left_caster'",
        ),
    ] {
        let path = work.join("bad.toml");
        let edited = text.replace(from, to);
        assert_ne!(edited, text, "{from}");
        std::fs::write(&path, edited).unwrap();
        let out = work.join("out");
        let r = moma()
            .args(["simulate", "--quiet", "--output"])
            .arg(&out)
            .arg(&path)
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(1), "{want}: {err}");
        assert!(
            err.contains("bad.toml") && err.contains(want),
            "{want}: {err}"
        );
        assert!(!out.exists(), "{want}: output written");
    }
    let _ = std::fs::remove_dir_all(&work);
}

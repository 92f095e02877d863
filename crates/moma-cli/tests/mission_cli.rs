//! `moma mission`: the default mission runs with no argument and writes the whole output
//! set (exit 0); a sealed goal writes it too with `reached: false` (exit 3); input errors
//! exit 1 with one message and no output.

mod cli_common;

use cli_common::{mission, moma, scenarios, summary, temp_dir};

const OUTPUTS: &[&str] = &[
    "summary.json",
    "trajectory.csv",
    "events.json",
    "report.html",
    "top_view.svg",
    "speed.svg",
    "zmp_margin.svg",
    "torques.svg",
];

#[test]
fn default_mission_runs_without_an_argument_and_reaches_its_goal() {
    let work = temp_dir("default");
    let out = work.join("out");
    // from an empty directory: the default is found next to the source tree
    let run = moma()
        .current_dir(&work)
        .args(["mission", "--quiet", "--output"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    assert!(run.stdout.is_empty());
    for f in OUTPUTS {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    let s = summary(&out);
    assert_eq!(s["reached"], true);
    assert!(s["reason"].is_null());
    assert_eq!(s["replans"], 1, "the crate forces one re-plan");
    assert!(s["min_zmp_margin"].as_f64().unwrap() > 0.0);
    assert!(s["min_clearance"].as_f64().unwrap() > 0.0);
    assert!(s["end_effector_error"].as_f64().unwrap() < 0.02);
    let fpe = s["final_pose_error"].as_array().unwrap();
    assert!(fpe[0].as_f64().unwrap() < 0.1 && fpe[1].as_f64().unwrap() < 0.1);
    for k in [
        "time_to_goal",
        "max_tracking_error",
        "wall_time_s",
        "max_slip_ratio",
        "min_force_angle",
    ] {
        assert!(s[k].is_number(), "{k}: {}", s[k]);
    }
    for k in [
        "planning_s",
        "smoothing_timing_s",
        "simulation_s",
        "report_s",
    ] {
        assert!(s["wall_time"][k].is_number(), "{k}");
    }
    let rp = &s["replan_timing"][0];
    assert!(rp["dstar_lite_ms"].is_number() && rp["smoothing_timing_ms"].is_number());
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    assert!(
        header.starts_with("t [s],x [m],y [m],theta [rad],v [m/s],omega [rad/s],"),
        "{header}"
    );
    for col in [
        "zmp_margin [m]",
        "clearance [m]",
        "q_shoulder_lift_joint [rad]",
        "tau_left [N m]",
    ] {
        assert!(
            header.split(',').any(|c| c == col),
            "no column {col}: {header}"
        );
    }
    assert_eq!(
        csv.lines().count() as u64,
        s["samples"].as_u64().unwrap() + 1
    );
    // a rerun replaces the folder as a whole
    std::fs::write(out.join("stale.txt"), "old").unwrap();
    let again = moma()
        .args(["mission", "--quiet", "--output"])
        .arg(&out)
        .arg(scenarios().join("mission.toml"))
        .status()
        .unwrap();
    assert!(again.success());
    assert!(!out.join("stale.txt").exists());
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn sealed_goal_writes_everything_and_exits_3() {
    let work = temp_dir("sealed");
    let out = work.join("out");
    let run = mission(&scenarios().join("mission_sealed.toml"), &out);
    assert_eq!(
        run.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    for f in OUTPUTS {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    let s = summary(&out);
    assert_eq!(s["reached"], false);
    assert!(s["reason"].as_str().unwrap().contains("seals the goal"));
    assert!(s["time_to_goal"].is_null());
    assert!(s["end_effector_error"].is_null());
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn shipped_offset_mission_reaches_its_goal_with_the_base_frame_off_the_axle() {
    // d = 0.12: planned and tracked on the axle midpoint, reported for the base frame
    let work = temp_dir("offset");
    let out = work.join("out");
    let run = mission(&scenarios().join("mission_offset.toml"), &out);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let s = summary(&out);
    assert_eq!(s["reached"], true, "{:?}", s["reason"]);
    assert_eq!(s["replans"], 1);
    let fpe = s["final_pose_error"].as_array().unwrap();
    assert!(fpe[0].as_f64().unwrap() < 0.02 && fpe[1].as_f64().unwrap() < 0.02);
    assert!(s["max_tracking_error"].as_f64().unwrap() < 0.01);
    assert!(s["min_clearance"].as_f64().unwrap() > 0.0);
    assert!(s["min_zmp_margin"].as_f64().unwrap() > 0.0);
    assert!(s["end_effector_error"].as_f64().unwrap() < 0.02);
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn input_errors_exit_1_with_no_output() {
    let work = temp_dir("errors");
    let text = std::fs::read_to_string(scenarios().join("mission.toml")).unwrap();
    let text = text
        .replace(
            "maps/depot.yaml",
            &scenarios().join("maps/depot.yaml").display().to_string(),
        )
        .replace(
            "robots/mobile_manipulator.urdf",
            &scenarios()
                .join("robots/mobile_manipulator.urdf")
                .display()
                .to_string(),
        );
    let cases = [
        (
            "goal_in_wall",
            text.replace("pose = [17.0, 7.3, 0.0]", "pose = [0.02, 7.3, 0.0]"),
            "goal.pose",
        ),
        (
            "goal_outside",
            text.replace("pose = [17.0, 7.3, 0.0]", "pose = [99.0, 7.3, 0.0]"),
            "outside",
        ),
        (
            "huge_footprint",
            text.replace("footprint_radius = 0.38", "footprint_radius = 8.0"),
            "fits nowhere",
        ),
        (
            "unknown_key",
            text.replace("mu = 0.6", "mu = 0.6\nspeed = 3"),
            "speed",
        ),
        ("malformed", text.replace("[limits]", "[limits"), "bad.toml"),
    ];
    for (tag, body, needle) in cases {
        let file = work.join("bad.toml");
        std::fs::write(&file, body).unwrap();
        let out = work.join(format!("out-{tag}"));
        let run = mission(&file, &out);
        let err = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{tag}: {err}");
        assert!(err.contains(needle), "{tag}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{tag}: one message: {err}");
        assert!(!out.exists(), "{tag}: output written");
        assert!(!err.contains("panicked"), "{tag}: {err}");
    }
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn the_default_mission_run_elsewhere_writes_to_the_current_directory_and_says_where() {
    let work = temp_dir("elsewhere");
    let run = moma().current_dir(&work).arg("mission").output().unwrap();
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{err}");
    let out = work.join("mission-output");
    for f in OUTPUTS {
        assert!(out.join(f).is_file(), "missing {f} in {}", out.display());
    }
    assert!(
        err.contains("to mission-output; report: mission-output/report.html"),
        "{err}"
    );
}

#[test]
fn a_mission_file_that_cannot_be_read_gives_the_os_reason() {
    let work = temp_dir("nope");
    let run = moma()
        .current_dir(&work)
        .args(["mission", "nope.toml"])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(
        err.contains("nope.toml: cannot read file: No such file or directory"),
        "{err}"
    );
}

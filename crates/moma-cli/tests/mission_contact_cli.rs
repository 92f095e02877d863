//! `moma mission` on the contact plant: the shipped `mission_contact.toml` reaches its
//! goal and its summary says what the contacts did (nothing lifted off or slid); bad
//! contact parameters exit 1 naming the file and the field, with no output.

mod cli_common;

use cli_common::{mission, scenarios, summary, temp_dir};

#[test]
fn the_contact_mission_reaches_its_goal_and_reports_its_contacts() {
    let work = temp_dir("contact");
    let out = work.join("out");
    let run = mission(&scenarios().join("mission_contact.toml"), &out);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let s = summary(&out);
    assert_eq!(s["reached"], true, "{:?}", s["reason"]);
    assert_eq!(s["replans"], 1, "the crate forces one re-plan");
    let fpe = s["final_pose_error"].as_array().unwrap();
    assert!(fpe[0].as_f64().unwrap() < 0.1 && fpe[1].as_f64().unwrap() < 0.1);
    assert!(s["end_effector_error"].as_f64().unwrap() < 0.02);
    let c = &s["contact"];
    assert!(c["first_lift_off"].is_null(), "{}", c["first_lift_off"]);
    assert!(c["first_slip"].is_null(), "{}", c["first_slip"]);
    let totals = c["totals"].as_array().unwrap();
    let names: Vec<&str> = totals
        .iter()
        .map(|t| t["contact"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "left_wheel_joint",
            "right_wheel_joint",
            "caster_front_left",
            "caster_front_right",
            "caster_rear_left",
            "caster_rear_right"
        ]
    );
    for t in totals {
        assert_eq!(t["lifted_time"], 0.0, "{t}");
        assert!(t["min_normal"].as_f64().unwrap() > 0.0, "{t}");
    }
    assert!(s["min_zmp_margin"].as_f64().unwrap() > 0.0);
    let events = std::fs::read_to_string(out.join("events.json")).unwrap();
    assert!(!events.contains("\"lift_off\"") && !events.contains("\"slip\""));
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn bad_contact_parameters_exit_1_naming_the_field() {
    let work = temp_dir("contact-errors");
    let text = std::fs::read_to_string(scenarios().join("mission_contact.toml"))
        .unwrap()
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
    for (tag, to, field) in [
        ("mu", "mu = 0.0", "contact.mu"),
        (
            "stiffness",
            "mu = 1.0\nstiffness = 1e12",
            "contact.stiffness",
        ),
    ] {
        let path = work.join(format!("{tag}.toml"));
        std::fs::write(&path, text.replacen("mu = 1.0", to, 1)).unwrap();
        let out = work.join(format!("out-{tag}"));
        let run = mission(&path, &out);
        assert_eq!(run.status.code(), Some(1), "{tag}");
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(err.contains(field), "{tag}: {err}");
        assert!(err.contains(&format!("{tag}.toml")), "{tag}: {err}");
        assert!(!err.contains("panicked"), "{tag}: {err}");
        assert!(!out.exists(), "{tag}: output written");
    }
    let _ = std::fs::remove_dir_all(&work);
}

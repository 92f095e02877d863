//! `moma simulate` with a `[stability]` table: the shipped brake scenarios (the arm
//! extended tips, the arm tucked does not), the stability outputs, `stop_at_tip`,
//! `require_stable` (exit status 3) and the table's errors.

use std::path::{Path, PathBuf};

mod cli_common;

use cli_common::{scenarios, simulate as run, summary, temp_dir};

/// The extended brake scenario with its `[stability]` table replaced by `table`, written
/// into `dir` (the URDF path made absolute).
fn variant(dir: &Path, table: &str) -> PathBuf {
    let text = std::fs::read_to_string(scenarios().join("brake_arm_extended.toml")).unwrap();
    let urdf = scenarios().join("robots/brake_test_robot.urdf");
    let head = text.split("[stability]").next().unwrap();
    let body = head.replace(
        "urdf = \"robots/brake_test_robot.urdf\"",
        &format!("urdf = {:?}", urdf.to_str().unwrap()),
    );
    let p = dir.join("variant.toml");
    std::fs::write(&p, format!("{body}{table}\n")).unwrap();
    p
}

#[test]
fn extended_arm_brake_tips_and_tucked_does_not() {
    let work = temp_dir("brake");
    let ext = work.join("ext");
    let r = run(&scenarios().join("brake_arm_extended.toml"), &ext);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let s = summary(&ext);
    let st = &s["stability"];
    assert_eq!(st["tipped"], true);
    let c = &st["first_crossing"]["zmp_margin"];
    let t = c["time"].as_f64().unwrap();
    let ts = c["sample_time"].as_f64().unwrap();
    // during the brake ramp (0.2 s to 0.3 s), within one record interval of its sample
    assert!(t > 0.2 && t < 0.3, "{t}");
    assert!(t <= ts && ts - t <= 0.005 + 1e-12, "{t} {ts}");
    assert_eq!(st["tip_edge"]["from"], "left_wheel_joint");
    assert_eq!(st["tip_edge"]["to"], "right_wheel_joint");
    assert_eq!(st["load_rule"], "minimum_norm");
    assert!(
        st["load_rule_description"]
            .as_str()
            .unwrap()
            .contains("least-squares")
    );
    assert!(st["first_crossing"]["slip"].is_null());
    assert!(st["max_slip_ratio"]["value"].as_f64().unwrap() < 1.0);
    assert!(st["min_zmp_margin"]["value"].as_f64().unwrap() < 0.0);
    // the run went on to the end (no stop_at_tip)
    assert!(st["stopped_at_tip"].is_null());
    assert_eq!(s["samples"].as_u64().unwrap(), 161);
    for f in [
        "stability.csv",
        "stability_zmp.svg",
        "stability_force_angle.svg",
        "stability_mhs.svg",
        "wheel_loads.svg",
        "slip.svg",
    ] {
        let text = std::fs::read_to_string(ext.join(f)).unwrap();
        assert!(
            !text.contains("NaN") && !text.contains("nan"),
            "{f} has a NaN"
        );
    }
    let csv = std::fs::read_to_string(ext.join("stability.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    assert!(header.starts_with("t [s],zmp_x [m],zmp_y [m],zmp_margin [m],critical_edge,"));
    assert!(header.contains("normal_load_rear_left_caster [N]"));
    assert!(header.ends_with("right_wheel_joint_slip_ratio"));
    assert_eq!(csv.lines().count(), 162);

    let tuck = work.join("tuck");
    let r = run(&scenarios().join("brake_arm_tucked.toml"), &tuck);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let st = &summary(&tuck)["stability"];
    assert_eq!(st["tipped"], false);
    assert!(st["first_crossing"]["zmp_margin"].is_null());
    assert!(st["tip_edge"].is_null());
    let m = st["min_zmp_margin"]["value"].as_f64().unwrap();
    assert!(m > 0.05, "{m}");
    assert!(st["first_crossing"]["slip"].is_null());
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn stop_at_tip_ends_the_run_and_require_stable_exits_3() {
    let work = temp_dir("stop");
    let sc = variant(&work, "[stability]\nmu = 0.9\nstop_at_tip = true");
    let out = work.join("out");
    let r = run(&sc, &out);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let s = summary(&out);
    let st = &s["stability"];
    let c = &st["first_crossing"]["zmp_margin"];
    assert_eq!(st["stopped_at_tip"], c["sample_time"]);
    assert_eq!(
        s["samples"].as_u64().unwrap(),
        c["sample"].as_u64().unwrap() + 1
    );
    // the recorded part is the same run: same crossing time as the full run
    let full = work.join("full");
    let sc_full = variant(&work, "[stability]\nmu = 0.9");
    assert!(run(&sc_full, &full).status.success());
    let tf = summary(&full)["stability"]["first_crossing"]["zmp_margin"]["time"]
        .as_f64()
        .unwrap();
    assert!((c["time"].as_f64().unwrap() - tf).abs() < 1e-9);

    // a declared goal (stay stable) that is missed: status 3, every output written
    let sc = variant(
        &work,
        "[stability]\nrequire_stable = true\nstop_at_tip = true",
    );
    let out3 = work.join("out3");
    let r = run(&sc, &out3);
    assert_eq!(r.status.code(), Some(3));
    let err = String::from_utf8_lossy(&r.stderr);
    assert!(
        err.contains("require_stable") && err.contains("t = 0.27"),
        "{err}"
    );
    assert!(out3.join("summary.json").is_file() && out3.join("stability.csv").is_file());
    // no mu: no slip columns, slip null
    let st = &summary(&out3)["stability"];
    assert!(st["mu"].is_null() && st["first_crossing"]["slip"].is_null());
    assert!(!out3.join("slip.svg").exists());

    // low friction: slip reported before the tip
    let sc = variant(&work, "[stability]\nmu = 0.3");
    let slip = work.join("slip");
    assert!(run(&sc, &slip).status.success());
    let st = &summary(&slip)["stability"];
    let ts = st["first_crossing"]["slip"]["time"].as_f64().unwrap();
    let tz = st["first_crossing"]["zmp_margin"]["time"].as_f64().unwrap();
    assert!(ts > 0.2 && ts < tz, "{ts} {tz}");
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn bad_stability_tables_fail_with_the_field_and_no_output() {
    let work = temp_dir("bad");
    for (table, expect) in [
        ("[stability]\nmu = 0.0", "stability.mu"),
        ("[stability]\nmu = -1.0", "stability.mu"),
        (
            "[stability]\nbodies = \"subtree:no_such_joint\"",
            "no_such_joint",
        ),
        ("[stability]\nbodies = \"some\"", "stability.bodies"),
        ("[stability]\nstop_at_tipp = true", "stop_at_tipp"),
    ] {
        let sc = variant(&work, table);
        let out = work.join("out");
        let r = run(&sc, &out);
        assert_eq!(r.status.code(), Some(1), "{table}");
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(err.contains(expect), "{table}: {err}");
        assert!(!out.exists(), "{table}: output written");
    }
    // a chapter model has no multibody state to evaluate
    let m1 = std::fs::read_to_string(scenarios().join("m1_unicycle.toml")).unwrap();
    let p = work.join("m1.toml");
    std::fs::write(&p, format!("{m1}\n[stability]\nmu = 0.5\n")).unwrap();
    let r = run(&p, &work.join("out"));
    assert_eq!(r.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&r.stderr).contains("[stability] needs a URDF robot"));
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn closed_loop_runs_evaluate_stability_after_the_run() {
    let work = temp_dir("closed");
    let text = std::fs::read_to_string(scenarios().join("control_kanayama.toml")).unwrap();
    let urdf = scenarios().join("robots/diffdrive_arm.urdf");
    let text = text.replace(
        "urdf = \"robots/diffdrive_arm.urdf\"",
        &format!("urdf = {:?}", urdf.to_str().unwrap()),
    );
    let p = work.join("kanayama.toml");
    std::fs::write(&p, format!("{text}\n[stability]\nmu = 0.6\n")).unwrap();
    let out = work.join("out");
    let r = run(&p, &out);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let s = summary(&out);
    let st = &s["stability"];
    assert_eq!(st["load_rule"], "exact");
    // tipped agrees with the first crossing and the smallest margin
    let tipped = st["tipped"].as_bool().unwrap();
    assert_eq!(tipped, !st["first_crossing"]["zmp_margin"].is_null());
    assert_eq!(
        tipped,
        st["min_zmp_margin"]["value"].as_f64().unwrap() <= 0.0
    );
    assert!(st["max_slip_ratio"]["value"].as_f64().unwrap().is_finite());
    let csv = std::fs::read_to_string(out.join("stability.csv")).unwrap();
    assert_eq!(
        csv.lines().count() as u64,
        s["samples"].as_u64().unwrap() + 1
    );
    assert!(out.join("stability_zmp.svg").is_file());
    assert!(!csv.contains("NaN"));
    // stopping needs an observer inside the loop: refused, no output
    std::fs::write(&p, format!("{text}\n[stability]\nstop_at_tip = true\n")).unwrap();
    let out2 = work.join("out2");
    let r = run(&p, &out2);
    assert_eq!(r.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&r.stderr).contains("stop_at_tip"));
    assert!(!out2.exists());
    let _ = std::fs::remove_dir_all(&work);
}

//! `moma mission` with law `mpc`: the shipped `scenarios/mission_pass_by.toml` reaches
//! (exit 0) and its summary carries the MPC's `mpc` object, as `moma simulate`'s; a bad
//! `[control.mpc]` value exits 1 with one message naming the field, and no output.

mod cli_common;

use cli_common::{edited_scenario, mission, scenarios, summary, temp_dir};

#[test]
fn the_pass_by_mission_reaches_on_the_move_and_reports_the_solves() {
    let work = temp_dir("mpc-pass-by");
    let out = work.join("out");
    let run = mission(&scenarios().join("mission_pass_by.toml"), &out);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let s = summary(&out);
    assert_eq!(s["reached"], true);
    let m = &s["mpc"];
    let solves = m["solves"].as_u64().unwrap();
    assert!(solves > 100, "{m}");
    let t = &m["solve_time_s"];
    let (p50, p99) = (t["median"].as_f64().unwrap(), t["p99"].as_f64().unwrap());
    assert!(0.0 < p50 && p50 <= p99, "{t}");
    assert!(m["iterations"]["max"].as_u64().unwrap() <= 4, "{m}");
    // Rollouts per solve: at most six line-search steps in each of the four iterations.
    let r = &m["rollouts"];
    let (r50, r99, rmax) = (
        r["median"].as_u64().unwrap(),
        r["p99"].as_u64().unwrap(),
        r["max"].as_u64().unwrap(),
    );
    assert!(r50 <= r99 && r99 <= rmax && rmax <= 24, "{r}");
    assert!(m["max_planned_violation"]["torque"].as_f64().unwrap() >= 0.0);
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    assert!(csv.contains("whole_body"));
    let events = std::fs::read_to_string(out.join("events.json")).unwrap();
    assert!(events.contains("\"reached\""), "{events}");
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn a_bad_mpc_value_exits_1_naming_the_field() {
    let work = temp_dir("mpc-bad");
    let file = edited_scenario(
        "mission_pass_by.toml",
        "badmpc",
        "zmp_margin = 0.05",
        "zmp_margin = \"high\"",
    );
    let out = work.join("out");
    let run = mission(&file, &out);
    let _ = std::fs::remove_file(&file);
    let err = String::from_utf8_lossy(&run.stderr);
    assert_eq!(run.status.code(), Some(1), "{err}");
    assert!(err.contains("control.mpc.zmp_margin"), "{err}");
    assert_eq!(err.trim().lines().count(), 1, "{err}");
    assert!(!out.exists());
    let _ = std::fs::remove_dir_all(&work);
}

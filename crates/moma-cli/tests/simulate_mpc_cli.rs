//! `moma simulate` with law `mpc`: the shipped `scenarios/mpc_reach_on_the_move.toml`
//! runs the whole-body MPC on Fetch and its summary carries the `mpc` object (solve-time
//! percentiles, iterations, the largest planned violations, the closed loop's smallest
//! ZMP margin and clearance), with the law's signals in `control.csv`; a bad
//! `[controller.mpc]` fails with one message naming the file and field, and no output.

mod cli_common;

use cli_common::{scenarios, simulate as run, temp_dir};

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("not a number: {v}"))
}

#[test]
fn the_reach_on_the_move_scenario_reports_its_solves() {
    let out = temp_dir("reach").join("out");
    let r = run(&scenarios().join("mpc_reach_on_the_move.toml"), &out);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(s["law"], "mpc");
    assert_eq!(s["reference"], "line_reach");
    let m = &s["mpc"];
    // One solve per 50 ms tick of the 5 s run.
    assert_eq!(m["solves"], 100);
    assert_eq!(s["control_ticks"], 100);
    let t = &m["solve_time_s"];
    let (p50, p90, p99, max) = (f(&t["median"]), f(&t["p90"]), f(&t["p99"]), f(&t["max"]));
    assert!(0.0 < p50 && p50 <= p90 && p90 <= p99 && p99 <= max, "{t}");
    // The solver budget is 4 iterations.
    let it = &m["iterations"];
    assert!(f(&it["mean"]) >= 1.0 && f(&it["mean"]) <= 4.0, "{it}");
    assert!(it["max"].as_u64().unwrap() <= 4, "{it}");
    assert!(
        it["median"].as_u64().unwrap() <= it["p99"].as_u64().unwrap(),
        "{it}"
    );
    // Rollouts per solve: at most six line-search steps in each of the four iterations.
    let r = &m["rollouts"];
    let (r50, r99, rmax) = (
        r["median"].as_u64().unwrap(),
        r["p99"].as_u64().unwrap(),
        r["max"].as_u64().unwrap(),
    );
    assert!(1 <= r50 && r50 <= r99 && r99 <= rmax && rmax <= 24, "{r}");
    let v = &m["max_planned_violation"];
    for kind in [
        "torque",
        "wheel_speed",
        "joint_speed",
        "joint_position",
        "zmp",
        "clearance",
    ] {
        assert!(f(&v[kind]) >= 0.0, "{kind}: {v}");
    }
    // The closed loop's figures (those of crates/moma/tests/sim_mpc.rs, same run): upright
    // with margin, clear of the table and of itself, the gripper within 5 cm of the
    // target.
    assert!(f(&m["min_zmp_margin"]) > 0.05, "{m}");
    assert!(f(&m["min_clearance"]) > 0.0, "{m}");
    assert!(f(&m["min_ee_error"]) < 0.06, "{m}");
    // The law's errors and signals.
    assert_eq!(
        s["error_names"],
        serde_json::json!([
            "ee_position [m]",
            "base_x [m]",
            "base_y [m]",
            "base_heading [rad]"
        ])
    );
    let csv = std::fs::read_to_string(out.join("control.csv")).unwrap();
    let header = csv.lines().next().unwrap();
    assert_eq!(
        header,
        "t [s],ee_position [m],base_x [m],base_y [m],base_heading [rad],solve_time [s],\
         iterations [1],planned_zmp_margin [m],clearance [m]"
    );
    assert_eq!(csv.lines().count(), 1 + 101);
}

#[test]
fn a_bad_mpc_table_names_the_file_and_the_field() {
    let work = temp_dir("bad");
    let text = std::fs::read_to_string(scenarios().join("mpc_reach_on_the_move.toml"))
        .unwrap()
        .replace(
            "../crates/",
            &format!("{}/", scenarios().join("../crates").display()),
        )
        .replace(
            "scenes/mpc_table.yaml",
            &scenarios()
                .join("scenes/mpc_table.yaml")
                .display()
                .to_string(),
        );
    for (from, to, want) in [
        (
            "stages = 20",
            "stages = -5",
            "controller.mpc.stages must be between 1 and 10000, got -5",
        ),
        (
            "stages = 20",
            "stages = 20\nhorizon_s = 1.0",
            "unknown field `horizon_s`",
        ),
        (
            "zmp_margin = 0.05",
            "zmp_margin = \"high\"",
            "controller.mpc.zmp_margin must be a number (m) or false, got string",
        ),
    ] {
        let file = work.join("bad.toml");
        std::fs::write(&file, text.replacen(from, to, 1)).unwrap();
        let out = work.join("out");
        let r = run(&file, &out);
        assert_eq!(r.status.code(), Some(1), "{to}");
        let err = String::from_utf8_lossy(&r.stderr);
        assert!(err.contains("bad.toml"), "{err}");
        assert!(err.contains(want), "{want}: {err}");
        assert!(!out.exists(), "no output for {to}");
    }
}

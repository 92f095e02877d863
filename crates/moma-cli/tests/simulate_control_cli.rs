//! `moma simulate` in closed loop: every shipped `scenarios/control_*.toml` runs, writes
//! its tracking-error, Lyapunov and torque plots and a summary whose monitors say what
//! the law did; bad `[controller]` / `[reference]` tables fail with one message naming
//! the file and field, and no output; a missed goal tolerance ends with status 3 after
//! the outputs are written.

use std::path::{Path, PathBuf};

mod cli_common;

use cli_common::{scenarios, simulate as run, summary, temp_dir};

fn f(v: &serde_json::Value) -> f64 {
    v.as_f64().unwrap()
}

#[test]
fn shipped_control_scenarios_run_and_report() {
    let work = temp_dir("shipped");
    let mut names: Vec<String> = std::fs::read_dir(scenarios())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("control_") && n.ends_with(".toml"))
        .collect();
    names.sort();
    assert!(names.len() >= 12, "{names:?}");
    for name in &names {
        let out = work.join(name.trim_end_matches(".toml"));
        let r = run(&scenarios().join(name), &out);
        assert!(
            r.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&r.stderr)
        );
        let s = summary(&out);
        let files: Vec<&str> = s["files"]
            .as_array()
            .unwrap()
            .iter()
            .map(|x| x.as_str().unwrap())
            .collect();
        for want in [
            "trajectory.csv",
            "control.csv",
            "tracking_error.svg",
            "inputs.svg",
        ] {
            assert!(
                files.contains(&want) && out.join(want).is_file(),
                "{name}: {want}"
            );
        }
        let has_v = s["lyapunov"].is_object();
        assert_eq!(out.join("lyapunov.svg").is_file(), has_v, "{name}");
        assert_eq!(
            has_v,
            !name.contains("astolfi") && !name.contains("pure_pursuit"),
            "{name}: which laws have V"
        );
        // the plant's own monitors stay clean in closed loop
        assert!(f(&s["max_constraint_residual"]) < 1e-9, "{name}");
        assert!(f(&s["relative_energy_error"]) < 1e-5, "{name}");
        if let Some(true) = s["goal_reached"].as_bool() {
            assert!(f(&s["final_error_norm"]) <= f(&s["goal_tolerance"]));
        }
        let csv = std::fs::read_to_string(out.join("control.csv")).unwrap();
        assert_eq!(
            csv.lines().count(),
            s["samples"].as_u64().unwrap() as usize + 1
        );
        let svg = std::fs::read_to_string(out.join("tracking_error.svg")).unwrap();
        assert!(
            svg.starts_with("<svg") || svg.starts_with("<?xml"),
            "{name}"
        );
        match name.as_str() {
            "control_kanayama_saturated.toml" => {
                let sat = &s["saturation"];
                assert!(sat["speed_limited"].as_u64().unwrap() > 0);
                assert!(sat["torque_limited"].as_u64().unwrap() > 0);
                assert_eq!(f(&sat["first_torque_limited_t"]), 0.0);
                let l = &s["lyapunov"];
                assert!(!l["monotone"].as_bool().unwrap());
                assert!(f(&l["first_violations"][0]["t"]) > 0.0);
            }
            "control_m5_pd_plus.toml"
            | "control_m5_computed_torque.toml"
            | "control_m5_decoupled_compensated.toml" => {
                let l = &s["lyapunov"];
                assert!(l["monotone"].as_bool().unwrap(), "{name}");
                assert!(f(&l["v_last"]) < 0.1 * f(&l["v_first"]), "{name}");
            }
            "control_m5_decoupled_naive.toml" => {
                // the dropped coupling shows: V departs from its ideal integral
                let l = &s["lyapunov"];
                assert!(f(&l["max_integral_error"]) > 1e-4, "{name}");
            }
            "control_coordinated.toml" => {
                // the tool follows the line beyond the arm's reach; the platform drove
                assert_eq!(s["goal_reached"].as_bool(), Some(true));
                assert!(f(&s["final_error_norm"]) < 1e-4);
                assert!(s["final_q"][0].as_f64().unwrap() > 1.9);
                assert!(files.contains(&"manipulability.svg"));
                let header = csv.lines().next().unwrap();
                assert!(header.ends_with(",manipulability [m^2]"), "{header}");
                let l = &s["lyapunov"];
                assert!(f(&l["v_last"]) < 1e-6 * f(&l["v_first"]));
            }
            "control_kanayama_map.toml" => {
                // reaches the planned goal across the depot
                assert_eq!(s["reference"].as_str(), Some("planned"));
                assert_eq!(s["goal_reached"].as_bool(), Some(true));
                let q = &s["final_q"];
                let (x, y, th) = (f(&q[0]), f(&q[1]), f(&q[2]));
                let axle = (x - 0.1 * th.cos(), y - 0.1 * th.sin());
                assert!((axle.0 - 17.0).hypot(axle.1 - 7.3) < 0.01, "{axle:?}");
            }
            "control_osc_panda.toml" => {
                assert_eq!(f(&s["control_period"]), 0.002);
                assert_eq!(s["control_ticks"].as_u64().unwrap(), 2000);
                assert!(f(&s["final_error_norm"]) < 1e-3);
            }
            _ => {}
        }
        if name.starts_with("control_m5") {
            assert!(s["control_period"].is_null());
        }
    }
    let _ = std::fs::remove_dir_all(&work);
}

fn write_scenario(dir: &Path, name: &str, body: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, body).unwrap();
    // the URDF is found relative to the scenario
    let robots = dir.join("robots");
    std::fs::create_dir_all(&robots).unwrap();
    std::fs::copy(
        scenarios().join("robots/diffdrive_arm.urdf"),
        robots.join("diffdrive_arm.urdf"),
    )
    .unwrap();
    p
}

const HEAD: &str = r#"
duration = 1.0
[robot]
kind = "urdf"
urdf = "robots/diffdrive_arm.urdf"
drive = { r_w = 0.08, b = 0.25, d = 0.1 }
[integrator]
method = "rk4"
dt = 0.002
"#;

#[test]
fn bad_controller_tables_fail_cleanly() {
    let work = temp_dir("bad");
    let cases: [(&str, &str); 12] = [
        (
            "[controller]\nlaw = \"coordinated\"\nframe = \"tool\"\ngains = { K_E = 2.0, K_Y = 1.0 }\n[reference]\nkind = \"ee_line\"\nfrom = [0, 0, 0]\nto = [1, 0, 0]\nduration = 1.0\n",
            "controller.joints: missing",
        ),
        (
            "[controller]\nlaw = \"kanayama\"\ngains = { Kx = 1.0, Ky = 4.0, Kth = 4.0 }\n[reference]\nkind = \"planned\"\nmap = \"nowhere.yaml\"\nstart = [0, 0, 0]\ngoal = [1, 0, 0]\nfootprint_radius = 0.2\ntiming = { v_max = 0.5, omega_max = 1.0, a_max = 0.5, alpha_max = 1.0 }\n",
            "reference.map nowhere.yaml",
        ),
        (
            "[controller]\nlaw = \"bogus\"\n[reference]\nkind = \"pose\"\ngoal = [0, 0, 0]\n",
            "controller.law = \"bogus\": unknown law",
        ),
        (
            "[controller]\nlaw = \"kanayama\"\ngains = { Kx = 1.0, Ky = 4.0 }\n[reference]\nkind = \"circle\"\nvr = 0.4\nwr = 0.2\n",
            "controller.gains.Kth: missing",
        ),
        (
            "[controller]\nlaw = \"samson\"\ngains = { k1 = 1.0, k2 = 1.0, k3 = 1.0, k4 = 2.0 }\n[reference]\nkind = \"pose\"\ngoal = [0, 0, 0]\n",
            "controller.gains.k4: unknown gain",
        ),
        (
            "[controller]\nlaw = \"astolfi\"\ngains = { k_rho = 1.0, k_alpha = 3.0, k_beta = 0.5 }\n[reference]\nkind = \"pose\"\ngoal = [0, 0, 0]\n",
            "k_beta < 0 violated",
        ),
        (
            "[controller]\nlaw = \"aicardi\"\ngains = { gamma = 1.0, k = 1.0, h = 1.0 }\n[reference]\nkind = \"circle\"\nvr = 0.4\nwr = 0.2\n",
            "reference.kind = \"circle\" does not fit law aicardi",
        ),
        (
            "[controller]\nlaw = \"kanayama\"\ngains = { Kx = 1.0, Ky = 4.0, Kth = 4.0 }\n",
            "[reference] is missing",
        ),
        (
            "[controller]\nlaw = \"kanayama\"\nperiod = -0.01\ngains = { Kx = 1.0, Ky = 4.0, Kth = 4.0 }\n[reference]\nkind = \"line\"\nvr = 0.4\n",
            "controller.period",
        ),
        (
            "[controller]\nlaw = \"kanayama\"\ngains = { Kx = 1.0, Ky = 4.0, Kth = 4.0 }\n[reference]\nkind = \"line\"\nvr = 0.4\n[[inputs]]\nkind = \"constant\"\nvalue = 0.0\n",
            "[[inputs]] and [controller] exclude each other",
        ),
        (
            "[controller]\nlaw = \"osc\"\ngains = { kp = 1.0, kv = 2.0 }\n[reference]\nkind = \"ee_line\"\nfrom = [0, 0, 0]\nto = [1, 0, 0]\nduration = 1.0\n",
            "controller.frame: missing",
        ),
        (
            "[controller]\nlaw = \"pd_plus\"\ngains = { Kp = [1, 1, 1, 1, 1], Kd = [1, 1, 1, 1, 1] }\n[reference]\nkind = \"pose\"\ngoal = [0, 0, 0]\n",
            "runs on the chapter model m5",
        ),
    ];
    for (i, (body, want)) in cases.iter().enumerate() {
        let p = write_scenario(&work, &format!("bad{i}.toml"), &format!("{HEAD}{body}"));
        let out = work.join(format!("out{i}"));
        let r = run(&p, &out);
        let err = String::from_utf8_lossy(&r.stderr);
        assert_eq!(r.status.code(), Some(1), "case {i}: {err}");
        assert!(err.contains(want), "case {i}: {err}");
        assert!(
            err.contains(&format!("bad{i}.toml")),
            "case {i} names the file: {err}"
        );
        assert!(!out.exists(), "case {i} wrote output");
    }
    let _ = std::fs::remove_dir_all(&work);
}

#[test]
fn missed_goal_tolerance_is_status_3_with_outputs() {
    let work = temp_dir("goal");
    let body = "[controller]\nlaw = \"aicardi\"\nperiod = 0.01\ngains = { gamma = 0.6, k = 1.5, h = 1.0 }\ngoal_tolerance = 1e-6\n[reference]\nkind = \"pose\"\ngoal = [1.0, 0.5, 0.0]\n";
    let p = write_scenario(&work, "goal.toml", &format!("{HEAD}{body}"));
    let out = work.join("out");
    let r = run(&p, &out);
    assert_eq!(
        r.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&r.stderr)
    );
    assert!(String::from_utf8_lossy(&r.stderr).contains("goal_tolerance"));
    let s = summary(&out);
    assert_eq!(s["goal_reached"].as_bool(), Some(false));
    let _ = std::fs::remove_dir_all(&work);
}

/// A 4 m × 4 m ROS map (5 cm cells) with a closed 1 m box in the middle.
fn write_box_map(dir: &Path) {
    let (w, h) = (80usize, 80usize);
    let mut px = vec![254u8; w * h];
    for i in 30..=50 {
        for (x, y) in [(i, 30), (i, 50), (30, i), (50, i)] {
            px[y * w + x] = 0;
        }
    }
    let mut pgm = format!("P5\n{w} {h}\n255\n").into_bytes();
    pgm.extend_from_slice(&px);
    std::fs::write(dir.join("box.pgm"), pgm).unwrap();
    std::fs::write(
        dir.join("box.yaml"),
        "image: box.pgm\nmode: trinary\nresolution: 0.05\norigin: [0.0, 0.0, 0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.25\n",
    )
    .unwrap();
}

#[test]
fn a_planned_reference_reaches_its_goal_and_an_unreachable_goal_is_an_error() {
    let work = temp_dir("planned");
    write_box_map(&work);
    let body = |goal: &str| {
        format!(
            "{HEAD}[initial]\nq = [0.7, 0.6, 0.0, 0.0, 0.0, 0.0, 2.8, 0.3]\n[controller]\nlaw = \"kanayama\"\nperiod = 0.02\ngains = {{ Kx = 2.0, Ky = 8.0, Kth = 4.0 }}\ngoal_tolerance = 0.03\n[reference]\nkind = \"planned\"\nmap = \"box.yaml\"\nstart = [0.6, 0.6, 0.0]\ngoal = {goal}\nfootprint_radius = 0.2\ntiming = {{ v_max = 0.5, omega_max = 1.0, a_max = 0.5, alpha_max = 1.0 }}\n[output]\nrecord_interval = 0.05\n"
        )
        .replace("duration = 1.0", "duration = 14.0")
    };
    // around the box to the far corner
    let p = write_scenario(&work, "reach.toml", &body("[3.4, 3.4, 1.5707963]"));
    let out = work.join("reach");
    let r = run(&p, &out);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    let s = summary(&out);
    assert_eq!(s["goal_reached"].as_bool(), Some(true), "{s}");
    // inside the closed box: status 1, the goal named, nothing written
    let p = write_scenario(&work, "sealed.toml", &body("[2.0, 2.0, 0.0]"));
    let out = work.join("sealed");
    let r = run(&p, &out);
    let err = String::from_utf8_lossy(&r.stderr);
    assert_eq!(r.status.code(), Some(1), "{err}");
    assert!(
        err.contains("sealed.toml")
            && err.contains("reference.goal")
            && err.contains("unreachable"),
        "{err}"
    );
    assert!(!out.exists());
    let _ = std::fs::remove_dir_all(&work);
}

/// The stiff m5 closed loop the fuzzer found (one damping gain of 2.3e8 under the
/// adaptive integrator, the input CI replays from `fuzz/regressions/sim_scenario/`) ran
/// for many minutes; it now stops at the run's default step budget within seconds, with
/// status 1, one message naming the integrator, the budget, the time reached and what
/// to change, and no output. A budget the scenario sets is named as its key, and one out
/// of bounds is refused before the run.
#[test]
fn a_stiff_loop_stops_at_the_step_budget() {
    let work = temp_dir("stiff");
    let regression = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fuzz/regressions/sim_scenario/m5-computed-torque-stiff-kd.toml");
    let text = std::fs::read_to_string(&regression).unwrap();
    let cases = [
        (
            "default",
            text.clone(),
            vec!["step budget of 100000 steps", "the default"],
        ),
        (
            "set",
            text.replace("atol = 1e-9", "atol = 1e-9\nmax_steps = 5000"),
            vec!["step budget of 5000 steps", "integrator.max_steps"],
        ),
    ];
    for (tag, body, needles) in cases {
        let file = work.join(format!("{tag}.toml"));
        std::fs::write(&file, body).unwrap();
        let out = work.join(format!("out-{tag}"));
        let o = run(&file, &out);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{tag}: {err}");
        assert!(
            err.starts_with("error:") && !err.contains("panicked"),
            "{err}"
        );
        for n in needles.iter().chain(&[
            "Dormand-Prince 5(4)",
            "ran out at t = ",
            "of 4 s",
            "method = \"rk4\"",
            "smaller gains",
        ]) {
            assert!(err.contains(n), "{tag}: lacks {n}: {err}");
        }
        assert!(!out.exists(), "{tag}: output left behind");
    }
    let file = work.join("zero.toml");
    std::fs::write(
        &file,
        text.replace("atol = 1e-9", "atol = 1e-9\nmax_steps = 0"),
    )
    .unwrap();
    let o = run(&file, &work.join("out-zero"));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("integrator.max_steps"), "{err}");
    let _ = std::fs::remove_dir_all(&work);
}

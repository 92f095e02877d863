//! `moma::sim_config`: every shipped `moma simulate` scenario builds into the run its tables
//! ask for, and a scenario that cannot run gets the message that names its file and field.

use std::path::{Path, PathBuf};

use moma::sim_config::{Run, Scenario, load, prepare};

fn scenarios() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios")
}

fn kind(run: &Run) -> &'static str {
    match run {
        Run::Open(_) => "open",
        Run::Closed(_) => "closed",
        Run::Space(_) => "space",
    }
}

#[test]
fn every_shipped_scenario_builds_its_run() {
    let mut seen = 0;
    for entry in std::fs::read_dir(scenarios()).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        if !name.ends_with(".toml") || name.starts_with("mission") {
            continue;
        }
        let sc: Scenario = load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        sc.check_header(&path).unwrap();
        if name.starts_with("contact_") {
            let run = moma::sim_config::contact::prepare_contact(&sc, &path)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            assert_eq!(run.q0.len(), run.map.robot.model.nq, "{name}");
            seen += 1;
            continue;
        }
        let run = prepare(&sc, &path).unwrap_or_else(|e| panic!("{name}: {e}"));
        let want = if ["control_", "uncertainty_", "mpc_"]
            .iter()
            .any(|p| name.starts_with(p))
        {
            "closed"
        } else if name.starts_with("space_") {
            "space"
        } else {
            "open"
        };
        assert_eq!(kind(&run), want, "{name}");
        match &run {
            Run::Open(ol) => {
                assert_eq!(ol.q0.len(), ol.system.nq(), "{name}");
                assert_eq!(ol.monitor.is_some(), sc.stability.is_some(), "{name}");
            }
            Run::Closed(cl) => {
                assert_eq!(cl.v0.len(), cl.system.nv(), "{name}");
                assert!(cl.options.lyapunov_tolerance > 0.0, "{name}");
            }
            Run::Space(sr) => assert_eq!(sr.v0.len(), sr.model.nv, "{name}"),
        }
        seen += 1;
    }
    assert!(seen >= 25, "only {seen} simulate scenarios found");
}

fn edited(file: &str, from: &str, to: &str) -> (Scenario, PathBuf) {
    let path = scenarios().join(file);
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(from), "{file} has no {from:?}");
    let text = text.replacen(from, to, 1);
    let sc = moma::sim_config::schema::parse_scenario(&text, &path).unwrap();
    (sc, path)
}

fn message(file: &str, from: &str, to: &str) -> String {
    let (sc, path) = edited(file, from, to);
    match prepare(&sc, &path) {
        Ok(_) => panic!("{file} with {to:?} built"),
        Err(e) => {
            assert!(matches!(e, moma::Error::Scenario(_)), "{e:?}");
            e.to_string()
        }
    }
}

#[test]
fn errors_name_the_file_and_the_field() {
    let m = message(
        "control_kanayama.toml",
        "[controller]",
        "[controller]\nmax_torque = -1.0",
    );
    assert!(
        m.contains(
            "control_kanayama.toml: controller.max_torque must be a positive finite number, got -1"
        ),
        "{m}"
    );
    let m = message(
        "control_kanayama.toml",
        "law = \"kanayama\"",
        "law = \"nope\"",
    );
    assert!(m.contains("controller.law = \"nope\": unknown law"), "{m}");
    let m = message("brake_arm_tucked.toml", "mu = 0.9", "mu = 0.0");
    assert!(
        m.contains(
            "brake_arm_tucked.toml: stability: stability.mu must be a positive finite number, got 0"
        ),
        "{m}"
    );
    let m = message(
        "space_capture.toml",
        "inertia_diagonal = [0.03",
        "inertia_diagonal = [-0.03",
    );
    assert!(
        m.ends_with("space_capture.toml: space.capture.inertia_diagonal must not be negative"),
        "{m}"
    );
}

/// Extreme `[uncertainty]` draws (a payload of 1e300 kg or 1e300 m off its link, a mass
/// scale of 1e-300, a noise of 1e300) are refused before the run, naming the field and
/// the bound; they used to end the run in a singular mass matrix or a non-finite energy.
#[test]
fn extreme_uncertainty_draws_name_the_field_and_the_bound() {
    let file = "uncertainty_brake.toml";
    let payload = "payload = { link = \"payload\", mass = { uniform = [0.0, 1.0] }, position = [{ uniform = [0.0, 0.05] }, 0.0, 0.0] }";
    for (from, to, want) in [
        (
            payload,
            "payload = { link = \"payload\", mass = 1e300 }",
            "uncertainty.payload.mass: can draw 1e300, beyond the bound 1e4",
        ),
        (
            payload,
            "payload = { link = \"payload\", mass = 1.0, position = [1e300, 0.0, 0.0] }",
            "uncertainty.payload.position[0]: can draw 1e300, beyond the bound 1e2",
        ),
        (
            "link_mass_scale = { normal = [1.0, 0.03] }",
            "link_mass_scale = 1e-300",
            "uncertainty.link_mass_scale: can draw 1e-300, the value must be >= 0.001",
        ),
        (
            "q = [0.002,",
            "q = [1e300,",
            "uncertainty.sensor_noise.q[0] must be a number in [0, 100], got 1e300",
        ),
    ] {
        let m = message(file, from, to);
        assert!(m.contains(&format!("{file}: {want}")), "{to}: {m}");
    }
}

/// Law `mpc`: a key the `[controller.mpc]` table does not have, a horizon that is not a
/// positive number of stages or of seconds, and the law on a robot that is not a URDF
/// robot on a differential drive each get a message naming the file and the field.
#[test]
fn mpc_errors_name_the_file_and_the_field() {
    let file = "mpc_reach_on_the_move.toml";
    let path = scenarios().join(file);
    let text = std::fs::read_to_string(&path).unwrap().replacen(
        "stages = 20",
        "stages = 20\nhorizon = 1.0",
        1,
    );
    let parsed: moma::Result<Scenario> = moma::sim_config::schema::parse_scenario(&text, &path);
    let Err(e) = parsed else {
        panic!("an unknown key parsed")
    };
    let m = e.to_string();
    assert!(m.contains("mpc_reach_on_the_move.toml"), "{m}");
    assert!(m.contains("unknown field `horizon`"), "{m}");
    let m = message(file, "stages = 20", "stages = -5");
    assert!(
        m.contains(
            "mpc_reach_on_the_move.toml: controller.mpc.stages must be between 1 and 10000, got -5"
        ),
        "{m}"
    );
    let m = message(file, "dt = 0.05", "dt = -0.05");
    assert!(
        m.contains(
            "mpc_reach_on_the_move.toml: controller.mpc.dt must be a positive finite number, got -0.05"
        ),
        "{m}"
    );
    // No map in moma simulate: the map-clearance key of moma mission's table is refused.
    let m = message(
        file,
        "clearance = 0.03",
        "clearance = 0.03\nmap_clearance = 0.1",
    );
    assert!(
        m.contains(
            "mpc_reach_on_the_move.toml: controller.mpc.map_clearance: moma simulate has no map"
        ),
        "{m}"
    );
    let m = message(file, "ee_orientation = 0.0", "ee_orientation = -1.0");
    assert!(
        m.contains("controller.mpc.weights.ee_orientation must not be negative, got -1"),
        "{m}"
    );
    let m = message(
        "control_m5_pd_plus.toml",
        "law = \"pd_plus\"",
        "law = \"mpc\"",
    );
    assert!(
        m.contains(
            "control_m5_pd_plus.toml: law mpc drives a URDF robot on a differential drive (robot.kind = \"urdf\")"
        ),
        "{m}"
    );
}

/// The stiff closed loop the fuzzer found (the m5 computed-torque law with one damping
/// gain of 2.3e8 under the adaptive integrator; `fuzz/regressions/sim_scenario/`): its
/// Dormand–Prince steps are near 1e-8 s, so the run stops at its step budget, shared by
/// all recording intervals, with an error naming the integrator, the budget, the time
/// reached and the fixed-step integrator, instead of running for many minutes.
#[test]
fn a_stiff_closed_loop_stops_at_the_step_budget_of_the_whole_run() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../fuzz/regressions/sim_scenario/m5-computed-torque-stiff-kd.toml");
    let mut sc: Scenario = load(&path).unwrap();
    sc.check_header(&path).unwrap();
    // a small budget keeps the test short; the default one is exercised by the CLI test
    let moma::sim::settings::IntegratorSettings::Adaptive { max_steps, .. } = &mut sc.integrator
    else {
        panic!("the regression runs the adaptive integrator")
    };
    *max_steps = Some(5_000);
    let Run::Closed(mut cl) = prepare(&sc, &path).unwrap() else {
        panic!("a closed loop")
    };
    let err = cl.run(&mut |_| {}).unwrap_err();
    let moma::Error::Numerical { t, message } = &err else {
        panic!("{err}")
    };
    // steps near 1e-8 s: 5,000 of them reach well under a millisecond (the first
    // recording interval is 10 ms)
    assert!(*t > 0.0 && *t < 1e-3, "{err}");
    for needle in [
        "Dormand-Prince 5(4)",
        "step budget of 5000 steps",
        "integrator.max_steps",
        "of 4 s",
        "method = \"rk4\"",
        "smaller gains",
    ] {
        assert!(message.contains(needle), "lacks {needle}: {err}");
    }
}

/// A run too long to record names the field the user set (`duration`) and the bound it
/// breaks, for every kind of run, before any buffer is sized.
#[test]
fn a_run_too_long_to_record_names_duration_and_the_bound() {
    for (file, from) in [
        ("default.toml", "duration = 5.0"),
        ("control_kanayama.toml", "duration = "),
        ("space_capture.toml", "duration = "),
    ] {
        let path = scenarios().join(file);
        let text = std::fs::read_to_string(&path).unwrap();
        let line = text
            .lines()
            .find(|l| l.starts_with(from))
            .unwrap_or_else(|| panic!("{file} has no {from:?}"))
            .to_string();
        let m = message(file, &line, "duration = 1e12");
        assert!(
            m.contains(&format!("{file}: duration = 1e12 s"))
                && m.contains("output.record_interval")
                && m.contains("1e7"),
            "{m}"
        );
    }
}

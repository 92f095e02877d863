//! What the `moma simulate` targets do with one scenario text: the whole schema read by
//! the library (`sim_config::schema::parse_scenario`; the command's own `[space]`,
//! `[stability]`, `[controller]` and `[reference]` tables as any TOML table), the header
//! checks, the integrator and the input profiles validated, the profiles evaluated at
//! four times (a validated profile must give finite inputs), and, for a chapter model or
//! a URDF robot (its path kept on the shipped robots), the system built and the initial
//! state and inputs checked against its sizes (`Scenario::initial_state`).
//!
//! Then the same text is read with the command's own tables (`moma::sim_config::Scenario`)
//! and goes through the library's whole build (`moma::sim_config::prepare`: the robot, the
//! `[space]`, `[stability]`, `[controller]` and `[reference]` checks, the closed loop, the
//! free-floating run, the stability monitor), its URDF and map paths kept on shipped
//! files, and a run it builds is simulated over a horizon capped at 10 ms (skipped when
//! the step, control period or recording interval would take more than a few hundred
//! steps in it, or the adaptive tolerances are tighter than 1e-10) and with a step
//! budget of 2,000 integrator steps for the whole run (`integrator.max_steps`), so an
//! input stays around a millisecond.

use std::path::{Path, PathBuf};

use moma::sim::reduced_system::ReducedSystem;
use moma::sim::settings::InputProfile;
use moma::sim_config::schema::{RobotSpec, Scenario, parse_scenario};

/// The robots a fuzzed scenario may load, relative to `scenarios/`.
const ROBOTS: [&str; 5] = [
    "robots/mobile_manipulator_mount.urdf",
    "robots/diffdrive_arm.urdf",
    "robots/brake_test_robot.urdf",
    "robots/mobile_manipulator.urdf",
    "robots/panda.urdf",
];

fn urdf_path(p: &Path) -> PathBuf {
    let p = p.to_string_lossy();
    let kept = if ROBOTS.contains(&p.as_ref()) {
        &p
    } else {
        ROBOTS[p.len() % ROBOTS.len()]
    };
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenarios")
        .join(kept)
}

fn system(sc: &Scenario) -> Option<Box<dyn ReducedSystem>> {
    // The command's own builder, on the robot with its URDF kept on a shipped file.
    let mut spec = sc.robot.clone();
    if let RobotSpec::Urdf { urdf, .. } | RobotSpec::FixedBase { urdf } = &mut spec {
        *urdf = urdf_path(urdf);
    }
    moma::sim_config::robot::build_robot(&spec, sc.gravity, Path::new("."))
        .ok()
        .map(|(sys, _)| sys)
}

/// The maps a fuzzed `planned` reference may load, relative to `scenarios/`.
const MAPS: [&str; 3] = ["maps/depot.yaml", "maps/potential_trap.map", "maps/depot.pgm"];

/// The longest simulated horizon of a fuzzed run (s).
const HORIZON: f64 = 0.01;

/// Most steps (integrator steps, control ticks, recorded samples) a fuzzed run may take.
const MAX_STEPS: f64 = 400.0;

/// The step budget of a fuzzed run (`integrator.max_steps`, capped).
const FUZZ_MAX_STEPS: u64 = 2_000;

/// A shipped map for a fuzzed map path.
fn map_path(p: &Path) -> PathBuf {
    let p = p.to_string_lossy();
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../scenarios")
        .join(crate::files::pick(&p, &MAPS))
}

/// Keeps every file the scenario names on shipped files, and caps the horizon; `false`
/// when the run would take too many steps to simulate here.
fn confine(sc: &mut moma::sim_config::Scenario) -> bool {
    use moma::sim_config::ReferenceSpec;
    match &mut sc.robot {
        RobotSpec::Urdf { urdf, .. }
        | RobotSpec::FixedBase { urdf }
        | RobotSpec::FreeFloating { urdf, .. } => *urdf = urdf_path(urdf),
        RobotSpec::Chapter { .. } => {}
    }
    if let Some(ReferenceSpec::Planned { map, .. }) = &mut sc.reference {
        *map = map_path(map);
    }
    sc.duration = sc.duration.min(HORIZON);
    // One step budget for the whole run (every integrator step, over all recording
    // intervals, control ticks and phases): a stiff loop stops at it with an error.
    match &mut sc.integrator {
        moma::sim::settings::IntegratorSettings::Rk4 { max_steps, .. }
        | moma::sim::settings::IntegratorSettings::Adaptive { max_steps, .. } => {
            *max_steps = Some(max_steps.unwrap_or(FUZZ_MAX_STEPS).clamp(1, FUZZ_MAX_STEPS));
        }
    }
    let few = |step: f64| step.is_finite() && step > 0.0 && sc.duration / step <= MAX_STEPS;
    let integrator = match sc.integrator {
        moma::sim::settings::IntegratorSettings::Rk4 { dt, .. } => few(dt),
        moma::sim::settings::IntegratorSettings::Adaptive { rtol, atol, .. } => {
            rtol >= 1e-10 && atol >= 1e-10
        }
    };
    let period = sc
        .controller
        .as_ref()
        .and_then(|c| c.period)
        .is_none_or(few);
    integrator && period && few(sc.output.record_interval)
}

/// The library's whole build of a scenario with the command's tables, and a short run.
fn build_and_run(text: &str) {
    use moma::sim_config::Run;
    let path = Path::new("fuzz.toml");
    let Ok(mut sc) = parse_scenario::<
        moma::sim_config::SpaceSpec,
        moma::sim_config::StabilitySpec,
        moma::sim_config::ControllerSpec,
        moma::sim_config::ReferenceSpec,
    >(text, path) else {
        return;
    };
    if sc.check_header(path).is_err() {
        return;
    }
    let short = confine(&mut sc);
    let Ok(run) = moma::sim_config::prepare(&sc, path) else {
        return;
    };
    if !short {
        return;
    }
    match run {
        Run::Open(mut ol) => {
            let _ = ol.run(&mut |_| {});
        }
        Run::Closed(mut cl) => {
            if let Ok(res) = cl.run(&mut |_| {})
                && let Some(spec) = &sc.stability
            {
                let _ = moma::sim_config::replay(spec, &sc.robot, sc.gravity, Path::new("."), &res.recorder);
            }
        }
        Run::Space(sr) => {
            let _ = moma::sim::free_floating::run(&sr.model, &sr.q0, &sr.v0, &sr.settings);
        }
    }
}

pub fn check(text: &str) {
    build_and_run(text);
    let path = Path::new("fuzz.toml");
    let Ok(sc) = parse_scenario::<toml::Table, toml::Table, toml::Table, toml::Table>(text, path)
    else {
        return;
    };
    let header = sc.check_header(path).is_ok();
    let _ = sc.integrator.validate();
    if let Some(channels) = &sc.inputs
        && channels.len() <= 64
        && channels
            .iter()
            .enumerate()
            .all(|(k, c)| c.validate(&format!("inputs[{k}]")).is_ok())
    {
        let p = InputProfile {
            channels: channels.clone(),
        };
        let mut u = vec![0.0; p.channels.len()];
        for t in [0.0, 0.5, 1e9, -1.0] {
            p.eval(t, &mut u);
            assert!(
                u.iter().all(|x| x.is_finite()),
                "a validated profile gave {u:?}"
            );
        }
    }
    if !header {
        return;
    }
    if let Some(sys) = system(&sc)
        && let Ok((q, v, u)) = sc.initial_state(sys.as_ref(), path)
    {
        assert_eq!((q.len(), v.len()), (sys.nq(), sys.nv()));
        assert_eq!(u.channels.len(), sys.nu());
        assert!(q.iter().chain(&v).all(|x| x.is_finite()));
    }
}

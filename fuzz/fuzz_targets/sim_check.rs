//! What the `moma simulate` targets do with one scenario text: the whole schema read by
//! the library (`sim::scenario::parse_scenario`; the command's own `[space]`,
//! `[stability]`, `[controller]` and `[reference]` tables as any TOML table), the header
//! checks, the integrator and the input profiles validated, the profiles evaluated at
//! four times (a validated profile must give finite inputs), and, for a chapter model or
//! a URDF robot (its path kept on the shipped robots), the system built and the initial
//! state and inputs checked against its sizes (`Scenario::initial_state`). Nothing is
//! simulated.

use std::path::{Path, PathBuf};

use moma::sim::scenario::{InputProfile, RobotSpec, Scenario, parse_scenario};
use moma::sim::wheeled::ReducedSystem;

/// The robots a fuzzed scenario may load, relative to `scenarios/`.
const ROBOTS: [&str; 4] = [
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
    use moma::multibody::RootJoint;
    match &sc.robot {
        RobotSpec::Chapter { model, params } => {
            let json = serde_json::to_value(params).ok()?;
            moma::sim::chapter_models::chapter_system(model, &json).ok()
        }
        RobotSpec::Urdf {
            urdf,
            drive,
            wheel_joints,
            casters,
        } => {
            use moma::mobile::{Caster, DiffDrive, WheeledBase, WheeledModel};
            let model =
                moma::io::urdf::model_from_urdf_file(&urdf_path(urdf), RootJoint::Planar).ok()?;
            let base = WheeledBase {
                drive: DiffDrive::new(drive.r_w, drive.b, drive.d).ok()?,
                casters: casters
                    .iter()
                    .map(|c| Caster {
                        name: c.name.clone(),
                        position: c.position,
                    })
                    .collect(),
                wheel_joints: wheel_joints.clone(),
            };
            let wm = WheeledModel::new(model, base).ok()?;
            Some(Box::new(moma::sim::wheeled_system::WheeledSystem::new(wm)))
        }
        RobotSpec::FixedBase { urdf } => {
            let model =
                moma::io::urdf::model_from_urdf_file(&urdf_path(urdf), RootJoint::Fixed).ok()?;
            Some(Box::new(
                moma::sim::fixed_base::FixedBaseSystem::new(model).ok()?,
            ))
        }
        RobotSpec::FreeFloating { .. } => None,
    }
}

pub fn check(text: &str) {
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

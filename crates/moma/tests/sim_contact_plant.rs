//! `plant = "contact"` in a `moma simulate` scenario (`moma::sim_config::contact`,
//! `moma::sim::contact_run`): the shipped contact scenarios run, the coordinated law on the
//! contact plant follows the rolling plant's run of the same file, the hard brake lifts the
//! casters when the rolling run's ZMP leaves the support polygon, a caster given by its
//! position in a link is the caster on the frame there, the state map round-trips through
//! the rolling model's own velocity basis, and bad input names the field.

use std::path::{Path, PathBuf};

use moma::sim::contact_run::ContactResult;
use moma::sim::stability_monitor::first_crossing;
use moma::sim::wheeled::{SampleObserver, simulate_observed};
use moma::sim_config::contact::prepare_contact;
use moma::sim_config::schema::parse_scenario;
use moma::sim_config::{Run, Scenario, prepare};

fn scenario_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios")
        .join(name)
}

/// The scenario `name` with `edit` applied to its text; its path stays in `scenarios/`,
/// so relative robot paths resolve.
fn scenario(name: &str, edit: impl Fn(String) -> String) -> (Scenario, PathBuf) {
    let path = scenario_path(name);
    let text = edit(std::fs::read_to_string(&path).unwrap());
    let sc: Scenario = parse_scenario(&text, &path).unwrap();
    sc.check_header(&path).unwrap();
    (sc, path)
}

fn run_contact(sc: &Scenario, path: &Path) -> ContactResult {
    let mut run = prepare_contact(sc, path).unwrap();
    run.run(&mut |_| {}).unwrap()
}

/// The rolling plant's file of a contact scenario: `plant` and `[contact]` removed.
fn rolling(text: String) -> String {
    let text = text.replace("plant = \"contact\"\n", "");
    text.split("\n[contact]").next().unwrap().to_string()
}

fn column(res: &ContactResult, name: &str) -> Vec<f64> {
    let j = res
        .column_names()
        .iter()
        .position(|c| c == name)
        .unwrap_or_else(|| panic!("no column {name}"));
    res.rows.iter().map(|r| r[j]).collect()
}

#[test]
fn the_coordinated_law_on_the_contact_plant_follows_the_rolling_run() {
    let (sc, path) = scenario("contact_coordinated.toml", |t| t);
    let c = run_contact(&sc, &path);
    assert!(
        c.first_lift_off.is_none() && c.first_slip.is_none(),
        "nothing should lift or slip: {:?} {:?}",
        c.first_lift_off,
        c.first_slip
    );
    let (sr, path_r) = scenario("contact_coordinated.toml", rolling);
    let Run::Closed(mut cl) = prepare(&sr, &path_r).unwrap() else {
        panic!("a closed loop")
    };
    let r = cl.run(&mut |_| {}).unwrap();
    let rec = &r.recorder;
    let (mut pos, mut yaw, mut joints, mut n) = (0.0f64, 0.0f64, 0.0f64, 0);
    for (i, &t) in rec.times.iter().enumerate() {
        let Some(k) = c.times.iter().position(|&tc| (tc - t).abs() < 1e-9) else {
            continue;
        };
        n += 1;
        let (a, b) = (&c.rows[k], rec.q_row(i));
        pos = pos.max((a[0] - b[0]).hypot(a[1] - b[1]));
        yaw = yaw.max((a[2] - b[2]).abs());
        // Arm joints (the wheel angles, 3 and 4, are not compared: they differ by the
        // creep of the compliant contacts, which the base position already shows).
        for j in 5..8 {
            joints = joints.max((a[j] - b[j]).abs());
        }
    }
    let last = rec.q_row(rec.len() - 1);
    let travelled = last[0].hypot(last[1]);
    eprintln!(
        "{n} samples over {} s ({travelled:.2} m): base {pos:.2e} m, heading {yaw:.2e} rad, arm {joints:.2e} rad",
        sc.duration
    );
    assert!(n > 500 && travelled > 1.5, "{n} samples, {travelled} m");
    // Tolerances (measured 0.21 mm, 0.25 mrad, 4.2 mrad): 1 mm, 2 mrad, 10 mrad. The arm
    // differs most: the contact plant's base sinks 0.7 mm and pitches a little under the
    // arm's motion, which the law's rolling model does not know.
    assert!(pos < 1e-3, "base position differs by {pos} m");
    assert!(yaw < 2e-3, "heading differs by {yaw} rad");
    assert!(joints < 1e-2, "arm joints differ by {joints} rad");
}

#[test]
fn the_hard_brake_lifts_the_casters_when_the_rolling_runs_zmp_leaves_the_support() {
    let (sc, path) = scenario("contact_brake_arm_extended.toml", |t| t);
    let c = run_contact(&sc, &path);
    let lift = c.first_lift_off.clone().expect("a caster should lift");
    assert!(lift.contact.starts_with("rear_"), "{lift:?}");
    assert!(c.first_slip.is_none(), "μ = 0.9 holds: {:?}", c.first_slip);
    // The rolling plant of the same file, with the stability monitor of the shipped
    // brake_arm_extended.toml (same robot, start and torques).
    let (sr, path_r) = scenario("brake_arm_extended.toml", |t| t);
    let Run::Open(mut ol) = prepare(&sr, &path_r).unwrap() else {
        panic!("an open loop")
    };
    let mut mon = ol.monitor.take().unwrap();
    simulate_observed(
        ol.system.as_mut(),
        &ol.input,
        &ol.q0,
        &ol.v0,
        &ol.options,
        &mut |_| {},
        Some(&mut mon as &mut dyn SampleObserver),
    )
    .unwrap();
    let tr = &mon.trace;
    let zmp = first_crossing(&tr.times, &tr.zmp_margin, true)
        .expect("the rolling run's ZMP leaves the support")
        .time;
    eprintln!(
        "rolling plant: ZMP leaves the support at {zmp:.4} s; contact plant: '{}' unloaded at {:.4} s; largest tilt {:.3} rad",
        lift.contact, lift.t, c.max_tilt
    );
    // Tolerance 10 ms (measured 4.4 ms): the compliant contacts take a few milliseconds
    // to unload, and the brake torque ramps at 112 N·m/s, so 10 ms is 1.1 N·m of brake.
    assert!(
        (lift.t - zmp).abs() < 0.01,
        "lift-off {} s vs ZMP {zmp} s",
        lift.t
    );
    assert!(
        c.max_tilt > 0.02,
        "the robot should pitch: {} rad",
        c.max_tilt
    );
    // The casters carry nothing while lifted: at least 0.1 s of it.
    let n = column(&c, "normal_rear_left_caster [N]");
    let lifted = n.iter().filter(|&&x| x == 0.0).count() as f64 * sc.output.record_interval;
    assert!(lifted > 0.1, "lifted for {lifted} s");
    // The same brake with the arm tucked (the start and holding torque of the shipped
    // brake_arm_tucked.toml, whose ZMP stays inside the support) lifts nothing.
    let (st, path_t) = scenario("contact_brake_arm_extended.toml", |t| {
        let t2 = t
            .replace(
                "q = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.5707963267948966, 0.0]",
                "q = [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.5707963267948966, 3.141592653589793]",
            )
            .replace("value = -44.6355", "value = 17.1675");
        assert_ne!(t, t2);
        t2
    });
    let tucked = run_contact(&st, &path_t);
    assert!(
        tucked.first_lift_off.is_none(),
        "tucked: {:?}",
        tucked.first_lift_off
    );
}

#[test]
fn a_caster_by_position_in_a_link_is_the_caster_on_the_frame_there() {
    // brake_test_robot.urdf's caster frames sit on fixed joints of base_link at
    // (−0.4, ±0.2, 0): the same casters by position give the same run to the bit, their
    // columns named by the link and the position.
    let (sc, path) = scenario("contact_brake_arm_extended.toml", |t| t);
    let on_frames = run_contact(&sc, &path);
    let (sp, path_p) = scenario("contact_brake_arm_extended.toml", |t| {
        let t2 = t
            .replace(
                "{ frame = \"rear_left_caster\", radius = 0.0 }",
                "{ link = \"base_link\", position = [-0.4, 0.2, 0.0], radius = 0.0 }",
            )
            .replace(
                "{ frame = \"rear_right_caster\", radius = 0.0 }",
                "{ link = \"base_link\", position = [-0.4, -0.2, 0.0], radius = 0.0 }",
            );
        assert_ne!(t, t2);
        t2
    });
    let by_position = run_contact(&sp, &path_p);
    assert_eq!(on_frames.rows, by_position.rows);
    assert_eq!(
        by_position.first_lift_off.as_ref().unwrap().t,
        on_frames.first_lift_off.as_ref().unwrap().t
    );
    let n = column(&by_position, "normal_base_link [-0.4 0.2 0] [N]");
    assert_eq!(n, column(&on_frames, "normal_rear_left_caster [N]"));
    // a link the description lacks, and a frame given with a position, name the field
    let e = contact_error("contact_brake_arm_extended.toml", |t| {
        t.replace(
            "{ frame = \"rear_left_caster\", radius = 0.0 }",
            "{ link = \"rear_axle\", position = [-0.4, 0.2, 0.0], radius = 0.0 }",
        )
    });
    assert!(
        e.contains("contact.casters[0].link") && e.contains("no link 'rear_axle'"),
        "{e}"
    );
    let e = contact_error("contact_brake_arm_extended.toml", |t| {
        t.replace(
            "{ frame = \"rear_right_caster\", radius = 0.0 }",
            "{ frame = \"rear_right_caster\", position = [-0.4, -0.2, 0.0], radius = 0.0 }",
        )
    });
    assert!(e.contains("contact.casters[1].position"), "{e}");
}

/// `caster_friction = true` in the `[contact]` table is the plant built with
/// `ContactPlant::with_caster_friction`: the same run to the bit, which differs from the
/// frictionless casters' (the casters carry the brake's horizontal load until they lift).
/// A value that is not a boolean is refused naming the field and the file.
#[test]
fn caster_friction_in_the_file_is_the_plants_caster_friction() {
    let brake = "contact_brake_arm_extended.toml";
    let with_friction = |t: String| t.replace("mu = 0.9", "mu = 0.9\ncaster_friction = true");
    let (sf, path_f) = scenario(brake, with_friction);
    let from_file = run_contact(&sf, &path_f);
    let (sc, path) = scenario(brake, |t| t);
    let mut run = prepare_contact(&sc, &path).unwrap();
    let frictionless = run.run(&mut |_| {}).unwrap();
    let mut run = prepare_contact(&sc, &path).unwrap();
    run.plant = run.plant.with_caster_friction();
    let by_method = run.run(&mut |_| {}).unwrap();
    assert_eq!(from_file.rows, by_method.rows);
    assert_ne!(from_file.rows, frictionless.rows);
    // `false` is the default
    let (s0, path_0) = scenario(brake, |t| {
        t.replace("mu = 0.9", "mu = 0.9\ncaster_friction = false")
    });
    assert_eq!(run_contact(&s0, &path_0).rows, frictionless.rows);
    let text = std::fs::read_to_string(&path).unwrap();
    for bad in ["caster_friction = 1", "caster_friction = \"yes\""] {
        let e = parse_scenario::<toml::Table, toml::Table, toml::Table, toml::Table>(
            &text.replace("mu = 0.9", &format!("mu = 0.9\n{bad}")),
            &path,
        )
        .err()
        .unwrap()
        .to_string();
        assert!(
            e.contains("caster_friction") && e.contains(&path.display().to_string()),
            "{e}"
        );
    }
}

#[test]
fn the_state_map_round_trips_through_the_rolling_models_velocity_basis() {
    let (sc, path) = scenario("contact_coordinated.toml", |t| t);
    let mut run = prepare_contact(&sc, &path).unwrap();
    let q_r = [0.3, -0.2, 0.7, 0.1, -0.4, 0.2, 0.8, -0.3];
    let v_r = [0.6, -0.9, 0.3, -0.2, 0.5];
    let (qc, vc) = run.map.to_contact(&q_r, &v_r);
    // The start is on the ground: the wheels' lowest points at z = 0.
    assert!((qc[2] - 0.08).abs() < 1e-12, "base height {}", qc[2]);
    let st = moma::contact::ContactState::new(&run.plant, &qc, &vc).unwrap();
    let (mut q2, mut v2) = ([0.0; 8], [0.0; 5]);
    run.map.to_reduced(&st, &mut q2, &mut v2);
    for k in 0..8 {
        assert!(
            (q2[k] - q_r[k]).abs() < 1e-12,
            "q[{k}]: {} vs {}",
            q2[k],
            q_r[k]
        );
    }
    for k in 0..5 {
        assert!(
            (v2[k] - v_r[k]).abs() < 1e-12,
            "v[{k}]: {} vs {}",
            v2[k],
            v_r[k]
        );
    }
    // The wheels of the contact start roll: their contact points do not slide.
    for r in &st.contacts[..2] {
        assert!(r.slip.norm() < 1e-12, "wheel slip {}", r.slip.norm());
    }
}

fn contact_error(name: &str, edit: impl Fn(String) -> String) -> String {
    let (sc, path) = scenario(name, edit);
    match prepare_contact(&sc, &path) {
        Ok(_) => panic!("should fail"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_contact_input_names_the_field() {
    let brake = "contact_brake_arm_extended.toml";
    let e = contact_error(brake, |t| t.replace("mu = 0.9", "mu = 0.0"));
    assert!(e.contains("contact.mu") && e.contains("must be > 0"), "{e}");
    let e = contact_error(brake, |t| t.replace("mu = 0.9", "mu = -1.0"));
    assert!(e.contains("contact.mu"), "{e}");
    // Stiffness 1e11 N/m: ω_n dt ≫ 2 at dt = 0.1 ms for every contact's effective mass.
    let e = contact_error(brake, |t| {
        t.replace("mu = 0.9", "mu = 0.9\nstiffness = 1e11")
    });
    assert!(
        e.contains("contact.stiffness") && e.contains("contact.dt = 0.0001"),
        "{e}"
    );
    // A caster 5 cm below the ground at the start.
    let e = contact_error("contact_coordinated.toml", |t| {
        t.replace("radius = 0.03", "radius = 0.08")
    });
    assert!(
        e.contains("contact.casters[0] 'caster'") && e.contains("below the ground"),
        "{e}"
    );
    let e = contact_error(brake, |t| rolling(t) + "\n");
    assert!(e.contains("plant = \"contact\""), "{e}");
    let e = contact_error(brake, |t| {
        t.replace("\n[contact]", "\n[contactx]")
            .split("\n[contactx]")
            .next()
            .unwrap()
            .to_string()
    });
    assert!(e.contains("needs a [contact] table"), "{e}");
    let e = contact_error(brake, |t| {
        t.replace(
            "wheel_joints = [\"left_wheel_joint\", \"right_wheel_joint\"]\n",
            "",
        )
    });
    assert!(e.contains("robot.wheel_joints"), "{e}");
    let e = contact_error(brake, |t| t + "\n[stability]\nmu = 0.9\n");
    assert!(e.contains("[stability]"), "{e}");
    let e = contact_error(brake, |t| {
        t.replace("frame = \"rear_left_caster\"", "frame = \"nowhere\"")
    });
    assert!(e.contains("contact.casters[0].frame"), "{e}");
    // A [contact] table on the rolling plant, and plant = "contact" given to prepare.
    let (sc, path) = scenario(brake, |t| t.replace("plant = \"contact\"\n", ""));
    let e = prepare(&sc, &path).err().unwrap().to_string();
    assert!(e.contains("[contact] table is read only with plant"), "{e}");
    let (sc, path) = scenario(brake, |t| t);
    let e = prepare(&sc, &path).err().unwrap().to_string();
    assert!(e.contains("prepare_contact"), "{e}");
    // An unknown plant and an unknown [contact] field are parse errors naming them.
    let path = scenario_path(brake);
    let text = std::fs::read_to_string(&path).unwrap();
    let e = parse_scenario::<toml::Table, toml::Table, toml::Table, toml::Table>(
        &text.replace("plant = \"contact\"", "plant = \"sticky\""),
        &path,
    )
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("sticky"), "{e}");
    let e = parse_scenario::<toml::Table, toml::Table, toml::Table, toml::Table>(
        &text.replace("mu = 0.9", "mu = 0.9\nfriction = 2"),
        &path,
    )
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("friction"), "{e}");
}

//! The tip-over limits that `stability::acceleration_limits` predicts, tested on the
//! contact plant (`moma::contact`) for the diff-drive arm of
//! `scenarios/robots/diffdrive_arm.urdf`, in three arm postures, with and without a 2 kg
//! payload at the tool: at 0.9 × the predicted limit no contact lifts, at 1.1 × one does.
//!
//! How the acceleration is imposed (`moma::sim::lift_off`): by d'Alembert's principle, a
//! robot whose every body accelerates at `a u` with its joints held (the motion the limit
//! is defined for) feels the same contact forces as the robot at rest under gravity
//! `g − a u`. The run ramps the plant's gravity from `g` to `g − a u` over 1 s and holds
//! it 0.7 s, with the arm joints and the wheels held by stiff PD laws; the wheels'
//! friction (μ = 2) carries the horizontal load. What this does not test: the transients
//! of a real start or stop (the wheel torque's onset, the arm's swing), only the steady
//! acceleration the prediction is about. The prediction here is computed from the
//! support polygon written out by hand, not from the plant's contacts.
//!
//! Direction: `forward` (+x: speeding up forwards, or braking a backwards run), where the
//! robot tips back about the wheel axle and the caster lifts. The other way (braking a
//! forward run) the robot would tip over the caster, but only the drive wheels (behind
//! the centre of mass; the caster is frictionless) can carry the braking force, and
//! tipping over the caster unloads exactly them: at that limit their normal load, and so
//! their friction, is zero, so a brake cannot reach it on this robot. It is not tested.
//!
//! The braking test robot (`scenarios/robots/brake_test_robot.urdf`, driven axle at the
//! front, two casters at the rear) is the mirror case: braking (−x) tips it forward over
//! the wheels, which carry the whole load and so the braking force; tested in its two
//! shipped postures (arm extended, arm tucked), with and without 2 kg more at its
//! `payload` frame. Speeding it up would tip it back over the casters, unloading the
//! wheels: unreachable by traction, as braking the diff-drive arm.
//!
//! The UR5-class mobile manipulator (`scenarios/robots/mobile_manipulator.urdf`) and
//! Fetch (`tests/data/robots/fetch`), wheels under the centre and four casters, stand on
//! a statically indeterminate support: a far caster lifts well before the predicted limit,
//! in both directions, in the transport posture of their contact missions and a reach
//! posture, with and without 2 kg at the tool; the tests state by how much and why.

use moma::contact::{ContactParams, ContactPlant};
use moma::dynamics::center_of_mass;
use moma::error::Error;
use moma::multibody::{Data, Model};
use moma::sim::lift_off::{JointGains, LiftOffProblem, LiftOffSettings};
use moma::sim::model_mismatch::Payload;
use moma::spatial::Inertia;
use moma::stability::{SupportPolygon, acceleration_limits};
use nalgebra::{DVector, Matrix3, Vector2, Vector3};

mod contact_common;
use contact_common::{
    FETCH_ARM, MOBILE_MANIPULATOR_ARM, brake_test_robot_plant, diffdrive_arm_model,
    diffdrive_arm_plant, fetch_plant, mobile_manipulator_plant, standing,
};

const G: f64 = 9.81;

fn model(payload: f64) -> Model {
    let mut m = diffdrive_arm_model();
    if payload > 0.0 {
        // A point mass at the tool (0.3 m along the forearm from the elbow).
        let j = m.joint_id("elbow_joint").unwrap().0;
        m.inertias[j] += Inertia::new(payload, Vector3::new(0.0, 0.0, 0.3), Matrix3::zeros());
    }
    m
}

fn plant() -> ContactPlant {
    diffdrive_arm_plant(ContactParams {
        mu: 2.0,
        slip_velocity: 0.1,
        ..ContactParams::default()
    })
}

/// The predicted forward limit (m/s²) of the posture at rest on the ground.
fn predicted_forward_limit(payload: f64, arm: [f64; 3]) -> f64 {
    let m = model(payload);
    let mut data = Data::new(&m);
    let com = center_of_mass(&m, &mut data, &DVector::from_vec(standing(arm)));
    let support = SupportPolygon::from_points(&[
        Vector2::new(-0.1, 0.25),
        Vector2::new(-0.1, -0.25),
        Vector2::new(0.25, 0.0),
    ])
    .unwrap();
    let lim = acceleration_limits(
        m.total_mass(),
        &com,
        &Vector3::new(0.0, 0.0, -G),
        &support,
        0.0,
    );
    lim.forward.expect("a forward limit")
}

/// The posture (wheels at 0, the arm at `arm`) with the payload at the tool (the frame
/// 0.3 m along the forearm from the elbow, where `model` puts it), accelerated forwards.
fn problem(payload: f64, arm: [f64; 3]) -> LiftOffProblem {
    let tool = Payload {
        link: "tool".into(),
        mass: payload,
        position: Vector3::zeros(),
    };
    let p = LiftOffProblem::new(
        &plant(),
        &standing(arm)[7..],
        (payload > 0.0).then_some(&tool),
        Vector2::new(1.0, 0.0),
    )
    .unwrap();
    assert!(
        (p.start()[2] - 0.08).abs() < 1e-12,
        "the robot starts on its wheels"
    );
    p
}

/// The first contact that lifted (carried no normal force) after the first 0.3 s of
/// settling under the steady forward acceleration `a`, if any.
fn lifts(payload: f64, arm: [f64; 3], a: f64) -> Option<usize> {
    problem(payload, arm)
        .lifted_contact(a, &LiftOffSettings::default())
        .unwrap()
}

#[test]
fn at_0_9_times_the_predicted_limit_nothing_lifts_and_at_1_1_times_the_caster_does() {
    for payload in [0.0, 2.0] {
        for arm in [[0.0, 0.3, 0.5], [0.0, 1.5, 0.0], [0.0, -1.2, 0.6]] {
            let lim = predicted_forward_limit(payload, arm);
            // The library's prediction, on the support of the plant's contacts at the
            // start, is this one.
            let lib = problem(payload, arm).predicted_limit().unwrap().unwrap();
            assert!((lib - lim).abs() < 1e-9 * lim, "library {lib} vs {lim}");
            eprintln!("payload {payload} kg, arm {arm:?}: predicted forward limit {lim:.3} m/s²");
            assert!(
                lim * 1.1 < 2.0 * G * 0.9,
                "the test needs friction to carry 1.1 × the limit"
            );
            assert_eq!(
                lifts(payload, arm, 0.9 * lim),
                None,
                "payload {payload}, arm {arm:?}: lifted at 0.9 × {lim}"
            );
            assert_eq!(
                lifts(payload, arm, 1.1 * lim),
                Some(2),
                "payload {payload}, arm {arm:?}: the caster (contact 2) should lift at 1.1 × {lim}"
            );
        }
    }
}

#[test]
fn the_simulated_lift_off_acceleration_is_the_predicted_limit_within_five_percent() {
    // Bisection on the steady acceleration between 0.9 × and 1.1 × the prediction: the
    // smallest that lifts a contact. Measured: 1.8 % and 4.1 % below the prediction. The
    // prediction is for a rigid robot in its posture at rest; the plant's contacts are
    // compliant and its joints PD-held, so as the caster unloads the base pitches back
    // and the arm deflects, which moves the centre of mass towards the axle (the share
    // of each is not separated here).
    for (payload, arm) in [(0.0, [0.0, 1.5, 0.0]), (2.0, [0.0, -1.2, 0.6])] {
        let lim = predicted_forward_limit(payload, arm);
        // Bisection to 0.2 % of the bracket's upper end: 7 halvings of 0.2 × lim.
        let settings = LiftOffSettings {
            tolerance: 0.002,
            ..LiftOffSettings::default()
        };
        let found = problem(payload, arm)
            .search(0.9 * lim, 1.1 * lim, &settings)
            .unwrap();
        assert_eq!(found.contact, 2, "the caster lifts");
        let sim = found.acceleration;
        eprintln!(
            "payload {payload} kg, arm {arm:?}: predicted {lim:.4} m/s², simulated lift-off {sim:.4} m/s² ({:+.2} %)",
            100.0 * (sim / lim - 1.0)
        );
        assert!(
            (sim / lim - 1.0).abs() < 0.05,
            "simulated {sim} vs predicted {lim}"
        );
    }
}

/// The posture of `plant` with the named joints set (every other joint below the root at
/// 0), in model order.
fn posture(plant: &ContactPlant, joints: &[(&str, f64)]) -> Vec<f64> {
    let m = &plant.model;
    let mut q = vec![0.0; m.nq - 7];
    for (name, value) in joints {
        let j = m.joint_id(name).unwrap().0;
        q[m.idx_q[j] - 7] = *value;
    }
    q
}

/// `plant` in the posture `joints`, with `payload` kg at the origin of `frame` (none when
/// 0), accelerated along `direction`.
fn problem_on(
    plant: &ContactPlant,
    joints: &[(&str, f64)],
    frame: &str,
    payload: f64,
    direction: Vector2<f64>,
) -> LiftOffProblem {
    let tool = Payload {
        link: frame.into(),
        mass: payload,
        position: Vector3::zeros(),
    };
    LiftOffProblem::new(
        plant,
        &posture(plant, joints),
        (payload > 0.0).then_some(&tool),
        direction,
    )
    .unwrap()
}

/// The braking test robot in its two shipped postures (`scenarios/brake_arm_extended.toml`:
/// the arm stretched forward; `scenarios/brake_arm_tucked.toml`: the arm folded back over
/// the platform), braking a forward run (acceleration along −x).
const BRAKE_POSTURES: [(&str, [(&str, f64); 2]); 2] = [
    (
        "extended",
        [
            ("shoulder_joint", std::f64::consts::FRAC_PI_2),
            ("elbow_joint", 0.0),
        ],
    ),
    (
        "tucked",
        [
            ("shoulder_joint", -std::f64::consts::FRAC_PI_2),
            ("elbow_joint", std::f64::consts::PI),
        ],
    ),
];

fn brake_plant() -> ContactPlant {
    brake_test_robot_plant(ContactParams {
        mu: 2.0,
        slip_velocity: 0.1,
        ..ContactParams::default()
    })
}

#[test]
fn braking_the_brake_test_robot_at_0_9_times_the_limit_lifts_nothing_and_at_1_1_times_a_rear_caster()
 {
    // Braking tips the robot forward about the driven axle at the front: the rear casters
    // (contacts 2 and 3) lift, and at the limit the wheels carry the whole load, so their
    // friction can carry the braking force.
    let plant = brake_plant();
    for payload in [0.0, 2.0] {
        for (name, joints) in BRAKE_POSTURES {
            let p = problem_on(&plant, &joints, "payload", payload, Vector2::new(-1.0, 0.0));
            let lim = p.predicted_limit().unwrap().expect("a braking limit");
            eprintln!(
                "brake test robot, arm {name}, extra payload {payload} kg: predicted braking limit {lim:.3} m/s²"
            );
            assert!(
                lim * 1.1 < 2.0 * G * 0.9,
                "friction carries 1.1 × the limit"
            );
            let s = LiftOffSettings::default();
            assert_eq!(
                p.lifted_contact(0.9 * lim, &s).unwrap(),
                None,
                "{name}, {payload} kg: lifted at 0.9 × {lim}"
            );
            let lifted = p.lifted_contact(1.1 * lim, &s).unwrap();
            assert!(
                matches!(lifted, Some(2 | 3)),
                "{name}, {payload} kg: a rear caster should lift at 1.1 × {lim}, got {lifted:?}"
            );
        }
    }
}

#[test]
fn the_brake_test_robots_simulated_braking_lift_off_is_the_predicted_limit_within_five_percent() {
    // Measured: −0.55 % (extended) and −1.33 % (tucked) without an extra payload, +0.08 %
    // and −1.33 % with 2 kg: below the prediction, as on the diff-drive arm (the compliant
    // contacts and PD-held joints let the base pitch and the arm deflect forwards).
    let plant = brake_plant();
    let settings = LiftOffSettings {
        tolerance: 0.002,
        ..LiftOffSettings::default()
    };
    for payload in [0.0, 2.0] {
        for (name, joints) in BRAKE_POSTURES {
            let p = problem_on(&plant, &joints, "payload", payload, Vector2::new(-1.0, 0.0));
            let lim = p.predicted_limit().unwrap().unwrap();
            let found = p.search(0.9 * lim, 1.1 * lim, &settings).unwrap();
            let sim = found.acceleration;
            eprintln!(
                "brake test robot, arm {name}, extra payload {payload} kg: predicted {lim:.4} m/s², simulated lift-off {sim:.4} m/s² ({:+.2} %)",
                100.0 * (sim / lim - 1.0)
            );
            assert!(
                found.contact == 2 || found.contact == 3,
                "a rear caster lifts"
            );
            assert!(
                (sim / lim - 1.0).abs() < 0.05,
                "simulated {sim} vs predicted {lim}"
            );
        }
    }
}

/// A robot whose drive wheels sit between front and rear casters, in the postures tested.
struct OnCasters {
    name: &'static str,
    plant: ContactPlant,
    arm: &'static [&'static str],
    postures: [(&'static str, [f64; 8]); 2],
    /// The payload's frame.
    tool: &'static str,
    /// What the name of the caster that lifts first contains: speeding up (+x, a front
    /// caster), braking (−x, a rear one).
    far: [&'static str; 2],
}

/// The default gains (the arm's from each joint's own inertia), the bisection to 1 %.
const ON_CASTERS_SETTINGS: LiftOffSettings = LiftOffSettings {
    tolerance: 0.01,
    ..DEFAULT_SETTINGS
};

/// The UR5-class robot: the drive wheels under the base's centre, four casters at
/// x = ±0.24 m; `scenarios/mission_contact.toml`'s transport posture and the arm reaching
/// forwards (the last two entries unused).
fn mobile_manipulator() -> OnCasters {
    OnCasters {
        name: "mobile manipulator",
        plant: mobile_manipulator_plant(ContactParams {
            mu: 2.0,
            slip_velocity: 0.1,
            ..ContactParams::default()
        }),
        arm: &MOBILE_MANIPULATOR_ARM,
        postures: [
            ("transport", [0.0, -0.5, 2.6, 1.04, 0.0, 0.0, 0.0, 0.0]),
            ("reach", [0.0, -0.3, 0.3, 0.0, 0.0, 0.0, 0.0, 0.0]),
        ],
        tool: "tool0",
        far: ["caster_front", "caster_rear"],
    }
}

/// Fetch: drive wheels at x = 0, casters at x = 0.15 m and −0.2 m;
/// `scenarios/mission_fetch_contact.toml`'s transport posture and the torso up with the
/// arm reaching forwards and down.
fn fetch() -> OnCasters {
    OnCasters {
        name: "Fetch",
        plant: fetch_plant(ContactParams {
            mu: 2.0,
            slip_velocity: 0.1,
            ..ContactParams::default()
        }),
        arm: &FETCH_ARM,
        postures: [
            ("transport", [0.0, 1.32, 1.40, -0.2, 1.72, 0.0, 1.66, 0.0]),
            ("reach", [0.2, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0]),
        ],
        tool: "gripper_link",
        far: ["[0.15", "[-0.2"],
    }
}

impl OnCasters {
    /// Calls `f` with each case's label, the caster expected to lift, the problem and its
    /// predicted limit: per posture, payload (0 and 2 kg at the tool) and direction.
    fn each(&self, mut f: impl FnMut(&str, &str, &LiftOffProblem, f64)) {
        for (posture, q) in &self.postures {
            let joints: Vec<(&str, f64)> =
                self.arm.iter().copied().zip(q.iter().copied()).collect();
            for payload in [0.0, 2.0] {
                for (dir, far) in [(1.0, self.far[0]), (-1.0, self.far[1])] {
                    let p = problem_on(
                        &self.plant,
                        &joints,
                        self.tool,
                        payload,
                        Vector2::new(dir, 0.0),
                    );
                    let lim = p.predicted_limit().unwrap().unwrap();
                    let label =
                        format!("{}, {posture}, {payload} kg, direction {dir:+}", self.name);
                    f(&label, far, &p, lim);
                }
            }
        }
    }

    /// At 0.9 × the predicted limit a far caster has already lifted, in every case.
    fn far_caster_lifts_at_0_9_times_the_limit(&self) {
        self.each(|label, far, p, lim| {
            let lifted = p.lifted_contact(0.9 * lim, &ON_CASTERS_SETTINGS).unwrap();
            let name = lifted.map(|k| self.plant.contact_name(k));
            eprintln!("{label}: predicted {lim:.3} m/s², at 0.9 × lifted {name:?}");
            assert!(
                name.is_some_and(|n| n.contains(far)),
                "{label}: {name:?}, expected {far}"
            );
        });
    }

    /// The bisected first lift-off (to 1 %) lies in `band` times the prediction.
    fn first_lift_off_within(&self, band: std::ops::Range<f64>) {
        self.each(|label, far, p, lim| {
            let found = p.search(0.1 * lim, 0.9 * lim, &ON_CASTERS_SETTINGS).unwrap();
            let ratio = found.acceleration / lim;
            let contact = self.plant.contact_name(found.contact);
            eprintln!(
                "{label}: predicted {lim:.3} m/s², first lift-off {:.3} m/s² ({ratio:.3} ×) at {contact}",
                found.acceleration
            );
            assert!(contact.contains(far), "{label}: {contact}");
            assert!(band.contains(&ratio), "{label}: {ratio}");
        });
    }
}

// The mobile manipulator's support is statically indeterminate: on equal linear springs
// under a rigid base the loads vary linearly with x, and the far casters' load reaches
// zero when the ZMP is 2/3 of the way from the centre to the tipping edge (x = ∓0.16 m),
// not at the edge (the prediction's tip-over): about 0.67 × the limit for a centre of
// mass over the axle. And at the limit itself (every contact off the edge unloaded, the
// drive wheels included) the wheels' friction, the only horizontal force, is zero: the
// robot's own traction cannot reach it. Fetch likewise: its far casters unload with the
// ZMP at x = −0.14 m (speeding up) or 0.0955 m (braking), 0.70 × and 0.64 × of the way to
// the edges; its casters also start 0.225 mm above the wheels' lowest points, so the
// wheels carry more than their share and the casters unload earlier still.

#[test]
fn on_the_mobile_manipulator_a_far_caster_has_lifted_at_0_9_times_the_predicted_limit() {
    mobile_manipulator().far_caster_lifts_at_0_9_times_the_limit();
}

#[test]
fn on_fetch_a_far_caster_has_lifted_at_0_9_times_the_predicted_limit() {
    fetch().far_caster_lifts_at_0_9_times_the_limit();
}

#[test]
#[ignore = "16 bisections, about 40 s in release on two quiet cores, 115 s loaded (CI tier 2)"]
fn on_the_robots_on_casters_the_first_lift_off_is_well_below_the_predicted_limit() {
    // Measured (docs/contact.md lists every case): 0.60 to 0.69 × on the mobile
    // manipulator, 0.49 to 0.67 × on Fetch.
    mobile_manipulator().first_lift_off_within(0.55..0.75);
    fetch().first_lift_off_within(0.35..0.75);
}

/// What `LiftOffSettings::default()` holds, as a constant.
const DEFAULT_SETTINGS: LiftOffSettings = LiftOffSettings {
    settle: 0.3,
    ramp: 1.0,
    hold: 0.7,
    wheel_gains: [500.0, 20.0],
    joint_gains: moma::sim::lift_off::DEFAULT_JOINT_GAINS,
    tolerance: 0.005,
    max_iterations: 20,
};

#[test]
fn the_default_settings_are_the_constant_these_tests_use() {
    assert_eq!(LiftOffSettings::default(), DEFAULT_SETTINGS);
}

#[test]
fn arm_gains_unstable_at_the_step_are_refused_before_the_run_naming_the_joint() {
    // 2000 N·m/rad and 100 N·m·s/rad on every arm joint (the study's former default): on
    // the light wrist and head joints (effective inertia 1.4e-3 and 1.6e-3 kg·m²) explicit
    // damping is unstable at 0.1 ms (kd dt / I ≈ 7 > 2); the run used to end in
    // non-finite accelerations. Now no step is taken: the error is the gains', not a
    // numerical failure.
    let stiff = LiftOffSettings {
        joint_gains: JointGains::Fixed([2000.0, 100.0]),
        ..DEFAULT_SETTINGS
    };
    // The first joint in model order whose gains break the bound (measured).
    for (robot, first) in [
        (mobile_manipulator(), "wrist_2_joint"),
        (fetch(), "head_tilt_joint"),
    ] {
        let joints: Vec<(&str, f64)> = robot
            .arm
            .iter()
            .copied()
            .zip(robot.postures[0].1.iter().copied())
            .collect();
        let p = problem_on(
            &robot.plant,
            &joints,
            robot.tool,
            0.0,
            Vector2::new(1.0, 0.0),
        );
        for e in [
            p.joint_gains(&stiff).unwrap_err(),
            p.lifted_contact(1.0, &stiff).unwrap_err(),
            p.search(0.5, 1.0, &stiff).unwrap_err(),
        ] {
            let Error::InvalidInput { field, message } = &e else {
                panic!("{}: {e}", robot.name)
            };
            assert_eq!(field, "joint_gains", "{e}");
            assert!(
                message.contains("need dt <") && message.contains("contact.dt"),
                "{e}"
            );
            let joint = message.split('\'').nth(1).unwrap();
            eprintln!("{}: {message}", robot.name);
            assert_eq!(joint, first, "{}: {e}", robot.name);
        }
    }
}

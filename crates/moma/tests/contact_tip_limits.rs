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
//!
//! Their tip-over itself (every contact off a caster edge unloaded, the drive wheels
//! included) needs horizontal force at the casters: with friction given to the casters
//! (`ContactPlant::with_caster_friction`) and the joints held with their static torque
//! (`LiftOffProblem::with_static_torque`), in the same postures, payloads and directions,
//! 0.9 × the predicted limit does not tip the robot over and 1.1 × does, within 3 % of the
//! prediction (the contacts stiffened with their damping ratio kept); at every step the
//! ZMP that `stability::evaluate` computes from the model's dynamics is the point about
//! which the plant's contact forces have no horizontal moment, and its margin stays
//! positive until every contact off the edge has lost its load and is within 1 mm of zero
//! at that step. After the ramp Fetch rocks on its wheels about the tipping edge, damped by
//! the contacts' damping ratio. Held (bisection on the held acceleration), the mobile
//! manipulator's tip-over threshold approaches the prediction as the contacts stiffen (the
//! base's pitch on its contacts is the gap) and depends neither on the ramp's length nor on
//! the hold's.

use moma::contact::{ContactParams, ContactPlant};
use moma::dynamics::center_of_mass;
use moma::error::Error;
use moma::multibody::{Data, Model};
use moma::sim::lift_off::{JointGains, LiftOffEvent, LiftOffProblem, LiftOffSettings};
use moma::sim::model_mismatch::Payload;
use moma::spatial::Inertia;
use moma::stability::{
    BodySet, ExternalLoads, StabilityData, StabilityModel, SupportAttachment, SupportPolygon,
    acceleration_limits, evaluate,
};
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
    // smallest that lifts a contact. Measured: 0.55 % and 3.36 % below the prediction. The
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
    // Measured: +0.08 % (extended) and −0.70 % (tucked) without an extra payload, +0.39 %
    // and −0.70 % with 2 kg: below the prediction, as on the diff-drive arm (the compliant
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

/// The contact parameters of the runs on casters: wheel friction μ = 2 (it carries the
/// horizontal load), the default stiffness.
fn on_casters_params() -> ContactParams {
    ContactParams {
        mu: 2.0,
        slip_velocity: 0.1,
        ..ContactParams::default()
    }
}

/// The UR5-class robot: the drive wheels under the base's centre, four casters at
/// x = ±0.24 m; `scenarios/mission_contact.toml`'s transport posture and the arm reaching
/// forwards (the last two entries unused).
fn mobile_manipulator(params: ContactParams) -> OnCasters {
    OnCasters {
        name: "mobile manipulator",
        plant: mobile_manipulator_plant(params),
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
fn fetch(params: ContactParams) -> OnCasters {
    OnCasters {
        name: "Fetch",
        plant: fetch_plant(params),
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
        for (k, (posture, _)) in self.postures.iter().enumerate() {
            for payload in [0.0, 2.0] {
                for (dir, far) in [(1.0, self.far[0]), (-1.0, self.far[1])] {
                    let p = self.problem(k, payload, dir);
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
    mobile_manipulator(on_casters_params()).far_caster_lifts_at_0_9_times_the_limit();
}

#[test]
fn on_fetch_a_far_caster_has_lifted_at_0_9_times_the_predicted_limit() {
    fetch(on_casters_params()).far_caster_lifts_at_0_9_times_the_limit();
}

#[test]
#[ignore = "16 bisections, about 40 s in release on two quiet cores, 115 s loaded (CI tier 2)"]
fn on_the_robots_on_casters_the_first_lift_off_is_well_below_the_predicted_limit() {
    // Measured (docs/contact.md lists every case): 0.60 to 0.70 × on the mobile
    // manipulator, 0.50 to 0.68 × on Fetch.
    mobile_manipulator(on_casters_params()).first_lift_off_within(0.55..0.75);
    fetch(on_casters_params()).first_lift_off_within(0.35..0.75);
}

// The tip-over itself, on these robots. With frictionless casters their own traction
// cannot reach it: the drive wheels are the only frictional contacts, inside the support,
// and a tip-over over a caster edge unloads them, so at that limit no horizontal force is
// left to accelerate the robot (or to carry the tilted gravity of the d'Alembert run).
// The edge is reachable when the contacts on it carry friction: the runs below give the
// casters the wheels' μ = 2 (`ContactPlant::with_caster_friction`, as braked or locked
// casters would have), which changes neither the prediction (mass, centre of mass,
// support) nor the stability module's inputs. Speeding up (+x) tips the robot back over
// the rear casters, braking (−x) forward over the front ones.
//
// The check: at every step after the settling, `stability::evaluate` computes the ZMP from
// the model's dynamics (the step's q, v, v̇ and the plant's gravity of that step), on the
// support polygon of the contacts at the start, and it must be the point on the ground
// plane about which the plant's contact forces have no horizontal moment; and the ZMP
// margin must reach zero at the step at which every contact off the tipping edge carries
// no normal force, not before.

/// Contact stiffness (N/m) of the tip-over runs, ten times the default: the contacts sink
/// less (about 0.3 to 0.6 mm at the edge as the robot tips), so the ZMP on the ground
/// plane z = 0 and the centre of pressure of the normal forces at the contacts' depth δ,
/// which differ by δ |F_t| / N, are within about 0.3 mm (the default's 3 to 6 mm would
/// swamp a shifted support polygon).
const EDGE_STIFFNESS: f64 = 1e6;

/// The on-casters contact parameters with the normal stiffness `stiffness` (N/m) and the
/// damping that keeps the default contact's damping ratio: ζ = c / (2 √(k m)) on any mass,
/// so c = c₀ √(k / k₀) (6.32e3 N·s/m at `EDGE_STIFFNESS`). Stiffening the contacts at the
/// default's c would lower the damping ratio of every contact mode by √(k / k₀): at
/// 1e6 N/m and 2e3 N·s/m Fetch rocks on its drive wheels about the tipping edge at 4.2 Hz
/// with ζ ≈ 0.05, and the ramp's tip-over came early by that swing (docs/contact.md).
fn stiffened(stiffness: f64) -> ContactParams {
    let default = ContactParams::default();
    ContactParams {
        stiffness,
        damping: default.damping * (stiffness / default.stiffness).sqrt(),
        ..on_casters_params()
    }
}

/// Largest |ZMP margin| (m) of the stability module at the step the last contact off the
/// tipping edge loses its load (measured −0.04 to +0.29 mm: the contacts' depth times
/// |F_t| / N, see `EDGE_STIFFNESS`, and the casters' rolling contact points).
const MARGIN_AT_TIP: f64 = 1e-3;

/// Lowest ZMP margin (m) allowed before the tip-over: the support is the contacts' at the
/// start, carried with the base, while a caster's contact point rolls round its sphere as
/// the base pitches (r θ: about 0.1 mm for Fetch's 6 cm casters at a few mrad); measured
/// −0.03 mm at worst (Fetch, reach, braking, 2 kg).
const MARGIN_BEFORE_TIP: f64 = -0.5e-3;

/// Largest distance (m) between the stability module's ZMP and the contact forces'.
const ZMP_AGREEMENT: f64 = 1e-6;

/// What one tip-over run showed after the settling.
#[derive(Debug)]
struct EdgeRun {
    /// Largest distance (m) between the stability module's ZMP and the point on z = 0
    /// about which the plant's contact forces have no horizontal moment.
    zmp_gap: f64,
    /// Largest distance (m) between the stability module's ZMP and the centre of pressure
    /// of the plant's normal forces alone.
    cop_gap: f64,
    /// The smallest ZMP margin (m) of the stability module before the tip-over.
    margin_before: f64,
    /// The ramp's acceleration (m/s²) at the first step every contact off the tipping
    /// edge carried no normal force, and the stability module's ZMP margin there (m).
    tip: Option<(f64, f64)>,
}

/// The contacts off the tipping edge of `p` (the edge: the contacts at the start farthest
/// back along the acceleration).
fn off_edge(p: &LiftOffProblem) -> Vec<usize> {
    let start = p.plant().contact_points(p.start()).unwrap();
    let u = p.direction();
    let along = |c: &Vector3<f64>| c.xy().dot(&u.xy());
    let back = start.iter().map(along).fold(f64::INFINITY, f64::min);
    (0..start.len())
        .filter(|&k| along(&start[k]) > back + 1e-3)
        .collect()
}

/// Runs `p` at the acceleration `a` (until the tip-over), the stability module evaluating
/// every step on the support polygon of the contacts at the start moved by `shift`.
fn edge_run(p: &LiftOffProblem, a: f64, shift: Vector2<f64>) -> EdgeRun {
    let plant = p.plant();
    let model = &plant.model;
    let start = plant.contact_points(p.start()).unwrap();
    let touching: Vec<Vector2<f64>> = start
        .iter()
        .filter(|c| c.z <= plant.params.start_penetration_tol)
        .map(|c| c.xy() + shift)
        .collect();
    let support = SupportPolygon::from_points(&touching).unwrap();
    let mut sm =
        StabilityModel::new(model, support, SupportAttachment::Base, &BodySet::All).unwrap();
    let mut sd = StabilityData::new(&sm);
    let mut data = Data::new(model);
    let u = p.direction();
    let off_edge = off_edge(p);
    let g = model.gravity;
    let mut run = EdgeRun {
        zmp_gap: 0.0,
        cop_gap: 0.0,
        margin_before: f64::INFINITY,
        tip: None,
    };
    p.run(a, &ON_CASTERS_SETTINGS, |s| {
        if s.time <= ON_CASTERS_SETTINGS.settle {
            return false;
        }
        sm.gravity = s.gravity;
        let report = evaluate(
            model,
            &mut data,
            &sm,
            &mut sd,
            s.q,
            s.v,
            s.acceleration,
            &ExternalLoads::NONE,
        );
        let zmp = report.zmp.expect("the robot presses on the ground").xy();
        let margin = report.zmp_margin.unwrap();
        let (mut force, mut moment, mut pressure) =
            (Vector3::zeros(), Vector3::zeros(), Vector2::zeros());
        for r in s.contacts {
            let f = Vector3::new(r.friction.x, r.friction.y, r.normal);
            force += f;
            moment += r.point.cross(&f);
            pressure += r.normal * r.point.xy();
        }
        let contact_zmp = Vector2::new(-moment.y / force.z, moment.x / force.z);
        run.zmp_gap = run.zmp_gap.max((zmp - contact_zmp).norm());
        run.cop_gap = run.cop_gap.max((zmp - pressure / force.z).norm());
        let accel = (g - s.gravity).dot(&u);
        if off_edge.iter().all(|&k| s.contacts[k].normal == 0.0) {
            run.tip = Some((accel, margin));
            return true;
        }
        run.margin_before = run.margin_before.min(margin);
        false
    })
    .unwrap();
    run
}

impl OnCasters {
    /// The study in the posture `self.postures[posture]` with `payload` kg at the tool,
    /// accelerated along x (`direction` +1: speeding up, −1: braking).
    fn problem(&self, posture: usize, payload: f64, direction: f64) -> LiftOffProblem {
        let joints: Vec<(&str, f64)> = self
            .arm
            .iter()
            .copied()
            .zip(self.postures[posture].1.iter().copied())
            .collect();
        problem_on(
            &self.plant,
            &joints,
            self.tool,
            payload,
            Vector2::new(direction, 0.0),
        )
    }

    /// The study in the first posture, no payload, speeding up (+x).
    fn first_posture_speeding_up(&self) -> LiftOffProblem {
        self.problem(0, 0.0, 1.0)
    }

    /// The same robot with friction at its casters and stiffer contacts (`stiffened`).
    fn with_caster_friction(params: fn(ContactParams) -> Self) -> Self {
        let mut r = params(stiffened(EDGE_STIFFNESS));
        r.plant = r.plant.with_caster_friction();
        r
    }

    /// At 0.9 × the predicted limit the robot does not tip over; at 1.1 × it does, within
    /// `band` times the prediction, with the stability module's ZMP margin positive until
    /// that step and within `MARGIN_AT_TIP` of zero there, and its ZMP that of the contact
    /// forces at every step.
    fn tips_over_the_edge_where_the_zmp_margin_reaches_zero(&self, band: std::ops::Range<f64>) {
        self.each(|label, _, p, lim| {
            let p = p
                .clone()
                .with_event(LiftOffEvent::TipOver)
                .with_static_torque();
            assert!(
                lim * 1.1 < 2.0 * G * 0.9,
                "{label}: friction carries 1.1 × {lim}"
            );
            let lifted = p.lifted_contact(0.9 * lim, &ON_CASTERS_SETTINGS).unwrap();
            assert_eq!(lifted, None, "{label}: tipped at 0.9 × {lim}");
            let run = edge_run(&p, 1.1 * lim, Vector2::zeros());
            eprintln!("{label}: predicted {lim:.3} m/s², {run:?}");
            let (at, margin) = run
                .tip
                .unwrap_or_else(|| panic!("{label}: no tip-over at 1.1 × {lim}"));
            assert!(
                band.contains(&(at / lim)),
                "{label}: tipped at {at} = {} ×",
                at / lim
            );
            assert!(
                run.zmp_gap < ZMP_AGREEMENT,
                "{label}: ZMP gap {}",
                run.zmp_gap
            );
            assert!(
                margin.abs() < MARGIN_AT_TIP,
                "{label}: ZMP margin {margin} at the tip-over"
            );
            assert!(
                run.margin_before > MARGIN_BEFORE_TIP,
                "{label}: the ZMP margin fell to {} m before the tip-over",
                run.margin_before
            );
        });
    }
}

#[test]
fn with_caster_friction_the_mobile_manipulator_tips_over_where_the_stability_modules_zmp_margin_reaches_zero()
 {
    OnCasters::with_caster_friction(mobile_manipulator)
        .tips_over_the_edge_where_the_zmp_margin_reaches_zero(0.97..1.03);
}

#[test]
fn with_caster_friction_fetch_tips_over_where_the_stability_modules_zmp_margin_reaches_zero() {
    // Measured 0.980 to 1.006 × (reach braking lowest). With the stiffened contacts at the
    // default's damping (2e3 N·s/m) it was down to 0.964 ×: Fetch rocked on its drive
    // wheels about the tipping edge, lightly damped (below), and the ramp's tip-over came
    // at a trough of that swing.
    OnCasters::with_caster_friction(fetch)
        .tips_over_the_edge_where_the_zmp_margin_reaches_zero(0.97..1.03);
}

/// The smallest and the mean off-edge load (N, summed over the contacts off the tipping
/// edge) over a 2 s hold of Fetch's reach posture braking at 0.95 × the predicted limit,
/// casters with friction, the posture held with its static torque, on `params`.
fn fetch_reach_braking_hold_loads(params: ContactParams) -> (f64, f64) {
    let mut robot = fetch(params);
    robot.plant = robot.plant.with_caster_friction();
    let p = robot
        .problem(1, 0.0, -1.0)
        .with_event(LiftOffEvent::TipOver)
        .with_static_torque();
    let lim = p.predicted_limit().unwrap().unwrap();
    let off = off_edge(&p);
    let settings = LiftOffSettings {
        hold: 2.0,
        ..ON_CASTERS_SETTINGS
    };
    let (mut least, mut sum, mut n) = (f64::INFINITY, 0.0, 0.0);
    p.run(0.95 * lim, &settings, |s| {
        if s.time > settings.settle + settings.ramp {
            let load: f64 = off.iter().map(|&k| s.contacts[k].normal).sum();
            least = least.min(load);
            sum += load;
            n += 1.0;
        }
        false
    })
    .unwrap();
    (least, sum / n)
}

#[test]
fn fetchs_rocking_on_its_wheels_after_the_ramp_is_damped_by_the_contacts_damping_ratio() {
    // After the ramp Fetch (reach, braking) stands on its front casters and, off the edge,
    // its drive wheels 0.15 m behind them (the rear casters, 0.225 mm higher, have lifted):
    // it rocks about the edge on the wheels' contact springs at 4.2 Hz (2.9 and 6.0 Hz at
    // 5e5 and 2e6 N/m: as √k), every joint, the wheels included, moving in that mode
    // quasi-statically. At the default's damping the swing's troughs reach 0.31 × the
    // mean load (12.9 of 41.5 N, ζ ≈ 0.05 from its decay); with the damping ratio kept
    // (`stiffened`) 0.64 × (26.7 of 41.8 N, ζ ≈ 0.1). The mean, the steady load, is the
    // same.
    let (kept_least, kept_mean) = fetch_reach_braking_hold_loads(stiffened(EDGE_STIFFNESS));
    let (soft_least, soft_mean) = fetch_reach_braking_hold_loads(ContactParams {
        stiffness: EDGE_STIFFNESS,
        ..on_casters_params()
    });
    eprintln!(
        "damping ratio kept: least {kept_least:.2} N of a mean {kept_mean:.2} N; \
         default damping: least {soft_least:.2} N of a mean {soft_mean:.2} N"
    );
    assert!(
        (kept_mean / soft_mean - 1.0).abs() < 0.02,
        "{kept_mean} vs {soft_mean}"
    );
    assert!(kept_least > 0.5 * kept_mean, "{kept_least} of {kept_mean}");
    assert!(soft_least < 0.4 * soft_mean, "{soft_least} of {soft_mean}");
}

// Held, below the ramp's value: the steady threshold (bisection on the held acceleration)
// on the plant sits a little below the prediction for the rigid robot, because the base
// pitches on its compliant contacts as the load moves to the tipping edge, which carries
// the centre of mass towards the edge by about its height times the pitch (mobile
// manipulator, transport, at 0.99 ×: 1.45 mrad, 0.43 mm). The pitch goes as 1 / stiffness,
// and so does the gap. What it is not: creep (the regularised friction lets the robot slide
// at a steady 0.04 m/s, which changes no force), the hold's duration, the joints' PD sag
// (the static torque holds the posture), or the ramp's end (the ramp is a smooth step; the
// former linear ramp's jump in rate where the hold began set the base rocking, and the
// bisection read that overshoot: 0.988 × here, 0.964 × on Fetch).

/// The held tip-over threshold of the mobile manipulator in its transport posture, speeding
/// up (+x, over the rear casters), as a factor of the prediction: casters with friction,
/// the posture held with its static torque, contacts of `stiffness` N/m (`stiffened`), bisection to
/// 0.1 %.
fn held_tip_over_ratio(stiffness: f64, ramp: f64, hold: f64) -> f64 {
    let mut robot = mobile_manipulator(stiffened(stiffness));
    robot.plant = robot.plant.with_caster_friction();
    let p = robot
        .first_posture_speeding_up()
        .with_event(LiftOffEvent::TipOver)
        .with_static_torque();
    let lim = p.predicted_limit().unwrap().unwrap();
    let settings = LiftOffSettings {
        ramp,
        hold,
        tolerance: 0.001,
        ..DEFAULT_SETTINGS
    };
    let found = p.search(0.9 * lim, 1.05 * lim, &settings).unwrap();
    let ratio = found.acceleration / lim;
    eprintln!(
        "stiffness {stiffness:e} N/m, ramp {ramp} s, hold {hold} s: predicted {lim:.4} m/s², held threshold {:.4} m/s² ({ratio:.4} ×)",
        found.acceleration
    );
    ratio
}

#[test]
fn held_the_tip_over_threshold_approaches_the_prediction_as_the_contacts_stiffen() {
    // Measured: 0.9864, 0.9958, 0.9987 × (gaps 1.36 %, 0.42 %, 0.13 %).
    let gaps = [3e5, 1e6, 3e6].map(|k| 1.0 - held_tip_over_ratio(k, 1.0, 0.7));
    assert!(gaps[0] > gaps[1] && gaps[1] > gaps[2], "{gaps:?}");
    // Stiffness × 10/3, gap ÷ 10/3 (within the bisection's 0.1 %).
    let scale = gaps[0] / gaps[1];
    assert!((2.0..5.0).contains(&scale), "gap ratio {scale}: {gaps:?}");
    assert!(gaps[0] > 0.008, "{gaps:?}");
    assert!(gaps[2].abs() < 0.003, "{gaps:?}");
}

#[test]
fn held_the_tip_over_threshold_depends_neither_on_the_ramps_length_nor_on_the_holds() {
    // A steady threshold, not a transient's: the same within the bisection's tolerance
    // for a 1 s or 3 s ramp and a 0.7 s or 2 s hold (measured 0.9958, 0.9970, 0.9958 ×).
    // With the former linear ramp
    // the 1 s ramp's threshold was 0.6 % below the 3 s one's (0.988 and 0.994 ×): the
    // jolt at the ramp's end.
    let ratios = [(1.0, 0.7), (3.0, 0.7), (1.0, 2.0)]
        .map(|(ramp, hold)| held_tip_over_ratio(EDGE_STIFFNESS, ramp, hold));
    let spread = ratios.iter().copied().fold(f64::NEG_INFINITY, f64::max)
        - ratios.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(spread < 0.002, "{ratios:?}");
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
        (mobile_manipulator(on_casters_params()), "wrist_2_joint"),
        (fetch(on_casters_params()), "head_tilt_joint"),
    ] {
        let p = robot.first_posture_speeding_up();
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

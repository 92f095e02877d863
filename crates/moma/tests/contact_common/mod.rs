//! Shared test fixture: the contact plant of `scenarios/robots/diffdrive_arm.urdf` (the
//! three-joint arm on a differential drive): the robot on a free-flyer root, its two drive
//! wheels as disks of radius [`WHEEL_RADIUS`] and its ball caster (frame `caster`) as a
//! sphere of radius [`CASTER_RADIUS`]; and that of the UR5-class mobile manipulator
//! (`scenarios/robots/mobile_manipulator.urdf`, [`mobile_manipulator_plant`]). Used by the
//! contact tests and `benches/contact.rs`.
#![allow(dead_code)]

use moma::contact::{CasterSpec, ContactParams, ContactPlant, WheelSpec};
use moma::io::urdf::model_from_urdf_file;
use moma::multibody::{Model, RootJoint};

/// Radius of the drive wheels (m), the description's.
pub const WHEEL_RADIUS: f64 = 0.08;
/// Radius of the ball caster (m).
pub const CASTER_RADIUS: f64 = 0.03;

/// The description's path.
pub fn diffdrive_arm_urdf() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/robots/diffdrive_arm.urdf")
}

/// The robot on a free-flyer root.
pub fn diffdrive_arm_model() -> Model {
    model_from_urdf_file(diffdrive_arm_urdf(), RootJoint::FreeFlyer).expect("diffdrive_arm.urdf")
}

/// The contact plant on `model` (the robot on a free-flyer root, possibly changed by the
/// caller) with the contact parameters `params`.
pub fn diffdrive_arm_plant_on(model: Model, params: ContactParams) -> ContactPlant {
    let wheels = ["left_wheel_joint", "right_wheel_joint"].map(|j| WheelSpec {
        joint: j.into(),
        radius: WHEEL_RADIUS,
    });
    let casters = [CasterSpec::on_frame("caster", CASTER_RADIUS)];
    ContactPlant::new(model, &wheels, &casters, params).expect("the contact plant")
}

/// The contact plant of the unchanged robot with the contact parameters `params`.
pub fn diffdrive_arm_plant(params: ContactParams) -> ContactPlant {
    diffdrive_arm_plant_on(diffdrive_arm_model(), params)
}

/// The configuration standing on the ground at the origin, level and heading along x, the
/// wheels at 0 and the arm joints at `arm`.
pub fn standing(arm: [f64; 3]) -> Vec<f64> {
    let mut q = vec![0.0, 0.0, WHEEL_RADIUS, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0];
    q.extend_from_slice(&arm);
    q
}

/// Radius of the drive wheels (m) of `scenarios/robots/mobile_manipulator.urdf`.
pub const MOBILE_MANIPULATOR_WHEEL_RADIUS: f64 = 0.10;
/// Its four ball casters: the frame at each sphere's centre and the radius (m), as
/// `scenarios/mission_contact.toml` gives them.
pub const MOBILE_MANIPULATOR_CASTERS: [(&str, f64); 4] = [
    ("caster_front_left", 0.04),
    ("caster_front_right", 0.04),
    ("caster_rear_left", 0.04),
    ("caster_rear_right", 0.04),
];

/// The contact plant of the UR5-class mobile manipulator
/// (`scenarios/robots/mobile_manipulator.urdf`, base frame on the ground under the axle) on
/// a free-flyer root, with the contact parameters `params`. Its inputs are the six arm
/// joints, then the two wheels (model order).
pub fn mobile_manipulator_plant(params: ContactParams) -> ContactPlant {
    let urdf = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/robots/mobile_manipulator.urdf");
    let model = model_from_urdf_file(urdf, RootJoint::FreeFlyer).expect("mobile_manipulator.urdf");
    let wheels = ["left_wheel_joint", "right_wheel_joint"].map(|j| WheelSpec {
        joint: j.into(),
        radius: MOBILE_MANIPULATOR_WHEEL_RADIUS,
    });
    let casters = MOBILE_MANIPULATOR_CASTERS.map(|(f, r)| CasterSpec::on_frame(f, r));
    ContactPlant::new(model, &wheels, &casters, params).expect("the contact plant")
}

/// Radius of the drive wheels (m) of `scenarios/robots/brake_test_robot.urdf`.
pub const BRAKE_TEST_ROBOT_WHEEL_RADIUS: f64 = 0.1;

/// The contact plant of the braking test robot (`scenarios/robots/brake_test_robot.urdf`:
/// the driven axle at the front, x = 0.2 m, two point casters at the rear, x = −0.4 m,
/// as `scenarios/contact_brake_arm_extended.toml` gives them) on a free-flyer root, with
/// the contact parameters `params`. Its joints below the root: the two wheels, then the
/// turret, shoulder and elbow (model order).
pub fn brake_test_robot_plant(params: ContactParams) -> ContactPlant {
    let urdf = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/robots/brake_test_robot.urdf");
    let model = model_from_urdf_file(urdf, RootJoint::FreeFlyer).expect("brake_test_robot.urdf");
    let wheels = ["left_wheel_joint", "right_wheel_joint"].map(|j| WheelSpec {
        joint: j.into(),
        radius: BRAKE_TEST_ROBOT_WHEEL_RADIUS,
    });
    let casters = ["rear_left_caster", "rear_right_caster"].map(|f| CasterSpec::on_frame(f, 0.0));
    ContactPlant::new(model, &wheels, &casters, params).expect("the contact plant")
}

/// The mobile manipulator's six arm joints, base to tool.
pub const MOBILE_MANIPULATOR_ARM: [&str; 6] = [
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
];

/// Radius of Fetch's drive wheels (m): the rim of their collision meshes, as
/// `mobile::wheeled_base_from_urdf` reads it.
pub const FETCH_WHEEL_RADIUS: f64 = 0.060325002979023566;

/// Fetch's torso and seven arm joints, base to tool.
pub const FETCH_ARM: [&str; 8] = [
    "torso_lift_joint",
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "upperarm_roll_joint",
    "elbow_flex_joint",
    "forearm_roll_joint",
    "wrist_flex_joint",
    "wrist_roll_joint",
];

/// The contact plant of Fetch (`tests/data/robots/fetch`, its description's drive wheels
/// and the four ball casters of `scenarios/mission_fetch_contact.toml`: spheres of radius
/// 0.0601 m at x = 0.15 and −0.2 m, y = ±0.12 m, z = 0.055325 m in `base_link`) on a
/// free-flyer root, with the contact parameters `params`.
pub fn fetch_plant(params: ContactParams) -> ContactPlant {
    let urdf = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/robots/fetch/fetch_description/robots/fetch.urdf");
    let model = model_from_urdf_file(urdf, RootJoint::FreeFlyer).expect("fetch.urdf");
    let wheels = ["l_wheel_joint", "r_wheel_joint"].map(|j| WheelSpec {
        joint: j.into(),
        radius: FETCH_WHEEL_RADIUS,
    });
    let casters = [[0.15, 0.12], [0.15, -0.12], [-0.2, -0.12], [-0.2, 0.12]]
        .map(|[x, y]| CasterSpec::at_position("base_link", [x, y, 0.055325], 0.0601));
    ContactPlant::new(model, &wheels, &casters, params).expect("the contact plant")
}

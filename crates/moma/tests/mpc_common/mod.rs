//! Fetch set up for the whole-body MPC, shared by the MPC tests, its bench and example.
//!
//! Drive: wheel radius 0.0603 m (the extent of `l_wheel_link_collision.STL`), half track
//! 0.18738 m (the wheel joints' origins), axle on the base origin (d = 0; the URDF's
//! 1.3 mm offset is left out). The URDF has no casters: four are assumed at
//! (±0.20, ±0.12) m in the base frame, inside the base's collision footprint
//! (±0.287 m × ±0.264 m). Moved joints: torso and the seven arm joints; the head and
//! the gripper fingers are held.
#![allow(dead_code)]

use moma::collision::{Convex, GeometryModel, GeometryOptions, Scene, SceneObject};
use moma::control::mpc::{Clearance, MpcRobot, MpcSettings, WholeBodyMpc};
use moma::io::urdf::model_from_urdf_file;
use moma::mobile::{Caster, DiffDrive, WheeledBase, WheeledModel};
use moma::multibody::RootJoint;
use moma::spatial::SE3;
use moma::stability::{BodySet, StabilityModel, SupportAttachment, SupportPolygon};
use nalgebra::{DVector, Vector3};

/// The moved joints.
pub const MOVED: [&str; 8] = [
    "torso_lift_joint",
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "upperarm_roll_joint",
    "elbow_flex_joint",
    "forearm_roll_joint",
    "wrist_flex_joint",
    "wrist_roll_joint",
];

/// The folder of Fetch's files.
pub fn fetch_dir() -> String {
    format!("{}/tests/data/robots/fetch", env!("CARGO_MANIFEST_DIR"))
}

/// Fetch on its differential drive with the assumed casters.
pub fn fetch_wheeled() -> WheeledModel {
    let urdf = format!("{}/fetch_description/robots/fetch.urdf", fetch_dir());
    let model = model_from_urdf_file(&urdf, RootJoint::Planar).unwrap();
    let casters = [(0.2, 0.12), (0.2, -0.12), (-0.2, 0.12), (-0.2, -0.12)]
        .iter()
        .enumerate()
        .map(|(i, &(x, y))| Caster {
            name: format!("caster_{i}"),
            position: [x, y],
        })
        .collect();
    let base = WheeledBase {
        drive: DiffDrive::new(0.0603, 0.18738, 0.0).unwrap(),
        casters,
        wheel_joints: Some(["l_wheel_joint".into(), "r_wheel_joint".into()]),
    };
    WheeledModel::new(model, base).unwrap()
}

/// A table-top box: centre and half sizes (m).
pub fn box_object(id: &str, centre: [f64; 3], half: [f64; 3]) -> SceneObject {
    let pose = SE3::new(nalgebra::Matrix3::identity(), Vector3::from(centre));
    SceneObject::new(
        id,
        vec![(
            pose,
            Convex::Box {
                half: Vector3::from(half),
            },
        )],
    )
    .unwrap()
}

/// The SRDF of the MPC's Fetch, `scenarios/fetch_mpc.srdf`: Fetch's, with the pair
/// `torso_lift_link`–`shoulder_lift_link` disabled too (their hulls are under 0.02 m apart
/// in every posture, so no clearance of 0.03 m can hold for them; see that file).
pub fn mpc_srdf() -> String {
    format!(
        "{}/../../scenarios/fetch_mpc.srdf",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// The MPC's view of Fetch with `scene` (`None`: no clearance constraint).
pub fn fetch_robot(scene: Option<Scene>) -> MpcRobot {
    let wm = fetch_wheeled();
    let support = SupportPolygon::from_wheeled_model(&wm).unwrap();
    let sm =
        StabilityModel::new(&wm.model, support, SupportAttachment::Base, &BodySet::All).unwrap();
    let clearance = scene.map(|scene| {
        let dir = fetch_dir();
        let urdf = format!("{dir}/fetch_description/robots/fetch.urdf");
        let opts = GeometryOptions {
            package_dirs: vec![dir.clone().into()],
            srdf: Some(mpc_srdf().into()),
        };
        let geometry = GeometryModel::from_urdf(&wm.model, urdf.as_ref(), &opts).unwrap();
        Clearance { geometry, scene }
    });
    MpcRobot::new(wm, sm, clearance, &MOVED, "gripper_link").unwrap()
}

/// A start configuration: base at the origin, torso down, the arm folded in front of the
/// body, clear of itself.
pub fn fetch_start(robot: &MpcRobot) -> DVector<f64> {
    let model = &robot.wheeled.model;
    let mut q = DVector::zeros(model.nq);
    for (name, v) in [
        ("torso_lift_joint", 0.1),
        ("shoulder_pan_joint", 0.0),
        ("shoulder_lift_joint", -0.6),
        ("upperarm_roll_joint", 0.0),
        ("elbow_flex_joint", 1.6),
        ("forearm_roll_joint", 0.0),
        ("wrist_flex_joint", 0.6),
        ("wrist_roll_joint", 0.0),
    ] {
        let j = model.joint_id(name).unwrap();
        q[model.idx_q[j.0]] = v;
    }
    q
}

/// The MPC on Fetch with default settings.
pub fn fetch_mpc(scene: Option<Scene>, settings: MpcSettings) -> (WholeBodyMpc, DVector<f64>) {
    let robot = fetch_robot(scene);
    let q0 = fetch_start(&robot);
    (WholeBodyMpc::new(robot, settings, &q0).unwrap(), q0)
}

/// The MPC on Fetch set up for a hard stop: five times Fetch's wheel torque (so that
/// braking can tip it) and the arm raised forward (torso up 0.38 m, shoulder lifted by
/// −1 rad, elbow and wrist straight) in the returned configuration.
pub fn fetch_hard_stop(settings: MpcSettings) -> (WholeBodyMpc, DVector<f64>) {
    let (mut mpc, mut q0) = fetch_mpc(None, settings);
    let robot = &mut mpc.problem.robot;
    robot.torque_limit[0] *= 5.0;
    robot.torque_limit[1] *= 5.0;
    let model = &robot.wheeled.model;
    for (name, v) in [
        ("torso_lift_joint", 0.38),
        ("shoulder_lift_joint", -1.0),
        ("elbow_flex_joint", 0.0),
        ("wrist_flex_joint", 0.0),
    ] {
        let j = model.joint_id(name).unwrap();
        q0[model.idx_q[j.0]] = v;
    }
    (mpc, q0)
}

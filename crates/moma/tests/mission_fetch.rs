//! The shipped Fetch mission: the robot read from its URDF package (drive from the wheel
//! joints, casters from the casters file, arm joints named) and its footprint taken from
//! its collision geometry, against Pinocchio's placement of the same meshes.

use moma::mission::{FootprintSource, load};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `radius`, `x` and `y` of tests/data/robots/fetch/footprint_pinocchio.txt.
fn reference() -> (f64, [f64; 2], [f64; 2]) {
    let text = std::fs::read_to_string(
        root().join("crates/moma/tests/data/robots/fetch/footprint_pinocchio.txt"),
    )
    .unwrap();
    let v: toml::Value = toml::from_str(&text).unwrap();
    let pair = |k: &str| {
        let a = v[k].as_array().unwrap();
        [a[0].as_float().unwrap(), a[1].as_float().unwrap()]
    };
    (v["radius"].as_float().unwrap(), pair("x"), pair("y"))
}

#[test]
fn fetch_footprint_is_its_collision_geometry_at_the_transport_posture() {
    let m = load(&root().join("scenarios/mission_fetch.toml")).unwrap();
    let (radius, x, y) = reference();
    // moma's hull vertices are the meshes' (single precision) vertices placed by moma's
    // kinematics; Pinocchio places the same vertices: agreement to rounding.
    assert!(
        (m.footprint.radius - radius).abs() < 1e-9,
        "{} vs {radius}",
        m.footprint.radius
    );
    let FootprintSource::Robot {
        polygon, padding, ..
    } = &m.footprint.source
    else {
        panic!("the footprint comes from the robot");
    };
    assert_eq!(*padding, 0.0);
    let xs = polygon.iter().map(|p| p[0]);
    let ys = polygon.iter().map(|p| p[1]);
    let (x0, x1) = (
        xs.clone().fold(f64::MAX, f64::min),
        xs.fold(f64::MIN, f64::max),
    );
    let (y0, y1) = (
        ys.clone().fold(f64::MAX, f64::min),
        ys.fold(f64::MIN, f64::max),
    );
    for (a, b) in [(x0, x[0]), (x1, x[1]), (y0, y[0]), (y1, y[1])] {
        assert!((a - b).abs() < 1e-9, "{a} vs {b}");
    }
    // The drive from the URDF: Fetch's wheel joints and wheel meshes.
    let dd = m.robot.base.drive;
    assert!((dd.half_track - 0.18738).abs() < 1e-12);
    assert!((dd.d + 0.0012914).abs() < 1e-12);
    // The casters from the casters file, the postures over the named joints only.
    assert_eq!(m.robot.base.casters.len(), 4);
    let names = m.robot.model.names.clone();
    let named: Vec<&str> = m
        .robot
        .arm_dofs()
        .iter()
        .zip(&m.transport)
        .filter(|(_, a)| **a != 0.0)
        .map(|(&i, _)| names[m.robot.model.joint_of_dof[i].0].as_str())
        .collect();
    assert_eq!(
        named,
        [
            "shoulder_pan_joint",
            "shoulder_lift_joint",
            "upperarm_roll_joint",
            "elbow_flex_joint",
            "wrist_flex_joint"
        ]
    );
}

#[test]
fn padding_grows_the_robot_footprint_and_a_typed_radius_stays() {
    let path = root().join("scenarios/mission_fetch.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    let base = path.parent().unwrap();
    let with = |t: &str| {
        let f = moma::mission::scenario::parse_file(t, &path).unwrap();
        moma::mission::scenario::from_file(f, &path, base)
    };
    let padded = with(&text.replace(
        "footprint = \"robot\"",
        "footprint = { from = \"robot\", padding = 0.05 }",
    ))
    .unwrap();
    let (radius, _, _) = reference();
    assert!((padded.footprint.radius - (radius + 0.05)).abs() < 1e-9);
    let typed = with(&text.replace("footprint = \"robot\"", "footprint_radius = 0.4")).unwrap();
    assert_eq!(typed.footprint.radius, 0.4);
    assert_eq!(typed.footprint.source, FootprintSource::Radius);
    let both = with(&text.replace(
        "footprint = \"robot\"",
        "footprint = \"robot\"\nfootprint_radius = 0.4",
    ))
    .unwrap_err()
    .to_string();
    assert!(both.contains("robot.footprint"), "{both}");
}

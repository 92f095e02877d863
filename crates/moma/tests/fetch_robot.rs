//! Fetch as a wheeled robot read from its URDF: the differential drive (wheel radius from
//! the wheel links' collision meshes, track and axle offset from the wheel joints), the
//! casters from the shipped casters file, the torso lift and the seven arm joints with
//! their URDF limits, and the wheeled model they make.

use moma::collision::GeometryModel;
use moma::mobile::{WheeledModel, read_casters, wheeled_base_from_urdf};
use moma::multibody::{Model, RootJoint};
use moma::stability::SupportPolygon;
use std::path::Path;

mod fetch_common;
use fetch_common::{fetch_dir, fetch_geometry};

fn fetch() -> (Model, GeometryModel) {
    fetch_geometry(RootJoint::Planar)
}

/// The largest distance of the wheel collision mesh's vertices from the wheel axle (the
/// mesh's y axis), computed with Python's `struct` from the binary STL files
/// `l_wheel_link_collision.STL` and `r_wheel_link_collision.STL` (1372 triangles each, the
/// same value for both): the vertices are single precision.
const WHEEL_RADIUS_FROM_STL: f64 = 0.060325002979023566;

#[test]
fn fetch_drive_comes_from_its_urdf() {
    let (model, gm) = fetch();
    let casters = read_casters(&fetch_dir().join("casters.toml")).unwrap();
    let base =
        wheeled_base_from_urdf(&model, &gm, ["l_wheel_joint", "r_wheel_joint"], casters).unwrap();
    let dd = base.drive;
    // The URDF's wheel joints: origins (0.0012914, ±0.18738, 0.055325), axes along y.
    assert!(
        (dd.half_track - 0.18738).abs() < 1e-12,
        "b = {}",
        dd.half_track
    );
    assert!((dd.d + 0.0012914).abs() < 1e-12, "d = {}", dd.d);
    // The hull of the mesh holds its vertices exactly (f32 read as f64).
    assert!(
        (dd.wheel_radius - WHEEL_RADIUS_FROM_STL).abs() < 1e-9,
        "r_w = {}",
        dd.wheel_radius
    );
    // The wheels sit 5 mm below base_link's origin (axle 0.055325 m up, radius 0.060325 m):
    // the tracked wheels put the ground there.
    let robot = WheeledModel::new(model, base).unwrap();
    assert!((robot.ground_z() - (0.055325 - WHEEL_RADIUS_FROM_STL)).abs() < 1e-9);
    // The support: two wheel contacts and four casters, a hexagon around the base origin.
    let support = SupportPolygon::from_wheeled_model(&robot).unwrap();
    assert_eq!(support.len(), 6);
    let xs: Vec<f64> = support.vertices_xy().iter().map(|v| v.x).collect();
    let ys: Vec<f64> = support.vertices_xy().iter().map(|v| v.y).collect();
    let max = |v: &[f64]| v.iter().copied().fold(f64::MIN, f64::max);
    let min = |v: &[f64]| v.iter().copied().fold(f64::MAX, f64::min);
    assert_eq!((min(&xs), max(&xs)), (-0.2, 0.15));
    assert!((max(&ys) - 0.18738).abs() < 1e-12 && (min(&ys) + 0.18738).abs() < 1e-12);
}

#[test]
fn fetch_arm_with_torso_has_the_urdf_limits() {
    let (model, _) = fetch();
    // (joint, continuous, lower, upper, velocity, effort) as in fetch.urdf.
    let want: [(&str, bool, f64, f64, f64, f64); 8] = [
        ("torso_lift_joint", false, 0.0, 0.38615, 0.1, 450.0),
        ("shoulder_pan_joint", false, -1.6056, 1.6056, 1.256, 33.82),
        ("shoulder_lift_joint", false, -1.221, 1.518, 1.454, 131.76),
        ("upperarm_roll_joint", true, 0.0, 0.0, 1.571, 76.94),
        ("elbow_flex_joint", false, -2.251, 2.251, 1.521, 66.18),
        ("forearm_roll_joint", true, 0.0, 0.0, 1.571, 29.35),
        ("wrist_flex_joint", false, -2.16, 2.16, 2.268, 25.7),
        ("wrist_roll_joint", true, 0.0, 0.0, 2.268, 7.36),
    ];
    let group = moma::motion::JointGroup::new(&model, &want.map(|w| w.0)).unwrap();
    assert_eq!(
        group.prismatic,
        [true, false, false, false, false, false, false, false]
    );
    for (k, (name, continuous, lo, hi, vel, effort)) in want.into_iter().enumerate() {
        let j = model.joint_id(name).unwrap().0;
        let (iq, iv) = (model.idx_q[j], model.idx_v[j]);
        assert_eq!(group.continuous[k], continuous, "{name}");
        if continuous {
            assert!(model.lower_position_limit[iq].is_infinite(), "{name}");
            assert!(model.upper_position_limit[iq].is_infinite(), "{name}");
        } else {
            assert_eq!(model.lower_position_limit[iq], lo, "{name}");
            assert_eq!(model.upper_position_limit[iq], hi, "{name}");
        }
        assert_eq!(model.velocity_limit[iv], vel, "{name}");
        assert_eq!(model.effort_limit[iv], effort, "{name}");
    }
}

#[test]
fn bad_wheels_and_casters_are_named() {
    let (model, gm) = fetch();
    let err = wheeled_base_from_urdf(&model, &gm, ["torso_lift_joint", "r_wheel_joint"], vec![])
        .unwrap_err()
        .to_string();
    assert!(err.contains("torso_lift_joint"), "{err}");
    let err = wheeled_base_from_urdf(&model, &gm, ["r_wheel_joint", "l_wheel_joint"], vec![])
        .unwrap_err()
        .to_string();
    assert!(err.contains("+y side"), "{err}");
    let err = wheeled_base_from_urdf(&model, &gm, ["shoulder_pan_joint", "r_wheel_joint"], vec![])
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("shoulder_pan_joint") && err.contains("planar base"),
        "{err}"
    );
    let p = Path::new("casters.toml");
    let err = moma::mobile::casters_from_str(
        "[[casters]]\nname = \"a\"\nposition = [0.1, 0.2]\n[[casters]]\nname = \"a\"\nposition = [0.0, 0.0]\n",
        p,
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("casters.toml") && err.contains("casters[1].name"),
        "{err}"
    );
    let err = moma::mobile::casters_from_str("[[casters]]\nname = \"a\"\nposition = [0.1]\n", p)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("casters.toml") && err.contains("position"),
        "{err}"
    );
}

//! Collision geometry beyond the coal reference: the distance derivative against finite
//! differences, the footprint, voxel scenes against a brute-force minimum, and bad input
//! (each error names the file and the element).

use moma::collision::{
    GeometryData, GeometryModel, GeometryOptions, PairSelection, Scene, SceneData, SceneObject,
    SceneOptions, compute_distances, compute_scene_distances, distance_derivative, footprint,
    point_cloud_object, read_scene, update_geometry_placements, voxel_object,
};
use moma::kinematics::{compute_joint_jacobians, forward_kinematics, random_configuration};
use moma::multibody::{Data, Model, RootJoint};
use moma::planning::grid3::Grid3;
use nalgebra::{DVector, Vector3};
use rand::{Rng, SeedableRng};
use std::path::{Path, PathBuf};

fn fetch_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/robots/fetch")
}

fn fetch(root: RootJoint) -> (Model, GeometryModel) {
    let dir = fetch_dir();
    let urdf = dir.join("fetch_description/robots/fetch.urdf");
    let model = moma::io::urdf::model_from_urdf_file(&urdf, root).unwrap();
    let opts = GeometryOptions {
        package_dirs: vec![dir.clone()],
        srdf: Some(dir.join("fetch.srdf")),
    };
    let gm = GeometryModel::from_urdf(&model, &urdf, &opts).unwrap();
    (model, gm)
}

fn distances_at(
    model: &Model,
    gm: &GeometryModel,
    data: &mut Data,
    gd: &mut GeometryData,
    q: &DVector<f64>,
) {
    forward_kinematics(model, data, q);
    update_geometry_placements(gm, data, gd);
    compute_distances(gm, gd, PairSelection::Enabled);
}

#[test]
fn distance_derivative_matches_finite_differences() {
    let (model, gm) = fetch(RootJoint::Planar);
    let mut data = Data::new(&model);
    let mut gd = GeometryData::new(&gm);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let mut grad = DVector::zeros(model.nv);
    let h = 1e-7;
    let mut checked = 0;
    for _ in 0..30 {
        let q = random_configuration(&model, &mut rng);
        distances_at(&model, &gm, &mut data, &mut gd, &q);
        compute_joint_jacobians(&model, &mut data, &q);
        let base = gd.results.clone();
        for p in 0..gm.pairs.len() {
            // Away from contact, where the closest features are well defined.
            if !gm.enabled[p] || base[p].distance < 0.01 {
                continue;
            }
            distance_derivative(&model, &data, &gm, &gd, p, &mut grad);
            let k = rng.random_range(0..model.nv);
            let mut v = DVector::zeros(model.nv);
            v[k] = 1.0;
            let mut qp = q.clone();
            moma::kinematics::integrate(&model, &q, &(&v * h), &mut qp);
            let mut qm = q.clone();
            moma::kinematics::integrate(&model, &q, &(&v * -h), &mut qm);
            distances_at(&model, &gm, &mut data, &mut gd, &qp);
            let dp = gd.results[p].distance;
            distances_at(&model, &gm, &mut data, &mut gd, &qm);
            let dm = gd.results[p].distance;
            let fd = (dp - dm) / (2.0 * h);
            // Restore the state's kinematics for the next pair.
            distances_at(&model, &gm, &mut data, &mut gd, &q);
            compute_joint_jacobians(&model, &mut data, &q);
            // A kink (the closest features switching within ±h) shows as one-sided
            // slopes that disagree; skip those.
            let one_sided = ((dp - base[p].distance) / h - (base[p].distance - dm) / h).abs();
            if one_sided > 1e-3 {
                continue;
            }
            assert!(
                (fd - grad[k]).abs() <= 1e-4 * (1.0 + fd.abs()),
                "pair {p} dof {k}: analytic {} vs finite difference {fd}",
                grad[k]
            );
            checked += 1;
        }
    }
    assert!(checked > 300, "{checked} derivatives checked");
}

#[test]
fn footprint_contains_the_projected_geometry_and_follows_the_base() {
    let (model, gm) = fetch(RootJoint::Planar);
    let mut data = Data::new(&model);
    let mut gd = GeometryData::new(&gm);
    let mut scratch = Vec::new();
    let mut q = DVector::zeros(model.nq);
    forward_kinematics(&model, &mut data, &q);
    update_geometry_placements(&gm, &data, &mut gd);
    let fp = footprint(&gm, &gd, &mut scratch);
    // Counter-clockwise and convex.
    let n = fp.len();
    assert!(n >= 3);
    for i in 0..n {
        let (a, b, c) = (fp[i], fp[(i + 1) % n], fp[(i + 2) % n]);
        assert!((b - a).perp(&(c - b)) >= -1e-12);
    }
    // Every hull vertex of every link projects inside.
    for (o, pose) in gm.objects.iter().zip(&gd.placements) {
        if let moma::collision::Convex::Hull { vertices, .. } = &o.shape {
            for v in vertices {
                let p = pose.act_point(v);
                for i in 0..n {
                    let (a, b) = (fp[i], fp[(i + 1) % n]);
                    assert!((b - a).perp(&(p.xy() - a)) >= -1e-9);
                }
            }
        }
    }
    // Fetch's base is a disc of radius ~0.28 m about base_link.
    let reach = fp.iter().map(|p| p.norm()).fold(0.0, f64::max);
    assert!(reach > 0.25 && reach < 1.2, "{reach}");
    // Moving the base by (1, 2) moves the footprint by (1, 2).
    q[0] = 1.0;
    q[1] = 2.0;
    forward_kinematics(&model, &mut data, &q);
    update_geometry_placements(&gm, &data, &mut gd);
    let moved = footprint(&gm, &gd, &mut scratch);
    let area = |p: &[nalgebra::Vector2<f64>]| {
        (0..p.len())
            .map(|i| p[i].perp(&p[(i + 1) % p.len()]))
            .sum::<f64>()
            / 2.0
    };
    assert!((area(&moved) - area(&fp)).abs() < 1e-9);
    let cx = |p: &[nalgebra::Vector2<f64>]| p.iter().map(|v| v.x).fold(f64::INFINITY, f64::min);
    assert!((cx(&moved) - cx(&fp) - 1.0).abs() < 1e-9);
}

#[test]
fn voxel_and_point_cloud_scenes_match_brute_force() {
    let (model, gm) = fetch(RootJoint::Fixed);
    let mut data = Data::new(&model);
    let mut gd = GeometryData::new(&gm);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let mut grid = Grid3::new(40, 30, 20).unwrap();
    for _ in 0..3000 {
        let (x, y, z) = (
            rng.random_range(0..40),
            rng.random_range(0..30),
            rng.random_range(0..20),
        );
        grid.set_blocked(x, y, z, true);
    }
    let origin = Vector3::new(0.3, -0.75, 0.0);
    let tree = Scene {
        objects: vec![voxel_object("grid", &grid, 0.05, origin).unwrap()],
    };
    // The same voxels, one object each: no tree to prune.
    let flat = Scene {
        objects: tree.objects[0]
            .shapes
            .iter()
            .enumerate()
            .map(|(i, s)| {
                SceneObject::new(format!("v{i}"), vec![(s.pose, s.shape.clone())]).unwrap()
            })
            .collect(),
    };
    let mut sd_tree = SceneData::new(&gm, &tree);
    let mut sd_flat = SceneData::new(&gm, &flat);
    for _ in 0..5 {
        let q = random_configuration(&model, &mut rng);
        forward_kinematics(&model, &mut data, &q);
        update_geometry_placements(&gm, &data, &mut gd);
        let a = compute_scene_distances(&gm, &mut gd, &tree, &mut sd_tree);
        let b = compute_scene_distances(&gm, &mut gd, &flat, &mut sd_flat);
        assert!((a - b).abs() < 1e-9, "tree {a} vs brute force {b}");
        for l in 0..gm.links.len() {
            let per_link = (0..flat.objects.len())
                .map(|o| sd_flat.results[l * flat.objects.len() + o].distance)
                .fold(f64::INFINITY, f64::min);
            assert!((sd_tree.results[l].distance - per_link).abs() < 1e-9);
        }
    }
    // A point cloud: one voxel per occupied cell.
    let pts = [
        Vector3::new(0.01, 0.01, 0.01),
        Vector3::new(0.02, 0.03, 0.04),
        Vector3::new(1.0, 0.0, 0.0),
    ];
    assert_eq!(
        point_cloud_object("cloud", &pts, 0.1).unwrap().shapes.len(),
        2
    );
    let e = point_cloud_object("cloud", &[Vector3::new(f64::NAN, 0.0, 0.0)], 0.1).unwrap_err();
    assert!(e.to_string().contains("point 0"), "{e}");
}

fn write(dir: &Path, name: &str, text: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn bad_input_names_the_file_and_the_element() {
    let dir = std::env::temp_dir().join(format!("moma_collision_bad_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let urdf_with = |mesh: &str| {
        format!(
            r#"<robot name="r"><link name="a"><collision><geometry><box size="1 1 1"/></geometry></collision></link>
<link name="b"><collision><geometry><mesh filename="{mesh}"/></geometry></collision></link>
<joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"#
        )
    };
    let load = |urdf: &str, srdf: Option<PathBuf>| {
        let p = write(&dir, "r.urdf", urdf.as_bytes());
        let model = moma::io::urdf::model_from_urdf_file(&p, RootJoint::Fixed).unwrap();
        GeometryModel::from_urdf(
            &model,
            &p,
            &GeometryOptions {
                package_dirs: vec![],
                srdf,
            },
        )
        .map(|_| ())
        .unwrap_err()
        .to_string()
    };
    let e = load(&urdf_with("missing.stl"), None);
    assert!(e.contains("link 'b'") && e.contains("missing.stl"), "{e}");
    let e = load(&urdf_with("package://nopkg/m.stl"), None);
    assert!(
        e.contains("link 'b'")
            && e.contains("package://nopkg/m.stl")
            && e.contains("--package-dir"),
        "{e}"
    );
    write(&dir, "empty.stl", b"");
    let e = load(&urdf_with("empty.stl"), None);
    assert!(e.contains("empty.stl") && e.contains("link 'b'"), "{e}");
    write(
        &dir,
        "nan.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 nan 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n",
    );
    let e = load(&urdf_with("nan.obj"), None);
    assert!(e.contains("nan.obj") && e.contains("not finite"), "{e}");
    write(&dir, "m.dae", b"<COLLADA/>");
    let e = load(&urdf_with("m.dae"), None);
    assert!(
        e.contains("m.dae") && e.contains("unsupported mesh format"),
        "{e}"
    );
    let srdf = write(
        &dir,
        "r.srdf",
        br#"<robot name="r"><disable_collisions link1="a" link2="ghost" reason="Never"/></robot>"#,
    );
    let good = urdf_with("package://p/m.stl").replace(
        r#"<mesh filename="package://p/m.stl"/>"#,
        r#"<sphere radius="0.1"/>"#,
    );
    let e = load(&good, Some(srdf));
    assert!(
        e.contains("r.srdf") && e.contains("ghost") && e.contains("element 1"),
        "{e}"
    );
    // Scenes: a negative size, an unknown frame.
    let opts = SceneOptions {
        world_frames: vec!["base_link".into()],
        package_dirs: vec![],
    };
    let scene = |text: &str| {
        read_scene(&write(&dir, "s.yaml", text.as_bytes()), &opts)
            .map(|_| ())
            .unwrap_err()
            .to_string()
    };
    let e = scene(
        "world:\n  collision_objects:\n    - header: {frame_id: base_link}\n      id: Box1\n      primitives: [{type: box, dimensions: [0.1, -0.2, 0.3]}]\n      primitive_poses: [{position: [0, 0, 0], orientation: [0, 0, 0, 1]}]\n",
    );
    assert!(
        e.contains("s.yaml") && e.contains("Box1") && e.contains("-0.2"),
        "{e}"
    );
    let e = scene(
        "world:\n  collision_objects:\n    - header: {frame_id: odom}\n      id: Box1\n      primitives: [{type: box, dimensions: [0.1, 0.2, 0.3]}]\n      primitive_poses: [{position: [0, 0, 0], orientation: [0, 0, 0, 1]}]\n",
    );
    assert!(
        e.contains("s.yaml") && e.contains("Box1") && e.contains("unknown frame 'odom'"),
        "{e}"
    );
    let e = scene("world: [");
    assert!(e.contains("s.yaml"), "{e}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn panda_without_its_meshes_names_the_first_link_and_uri() {
    // The repository's Panda URDF has 17 collision elements: 9 STL meshes of
    // example-robot-data (in tests/data/robots/panda, not given here) and 8 boxes on the
    // fingers.
    let urdf = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pinocchio/urdf/panda.urdf");
    let model = moma::io::urdf::model_from_urdf_file(&urdf, RootJoint::Fixed).unwrap();
    let e = GeometryModel::from_urdf(&model, &urdf, &GeometryOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("link 'panda_link0'")
            && e.contains(
                "package://example-robot-data/robots/panda_description/meshes/collision/link0.stl"
            )
            && e.contains("--package-dir"),
        "{e}"
    );
}

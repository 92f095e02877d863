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
    // A mesh file that does not exist: the URDF, the link, the URI.
    let e = load(&urdf_with("missing.stl"), None);
    assert!(
        e.contains("r.urdf")
            && e.contains("link 'b' mesh 'missing.stl'")
            && e.contains("cannot resolve"),
        "{e}"
    );
    let e = load(&urdf_with("package://nopkg/m.stl"), None);
    assert!(
        e.contains("link 'b'")
            && e.contains("package://nopkg/m.stl")
            && e.contains("--package-dir"),
        "{e}"
    );
    // Empty mesh files: the URDF, the link, the mesh file, and that it is empty.
    write(&dir, "empty.stl", b"");
    write(&dir, "empty.obj", b"\n");
    for name in ["empty.stl", "empty.obj"] {
        let e = load(&urdf_with(name), None);
        assert!(
            e.contains("r.urdf")
                && e.contains(&format!("link 'b' mesh '{name}'"))
                && e.contains(&format!("{name}: the mesh file is empty")),
            "{e}"
        );
    }
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

/// A link of the test robots: its name and the content of its `<collision>` element
/// (`None`: no collision element).
fn link_xml(name: &str, geometry: Option<&str>) -> String {
    match geometry {
        Some(g) => format!(
            r#"<link name="{name}"><inertial><mass value="1"/><inertia ixx="0.01" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial><collision>{g}</collision></link>"#
        ),
        None => format!(r#"<link name="{name}"/>"#),
    }
}

/// A joint of the test robots: name, type, parent and child links, origin and axis.
fn joint_xml(name: &str, kind: &str, parent: &str, child: &str, xyz: &str, axis: &str) -> String {
    format!(
        r#"<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/><origin xyz="{xyz}"/><axis xyz="{axis}"/><limit lower="-2" upper="2" effort="1" velocity="1"/></joint>"#
    )
}

/// The names of the enabled pairs, each sorted, in a sorted list.
fn enabled_pairs(gm: &GeometryModel) -> Vec<[String; 2]> {
    let mut out: Vec<[String; 2]> = gm
        .pairs
        .iter()
        .zip(&gm.enabled)
        .filter(|(_, e)| **e)
        .map(|(&[a, b], _)| {
            let mut p = [gm.links[a].name.clone(), gm.links[b].name.clone()];
            p.sort();
            p
        })
        .collect();
    out.sort();
    out
}

#[test]
fn pair_rules_without_an_srdf_drop_adjacent_and_fixed_together_links() {
    // base ─fixed─ torso ─revolute─ arm1 ─revolute─ arm2 ─fixed─ mount ─fixed─ hand
    //  │              └─revolute─ head (a branch)
    //  └─fixed─ caster
    // `mount` has no geometry: arm2 and hand are fixed to each other without one joint
    // between them; base, torso and caster ride on the fixed root together.
    let sphere = r#"<geometry><sphere radius="0.05"/></geometry>"#;
    let mut urdf = String::from(r#"<robot name="tree">"#);
    for (name, g) in [
        ("base", Some(sphere)),
        ("torso", Some(sphere)),
        ("caster", Some(sphere)),
        ("arm1", Some(sphere)),
        ("arm2", Some(sphere)),
        ("mount", None),
        ("hand", Some(sphere)),
        ("head", Some(sphere)),
    ] {
        urdf.push_str(&link_xml(name, g));
    }
    for (name, kind, parent, child) in [
        ("j_torso", "fixed", "base", "torso"),
        ("j_caster", "fixed", "base", "caster"),
        ("j_arm1", "revolute", "torso", "arm1"),
        ("j_arm2", "revolute", "arm1", "arm2"),
        ("j_mount", "fixed", "arm2", "mount"),
        ("j_hand", "fixed", "mount", "hand"),
        ("j_head", "revolute", "torso", "head"),
    ] {
        urdf.push_str(&joint_xml(name, kind, parent, child, "0 0 0.3", "0 0 1"));
    }
    urdf.push_str("</robot>");
    let dir = std::env::temp_dir().join(format!("moma_collision_pairs_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = write(&dir, "tree.urdf", urdf.as_bytes());
    let model = moma::io::urdf::model_from_urdf_file(&path, RootJoint::Fixed).unwrap();
    let load = |srdf: Option<PathBuf>| {
        GeometryModel::from_urdf(
            &model,
            &path,
            &GeometryOptions {
                package_dirs: vec![],
                srdf,
            },
        )
        .unwrap()
    };
    let gm = load(None);
    assert_eq!(gm.links.len(), 7);
    assert_eq!(gm.pairs.len(), 21);
    // Dropped: base–torso, base–caster, torso–caster (the fixed root), arm2–hand (fixed
    // through mount), torso–arm1, arm1–arm2, torso–head (one joint each).
    let want: Vec<[String; 2]> = [
        ["arm1", "base"],
        ["arm1", "caster"],
        ["arm1", "hand"],
        ["arm1", "head"],
        ["arm2", "base"],
        ["arm2", "caster"],
        ["arm2", "head"],
        ["arm2", "torso"],
        ["base", "hand"],
        ["base", "head"],
        ["caster", "hand"],
        ["caster", "head"],
        ["hand", "head"],
        ["hand", "torso"],
    ]
    .iter()
    .map(|p| p.map(String::from))
    .collect();
    assert_eq!(enabled_pairs(&gm), want);
    assert_eq!(gm.n_enabled(), 14);
    // An SRDF drops one more pair; a pair naming a link without geometry (mount) is
    // accepted and changes nothing.
    let srdf = write(
        &dir,
        "tree.srdf",
        br#"<robot name="tree"><disable_collisions link1="hand" link2="arm1" reason="Never"/><disable_collisions link1="mount" link2="base" reason="Never"/></robot>"#,
    );
    let gm = load(Some(srdf));
    let fewer: Vec<[String; 2]> = want
        .iter()
        .filter(|p| *p != &["arm1".to_string(), "hand".to_string()])
        .cloned()
        .collect();
    assert_eq!(fewer.len(), 13);
    assert_eq!(enabled_pairs(&gm), fewer);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_urdf_capsule_and_an_obj_mesh_measure_their_closed_forms() {
    // `cap`: a capsule of radius 0.1 whose segment runs from z = 0.3 to 0.7 (length 0.4,
    // centred at z = 0.5). `ball`: a sphere of radius 0.05 at (0.3, 0, q0). `cube`: an OBJ
    // cube of half-side 1 scaled by 0.1, centred at (−0.4, 0, q1); a vertex in the middle
    // of one edge makes its two faces pentagons and the other four are quads, so tobj
    // triangulates 4 × 2 + 2 × 3 = 14 triangles.
    let dir = std::env::temp_dir().join(format!("moma_collision_shapes_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    write(
        &dir,
        "cube.obj",
        b"# a cube with a pentagon on top\n\
v -1 -1 -1\nv 1 -1 -1\nv 1 1 -1\nv -1 1 -1\n\
v -1 -1 1\nv 1 -1 1\nv 1 1 1\nv -1 1 1\nv 1 0 1\n\
f 1 4 3 2\nf 1 2 6 5\nf 2 3 7 9 6\nf 3 4 8 7\nf 4 1 5 8\nf 5 6 9 7 8\n",
    );
    let mut urdf = String::from(r#"<robot name="shapes">"#);
    urdf.push_str(&link_xml(
        "cap",
        Some(r#"<origin xyz="0 0 0.5"/><geometry><capsule radius="0.1" length="0.4"/></geometry>"#),
    ));
    urdf.push_str(&link_xml(
        "ball",
        Some(r#"<geometry><sphere radius="0.05"/></geometry>"#),
    ));
    urdf.push_str(&link_xml(
        "cube",
        Some(r#"<geometry><mesh filename="cube.obj" scale="0.1 0.1 0.1"/></geometry>"#),
    ));
    urdf.push_str(&joint_xml(
        "z_ball",
        "prismatic",
        "cap",
        "ball",
        "0.3 0 0",
        "0 0 1",
    ));
    urdf.push_str(&joint_xml(
        "z_cube",
        "prismatic",
        "cap",
        "cube",
        "-0.4 0 0",
        "0 0 1",
    ));
    urdf.push_str("</robot>");
    let path = write(&dir, "shapes.urdf", urdf.as_bytes());
    let model = moma::io::urdf::model_from_urdf_file(&path, RootJoint::Fixed).unwrap();
    let gm = GeometryModel::from_urdf(&model, &path, &GeometryOptions::default()).unwrap();
    let cube = &gm.objects[gm.links[gm.link_index("cube").unwrap()].first];
    let mesh = cube.mesh.as_ref().expect("the cube keeps its triangles");
    assert_eq!((mesh.vertices.len(), mesh.triangles.len()), (9, 14));
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| mesh.vertices[i as usize]);
        assert!((b - a).cross(&(c - a)).norm() > 1e-3, "degenerate {t:?}");
    }
    let pair = |a: &str, b: &str| {
        let (ia, ib) = (gm.link_index(a).unwrap(), gm.link_index(b).unwrap());
        gm.pairs
            .iter()
            .position(|p| *p == [ia.min(ib), ia.max(ib)])
            .unwrap()
    };
    let (cap_ball, cap_cube) = (pair("cap", "ball"), pair("cap", "cube"));
    let (qb, qc) = (
        model.idx_q[model.joint_id("z_ball").unwrap().0],
        model.idx_q[model.joint_id("z_cube").unwrap().0],
    );
    let mut data = Data::new(&model);
    let mut gd = GeometryData::new(&gm);
    // (ball height, cube height, ball–capsule, cube–capsule): beside the segment, above
    // its top end (the cube's nearest edge 0.3 m out and 0.2 m up from it), level with
    // its top end, below its bottom end (0.3 m out and 0.3 m down).
    let cases = [
        (0.5, 0.5, 0.15, 0.2),
        (1.0, 1.0, 0.18f64.sqrt() - 0.15, 0.13f64.sqrt() - 0.1),
        (0.7, 0.7, 0.15, 0.2),
        (-0.1, -0.1, 0.5 - 0.15, 0.18f64.sqrt() - 0.1),
    ];
    for (zb, zc, want_ball, want_cube) in cases {
        let mut q = DVector::zeros(model.nq);
        q[qb] = zb;
        q[qc] = zc;
        forward_kinematics(&model, &mut data, &q);
        update_geometry_placements(&gm, &data, &mut gd);
        compute_distances(&gm, &mut gd, PairSelection::All);
        let (db, dc) = (gd.results[cap_ball].distance, gd.results[cap_cube].distance);
        assert!(
            (db - want_ball).abs() < 1e-9,
            "ball at z {zb}: {db} vs {want_ball}"
        );
        assert!(
            (dc - want_cube).abs() < 1e-9,
            "cube at z {zc}: {dc} vs {want_cube}"
        );
    }
    std::fs::remove_dir_all(&dir).ok();
}

//! Exact triangle-mesh distances (`collision::exact`) against coal 3.0.3's distances
//! between Fetch's BVH meshes (through Pinocchio 4.1.0), `distance_mesh` (0 where
//! triangles intersect; see tests/data/collision/SOURCES.md): the 76 SRDF-enabled link
//! pairs of every state of `fetch_self_public.json`, and every (link, object) pair of
//! the three MotionBenchMaker scenes of `fetch_scene_public.json` (the link meshes
//! against solid boxes and cylinders); a link mesh placed in the scene as a mesh object
//! is measured by its triangles, as the link itself. Panda the same way, against coal's
//! `distance_mesh` of `panda_self.json` and `panda_scene.json` (written by
//! `bench/pinocchio/panda_collision_reference.py`): every pair, the minimum and the
//! in-collision verdict (minimum 0) of every state, including states bisected to within
//! 3 mm of a mesh contact.

use moma::collision::{
    ExactGeometry, ExactScene, GeometryData, GeometryModel, PairSelection, SceneData, SceneOptions,
    compute_exact_distances, compute_exact_scene_distances, compute_scene_distances, read_scene,
    update_geometry_placements,
};
use moma::kinematics::forward_kinematics;
use moma::multibody::{Data, Model, RootJoint};
use nalgebra::{DVector, Rotation3, UnitQuaternion};
use serde_json::Value;

mod fetch_common;
use fetch_common::{data_dir, fetch_geometry, panda_geometry};

/// Fetch on a fixed base, its geometry with the SRDF, and its exact shapes.
fn fetch() -> (Model, GeometryModel, ExactGeometry) {
    let (model, gm) = fetch_geometry(RootJoint::Fixed);
    let ex = ExactGeometry::new(&gm).unwrap();
    (model, gm, ex)
}

/// A reference state's configuration (moma layout) from its `q_by_joint`.
fn q_of(model: &Model, s: &Value) -> DVector<f64> {
    let mut q = DVector::zeros(model.nq);
    for (name, v) in s["q_by_joint"].as_object().unwrap() {
        let j = model.joint_id(name).unwrap();
        q[model.idx_q[j.0]] = v.as_f64().unwrap();
    }
    q
}

fn reference(file: &str) -> Value {
    let text = std::fs::read_to_string(data_dir().join("collision").join(file)).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// The index in `gm.pairs` of each of the reference's `pairs` (two link names each).
fn pair_indices(gm: &GeometryModel, r: &Value) -> Vec<usize> {
    r["pairs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let a = gm.link_index(p[0].as_str().unwrap()).unwrap();
            let b = gm.link_index(p[1].as_str().unwrap()).unwrap();
            gm.pairs
                .iter()
                .position(|x| *x == [a.min(b), a.max(b)])
                .unwrap()
        })
        .collect()
}

#[test]
fn fetch_mesh_distances_match_coal() {
    let (model, gm, ex) = fetch();
    let r = reference("fetch_self_public.json");
    let pairs = pair_indices(&gm, &r);
    let mut data = Data::new(&model);
    let mut gd = GeometryData::new(&gm);
    let (mut worst, mut zeros, mut checked) = (0.0_f64, 0, 0);
    for s in r["states"].as_array().unwrap() {
        let q = q_of(&model, s);
        forward_kinematics(&model, &mut data, &q);
        update_geometry_placements(&gm, &data, &mut gd);
        compute_exact_distances(&gm, &ex, &mut gd, PairSelection::Enabled);
        let convex = s["distance_convex"].as_array().unwrap();
        for (k, want) in s["distance_mesh"].as_array().unwrap().iter().enumerate() {
            if !gm.enabled[pairs[k]] {
                continue;
            }
            let want = want.as_f64().unwrap();
            let res = &gd.results[pairs[k]];
            let err = (res.distance - want).abs();
            assert!(
                err <= 1e-6,
                "state {} pair {:?}: exact {} vs coal {want}",
                s["index"],
                r["pairs"][k],
                res.distance
            );
            // Never below the hulls' distance; the witnesses are the distance apart.
            assert!(res.distance >= convex[k].as_f64().unwrap() - 1e-9);
            assert!(((res.witness_b - res.witness_a).norm() - res.distance).abs() < 1e-9);
            worst = worst.max(err);
            zeros += usize::from(want == 0.0);
            checked += 1;
        }
    }
    eprintln!("{checked} pairs, {zeros} touching, worst error {worst:e} m");
    assert!(checked == 76 * 20 && zeros > 0, "{checked} {zeros}");
}

#[test]
fn fetch_scene_mesh_distances_match_coal() {
    let (model, gm, ex) = fetch();
    let r = reference("fetch_scene_public.json");
    let mut data = Data::new(&model);
    let mut gd = GeometryData::new(&gm);
    let opts = SceneOptions {
        world_frames: vec!["base_link".into()],
        package_dirs: vec![],
    };
    let (mut worst, mut separated, mut touching) = (0.0_f64, 0, 0);
    for (name, sc) in r["scenes"].as_object().unwrap() {
        let yaml = data_dir()
            .join("scenes/motion_bench_maker")
            .join(sc["scene_yaml"].as_str().unwrap());
        let scene = read_scene(&yaml, &opts).unwrap();
        let exs = ExactScene::new(&scene).unwrap();
        let mut sd = SceneData::new(&gm, &scene);
        let pairs = sc["pairs"].as_array().unwrap();
        assert_eq!(pairs.len(), gm.links.len() * scene.objects.len(), "{name}");
        for s in r["states"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|s| s["scene"] == name.as_str())
        {
            forward_kinematics(&model, &mut data, &q_of(&model, s));
            update_geometry_placements(&gm, &data, &mut gd);
            let min = compute_exact_scene_distances(&gm, &ex, &mut gd, &scene, &exs, &mut sd);
            let mut want_min = f64::INFINITY;
            for (k, p) in pairs.iter().enumerate() {
                let l = gm.link_index(p[0].as_str().unwrap()).unwrap();
                let o = scene.objects.iter().position(|o| o.id == p[1]).unwrap();
                let got = &sd.results[l * scene.objects.len() + o];
                let want = s["distance_mesh"][k].as_f64().unwrap();
                want_min = want_min.min(want);
                let label = format!("{name} {} {p}", s["label"]);
                if want > 0.0 {
                    let err = (got.distance - want).abs();
                    assert!(
                        err <= 1e-6,
                        "{label}: exact {} vs coal {want}",
                        got.distance
                    );
                    worst = worst.max(err);
                    separated += 1;
                    // the witnesses are the distance apart
                    assert!(((got.witness_b - got.witness_a).norm() - got.distance).abs() < 1e-9);
                } else {
                    assert_eq!(got.distance, 0.0, "{label}: coal's triangles intersect");
                    touching += 1;
                }
                // never below the hulls' distance
                let convex = s["distance_convex"][k].as_f64().unwrap();
                assert!(got.distance >= convex - 1e-9, "{label}");
            }
            assert!(
                (min - want_min).abs() <= 1e-6,
                "{name}: min {min} vs {want_min}"
            );
        }
    }
    eprintln!("{separated} separated pairs (worst error {worst:e} m), {touching} touching");
    assert!(separated > 5000 && touching > 0, "{separated} {touching}");
}

#[test]
fn a_link_mesh_placed_in_the_scene_is_measured_by_its_triangles() {
    // MotionBenchMaker's tucked default state: the torso's hull overlaps the shoulder
    // (coal: -0.0246 m) while the meshes are 0.0273 m apart.
    let (model, gm, ex) = fetch();
    let r = reference("fetch_self_public.json");
    let s = r["states"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["label"] == "mbm_fetch_default")
        .unwrap();
    let k = r["pairs"]
        .as_array()
        .unwrap()
        .iter()
        .position(|p| p[0] == "torso_lift_link" && p[1] == "shoulder_lift_link")
        .unwrap();
    let (want_mesh, want_convex) = (
        s["distance_mesh"][k].as_f64().unwrap(),
        s["distance_convex"][k].as_f64().unwrap(),
    );
    let mut data = Data::new(&model);
    let mut gd = GeometryData::new(&gm);
    forward_kinematics(&model, &mut data, &q_of(&model, s));
    update_geometry_placements(&gm, &data, &mut gd);
    // the torso's mesh as a scene object, where the torso stands
    let torso = &gm.links[gm.link_index("torso_lift_link").unwrap()];
    assert_eq!(torso.count, 1);
    let pose = gd.placements[torso.first];
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(pose.rotation));
    let t = pose.translation;
    let yaml = format!(
        "world:\n  collision_objects:\n    - header:\n        frame_id: world\n      \
         id: torso_copy\n      meshes:\n        - resource: \
         package://fetch_description/meshes/torso_lift_link_collision.STL\n      \
         mesh_poses:\n        - position: [{}, {}, {}]\n          \
         orientation: [{}, {}, {}, {}]\n",
        t.x, t.y, t.z, q.i, q.j, q.k, q.w
    );
    let dir = std::env::temp_dir().join(format!("moma_collision_exact_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("torso_copy.yaml");
    std::fs::write(&file, yaml).unwrap();
    let scene = read_scene(
        &file,
        &SceneOptions {
            world_frames: vec!["world".into()],
            package_dirs: vec![data_dir().join("robots/fetch")],
        },
    )
    .unwrap();
    let shoulder = gm.link_index("shoulder_lift_link").unwrap();
    let mut sd = SceneData::new(&gm, &scene);
    compute_scene_distances(&gm, &mut gd, &scene, &mut sd);
    let hull = sd.results[shoulder].distance;
    assert!(
        (hull - want_convex).abs() <= 1e-6,
        "{hull} vs coal {want_convex}"
    );
    compute_exact_scene_distances(
        &gm,
        &ex,
        &mut gd,
        &scene,
        &ExactScene::new(&scene).unwrap(),
        &mut sd,
    );
    let exact = sd.results[shoulder];
    assert!(
        (exact.distance - want_mesh).abs() <= 1e-6,
        "{} vs coal {want_mesh}",
        exact.distance
    );
    // the torso itself touches its copy
    assert_eq!(
        sd.results[gm.link_index("torso_lift_link").unwrap()].distance,
        0.0
    );
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_link_mesh_inside_a_solid_box_is_at_zero() {
    use moma::collision::{Convex, Scene, SceneObject};
    let (model, gm, ex) = fetch();
    let mut data = Data::new(&model);
    let mut gd = GeometryData::new(&gm);
    forward_kinematics(&model, &mut data, &DVector::zeros(model.nq));
    update_geometry_placements(&gm, &data, &mut gd);
    // a box around the gripper's bounding ball: no triangle reaches its faces
    let gripper = &gm.links[gm.link_index("gripper_link").unwrap()];
    let o = &gm.objects[gripper.first];
    let centre = gd.placements[gripper.first].act_point(&o.bounding_centre);
    let half = nalgebra::Vector3::repeat(o.bounding_radius + 0.01);
    let scene = Scene {
        objects: vec![
            SceneObject::new(
                "case",
                vec![(
                    moma::spatial::SE3::from_translation(centre),
                    Convex::Box { half },
                )],
            )
            .unwrap(),
        ],
    };
    let mut sd = SceneData::new(&gm, &scene);
    let g = gm.link_index("gripper_link").unwrap();
    compute_scene_distances(&gm, &mut gd, &scene, &mut sd);
    // the hull is inside by at least the 1 cm margin
    assert!(sd.results[g].distance < -0.01, "{}", sd.results[g].distance);
    compute_exact_scene_distances(
        &gm,
        &ex,
        &mut gd,
        &scene,
        &ExactScene::new(&scene).unwrap(),
        &mut sd,
    );
    assert_eq!(sd.results[g].distance, 0.0);
}

/// Panda (example-robot-data's URDF: 9 STL meshes, four boxes per finger) with its SRDF,
/// and its exact shapes.
fn panda() -> (Model, GeometryModel, ExactGeometry) {
    let (model, gm) = panda_geometry();
    let ex = ExactGeometry::new(&gm).unwrap();
    (model, gm, ex)
}

/// One pair against coal: `0` where coal's meshes touch, else within 1e-6 m, never below
/// the hulls', the witnesses the distance apart. Returns the error (0 for a touching pair).
fn check_mesh_pair(
    got: &moma::collision::PairDistance,
    want: f64,
    convex: f64,
    label: &str,
) -> f64 {
    assert!(got.distance >= convex - 1e-9, "{label}: below the hulls");
    assert!(
        ((got.witness_b - got.witness_a).norm() - got.distance).abs() < 1e-9,
        "{label}"
    );
    if want == 0.0 {
        assert_eq!(got.distance, 0.0, "{label}: coal's meshes touch");
        0.0
    } else {
        let err = (got.distance - want).abs();
        assert!(
            err <= 1e-6,
            "{label}: exact {} vs coal {want}",
            got.distance
        );
        err
    }
}

/// The verdicts compared: (in collision, free).
fn verdict(got_min: f64, want_min: f64, counts: &mut [usize; 2], label: &str) {
    assert!(
        (got_min - want_min).abs() <= 1e-6,
        "{label}: min {got_min} vs coal {want_min}"
    );
    if want_min == 0.0 || want_min > 1e-6 {
        assert_eq!(got_min <= 0.0, want_min == 0.0, "{label}: in collision");
        counts[usize::from(want_min > 0.0)] += 1;
    }
}

#[test]
fn panda_mesh_distances_match_coal() {
    let (model, gm, ex) = panda();
    let r = reference("panda_self.json");
    let pairs = pair_indices(&gm, &r);
    let mut data = Data::new(&model);
    let mut gd = GeometryData::new(&gm);
    let (mut worst, mut checked, mut counts) = (0.0_f64, 0, [0usize; 2]);
    for s in r["states"].as_array().unwrap() {
        forward_kinematics(&model, &mut data, &q_of(&model, s));
        update_geometry_placements(&gm, &data, &mut gd);
        // Every pair, enabled or not.
        compute_exact_distances(&gm, &ex, &mut gd, PairSelection::All);
        for (k, want) in s["distance_mesh"].as_array().unwrap().iter().enumerate() {
            let label = format!("{} {}", s["label"], r["pairs"][k]);
            let convex = s["distance_convex"][k].as_f64().unwrap();
            let err = check_mesh_pair(
                &gd.results[pairs[k]],
                want.as_f64().unwrap(),
                convex,
                &label,
            );
            worst = worst.max(err);
            checked += 1;
        }
        let min = compute_exact_distances(&gm, &ex, &mut gd, PairSelection::Enabled);
        let want_min = s["min_enabled_mesh"].as_f64().unwrap();
        assert_eq!(s["in_collision_enabled_mesh"], want_min == 0.0);
        verdict(min, want_min, &mut counts, &s["label"].to_string());
    }
    eprintln!("{checked} pairs, worst error {worst:e} m; verdicts in collision / free: {counts:?}");
    assert!(
        checked >= 70 * 55 && counts[0] >= 5 && counts[1] >= 5,
        "{checked} {counts:?}"
    );
}

#[test]
fn panda_scene_mesh_distances_match_coal() {
    let (model, gm, ex) = panda();
    let r = reference("panda_scene.json");
    let sc = &r["scenes"]["table"];
    let scene = read_scene(
        &data_dir().join(sc["scene_yaml"].as_str().unwrap()),
        &SceneOptions {
            world_frames: vec!["panda_link0".into()],
            package_dirs: vec![],
        },
    )
    .unwrap();
    let exs = ExactScene::new(&scene).unwrap();
    let mut sd = SceneData::new(&gm, &scene);
    let mut data = Data::new(&model);
    let mut gd = GeometryData::new(&gm);
    let pairs = sc["pairs"].as_array().unwrap();
    assert_eq!(pairs.len(), gm.links.len() * scene.objects.len());
    let (mut worst, mut checked, mut counts) = (0.0_f64, 0, [0usize; 2]);
    for s in r["states"].as_array().unwrap() {
        forward_kinematics(&model, &mut data, &q_of(&model, s));
        update_geometry_placements(&gm, &data, &mut gd);
        let min = compute_exact_scene_distances(&gm, &ex, &mut gd, &scene, &exs, &mut sd);
        for (k, p) in pairs.iter().enumerate() {
            let l = gm.link_index(p[0].as_str().unwrap()).unwrap();
            let o = scene.objects.iter().position(|o| o.id == p[1]).unwrap();
            let got = &sd.results[l * scene.objects.len() + o];
            let want = s["distance_mesh"][k].as_f64().unwrap();
            let convex = s["distance_convex"][k].as_f64().unwrap();
            let err = check_mesh_pair(got, want, convex, &format!("{} {p}", s["label"]));
            worst = worst.max(err);
            checked += 1;
        }
        let want_min = s["min_distance_mesh"].as_f64().unwrap();
        assert_eq!(s["in_collision_mesh"], want_min == 0.0);
        verdict(min, want_min, &mut counts, &s["label"].to_string());
    }
    eprintln!("{checked} pairs, worst error {worst:e} m; verdicts in collision / free: {counts:?}");
    assert!(
        checked >= 38 * 33 && counts[0] >= 5 && counts[1] >= 5,
        "{checked} {counts:?}"
    );
}

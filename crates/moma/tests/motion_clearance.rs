//! The planning group's state check (`ClearanceChecker::is_valid`, the probe of the
//! search) against its exact report (`distance_report`: every checked pair's signed
//! distance computed in full) on Fetch in MotionBenchMaker's cage and bookshelf scenes:
//! on states drawn in the group's box and along the segments from each query's start to
//! its goal (which end between the cage's bars and the shelf boards), a state passes
//! exactly when its closest pair is farther apart than the margin.

use moma::collision::{GeometryModel, Scene};
use moma::motion::{ClearanceChecker, JointGroup};
use moma::multibody::{Model, RootJoint};
use moma::planning::StateValidity;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

mod fetch_common;
use fetch_common::{FetchQueries, fetch_geometry, numbers};

/// Fetch on a fixed root with its geometry, the shipped query folder, and its group.
fn fetch() -> (Model, GeometryModel, FetchQueries, JointGroup) {
    let (model, gm) = fetch_geometry(RootJoint::Fixed);
    let queries = FetchQueries::load();
    let group = queries.group(&model);
    (model, gm, queries, group)
}

/// A query's scene and start state, and the group states the tests check: `line + 1`
/// states evenly along the segment from the query's start to its goal, then 1000 drawn
/// uniformly in the group's box.
fn query_states(
    queries: &FetchQueries,
    group: &JointGroup,
    name: &str,
    line: u32,
    rng: &mut ChaCha8Rng,
) -> (Scene, Vec<f64>, Vec<Vec<f64>>) {
    let dim = group.dim();
    let query = queries.query(name);
    let start = numbers(&query["start"]);
    let goal = numbers(&query["goal_state"]);
    let (mut xa, mut xb) = (vec![0.0; dim], vec![0.0; dim]);
    group.extract(&start, &mut xa);
    group.extract(&goal, &mut xb);
    let mut states: Vec<Vec<f64>> = (0..=line)
        .map(|k| {
            let t = f64::from(k) / f64::from(line);
            xa.iter().zip(&xb).map(|(a, b)| a + t * (b - a)).collect()
        })
        .collect();
    for _ in 0..1000 {
        let x: Vec<f64> = (0..dim)
            .map(|i| rng.random_range(group.lower[i]..=group.upper[i]))
            .collect();
        states.push(x);
    }
    (queries.scene(query), start, states)
}

/// Asserts that the state check passes `x` exactly when its exact report's closest pair is
/// farther apart than `margin`, and returns the verdict.
fn passes_exactly_when_clear(
    checker: &mut ClearanceChecker,
    name: &str,
    x: &[f64],
    margin: f64,
) -> bool {
    let valid = checker.is_valid(x);
    judged(valid, checker, name, x, margin)
}

/// `valid` (a check's verdict on `x`), asserted to be whether `judge`'s exact report finds
/// the closest pair farther apart than the margin.
fn judged(valid: bool, judge: &mut ClearanceChecker, name: &str, x: &[f64], margin: f64) -> bool {
    let closest = judge.distance_report(x).unwrap();
    assert_eq!(
        valid,
        closest.distance > margin,
        "{name}: state {x:?}: is_valid {valid}, closest pair {closest:?}"
    );
    valid
}

/// Asserts that every state at 1/40 steps of the passed segment from `x` to `y` keeps half
/// the margin by `judge`'s exact report (the continuous check's guarantee).
fn assert_segment_keeps_half_the_margin(
    judge: &mut ClearanceChecker,
    name: &str,
    x: &[f64],
    y: &[f64],
    margin: f64,
) {
    for k in 0..=40 {
        let t = f64::from(k) / 40.0;
        let z: Vec<f64> = x.iter().zip(y).map(|(a, b)| a + t * (b - a)).collect();
        let d = judge.distance_report(&z).unwrap().distance;
        assert!(
            d > 0.5 * margin - 1e-9,
            "{name}: {z:?} at {d} m on a passed segment"
        );
    }
}

#[test]
fn the_state_check_passes_exactly_the_states_clear_of_the_margin() {
    let (model, gm, queries, group) = fetch();
    let dim = group.dim();
    let margin = 2e-3;
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let (mut passed, mut failed) = (0, 0);
    for name in ["cage-Front-Cube1-0", "bookshelf_small-Front-Can1-1"] {
        let (scene, start, states) = query_states(&queries, &group, name, 200, &mut rng);
        let mut checker =
            ClearanceChecker::new(&model, &gm, &scene, &group, &start, margin, &vec![1.0; dim])
                .unwrap();
        for x in &states {
            if passes_exactly_when_clear(&mut checker, name, x, margin) {
                passed += 1;
            } else {
                failed += 1;
            }
        }
    }
    // Both answers occur often, so the agreement is tested both ways.
    assert!(
        passed > 200 && failed > 200,
        "{passed} passed, {failed} failed"
    );
}

/// The closed-form bounds the check tries before GJK (ball covers against the other side's
/// balls, planes or primitive) never pass a pair GJK finds too close: at a margin of 1 cm
/// (five times the planner's, so more pairs fall between the bounds and the exact
/// distance) a state passes exactly when its closest pair is farther than the margin, and
/// every random segment from a passing state that passes keeps half the margin at each of
/// 41 states along it (the continuous check's guarantee).
#[test]
fn the_bounds_before_gjk_never_pass_a_state_too_close() {
    let (model, gm, queries, group) = fetch();
    let dim = group.dim();
    let space =
        moma::planning::JointSpace::new(group.lower.clone(), group.upper.clone(), 0.05).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(21);
    let (mut passed, mut failed, mut segments) = (0, 0, 0);
    let margin = 0.01;
    for name in ["cage-Front-Cube1-0", "bookshelf_small-Front-Can1-1"] {
        let (scene, start, states) = query_states(&queries, &group, name, 100, &mut rng);
        let mut checker =
            ClearanceChecker::new(&model, &gm, &scene, &group, &start, margin, &vec![1.0; dim])
                .unwrap();
        for x in &states {
            if passes_exactly_when_clear(&mut checker, name, x, margin) {
                passed += 1;
            } else {
                failed += 1;
                continue;
            }
            // A segment from the clear state a random way, up to 0.3 rad per joint.
            let y: Vec<f64> = x
                .iter()
                .enumerate()
                .map(|(i, v)| {
                    (v + rng.random_range(-0.3..0.3)).clamp(group.lower[i], group.upper[i])
                })
                .collect();
            let mut scratch = Vec::new();
            if !checker.segment_valid(&space, x, &y, &mut scratch, &mut 0) {
                continue;
            }
            segments += 1;
            assert_segment_keeps_half_the_margin(&mut checker, name, x, &y, margin);
        }
    }
    assert!(
        passed > 50 && failed > 50 && segments > 10,
        "{passed} passed, {failed} failed, {segments} segments passed"
    );
}

/// A concave mesh scene given as its triangles (`--mesh exact`): MotionBenchMaker's table
/// with the two plates whose hull holds the tucked arm, and Fetch's base mesh (4720
/// triangles) standing on the table where the arm reaches. The state check prunes the
/// triangles by the scene object's tree; on 600 random states it passes a state exactly
/// when the full report over every triangle finds its closest pair farther than the
/// margin, and never passes one that the exact mesh distances
/// (`compute_exact_scene_distances`: the link meshes against the scene meshes and
/// primitives) put within the margin of the scene.
#[test]
fn the_state_check_never_passes_a_state_within_the_margin_of_a_concave_mesh_scene() {
    use moma::collision::{
        ExactGeometry, ExactScene, GeometryData, SceneData, SceneOptions,
        compute_exact_scene_distances, read_scene, update_geometry_placements,
    };
    use moma::kinematics::forward_kinematics;
    use moma::multibody::Data;
    let (model, gm, queries, group) = fetch();
    let dim = group.dim();
    let start = numbers(&queries.query("cage-Front-Cube1-0")["start"]);
    let fetch_dir = fetch_common::fetch_dir();
    let options = SceneOptions {
        world_frames: vec!["base_link".into()],
        package_dirs: vec![fetch_dir.clone()],
    };
    let plates = fetch_common::data_dir().join("scenes/motion_bench_maker/concave_plates");
    let mut scene = read_scene(&plates.join("scene.yaml"), &options).unwrap();
    let dir = std::env::temp_dir().join(format!("moma_motion_clearance_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("base_on_table.yaml");
    std::fs::write(
        &file,
        "world:\n  collision_objects:\n    - header:\n        frame_id: base_link\n      \
         id: base_copy\n      meshes:\n        - resource: \
         package://fetch_description/meshes/base_link_collision.STL\n      \
         mesh_poses:\n        - position: [0.75, 0.0, 0.72]\n          \
         orientation: [0, 0, 0, 1]\n",
    )
    .unwrap();
    scene
        .objects
        .extend(read_scene(&file, &options).unwrap().objects);
    std::fs::remove_dir_all(&dir).ok();
    let meshes: Vec<usize> = scene
        .objects
        .iter()
        .enumerate()
        .filter(|(_, o)| o.shapes.iter().any(|s| s.mesh.is_some()))
        .map(|(i, _)| i)
        .collect();
    assert_eq!(meshes.len(), 2);
    let triangles = scene.with_mesh_triangles().unwrap();
    let margin = 0.01;
    let mut checker = ClearanceChecker::new(
        &model,
        &gm,
        &triangles,
        &group,
        &start,
        margin,
        &vec![1.0; dim],
    )
    .unwrap();
    let ex = ExactGeometry::new(&gm).unwrap();
    let exs = ExactScene::new(&scene).unwrap();
    let mut sd = SceneData::new(&gm, &scene);
    let mut data = Data::new(&model);
    let mut gd = GeometryData::new(&gm);
    let mut q = start.clone();
    let mut rng = ChaCha8Rng::seed_from_u64(23);
    let (mut passed, mut near_mesh) = (0, 0);
    for _ in 0..600 {
        let x: Vec<f64> = (0..dim)
            .map(|i| rng.random_range(group.lower[i]..=group.upper[i]))
            .collect();
        let valid = passes_exactly_when_clear(&mut checker, "concave meshes", &x, margin);
        group.embed(&x, &mut q);
        forward_kinematics(&model, &mut data, &nalgebra::DVector::from_column_slice(&q));
        update_geometry_placements(&gm, &data, &mut gd);
        let exact = compute_exact_scene_distances(&gm, &ex, &mut gd, &scene, &exs, &mut sd);
        assert!(
            !(valid && exact <= margin),
            "state {x:?} passes, exact scene distance {exact}"
        );
        passed += usize::from(valid);
        let no = scene.objects.len();
        near_mesh += usize::from((0..gm.links.len()).any(|l| {
            meshes
                .iter()
                .any(|&o| sd.results[l * no + o].distance <= margin)
        }));
    }
    // Both answers occur, and the meshes decide many states.
    assert!(
        passed >= 30 && near_mesh >= 30,
        "{passed} passed, {near_mesh} within the margin of a mesh"
    );
}

/// The shortcuts that depend on what the check saw before (the plane each pair's last GJK
/// run ended with, tried before GJK; the clusters a segment's first state leaves live) never
/// pass a state or a segment too close. One checker checks a random walk of small steps
/// (so the planes stay tight and are used) and segments between its states, with no exact
/// report in between; a second checker's exact report judges it: a state passes exactly
/// when its closest pair is farther than the margin, and every state at 1/40 steps of a
/// passed segment keeps half the margin.
#[test]
fn the_plane_and_live_cluster_shortcuts_never_pass_a_state_too_close() {
    let (model, gm, queries, group) = fetch();
    // From every 20th state, a walk of 20 steps.
    let [passed, failed, segments, planes] =
        judged_walks(&model, &gm, &queries, &group, 33, 20, 20);
    assert!(
        passed > 100 && failed > 50 && segments > 100 && planes > 1000,
        "{passed} passed, {failed} failed, {segments} segments passed, {planes} pairs cleared \
         by a plane"
    );
}

/// The cluster pass (every link ball against every other link's ball and every scene
/// object's box at once) and the block bound it shares with its cluster (two links of one
/// ball each) never pass a state too close, nor fail one that is clear: with the gripper
/// and the right finger swapped for their mesh surfaces (links of many patches, in ball
/// groups, beside links of one hull), random walks in the cage and bookshelf scenes at a
/// 1 cm margin pass a state exactly when the exact report finds its closest pair farther
/// than the margin, and every passed segment keeps half the margin along it.
#[test]
fn the_cluster_pass_never_passes_a_state_too_close_with_links_of_many_patches() {
    let (model, gm, queries, group) = fetch();
    let source = moma::motion::MeshSource {
        urdf: fetch_common::fetch_urdf(),
        package_dirs: vec![fetch_common::fetch_dir()],
    };
    let mut patched = gm;
    for link in ["gripper_link", "r_gripper_finger_link"] {
        patched = moma::motion::with_mesh_surface(
            &model,
            &patched,
            &source,
            link,
            &moma::motion::Patching::uniform(moma::motion::PATCH_TRIANGLES),
        )
        .unwrap();
    }
    // From every 40th state, a walk of 15 steps.
    let [passed, failed, segments, _] =
        judged_walks(&model, &patched, &queries, &group, 41, 40, 15);
    assert!(
        passed > 50 && failed > 50 && segments > 50,
        "{passed} passed, {failed} failed, {segments} segments passed"
    );
}

/// Random walks in the cage and a bookshelf query at a 1 cm margin (from every `stride`-th
/// of `query_states`' states, `steps` steps of up to 0.05 rad per joint, drawn from
/// `seed`): each state the check passes or fails is judged by a second checker's exact
/// report ([`judged`]) and each segment it passes is held to half the margin
/// ([`assert_segment_keeps_half_the_margin`]). Returns the states passed and failed, the
/// segments passed and the robot pairs the check cleared by a plane.
fn judged_walks(
    model: &Model,
    gm: &GeometryModel,
    queries: &FetchQueries,
    group: &JointGroup,
    seed: u64,
    stride: usize,
    steps: usize,
) -> [u64; 4] {
    let dim = group.dim();
    let space =
        moma::planning::JointSpace::new(group.lower.clone(), group.upper.clone(), 0.05).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut passed, mut failed, mut segments, mut planes) = (0, 0, 0, 0);
    let margin = 0.01;
    for name in ["cage-Front-Cube1-0", "bookshelf_small-Front-Can1-1"] {
        let (scene, start, states) = query_states(queries, group, name, 100, &mut rng);
        let weights = vec![1.0; dim];
        let mut check =
            ClearanceChecker::new(model, gm, &scene, group, &start, margin, &weights).unwrap();
        let mut judge =
            ClearanceChecker::new(model, gm, &scene, group, &start, margin, &weights).unwrap();
        for origin in states.iter().step_by(stride) {
            let mut x = origin.clone();
            for _ in 0..steps {
                let y: Vec<f64> = x
                    .iter()
                    .enumerate()
                    .map(|(i, v)| {
                        (v + rng.random_range(-0.05..0.05)).clamp(group.lower[i], group.upper[i])
                    })
                    .collect();
                let valid = judged(check.is_valid(&y), &mut judge, name, &y, margin);
                if valid {
                    passed += 1;
                } else {
                    failed += 1;
                }
                let mut scratch = Vec::new();
                if valid && check.segment_valid(&space, &x, &y, &mut scratch, &mut 0) {
                    segments += 1;
                    assert_segment_keeps_half_the_margin(&mut judge, name, &x, &y, margin);
                }
                x = y;
            }
        }
        planes += check.planes_cleared;
    }
    [passed, failed, segments, planes]
}

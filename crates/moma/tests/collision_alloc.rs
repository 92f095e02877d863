//! The geometry queries allocate nothing once their workspaces have seen a round of
//! states: forward kinematics, placements, all self-distances, the in-collision check,
//! the scene distances, the scene's in-collision check, the distance derivatives (of
//! every enabled pair and of the minimum) and the exact triangle-mesh distances (self and
//! scene) on 40 random Fetch states against MotionBenchMaker's cage.

mod counting_alloc;
use counting_alloc::allocations;
use moma::collision::{
    ExactGeometry, ExactScene, GeometryData, GeometryModel, GeometryOptions, PairSelection,
    SceneData, SceneOptions, compute_collision, compute_distances, compute_exact_distances,
    compute_exact_scene_distances, compute_scene_distances, distance_derivative,
    min_distance_gradient, read_scene, scene_collision, update_geometry_placements,
};
use moma::kinematics::{compute_joint_jacobians, forward_kinematics, random_configuration};
use moma::multibody::{Data, RootJoint};
use nalgebra::DVector;
use rand::SeedableRng;
use std::path::Path;

#[test]
fn queries_do_not_allocate_after_warm_up() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/robots/fetch");
    let urdf = dir.join("fetch_description/robots/fetch.urdf");
    let model = moma::io::urdf::model_from_urdf_file(&urdf, RootJoint::Fixed).unwrap();
    let opts = GeometryOptions {
        package_dirs: vec![dir.clone()],
        srdf: Some(dir.join("fetch.srdf")),
    };
    let gm = GeometryModel::from_urdf(&model, &urdf, &opts).unwrap();
    let mut data = Data::new(&model);
    let mut gd = GeometryData::new(&gm);
    let scene = read_scene(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/scenes/motion_bench_maker/configs/scenes/cage/scene_cage.yaml"),
        &SceneOptions {
            world_frames: vec!["base_link".into()],
            package_dirs: vec![],
        },
    )
    .unwrap();
    let mut sd = SceneData::new(&gm, &scene);
    let (ex, exs) = (
        ExactGeometry::new(&gm).unwrap(),
        ExactScene::new(&scene).unwrap(),
    );
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let states: Vec<_> = (0..40)
        .map(|_| random_configuration(&model, &mut rng))
        .collect();
    let mut derivative = DVector::zeros(model.nv);
    // What the queries found, so that the test sees they ran: pairs in collision with the
    // scene, minima whose derivative was taken, non-zero derivatives, finite exact minima
    // (self and scene).
    let mut found = [0usize; 5];
    let mut run = |data: &mut Data, gd: &mut GeometryData, sd: &mut SceneData| {
        for q in &states {
            forward_kinematics(&model, data, q);
            update_geometry_placements(&gm, data, gd);
            compute_distances(&gm, gd, PairSelection::All);
            compute_collision(&gm, gd);
            compute_scene_distances(&gm, gd, &scene, sd);
            found[0] += usize::from(scene_collision(&gm, gd, &scene, sd).is_some());
            compute_joint_jacobians(&model, data, q);
            for p in (0..gm.pairs.len()).filter(|&p| gm.enabled[p]) {
                distance_derivative(&model, data, &gm, gd, p, &mut derivative);
                found[2] += usize::from(derivative.amax() > 0.0);
            }
            found[1] += usize::from(
                min_distance_gradient(&model, data, &gm, gd, &scene, sd, &mut derivative).is_some(),
            );
            let self_min = compute_exact_distances(&gm, &ex, gd, PairSelection::Enabled);
            let scene_min = compute_exact_scene_distances(&gm, &ex, gd, &scene, &exs, sd);
            found[3] += usize::from(self_min.is_finite());
            found[4] += usize::from(scene_min.is_finite());
        }
    };
    run(&mut data, &mut gd, &mut sd);
    let (count, ()) = allocations(|| {
        run(&mut data, &mut gd, &mut sd);
    });
    assert_eq!(count, 0, "the geometry queries allocated");
    assert!(
        found[0] > 0
            && found[1] == 2 * states.len()
            && found[2] > 0
            && found[3] == 2 * states.len()
            && found[4] == 2 * states.len(),
        "{found:?}"
    );
}

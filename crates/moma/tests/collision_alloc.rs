//! The geometry queries allocate nothing once their workspaces have seen a round of
//! states: forward kinematics, placements, all self-distances, the in-collision check and
//! the scene distances on 40 random Fetch states against MotionBenchMaker's cage.

mod counting_alloc;
use counting_alloc::allocations;
use moma::collision::{
    GeometryData, GeometryModel, GeometryOptions, PairSelection, SceneData, SceneOptions,
    compute_collision, compute_distances, compute_scene_distances, read_scene,
    update_geometry_placements,
};
use moma::kinematics::{forward_kinematics, random_configuration};
use moma::multibody::{Data, RootJoint};
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
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let states: Vec<_> = (0..40)
        .map(|_| random_configuration(&model, &mut rng))
        .collect();
    let run = |data: &mut Data, gd: &mut GeometryData, sd: &mut SceneData| {
        for q in &states {
            forward_kinematics(&model, data, q);
            update_geometry_placements(&gm, data, gd);
            compute_distances(&gm, gd, PairSelection::All);
            compute_collision(&gm, gd);
            compute_scene_distances(&gm, gd, &scene, sd);
        }
    };
    run(&mut data, &mut gd, &mut sd);
    let (count, ()) = allocations(|| {
        run(&mut data, &mut gd, &mut sd);
    });
    assert_eq!(count, 0, "the geometry queries allocated");
}

//! Collision-geometry bench on Fetch (fixed base, 21 links with STL collision meshes used
//! as convex hulls, the SRDF's 76 enabled pairs): one full self-distance evaluation, one
//! in-collision check with early exit, the distances of all 21 links to MotionBenchMaker's
//! table scene (the YAML's 12 objects) and its in-collision check, the same scene
//! voxelised as coal's OcTree row (99,826 cells; distances and in-collision), and the
//! distances to a scene of ten boxes and to a slab of 100,000 voxels. Each iteration runs forward
//! kinematics, the geometry placements and the query on the next of the 100 states of
//! `benches/data/fetch_states_pinocchio.txt` — the states `bench/pinocchio/run.sh
//! collision` times with Pinocchio + coal — with the warm starts of the previous state.
//! Before timing, the per-state in-collision verdicts are printed as `# verdicts QUERY
//! 0101...` lines, to compare with coal's.
//!
//! Run: `cargo bench -p moma --bench collision --locked -- --warm-up-time 1 --measurement-time 3`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use moma::collision::Convex;
use moma::collision::{
    ExactGeometry, GeometryData, GeometryModel, GeometryOptions, PairSelection, Scene, SceneData,
    SceneObject, SceneOptions, compute_collision, compute_distances, compute_exact_distances,
    compute_scene_distances, point_cloud_object, read_scene, scene_collision,
    update_geometry_placements, voxel_object,
};
use moma::io::pinocchio_layout::PinocchioLayout;
use moma::kinematics::forward_kinematics;
use moma::multibody::{Data, Model, RootJoint};
use moma::planning::grid3::Grid3;
use moma::spatial::SE3;
use nalgebra::{DVector, Vector3};
use rand::{Rng, SeedableRng};

/// Fetch on a fixed root with its collision geometry and SRDF, as shipped in the tests' data.
fn fetch() -> (Model, GeometryModel) {
    let dir = format!("{}/tests/data/robots/fetch", env!("CARGO_MANIFEST_DIR"));
    let urdf = format!("{dir}/fetch_description/robots/fetch.urdf");
    let model = moma::io::urdf::model_from_urdf_file(&urdf, RootJoint::Fixed).expect("model");
    let opts = GeometryOptions {
        package_dirs: vec![dir.clone().into()],
        srdf: Some(format!("{dir}/fetch.srdf").into()),
    };
    let gm = GeometryModel::from_urdf(&model, urdf.as_ref(), &opts).expect("geometry");
    (model, gm)
}

fn bench(c: &mut Criterion) {
    let (model, gm) = fetch();
    let mut data = Data::new(&model);
    let mut gd = GeometryData::new(&gm);
    let layout = PinocchioLayout::new(&model);
    let text = std::fs::read_to_string(format!(
        "{}/benches/data/fetch_states_pinocchio.txt",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("states file");
    let states: Vec<DVector<f64>> = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let pin: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            let mut q = DVector::zeros(model.nq);
            layout.q_from_pinocchio(&pin, q.as_mut_slice()).unwrap();
            q
        })
        .collect();
    assert_eq!(states.len(), 100);
    let table = read_scene(
        format!(
            "{}/tests/data/scenes/motion_bench_maker/configs/scenes/table/scene_table.yaml",
            env!("CARGO_MANIFEST_DIR")
        )
        .as_ref(),
        &SceneOptions {
            world_frames: vec!["base_link".into()],
            package_dirs: Vec::new(),
        },
    )
    .expect("scene");
    let mut table_sd = SceneData::new(&gm, &table);
    let verdicts = |data: &mut Data,
                    gd: &mut GeometryData,
                    name: &str,
                    f: &mut dyn FnMut(&mut GeometryData) -> bool| {
        let v: String = states
            .iter()
            .map(|q| {
                forward_kinematics(&model, data, q);
                update_geometry_placements(&gm, data, gd);
                if f(gd) { '1' } else { '0' }
            })
            .collect();
        eprintln!("# verdicts {name} {v}");
    };
    verdicts(&mut data, &mut gd, "self_collisions_first", &mut |gd| {
        compute_collision(&gm, gd).is_some()
    });
    verdicts(&mut data, &mut gd, "scene_collisions_first", &mut |gd| {
        scene_collision(&gm, gd, &table, &mut table_sd).is_some()
    });
    // The mean minimum distances over the states, to compare with coal's '# check' lines.
    let (mut self_sum, mut scene_sum) = (0.0, 0.0);
    for q in &states {
        forward_kinematics(&model, &mut data, q);
        update_geometry_placements(&gm, &data, &mut gd);
        self_sum += compute_distances(&gm, &mut gd, PairSelection::Enabled);
        scene_sum += compute_scene_distances(&gm, &mut gd, &table, &mut table_sd);
    }
    let n = states.len() as f64;
    eprintln!(
        "# check mean min self distance over the states {:.9}",
        self_sum / n
    );
    eprintln!(
        "# check fetch+table mean min scene distance over the states {:.9}",
        scene_sum / n
    );
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let mut k = 0;
    c.bench_function("fetch/self_distance_enabled_hulls", |b| {
        b.iter(|| {
            k = (k + 1) % states.len();
            forward_kinematics(&model, &mut data, &states[k]);
            update_geometry_placements(&gm, &data, &mut gd);
            black_box(compute_distances(&gm, &mut gd, PairSelection::Enabled))
        })
    });
    // The exact triangle meshes (`--mesh exact`): the same 76 pairs, mesh against mesh.
    let exact = ExactGeometry::new(&gm).expect("exact meshes");
    let exact_sum: f64 = states
        .iter()
        .map(|q| {
            forward_kinematics(&model, &mut data, q);
            update_geometry_placements(&gm, &data, &mut gd);
            compute_exact_distances(&gm, &exact, &mut gd, PairSelection::Enabled)
        })
        .sum();
    eprintln!(
        "# check mean min enabled mesh distance over the states {:.9}",
        exact_sum / n
    );
    c.bench_function("fetch/self_distance_enabled_exact", |b| {
        b.iter(|| {
            k = (k + 1) % states.len();
            forward_kinematics(&model, &mut data, &states[k]);
            update_geometry_placements(&gm, &data, &mut gd);
            black_box(compute_exact_distances(
                &gm,
                &exact,
                &mut gd,
                PairSelection::Enabled,
            ))
        })
    });
    c.bench_function("fetch/in_collision_early_exit", |b| {
        b.iter(|| {
            k = (k + 1) % states.len();
            forward_kinematics(&model, &mut data, &states[k]);
            update_geometry_placements(&gm, &data, &mut gd);
            black_box(compute_collision(&gm, &mut gd))
        })
    });
    c.bench_function("fetch/scene_distance_mbm_table", |b| {
        b.iter(|| {
            k = (k + 1) % states.len();
            forward_kinematics(&model, &mut data, &states[k]);
            update_geometry_placements(&gm, &data, &mut gd);
            black_box(compute_scene_distances(&gm, &mut gd, &table, &mut table_sd))
        })
    });
    c.bench_function("fetch/scene_in_collision_mbm_table", |b| {
        b.iter(|| {
            k = (k + 1) % states.len();
            forward_kinematics(&model, &mut data, &states[k]);
            update_geometry_placements(&gm, &data, &mut gd);
            black_box(scene_collision(&gm, &gd, &table, &mut table_sd))
        })
    });
    // Ten boxes around the robot (a table and shelves' worth) ...
    let boxes = Scene {
        objects: (0..10)
            .map(|i| {
                let c = Vector3::new(
                    0.6 + 0.1 * i as f64,
                    rng.random_range(-0.8..0.8),
                    rng.random_range(0.3..1.4),
                );
                SceneObject::new(
                    format!("box{i}"),
                    vec![(
                        SE3::from_translation(c),
                        Convex::Box {
                            half: Vector3::new(0.1, 0.2, 0.05),
                        },
                    )],
                )
                .unwrap()
            })
            .collect(),
    };
    // ... and a 4 m × 2 m × 10 cm slab of 2 cm voxels (200 × 100 × 5 = 100,000) at table
    // height in front of the robot.
    let mut grid = Grid3::new(200, 100, 5).unwrap();
    for z in 0..5 {
        for y in 0..100 {
            for x in 0..200 {
                grid.set_blocked(x, y, z, true);
            }
        }
    }
    let voxels = Scene {
        objects: vec![voxel_object("slab", &grid, 0.02, Vector3::new(0.5, -1.0, 0.7)).unwrap()],
    };
    assert_eq!(voxels.objects[0].shapes.len(), 100_000);
    // The table scene voxelised as coal_fetch_bench.cpp does for its OcTree row: the
    // cells of edge VOXEL_EDGE (the size its bisection picks for ~100,000 cells) whose
    // centre lies inside a primitive.
    let table_voxels = Scene {
        objects: vec![
            point_cloud_object(
                "table_voxels",
                &voxel_centres(&table, VOXEL_EDGE),
                VOXEL_EDGE,
            )
            .unwrap(),
        ],
    };
    eprintln!(
        "# fetch+table_voxels: {} voxels of {VOXEL_EDGE} m",
        table_voxels.objects[0].shapes.len()
    );
    {
        let mut sd = SceneData::new(&gm, &table_voxels);
        verdicts(&mut data, &mut gd, "voxel_collisions_first", &mut |gd| {
            scene_collision(&gm, gd, &table_voxels, &mut sd).is_some()
        });
        c.bench_function("fetch/scene_in_collision_mbm_table_voxels", |b| {
            b.iter(|| {
                k = (k + 1) % states.len();
                forward_kinematics(&model, &mut data, &states[k]);
                update_geometry_placements(&gm, &data, &mut gd);
                black_box(scene_collision(&gm, &gd, &table_voxels, &mut sd))
            })
        });
    }
    for (name, scene) in [
        ("10_boxes", &boxes),
        ("100000_voxels", &voxels),
        ("mbm_table_voxels", &table_voxels),
    ] {
        let mut sd = SceneData::new(&gm, scene);
        c.bench_function(&format!("fetch/scene_distance_{name}"), |b| {
            b.iter(|| {
                k = (k + 1) % states.len();
                forward_kinematics(&model, &mut data, &states[k]);
                update_geometry_placements(&gm, &data, &mut gd);
                black_box(compute_scene_distances(&gm, &mut gd, scene, &mut sd))
            })
        });
    }
}

/// coal_fetch_bench.cpp's voxel edge for the table scene (its '# fetch+table_voxels' line).
const VOXEL_EDGE: f64 = 0.011287292;

/// Centres `(i + 1/2) r` of the grid cells of edge `r` whose centre lies inside a box or
/// cylinder of the scene.
fn voxel_centres(scene: &Scene, r: f64) -> Vec<Vector3<f64>> {
    let mut out = Vec::new();
    for s in scene.objects.iter().flat_map(|o| &o.shapes) {
        let (lo, hi) = s.aabb;
        let cell = |x: f64| (x / r).floor() as i64;
        for i in cell(lo.x) - 1..=cell(hi.x) + 1 {
            for j in cell(lo.y) - 1..=cell(hi.y) + 1 {
                for k in cell(lo.z) - 1..=cell(hi.z) + 1 {
                    let x = Vector3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5) * r;
                    let l = s.pose.rotation.tr_mul(&(x - s.pose.translation));
                    let inside = match &s.shape {
                        Convex::Box { half } => (0..3).all(|a| l[a].abs() <= half[a]),
                        Convex::Cylinder {
                            radius,
                            half_height,
                        } => l.z.abs() <= *half_height && l.xy().norm() <= *radius,
                        Convex::Sphere { radius } => l.norm() <= *radius,
                        other => panic!("no voxeliser for {other:?}"),
                    };
                    if inside {
                        out.push(x);
                    }
                }
            }
        }
    }
    out
}

/// The hull support map on each of Fetch's mesh hulls, by size: `climb` is the hull as
/// built (hulls above `convex::CLIMB_ABOVE` vertices climb along edges from the last
/// support vertex), `scan` the same vertices without their adjacency (every vertex
/// scanned). The directions are a random walk on the sphere (steps of 0.3 rad on
/// average), the hint carried from one call to the next, as GJK's iterations and the
/// warm starts across states carry it.
fn bench_support(c: &mut Criterion) {
    let (_, gm) = fetch();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let mut d = Vector3::x();
    let dirs: Vec<Vector3<f64>> = (0..1024)
        .map(|_| {
            let step = Vector3::new(
                rng.random_range(-0.3..0.3),
                rng.random_range(-0.3..0.3),
                rng.random_range(-0.3..0.3),
            );
            d = (d + step).normalize();
            d
        })
        .collect();
    let mut hulls: Vec<&Convex> = gm
        .objects
        .iter()
        .map(|o| &o.shape)
        .filter(|s| matches!(s, Convex::Hull { .. }))
        .collect();
    let size = |s: &Convex| match s {
        Convex::Hull { vertices, .. } => vertices.len(),
        _ => 0,
    };
    hulls.sort_by_key(|s| size(s));
    hulls.dedup_by_key(|s| size(s));
    let mut group = c.benchmark_group("support");
    group
        .warm_up_time(std::time::Duration::from_millis(300))
        .measurement_time(std::time::Duration::from_secs(1));
    for hull in hulls {
        let Convex::Hull { vertices, .. } = hull else {
            continue;
        };
        let scan = Convex::Hull {
            vertices: vertices.clone(),
            neighbours: vec![Vec::new(); vertices.len()],
        };
        for (name, shape) in [("climb", hull), ("scan", &scan)] {
            let (mut k, mut hint) = (0, 0);
            group.bench_function(format!("{:04}_vertices/{name}", vertices.len()), |b| {
                b.iter(|| {
                    k = (k + 1) % dirs.len();
                    black_box(shape.core_support(&dirs[k], &mut hint))
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench, bench_support);
criterion_main!(benches);

//! Space manipulators on Panda as a free flyer: the generalized Jacobian J* against one
//! CRBA on the same model and state, H*, the base twist, and one free-floating RK4 step
//! (four ABA passes) for the side-by-side with MuJoCo's `mj_step` (bench/mujoco_space.py).
//!
//! Run: `cargo bench -p moma --bench space --locked`.

use criterion::{Criterion, criterion_group, criterion_main};
use moma::dynamics;
use moma::io::urdf::model_from_urdf_file;
use moma::kinematics;
use moma::multibody::{Data, RootJoint};
use moma::sim::Rk4;
use moma::sim::free_floating::FreeFloatingOde;
use moma::space::{self, SpaceData};
use moma::spatial::Force;
use nalgebra::Vector3;
use rand::SeedableRng;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/pinocchio/urdf/panda.urdf");
    let mut model = model_from_urdf_file(path, RootJoint::FreeFlyer).unwrap();
    model.gravity = Vector3::zeros();
    let mut data = Data::new(&model);
    let mut sd = SpaceData::new(&model).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let q = kinematics::random_configuration(&model, &mut rng);
    let frame = model.frame_id("panda_hand_tcp").unwrap();
    let qd = [0.1; 9];
    let mut g = c.benchmark_group("space_panda_free_flyer");
    g.bench_function("crba", |b| {
        b.iter(|| {
            dynamics::crba(&model, &mut data, black_box(&q));
        })
    });
    g.bench_function("generalized_jacobian", |b| {
        b.iter(|| {
            space::generalized_jacobian(&model, &mut data, &mut sd, black_box(&q), frame).unwrap();
        })
    });
    g.bench_function("generalized_inertia", |b| {
        b.iter(|| {
            space::generalized_inertia(&model, &mut data, &mut sd, black_box(&q)).unwrap();
        })
    });
    g.bench_function("base_velocity", |b| {
        b.iter(|| {
            space::base_velocity(
                &model,
                &mut data,
                &mut sd,
                black_box(&q),
                &qd,
                &Force::zero(),
            )
            .unwrap();
        })
    });
    let mut ode = FreeFloatingOde::new(&model).unwrap();
    let mut x: Vec<f64> = q
        .iter()
        .copied()
        .chain(std::iter::repeat_n(0.1, model.nv))
        .collect();
    let mut rk = Rk4::new(x.len());
    g.bench_function("free_floating_rk4_step_1ms", |b| {
        b.iter(|| {
            ode.rk4_step(&mut rk, 0.0, black_box(&mut x), 1e-3).unwrap();
        })
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

//! Whole-body MPC solve time on Fetch (torso + 7-joint arm on its differential drive),
//! 1 s horizon (20 stages of 50 ms), every constraint on: torque, wheel and joint speed,
//! joint position, ZMP margin ≥ 0.05 m, clearance ≥ 0.03 m to a table and between the
//! enabled self pairs. The state is the one the closed loop of `tests/sim_mpc.rs`
//! reaches at t = 2.5 s (gripper reaching beside the path, base moving); each iteration
//! is one warm-started solve from it (4 iterations at most).

#[path = "../tests/mpc_common/mod.rs"]
mod mpc_common;

use criterion::{Criterion, criterion_group, criterion_main};
use moma::collision::Scene;
use moma::control::mpc::{KnotReference, MpcSettings};
use moma::sim::mpc_loop::{MpcLoopSettings, run_mpc_loop};
use moma::sim::wheeled_system::WheeledSystem;
use nalgebra::{Matrix3, Vector3};
use std::hint::black_box;

fn bench_mpc(c: &mut Criterion) {
    let scene = Scene {
        objects: vec![mpc_common::box_object(
            "table",
            [1.0, -0.85, 0.35],
            [0.3, 0.25, 0.35],
        )],
    };
    let mut s = MpcSettings::default();
    s.weights.ee_orientation = 0.0;
    let (mut mpc, q0) = mpc_common::fetch_mpc(Some(scene), s);
    let mut plant = WheeledSystem::new(mpc.problem.robot.wheeled.clone());
    let v0 = vec![0.0; plant.robot.nr()];
    let target = Vector3::new(1.0, -0.45, 0.85);
    let reference = move |t: f64| KnotReference {
        base: [0.3 * t, 0.0, 0.0],
        end_effector: (t >= 1.0).then_some((target, Matrix3::identity())),
    };
    let settings = MpcLoopSettings {
        duration: 2.5,
        period: 0.05,
        substeps: 5,
    };
    let run = run_mpc_loop(
        &mut mpc,
        &mut plant,
        q0.as_slice(),
        &v0,
        &settings,
        reference,
    )
    .unwrap();
    let last = run.samples.last().unwrap();
    let (q, v) = (last.q.clone(), last.v.clone());
    mpc.set_reference(last.t, reference);
    c.bench_function("mpc/fetch_1s_all_constraints", |b| {
        b.iter(|| black_box(mpc.solve(black_box(&q), black_box(&v)).unwrap()));
    });
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(50);
    targets = bench_mpc
}
criterion_main!(benches);

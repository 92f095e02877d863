//! Whole-body kinematics and manipulability benches (Panda on a differential drive):
//!
//! * `whole_body/jacobian_and_measures`: frame Jacobian (6 × 12) → whole-body J̄ (6 × 11)
//!   → SVD and every measure, one seeded configuration per call;
//! * `svd/{jacobi,nalgebra}_{3x7,6x7,6x11}`: the decomposition behind every measure
//!   (`JacobianSvd::new`, one-sided Jacobi) beside nalgebra's SVD with left vectors (what
//!   it replaced: wrong on some rank-deficient matrices), on Panda's position rows, arm
//!   Jacobian and whole-body J̄ over the same 64 configurations;
//! * `ik/panda_100_targets`: DLS/LM IK to 1e-6 (full pose) on 100 seeded reachable targets
//!   (FK of random configurations) from the neutral configuration;
//! * `placement/panda_100x100x8`: a 100 × 100 × 8 base-placement map (position target).
//!
//! `cargo bench -p moma --bench manipulability`

use criterion::{Criterion, criterion_group, criterion_main};
use moma::ik::model::ModelFrame;
use moma::ik::placement::{ArmReachEvaluator, MeasureScope, PlacementGrid, placement_map};
use moma::ik::tasks::{FrameKinematics, PoseTask, TaskRows};
use moma::ik::{IkOptions, IkWorkspace, solve_with_restarts};
use moma::io::urdf::model_from_urdf_file;
use moma::manipulability::{JacobianSvd, Measure, report};
use moma::mobile::DiffDrive;
use moma::mobile::whole_body::{BaseInputs, compose_jacobian};
use moma::multibody::RootJoint;
use nalgebra::{DMatrix, DVector, Isometry3};
use rand::SeedableRng;
use std::hint::black_box;
use std::sync::Arc;

fn panda(root: RootJoint) -> ModelFrame {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/manipulability/panda.urdf"
    );
    let model = model_from_urdf_file(path, root).expect("panda.urdf");
    ModelFrame::by_name(Arc::new(model), "panda_hand_tcp").expect("frame")
}

fn bench_whole_body(c: &mut Criterion) {
    let mut kin = panda(RootJoint::Planar);
    let model = kin.model().clone();
    let drive = DiffDrive::new(0.08, 0.27, 0.12).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let qs: Vec<DVector<f64>> = (0..64)
        .map(|_| moma::kinematics::random_configuration(&model, &mut rng))
        .collect();
    let mut j6 = DMatrix::zeros(6, model.nv);
    let mut jbar = DMatrix::zeros(6, model.nv - 1);
    let mut pose = Isometry3::identity();
    let mut i = 0;
    c.bench_function("whole_body/jacobian_6x11", |b| {
        b.iter(|| {
            let q = &qs[i % qs.len()];
            i += 1;
            kin.pose_and_jacobian(q, &mut pose, &mut j6).unwrap();
            compose_jacobian(&drive, BaseInputs::Wheels, q[2], &j6, &mut jbar).unwrap();
            black_box(&jbar);
        })
    });
    c.bench_function("whole_body/jacobian_and_all_measures", |b| {
        b.iter(|| {
            let q = &qs[i % qs.len()];
            i += 1;
            kin.pose_and_jacobian(q, &mut pose, &mut j6).unwrap();
            compose_jacobian(&drive, BaseInputs::Wheels, q[2], &j6, &mut jbar).unwrap();
            black_box(report(&jbar, Some(&[1.0, 0.0, 0.0, 0.0, 0.0, 0.0])).unwrap());
        })
    });
}

fn bench_svd(c: &mut Criterion) {
    let mut kin = panda(RootJoint::Planar);
    let model = kin.model().clone();
    let drive = DiffDrive::new(0.08, 0.27, 0.12).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let mut pose = Isometry3::identity();
    let mut j6 = DMatrix::zeros(6, model.nv);
    let mut jbar = DMatrix::zeros(6, model.nv - 1);
    let mut shapes: [(&str, Vec<DMatrix<f64>>); 3] = [
        ("3x7", Vec::new()),
        ("6x7", Vec::new()),
        ("6x11", Vec::new()),
    ];
    for _ in 0..64 {
        let q = moma::kinematics::random_configuration(&model, &mut rng);
        kin.pose_and_jacobian(&q, &mut pose, &mut j6).unwrap();
        compose_jacobian(&drive, BaseInputs::Wheels, q[2], &j6, &mut jbar).unwrap();
        // arm columns: after the planar root's 3 and before the 2 fingers
        shapes[0].1.push(j6.view((0, 3), (3, 7)).into_owned());
        shapes[1].1.push(j6.view((0, 3), (6, 7)).into_owned());
        shapes[2].1.push(jbar.clone());
    }
    for (name, js) in &shapes {
        let mut i = 0;
        c.bench_function(&format!("svd/jacobi_{name}"), |b| {
            b.iter(|| {
                i += 1;
                black_box(JacobianSvd::new(&js[i % js.len()]).unwrap())
            })
        });
        c.bench_function(&format!("svd/nalgebra_{name}"), |b| {
            b.iter(|| {
                i += 1;
                let j = js[i % js.len()].clone();
                let mut svd = nalgebra::SVD::try_new(j, true, false, f64::EPSILON, 10_000).unwrap();
                svd.sort_by_singular_values();
                black_box(svd)
            })
        });
    }
}

fn ik_targets(kin: &ModelFrame, n: usize) -> Vec<Isometry3<f64>> {
    let model = kin.model().clone();
    let mut k = kin.clone();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let mut j = DMatrix::zeros(6, model.nv);
    (0..n)
        .map(|_| {
            let q = moma::kinematics::random_configuration(&model, &mut rng);
            let mut p = Isometry3::identity();
            k.pose_and_jacobian(&q, &mut p, &mut j).unwrap();
            p
        })
        .collect()
}

fn bench_ik(c: &mut Criterion) {
    let kin = panda(RootJoint::Fixed);
    let targets = ik_targets(&kin, 100);
    let q0 = moma::kinematics::neutral(kin.model());
    let opts = IkOptions::default();
    let mut task = PoseTask::new(kin.clone(), targets[0], &TaskRows::Full).unwrap();
    let mut ws = IkWorkspace::new(&task);
    // One pass for the iteration statistics (printed once).
    let (mut conv, mut iters) = (0, 0);
    for (s, t) in targets.iter().enumerate() {
        task.target = *t;
        let r = solve_with_restarts(&mut task, &q0, &opts, 10, s as u64, &mut ws).unwrap();
        conv += r.converged as usize;
        iters += r.iterations;
    }
    eprintln!("ik/panda_100_targets: {conv}/100 converged to 1e-6, {iters} iterations in total");
    c.bench_function("ik/panda_100_targets", |b| {
        b.iter(|| {
            for (s, t) in targets.iter().enumerate() {
                task.target = *t;
                black_box(
                    solve_with_restarts(&mut task, &q0, &opts, 10, s as u64, &mut ws).unwrap(),
                );
            }
        })
    });
}

fn bench_placement(c: &mut Criterion) {
    let kin = panda(RootJoint::Fixed);
    let q0 = moma::kinematics::neutral(kin.model());
    let evaluator = ArmReachEvaluator {
        arm: kin,
        mount: Isometry3::identity(),
        target: Isometry3::translation(1.0, 0.5, 0.5),
        rows: TaskRows::Position,
        options: IkOptions {
            max_iterations: 100,
            ..IkOptions::default()
        },
        seed: q0,
        restarts: 2,
        measure: Measure::Yoshikawa,
        scope: MeasureScope::Arm,
    };
    // 100 × 100 cells (step 0.02 m over 1.98 m), 8 headings.
    let grid = PlacementGrid::new([0.0, -0.5, 1.98, 1.48], 0.02, 8).unwrap();
    assert_eq!((grid.nx, grid.ny), (100, 100));
    let map = placement_map(&evaluator, &grid).unwrap();
    eprintln!(
        "placement/panda_100x100x8: {} of {} poses reachable, {} rayon threads",
        map.reachable,
        map.samples.len(),
        rayon::current_num_threads()
    );
    let mut g = c.benchmark_group("placement");
    g.sample_size(10);
    g.bench_function("panda_100x100x8", |b| {
        b.iter(|| black_box(placement_map(&evaluator, &grid).unwrap()))
    });
    g.finish();
}

criterion_group!(
    benches,
    bench_whole_body,
    bench_svd,
    bench_ik,
    bench_placement
);
criterion_main!(benches);

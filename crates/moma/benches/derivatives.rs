//! Criterion benches of the analytical derivatives of the dynamics
//! (`dynamics::rnea_derivatives`, `dynamics::aba_derivatives`) on Panda (fixed and
//! free-flyer root), UR5, and TIAGo (fixed and planar root, continuous wheels): one call
//! per iteration, cycling over 100 seeded random states (q = neutral ⊕ U(−π, π)^nv; v, a,
//! τ ~ U(−1, 1)), so the time is per call, as Pinocchio's `computeRNEADerivatives` /
//! `computeABADerivatives` are timed.
//!
//! `cargo bench -p moma --bench derivatives -- --warm-up-time 1 --measurement-time 3`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use moma::dynamics::{self, DerivativeData};
use moma::io::urdf::model_from_urdf_file;
use moma::kinematics;
use moma::multibody::{Model, RootJoint};
use nalgebra::DVector;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;

const NSTATES: usize = 100;

type States = Vec<(DVector<f64>, DVector<f64>, DVector<f64>, DVector<f64>)>;

fn case(file: &str, root: RootJoint) -> (Model, States) {
    let dir =
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/pinocchio/urdf");
    let model = model_from_urdf_file(dir.join(file), root).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let q0 = kinematics::neutral(&model);
    let nv = model.nv;
    let states = (0..NSTATES)
        .map(|_| {
            let dq = DVector::from_fn(nv, |_, _| {
                std::f64::consts::PI * rng.random_range(-1.0..1.0)
            });
            let mut q = q0.clone();
            kinematics::integrate(&model, &q0, &dq, &mut q);
            let mut r = || DVector::from_fn(nv, |_, _| rng.random_range(-1.0..1.0));
            (q, r(), r(), r())
        })
        .collect();
    (model, states)
}

fn bench(cr: &mut Criterion) {
    let mut group = cr.benchmark_group("derivatives");
    for (name, file, root) in [
        ("panda", "panda.urdf", RootJoint::Fixed),
        ("ur5", "ur5_robot.urdf", RootJoint::Fixed),
        ("tiago", "tiago.urdf", RootJoint::Fixed),
        ("tiago_planar", "tiago.urdf", RootJoint::Planar),
        ("panda_freeflyer", "panda.urdf", RootJoint::FreeFlyer),
    ] {
        let (model, states) = case(file, root);
        let mut dd = DerivativeData::new(&model);
        let mut k = 0;
        group.bench_function(BenchmarkId::new("rnea_derivatives", name), |b| {
            b.iter(|| {
                let (q, v, a, _) = &states[k % NSTATES];
                k += 1;
                dynamics::rnea_derivatives(&model, &mut dd, q, v, a);
                black_box(dd.drnea_dq[(0, 0)]);
            });
        });
        group.bench_function(BenchmarkId::new("aba_derivatives", name), |b| {
            b.iter(|| {
                let (q, v, _, tau) = &states[k % NSTATES];
                k += 1;
                dynamics::aba_derivatives(&model, &mut dd, q, v, tau).unwrap();
                black_box(dd.daba_dq[(0, 0)]);
            });
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);

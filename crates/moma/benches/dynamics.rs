//! Criterion benches of the rigid-body algorithms on Panda (fixed and planar base) and UR5:
//! RNEA, CRBA, ABA, forward kinematics and one frame Jacobian (kinematics included), each
//! over 100 seeded random states per iteration batch, as `moma bench` and Pinocchio's
//! benchmark do; `rnea_batch` runs the multi-state RNEA kernel over the same 100 states
//! (row-major), to set side by side with `rnea`'s loop of single calls.
//!
//! `cargo bench -p moma --bench dynamics` (add `RUSTFLAGS="-C target-cpu=native"` for the
//! native build).

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use moma::dynamics;
use moma::io::urdf::model_from_urdf_file;
use moma::kinematics::{self, ReferenceFrame};
use moma::multibody::{Data, Model, RootJoint};
use nalgebra::{DVector, Matrix6xX};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::hint::black_box;

const NSTATES: usize = 100;

struct Case {
    name: &'static str,
    model: Model,
    frame: &'static str,
    q: Vec<DVector<f64>>,
    v: Vec<DVector<f64>>,
    a: Vec<DVector<f64>>,
    tau: Vec<DVector<f64>>,
}

fn cases() -> Vec<Case> {
    let dir =
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/pinocchio/urdf");
    [
        ("panda", "panda.urdf", RootJoint::Fixed, "panda_hand_tcp"),
        (
            "panda_planar",
            "panda.urdf",
            RootJoint::Planar,
            "panda_hand_tcp",
        ),
        ("ur5", "ur5_robot.urdf", RootJoint::Fixed, "tool0"),
    ]
    .into_iter()
    .map(|(name, file, root, frame)| {
        let model = model_from_urdf_file(dir.join(file), root).unwrap();
        let mut rng = ChaCha8Rng::seed_from_u64(42);
        let q0 = kinematics::neutral(&model);
        let nv = model.nv;
        let mut c = Case {
            name,
            model,
            frame,
            q: vec![],
            v: vec![],
            a: vec![],
            tau: vec![],
        };
        for _ in 0..NSTATES {
            let dq = DVector::from_fn(nv, |_, _| {
                std::f64::consts::PI * rng.random_range(-1.0..1.0)
            });
            let mut q = q0.clone();
            kinematics::integrate(&c.model, &q0, &dq, &mut q);
            c.q.push(q);
            c.v.push(DVector::from_fn(nv, |_, _| rng.random_range(-1.0..1.0)));
            c.a.push(DVector::from_fn(nv, |_, _| rng.random_range(-1.0..1.0)));
            c.tau
                .push(DVector::from_fn(nv, |_, _| rng.random_range(-1.0..1.0)));
        }
        c
    })
    .collect()
}

fn bench(cr: &mut Criterion) {
    for c in cases() {
        let m = &c.model;
        let mut data = Data::new(m);
        let mut jac = Matrix6xX::zeros(m.nv);
        let fid = m.frame_id(c.frame).unwrap();
        let mut g = cr.benchmark_group(format!("rigid_body/{}", c.name));
        g.throughput(criterion::Throughput::Elements(NSTATES as u64));
        g.bench_function(BenchmarkId::new("rnea", NSTATES), |b| {
            b.iter(|| {
                for i in 0..NSTATES {
                    black_box(dynamics::rnea(m, &mut data, &c.q[i], &c.v[i], &c.a[i])[0]);
                }
            });
        });
        let flat =
            |x: &[DVector<f64>]| x.iter().flat_map(|r| r.iter().copied()).collect::<Vec<_>>();
        let (qs, vs, accs) = (flat(&c.q), flat(&c.v), flat(&c.a));
        let mut batch = dynamics::BatchData::new(m);
        let mut out = vec![0.0; NSTATES * m.nv];
        g.bench_function(BenchmarkId::new("rnea_batch", NSTATES), |b| {
            b.iter(|| {
                dynamics::rnea_batch(m, &mut batch, &qs, &vs, &accs, &mut out);
                black_box(out[0]);
            });
        });
        g.bench_function(BenchmarkId::new("crba", NSTATES), |b| {
            b.iter(|| {
                for i in 0..NSTATES {
                    black_box(dynamics::crba(m, &mut data, &c.q[i])[(0, 0)]);
                }
            });
        });
        g.bench_function(BenchmarkId::new("aba", NSTATES), |b| {
            b.iter(|| {
                for i in 0..NSTATES {
                    black_box(dynamics::aba(m, &mut data, &c.q[i], &c.v[i], &c.tau[i])[0]);
                }
            });
        });
        g.bench_function(BenchmarkId::new("fk", NSTATES), |b| {
            b.iter(|| {
                for i in 0..NSTATES {
                    kinematics::forward_kinematics(m, &mut data, &c.q[i]);
                    black_box(data.world_from_joint[m.njoints - 1].translation.x);
                }
            });
        });
        g.bench_function(BenchmarkId::new("frame_jacobian", NSTATES), |b| {
            b.iter(|| {
                for i in 0..NSTATES {
                    kinematics::frame_jacobian(
                        m,
                        &mut data,
                        &c.q[i],
                        fid,
                        ReferenceFrame::LocalWorldAligned,
                        &mut jac,
                    );
                    black_box(jac[(0, 0)]);
                }
            });
        });
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);

//! Tip-over stability bench: all three measures (ZMP with per-edge distances,
//! Force-Angle with and without the couple, Moment-Height over every body) with the
//! gravito-inertial wrench from (q, v, a), against one RNEA on the same model, on TIAGo
//! (planar base) and Panda (planar base). Support: five contacts (a rectangle and an
//! interior caster), moving with the base.
//!
//! Run: `cargo bench -p moma --bench stability --locked`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use moma::dynamics::rnea;
use moma::io::urdf::model_from_urdf_file;
use moma::multibody::{Data, RootJoint};
use moma::stability::{
    BodySet, ExternalLoads, StabilityData, StabilityModel, SupportAttachment, SupportPolygon,
    evaluate,
};
use nalgebra::{DVector, Vector2};
use rand::SeedableRng;

fn bench(c: &mut Criterion) {
    for file in ["tiago.urdf", "panda.urdf"] {
        let path = format!(
            "{}/tests/data/pinocchio/urdf/{file}",
            env!("CARGO_MANIFEST_DIR")
        );
        let model = model_from_urdf_file(path, RootJoint::Planar).expect("model");
        let name = file.trim_end_matches(".urdf");
        let support = SupportPolygon::from_points(&[
            Vector2::new(0.3, 0.25),
            Vector2::new(0.3, -0.25),
            Vector2::new(-0.3, -0.25),
            Vector2::new(-0.3, 0.25),
            Vector2::new(0.0, 0.0),
        ])
        .unwrap();
        let sm =
            StabilityModel::new(&model, support, SupportAttachment::Base, &BodySet::All).unwrap();
        let mut data = Data::new(&model);
        let mut sd = StabilityData::new(&sm);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
        let q = moma::kinematics::random_configuration(&model, &mut rng);
        let v = DVector::from_element(model.nv, 0.3);
        let a = DVector::from_element(model.nv, -0.2);
        c.bench_function(&format!("{name}/rnea"), |b| {
            b.iter(|| {
                black_box(rnea(&model, &mut data, black_box(&q), &v, &a));
            })
        });
        c.bench_function(&format!("{name}/stability_all_measures"), |b| {
            b.iter(|| {
                let r = evaluate(
                    &model,
                    &mut data,
                    &sm,
                    &mut sd,
                    black_box(&q),
                    &v,
                    &a,
                    &ExternalLoads::NONE,
                );
                black_box(r.mhs_min);
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);

//! `stability::evaluate` allocates nothing after `StabilityData::new`: a counting global
//! allocator wraps the system one while the measures run on TIAGo and Panda (planar base,
//! support moving with the base, external loads, every body set kind).

use moma::io::urdf::model_from_urdf_file;
use moma::multibody::{Data, RootJoint};
use moma::stability::{
    BodySet, ExternalLoads, PointForce, StabilityData, StabilityModel, SupportAttachment,
    SupportPolygon, evaluate,
};
use nalgebra::{DVector, Vector2, Vector3};
use rand::SeedableRng;

mod counting_alloc;
use counting_alloc::allocations;

#[test]
fn evaluate_does_not_allocate() {
    let dir =
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/pinocchio/urdf");
    for (file, set) in [
        ("tiago.urdf", "all"),
        ("panda.urdf", "subtree:panda_joint2"),
        ("panda.urdf", "links:panda_link3,panda_hand"),
    ] {
        let model = model_from_urdf_file(dir.join(file), RootJoint::Planar).unwrap();
        let mut data = Data::new(&model);
        let support = SupportPolygon::from_points(&[
            Vector2::new(0.3, 0.25),
            Vector2::new(0.3, -0.25),
            Vector2::new(-0.3, -0.25),
            Vector2::new(-0.3, 0.25),
            Vector2::new(0.0, 0.0),
        ])
        .unwrap();
        let bodies: BodySet = set.parse().unwrap();
        let sm = StabilityModel::new(&model, support, SupportAttachment::Base, &bodies).unwrap();
        let mut sd = StabilityData::new(&sm);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let q = moma::kinematics::random_configuration(&model, &mut rng);
        let v = DVector::from_element(model.nv, 0.3);
        let a = DVector::from_element(model.nv, -0.2);
        let f = [PointForce {
            point: Vector3::new(0.5, 0.0, 1.0),
            force: Vector3::new(10.0, 0.0, -5.0),
        }];
        let m = [Vector3::new(0.0, 1.0, 0.0)];
        let ext = ExternalLoads {
            forces: &f,
            moments: &m,
        };
        evaluate(&model, &mut data, &sm, &mut sd, &q, &v, &a, &ext);
        let (count, ()) = allocations(|| {
            for _ in 0..3 {
                evaluate(&model, &mut data, &sm, &mut sd, &q, &v, &a, &ext);
                let _ = sd.acceleration_limits(&sm);
            }
        });
        assert_eq!(count, 0, "{file}: evaluate allocated");
        assert!(sd.report.zmp.is_some());
    }
}

//! The space algorithms allocate nothing after `SpaceData::new` / `Data::new`: a counting
//! global allocator wraps the system one and every call runs with the counter armed.

use moma::io::urdf::model_from_urdf_file;
use moma::kinematics;
use moma::multibody::{Data, RootJoint};
use moma::space::{self, SpaceData};
use moma::spatial::Force;
use nalgebra::Vector3;
use rand::SeedableRng;

mod counting_alloc;
use counting_alloc::allocations;

#[test]
fn space_algorithms_do_not_allocate() {
    let path = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/pinocchio/urdf/panda.urdf");
    let mut model = model_from_urdf_file(path, RootJoint::FreeFlyer).unwrap();
    model.gravity = Vector3::zeros();
    let mut data = Data::new(&model);
    let mut sd = SpaceData::new(&model).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(9);
    let q = kinematics::random_configuration(&model, &mut rng);
    let v = nalgebra::DVector::from_element(model.nv, 0.2);
    let frame = model.frame_id("panda_hand_tcp").unwrap();
    let qd = [0.1; 9];
    let h = Force::new(Vector3::new(0.1, 0.2, 0.3), Vector3::new(-0.1, 0.0, 0.2));
    let (count, ()) = allocations(|| {
        for _ in 0..3 {
            let _ = space::momentum(&model, &mut data, &q, &v);
            space::momentum_maps(&model, &mut data, &mut sd, &q).unwrap();
            space::base_velocity(&model, &mut data, &mut sd, &q, &qd, &h).unwrap();
            space::generalized_jacobian(&model, &mut data, &mut sd, &q, frame).unwrap();
            let _ = space::momentum_drift(&sd, &h);
            let _ = space::frame_velocity(&sd, &qd, &h);
            space::generalized_inertia(&model, &mut data, &mut sd, &q).unwrap();
            space::dynamic_singularity(&model, &mut data, &mut sd, &q, frame).unwrap();
        }
    });
    assert_eq!(count, 0, "allocations in the space algorithms");
}

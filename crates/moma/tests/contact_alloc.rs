//! A step of the contact plant allocates nothing once its state is built, whether the
//! contacts stick or slide (counted per thread by `counting_alloc`).

use moma::contact::{CasterSpec, ContactParams, ContactPlant, ContactState, WheelSpec};
use moma::io::urdf::model_from_urdf_file;
use moma::multibody::RootJoint;

mod counting_alloc;
use counting_alloc::allocations;

#[test]
fn a_contact_step_does_not_allocate() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/robots/diffdrive_arm.urdf");
    let model = model_from_urdf_file(path, RootJoint::FreeFlyer).unwrap();
    let wheels = ["left_wheel_joint", "right_wheel_joint"].map(|j| WheelSpec {
        joint: j.into(),
        radius: 0.08,
    });
    let casters = [CasterSpec {
        frame: "caster".into(),
        radius: 0.03,
    }];
    let params = ContactParams {
        mu: 0.3,
        ..ContactParams::default()
    };
    let plant = ContactPlant::new(model, &wheels, &casters, params).unwrap();
    let q0 = [0.0, 0.0, 0.08, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.5, 0.0];
    let mut st = ContactState::new(&plant, &q0, &[0.0; 11]).unwrap();
    // Settling onto the contacts (starting unloaded), then a spin beyond μ (slipping):
    // both branches of the friction law.
    let mut slipped = false;
    let (allocations, ()) = allocations(|| {
        for k in 0..15_000 {
            let w = if k < 3000 { 0.0 } else { 4.0 };
            let u = [-w, w, 0.0, 0.0, 0.0];
            plant.step(&mut st, &u).unwrap();
            slipped |= st.contacts[0].slipping;
        }
    });
    assert!(slipped, "the run should make a wheel slip");
    assert_eq!(allocations, 0, "allocations during contact steps");
}

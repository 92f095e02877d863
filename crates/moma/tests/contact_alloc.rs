//! A step of the contact plant allocates nothing once its state is built, whether the
//! contacts stick or slide (counted per thread by `counting_alloc`).

use moma::contact::{ContactParams, ContactState};

mod contact_common;
mod counting_alloc;
use contact_common::{diffdrive_arm_plant, standing};
use counting_alloc::allocations;

#[test]
fn a_contact_step_does_not_allocate() {
    let plant = diffdrive_arm_plant(ContactParams {
        mu: 0.3,
        ..ContactParams::default()
    });
    let q0 = standing([0.0, 1.5, 0.0]);
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

#![allow(unsafe_code)]
//! A step of the contact plant allocates nothing once its state is built, whether the
//! contacts stick or slide. The counting global allocator counts per thread: only the
//! test's own allocations count, not the test harness's on its other threads.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;

use moma::contact::{CasterSpec, ContactParams, ContactPlant, ContactState, WheelSpec};
use moma::io::urdf::model_from_urdf_file;
use moma::multibody::RootJoint;

struct Counting;

thread_local! {
    static COUNT: Cell<usize> = const { Cell::new(0) };
}

fn bump() {
    // `try_with`: the slot may be gone while a thread shuts down.
    let _ = COUNT.try_with(|c| c.set(c.get() + 1));
}

// SAFETY: forwards every call to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        bump();
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        bump();
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

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
    let before = COUNT.with(Cell::get);
    for k in 0..15_000 {
        let w = if k < 3000 { 0.0 } else { 4.0 };
        let u = [-w, w, 0.0, 0.0, 0.0];
        plant.step(&mut st, &u).unwrap();
        slipped |= st.contacts[0].slipping;
    }
    let allocations = COUNT.with(Cell::get) - before;
    assert!(slipped, "the run should make a wheel slip");
    assert_eq!(allocations, 0, "allocations during contact steps");
}

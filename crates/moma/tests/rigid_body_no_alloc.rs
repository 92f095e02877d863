//! The rigid-body algorithms allocate nothing after `Data::new`: a counting global
//! allocator wraps the system one and every algorithm is called on Panda (fixed and
//! planar base) and a free-flyer model with the counter armed.
#![allow(unsafe_code)]

use moma::dynamics;
use moma::io::urdf::model_from_urdf_file;
use moma::kinematics::{self, ReferenceFrame};
use moma::multibody::{Data, RootJoint};
use nalgebra::{DVector, Matrix6xX};
use rand::SeedableRng;
use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

struct Counting;

static ARMED: AtomicBool = AtomicBool::new(false);
static COUNT: AtomicUsize = AtomicUsize::new(0);

// SAFETY: forwards every call to the system allocator unchanged; only counts.
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if ARMED.load(Ordering::Relaxed) {
            COUNT.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: same contract as the caller's.
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if ARMED.load(Ordering::Relaxed) {
            COUNT.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: same contract as the caller's.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn algorithms_do_not_allocate() {
    let dir =
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/pinocchio/urdf");
    for root in [RootJoint::Fixed, RootJoint::Planar, RootJoint::FreeFlyer] {
        let model = model_from_urdf_file(dir.join("panda.urdf"), root).unwrap();
        let mut data = Data::new(&model);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let q = kinematics::random_configuration(&model, &mut rng);
        let v = DVector::from_element(model.nv, 0.3);
        let a = DVector::from_element(model.nv, -0.2);
        let mut q_out = q.clone();
        let mut v_out = v.clone();
        let mut jac = Matrix6xX::zeros(model.nv);
        let fid = model.frame_id("panda_hand_tcp").unwrap();

        COUNT.store(0, Ordering::SeqCst);
        ARMED.store(true, Ordering::SeqCst);
        for _ in 0..3 {
            kinematics::forward_kinematics(&model, &mut data, &q);
            kinematics::forward_kinematics_second_order(&model, &mut data, &q, &v, &a);
            kinematics::update_frame_placements(&model, &mut data);
            kinematics::frames_forward_kinematics(&model, &mut data, &q);
            kinematics::compute_joint_jacobians(&model, &mut data, &q);
            for rf in [
                ReferenceFrame::World,
                ReferenceFrame::Local,
                ReferenceFrame::LocalWorldAligned,
            ] {
                kinematics::frame_jacobian(&model, &mut data, &q, fid, rf, &mut jac);
                kinematics::frame_jacobian_from_kinematics(&model, &mut data, fid, rf, &mut jac);
                let _ = kinematics::frame_acceleration_bias(&model, &mut data, &q, &v, fid, rf);
                let _ = kinematics::frame_velocity(&model, &data, fid, rf);
            }
            kinematics::integrate(&model, &q, &v, &mut q_out);
            kinematics::difference(&model, &q, &q_out, &mut v_out);
            let _ = dynamics::rnea(&model, &mut data, &q, &v, &a);
            let _ = dynamics::crba(&model, &mut data, &q);
            let _ = dynamics::aba(&model, &mut data, &q, &v, &a);
            let _ = dynamics::nonlinear_effects(&model, &mut data, &q, &v);
            let _ = dynamics::gravity_torque(&model, &mut data, &q);
            let _ = dynamics::coriolis_matrix(&model, &mut data, &q, &v);
            let _ = dynamics::kinetic_energy(&model, &mut data, &q, &v);
            let _ = dynamics::potential_energy(&model, &mut data, &q);
            let _ = dynamics::center_of_mass(&model, &mut data, &q);
            let _ = dynamics::centroidal_momentum_matrix(&model, &mut data, &q);
            let _ = dynamics::centroidal_momentum(&model, &mut data, &q, &v);
        }
        ARMED.store(false, Ordering::SeqCst);
        let n = COUNT.load(Ordering::SeqCst);
        assert_eq!(n, 0, "{root}: {n} allocations on the hot path");
        // the counter works: an allocation while armed is seen
        ARMED.store(true, Ordering::SeqCst);
        let probe = std::hint::black_box(vec![1u8; 16]);
        ARMED.store(false, Ordering::SeqCst);
        drop(probe);
        assert!(COUNT.load(Ordering::SeqCst) > 0);
    }
}

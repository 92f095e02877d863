//! The one computed torque of the wheeled closed loops (`sim::computed_torque`): the wheel
//! block of `N_Cᵀ S` it inverts once is the same at every configuration, and its torques
//! give the desired reduced acceleration on the plant's own forward dynamics.

use moma::io::urdf::model_from_urdf_file;
use moma::mobile::wheeled::{
    WheeledBase, reduced_forward_dynamics_crba, reduced_forward_dynamics_under_inputs,
};
use moma::mobile::{DiffDrive, WheeledData, WheeledModel};
use moma::multibody::RootJoint;
use moma::sim::computed_torque::{ComputedTorque, wheel_block};
use nalgebra::DVector;

fn robot(tracked: bool, d: f64) -> WheeledModel {
    let urdf = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../scenarios/robots/mobile_manipulator.urdf"
    );
    let model = model_from_urdf_file(urdf, RootJoint::Planar).unwrap();
    let mut base = WheeledBase::new(DiffDrive::new(0.1, 0.22, d).unwrap());
    if tracked {
        base.wheel_joints = Some(["left_wheel_joint".into(), "right_wheel_joint".into()]);
    }
    WheeledModel::new(model, base).unwrap()
}

/// The wheel block is taken once: it must not depend on the configuration.
#[test]
fn the_wheel_block_does_not_depend_on_the_configuration() {
    for (tracked, d) in [(true, 0.0), (false, 0.0), (false, 0.15), (true, 0.15)] {
        let wm = robot(tracked, d);
        let b0 = wheel_block(&wm, &moma::multibody::neutral(&wm.model));
        assert!(b0.determinant().abs() > 1e-6);
        for k in 0..5 {
            let q = DVector::from_fn(wm.model.nq, |i, _| {
                (1.7 * (i + 1) as f64 + 0.9 * k as f64).sin() * 3.0
            });
            let b = wheel_block(&wm, &q);
            assert!((b - b0).amax() < 1e-12, "{tracked} {d}: {b} vs {b0}");
        }
    }
}

/// The inputs reproduce the desired reduced acceleration through the plant's own
/// forward dynamics, and a bound clips.
#[test]
fn inputs_give_the_desired_acceleration_on_the_plant() {
    let wm = robot(true, 0.0);
    let (nq, nr, nu) = (wm.model.nq, wm.nr(), wm.nu());
    let q = DVector::from_fn(nq, |i, _| 0.3 * (i as f64 + 0.5).cos());
    let v = DVector::from_fn(nr, |i, _| 0.2 * (i as f64 + 1.0).sin());
    let a = DVector::from_fn(nr, |i, _| 0.5 - 0.1 * i as f64);
    let mut wd = WheeledData::new(&wm);
    reduced_forward_dynamics_crba(&wm, &mut wd, &q, &v, &vec![0.0; nu]).unwrap();
    let ct = ComputedTorque::new(&wm, vec![f64::INFINITY; nu]).unwrap();
    let mut u = vec![0.0; nu];
    assert!(!ct.inputs(&wd.reduced, &a, &mut u));
    let mut plant = WheeledData::new(&wm);
    let vdot = reduced_forward_dynamics_crba(&wm, &mut plant, &q, &v, &u)
        .unwrap()
        .clone();
    assert!((&vdot - &a).amax() < 1e-9, "{vdot} vs {a}");
    // the controller's evaluation under the torques is the plant's, to the bit
    reduced_forward_dynamics_under_inputs(&wm, &mut wd, &q, &u).unwrap();
    assert_eq!(wd.reduced.vdot, vdot);
    assert_eq!(wd.reduced.qddot, plant.reduced.qddot);

    let peak = u.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let bounded = ComputedTorque::new(&wm, vec![0.5 * peak; nu]).unwrap();
    let mut uc = vec![0.0; nu];
    assert!(bounded.inputs(&wd.reduced, &a, &mut uc));
    assert!(uc.iter().all(|x| x.abs() <= 0.5 * peak));
    assert!(ComputedTorque::new(&wm, vec![0.0; nu]).is_err());
    assert!(ComputedTorque::new(&wm, vec![1.0; nu + 1]).is_err());
}

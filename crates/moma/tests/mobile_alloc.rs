//! The reduced forward dynamics, multipliers and the simulator's right-hand side do not
//! allocate after construction (counting global allocator).

use moma::io::urdf::model_from_urdf_file;
use moma::mobile::DiffDrive;
use moma::mobile::reduced_forward_dynamics;
use moma::mobile::wheeled::{WheeledBase, WheeledData, WheeledModel, lagrange_multipliers};
use moma::multibody::RootJoint;
use moma::sim::OdeSystem;
use moma::sim::settings::InputProfile;
use moma::sim::wheeled::ReducedOde;
use moma::sim::wheeled_system::WheeledSystem;
use nalgebra::DVector;

mod counting_alloc;
use counting_alloc::allocations;

fn robot() -> WheeledModel {
    let path = format!(
        "{}/tests/data/mobile/diffdrive_arm.urdf",
        env!("CARGO_MANIFEST_DIR")
    );
    let model = model_from_urdf_file(path, RootJoint::Planar).unwrap();
    let mut base = WheeledBase::new(DiffDrive::new(0.08, 0.25, 0.1).unwrap());
    base.wheel_joints = Some(["left_wheel_joint".into(), "right_wheel_joint".into()]);
    WheeledModel::new(model, base).unwrap()
}

#[test]
fn hot_paths_do_not_allocate() {
    let wm = robot();
    let mut wd = WheeledData::new(&wm);
    let q = DVector::from_fn(wm.model.nq, |i, _| 0.1 * i as f64);
    let v = DVector::from_fn(wm.nr(), |i, _| 0.2 - 0.05 * i as f64);
    let u = vec![0.3; wm.nu()];
    // Warm up once, then count.
    reduced_forward_dynamics(&wm, &mut wd, &q, &v, &u).unwrap();
    lagrange_multipliers(&wm, &mut wd, &q).unwrap();
    let (count, ()) = allocations(|| {
        for _ in 0..100 {
            reduced_forward_dynamics(&wm, &mut wd, &q, &v, &u).unwrap();
            lagrange_multipliers(&wm, &mut wd, &q).unwrap();
        }
    });
    assert_eq!(count, 0, "reduced dynamics allocated {} times", count);

    // The root-constrained ABA path (wheels not tracked).
    let mut untracked = robot();
    untracked = WheeledModel::new(
        untracked.model.clone(),
        WheeledBase::new(DiffDrive::new(0.08, 0.25, 0.1).unwrap()),
    )
    .unwrap();
    let mut wd2 = WheeledData::new(&untracked);
    let q2 = DVector::from_fn(untracked.model.nq, |i, _| 0.1 * i as f64);
    let v2 = DVector::from_fn(untracked.nr(), |i, _| 0.2 - 0.05 * i as f64);
    let u2 = vec![0.3; untracked.nu()];
    reduced_forward_dynamics(&untracked, &mut wd2, &q2, &v2, &u2).unwrap();
    let (count, ()) = allocations(|| {
        for _ in 0..100 {
            reduced_forward_dynamics(&untracked, &mut wd2, &q2, &v2, &u2).unwrap();
            lagrange_multipliers(&untracked, &mut wd2, &q2).unwrap();
        }
    });
    assert_eq!(count, 0, "root-constrained ABA allocated {} times", count);

    // The simulator's ODE right-hand side.
    let mut sys = WheeledSystem::new(robot());
    let input = InputProfile::zero(sys.robot.nu());
    let mut ode = ReducedOde::new(&mut sys, &input).unwrap();
    let n = ode.dim();
    let x: Vec<f64> = (0..n).map(|i| 0.05 * i as f64).collect();
    let mut dx = vec![0.0; n];
    ode.rhs(0.0, &x, &mut dx).unwrap();
    let (count, ()) = allocations(|| {
        for k in 0..100 {
            ode.rhs(0.01 * k as f64, &x, &mut dx).unwrap();
        }
    });
    assert_eq!(count, 0, "ODE rhs allocated {} times", count);
}

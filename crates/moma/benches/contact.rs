//! One step of the contact plant (`moma::contact`), default parameters (dt = 0.1 ms), on
//! the two robots of the MuJoCo comparison:
//!
//! * `contact/diffdrive_arm/step`: `scenarios/robots/diffdrive_arm.urdf`, free-flyer root
//!   (nv = 11), two wheel disks and a ball caster in contact;
//! * `contact/mobile_manipulator/step`: the UR5-class mobile manipulator of
//!   `scenarios/robots/mobile_manipulator.urdf` (nv = 14), two wheel disks and four ball
//!   casters in contact.
//!
//! Each settles for 0.5 s with the arm held by the PD law of the comparison, then the timed
//! run drives with the wheel torques of the comparison's `roll` (all contacts loaded, the
//! wheels rolling) and restarts from the settled state every simulated second. Compare with
//! MuJoCo's `mj_step` on the same robots (`bench/mujoco_contact_compare.py ROBOT DIR
//! --time`).
//!
//! Run: `cargo bench -p moma --bench contact --locked`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use moma::contact::{ContactParams, ContactPlant, ContactState};

#[path = "../tests/contact_common/mod.rs"]
mod contact_common;
use contact_common::{diffdrive_arm_plant, mobile_manipulator_plant};

/// Times one step of `plant` standing at `base_height` with the arm (the inputs that are
/// not wheels, model order) held at `arm` by `u = kp (arm − q) − kd q̇`, the wheels driven
/// with `wheel_torques`.
#[allow(clippy::too_many_arguments)]
fn bench_step(
    c: &mut Criterion,
    name: &str,
    plant: &ContactPlant,
    base_height: f64,
    arm: &[f64],
    kp: &[f64],
    kd: &[f64],
    wheel_torques: [f64; 2],
) {
    let inputs = plant.input_names();
    let wheels = ["left_wheel_joint", "right_wheel_joint"]
        .map(|j| inputs.iter().position(|n| n == j).expect("a wheel input"));
    let arm_inputs: Vec<usize> = (0..plant.nu()).filter(|i| !wheels.contains(i)).collect();
    let mut q0 = vec![0.0; plant.model.nq];
    q0[2] = base_height;
    q0[6] = 1.0;
    for (j, &i) in arm_inputs.iter().enumerate() {
        q0[7 + i] = arm[j];
    }
    let mut st = ContactState::new(plant, &q0, &vec![0.0; plant.model.nv]).expect("state");
    let mut u = vec![0.0; plant.nu()];
    let hold = |st: &ContactState, u: &mut [f64]| {
        for (j, &i) in arm_inputs.iter().enumerate() {
            u[i] = kp[j] * (arm[j] - st.q[7 + i]) - kd[j] * st.v[6 + i];
        }
    };
    for _ in 0..5000 {
        hold(&st, &mut u);
        plant.step(&mut st, &u).expect("step");
    }
    u[wheels[0]] = wheel_torques[0];
    u[wheels[1]] = wheel_torques[1];
    let settled = st.clone();
    c.bench_function(name, |b| {
        b.iter_custom(|iters| {
            let mut s = settled.clone();
            let t0 = std::time::Instant::now();
            for i in 0..iters {
                if i.is_multiple_of(10_000) {
                    s.clone_from(&settled);
                }
                hold(&s, &mut u);
                plant.step(black_box(&mut s), black_box(&u)).expect("step");
            }
            t0.elapsed()
        })
    });
}

fn bench(c: &mut Criterion) {
    bench_step(
        c,
        "contact/diffdrive_arm/step",
        &diffdrive_arm_plant(ContactParams::default()),
        0.08,
        &[0.0, 0.3, 0.5],
        &[200.0; 3],
        &[20.0; 3],
        [0.25, 0.45],
    );
    bench_step(
        c,
        "contact/mobile_manipulator/step",
        &mobile_manipulator_plant(ContactParams::default()),
        0.0,
        &[0.0, -0.5, 2.6, 1.04, 0.0, 0.0],
        &[2000.0, 2000.0, 1000.0, 100.0, 100.0, 100.0],
        &[100.0, 100.0, 50.0, 2.0, 2.0, 1.0],
        [0.4, 0.64],
    );
}

criterion_group!(benches, bench);
criterion_main!(benches);

//! One step of the contact plant (`moma::contact`) on the diff-drive arm of
//! `scenarios/robots/diffdrive_arm.urdf`: free-flyer root (nv = 11), two wheel disks and a
//! ball caster in contact, default parameters (dt = 0.1 ms). Compare with MuJoCo's
//! `mj_step` on the same robot (`bench/mujoco_wheeled.py`).
//!
//! Run: `cargo bench -p moma --bench contact --locked`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use moma::contact::{ContactParams, ContactState};

#[path = "../tests/contact_common/mod.rs"]
mod contact_common;
use contact_common::{diffdrive_arm_plant, standing};

fn bench(c: &mut Criterion) {
    let plant = diffdrive_arm_plant(ContactParams::default());
    let arm = [0.0, 0.3, 0.5];
    let q0 = standing(arm);
    let mut st = ContactState::new(&plant, &q0, &vec![0.0; plant.model.nv]).expect("state");
    // Settle for 0.5 s with the arm held by a PD law; the timed run then drives with
    // wheel torques (0.25, 0.45) N·m (all three contacts loaded, the wheels rolling) and
    // restarts from the settled state every simulated second.
    let mut u = [0.0; 5];
    let hold = |st: &ContactState, u: &mut [f64; 5]| {
        for j in 0..3 {
            u[2 + j] = 200.0 * (arm[j] - st.q[9 + j]) - 20.0 * st.v[8 + j];
        }
    };
    for _ in 0..5000 {
        hold(&st, &mut u);
        plant.step(&mut st, &u).expect("step");
    }
    u[0] = 0.25;
    u[1] = 0.45;
    let settled = st.clone();
    c.bench_function("contact/diffdrive_arm/step", |b| {
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

criterion_group!(benches, bench);
criterion_main!(benches);

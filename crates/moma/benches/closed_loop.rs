//! Closed-loop simulation speed: the Panda on a differential drive (planar root, 9
//! arm/finger joints, one no-side-slip row) under operational-space control of its tool
//! point through the reduced model, zero-order hold at 1 kHz over fixed-step RK4 at
//! 1 ms: each step is one OSC update (CRBA, nonlinear effects, J̇q̇, frame Jacobian,
//! the reduced projection, two Cholesky factorisations), the actuator map and one RK4
//! step (4 reduced forward dynamics). One iteration runs 200 steps (0.2 s) from the
//! same state; throughput is reported per step.
//!
//! Run: `cargo bench -p moma --bench closed_loop --locked`.

use std::hint::black_box;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use moma::io::urdf::model_from_urdf_file;
use moma::mobile::DiffDrive;
use moma::mobile::wheeled::{WheeledBase, WheeledModel};
use moma::multibody::RootJoint;
use moma::sim::closed_loop::{ClosedLoopOptions, simulate_closed_loop};
use moma::sim::feedback::{OscController, OscGains, PointReference};
use moma::sim::monitor::MonitorLimits;
use moma::sim::settings::IntegratorSettings;
use moma::sim::wheeled_system::WheeledSystem;

fn panda_on_diff_drive() -> WheeledModel {
    let model = model_from_urdf_file(
        format!(
            "{}/tests/data/pinocchio/urdf/panda.urdf",
            env!("CARGO_MANIFEST_DIR")
        ),
        RootJoint::Planar,
    )
    .expect("panda");
    WheeledModel::new(
        model,
        WheeledBase::new(DiffDrive::new(0.1, 0.3, 0.2).unwrap()),
    )
    .unwrap()
}

fn bench_closed_loop(c: &mut Criterion) {
    let wm = panda_on_diff_drive();
    let q0 = vec![
        0.0, 0.0, 0.0, 0.0, -0.3, 0.0, -2.2, 0.0, 2.0, 0.8, 0.02, 0.02,
    ];
    let v0 = vec![0.0; wm.nr()];
    let posture: Vec<f64> = wm.arm_dofs().iter().map(|&d| q0[d]).collect();
    let mut law = OscController::new(
        wm.clone(),
        "panda_hand_tcp",
        PointReference::Circle {
            center: [0.45, 0.0, 0.5],
            radius: 0.1,
            period: 4.0,
            phase: 0.0,
        },
        OscGains {
            kp: 64.0,
            kv: 16.0,
            posture_kp: 10.0,
            posture_kd: 2.0,
        },
        posture,
        None,
    )
    .unwrap();
    let mut plant = WheeledSystem::new(wm);
    let steps = 200;
    let options = ClosedLoopOptions {
        duration: 0.2,
        integrator: IntegratorSettings::rk4(1e-3),
        control_period: Some(1e-3),
        record_interval: 0.1,
        limits: MonitorLimits::default(),
        lyapunov_tolerance: 1e-9,
    };
    let mut g = c.benchmark_group("closed_loop/panda_diffdrive_osc_reduced");
    g.throughput(Throughput::Elements(steps));
    g.bench_function("zoh_1khz_rk4_1ms_step", |b| {
        b.iter(|| {
            let r = simulate_closed_loop(
                &mut plant,
                &mut law,
                black_box(&q0),
                &v0,
                &options,
                None,
                &mut |_| {},
            )
            .unwrap();
            black_box(r.control_ticks)
        });
    });
    g.finish();
}

criterion_group!(benches, bench_closed_loop);
criterion_main!(benches);

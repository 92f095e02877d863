//! Non-holonomic dynamics and simulation benches.
//!
//! * reduced forward dynamics of a Panda on a differential-drive base (planar root +
//!   9 arm/finger joints, one no-side-slip row) against ABA on the same model without
//!   the constraint;
//! * one RK4 step (4 right-hand sides) of the reduced-coordinate simulator for the
//!   chapter's m5 (closed form and rebuilt as a multibody model), the bundled
//!   diff-drive arm (tracked wheels) and the Panda on a diff drive.
//!
//! Run: `cargo bench -p moma --bench mobile --locked`.

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use moma::closed_form::m5_mobile_manipulator::MobileManipulatorParams;
use moma::closed_form::multibody_models::m5_model;
use moma::dynamics::aba;
use moma::io::urdf::model_from_urdf_file;
use moma::mobile::DiffDrive;
use moma::mobile::reduced_forward_dynamics;
use moma::mobile::wheeled::{WheeledBase, WheeledData, WheeledModel, lagrange_multipliers};
use moma::multibody::{Data, RootJoint};
use moma::sim::Rk4;
use moma::sim::chapter_models::m5;
use moma::sim::reduced_system::ReducedSystem;
use moma::sim::settings::InputProfile;
use moma::sim::wheeled::ReducedOde;
use moma::sim::wheeled_system::WheeledSystem;
use nalgebra::DVector;

fn data(path: &str) -> String {
    format!("{}/{path}", env!("CARGO_MANIFEST_DIR"))
}

fn panda_on_diff_drive() -> WheeledModel {
    let model = model_from_urdf_file(
        data("tests/data/pinocchio/urdf/panda.urdf"),
        RootJoint::Planar,
    )
    .expect("panda");
    WheeledModel::new(
        model,
        WheeledBase::new(DiffDrive::new(0.1, 0.3, 0.2).unwrap()),
    )
    .unwrap()
}

fn diffdrive_arm() -> WheeledModel {
    let model = model_from_urdf_file(
        data("tests/data/mobile/diffdrive_arm.urdf"),
        RootJoint::Planar,
    )
    .expect("diffdrive_arm");
    let mut base = WheeledBase::new(DiffDrive::new(0.08, 0.25, 0.1).unwrap());
    base.wheel_joints = Some(["left_wheel_joint".into(), "right_wheel_joint".into()]);
    WheeledModel::new(model, base).unwrap()
}

fn m5_params() -> MobileManipulatorParams {
    // Case 0 of the chapter's m5 reference vectors.
    serde_json::from_str(
        r#"{"M_cart":24.36420141838852,"I_p":4.012069267412742,"I_c":0.042565672604483885,
        "d":0.39185270120856414,"L":0.06489388163606317,"r_w":0.09464851202565827,
        "b":0.32071159780043784,"m1":3.380025829299446,"m2":4.750664126001607,
        "M1":0.5117625576869602,"M2":2.003366116333738,"L1":0.34933150384073625,
        "L2":0.7583372254331622,"L1cm":0.1738672565909877,"L2cm":0.3550820338276041,
        "k1":0.13489344009557977,"k2":0.24513725919898224,"k1y":0.05240470818470655,
        "k2y":0.255677014167748,"g":9.81}"#,
    )
    .unwrap()
}

fn state(nq: usize, nv: usize) -> (DVector<f64>, DVector<f64>) {
    (
        DVector::from_fn(nq, |i, _| 0.3 * ((i as f64) * 1.3).sin() + 0.1),
        DVector::from_fn(nv, |i, _| 0.5 * ((i as f64) * 0.7).cos()),
    )
}

fn bench_dynamics(c: &mut Criterion) {
    let wm = panda_on_diff_drive();
    let mut wd = WheeledData::new(&wm);
    let (q, vr) = state(wm.model.nq, wm.nr());
    let u = vec![0.5; wm.nu()];
    c.bench_function("mobile/panda_diffdrive/reduced_forward_dynamics", |b| {
        b.iter(|| {
            reduced_forward_dynamics(&wm, &mut wd, black_box(&q), black_box(&vr), black_box(&u))
                .unwrap()[0]
        })
    });
    c.bench_function(
        "mobile/panda_diffdrive/reduced_forward_dynamics+lambda",
        |b| {
            b.iter(|| {
                reduced_forward_dynamics(
                    &wm,
                    &mut wd,
                    black_box(&q),
                    black_box(&vr),
                    black_box(&u),
                )
                .unwrap();
                lagrange_multipliers(&wm, &mut wd, &q).unwrap()[0]
            })
        },
    );
    let mut d = Data::new(&wm.model);
    let (_, v) = state(wm.model.nq, wm.model.nv);
    let tau = DVector::from_element(wm.model.nv, 0.5);
    c.bench_function("mobile/panda_planar_unconstrained/aba", |b| {
        b.iter(|| {
            aba(
                &wm.model,
                &mut d,
                black_box(&q),
                black_box(&v),
                black_box(&tau),
            )[0]
        })
    });
    // The two core passes the reduced fast path is built from, for the cost breakdown.
    c.bench_function("mobile/panda_planar_unconstrained/crba", |b| {
        b.iter(|| moma::dynamics::crba(&wm.model, &mut d, black_box(&q))[(0, 0)])
    });
    c.bench_function("mobile/panda_planar_unconstrained/rnea", |b| {
        b.iter(|| {
            moma::dynamics::rnea(
                &wm.model,
                &mut d,
                black_box(&q),
                black_box(&v),
                black_box(&tau),
            )[0]
        })
    });
}

fn rk4_bench(c: &mut Criterion, name: &str, sys: &mut dyn ReducedSystem, dt: f64) {
    let (nq, nv) = (sys.nq(), sys.nv());
    let (q, v) = state(nq, nv);
    let input = InputProfile::zero(sys.nu());
    let mut x: Vec<f64> = q.iter().chain(v.iter()).copied().chain([0.0]).collect();
    let x0 = x.clone();
    let mut rk = Rk4::new(nq + nv + 1);
    let mut ode = ReducedOde::new(sys, &input).unwrap();
    c.bench_function(name, |b| {
        b.iter(|| {
            x.copy_from_slice(&x0);
            rk.step(&mut ode, 0.0, &mut x, dt).unwrap();
            x[0]
        })
    });
}

fn bench_simulation(c: &mut Criterion) {
    let mut m5_cf = m5(m5_params()).unwrap();
    rk4_bench(c, "sim/m5_closed_form/rk4_step", &mut m5_cf, 1e-3);
    let mut m5_mb = WheeledSystem::new(m5_model(&m5_params()).unwrap());
    rk4_bench(c, "sim/m5_multibody/rk4_step", &mut m5_mb, 1e-3);
    let mut arm = WheeledSystem::new(diffdrive_arm());
    rk4_bench(
        c,
        "sim/diffdrive_arm_tracked_wheels/rk4_step",
        &mut arm,
        1e-3,
    );
    let massless = {
        let wm = diffdrive_arm();
        WheeledModel::new(wm.model, WheeledBase::new(wm.base.drive)).unwrap()
    };
    let mut arm2 = WheeledSystem::new(massless);
    rk4_bench(
        c,
        "sim/diffdrive_arm_massless_wheels/rk4_step",
        &mut arm2,
        1e-3,
    );
    let mut panda = WheeledSystem::new(panda_on_diff_drive());
    rk4_bench(c, "sim/panda_diffdrive/rk4_step", &mut panda, 1e-3);
}

criterion_group!(benches, bench_dynamics, bench_simulation);
criterion_main!(benches);

//! Chapter models: m5 reduced forward dynamics and simulation throughput.
//!
//! Run: `cargo bench -p moma --bench chapter --locked`.

use criterion::{Criterion, criterion_group, criterion_main};
use moma::closed_form::ConstantInputOde;
use moma::closed_form::lagrange;
use moma::closed_form::m5_mobile_manipulator::{MobileManipulator, MobileManipulatorParams};
use moma::ode::{AdaptiveOptions, Dop853, DormandPrince45, OdeSystem, Rk4};
use nalgebra::SVector;
use std::hint::black_box;

fn model() -> (
    MobileManipulator,
    SVector<f64, 6>,
    SVector<f64, 5>,
    SVector<f64, 5>,
) {
    // case 0 of the m5 reference file
    let p = MobileManipulatorParams {
        M_cart: 24.36420141838852,
        I_p: 4.012069267412742,
        I_c: 0.042565672604483885,
        d: 0.39185270120856414,
        L: 0.06489388163606317,
        r_w: 0.09464851202565827,
        b: 0.32071159780043784,
        m1: 3.380025829299446,
        m2: 4.750664126001607,
        M1: 0.5117625576869602,
        M2: 2.003366116333738,
        L1: 0.34933150384073625,
        L2: 0.7583372254331622,
        L1cm: 0.1738672565909877,
        L2cm: 0.3550820338276041,
        k1: 0.13489344009557977,
        k2: 0.24513725919898224,
        k1y: 0.05240470818470655,
        k2y: 0.255677014167748,
        g: 9.81,
    };
    let q = SVector::<f64, 6>::from_column_slice(&[
        1.3276033109095446,
        0.053031822690774444,
        -3.0010313526235466,
        2.241663450788556,
        1.1715161834864416,
        0.4273408209789179,
    ]);
    let v = SVector::<f64, 5>::from_column_slice(&[
        0.7319008449013693,
        0.06211815553794209,
        -0.11077994718546846,
        0.6387032402336714,
        -0.4599832808306971,
    ]);
    let u = SVector::<f64, 5>::from_column_slice(&[2.6, -0.13, 0.27, -1.2, 0.3]);
    (MobileManipulator::new(p).unwrap(), q, v, u)
}

fn bench(c: &mut Criterion) {
    let (m, q, v, u) = model();
    c.bench_function("m5_reduced_forward_dynamics", |b| {
        b.iter(|| {
            lagrange::state_derivative(&m, black_box(&q), black_box(&v), black_box(&u)).unwrap()
        })
    });
    c.bench_function("m5_evaluate_all_outputs", |b| {
        b.iter(|| {
            m.evaluate(black_box(&q), black_box(&v), black_box(&u))
                .unwrap()
        })
    });
    let x0: Vec<f64> = q.iter().chain(v.iter()).copied().collect();
    c.bench_function("m5_rk4_step_h1ms", |b| {
        let mut ode = ConstantInputOde {
            system: &m,
            input: u,
        };
        let mut rk = Rk4::new(ode.dim());
        let mut x = x0.clone();
        b.iter(|| {
            x.copy_from_slice(&x0);
            rk.step(&mut ode, 0.0, black_box(&mut x), 1e-3).unwrap();
        })
    });
    for tol in [1e-9, 1e-12] {
        let mut ode = ConstantInputOde {
            system: &m,
            input: u,
        };
        let mut dp = DormandPrince45::new(11, AdaptiveOptions::with_tolerance(tol)).unwrap();
        dp.solve_at(&mut ode, 0.0, &x0, &[1.0]).unwrap();
        eprintln!(
            "m5 DP45 tol {tol:e}: {} accepted, {} rejected, {} rhs evaluations per simulated second",
            dp.stats.accepted, dp.stats.rejected, dp.stats.rhs_evals
        );
        c.bench_function(&format!("m5_dp45_1s_tol{tol:e}"), |b| {
            b.iter(|| dp.solve_at(&mut ode, 0.0, black_box(&x0), &[1.0]).unwrap())
        });
    }
    for tol in [1e-9, 1e-12] {
        let mut ode = ConstantInputOde {
            system: &m,
            input: u,
        };
        let mut dp = Dop853::new(11, AdaptiveOptions::with_tolerance(tol)).unwrap();
        dp.solve_at(&mut ode, 0.0, &x0, &[1.0]).unwrap();
        eprintln!(
            "m5 DOP853 tol {tol:e}: {} accepted, {} rejected, {} rhs evaluations per simulated second",
            dp.stats.accepted, dp.stats.rejected, dp.stats.rhs_evals
        );
        c.bench_function(&format!("m5_dop853_1s_tol{tol:e}"), |b| {
            b.iter(|| dp.solve_at(&mut ode, 0.0, black_box(&x0), &[1.0]).unwrap())
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);

//! The native side of the Python batch benchmark (`crates/moma-py/bench/rnea_vs_pin.py`):
//! RNEA over 10,000 seeded states of a fixed-base URDF in a plain Rust loop, the same work
//! as one thread of `moma.rnea_batch` (RNEA, then the torques copied into a row of the
//! output); then the same states through the multi-state kernel `dynamics::rnea_batch`
//! (four states per pass), rounds interleaved with the loop's. Timed in wall-clock time
//! (`std::time::Instant`; the thread CPU time of `/proc/thread-self/schedstat` advances
//! by scheduler ticks, too coarse for a round of a few milliseconds), so run it on an idle
//! machine; medians of 31 rounds. Usage:
//! `cargo run --release --locked -p moma --example rnea_native_loop -- ROBOT.urdf`.
use moma::dynamics;
use moma::io::urdf::model_from_urdf_file;
use moma::multibody::{Data, RootJoint};
use nalgebra::DVector;

/// Nanoseconds since `t0`.
fn ns_since(t0: std::time::Instant) -> f64 {
    t0.elapsed().as_secs_f64() * 1e9
}

fn main() {
    let path = std::env::args()
        .nth(1)
        .expect("usage: rnea_native_loop ROBOT.urdf");
    let m = model_from_urdf_file(&path, RootJoint::Fixed).unwrap();
    let mut d = Data::new(&m);
    let n = 10000;
    let mut s = 1u64;
    let mut r = || {
        s = s
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    };
    let qs: Vec<DVector<f64>> = (0..n).map(|_| DVector::from_fn(m.nq, |_, _| r())).collect();
    let vs: Vec<DVector<f64>> = (0..n).map(|_| DVector::from_fn(m.nv, |_, _| r())).collect();
    let as_: Vec<DVector<f64>> = (0..n).map(|_| DVector::from_fn(m.nv, |_, _| r())).collect();
    let mut out = vec![0.0; n * m.nv];
    let flat = |x: &[DVector<f64>]| x.iter().flat_map(|r| r.iter().copied()).collect::<Vec<_>>();
    let (fq, fv, fa) = (flat(&qs), flat(&vs), flat(&as_));
    let mut batch = dynamics::BatchData::new(&m);
    let mut out_b = vec![0.0; n * m.nv];
    let (mut meds, mut meds_b) = (Vec::new(), Vec::new());
    for _ in 0..31 {
        let t0 = std::time::Instant::now();
        for k in 0..n {
            let t = dynamics::rnea(&m, &mut d, &qs[k], &vs[k], &as_[k]);
            out[k * m.nv..(k + 1) * m.nv].copy_from_slice(t.as_slice());
        }
        meds.push(ns_since(t0) / n as f64);
        let t0 = std::time::Instant::now();
        dynamics::rnea_batch(&m, &mut batch, &fq, &fv, &fa, &mut out_b);
        meds_b.push(ns_since(t0) / n as f64);
    }
    assert!(out == out_b, "the kernel's torques differ from the loop's");
    meds.sort_by(|a, b| a.partial_cmp(b).unwrap());
    meds_b.sort_by(|a, b| a.partial_cmp(b).unwrap());
    println!(
        "native rnea loop, 10,000 states, 31 rounds: median {:.0} ns/state wall (checksum {:.3})",
        meds[15],
        out.iter().sum::<f64>()
    );
    println!(
        "native rnea_batch (4 lanes), same states: median {:.0} ns/state wall ({:.2}x the loop; torques identical)",
        meds_b[15],
        meds[15] / meds_b[15]
    );
}

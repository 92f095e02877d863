//! The native side of the Python batch benchmark (`crates/moma-py/bench/rnea_vs_pin.py`):
//! RNEA over 10,000 seeded states of a fixed-base URDF in a plain Rust loop, the same work
//! as one thread of `moma.rnea_batch` (RNEA, then the torques copied into a row of the
//! output), timed in this thread's CPU time (`/proc/thread-self/schedstat`, Linux) so it
//! can run side by side with the Python figures on a shared machine; then the same states
//! through the multi-state kernel `dynamics::rnea_batch` (four states per pass), rounds
//! interleaved with the loop's. Usage:
//! `cargo run --release --locked -p moma --example rnea_native_loop -- ROBOT.urdf`.
use moma::dynamics;
use moma::io::urdf::model_from_urdf_file;
use moma::multibody::{Data, RootJoint};
use nalgebra::DVector;

/// This thread's CPU time in nanoseconds (first field of `/proc/thread-self/schedstat`).
fn cpu_ns() -> f64 {
    let t = std::fs::read_to_string("/proc/thread-self/schedstat").unwrap();
    t.split_whitespace().next().unwrap().parse::<f64>().unwrap()
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
    for _ in 0..15 {
        let t0 = cpu_ns();
        for k in 0..n {
            let t = dynamics::rnea(&m, &mut d, &qs[k], &vs[k], &as_[k]);
            out[k * m.nv..(k + 1) * m.nv].copy_from_slice(t.as_slice());
        }
        meds.push((cpu_ns() - t0) / n as f64);
        let t0 = cpu_ns();
        dynamics::rnea_batch(&m, &mut batch, &fq, &fv, &fa, &mut out_b);
        meds_b.push((cpu_ns() - t0) / n as f64);
    }
    assert!(out == out_b, "the kernel's torques differ from the loop's");
    meds.sort_by(|a, b| a.partial_cmp(b).unwrap());
    meds_b.sort_by(|a, b| a.partial_cmp(b).unwrap());
    println!(
        "native rnea loop, 10,000 states, 15 rounds: median {:.0} ns/state CPU (checksum {:.3})",
        meds[7],
        out.iter().sum::<f64>()
    );
    println!(
        "native rnea_batch (4 lanes), same states: median {:.0} ns/state CPU ({:.2}x the loop; torques identical)",
        meds_b[7],
        meds[7] / meds_b[7]
    );
}

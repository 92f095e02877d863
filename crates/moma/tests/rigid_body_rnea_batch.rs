//! The multi-state RNEA kernel (`dynamics::rnea_batch`) against the scalar `rnea`, state
//! by state and bit for bit, on Panda and UR5 (fixed base), TIAGo (planar root), ANYmal C
//! (free-flyer root, unaligned axes) and the synthetic edge-case robot (prismatic,
//! unaligned and continuous joints), for batch lengths 0, 1, L − 1, L and 3L + 1 of seeded
//! random states, on every instruction set this CPU runs (portable, AVX2, AVX-512); and
//! against Pinocchio's RNEA on the shared reference dumps.

// shared with the Pinocchio cross-checks; this file uses only part of it
mod pinocchio_common;

use moma::dynamics::{self, BatchData, BatchIsa, RNEA_LANES as L};
use moma::io::urdf::model_from_urdf_file;
use moma::multibody::{Data, JointType, Model, RootJoint};
use nalgebra::DVector;
use pinocchio_common::{Case, check, data_dir, vecf};
use rand::{Rng, SeedableRng};

fn load(urdf: &str, root: RootJoint) -> Model {
    model_from_urdf_file(data_dir().join("urdf").join(urdf), root).unwrap()
}

/// `n` seeded random states (row-major q in ±`q_range`, v, a); free-flyer quaternions are
/// random unit quaternions.
fn random_states(
    model: &Model,
    n: usize,
    seed: u64,
    q_range: f64,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let mut rng = rand::rngs::StdRng::seed_from_u64(seed);
    let mut qs = Vec::new();
    for _ in 0..n {
        let mut q: Vec<f64> = (0..model.nq)
            .map(|_| rng.random_range(-q_range..q_range))
            .collect();
        for i in 1..model.njoints {
            if matches!(model.joint_types[i], JointType::FreeFlyer) {
                let quat = &mut q[model.idx_q[i] + 3..model.idx_q[i] + 7];
                let norm = quat.iter().map(|x| x * x).sum::<f64>().sqrt();
                quat.iter_mut().for_each(|x| *x /= norm);
            }
        }
        qs.extend(q);
    }
    let mut draw =
        |len: usize| -> Vec<f64> { (0..len).map(|_| rng.random_range(-2.0..2.0)).collect() };
    let vs = draw(n * model.nv);
    let accs = draw(n * model.nv);
    (qs, vs, accs)
}

/// Runs the batch kernel on `n` random states, compiled for every instruction set this
/// CPU has, and asserts every torque equals the scalar RNEA's exactly.
fn same_as_scalar(model: &Model, what: &str) {
    for isa in BatchIsa::available() {
        same_as_scalar_on(isa, model, &format!("{what} ({isa:?})"), 3.0);
        // angles up to 2e5 rad: about half beyond `trig::REDUCED_RANGE`, where both the
        // lanes and the scalar joint take the platform's sine and cosine
        same_as_scalar_on(isa, model, &format!("{what} ({isa:?}, far angles)"), 2e5);
    }
}

fn same_as_scalar_on(isa: BatchIsa, model: &Model, what: &str, q_range: f64) {
    let (nq, nv) = (model.nq, model.nv);
    let mut batch = BatchData::new(model);
    let mut data = Data::new(model);
    for (seed, n) in [0, 1, L - 1, L, 3 * L + 1].into_iter().enumerate() {
        let (qs, vs, accs) = random_states(model, n, seed as u64 + 7, q_range);
        // a stale output must be overwritten everywhere
        let mut out = vec![f64::NAN; n * nv];
        dynamics::rnea_batch_isa(isa, model, &mut batch, &qs, &vs, &accs, &mut out);
        for r in 0..n {
            let q = DVector::from_column_slice(&qs[r * nq..(r + 1) * nq]);
            let v = DVector::from_column_slice(&vs[r * nv..(r + 1) * nv]);
            let a = DVector::from_column_slice(&accs[r * nv..(r + 1) * nv]);
            let want = dynamics::rnea(model, &mut data, &q, &v, &a);
            let got = &out[r * nv..(r + 1) * nv];
            for (k, (g, w)) in got.iter().zip(want.iter()).enumerate() {
                assert!(
                    g.to_bits() == w.to_bits(),
                    "{what}: batch of {n}, row {r}, tau[{k}]: {g:e} != scalar {w:e}"
                );
            }
        }
    }
}

#[test]
fn panda_batch_is_the_scalar_rnea() {
    same_as_scalar(&load("panda.urdf", RootJoint::Fixed), "panda");
}

#[test]
fn ur5_batch_is_the_scalar_rnea() {
    same_as_scalar(&load("ur5_robot.urdf", RootJoint::Fixed), "ur5");
}

#[test]
fn tiago_planar_batch_is_the_scalar_rnea() {
    same_as_scalar(&load("tiago.urdf", RootJoint::Planar), "tiago planar");
}

#[test]
fn anymal_free_flyer_batch_is_the_scalar_rnea() {
    same_as_scalar(
        &load("anymal_c.urdf", RootJoint::FreeFlyer),
        "anymal free-flyer",
    );
}

#[test]
fn edge_cases_batch_is_the_scalar_rnea() {
    let model = load("edge_general.urdf", RootJoint::Planar);
    let kinds: Vec<_> = model.joint_types.iter().map(|j| j.name()).collect();
    assert!(
        kinds.contains(&"prismatic_unaligned") || kinds.iter().any(|k| k.starts_with("prismatic"))
    );
    same_as_scalar(&model, "edge_general planar");
}

/// All the states of a reference dump in one batch, against Pinocchio's RNEA.
fn matches_pinocchio(file: &str, root: RootJoint) {
    let case = Case::load(file, root);
    case.check_structure();
    let (mut qs, mut vs, mut accs, mut want) = (vec![], vec![], vec![], vec![]);
    case.compare_states(|_, st, _| {
        qs.extend(st.q.iter());
        vs.extend(st.v.iter());
        accs.extend(st.a.iter());
        want.extend((st.t.transpose() * DVector::from_vec(vecf(&st.s["rnea_tau"]))).iter());
    });
    let model = &case.model;
    let mut out = vec![0.0; want.len()];
    dynamics::rnea_batch(model, &mut BatchData::new(model), &qs, &vs, &accs, &mut out);
    check(&format!("{file} rnea_batch"), &out, &want);
}

#[test]
fn batch_matches_pinocchio_dumps() {
    matches_pinocchio("panda.json", RootJoint::Fixed);
    matches_pinocchio("tiago_planar.json", RootJoint::Planar);
    matches_pinocchio("tiago_freeflyer.json", RootJoint::FreeFlyer);
}

#[test]
#[should_panic(expected = "not a multiple of nq")]
fn ragged_rows_panic() {
    let model = load("panda.urdf", RootJoint::Fixed);
    let mut out = vec![0.0; model.nv];
    let q = vec![0.0; model.nq + 1];
    let v = vec![0.0; model.nv];
    dynamics::rnea_batch(&model, &mut BatchData::new(&model), &q, &v, &v, &mut out);
}

//! The analytical derivatives of RNEA and ABA (`dynamics::rnea_derivatives`,
//! `dynamics::aba_derivatives`) against Pinocchio 4.1's `computeRNEADerivatives` and
//! `computeABADerivatives` (the reference files of `tests/data/derivatives/`, in
//! Pinocchio's layout: the chain rule of `PinocchioLayout::*_derivatives_to_pinocchio` is
//! under test too), and against central finite differences of moma's own RNEA and ABA in
//! moma's layout (q moved by `kinematics::integrate`).

mod pinocchio_common;

use moma::dynamics::{self, DerivativeData};
use moma::io::pinocchio_layout::PinocchioLayout;
use moma::io::urdf::model_from_urdf_file;
use moma::kinematics;
use moma::multibody::{Data, Model, RootJoint};
use nalgebra::{DMatrix, DVector};
use pinocchio_common::{matf, rel_err, root_of, vecf};
use rand::{Rng, SeedableRng};
use serde_json::Value;
use std::path::PathBuf;

fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

/// Runs one reference file through the library and the layout's chain rule; returns the
/// worst relative error.
fn run_reference(file: &str) -> f64 {
    let path = data_dir().join("derivatives").join(file);
    let doc: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let urdf = path.parent().unwrap().join(doc["urdf"].as_str().unwrap());
    let model = model_from_urdf_file(&urdf, root_of(doc["root"].as_str().unwrap())).unwrap();
    assert_eq!(model.nv, doc["nv"].as_u64().unwrap() as usize, "{file}: nv");
    let layout = PinocchioLayout::new(&model);
    assert_eq!(
        layout.nq(),
        doc["nq"].as_u64().unwrap() as usize,
        "{file}: nq"
    );
    let nv = model.nv;
    let mut dd = DerivativeData::new(&model);
    let mut worst: f64 = 0.0;
    let states = doc["states"].as_array().unwrap();
    assert!(!states.is_empty());
    for (n, s) in states.iter().enumerate() {
        let mut q = DVector::zeros(model.nq);
        layout
            .q_from_pinocchio(&vecf(&s["q"]), q.as_mut_slice())
            .unwrap();
        let (vp, ap, tp) = (vecf(&s["v"]), vecf(&s["a"]), vecf(&s["tau"]));
        let (mut v, mut a, mut tau) = (DVector::zeros(nv), DVector::zeros(nv), DVector::zeros(nv));
        layout.v_from_pinocchio(q.as_slice(), &vp, v.as_mut_slice());
        layout.a_from_pinocchio(q.as_slice(), v.as_slice(), &ap, a.as_mut_slice());
        layout.tau_from_pinocchio(q.as_slice(), &tp, tau.as_mut_slice());

        dynamics::rnea_derivatives(&model, &mut dd, &q, &v, &a);
        let (mut dq, mut dv, mut da) = (
            dd.drnea_dq.clone(),
            dd.drnea_dv.clone(),
            dd.drnea_da.clone(),
        );
        layout.rnea_derivatives_to_pinocchio(
            q.as_slice(),
            v.as_slice(),
            a.as_slice(),
            dd.tau.as_slice(),
            &mut dq,
            &mut dv,
            &mut da,
        );
        dynamics::aba_derivatives(&model, &mut dd, &q, &v, &tau).unwrap();
        let (mut bq, mut bv, mut bt) =
            (dd.daba_dq.clone(), dd.daba_dv.clone(), dd.daba_dtau.clone());
        layout.aba_derivatives_to_pinocchio(
            q.as_slice(),
            v.as_slice(),
            tau.as_slice(),
            dd.ddq.as_slice(),
            &mut bq,
            &mut bv,
            &mut bt,
        );
        for (key, got) in [
            ("drnea_dq", &dq),
            ("drnea_dv", &dv),
            ("drnea_da", &da),
            ("daba_dq", &bq),
            ("daba_dv", &bv),
            ("daba_dtau", &bt),
        ] {
            let want = matf(&s[key]);
            let e = rel_err(got, &want);
            assert!(e <= 1e-8, "{file} state {n} {key}: relative error {e:e}");
            worst = worst.max(e);
        }
    }
    worst
}

#[test]
fn shared_panda_reference() {
    run_reference("panda.json");
}

#[test]
fn panda_on_every_root() {
    for f in [
        "panda_fixed.json",
        "panda_planar.json",
        "panda_freeflyer.json",
    ] {
        run_reference(f);
    }
}

#[test]
fn ur5_on_every_root() {
    for f in ["ur5_fixed.json", "ur5_planar.json", "ur5_freeflyer.json"] {
        run_reference(f);
    }
}

#[test]
fn tiago_with_continuous_wheels_on_every_root() {
    for f in [
        "tiago_fixed.json",
        "tiago_planar.json",
        "tiago_freeflyer.json",
    ] {
        run_reference(f);
    }
}

fn load(urdf: &str, root: RootJoint) -> Model {
    model_from_urdf_file(data_dir().join("pinocchio/urdf").join(urdf), root).unwrap()
}

/// Central differences (step h) of `f` along q ⊕ (±h e_j) and along the nv-vector `x`.
fn fd_q(
    model: &Model,
    q: &DVector<f64>,
    h: f64,
    mut f: impl FnMut(&DVector<f64>) -> DVector<f64>,
) -> DMatrix<f64> {
    let nv = model.nv;
    let mut out = DMatrix::zeros(nv, nv);
    let (mut qp, mut qm) = (q.clone(), q.clone());
    for j in 0..nv {
        let mut e = DVector::zeros(nv);
        e[j] = h;
        kinematics::integrate(model, q, &e, &mut qp);
        kinematics::integrate(model, q, &(-&e), &mut qm);
        out.set_column(j, &((f(&qp) - f(&qm)) / (2.0 * h)));
    }
    out
}

fn fd_vec(
    x: &DVector<f64>,
    h: f64,
    mut f: impl FnMut(&DVector<f64>) -> DVector<f64>,
) -> DMatrix<f64> {
    let n = x.len();
    let mut out = DMatrix::zeros(n, n);
    for j in 0..n {
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[j] += h;
        xm[j] -= h;
        out.set_column(j, &((f(&xp) - f(&xm)) / (2.0 * h)));
    }
    out
}

/// Every derivative of both functions against central differences of moma's own RNEA and
/// ABA, in moma's layout (planar root: world-axes velocity, q + δq).
fn finite_differences(urdf: &str, root: RootJoint, seed: u64) {
    let model = load(urdf, root);
    let nv = model.nv;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut data = Data::new(&model);
    let mut dd = DerivativeData::new(&model);
    for _ in 0..2 {
        let q = kinematics::random_configuration(&model, &mut rng);
        let mut rand_vec = || DVector::from_fn(nv, |_, _| rng.random_range(-1.0..1.0));
        let (v, a, tau) = (rand_vec(), rand_vec(), rand_vec());
        dynamics::rnea_derivatives(&model, &mut dd, &q, &v, &a);
        let h = 1e-6;
        let dq = fd_q(&model, &q, h, |q| {
            dynamics::rnea(&model, &mut data, q, &v, &a).clone()
        });
        let dv = fd_vec(&v, h, |v| {
            dynamics::rnea(&model, &mut data, &q, v, &a).clone()
        });
        let da = fd_vec(&a, h, |a| {
            dynamics::rnea(&model, &mut data, &q, &v, a).clone()
        });
        let tau_rnea = dynamics::rnea(&model, &mut data, &q, &v, &a).clone();
        assert!((&dd.tau - tau_rnea).amax() < 1e-9, "{urdf} {root:?}: tau");
        let tol = 1e-6;
        for (what, got, want) in [
            ("drnea_dq", &dd.drnea_dq, &dq),
            ("drnea_dv", &dd.drnea_dv, &dv),
            ("drnea_da", &dd.drnea_da, &da),
        ] {
            let e = rel_err(got, want);
            assert!(e < tol, "{urdf} {root:?} {what}: relative error {e:e}");
        }
        let mass = dynamics::crba(&model, &mut data, &q).clone();
        assert!(
            rel_err(&dd.drnea_da, &mass) < 1e-12,
            "{urdf} {root:?}: H = CRBA"
        );

        dynamics::aba_derivatives(&model, &mut dd, &q, &v, &tau).unwrap();
        let ddq = dynamics::aba(&model, &mut data, &q, &v, &tau).clone();
        // q̈ by the LᵀDL solve of the derivative passes against ABA: the same to rounding
        let e = (&dd.ddq - &ddq).amax() / ddq.amax().max(1.0);
        assert!(e < 1e-11, "{urdf} {root:?}: ddq relative error {e:e}");
        let h = 1e-6;
        let bq = fd_q(&model, &q, h, |q| {
            dynamics::aba(&model, &mut data, q, &v, &tau).clone()
        });
        let bv = fd_vec(&v, h, |v| {
            dynamics::aba(&model, &mut data, &q, v, &tau).clone()
        });
        let bt = fd_vec(&tau, h, |t| {
            dynamics::aba(&model, &mut data, &q, &v, t).clone()
        });
        for (what, got, want) in [
            ("daba_dq", &dd.daba_dq, &bq),
            ("daba_dv", &dd.daba_dv, &bv),
            ("daba_dtau", &dd.daba_dtau, &bt),
        ] {
            let e = rel_err(got, want);
            assert!(e < 1e-5, "{urdf} {root:?} {what}: relative error {e:e}");
        }
        // H⁻¹ H = 1
        let id = &dd.daba_dtau * &mass;
        assert!(
            rel_err(&id, &DMatrix::identity(nv, nv)) < 1e-6,
            "{urdf} {root:?}: H⁻¹H"
        );
    }
}

#[test]
fn finite_differences_panda() {
    for root in [RootJoint::Fixed, RootJoint::Planar, RootJoint::FreeFlyer] {
        finite_differences("panda.urdf", root, 11);
    }
}

#[test]
fn finite_differences_ur5() {
    for root in [RootJoint::Fixed, RootJoint::Planar, RootJoint::FreeFlyer] {
        finite_differences("ur5_robot.urdf", root, 12);
    }
}

#[test]
fn finite_differences_tiago() {
    for root in [RootJoint::Fixed, RootJoint::Planar] {
        finite_differences("tiago.urdf", root, 13);
    }
}

/// moma's synthetic edge cases: unaligned and negative axes, a continuous joint with
/// limits, a zero-mass link, rotated fixed-joint chains.
#[test]
fn finite_differences_edge_cases() {
    for root in [RootJoint::Fixed, RootJoint::Planar, RootJoint::FreeFlyer] {
        finite_differences("edge_general.urdf", root, 14);
    }
}

/// The inverse chain rule undoes the forward one (the library uses the inverse, the CLI
/// the forward).
#[test]
fn layout_chain_rule_round_trip() {
    let model = load("panda.urdf", RootJoint::Planar);
    let layout = PinocchioLayout::new(&model);
    let nv = model.nv;
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let q = kinematics::random_configuration(&model, &mut rng);
    let mut r = || DVector::from_fn(nv, |_, _| rng.random_range(-1.0..1.0));
    let (v, a, tau) = (r(), r(), r());
    let m0: Vec<DMatrix<f64>> = (0..3)
        .map(|k| DMatrix::from_fn(nv, nv, |i, j| ((i * 7 + j * 3 + k) % 11) as f64 - 5.0))
        .collect();
    let (mut x, mut y, mut z) = (m0[0].clone(), m0[1].clone(), m0[2].clone());
    let (qs, vs, as_, ts) = (q.as_slice(), v.as_slice(), a.as_slice(), tau.as_slice());
    layout.rnea_derivatives_to_pinocchio(qs, vs, as_, ts, &mut x, &mut y, &mut z);
    assert!(rel_err(&x, &m0[0]) > 1e-3, "the heading must act");
    layout.rnea_derivatives_from_pinocchio(qs, vs, as_, ts, &mut x, &mut y, &mut z);
    for (got, want) in [(&x, &m0[0]), (&y, &m0[1]), (&z, &m0[2])] {
        assert!(rel_err(got, want) < 1e-13);
    }
}

//! The space module against its references: Pinocchio's momentum / Jacobian / CRBA values
//! for Panda as a free flyer, SpaceDyn's generalized Jacobian on the planar two-link arm,
//! the dynamic-singularity values, and identities any free-floating system must satisfy
//! (momentum map, drift term, Schur complement, attitude invariance).

use moma::dynamics;
use moma::io::urdf::model_from_urdf_file;
use moma::kinematics::{self, ReferenceFrame};
use moma::multibody::{Data, Model, RootJoint};
use moma::space::{self, SpaceData};
use moma::spatial::Force;
use nalgebra::{DVector, Matrix6xX, Vector3};
use rand::{Rng, SeedableRng};
use serde_json::Value;

fn data_dir() -> std::path::PathBuf {
    std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

fn load(name: &str) -> Value {
    let p = data_dir().join("space").join(name);
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn planar() -> Model {
    let mut m = model_from_urdf_file(
        data_dir().join("space/planar2link.urdf"),
        RootJoint::FreeFlyer,
    )
    .unwrap();
    m.gravity = Vector3::zeros();
    m
}

fn panda() -> Model {
    let mut m = model_from_urdf_file(
        data_dir().join("pinocchio/urdf/panda.urdf"),
        RootJoint::FreeFlyer,
    )
    .unwrap();
    m.gravity = Vector3::zeros();
    m
}

/// q of the planar robot with the base at the origin, attitude identity.
fn planar_q(q1: f64, q2: f64) -> DVector<f64> {
    DVector::from_vec(vec![0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0, q1, q2])
}

fn force(lin: &[f64], ang: &[f64]) -> Force {
    Force::new(
        Vector3::from_column_slice(lin),
        Vector3::from_column_slice(ang),
    )
}

#[test]
fn panda_free_flyer_matches_pinocchio() {
    let doc = load("multibody_public.json");
    let model = panda();
    let mut data = Data::new(&model);
    let mut sd = SpaceData::new(&model).unwrap();
    let mut worst: f64 = 0.0;
    let mut check = |what: &str, got: &[f64], want: &[f64]| {
        assert_eq!(got.len(), want.len(), "{what}");
        for (i, (a, b)) in got.iter().zip(want).enumerate() {
            let e = (a - b).abs();
            worst = worst.max(e);
            assert!(e < 1e-10, "{what}[{i}]: {a} vs {b}");
        }
    };
    for case in doc["cases"].as_array().unwrap() {
        let st = &case["state"];
        let q = DVector::from_vec(nums(&st["q"]));
        let qd = nums(&st["qdot_joints"]);
        let h = force(
            &nums(&st["momentum"]["linear"]),
            &nums(&st["momentum"]["angular_about_com"]),
        );
        let frame = model.frame_id(case["frame"].as_str().unwrap()).unwrap();
        let ex = &case["expected"];
        let vb = space::base_velocity(&model, &mut data, &mut sd, &q, &qd, &h).unwrap();
        check(
            "total_mass",
            &[sd.total_mass],
            &[ex["total_mass"].as_f64().unwrap()],
        );
        check("com", sd.com.as_slice(), &nums(&ex["com"]));
        check(
            "base_velocity",
            vb.to_vector().as_slice(),
            &nums(&ex["base_velocity"]),
        );
        check("v", sd.v.as_slice(), &nums(&ex["v"]));
        let v = sd.v.clone();
        space::generalized_jacobian(&model, &mut data, &mut sd, &q, frame).unwrap();
        for (r, row) in ex["generalized_jacobian"]
            .as_array()
            .unwrap()
            .iter()
            .enumerate()
        {
            let got: Vec<f64> = sd.generalized_jacobian.row(r).iter().copied().collect();
            check("generalized_jacobian", &got, &nums(row));
        }
        let xf = space::frame_velocity(&sd, &qd, &h);
        check(
            "frame_velocity",
            xf.as_slice(),
            &nums(&ex["frame_velocity"]),
        );
        // the same velocity from the full Jacobian and the full v
        let full = &sd.frame_jacobian * &v;
        check("J v", full.as_slice(), xf.as_slice());
        let hs = space::generalized_inertia(&model, &mut data, &mut sd, &q).unwrap();
        for (r, row) in ex["generalized_inertia"]
            .as_array()
            .unwrap()
            .iter()
            .enumerate()
        {
            let got: Vec<f64> = hs.row(r).iter().copied().collect();
            check("generalized_inertia", &got, &nums(row));
        }
        // the momentum of the reconstructed state is the requested one
        let hm = space::momentum(&model, &mut data, &q, &v);
        check(
            "momentum",
            hm.to_vector().as_slice(),
            h.to_vector().as_slice(),
        );
    }
    eprintln!("worst |moma − Pinocchio| = {worst:e}");
}

#[test]
fn generalized_jacobian_matches_spacedyn() {
    let doc = load("spacedyn_gj_planar2link.json");
    let model = planar();
    let mut data = Data::new(&model);
    let mut sd = SpaceData::new(&model).unwrap();
    let ee = model.frame_id("end_point").unwrap();
    for case in doc["cases"].as_array().unwrap() {
        let qj = nums(&case["q"]);
        let qd = nums(&case["qd"]);
        let q = planar_q(qj[0], qj[1]);
        let gj = space::generalized_jacobian(&model, &mut data, &mut sd, &q, ee).unwrap();
        let rows = case["GJ_rows_vx_vy_wz"].as_array().unwrap();
        for (r, want) in [0usize, 1, 5].iter().zip(rows) {
            let want = nums(want);
            for k in 0..2 {
                assert!(
                    (gj[(*r, k)] - want[k]).abs() < 1e-12,
                    "J*[{r},{k}] = {} vs SpaceDyn {}",
                    gj[(*r, k)],
                    want[k]
                );
            }
        }
        // out-of-plane rows vanish
        for r in [2usize, 3, 4] {
            assert!(gj.row(r).norm() < 1e-14);
        }
        let p = sd.frame_position;
        let want_p = nums(&case["end_point"]);
        assert!((p - Vector3::from_column_slice(&want_p)).norm() < 1e-13);
        let xe = space::frame_velocity(&sd, &qd, &Force::zero());
        let want = nums(&case["end_velocity_GJ_qd"]);
        for i in 0..6 {
            assert!((xe[i] - want[i]).abs() < 1e-12, "ẋ_e[{i}]");
        }
        // base twist: SpaceDyn's v0 is the base CoM velocity (here the base origin), world
        let vb = space::base_velocity(&model, &mut data, &mut sd, &q, &qd, &Force::zero()).unwrap();
        let v0 = nums(&case["base_v0"]);
        let w0 = nums(&case["base_w0"]);
        for i in 0..3 {
            assert!((vb.linear[i] - v0[i]).abs() < 1e-12, "v0[{i}]");
            assert!((vb.angular[i] - w0[i]).abs() < 1e-12, "w0[{i}]");
        }
    }
}

#[test]
fn dynamic_singularities_of_the_planar_arm() {
    let doc = load("free_floating_dynamic_singularity.json");
    let model = planar();
    let mut data = Data::new(&model);
    let mut sd = SpaceData::new(&model).unwrap();
    let ee = model.frame_id("end_point").unwrap();
    let det2 = |m: &Matrix6xX<f64>, off: usize| {
        m[(0, off)] * m[(1, off + 1)] - m[(0, off + 1)] * m[(1, off)]
    };
    for spot in doc["spot_values"].as_array().unwrap() {
        let qj = nums(&spot["q"]);
        let q = planar_q(qj[0], qj[1]);
        let s = space::dynamic_singularity(&model, &mut data, &mut sd, &q, ee).unwrap();
        let dg = det2(&sd.generalized_jacobian, 0);
        let df = det2(&sd.frame_jacobian, 6);
        let want_g = spot["det_GJ_pos"].as_f64().unwrap();
        let want_f = spot["det_fixed_base_pos"].as_f64().unwrap();
        assert!(
            (dg - want_g).abs() < 1e-12,
            "det J*_pos at {qj:?}: {dg} vs {want_g}"
        );
        assert!(
            (df - want_f).abs() < 1e-12,
            "det J_pos at {qj:?}: {df} vs {want_f}"
        );
        // for a planar 3 × 2 block |det| = σ1 σ2
        assert!(s.det_generalized.is_none());
        if want_g == 0.0 {
            assert!(s.sigma_min_generalized < 1e-9);
        } else {
            assert!(s.sigma_min_generalized > 1e-3);
        }
    }
    // (1, 0): fixed-base singular, J* regular — the reverse of a dynamic singularity
    let s =
        space::dynamic_singularity(&model, &mut data, &mut sd, &planar_q(1.0, 0.0), ee).unwrap();
    assert!(s.sigma_min_fixed_base < 1e-12 && s.sigma_min_generalized > 1e-2);
    for z in doc["zero_set"].as_array().unwrap() {
        let q1 = z["q1"].as_f64().unwrap();
        for (q2, fdet) in nums(&z["q2_roots"])
            .iter()
            .zip(nums(&z["fixed_base_det_at_roots"]))
        {
            let q = planar_q(q1, *q2);
            let s = space::dynamic_singularity(&model, &mut data, &mut sd, &q, ee).unwrap();
            assert!(det2(&sd.generalized_jacobian, 0).abs() < 1e-10);
            assert!((det2(&sd.frame_jacobian, 6) - fdet).abs() < 1e-10);
            assert!(s.is_dynamic_singularity(1e-9), "{q1}, {q2}: {s:?}");
        }
    }
}

#[test]
fn momentum_identities_on_random_states() {
    let model = panda();
    let mut data = Data::new(&model);
    let mut sd = SpaceData::new(&model).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(12);
    let frame = model.frame_id("panda_hand_tcp").unwrap();
    let n = model.nv - 6;
    for _ in 0..20 {
        let q = kinematics::random_configuration(&model, &mut rng);
        let qd: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
        let lin: Vec<f64> = (0..3).map(|_| rng.random_range(-2.0..2.0)).collect();
        let ang: Vec<f64> = (0..3).map(|_| rng.random_range(-2.0..2.0)).collect();
        for h in [Force::zero(), force(&lin, &ang)] {
            // 1. the base twist reproduces the momentum
            space::base_velocity(&model, &mut data, &mut sd, &q, &qd, &h).unwrap();
            let v = sd.v.clone();
            let hm = space::momentum(&model, &mut data, &q, &v);
            assert!((hm.to_vector() - h.to_vector()).norm() < 1e-11);
            // 7. frame velocity = J* q̇ + drift, exactly the drift apart from J* q̇
            space::generalized_jacobian(&model, &mut data, &mut sd, &q, frame).unwrap();
            let xf = &sd.frame_jacobian * &v;
            let xs = space::frame_velocity(&sd, &qd, &h);
            assert!((xf - xs).norm() < 1e-12);
            let d = space::momentum_drift(&sd, &h);
            let jq = &sd.generalized_jacobian * DVector::from_column_slice(&qd);
            assert!((xs - jq - d).norm() < 1e-13);
        }
        // 3. H* symmetric positive definite and T = ½ q̇ᵀ H* q̇ at zero momentum
        space::base_velocity(&model, &mut data, &mut sd, &q, &qd, &Force::zero()).unwrap();
        let v = sd.v.clone();
        let t = dynamics::kinetic_energy(&model, &mut data, &q, &v);
        let hs = space::generalized_inertia(&model, &mut data, &mut sd, &q)
            .unwrap()
            .clone();
        let qdv = DVector::from_column_slice(&qd);
        assert!((0.5 * qdv.dot(&(&hs * &qdv)) - t).abs() < 1e-12 * t.max(1.0));
        assert!((&hs - hs.transpose()).norm() < 1e-14);
        assert!(hs.clone().cholesky().is_some());
    }
}

#[test]
fn attitude_invariance() {
    // J*(q, R0) = blockdiag(R0, R0) J*(q, I); the base position does not matter either.
    let model = panda();
    let mut data = Data::new(&model);
    let mut sd = SpaceData::new(&model).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let frame = model.frame_id("panda_hand_tcp").unwrap();
    for _ in 0..5 {
        let mut q = kinematics::random_configuration(&model, &mut rng);
        let mut q_id = q.clone();
        for i in 0..6 {
            q_id[i] = 0.0;
        }
        q_id[6] = 1.0;
        let j0 = space::generalized_jacobian(&model, &mut data, &mut sd, &q_id, frame)
            .unwrap()
            .clone();
        let s0 = space::dynamic_singularity(&model, &mut data, &mut sd, &q_id, frame).unwrap();
        q[0] = 3.0;
        let j = space::generalized_jacobian(&model, &mut data, &mut sd, &q, frame)
            .unwrap()
            .clone();
        let r = data.world_from_joint[1].rotation;
        let mut rot = Matrix6xX::zeros(j0.ncols());
        for k in 0..j0.ncols() {
            let c = j0.column(k);
            let l = r * Vector3::new(c[0], c[1], c[2]);
            let a = r * Vector3::new(c[3], c[4], c[5]);
            rot.column_mut(k)
                .copy_from_slice(&[l.x, l.y, l.z, a.x, a.y, a.z]);
        }
        assert!((j - rot).norm() < 1e-12);
        let s = space::dynamic_singularity(&model, &mut data, &mut sd, &q, frame).unwrap();
        assert!((s.sigma_min_generalized - s0.sigma_min_generalized).abs() < 1e-12);
    }
}

#[test]
fn rejects_models_without_a_free_flyer_root() {
    let m = model_from_urdf_file(
        data_dir().join("pinocchio/urdf/panda.urdf"),
        RootJoint::Fixed,
    )
    .unwrap();
    let e = SpaceData::new(&m).unwrap_err();
    assert!(e.to_string().contains("free flyer"), "{e}");
    let m = model_from_urdf_file(
        data_dir().join("pinocchio/urdf/panda.urdf"),
        RootJoint::Planar,
    )
    .unwrap();
    assert!(SpaceData::new(&m).is_err());
}

#[test]
fn frame_jacobian_is_consistent_with_kinematics() {
    // the frame Jacobian kept in SpaceData is the ordinary LOCAL_WORLD_ALIGNED one
    let model = panda();
    let mut data = Data::new(&model);
    let mut sd = SpaceData::new(&model).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let frame = model.frame_id("panda_link7").unwrap();
    let q = kinematics::random_configuration(&model, &mut rng);
    space::generalized_jacobian(&model, &mut data, &mut sd, &q, frame).unwrap();
    let mut j = Matrix6xX::zeros(model.nv);
    kinematics::frame_jacobian(
        &model,
        &mut data,
        &q,
        frame,
        ReferenceFrame::LocalWorldAligned,
        &mut j,
    );
    assert!((j - &sd.frame_jacobian).norm() < 1e-15);
}

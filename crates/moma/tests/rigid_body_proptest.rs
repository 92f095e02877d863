//! Property tests over random configurations of random small trees built with
//! `ModelBuilder`: mixed joint types (aligned and unaligned revolute and prismatic),
//! fixed, planar and free-flyer roots, random placements and inertias.

use approx::assert_relative_eq;
use moma::dynamics;
use moma::kinematics::{self, ReferenceFrame};
use moma::multibody::{Data, FrameKind, JointIndex, JointLimits, JointType, Model, ModelBuilder};
use moma::spatial::{Inertia, SE3, rotation_from_rpy};
use nalgebra::{DVector, Matrix3, Matrix6xX, Vector3};
use proptest::prelude::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const TOL: f64 = 1e-8;

fn random_model(seed: u64) -> Model {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut b = ModelBuilder::new(format!("tree{seed}"));
    let mut r3 = |rng: &mut ChaCha8Rng, s: f64| {
        Vector3::new(
            rng.random_range(-s..s),
            rng.random_range(-s..s),
            rng.random_range(-s..s),
        )
    };
    let placement = |rng: &mut ChaCha8Rng,
                     r3: &mut dyn FnMut(&mut ChaCha8Rng, f64) -> Vector3<f64>| {
        let rpy = r3(rng, 3.0);
        SE3::new(rotation_from_rpy(rpy.x, rpy.y, rpy.z), r3(rng, 0.5))
    };
    let mut joints = vec![JointIndex(0)];
    let root = rng.random_range(0..3);
    if root > 0 {
        let jt = if root == 1 {
            JointType::Planar
        } else {
            JointType::FreeFlyer
        };
        let j = b
            .add_joint(
                JointIndex(0),
                "root",
                jt,
                SE3::identity(),
                JointLimits::unlimited(),
            )
            .unwrap();
        joints.push(j);
    }
    let n = rng.random_range(1..7);
    for k in 0..n {
        let parent = joints[rng.random_range(0..joints.len())];
        let axis = r3(&mut rng, 1.0) + Vector3::new(0.0, 0.0, 0.1);
        let jt = match rng.random_range(0..8) {
            0 => JointType::RevoluteX,
            1 => JointType::RevoluteY,
            2 => JointType::RevoluteZ,
            3 | 4 => JointType::revolute(axis).unwrap(),
            5 => JointType::PrismaticZ,
            6 => JointType::PrismaticX,
            _ => JointType::prismatic(axis).unwrap(),
        };
        let pl = placement(&mut rng, &mut r3);
        let j = b
            .add_joint(parent, &format!("j{k}"), jt, pl, JointLimits::unlimited())
            .unwrap();
        joints.push(j);
    }
    // every moving joint carries a body; some also get a second, merged body (as a fixed
    // joint would) and a frame
    for (k, &j) in joints.iter().enumerate().skip(1) {
        let m = rng.random_range(0.1..3.0);
        let d = Vector3::new(
            rng.random_range(0.01..0.2),
            rng.random_range(0.01..0.2),
            rng.random_range(0.01..0.2),
        );
        let inertia = Inertia::new(m, r3(&mut rng, 0.3), Matrix3::from_diagonal(&d));
        let pl = placement(&mut rng, &mut r3);
        b.append_body_inertia(j, &inertia, &pl).unwrap();
        if rng.random_bool(0.5) {
            b.append_body_inertia(
                j,
                &Inertia::point_mass(0.5, r3(&mut rng, 0.3)),
                &SE3::identity(),
            )
            .unwrap();
        }
        let pl = placement(&mut rng, &mut r3);
        b.add_frame(
            &format!("f{k}"),
            j,
            moma::multibody::FrameIndex(0),
            pl,
            FrameKind::Operational,
        )
        .unwrap();
    }
    b.build().unwrap()
}

fn rand_vec(rng: &mut ChaCha8Rng, n: usize) -> DVector<f64> {
    DVector::from_fn(n, |_, _| rng.random_range(-1.0..1.0))
}

fn step(model: &Model, q: &DVector<f64>, v: &DVector<f64>, h: f64) -> DVector<f64> {
    let mut out = q.clone();
    kinematics::integrate(model, q, &(v * h), &mut out);
    out
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn dynamics_identities_hold_on_random_trees(seed in any::<u64>(), state_seed in any::<u64>()) {
        let model = random_model(seed);
        let mut data = Data::new(&model);
        let mut rng = ChaCha8Rng::seed_from_u64(state_seed);
        let q = kinematics::random_configuration(&model, &mut rng);
        let v = rand_vec(&mut rng, model.nv);
        let a = rand_vec(&mut rng, model.nv);
        let nv = model.nv;

        // H symmetric positive definite, columns from RNEA differences (v = 0, g = 0)
        let h = dynamics::crba(&model, &mut data, &q).clone();
        assert_relative_eq!(h.clone(), h.transpose(), epsilon = 1e-12);
        prop_assert!(h.clone().cholesky().is_some());
        let mut m0 = model.clone();
        m0.gravity = Vector3::zeros();
        let mut d0 = Data::new(&m0);
        let zero = DVector::zeros(nv);
        let t0 = dynamics::rnea(&m0, &mut d0, &q, &zero, &zero).clone();
        for j in 0..nv {
            let mut e = DVector::zeros(nv);
            e[j] = 1.0;
            let col = dynamics::rnea(&m0, &mut d0, &q, &zero, &e) - &t0;
            assert_relative_eq!(col, h.column(j).clone_owned(), epsilon = TOL, max_relative = TOL);
        }

        // ABA inverts RNEA; h = C v + g; H a + h = τ
        let tau = dynamics::rnea(&model, &mut data, &q, &v, &a).clone();
        let a2 = dynamics::aba(&model, &mut data, &q, &v, &tau).clone();
        assert_relative_eq!(a2, a.clone(), epsilon = 1e-7, max_relative = 1e-7);
        let nle = dynamics::nonlinear_effects(&model, &mut data, &q, &v).clone();
        assert_relative_eq!(&h * &a + &nle, tau, epsilon = TOL, max_relative = TOL);
        let g = dynamics::gravity_torque(&model, &mut data, &q).clone();
        let c = dynamics::coriolis_matrix(&model, &mut data, &q, &v).clone();
        assert_relative_eq!(&c * &v + &g, nle, epsilon = TOL, max_relative = TOL);

        // Ḣ = C + Cᵀ (Christoffel consistency), by central differences along q ⊕ t v
        let fd = 1e-6;
        let hp = dynamics::crba(&model, &mut data, &step(&model, &q, &v, fd)).clone();
        let hm = dynamics::crba(&model, &mut data, &step(&model, &q, &v, -fd)).clone();
        let hdot = (hp - hm) / (2.0 * fd);
        assert_relative_eq!(hdot, &c + c.transpose(), epsilon = 1e-5, max_relative = 1e-5);

        // energies
        let t = dynamics::kinetic_energy(&model, &mut data, &q, &v);
        assert_relative_eq!(t, 0.5 * v.dot(&(&h * &v)), epsilon = 1e-10, max_relative = 1e-10);

        // every frame's LWA Jacobian against finite differences of its placement
        let mut jac = Matrix6xX::zeros(nv);
        for f in 1..model.nframes() {
            let fid = moma::multibody::FrameIndex(f);
            kinematics::frame_jacobian(&model, &mut data, &q, fid, ReferenceFrame::LocalWorldAligned, &mut jac);
            let tw = &jac * &v;
            kinematics::frames_forward_kinematics(&model, &mut data, &step(&model, &q, &v, fd));
            let mp = data.world_from_frame[f];
            kinematics::frames_forward_kinematics(&model, &mut data, &step(&model, &q, &v, -fd));
            let mm = data.world_from_frame[f];
            let lin = (mp.translation - mm.translation) / (2.0 * fd);
            let ang = moma::spatial::log3(&(mp.rotation * mm.rotation.transpose())) / (2.0 * fd);
            assert_relative_eq!(lin, tw.fixed_rows::<3>(0).clone_owned(), epsilon = 1e-6);
            assert_relative_eq!(ang, tw.fixed_rows::<3>(3).clone_owned(), epsilon = 1e-6);
        }

        // integrate / difference round trip
        let mut q1 = q.clone();
        kinematics::integrate(&model, &q, &v, &mut q1);
        let mut d = DVector::zeros(nv);
        kinematics::difference(&model, &q, &q1, &mut d);
        assert_relative_eq!(d, v, epsilon = 1e-9);
    }
}

//! Each closed-form chapter model equals the general multibody model of the same robot
//! built with `ModelBuilder` (planar root q = [x, y, θ] in world axes for the platforms,
//! a prismatic root joint for the m4 cart): mass matrix (CRBA), Coriolis matrix, h and G.
//!
//! Coordinate mapping:
//! * m1, m2: the multibody coordinates are exactly the closed-form ones
//!   (`[x, y, φ]` = planar root, `θ1, θ2` revolute about z); q̇ is the same vector.
//! * m4: `[d0, θ1, θ2]` = prismatic x, revolute y (θ1 from the vertical towards +x), and a
//!   revolute joint about −y for θ2 (link 2 at θ1 − θ2 from the vertical).
//! * m5: the multibody coordinates are the JOINT coordinates `q_j = [x, y, φ, φ1, θ1, θ2]`
//!   (capstan revolute z at L ahead of the CM, shoulder revolute y, elbow revolute −y);
//!   the closed form uses `q = P q_j`. Since P is constant, `H_j = Pᵀ H P`,
//!   `C_j = Pᵀ C_cor P`, `h_j = Pᵀ h`, `G_j = Pᵀ G` with `q̇ = P q̇_j`.

use moma::closed_form::lagrange;
use moma::closed_form::m1_unicycle::{Unicycle, UnicycleParams};
use moma::closed_form::m2_platform_arm::{PlatformArm, PlatformArmParams};
use moma::closed_form::m4_cart_two_link::{CartTwoLink, CartTwoLinkParams};
use moma::closed_form::m5_mobile_manipulator::{
    MobileManipulator, MobileManipulatorParams, joint_to_absolute,
};
use moma::dynamics::{coriolis_matrix, crba, gravity_torque, nonlinear_effects};
use moma::multibody::{Data, JointIndex, JointLimits, JointType, Model, ModelBuilder, RootJoint};
use moma::spatial::{Inertia, SE3};
use nalgebra::{DMatrix, DVector, Matrix3, SMatrix, SVector, Vector3};
use serde_json::Value;

fn cases(name: &str) -> Vec<Value> {
    let path = format!(
        "{}/tests/data/chapter/{name}.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let doc: Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    doc["cases"].as_array().unwrap().clone()
}

fn vec_of<const K: usize>(v: &Value) -> SVector<f64, K> {
    let x: Vec<f64> = serde_json::from_value(v.clone()).unwrap();
    SVector::from_column_slice(&x)
}

fn t(x: f64, y: f64, z: f64) -> SE3 {
    SE3::from_translation(Vector3::new(x, y, z))
}

fn planar_root(b: &mut ModelBuilder, mass: f64, yaw_inertia: f64) -> JointIndex {
    b.set_root(RootJoint::Planar);
    let base = b
        .add_joint(
            JointIndex(0),
            "base",
            JointType::Planar,
            SE3::identity(),
            JointLimits::unlimited(),
        )
        .unwrap();
    b.append_body_inertia(
        base,
        &Inertia::new(
            mass,
            Vector3::zeros(),
            Matrix3::from_diagonal(&Vector3::new(0.0, 0.0, yaw_inertia)),
        ),
        &SE3::identity(),
    )
    .unwrap();
    base
}

struct Terms {
    h_mass: DMatrix<f64>,
    coriolis: DMatrix<f64>,
    h: DVector<f64>,
    g: DVector<f64>,
}

fn multibody_terms(model: &Model, q: &DVector<f64>, qd: &DVector<f64>) -> Terms {
    let mut data = Data::new(model);
    let h_mass = crba(model, &mut data, q).clone();
    let coriolis = coriolis_matrix(model, &mut data, q, qd).clone();
    let nle = nonlinear_effects(model, &mut data, q, qd).clone();
    let g = gravity_torque(model, &mut data, q).clone();
    Terms {
        h_mass,
        coriolis,
        h: nle - &g,
        g,
    }
}

fn close<const R: usize, const C: usize>(what: &str, a: &SMatrix<f64, R, C>, b: &DMatrix<f64>) {
    let b = SMatrix::<f64, R, C>::from_fn(|i, j| b[(i, j)]);
    let err = (a - b).norm() / (1.0 + a.norm());
    assert!(
        err < 1e-12,
        "{what}: relative error {err:e}\nclosed form {a}\nmultibody {b}"
    );
}

#[test]
fn m1_matches_multibody() {
    for c in cases("m1_unicycle") {
        let p: UnicycleParams = serde_json::from_value(c["params"].clone()).unwrap();
        let sys = Unicycle::new(p.clone()).unwrap();
        let mut b = ModelBuilder::new("m1");
        planar_root(&mut b, p.m, p.inertia);
        let model = b.build().unwrap();
        let q = vec_of::<3>(&c["state"]["q"]);
        let qd = vec_of::<3>(&c["outputs"]["qdot"]);
        let mb = multibody_terms(
            &model,
            &DVector::from_column_slice(q.as_slice()),
            &DVector::from_column_slice(qd.as_slice()),
        );
        close("m1 M", &lagrange::mass_matrix(&sys, &q), &mb.h_mass);
        assert!(mb.h.norm() < 1e-12 && mb.g.norm() < 1e-12);
    }
}

#[test]
fn m2_matches_multibody() {
    for c in cases("m2_platform_planar_arm") {
        let p: PlatformArmParams = serde_json::from_value(c["params"].clone()).unwrap();
        let sys = PlatformArm::new(p.clone()).unwrap();
        let mut b = ModelBuilder::new("m2");
        let base = planar_root(&mut b, p.m_p, p.I_p);
        let j1 = b
            .add_joint(
                base,
                "theta1",
                JointType::RevoluteZ,
                t(p.L, 0.0, 0.0),
                JointLimits::unlimited(),
            )
            .unwrap();
        let link = |m: f64, lcm: f64, k: f64| {
            Inertia::new(
                m,
                Vector3::new(lcm, 0.0, 0.0),
                Matrix3::from_diagonal(&Vector3::new(0.0, 0.0, m * k * k)),
            )
        };
        b.append_body_inertia(j1, &link(p.m1, p.L1cm, p.k1), &SE3::identity())
            .unwrap();
        b.append_body_inertia(
            j1,
            &Inertia::point_mass(p.M1, Vector3::new(p.L1, 0.0, 0.0)),
            &SE3::identity(),
        )
        .unwrap();
        let j2 = b
            .add_joint(
                j1,
                "theta2",
                JointType::RevoluteZ,
                t(p.L1, 0.0, 0.0),
                JointLimits::unlimited(),
            )
            .unwrap();
        b.append_body_inertia(j2, &link(p.m2, p.L2cm, p.k2), &SE3::identity())
            .unwrap();
        b.append_body_inertia(
            j2,
            &Inertia::point_mass(p.M2, Vector3::new(p.L2, 0.0, 0.0)),
            &SE3::identity(),
        )
        .unwrap();
        let model = b.build().unwrap();
        let q = vec_of::<5>(&c["state"]["q"]);
        let qd = vec_of::<5>(&c["outputs"]["qdot"]);
        let mb = multibody_terms(
            &model,
            &DVector::from_column_slice(q.as_slice()),
            &DVector::from_column_slice(qd.as_slice()),
        );
        let cf = lagrange::lagrange_terms(&sys, &q, &qd);
        close("m2 H", &cf.mass, &mb.h_mass);
        close("m2 C_cor", &cf.coriolis, &mb.coriolis);
        close(
            "m2 h",
            &cf.h,
            &DMatrix::from_column_slice(5, 1, mb.h.as_slice()),
        );
        assert!(mb.g.norm() < 1e-12 && cf.gravity.norm() < 1e-12);
    }
}

/// Two pitching links along +z of their joint frames: shoulder revolute y (θ1), elbow
/// revolute −y (θ2), so link 2 is at θ1 − θ2 from the vertical.
#[allow(clippy::too_many_arguments)]
fn vertical_arm(
    b: &mut ModelBuilder,
    parent: JointIndex,
    shoulder: SE3,
    (m1, m2, big_m1, big_m2): (f64, f64, f64, f64),
    (l1, l2, l1cm, l2cm): (f64, f64, f64, f64),
    (k1, k2, k1y, k2y): (f64, f64, f64, f64),
) {
    let link = |m: f64, lcm: f64, k: f64, ky: f64| {
        Inertia::new(
            m,
            Vector3::new(0.0, 0.0, lcm),
            Matrix3::from_diagonal(&Vector3::new(m * ky * ky, m * k * k, 0.0)),
        )
    };
    let j1 = b
        .add_joint(
            parent,
            "shoulder",
            JointType::RevoluteY,
            shoulder,
            JointLimits::unlimited(),
        )
        .unwrap();
    b.append_body_inertia(j1, &link(m1, l1cm, k1, k1y), &SE3::identity())
        .unwrap();
    b.append_body_inertia(
        j1,
        &Inertia::point_mass(big_m1, Vector3::new(0.0, 0.0, l1)),
        &SE3::identity(),
    )
    .unwrap();
    let elbow = JointType::revolute(Vector3::new(0.0, -1.0, 0.0)).unwrap();
    let j2 = b
        .add_joint(
            j1,
            "elbow",
            elbow,
            t(0.0, 0.0, l1),
            JointLimits::unlimited(),
        )
        .unwrap();
    b.append_body_inertia(j2, &link(m2, l2cm, k2, k2y), &SE3::identity())
        .unwrap();
    b.append_body_inertia(
        j2,
        &Inertia::point_mass(big_m2, Vector3::new(0.0, 0.0, l2)),
        &SE3::identity(),
    )
    .unwrap();
}

#[test]
fn m4_matches_multibody_with_prismatic_root() {
    for c in cases("m4_cart_two_link") {
        let p: CartTwoLinkParams = serde_json::from_value(c["params"].clone()).unwrap();
        let sys = CartTwoLink::new(p.clone()).unwrap();
        let mut b = ModelBuilder::new("m4");
        b.set_gravity(Vector3::new(0.0, 0.0, -p.g));
        let cart = b
            .add_joint(
                JointIndex(0),
                "d0",
                JointType::PrismaticX,
                SE3::identity(),
                JointLimits::unlimited(),
            )
            .unwrap();
        b.append_body_inertia(
            cart,
            &Inertia::point_mass(p.M_cart, Vector3::zeros()),
            &SE3::identity(),
        )
        .unwrap();
        // k_y is irrelevant in the vertical plane (no rotation about the vertical)
        vertical_arm(
            &mut b,
            cart,
            SE3::identity(),
            (p.m1, p.m2, p.M1, p.M2),
            (p.L1, p.L2, p.L1cm, p.L2cm),
            (p.k1, p.k2, 0.0, 0.0),
        );
        let model = b.build().unwrap();
        let q = vec_of::<3>(&c["state"]["q"]);
        let qd = vec_of::<3>(&c["state"]["qdot"]);
        let mb = multibody_terms(
            &model,
            &DVector::from_column_slice(q.as_slice()),
            &DVector::from_column_slice(qd.as_slice()),
        );
        let cf = lagrange::lagrange_terms(&sys, &q, &qd);
        close("m4 H", &cf.mass, &mb.h_mass);
        close("m4 C_cor", &cf.coriolis, &mb.coriolis);
        close(
            "m4 h",
            &cf.h,
            &DMatrix::from_column_slice(3, 1, mb.h.as_slice()),
        );
        close(
            "m4 G",
            &cf.gravity,
            &DMatrix::from_column_slice(3, 1, mb.g.as_slice()),
        );
    }
}

#[test]
fn m5_matches_multibody_in_joint_coordinates() {
    let pm = joint_to_absolute();
    let pinv = pm.try_inverse().unwrap();
    for c in cases("m5_mobile_manipulator_3d") {
        let p: MobileManipulatorParams = serde_json::from_value(c["params"].clone()).unwrap();
        let sys = MobileManipulator::new(p.clone()).unwrap();
        let mut b = ModelBuilder::new("m5");
        b.set_gravity(Vector3::new(0.0, 0.0, -p.g));
        let base = planar_root(&mut b, p.M_cart, p.I_p);
        let cap = b
            .add_joint(
                base,
                "capstan",
                JointType::RevoluteZ,
                t(p.L, 0.0, 0.0),
                JointLimits::unlimited(),
            )
            .unwrap();
        b.append_body_inertia(
            cap,
            &Inertia::new(
                0.0,
                Vector3::zeros(),
                Matrix3::from_diagonal(&Vector3::new(0.0, 0.0, p.I_c)),
            ),
            &SE3::identity(),
        )
        .unwrap();
        vertical_arm(
            &mut b,
            cap,
            SE3::identity(),
            (p.m1, p.m2, p.M1, p.M2),
            (p.L1, p.L2, p.L1cm, p.L2cm),
            (p.k1, p.k2, p.k1y, p.k2y),
        );
        let model = b.build().unwrap();
        let q = vec_of::<6>(&c["state"]["q"]);
        let qd = vec_of::<6>(&c["outputs"]["qdot"]);
        let qj = pinv * q;
        let qjd = pinv * qd;
        let reference_qj = vec_of::<6>(&c["state"]["q_joint"]);
        assert!((qj - reference_qj).norm() < 1e-12);
        let mb = multibody_terms(
            &model,
            &DVector::from_column_slice(qj.as_slice()),
            &DVector::from_column_slice(qjd.as_slice()),
        );
        let cf = lagrange::lagrange_terms(&sys, &q, &qd);
        let pt = pm.transpose();
        close("m5 H_joint", &(pt * cf.mass * pm), &mb.h_mass);
        close("m5 C_joint", &(pt * cf.coriolis * pm), &mb.coriolis);
        close(
            "m5 h_joint",
            &(pt * cf.h),
            &DMatrix::from_column_slice(6, 1, mb.h.as_slice()),
        );
        close(
            "m5 G_joint",
            &(pt * cf.gravity),
            &DMatrix::from_column_slice(6, 1, mb.g.as_slice()),
        );
    }
}

/// Seeded random parameters and states (wider than the reference sets: negative d and
/// counterweighted links included) — the closed forms must hold in general.
#[test]
fn random_robots_match_multibody() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(20261122);
    for _ in 0..25 {
        let mut r = |a: f64, b: f64| rng.random_range(a..b);
        let m5p = MobileManipulatorParams {
            M_cart: r(5.0, 50.0),
            I_p: r(0.5, 5.0),
            I_c: r(0.0, 0.1),
            d: r(-0.5, 0.5),
            L: r(-0.4, 0.4),
            r_w: r(0.03, 0.2),
            b: r(0.1, 0.5),
            m1: r(0.5, 8.0),
            m2: r(0.5, 8.0),
            M1: r(0.0, 3.0),
            M2: r(0.0, 3.0),
            L1: r(0.2, 1.0),
            L2: r(0.2, 1.0),
            L1cm: r(-0.3, 0.6),
            L2cm: r(-0.3, 0.6),
            k1: r(0.01, 0.3),
            k2: r(0.01, 0.3),
            k1y: r(0.01, 0.3),
            k2y: r(0.01, 0.3),
            g: 9.81,
        };
        if m5p.d.abs() < 1e-3 {
            continue;
        }
        let q = SVector::<f64, 6>::from_fn(|_, _| r(-3.0, 3.0));
        let qd = SVector::<f64, 6>::from_fn(|_, _| r(-2.0, 2.0));
        let p = m5p.clone();
        let sys = MobileManipulator::new(m5p).unwrap();
        let mut b = ModelBuilder::new("m5");
        b.set_gravity(Vector3::new(0.0, 0.0, -p.g));
        let base = planar_root(&mut b, p.M_cart, p.I_p);
        let cap = b
            .add_joint(
                base,
                "capstan",
                JointType::RevoluteZ,
                t(p.L, 0.0, 0.0),
                JointLimits::unlimited(),
            )
            .unwrap();
        b.append_body_inertia(
            cap,
            &Inertia::new(
                0.0,
                Vector3::zeros(),
                Matrix3::from_diagonal(&Vector3::new(0.0, 0.0, p.I_c)),
            ),
            &SE3::identity(),
        )
        .unwrap();
        vertical_arm(
            &mut b,
            cap,
            SE3::identity(),
            (p.m1, p.m2, p.M1, p.M2),
            (p.L1, p.L2, p.L1cm, p.L2cm),
            (p.k1, p.k2, p.k1y, p.k2y),
        );
        let model = b.build().unwrap();
        let pm = joint_to_absolute();
        let pinv = pm.try_inverse().unwrap();
        let (qj, qjd) = (pinv * q, pinv * qd);
        let mb = multibody_terms(
            &model,
            &DVector::from_column_slice(qj.as_slice()),
            &DVector::from_column_slice(qjd.as_slice()),
        );
        let cf = lagrange::lagrange_terms(&sys, &q, &qd);
        let pt = pm.transpose();
        close("random m5 H_joint", &(pt * cf.mass * pm), &mb.h_mass);
        close("random m5 C_joint", &(pt * cf.coriolis * pm), &mb.coriolis);
        close(
            "random m5 h_joint",
            &(pt * cf.h),
            &DMatrix::from_column_slice(6, 1, mb.h.as_slice()),
        );
        close(
            "random m5 G_joint",
            &(pt * cf.gravity),
            &DMatrix::from_column_slice(6, 1, mb.g.as_slice()),
        );

        // m2 with the same kind of spread
        let p2 = PlatformArmParams {
            m_p: p.M_cart,
            I_p: p.I_p,
            d: p.d,
            L: p.L,
            r_w: p.r_w,
            b: p.b,
            m1: p.m1,
            m2: p.m2,
            M1: p.M1,
            M2: p.M2,
            L1: p.L1,
            L2: p.L2,
            L1cm: p.L1cm,
            L2cm: p.L2cm,
            k1: p.k1,
            k2: p.k2,
        };
        let sys2 = PlatformArm::new(p2.clone()).unwrap();
        let mut b = ModelBuilder::new("m2");
        let base = planar_root(&mut b, p2.m_p, p2.I_p);
        let j1 = b
            .add_joint(
                base,
                "theta1",
                JointType::RevoluteZ,
                t(p2.L, 0.0, 0.0),
                JointLimits::unlimited(),
            )
            .unwrap();
        let link = |m: f64, lcm: f64, k: f64| {
            Inertia::new(
                m,
                Vector3::new(lcm, 0.0, 0.0),
                Matrix3::from_diagonal(&Vector3::new(0.0, 0.0, m * k * k)),
            )
        };
        b.append_body_inertia(j1, &link(p2.m1, p2.L1cm, p2.k1), &SE3::identity())
            .unwrap();
        b.append_body_inertia(
            j1,
            &Inertia::point_mass(p2.M1, Vector3::new(p2.L1, 0.0, 0.0)),
            &SE3::identity(),
        )
        .unwrap();
        let j2 = b
            .add_joint(
                j1,
                "theta2",
                JointType::RevoluteZ,
                t(p2.L1, 0.0, 0.0),
                JointLimits::unlimited(),
            )
            .unwrap();
        b.append_body_inertia(j2, &link(p2.m2, p2.L2cm, p2.k2), &SE3::identity())
            .unwrap();
        b.append_body_inertia(
            j2,
            &Inertia::point_mass(p2.M2, Vector3::new(p2.L2, 0.0, 0.0)),
            &SE3::identity(),
        )
        .unwrap();
        let model2 = b.build().unwrap();
        let q2 = q.fixed_rows::<5>(0).into_owned();
        let qd2 = qd.fixed_rows::<5>(0).into_owned();
        let mb2 = multibody_terms(
            &model2,
            &DVector::from_column_slice(q2.as_slice()),
            &DVector::from_column_slice(qd2.as_slice()),
        );
        let cf2 = lagrange::lagrange_terms(&sys2, &q2, &qd2);
        close("random m2 H", &cf2.mass, &mb2.h_mass);
        close("random m2 C", &cf2.coriolis, &mb2.coriolis);

        // m4
        let p4 = CartTwoLinkParams {
            m1: p.m1,
            m2: p.m2,
            M1: p.M1,
            M2: p.M2,
            M_cart: p.M_cart,
            L1: p.L1,
            L2: p.L2,
            L1cm: p.L1cm,
            L2cm: p.L2cm,
            k1: p.k1,
            k2: p.k2,
            g: p.g,
        };
        let sys4 = CartTwoLink::new(p4.clone()).unwrap();
        let mut b = ModelBuilder::new("m4");
        b.set_gravity(Vector3::new(0.0, 0.0, -p4.g));
        let cart = b
            .add_joint(
                JointIndex(0),
                "d0",
                JointType::PrismaticX,
                SE3::identity(),
                JointLimits::unlimited(),
            )
            .unwrap();
        b.append_body_inertia(
            cart,
            &Inertia::point_mass(p4.M_cart, Vector3::zeros()),
            &SE3::identity(),
        )
        .unwrap();
        vertical_arm(
            &mut b,
            cart,
            SE3::identity(),
            (p4.m1, p4.m2, p4.M1, p4.M2),
            (p4.L1, p4.L2, p4.L1cm, p4.L2cm),
            (p4.k1, p4.k2, 0.0, 0.0),
        );
        let model4 = b.build().unwrap();
        let q4 = q.fixed_rows::<3>(3).into_owned();
        let qd4 = qd.fixed_rows::<3>(3).into_owned();
        let mb4 = multibody_terms(
            &model4,
            &DVector::from_column_slice(q4.as_slice()),
            &DVector::from_column_slice(qd4.as_slice()),
        );
        let cf4 = lagrange::lagrange_terms(&sys4, &q4, &qd4);
        close("random m4 H", &cf4.mass, &mb4.h_mass);
        close(
            "random m4 h",
            &cf4.h,
            &DMatrix::from_column_slice(3, 1, mb4.h.as_slice()),
        );
        close(
            "random m4 G",
            &cf4.gravity,
            &DMatrix::from_column_slice(3, 1, mb4.g.as_slice()),
        );
    }
}

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

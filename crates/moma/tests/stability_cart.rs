//! The chapter's cart (m4, Figure 5.2) on its two wheel contacts: the gravito-inertial
//! wrench agrees with the closed-form dynamics, and the balanced-manipulator test of the
//! theory notes (1.8 item 10): with Γ1 = Γ2 = 0 the static ZMP, Force-Angle and
//! Moment-Height values do not change with the arm's posture, but at speed the ZMP moves
//! by `L̇ / (M g)` (the motor reaction), so the chapter's "no tip-over possible" holds
//! statically only.

use moma::closed_form::m4_cart_two_link::{CartSupport, CartTwoLink, CartTwoLinkParams};
use moma::stability::StabilityReport;
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn params(balanced: bool) -> CartTwoLinkParams {
    let mut p = CartTwoLinkParams {
        m1: 2.0,
        m2: 1.5,
        M1: 0.5,
        M2: 0.8,
        M_cart: 10.0,
        L1: 0.6,
        L2: 0.5,
        L1cm: 0.3,
        L2cm: 0.25,
        k1: 0.12,
        k2: 0.09,
        g: 9.81,
    };
    if balanced {
        let (l1, l2) = p.balancing_offsets();
        p.L1cm = l1;
        p.L2cm = l2;
    }
    p
}

const SUPPORT: CartSupport = CartSupport {
    wheelbase: 0.8,
    shoulder_height: 0.3,
};

fn static_values(r: &StabilityReport) -> Vec<f64> {
    let mut v = vec![r.zmp.unwrap().x - 0.0, r.zmp_margin.unwrap()];
    for e in &r.edges {
        v.extend([
            e.zmp_distance.unwrap(),
            e.force_angle.unwrap(),
            e.force_angle_beta.unwrap(),
            e.moment,
            e.inertia,
            e.mhs.unwrap(),
        ]);
    }
    v
}

#[test]
fn cart_wrench_matches_the_closed_form_dynamics() {
    let mut rng = ChaCha8Rng::seed_from_u64(4);
    for balanced in [false, true] {
        let cart = CartTwoLink::new(params(balanced)).unwrap();
        let p = &cart.params;
        for _ in 0..20 {
            let mut r = |s: f64| rng.random_range(-s..s);
            let q = Vector3::new(r(1.0), r(1.5), r(1.5));
            let qd = Vector3::new(r(1.0), r(2.0), r(2.0));
            let u = Vector3::new(r(20.0), r(5.0), r(5.0));
            let out = cart.evaluate(&q, &qd, &u).unwrap();
            let w = cart.gravito_inertial_wrench(&q, &qd, &out.qddot);
            // f_gi = arm force on the cart + the cart's own −M_cart (d̈0, g)
            let fx = out.arm_force_on_cart[0] - p.M_cart * out.qddot[0];
            let fz = out.arm_force_on_cart[1] - p.M_cart * p.g;
            assert!((w.force.x - fx).abs() < 1e-10, "{} vs {fx}", w.force.x);
            assert!((w.force.z - fz).abs() < 1e-10);
            assert_eq!(w.force.y, 0.0);
            assert!((w.mass - p.total_mass()).abs() < 1e-12);
            // horizontal momentum balance: −f_x = (H q̈ + h)[0] = u[0] (G[0] = 0)
            assert!((-w.force.x - u[0]).abs() < 1e-9);
            // the moment lies along the rotation axis y only
            assert_eq!(w.moment_about_com.x, 0.0);
            assert_eq!(w.moment_about_com.z, 0.0);
        }
    }
}

#[test]
fn balanced_arm_static_measures_are_constant_but_the_zmp_moves_at_speed() {
    let cart = CartTwoLink::new(params(true)).unwrap();
    assert!(cart.is_balanced(1e-12));
    let p = cart.params.clone();
    let z = Vector3::zeros();
    let reference = static_values(
        &cart
            .stability(&SUPPORT, &Vector3::new(0.0, 0.0, 0.0), &z, &z)
            .unwrap(),
    );
    let mut rng = ChaCha8Rng::seed_from_u64(10);
    for _ in 0..30 {
        let q = Vector3::new(
            0.0,
            rng.random_range(-3.0..3.0),
            rng.random_range(-3.0..3.0),
        );
        let r = cart.stability(&SUPPORT, &q, &z, &z).unwrap();
        for (a, b) in static_values(&r).iter().zip(&reference) {
            assert!((a - b).abs() < 1e-12 * (1.0 + b.abs()), "{a} vs {b}");
        }
        assert!(r.stable);
        // the system CoM stays over the shoulder
        let w = cart.gravito_inertial_wrench(&q, &z, &z);
        assert!(w.com.x.abs() < 1e-13 && w.com.z.abs() < 1e-13);
    }
    // At speed, with the cart not accelerating: s_zmp − s_CoM = −L̇_y / (M g), where the
    // arm's angular-momentum rate about the shoulder is L̇_y = (I11 + I22) θ̈1 − I22 θ̈2 = τ1.
    let (i11, i22, m_t) = (p.i11(), p.i22(), p.total_mass());
    let mut moved = 0.0_f64;
    for _ in 0..30 {
        let mut r = |s: f64| rng.random_range(-s..s);
        let q = Vector3::new(r(1.0), r(3.0), r(3.0));
        let qd = Vector3::new(r(1.0), r(4.0), r(4.0));
        let qdd = Vector3::new(0.0, r(20.0), r(20.0));
        let rep = cart.stability(&SUPPORT, &q, &qd, &qdd).unwrap();
        let w = cart.gravito_inertial_wrench(&q, &qd, &qdd);
        let ldot = (i11 + i22) * qdd[1] - i22 * qdd[2];
        let shift = rep.zmp.unwrap().x - w.com.x;
        assert!(
            (shift + ldot / (m_t * p.g)).abs() < 1e-12,
            "{shift} vs {}",
            -ldot / (m_t * p.g)
        );
        // the motor torque that produces it, from the closed form: τ1 = L̇_y
        let out = cart
            .evaluate(&q, &qd, &Vector3::new(0.0, ldot, i22 * (qdd[2] - qdd[1])))
            .unwrap();
        assert!((out.qddot - qdd).norm() < 1e-9);
        // and the Moment-Height moment moves with it: M_i = |f_z| s_i on both axes
        for e in &rep.edges {
            assert!((e.moment - w.force.z.abs() * e.zmp_distance.unwrap()).abs() < 1e-9);
        }
        moved = moved.max(shift.abs());
    }
    assert!(
        moved > 0.1,
        "the arm's acceleration should move the ZMP, max shift {moved}"
    );
    // fast enough, the balanced arm tips the cart: the ZMP crosses the front contact
    let tip = Vector3::new(0.0, -(0.45 * m_t * p.g) / (i11 + i22), 0.0);
    let rep = cart
        .stability(&SUPPORT, &Vector3::new(0.0, 0.3, 0.2), &z, &tip)
        .unwrap();
    assert!(!rep.stable);
    assert_eq!(rep.zmp_critical_edge, Some(1));
    assert!(rep.edges[1].force_angle.unwrap() < 0.0 && rep.edges[1].moment < 0.0);
}

#[test]
fn unbalanced_arm_static_measures_follow_the_arm() {
    let cart = CartTwoLink::new(params(false)).unwrap();
    let z = Vector3::zeros();
    let a = static_values(
        &cart
            .stability(&SUPPORT, &Vector3::new(0.0, 0.0, 0.0), &z, &z)
            .unwrap(),
    );
    let b = static_values(
        &cart
            .stability(&SUPPORT, &Vector3::new(0.0, 0.8, 0.0), &z, &z)
            .unwrap(),
    );
    assert!(
        (a[1] - b[1]).abs() > 0.01,
        "margin should change: {} {}",
        a[1],
        b[1]
    );
    // segment support: edge 0 is the rear contact, its inward normal +x
    let r = cart
        .stability(&SUPPORT, &Vector3::new(0.0, 0.8, 0.0), &z, &z)
        .unwrap();
    assert!(r.edges[0].zmp_distance.unwrap() > r.edges[1].zmp_distance.unwrap());
    let s0 = r.edges[0].zmp_distance.unwrap() + r.edges[1].zmp_distance.unwrap();
    assert!((s0 - SUPPORT.wheelbase).abs() < 1e-12);
    let bad = CartSupport {
        wheelbase: 0.0,
        shoulder_height: 0.3,
    };
    assert!(cart.stability(&bad, &z, &z, &z).is_err());
}

//! The library's Pinocchio layout map on the Pinocchio reference dumps: Pinocchio's
//! q, v, a and τ are fed as they are, converted to moma's layout, run through moma's
//! algorithms, and the results converted back are compared with Pinocchio's outputs
//! (RNEA, CRBA, ABA, nonlinear effects, gravity, the end-effector Jacobian), to 1e-9
//! relative. The dumps cover a fixed arm (UR5, identity layout), a planar root (Panda,
//! TIAGo) with continuous wheel joints (TIAGo) and a free-flyer root (TIAGo).

mod pinocchio_common;

use moma::dynamics;
use moma::io::pinocchio_layout::PinocchioLayout;
use moma::kinematics::{self, ReferenceFrame};
use moma::multibody::{Data, RootJoint};
use nalgebra::{DMatrix, DVector, Matrix6xX};
use pinocchio_common::{Case, check, matf, vecf};

fn run(file: &str, root: RootJoint, identity: bool) {
    let case = Case::load(file, root);
    let model = &case.model;
    let layout = PinocchioLayout::new(model);
    assert_eq!(
        layout.nq(),
        case.j["nq"].as_u64().unwrap() as usize,
        "{file}: nq"
    );
    assert_eq!(layout.nv(), model.nv);
    assert_eq!(layout.is_identity(), identity, "{file}");
    let nv = model.nv;
    let mut data = Data::new(model);
    for (si, s) in case.j["states"].as_array().unwrap().iter().enumerate() {
        let what = |x: &str| format!("{file} state {si}: {x}");
        let q_pin = vecf(&s["q"]);
        let mut q = DVector::zeros(model.nq);
        layout.q_from_pinocchio(&q_pin, q.as_mut_slice()).unwrap();
        let mut q_back = vec![0.0; layout.nq()];
        layout.q_to_pinocchio(q.as_slice(), &mut q_back);
        check(&what("q round trip"), &q_back, &q_pin);

        let mut v = DVector::zeros(nv);
        let mut a = DVector::zeros(nv);
        let mut tau_in = DVector::zeros(nv);
        layout.v_from_pinocchio(q.as_slice(), &vecf(&s["v"]), v.as_mut_slice());
        layout.a_from_pinocchio(q.as_slice(), v.as_slice(), &vecf(&s["a"]), a.as_mut_slice());
        layout.tau_from_pinocchio(q.as_slice(), &vecf(&s["tau_in"]), tau_in.as_mut_slice());

        let mut out = vec![0.0; nv];
        let tau = dynamics::rnea(model, &mut data, &q, &v, &a).clone();
        layout.tau_to_pinocchio(q.as_slice(), tau.as_slice(), &mut out);
        check(&what("rnea"), &out, &vecf(&s["rnea_tau"]));

        // Pinocchio's bias is RNEA at a_P = 0, which is a = ω S v in moma's layout (the
        // bias differs by H ω S v between the layouts, so it is no τ-transform).
        let mut a0 = DVector::zeros(nv);
        layout.a_from_pinocchio(
            q.as_slice(),
            v.as_slice(),
            &vec![0.0; nv],
            a0.as_mut_slice(),
        );
        let nle = dynamics::rnea(model, &mut data, &q, &v, &a0).clone();
        layout.tau_to_pinocchio(q.as_slice(), nle.as_slice(), &mut out);
        check(&what("nle"), &out, &vecf(&s["nle"]));
        let nle_moma = dynamics::nonlinear_effects(model, &mut data, &q, &v).clone();
        if !identity {
            let diff = (&nle - &nle_moma).norm();
            let h_a0 = (dynamics::crba(model, &mut data, &q) * &a0).norm();
            assert!(
                (diff - h_a0).abs() <= 1e-9 * h_a0.max(1.0),
                "{diff} vs {h_a0}"
            );
        }

        let g = dynamics::gravity_torque(model, &mut data, &q).clone();
        layout.tau_to_pinocchio(q.as_slice(), g.as_slice(), &mut out);
        check(&what("gravity"), &out, &vecf(&s["gravity_torque"]));

        let ddq = dynamics::aba(model, &mut data, &q, &v, &tau_in).clone();
        layout.a_to_pinocchio(q.as_slice(), v.as_slice(), ddq.as_slice(), &mut out);
        check(&what("aba"), &out, &vecf(&s["aba_ddq"]));

        let h = dynamics::crba(model, &mut data, &q).clone();
        let mut h_pin = DMatrix::zeros(nv, nv);
        layout.matrix_to_pinocchio(q.as_slice(), &h, &mut h_pin);
        check(
            &what("crba"),
            h_pin.as_slice(),
            matf(&s["crba_M"]).as_slice(),
        );
        let mut h_back = DMatrix::zeros(nv, nv);
        layout.matrix_from_pinocchio(q.as_slice(), &matf(&s["crba_M"]), &mut h_back);
        check(
            &what("crba from Pinocchio"),
            h_back.as_slice(),
            h.as_slice(),
        );

        let ee = &s["ee_frame"];
        let frame = model.frame_id(ee["name"].as_str().unwrap()).unwrap();
        let mut jac = Matrix6xX::zeros(nv);
        kinematics::frame_jacobian(
            model,
            &mut data,
            &q,
            frame,
            ReferenceFrame::LocalWorldAligned,
            &mut jac,
        );
        let j = DMatrix::from_column_slice(6, nv, jac.as_slice());
        let mut j_pin = DMatrix::zeros(6, nv);
        layout.jacobian_to_pinocchio(q.as_slice(), &j, &mut j_pin);
        let want = matf(&ee["jacobian_local_world_aligned"]);
        check(&what("jacobian"), j_pin.as_slice(), want.as_slice());
        let mut j_back = DMatrix::zeros(6, nv);
        layout.jacobian_from_pinocchio(q.as_slice(), &want, &mut j_back);
        check(
            &what("jacobian from Pinocchio"),
            j_back.as_slice(),
            j.as_slice(),
        );
    }
}

#[test]
fn ur5_fixed_is_the_identity_layout() {
    run("ur5.json", RootJoint::Fixed, true);
}

#[test]
fn panda_on_a_planar_base() {
    run("panda_planar.json", RootJoint::Planar, false);
}

#[test]
fn tiago_planar_with_continuous_wheels() {
    run("tiago_planar.json", RootJoint::Planar, false);
}

#[test]
fn tiago_free_flyer_with_continuous_wheels() {
    run("tiago_freeflyer.json", RootJoint::FreeFlyer, false);
}

//! The analytical derivatives of a frame's velocity and acceleration
//! (`dynamics::frame_velocity_derivatives`, `dynamics::frame_acceleration_derivatives`)
//! against Pinocchio 4.1's `getFrameVelocityDerivatives` / `getFrameAccelerationDerivatives`
//! (the files `tests/data/derivatives/frame_*.json`, Pinocchio's layout: the chain rule of
//! `PinocchioLayout::frame_*_derivatives_to_pinocchio` is under test too), and against
//! central finite differences, in moma's layout, of the frame motion computed by
//! `kinematics::forward_kinematics_second_order` and of the frame placement.

mod pinocchio_common;

use moma::dynamics::{self, FrameDerivativeData};
use moma::io::pinocchio_layout::PinocchioLayout;
use moma::io::urdf::model_from_urdf_file;
use moma::kinematics::{self, ReferenceFrame};
use moma::multibody::{Data, FrameIndex, Model, RootJoint};
use moma::spatial::{SE3, log3, log6};
use nalgebra::{DMatrix, DVector, Matrix6xX, Vector6};
use pinocchio_common::{matf, rel_err, root_of, vecf};
use rand::{Rng, SeedableRng};
use serde_json::Value;
use std::path::PathBuf;

const FRAMES: [(&str, ReferenceFrame); 3] = [
    ("local", ReferenceFrame::Local),
    ("world", ReferenceFrame::World),
    ("local_world_aligned", ReferenceFrame::LocalWorldAligned),
];

fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

fn dm(m: &Matrix6xX<f64>) -> DMatrix<f64> {
    DMatrix::from_column_slice(6, m.ncols(), m.as_slice())
}

fn run_reference(file: &str) {
    let path = data_dir().join("derivatives").join(file);
    let doc: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let urdf = path.parent().unwrap().join(doc["urdf"].as_str().unwrap());
    let model = model_from_urdf_file(&urdf, root_of(doc["root"].as_str().unwrap())).unwrap();
    let nv = model.nv;
    assert_eq!(nv, doc["nv"].as_u64().unwrap() as usize, "{file}: nv");
    let frame = model.frame_id(doc["frame"].as_str().unwrap()).unwrap();
    let layout = PinocchioLayout::new(&model);
    let mut fd = FrameDerivativeData::new(&model);
    let mut data = Data::new(&model);
    let mut m = [(); 4].map(|()| Matrix6xX::zeros(nv));
    let mut jac = Matrix6xX::zeros(nv);
    for (n, s) in doc["states"].as_array().unwrap().iter().enumerate() {
        let mut q = DVector::zeros(model.nq);
        layout
            .q_from_pinocchio(&vecf(&s["q"]), q.as_mut_slice())
            .unwrap();
        let (vp, ap) = (vecf(&s["v"]), vecf(&s["a"]));
        let (mut v, mut a) = (DVector::zeros(nv), DVector::zeros(nv));
        layout.v_from_pinocchio(q.as_slice(), &vp, v.as_mut_slice());
        layout.a_from_pinocchio(q.as_slice(), v.as_slice(), &ap, a.as_mut_slice());
        dynamics::forward_kinematics_derivatives(&model, &mut fd, &q, &v, &a);
        let (placement, _, _) = dynamics::frame_motion(&model, &fd, frame, ReferenceFrame::World);
        let want_p = &s["placement"];
        let tr = DMatrix::from_column_slice(3, 1, placement.translation.as_slice());
        let rot = DMatrix::from_column_slice(3, 3, placement.rotation.as_slice());
        let e = rel_err(
            &tr,
            &matf(&Value::Array(vec![want_p["translation"].clone()])).transpose(),
        )
        .max(rel_err(&rot, &matf(&want_p["rotation"])));
        assert!(e <= 1e-10, "{file} state {n} placement: {e:e}");
        for (key, rf) in FRAMES {
            let want = &s[key];
            let [vq, aq, av, aa] = &mut m;
            dynamics::frame_acceleration_derivatives(&model, &fd, frame, rf, vq, aq, av, aa);
            let (_, vel, acc) = dynamics::frame_motion(&model, &fd, frame, rf);
            // the velocity-only entry gives the same ∂V/∂q and ∂V/∂v = J
            let (mut vq2, mut vv2) = (Matrix6xX::zeros(nv), Matrix6xX::zeros(nv));
            dynamics::frame_velocity_derivatives(&model, &fd, frame, rf, &mut vq2, &mut vv2);
            assert_eq!(vq2, *vq, "{file} {key}: dv_dq of the two entries");
            assert_eq!(vv2, *aa, "{file} {key}: dv_dv = da_da");
            kinematics::frame_jacobian(&model, &mut data, &q, frame, rf, &mut jac);
            let e = rel_err(&dm(&jac), &dm(aa));
            assert!(
                e <= 1e-12,
                "{file} {key}: frame_jacobian against da_da {e:e}"
            );
            let (qs, vs, as_) = (q.as_slice(), v.as_slice(), a.as_slice());
            layout.frame_velocity_derivatives_to_pinocchio(qs, vs, &mut vq2, &mut vv2);
            layout.frame_acceleration_derivatives_to_pinocchio(qs, vs, as_, vq, aq, av, aa);
            for (name, got) in [
                ("dv_dq", dm(vq)),
                ("dv_dq", dm(&vq2)),
                ("dv_dv", dm(&vv2)),
                ("jacobian", dm(&vv2)),
                ("da_dq", dm(aq)),
                ("da_dv", dm(av)),
                ("da_da", dm(aa)),
            ] {
                let e = rel_err(&got, &matf(&want[name]));
                assert!(
                    e <= 1e-8,
                    "{file} state {n} {key} {name}: relative error {e:e}"
                );
            }
            for (name, got) in [
                ("velocity", vel.to_vector()),
                ("acceleration", acc.to_vector()),
            ] {
                let got = DMatrix::from_column_slice(6, 1, got.as_slice());
                let want = DMatrix::from_column_slice(6, 1, &vecf(&want[name]));
                let e = rel_err(&got, &want);
                assert!(
                    e <= 1e-8,
                    "{file} state {n} {key} {name}: relative error {e:e}"
                );
            }
        }
    }
}

#[test]
fn ur5_on_every_root() {
    for r in ["fixed", "planar", "freeflyer"] {
        run_reference(&format!("frame_ur5_{r}.json"));
    }
}

#[test]
fn panda_on_every_root() {
    for r in ["fixed", "planar", "freeflyer"] {
        run_reference(&format!("frame_panda_{r}.json"));
    }
}

#[test]
fn tiago_with_continuous_wheels_on_every_root() {
    for r in ["fixed", "planar", "freeflyer"] {
        run_reference(&format!("frame_tiago_{r}.json"));
    }
}

/// The frame's twist and spatial acceleration in `rf` (Pinocchio's definitions) from
/// `kinematics::forward_kinematics_second_order`, independent of the code under test.
fn motion(
    model: &Model,
    data: &mut Data,
    frame: FrameIndex,
    rf: ReferenceFrame,
    q: &DVector<f64>,
    v: &DVector<f64>,
    a: &DVector<f64>,
) -> (Vector6<f64>, Vector6<f64>) {
    kinematics::forward_kinematics_second_order(model, data, q, v, a);
    let fr = &model.frames[frame.0];
    let j = fr.parent_joint.0;
    let vl = fr.placement.inverse_act_motion(&data.v[j]);
    let al = fr.placement.inverse_act_motion(&data.a[j]);
    let m = data.world_from_joint[j].compose(&fr.placement);
    let express = |x: &moma::spatial::Motion| match rf {
        ReferenceFrame::Local => x.to_vector(),
        ReferenceFrame::World => m.act_motion(x).to_vector(),
        ReferenceFrame::LocalWorldAligned => {
            let (l, w) = (m.rotation * x.linear, m.rotation * x.angular);
            Vector6::new(l.x, l.y, l.z, w.x, w.y, w.z)
        }
    };
    (express(&vl), express(&al))
}

/// The placement's tangent displacement from `m0` to `m1` as `rf` defines the Jacobian.
fn displacement(m0: &SE3, m1: &SE3, rf: ReferenceFrame) -> Vector6<f64> {
    match rf {
        ReferenceFrame::Local => log6(&m0.inverse_compose(m1)).to_vector(),
        ReferenceFrame::World => log6(&m1.compose(&m0.inverse())).to_vector(),
        ReferenceFrame::LocalWorldAligned => {
            let dp = m1.translation - m0.translation;
            let w = log3(&(m1.rotation * m0.rotation.transpose()));
            Vector6::new(dp.x, dp.y, dp.z, w.x, w.y, w.z)
        }
    }
}

/// Every derivative, on random states of every root, against central differences in
/// moma's layout (planar root: world-axes velocity, q ⊕ δq by `kinematics::integrate`).
#[test]
fn finite_differences_on_every_root() {
    let mut rng = rand::rngs::StdRng::seed_from_u64(25);
    let h = 1e-6;
    for (urdf, frame) in [
        ("ur5_robot.urdf", "tool0"),
        ("panda.urdf", "panda_hand_tcp"),
        ("tiago.urdf", "arm_tool_link"),
    ] {
        for root in [RootJoint::Fixed, RootJoint::Planar, RootJoint::FreeFlyer] {
            let model =
                model_from_urdf_file(data_dir().join("pinocchio/urdf").join(urdf), root).unwrap();
            let frame = model.frame_id(frame).unwrap();
            let nv = model.nv;
            let mut data = Data::new(&model);
            let mut fd = FrameDerivativeData::new(&model);
            let mut m = [(); 4].map(|()| Matrix6xX::zeros(nv));
            for _ in 0..2 {
                let q = kinematics::random_configuration(&model, &mut rng);
                let v = DVector::from_fn(nv, |_, _| rng.random_range(-1.0..1.0));
                let a = DVector::from_fn(nv, |_, _| rng.random_range(-1.0..1.0));
                dynamics::forward_kinematics_derivatives(&model, &mut fd, &q, &v, &a);
                for (key, rf) in FRAMES {
                    let [vq, aq, av, aa] = &mut m;
                    dynamics::frame_acceleration_derivatives(
                        &model, &fd, frame, rf, vq, aq, av, aa,
                    );
                    let (_, vel, acc) = dynamics::frame_motion(&model, &fd, frame, rf);
                    let (mut vq, mut aq) = (dm(vq), dm(aq));
                    if rf == ReferenceFrame::LocalWorldAligned {
                        // Pinocchio's ∂/∂q plus the frame origin's own displacement
                        let (w, alpha) = (vel.angular, acc.angular);
                        for k in 0..nv {
                            let dp = aa.fixed_view::<3, 1>(0, k).into_owned();
                            let (cw, ca) = (w.cross(&dp), alpha.cross(&dp));
                            for r in 0..3 {
                                vq[(r, k)] += cw[r];
                                aq[(r, k)] += ca[r];
                            }
                        }
                    }
                    let mut fd_vq = DMatrix::zeros(6, nv);
                    let mut fd_aq = DMatrix::zeros(6, nv);
                    let mut fd_av = DMatrix::zeros(6, nv);
                    let mut fd_aa = DMatrix::zeros(6, nv);
                    let mut fd_p = DMatrix::zeros(6, nv);
                    let (mut qp, mut qm) = (q.clone(), q.clone());
                    let (_, _, m0) = (0, 0, {
                        kinematics::frames_forward_kinematics(&model, &mut data, &q);
                        data.world_from_frame[frame.0]
                    });
                    for j in 0..nv {
                        let mut e = DVector::zeros(nv);
                        e[j] = h;
                        kinematics::integrate(&model, &q, &e, &mut qp);
                        kinematics::integrate(&model, &q, &(-&e), &mut qm);
                        let (v1, a1) = motion(&model, &mut data, frame, rf, &qp, &v, &a);
                        let (v0, a0) = motion(&model, &mut data, frame, rf, &qm, &v, &a);
                        fd_vq.set_column(j, &((v1 - v0) / (2.0 * h)));
                        fd_aq.set_column(j, &((a1 - a0) / (2.0 * h)));
                        kinematics::frames_forward_kinematics(&model, &mut data, &qp);
                        let mp = data.world_from_frame[frame.0];
                        kinematics::frames_forward_kinematics(&model, &mut data, &qm);
                        let mm = data.world_from_frame[frame.0];
                        fd_p.set_column(
                            j,
                            &((displacement(&m0, &mp, rf) - displacement(&m0, &mm, rf))
                                / (2.0 * h)),
                        );
                        let (_, a1) = motion(&model, &mut data, frame, rf, &q, &(&v + &e), &a);
                        let (_, a0) = motion(&model, &mut data, frame, rf, &q, &(&v - &e), &a);
                        fd_av.set_column(j, &((a1 - a0) / (2.0 * h)));
                        let (_, a1) = motion(&model, &mut data, frame, rf, &q, &v, &(&a + &e));
                        let (_, a0) = motion(&model, &mut data, frame, rf, &q, &v, &(&a - &e));
                        fd_aa.set_column(j, &((a1 - a0) / (2.0 * h)));
                    }
                    let jac = dm(aa);
                    for (name, got, want) in [
                        ("dv_dq", &vq, &fd_vq),
                        ("da_dq", &aq, &fd_aq),
                        ("da_dv", &dm(av), &fd_av),
                        ("da_da", &jac, &fd_aa),
                        ("placement jacobian", &jac, &fd_p),
                    ] {
                        let e = rel_err(got, want);
                        assert!(
                            e <= 1e-6,
                            "{urdf} {root:?} {key} {name}: relative error {e:e} against finite differences"
                        );
                    }
                }
            }
        }
    }
}

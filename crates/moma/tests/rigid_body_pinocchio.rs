//! Agreement with Pinocchio 4.1.0 on Panda (fixed and planar base) and UR5: every output
//! of the reference files, to 1e-9 relative (absolute below 1).
//!
//! Pinocchio's planar base uses q = [x, y, cos θ, sin θ] and a base-frame velocity
//! v_P = T v with T = diag(Rᵀ(θ), 1); ours is q = [x, y, θ] with world-axes v. Hence
//! τ = Tᵀ τ_P, H = Tᵀ H_P T, J = J_P T, A_g = A_g,P T, and accelerations
//! a = T⁻¹ a_P + Ṫ⁻¹ v_P. Continuous joints ([cos, sin] in Pinocchio) become one angle.

use moma::dynamics;
use moma::io::urdf::model_from_urdf_file;
use moma::kinematics::{self, ReferenceFrame};
use moma::multibody::{Data, Model, RootJoint};
use nalgebra::{DMatrix, DVector, Matrix6xX};
use serde_json::Value;
use std::path::PathBuf;

const REL_TOL: f64 = 1e-9;

fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/pinocchio")
}

fn vecf(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn matf(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = v.as_array().unwrap().iter().map(vecf).collect();
    let (r, c) = (rows.len(), rows[0].len());
    DMatrix::from_fn(r, c, |i, j| rows[i][j])
}

#[track_caller]
fn check(what: &str, got: &[f64], want: &[f64]) -> f64 {
    assert_eq!(got.len(), want.len(), "{what}: length");
    let mut worst: f64 = 0.0;
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        let err = (g - w).abs() / w.abs().max(1.0);
        assert!(
            err <= REL_TOL,
            "{what}[{k}]: got {g}, want {w} (rel err {err:e})"
        );
        worst = worst.max(err);
    }
    worst
}

/// Maps between Pinocchio's coordinates and ours for one reference file.
struct Conv {
    /// (pinocchio idx_q, our idx_q, kind) per joint: 0 = same, 1 = planar, 2 = unbounded.
    joints: Vec<(usize, usize, usize, usize, u8)>,
}

impl Conv {
    fn new(j: &Value) -> Self {
        let mut joints = Vec::new();
        let mut oq = 0;
        for jt in j["joints"].as_array().unwrap() {
            let ty = jt["type"].as_str().unwrap();
            let iq = jt["idx_q"].as_u64().unwrap() as usize;
            let iv = jt["idx_v"].as_u64().unwrap() as usize;
            let nv = jt["nv"].as_u64().unwrap() as usize;
            let kind = if ty.contains("Planar") {
                1
            } else if ty.contains("RUB") || ty.contains("Unbounded") {
                2
            } else {
                0
            };
            let onq = match kind {
                1 => 3,
                2 => 1,
                _ => jt["nq"].as_u64().unwrap() as usize,
            };
            joints.push((iq, oq, iv, nv, kind));
            oq += onq;
        }
        Self { joints }
    }

    fn q(&self, qp: &[f64], nq: usize) -> DVector<f64> {
        let mut q = DVector::zeros(nq);
        for &(iq, oq, _, nv, kind) in &self.joints {
            match kind {
                1 => {
                    q[oq] = qp[iq];
                    q[oq + 1] = qp[iq + 1];
                    q[oq + 2] = qp[iq + 3].atan2(qp[iq + 2]);
                }
                2 => q[oq] = qp[iq + 1].atan2(qp[iq]),
                _ => {
                    let n = if nv == 6 { 7 } else { nv };
                    for k in 0..n {
                        q[oq + k] = qp[iq + k];
                    }
                }
            }
        }
        q
    }

    /// The planar base angle θ and v index, if any.
    fn planar(&self, q: &DVector<f64>) -> Option<(f64, usize)> {
        self.joints
            .iter()
            .find(|j| j.4 == 1)
            .map(|&(_, oq, iv, _, _)| (q[oq + 2], iv))
    }

    /// T (nv × nv) with v_P = T v.
    fn t(&self, q: &DVector<f64>, nv: usize) -> DMatrix<f64> {
        let mut t = DMatrix::identity(nv, nv);
        if let Some((th, iv)) = self.planar(q) {
            let (s, c) = th.sin_cos();
            // Rᵀ = [c s; -s c]
            t[(iv, iv)] = c;
            t[(iv, iv + 1)] = s;
            t[(iv + 1, iv)] = -s;
            t[(iv + 1, iv + 1)] = c;
        }
        t
    }

    /// Our acceleration from Pinocchio's (a = T⁻¹ a_P + Ṫ⁻¹ v_P).
    fn acc(&self, q: &DVector<f64>, v_p: &DVector<f64>, a_p: &DVector<f64>) -> DVector<f64> {
        let t = self.t(q, v_p.len());
        let mut a = t.transpose() * a_p; // T⁻¹ = Tᵀ (rotation block)
        if let Some((_, iv)) = self.planar(q) {
            let v_w = t.transpose() * v_p;
            let w = v_p[iv + 2];
            a[iv] += -w * v_w[iv + 1];
            a[iv + 1] += w * v_w[iv];
        }
        a
    }
}

fn run(file: &str, root: RootJoint) {
    let text = std::fs::read_to_string(data_dir().join(file)).unwrap();
    let j: Value = serde_json::from_str(&text).unwrap();
    let urdf = data_dir().join(j["urdf"].as_str().unwrap());
    let mut model: Model = model_from_urdf_file(&urdf, root).unwrap();
    model.gravity = nalgebra::Vector3::from_vec(vecf(&j["gravity"]));
    let conv = Conv::new(&j);
    let (nq, nv) = (model.nq, model.nv);
    assert_eq!(nv, j["nv"].as_u64().unwrap() as usize, "nv");
    assert_eq!(
        model.njoints,
        j["njoints"].as_u64().unwrap() as usize,
        "njoints"
    );
    assert_eq!(
        model.nframes(),
        j["nframes"].as_u64().unwrap() as usize,
        "nframes"
    );
    check(
        "total_mass",
        &[model.total_mass()],
        &[j["total_mass"].as_f64().unwrap()],
    );
    for (k, jt) in j["joints"].as_array().unwrap().iter().enumerate() {
        let name = jt["name"].as_str().unwrap();
        let id = model.joint_id(name).unwrap();
        assert_eq!(id.0, k + 1, "joint order of {name}");
        assert_eq!(
            model.idx_v[id.0],
            jt["idx_v"].as_u64().unwrap() as usize,
            "idx_v {name}"
        );
        let parent = jt["parent"].as_str().unwrap();
        assert_eq!(
            model.names[model.parents[id.0].0], parent,
            "parent of {name}"
        );
        if conv.joints[k].4 == 0 && model.nvs[id.0] == 1 {
            let iq = jt["idx_q"].as_u64().unwrap() as usize;
            let oq = model.idx_q[id.0];
            check(
                &format!("limits {name}"),
                &[
                    model.lower_position_limit[oq],
                    model.upper_position_limit[oq],
                ],
                &[
                    vecf(&j["lower_position_limit"])[iq],
                    vecf(&j["upper_position_limit"])[iq],
                ],
            );
        }
    }
    // the default end-effector ("last link") is the shared reference files' last_frame
    if !file.starts_with("tiago") {
        let last = j["states"][0]["last_frame"]["name"].as_str().unwrap();
        assert_eq!(
            model.frames[model.last_link_frame().0].name,
            last,
            "last link"
        );
    }
    let mut data = Data::new(&model);
    let mut worst: f64 = 0.0;
    for (si, s) in j["states"].as_array().unwrap().iter().enumerate() {
        let tag = |f: &str| format!("{file} state {si} {f}");
        let q = conv.q(&vecf(&s["q"]), nq);
        let v_p = DVector::from_vec(vecf(&s["v"]));
        let a_p = DVector::from_vec(vecf(&s["a"]));
        let tau_p = DVector::from_vec(vecf(&s["tau_in"]));
        let t = conv.t(&q, nv);
        let v = t.transpose() * &v_p;
        let a = conv.acc(&q, &v_p, &a_p);
        let tau_in = t.transpose() * &tau_p;

        let want = t.transpose() * DVector::from_vec(vecf(&s["rnea_tau"]));
        let got = dynamics::rnea(&model, &mut data, &q, &v, &a).clone();
        worst = worst.max(check(&tag("rnea_tau"), got.as_slice(), want.as_slice()));

        let m_p = matf(&s["crba_M"]);
        let want = t.transpose() * &m_p * &t;
        let got = dynamics::crba(&model, &mut data, &q).clone();
        worst = worst.max(check(&tag("crba_M"), got.as_slice(), want.as_slice()));

        let ddq_p = DVector::from_vec(vecf(&s["aba_ddq"]));
        let want = conv.acc(&q, &v_p, &ddq_p);
        let got = dynamics::aba(&model, &mut data, &q, &v, &tau_in).clone();
        worst = worst.max(check(&tag("aba_ddq"), got.as_slice(), want.as_slice()));

        // nle: our a = 0 is Pinocchio's a_P = −T Ṫ⁻¹ v_P
        let zero = DVector::zeros(nv);
        let a0_p = &t * (&zero - conv.acc(&q, &v_p, &zero));
        let want = t.transpose() * (&m_p * a0_p + DVector::from_vec(vecf(&s["nle"])));
        let got = dynamics::nonlinear_effects(&model, &mut data, &q, &v).clone();
        worst = worst.max(check(&tag("nle"), got.as_slice(), want.as_slice()));

        let want = t.transpose() * DVector::from_vec(vecf(&s["gravity_torque"]));
        let got = dynamics::gravity_torque(&model, &mut data, &q).clone();
        worst = worst.max(check(
            &tag("gravity_torque"),
            got.as_slice(),
            want.as_slice(),
        ));

        let got = dynamics::center_of_mass(&model, &mut data, &q);
        worst = worst.max(check(&tag("com"), got.as_slice(), &vecf(&s["com"])));

        let want = matf(&s["centroidal_map_Ag"]) * &t;
        let got = dynamics::centroidal_momentum_matrix(&model, &mut data, &q).clone();
        worst = worst.max(check(
            &tag("centroidal_map_Ag"),
            got.as_slice(),
            want.as_slice(),
        ));
        check(&tag("ccrba com"), data.com.as_slice(), &vecf(&s["com"]));

        for key in ["last_frame", "ee_frame"] {
            let fj = &s[key];
            let fid = model.frame_id(fj["name"].as_str().unwrap()).unwrap();
            let mut jac = Matrix6xX::zeros(nv);
            kinematics::frame_jacobian(
                &model,
                &mut data,
                &q,
                fid,
                ReferenceFrame::LocalWorldAligned,
                &mut jac,
            );
            let want = matf(&fj["jacobian_local_world_aligned"]) * &t;
            worst = worst.max(check(
                &tag(&format!("{key} jacobian")),
                jac.as_slice(),
                want.as_slice(),
            ));
            let m = data.world_from_frame[fid.0];
            worst = worst.max(check(
                &tag(&format!("{key} position")),
                m.translation.as_slice(),
                &vecf(&fj["position"]),
            ));
            let r = matf(&fj["rotation"]);
            worst = worst.max(check(
                &tag(&format!("{key} rotation")),
                m.rotation.as_slice(),
                r.as_slice(),
            ));
            kinematics::frames_forward_kinematics(&model, &mut data, &q);
            check(
                &tag(&format!("{key} fk position")),
                data.world_from_frame[fid.0].translation.as_slice(),
                &vecf(&fj["position"]),
            );
        }
    }
    eprintln!("{file}: worst relative error {worst:e}");
}

#[test]
fn panda_fixed_matches_pinocchio() {
    run("panda.json", RootJoint::Fixed);
}

#[test]
fn panda_planar_matches_pinocchio() {
    run("panda_planar.json", RootJoint::Planar);
}

#[test]
fn ur5_matches_pinocchio() {
    run("ur5.json", RootJoint::Fixed);
}

/// TIAGo (48 joints + base: continuous wheels, prismatic torso, 29 fixed joints, point
/// masses) on a planar base, against Pinocchio (`generate_tiago.py`).
#[test]
fn tiago_planar_matches_pinocchio() {
    run("tiago_planar.json", RootJoint::Planar);
}

/// TIAGo on a free-flyer base.
#[test]
fn tiago_freeflyer_matches_pinocchio() {
    run("tiago_freeflyer.json", RootJoint::FreeFlyer);
}

//! Agreement with Pinocchio 4.1.0 on structurally different robots (references made by
//! `tests/data/pinocchio/generate_more.py`): ANYmal C (quadruped with unaligned joint axes,
//! free-flyer root), Unitree G1 (29-joint humanoid, free-flyer root), the Allegro right
//! hand (a wide tree on a fixed palm) and `edge_general.urdf`, moma's synthetic edge cases
//! (root link with inertia, non-normalised / negative / unaligned axes, a continuous joint
//! with limits, a mimic joint, a zero-mass link with rotational inertia, a point mass,
//! chains of rotated fixed joints, children whose name order differs from document order,
//! a link and a joint sharing a name, a visual material with an empty `<texture/>`) on a
//! fixed and a planar root.
//!
//! Every field is compared to 1e-9 relative (absolute below 1): the structure (joint order,
//! parents, types, limits, frames, total mass, default end-effector) and, per state, RNEA,
//! CRBA, ABA, nonlinear effects, gravity, the Coriolis matrix, CoM, centroidal momentum
//! matrix, energies, every frame placement and a few LOCAL_WORLD_ALIGNED frame Jacobians.
//! Pinocchio's planar-base and continuous-joint coordinates are converted as in
//! `rigid_body_pinocchio.rs`.

use moma::dynamics;
use moma::io::urdf::{model_from_urdf_file, model_from_urdf_str};
use moma::kinematics::{self, ReferenceFrame};
use moma::multibody::{Data, FrameIndex, Model, RootJoint};
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

#[derive(Clone, Copy, PartialEq)]
enum Kind {
    Same,
    Planar,
    Unbounded,
}

/// Pinocchio's coordinates → ours.
struct Conv {
    /// (pinocchio idx_q, our idx_q, idx_v, nq (pinocchio), kind) per joint.
    joints: Vec<(usize, usize, usize, usize, Kind)>,
}

impl Conv {
    fn new(j: &Value) -> Self {
        let mut joints = Vec::new();
        let mut oq = 0;
        for jt in j["joints"].as_array().unwrap() {
            let ty = jt["type"].as_str().unwrap();
            let u = |k: &str| jt[k].as_u64().unwrap() as usize;
            let kind = if ty.contains("Planar") {
                Kind::Planar
            } else if ty.contains("RUB") || ty.contains("Unbounded") {
                Kind::Unbounded
            } else {
                Kind::Same
            };
            joints.push((u("idx_q"), oq, u("idx_v"), u("nq"), kind));
            oq += match kind {
                Kind::Planar => 3,
                Kind::Unbounded => 1,
                Kind::Same => u("nq"),
            };
        }
        Self { joints }
    }

    fn q(&self, qp: &[f64], nq: usize) -> DVector<f64> {
        let mut q = DVector::zeros(nq);
        for &(iq, oq, _, pnq, kind) in &self.joints {
            match kind {
                Kind::Planar => {
                    q[oq] = qp[iq];
                    q[oq + 1] = qp[iq + 1];
                    q[oq + 2] = qp[iq + 3].atan2(qp[iq + 2]);
                }
                Kind::Unbounded => q[oq] = qp[iq + 1].atan2(qp[iq]),
                Kind::Same => q.rows_mut(oq, pnq).copy_from_slice(&qp[iq..iq + pnq]),
            }
        }
        q
    }

    fn planar(&self, q: &DVector<f64>) -> Option<(f64, usize)> {
        self.joints
            .iter()
            .find(|j| j.4 == Kind::Planar)
            .map(|&(_, oq, iv, _, _)| (q[oq + 2], iv))
    }

    /// T (nv × nv) with v_P = T v.
    fn t(&self, q: &DVector<f64>, nv: usize) -> DMatrix<f64> {
        let mut t = DMatrix::identity(nv, nv);
        if let Some((th, iv)) = self.planar(q) {
            let (s, c) = th.sin_cos();
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
        let mut a = t.transpose() * a_p;
        if let Some((_, iv)) = self.planar(q) {
            let v_w = t.transpose() * v_p;
            let w = v_p[iv + 2];
            a[iv] += -w * v_w[iv + 1];
            a[iv + 1] += w * v_w[iv];
        }
        a
    }
}

/// moma's joint type name for a Pinocchio shortname, up to the axis specialisation.
fn family(pin_type: &str) -> &'static str {
    if pin_type.contains("Planar") {
        "planar"
    } else if pin_type.contains("FreeFlyer") {
        "free_flyer"
    } else if pin_type.starts_with("JointModelR") {
        "revolute"
    } else if pin_type.starts_with("JointModelP") {
        "prismatic"
    } else {
        panic!("unexpected Pinocchio joint type {pin_type}")
    }
}

fn check_structure(model: &Model, j: &Value, conv: &Conv) {
    let u = |k: &str| j[k].as_u64().unwrap() as usize;
    assert_eq!(model.nv, u("nv"), "nv");
    assert_eq!(model.njoints, u("njoints"), "njoints");
    assert_eq!(model.nframes(), u("nframes"), "nframes");
    check(
        "total_mass",
        &[model.total_mass()],
        &[j["total_mass"].as_f64().unwrap()],
    );
    let (lo, hi) = (
        vecf(&j["lower_position_limit"]),
        vecf(&j["upper_position_limit"]),
    );
    let (vel, eff) = (vecf(&j["velocity_limit"]), vecf(&j["effort_limit"]));
    for (k, jt) in j["joints"].as_array().unwrap().iter().enumerate() {
        let id = k + 1;
        let name = jt["name"].as_str().unwrap();
        assert_eq!(model.names[id], name, "joint order");
        assert_eq!(
            model.names[model.parents[id].0],
            jt["parent"].as_str().unwrap(),
            "parent of {name}"
        );
        assert_eq!(
            model.idx_v[id],
            jt["idx_v"].as_u64().unwrap() as usize,
            "idx_v {name}"
        );
        let ty = model.joint_types[id].name();
        assert!(
            ty.starts_with(family(jt["type"].as_str().unwrap())),
            "type of {name}: {ty} vs {}",
            jt["type"]
        );
        if model.nvs[id] == 1 {
            let (iq, oq, iv) = (conv.joints[k].0, model.idx_q[id], model.idx_v[id]);
            if conv.joints[k].4 == Kind::Same {
                check(
                    &format!("position limits of {name}"),
                    &[
                        model.lower_position_limit[oq],
                        model.upper_position_limit[oq],
                    ],
                    &[lo[iq], hi[iq]],
                );
            } else {
                // continuous: no position limits (Pinocchio's [cos, sin] are unbounded too)
                assert!(model.lower_position_limit[oq] == f64::NEG_INFINITY);
                assert!(model.upper_position_limit[oq] == f64::INFINITY);
            }
            // a zero velocity or effort limit in the URDF means "unlimited" for moma
            for (what, ours, theirs) in [
                ("velocity", model.velocity_limit[iv], vel[iv]),
                ("effort", model.effort_limit[iv], eff[iv]),
            ] {
                let want = if theirs == 0.0 { f64::INFINITY } else { theirs };
                assert!(
                    ours == want
                        || check(&format!("{what} limit of {name}"), &[ours], &[want]) <= REL_TOL,
                    "{what} limit of {name}: {ours} vs {theirs}"
                );
            }
        }
    }
    for (k, f) in j["frames"].as_array().unwrap().iter().enumerate() {
        let ours = &model.frames[k];
        assert_eq!(ours.name, f["name"].as_str().unwrap(), "frame {k} name");
        assert_eq!(
            ours.kind.name(),
            f["type"].as_str().unwrap(),
            "frame {k} ({}) kind",
            ours.name
        );
        assert_eq!(
            model.names[ours.parent_joint.0],
            f["parent_joint"].as_str().unwrap(),
            "frame {k} ({}) parent joint",
            ours.name
        );
    }
    assert_eq!(
        model.frames[model.last_link_frame().0].name,
        j["last_body_frame"].as_str().unwrap(),
        "default end-effector (last link)"
    );
}

fn run(file: &str, root: RootJoint) {
    let text = std::fs::read_to_string(data_dir().join(file)).unwrap();
    let j: Value = serde_json::from_str(&text).unwrap();
    let urdf = data_dir().join(j["urdf"].as_str().unwrap());
    let mut model = model_from_urdf_file(&urdf, root).unwrap();
    model.gravity = nalgebra::Vector3::from_vec(vecf(&j["gravity"]));
    let conv = Conv::new(&j);
    check_structure(&model, &j, &conv);
    let (nq, nv) = (model.nq, model.nv);
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
        let mut cmp = |what: &str, got: &[f64], want: &[f64]| {
            worst = worst.max(check(&tag(what), got, want));
        };

        let want = t.transpose() * DVector::from_vec(vecf(&s["rnea_tau"]));
        let got = dynamics::rnea(&model, &mut data, &q, &v, &a);
        cmp("rnea_tau", got.as_slice(), want.as_slice());

        let m_p = matf(&s["crba_M"]);
        let want = t.transpose() * &m_p * &t;
        let got = dynamics::crba(&model, &mut data, &q);
        cmp("crba_M", got.as_slice(), want.as_slice());

        let want = conv.acc(&q, &v_p, &DVector::from_vec(vecf(&s["aba_ddq"])));
        let got = dynamics::aba(&model, &mut data, &q, &v, &tau_in);
        cmp("aba_ddq", got.as_slice(), want.as_slice());

        // nle: our a = 0 is Pinocchio's a_P = −T Ṫ⁻¹ v_P
        let zero = DVector::zeros(nv);
        let a0_p = &t * (&zero - conv.acc(&q, &v_p, &zero));
        let want = t.transpose() * (&m_p * a0_p + DVector::from_vec(vecf(&s["nle"])));
        let got = dynamics::nonlinear_effects(&model, &mut data, &q, &v);
        cmp("nle", got.as_slice(), want.as_slice());

        let want = t.transpose() * DVector::from_vec(vecf(&s["gravity_torque"]));
        let got = dynamics::gravity_torque(&model, &mut data, &q);
        cmp("gravity_torque", got.as_slice(), want.as_slice());

        if !s["coriolis_C"].is_null() {
            let want = matf(&s["coriolis_C"]);
            let got = dynamics::coriolis_matrix(&model, &mut data, &q, &v);
            cmp("coriolis_C", got.as_slice(), want.as_slice());
        }

        let got = dynamics::center_of_mass(&model, &mut data, &q);
        cmp("com", got.as_slice(), &vecf(&s["com"]));

        let want = matf(&s["centroidal_map_Ag"]) * &t;
        let got = dynamics::centroidal_momentum_matrix(&model, &mut data, &q);
        cmp("centroidal_map_Ag", got.as_slice(), want.as_slice());

        let ke = dynamics::kinetic_energy(&model, &mut data, &q, &v);
        cmp(
            "kinetic_energy",
            &[ke],
            &[s["kinetic_energy"].as_f64().unwrap()],
        );
        let pe = dynamics::potential_energy(&model, &mut data, &q);
        cmp(
            "potential_energy",
            &[pe],
            &[s["potential_energy"].as_f64().unwrap()],
        );

        kinematics::frames_forward_kinematics(&model, &mut data, &q);
        for (k, row) in s["frame_placements"].as_array().unwrap().iter().enumerate() {
            let m = data.world_from_frame[k];
            let r = m.rotation;
            let mut got = m.translation.as_slice().to_vec();
            for i in 0..3 {
                got.extend((0..3).map(|c| r[(i, c)]));
            }
            cmp(
                &format!("placement of frame {k} ({})", model.frames[k].name),
                &got,
                &vecf(row),
            );
        }

        for jf in s["jacobians"].as_array().unwrap() {
            let k = jf["frame"].as_u64().unwrap() as usize;
            assert_eq!(model.frames[k].name, jf["name"].as_str().unwrap());
            let mut jac = Matrix6xX::zeros(nv);
            kinematics::frame_jacobian(
                &model,
                &mut data,
                &q,
                FrameIndex(k),
                ReferenceFrame::LocalWorldAligned,
                &mut jac,
            );
            let want = matf(&jf["local_world_aligned"]) * &t;
            cmp(
                &format!("jacobian of frame {k} ({})", model.frames[k].name),
                jac.as_slice(),
                want.as_slice(),
            );
        }
    }
    eprintln!("{file}: worst relative error {worst:e}");
}

/// ANYmal C on a free-flyer: a quadruped whose hip and knee axes are unaligned.
#[test]
fn anymal_c_freeflyer_matches_pinocchio() {
    run("anymal_c_freeflyer.json", RootJoint::FreeFlyer);
}

/// Unitree G1 (29 joints) on a free-flyer: a humanoid, 35 velocity coordinates.
#[test]
fn g1_humanoid_freeflyer_matches_pinocchio() {
    run("g1_29dof_freeflyer.json", RootJoint::FreeFlyer);
}

/// The Allegro right hand on a fixed palm: four fingers branching from the root.
#[test]
fn allegro_hand_matches_pinocchio() {
    run("allegro_right_hand.json", RootJoint::Fixed);
}

/// The synthetic edge cases on a fixed root (the root link's inertia is welded to the
/// world and ignored, as Pinocchio).
#[test]
fn edge_cases_fixed_match_pinocchio() {
    run("edge_general_fixed.json", RootJoint::Fixed);
}

/// The synthetic edge cases on a planar root (the root link's inertia moves).
#[test]
fn edge_cases_planar_match_pinocchio() {
    run("edge_general_planar.json", RootJoint::Planar);
}

/// Regression: a `<texture/>` without a file name (iCub's materials) or a `<mesh/>`
/// without one made the parser refuse files urdfdom accepts; visuals, collisions and
/// materials are now ignored before parsing, and the model is the one without them.
#[test]
fn visuals_collisions_and_materials_are_ignored() {
    let body = |visuals: &str| {
        format!(
            r#"<robot name="r">{visuals}
            <link name="a">{visual_a}<inertial><mass value="1"/>
              <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.1" iyz="0" izz="0.1"/></inertial></link>
            <link name="b"><inertial><origin xyz="0.1 0 0"/><mass value="2"/>
              <inertia ixx="0.1" ixy="0" ixz="0" iyy="0.2" iyz="0" izz="0.3"/></inertial>{visual_b}</link>
            <joint name="j" type="revolute"><parent link="a"/><child link="b"/>
              <axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
            </robot>"#,
            visual_a = if visuals.is_empty() {
                ""
            } else {
                r#"<visual><geometry><mesh/></geometry><material name="m"><texture/></material></visual>"#
            },
            visual_b = if visuals.is_empty() {
                ""
            } else {
                r#"<collision name="c>d"><geometry><mesh scale="1 1 1"/></geometry></collision><visual/>"#
            },
        )
    };
    let plain = model_from_urdf_str(&body(""), RootJoint::Planar, "plain.urdf").unwrap();
    let messy = model_from_urdf_str(
        &body(r#"<material name="grey"><texture/></material><!-- <visual> -->"#),
        RootJoint::Planar,
        "messy.urdf",
    )
    .unwrap();
    assert_eq!(
        (messy.nq, messy.nv, messy.nframes()),
        (plain.nq, plain.nv, plain.nframes())
    );
    assert_eq!(messy.inertias, plain.inertias);
    assert_eq!(messy.joint_placements, plain.joint_placements);
}

/// A URDF joint called `root_joint` clashes with the planar / free-flyer root joint's name
/// (Pinocchio then has two joints of that name): a clear error with those roots, fine with
/// the fixed root.
#[test]
fn urdf_joint_named_like_the_root_joint() {
    let text = r#"<robot name="r"><link name="a"/><link name="b"><inertial><mass value="1"/>
        <inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
        <joint name="root_joint" type="revolute"><parent link="a"/><child link="b"/>
        <limit lower="0" upper="1" effort="1" velocity="1"/></joint></robot>"#;
    for root in [RootJoint::Planar, RootJoint::FreeFlyer] {
        let e = model_from_urdf_str(text, root, "rj.urdf")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("rj.urdf") && e.contains("'root_joint'") && e.contains("reserved"),
            "{e}"
        );
    }
    let m = model_from_urdf_str(text, RootJoint::Fixed, "rj.urdf").unwrap();
    assert_eq!(m.names[1], "root_joint");
}

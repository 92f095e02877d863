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
//! Pinocchio's planar-base and continuous-joint coordinates are converted, and the
//! comparisons shared with `rigid_body_pinocchio.rs` made, by `pinocchio_common`.

mod pinocchio_common;

use moma::dynamics;
use moma::io::urdf::model_from_urdf_str;
use moma::kinematics;
use moma::multibody::{FrameIndex, RootJoint};
use pinocchio_common::{Case, Kind, REL_TOL, check, matf, vecf};

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

/// What these files have beyond the common structure: joint types, the limits of
/// continuous joints, velocity and effort limits, every frame, the default end-effector.
fn check_more_structure(case: &Case) {
    let (model, j) = (&case.model, &case.j);
    let (vel, eff) = (vecf(&j["velocity_limit"]), vecf(&j["effort_limit"]));
    for (k, jt) in j["joints"].as_array().unwrap().iter().enumerate() {
        let id = k + 1;
        let name = jt["name"].as_str().unwrap();
        let ty = model.joint_types[id].name();
        assert!(
            ty.starts_with(family(jt["type"].as_str().unwrap())),
            "type of {name}: {ty} vs {}",
            jt["type"]
        );
        if model.nvs[id] == 1 {
            let (oq, iv) = (model.idx_q[id], model.idx_v[id]);
            if case.conv.joints[k].4 != Kind::Same {
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
    let case = Case::load(file, root);
    case.check_structure();
    check_more_structure(&case);
    let model = &case.model;
    // the default end-effector ("last link") is Pinocchio's last BODY frame
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pinocchio");
    let text = std::fs::read_to_string(dir.join("last_body_frames.json")).unwrap();
    let last_bodies: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(
        model.frames[model.last_link_frame().0].name,
        last_bodies[file]
            .as_str()
            .expect("file listed in last_body_frames.json"),
        "{file}: last link"
    );
    case.compare_states(|data, st, tally| {
        let (s, q, v) = (st.s, &st.q, &st.v);
        if !s["coriolis_C"].is_null() {
            let want = matf(&s["coriolis_C"]);
            let got = dynamics::coriolis_matrix(model, data, q, v);
            tally.cmp("coriolis_C", got.as_slice(), want.as_slice());
        }

        let ke = dynamics::kinetic_energy(model, data, q, v);
        let pe = dynamics::potential_energy(model, data, q);
        for (what, got) in [("kinetic_energy", ke), ("potential_energy", pe)] {
            tally.cmp(what, &[got], &[s[what].as_f64().unwrap()]);
        }

        kinematics::frames_forward_kinematics(model, data, q);
        for (k, row) in s["frame_placements"].as_array().unwrap().iter().enumerate() {
            let m = data.world_from_frame[k];
            let r = m.rotation;
            let mut got = m.translation.as_slice().to_vec();
            for i in 0..3 {
                got.extend((0..3).map(|c| r[(i, c)]));
            }
            tally.cmp(
                &format!("placement of frame {k} ({})", model.frames[k].name),
                &got,
                &vecf(row),
            );
        }

        for jf in s["jacobians"].as_array().unwrap() {
            let k = jf["frame"].as_u64().unwrap() as usize;
            assert_eq!(model.frames[k].name, jf["name"].as_str().unwrap());
            case.compare_frame_jacobian(data, st, FrameIndex(k), &jf["local_world_aligned"], tally);
        }
    });
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

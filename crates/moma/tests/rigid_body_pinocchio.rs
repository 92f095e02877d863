//! Agreement with Pinocchio 4.1.0 on Panda (fixed and planar base), UR5 and TIAGo: every
//! output of the reference files, to 1e-9 relative (absolute below 1). The coordinate
//! conversion and the comparisons shared with `rigid_body_pinocchio_more.rs` are in
//! `pinocchio_common`.

mod pinocchio_common;

use moma::kinematics;
use moma::multibody::RootJoint;
use pinocchio_common::{Case, matf, vecf};

fn run(file: &str, root: RootJoint) {
    let case = Case::load(file, root);
    case.check_structure();
    let model = &case.model;
    // the default end-effector ("last link") is Pinocchio's last BODY frame, for every
    // reference file (TIAGo's files use another frame as their `last_frame`)
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pinocchio");
    let text = std::fs::read_to_string(dir.join("last_body_frames.json")).unwrap();
    let last_bodies: serde_json::Value = serde_json::from_str(&text).unwrap();
    let last = last_bodies[file]
        .as_str()
        .expect("file listed in last_body_frames.json");
    assert_eq!(
        model.frames[model.last_link_frame().0].name,
        last,
        "{file}: last link"
    );
    case.compare_states(|data, st, tally| {
        for key in ["last_frame", "ee_frame"] {
            let fj = &st.s[key];
            let fid = model.frame_id(fj["name"].as_str().unwrap()).unwrap();
            case.compare_frame_jacobian(data, st, fid, &fj["jacobian_local_world_aligned"], tally);
            // placement as left by the Jacobian, then by forward kinematics alone
            let m = data.world_from_frame[fid.0];
            let r = matf(&fj["rotation"]);
            tally.cmp(
                &format!("{key} rotation"),
                m.rotation.as_slice(),
                r.as_slice(),
            );
            kinematics::frames_forward_kinematics(model, data, &st.q);
            for (what, m) in [
                ("position", m),
                ("fk position", data.world_from_frame[fid.0]),
            ] {
                tally.cmp(
                    &format!("{key} {what}"),
                    m.translation.as_slice(),
                    &vecf(&fj["position"]),
                );
            }
        }
    });
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

//! `multibody::mount_on_root`: a fixed-based arm mounted on a planar root is the model the
//! URDF loader builds with `root = planar` (identity mount), and with any mount every
//! frame sits at `platform · mount · (arm pose)`.

use moma::dynamics::crba;
use moma::io::urdf::model_from_urdf_file;
use moma::kinematics::{forward_kinematics, random_configuration, update_frame_placements};
use moma::multibody::{Data, RootJoint, mount_on_root};
use moma::spatial::SE3;
use nalgebra::{DVector, Vector3};
use rand::{Rng, SeedableRng};

fn panda(root: RootJoint) -> moma::multibody::Model {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/manipulability/panda.urdf"
    );
    model_from_urdf_file(path, root).unwrap()
}

fn frame_poses(model: &moma::multibody::Model, q: &DVector<f64>) -> Vec<SE3> {
    let mut data = Data::new(model);
    forward_kinematics(model, &mut data, q);
    update_frame_placements(model, &mut data);
    data.world_from_frame.clone()
}

#[test]
fn identity_mount_on_a_planar_root_is_the_planar_urdf_model() {
    let fixed = panda(RootJoint::Fixed);
    let planar = panda(RootJoint::Planar);
    let m = mount_on_root(&fixed, RootJoint::Planar, &SE3::identity()).unwrap();
    assert_eq!(
        (m.nq, m.nv, m.njoints),
        (planar.nq, planar.nv, planar.njoints)
    );
    assert_eq!(m.names, planar.names);
    assert_eq!(m.parents, planar.parents);
    assert_eq!(m.joint_types, planar.joint_types);
    assert_eq!((&m.idx_q, &m.idx_v), (&planar.idx_q, &planar.idx_v));
    assert_eq!(m.joint_of_dof, planar.joint_of_dof);
    assert_eq!(m.root, RootJoint::Planar);
    assert_eq!(m.lower_position_limit, planar.lower_position_limit);
    assert_eq!(m.upper_position_limit, planar.upper_position_limit);
    assert_eq!(m.velocity_limit, planar.velocity_limit);
    assert_eq!(m.effort_limit, planar.effort_limit);
    assert_eq!(
        m.frames[m.last_link_frame().0].name,
        planar.frames[planar.last_link_frame().0].name
    );
    // Every frame of the planar URDF model exists, of the same kind, on the same joint.
    assert_eq!(m.nframes(), planar.nframes());
    for f in &planar.frames {
        let g = m
            .frames
            .iter()
            .find(|g| g.name == f.name && g.kind == f.kind)
            .unwrap_or_else(|| panic!("frame {} missing", f.name));
        assert_eq!(
            m.names[g.parent_joint.0], planar.names[f.parent_joint.0],
            "{}",
            f.name
        );
    }
    // Same kinematics and the same joint-space inertia (the root link's mass moves with
    // the planar root in both).
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3);
    let (mut dm, mut dp) = (Data::new(&m), Data::new(&planar));
    for _ in 0..10 {
        let q = random_configuration(&planar, &mut rng);
        let (a, b) = (frame_poses(&m, &q), frame_poses(&planar, &q));
        for (i, f) in m.frames.iter().enumerate() {
            let j = planar.frame_id(&f.name).unwrap().0;
            let j = planar
                .frames
                .iter()
                .position(|g| g.name == f.name && g.kind == f.kind)
                .unwrap_or(j);
            assert!(
                (a[i].translation - b[j].translation).norm() < 1e-12,
                "{}",
                f.name
            );
            assert!((a[i].rotation - b[j].rotation).norm() < 1e-12, "{}", f.name);
        }
        let hm = crba(&m, &mut dm, &q).clone();
        let hp = crba(&planar, &mut dp, &q).clone();
        assert!((&hm - &hp).abs().max() < 1e-12, "H differs");
    }
}

#[test]
fn every_frame_sits_at_platform_times_mount_times_its_arm_pose() {
    let fixed = panda(RootJoint::Fixed);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    for _ in 0..10 {
        let mount = SE3::from_xyz_rpy(
            [
                rng.random_range(-0.3..0.3),
                rng.random_range(-0.3..0.3),
                0.4,
            ],
            [0.1, -0.2, rng.random_range(-3.0..3.0)],
        );
        let m = mount_on_root(&fixed, RootJoint::Planar, &mount).unwrap();
        let q_arm = random_configuration(&fixed, &mut rng);
        let base = [
            rng.random_range(-2.0..2.0),
            rng.random_range(-2.0..2.0),
            1.3,
        ];
        let q = DVector::from_iterator(m.nq, base.iter().copied().chain(q_arm.iter().copied()));
        let platform = SE3::from_xyz_rpy([base[0], base[1], 0.0], [0.0, 0.0, base[2]]);
        let (a, b) = (frame_poses(&m, &q), frame_poses(&fixed, &q_arm));
        // Frame 0 is the universe, frame 1 the new root joint, frame f + 1 the arm's f.
        assert!((a[1].translation - Vector3::new(base[0], base[1], 0.0)).norm() < 1e-15);
        for f in 1..fixed.nframes() {
            let want = platform.compose(&mount).compose(&b[f]);
            assert!((a[f + 1].translation - want.translation).norm() < 1e-12);
            assert!((a[f + 1].rotation - want.rotation).norm() < 1e-12);
            assert_eq!(m.frames[f + 1].name, fixed.frames[f].name);
        }
        // Mass is the arm's plus its fixed base link, which now moves with the platform.
        let base_mass = fixed.inertias[0].mass();
        assert!((m.total_mass() - fixed.total_mass() - base_mass).abs() < 1e-12);
    }
}

#[test]
fn only_a_fixed_based_model_mounts_on_a_moving_root() {
    let planar = panda(RootJoint::Planar);
    let err = mount_on_root(&planar, RootJoint::Planar, &SE3::identity()).unwrap_err();
    assert!(
        err.to_string().contains("only a fixed-based model"),
        "{err}"
    );
    let fixed = panda(RootJoint::Fixed);
    let err = mount_on_root(&fixed, RootJoint::Fixed, &SE3::identity()).unwrap_err();
    assert!(err.to_string().contains("planar or free-flyer"), "{err}");
    let mut bad = SE3::identity();
    bad.rotation[(0, 0)] = 2.0;
    let err = mount_on_root(&fixed, RootJoint::Planar, &bad).unwrap_err();
    assert!(err.to_string().contains("rotation"), "{err}");
}

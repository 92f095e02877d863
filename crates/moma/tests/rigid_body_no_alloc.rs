//! The rigid-body algorithms allocate nothing after `Data::new`: a counting global
//! allocator wraps the system one and every algorithm (the analytical derivatives of RNEA and ABA
//! after their `DerivativeData::new`) is called with the counter armed,
//! on Panda (fixed, planar and free-flyer root) and on a tree whose joints are not in
//! depth-first order (the ancestor-walk variants), with each root.

use moma::dynamics;
use moma::io::urdf::model_from_urdf_file;
use moma::kinematics::{self, ReferenceFrame};
use moma::multibody::{
    Data, FrameIndex, FrameKind, JointIndex, JointLimits, JointType, Model, ModelBuilder, RootJoint,
};
use moma::spatial::{Inertia, SE3};
use nalgebra::{DVector, Matrix3, Matrix6xX, Vector3};
use rand::SeedableRng;

mod counting_alloc;
use counting_alloc::allocations;

/// Runs every rigid-body algorithm three times on `model` with the counter armed and
/// returns the number of allocations (`rnea_batch` after its `BatchData::new`).
fn count_hot_path(model: &Model, frame: FrameIndex) -> usize {
    let mut data = Data::new(model);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    let q = kinematics::random_configuration(model, &mut rng);
    let v = DVector::from_element(model.nv, 0.3);
    let a = DVector::from_element(model.nv, -0.2);
    let mut q_out = q.clone();
    let mut v_out = v.clone();
    let mut jac = Matrix6xX::zeros(model.nv);
    let fid = frame;
    // five states for the multi-state kernel (one full group of four and a padded tail)
    let mut batch = dynamics::BatchData::new(model);
    let qs: Vec<f64> = (0..5).flat_map(|_| q.iter().copied()).collect();
    let vs: Vec<f64> = (0..5).flat_map(|_| v.iter().copied()).collect();
    let accs: Vec<f64> = (0..5).flat_map(|_| a.iter().copied()).collect();
    let mut taus = vec![0.0; 5 * model.nv];
    let mut derivatives = dynamics::DerivativeData::new(model);
    let mut frame_derivatives = dynamics::FrameDerivativeData::new(model);
    let mut fm = [(); 4].map(|()| Matrix6xX::zeros(model.nv));

    allocations(|| {
        for _ in 0..3 {
            kinematics::forward_kinematics(model, &mut data, &q);
            kinematics::forward_kinematics_second_order(model, &mut data, &q, &v, &a);
            kinematics::update_frame_placements(model, &mut data);
            kinematics::frames_forward_kinematics(model, &mut data, &q);
            kinematics::compute_joint_jacobians(model, &mut data, &q);
            for rf in [
                ReferenceFrame::World,
                ReferenceFrame::Local,
                ReferenceFrame::LocalWorldAligned,
            ] {
                kinematics::frame_jacobian(model, &mut data, &q, fid, rf, &mut jac);
                kinematics::frame_jacobian_from_kinematics(model, &mut data, fid, rf, &mut jac);
                let _ = kinematics::frame_acceleration_bias(model, &mut data, &q, &v, fid, rf);
                let _ = kinematics::frame_velocity(model, &data, fid, rf);
            }
            kinematics::integrate(model, &q, &v, &mut q_out);
            kinematics::difference(model, &q, &q_out, &mut v_out);
            let _ = dynamics::rnea(model, &mut data, &q, &v, &a);
            dynamics::rnea_batch(model, &mut batch, &qs, &vs, &accs, &mut taus);
            let _ = dynamics::crba(model, &mut data, &q);
            let _ = dynamics::aba(model, &mut data, &q, &v, &a);
            let _ = dynamics::nonlinear_effects(model, &mut data, &q, &v);
            let _ = dynamics::gravity_torque(model, &mut data, &q);
            let _ = dynamics::coriolis_matrix(model, &mut data, &q, &v);
            let _ = dynamics::kinetic_energy(model, &mut data, &q, &v);
            let _ = dynamics::potential_energy(model, &mut data, &q);
            let _ = dynamics::center_of_mass(model, &mut data, &q);
            let _ = dynamics::centroidal_momentum_matrix(model, &mut data, &q);
            let _ = dynamics::centroidal_momentum(model, &mut data, &q, &v);
            dynamics::rnea_derivatives(model, &mut derivatives, &q, &v, &a);
            dynamics::aba_derivatives(model, &mut derivatives, &q, &v, &a).unwrap();
            dynamics::forward_kinematics_derivatives(model, &mut frame_derivatives, &q, &v, &a);
            for rf in [
                ReferenceFrame::World,
                ReferenceFrame::Local,
                ReferenceFrame::LocalWorldAligned,
            ] {
                let [vq, aq, av, aa] = &mut fm;
                dynamics::frame_velocity_derivatives(model, &frame_derivatives, fid, rf, vq, aq);
                dynamics::frame_acceleration_derivatives(
                    model,
                    &frame_derivatives,
                    fid,
                    rf,
                    vq,
                    aq,
                    av,
                    aa,
                );
                let _ = dynamics::frame_motion(model, &frame_derivatives, fid, rf);
            }
        }
    })
    .0
}

/// A tree whose joints are not in depth-first order: `a` and `b` hang from the root,
/// `c` from `a` but is added after `b` (Data::new picks the ancestor-walk variants).
fn non_depth_first_model(root: RootJoint) -> (Model, FrameIndex) {
    let mut b = ModelBuilder::new("non-dfs");
    b.set_root(root);
    let body = Inertia::new(
        1.0,
        Vector3::new(0.1, 0.0, 0.05),
        Matrix3::identity() * 0.02,
    );
    let mut parent = JointIndex(0);
    match root {
        RootJoint::Fixed => {}
        RootJoint::Planar | RootJoint::FreeFlyer => {
            let jt = if root == RootJoint::Planar {
                JointType::Planar
            } else {
                JointType::FreeFlyer
            };
            parent = b
                .add_joint(
                    parent,
                    "root_joint",
                    jt,
                    SE3::identity(),
                    JointLimits::unlimited(),
                )
                .unwrap();
            b.append_body_inertia(parent, &body, &SE3::identity())
                .unwrap();
        }
    }
    let off = SE3::from_translation(Vector3::new(0.2, 0.1, 0.3));
    let ja = b
        .add_joint(
            parent,
            "a",
            JointType::RevoluteZ,
            off,
            JointLimits::unlimited(),
        )
        .unwrap();
    let jb = b
        .add_joint(
            parent,
            "b",
            JointType::PrismaticX,
            off,
            JointLimits::unlimited(),
        )
        .unwrap();
    let jc = b
        .add_joint(ja, "c", JointType::RevoluteY, off, JointLimits::unlimited())
        .unwrap();
    for j in [ja, jb, jc] {
        b.append_body_inertia(j, &body, &SE3::identity()).unwrap();
    }
    let f = b
        .add_frame("tip", jc, FrameIndex(0), off, FrameKind::Operational)
        .unwrap();
    let model = b.build().unwrap();
    assert!(
        model
            .parents
            .iter()
            .enumerate()
            .skip(1)
            .all(|(i, p)| p.0 < i)
    );
    (model, f)
}

#[test]
fn algorithms_do_not_allocate() {
    let dir =
        std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/pinocchio/urdf");
    for root in [RootJoint::Fixed, RootJoint::Planar, RootJoint::FreeFlyer] {
        let model = model_from_urdf_file(dir.join("panda.urdf"), root).unwrap();
        let fid = model.frame_id("panda_hand_tcp").unwrap();
        let n = count_hot_path(&model, fid);
        assert_eq!(n, 0, "panda {root}: {n} allocations on the hot path");
        // The slower variants for a tree that is not in depth-first order.
        let (model, fid) = non_depth_first_model(root);
        let n = count_hot_path(&model, fid);
        assert_eq!(
            n, 0,
            "non-depth-first {root}: {n} allocations on the hot path"
        );
        // the counter works: an allocation while armed is seen
        let (seen, probe) = allocations(|| std::hint::black_box(vec![1u8; 16]));
        drop(probe);
        assert!(seen > 0);
    }
}

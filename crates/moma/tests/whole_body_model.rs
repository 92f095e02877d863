//! The whole-body Jacobian on rigid-body models: the chapter's m3 robot built with
//! `ModelBuilder` (against the m3 reference J, det J and manipulability), and Panda on a
//! differential drive (against finite differences of the exact constant-input motion,
//! including the bias term J̄̇·u), plus Panda IK on FK-generated targets.

use moma::ik::model::ModelFrame;
use moma::ik::tasks::{FrameKinematics, PoseTask, TaskRows, WholeBodyTask, pose_error};
use moma::ik::{IkOptions, IkWorkspace, solve, solve_with_restarts};
use moma::io::urdf::model_from_urdf_file;
use moma::manipulability::JacobianSvd;
use moma::mobile::DiffDrive;
use moma::mobile::whole_body::{
    BaseInputs, bias_acceleration, inputs_to_velocity, integrate_base, whole_body_jacobian,
};
use moma::multibody::{
    FrameIndex, FrameKind, JointIndex, JointLimits, JointType, ModelBuilder, RootJoint,
};
use moma::spatial::{Inertia, SE3};
use nalgebra::{DMatrix, DVector, Isometry3, Matrix3, Vector3};
use rand::{Rng, SeedableRng};
use serde_json::Value;
use std::sync::Arc;

fn data_path(name: &str) -> String {
    format!(
        "{}/tests/data/manipulability/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn mat(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = serde_json::from_value(v.clone()).unwrap();
    DMatrix::from_fn(rows.len(), rows[0].len(), |i, j| rows[i][j])
}

/// m3 as a rigid-body model: planar root (the platform CM), capstan (revolute z) L ahead,
/// shoulder pitch about +y (θ1 from the upward vertical), elbow about −y (link 2 at
/// θ1 − θ2), frames at B and at the end effector E.
fn m3_model(l: f64, l1: f64, l2: f64) -> (Arc<moma::multibody::Model>, FrameIndex, FrameIndex) {
    let mut b = ModelBuilder::new("m3");
    b.set_root(RootJoint::Planar);
    let small = Inertia::new(1.0, Vector3::zeros(), Matrix3::identity() * 0.01);
    let root = b
        .add_joint(
            JointIndex(0),
            "platform",
            JointType::Planar,
            SE3::identity(),
            JointLimits::unlimited(),
        )
        .unwrap();
    b.append_body_inertia(root, &small, &SE3::identity())
        .unwrap();
    let cap = b
        .add_joint(
            root,
            "capstan",
            JointType::RevoluteZ,
            SE3::from_translation(Vector3::new(l, 0.0, 0.0)),
            JointLimits::unlimited(),
        )
        .unwrap();
    b.append_body_inertia(cap, &small, &SE3::identity())
        .unwrap();
    let sh = b
        .add_joint(
            cap,
            "shoulder",
            JointType::RevoluteY,
            SE3::identity(),
            JointLimits::unlimited(),
        )
        .unwrap();
    b.append_body_inertia(sh, &small, &SE3::identity()).unwrap();
    let el = b
        .add_joint(
            sh,
            "elbow",
            JointType::revolute(Vector3::new(0.0, -1.0, 0.0)).unwrap(),
            SE3::from_translation(Vector3::new(0.0, 0.0, l1)),
            JointLimits::unlimited(),
        )
        .unwrap();
    b.append_body_inertia(el, &small, &SE3::identity()).unwrap();
    let fb = b
        .add_frame(
            "B",
            cap,
            FrameIndex(0),
            SE3::identity(),
            FrameKind::Operational,
        )
        .unwrap();
    let fe = b
        .add_frame(
            "E",
            el,
            FrameIndex(0),
            SE3::from_translation(Vector3::new(0.0, 0.0, l2)),
            FrameKind::Operational,
        )
        .unwrap();
    (Arc::new(b.build().unwrap()), fb, fe)
}

#[test]
fn m3_built_with_model_builder_matches_the_reference() {
    let d: Value = serde_json::from_str(
        &std::fs::read_to_string(data_path("m3_diffdrive_kinematics.json")).unwrap(),
    )
    .unwrap();
    for case in d["cases"].as_array().unwrap() {
        let p = &case["params"];
        let g = |k: &str| p[k].as_f64().unwrap();
        let (model, fb, fe) = m3_model(g("L"), g("L1"), g("L2"));
        let drive = DiffDrive::new(g("r_w"), g("b"), g("d")).unwrap();
        let q: Vec<f64> = serde_json::from_value(case["state"]["q"].clone()).unwrap();
        let q = DVector::from_vec(q);
        let mut pose = Isometry3::identity();
        let mut jb = DMatrix::zeros(6, model.nv);
        let mut je = DMatrix::zeros(6, model.nv);
        ModelFrame::new(model.clone(), fb)
            .unwrap()
            .pose_and_jacobian(&q, &mut pose, &mut jb)
            .unwrap();
        ModelFrame::new(model.clone(), fe)
            .unwrap()
            .pose_and_jacobian(&q, &mut pose, &mut je)
            .unwrap();
        // Position X = [x_B, y_B, x_E, y_E, z_E].
        let x_ref: Vec<f64> = serde_json::from_value(case["outputs"]["X"].clone()).unwrap();
        let t = pose.translation.vector;
        for (a, b) in [t.x, t.y, t.z].iter().zip(&x_ref[2..]) {
            assert!((a - b).abs() < 1e-12);
        }
        let jbar_b = whole_body_jacobian(&drive, BaseInputs::Wheels, q[2], &jb).unwrap();
        let jbar_e = whole_body_jacobian(&drive, BaseInputs::Wheels, q[2], &je).unwrap();
        let mut j = DMatrix::zeros(5, 5);
        j.row_mut(0).copy_from(&jbar_b.row(0));
        j.row_mut(1).copy_from(&jbar_b.row(1));
        for r in 0..3 {
            j.row_mut(2 + r).copy_from(&jbar_e.row(r));
        }
        let j_ref = mat(&case["outputs"]["J"]);
        assert!((&j - &j_ref).abs().max() < 1e-12, "case {}", case["id"]);
        let det_ref = case["outputs"]["det_J"].as_f64().unwrap();
        assert!((j.determinant() - det_ref).abs() < 1e-10 * det_ref.abs().max(1e-6));
        let svd = JacobianSvd::new(&j).unwrap();
        let m = &case["outputs"]["manipulability_J"];
        let w = m["yoshikawa_sqrt_det_JJt"].as_f64().unwrap();
        assert!((svd.yoshikawa().unwrap() - w).abs() < 1e-9 * w);
        let ee = &case["outputs"]["manipulability_J_endeffector"];
        let svd_e = JacobianSvd::new(&j.rows(2, 3).into_owned()).unwrap();
        let we = ee["yoshikawa_sqrt_det_JJt"].as_f64().unwrap();
        assert!((svd_e.yoshikawa().unwrap() - we).abs() < 1e-9 * we);
    }
}

fn panda_planar() -> ModelFrame {
    let model = model_from_urdf_file(data_path("panda.urdf"), RootJoint::Planar).unwrap();
    ModelFrame::by_name(Arc::new(model), "panda_hand_tcp").unwrap()
}

/// Model configuration after applying whole-body inputs `u` for time `t` from `q`.
fn flow(
    drive: &DiffDrive,
    inputs: BaseInputs,
    q: &DVector<f64>,
    u: &DVector<f64>,
    t: f64,
) -> DVector<f64> {
    let (v, om) = match inputs {
        BaseInputs::Platform => (u[0], u[1]),
        BaseInputs::Wheels => {
            let w = drive.wheel_to_platform();
            (
                w[(0, 0)] * u[0] + w[(0, 1)] * u[1],
                w[(1, 0)] * u[0] + w[(1, 1)] * u[1],
            )
        }
    };
    let b = integrate_base(drive, [q[0], q[1], q[2]], v * t, om * t);
    let mut out = q.clone();
    out[0] = b[0];
    out[1] = b[1];
    out[2] = b[2];
    for k in 2..u.len() {
        out[k + 1] += u[k] * t;
    }
    out
}

#[test]
fn panda_whole_body_jacobian_and_bias_match_finite_differences() {
    let mut kin = panda_planar();
    let model = Arc::new(kin.model().clone());
    let drive = DiffDrive::new(0.08, 0.27, 0.12).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let nv = kin.nv();
    for inputs in [BaseInputs::Platform, BaseInputs::Wheels] {
        for _ in 0..5 {
            let mut q = moma::kinematics::random_configuration(&model, &mut rng);
            q[2] = rng.random_range(-3.0..3.0);
            let mut pose = Isometry3::identity();
            let mut j6 = DMatrix::zeros(6, nv);
            kin.pose_and_jacobian(&q, &mut pose, &mut j6).unwrap();
            assert_eq!((j6.nrows(), j6.ncols()), (6, 12));
            let jbar = whole_body_jacobian(&drive, inputs, q[2], &j6).unwrap();
            assert_eq!((jbar.nrows(), jbar.ncols()), (6, 11));
            // Column k: d/dt of the pose along the exact motion with unit input k.
            let h = 1e-6;
            for k in 0..11 {
                let mut u = DVector::zeros(11);
                u[k] = 1.0;
                let mut pp = Isometry3::identity();
                let mut pm = Isometry3::identity();
                let mut jj = DMatrix::zeros(6, nv);
                kin.pose_and_jacobian(&flow(&drive, inputs, &q, &u, h), &mut pp, &mut jj)
                    .unwrap();
                kin.pose_and_jacobian(&flow(&drive, inputs, &q, &u, -h), &mut pm, &mut jj)
                    .unwrap();
                let e = pose_error(&pp, &pm);
                for r in 0..6 {
                    let fd = e[r] / (2.0 * h);
                    assert!(
                        (fd - jbar[(r, k)]).abs() < 1e-6,
                        "{inputs:?} col {k} row {r}: {fd} vs {}",
                        jbar[(r, k)]
                    );
                }
            }
            // Bias J̄̇·u against the second difference of the position along constant u.
            let u = DVector::from_fn(11, |_, _| rng.random_range(-0.5..0.5));
            let v = inputs_to_velocity(&drive, inputs, q[2], &u);
            let jdqd = kin.jdot_qdot(&q, &v);
            let bias = bias_acceleration(&drive, inputs, q[2], &j6, &jdqd, &u).unwrap();
            let h = 1e-4;
            let pos = |qq: &DVector<f64>, kin: &mut ModelFrame| {
                let mut p = Isometry3::identity();
                let mut jj = DMatrix::zeros(6, nv);
                kin.pose_and_jacobian(qq, &mut p, &mut jj).unwrap();
                p.translation.vector
            };
            let acc = (pos(&flow(&drive, inputs, &q, &u, h), &mut kin) - 2.0 * pos(&q, &mut kin)
                + pos(&flow(&drive, inputs, &q, &u, -h), &mut kin))
                / (h * h);
            for r in 0..3 {
                assert!(
                    (acc[r] - bias[r]).abs() < 1e-5,
                    "{inputs:?} bias row {r}: {} vs {}",
                    acc[r],
                    bias[r]
                );
            }
        }
    }
}

#[test]
fn panda_ik_on_fk_targets() {
    let model = Arc::new(model_from_urdf_file(data_path("panda.urdf"), RootJoint::Fixed).unwrap());
    let kin = ModelFrame::by_name(model.clone(), "panda_hand_tcp").unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let q0 = moma::kinematics::neutral(&model);
    let opts = IkOptions::default();
    let mut converged = 0;
    let mut ws: Option<IkWorkspace> = None;
    for i in 0..100 {
        let q_true = moma::kinematics::random_configuration(&model, &mut rng);
        let mut k2 = kin.clone();
        let mut target = Isometry3::identity();
        let mut j = DMatrix::zeros(6, model.nv);
        k2.pose_and_jacobian(&q_true, &mut target, &mut j).unwrap();
        let mut task = PoseTask::new(kin.clone(), target, &TaskRows::Full).unwrap();
        let w = ws.get_or_insert_with(|| IkWorkspace::new(&task));
        let r = solve_with_restarts(&mut task, &q0, &opts, 10, i, w).unwrap();
        if r.converged {
            converged += 1;
            let mut p = Isometry3::identity();
            k2.pose_and_jacobian(&r.q, &mut p, &mut j).unwrap();
            let e = pose_error(&p, &target);
            assert!(e.iter().map(|x| x * x).sum::<f64>().sqrt() <= 1e-6);
            for k in 0..model.nq {
                assert!(r.q[k] >= model.lower_position_limit[k] - 1e-12);
                assert!(r.q[k] <= model.upper_position_limit[k] + 1e-12);
            }
        }
    }
    assert!(converged >= 97, "{converged}/100");
}

#[test]
fn panda_whole_body_ik_reaches_a_far_target() {
    let kin = panda_planar();
    let drive = DiffDrive::new(0.08, 0.27, 0.12).unwrap();
    let target = moma::ik::tasks::target_from_slice(&[3.0, -2.0, 0.4, 1.0, 0.0, 0.0, 0.0]).unwrap();
    let mut q0 = moma::kinematics::neutral(kin.model());
    q0[6] = -1.5; // joint 4 away from its limit
    q0[8] = 1.5;
    let mut task = WholeBodyTask::new(
        kin.clone(),
        drive,
        BaseInputs::Platform,
        target,
        &TaskRows::Full,
    )
    .unwrap();
    let mut ws = IkWorkspace::new(&task);
    let r = solve(
        &mut task,
        &q0,
        &IkOptions {
            max_iterations: 500,
            ..IkOptions::default()
        },
        &mut ws,
    )
    .unwrap();
    assert!(r.converged, "{r:?}");
    let mut k = kin.clone();
    let mut p = Isometry3::identity();
    let mut j = DMatrix::zeros(6, k.nv());
    k.pose_and_jacobian(&r.q, &mut p, &mut j).unwrap();
    let e = pose_error(&p, &target);
    assert!(e.iter().map(|x| x * x).sum::<f64>().sqrt() <= 1e-6);
}

#[test]
fn panda_whole_body_null_space_raises_arm_manipulability() {
    use moma::ik::{KinematicTask, NullSpaceObjective};
    use moma::manipulability::Measure;
    let kin = panda_planar();
    let drive = DiffDrive::new(0.08, 0.27, 0.12).unwrap();
    let target = moma::ik::tasks::target_from_slice(&[3.0, -1.0, 0.4, 1.0, 0.0, 0.0, 0.0]).unwrap();
    let q0 = DVector::from_vec(vec![0., 0., 0., 0., 0., 0., -1.5, 0., 1.5, 0.7, 0., 0.]);
    let arm_w = |ns: NullSpaceObjective| {
        let mut task = WholeBodyTask::new(
            kin.clone(),
            drive,
            BaseInputs::Platform,
            target,
            &TaskRows::Full,
        )
        .unwrap();
        let mut ws = IkWorkspace::new(&task);
        let opts = IkOptions {
            null_space: ns,
            max_iterations: 3000,
            ..IkOptions::default()
        };
        let r = solve(&mut task, &q0, &opts, &mut ws).unwrap();
        // converged: the task is met and the objective settled before the budget ran out
        assert!(r.converged && r.task_met, "{r:?}");
        let mut e = DVector::zeros(6);
        let mut j = DMatrix::zeros(6, 11);
        task.residual_and_jacobian(&r.q, &mut e, &mut j).unwrap();
        let arm = j.columns(2, 9).into_owned();
        JacobianSvd::new(&arm).unwrap().yoshikawa().unwrap()
    };
    let plain = arm_w(NullSpaceObjective::None);
    let boosted = arm_w(NullSpaceObjective::Manipulability {
        measure: Measure::Yoshikawa,
        gain: 0.2,
    });
    assert!(boosted > 1.05 * plain, "{boosted} vs {plain}");
}

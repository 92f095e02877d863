//! IK conventions on real models: the task Jacobian is the exact derivative of the pose
//! error (the orientation rows through the inverse left Jacobian of SO(3)), the solver
//! converges on rotation errors near π, the posture term takes the shortest way for
//! continuous joints and works on free-flyer models, and the statuses say what happened.

use moma::ik::model::ModelFrame;
use moma::ik::tasks::{FrameKinematics, PoseTask, TaskRows, pose_error};
use moma::ik::{IkOptions, IkStatus, IkWorkspace, KinematicTask, NullSpaceObjective, solve};
use moma::io::urdf::model_from_urdf_file;
use moma::kinematics;
use moma::multibody::{JointIndex, JointLimits, JointType, Model, ModelBuilder, RootJoint};
use moma::spatial::{Inertia, SE3};
use nalgebra::{DMatrix, DVector, Isometry3, Matrix3, Vector3};
use rand::SeedableRng;
use std::f64::consts::PI;
use std::sync::Arc;

fn panda(root: RootJoint) -> ModelFrame {
    let path = format!(
        "{}/tests/data/pinocchio/urdf/panda.urdf",
        env!("CARGO_MANIFEST_DIR")
    );
    let model = Arc::new(model_from_urdf_file(path, root).unwrap());
    ModelFrame::by_name(model, "panda_hand_tcp").unwrap()
}

fn pose_of(kin: &mut ModelFrame, q: &DVector<f64>) -> Isometry3<f64> {
    let mut pose = Isometry3::identity();
    let mut j = DMatrix::zeros(6, kin.nv());
    kin.pose_and_jacobian(q, &mut pose, &mut j).unwrap();
    pose
}

fn rotation_angle(a: &Isometry3<f64>, b: &Isometry3<f64>) -> f64 {
    (a.rotation * b.rotation.inverse()).angle()
}

#[test]
fn task_jacobian_is_the_exact_derivative_of_the_error() {
    let mut kin = panda(RootJoint::Fixed);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(11);
    let nv = kin.nv();
    let mut checked_large = 0;
    for _ in 0..40 {
        let q = kinematics::random_configuration(kin.model(), &mut rng);
        let qt = kinematics::random_configuration(kin.model(), &mut rng);
        let target = pose_of(&mut kin, &qt);
        let mut task = PoseTask::new(kin.clone(), target, &TaskRows::Full).unwrap();
        let mut e = DVector::zeros(6);
        let mut j = DMatrix::zeros(6, nv);
        task.residual_and_jacobian(&q, &mut e, &mut j).unwrap();
        let theta = e.rows(3, 3).norm();
        if theta > 3.0 {
            continue; // too close to the cut of the log map for a central difference
        }
        if theta > 2.0 {
            checked_large += 1;
        }
        let h = 1e-6;
        let (mut ep, mut em) = (DVector::zeros(6), DVector::zeros(6));
        let mut jj = DMatrix::zeros(6, nv);
        let mut qp = q.clone();
        let mut qm = q.clone();
        for k in 0..nv {
            let mut d = DVector::zeros(nv);
            d[k] = h;
            kinematics::integrate(kin.model(), &q, &d, &mut qp);
            kinematics::integrate(kin.model(), &q, &(-&d), &mut qm);
            task.residual_and_jacobian(&qp, &mut ep, &mut jj).unwrap();
            task.residual_and_jacobian(&qm, &mut em, &mut jj).unwrap();
            let fd = (&ep - &em) / (2.0 * h);
            let err = (&fd - j.column(k)).norm();
            assert!(err < 1e-6, "θ = {theta:.3}: column {k} off by {err:e}");
        }
    }
    assert!(checked_large >= 3, "only {checked_large} large-angle cases");
}

#[test]
fn converges_on_rotation_errors_near_pi() {
    // Targets from FK (so reachable), seeds that turn the wrist joint by about 3 rad and
    // perturb the other joints: rotation errors between 2.9 rad and π at the seed.
    use rand::Rng;
    let mut kin = panda(RootJoint::Fixed);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    let opts = IkOptions {
        tolerance: 1e-10,
        max_iterations: 300,
        ..IkOptions::default()
    };
    let mut found = 0;
    let mut tries = 0;
    while found < 8 {
        tries += 1;
        assert!(tries < 1000, "no seed/target pairs near π");
        let mut qt = kinematics::random_configuration(kin.model(), &mut rng);
        qt[6] = rng.random_range(-2.8..-0.3);
        let mut q0 = qt.clone();
        for k in 0..6 {
            q0[k] = (qt[k] + rng.random_range(-0.15..0.15)).clamp(
                kin.model().lower_position_limit[k],
                kin.model().upper_position_limit[k],
            );
        }
        q0[6] = qt[6] + rng.random_range(2.95..3.1);
        let target = pose_of(&mut kin, &qt);
        let angle = rotation_angle(&pose_of(&mut kin, &q0), &target);
        if angle < 2.9 {
            continue;
        }
        found += 1;
        let mut task = PoseTask::new(kin.clone(), target, &TaskRows::Full).unwrap();
        let mut ws = IkWorkspace::new(&task);
        let r = solve(&mut task, &q0, &opts, &mut ws).unwrap();
        assert!(
            r.converged,
            "start angle {angle:.4} rad: {:?}, residual {:e}",
            r.status, r.residual_norm
        );
        let e = pose_error(&pose_of(&mut kin, &r.q), &target);
        assert!(e.iter().all(|x| x.abs() < 1e-9), "{e:?}");
    }
}

/// A free-flyer body carrying a continuous joint (unbounded revolute z) with a frame on
/// an arm of 0.5 m.
fn floating_with_continuous_joint() -> Arc<Model> {
    let mut b = ModelBuilder::new("ff");
    b.set_root(RootJoint::FreeFlyer);
    let body = Inertia::new(1.0, Vector3::zeros(), Matrix3::identity() * 0.1);
    let root = b
        .add_joint(
            JointIndex(0),
            "root_joint",
            JointType::FreeFlyer,
            SE3::identity(),
            JointLimits::unlimited(),
        )
        .unwrap();
    b.append_body_inertia(root, &body, &SE3::identity())
        .unwrap();
    let j = b
        .add_joint(
            root,
            "spin",
            JointType::RevoluteZ,
            SE3::identity(),
            JointLimits::unlimited(),
        )
        .unwrap();
    b.append_body_inertia(j, &body, &SE3::identity()).unwrap();
    b.add_frame(
        "tip",
        j,
        moma::multibody::FrameIndex(0),
        SE3::from_translation(Vector3::new(0.5, 0.0, 0.0)),
        moma::multibody::FrameKind::Operational,
    )
    .unwrap();
    Arc::new(b.build().unwrap())
}

#[test]
fn difference_takes_the_shortest_angle() {
    let model = floating_with_continuous_joint();
    let mut q0 = kinematics::neutral(&model);
    let mut q1 = q0.clone();
    q0[7] = 3.0;
    q1[7] = -3.0; // 2π − 6 = 0.283 rad ahead, not 6 rad back
    let mut d = DVector::zeros(model.nv);
    kinematics::difference(&model, &q0, &q1, &mut d);
    assert!((d[6] - (2.0 * PI - 6.0)).abs() < 1e-12, "{d}");
    // integrate(q0, d) lands on q1 modulo 2π
    let mut back = q0.clone();
    kinematics::integrate(&model, &q0, &d, &mut back);
    assert!((kinematics::wrap_angle(back[7] - q1[7])).abs() < 1e-12);
    // a planar root: only θ wraps, x and y subtract (world axes)
    let panda = panda(RootJoint::Planar);
    let m = panda.model();
    let mut a = kinematics::neutral(m);
    let mut b = a.clone();
    a[0] = -5.0;
    b[0] = 5.0;
    a[2] = -3.1;
    b[2] = 3.1;
    let mut d = DVector::zeros(m.nv);
    kinematics::difference(m, &a, &b, &mut d);
    assert_eq!(d[0], 10.0);
    assert!((d[2] - (6.2 - 2.0 * PI)).abs() < 1e-12, "{d}");
    // bounded revolute joints subtract (Panda's joints have limits)
    a[3] = -2.0;
    b[3] = 2.0;
    kinematics::difference(m, &a, &b, &mut d);
    assert_eq!(d[3], 4.0);
}

#[test]
fn posture_term_wraps_and_works_on_a_free_flyer() {
    let model = floating_with_continuous_joint();
    let kin = ModelFrame::by_name(model.clone(), "tip").unwrap();
    let mut pref = kinematics::neutral(&model);
    pref[7] = 3.0;
    let mut q = kinematics::neutral(&model);
    q[7] = -3.0;
    let task = PoseTask::new(kin, Isometry3::identity(), &TaskRows::Position)
        .unwrap()
        .with_preferred_posture(pref)
        .unwrap();
    let mut g = DVector::zeros(model.nv);
    assert!(task.posture_gradient(&q, &mut g));
    // the shortest way from −3 to 3 is −0.283 rad, not +6 rad; the base is already there
    assert!((g[6] + (2.0 * PI - 6.0)).abs() < 1e-12, "{g}");
    assert!(g.rows(0, 6).norm() < 1e-12);
}

#[test]
fn null_space_objective_that_has_not_settled_is_not_called_converged() {
    // A redundant 7-dof arm, a position task (4 redundant dofs) and a posture objective
    // that pulls far away: 3 iterations meet the task but cannot finish the objective.
    let kin = panda(RootJoint::Fixed);
    let mut kin2 = kin.clone();
    let q_goal = DVector::from_vec(vec![0.3, -0.4, 0.2, -1.8, 0.1, 1.6, 0.5, 0.02, 0.02]);
    let target = pose_of(&mut kin2, &q_goal);
    let pref = DVector::from_vec(vec![-2.0, 1.2, -2.0, -0.5, -2.0, 3.0, -2.0, 0.0, 0.04]);
    let mut task = PoseTask::new(kin, target, &TaskRows::Position)
        .unwrap()
        .with_preferred_posture(pref)
        .unwrap();
    let mut ws = IkWorkspace::new(&task);
    let opts = |max_iterations| IkOptions {
        tolerance: 1e-6,
        max_iterations,
        null_space: NullSpaceObjective::Posture { gain: 0.05 },
        ..IkOptions::default()
    };
    let r = solve(&mut task, &q_goal, &opts(3), &mut ws).unwrap();
    assert_eq!(r.status, IkStatus::ObjectiveUnsettled, "{r:?}");
    assert!(r.task_met && !r.converged);
    assert!(r.residual_norm <= 1e-6);
    // position task: the residual has the three position rows only
    assert_eq!(r.residual.len(), 3);
    // with a generous budget the objective settles and the solver converges
    let r = solve(&mut task, &q_goal, &opts(5000), &mut ws).unwrap();
    assert_eq!(r.status, IkStatus::Converged, "{r:?}");
    assert!(r.converged && r.task_met && r.iterations < 5000);
}

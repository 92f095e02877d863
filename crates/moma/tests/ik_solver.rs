//! The IK solver core on an analytic kinematic chain: a planar n-R arm (revolute z joints)
//! optionally mounted on a differential-drive platform. Checks convergence on reachable
//! targets, honest non-convergence on unreachable ones, joint limits, singular seeds,
//! the whole-body task (base motion, weights, null-space objectives).

use moma::ik::tasks::{FrameKinematics, PoseTask, TaskRows, WholeBodyTask, pose_error};
use moma::ik::{
    IkOptions, IkStatus, IkWorkspace, KinematicTask, NullSpaceObjective, solve, solve_with_restarts,
};
use moma::manipulability::{JacobianSvd, Measure};
use moma::mobile::DiffDrive;
use moma::mobile::whole_body::BaseInputs;
use nalgebra::{DMatrix, DVector, Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, SeedableRng};

mod ik_common;
use ik_common::PlanarChain;

fn random_q(rng: &mut impl Rng, chain: &PlanarChain) -> DVector<f64> {
    let n = chain.nq();
    let o = chain.off();
    DVector::from_fn(n, |k, _| {
        if k < o {
            rng.random_range(-1.0..1.0)
        } else {
            rng.random_range(chain.lower[k - o].max(-3.0)..chain.upper[k - o].min(3.0))
        }
    })
}

#[test]
fn arm_converges_on_reachable_targets() {
    let chain = PlanarChain::arm(vec![0.5, 0.4, 0.3, 0.2]);
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(1);
    let opts = IkOptions {
        tolerance: 1e-9,
        ..IkOptions::default()
    };
    let rows: TaskRows = "rows:0,1,5".parse().unwrap();
    let mut converged = 0;
    let mut not_converged = 0;
    for _ in 0..100 {
        let q_true = random_q(&mut rng, &chain);
        let target = chain.fk(&q_true);
        let mut task = PoseTask::new(chain.clone(), target, &rows).unwrap();
        let mut ws = IkWorkspace::new(&task);
        let q0 = random_q(&mut rng, &chain);
        let r = solve(&mut task, &q0, &opts, &mut ws).unwrap();
        assert!(r.residual_norm.is_finite());
        let r = if r.converged {
            r
        } else {
            // Joint limits create genuine local minima: restarts get out of them.
            solve_with_restarts(&mut task, &q0, &opts, 10, 3, &mut ws).unwrap()
        };
        if r.converged {
            converged += 1;
            let e = pose_error(&chain.fk(&r.q), &target);
            assert!(e[0].abs() < 1e-9 && e[1].abs() < 1e-9 && e[5].abs() < 1e-9);
            for i in 0..4 {
                assert!(r.q[i] >= chain.lower[i] && r.q[i] <= chain.upper[i]);
            }
        } else {
            not_converged += 1;
            // An honest report: a status that says why, the residual that belongs to
            // the returned q (recomputed from the chain's own FK), within the limits.
            assert_ne!(r.status, IkStatus::Converged);
            assert!(!r.task_met);
            let e = pose_error(&chain.fk(&r.q), &target);
            let e3 = [e[0], e[1], e[5]];
            for (got, want) in r.residual.iter().zip(e3) {
                assert!((got - want).abs() < 1e-12, "{got} vs {want}");
            }
            let norm = (e3[0] * e3[0] + e3[1] * e3[1] + e3[2] * e3[2]).sqrt();
            assert!((r.residual_norm - norm).abs() < 1e-12);
            for i in 0..4 {
                assert!(r.q[i] >= chain.lower[i] && r.q[i] <= chain.upper[i]);
            }
        }
    }
    assert!(converged >= 99, "converged {converged}/100");
    assert_eq!(converged + not_converged, 100);
}

#[test]
fn unreachable_target_reports_not_converged() {
    let chain = PlanarChain::arm(vec![0.5, 0.4]);
    let target = Isometry3::translation(2.0, 0.5, 0.0);
    let mut task = PoseTask::new(chain, target, &TaskRows::Position).unwrap();
    let mut ws = IkWorkspace::new(&task);
    let r = solve(
        &mut task,
        &DVector::from_vec(vec![0.3, 0.4]),
        &IkOptions::default(),
        &mut ws,
    )
    .unwrap();
    assert!(!r.converged);
    assert_ne!(r.status, IkStatus::Converged);
    // Best effort: the arm stretches towards the target (distance 0.9 from it).
    let dist = (2.0f64.hypot(0.5)) - 0.9;
    // (within 1 %: the solver stops once the crawl towards the closest point slows down).
    assert!(
        r.residual_norm >= dist - 1e-9 && r.residual_norm < dist * 1.01,
        "{}",
        r.residual_norm
    );
    assert!(r.q.iter().all(|x| x.is_finite()));
    // Stretched arm: the final Jacobian is (nearly) singular, and σ_min says so.
    assert!(r.sigma_min < 0.1, "{}", r.sigma_min);
}

#[test]
fn singular_seed_and_limits() {
    // Start exactly stretched (singular) – damping must still find the target.
    let mut chain = PlanarChain::arm(vec![0.5, 0.4]);
    chain.lower = vec![-3.0, 0.0];
    chain.upper = vec![3.0, 3.0];
    let q_true = DVector::from_vec(vec![0.2, 1.0]);
    let target = chain.fk(&q_true);
    let mut task = PoseTask::new(chain.clone(), target, &TaskRows::Position).unwrap();
    let mut ws = IkWorkspace::new(&task);
    let r = solve(
        &mut task,
        &DVector::from_vec(vec![0.0, 0.0]),
        &IkOptions::default(),
        &mut ws,
    )
    .unwrap();
    assert!(r.converged, "{r:?}");
    // The elbow limit q2 >= 0 excludes the mirror solution.
    assert!((r.q[0] - 0.2).abs() < 1e-5 && (r.q[1] - 1.0).abs() < 1e-5);

    // A target only reachable with q2 < 0 (limit) is not reached; q stays inside limits.
    let target = chain.fk(&DVector::from_vec(vec![0.2, -1.0]));
    let mut task = PoseTask::new(chain, target, &TaskRows::Full).unwrap();
    let r = solve(
        &mut task,
        &DVector::from_vec(vec![0.0, 0.5]),
        &IkOptions::default(),
        &mut ws,
    )
    .unwrap();
    assert!(!r.converged);
    assert!(r.q[1] >= 0.0);
}

#[test]
fn bad_options_and_seed_are_errors() {
    let chain = PlanarChain::arm(vec![0.5, 0.4]);
    let mut task = PoseTask::new(chain, Isometry3::identity(), &TaskRows::Position).unwrap();
    let mut ws = IkWorkspace::new(&task);
    let q0 = DVector::from_vec(vec![0.1, 0.2]);
    assert!(
        solve(
            &mut task,
            &DVector::zeros(3),
            &IkOptions::default(),
            &mut ws
        )
        .is_err()
    );
    let nan = DVector::from_vec(vec![f64::NAN, 0.2]);
    assert!(solve(&mut task, &nan, &IkOptions::default(), &mut ws).is_err());
    let bad = IkOptions {
        tolerance: -1.0,
        ..IkOptions::default()
    };
    assert!(solve(&mut task, &q0, &bad, &mut ws).is_err());
    let bad = IkOptions {
        weights: Some(vec![1.0]),
        ..IkOptions::default()
    };
    assert!(solve(&mut task, &q0, &bad, &mut ws).is_err());
    let bad = IkOptions {
        null_space: NullSpaceObjective::Manipulability {
            measure: Measure::Eccentricity,
            gain: 1.0,
        },
        ..IkOptions::default()
    };
    assert!(solve(&mut task, &q0, &bad, &mut ws).is_err());
    assert!("rows:0,7".parse::<TaskRows>().is_err());
    assert!("rows:1,1".parse::<TaskRows>().is_err());
    assert!("sideways".parse::<TaskRows>().is_err());
}

fn mobile_chain() -> PlanarChain {
    PlanarChain {
        mobile: true,
        mount: 0.2,
        lengths: vec![0.5, 0.4, 0.2],
        lower: vec![-2.8; 3],
        upper: vec![2.8; 3],
    }
}

#[test]
fn whole_body_reaches_beyond_the_arm_and_respects_the_constraint() {
    let chain = mobile_chain();
    let drive = DiffDrive::new(0.1, 0.25, 0.15).unwrap();
    let q0 = DVector::from_vec(vec![0.0, 0.0, 0.0, 0.3, 0.5, 0.2]);
    // 3 m away, sideways: the arm (reach 1.3 m) alone cannot get there.
    let target = Isometry3::from_parts(
        Translation3::new(1.0, 3.0, 0.0),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), 0.7),
    );
    let rows: TaskRows = "rows:0,1,5".parse().unwrap();
    for inputs in [BaseInputs::Platform, BaseInputs::Wheels] {
        let task = WholeBodyTask::new(chain.clone(), drive, inputs, target, &rows).unwrap();
        let mut task = Recording {
            inner: task,
            steps: Default::default(),
        };
        let mut ws = IkWorkspace::new(&task);
        let opts = IkOptions {
            max_iterations: 500,
            ..IkOptions::default()
        };
        let r = solve(&mut task, &q0, &opts, &mut ws).unwrap();
        assert!(r.converged, "{inputs:?}: {r:?}");
        let e = pose_error(&chain.fk(&r.q), &target);
        assert!(e[0].abs() < 1e-6 && e[1].abs() < 1e-6 && e[5].abs() < 1e-6);
        // The base moved a lot (more than the arm could cover).
        assert!(r.q[0].hypot(r.q[1]) > 1.5);
        // The constraint: every base motion the solver tried is a rolling arc without
        // side slip. The axle midpoint P (d behind the base origin) moves along a circle
        // tangent to the heading, so its chord points along the mean heading
        // θ0 + Δθ/2 (forwards or backwards): the chord's sideways component is zero.
        let steps = task.steps.borrow();
        assert!(steps.len() > 3, "{} steps", steps.len());
        let mut travelled = 0.0;
        for (q, out) in steps.iter() {
            let axle = |x: f64, y: f64, th: f64| (x - drive.d * th.cos(), y - drive.d * th.sin());
            let (px0, py0) = axle(q[0], q[1], q[2]);
            let (px1, py1) = axle(out[0], out[1], out[2]);
            let mid = 0.5 * (q[2] + out[2]);
            let sideways = -(px1 - px0) * mid.sin() + (py1 - py0) * mid.cos();
            let chord = (px1 - px0).hypot(py1 - py0);
            assert!(
                sideways.abs() <= 1e-9 * (1.0 + chord),
                "{inputs:?}: side slip {sideways:e} over a chord of {chord}"
            );
            travelled += chord;
        }
        assert!(travelled > 1.5, "{travelled}");
    }
}

/// A task wrapper that records every `(q, q ⊕ δ)` the solver asks for.
struct Recording<T> {
    inner: T,
    steps: std::cell::RefCell<Vec<(DVector<f64>, DVector<f64>)>>,
}

impl<T: KinematicTask> KinematicTask for Recording<T> {
    fn nq(&self) -> usize {
        self.inner.nq()
    }
    fn nv(&self) -> usize {
        self.inner.nv()
    }
    fn task_dim(&self) -> usize {
        self.inner.task_dim()
    }
    fn residual_and_jacobian(
        &mut self,
        q: &DVector<f64>,
        residual: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> moma::Result<()> {
        self.inner.residual_and_jacobian(q, residual, jacobian)
    }
    fn integrate(&self, q: &DVector<f64>, delta: &DVector<f64>, out: &mut DVector<f64>) {
        self.inner.integrate(q, delta, out);
        self.steps.borrow_mut().push((q.clone(), out.clone()));
    }
    fn blocked_inputs(&self, q: &DVector<f64>, delta: &DVector<f64>, blocked: &mut [bool]) {
        self.inner.blocked_inputs(q, delta, blocked);
    }
}

#[test]
fn whole_body_weights_trade_base_against_arm() {
    let chain = mobile_chain();
    let drive = DiffDrive::new(0.1, 0.25, 0.0).unwrap();
    let q0 = DVector::from_vec(vec![0.0, 0.0, 0.0, 0.3, 0.5, 0.2]);
    // Reachable by the arm alone.
    let target = Isometry3::translation(0.6, 0.7, 0.0);
    let base_travel = |w_base: f64| {
        let mut task = WholeBodyTask::new(
            chain.clone(),
            drive,
            BaseInputs::Platform,
            target,
            &TaskRows::Position,
        )
        .unwrap();
        let mut ws = IkWorkspace::new(&task);
        let opts = IkOptions {
            weights: Some(vec![w_base, w_base, 1.0, 1.0, 1.0]),
            ..IkOptions::default()
        };
        let r = solve(&mut task, &q0, &opts, &mut ws).unwrap();
        assert!(r.converged);
        r.q[0].hypot(r.q[1]) + r.q[2].abs()
    };
    let heavy = base_travel(1e4);
    let light = base_travel(1e-2);
    assert!(heavy < 1e-2, "{heavy}");
    assert!(light > 10.0 * heavy, "{light} vs {heavy}");
}

#[test]
fn null_space_manipulability_keeps_the_arm_well_conditioned() {
    // Wide limits: this test is about the null space, not about limit-induced minima.
    let mut chain = PlanarChain::arm(vec![0.5, 0.4, 0.3]);
    chain.lower = vec![-10.0; 3];
    chain.upper = vec![10.0; 3];
    let target = Isometry3::translation(0.35, 0.2, 0.0);
    let w_final = |ns: NullSpaceObjective, q0: &DVector<f64>| {
        let rows = TaskRows::Rows(vec![0, 1]);
        let mut task = PoseTask::new(chain.clone(), target, &rows).unwrap();
        let mut ws = IkWorkspace::new(&task);
        let opts = IkOptions {
            null_space: ns,
            tolerance: 1e-8,
            max_iterations: 400,
            ..IkOptions::default()
        };
        let r = solve(&mut task, q0, &opts, &mut ws).unwrap();
        assert!(r.converged, "{r:?}");
        let mut e = DVector::zeros(2);
        let mut j = DMatrix::zeros(2, 3);
        task.residual_and_jacobian(&r.q, &mut e, &mut j).unwrap();
        JacobianSvd::new(&j).unwrap().yoshikawa().unwrap()
    };
    // The best w over the self-motion manifold, by brute force: sweep q1, solve the
    // remaining 2R analytically (both elbows).
    let (l1, l2, l3) = (0.5, 0.4, 0.3);
    let (tx, ty) = (target.translation.x, target.translation.y);
    let mut w_max: f64 = 0.0;
    for k in 0..20000 {
        let q1 = -3.0 + 6.0 * k as f64 / 20000.0;
        let (px, py) = (tx - l1 * q1.cos(), ty - l1 * q1.sin());
        let c3 = (px * px + py * py - l2 * l2 - l3 * l3) / (2.0 * l2 * l3);
        if c3.abs() > 1.0 {
            continue;
        }
        for sgn in [-1.0, 1.0] {
            let q3 = sgn * c3.acos();
            let a12 = py.atan2(px) - (l3 * q3.sin()).atan2(l2 + l3 * q3.cos());
            let q2 = a12 - q1;
            let q = DVector::from_vec(vec![q1, q2, q3]);
            let mut c = PlanarChain::arm(vec![l1, l2, l3]);
            let mut pose = Isometry3::identity();
            let mut j6 = DMatrix::zeros(6, 3);
            c.pose_and_jacobian(&q, &mut pose, &mut j6).unwrap();
            let w = JacobianSvd::new(&j6.rows(0, 2).into_owned())
                .unwrap()
                .yoshikawa()
                .unwrap();
            w_max = w_max.max(w);
        }
    }
    // From several seeds: without the null-space term the solver stops wherever it first
    // meets the target; with it, it climbs to a (local) maximum of w on the manifold.
    let mut worst_plain = f64::INFINITY;
    for q0 in [
        [-0.8, 2.4, 1.4],
        [0.1, 0.05, 0.05],
        [1.5, -2.0, -1.0],
        [2.5, 1.0, -2.5],
    ] {
        let q0 = DVector::from_vec(q0.to_vec());
        let plain = w_final(NullSpaceObjective::None, &q0);
        let boosted = w_final(
            NullSpaceObjective::Manipulability {
                measure: Measure::Yoshikawa,
                gain: 0.5,
            },
            &q0,
        );
        assert!(boosted >= plain - 1e-9, "{boosted} vs {plain}");
        // Gradient ascent on the manifold ends at a local maximum of w (the elbow branches
        // have their own); all of them are well conditioned here.
        assert!(
            boosted > 0.85 * w_max,
            "{boosted} vs max {w_max} (plain {plain})"
        );
        worst_plain = worst_plain.min(plain);
    }
    assert!(
        worst_plain < 0.9 * w_max,
        "{worst_plain} vs {w_max}: no seed discriminates"
    );

    // Preferred posture: among the solutions, ends close to it.
    let pref = DVector::from_vec(vec![0.2, 0.9, 0.6]);
    let mut task = PoseTask::new(chain.clone(), target, &TaskRows::Position)
        .unwrap()
        .with_preferred_posture(pref.clone())
        .unwrap();
    let mut ws = IkWorkspace::new(&task);
    let opts = IkOptions {
        null_space: NullSpaceObjective::Posture { gain: 0.3 },
        tolerance: 1e-8,
        max_iterations: 400,
        ..IkOptions::default()
    };
    let q0 = DVector::from_vec(vec![-0.8, 2.4, 1.4]);
    let r = solve(&mut task, &q0, &opts, &mut ws).unwrap();
    assert!(r.converged);
    let mut plain_task = PoseTask::new(chain, target, &TaskRows::Position).unwrap();
    let r0 = solve(&mut plain_task, &q0, &IkOptions::default(), &mut ws).unwrap();
    assert!((&r.q - &pref).norm() < (&r0.q - &pref).norm());
}

//! Whole-body MPC solve time on Fetch (torso + 7-joint arm on its differential drive),
//! 1 s horizon (20 stages of 50 ms), every constraint on: torque, wheel and joint speed,
//! joint position, ZMP margin ≥ 0.05 m, clearance ≥ 0.03 m to a table and between the
//! enabled self pairs. The state is the one the closed loop of `tests/sim_mpc.rs`
//! reaches at t = 2.5 s (gripper reaching beside the path, base moving); each iteration
//! is one warm-started solve from it (4 iterations at most).
//!
//! Beside it, the quadratic program of one iteration (the stage models at the warm
//! start: variables `δu_0, δx_1, …, δu_{N−1}, δx_N`, the linearised dynamics as
//! equalities, the input bounds as inequalities) solved two ways: the solver's own
//! Riccati backward pass (`Solver::backward_pass`, box-DDP stage QPs) and the interior-
//! point solver `clarabel` on the sparse form built from the same stage models, and, with
//! `--features bench-osqp` (OSQP is C, built with CMake), the operator-splitting solver
//! OSQP on that same sparse form.

#[path = "../tests/mpc_common/mod.rs"]
mod mpc_common;

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, NonnegativeConeT, SolverStatus, ZeroConeT,
};
use criterion::{Criterion, criterion_group, criterion_main};
use moma::collision::Scene;
use moma::control::mpc::{
    KnotReference, MpcSettings, OptimalControlProblem, Solver, StageModel, Trajectory,
};
use moma::sim::mpc_loop::{MpcLoopSettings, run_mpc_loop};
use moma::sim::wheeled_system::WheeledSystem;
use nalgebra::{DVector, Matrix3, Vector3};
use std::hint::black_box;

fn bench_mpc(c: &mut Criterion) {
    let scene = Scene {
        objects: vec![mpc_common::box_object(
            "table",
            [1.0, -0.85, 0.35],
            [0.3, 0.25, 0.35],
        )],
    };
    let mut s = MpcSettings::default();
    s.weights.ee_orientation = 0.0;
    let (mut mpc, q0) = mpc_common::fetch_mpc(Some(scene), s);
    let mut plant = WheeledSystem::new(mpc.problem.robot.wheeled.clone());
    let v0 = vec![0.0; plant.robot.nr()];
    let target = Vector3::new(1.0, -0.45, 0.85);
    let reference = move |t: f64| KnotReference {
        base: [0.3 * t, 0.0, 0.0],
        end_effector: (t >= 1.0).then_some((target, Matrix3::identity())),
    };
    let settings = MpcLoopSettings {
        duration: 2.5,
        period: 0.05,
        substeps: 5,
    };
    let run = run_mpc_loop(
        &mut mpc,
        &mut plant,
        q0.as_slice(),
        &v0,
        &settings,
        reference,
    )
    .unwrap();
    let last = run.samples.last().unwrap();
    let (q, v) = (last.q.clone(), last.v.clone());
    mpc.set_reference(last.t, reference);
    // One iteration's QP at the warm start of the next solve (on a copy, so that the
    // solve benchmark below starts from the same state).
    let mut mpc_qp = mpc.clone();
    let mpc_qp = &mut mpc_qp;
    let robot = &mpc_qp.problem.robot;
    let (nx, nu, n) = (robot.nx(), robot.nu(), mpc_qp.problem.horizon());
    let mut x0 = DVector::zeros(nx);
    robot.state_from_plant(&q, &v, &mut x0);
    let mut traj: Trajectory = mpc_qp.solution.clone();
    let mut riccati = Solver::new(nx, nu, n);
    riccati
        .linearize(&mut mpc_qp.problem, &x0, &mut traj)
        .unwrap();
    // Each stage's input bounds at its state (the joint speeds' limits make them
    // depend on it).
    let bounds: Vec<(DVector<f64>, DVector<f64>)> = (0..n)
        .map(|k| {
            let (mut l, mut h) = (DVector::zeros(nu), DVector::zeros(nu));
            mpc_qp.problem.input_bounds(k, &traj.xs[k], &mut l, &mut h);
            (l, h)
        })
        .collect();
    let stages = riccati.stages().to_vec();
    riccati.backward_pass(&mpc_qp.problem, &traj, 0.0).unwrap();
    let qp = StepQp::new(&stages, &traj, &bounds);
    let z = qp.solve();
    let du0 = DVector::from_column_slice(&z[..nu]);
    println!(
        "first input step: Riccati {:.6?}, clarabel {:.6?}, largest difference {:.3e}",
        riccati.feedforward[0].as_slice(),
        du0.as_slice(),
        (&riccati.feedforward[0] - &du0).amax()
    );
    c.bench_function("mpc/qp_riccati", |b| {
        b.iter(|| black_box(riccati.backward_pass(&mpc_qp.problem, &traj, 0.0).unwrap()));
    });
    c.bench_function("mpc/qp_clarabel", |b| {
        b.iter(|| black_box(StepQp::new(&stages, &traj, &bounds).solve()));
    });
    #[cfg(feature = "bench-osqp")]
    {
        let z = qp.solve_osqp();
        let du0 = DVector::from_column_slice(&z[..nu]);
        println!(
            "first input step: osqp {:.6?}, largest difference to Riccati {:.3e}",
            du0.as_slice(),
            (&riccati.feedforward[0] - &du0).amax()
        );
        c.bench_function("mpc/qp_osqp", |b| {
            b.iter(|| black_box(StepQp::new(&stages, &traj, &bounds).solve_osqp()));
        });
    }

    c.bench_function("mpc/fetch_1s_all_constraints", |b| {
        b.iter(|| black_box(mpc.solve(black_box(&q), black_box(&v)).unwrap()));
    });
}

/// The QP of one iteration in `clarabel`'s form, `min ½zᵀPz + qᵀz, A z + s = b`, with
/// `z = [δu_0, δx_1, δu_1, …, δu_{N−1}, δx_N]` (δx_0 = 0: the state is measured).
struct StepQp {
    p: CscMatrix<f64>,
    q: Vec<f64>,
    a: CscMatrix<f64>,
    b: Vec<f64>,
    equalities: usize,
    inequalities: usize,
}

impl StepQp {
    fn new(
        stages: &[StageModel],
        traj: &Trajectory,
        bounds: &[(DVector<f64>, DVector<f64>)],
    ) -> Self {
        let n = traj.us.len();
        let (nx, nu) = (traj.xs[0].len(), traj.us[0].len());
        let w = nx + nu;
        let nz = n * w;
        let iu = |k: usize| k * w;
        let ix = |k: usize| (k - 1) * w + nu; // k ≥ 1
        let (mut pi, mut pj, mut pv) = (Vec::new(), Vec::new(), Vec::new());
        let mut push_p = |r: usize, c: usize, v: f64| {
            if v != 0.0 && r <= c {
                pi.push(r);
                pj.push(c);
                pv.push(v);
            }
        };
        let mut q = vec![0.0; nz];
        for (k, s) in stages.iter().enumerate() {
            if k < n {
                for i in 0..nu {
                    q[iu(k) + i] += s.lu[i];
                    for j in 0..nu {
                        push_p(iu(k) + i, iu(k) + j, s.luu[(i, j)]);
                    }
                }
            }
            if k >= 1 {
                for i in 0..nx {
                    q[ix(k) + i] += s.lx[i];
                    for j in 0..nx {
                        push_p(ix(k) + i, ix(k) + j, s.lxx[(i, j)]);
                    }
                    if k < n {
                        for j in 0..nu {
                            push_p(ix(k) + i, iu(k) + j, s.lux[(j, i)]);
                        }
                    }
                }
            }
        }
        let p = CscMatrix::new_from_triplets(nz, nz, pi, pj, pv);
        // δx_{k+1} − A_k δx_k − B_k δu_k = 0, then ±δu_k ≤ bounds.
        let (mut ai, mut aj, mut av) = (Vec::new(), Vec::new(), Vec::new());
        let mut b = Vec::new();
        for (k, s) in stages.iter().enumerate().take(n) {
            for r in 0..nx {
                let row = b.len();
                ai.push(row);
                aj.push(ix(k + 1) + r);
                av.push(1.0);
                for c in 0..nu {
                    if s.b[(r, c)] != 0.0 {
                        ai.push(row);
                        aj.push(iu(k) + c);
                        av.push(-s.b[(r, c)]);
                    }
                }
                if k >= 1 {
                    for c in 0..nx {
                        if s.a[(r, c)] != 0.0 {
                            ai.push(row);
                            aj.push(ix(k) + c);
                            av.push(-s.a[(r, c)]);
                        }
                    }
                }
                b.push(0.0);
            }
        }
        let equalities = b.len();
        for (k, (lo, hi)) in bounds.iter().enumerate() {
            for i in 0..nu {
                for (sign, bound) in [(1.0, hi[i] - traj.us[k][i]), (-1.0, traj.us[k][i] - lo[i])] {
                    ai.push(b.len());
                    aj.push(iu(k) + i);
                    av.push(sign);
                    b.push(bound);
                }
            }
        }
        let inequalities = b.len() - equalities;
        let a = CscMatrix::new_from_triplets(b.len(), nz, ai, aj, av);
        Self {
            p,
            q,
            a,
            b,
            equalities,
            inequalities,
        }
    }

    fn solve(&self) -> Vec<f64> {
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .build()
            .unwrap();
        let cones = [
            ZeroConeT(self.equalities),
            NonnegativeConeT(self.inequalities),
        ];
        let mut solver =
            DefaultSolver::new(&self.p, &self.q, &self.a, &self.b, &cones, settings).unwrap();
        solver.solve();
        assert!(
            matches!(solver.solution.status, SolverStatus::Solved),
            "{:?}",
            solver.solution.status
        );
        solver.solution.x.clone()
    }

    /// The same QP by OSQP, `l ≤ A z ≤ u`: the equalities with `l = u = b`, the
    /// inequalities with `l = −∞` (OSQP's infinity, 1e30); default settings, silent, set up
    /// and solved each time as clarabel is.
    #[cfg(feature = "bench-osqp")]
    fn solve_osqp(&self) -> Vec<f64> {
        fn csc(m: &CscMatrix<f64>) -> osqp::CscMatrix<'_> {
            osqp::CscMatrix {
                nrows: m.m,
                ncols: m.n,
                indptr: m.colptr.as_slice().into(),
                indices: m.rowval.as_slice().into(),
                data: m.nzval.as_slice().into(),
            }
        }
        let lower: Vec<f64> = (0..self.b.len())
            .map(|i| {
                if i < self.equalities {
                    self.b[i]
                } else {
                    -1e30
                }
            })
            .collect();
        let settings = osqp::Settings::default().verbose(false);
        let mut problem = osqp::Problem::new(
            csc(&self.p),
            &self.q,
            csc(&self.a),
            &lower,
            &self.b,
            &settings,
        )
        .unwrap();
        let status = problem.solve();
        status.x().expect("OSQP solved the QP").to_vec()
    }
}

criterion_group! {
    name = benches;
    config = Criterion::default().sample_size(50);
    targets = bench_mpc
}
criterion_main!(benches);

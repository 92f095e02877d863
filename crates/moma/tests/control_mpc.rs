//! The whole-body MPC's solver and problem: the linear-quadratic case against an
//! independent Riccati iteration, and the stage model against finite differences.

mod mpc_common;

use moma::Result;
use moma::control::mpc::{
    KnotReference, MpcSettings, OptimalControlProblem, Solver, SolverOptions, StageModel,
    Trajectory,
};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// `x⁺ = A x + B u`, `ℓ = xᵀQx + uᵀRu`, `ℓ_N = xᵀ P_N x`, with box bounds.
struct LinearQuadratic {
    a: DMatrix<f64>,
    b: DMatrix<f64>,
    q: DMatrix<f64>,
    r: DMatrix<f64>,
    p_n: DMatrix<f64>,
    n: usize,
    lo: DVector<f64>,
    hi: DVector<f64>,
}

impl OptimalControlProblem for LinearQuadratic {
    fn nx(&self) -> usize {
        self.a.nrows()
    }
    fn nu(&self) -> usize {
        self.b.ncols()
    }
    fn horizon(&self) -> usize {
        self.n
    }
    fn dynamics(
        &mut self,
        _k: usize,
        x: &DVector<f64>,
        u: &DVector<f64>,
        next: &mut DVector<f64>,
    ) -> Result<()> {
        next.copy_from(&(&self.a * x + &self.b * u));
        Ok(())
    }
    fn cost(&mut self, _k: usize, x: &DVector<f64>, u: Option<&DVector<f64>>) -> Result<f64> {
        Ok(match u {
            Some(u) => (x.transpose() * &self.q * x)[0] + (u.transpose() * &self.r * u)[0],
            None => (x.transpose() * &self.p_n * x)[0],
        })
    }
    fn approximate(
        &mut self,
        k: usize,
        x: &DVector<f64>,
        u: Option<&DVector<f64>>,
        out: &mut StageModel,
    ) -> Result<f64> {
        out.a.copy_from(&self.a);
        out.b.copy_from(&self.b);
        out.lux.fill(0.0);
        match u {
            Some(u) => {
                out.lx.copy_from(&(2.0 * &self.q * x));
                out.lxx.copy_from(&(2.0 * &self.q));
                out.lu.copy_from(&(2.0 * &self.r * u));
                out.luu.copy_from(&(2.0 * &self.r));
            }
            None => {
                out.lx.copy_from(&(2.0 * &self.p_n * x));
                out.lxx.copy_from(&(2.0 * &self.p_n));
            }
        }
        self.cost(k, x, u)
    }
    fn input_bounds(
        &self,
        _k: usize,
        _x: &DVector<f64>,
        lo: &mut DVector<f64>,
        hi: &mut DVector<f64>,
    ) {
        lo.copy_from(&self.lo);
        hi.copy_from(&self.hi);
    }
}

/// A double integrator per axis, two axes coupled through B, sampled at 0.1 s.
fn double_integrator(n: usize, bound: f64) -> LinearQuadratic {
    let h = 0.1;
    let a = DMatrix::from_row_slice(
        4,
        4,
        &[
            1.0, 0.0, h, 0.0, //
            0.0, 1.0, 0.0, h, //
            0.0, 0.0, 1.0, 0.0, //
            0.0, 0.0, 0.0, 1.0,
        ],
    );
    let b = DMatrix::from_row_slice(
        4,
        2,
        &[
            0.5 * h * h,
            0.0, //
            0.0,
            0.5 * h * h, //
            h,
            0.2 * h, //
            0.0,
            h,
        ],
    );
    let q = DMatrix::from_diagonal(&DVector::from_vec(vec![1.0, 2.0, 0.1, 0.1]));
    let r = DMatrix::from_row_slice(2, 2, &[0.05, 0.01, 0.01, 0.08]);
    LinearQuadratic {
        a,
        b,
        p_n: q.clone() * 3.0,
        q,
        r,
        n,
        lo: DVector::from_element(2, -bound),
        hi: DVector::from_element(2, bound),
    }
}

/// The finite-horizon LQR gain of the first stage, by the discrete Riccati recursion
/// `K = (R + BᵀPB)⁻¹ BᵀPA`, `P ← Q + AᵀP(A − BK)` from `P_N` (written out here, apart
/// from the solver's backward pass).
fn lqr_first_gain(p: &LinearQuadratic, stages: usize) -> DMatrix<f64> {
    let mut pk = p.p_n.clone();
    let mut k = DMatrix::zeros(2, 4);
    for _ in 0..stages {
        let btp = p.b.transpose() * &pk;
        k = (&p.r + &btp * &p.b).try_inverse().unwrap() * (&btp * &p.a);
        pk = &p.q + p.a.transpose() * &pk * (&p.a - &p.b * &k);
    }
    k
}

#[test]
fn linear_quadratic_first_input_is_the_lqr_input() {
    let x0 = DVector::from_vec(vec![1.0, -0.5, 0.3, 0.2]);
    for stages in [1, 5, 40] {
        let mut p = double_integrator(stages, f64::INFINITY);
        let mut solver = Solver::new(4, 2, stages);
        let mut traj = Trajectory::zeros(4, 2, stages);
        let stats = solver
            .solve(&mut p, &x0, &mut traj, &SolverOptions::default())
            .unwrap();
        let u_lqr = -lqr_first_gain(&p, stages) * &x0;
        let err = (&traj.us[0] - &u_lqr).amax();
        assert!(
            err < 1e-9 * u_lqr.amax().max(1.0),
            "N = {stages}: MPC {} vs LQR {u_lqr}",
            traj.us[0]
        );
        assert!(stats.converged && stats.iterations <= 2, "{stats:?}");
        // The feedback gain too: K of the solver's first stage is −K_lqr.
        let gk = (&solver.gains[0] + lqr_first_gain(&p, stages)).amax();
        assert!(gk < 1e-9, "N = {stages}: gain error {gk}");
    }
    // A long horizon reaches the infinite-horizon gain (the Riccati fixed point).
    let p = double_integrator(400, f64::INFINITY);
    let k400 = lqr_first_gain(&p, 400);
    let k800 = lqr_first_gain(&p, 800);
    assert!((&k400 - &k800).amax() < 1e-10);
}

#[test]
fn bounded_inputs_stay_in_the_box_and_beat_the_clipped_lqr() {
    let x0 = DVector::from_vec(vec![3.0, -2.0, 0.0, 0.0]);
    let stages = 30;
    let mut p = double_integrator(stages, 1.0);
    let mut solver = Solver::new(4, 2, stages);
    let mut traj = Trajectory::zeros(4, 2, stages);
    let stats = solver
        .solve(&mut p, &x0, &mut traj, &SolverOptions::default())
        .unwrap();
    assert!(traj.us.iter().all(|u| u.amax() <= 1.0 + 1e-12));
    assert!(
        traj.us[0].amax() > 1.0 - 1e-12,
        "the first input saturates: {}",
        traj.us[0]
    );
    // Rolling out the LQR policy clipped to the box costs more.
    let k = lqr_first_gain(&p, stages);
    let mut x = x0.clone();
    let mut clipped = 0.0;
    let mut next = DVector::zeros(4);
    for _ in 0..stages {
        let u = (-&k * &x).map(|v| v.clamp(-1.0, 1.0));
        clipped += p.cost(0, &x, Some(&u)).unwrap();
        p.dynamics(0, &x, &u, &mut next).unwrap();
        x.copy_from(&next);
    }
    clipped += p.cost(stages, &x, None).unwrap();
    assert!(stats.cost < clipped, "{} vs {clipped}", stats.cost);
}

/// The stage model of the Fetch problem against central differences of its cost, with
/// the exact-derivative terms only (position tracking, base path, effort, the linear
/// limits): the torque, ZMP and orientation terms use documented approximations.
#[test]
fn fetch_stage_model_matches_finite_differences() {
    let mut s = MpcSettings::default();
    s.constraints.zmp_margin = None;
    s.constraints.clearance = None;
    s.constraints.torque_fraction = 1e9;
    s.weights.ee_orientation = 0.0;
    let (mut mpc, q0) = mpc_common::fetch_mpc(None, s);
    mpc.set_reference(0.0, |t| KnotReference {
        base: [0.3 * t, 0.1, 0.05],
        end_effector: Some((Vector3::new(0.8, -0.3, 0.9), Matrix3::identity())),
    });
    let p = &mut mpc.problem;
    let (nx, nu) = (p.nx(), p.nu());
    let mut x = DVector::zeros(nx);
    let mut vr = vec![0.0; p.robot.wheeled.nr()];
    vr[0] = 0.3;
    vr[1] = -0.2;
    vr[3] = 0.4;
    p.robot.state_from_plant(q0.as_slice(), &vr, &mut x);
    // Push a joint speed past its limit so that an AL term is active.
    x[5 + 8 + 2] = p.robot.speed_limit[2] * 1.1;
    let u = DVector::from_fn(nu, |i, _| 0.1 * (i as f64 + 1.0) - 0.4);
    let mut m = StageModel::new(nx, nu);
    p.approximate(3, &x, Some(&u), &mut m).unwrap();
    let eps = 1e-6;
    for i in 0..nx {
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[i] += eps;
        xm[i] -= eps;
        let fd =
            (p.cost(3, &xp, Some(&u)).unwrap() - p.cost(3, &xm, Some(&u)).unwrap()) / (2.0 * eps);
        assert!(
            (fd - m.lx[i]).abs() < 1e-4 * (1.0 + fd.abs()),
            "lx[{i}]: model {} vs fd {fd}",
            m.lx[i]
        );
    }
    for i in 0..nu {
        let (mut up, mut um) = (u.clone(), u.clone());
        up[i] += eps;
        um[i] -= eps;
        let fd =
            (p.cost(3, &x, Some(&up)).unwrap() - p.cost(3, &x, Some(&um)).unwrap()) / (2.0 * eps);
        assert!(
            (fd - m.lu[i]).abs() < 1e-4 * (1.0 + fd.abs()),
            "lu[{i}]: model {} vs fd {fd}",
            m.lu[i]
        );
    }
    // The transition's Jacobians.
    let mut fp = DVector::zeros(nx);
    let mut fm = DVector::zeros(nx);
    for i in 0..nx {
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[i] += eps;
        xm[i] -= eps;
        p.dynamics(3, &xp, &u, &mut fp).unwrap();
        p.dynamics(3, &xm, &u, &mut fm).unwrap();
        let col = (&fp - &fm) / (2.0 * eps);
        assert!((col - m.a.column(i)).amax() < 1e-8, "A column {i}");
    }
    for i in 0..nu {
        let (mut up, mut um) = (u.clone(), u.clone());
        up[i] += eps;
        um[i] -= eps;
        p.dynamics(3, &x, &up, &mut fp).unwrap();
        p.dynamics(3, &x, &um, &mut fm).unwrap();
        let col = (&fp - &fm) / (2.0 * eps);
        assert!((col - m.b.column(i)).amax() < 1e-8, "B column {i}");
    }
}

/// The ZMP margin's gradient in the input (exact: the momentum rate is affine in the
/// accelerations) against central differences of the margin, on Fetch moving with the
/// arm swinging.
#[test]
fn zmp_margin_input_gradient_matches_finite_differences() {
    use moma::control::mpc::robot::{KnotWorkspace, evaluate_knot};
    let robot = mpc_common::fetch_robot(None);
    let q0 = mpc_common::fetch_start(&robot);
    let mut ws = KnotWorkspace::new(&robot, 1);
    let (nx, nu) = (robot.nx(), robot.nu());
    let mut x = DVector::zeros(nx);
    let mut vr = vec![0.0; robot.wheeled.nr()];
    vr[0] = 0.6;
    vr[1] = 0.3;
    vr[3] = -0.5;
    vr[4] = 0.8;
    robot.state_from_plant(q0.as_slice(), &vr, &mut x);
    let u = DVector::from_fn(nu, |i, _| 0.7 * (i as f64 + 1.0) - 3.0);
    evaluate_knot(&robot, &mut ws, &q0, &x, Some(&u), true);
    let grad = ws.values.zmp_du.clone();
    assert!(grad.amax() > 1e-3, "a gradient that moves: {grad}");
    let eps = 1e-6;
    for i in 0..nu {
        let mut margin = |d: f64| {
            let mut ud = u.clone();
            ud[i] += d;
            evaluate_knot(&robot, &mut ws, &q0, &x, Some(&ud), false);
            ws.values.zmp_margin.unwrap()
        };
        let fd = (margin(eps) - margin(-eps)) / (2.0 * eps);
        assert!(
            (fd - grad[i]).abs() < 1e-6 * (1.0 + fd.abs()),
            "zmp_du[{i}]: {} vs central difference {fd}",
            grad[i]
        );
    }
}

/// A self pair's distance does not change when the base drives and turns with the arm
/// still, so a knot evaluated after such a move queries no more pairs than before it
/// (the bound from each pair's last query holds in the base frame), and reports the
/// clearance a query of every pair gives. Fetch in the mission's transport posture
/// (arm folded over the base), where several pairs are within the cut-off.
#[test]
fn a_base_move_queries_no_more_self_pairs() {
    use moma::collision::Scene;
    use moma::control::mpc::robot::{KnotWorkspace, evaluate_knot, select_pairs};
    let robot = mpc_common::fetch_robot(Some(Scene::default()));
    let (q, x) = fetch_tucked(&robot);
    let cutoff = 0.05;
    let mut ws = KnotWorkspace::new(&robot, 1);
    select_pairs(&robot, &mut ws, &q, f64::INFINITY);
    ws.distance_cutoff = cutoff;
    evaluate_knot(&robot, &mut ws, &q, &x, None, true);
    let before = ws.queried_pairs;
    assert!(before > 0, "some pairs within {cutoff} m when tucked");
    // Drive 0.6 m and turn 0.8 rad, the arm as it was.
    let mut moved = q.clone();
    moved[0] += 0.6;
    moved[1] -= 0.2;
    moved[2] += 0.8;
    let mut x_moved = x.clone();
    x_moved[0] = moved[0];
    x_moved[1] = moved[1];
    x_moved[2] = moved[2];
    evaluate_knot(&robot, &mut ws, &moved, &x_moved, None, true);
    assert_eq!(ws.queried_pairs, before, "pairs queried after a base move");
    // Every pair queried there gives the same clearance.
    let mut all = KnotWorkspace::new(&robot, 1);
    select_pairs(&robot, &mut all, &moved, f64::INFINITY);
    all.distance_cutoff = f64::INFINITY;
    evaluate_knot(&robot, &mut all, &moved, &x_moved, None, true);
    assert!(
        all.queried_pairs > before,
        "{} pairs in all",
        all.queried_pairs
    );
    let full = all.values.distances[0];
    assert!(full < cutoff, "closest pair {full} m");
    assert!(
        (ws.values.distances[0] - full).abs() < 1e-9,
        "{} vs {full}",
        ws.values.distances[0]
    );
    assert!((&ws.values.distances_dx[0] - &all.values.distances_dx[0]).amax() < 1e-9);
}

/// Fetch in the mission's transport posture (arm folded over the base), where several
/// self pairs are within a few centimetres: the MPC state and configuration.
fn fetch_tucked(robot: &moma::control::mpc::MpcRobot) -> (DVector<f64>, DVector<f64>) {
    let model = &robot.wheeled.model;
    let mut q = DVector::zeros(model.nq);
    for (name, v) in [
        ("torso_lift_joint", 0.0),
        ("shoulder_pan_joint", 1.32),
        ("shoulder_lift_joint", 1.40),
        ("upperarm_roll_joint", -0.2),
        ("elbow_flex_joint", 1.72),
        ("forearm_roll_joint", 0.0),
        ("wrist_flex_joint", 1.66),
        ("wrist_roll_joint", 0.0),
    ] {
        let j = model.joint_id(name).unwrap();
        q[model.idx_q[j.0]] = v;
    }
    let vr = vec![0.0; robot.wheeled.nr()];
    let mut x = DVector::zeros(robot.nx());
    robot.state_from_plant(q.as_slice(), &vr, &mut x);
    (q, x)
}

/// Each clearance slot holds one pair's distance, nearest first, with that pair's own
/// gradient: the first slot is the closest pair of a one-slot evaluation, and every
/// filled slot's gradient matches central differences of that slot's distance along
/// each moved joint (the pairs' order does not change over such small steps), so the
/// second slot's gradient is not the nearest pair's.
#[test]
fn each_clearance_slot_is_one_pair_with_its_own_gradient() {
    use moma::collision::Scene;
    use moma::control::mpc::robot::{KnotWorkspace, evaluate_knot, select_pairs};
    let robot = mpc_common::fetch_robot(Some(Scene::default()));
    let (q, x) = fetch_tucked(&robot);
    let slots = 4;
    let cutoff = 0.1;
    let evaluate = |slots: usize, x: &DVector<f64>| {
        let mut ws = KnotWorkspace::new(&robot, slots);
        select_pairs(&robot, &mut ws, &q, f64::INFINITY);
        ws.distance_cutoff = cutoff;
        evaluate_knot(&robot, &mut ws, &q, x, None, true);
        ws.values
    };
    let one = evaluate(1, &x);
    let vals = evaluate(slots, &x);
    assert_eq!(vals.distances.len(), slots);
    assert_eq!(vals.distances[0], one.distances[0]);
    assert!((&vals.distances_dx[0] - &one.distances_dx[0]).amax() < 1e-12);
    let filled = vals.distances.iter().filter(|&&d| d < cutoff).count();
    assert!(filled >= 2, "pairs within {cutoff} m: {:?}", vals.distances);
    for w in vals.distances.windows(2) {
        assert!(w[0] <= w[1], "not ascending: {:?}", vals.distances);
    }
    assert!(
        (&vals.distances_dx[1] - &vals.distances_dx[0]).amax() > 1e-3,
        "the second slot has the first's gradient"
    );
    let n = robot.n_moved();
    let eps = 1e-6;
    for col in 3..3 + n {
        let (mut xp, mut xm) = (x.clone(), x.clone());
        xp[col] += eps;
        xm[col] -= eps;
        let (p, m) = (evaluate(slots, &xp), evaluate(slots, &xm));
        for s in 0..filled {
            let fd = (p.distances[s] - m.distances[s]) / (2.0 * eps);
            let g = vals.distances_dx[s][col];
            assert!(
                (fd - g).abs() < 1e-4 * (1.0 + fd.abs()),
                "slot {s}, column {col}: gradient {g}, central difference {fd}"
            );
        }
    }
}

/// An inactive clearance row within `clearance_band` of the set value gives the step's
/// model its Gauss–Newton curvature `ρ ∇c ∇cᵀ` and nothing else (no gradient, no cost);
/// beyond the band it gives nothing.
#[test]
fn an_inactive_clearance_row_in_the_band_gives_only_curvature() {
    use moma::collision::Scene;
    use moma::control::mpc::ConstraintSettings;
    use moma::control::mpc::constraints::ConstraintSet;
    use moma::control::mpc::robot::{KnotWorkspace, evaluate_knot, select_pairs};
    let robot = mpc_common::fetch_robot(Some(Scene::default()));
    let (q, x) = fetch_tucked(&robot);
    let mut ws = KnotWorkspace::new(&robot, 1);
    select_pairs(&robot, &mut ws, &q, f64::INFINITY);
    ws.distance_cutoff = f64::INFINITY;
    let u = DVector::zeros(robot.nu());
    evaluate_knot(&robot, &mut ws, &q, &x, Some(&u), true);
    let mut vals = ws.values.clone();
    let grad = vals.distances_dx[0].clone();
    assert!(grad.amax() > 1e-3);
    let terms = |band: f64, distance: f64, vals: &mut moma::control::mpc::robot::KnotValues| {
        let s = ConstraintSettings {
            clearance: Some(0.03),
            clearance_pairs: 1,
            clearance_band: band,
            ..ConstraintSettings::default()
        };
        vals.distances[0] = distance;
        let mut set = ConstraintSet::new(&robot, &s, 2);
        let mut out = StageModel::new(robot.nx(), robot.nu());
        let cost = set.knot_terms(&robot, &s, 1, &x, Some(&u), &*vals, Some(&mut out));
        (cost, out)
    };
    let s = ConstraintSettings::default();
    let scale = s.penalty / (s.length_scale * s.length_scale);
    // 2 mm above the set value: inactive (λ = 0), inside a 3 mm band.
    let (c0, m0) = terms(0.0, 0.032, &mut vals);
    let (c1, m1) = terms(0.003, 0.032, &mut vals);
    assert_eq!(c0, c1);
    assert!((&m1.lx - &m0.lx).amax() == 0.0);
    let want = scale * &grad * grad.transpose();
    let got = &m1.lxx - &m0.lxx;
    assert!(
        (&got - &want).amax() < 1e-9 * want.amax(),
        "curvature {got} != ρ ∇c ∇cᵀ {want}"
    );
    // 4 mm above: beyond the band, nothing.
    let (_, m2) = terms(0.0, 0.034, &mut vals);
    let (_, m3) = terms(0.003, 0.034, &mut vals);
    assert!((&m3.lxx - &m2.lxx).amax() == 0.0);
}

/// The inputs Fetch's MPC applies in its rollouts (`admissible_input`), from 300 states
/// with the wheel rates and joint speeds anywhere within their limits and inputs of up
/// to 5× the acceleration bounds: the next knot's joint speeds and wheel rates, stepped
/// by the problem's own transition, stay within their limits, the inputs within the
/// acceleration bounds; the platform input is the nearest admissible one to the one
/// asked for (no point of a 161 × 161 grid of the wheels' accelerations that is
/// admissible lies nearer); and an admissible input is left as it is.
#[test]
fn fetch_admissible_inputs_keep_the_next_knots_speed_limits_and_are_the_nearest() {
    let s = MpcSettings::default();
    let (a_lin, a_ang, a_joint) = (
        s.max_linear_acceleration,
        s.max_angular_acceleration,
        s.max_joint_acceleration,
    );
    let (mut mpc, q0) = mpc_common::fetch_mpc(None, s);
    let p = &mut mpc.problem;
    let (nx, nu, n) = (p.nx(), p.nu(), p.robot.n_moved());
    let dt = p.settings.dt;
    let w = p.robot.wheel_map;
    let w_inv = w.try_inverse().unwrap();
    let wl = p.robot.wheel_rate_limit;
    let speed_limit = p.robot.speed_limit.clone();
    let mut x = DVector::zeros(nx);
    let vr = vec![0.0; p.robot.wheeled.nr()];
    p.robot.state_from_plant(q0.as_slice(), &vr, &mut x);
    let (mut lo, mut hi) = (DVector::zeros(nu), DVector::zeros(nu));
    let mut next = DVector::zeros(nx);
    let mut rnd = uniform_pm1(0x2545_f491_4f6c_dd1d_u64);
    let mut moved = 0;
    for trial in 0..300 {
        let rates = nalgebra::Vector2::new(wl * rnd(), wl * rnd());
        let platform = w_inv * rates;
        x[3 + n] = platform[0];
        x[4 + n] = platform[1];
        for i in 0..n {
            x[5 + n + i] = speed_limit[i] * rnd();
        }
        let mut u = DVector::zeros(nu);
        u[0] = a_lin * rnd();
        u[1] = a_ang * rnd();
        for i in 2..nu {
            u[i] = 5.0 * a_joint * rnd();
        }
        let asked = u.clone();
        p.admissible_input(1, &x, &mut u, &mut lo, &mut hi);
        p.dynamics(1, &x, &u, &mut next).unwrap();
        let rates_next = w * nalgebra::Vector2::new(next[3 + n], next[4 + n]);
        assert!(
            rates_next.amax() <= wl * (1.0 + 1e-9),
            "{trial}: {rates_next}"
        );
        for i in 0..n {
            let qd = next[5 + n + i];
            assert!(
                qd.abs() <= speed_limit[i] * (1.0 + 1e-9),
                "{trial}: joint {i} {qd}"
            );
            assert!(u[2 + i].abs() <= a_joint * (1.0 + 1e-12), "{trial}: {u}");
        }
        assert!(u[0].abs() <= a_lin * (1.0 + 1e-12) && u[1].abs() <= a_ang * (1.0 + 1e-12));
        // Nearest: the wheels' accelerations z = W u of every admissible grid point are
        // no nearer the asked input's.
        let z_asked = w * nalgebra::Vector2::new(asked[0], asked[1]);
        let z_got = w * nalgebra::Vector2::new(u[0], u[1]);
        let d_got = (z_got - z_asked).norm();
        if d_got > 0.0 {
            moved += 1;
        }
        for a in 0..=160 {
            for b in 0..=160 {
                let z = nalgebra::Vector2::new(
                    (-wl - rates[0] + 2.0 * wl * a as f64 / 160.0) / dt,
                    (-wl - rates[1] + 2.0 * wl * b as f64 / 160.0) / dt,
                );
                let up = w_inv * z;
                if up[0].abs() <= a_lin && up[1].abs() <= a_ang {
                    let d = (z - z_asked).norm();
                    assert!(d_got <= d * (1.0 + 1e-9) + 1e-9, "{trial}: {d_got} > {d}");
                }
            }
        }
        // Admissible already: unchanged.
        let kept = u.clone();
        p.admissible_input(1, &x, &mut u, &mut lo, &mut hi);
        assert!(
            (&u - &kept).amax() <= 1e-12 * (1.0 + kept.amax()),
            "{trial}"
        );
    }
    assert!(
        moved > 30,
        "the wheel-rate limit moved {moved} of 300 inputs"
    );
}

/// At knot 0 the first input's platform part is moved onto the inputs that keep the ZMP
/// margin at the measured state at least its set value (Fetch with five times its wheel
/// torque and the arm raised forward, so that the base's accelerations can tip it): from
/// random states and inputs, the margin of the accelerations the returned input's torques
/// give on the plant (`stability::evaluate` of the forward dynamics, not the MPC's rows)
/// is at least the set value wherever a 31 × 31 grid of the platform's accelerations,
/// with the same arm input, holds a point that keeps it within the wheels' torque and
/// rate limits; and the wheels' torques stay within their limits.
#[test]
fn the_first_input_keeps_the_zmp_margin_at_the_measured_state() {
    use moma::mobile::wheeled::{WheeledData, reduced_forward_dynamics_crba};
    use moma::stability::{ExternalLoads, StabilityData, evaluate};
    let set_value = 0.03;
    let mut s = MpcSettings::default();
    s.constraints.zmp_margin = Some(set_value);
    s.max_linear_acceleration = 8.0;
    let (a_lin, a_ang, a_joint) = (
        s.max_linear_acceleration,
        s.max_angular_acceleration,
        s.max_joint_acceleration,
    );
    let (mut mpc, q0) = mpc_common::fetch_hard_stop(s);
    let robot = mpc.problem.robot.clone();
    let (nx, nu, n) = (robot.nx(), robot.nu(), robot.n_moved());
    let wm = &robot.wheeled;
    let (w, wl, dt) = (robot.wheel_map, robot.wheel_rate_limit, 0.05);
    let mut wd = WheeledData::new(wm);
    let mut sd = StabilityData::new(&robot.stability);
    let mut tau = vec![0.0; wm.nu()];
    // The ZMP margin and the wheels' torques and next rates of the input `u` at (q, v),
    // through the torques that realise it and the plant's forward dynamics of them.
    let mut outcome = |mpc: &mut moma::control::mpc::WholeBodyMpc,
                       q: &DVector<f64>,
                       v: &DVector<f64>,
                       u: &DVector<f64>| {
        mpc.solution.us[0].copy_from(u);
        mpc.first_input_torques_at(q.as_slice(), v.as_slice(), &mut tau, false)
            .unwrap();
        reduced_forward_dynamics_crba(wm, &mut wd, q, v, &tau).unwrap();
        let margin = evaluate(
            &wm.model,
            &mut wd.data,
            &robot.stability,
            &mut sd,
            q,
            &wd.qdot,
            &wd.reduced.qddot,
            &ExternalLoads::NONE,
        )
        .zmp_margin
        .unwrap_or(f64::NEG_INFINITY);
        let torque =
            (tau[0].abs() / robot.torque_limit[0]).max(tau[1].abs() / robot.torque_limit[1]);
        let rates = w * nalgebra::Vector2::new(v[0] + dt * u[0], v[1] + dt * u[1]);
        (margin, torque, rates.amax() / wl)
    };
    let mut rnd = uniform_pm1(0x9e37_79b9_7f4a_7c15_u64);
    let (mut lo, mut hi) = (DVector::zeros(nu), DVector::zeros(nu));
    let mut x = DVector::zeros(nx);
    let (mut held, mut tipping, mut infeasible) = (0, 0, 0);
    for trial in 0..40 {
        let mut q = q0.clone();
        q[0] = rnd();
        q[1] = rnd();
        q[2] = 3.0 * rnd();
        for &d in &robot.dofs {
            q[d] += 0.3 * rnd();
        }
        let mut v = DVector::zeros(wm.nr());
        let platform =
            w.try_inverse().unwrap() * nalgebra::Vector2::new(0.8 * wl * rnd(), 0.8 * wl * rnd());
        v[0] = platform[0];
        v[1] = platform[1];
        for i in 0..n {
            v[robot.reduced[i]] = 0.3 * robot.speed_limit[i] * rnd();
        }
        mpc.solve(q.as_slice(), v.as_slice()).unwrap();
        robot.state_from_plant(q.as_slice(), v.as_slice(), &mut x);
        let mut u = DVector::zeros(nu);
        u[0] = a_lin * rnd();
        u[1] = a_ang * rnd();
        for i in 2..nu {
            u[i] = a_joint * rnd();
        }
        let mut asked = u.clone();
        mpc.problem
            .clamp_to_input_bounds(0, &x, &mut asked, &mut lo, &mut hi);
        mpc.problem
            .admissible_input(0, &x, &mut u, &mut lo, &mut hi);
        assert_eq!(
            u.rows(2, n),
            asked.rows(2, n),
            "{trial}: the arm's input is kept"
        );
        let (asked_margin, _, _) = outcome(&mut mpc, &q, &v, &asked);
        let (margin, torque, _) = outcome(&mut mpc, &q, &v, &u);
        // Whether the grid holds an admissible input that keeps the set value.
        let mut feasible = false;
        let mut trial_u = u.clone();
        for a in 0..=30 {
            for b in 0..=30 {
                trial_u[0] = a_lin * (a as f64 / 15.0 - 1.0);
                trial_u[1] = a_ang * (b as f64 / 15.0 - 1.0);
                let (m, t, r) = outcome(&mut mpc, &q, &v, &trial_u);
                feasible |= m >= set_value && t <= 1.0 && r <= 1.0;
            }
        }
        if !feasible {
            infeasible += 1;
            continue;
        }
        if asked_margin < set_value {
            tipping += 1;
        }
        held += 1;
        assert!(
            margin >= set_value - 1e-9,
            "{trial}: margin {margin} (asked for {asked_margin}), input {u}"
        );
        assert!(
            torque <= 1.0 + 1e-9,
            "{trial}: wheel torque {torque} of the limit"
        );
    }
    println!("held {held} (asked to tip: {tipping}), no grid point: {infeasible}");
    assert!(
        tipping >= 10 && held >= 20,
        "held {held}, tipping {tipping}"
    );
}

/// Numbers uniform in [−1, 1) from `seed` (xorshift64), for the tests' random states.
fn uniform_pm1(mut seed: u64) -> impl FnMut() -> f64 {
    move || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    }
}

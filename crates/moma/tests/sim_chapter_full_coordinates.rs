//! The chapter's constrained dynamic models m1, m2 and m5 in full coordinates: the
//! reduced-coordinate simulator (which integrates `q̇ = N(q) v` and the reduced dynamics,
//! so its own `‖C q̇‖` monitor holds by construction) is checked against an independent
//! integration of the full-coordinate DAE
//!
//! ```text
//! [H  Cᵀ] [q̈]   [S u − h − G]
//! [C  0 ] [λ] = [  −Ċ q̇     ]
//! ```
//!
//! which never uses the null-space basis `N`. Positions, multipliers and the DAE's own
//! constraint drift `|C q̇|` are compared. A deliberately wrong `N` (one entry perturbed)
//! fails the same comparison. (m3 is a kinematic model and m4 has no constraint; neither
//! is simulated with multipliers.)

use moma::closed_form::ad::Real;
use moma::closed_form::ad::{Dual, seed_direction};
use moma::closed_form::lagrange::{self, LagrangianSystem, PfaffianSystem};
use moma::closed_form::m1_unicycle::Unicycle;
use moma::closed_form::m2_platform_arm::PlatformArm;
use moma::closed_form::m5_mobile_manipulator::MobileManipulator;
use moma::sim::chapter_models::chapter_system;
use moma::sim::monitor::MonitorLimits;
use moma::sim::settings::{ChannelProfile, InputProfile, IntegratorSettings};
use moma::sim::wheeled::{SimulationOptions, simulate};
use moma::sim::{AdaptiveOptions, DormandPrince45, OdeSystem};
use nalgebra::{DMatrix, DVector, SMatrix, SVector};
use serde_json::Value;

const HORIZON: f64 = 2.0;
const RECORD: f64 = 0.25;

fn load(name: &str) -> Value {
    let path = format!("{}/tests/data/mobile/{name}", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn floats(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// The full-coordinate DAE of a Pfaffian system, state `[q, q̇]`, constant input `u`.
struct FullDae<'a, S, const N: usize, const NU: usize> {
    sys: &'a S,
    u: SVector<f64, NU>,
    lambda: f64,
}

impl<S, const N: usize, const NU: usize> FullDae<'_, S, N, NU> {
    /// `(C q̇, λ)` at state `x`.
    fn constraint_and_multiplier<const NV: usize>(&mut self, x: &[f64]) -> (f64, f64)
    where
        S: PfaffianSystem<N, NV, NU>,
    {
        let mut dx = vec![0.0; 2 * N];
        self.eval::<NV>(x, &mut dx);
        let q: [f64; N] = x[..N].try_into().unwrap();
        let c = self.sys.constraint_row_generic(&q);
        ((0..N).map(|i| c[i] * x[N + i]).sum(), self.lambda)
    }

    fn eval<const NV: usize>(&mut self, x: &[f64], dx: &mut [f64])
    where
        S: PfaffianSystem<N, NV, NU>,
    {
        let q = SVector::<f64, N>::from_column_slice(&x[..N]);
        let qd = SVector::<f64, N>::from_column_slice(&x[N..]);
        let terms = lagrange::lagrange_terms(self.sys, &q, &qd);
        let qa: [f64; N] = x[..N].try_into().unwrap();
        let qda: [f64; N] = x[N..].try_into().unwrap();
        let c = self.sys.constraint_row_generic(&qa);
        let cd: [Dual<1>; N] = self.sys.constraint_row_generic(&seed_direction(&qa, &qda));
        let cdot_qd: f64 = (0..N).map(|j| cd[j].du[0] * qda[j]).sum();
        let force = self.sys.input_matrix(&q) * self.u;
        let mut kkt = DMatrix::zeros(N + 1, N + 1);
        let mut rhs = DVector::zeros(N + 1);
        for i in 0..N {
            for j in 0..N {
                kkt[(i, j)] = terms.mass[(i, j)];
            }
            kkt[(i, N)] = c[i];
            kkt[(N, i)] = c[i];
            rhs[i] = force[i] - terms.h[i] - terms.gravity[i];
        }
        rhs[N] = -cdot_qd;
        let sol = kkt.lu().solve(&rhs).expect("the KKT matrix is regular");
        dx[..N].copy_from_slice(&x[N..]);
        dx[N..].copy_from_slice(&sol.as_slice()[..N]);
        self.lambda = sol[N];
    }
}

/// `OdeSystem` needs the velocity dimension for `eval`; one wrapper per model size.
struct Dae<'a, S, const N: usize, const NV: usize, const NU: usize>(FullDae<'a, S, N, NU>);

impl<S, const N: usize, const NV: usize, const NU: usize> OdeSystem for Dae<'_, S, N, NV, NU>
where
    S: PfaffianSystem<N, NV, NU>,
{
    fn dim(&self) -> usize {
        2 * N
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> moma::Result<()> {
        self.0.eval::<NV>(x, dx);
        Ok(())
    }
}

/// The reduced model `q̇ = N v`, `v̇ = Mr⁻¹(Qr − Cr v − Gr)` integrated on its own (the
/// simulator's right-hand side, for models the simulator cannot be handed).
struct Reduced<'a, S, const N: usize, const NV: usize, const NU: usize> {
    sys: &'a S,
    u: SVector<f64, NU>,
}

impl<S, const N: usize, const NV: usize, const NU: usize> OdeSystem for Reduced<'_, S, N, NV, NU>
where
    S: PfaffianSystem<N, NV, NU>,
{
    fn dim(&self) -> usize {
        N + NV
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> moma::Result<()> {
        let (qd, vd) = lagrange::state_derivative(
            self.sys,
            &SVector::<f64, N>::from_column_slice(&x[..N]),
            &SVector::<f64, NV>::from_column_slice(&x[N..]),
            &self.u,
        )?;
        dx[..N].copy_from_slice(qd.as_slice());
        dx[N..].copy_from_slice(vd.as_slice());
        Ok(())
    }
}

/// What the full-coordinate DAE gives at the record times `k · RECORD`: positions,
/// multipliers, and the largest `|C q̇|` it drifted to.
struct DaeRun {
    q: Vec<Vec<f64>>,
    lambda: Vec<f64>,
    max_drift: f64,
}

fn run_dae<S, const N: usize, const NV: usize, const NU: usize>(
    sys: &S,
    q0: &[f64],
    v0: &[f64],
    u: &[f64],
) -> DaeRun
where
    S: PfaffianSystem<N, NV, NU>,
{
    let qa: [f64; N] = q0.try_into().unwrap();
    let nb = sys.velocity_basis_generic::<f64>(&qa);
    let qd0: Vec<f64> = (0..N)
        .map(|i| (0..NV).map(|j| nb[i][j] * v0[j]).sum())
        .collect();
    let mut dae = Dae::<S, N, NV, NU>(FullDae {
        sys,
        u: SVector::from_column_slice(u),
        lambda: 0.0,
    });
    let mut x: Vec<f64> = q0.iter().chain(&qd0).copied().collect();
    let mut dp = DormandPrince45::new(2 * N, AdaptiveOptions::with_tolerance(1e-12)).unwrap();
    let (mut t, steps) = (0.0, (HORIZON / RECORD).round() as usize);
    let mut out = DaeRun {
        q: Vec::new(),
        lambda: Vec::new(),
        max_drift: 0.0,
    };
    for k in 0..=steps {
        if k > 0 {
            dp.integrate_to(&mut dae, &mut t, &mut x, k as f64 * RECORD)
                .unwrap();
        }
        let (cqd, lambda) = dae.0.constraint_and_multiplier::<NV>(&x);
        out.max_drift = out.max_drift.max(cqd.abs());
        out.q.push(x[..N].to_vec());
        out.lambda.push(lambda);
    }
    out
}

/// Positions of the stand-alone reduced integration at the record times.
fn run_reduced<S, const N: usize, const NV: usize, const NU: usize>(
    sys: &S,
    q0: &[f64],
    v0: &[f64],
    u: &[f64],
) -> Vec<Vec<f64>>
where
    S: PfaffianSystem<N, NV, NU>,
{
    let mut ode = Reduced::<S, N, NV, NU> {
        sys,
        u: SVector::<f64, NU>::from_column_slice(u),
    };
    let mut x: Vec<f64> = q0.iter().chain(v0).copied().collect();
    let mut dp = DormandPrince45::new(N + NV, AdaptiveOptions::with_tolerance(1e-12)).unwrap();
    let (mut t, steps) = (0.0, (HORIZON / RECORD).round() as usize);
    let mut q = vec![q0.to_vec()];
    for k in 1..=steps {
        dp.integrate_to(&mut ode, &mut t, &mut x, k as f64 * RECORD)
            .unwrap();
        q.push(x[..N].to_vec());
    }
    q
}

/// Largest coordinate difference between two position histories.
fn max_gap(a: &[Vec<f64>], b: &[Vec<f64>]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs()))
        .fold(0.0, f64::max)
}

/// Bound on the position gap between the reduced simulation and the full DAE (both at
/// tolerance 1e-12 over 2 s; the gaps measured are below 1e-9).
const GAP_BOUND: f64 = 1e-8;

fn check_model<S, const N: usize, const NV: usize, const NU: usize>(
    file: &str,
    name: &str,
    build: impl Fn(&Value) -> S,
) where
    S: PfaffianSystem<N, NV, NU>,
{
    let data = load(file);
    for (c, case) in data["cases"].as_array().unwrap().iter().enumerate() {
        let sys = build(&case["params"]);
        let q0 = floats(&case["state"]["q"]);
        let v0 = floats(&case["state"]["v"]);
        let u = floats(&case["inputs"]["u"]);
        let dae = run_dae::<S, N, NV, NU>(&sys, &q0, &v0, &u);
        // The DAE keeps its own constraint (it is integrated, not projected).
        assert!(
            dae.max_drift < 1e-9,
            "{name} case {c}: DAE drift |C q̇| = {:e}",
            dae.max_drift
        );
        // The simulator, as `moma simulate` runs it.
        let mut red = chapter_system(name, &case["params"]).unwrap();
        let input = InputProfile {
            channels: u
                .iter()
                .map(|&value| ChannelProfile::Constant { value })
                .collect(),
        };
        let opts = SimulationOptions {
            duration: HORIZON,
            integrator: IntegratorSettings::adaptive(1e-12, 1e-12),
            record_interval: RECORD,
            limits: MonitorLimits::default(),
        };
        let res = simulate(red.as_mut(), &input, &q0, &v0, &opts, &mut |_| {}).unwrap();
        let rec = &res.recorder;
        assert_eq!(rec.len(), dae.q.len());
        let sim_q: Vec<Vec<f64>> = (0..rec.len()).map(|k| rec.q_row(k).to_vec()).collect();
        let gap = max_gap(&sim_q, &dae.q);
        assert!(
            gap < GAP_BOUND,
            "{name} case {c}: simulator vs DAE position gap {gap:e}"
        );
        for k in 0..rec.len() {
            let (a, b) = (rec.lambda_row(k)[0], dae.lambda[k]);
            assert!(
                (a - b).abs() < 1e-6 * (1.0 + b.abs()),
                "{name} case {c} t={}: λ {a} vs DAE {b}",
                rec.times[k]
            );
        }
        // The stand-alone reduced integration used for the wrong-N check below agrees.
        let alone = run_reduced::<S, N, NV, NU>(&sys, &q0, &v0, &u);
        assert!(max_gap(&alone, &sim_q) < 1e-9, "{name} case {c}");
    }
}

#[test]
fn m1_reduced_simulation_matches_the_full_coordinate_dae() {
    check_model::<_, 3, 2, 2>("m1_unicycle.json", "m1", |p| {
        Unicycle::new(serde_json::from_value(p.clone()).unwrap()).unwrap()
    });
}

#[test]
fn m2_reduced_simulation_matches_the_full_coordinate_dae() {
    check_model::<_, 5, 4, 4>("m2_platform_planar_arm.json", "m2", |p| {
        PlatformArm::new(serde_json::from_value(p.clone()).unwrap()).unwrap()
    });
}

#[test]
fn m5_reduced_simulation_matches_the_full_coordinate_dae() {
    check_model::<_, 6, 5, 5>("m5_mobile_manipulator_3d.json", "m5", |p| {
        MobileManipulator::new(serde_json::from_value(p.clone()).unwrap()).unwrap()
    });
}

/// A model whose null-space basis is wrong: entry (row, col) of `N` is off by `eps`.
struct WrongBasis<S> {
    inner: S,
    row: usize,
    col: usize,
    eps: f64,
}

impl<S: LagrangianSystem<N>, const N: usize> LagrangianSystem<N> for WrongBasis<S> {
    fn mass_matrix_generic<T: Real>(&self, q: &[T; N]) -> [[T; N]; N] {
        self.inner.mass_matrix_generic(q)
    }
    fn potential_generic<T: Real>(&self, q: &[T; N]) -> T {
        self.inner.potential_generic(q)
    }
}

impl<S, const N: usize, const NV: usize, const NU: usize> PfaffianSystem<N, NV, NU>
    for WrongBasis<S>
where
    S: PfaffianSystem<N, NV, NU>,
{
    fn constraint_row_generic<T: Real>(&self, q: &[T; N]) -> [T; N] {
        self.inner.constraint_row_generic(q)
    }
    fn velocity_basis_generic<T: Real>(&self, q: &[T; N]) -> [[T; NV]; N] {
        let mut nb = self.inner.velocity_basis_generic(q);
        nb[self.row][self.col] = nb[self.row][self.col] + T::cst(self.eps);
        nb
    }
    fn input_matrix(&self, q: &SVector<f64, N>) -> SMatrix<f64, N, NU> {
        self.inner.input_matrix(q)
    }
}

#[test]
fn a_wrong_null_space_basis_fails_the_full_coordinate_comparison() {
    let data = load("m2_platform_planar_arm.json");
    let case = &data["cases"][0];
    let good = PlatformArm::new(serde_json::from_value(case["params"].clone()).unwrap()).unwrap();
    let q0 = floats(&case["state"]["q"]);
    let v0 = floats(&case["state"]["v"]);
    let u = floats(&case["inputs"]["u"]);
    let dae = run_dae::<_, 5, 4, 4>(&good, &q0, &v0, &u);
    assert!(max_gap(&run_reduced::<_, 5, 4, 4>(&good, &q0, &v0, &u), &dae.q) < GAP_BOUND);
    // A 1e-3 error in one entry of N (x row, first input; then an arm row), or in the
    // base block alone, is far outside the bound.
    for (row, col) in [(0, 0), (1, 1), (3, 0)] {
        let bad = WrongBasis {
            inner: PlatformArm::new(good.params.clone()).unwrap(),
            row,
            col,
            eps: 1e-3,
        };
        let gap = max_gap(&run_reduced::<_, 5, 4, 4>(&bad, &q0, &v0, &u), &dae.q);
        assert!(
            gap > 1e3 * GAP_BOUND,
            "N[{row}][{col}] + 1e-3: gap only {gap:e}"
        );
    }
}

//! The wheeled layer on a URDF robot (differential drive with wheel joints, caster and a
//! three-joint arm): constraint and basis identities, Ṅ_C, multipliers against the full
//! DAE, wheel-rate kinematics, d = 0, singular reporting, and long unforced simulations
//! (energy drift and constraint residual).

use moma::dynamics::{center_of_mass, crba, gravity_torque, nonlinear_effects};
use moma::io::urdf::model_from_urdf_file;
use moma::mobile::reduced::{JointSpaceTerms, lagrange_multipliers_dae};
use moma::mobile::reduced_forward_dynamics;
use moma::mobile::wheeled::{
    WheeledBase, WheeledData, WheeledModel, actuation_matrix, admissible_velocity_basis,
    admissible_velocity_basis_dot, center_of_mass_velocity, constraint_matrix,
    lagrange_multipliers, platform_point_velocity, wheel_longitudinal_forces,
};
use moma::mobile::{Caster, DiffDrive};
use moma::multibody::RootJoint;
use moma::sim::monitor::MonitorLimits;
use moma::sim::settings::{InputProfile, IntegratorSettings};
use moma::sim::wheeled::{SimulationOptions, simulate};
use moma::sim::wheeled_system::WheeledSystem;
use nalgebra::{DMatrix, DVector, Vector2};

fn urdf() -> String {
    format!(
        "{}/tests/data/mobile/diffdrive_arm.urdf",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn robot(track_wheels: bool, d: f64) -> WheeledModel {
    let model = model_from_urdf_file(urdf(), RootJoint::Planar).unwrap();
    let base = WheeledBase {
        drive: DiffDrive::new(0.08, 0.25, d).unwrap(),
        casters: vec![Caster {
            name: "rear".into(),
            position: [0.25, 0.0],
        }],
        wheel_joints: track_wheels.then(|| {
            [
                "left_wheel_joint".to_string(),
                "right_wheel_joint".to_string(),
            ]
        }),
    };
    WheeledModel::new(model, base).unwrap()
}

fn state(wm: &WheeledModel) -> (DVector<f64>, DVector<f64>, Vec<f64>) {
    let q = DVector::from_fn(wm.model.nq, |i, _| 0.3 * ((i as f64) * 1.7).sin() + 0.1);
    let v = DVector::from_fn(wm.nr(), |i, _| 0.4 * ((i as f64) * 2.3 + 0.5).cos());
    let u = (0..wm.nu())
        .map(|i| 0.7 * ((i as f64) * 0.9).sin() + 0.2)
        .collect();
    (q, v, u)
}

#[test]
fn layout_names_and_dimensions() {
    let wm = robot(true, 0.1);
    assert_eq!(wm.nv(), 3 + 2 + 3);
    assert_eq!((wm.nk(), wm.nr(), wm.nu()), (3, 5, 5));
    assert_eq!(wm.wheel_dofs(), Some([3, 4]));
    assert_eq!(wm.arm_dofs(), &[5, 6, 7]);
    assert_eq!(wm.v_names()[2], "turret_joint_dot");
    let wm = robot(false, 0.1);
    assert_eq!((wm.nk(), wm.nr(), wm.nu()), (1, 7, 7));
    assert_eq!(wm.base.support_points().len(), 3);
    // Bad wheel joint names are errors naming the joint.
    let model = model_from_urdf_file(urdf(), RootJoint::Planar).unwrap();
    let mut base = WheeledBase::new(DiffDrive::new(0.08, 0.25, 0.0).unwrap());
    base.wheel_joints = Some(["nope".into(), "right_wheel_joint".into()]);
    let err = WheeledModel::new(model.clone(), base.clone()).unwrap_err();
    assert!(err.to_string().contains("nope"), "{err}");
    base.wheel_joints = Some(["turret_joint".into(), "right_wheel_joint".into()]);
    let err = WheeledModel::new(model, base).unwrap_err();
    assert!(err.to_string().contains("turret_joint"), "{err}");
    // A fixed-root model is rejected.
    let fixed = model_from_urdf_file(urdf(), RootJoint::Fixed).unwrap();
    assert!(
        WheeledModel::new(
            fixed,
            WheeledBase::new(DiffDrive::new(0.1, 0.2, 0.0).unwrap())
        )
        .is_err()
    );
}

#[test]
fn basis_annihilates_constraints_and_its_derivative_matches_finite_differences() {
    for track in [false, true] {
        for d in [0.1, 0.0, -0.2] {
            let wm = robot(track, d);
            let (q, v, _) = state(&wm);
            let (nv, nr, nk) = (wm.nv(), wm.nr(), wm.nk());
            let mut n = DMatrix::zeros(nv, nr);
            let mut c = DMatrix::zeros(nk, nv);
            admissible_velocity_basis(&wm, &q, &mut n);
            constraint_matrix(&wm, &q, &mut c);
            assert!((&c * &n).norm() < 1e-14, "C N_C");
            assert_eq!(n.rank(1e-10), nr);
            assert_eq!(c.rank(1e-10), nk);
            let qd = &n * &v;
            let mut nd = DMatrix::zeros(nv, nr);
            admissible_velocity_basis_dot(&wm, &q, qd[2], &mut nd);
            let h = 1e-6;
            let (mut np, mut nm) = (DMatrix::zeros(nv, nr), DMatrix::zeros(nv, nr));
            admissible_velocity_basis(&wm, &(&q + &qd * h), &mut np);
            admissible_velocity_basis(&wm, &(&q - &qd * h), &mut nm);
            assert!(((np - nm) / (2.0 * h) - nd).norm() < 1e-8);
            // Wheel torques do the same reduced work whether wheels are tracked or not.
            let mut s = DMatrix::zeros(nv, wm.nu());
            actuation_matrix(&wm, &q, &mut s);
            let qr = n.transpose() * &s;
            let w = wm.base.drive.platform_to_wheel();
            let want = w.transpose();
            for i in 0..2 {
                for j in 0..2 {
                    assert!(
                        (qr[(i, j)] - want[(i, j)]).abs() < 1e-12,
                        "Nᵀ S wheel block"
                    );
                }
            }
        }
    }
}

#[test]
fn multipliers_agree_with_the_full_coordinate_dae() {
    for track in [false, true] {
        let wm = robot(track, 0.1);
        let (q, v, u) = state(&wm);
        let mut wd = WheeledData::new(&wm);
        reduced_forward_dynamics(&wm, &mut wd, &q, &v, &u).unwrap();
        let qdot = wd.qdot.clone();
        let qddot = wd.reduced.qddot.clone();
        let lam = lagrange_multipliers(&wm, &mut wd, &q).unwrap().clone();
        // Full DAE: H, h, G, Q; Ċ q̇ by central differences of C along q̇.
        let hm = crba(&wm.model, &mut wd.data, &q).clone();
        let g = gravity_torque(&wm.model, &mut wd.data, &q).clone();
        let hv = nonlinear_effects(&wm.model, &mut wd.data, &q, &qdot).clone() - &g;
        let mut s = DMatrix::zeros(wm.nv(), wm.nu());
        actuation_matrix(&wm, &q, &mut s);
        let qf = &s * DVector::from_column_slice(&u);
        let mut c = DMatrix::zeros(wm.nk(), wm.nv());
        constraint_matrix(&wm, &q, &mut c);
        let eps = 1e-6;
        let (mut cp, mut cm) = (c.clone(), c.clone());
        constraint_matrix(&wm, &(&q + &qdot * eps), &mut cp);
        constraint_matrix(&wm, &(&q - &qdot * eps), &mut cm);
        let cdot_qdot = (cp - cm) / (2.0 * eps) * &qdot;
        let terms = JointSpaceTerms {
            mass_matrix: &hm,
            velocity_terms: &hv,
            gravity: &g,
            force: &qf,
        };
        let lam_dae = lagrange_multipliers_dae(&terms, &c, &cdot_qdot).unwrap();
        assert!(
            (&lam - &lam_dae).norm() < 1e-7 * (1.0 + lam.norm()),
            "{lam} vs {lam_dae}"
        );
        // The full equation of motion holds with the constraint force.
        let resid = &hm * &qddot + &hv + &g - &qf + c.transpose() * &lam;
        assert!(
            resid.norm() < 1e-9 * (1.0 + qf.norm()),
            "DAE residual {resid}"
        );
        // And the acceleration satisfies C q̈ + Ċ q̇ = 0.
        assert!((&c * &qddot + &cdot_qdot).norm() < 1e-7);
    }
}

#[test]
fn wheel_rate_kinematics() {
    let dd = DiffDrive::new(0.08, 0.25, 0.1).unwrap();
    let theta = 0.6;
    let rates = [2.0, 3.0];
    // The axle midpoint never moves sideways; its speed is r_w (φ̇_L + φ̇_R)/2.
    let p0 = platform_point_velocity(&dd, theta, [-dd.d, 0.0], rates);
    let lat = Vector2::new(-theta.sin(), theta.cos());
    assert!(p0.dot(&lat).abs() < 1e-14);
    assert!((p0.norm() - 0.08 * 2.5).abs() < 1e-14);
    // Each wheel contact moves at r_w φ̇ along the heading.
    let left = platform_point_velocity(&dd, theta, [-dd.d, dd.half_track], rates);
    assert!((left.norm() - 0.08 * 2.0).abs() < 1e-14);
    // CM velocity of the whole robot equals the finite difference of the CM.
    let wm = robot(true, 0.1);
    let (q, v, _) = state(&wm);
    let mut wd = WheeledData::new(&wm);
    let mut n = DMatrix::zeros(wm.nv(), wm.nr());
    admissible_velocity_basis(&wm, &q, &mut n);
    let qd = &n * &v;
    let vc = center_of_mass_velocity(&wm, &mut wd, &q, &qd);
    let h = 1e-6;
    let fd = (center_of_mass(&wm.model, &mut wd.data, &(&q + &qd * h))
        - center_of_mass(&wm.model, &mut wd.data, &(&q - &qd * h)))
        / (2.0 * h);
    assert!((vc - fd).norm() < 1e-8, "{vc} vs {fd}");
}

#[test]
fn singular_reduced_mass_is_reported() {
    // An arm joint carrying no inertia gives a zero row in H: Mr is singular and the
    // forward dynamics report it instead of dividing by it.
    use moma::multibody::{JointIndex, JointLimits, JointType, ModelBuilder};
    use moma::spatial::{Inertia, SE3};
    let mut b = ModelBuilder::new("massless_arm");
    b.set_root(RootJoint::Planar);
    let base = b
        .add_joint(
            JointIndex(0),
            "base",
            JointType::Planar,
            SE3::identity(),
            JointLimits::unlimited(),
        )
        .unwrap();
    b.append_body_inertia(
        base,
        &Inertia::new(
            10.0,
            nalgebra::Vector3::zeros(),
            nalgebra::Matrix3::identity(),
        ),
        &SE3::identity(),
    )
    .unwrap();
    b.add_joint(
        base,
        "empty",
        JointType::RevoluteZ,
        SE3::identity(),
        JointLimits::unlimited(),
    )
    .unwrap();
    let wm = WheeledModel::new(
        b.build().unwrap(),
        WheeledBase::new(DiffDrive::new(0.08, 0.25, 0.0).unwrap()),
    )
    .unwrap();
    let mut wd = WheeledData::new(&wm);
    let (q, v, u) = state(&wm);
    let err = reduced_forward_dynamics(&wm, &mut wd, &q, &v, &u).unwrap_err();
    assert!(matches!(err, moma::Error::Singular { .. }), "{err}");
    assert!(err.to_string().contains("Mr"), "{err}");
}

fn unforced_run(track: bool, d: f64) {
    let mut sys = WheeledSystem::new(robot(track, d));
    let (q, v, _) = state(&sys.robot);
    let nu = sys.robot.nu();
    let opts = SimulationOptions {
        duration: 10.0,
        integrator: IntegratorSettings::adaptive(1e-12, 1e-12),
        record_interval: 0.05,
        limits: MonitorLimits::default(),
    };
    let res = simulate(
        &mut sys,
        &InputProfile::zero(nu),
        q.as_slice(),
        v.as_slice(),
        &opts,
        &mut |_| {},
    )
    .unwrap();
    let drift = res.monitor.relative_energy_error();
    assert!(
        drift < 1e-9,
        "track={track} d={d}: relative energy drift {drift:e}"
    );
    assert!(
        res.monitor.max_residual < 1e-12,
        "track={track} d={d}: residual {:e}",
        res.monitor.max_residual
    );
    assert!(res.recorder.kinetic[0] > 0.1, "the run must actually move");
    // The monitored ‖C q̇‖ holds by construction (q̇ = N_C v). An independent check on the
    // integrated full coordinates: the axle midpoint P = (x − d cos θ, y − d sin θ) of the
    // recorded configurations moves along the heading: the sideways component of its
    // central difference is only the O(h²) truncation error, so halving the step divides
    // it by about 4 (measured: 0.37; a slipping base would leave a sideways speed that
    // does not shrink).
    let rec = &res.recorder;
    let nq = sys.robot.model.nq;
    let h = opts.record_interval;
    let p = |k: usize| {
        let q = &rec.q[k * nq..k * nq + 3];
        (q[0] - d * q[2].cos(), q[1] - d * q[2].sin(), q[2])
    };
    let sideways = |k: usize, m: usize| {
        let ((x0, y0, _), (_, _, th), (x2, y2, _)) = (p(k - m), p(k), p(k + m));
        let (vx, vy) = (
            (x2 - x0) / (2.0 * h * m as f64),
            (y2 - y0) / (2.0 * h * m as f64),
        );
        ((-vx * th.sin() + vy * th.cos()).abs(), vx.hypot(vy))
    };
    let (mut fine, mut coarse, mut fastest) = (0.0f64, 0.0f64, 0.0f64);
    for k in 2..rec.times.len() - 2 {
        let (s1, v) = sideways(k, 1);
        let (s2, _) = sideways(k, 2);
        fine = fine.max(s1);
        coarse = coarse.max(s2);
        fastest = fastest.max(v);
    }
    assert!(
        fastest > 0.05,
        "track={track} d={d}: the base must drive ({fastest})"
    );
    assert!(
        fine < 0.5 * coarse && fine < 2e-2 * fastest,
        "track={track} d={d}: sideways speed of the axle midpoint {fine:e} (step h), \
         {coarse:e} (step 2h), speed {fastest}"
    );
    // Independent of the potential's datum: the drift relative to the initial kinetic energy.
    let t0 = res.recorder.kinetic[0];
    let rel_t = res.monitor.max_energy_error / t0;
    assert!(
        rel_t < 1e-9,
        "track={track} d={d}: drift relative to T0 {rel_t:e}"
    );
}

#[test]
fn unforced_energy_drift_and_residual_with_tracked_wheels() {
    unforced_run(true, 0.1);
}

#[test]
fn unforced_energy_drift_and_residual_massless_wheels_and_d_zero() {
    unforced_run(false, 0.0);
}

#[test]
fn driven_run_balances_energy_with_input_work() {
    use moma::sim::settings::ChannelProfile;
    let mut sys = WheeledSystem::new(robot(true, 0.1));
    let (q, v, _) = state(&sys.robot);
    let input = InputProfile {
        channels: vec![
            ChannelProfile::Constant { value: 1.0 },
            ChannelProfile::Sinusoid {
                offset: 1.5,
                amplitude: 0.5,
                frequency: 0.5,
                phase: 0.0,
            },
            ChannelProfile::Piecewise {
                times: vec![0.0, 1.0],
                values: vec![0.5, -0.5],
            },
            ChannelProfile::Constant { value: 0.0 },
            ChannelProfile::Constant { value: 0.0 },
        ],
    };
    let opts = SimulationOptions {
        duration: 2.0,
        integrator: IntegratorSettings::rk4(1e-3),
        record_interval: 0.01,
        limits: MonitorLimits::default(),
    };
    let res = simulate(
        &mut sys,
        &input,
        q.as_slice(),
        v.as_slice(),
        &opts,
        &mut |_| {},
    )
    .unwrap();
    assert!(res.recorder.work.last().unwrap().abs() > 0.1);
    assert!(
        res.monitor.relative_energy_error() < 1e-5,
        "{}",
        res.monitor.relative_energy_error()
    );
    assert!(res.monitor.max_residual < 1e-12);
}

/// Panda on a planar root over differential drives with the axle 0.2 m behind, on and
/// 0.3 m ahead of the base origin: `(d, model)`.
fn panda_on_diff_drives() -> Vec<(f64, WheeledModel)> {
    let path = format!(
        "{}/tests/data/pinocchio/urdf/panda.urdf",
        env!("CARGO_MANIFEST_DIR")
    );
    let model = model_from_urdf_file(path, RootJoint::Planar).unwrap();
    [0.2, 0.0, -0.3]
        .into_iter()
        .map(|d| {
            let base = WheeledBase::new(DiffDrive::new(0.1, 0.3, d).unwrap());
            (d, WheeledModel::new(model.clone(), base).unwrap())
        })
        .collect()
}

/// The `k`-th of a fixed sequence of states and inputs `(q, v_r, u)` of `wm`.
fn deterministic_state(wm: &WheeledModel, k: usize) -> (DVector<f64>, DVector<f64>, Vec<f64>) {
    let q = DVector::from_fn(wm.model.nq, |i, _| ((i * 7 + k * 3) as f64 * 0.37).sin());
    let v = DVector::from_fn(wm.nr(), |i, _| ((i * 5 + k) as f64 * 0.53).cos());
    let u = (0..wm.nu())
        .map(|i| ((i + k) as f64 * 0.71).sin())
        .collect();
    (q, v, u)
}

#[test]
fn root_constrained_aba_equals_the_joint_space_route_on_panda() {
    use moma::mobile::wheeled::reduced_forward_dynamics_crba;
    for (d, wm) in panda_on_diff_drives() {
        let mut wd = WheeledData::new(&wm);
        for k in 0..5 {
            let (q, v, u) = deterministic_state(&wm, k);
            let fast = reduced_forward_dynamics(&wm, &mut wd, &q, &v, &u)
                .unwrap()
                .clone();
            let qdd_fast = wd.reduced.qddot.clone();
            let slow = reduced_forward_dynamics_crba(&wm, &mut wd, &q, &v, &u)
                .unwrap()
                .clone();
            assert!(
                (&fast - &slow).norm() < 1e-9 * (1.0 + slow.norm()),
                "d={d}: {fast} vs {slow}"
            );
            assert!((&qdd_fast - &wd.reduced.qddot).norm() < 1e-9 * (1.0 + slow.norm()));
        }
    }
}

/// The reduced inverse dynamics by one RNEA undoes the reduced forward dynamics (CRBA and
/// Cholesky): at the acceleration that an input gives, `Mr v̇_r + cr + Gr` is that
/// input's reduced force `Qr`, and q̈ is the forward dynamics' q̈.
#[test]
fn reduced_inverse_dynamics_undoes_the_forward_dynamics_on_panda() {
    use moma::mobile::wheeled::{reduced_forward_dynamics_crba, reduced_inverse_dynamics};
    for (d, wm) in panda_on_diff_drives() {
        let mut wd = WheeledData::new(&wm);
        let mut force = DVector::zeros(wm.nr());
        for k in 0..5 {
            let (q, v, u) = deterministic_state(&wm, k);
            let vdot = reduced_forward_dynamics_crba(&wm, &mut wd, &q, &v, &u)
                .unwrap()
                .clone();
            let (qr, qdd) = (wd.reduced.force.clone(), wd.reduced.qddot.clone());
            reduced_inverse_dynamics(&wm, &mut wd, &q, &v, &vdot, &mut force);
            assert!(
                (&force - &qr).norm() < 1e-9 * (1.0 + qr.norm()),
                "d={d}: {force} vs {qr}"
            );
            assert!((&wd.reduced.qddot - &qdd).norm() < 1e-9 * (1.0 + qdd.norm()));
        }
    }
}

/// The full-coordinate DAE (index 1: `[H Cᵀ; C 0][q̈; λ] = [Q − h − G; −Ċ q̇]`, state
/// `[q, q̇]`) integrated independently gives the same trajectory and multipliers as the
/// reduced-coordinate simulator.
struct FullDae {
    wm: WheeledModel,
    data: moma::multibody::Data,
    u: Vec<f64>,
    last_lambda: DVector<f64>,
}

impl moma::sim::OdeSystem for FullDae {
    fn dim(&self) -> usize {
        2 * self.wm.nv()
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> moma::Result<()> {
        let (nv, nk) = (self.wm.nv(), self.wm.nk());
        let q = DVector::from_column_slice(&x[..nv]);
        let qd = DVector::from_column_slice(&x[nv..]);
        let h = crba(&self.wm.model, &mut self.data, &q).clone();
        let nle = nonlinear_effects(&self.wm.model, &mut self.data, &q, &qd).clone();
        let mut s = DMatrix::zeros(nv, self.wm.nu());
        actuation_matrix(&self.wm, &q, &mut s);
        let qf = &s * DVector::from_column_slice(&self.u);
        let mut c = DMatrix::zeros(nk, nv);
        constraint_matrix(&self.wm, &q, &mut c);
        // Ċ: only the θ-dependent base entries change: d/dt of [−sin, cos] and [cos, sin].
        let (st, ct, thd) = (q[2].sin(), q[2].cos(), qd[2]);
        let mut cdot_qd = DVector::zeros(nk);
        cdot_qd[0] = (-ct * qd[0] - st * qd[1]) * thd;
        for r in 1..nk {
            cdot_qd[r] = (-st * qd[0] + ct * qd[1]) * thd;
        }
        let mut kkt = DMatrix::zeros(nv + nk, nv + nk);
        kkt.view_mut((0, 0), (nv, nv)).copy_from(&h);
        kkt.view_mut((0, nv), (nv, nk)).copy_from(&c.transpose());
        kkt.view_mut((nv, 0), (nk, nv)).copy_from(&c);
        let mut rhs = DVector::zeros(nv + nk);
        rhs.rows_mut(0, nv).copy_from(&(qf - nle));
        rhs.rows_mut(nv, nk).copy_from(&(-cdot_qd));
        let sol = kkt.lu().solve(&rhs).expect("KKT system");
        dx[..nv].copy_from_slice(qd.as_slice());
        dx[nv..].copy_from_slice(&sol.as_slice()[..nv]);
        self.last_lambda = sol.rows(nv, nk).into_owned();
        Ok(())
    }
}

#[test]
fn reduced_simulation_agrees_with_the_full_coordinate_dae() {
    use moma::sim::settings::ChannelProfile;
    use moma::sim::{AdaptiveOptions, DormandPrince45};
    for track in [true, false] {
        let wm = robot(track, 0.1);
        let (q0, v0, u) = state(&wm);
        // Reduced simulation to t = 1 s.
        let mut sys = WheeledSystem::new(wm.clone());
        let input = InputProfile {
            channels: u
                .iter()
                .map(|&value| ChannelProfile::Constant { value })
                .collect(),
        };
        let opts = SimulationOptions {
            duration: 1.0,
            integrator: IntegratorSettings::adaptive(1e-12, 1e-12),
            record_interval: 1.0,
            limits: MonitorLimits::default(),
        };
        let res = simulate(
            &mut sys,
            &input,
            q0.as_slice(),
            v0.as_slice(),
            &opts,
            &mut |_| {},
        )
        .unwrap();
        // Full DAE from the same initial state.
        let mut n = DMatrix::zeros(wm.nv(), wm.nr());
        admissible_velocity_basis(&wm, &q0, &mut n);
        let qd0 = &n * &v0;
        let nv = wm.nv();
        let mut dae = FullDae {
            data: moma::multibody::Data::new(&wm.model),
            wm,
            u: u.clone(),
            last_lambda: DVector::zeros(0),
        };
        let mut x: Vec<f64> = q0.iter().chain(qd0.iter()).copied().collect();
        let mut dp = DormandPrince45::new(2 * nv, AdaptiveOptions::with_tolerance(1e-12)).unwrap();
        let mut t = 0.0;
        dp.integrate_to(&mut dae, &mut t, &mut x, 1.0).unwrap();
        let q_red = res.recorder.q_row(1);
        for i in 0..nv {
            assert!(
                (x[i] - q_red[i]).abs() < 1e-8,
                "track={track} q[{i}]: {} vs {}",
                x[i],
                q_red[i]
            );
        }
        // λ at the final state.
        let mut dx = vec![0.0; 2 * nv];
        moma::sim::OdeSystem::rhs(&mut dae, 1.0, &x, &mut dx).unwrap();
        let lam_red = res.recorder.lambda_row(1);
        for (a, b) in dae.last_lambda.iter().zip(lam_red) {
            assert!(
                (a - b).abs() < 1e-6 * (1.0 + a.abs()),
                "track={track} λ: {a} vs {b}"
            );
        }
    }
}

/// Equal positive wheel torques from rest drive the robot forward: the ground pushes each
/// tracked wheel forward (traction, +) by less than τ/r (part of the torque spins the
/// wheel up). The opposite sign, which the mission's own slip monitor once used, fails.
#[test]
fn traction_from_rest_is_a_positive_longitudinal_force() {
    let wm = robot(true, 0.0);
    let mut wd = WheeledData::new(&wm);
    let q = DVector::zeros(wm.model.nq);
    let v = DVector::zeros(wm.nr());
    let mut u = vec![0.0; wm.nu()];
    u[0] = 2.0;
    u[1] = 2.0;
    reduced_forward_dynamics(&wm, &mut wd, &q, &v, &u).unwrap();
    assert!(wd.reduced.vdot[0] > 0.0, "v̇ = {}", wd.reduced.vdot[0]);
    let lam = lagrange_multipliers(&wm, &mut wd, &q).unwrap().clone();
    let f = wheel_longitudinal_forces(&wm, lam.as_slice(), &u);
    let r = wm.base.drive.wheel_radius;
    for (side, fi) in f.iter().enumerate() {
        assert!(
            *fi > 0.0 && *fi < u[side] / r,
            "wheel {side}: {fi} N (τ/r = {})",
            u[side] / r
        );
    }
    // untracked (massless) wheels: the whole torque over the radius
    let wm = robot(false, 0.0);
    assert_eq!(
        wheel_longitudinal_forces(&wm, &[0.0], &u),
        [2.0 / r, 2.0 / r]
    );
}

//! Stability live in simulation (`sim::stability_monitor`): the contact loads balance the
//! gravito-inertial wrench at every sample (three contacts exactly, four by the
//! least-squares rule), the wrench's horizontal force is the ground force of the
//! constraint multipliers, the full-state acceleration is the derivative of the full
//! velocity, slip follows μ, undefined measures are `None`, the first crossing is
//! accurate to the record interval, and a run stops at the tip when asked.

use std::path::Path;

use moma::mobile::{Caster, DiffDrive, WheeledBase, WheeledModel};
use moma::sim::settings::{ChannelProfile, InputProfile, IntegratorSettings};
use moma::sim::stability_monitor::{
    StabilityMonitor, StabilitySettings, first_crossing, first_slip,
};
use moma::sim::wheeled::{SampleObserver, SimulationOptions, simulate_observed};
use moma::sim::wheeled_system::WheeledSystem;
use moma::stability::{LoadRule, load_equilibrium_residual, zero_moment_point};
use nalgebra::{Vector2, Vector3};

/// The brake test robot with the given casters (tracked wheels).
fn robot(casters: &[(&str, [f64; 2])], gravity: f64) -> WheeledModel {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/robots/brake_test_robot.urdf");
    let mut model =
        moma::io::urdf::model_from_urdf_file(&path, moma::multibody::RootJoint::Planar).unwrap();
    model.gravity = Vector3::new(0.0, 0.0, -gravity);
    let base = WheeledBase {
        drive: DiffDrive::new(0.1, 0.25, -0.2).unwrap(),
        casters: casters
            .iter()
            .map(|(n, p)| Caster {
                name: (*n).to_string(),
                position: *p,
            })
            .collect(),
        wheel_joints: Some(["left_wheel_joint".into(), "right_wheel_joint".into()]),
    };
    WheeledModel::new(model, base).unwrap()
}

const REAR_PAIR: [(&str, [f64; 2]); 2] = [("rl", [-0.4, 0.2]), ("rr", [-0.4, -0.2])];
const ONE_REAR: [(&str, [f64; 2]); 1] = [("rear", [-0.4, 0.0])];
/// Arm horizontal, forward, and its holding torques (the shipped extended scenario).
const EXTENDED: [f64; 3] = [0.0, std::f64::consts::FRAC_PI_2, 0.0];
const HOLD_EXTENDED: [f64; 2] = [-44.6355, -13.734];

fn constant(v: f64) -> ChannelProfile {
    ChannelProfile::Constant { value: v }
}

/// The shipped brake: free rolling at 1.5 m/s, a brake ramping to −14 N·m per wheel from
/// t = 0.2 s, released at 0.42 s; arm extended and held.
fn brake_inputs() -> InputProfile {
    let wheel = ChannelProfile::Piecewise {
        times: vec![0.2, 0.225, 0.25, 0.275, 0.3, 0.42],
        values: vec![-2.8, -5.6, -8.4, -11.2, -14.0, 0.0],
    };
    InputProfile {
        channels: vec![
            wheel.clone(),
            wheel,
            constant(0.0),
            constant(HOLD_EXTENDED[0]),
            constant(HOLD_EXTENDED[1]),
        ],
    }
}

fn extended_q() -> Vec<f64> {
    let mut q = vec![0.0; 5];
    q.extend(EXTENDED);
    q
}

fn options(duration: f64, record: f64) -> SimulationOptions {
    SimulationOptions {
        duration,
        integrator: IntegratorSettings::adaptive(1e-10, 1e-10),
        record_interval: record,
        limits: Default::default(),
    }
}

/// A per-sample check: the monitor after the sample, `q` and `u`.
type Check<'a> = dyn FnMut(&StabilityMonitor, &[f64], &[f64]) + 'a;

/// Runs `wm` from `(q0, v0)` with a monitor of `settings`; `check` sees the monitor
/// after every sample.
fn run(
    wm: &WheeledModel,
    settings: StabilitySettings,
    input: &InputProfile,
    q0: &[f64],
    v0: &[f64],
    opts: &SimulationOptions,
    check: &mut Check<'_>,
) -> (StabilityMonitor, Option<f64>, usize) {
    struct Checked<'a> {
        mon: StabilityMonitor,
        check: &'a mut Check<'a>,
    }
    impl SampleObserver for Checked<'_> {
        fn observe(&mut self, t: f64, q: &[f64], v: &[f64], u: &[f64]) -> moma::Result<bool> {
            let stop = self.mon.observe(t, q, v, u)?;
            (self.check)(&self.mon, q, u);
            Ok(stop)
        }
    }
    let mut obs = Checked {
        mon: StabilityMonitor::new(wm, settings).unwrap(),
        check,
    };
    let mut sys = WheeledSystem::new(wm.clone());
    let res =
        simulate_observed(&mut sys, input, q0, v0, opts, &mut |_| {}, Some(&mut obs)).unwrap();
    (obs.mon, res.stopped_at, res.recorder.len())
}

/// Turning, braking and a swinging arm: every force and moment is exercised.
fn manoeuvre() -> InputProfile {
    let sin = |offset: f64, amplitude: f64, frequency: f64| ChannelProfile::Sinusoid {
        offset,
        amplitude,
        frequency,
        phase: 0.3,
    };
    InputProfile {
        channels: vec![
            sin(-3.0, 2.0, 1.5),
            sin(1.0, 3.0, 1.0),
            sin(0.0, 2.0, 2.0),
            sin(HOLD_EXTENDED[0], 8.0, 1.2),
            sin(HOLD_EXTENDED[1], 3.0, 1.7),
        ],
    }
}

#[test]
fn loads_balance_the_wrench_and_the_ground_forces_are_the_multipliers() {
    let v0 = [1.0, 0.4, 0.2, 0.0, 0.0];
    for (casters, rule) in [
        (&ONE_REAR[..], LoadRule::Exact),
        (&REAR_PAIR[..], LoadRule::MinimumNorm),
    ] {
        let wm = robot(casters, 9.81);
        let settings = StabilitySettings {
            mu: Some(0.8),
            ..Default::default()
        };
        let mut n = 0;
        let mut check = |mon: &StabilityMonitor, q: &[f64], _u: &[f64]| {
            n += 1;
            let w = mon.wrench();
            let mg = w.mass * 9.81;
            let loads = mon.normal_loads();
            let contacts = mon.contacts_world();
            assert_eq!(mon.load_rule(), Some(rule));
            // Σ N = −f_z and the moments about horizontal axes balance
            let sum: f64 = loads.iter().sum();
            assert!(
                (sum + w.force.z).abs() < 1e-9 * mg,
                "{sum} vs {}",
                w.force.z
            );
            let r = load_equilibrium_residual(contacts, 0.0, w, loads);
            assert!(r.norm() < 1e-9 * mg, "residual {r}");
            for p0 in [Vector3::zeros(), Vector3::new(q[0] + 1.0, q[1] - 2.0, 0.0)] {
                let mut m = w.moment_about(&p0);
                for (c, nj) in contacts.iter().zip(loads) {
                    m += (Vector3::new(c.x, c.y, 0.0) - p0).cross(&Vector3::new(0.0, 0.0, *nj));
                }
                assert!(m.x.abs() < 1e-8 * mg && m.y.abs() < 1e-8 * mg, "moment {m}");
            }
            if rule == LoadRule::Exact {
                // three contacts: the loads' centre of pressure is the ZMP
                let zmp = zero_moment_point(w, 0.0).unwrap();
                let cop = contacts
                    .iter()
                    .zip(loads)
                    .map(|(c, nj)| c * *nj)
                    .sum::<Vector2<f64>>()
                    / sum;
                assert!((cop - zmp.xy()).norm() < 1e-9, "{cop} vs {zmp}");
            }
            // the horizontal ground force of the multipliers balances f_gi: lateral −λ0
            // on the axle, longitudinal −λ1, −λ2 at the wheels
            let lam = mon.multipliers();
            let (s, c) = q[2].sin_cos();
            let ground = Vector2::new(-s, c) * (-lam[0]) + Vector2::new(c, s) * (-lam[1] - lam[2]);
            assert!(
                (w.force.xy() + ground).norm() < 1e-8 * mg,
                "{} vs {ground}",
                w.force.xy()
            );
            // ... and the wheels' shares add up to it
            let f = mon.trace.wheels.last().unwrap();
            assert!((f[0].lateral + f[1].lateral + lam[0]).abs() < 1e-9 * mg);
            assert!((f[0].longitudinal + lam[1]).abs() < 1e-12 * mg);
        };
        let (mon, stopped, len) = run(
            &wm,
            settings,
            &manoeuvre(),
            &extended_q(),
            &v0,
            &options(0.6, 0.02),
            &mut check,
        );
        assert_eq!(stopped, None);
        assert_eq!(n, len);
        assert_eq!(mon.trace.times.len(), len);
    }
}

#[test]
fn massless_wheels_push_with_their_torque_over_the_radius() {
    // Wheel joints not tracked: the wheels are free-spinning joints and the drive pushes
    // with τ / r_w at the contacts; the ground force is still the wrench's.
    let mut wm = robot(&REAR_PAIR, 9.81);
    wm.base.wheel_joints = None;
    let wm = WheeledModel::new(wm.model, wm.base).unwrap();
    assert!(wm.wheel_dofs().is_none());
    let m = manoeuvre();
    let zero = constant(0.0);
    let input = InputProfile {
        channels: vec![
            m.channels[0].clone(),
            m.channels[1].clone(),
            zero.clone(),
            zero,
            m.channels[2].clone(),
            m.channels[3].clone(),
            m.channels[4].clone(),
        ],
    };
    let settings = StabilitySettings {
        mu: Some(0.8),
        ..Default::default()
    };
    let mut n = 0;
    let mut check = |mon: &StabilityMonitor, q: &[f64], u: &[f64]| {
        n += 1;
        let w = mon.wrench();
        let mg = w.mass * 9.81;
        let lam = mon.multipliers();
        assert_eq!(lam.len(), 1);
        let (s, c) = q[2].sin_cos();
        let ground = Vector2::new(-s, c) * (-lam[0]) + Vector2::new(c, s) * ((u[0] + u[1]) / 0.1);
        assert!(
            (w.force.xy() + ground).norm() < 1e-8 * mg,
            "{} vs {ground}",
            w.force.xy()
        );
        let f = mon.trace.wheels.last().unwrap();
        assert!((f[0].longitudinal - u[0] / 0.1).abs() < 1e-12 * mg);
        let sum: f64 = mon.normal_loads().iter().sum();
        assert!((sum + w.force.z).abs() < 1e-9 * mg);
    };
    let v0 = [1.0, 0.4, 10.0, 6.0, 0.2, 0.0, 0.0];
    run(
        &wm,
        settings,
        &input,
        &extended_q(),
        &v0,
        &options(0.3, 0.02),
        &mut check,
    );
    assert_eq!(n, 16);
}

#[test]
fn the_full_state_acceleration_is_the_derivative_of_the_full_velocity() {
    let wm = robot(&REAR_PAIR, 9.81);
    let mut rows: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
    let mut check = |mon: &StabilityMonitor, _q: &[f64], _u: &[f64]| {
        let (qd, qdd) = mon.full_state_rates();
        rows.push((qd.as_slice().to_vec(), qdd.as_slice().to_vec()));
    };
    let h = 5e-4;
    run(
        &wm,
        StabilitySettings::default(),
        &manoeuvre(),
        &extended_q(),
        &[1.0, 0.4, 0.2, 0.0, 0.0],
        &options(0.1, h),
        &mut check,
    );
    let mut worst = 0.0f64;
    for i in 1..rows.len() - 1 {
        for k in 0..rows[i].0.len() {
            let fd = (rows[i + 1].0[k] - rows[i - 1].0[k]) / (2.0 * h);
            worst = worst.max((fd - rows[i].1[k]).abs() / (1.0 + rows[i].1[k].abs()));
        }
    }
    assert!(worst < 1e-4, "central difference of q̇ vs q̈: {worst:e}");
}

#[test]
fn extended_arm_brake_tips_and_the_crossing_is_accurate_to_the_record_interval() {
    let wm = robot(&REAR_PAIR, 9.81);
    let v0 = [1.5, 0.0, 0.0, 0.0, 0.0];
    let settings = StabilitySettings {
        mu: Some(0.9),
        ..Default::default()
    };
    let mut none = |_: &StabilityMonitor, _: &[f64], _: &[f64]| {};
    let mut crossing = |record: f64| {
        let (mon, _, _) = run(
            &wm,
            settings.clone(),
            &brake_inputs(),
            &extended_q(),
            &v0,
            &options(0.4, record),
            &mut none,
        );
        let tr = &mon.trace;
        let c = first_crossing(&tr.times, &tr.zmp_margin, true).unwrap();
        // the sample before is stable, the crossing sample is not
        assert!(tr.zmp_margin[c.sample - 1].unwrap() > 0.0);
        assert!(tr.zmp_margin[c.sample].unwrap() <= 0.0);
        assert!(c.time > c.sample_time - record - 1e-12 && c.time <= c.sample_time);
        // the robot tips forward, about the driven axle (edge 2: left → right wheel)
        let e = mon.edges()[tr.critical_edge[c.sample].unwrap()];
        assert_eq!((e.from, e.to), (0, 1));
        assert!(mon.tipped());
        // FA and MHS cross on the same edge: MHS at the ZMP's time (flat ground)
        let m = first_crossing(&tr.times, &tr.mhs_min, false).unwrap();
        assert_eq!(m.sample, c.sample);
        assert!((m.time - c.time).abs() < 1e-9);
        assert_eq!(
            first_crossing(&tr.times, &tr.force_angle_min, false)
                .unwrap()
                .sample,
            c.sample
        );
        c.time
    };
    let coarse = crossing(0.01);
    let fine = crossing(0.0005);
    assert!(coarse > 0.2 && coarse < 0.3, "{coarse}");
    assert!((coarse - fine).abs() <= 0.01, "{coarse} vs {fine}");
    // the interpolation does better than the interval
    assert!((coarse - fine).abs() <= 0.002, "{coarse} vs {fine}");

    // the same brake heading elsewhere: same crossing, same edge (base-frame numbering)
    let mut q0 = extended_q();
    q0[..3].copy_from_slice(&[3.0, -1.0, 2.0]);
    let (mon, _, _) = run(
        &wm,
        settings.clone(),
        &brake_inputs(),
        &q0,
        &v0,
        &options(0.4, 0.01),
        &mut none,
    );
    let tr = &mon.trace;
    let c = first_crossing(&tr.times, &tr.zmp_margin, true).unwrap();
    assert!((c.time - coarse).abs() < 1e-9, "{} vs {coarse}", c.time);
    let e = mon.edges()[tr.critical_edge[c.sample].unwrap()];
    assert_eq!((e.from, e.to), (0, 1));
    assert!(
        tr.critical_edge
            .iter()
            .all(|&e| e.is_some_and(|e| e == 0 || e == 2))
    );

    // stop_at_tip ends the run at the crossing sample
    let stop = StabilitySettings {
        stop_at_tip: true,
        ..settings.clone()
    };
    let (mon, stopped, len) = run(
        &wm,
        stop,
        &brake_inputs(),
        &extended_q(),
        &v0,
        &options(0.4, 0.01),
        &mut none,
    );
    let c = first_crossing(&mon.trace.times, &mon.trace.zmp_margin, true).unwrap();
    assert_eq!(stopped, Some(c.sample_time));
    assert_eq!(len, c.sample + 1);
    assert!((c.time - coarse).abs() < 1e-9);
}

#[test]
fn slip_follows_mu() {
    let wm = robot(&REAR_PAIR, 9.81);
    let v0 = [1.5, 0.0, 0.0, 0.0, 0.0];
    let mut none = |_: &StabilityMonitor, _: &[f64], _: &[f64]| {};
    let mut trace = |mu: f64| {
        let settings = StabilitySettings {
            mu: Some(mu),
            ..Default::default()
        };
        run(
            &wm,
            settings,
            &brake_inputs(),
            &extended_q(),
            &v0,
            &options(0.3, 0.005),
            &mut none,
        )
        .0
        .trace
    };
    let high = trace(0.9);
    let low = trace(0.3);
    assert!(first_slip(&high).is_none());
    // same trajectory: the ratios scale as 1/μ exactly
    for (a, b) in high.wheels.iter().zip(&low.wheels) {
        for k in 0..2 {
            let (ra, rb) = (a[k].slip_ratio.unwrap(), b[k].slip_ratio.unwrap());
            assert!((rb - 3.0 * ra).abs() <= 1e-12 * (1.0 + rb), "{ra} {rb}");
            assert_eq!(b[k].slips, rb > 1.0);
        }
    }
    let s = first_slip(&low).unwrap();
    let ratio = |i: usize| {
        low.wheels[i][0]
            .slip_ratio
            .unwrap()
            .max(low.wheels[i][1].slip_ratio.unwrap())
    };
    assert!(ratio(s.sample) > 1.0 && ratio(s.sample - 1) <= 1.0);
    assert!(s.time > low.times[s.sample - 1] && s.time <= s.sample_time);
    // the brake starts at 0.2 s: no slip before
    assert!(s.sample_time > 0.2);
}

#[test]
fn undefined_measures_are_none_never_nan() {
    let settings = StabilitySettings {
        mu: Some(0.5),
        ..Default::default()
    };
    let input = InputProfile::zero(5);
    let v0 = [0.5, 0.0, 0.0, 0.0, 0.0];
    let mut none = |_: &StabilityMonitor, _: &[f64], _: &[f64]| {};
    // No gravity, rolling straight at constant speed: no effective force, so no
    // Force-Angle; zero loads, no slip ratio and no slip.
    let wm = robot(&REAR_PAIR, 0.0);
    let (mon, _, _) = run(
        &wm,
        settings.clone(),
        &input,
        &extended_q(),
        &v0,
        &options(0.05, 0.01),
        &mut none,
    );
    let tr = &mon.trace;
    assert!(tr.force_angle_min.iter().all(Option::is_none));
    assert!(tr.force_angle_alpha.iter().all(Option::is_none));
    // M_i = 0 over I_i > 0: defined and zero
    assert!(tr.mhs_min.iter().all(|m| m.is_some_and(|m| m.abs() < 1e-9)));
    assert!(tr.normal_loads.iter().all(|x| x.abs() < 1e-9));
    for w in tr.wheels.iter().flatten() {
        assert_eq!(w.slip_ratio, None);
        assert!(!w.slips);
    }
    assert!(first_slip(tr).is_none());
    // Gravity pointing up: the ground would have to pull, there is no ZMP, the loads
    // are negative and finite, and the robot counts as tipped from the first sample.
    let wm = robot(&REAR_PAIR, -1.0);
    let (mon, _, _) = run(
        &wm,
        settings,
        &input,
        &extended_q(),
        &v0,
        &options(0.05, 0.01),
        &mut none,
    );
    let tr = &mon.trace;
    assert!(tr.zmp.iter().all(Option::is_none));
    assert!(tr.zmp_margin.iter().all(Option::is_none));
    assert!(tr.critical_edge.iter().all(Option::is_none));
    assert!(tr.normal_loads.iter().all(|x| x.is_finite() && *x < 0.0));
    for w in tr.wheels.iter().flatten() {
        assert_eq!(w.slip_ratio, None);
        assert!(w.lateral.is_finite() && w.longitudinal.is_finite());
    }
    assert!(mon.tipped());
    let c = first_crossing(&tr.times, &tr.zmp_margin, true).unwrap();
    assert_eq!((c.sample, c.time), (0, 0.0));
}

#[test]
fn a_support_without_a_caster_is_an_error() {
    let wm = robot(&[], 9.81);
    let e = StabilityMonitor::new(&wm, StabilitySettings::default()).unwrap_err();
    assert!(e.to_string().contains("caster"), "{e}");
    let wm = robot(&REAR_PAIR, 9.81);
    let bad_mu = StabilitySettings {
        mu: Some(0.0),
        ..Default::default()
    };
    assert!(
        StabilityMonitor::new(&wm, bad_mu)
            .unwrap_err()
            .to_string()
            .contains("mu")
    );
    let bad_body = StabilitySettings {
        bodies: moma::stability::BodySet::Subtree("no_such_joint".into()),
        ..Default::default()
    };
    assert!(StabilityMonitor::new(&wm, bad_body).is_err());
}

//! The whole-body MPC in closed loop on Fetch's reduced-model plant: reaching a target
//! beside the path while the base drives, and the tip-over constraint holding the ZMP
//! margin where the unconstrained MPC lets it go negative; the torques of a planned
//! input, recomputed at a state the plant moved to, realising that input there.

mod mpc_common;

use moma::collision::Scene;
use moma::control::mpc::{KnotReference, MpcSettings};
use moma::sim::mpc_loop::{MpcLoopSettings, run_mpc_loop};
use moma::sim::mpc_run::MpcRun;
use moma::sim::wheeled_system::WheeledSystem;
use nalgebra::{DVector, Matrix3, Vector3};

/// The reach-on-the-move scenario: the base follows y = 0 at 0.3 m/s for the whole run;
/// from t = 1 s the gripper is asked to a point 0.45 m right of the path at x = 1.0 m,
/// above a table, which the base passes at about t = 3.3 s.
pub fn reach_on_the_move(settings: MpcSettings, duration: f64) -> MpcRun {
    let scene = Scene {
        objects: vec![mpc_common::box_object(
            "table",
            [1.0, -0.85, 0.35],
            [0.3, 0.25, 0.35],
        )],
    };
    let (mut mpc, q0) = mpc_common::fetch_mpc(Some(scene), settings);
    let mut plant = WheeledSystem::new(mpc.problem.robot.wheeled.clone());
    let v0 = vec![0.0; plant.robot.nr()];
    let target = Vector3::new(1.0, -0.45, 0.85);
    let loop_settings = MpcLoopSettings {
        duration,
        period: 0.05,
        substeps: 5,
    };
    run_mpc_loop(
        &mut mpc,
        &mut plant,
        q0.as_slice(),
        &v0,
        &loop_settings,
        |t| KnotReference {
            base: [0.3 * t, 0.0, 0.0],
            end_effector: (t >= 1.0).then_some((target, Matrix3::identity())),
        },
    )
    .unwrap()
}

#[test]
fn reaches_while_the_base_moves_within_bounded_violations() {
    let mut s = MpcSettings::default();
    s.weights.ee_orientation = 0.0;
    let run = reach_on_the_move(s, 5.0);
    let sum = &run.summary;
    println!("{sum:#?}");
    // The closest approach of the gripper, and the base speed then.
    let best = run
        .samples
        .iter()
        .filter(|s| s.ee_error.is_some())
        .min_by(|a, b| a.ee_error.unwrap().total_cmp(&b.ee_error.unwrap()))
        .unwrap();
    println!(
        "closest {:?} m at t = {} s, base speed {} m/s",
        best.ee_error, best.t, best.v[0]
    );
    assert!(best.ee_error.unwrap() < 0.06, "{:?}", best.ee_error);
    assert!(best.v[0].abs() > 0.1, "the base still moves: {}", best.v[0]);
    // Closed-loop constraint violations, bounded.
    assert!(sum.min_zmp_margin > 0.05, "{}", sum.min_zmp_margin);
    assert!(sum.min_clearance > 0.0, "{}", sum.min_clearance);
    assert!(sum.wheel_speed_excess == 0.0, "{sum:?}");
    assert!(sum.joint_speed_excess < 1.5, "{sum:?}");
    assert!(sum.joint_position_excess < 0.05, "{sum:?}");
    assert!(sum.max_torque_excess < 1.0, "{sum:?}");
}

/// Fetch with five times its wheel torque (so that braking can tip it): the base, moving
/// at 1 m/s with the arm raised forward, is asked to stop at once.
fn hard_stop(zmp: Option<f64>) -> MpcRun {
    let mut s = MpcSettings::default();
    s.constraints.zmp_margin = zmp;
    s.max_linear_acceleration = 8.0;
    s.weights.base_position = 400.0;
    let (mut mpc, q0) = mpc_common::fetch_hard_stop(s);
    let robot = &mpc.problem.robot;
    mpc.problem.posture =
        nalgebra::DVector::from_iterator(robot.n_moved(), robot.dofs.iter().map(|&d| q0[d]));
    let mut plant = WheeledSystem::new(mpc.problem.robot.wheeled.clone());
    let mut v0 = vec![0.0; plant.robot.nr()];
    v0[0] = 1.0;
    let loop_settings = MpcLoopSettings {
        duration: 1.5,
        period: 0.05,
        substeps: 5,
    };
    run_mpc_loop(
        &mut mpc,
        &mut plant,
        q0.as_slice(),
        &v0,
        &loop_settings,
        |_| KnotReference {
            base: [0.0, 0.0, 0.0],
            end_effector: None,
        },
    )
    .unwrap()
}

/// The smallest ZMP margin of the plant over the whole run, not only at the solves: each
/// period replayed from its sample's state under the torques held over it (the loop's
/// zero-order hold), RK4 at 1 ms, the margin of the plant's acceleration at every step
/// (`stability::evaluate`, as the samples'); lift-off counts as `−∞`.
fn min_margin_between_solves(run: &MpcRun, wheeled: &moma::mobile::WheeledModel) -> f64 {
    use moma::mobile::wheeled::{WheeledData, reduced_forward_dynamics_crba};
    use moma::sim::reduced_system::ReducedSystem;
    use moma::stability::{ExternalLoads, StabilityData, evaluate};
    let robot = mpc_common::fetch_robot(None);
    let mut plant = WheeledSystem::new(wheeled.clone());
    let mut wd = WheeledData::new(wheeled);
    let mut sd = StabilityData::new(&robot.stability);
    let (nq, nv) = (plant.nq(), plant.nv());
    let mut margin = |q: &[f64], v: &[f64], tau: &[f64]| {
        let (q, v) = (DVector::from_column_slice(q), DVector::from_column_slice(v));
        reduced_forward_dynamics_crba(wheeled, &mut wd, &q, &v, tau).unwrap();
        evaluate(
            &wheeled.model,
            &mut wd.data,
            &robot.stability,
            &mut sd,
            &q,
            &wd.qdot,
            &wd.reduced.qddot,
            &ExternalLoads::NONE,
        )
        .zmp_margin
        .unwrap_or(f64::NEG_INFINITY)
    };
    let (steps, h) = (50, 0.001);
    let mut lowest = f64::INFINITY;
    for s in &run.samples {
        let (mut q, mut v) = (s.q.clone(), s.v.clone());
        for _ in 0..steps {
            lowest = lowest.min(margin(&q, &v, &s.torque));
            // Classic RK4 on (q, v): slopes at y, y + h/2 k1, y + h/2 k2, y + h k3.
            let mut slopes: Vec<(Vec<f64>, Vec<f64>)> = Vec::with_capacity(4);
            for c in [0.0, 0.5 * h, 0.5 * h, h] {
                let (qs, vs): (Vec<f64>, Vec<f64>) = match slopes.last() {
                    Some((kq, kv)) => (
                        q.iter().zip(kq).map(|(a, b)| a + c * b).collect(),
                        v.iter().zip(kv).map(|(a, b)| a + c * b).collect(),
                    ),
                    None => (q.clone(), v.clone()),
                };
                let (mut kq, mut kv) = (vec![0.0; nq], vec![0.0; nv]);
                plant
                    .dynamics(&qs, &vs, &s.torque, &mut kq, &mut kv)
                    .unwrap();
                slopes.push((kq, kv));
            }
            for (w, (kq, kv)) in [1.0, 2.0, 2.0, 1.0].iter().zip(&slopes) {
                for i in 0..nq {
                    q[i] += w * h / 6.0 * kq[i];
                }
                for i in 0..nv {
                    v[i] += w * h / 6.0 * kv[i];
                }
            }
        }
    }
    lowest
}

#[test]
fn tip_over_constraint_keeps_the_zmp_margin_that_the_unconstrained_mpc_loses() {
    let free = hard_stop(None);
    let kept = hard_stop(Some(0.03));
    println!("free {:#?}\nkept {:#?}", free.summary, kept.summary);
    let wheeled = mpc_common::fetch_robot(None).wheeled;
    let (free_between, kept_between) = (
        min_margin_between_solves(&free, &wheeled),
        min_margin_between_solves(&kept, &wheeled),
    );
    println!("between solves: free {free_between} m, kept {kept_between} m");
    // Without the constraint the ZMP leaves the support.
    assert!(
        free.summary.min_zmp_margin < 0.0,
        "{}",
        free.summary.min_zmp_margin
    );
    // With it, at every solve the first input keeps the set value exactly at the
    // measured state ("Limits the solver enforces", docs/mpc.md); the applied torques
    // realise it on the plant to the rounding of the forward dynamics of the plant's
    // state (the held joints' small velocities, which the MPC's model zeroes).
    // Measured: 0.0299998 m.
    assert!(
        kept.summary.min_zmp_margin > 0.03 - 1e-6,
        "{}",
        kept.summary.min_zmp_margin
    );
    // Between solves the torques are held over the 50 ms period while the state moves,
    // so the acceleration, hence the ZMP, drifts from the one the solve held. Measured:
    // 0.02846 m at worst, 1.5 mm below the set value, at the end of the period from
    // t = 0.70 s (the base speeding up from 0.27 to 0.50 m/s at the held torques, the
    // margin falling steadily through the period); 2.5 mm allowed.
    assert!(kept_between > 0.03 - 0.0025, "{kept_between}");
}

/// `scenarios/mpc_reach_on_the_move.toml`, read by `moma::sim_config` and run by the
/// closed loop of `moma simulate`, is the closed loop of [`reach_on_the_move`]: every
/// solve starts from the same state and applies the same torques, to the last bit (the
/// solve times, wall-clock, excepted).
#[test]
fn the_shipped_scenario_is_the_reach_on_the_move_loop() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/mpc_reach_on_the_move.toml");
    let sc = moma::sim_config::load(&path).unwrap();
    let moma::sim_config::Run::Closed(mut cl) = moma::sim_config::prepare(&sc, &path).unwrap()
    else {
        panic!("not a closed loop");
    };
    let res = cl.run(&mut |_| {}).unwrap();
    let from_file = cl.law.mpc_run().unwrap();
    let mut s = MpcSettings::default();
    s.weights.ee_orientation = 0.0;
    let direct = reach_on_the_move(s, 5.0);
    assert_eq!(from_file.samples.len(), direct.samples.len());
    for (a, b) in from_file.samples.iter().zip(&direct.samples) {
        assert_eq!((a.t, &a.q, &a.v, &a.torque), (b.t, &b.q, &b.v, &b.torque));
        assert_eq!(a.solve.iterations, b.solve.iterations, "t = {}", a.t);
        assert_eq!(a.solve.violations, b.solve.violations, "t = {}", a.t);
        assert_eq!(
            (a.zmp_margin, a.clearance, a.ee_error),
            (b.zmp_margin, b.clearance, b.ee_error)
        );
    }
    let (f, d) = (&from_file.summary, &direct.summary);
    assert_eq!(f.min_zmp_margin, d.min_zmp_margin);
    assert_eq!(f.min_clearance, d.min_clearance);
    assert_eq!(f.min_ee_error, d.min_ee_error);
    assert_eq!(f.planned_violations, d.planned_violations);
    // The law's errors and signals as recorded by the loop.
    assert_eq!(
        res.error_names,
        [
            "ee_position [m]",
            "base_x [m]",
            "base_y [m]",
            "base_heading [rad]"
        ]
    );
    assert_eq!(
        res.signal_names,
        [
            "solve_time [s]",
            "iterations [1]",
            "planned_zmp_margin [m]",
            "clearance [m]"
        ]
    );
    // Recorded every 50 ms, after the solve of that tick: the tick's iterations and, at
    // t = 2 s (sample 40), the base's error to x = 0.6 m. The recorded clearance is a
    // second query at the sample's configuration, warm-started from the sample's own, so
    // it may differ in the last bits (the distances converge to a 1e-12 m gap).
    let row = res.signal_row(40);
    assert_eq!(row[1], direct.samples[40].solve.iterations as f64);
    assert!(
        (row[3] - direct.samples[40].clearance).abs() < 1e-12,
        "{} vs {}",
        row[3],
        direct.samples[40].clearance
    );
    let e = res.error_row(40);
    assert_eq!(e[0], direct.samples[40].ee_error.unwrap());
    assert_eq!(e[1], direct.samples[40].q[0] - 0.3 * 2.0);
    assert!(res.error_row(0)[0].is_nan(), "no target before t = 1 s");
}

/// Between solves the torques of the planned input are recomputed at the measured state:
/// there they give the planned acceleration `[v̇, ω̇, q̈_c]` (the plant's forward dynamics
/// of them, not the inverse dynamics that made them), where the torques of the solve's
/// state, held, give another.
#[test]
fn the_planned_input_is_realised_at_a_state_the_plant_moved_to() {
    use moma::mobile::wheeled::{WheeledData, reduced_forward_dynamics_crba};
    let (mut mpc, q0) = mpc_common::fetch_mpc(None, MpcSettings::default());
    let nr = mpc.problem.robot.wheeled.nr();
    let v0 = DVector::zeros(nr);
    mpc.set_reference(0.0, |_| KnotReference {
        base: [0.5, 0.0, 0.0],
        end_effector: Some((Vector3::new(0.8, -0.3, 0.9), Matrix3::identity())),
    });
    mpc.solve(q0.as_slice(), v0.as_slice()).unwrap();
    let input = mpc.first_input().clone();
    let robot = mpc.problem.robot.clone();
    let n = robot.n_moved();
    assert!(input.amax() > 0.1, "a plan that moves: {input}");
    // Where the plant is partway through the period: base and moved joints displaced and
    // moving (the held joints stay put, as the MPC's model holds them).
    let (mut q1, mut v1) = (q0.clone(), v0.clone());
    q1[2] += 0.05;
    v1[0] = 0.3;
    v1[1] = -0.4;
    for i in 0..n {
        q1[robot.dofs[i]] += 0.02 * (i as f64 + 1.0);
        v1[robot.reduced[i]] = 0.6 * if i % 2 == 0 { 1.0 } else { -1.0 };
    }
    let nu = robot.wheeled.nu();
    let mut wd = WheeledData::new(&robot.wheeled);
    let mut realised = |tau: &[f64]| {
        reduced_forward_dynamics_crba(&robot.wheeled, &mut wd, &q1, &v1, tau)
            .unwrap()
            .clone()
    };
    let planned_error = |a: &DVector<f64>| {
        let mut e: f64 = (a[0] - input[0]).abs().max((a[1] - input[1]).abs());
        for i in 0..n {
            e = e.max((a[robot.reduced[i]] - input[2 + i]).abs());
        }
        e
    };
    let mut tau_now = vec![0.0; nu];
    mpc.first_input_torques_at(q1.as_slice(), v1.as_slice(), &mut tau_now, false)
        .unwrap();
    let a_now = realised(&tau_now);
    assert!(planned_error(&a_now) < 1e-9, "{a_now} vs {input}");
    let mut tau_held = vec![0.0; nu];
    mpc.first_input_torques_at(q0.as_slice(), v0.as_slice(), &mut tau_held, false)
        .unwrap();
    let a_held = realised(&tau_held);
    assert!(planned_error(&a_held) > 0.1, "{a_held} vs {input}");
    // A state of the wrong length is an error, not a panic.
    let e = mpc
        .first_input_torques_at(&q1.as_slice()[1..], v1.as_slice(), &mut tau_now, false)
        .unwrap_err();
    assert!(e.to_string().contains("mpc state"), "{e}");
}

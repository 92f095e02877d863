//! The hot paths that the documentation calls allocation-free, beyond the rigid-body core
//! and the reduced dynamics: IK iterations (no objective and the posture objective),
//! one integrator step (RK4, Dormand–Prince, DOP853), A* and D* Lite queries after
//! warm-up and `DStarLite::clone_from`. A counting global allocator counts per thread, so
//! the tests may run in parallel.

use moma::ik::model::ModelFrame;
use moma::ik::tasks::{PoseTask, TaskRows};
use moma::ik::{IkOptions, IkStatus, IkWorkspace, NullSpaceObjective, solve};
use moma::io::urdf::model_from_urdf_file;
use moma::multibody::RootJoint;
use moma::planning::astar::astar_cost;
use moma::planning::dstar_lite::DStarLite;
use moma::planning::{AstarWorkspace, SearchGrid};
use moma::sim::{AdaptiveOptions, Dop853, DormandPrince45, OdeSystem, Rk4};
use nalgebra::{DVector, Isometry3};
use std::sync::Arc;

mod counting_alloc;
use counting_alloc::allocations;

#[test]
fn the_counter_counts() {
    let (n, v) = allocations(|| std::hint::black_box(vec![1u8; 32]));
    assert!(n >= 1);
    drop(v);
}

fn panda_task() -> PoseTask<ModelFrame> {
    let path = format!(
        "{}/tests/data/pinocchio/urdf/panda.urdf",
        env!("CARGO_MANIFEST_DIR")
    );
    let model = Arc::new(model_from_urdf_file(path, RootJoint::Fixed).unwrap());
    let kin = ModelFrame::by_name(model, "panda_hand_tcp").unwrap();
    let target = Isometry3::translation(0.9, 0.6, 0.3); // out of reach: never converges
    PoseTask::new(kin, target, &TaskRows::Full)
        .unwrap()
        .with_preferred_posture(DVector::from_vec(vec![
            0.1, -0.2, 0.3, -1.5, 0.2, 1.4, 0.3, 0.02, 0.02,
        ]))
        .unwrap()
}

#[test]
fn ik_iterations_do_not_allocate() {
    // A solve allocates a fixed amount (its start vectors and the result); the
    // iterations allocate nothing, so 5 and 60 iterations allocate the same.
    let mut task = panda_task();
    let mut ws = IkWorkspace::new(&task);
    let q0 = DVector::from_vec(vec![0.0, -0.3, 0.0, -1.8, 0.0, 1.5, 0.8, 0.02, 0.02]);
    for null_space in [
        NullSpaceObjective::None,
        NullSpaceObjective::Posture { gain: 0.1 },
    ] {
        let opts = |max_iterations| IkOptions {
            max_iterations,
            stall_iterations: usize::MAX,
            null_space: null_space.clone(),
            ..IkOptions::default()
        };
        let (short_opts, long_opts) = (opts(5), opts(60));
        solve(&mut task, &q0, &long_opts, &mut ws).unwrap(); // warm-up
        let (short, r5) = allocations(|| solve(&mut task, &q0, &short_opts, &mut ws).unwrap());
        let (long, r60) = allocations(|| solve(&mut task, &q0, &long_opts, &mut ws).unwrap());
        assert_eq!(r5.iterations, 5);
        assert_eq!(r60.iterations, 60, "{:?}", r60.status);
        assert_eq!(r60.status, IkStatus::MaxIterations);
        assert_eq!(long, short, "{null_space:?}: 55 more iterations allocated");
    }
}

/// ẋ = A x for a fixed 4 × 4 rotation-like A (no allocation in the right-hand side).
struct Linear;

impl OdeSystem for Linear {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> moma::Result<()> {
        dx[0] = x[1];
        dx[1] = -x[0];
        dx[2] = 0.5 * x[3];
        dx[3] = -0.5 * x[2] - 0.01 * x[3];
        Ok(())
    }
}

#[test]
fn integrator_steps_do_not_allocate() {
    let mut sys = Linear;
    let mut x = [1.0, 0.0, 0.5, 0.2];
    let mut rk = Rk4::new(4);
    rk.step(&mut sys, 0.0, &mut x, 0.01).unwrap();
    let (n, ()) = allocations(|| {
        for k in 0..100 {
            rk.step(&mut sys, 0.01 * k as f64, &mut x, 0.01).unwrap();
        }
    });
    assert_eq!(n, 0, "RK4 steps allocated {n} times");

    let mut dp = DormandPrince45::new(4, AdaptiveOptions::default()).unwrap();
    let mut t = 0.0;
    dp.integrate_to(&mut sys, &mut t, &mut x, 0.1).unwrap();
    let (n, ()) = allocations(|| dp.integrate_to(&mut sys, &mut t, &mut x, 5.0).unwrap());
    assert_eq!(n, 0, "Dormand–Prince steps allocated {n} times");
    assert!(dp.stats.accepted > 3);

    let mut d8 = Dop853::new(4, AdaptiveOptions::default()).unwrap();
    let mut t = 0.0;
    d8.integrate_to(&mut sys, &mut t, &mut x, 0.1).unwrap();
    let (n, ()) = allocations(|| d8.integrate_to(&mut sys, &mut t, &mut x, 5.0).unwrap());
    assert_eq!(n, 0, "DOP853 steps allocated {n} times");
}

fn maze(w: usize, h: usize) -> Vec<bool> {
    // walls every 8 columns with a gap alternating top and bottom
    let mut obst = vec![false; w * h];
    for x in (8..w - 1).step_by(8) {
        let gap = if (x / 8) % 2 == 0 { 1 } else { h - 2 };
        for y in 0..h {
            if y != gap {
                obst[y * w + x] = true;
            }
        }
    }
    obst
}

#[test]
fn planner_queries_do_not_allocate_after_warm_up() {
    let (w, h) = (96, 64);
    let grid = SearchGrid::from_obstacles(&maze(w, h), w, h).unwrap();
    let mut ws = AstarWorkspace::new();
    let (start, goal) = ((1, 1), (w - 2, h - 2));
    // Warm-up: the workspace grows to the map and to the largest queue seen so far.
    let (c0, _) = astar_cost(&grid, &mut ws, start, goal).unwrap();
    let (c2, _) = astar_cost(&grid, &mut ws, (3, 60), (90, 2)).unwrap();
    assert!(c0.is_some() && c2.is_some());
    assert!(
        astar_cost(&grid, &mut ws, (5, 5), (60, 40))
            .unwrap()
            .0
            .is_some()
    );
    // (the open list's buckets keep the largest size each has reached; a few rounds of
    // the same queries bring every bucket there)
    for _ in 0..3 {
        for (a, b) in [(start, goal), ((3, 60), (90, 2)), ((5, 5), (60, 40))] {
            astar_cost(&grid, &mut ws, a, b).unwrap();
        }
    }
    let (n, ()) = allocations(|| {
        for _ in 0..3 {
            assert_eq!(astar_cost(&grid, &mut ws, start, goal).unwrap().0, c0);
            assert_eq!(astar_cost(&grid, &mut ws, (3, 60), (90, 2)).unwrap().0, c2);
            assert!(
                astar_cost(&grid, &mut ws, (5, 5), (60, 40))
                    .unwrap()
                    .0
                    .is_some()
            );
        }
    });
    assert_eq!(n, 0, "A* queries allocated {n} times");

    // D* Lite: a first plan, then moves and map changes re-planned in place.
    let mut planner = DStarLite::new(&grid, start, goal).unwrap();
    planner.compute().unwrap();
    let mut snapshot = planner.clone();
    // warm-up of the change/replan cycle (the queue reaches its working size)
    planner.set_blocked((20, 30), true).unwrap();
    planner.compute().unwrap();
    planner.set_blocked((20, 30), false).unwrap();
    planner.compute().unwrap();
    let (n, ()) = allocations(|| {
        planner.move_start((2, 2)).unwrap();
        planner.set_blocked((20, 31), true).unwrap();
        assert!(planner.compute().is_some());
        planner.set_blocked((20, 31), false).unwrap();
        assert!(planner.compute().is_some());
    });
    assert_eq!(n, 0, "D* Lite re-planning allocated {n} times");
    // The first snapshot brings the copy's queue to the source's size; later snapshots
    // of the same planner reuse it.
    snapshot.clone_from(&planner);
    planner.set_blocked((20, 31), true).unwrap();
    planner.compute().unwrap();
    let (n, ()) = allocations(|| snapshot.clone_from(&planner));
    assert_eq!(n, 0, "DStarLite::clone_from allocated {n} times");
    assert_eq!(snapshot.start(), planner.start());
}

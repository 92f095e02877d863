//! The arm planner's balanced trees on Fetch in MotionBenchMaker's cage scenes: the goal
//! states put the arm between the cage's front bars, where most steps of the goal tree are
//! blocked at their first probe, while the start tree grows freely outside. Letting the
//! tree with fewer nodes extend next (`MotionOptions::search_balanced`) spends the
//! iterations on the pocketed tree: the five cage queries solve with far fewer checked
//! states than with the two trees alternating.

use moma::motion::{MotionOptions, MotionProblem, plan_motion};
use moma::multibody::RootJoint;
use std::time::Duration;

mod fetch_common;
use fetch_common::{FetchQueries, PreparedQuery, fetch_geometry};

#[test]
fn balanced_trees_solve_the_cage_with_fewer_checked_states() {
    let (model, gm) = fetch_geometry(RootJoint::Fixed);
    let queries = FetchQueries::load();
    let group = queries.group(&model);
    // Search states over the five queries at seed 0 when the default was chosen:
    // alternating 328,437, balanced 116,977 (2.8 ×; per query 1.2–6.9 ×). The bound
    // below (1.5 ×) leaves room for other seeded paths.
    let (mut alternating, mut balanced) = (0u64, 0u64);
    for k in 0..5 {
        let name = format!("cage-Front-Cube1-{k}");
        let PreparedQuery {
            scene,
            start,
            goal,
            geometry,
        } = queries.prepare(&model, &gm, &group, &name);
        let problem = MotionProblem {
            model: &model,
            geometry: &geometry,
            scene: &scene,
            group: &group,
        };
        let run = |balance: bool| {
            let mut o = MotionOptions::new(group.dim());
            // Long enough for either run on a loaded machine; the figures compared are
            // checked states, which the seed fixes.
            o.time_limit = Duration::from_secs(60);
            o.search_balanced = balance;
            o.shortcut_attempts = 0;
            let out = plan_motion(&problem, &start, &goal, &o).unwrap();
            assert!(out.not_solved.is_none(), "{name}: {:?}", out.not_solved);
            out.phase_checks.search
        };
        let (a, b) = (run(false), run(true));
        eprintln!("{name}: alternating {a} search states, balanced {b}");
        alternating += a;
        balanced += b;
    }
    eprintln!("cage, seed 0: alternating {alternating} search states, balanced {balanced}");
    assert!(
        3 * balanced < 2 * alternating,
        "balanced {balanced} search states, alternating {alternating}"
    );
}

//! The arm planner's local samples on Fetch in MotionBenchMaker's bookshelf scenes: the
//! goal states lie between shelf boards, where almost every uniform sample's step from the
//! goal tree is blocked at once, so that tree hardly grows. Drawing a share of the samples
//! near the tree's own nodes (`MotionOptions::search_local_share`) lets it leave the
//! pocket: the same queries solve with far fewer checked states than with uniform samples
//! when the search's two trees alternate (`MotionOptions::search_balanced` off).

use moma::motion::{MotionOptions, MotionProblem, plan_motion};
use moma::multibody::RootJoint;
use std::time::Duration;

mod fetch_common;
use fetch_common::{FetchQueries, PreparedQuery, fetch_geometry};

#[test]
fn local_samples_let_the_goal_tree_leave_the_shelf() {
    let (model, gm) = fetch_geometry(RootJoint::Fixed);
    let queries = FetchQueries::load();
    let group = queries.group(&model);
    // (query, seed): checked states with uniform samples and with the default share of
    // local samples, measured when the default was chosen: 48,349 and 3,366; 76,483 and
    // 1,992 (without shortcutting). Since the nearest-node scan sums in vector lanes (its
    // last bits differ, and the seeded searches with them): 25,251 and 8,604; 11,086 and
    // 1,273. The ratio moves with the search's path at one seed; the bound below (2)
    // sits under the smaller one (2.9).
    for (name, seed) in [
        ("bookshelf_small-Front-Can1-1", 0),
        ("bookshelf_tall-Front-Can4-0", 0),
    ] {
        let PreparedQuery {
            scene,
            start,
            goal,
            geometry,
        } = queries.prepare(&model, &gm, &group, name);
        let problem = MotionProblem {
            model: &model,
            geometry: &geometry,
            scene: &scene,
            group: &group,
        };
        let run = |share: f64| {
            let mut o = MotionOptions::new(group.dim());
            // Long enough for either run on a loaded machine; the figures compared are
            // checked states, which the seed fixes.
            o.time_limit = Duration::from_secs(30);
            o.seed = seed;
            o.search_local_share = share;
            // The trees alternate, as when the default share was chosen: with the search's
            // balanced trees (the default since) the smaller tree gets the iterations, and
            // bookshelf_small-Front-Can1-1 at seed 0 then needs 2,419 checked states with
            // uniform samples and 4,563 with local ones.
            o.search_balanced = false;
            o.shortcut_attempts = 0;
            plan_motion(&problem, &start, &goal, &o).unwrap()
        };
        let local = run(MotionOptions::new(group.dim()).search_local_share);
        let uniform = run(0.0);
        eprintln!(
            "{name} seed {seed}: uniform {} checks (solved {}), local {} checks",
            uniform.checks,
            uniform.not_solved.is_none(),
            local.checks
        );
        assert!(local.not_solved.is_none(), "{name}: {:?}", local.not_solved);
        assert!(local.checks < 10_000, "{name}: {} checks", local.checks);
        assert!(
            uniform.not_solved.is_some() || uniform.checks > 2 * local.checks,
            "{name}: uniform samples {} checks, local {}",
            uniform.checks,
            local.checks
        );
    }
}

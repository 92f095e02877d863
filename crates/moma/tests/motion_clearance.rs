//! The planning group's state check (`ClearanceChecker::is_valid`, the probe of the
//! search) against its exact report (`distance_report`: every checked pair's signed
//! distance computed in full) on Fetch in MotionBenchMaker's cage and bookshelf scenes:
//! on states drawn in the group's box and along the segments from each query's start to
//! its goal (which end between the cage's bars and the shelf boards), a state passes
//! exactly when its closest pair is farther apart than the margin.

use moma::collision::GeometryModel;
use moma::motion::ClearanceChecker;
use moma::multibody::{Model, RootJoint};
use moma::planning::StateValidity;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

mod fetch_common;
use fetch_common::{FetchQueries, fetch_geometry, numbers};

fn fetch() -> (Model, GeometryModel) {
    fetch_geometry(RootJoint::Fixed)
}

#[test]
fn the_state_check_passes_exactly_the_states_clear_of_the_margin() {
    let (model, gm) = fetch();
    let queries = FetchQueries::load();
    let group = queries.group(&model);
    let dim = group.dim();
    let margin = 2e-3;
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let (mut passed, mut failed) = (0, 0);
    for name in ["cage-Front-Cube1-0", "bookshelf_small-Front-Can1-1"] {
        let query = queries.query(name);
        let scene = queries.scene(query);
        let start = numbers(&query["start"]);
        let goal = numbers(&query["goal_state"]);
        let mut checker =
            ClearanceChecker::new(&model, &gm, &scene, &group, &start, margin, &vec![1.0; dim])
                .unwrap();
        let (mut xa, mut xb) = (vec![0.0; dim], vec![0.0; dim]);
        group.extract(&start, &mut xa);
        group.extract(&goal, &mut xb);
        let mut states: Vec<Vec<f64>> = (0..=200)
            .map(|k| {
                let t = f64::from(k) / 200.0;
                xa.iter().zip(&xb).map(|(a, b)| a + t * (b - a)).collect()
            })
            .collect();
        for _ in 0..1000 {
            let x: Vec<f64> = (0..dim)
                .map(|i| rng.random_range(group.lower[i]..=group.upper[i]))
                .collect();
            states.push(x);
        }
        for x in &states {
            let valid = checker.is_valid(x);
            let closest = checker.distance_report(x).unwrap();
            assert_eq!(
                valid,
                closest.distance > margin,
                "{name}: state {x:?}: is_valid {valid}, closest pair {closest:?}"
            );
            if valid {
                passed += 1;
            } else {
                failed += 1;
            }
        }
    }
    // Both answers occur often, so the agreement is tested both ways.
    assert!(
        passed > 200 && failed > 200,
        "{passed} passed, {failed} failed"
    );
}

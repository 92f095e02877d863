//! Potential fields: the literal Euclidean-goal field gets stuck on the shipped trap map
//! and says so; the geodesic form has no local minima and reaches the goal.

use moma::planning::potential::{DescentEnd, GoalTerm, PotentialParams, descend, potential_field};
use moma::planning::{SearchGrid, load_map};
use rand::{Rng, SeedableRng};
use std::path::Path;

fn trap() -> SearchGrid {
    // The same map is shipped as scenarios/maps/potential_trap.map.
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/maps/potential_trap.map");
    SearchGrid::from_grid(&load_map(&p, None).unwrap().grid, true).unwrap()
}

#[test]
fn euclidean_field_is_trapped_by_the_u_obstacle() {
    let g = trap();
    let (start, goal) = ((16, 12), (34, 12));
    let f = potential_field(&g, goal, GoalTerm::Euclidean, &PotentialParams::default()).unwrap();
    let d = descend(&g, &f, start).unwrap();
    match d.end {
        DescentEnd::LocalMinimum {
            cell,
            distance_to_goal,
            ..
        } => {
            // Stuck inside the cup, in front of its bottom wall (x = 24, 25).
            assert!(
                (18..24).contains(&cell.0) && (6..18).contains(&cell.1),
                "{cell:?}"
            );
            assert!(distance_to_goal > 9.0);
        }
        other => panic!("expected a local minimum, got {other:?}"),
    }
    let report = d.report();
    assert!(
        report.contains("local minimum") && report.contains("cells from the goal"),
        "{report}"
    );
}

#[test]
fn geodesic_field_reaches_the_goal_from_the_trap() {
    let g = trap();
    let (start, goal) = ((16, 12), (34, 12));
    let f = potential_field(&g, goal, GoalTerm::Geodesic, &PotentialParams::default()).unwrap();
    let d = descend(&g, &f, start).unwrap();
    assert_eq!(d.end, DescentEnd::Reached, "{}", d.report());
    assert_eq!(*d.cells.last().unwrap(), goal);
    for w in d.cells.windows(2) {
        let (dx, dy) = (w[1].0 as i64 - w[0].0 as i64, w[1].1 as i64 - w[0].1 as i64);
        assert!(g.can_step(w[0].0 as i64, w[0].1 as i64, dx, dy));
        let (a, b) = (
            f.values[w[0].1 * f.width + w[0].0],
            f.values[w[1].1 * f.width + w[1].0],
        );
        assert!(b < a, "potential must strictly decrease");
    }
}

#[test]
fn geodesic_field_has_no_local_minimum_anywhere() {
    // Random maps, every free cell connected to the goal: no cell except the goal may be
    // a local minimum, for several weights and influence ranges.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
    for trial in 0..6 {
        let (w, h) = (48, 36);
        let obst: Vec<bool> = (0..w * h).map(|_| rng.random_bool(0.25)).collect();
        let g = SearchGrid::from_obstacles(&obst, w, h).unwrap();
        let goal = (0..w * h)
            .map(|i| (i % w, i / w))
            .find(|&(x, y)| g.is_free(x as i64, y as i64))
            .unwrap();
        let params = PotentialParams {
            goal_weight: [1.05, 2.0, 5.0][trial % 3],
            influence: [3.0, 10.0][trial % 2],
        };
        let f = potential_field(&g, goal, GoalTerm::Geodesic, &params).unwrap();
        let mut minima = 0;
        for y in 0..h {
            for x in 0..w {
                let v = f.values[y * w + x];
                if !v.is_finite() || (x, y) == goal {
                    continue;
                }
                let lower = (-1..=1i64)
                    .flat_map(|dy| (-1..=1i64).map(move |dx| (dx, dy)))
                    .any(|(dx, dy)| {
                        (dx, dy) != (0, 0)
                            && g.can_step(x as i64, y as i64, dx, dy)
                            && f.values[(y as i64 + dy) as usize * w + (x as i64 + dx) as usize] < v
                    });
                if !lower {
                    minima += 1;
                }
            }
        }
        assert_eq!(minima, 0, "trial {trial}");
    }
}

#[test]
fn bad_parameters_are_rejected() {
    let g = trap();
    let geo_w1 = PotentialParams {
        goal_weight: 1.0,
        influence: 5.0,
    };
    let e = potential_field(&g, (34, 12), GoalTerm::Geodesic, &geo_w1)
        .unwrap_err()
        .to_string();
    assert!(e.contains("w > 1"), "{e}");
    let nan = PotentialParams {
        goal_weight: f64::NAN,
        influence: 5.0,
    };
    assert!(potential_field(&g, (34, 12), GoalTerm::Euclidean, &nan).is_err());
    // A finite weight whose product with a goal distance overflows is named, not turned
    // into an infinite ("unreachable") potential.
    for term in [GoalTerm::Euclidean, GoalTerm::Geodesic] {
        let huge = PotentialParams {
            goal_weight: 1e308,
            influence: 5.0,
        };
        let e = potential_field(&g, (34, 12), term, &huge)
            .unwrap_err()
            .to_string();
        assert!(e.contains("goal weight") && e.contains("overflows"), "{e}");
    }
    assert!(
        potential_field(
            &g,
            (24, 12),
            GoalTerm::Euclidean,
            &PotentialParams::default()
        )
        .unwrap_err()
        .to_string()
        .contains("obstacle")
    );
    // A goal in a separate component: the geodesic descent reports unreachable.
    let mut obst = vec![false; 10 * 4];
    for y in 0..4 {
        obst[y * 10 + 5] = true;
    }
    let g = SearchGrid::from_obstacles(&obst, 10, 4).unwrap();
    let f = potential_field(&g, (8, 1), GoalTerm::Geodesic, &PotentialParams::default()).unwrap();
    assert_eq!(
        descend(&g, &f, (1, 1)).unwrap().end,
        DescentEnd::Unreachable
    );
}

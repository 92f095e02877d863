//! D* Lite: while the robot walks its path and cells near it become blocked or free, the
//! re-planned cost equals A* from scratch on the changed map.

use moma::planning::{self, SearchGrid, dstar_lite::DStarLite, load_map};
use rand::{Rng, SeedableRng};
use std::path::Path;

fn walk_and_check(map: &str, start: (usize, usize), goal: (usize, usize), seed: u64) -> usize {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/planning/movingai")
        .join(map);
    let grid = load_map(&path, None).unwrap().grid;
    let sg = SearchGrid::from_grid(&grid, true).unwrap();
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    let mut d = DStarLite::new(&sg, start, goal).unwrap();
    let first = d.compute().unwrap();
    let astar_first = planning::astar(&sg, start, goal).unwrap().unwrap().cost;
    assert!((first - astar_first).abs() < 1e-9);
    let mut checks = 0;
    for _step in 0..60 {
        let Some(p) = d.path() else { break };
        assert_eq!(p[0], d.start());
        if p.len() < 3 {
            break;
        }
        d.move_start(p[1]).unwrap();
        // Sense: block or free a few cells within 4 cells of the robot (never the robot's
        // own cell or the goal).
        let (rx, ry) = d.start();
        for _ in 0..3 {
            let x = (rx as i64 + rng.random_range(-4..=4)).clamp(0, grid.width as i64 - 1) as usize;
            let y =
                (ry as i64 + rng.random_range(-4..=4)).clamp(0, grid.height as i64 - 1) as usize;
            if (x, y) == (rx, ry) || (x, y) == goal {
                continue;
            }
            let block = rng.random_bool(0.7);
            d.set_blocked((x, y), block).unwrap();
        }
        // Also block the next cell of the current path now and then.
        if rng.random_bool(0.3) && p.len() > 3 && p[2] != goal {
            d.set_blocked(p[2], true).unwrap();
        }
        let c = d.compute();
        let a = planning::astar(d.grid(), d.start(), goal)
            .unwrap()
            .map(|p| p.cost);
        match (c, a) {
            (Some(c), Some(a)) => assert!((c - a).abs() < 1e-9, "D* Lite {c} vs A* {a}"),
            (None, None) => break,
            other => panic!("D* Lite and A* disagree on reachability: {other:?}"),
        }
        if let Some(p) = d.path() {
            let len: f64 = p
                .windows(2)
                .map(|w| {
                    if w[0].0 != w[1].0 && w[0].1 != w[1].1 {
                        std::f64::consts::SQRT_2
                    } else {
                        1.0
                    }
                })
                .sum();
            assert!((len - c.unwrap()).abs() < 1e-9);
            for w in p.windows(2) {
                let (dx, dy) = (w[1].0 as i64 - w[0].0 as i64, w[1].1 as i64 - w[0].1 as i64);
                assert!(d.grid().can_step(w[0].0 as i64, w[0].1 as i64, dx, dy));
            }
        }
        checks += 1;
    }
    checks
}

#[test]
fn dstar_lite_matches_astar_after_changes() {
    let mut total = 0;
    total += walk_and_check("den520d.map", (100, 163), (200, 200), 1);
    total += walk_and_check("arena.map", (3, 3), (45, 45), 2);
    total += walk_and_check("random512-10-0.map", (10, 10), (300, 280), 3);
    total += walk_and_check("Berlin_0_256.map", (38, 240), (200, 20), 4);
    assert!(total > 100, "only {total} re-plans checked");
}

#[test]
fn dstar_lite_unreachable_and_errors() {
    let mut obst = vec![false; 8 * 4];
    obst[4] = true;
    let sg = SearchGrid::from_obstacles(&obst, 8, 4).unwrap();
    let mut d = DStarLite::new(&sg, (0, 0), (7, 3)).unwrap();
    assert!(d.compute().is_some());
    for y in 0..4 {
        d.set_blocked((4, y), true).unwrap();
    }
    assert_eq!(d.compute(), None);
    assert!(d.path().is_none());
    d.set_blocked((4, 2), false).unwrap();
    assert_eq!(
        d.compute(),
        planning::astar(d.grid(), (0, 0), (7, 3))
            .unwrap()
            .map(|p| p.cost)
    );
    assert!(
        d.set_blocked((7, 3), true)
            .unwrap_err()
            .to_string()
            .contains("goal")
    );
    assert!(d.set_blocked((9, 3), true).is_err());
    assert!(
        DStarLite::new(&sg, (4, 0), (7, 3))
            .unwrap_err()
            .to_string()
            .contains("obstacle")
    );
}

#[test]
fn dstar_lite_snapshot_replans_like_the_original() {
    // A snapshot taken with `clone_from` (buffers reused) re-plans exactly like the
    // planner it was copied from, and the original is unaffected by the copy's changes.
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/planning/movingai/random512-10-0.map");
    let sg = SearchGrid::from_grid(&load_map(&path, None).unwrap().grid, true).unwrap();
    let (start, goal) = ((20, 20), (300, 200));
    let (start, goal) = (
        (0..60)
            .map(|d| (start.0 + d, start.1))
            .find(|&c| sg.is_free(c.0 as i64, c.1 as i64))
            .unwrap(),
        (0..60)
            .map(|d| (goal.0 + d, goal.1))
            .find(|&c| sg.is_free(c.0 as i64, c.1 as i64))
            .unwrap(),
    );
    let mut d = DStarLite::new(&sg, start, goal).unwrap();
    let before = d.compute().unwrap();
    let mut other = DStarLite::new(&sg, start, goal).unwrap();
    let ahead = d.path().unwrap()[3];
    for _ in 0..3 {
        other.clone_from(&d);
        other.set_blocked(ahead, true).unwrap();
        let c = other.compute().unwrap();
        let a = planning::astar(other.grid(), start, goal)
            .unwrap()
            .unwrap()
            .cost;
        assert_eq!(c, a);
        assert!(c >= before);
        assert!(!other.path().unwrap().contains(&ahead));
    }
    // The original never saw the change.
    assert!(d.grid().is_free(ahead.0 as i64, ahead.1 as i64));
    assert_eq!(d.compute().unwrap(), before);
}

/// Checks the planner's cost, reachability and path against A* from scratch on its grid.
fn check_against_astar(d: &DStarLite, c: Option<f64>, goal: (usize, usize), ctx: &str) {
    let a = planning::astar(d.grid(), d.start(), goal)
        .unwrap()
        .map(|p| p.cost);
    match (c, a) {
        // Same integer costs, same decoding: the lengths agree to the last bit.
        (Some(c), Some(a)) => assert_eq!(c, a, "{ctx}: D* Lite {c} vs A* {a}"),
        (None, None) => {}
        other => panic!("{ctx}: D* Lite and A* disagree on reachability: {other:?}"),
    }
    if let (Some(c), Some(p)) = (c, d.path()) {
        assert_eq!(p[0], d.start(), "{ctx}");
        assert_eq!(*p.last().unwrap(), goal, "{ctx}");
        let mut len = 0.0;
        for w in p.windows(2) {
            let (dx, dy) = (w[1].0 as i64 - w[0].0 as i64, w[1].1 as i64 - w[0].1 as i64);
            assert!(
                d.grid().can_step(w[0].0 as i64, w[0].1 as i64, dx, dy),
                "{ctx}: illegal step {w:?}"
            );
            len += if dx != 0 && dy != 0 {
                std::f64::consts::SQRT_2
            } else {
                1.0
            };
        }
        assert!(
            (len - c).abs() < 1e-9,
            "{ctx}: path length {len} vs cost {c}"
        );
    }
}

#[test]
fn dstar_lite_matches_astar_on_random_maps_and_changes() {
    // Seeded random maps (sizes 6..48, obstacle densities 0..40 %), random start and goal,
    // then a robot that walks its path while cells near it (and now and then anywhere)
    // become blocked or free, several changes per step, sometimes none; after every
    // re-plan the cost must equal A* from scratch on the changed map exactly.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(0x5eed_d57a);
    let mut replans = 0;
    for map in 0..300 {
        let (w, h) = (rng.random_range(6..48), rng.random_range(6..48));
        let density = rng.random_range(0.0..0.4);
        let obst: Vec<bool> = (0..w * h).map(|_| rng.random_bool(density)).collect();
        let sg = SearchGrid::from_obstacles(&obst, w, h).unwrap();
        let free: Vec<(usize, usize)> = (0..w * h)
            .filter(|&i| !obst[i])
            .map(|i| (i % w, i / w))
            .collect();
        if free.len() < 2 {
            continue;
        }
        let start = free[rng.random_range(0..free.len())];
        let goal = free[rng.random_range(0..free.len())];
        let mut d = DStarLite::new(&sg, start, goal).unwrap();
        let c = d.compute();
        check_against_astar(&d, c, goal, &format!("map {map}, first plan"));
        for step in 0..40 {
            // Move one cell along the path when there is one.
            if let Some(p) = d.path()
                && p.len() >= 2
                && rng.random_bool(0.8)
            {
                d.move_start(p[1]).unwrap();
            }
            let (rx, ry) = d.start();
            let n_changes = rng.random_range(0..4);
            for _ in 0..n_changes {
                let (x, y) = if rng.random_bool(0.8) {
                    let r = rng.random_range(1..=4i64);
                    (
                        (rx as i64 + rng.random_range(-r..=r)).clamp(0, w as i64 - 1) as usize,
                        (ry as i64 + rng.random_range(-r..=r)).clamp(0, h as i64 - 1) as usize,
                    )
                } else {
                    (rng.random_range(0..w), rng.random_range(0..h))
                };
                if (x, y) == (rx, ry) || (x, y) == goal {
                    continue;
                }
                d.set_blocked((x, y), rng.random_bool(0.6)).unwrap();
            }
            let c = d.compute();
            check_against_astar(&d, c, goal, &format!("map {map}, step {step}"));
            replans += 1;
        }
    }
    assert!(replans > 10_000, "only {replans} re-plans checked");
}

#[test]
fn dstar_lite_robot_cell_blocked_then_freed() {
    // A sensed obstacle on the robot's own cell leaves it without a legal step: no path,
    // reported without expanding the map; freeing the cell restores A*'s cost.
    let sg = SearchGrid::from_obstacles(&[false; 40 * 30], 40, 30).unwrap();
    let (start, goal) = ((2, 2), (37, 27));
    let mut d = DStarLite::new(&sg, start, goal).unwrap();
    let first = d.compute().unwrap();
    d.set_blocked(start, true).unwrap();
    assert_eq!(d.compute(), None);
    assert!(d.expanded() < 50, "{} expansions", d.expanded());
    assert!(d.path().is_none());
    d.set_blocked(start, false).unwrap();
    assert_eq!(d.compute(), Some(first));
    let a = planning::astar(d.grid(), start, goal)
        .unwrap()
        .unwrap()
        .cost;
    assert_eq!(first, a);
}

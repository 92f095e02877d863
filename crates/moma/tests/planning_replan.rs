//! D* Lite: while the robot walks its path and cells near it become blocked or free, the
//! re-planned cost equals A* from scratch on the changed map.

use moma::planning::{self, SearchGrid, dstar_lite::DStarLite, load_map};
use rand::{Rng, SeedableRng};
use std::path::Path;

fn walk_and_check(map: &str, start: (usize, usize), goal: (usize, usize), seed: u64) -> usize {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/planning/movingai").join(map);
    let grid = load_map(&path, None).unwrap().grid;
    let sg = SearchGrid::from_grid(&grid, true);
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
            let y = (ry as i64 + rng.random_range(-4..=4)).clamp(0, grid.height as i64 - 1) as usize;
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
        let a = planning::astar(d.grid(), d.start(), goal).unwrap().map(|p| p.cost);
        match (c, a) {
            (Some(c), Some(a)) => assert!((c - a).abs() < 1e-9, "D* Lite {c} vs A* {a}"),
            (None, None) => break,
            other => panic!("D* Lite and A* disagree on reachability: {other:?}"),
        }
        if let Some(p) = d.path() {
            let len: f64 = p.windows(2).map(|w| if w[0].0 != w[1].0 && w[0].1 != w[1].1 { std::f64::consts::SQRT_2 } else { 1.0 }).sum();
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
    assert_eq!(d.compute(), planning::astar(d.grid(), (0, 0), (7, 3)).unwrap().map(|p| p.cost));
    assert!(d.set_blocked((7, 3), true).unwrap_err().to_string().contains("goal"));
    assert!(d.set_blocked((9, 3), true).is_err());
    assert!(DStarLite::new(&sg, (4, 0), (7, 3)).unwrap_err().to_string().contains("obstacle"));
}

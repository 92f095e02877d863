//! A* reproduces the Moving AI optimal lengths (2-D and 3-D); the distance transform is
//! exact against brute force.

use moma::planning::{
    self, AstarWorkspace, MovingAiScenario, SearchGrid, astar::astar_cost, load_map,
};
use proptest::prelude::*;
use std::path::{Path, PathBuf};

fn data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/planning")
        .join(p)
}

const MAPS: [&str; 8] = [
    "arena",
    "den520d",
    "brc202d",
    "Berlin_0_256",
    "Berlin_0_1024",
    "maze512-1-0",
    "random512-10-0",
    "32room_000",
];

/// Runs every `every`-th problem of a map; returns (problems run, mismatches).
fn run_scen(name: &str, every: usize) -> (usize, usize) {
    let grid = load_map(&data(&format!("movingai/{name}.map")), None)
        .unwrap()
        .grid;
    let sg = SearchGrid::from_grid(&grid, true).unwrap();
    let scen = MovingAiScenario::load(&data(&format!("movingai/{name}.map.scen"))).unwrap();
    let mut ws = AstarWorkspace::new();
    let (mut n, mut bad) = (0, 0);
    for p in scen.problems.iter().step_by(every) {
        let (cost, _) = astar_cost(&sg, &mut ws, p.start, p.goal).unwrap();
        let cost = cost.expect("every benchmark problem is solvable");
        // The older files print 6 significant digits.
        if (cost - p.optimal).abs() > 1e-5 * p.optimal.max(1.0) {
            bad += 1;
            eprintln!("{name} #{}: found {cost}, optimal {}", p.index, p.optimal);
        }
        n += 1;
    }
    (n, bad)
}

#[test]
fn astar_matches_every_tenth_scen_problem() {
    let mut total = 0;
    for m in MAPS {
        let (n, bad) = run_scen(m, 10);
        assert_eq!(bad, 0, "{m}: {bad} mismatches");
        total += n;
    }
    assert_eq!(total, 2_388);
}

#[test]
#[ignore = "all 23,877 problems: about 45 s in release on two cores (CI tier 2)"]
fn astar_matches_all_scen_problems() {
    let mut total = 0;
    for m in MAPS {
        let (n, bad) = run_scen(m, 1);
        assert_eq!(bad, 0, "{m}: {bad} mismatches");
        total += n;
    }
    assert_eq!(total, 23_877);
}

#[test]
fn astar_path_is_valid_and_costs_its_length() {
    let grid = load_map(&data("movingai/den520d.map"), None).unwrap().grid;
    let sg = SearchGrid::from_grid(&grid, true).unwrap();
    let scen = MovingAiScenario::load(&data("movingai/den520d.map.scen")).unwrap();
    let p = &scen.problems[800];
    let path = planning::astar(&sg, p.start, p.goal).unwrap().unwrap();
    assert_eq!(path.cells[0], p.start);
    assert_eq!(*path.cells.last().unwrap(), p.goal);
    for w in path.cells.windows(2) {
        let (dx, dy) = (w[1].0 as i64 - w[0].0 as i64, w[1].1 as i64 - w[0].1 as i64);
        assert!(dx.abs() <= 1 && dy.abs() <= 1 && (dx, dy) != (0, 0));
        assert!(
            sg.can_step(w[0].0 as i64, w[0].1 as i64, dx, dy),
            "illegal step {w:?}"
        );
    }
    assert!((path.length() - path.cost).abs() < 1e-9);
    assert!((path.cost - p.optimal).abs() < 1e-5 * p.optimal);
}

#[test]
fn unreachable_and_invalid_queries() {
    // A wall splits the map: unreachable goal is a clean None.
    let mut obst = vec![false; 10 * 5];
    for y in 0..5 {
        obst[y * 10 + 5] = true;
    }
    let sg = SearchGrid::from_obstacles(&obst, 10, 5).unwrap();
    assert!(planning::astar(&sg, (0, 0), (9, 4)).unwrap().is_none());
    assert!(planning::astar(&sg, (0, 0), (4, 4)).unwrap().is_some());
    let e = planning::astar(&sg, (0, 0), (5, 2))
        .unwrap_err()
        .to_string();
    assert!(e.contains("goal") && e.contains("obstacle"), "{e}");
    let e = planning::astar(&sg, (10, 0), (1, 1))
        .unwrap_err()
        .to_string();
    assert!(e.contains("start") && e.contains("outside"), "{e}");
    // Corner cutting is not allowed: two diagonal blocks close the gap.
    let mut obst = vec![false; 3 * 3];
    obst[1] = true; // (1, 0)
    obst[3] = true; // (0, 1)
    let sg = SearchGrid::from_obstacles(&obst, 3, 3).unwrap();
    assert!(planning::astar(&sg, (0, 0), (2, 2)).unwrap().is_none());
}

/// Checks one 3-D problem: the optimal length (1e-5 relative, the files print 8
/// decimals), start to goal, unit moves.
fn check_3d(p: &planning::Scen3Problem, r: Option<planning::Path3>) -> usize {
    let r = r.expect("every benchmark problem is solvable");
    assert!(
        (r.cost - p.optimal).abs() <= 1e-5 * p.optimal,
        "problem {}: {} vs {}",
        p.index,
        r.cost,
        p.optimal
    );
    assert_eq!((r.voxels[0], *r.voxels.last().unwrap()), (p.start, p.goal));
    for w in r.voxels.windows(2) {
        let d = [
            w[1].0 as i64 - w[0].0 as i64,
            w[1].1 as i64 - w[0].1 as i64,
            w[1].2 as i64 - w[0].2 as i64,
        ];
        assert!(d.iter().all(|v| v.abs() <= 1) && d != [0, 0, 0]);
    }
    r.expanded
}

#[test]
fn astar3d_matches_3dscen_subsample() {
    let g = planning::load_3dmap(&data("movingai/3d/A1.3dmap")).unwrap();
    let probs = planning::load_3dscen(&data("movingai/3d/A1.every10.3dscen")).unwrap();
    let mut ws = planning::Astar3Workspace::new();
    let mut n = 0;
    // The shorter problems of the subsample (long 3-D problems expand millions of
    // voxels; the full subsample is the ignored test below).
    for p in probs.iter().filter(|p| p.optimal <= 100.0) {
        check_3d(
            p,
            planning::astar3d_with(&g, &mut ws, p.start, p.goal).unwrap(),
        );
        n += 1;
    }
    assert_eq!(n, 339);
}

#[test]
#[ignore = "1,000 3-D problems, 434 million expansions: about 65 s in release on two cores (CI tier 2)"]
fn astar3d_matches_full_3dscen_subsample() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let g = planning::load_3dmap(&data("movingai/3d/A1.3dmap")).unwrap();
    let mut probs = planning::load_3dscen(&data("movingai/3d/A1.every10.3dscen")).unwrap();
    assert_eq!(probs.len(), 1_000);
    // longest first on two threads, each with its own workspace, so neither ends on a
    // long problem while the other idles
    probs.sort_by(|a, b| b.optimal.total_cmp(&a.optimal));
    let next = AtomicUsize::new(0);
    let t0 = std::time::Instant::now();
    let expanded: usize = std::thread::scope(|sc| {
        let workers: Vec<_> = (0..2)
            .map(|_| {
                sc.spawn(|| {
                    let mut ws = planning::Astar3Workspace::new();
                    let mut expanded = 0;
                    loop {
                        let i = next.fetch_add(1, Ordering::Relaxed);
                        let Some(p) = probs.get(i) else {
                            break expanded;
                        };
                        let r = planning::astar3d_with(&g, &mut ws, p.start, p.goal).unwrap();
                        expanded += check_3d(p, r);
                    }
                })
            })
            .collect();
        workers.into_iter().map(|w| w.join().unwrap()).sum()
    });
    eprintln!(
        "1,000 problems, {expanded} expansions, {:.1} s",
        t0.elapsed().as_secs_f64()
    );
}

#[test]
fn edt_exact_on_real_map_window() {
    let grid = load_map(&data("movingai/den520d.map"), None).unwrap().grid;
    // A 64 x 48 window keeps the brute force cheap.
    let (w, h) = (64, 48);
    let mut obst = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            obst[y * w + x] = grid.cells[(y + 100) * grid.width + x + 80] >= 100;
        }
    }
    let fast = planning::distance_transform(&obst, w, h);
    let slow = planning::edt::distance_transform_brute_force(&obst, w, h);
    assert_eq!(fast, slow);
}

#[test]
fn edt_without_obstacles_is_infinite() {
    let d = planning::distance_transform(&[false; 12], 4, 3);
    assert!(d.iter().all(|v| v.is_infinite()));
    let mut o = [false; 12];
    o[11] = true;
    let d = planning::distance_transform(&o, 4, 3);
    assert_eq!(d[0], (9.0f32 + 4.0).sqrt());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn edt_matches_brute_force(w in 1usize..40, h in 1usize..40, seed in any::<u64>(), density in 0.0f64..0.6) {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let obst: Vec<bool> = (0..w * h).map(|_| rng.random_bool(density)).collect();
        prop_assert_eq!(planning::distance_transform(&obst, w, h), planning::edt::distance_transform_brute_force(&obst, w, h));
    }
}

//! Planning benchmarks, measured side by side in one run:
//!
//! * A* per query vs the `pathfinding` crate's `astar` with the same move model
//!   (8-connected, octile costs, no corner cutting) on four Moving AI maps: first a
//!   printed table of per-query medians (queries interleaved moma / pathfinding), then
//!   criterion groups over a fixed problem subset;
//! * the exact Euclidean distance transform on nav2's `100by100_20` map (4 M cells);
//! * D* Lite re-planning after a local change near the robot vs A* from scratch on the
//!   changed map, over a set of changes per map (see [`replan_positions`]): a printed table
//!   of per-change medians, then criterion groups over the whole set.
//!
//! * re-planning on ROS maps after a disk obstacle appears on the path ahead of the robot
//!   (nav2 `tb3_sandbox`, turtlebot3, nav2 `warehouse`): D* Lite `set_blocked` of every
//!   C-space cell of the disk + `compute` + `path`, then, timed separately, smoothing the
//!   new path ([`planning::curvature::smooth_diff_drive`]) and timing it
//!   ([`planning::trajectory::time_parameterize_curve`]): a printed table of medians and
//!   criterion groups;
//! * the default mission's own re-plan (`scenarios/mission.toml`, nav2's depot map): the
//!   mission is run once to find the robot's cell, pose and speed when the crate appears;
//!   then, on a copy of the mission's first D* Lite planner, the same `move_start`,
//!   `set_blocked` of the crate's C-space cells, `compute` and `path` (checked to give the
//!   mission's re-planned cells and expansion count), the refresh of the distance
//!   transform, and the smoothing and timing of the new path by the function the mission
//!   calls ([`planning::curve_timing::time_cells_curved`], checked to give the mission's
//!   path) are timed separately ([`MissionReplan`]).
//!
//! * `moma plan`'s pipeline ([`planning::pipeline::plan`]) against the primitives it
//!   calls composed by hand (`MOMA_BENCH_PIPELINE_ONLY=1` runs this group alone).
//!
//! Run: `cargo bench -p moma --bench planning` (add `RUSTFLAGS="-C target-cpu=native"`
//! for a native build).

use criterion::{Criterion, criterion_group};
use moma::planning::curvature::{SmoothOptions, smooth_diff_drive};
use moma::planning::curve_timing::{CurvatureTiming, TimedCurve, time_cells_curved};
use moma::planning::trajectory::{DiffDriveLimits, TipOverAcceleration, time_parameterize_curve};
use moma::planning::{
    self, AstarWorkspace, MovingAiScenario, OccupancyGrid, SearchGrid, astar_with, costmap,
    dstar_lite::DStarLite, load_map,
};
use pathfinding::num_traits::Zero;
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

fn data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/planning")
        .join(p)
}

const MAPS: [&str; 4] = ["den520d", "Berlin_0_256", "random512-10-0", "maze512-1-0"];

/// f64 cost with a total order, as the crate's `astar` needs `Ord + Zero`.
#[derive(Clone, Copy, PartialEq, Debug)]
struct Cost(f64);
impl Eq for Cost {}
impl Ord for Cost {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        self.0.total_cmp(&o.0)
    }
}
impl PartialOrd for Cost {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl std::ops::Add for Cost {
    type Output = Cost;
    fn add(self, o: Cost) -> Cost {
        Cost(self.0 + o.0)
    }
}
impl Zero for Cost {
    fn zero() -> Self {
        Cost(0.0)
    }
    fn is_zero(&self) -> bool {
        self.0 == 0.0
    }
}

/// (start, goal, optimal length).
type Problem = ((usize, usize), (usize, usize), f64);

struct MapCase {
    name: &'static str,
    grid: SearchGrid,
    free: Vec<bool>,
    w: i32,
    h: i32,
    problems: Vec<Problem>,
}

fn load_case(name: &'static str) -> MapCase {
    let g = load_map(&data(&format!("movingai/{name}.map")), None)
        .unwrap()
        .grid;
    let scen = MovingAiScenario::load(&data(&format!("movingai/{name}.map.scen"))).unwrap();
    // About 100 problems spread over all buckets (lengths).
    let step = (scen.problems.len() / 100).max(1);
    MapCase {
        name,
        grid: SearchGrid::from_grid(&g, true).unwrap(),
        free: g.cells.iter().map(|&v| v == 0).collect(),
        w: g.width as i32,
        h: g.height as i32,
        problems: scen
            .problems
            .iter()
            .step_by(step)
            .map(|p| (p.start, p.goal, p.optimal))
            .collect(),
    }
}

/// The `pathfinding` crate's A* with the same move model (no allocation in successors).
fn crate_astar(c: &MapCase, s: (usize, usize), t: (usize, usize)) -> Option<f64> {
    let (w, h) = (c.w, c.h);
    let free = |x: i32, y: i32| x >= 0 && y >= 0 && x < w && y < h && c.free[(y * w + x) as usize];
    let goal = (t.0 as i32, t.1 as i32);
    pathfinding::directed::astar::astar(
        &(s.0 as i32, s.1 as i32),
        |&(x, y)| {
            let mut out = [None; 8];
            let (e, wv, n, so) = (
                free(x + 1, y),
                free(x - 1, y),
                free(x, y + 1),
                free(x, y - 1),
            );
            if e {
                out[0] = Some(((x + 1, y), Cost(1.0)));
            }
            if wv {
                out[1] = Some(((x - 1, y), Cost(1.0)));
            }
            if n {
                out[2] = Some(((x, y + 1), Cost(1.0)));
            }
            if so {
                out[3] = Some(((x, y - 1), Cost(1.0)));
            }
            let d = Cost(std::f64::consts::SQRT_2);
            if e && n && free(x + 1, y + 1) {
                out[4] = Some(((x + 1, y + 1), d));
            }
            if wv && n && free(x - 1, y + 1) {
                out[5] = Some(((x - 1, y + 1), d));
            }
            if e && so && free(x + 1, y - 1) {
                out[6] = Some(((x + 1, y - 1), d));
            }
            if wv && so && free(x - 1, y - 1) {
                out[7] = Some(((x - 1, y - 1), d));
            }
            out.into_iter().flatten()
        },
        |&(x, y)| Cost(planning::octile((goal.0 - x) as i64, (goal.1 - y) as i64)),
        |&p| p == goal,
    )
    .map(|(_, c)| c.0)
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Per-query medians, moma and the crate interleaved query by query.
fn per_query_table(cases: &[MapCase]) {
    println!("\nA* per query (median over the subset; moma and pathfinding interleaved)");
    println!("| map | problems | moma median | pathfinding median | ratio | mismatches |");
    println!("| --- | --- | --- | --- | --- | --- |");
    let mut ws = AstarWorkspace::new();
    for c in cases {
        let (mut tm, mut tp, mut bad) = (Vec::new(), Vec::new(), 0);
        for &(s, t, opt) in &c.problems {
            // Warm both once, then time each three times and keep the fastest (noise).
            let mut best_m = f64::INFINITY;
            let mut best_p = f64::INFINITY;
            let mut cm = 0.0;
            let mut cp = 0.0;
            for _ in 0..3 {
                let t0 = Instant::now();
                let r = astar_with(&c.grid, &mut ws, s, t).unwrap().unwrap();
                best_m = best_m.min(t0.elapsed().as_secs_f64());
                cm = black_box(r).cost;
                let t0 = Instant::now();
                cp = black_box(crate_astar(c, s, t).unwrap());
                best_p = best_p.min(t0.elapsed().as_secs_f64());
            }
            if (cm - opt).abs() > 1e-5 * opt.max(1.0) || (cp - opt).abs() > 1e-5 * opt.max(1.0) {
                bad += 1;
            }
            tm.push(best_m);
            tp.push(best_p);
        }
        let (mm, mp) = (median(&mut tm), median(&mut tp));
        println!(
            "| {} | {} | {:.3} ms | {:.3} ms | {:.2}x | {} |",
            c.name,
            c.problems.len(),
            mm * 1e3,
            mp * 1e3,
            mp / mm,
            bad
        );
    }
    println!();
}

fn bench_astar(cr: &mut Criterion, cases: &[MapCase]) {
    let mut g = cr.benchmark_group("astar");
    g.sample_size(10)
        .measurement_time(std::time::Duration::from_secs(4));
    for c in cases {
        // A fixed subset of 20 problems per iteration.
        let sub: Vec<_> = c
            .problems
            .iter()
            .step_by((c.problems.len() / 20).max(1))
            .take(20)
            .copied()
            .collect();
        let mut ws = AstarWorkspace::new();
        g.bench_function(format!("{}/moma_20_queries", c.name), |b| {
            b.iter(|| {
                for &(s, t, _) in &sub {
                    black_box(astar_with(&c.grid, &mut ws, s, t).unwrap());
                }
            })
        });
        g.bench_function(format!("{}/pathfinding_20_queries", c.name), |b| {
            b.iter(|| {
                for &(s, t, _) in &sub {
                    black_box(crate_astar(c, s, t));
                }
            })
        });
    }
    g.finish();
}

fn bench_edt(cr: &mut Criterion) {
    let m = load_map(&data("rosmaps/nav2/100by100_20_png.yaml"), None).unwrap();
    let g = m.grid;
    let obst = g.obstacle_mask(100, false);
    let mut ws = planning::EdtWorkspace::new();
    let mut out = Vec::new();
    let mut grp = cr.benchmark_group("edt");
    grp.sample_size(20);
    grp.throughput(criterion::Throughput::Elements((g.width * g.height) as u64));
    grp.bench_function("100by100_20 (2000x2000)", |b| {
        b.iter(|| {
            planning::distance_transform_into(
                black_box(&obst),
                g.width,
                g.height,
                &mut ws,
                &mut out,
            )
        })
    });
    grp.finish();
}

/// Kind of a local change near the robot.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum ChangeKind {
    /// A cell of the robot's current path, k cells ahead, becomes blocked.
    BlockOnPath(usize),
    /// The free cell beside the path (not on it) nearest to the robot becomes blocked.
    BlockBeside,
    /// The blocked cell nearest to the robot within 2 cells of its next 6 path cells
    /// becomes free.
    Free,
}

/// One robot position: the planner snapshot (after driving and re-planning) and the
/// changes tried from it, each on a fresh copy of the snapshot.
struct ReplanPosition {
    planner: DStarLite,
    goal: (usize, usize),
    changes: Vec<(ChangeKind, (usize, usize), bool)>,
    /// The changed grid for each change (A* from scratch runs on it).
    changed: Vec<SearchGrid>,
    /// Whether the goal stays reachable after each change.
    reachable: Vec<bool>,
}

/// The change set of a map: `problems` problems of the scenario file spread over the
/// lengths ≥ 64 (always including the longest); from each, two robot positions (after
/// driving 10 cells and after driving a third of the path); at each position five local
/// changes: block the path cell 2, 5 and 9 ahead, block the free cell beside the path
/// nearest to the robot, free the nearest blocked cell next to the path ahead.
fn replan_positions(name: &str, problems: usize) -> Vec<ReplanPosition> {
    let g = load_map(&data(&format!("movingai/{name}.map")), None)
        .unwrap()
        .grid;
    let sg = SearchGrid::from_grid(&g, true).unwrap();
    let scen = MovingAiScenario::load(&data(&format!("movingai/{name}.map.scen"))).unwrap();
    let mut long: Vec<_> = scen.problems.iter().filter(|p| p.optimal >= 64.0).collect();
    long.sort_by(|a, b| a.optimal.total_cmp(&b.optimal));
    let m = long.len();
    let picked: Vec<_> = (0..problems)
        .map(|i| long[(i * (m - 1)) / (problems - 1).max(1)])
        .collect();
    let mut out = Vec::new();
    for p in picked {
        let mut d = DStarLite::new(&sg, p.start, p.goal).unwrap();
        d.compute().unwrap();
        let n_path = d.path().unwrap().len();
        let mut driven = 0;
        for target in [10, n_path / 3] {
            while driven < target {
                let next = d.path().unwrap()[1];
                d.move_start(next).unwrap();
                d.compute().unwrap();
                driven += 1;
            }
            let path = d.path().unwrap();
            if path.len() < 12 {
                continue;
            }
            let grid = d.grid();
            let mut changes = Vec::new();
            for k in [2, 5, 9] {
                changes.push((ChangeKind::BlockOnPath(k), path[k], true));
            }
            let near = |c: (usize, usize)| {
                let (rx, ry) = (path[0].0 as i64, path[0].1 as i64);
                (c.0 as i64 - rx).abs().max((c.1 as i64 - ry).abs())
            };
            // Cells around the next path cells, nearest to the robot first.
            let mut around = Vec::new();
            for &c in &path[1..=6] {
                for dy in -2i64..=2 {
                    for dx in -2i64..=2 {
                        let (x, y) = (c.0 as i64 + dx, c.1 as i64 + dy);
                        if x >= 0
                            && y >= 0
                            && (x as usize) < grid.width()
                            && (y as usize) < grid.height()
                        {
                            around.push(((x as usize, y as usize), dx.abs().max(dy.abs())));
                        }
                    }
                }
            }
            around.sort_by_key(|&(c, r)| (near(c), r, c));
            if let Some(&(c, _)) = around.iter().find(|&&(c, r)| {
                r == 1 && grid.is_free(c.0 as i64, c.1 as i64) && !path.contains(&c) && c != p.goal
            }) {
                changes.push((ChangeKind::BlockBeside, c, true));
            }
            if let Some(&(c, _)) = around
                .iter()
                .find(|&&(c, _)| !grid.is_free(c.0 as i64, c.1 as i64))
            {
                changes.push((ChangeKind::Free, c, false));
            }
            let changed: Vec<SearchGrid> = changes
                .iter()
                .map(|&(_, c, blocked)| {
                    let mut g2 = grid.clone();
                    g2.set_free(c.0, c.1, !blocked);
                    g2
                })
                .collect();
            let reachable = changed
                .iter()
                .map(|g2| planning::astar(g2, path[0], p.goal).unwrap().is_some())
                .collect();
            out.push(ReplanPosition {
                planner: d.clone(),
                goal: p.goal,
                changes,
                changed,
                reachable,
            });
        }
    }
    out
}

/// Per-change timings on one map: D* Lite re-plan (`set_blocked` + `compute` on a fresh
/// copy of the snapshot, the copy untimed) and A* from scratch on the changed map, each
/// the fastest of `reps` runs, interleaved change by change; the costs are asserted equal.
/// Returns (kind, D* Lite s, A* s, D* Lite expansions, goal reachable) per change.
fn replan_timings(
    positions: &[ReplanPosition],
    reps: usize,
) -> Vec<(ChangeKind, f64, f64, usize, bool, usize)> {
    let mut out = Vec::new();
    let mut ws = AstarWorkspace::new();
    let mut dd = positions[0].planner.clone();
    for pos in positions {
        let robot = pos.planner.start();
        for (&(kind, cell, blocked), changed) in pos.changes.iter().zip(&pos.changed) {
            let (mut td, mut ta) = (f64::INFINITY, f64::INFINITY);
            let mut exp = 0;
            let mut exp_a = 0;
            let mut reach = false;
            for _ in 0..reps {
                dd.clone_from(&pos.planner);
                let t0 = Instant::now();
                dd.set_blocked(cell, blocked).unwrap();
                let cd = black_box(dd.compute());
                td = td.min(t0.elapsed().as_secs_f64());
                exp = dd.expanded();
                let t0 = Instant::now();
                let (ca, ea) = black_box(
                    planning::astar::astar_cost(changed, &mut ws, robot, pos.goal).unwrap(),
                );
                exp_a = ea;
                ta = ta.min(t0.elapsed().as_secs_f64());
                match (cd, ca) {
                    (Some(a), Some(b)) => assert!(
                        (a - b).abs() <= 1e-9 * b.max(1.0),
                        "{kind:?} at {cell:?}: D* Lite {a} vs A* {b}"
                    ),
                    (None, None) => {}
                    other => panic!("{kind:?} at {cell:?}: reachability differs {other:?}"),
                }
                reach = ca.is_some();
            }
            out.push((kind, td, ta, exp, reach, exp_a));
        }
    }
    out
}

/// The printed re-planning table (medians over the change set).
fn replan_table(sets: &[(&str, Vec<ReplanPosition>)]) {
    println!("\nD* Lite re-plan vs A* from scratch, per change (fastest of 5 runs each)");
    println!(
        "| map | changes (reachable / cut off) | D* Lite median | A* median | ratio of medians | median per-change ratio | min ratio | on-path blocks: median ratio | D* Lite median expansions |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for (name, positions) in sets {
        let t = replan_timings(positions, 5);
        if std::env::var_os("MOMA_BENCH_REPLAN_VERBOSE").is_some() {
            for r in &t {
                println!(
                    "  {name} {:?}: D* Lite {:.1} µs ({} expansions, {:.0} ns each), A* {:.1} µs ({} expansions, {:.0} ns each), {:.1}x",
                    r.0,
                    r.1 * 1e6,
                    r.3,
                    r.1 * 1e9 / r.3.max(1) as f64,
                    r.2 * 1e6,
                    r.5,
                    r.2 * 1e9 / r.5.max(1) as f64,
                    r.2 / r.1
                );
            }
        }
        let reach: Vec<_> = t.iter().filter(|r| r.4).collect();
        let cut = t.len() - reach.len();
        let mut d: Vec<f64> = reach.iter().map(|r| r.1).collect();
        let mut a: Vec<f64> = reach.iter().map(|r| r.2).collect();
        let mut ratio: Vec<f64> = reach.iter().map(|r| r.2 / r.1).collect();
        let mut on_path: Vec<f64> = reach
            .iter()
            .filter(|r| matches!(r.0, ChangeKind::BlockOnPath(_)))
            .map(|r| r.2 / r.1)
            .collect();
        let mut exp: Vec<f64> = reach.iter().map(|r| r.3 as f64).collect();
        let min_ratio = ratio.iter().copied().fold(f64::INFINITY, f64::min);
        let fmt = |s: f64| {
            if s < 1e-3 {
                format!("{:.1} µs", s * 1e6)
            } else {
                format!("{:.3} ms", s * 1e3)
            }
        };
        let on_path_med = if on_path.is_empty() {
            "–".to_string()
        } else {
            format!("{:.1}x ({})", median(&mut on_path), on_path.len())
        };
        if reach.is_empty() {
            println!("| {name} | 0 / {cut} | – | – | – | – | – | – | – |");
        } else {
            let (md, ma) = (median(&mut d), median(&mut a));
            println!(
                "| {name} | {} / {cut} | {} | {} | {:.1}x | {:.1}x | {:.2}x | {on_path_med} | {:.0} |",
                reach.len(),
                fmt(md),
                fmt(ma),
                ma / md,
                median(&mut ratio),
                min_ratio,
                median(&mut exp)
            );
        }
        if cut > 0 {
            let cut_rows: Vec<_> = t.iter().filter(|r| !r.4).collect();
            let mut d: Vec<f64> = cut_rows.iter().map(|r| r.1).collect();
            let mut a: Vec<f64> = cut_rows.iter().map(|r| r.2).collect();
            let (md, ma) = (median(&mut d), median(&mut a));
            println!(
                "|   {name}, goal cut off | {cut} | {} | {} | {:.2}x | | | | |",
                fmt(md),
                fmt(ma),
                ma / md
            );
        }
    }
    println!();
}

fn bench_dstar(cr: &mut Criterion, sets: &[(&str, Vec<ReplanPosition>)]) {
    let mut grp = cr.benchmark_group("replan");
    grp.sample_size(10)
        .measurement_time(std::time::Duration::from_secs(4));
    for (name, positions) in sets {
        // One iteration = every change of the set whose goal stays reachable (the copy of
        // the snapshot before each change untimed).
        let mut dd = positions[0].planner.clone();
        grp.bench_function(format!("{name}/dstar_lite_all_changes"), |b| {
            b.iter_custom(|iters| {
                let mut total = std::time::Duration::ZERO;
                for _ in 0..iters {
                    for pos in positions {
                        for (&(_, cell, blocked), &ok) in pos.changes.iter().zip(&pos.reachable) {
                            if !ok {
                                continue;
                            }
                            dd.clone_from(&pos.planner);
                            let t0 = Instant::now();
                            dd.set_blocked(cell, blocked).unwrap();
                            black_box(dd.compute());
                            total += t0.elapsed();
                        }
                    }
                }
                total
            })
        });
        let mut ws = AstarWorkspace::new();
        grp.bench_function(format!("{name}/astar_all_changes"), |b| {
            b.iter(|| {
                for pos in positions {
                    let robot = pos.planner.start();
                    for (changed, _) in pos.changed.iter().zip(&pos.reachable).filter(|c| *c.1) {
                        black_box(
                            planning::astar::astar_cost(changed, &mut ws, robot, pos.goal).unwrap(),
                        );
                    }
                }
            })
        });
    }
    grp.finish();
}

/// A disk-obstacle re-plan case on a ROS map: the planner after driving part of the way,
/// the C-space cells of the disk that appears ahead, and what smoothing needs.
struct DiskCase {
    name: String,
    map: OccupancyGrid,
    planner: DStarLite,
    disk: Vec<(usize, usize)>,
    goal: [f64; 3],
    opts: SmoothOptions,
}

/// Per map: robot radius (m), obstacle radius (m), κ_max, start and goal poses.
type DiskMap = (&'static str, f64, f64, f64, [f64; 3], [f64; 3]);

const DISK_MAPS: [DiskMap; 3] = [
    (
        "nav2/tb3_sandbox.yaml",
        0.12,
        0.15,
        4.0,
        [-2.0, -0.5, 0.0],
        [2.0, 0.55, std::f64::consts::FRAC_PI_2],
    ),
    (
        "turtlebot3/map.yaml",
        0.12,
        0.15,
        4.0,
        [-1.6, 1.6, -0.3],
        [1.55, -1.6, 0.0],
    ),
    (
        "nav2/warehouse_png.yaml",
        0.3,
        0.4,
        1.5,
        [-5.5, -20.0, std::f64::consts::FRAC_PI_2],
        [11.0, 7.5, 0.0],
    ),
];

/// Cases: on each map, the robot drives 20 %, 40 % and 60 % of its path, then a disk
/// (obstacle radius + robot radius in the C-space) appears centred on the path cell 1 m
/// ahead (the goal cell and the robot's cell are never blocked).
fn disk_cases() -> Vec<DiskCase> {
    let mut out = Vec::new();
    for &(file, r_robot, r_obs, kmax, start, goal) in &DISK_MAPS {
        let m = load_map(&data(&format!("rosmaps/{file}")), None)
            .unwrap()
            .grid;
        let obst = m.obstacle_mask(100, true);
        let mask = costmap::inflate(&obst, m.width, m.height, r_robot / m.resolution).unwrap();
        let cs = SearchGrid::from_obstacles(&mask, m.width, m.height).unwrap();
        let sc = m.world_to_cell("start", start[0], start[1]).unwrap();
        let gc = m.world_to_cell("goal", goal[0], goal[1]).unwrap();
        let mut d = DStarLite::new(&cs, sc, gc).unwrap();
        d.compute().expect("goal reachable");
        let path = d.path().unwrap();
        let ahead = (1.0 / m.resolution).round() as usize;
        let rc = (r_obs + r_robot) / m.resolution;
        for frac in [0.2, 0.4, 0.6] {
            let mut p = d.clone();
            let k = (path.len() as f64 * frac) as usize;
            p.move_start(path[k]).unwrap();
            let Some(c) = path.get(k + ahead) else {
                continue;
            };
            let mut disk = Vec::new();
            let ri = rc.ceil() as i64;
            for dy in -ri..=ri {
                for dx in -ri..=ri {
                    let (x, y) = (c.0 as i64 + dx, c.1 as i64 + dy);
                    if ((dx * dx + dy * dy) as f64) <= rc * rc
                        && x >= 0
                        && y >= 0
                        && (x as usize) < m.width
                        && (y as usize) < m.height
                        && (x as usize, y as usize) != gc
                        && (x as usize, y as usize) != path[k]
                    {
                        disk.push((x as usize, y as usize));
                    }
                }
            }
            out.push(DiskCase {
                name: format!(
                    "{}@{:.0}%",
                    file.split('/').next_back().unwrap(),
                    frac * 100.0
                ),
                map: m.clone(),
                planner: p,
                disk,
                goal,
                opts: SmoothOptions::new(kmax),
            });
        }
    }
    out
}

/// The re-plan: block the disk, compute, extract the path.
fn disk_replan(p: &mut DStarLite, disk: &[(usize, usize)]) -> Option<Vec<(usize, usize)>> {
    for &c in disk {
        p.set_blocked(c, true).unwrap();
    }
    p.compute()?;
    p.path()
}

/// The robot's pose for smoothing the new path: its cell centre, heading along the new
/// path's first cells (a robot driving the old path points about that way).
fn robot_pose(m: &OccupancyGrid, cells: &[(usize, usize)]) -> [f64; 3] {
    let a = m.cell_to_world(cells[0].0 as f64, cells[0].1 as f64);
    let b = cells[cells.len().min(6) - 1];
    let b = m.cell_to_world(b.0 as f64, b.1 as f64);
    [a[0], a[1], (b[1] - a[1]).atan2(b[0] - a[0])]
}

const DD: DiffDriveLimits = DiffDriveLimits {
    v_max: 1.0,
    omega_max: 1.5,
    a_max: 0.8,
    alpha_max: 2.0,
};
const TIP: TipOverAcceleration = TipOverAcceleration {
    forward: 1.5,
    backward: 1.0,
    left: 1.2,
    right: 1.2,
};

/// The printed table: per case the median of 11 runs of the re-plan (on a fresh copy of
/// the planner, the copy untimed), of smoothing and of timing the new path.
fn disk_table(cases: &[DiskCase]) {
    println!(
        "\nDisk obstacle on the path 1 m ahead: D* Lite re-plan, then smoothing and timing (medians of 11 runs)"
    );
    println!(
        "| case | map cells | disk cells | new path (cells) | re-plan (set_blocked + compute + path) | expansions | smoothing | smooth length | timing | duration |"
    );
    println!("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |");
    for c in cases {
        let mut p = c.planner.clone();
        let (mut tr, mut ts, mut tt) = (vec![], vec![], vec![]);
        let mut cells = None;
        let mut smooth = None;
        let mut timed = None;
        for _ in 0..11 {
            p.clone_from(&c.planner);
            let t0 = Instant::now();
            let path = black_box(disk_replan(&mut p, &c.disk));
            tr.push(t0.elapsed().as_secs_f64());
            let Some(path) = path else { break };
            let start = robot_pose(&c.map, &path);
            let t0 = Instant::now();
            let sp = smooth_diff_drive(p.grid(), &c.map, &path, start, c.goal, &c.opts);
            ts.push(t0.elapsed().as_secs_f64());
            if let Ok(sp) = &sp {
                let t0 = Instant::now();
                let tp = black_box(time_parameterize_curve(sp, &DD, Some(&TIP), 0.0, 0.0));
                tt.push(t0.elapsed().as_secs_f64());
                timed = tp.ok().map(|t| t.duration());
            }
            smooth = Some(sp.map(|s| s.length()));
            cells = Some(path.len());
        }
        let ms = |v: &mut Vec<f64>| {
            if v.is_empty() {
                "–".to_string()
            } else {
                format!("{:.3} ms", median(v) * 1e3)
            }
        };
        println!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            c.name,
            c.map.width * c.map.height,
            c.disk.len(),
            cells.map_or("goal cut off".into(), |n| n.to_string()),
            ms(&mut tr),
            p.expanded(),
            ms(&mut ts),
            match &smooth {
                Some(Ok(l)) => format!("{l:.2} m"),
                Some(Err(e)) => format!("error: {e}"),
                None => "–".into(),
            },
            ms(&mut tt),
            timed.map_or("–".into(), |d| format!("{d:.2} s")),
        );
    }
    println!();
}

fn bench_disk(cr: &mut Criterion, cases: &[DiskCase]) {
    let mut grp = cr.benchmark_group("disk_replan");
    grp.sample_size(20)
        .measurement_time(std::time::Duration::from_secs(3));
    for c in cases {
        let mut p = c.planner.clone();
        grp.bench_function(format!("{}/dstar_lite", c.name), |b| {
            b.iter_custom(|iters| {
                let mut total = std::time::Duration::ZERO;
                for _ in 0..iters {
                    p.clone_from(&c.planner);
                    let t0 = Instant::now();
                    black_box(disk_replan(&mut p, &c.disk));
                    total += t0.elapsed();
                }
                total
            })
        });
        p.clone_from(&c.planner);
        let Some(path) = disk_replan(&mut p, &c.disk) else {
            continue;
        };
        let start = robot_pose(&c.map, &path);
        let Ok(sp) = smooth_diff_drive(p.grid(), &c.map, &path, start, c.goal, &c.opts) else {
            continue;
        };
        grp.bench_function(format!("{}/smooth", c.name), |b| {
            b.iter(|| {
                black_box(smooth_diff_drive(
                    p.grid(),
                    &c.map,
                    &path,
                    start,
                    c.goal,
                    &c.opts,
                ))
            })
        });
        grp.bench_function(format!("{}/time", c.name), |b| {
            b.iter(|| black_box(time_parameterize_curve(&sp, &DD, Some(&TIP), 0.0, 0.0)))
        });
    }
    grp.finish();
}

/// The default mission's re-plan when its crate appears, rebuilt from public parts.
struct MissionReplan {
    /// The mission's D* Lite planner after its first search (start to goal).
    planner: DStarLite,
    /// The robot's cell when the crate appears (the re-plan's first cell).
    robot: (usize, usize),
    /// The crate's configuration-space cells (free before, not the goal cell).
    disk: Vec<(usize, usize)>,
    /// Occupied map cells with the crate, for the distance-transform refresh.
    occupied: Vec<bool>,
    map: OccupancyGrid,
    start: [f64; 3],
    v0: f64,
    goal: [f64; 3],
    /// The mission's curvature-limited timing (its limits, tip-over accelerations,
    /// `kappa_max` and reference sampling period).
    timing: CurvatureTiming,
    /// What the mission got: re-planned cells, expansions, smoothed path.
    cells: Vec<(usize, usize)>,
    expanded: usize,
    path: Vec<[f64; 2]>,
}

fn mission_replan_case() -> MissionReplan {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/mission.toml");
    let m = moma::mission::load(&file).expect("default mission loads");
    let r = moma::mission::run(&m).expect("default mission runs");
    assert!(
        r.reached && r.replans() == 1,
        "the default mission re-plans once"
    );
    let f = &m.file;
    let o = f.obstacles[0];
    let rp = &r.plans[1];
    assert!((rp.t - o.t).abs() < 1e-9);
    let grid = m.map.grid.clone();
    let res = grid.resolution;
    // the mission's configuration space (planning::pipeline's disk C-space): disk
    // dilation by the footprint radius + |d| of the distance transform of the occupied
    // cells (blocked within the radius + half a cell, costmap::disk_reach)
    let mut occupied = grid.obstacle_mask(planning::grid::OCCUPIED, f.map.unknown_is_obstacle);
    let dist = planning::distance_transform(&occupied, grid.width, grid.height);
    let radius_cells = (m.footprint.radius + m.robot.base.drive.d.abs()) / res;
    let r_cells = costmap::disk_reach(radius_cells);
    let blocked = costmap::dilate_disk(&dist, radius_cells);
    let cs = SearchGrid::from_obstacles(&blocked, grid.width, grid.height).unwrap();
    let sc = grid
        .world_to_cell("start", f.start.pose[0], f.start.pose[1])
        .unwrap();
    let gc = grid
        .world_to_cell("goal", m.goal().unwrap().pose[0], m.goal().unwrap().pose[1])
        .unwrap();
    let mut planner = DStarLite::new(&cs, sc, gc).unwrap();
    planner.compute().expect("goal reachable");
    assert_eq!(
        planner.path().unwrap(),
        r.plans[0].cells,
        "the mission's first path"
    );
    // the crate's cells, as the mission marks them
    let c = grid.world_to_cell_f(o.center[0], o.center[1]);
    let (radius, reach) = (o.radius / res, o.radius / res + r_cells);
    let mut disk = Vec::new();
    for y in 0..grid.height {
        for x in 0..grid.width {
            let dc = (x as f64 + 0.5 - c[0]).hypot(y as f64 + 0.5 - c[1]);
            if dc <= radius {
                occupied[y * grid.width + x] = true;
            }
            if dc <= reach && (x, y) != gc && cs.is_free(x as i64, y as i64) {
                disk.push((x, y));
            }
        }
    }
    let i = r
        .samples
        .t
        .iter()
        .position(|&t| (t - o.t).abs() < 1e-9)
        .unwrap();
    let q = &r.samples.q[i];
    let l = &f.limits;
    let tl = &r.tip_limits;
    let side = |x: Option<f64>| x.map_or(f64::INFINITY, |a| l.tip_fraction * a);
    let case = MissionReplan {
        planner,
        robot: rp.cells[0],
        disk,
        occupied,
        // the pose the new path was smoothed from: where the base stood when the crate
        // appeared, or the stop along the old path when it braked to rest first (then
        // the new path is timed from rest); d = 0 here, so the axle midpoint is the base
        start: rp.smoothed_from,
        v0: if rp.smoothed_from == [q[0], q[1], q[2]] {
            rp.v_start
        } else {
            0.0
        },
        goal: m.goal().unwrap().pose,
        timing: CurvatureTiming {
            limits: l.platform(),
            tip: TipOverAcceleration {
                forward: l.tip_fraction * tl.forward.unwrap(),
                backward: l.tip_fraction * tl.backward.unwrap(),
                left: side(tl.left),
                right: side(tl.right),
            },
            kappa_max: l.kappa_max,
            // the mission's reference sampling period
            dt: 0.02,
        },
        cells: rp.cells.clone(),
        expanded: rp.search.expanded,
        path: rp.path.clone(),
        map: grid,
    };
    // the rebuilt re-plan is the mission's
    let mut p = case.planner.clone();
    let cells = mission_replan(&mut p, &case).expect("a path remains");
    assert_eq!(cells, case.cells, "the mission's re-planned cells");
    assert_eq!(p.expanded(), case.expanded, "the mission's expansion count");
    let curve = mission_timing(&p, &case, &cells).expect("the mission's smoothing succeeds");
    // the recorded path: the stretch braked along the old path (if any), then the new one
    let new_path = curve.geometry.points();
    assert!(
        case.path.ends_with(&new_path),
        "the mission's smoothed path: {} recorded points, {} re-smoothed",
        case.path.len(),
        new_path.len()
    );
    case
}

/// The mission's re-plan: `move_start` to the robot's cell, `set_blocked` on the crate's
/// cells, `compute`, `path`.
fn mission_replan(p: &mut DStarLite, c: &MissionReplan) -> Option<Vec<(usize, usize)>> {
    p.move_start(c.robot).unwrap();
    for &cell in &c.disk {
        p.set_blocked(cell, true).unwrap();
    }
    p.compute()?;
    p.path()
}

/// The mission's smoothing and timing of the re-planned cells: the pipeline's
/// curvature-limited timing, the function the mission itself calls (failed smoothing
/// attempts included in its time, as in the mission).
fn mission_timing(
    p: &DStarLite,
    c: &MissionReplan,
    cells: &[(usize, usize)],
) -> moma::Result<TimedCurve> {
    time_cells_curved(&c.map, p.grid(), cells, c.start, c.v0, c.goal, &c.timing)
}

fn mission_table(c: &MissionReplan) {
    let (mut tr, mut te, mut ts) = (vec![], vec![], vec![]);
    let mut p = c.planner.clone();
    for _ in 0..21 {
        p.clone_from(&c.planner);
        let t0 = Instant::now();
        let cells = black_box(mission_replan(&mut p, c)).unwrap();
        tr.push(t0.elapsed().as_secs_f64());
        let t0 = Instant::now();
        black_box(planning::distance_transform(
            &c.occupied,
            c.map.width,
            c.map.height,
        ));
        te.push(t0.elapsed().as_secs_f64());
        let t0 = Instant::now();
        black_box(mission_timing(&p, c, &cells).unwrap());
        ts.push(t0.elapsed().as_secs_f64());
    }
    println!(
        "\nThe default mission's re-plan (depot, {} x {} cells, crate at t = 5 s: {} C-space cells; medians of 21 runs)",
        c.map.width,
        c.map.height,
        c.disk.len()
    );
    println!(
        "| D* Lite (move_start + set_blocked + compute + path) | expansions | distance transform refresh | smoothing and timing |"
    );
    println!("| --- | --- | --- | --- |");
    println!(
        "| {:.3} ms | {} | {:.3} ms | {:.3} ms |\n",
        median(&mut tr) * 1e3,
        p.expanded(),
        median(&mut te) * 1e3,
        median(&mut ts) * 1e3
    );
}

fn bench_mission(cr: &mut Criterion, c: &MissionReplan) {
    let mut grp = cr.benchmark_group("disk_replan");
    grp.sample_size(20)
        .measurement_time(std::time::Duration::from_secs(3));
    let mut p = c.planner.clone();
    grp.bench_function("depot_mission/dstar_lite", |b| {
        b.iter_custom(|iters| {
            let mut total = std::time::Duration::ZERO;
            for _ in 0..iters {
                p.clone_from(&c.planner);
                let t0 = Instant::now();
                black_box(mission_replan(&mut p, c));
                total += t0.elapsed();
            }
            total
        })
    });
    grp.bench_function("depot_mission/distance_transform", |b| {
        b.iter(|| {
            black_box(planning::distance_transform(
                &c.occupied,
                c.map.width,
                c.map.height,
            ))
        })
    });
    p.clone_from(&c.planner);
    let cells = mission_replan(&mut p, c).unwrap();
    grp.bench_function("depot_mission/smooth_and_time", |b| {
        b.iter(|| black_box(mission_timing(&p, c, &cells)))
    });
    grp.finish();
}

/// `moma plan`'s work on the README's example (turtlebot3 map, disk of 0.1 m, A*, shortcut
/// smoothing, stop-and-turn timing) and on a polygon (the same ends, an 0.24 m x 0.16 m
/// rectangle over 8 headings): [`planning::pipeline::plan`] against the primitives it
/// calls composed by hand, as `moma plan` composed them before the pipeline existed (the
/// map loaded once, outside the timing).
fn bench_pipeline(c: &mut Criterion) {
    use planning::pipeline::{
        Frame, PlanFields, PlanRequest, RobotFootprint, Search, Timing, plan,
    };
    use planning::smooth::smooth;
    use planning::trajectory::time_parameterize;
    let grid = load_map(&data(PIPELINE_MAP), None).unwrap().grid;
    let limits = DiffDriveLimits {
        v_max: 0.5,
        omega_max: 1.0,
        a_max: 0.5,
        alpha_max: 2.0,
    };
    let polygon = costmap::Footprint::parse("-0.12,-0.08;0.12,-0.08;0.12,0.08;-0.12,0.08").unwrap();
    let request = |footprint| PlanRequest {
        start: [-2.0, -0.5],
        start_yaw: None,
        goal_yaw: None,
        goal: [1.5, 0.5],
        frame: Frame::Map,
        unknown_is_obstacle: true,
        footprint,
        axle_offset: 0.0,
        fields: PlanFields::default(),
        search: Search::Astar,
        turn_cost: 1.0,
        smooth: true,
        timing: Some(Timing::StopAndTurn { limits, dt: 0.1 }),
        polygon_check: None,
    };
    let disk = request(RobotFootprint::Disk(0.1));
    let poly = request(RobotFootprint::Polygon(polygon.clone()));
    // the composition of `moma plan` before the pipeline (disk: inflate, A*, smooth, time)
    let by_hand_disk = || {
        let (w, h) = (grid.width, grid.height);
        let obst = grid.obstacle_mask(100, true);
        SearchGrid::from_obstacles(&obst, w, h).unwrap();
        let s = grid.world_to_cell("start", -2.0, -0.5).unwrap();
        let g = grid.world_to_cell("goal", 1.5, 0.5).unwrap();
        let cs = costmap::inflate(&obst, w, h, 0.1 / grid.resolution).unwrap();
        let sg = SearchGrid::from_obstacles(&cs, w, h).unwrap();
        let p = planning::astar(&sg, s, g).unwrap().unwrap();
        let cells = smooth(&sg, &p.cells);
        let wp: Vec<[f64; 2]> = cells
            .iter()
            .map(|c| grid.cell_to_world(c.0 as f64, c.1 as f64))
            .collect();
        time_parameterize(&wp, None, &limits, 0.1).unwrap()
    };
    let by_hand_polygon = || {
        let (w, h) = (grid.width, grid.height);
        let obst = grid.obstacle_mask(100, true);
        SearchGrid::from_obstacles(&obst, w, h).unwrap();
        let s = grid.world_to_cell("start", -2.0, -0.5).unwrap();
        let g = grid.world_to_cell("goal", 1.5, 0.5).unwrap();
        let cs = costmap::inflate(&obst, w, h, 0.0).unwrap();
        SearchGrid::from_obstacles(&cs, w, h).unwrap();
        let r = grid.resolution;
        let fp = costmap::Footprint::new(
            polygon
                .vertices
                .iter()
                .map(|v| [v[0] / r, v[1] / r])
                .collect(),
        )
        .unwrap();
        let fcs = costmap::footprint_cspace(&obst, w, h, 1.0, &fp, 8).unwrap();
        let all_free = fcs.slices.iter().fold(vec![true; w * h], |acc, s| {
            acc.iter().zip(s).map(|(a, b)| *a && *b).collect()
        });
        SearchGrid::from_obstacles(&all_free, w, h).unwrap();
        let p = costmap::astar_footprint(&fcs, (s.0, s.1, 0), g, 1.0)
            .unwrap()
            .unwrap();
        p.states.len()
    };
    // same products
    let planned = plan(&grid, &disk).unwrap();
    assert_eq!(planned.trajectory, by_hand_disk());
    assert_eq!(plan(&grid, &poly).unwrap().cells.len(), by_hand_polygon());
    let mut grp = c.benchmark_group("pipeline");
    grp.bench_function("turtlebot3_disk/pipeline", |b| {
        b.iter(|| black_box(plan(&grid, &disk).unwrap()))
    });
    grp.bench_function("turtlebot3_disk/by_hand", |b| {
        b.iter(|| black_box(by_hand_disk()))
    });
    grp.bench_function("turtlebot3_polygon/pipeline", |b| {
        b.iter(|| black_box(plan(&grid, &poly).unwrap()))
    });
    grp.bench_function("turtlebot3_polygon/by_hand", |b| {
        b.iter(|| black_box(by_hand_polygon()))
    });
    grp.finish();
}

/// The README's `moma plan` map.
const PIPELINE_MAP: &str = "rosmaps/turtlebot3/map.yaml";

fn all(c: &mut Criterion) {
    if std::env::var_os("MOMA_BENCH_PIPELINE_ONLY").is_some() {
        bench_pipeline(c);
        return;
    }
    let mission = mission_replan_case();
    mission_table(&mission);
    let disk = disk_cases();
    disk_table(&disk);
    if std::env::var_os("MOMA_BENCH_DISK_ONLY").is_some() {
        bench_mission(c, &mission);
        bench_disk(c, &disk);
        return;
    }
    let replan_sets: Vec<(&str, Vec<ReplanPosition>)> =
        MAPS.iter().map(|&m| (m, replan_positions(m, 6))).collect();
    replan_table(&replan_sets);
    if std::env::var_os("MOMA_BENCH_REPLAN_ONLY").is_some() {
        return;
    }
    let cases: Vec<MapCase> = MAPS.iter().map(|&m| load_case(m)).collect();
    per_query_table(&cases);
    if std::env::var_os("MOMA_BENCH_TABLE_ONLY").is_some() {
        return;
    }
    bench_astar(c, &cases);
    bench_edt(c);
    bench_dstar(c, &replan_sets);
    bench_mission(c, &mission);
    bench_disk(c, &disk);
    bench_pipeline(c);
}

criterion_group!(benches, all);

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
}

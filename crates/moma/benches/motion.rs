//! The joint-space planner's own cost, before any collision checking: RRT-Connect on a
//! 7-D narrow-passage problem (`[-1, 1]^7`, a wall `|x0| < 0.05` open only where
//! `|x1| < 0.1` and `|x2| < 0.1`, resolution 0.01) whose validity check is three
//! comparisons, then shortcutting and time-optimal timing of the result.
//!
//! First a printed table: the median and 95th percentile over 200 seeds of the query time,
//! iterations, nodes and validity checks; then criterion groups over a fixed seed set.
//!
//! Run: `cargo bench -p moma --bench motion -- --warm-up-time 1 --measurement-time 3`.

use criterion::{Criterion, criterion_group};
use moma::planning::{
    JointLimits, JointPath, JointSpace, Planned, RrtConnectOptions, RrtConnectWorkspace,
    ShortcutOptions, TimingOptions, rrt_connect, shortcut, time_optimal,
};
use std::hint::black_box;
use std::time::Instant;

const START: [f64; 7] = [-0.8, 0.5, -0.5, 0.3, -0.3, 0.2, -0.2];
const GOAL: [f64; 7] = [0.8, 0.5, 0.5, -0.3, 0.3, -0.2, 0.2];

fn narrow_passage(q: &[f64]) -> bool {
    !(q[0].abs() < 0.05 && !(q[1].abs() < 0.1 && q[2].abs() < 0.1))
}

fn space() -> JointSpace {
    JointSpace::new(vec![-1.0; 7], vec![1.0; 7], 0.01).expect("space")
}

fn plan(space: &JointSpace, seed: u64, ws: &mut RrtConnectWorkspace) -> Planned {
    let options = RrtConnectOptions {
        seed,
        ..RrtConnectOptions::default()
    };
    let mut v = narrow_passage;
    rrt_connect(space, &mut v, &START, &GOAL, &options, ws).expect("query")
}

fn percentile(sorted: &[f64], p: f64) -> f64 {
    sorted[((sorted.len() - 1) as f64 * p).round() as usize]
}

fn table() {
    let space = space();
    let mut ws = RrtConnectWorkspace::new();
    let (mut times, mut iterations, mut nodes, mut checks) = (vec![], vec![], vec![], vec![]);
    let mut solved = 0;
    for seed in 0..200 {
        let began = Instant::now();
        let out = black_box(plan(&space, seed, &mut ws));
        times.push(began.elapsed().as_secs_f64() * 1e6);
        solved += usize::from(out.path().is_some());
        let s = out.stats();
        iterations.push(s.iterations as f64);
        nodes.push(s.nodes as f64);
        checks.push(s.checks as f64);
    }
    println!("RRT-Connect, 7-D narrow passage, 200 seeds: {solved} solved");
    println!("{:>12} {:>10} {:>10}", "", "median", "p95");
    for (name, v) in [
        ("time (us)", &mut times),
        ("iterations", &mut iterations),
        ("nodes", &mut nodes),
        ("checks", &mut checks),
    ] {
        v.sort_by(f64::total_cmp);
        println!(
            "{name:>12} {:>10.1} {:>10.1}",
            percentile(v, 0.5),
            percentile(v, 0.95)
        );
    }
}

fn bench(c: &mut Criterion) {
    table();
    let space = space();
    let mut ws = RrtConnectWorkspace::new();
    let seeds: Vec<u64> = (0..32).collect();
    let mut group = c.benchmark_group("motion_7d_narrow_passage");
    group.bench_function("rrt_connect_32_seeds", |b| {
        b.iter(|| {
            for &seed in &seeds {
                black_box(plan(&space, seed, &mut ws));
            }
        })
    });
    let paths: Vec<JointPath> = seeds
        .iter()
        .map(|&seed| plan(&space, seed, &mut ws).path().expect("solved").clone())
        .collect();
    group.bench_function("shortcut_32_paths", |b| {
        b.iter(|| {
            for (path, &seed) in paths.iter().zip(&seeds) {
                let mut v = narrow_passage;
                let options = ShortcutOptions {
                    attempts: 100,
                    seed,
                    ..ShortcutOptions::default()
                };
                black_box(shortcut(&space, &mut v, path, &options, &mut 0).expect("shortcut"));
            }
        })
    });
    let limits = JointLimits {
        velocity: vec![1.0, 1.2, 0.8, 1.5, 2.0, 2.0, 2.5],
        acceleration: vec![3.0, 2.0, 4.0, 5.0, 6.0, 6.0, 8.0],
    };
    let mut v = narrow_passage;
    let short = shortcut(
        &space,
        &mut v,
        &paths[0],
        &ShortcutOptions::default(),
        &mut 0,
    )
    .expect("shortcut");
    group.bench_function("time_optimal_one_path", |b| {
        b.iter(|| {
            let mut v = narrow_passage;
            black_box(
                time_optimal(&space, &mut v, &short, &limits, &TimingOptions::default())
                    .expect("timing"),
            )
        })
    });
    group.finish();
}

criterion_group!(benches, bench);

fn main() {
    benches();
    Criterion::default().configure_from_args().final_summary();
}

//! Per-problem times of the 3-D A* on the A1 every-10th subsample of the test data:
//! `cargo run --release --locked -p moma --example astar3d_times -- [EVERY] [FIRST]`
//! prints `index optimal found expanded wall_us cpu_us cpu_ns_per_expansion ok` for
//! every EVERY-th problem from FIRST. The CPU time is the thread's own (Linux
//! `/proc/thread-self/schedstat`, scheduler-tick resolution), so it is meaningful on a
//! loaded machine where the wall time is not; elsewhere it prints `-`.

use std::io::Write;
use std::path::Path;
use std::time::Instant;

fn cpu_ns() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |i: usize, d: usize| args.get(i).map_or(d, |s| s.parse().expect("a count"));
    let (every, first) = (arg(1, 1).max(1), arg(2, 0));
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/planning/movingai/3d");
    let grid = moma::planning::load_3dmap(&dir.join("A1.3dmap")).expect("the test map");
    let probs =
        moma::planning::load_3dscen(&dir.join("A1.every10.3dscen")).expect("the test scenario");
    let mut ws = moma::planning::Astar3Workspace::new();
    let mut out = std::io::stdout().lock();
    for (i, p) in probs.iter().enumerate().skip(first).step_by(every) {
        let (c0, t0) = (cpu_ns(), Instant::now());
        let r = moma::planning::astar3d_with(&grid, &mut ws, p.start, p.goal)
            .expect("valid problem")
            .expect("solvable");
        let wall = t0.elapsed().as_secs_f64() * 1e6;
        let ok = (r.cost - p.optimal).abs() <= 1e-5 * p.optimal;
        let cpu = match (c0, cpu_ns()) {
            (Some(a), Some(b)) => {
                let us = (b - a) / 1e3;
                format!("{us:.0} {:.1}", us * 1e3 / r.expanded as f64)
            }
            _ => "- -".into(),
        };
        writeln!(
            out,
            "{i} {:.4} {:.4} {} {wall:.0} {cpu} {ok}",
            p.optimal, r.cost, r.expanded
        )
        .expect("stdout");
        out.flush().expect("stdout");
    }
}

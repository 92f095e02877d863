//! `moma scen`: run every problem of a Moving AI scenario file (2-D `.map` + `.scen` or
//! 3-D `.3dmap` + `.3dscen`) and compare the found lengths with the optimal ones.
//!
//! Mismatches are the diagnostics this command exists for: the CSV (`--output`) and the
//! summary are written in full, then the run ends in `GoalNotReached` (exit status 3).

use super::common::goal_not_reached;
use crate::output::write_atomic;
use anyhow::{Context, Result, bail};
use moma::planning::{self, AstarWorkspace, MovingAiScenario, SearchGrid, astar::astar_cost};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `moma scen`.
#[derive(clap::Args)]
pub struct Args {
    /// The map: a Moving AI `.map` or `.3dmap`.
    pub map: PathBuf,
    /// The scenario: a `.scen` (for a `.map`) or `.3dscen` (for a `.3dmap`).
    pub scen: PathBuf,
    /// Run only every N-th problem (1 = all).
    #[arg(long, default_value_t = 1)]
    pub every: usize,
    /// Write one CSV row per problem here
    /// (`index,start [cell],goal [cell],cost [cell],optimal [cell],expanded,time [us]`).
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// Relative tolerance when comparing with the optimal length.
    #[arg(long, default_value_t = 1e-5)]
    pub tolerance: f64,
}

/// The CSV header: units in brackets (`docs/cli.md`); lengths are in cell edges.
const CSV_HEADER: &str =
    "index,start [cell],goal [cell],cost [cell],optimal [cell],expanded,time [us]\n";

struct Row {
    index: usize,
    start: String,
    goal: String,
    cost: Option<f64>,
    optimal: f64,
    expanded: usize,
    micros: f64,
}

/// Runs the subcommand.
pub fn run(args: Args) -> Result<()> {
    if args.every == 0 {
        bail!("--every must be at least 1");
    }
    if !(args.tolerance.is_finite() && args.tolerance >= 0.0) {
        bail!("--tolerance must be a finite non-negative number");
    }
    let is3d = args.map.extension().is_some_and(|e| e == "3dmap");
    let rows = if is3d { run3(&args)? } else { run2(&args)? };
    if rows.is_empty() {
        bail!(
            "{}: no problems to run (empty scenario file, or --every {} skips them all)",
            args.scen.display(),
            args.every
        );
    }
    let mut mismatches = Vec::new();
    let mut csv = String::from(CSV_HEADER);
    for r in &rows {
        let cost = r.cost.map(|c| format!("{c:.8}")).unwrap_or_default();
        csv.push_str(&format!(
            "{},{},{},{},{},{},{:.1}\n",
            r.index, r.start, r.goal, cost, r.optimal, r.expanded, r.micros
        ));
        let ok = r
            .cost
            .is_some_and(|c| (c - r.optimal).abs() <= args.tolerance * r.optimal.max(1.0));
        if !ok {
            mismatches.push(r);
        }
    }
    if let Some(out) = &args.output {
        write_atomic(out, csv.as_bytes())?;
    }
    let mut t: Vec<f64> = rows.iter().map(|r| r.micros).collect();
    t.sort_by(f64::total_cmp);
    let pct = |p: f64| {
        if t.is_empty() {
            0.0
        } else {
            t[((t.len() - 1) as f64 * p).round() as usize]
        }
    };
    let total: f64 = t.iter().sum();
    println!("{} problems from {}", rows.len(), args.scen.display());
    println!(
        "mismatches (relative tolerance {:e}): {}",
        args.tolerance,
        mismatches.len()
    );
    for r in mismatches.iter().take(10) {
        let c = r
            .cost
            .map(|c| format!("{c:.8}"))
            .unwrap_or_else(|| "no path".into());
        println!(
            "  #{} {} -> {}: found {c}, optimal {}",
            r.index, r.start, r.goal, r.optimal
        );
    }
    println!(
        "time per problem (us): median {:.1}, p90 {:.1}, p99 {:.1}, max {:.1}; total {:.3} s",
        pct(0.5),
        pct(0.9),
        pct(0.99),
        pct(1.0),
        total * 1e-6
    );
    if !mismatches.is_empty() {
        return goal_not_reached(format!(
            "{} of {} problems do not match the optimal length",
            mismatches.len(),
            rows.len()
        ));
    }
    Ok(())
}

fn run2(args: &Args) -> Result<Vec<Row>> {
    let grid = planning::load_movingai_map(&args.map)?;
    let scen = MovingAiScenario::load(&args.scen)?;
    let sg = SearchGrid::from_grid(&grid, true)?;
    let mut ws = AstarWorkspace::new();
    let mut rows = Vec::new();
    for p in scen.problems.iter().step_by(args.every) {
        if let (Some(w), Some(h)) = (p.map_width, p.map_height)
            && (w, h) != (grid.width, grid.height)
        {
            bail!(
                "{}: problem {} is for a {w} x {h} map, but {} is {} x {}",
                args.scen.display(),
                p.index,
                args.map.display(),
                grid.width,
                grid.height
            );
        }
        let t0 = Instant::now();
        let (cost, expanded) = astar_cost(&sg, &mut ws, p.start, p.goal)
            .with_context(|| format!("{}: problem {}", args.scen.display(), p.index))?;
        let micros = t0.elapsed().as_secs_f64() * 1e6;
        rows.push(Row {
            index: p.index,
            start: format!("{} {}", p.start.0, p.start.1),
            goal: format!("{} {}", p.goal.0, p.goal.1),
            cost,
            optimal: p.optimal,
            expanded,
            micros,
        });
    }
    Ok(rows)
}

fn run3(args: &Args) -> Result<Vec<Row>> {
    let grid = planning::load_3dmap(&args.map)?;
    let probs = planning::load_3dscen(&args.scen)?;
    let mut rows = Vec::new();
    let mut ws = planning::Astar3Workspace::new();
    for p in probs.iter().step_by(args.every) {
        let t0 = Instant::now();
        let r = planning::astar3d_with(&grid, &mut ws, p.start, p.goal)
            .with_context(|| format!("{}: problem {}", args.scen.display(), p.index))?;
        let micros = t0.elapsed().as_secs_f64() * 1e6;
        rows.push(Row {
            index: p.index,
            start: format!("{} {} {}", p.start.0, p.start.1, p.start.2),
            goal: format!("{} {} {}", p.goal.0, p.goal.1, p.goal.2),
            cost: r.as_ref().map(|r| r.cost),
            optimal: p.optimal,
            expanded: r.map_or(0, |r| r.expanded),
            micros,
        });
    }
    Ok(rows)
}

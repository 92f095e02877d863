//! `moma reach-map`: reachability and manipulability of a fixed end-effector target over
//! a grid of base placements, best placement, SVG heat map.

use super::common::{
    check_ik_budget, frame_name, frame_of, goal_not_reached, load_model, parse_base, parse_list,
    parse_task_rows,
};
use crate::output::{print_json, write_all_atomic};
use crate::svg_heatmap::{HeatMap, render};
use anyhow::{Result, anyhow, bail};
use moma::ik::IkOptions;
use moma::ik::model::ModelFrame;
use moma::ik::placement::{
    ArmReachEvaluator, MeasureScope, PlacementGrid, PlacementSample, placement_map,
};
use moma::ik::tasks::{FrameKinematics, TaskRows, target_from_slice};
use moma::manipulability::Measure;
use moma::mobile::whole_body::BaseInputs;
use moma::multibody::RootJoint;
use nalgebra::{DVector, Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::Serialize;
use std::path::PathBuf;
use std::sync::Arc;

/// Arguments of `moma reach-map`.
#[derive(clap::Args)]
pub struct Args {
    /// Robot model (URDF), root fixed to the platform frame (or to --mount).
    pub robot: PathBuf,
    /// End-effector target in world: x,y,z or x,y,z,qx,qy,qz,qw.
    #[arg(long, allow_hyphen_values = true)]
    pub target: String,
    /// Area of base positions: x0,y0,x1,y1 (m).
    #[arg(long, allow_hyphen_values = true)]
    pub area: String,
    /// Grid step (m).
    #[arg(long, allow_hyphen_values = true)]
    pub step: f64,
    /// Number of base headings per cell.
    #[arg(long, default_value_t = 8)]
    pub headings: usize,
    /// Write the heat map (best measure over headings per cell) to this SVG file.
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Print JSON on standard output.
    #[arg(long)]
    pub json: bool,
    /// Also write the JSON result to this file.
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    /// End-effector frame (default: the deepest link).
    #[arg(long)]
    pub frame: Option<String>,
    /// Measure (see `moma manipulability --help`).
    #[arg(long, default_value = "yoshikawa")]
    pub measure: String,
    /// Task rows (default: position for a 3-value target, full for a 7-value one).
    #[arg(long)]
    pub rows: Option<String>,
    /// Evaluate the measure on the whole-body Jacobian of this platform
    /// (diff-drive:r_w=R,b=B,d=D) instead of the arm's.
    #[arg(long)]
    pub base: Option<String>,
    /// Base inputs for the whole-body measure: platform or wheels.
    #[arg(long, default_value = "platform")]
    pub inputs: String,
    /// Arm base in the platform frame: x,y,z[,yaw] (default 0,0,0).
    #[arg(long, allow_hyphen_values = true)]
    pub mount: Option<String>,
    /// IK seed (arm joints; default neutral).
    #[arg(long, allow_hyphen_values = true)]
    pub q0: Option<String>,
    /// Layout of --q0: moma or pinocchio (continuous joints as cos, sin).
    #[arg(long, value_enum, default_value_t = super::common::Layout::Moma)]
    pub layout: super::common::Layout,
    /// IK tolerance.
    #[arg(long, default_value_t = 1e-6)]
    pub tol: f64,
    /// IK iterations per attempt.
    #[arg(long, default_value_t = 100)]
    pub max_iters: usize,
    /// Random IK restarts per base pose when the seed does not converge.
    #[arg(long, default_value_t = 2)]
    pub restarts: usize,
}

#[derive(Serialize)]
struct Output<'a> {
    robot: String,
    frame: String,
    target: Vec<f64>,
    measure: String,
    scope: &'static str,
    grid: &'a PlacementGrid,
    samples: usize,
    reachable: usize,
    best: Option<PlacementSample>,
    /// IK iterations over all samples (reachable, unreachable).
    ik_iterations: [usize; 2],
    /// Samples decided without IK (target outside the arm's reach sphere).
    pruned: usize,
    time_s: f64,
    /// Best measure over headings per cell: `ny` rows (from y0) of `nx` values (null =
    /// unreachable at every heading).
    cells: Vec<Vec<Option<f64>>>,
}

/// Parses `--mount x,y,z[,yaw]` (default: the identity).
fn parse_mount(mount: Option<&str>) -> Result<Isometry3<f64>> {
    let Some(m) = mount else {
        return Ok(Isometry3::identity());
    };
    let v = parse_list("--mount", m)?;
    if v.len() != 3 && v.len() != 4 {
        bail!(
            "--mount: expected x,y,z or x,y,z,yaw, got {} values",
            v.len()
        );
    }
    Ok(Isometry3::from_parts(
        Translation3::new(v[0], v[1], v[2]),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), *v.get(3).unwrap_or(&0.0)),
    ))
}

/// Parses `--measure` and checks a directional measure against the task rows.
fn parse_measure(text: &str, rows: &TaskRows) -> Result<Measure> {
    let measure: Measure = text.parse().map_err(|e| anyhow!("--measure: {e}"))?;
    if let Measure::Directional(u) = &measure
        && u.len() != rows.indices().len()
    {
        bail!(
            "--measure directional: expected {} components, got {}",
            rows.indices().len(),
            u.len()
        );
    }
    Ok(measure)
}

/// Most IK iterations a whole map may spend in the worst case (every sample unreachable,
/// every attempt to its last iteration): the sample count is bounded by the grid
/// (`moma::ik::placement::MAX_SAMPLES`) and each solve by the IK budget, but their product
/// is not, so a small `--step` with many restarts could run for hours.
pub const MAX_MAP_IK_ITERATIONS: f64 = 1e8;

/// Refuses a map whose worst-case work, samples × (restarts + 1) × max_iters, exceeds
/// [`MAX_MAP_IK_ITERATIONS`], naming the options that set it.
fn check_total_work(grid: &PlacementGrid, restarts: usize, max_iters: usize) -> Result<()> {
    let samples = grid.nx as f64 * grid.ny as f64 * grid.headings as f64;
    let work = samples * (restarts as f64 + 1.0) * max_iters as f64;
    if work > MAX_MAP_IK_ITERATIONS {
        bail!(
            "--step/--headings/--restarts/--max-iters: {samples:.0} samples × ({restarts} + 1) \
             attempts × {max_iters} iterations = {work:.3e} IK iterations in the worst case \
             exceed the budget of {MAX_MAP_IK_ITERATIONS:e}; use a larger --step or fewer \
             --headings, --restarts or --max-iters"
        );
    }
    Ok(())
}

/// Checks every option and builds the grid and the per-pose evaluator (robot loaded).
fn setup(args: &Args) -> Result<(Vec<f64>, PlacementGrid, ArmReachEvaluator<ModelFrame>)> {
    let tvals = parse_list("--target", &args.target)?;
    let target = target_from_slice(&tvals).map_err(|e| anyhow!("--target: {e}"))?;
    let area = parse_list("--area", &args.area)?;
    if area.len() != 4 {
        bail!("--area: expected 4 values x0,y0,x1,y1, got {}", area.len());
    }
    let grid = PlacementGrid::new(
        [area[0], area[1], area[2], area[3]],
        args.step,
        args.headings,
    )
    .map_err(|e| anyhow!("--area/--step/--headings: {e}"))?;
    let rows = parse_task_rows(args.rows.as_deref(), &tvals)?;
    let measure = parse_measure(&args.measure, &rows)?;
    let inputs: BaseInputs = args.inputs.parse().map_err(|e| anyhow!("--inputs: {e}"))?;
    let scope = match &args.base {
        Some(b) => MeasureScope::WholeBody(parse_base(b)?, inputs),
        None => MeasureScope::Arm,
    };
    let mount = parse_mount(args.mount.as_deref())?;
    check_ik_budget(args.tol, args.max_iters, args.restarts)?;
    check_total_work(&grid, args.restarts, args.max_iters)?;
    let model = Arc::new(load_model(&args.robot, RootJoint::Fixed)?);
    let arm = frame_of(&model, args.frame.as_deref(), &args.robot)?;
    let seed = match &args.q0 {
        Some(s) => {
            let v = super::common::LayoutConv::new(&model, args.layout)
                .q_in(parse_list("--q0", s)?, "--q0")?;
            if v.len() != arm.nq() {
                bail!("--q0: expected {} values, got {}", arm.nq(), v.len());
            }
            DVector::from_vec(v)
        }
        None => moma::kinematics::neutral(&model),
    };
    let evaluator = ArmReachEvaluator {
        arm,
        mount,
        target,
        rows,
        options: IkOptions {
            tolerance: args.tol,
            max_iterations: args.max_iters,
            ..IkOptions::default()
        },
        seed,
        restarts: args.restarts,
        measure,
        scope,
    };
    evaluator.validate()?;
    Ok((tvals, grid, evaluator))
}

/// Runs `moma reach-map`. A target reachable from no pose of the grid still writes its
/// outputs (an all-grey map), then ends in `GoalNotReached` (exit status 3).
pub fn run(args: Args) -> Result<()> {
    let (tvals, grid, evaluator) = setup(&args)?;
    let frame = frame_name(&evaluator.arm);
    let measure = evaluator.measure.clone();
    let larger = measure.larger_is_better();
    let start = std::time::Instant::now();
    let map = placement_map(&evaluator, &grid)?;
    let time_s = start.elapsed().as_secs_f64();
    let cells_flat = map.cell_best(larger);
    let sum_iters = |reachable: bool| -> usize {
        map.samples
            .iter()
            .filter(|s| s.reachable == reachable)
            .map(|s| s.iterations)
            .sum()
    };
    let out = Output {
        robot: args.robot.display().to_string(),
        frame: frame.clone(),
        target: tvals.clone(),
        measure: measure.to_string(),
        scope: match evaluator.scope {
            MeasureScope::Arm => "arm",
            MeasureScope::WholeBody(..) => "whole-body",
        },
        grid: &grid,
        samples: map.samples.len(),
        reachable: map.reachable,
        best: map.best,
        ik_iterations: [sum_iters(true), sum_iters(false)],
        pruned: map
            .samples
            .iter()
            .filter(|s| !s.reachable && s.iterations == 0)
            .count(),
        time_s,
        cells: cells_flat.chunks(grid.nx).map(|r| r.to_vec()).collect(),
    };
    let mut files = Vec::new();
    if let Some(path) = &args.svg {
        let title = format!(
            "{} — best {} over {} headings, target ({:.3}, {:.3}, {:.3})",
            frame, measure, grid.headings, tvals[0], tvals[1], tvals[2]
        );
        let svg = render(&HeatMap {
            title: &title,
            value_label: measure.name(),
            cells: &cells_flat,
            nx: grid.nx,
            ny: grid.ny,
            x0: grid.x0,
            y0: grid.y0,
            step: grid.step,
            target: Some((tvals[0], tvals[1])),
            best: map.best.map(|b| (b.base[0], b.base[1], b.base[2])),
            larger_is_better: larger,
        });
        files.push((path.clone(), svg.into_bytes()));
    }
    if let Some(path) = &args.output {
        let mut text = serde_json::to_string_pretty(&out)?;
        text.push('\n');
        files.push((path.clone(), text.into_bytes()));
    }
    write_all_atomic(&files)?;
    print_result(&args, &out, &grid)?;
    if out.reachable == 0 {
        return goal_not_reached(format!(
            "the target ({:.3}, {:.3}, {:.3}) is reachable from none of the {} base poses of the grid",
            tvals[0], tvals[1], tvals[2], out.samples
        ));
    }
    Ok(())
}

fn print_result(args: &Args, out: &Output, grid: &PlacementGrid) -> Result<()> {
    if args.json {
        return print_json(out);
    }
    outln!(
        "{}: frame '{}', {} base poses ({} x {} x {} headings) in {:.3} s; reachable from {}",
        out.robot,
        out.frame,
        out.samples,
        grid.nx,
        grid.ny,
        grid.headings,
        out.time_s,
        out.reachable
    );
    match &out.best {
        Some(b) => outln!(
            "best placement: x = {:.4} m, y = {:.4} m, θ = {:.4} rad, {} = {:.6e}",
            b.base[0],
            b.base[1],
            b.base[2],
            out.measure,
            b.measure.unwrap_or(0.0)
        ),
        None => outln!("the target is unreachable from every base pose of the grid"),
    }
    Ok(())
}

//! `moma plan`: plan a path on an occupancy map (ROS map in world coordinates, Moving AI
//! map in cells), smooth it and time-parameterise it for a differential drive, through
//! the library's one planning pipeline (`moma::planning::pipeline`).
//!
//! Output (`--output path.json`, schema in docs/planning.md): status, cost, the grid
//! path, the smoothed waypoints and the reference trajectory. A search that finds no
//! path is an error (non-zero exit, no file written) whose message gives the reason. A
//! potential-field descent stuck in a local minimum writes its outputs with
//! `"status": "local_minimum"` (so the trap can be inspected) and exits with status 3
//! (`docs/cli.md`). Errors name points in the user's frame (world metres on ROS maps)
//! and the cell.

use super::common::goal_not_reached;
use crate::output::write_all_atomic;
use crate::svg_map::{Scene, render};
use anyhow::{Context, Result, bail};
use moma::planning::costmap::{Footprint, InflationParams};
use moma::planning::load_map;
use moma::planning::pipeline::{
    self, Frame, MapFrame, PLAN_DT, PLAN_LIMITS, Plan, PlanFields, PlanRequest, PlanStatus,
    PolygonCheck, RobotFootprint, Search, Timing,
};
use moma::planning::potential::GoalTerm;
use moma::planning::trajectory::{DiffDriveLimits, TrajectoryPoint};
use std::path::PathBuf;

/// Planning algorithm.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Algo {
    /// A* (octile, no corner cutting); with --cost-aware over inflation costs.
    Astar,
    /// D* Lite (first plan; same cost as A*).
    DstarLite,
    /// Literal potential field: obstacle distance against weighted Euclidean goal distance.
    Potential,
    /// Potential field whose goal term is the geodesic (wavefront) distance.
    PotentialGeodesic,
}

/// What to do with unknown cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Unknown {
    /// Unknown cells are obstacles (safe default).
    Obstacle,
    /// Unknown cells are traversable.
    Free,
}

/// Arguments of `moma plan` (boxed: they are many, and the subcommand enum stays small).
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    inner: Box<PlanArgs>,
}

/// The options of `moma plan`.
#[derive(clap::Args)]
pub struct PlanArgs {
    /// The map: ROS YAML, Moving AI `.map`, or a bare PGM/PNG image.
    pub map: PathBuf,
    /// Resolution (m/cell) for a bare image (default 0.05).
    #[arg(long)]
    pub resolution: Option<f64>,
    /// Start `X,Y` or `X,Y,YAW` (world metres/radians for ROS maps, cells for Moving AI).
    #[arg(long, allow_hyphen_values = true)]
    pub start: String,
    /// Goal `X,Y`.
    #[arg(long, allow_hyphen_values = true)]
    pub goal: String,
    /// Robot radius (m, or cells on Moving AI maps): obstacles are dilated by this disk.
    #[arg(long, conflicts_with = "footprint")]
    pub radius: Option<f64>,
    /// Polygonal footprint `x1,y1;x2,y2;...` (nav2's `footprint` syntax) or
    /// `[[x1,y1],...]` in the robot frame (m, or cells); plans over (x, y, heading) with
    /// 8 headings, each pose checked at its heading (A* only).
    #[arg(long, allow_hyphen_values = true)]
    pub footprint: Option<String>,
    /// With a point or `--radius` disk: a convex polygon (the `--footprint` syntax) that
    /// every pose of the timed path is checked with at its heading, the way nav2 and the
    /// mission check a polygon robot planned on a disk; a pose where it meets an obstacle
    /// cell writes the outputs with status `colliding` and exits with status 3.
    #[arg(long, allow_hyphen_values = true)]
    pub check_footprint: Option<String>,
    /// The clearance (m, or cells) the `--check-footprint` polygon keeps from the
    /// obstacle cells (default 0).
    #[arg(long)]
    pub check_padding: Option<f64>,
    /// Algorithm.
    #[arg(long, value_enum, default_value_t = Algo::Astar)]
    pub algo: Algo,
    /// Unknown cells: obstacle or free.
    #[arg(long, value_enum, default_value_t = Unknown::Obstacle)]
    pub unknown: Unknown,
    /// A* over nav2-style inflation costs (Smac-2D edge costs) instead of the plain C-space.
    #[arg(long)]
    pub cost_aware: bool,
    /// Inflation radius (m or cells) for --cost-aware (default 0.55 m / 11 cells).
    #[arg(long)]
    pub inflation_radius: Option<f64>,
    /// Cost scaling factor (1/m or 1/cell) for --cost-aware (default 10 / 0.5).
    #[arg(long)]
    pub cost_scaling: Option<f64>,
    /// Cost travel multiplier for --cost-aware.
    #[arg(long, default_value_t = 2.0)]
    pub cost_multiplier: f64,
    /// Goal weight w of the potential (> 1 for the geodesic form).
    #[arg(long, default_value_t = 2.0)]
    pub goal_weight: f64,
    /// Obstacle influence range of the potential (m, or cells; default 5 cells).
    #[arg(long)]
    pub influence: Option<f64>,
    /// Turn cost per 45° for the footprint search (cells of travel).
    #[arg(long, default_value_t = 1.0)]
    pub turn_cost: f64,
    /// Skip shortcut smoothing.
    #[arg(long)]
    pub no_smooth: bool,
    /// Maximum forward speed (m/s, or cells/s).
    #[arg(long, default_value_t = PLAN_LIMITS.v_max)]
    pub v_max: f64,
    /// Maximum turn rate (rad/s).
    #[arg(long, default_value_t = PLAN_LIMITS.omega_max)]
    pub omega_max: f64,
    /// Maximum linear acceleration.
    #[arg(long, default_value_t = PLAN_LIMITS.a_max)]
    pub a_max: f64,
    /// Maximum angular acceleration (rad/s²).
    #[arg(long, default_value_t = PLAN_LIMITS.alpha_max)]
    pub alpha_max: f64,
    /// Trajectory sampling period (s).
    #[arg(long, default_value_t = PLAN_DT)]
    pub dt: f64,
    /// Write the result as JSON here.
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// Draw the map, the inflated obstacles and the path as SVG here.
    #[arg(long)]
    pub svg: Option<PathBuf>,
}

/// The `path.json` document.
#[derive(serde::Serialize)]
struct PlanOutput {
    map: String,
    frame: &'static str,
    algorithm: Algo,
    status: &'static str,
    report: String,
    start: [f64; 2],
    goal: [f64; 2],
    start_cell: [usize; 2],
    goal_cell: [usize; 2],
    robot: serde_json::Value,
    cost: Option<f64>,
    length: f64,
    expanded: usize,
    cells: Vec<[usize; 2]>,
    headings: Option<Vec<f64>>,
    waypoints: Vec<[f64; 2]>,
    limits: DiffDriveLimits,
    duration: f64,
    trajectory: Vec<TrajectoryPoint>,
}

fn parse_xy(what: &str, s: &str) -> Result<(f64, f64, Option<f64>)> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| {
            t.trim()
                .parse::<f64>()
                .with_context(|| format!("--{what}: '{t}' is not a number"))
        })
        .collect::<Result<_>>()?;
    if !(v.len() == 2 || (v.len() == 3 && what == "start")) {
        bail!(
            "--{what}: expected X,Y{}",
            if what == "start" { " or X,Y,YAW" } else { "" }
        );
    }
    if v.iter().any(|x| !x.is_finite()) {
        bail!("--{what}: values must be finite");
    }
    Ok((v[0], v[1], v.get(2).copied()))
}

/// Refuses NaN and ±inf in every numeric option, naming the option (the library's
/// range checks name its own parameter, e.g. `v_max`).
fn check_finite_options(args: &PlanArgs) -> Result<()> {
    let opt = |x: Option<f64>| x.unwrap_or(0.0);
    for (name, v) in [
        ("--resolution", opt(args.resolution)),
        ("--radius", opt(args.radius)),
        ("--check-padding", opt(args.check_padding)),
        ("--inflation-radius", opt(args.inflation_radius)),
        ("--cost-scaling", opt(args.cost_scaling)),
        ("--cost-multiplier", args.cost_multiplier),
        ("--goal-weight", args.goal_weight),
        ("--influence", opt(args.influence)),
        ("--turn-cost", args.turn_cost),
        ("--v-max", args.v_max),
        ("--omega-max", args.omega_max),
        ("--a-max", args.a_max),
        ("--alpha-max", args.alpha_max),
        ("--dt", args.dt),
    ] {
        if !v.is_finite() {
            bail!("{name}: must be a finite number, got {v}");
        }
    }
    Ok(())
}

/// The footprint, the search and the `robot` entry of `path.json` from the options.
fn footprint_and_search(
    args: &PlanArgs,
    mf: &MapFrame<'_>,
) -> Result<(RobotFootprint, Search, serde_json::Value)> {
    let mut robot = serde_json::json!({ "kind": "point" });
    let footprint = match (&args.footprint, args.radius) {
        (Some(text), _) => {
            if args.algo != Algo::Astar || args.cost_aware {
                bail!("--footprint works with --algo astar (without --cost-aware)");
            }
            let fp = Footprint::parse(text).context("--footprint")?;
            robot = serde_json::json!({ "kind": "polygon", "vertices": fp.vertices });
            RobotFootprint::Polygon(fp)
        }
        (None, Some(r)) => {
            if !(r.is_finite() && r >= 0.0) {
                bail!("--radius must be a finite non-negative number, got {r}");
            }
            robot = serde_json::json!({ "kind": "disk", "radius": r });
            RobotFootprint::Disk(r)
        }
        (None, None) => RobotFootprint::Point,
    };
    let search = match args.algo {
        Algo::Astar if args.cost_aware => {
            for (opt, v) in [
                ("--radius", args.radius),
                ("--inflation-radius", args.inflation_radius),
                ("--cost-scaling", args.cost_scaling),
            ] {
                if let Some(v) = v
                    && !(v.is_finite() && v >= 0.0)
                {
                    bail!("{opt}: must be finite and >= 0, got {v}");
                }
            }
            let inflation = InflationParams {
                inscribed_radius: args.radius.unwrap_or(0.0),
                inflation_radius: args.inflation_radius.unwrap_or(if mf.world() {
                    0.55
                } else {
                    11.0
                }),
                cost_scaling_factor: args.cost_scaling.unwrap_or(if mf.world() {
                    10.0
                } else {
                    0.5
                }),
            };
            robot["inflation"] = serde_json::to_value(inflation)?;
            Search::CostAware {
                inflation,
                cost_multiplier: args.cost_multiplier,
            }
        }
        _ if args.cost_aware => bail!("--cost-aware works with --algo astar"),
        Algo::Astar => Search::Astar,
        Algo::DstarLite => Search::DStarLite,
        Algo::Potential | Algo::PotentialGeodesic => Search::Potential {
            term: if args.algo == Algo::Potential {
                GoalTerm::Euclidean
            } else {
                GoalTerm::Geodesic
            },
            goal_weight: args.goal_weight,
            influence: args.influence,
        },
    };
    Ok((footprint, search, robot))
}

/// `--check-footprint` and `--check-padding`: the polygon the timed path of a point or
/// disk plan is checked with (the pipeline's [`PlanRequest::polygon_check`]), its origin
/// on the planned point; `None` without `--check-footprint`.
fn polygon_check(args: &PlanArgs) -> Result<Option<PolygonCheck>> {
    let Some(text) = &args.check_footprint else {
        if args.check_padding.is_some() {
            bail!("--check-padding: read only with --check-footprint");
        }
        return Ok(None);
    };
    if args.footprint.is_some() {
        bail!(
            "--check-footprint checks the path of a point or --radius plan; a --footprint \
             plan is searched at its headings already: give one of the two"
        );
    }
    let polygon = Footprint::parse(text).context("--check-footprint")?;
    Ok(Some(PolygonCheck::new(
        polygon.vertices,
        args.check_padding.unwrap_or(0.0),
        0.0,
        ["--check-footprint", "--check-padding"],
    )?))
}

/// Runs the subcommand. A potential field stuck in a local minimum, and a path that the
/// `--check-footprint` polygon collides along, still write their outputs (status
/// `local_minimum`, `colliding`), then end in `GoalNotReached` (exit status 3).
pub fn run(args: Args) -> Result<()> {
    let args = *args.inner;
    check_finite_options(&args)?;
    let loaded = load_map(&args.map, args.resolution)?;
    let mf = MapFrame::new(&loaded.grid);
    let (sx, sy, start_yaw) = parse_xy("start", &args.start)?;
    let (gx, gy, _) = parse_xy("goal", &args.goal)?;
    let (footprint, search, mut robot) = footprint_and_search(&args, &mf)?;
    let check = polygon_check(&args)?;
    let checked = check.is_some();
    let request = PlanRequest {
        start: [sx, sy],
        start_yaw,
        goal_yaw: None,
        goal: [gx, gy],
        frame: Frame::Map,
        unknown_is_obstacle: args.unknown == Unknown::Obstacle,
        footprint,
        axle_offset: 0.0,
        fields: PlanFields::default(),
        search,
        turn_cost: args.turn_cost,
        smooth: !args.no_smooth,
        timing: Some(Timing::StopAndTurn {
            limits: platform_limits(&args),
            dt: args.dt,
        }),
        // (`--footprint` searches the polygon's heading lattice, exact at the headings the
        // path is driven with: it needs no check of the timed path, docs/planning.md)
        polygon_check: check,
    };
    let plan = pipeline::plan(&loaded.grid, &request)?;
    if plan.status == PlanStatus::Unreachable {
        bail!("{}", plan.report);
    }
    if let Some(report) = plan.check_report(&request) {
        robot["check"] = serde_json::to_value(report)?;
    }
    let out = plan_output(&args, &mf, &request, robot, &plan);
    write_outputs(&args, &mf, &plan, &out)?;
    outln!("{}", out.report);
    outln!(
        "path: {} cells, {} waypoints, length {:.3} {}, duration {:.2} s",
        out.cells.len(),
        out.waypoints.len(),
        out.length,
        mf.units(),
        out.duration
    );
    if checked {
        outln!("{}", check_report(&mf, &plan));
    }
    if plan.status == PlanStatus::LocalMinimum {
        return goal_not_reached(format!(
            "the potential-field descent is stuck: {}",
            plan.report
        ));
    }
    if !plan.colliding.is_empty() {
        return goal_not_reached(check_report(&mf, &plan));
    }
    Ok(())
}

/// One line on the `--check-footprint` check of `plan`'s timed path.
fn check_report(mf: &MapFrame<'_>, plan: &Plan) -> String {
    match plan.colliding.first() {
        None => format!(
            "--check-footprint: the polygon clears the obstacles at all {} poses of the \
             timed path",
            plan.trajectory.len()
        ),
        Some(&first) => format!(
            "--check-footprint: the polygon meets an obstacle cell along the timed path, \
             with its origin in {} cell(s), the first {}",
            plan.colliding.len(),
            mf.describe(first)
        ),
    }
}

/// The platform limits of the stop-and-turn timing.
fn platform_limits(args: &PlanArgs) -> DiffDriveLimits {
    DiffDriveLimits {
        v_max: args.v_max,
        omega_max: args.omega_max,
        a_max: args.a_max,
        alpha_max: args.alpha_max,
    }
}

/// The `path.json` document of a plan.
fn plan_output(
    args: &PlanArgs,
    mf: &MapFrame<'_>,
    request: &PlanRequest,
    robot: serde_json::Value,
    plan: &Plan,
) -> PlanOutput {
    let waypoints = plan.waypoints.clone();
    let length: f64 = waypoints
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum();
    PlanOutput {
        map: args.map.display().to_string(),
        frame: if mf.world() { "world" } else { "cells" },
        algorithm: args.algo,
        status: plan.outcome(),
        report: plan.report.clone(),
        start: request.start,
        goal: request.goal,
        start_cell: [plan.start_cell.0, plan.start_cell.1],
        goal_cell: [plan.goal_cell.0, plan.goal_cell.1],
        robot,
        // in map units (m on ROS maps)
        cost: plan.cost_cells.map(|c| mf.cells_to_units(c)),
        length,
        expanded: plan.expanded,
        cells: plan.cells.iter().map(|c| [c.0, c.1]).collect(),
        headings: plan.headings.clone(),
        waypoints,
        limits: platform_limits(args),
        duration: plan.trajectory.last().map_or(0.0, |p| p.t),
        trajectory: plan.trajectory.clone(),
    }
}

/// Writes `--output` and `--svg`, both or neither.
fn write_outputs(args: &PlanArgs, mf: &MapFrame<'_>, plan: &Plan, out: &PlanOutput) -> Result<()> {
    let mut files = Vec::new();
    if let Some(p) = &args.output {
        let mut text = serde_json::to_string_pretty(out)?;
        text.push('\n');
        files.push((p.clone(), text.into_bytes()));
    }
    if let Some(p) = &args.svg {
        let blocked = plan.cspace.obstacles();
        let scene = Scene {
            grid: mf.grid,
            cspace: &blocked,
            path: &plan.cells,
            smooth: &plan.smoothed,
            start: plan.start_cell,
            goal: plan.goal_cell,
            title: format!("{:?} on {}\n{}", args.algo, args.map.display(), plan.report),
        };
        files.push((p.clone(), render(&scene)?.into_bytes()));
    }
    write_all_atomic(&files)
}

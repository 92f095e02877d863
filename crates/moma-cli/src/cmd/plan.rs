//! `moma plan`: plan a path on an occupancy map (ROS map in world coordinates, Moving AI
//! map in cells), smooth it and time-parameterise it for a differential drive.
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
use moma::planning::costmap::{self, Footprint, InflationParams};
use moma::planning::dstar_lite::DStarLite;
use moma::planning::potential::{DescentEnd, GoalTerm, PotentialParams, descend, potential_field};
use moma::planning::smooth::smooth;
use moma::planning::trajectory::{DiffDriveLimits, TrajectoryPoint, time_parameterize};
use moma::planning::{MapKind, OccupancyGrid, SearchGrid, astar, load_map};
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
    /// Polygonal footprint `x1,y1;x2,y2;...` or `[[x1,y1],...]` in the robot frame
    /// (m, or cells); plans over (x, y, heading) with 8 headings (A* only).
    #[arg(long, allow_hyphen_values = true)]
    pub footprint: Option<String>,
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
    #[arg(long, default_value_t = 0.5)]
    pub v_max: f64,
    /// Maximum turn rate (rad/s).
    #[arg(long, default_value_t = 1.0)]
    pub omega_max: f64,
    /// Maximum linear acceleration.
    #[arg(long, default_value_t = 0.5)]
    pub a_max: f64,
    /// Maximum angular acceleration (rad/s²).
    #[arg(long, default_value_t = 2.0)]
    pub alpha_max: f64,
    /// Trajectory sampling period (s).
    #[arg(long, default_value_t = 0.1)]
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

/// The map and the frame the user's coordinates are in.
struct MapFrame {
    grid: OccupancyGrid,
    /// ROS map: coordinates and lengths in world metres; Moving AI: in cells.
    world: bool,
}

impl MapFrame {
    /// A length in map units (m or cells) in cells.
    fn units_to_cells(&self, v: f64) -> f64 {
        if self.world {
            v / self.grid.resolution
        } else {
            v
        }
    }

    /// A length in cells in map units.
    fn cells_to_units(&self, v: f64) -> f64 {
        if self.world {
            v * self.grid.resolution
        } else {
            v
        }
    }

    fn units(&self) -> &'static str {
        if self.world { "m" } else { "cells" }
    }

    /// A cell named in the user's frame: `(x, y) m (cell (i, j))` on a ROS map (world
    /// coordinates of the cell centre), `cell (i, j)` on a Moving AI map.
    fn describe(&self, c: (usize, usize)) -> String {
        if self.world {
            let [x, y] = self.grid.cell_to_world(c.0 as f64, c.1 as f64);
            format!("({x:.3}, {y:.3}) m (cell ({}, {}))", c.0, c.1)
        } else {
            format!("cell ({}, {})", c.0, c.1)
        }
    }

    /// The cell of a point given in the user's frame.
    fn cell_of(&self, what: &str, x: f64, y: f64) -> Result<(usize, usize)> {
        let g = &self.grid;
        if self.world {
            return Ok(g.world_to_cell(what, x, y)?);
        }
        if x < 0.0
            || y < 0.0
            || x.fract() != 0.0
            || y.fract() != 0.0
            || x >= g.width as f64
            || y >= g.height as f64
        {
            bail!(
                "--{what}: ({}, {}) must be a cell of the {} x {} map (integers from 0)",
                short(x),
                short(y),
                g.width,
                g.height
            );
        }
        Ok((x as usize, y as usize))
    }
}

/// Refuses NaN and ±inf in every numeric option, naming the option (the library's
/// range checks name its own parameter, e.g. `v_max`).
fn check_finite_options(args: &PlanArgs) -> Result<()> {
    let opt = |x: Option<f64>| x.unwrap_or(0.0);
    for (name, v) in [
        ("--resolution", opt(args.resolution)),
        ("--radius", opt(args.radius)),
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

/// A number for a message: plain when moderate, in exponent form when huge or tiny (so
/// 1e308 does not print 309 digits).
fn short(x: f64) -> String {
    if x == 0.0 || (1e-4..1e6).contains(&x.abs()) || !x.is_finite() {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// Start and goal, checked against the raw map.
struct Endpoints {
    start_xy: [f64; 2],
    start_yaw: Option<f64>,
    goal_xy: [f64; 2],
    start: (usize, usize),
    goal: (usize, usize),
}

fn endpoints(args: &PlanArgs, mf: &MapFrame, obst: &[bool]) -> Result<Endpoints> {
    let (sx, sy, start_yaw) = parse_xy("start", &args.start)?;
    let (gx, gy, _) = parse_xy("goal", &args.goal)?;
    let start = mf.cell_of("start", sx, sy)?;
    let goal = mf.cell_of("goal", gx, gy)?;
    let w = mf.grid.width;
    for (what, c) in [("start", start), ("goal", goal)] {
        if obst[c.1 * w + c.0] {
            let kind = if mf.grid.cells[c.1 * w + c.0] < 0 {
                "an unknown cell (use --unknown free to allow)"
            } else {
                "an obstacle"
            };
            bail!("{what} at {} lies in {kind}", mf.describe(c));
        }
    }
    Ok(Endpoints {
        start_xy: [sx, sy],
        start_yaw,
        goal_xy: [gx, gy],
        start,
        goal,
    })
}

/// What a search found, in cells.
struct Found {
    cells: Vec<(usize, usize)>,
    /// In cells (potentials: None when stuck).
    cost_cells: Option<f64>,
    expanded: usize,
    status: &'static str,
    report: String,
    headings: Option<Vec<f64>>,
    /// The grid the path lives on (smoothing and the SVG's C-space band).
    sg: SearchGrid,
}

/// Disk (or point) configuration space; start and goal must be clear of it.
fn disk_cspace(
    args: &PlanArgs,
    mf: &MapFrame,
    obst: &[bool],
    ends: &Endpoints,
    robot: &mut serde_json::Value,
) -> Result<SearchGrid> {
    let (w, h) = (mf.grid.width, mf.grid.height);
    let radius_cells = match args.radius {
        Some(r) => {
            if !(r.is_finite() && r >= 0.0) {
                bail!("--radius must be a finite non-negative number, got {r}");
            }
            *robot = serde_json::json!({ "kind": "disk", "radius": r });
            mf.units_to_cells(r)
        }
        None => 0.0,
    };
    let cspace = costmap::inflate(obst, w, h, radius_cells)?;
    let sg = SearchGrid::from_obstacles(&cspace, w, h)?;
    for (what, c) in [("start", ends.start), ("goal", ends.goal)] {
        if !sg.is_free(c.0 as i64, c.1 as i64) {
            bail!(
                "{what} at {} is closer than the robot radius (--radius) {} {} to an obstacle (inside the configuration-space obstacle)",
                mf.describe(c),
                short(args.radius.unwrap_or(0.0)),
                mf.units()
            );
        }
    }
    Ok(sg)
}

/// A* over (x, y, 8 headings) for a polygonal footprint.
fn search_footprint(
    args: &PlanArgs,
    mf: &MapFrame,
    obst: &[bool],
    ends: &Endpoints,
    fp_text: &str,
    robot: &mut serde_json::Value,
) -> Result<Found> {
    if args.algo != Algo::Astar || args.cost_aware {
        bail!("--footprint works with --algo astar (without --cost-aware)");
    }
    let (w, h) = (mf.grid.width, mf.grid.height);
    let fp = Footprint::parse(fp_text).context("--footprint")?;
    *robot = serde_json::json!({ "kind": "polygon", "vertices": fp.vertices });
    let fp_cells = Footprint::new(
        fp.vertices
            .iter()
            .map(|v| [mf.units_to_cells(v[0]), mf.units_to_cells(v[1])])
            .collect(),
    )?;
    let cs = costmap::footprint_cspace(obst, w, h, 1.0, &fp_cells, 8)?;
    let yaw = ends.start_yaw.unwrap_or(0.0) - if mf.world { mf.grid.origin[2] } else { 0.0 };
    let k = ((yaw / std::f64::consts::FRAC_PI_4).round() as i64).rem_euclid(8) as usize;
    let start = (ends.start.0, ends.start.1, k);
    let Some(p) = costmap::astar_footprint(&cs, start, ends.goal, args.turn_cost)? else {
        bail!(
            "no path from the start at {} to the goal at {}: the footprint cannot reach the goal at any sequence of headings (explored the whole reachable (x, y, heading) space); the robot may be larger than the passages",
            mf.describe(ends.start),
            mf.describe(ends.goal)
        );
    };
    // A cell is free for smoothing and drawing when it is free at every heading.
    let all_free = cs.slices.iter().fold(vec![true; w * h], |acc, s| {
        acc.iter().zip(s).map(|(a, b)| *a && *b).collect()
    });
    Ok(Found {
        cells: p.states.iter().map(|s| (s.0, s.1)).collect(),
        cost_cells: Some(p.cost),
        expanded: p.expanded,
        status: "found",
        report: format!(
            "found a path for the footprint (cost {:.3} {}, {} states expanded)",
            mf.cells_to_units(p.cost),
            mf.units(),
            p.expanded
        ),
        headings: Some(
            p.states
                .iter()
                .map(|s| s.2 as f64 * std::f64::consts::FRAC_PI_4)
                .collect(),
        ),
        sg: SearchGrid::from_obstacles(&all_free, w, h)?,
    })
}

/// The nav2-style inflation-cost grid of `--cost-aware`.
fn cost_aware_grid(
    args: &PlanArgs,
    mf: &MapFrame,
    obst: &[bool],
    robot: &mut serde_json::Value,
) -> Result<SearchGrid> {
    if args.algo != Algo::Astar {
        bail!("--cost-aware works with --algo astar");
    }
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
    let g = &mf.grid;
    let params = InflationParams {
        inscribed_radius: args.radius.unwrap_or(0.0),
        inflation_radius: args
            .inflation_radius
            .unwrap_or(if mf.world { 0.55 } else { 11.0 }),
        cost_scaling_factor: args
            .cost_scaling
            .unwrap_or(if mf.world { 10.0 } else { 0.5 }),
    };
    let unknown: Vec<bool> = g.cells.iter().map(|&v| v < 0).collect();
    let res = if mf.world { g.resolution } else { 1.0 };
    let costs = costmap::inflation_layer(obst, Some(&unknown), g.width, g.height, res, &params)?;
    robot["inflation"] = serde_json::to_value(params)?;
    Ok(SearchGrid::from_costs(
        &costs,
        g.width,
        g.height,
        args.cost_multiplier,
        args.unknown == Unknown::Free,
    )?)
}

/// A* or D* Lite over `sg`.
fn search_graph(args: &PlanArgs, mf: &MapFrame, ends: &Endpoints, sg: SearchGrid) -> Result<Found> {
    let (start, goal) = (ends.start, ends.goal);
    let (path, expanded) = if args.algo == Algo::Astar {
        let p = astar(&sg, start, goal)?;
        let e = p.as_ref().map_or(0, |p| p.expanded);
        (p.map(|p| (p.cells, p.cost)), e)
    } else {
        let mut d = DStarLite::new(&sg, start, goal)?;
        let c = d.compute();
        (c.and_then(|c| d.path().map(|p| (p, c))), d.expanded())
    };
    let Some((cells, cost)) = path else {
        let why = match args.radius {
            Some(r) => format!(
                "for a robot of radius {r} {} (the inflated obstacles close every passage between them)",
                mf.units()
            ),
            None => "(they lie in disconnected free regions)".into(),
        };
        bail!(
            "no path: the goal at {} is not reachable from the start at {} {why}",
            mf.describe(goal),
            mf.describe(start)
        );
    };
    Ok(Found {
        cells,
        cost_cells: Some(cost),
        expanded,
        status: "found",
        report: format!(
            "found a path of cost {:.3} {} ({expanded} cells expanded)",
            mf.cells_to_units(cost),
            mf.units()
        ),
        headings: None,
        sg,
    })
}

/// Steepest descent of a potential field over `sg`.
fn search_potential(
    args: &PlanArgs,
    mf: &MapFrame,
    ends: &Endpoints,
    sg: SearchGrid,
) -> Result<Found> {
    let term = if args.algo == Algo::Potential {
        GoalTerm::Euclidean
    } else {
        GoalTerm::Geodesic
    };
    let params = PotentialParams {
        goal_weight: args.goal_weight,
        influence: args.influence.map(|r| mf.units_to_cells(r)).unwrap_or(5.0),
    };
    let field = potential_field(&sg, ends.goal, term, &params)?;
    let d = descend(&sg, &field, ends.start)?;
    let mut report = d.report();
    let status = match d.end {
        DescentEnd::Reached => "found",
        DescentEnd::LocalMinimum { cell, .. } => {
            if mf.world {
                report.push_str(&format!(" (the minimum is at {})", mf.describe(cell)));
            }
            "local_minimum"
        }
        DescentEnd::Unreachable => bail!(
            "no path from the start at {} to the goal at {}: {report}",
            mf.describe(ends.start),
            mf.describe(ends.goal)
        ),
    };
    let cost_cells = (status == "found").then(|| moma::planning::smooth::polyline_length(&d.cells));
    Ok(Found {
        cells: d.cells,
        cost_cells,
        expanded: 0,
        status,
        report,
        headings: None,
        sg,
    })
}

/// Runs the subcommand. A potential field stuck in a local minimum still writes its
/// outputs (status `local_minimum`), then ends in `GoalNotReached` (exit status 3).
pub fn run(args: Args) -> Result<()> {
    let args = *args.inner;
    check_finite_options(&args)?;
    let loaded = load_map(&args.map, args.resolution)?;
    let world = loaded.grid.kind == MapKind::Ros;
    let mf = MapFrame {
        grid: loaded.grid,
        world,
    };
    let (w, h) = (mf.grid.width, mf.grid.height);
    let obst = mf
        .grid
        .obstacle_mask(100, args.unknown == Unknown::Obstacle);
    // validates the map size for the searches before anything else is built
    SearchGrid::from_obstacles(&obst, w, h)?;
    let ends = endpoints(&args, &mf, &obst)?;
    let mut robot = serde_json::json!({ "kind": "point" });
    let sg = disk_cspace(&args, &mf, &obst, &ends, &mut robot)?;
    let found = match (&args.footprint, args.algo) {
        (Some(fp), _) => search_footprint(&args, &mf, &obst, &ends, fp, &mut robot)?,
        (None, Algo::Astar | Algo::DstarLite) => {
            let sg = if args.cost_aware {
                cost_aware_grid(&args, &mf, &obst, &mut robot)?
            } else {
                sg
            };
            search_graph(&args, &mf, &ends, sg)?
        }
        (None, Algo::Potential | Algo::PotentialGeodesic) => {
            search_potential(&args, &mf, &ends, sg)?
        }
    };
    let out = plan_output(&args, &mf, &ends, robot, &found)?;
    write_outputs(&args, &mf, &ends, &found, &out)?;
    outln!("{}", out.report);
    outln!(
        "path: {} cells, {} waypoints, length {:.3} {}, duration {:.2} s",
        out.cells.len(),
        out.waypoints.len(),
        out.length,
        mf.units(),
        out.duration
    );
    if found.status == "local_minimum" {
        return goal_not_reached(format!(
            "the potential-field descent is stuck: {}",
            found.report
        ));
    }
    Ok(())
}

/// Smooths and time-parameterises the path and fills the `path.json` document.
fn plan_output(
    args: &PlanArgs,
    mf: &MapFrame,
    ends: &Endpoints,
    robot: serde_json::Value,
    found: &Found,
) -> Result<PlanOutput> {
    let limits = DiffDriveLimits {
        v_max: args.v_max,
        omega_max: args.omega_max,
        a_max: args.a_max,
        alpha_max: args.alpha_max,
    };
    let smoothed = smoothed_cells(args, found);
    let to_world = |c: &(usize, usize)| mf.grid.cell_to_world(c.0 as f64, c.1 as f64);
    let waypoints: Vec<[f64; 2]> = smoothed.iter().map(to_world).collect();
    let trajectory = time_parameterize(&waypoints, ends.start_yaw, &limits, args.dt)?;
    let duration = trajectory.last().map_or(0.0, |p| p.t);
    let length: f64 = waypoints
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum();
    Ok(PlanOutput {
        map: args.map.display().to_string(),
        frame: if mf.world { "world" } else { "cells" },
        algorithm: args.algo,
        status: found.status,
        report: found.report.clone(),
        start: ends.start_xy,
        goal: ends.goal_xy,
        start_cell: [ends.start.0, ends.start.1],
        goal_cell: [ends.goal.0, ends.goal.1],
        robot,
        // in map units (m on ROS maps)
        cost: found.cost_cells.map(|c| mf.cells_to_units(c)),
        length,
        expanded: found.expanded,
        cells: found.cells.iter().map(|c| [c.0, c.1]).collect(),
        headings: found.headings.clone(),
        waypoints,
        limits,
        duration,
        trajectory,
    })
}

fn smoothed_cells(args: &PlanArgs, found: &Found) -> Vec<(usize, usize)> {
    if args.no_smooth || found.headings.is_some() {
        compress(&found.cells)
    } else {
        smooth(&found.sg, &found.cells)
    }
}

/// Writes `--output` and `--svg`, both or neither.
fn write_outputs(
    args: &PlanArgs,
    mf: &MapFrame,
    ends: &Endpoints,
    found: &Found,
    out: &PlanOutput,
) -> Result<()> {
    let mut files = Vec::new();
    if let Some(p) = &args.output {
        let mut text = serde_json::to_string_pretty(out)?;
        text.push('\n');
        files.push((p.clone(), text.into_bytes()));
    }
    if let Some(p) = &args.svg {
        let blocked = found.sg.obstacles();
        let smoothed = smoothed_cells(args, found);
        let scene = Scene {
            grid: &mf.grid,
            cspace: &blocked,
            path: &found.cells,
            smooth: &smoothed,
            start: ends.start,
            goal: ends.goal,
            title: format!(
                "{:?} on {}\n{}",
                args.algo,
                args.map.display(),
                found.report
            ),
        };
        files.push((p.clone(), render(&scene)?.into_bytes()));
    }
    write_all_atomic(&files)
}

/// Keeps only the cells where the direction changes (and repeated cells, i.e. turns).
fn compress(cells: &[(usize, usize)]) -> Vec<(usize, usize)> {
    let mut out: Vec<(usize, usize)> = Vec::new();
    for (i, &c) in cells.iter().enumerate() {
        if i == 0 || i == cells.len() - 1 {
            out.push(c);
            continue;
        }
        let (p, n) = (cells[i - 1], cells[i + 1]);
        let d1 = (c.0 as i64 - p.0 as i64, c.1 as i64 - p.1 as i64);
        let d2 = (n.0 as i64 - c.0 as i64, n.1 as i64 - c.1 as i64);
        if d1 != d2 && out.last() != Some(&c) {
            out.push(c);
        }
    }
    out
}

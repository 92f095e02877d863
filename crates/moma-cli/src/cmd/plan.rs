//! `moma plan`: plan a path on an occupancy map (ROS map in world coordinates, Moving AI
//! map in cells), smooth it and time-parameterise it for a differential drive.
//!
//! Output (`--output path.json`, schema in docs/planning.md): status, cost, the grid
//! path, the smoothed waypoints and the reference trajectory. A search that finds no
//! path is an error (non-zero exit, no file written) whose message gives the reason. A
//! potential-field descent stuck in a local minimum writes its outputs with
//! `"status": "local_minimum"` (so the trap can be inspected) and exits with code 3 (2 is a malformed command line).

use crate::output::{write_all_atomic, write_atomic, write_json};
use crate::svg_map::{Scene, render};
use anyhow::{Context, Result, bail};
use moma::planning::costmap::{self, Footprint, InflationParams};
use moma::planning::dstar_lite::DStarLite;
use moma::planning::potential::{DescentEnd, GoalTerm, PotentialParams, descend, potential_field};
use moma::planning::smooth::smooth;
use moma::planning::trajectory::{DiffDriveLimits, TrajectoryPoint, time_parameterize};
use moma::planning::{MapKind, SearchGrid, astar, load_map};
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

/// Runs the subcommand.
pub fn run(args: Args) -> Result<()> {
    let args = *args.inner;
    let loaded = load_map(&args.map, args.resolution)?;
    let grid = loaded.grid;
    let world = grid.kind == MapKind::Ros;
    // Lengths given in map units → cells.
    let to_cells = |v: f64| if world { v / grid.resolution } else { v };
    let (sx, sy, syaw) = parse_xy("start", &args.start)?;
    let (gx, gy, _) = parse_xy("goal", &args.goal)?;
    let cell_of = |what: &str, x: f64, y: f64| -> Result<(usize, usize)> {
        if world {
            Ok(grid.world_to_cell(what, x, y)?)
        } else {
            if x < 0.0
                || y < 0.0
                || x.fract() != 0.0
                || y.fract() != 0.0
                || x >= grid.width as f64
                || y >= grid.height as f64
            {
                bail!(
                    "{what} ({x}, {y}) must be a cell of the {} x {} map (integers from 0)",
                    grid.width,
                    grid.height
                );
            }
            Ok((x as usize, y as usize))
        }
    };
    let start = cell_of("start", sx, sy)?;
    let goal = cell_of("goal", gx, gy)?;
    let obst = grid.obstacle_mask(100, args.unknown == Unknown::Obstacle);
    let raw_grid = SearchGrid::from_obstacles(&obst, grid.width, grid.height)?;
    for (what, c) in [("start", start), ("goal", goal)] {
        if !raw_grid.is_free(c.0 as i64, c.1 as i64) {
            let kind = if grid.cells[c.1 * grid.width + c.0] < 0 {
                "an unknown cell (use --unknown free to allow)"
            } else {
                "an obstacle"
            };
            bail!("{what} ({}, {}) lies in {kind}", c.0, c.1);
        }
    }
    let limits = DiffDriveLimits {
        v_max: args.v_max,
        omega_max: args.omega_max,
        a_max: args.a_max,
        alpha_max: args.alpha_max,
    };
    let mut robot = serde_json::json!({ "kind": "point" });
    let units = if world { "m" } else { "cells" };

    // Configuration space.
    let radius_cells = match args.radius {
        Some(r) => {
            if !(r.is_finite() && r >= 0.0) {
                bail!("--radius must be a finite non-negative number, got {r}");
            }
            robot = serde_json::json!({ "kind": "disk", "radius": r });
            to_cells(r)
        }
        None => 0.0,
    };
    let cspace = costmap::inflate(&obst, grid.width, grid.height, radius_cells)?;
    let mut sg = SearchGrid::from_obstacles(&cspace, grid.width, grid.height)?;
    let clearance_msg = |what: &str, c: (usize, usize)| {
        format!(
            "{what} ({}, {}) is closer than the robot radius {} {units} to an obstacle (inside the configuration-space obstacle)",
            c.0,
            c.1,
            args.radius.unwrap_or(0.0)
        )
    };
    for (what, c) in [("start", start), ("goal", goal)] {
        if !sg.is_free(c.0 as i64, c.1 as i64) {
            bail!(clearance_msg(what, c));
        }
    }

    let mut headings = None;
    let (cells, cost, expanded, status, report) = if let Some(fp_text) = &args.footprint {
        if args.algo != Algo::Astar || args.cost_aware {
            bail!("--footprint works with --algo astar (without --cost-aware)");
        }
        let fp = Footprint::parse(fp_text).context("--footprint")?;
        robot = serde_json::json!({ "kind": "polygon", "vertices": fp.vertices });
        let fp_cells = Footprint::new(
            fp.vertices
                .iter()
                .map(|v| [to_cells(v[0]), to_cells(v[1])])
                .collect(),
        )?;
        let cs = costmap::footprint_cspace(&obst, grid.width, grid.height, 1.0, &fp_cells, 8)?;
        let yaw = syaw.unwrap_or(0.0) - if world { grid.origin[2] } else { 0.0 };
        let k = ((yaw / std::f64::consts::FRAC_PI_4).round() as i64).rem_euclid(8) as usize;
        let path = costmap::astar_footprint(&cs, (start.0, start.1, k), goal, args.turn_cost)?;
        let Some(p) = path else {
            bail!(
                "no path: the footprint cannot reach the goal from the start at any sequence of headings (explored the whole reachable (x, y, heading) space); the robot may be larger than the passages"
            );
        };
        // One cell per state, keeping the heading changes as repeated cells.
        sg = SearchGrid::from_obstacles(
            &cs.slices
                .iter()
                .fold(vec![true; grid.width * grid.height], |acc, s| {
                    acc.iter().zip(s).map(|(a, b)| *a && *b).collect()
                }),
            grid.width,
            grid.height,
        )?;
        headings = Some(
            p.states
                .iter()
                .map(|s| s.2 as f64 * std::f64::consts::FRAC_PI_4)
                .collect::<Vec<_>>(),
        );
        let cells: Vec<(usize, usize)> = p.states.iter().map(|s| (s.0, s.1)).collect();
        (
            cells,
            Some(p.cost),
            p.expanded,
            "found",
            format!(
                "found a path for the footprint (cost {:.3} {units}, {} states expanded)",
                if world {
                    p.cost * grid.resolution
                } else {
                    p.cost
                },
                p.expanded
            ),
        )
    } else {
        match args.algo {
            Algo::Astar | Algo::DstarLite => {
                if args.cost_aware {
                    if args.algo != Algo::Astar {
                        bail!("--cost-aware works with --algo astar");
                    }
                    let res = if world { grid.resolution } else { 1.0 };
                    let params = InflationParams {
                        inscribed_radius: args.radius.unwrap_or(0.0),
                        inflation_radius: args.inflation_radius.unwrap_or(if world {
                            0.55
                        } else {
                            11.0
                        }),
                        cost_scaling_factor: args.cost_scaling.unwrap_or(if world {
                            10.0
                        } else {
                            0.5
                        }),
                    };
                    let unknown: Vec<bool> = grid.cells.iter().map(|&v| v < 0).collect();
                    let costs = costmap::inflation_layer(
                        &obst,
                        Some(&unknown),
                        grid.width,
                        grid.height,
                        res,
                        &params,
                    )?;
                    sg = SearchGrid::from_costs(
                        &costs,
                        grid.width,
                        grid.height,
                        args.cost_multiplier,
                        args.unknown == Unknown::Free,
                    )?;
                    robot["inflation"] = serde_json::to_value(params)?;
                }
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
                    bail!(
                        "no path: the goal is not reachable from the start{}",
                        if args.radius.is_some() {
                            format!(
                                " for a robot of radius {} {units} (the inflated obstacles close every passage between them)",
                                args.radius.unwrap_or(0.0)
                            )
                        } else {
                            " (they lie in disconnected free regions)".into()
                        }
                    );
                };
                (
                    cells,
                    Some(cost),
                    expanded,
                    "found",
                    format!(
                        "found a path of cost {:.3} {units} ({expanded} cells expanded)",
                        if world { cost * grid.resolution } else { cost }
                    ),
                )
            }
            Algo::Potential | Algo::PotentialGeodesic => {
                let term = if args.algo == Algo::Potential {
                    GoalTerm::Euclidean
                } else {
                    GoalTerm::Geodesic
                };
                let params = PotentialParams {
                    goal_weight: args.goal_weight,
                    influence: args.influence.map(to_cells).unwrap_or(5.0),
                };
                let field = potential_field(&sg, goal, term, &params)?;
                let d = descend(&sg, &field, start)?;
                let status = match d.end {
                    DescentEnd::Reached => "found",
                    DescentEnd::LocalMinimum { .. } => "local_minimum",
                    DescentEnd::Unreachable => bail!("no path: {}", d.report()),
                };
                let cost = (status == "found").then(|| {
                    moma::planning::smooth::polyline_length(&d.cells)
                        * if world { grid.resolution } else { 1.0 }
                });
                let report = d.report();
                (d.cells, cost, 0, status, report)
            }
        }
    };

    // Report costs in map units (m on ROS maps).
    let cost = cost.map(|c| {
        if world
            && status == "found"
            && args.algo != Algo::Potential
            && args.algo != Algo::PotentialGeodesic
        {
            c * grid.resolution
        } else {
            c
        }
    });
    let smoothed = if args.no_smooth || headings.is_some() {
        compress(&cells)
    } else {
        smooth(&sg, &cells)
    };
    let to_world = |c: &(usize, usize)| grid.cell_to_world(c.0 as f64, c.1 as f64);
    let waypoints: Vec<[f64; 2]> = smoothed.iter().map(to_world).collect();
    let yaw0 = syaw;
    let trajectory = time_parameterize(&waypoints, yaw0, &limits, args.dt)?;
    let duration = trajectory.last().map_or(0.0, |p| p.t);
    let length: f64 = waypoints
        .windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum();
    let out = PlanOutput {
        map: args.map.display().to_string(),
        frame: if world { "world" } else { "cells" },
        algorithm: args.algo,
        status,
        report: report.clone(),
        start: [sx, sy],
        goal: [gx, gy],
        start_cell: [start.0, start.1],
        goal_cell: [goal.0, goal.1],
        robot,
        cost,
        length,
        expanded,
        cells: cells.iter().map(|c| [c.0, c.1]).collect(),
        headings,
        waypoints,
        limits,
        duration,
        trajectory,
    };
    let mut files = Vec::new();
    if let Some(p) = &args.output {
        let mut text = serde_json::to_string_pretty(&out)?;
        text.push('\n');
        files.push((p.clone(), text.into_bytes()));
    }
    if let Some(p) = &args.svg {
        let blocked = sg.obstacles();
        let scene = Scene {
            grid: &grid,
            cspace: &blocked,
            path: &cells,
            smooth: &smoothed,
            start,
            goal,
            title: format!("{:?} on {}: {}", args.algo, args.map.display(), report),
        };
        files.push((p.clone(), render(&scene)?.into_bytes()));
    }
    match (&args.output, files.len()) {
        (_, 0) => {}
        (Some(p), 1) => write_json(p, &out)?,
        (None, 1) => write_atomic(&files[0].0, &files[0].1)?,
        _ => write_all_atomic(&files)?,
    }
    println!("{report}");
    println!(
        "path: {} cells, {} waypoints, length {length:.3} {units}, duration {duration:.2} s",
        out.cells.len(),
        out.waypoints.len()
    );
    if status == "local_minimum" {
        eprintln!("error: the potential-field descent is stuck: {report}");
        std::process::exit(3);
    }
    Ok(())
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

//! `moma`: the command-line front end of the moma library.
//!
//! Every subcommand lives in its own file under `cmd/`; this file only dispatches and
//! applies the one exit-status rule of `docs/cli.md`: 0 success, 1 error (one message
//! naming the file and field), 2 malformed command line (clap), 3 the command ran but
//! did not reach its goal ([`cmd::common::GoalNotReached`]). Outputs are written
//! atomically (`output.rs`), so a failed run leaves none behind.

#[macro_use]
mod output;
mod cmd;
mod report;
mod svg_heatmap;
mod svg_map;
mod svg_placement;
mod svg_plots;
mod svg_stability;

use clap::{Parser, Subcommand};

/// Kinematics, dynamics, simulation and motion planning of wheeled mobile manipulators.
#[derive(Parser)]
#[command(name = "moma", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Print a robot model's structure: nq, nv, mass, frames, joints.
    Inspect(cmd::inspect::Args),
    /// Evaluate rigid-body dynamics (RNEA, CRBA, ABA, ...) on a list of states.
    Dynamics(cmd::dynamics::Args),
    /// Signed distances between the robot's links and against a scene, per state.
    Collision(cmd::collision::Args),
    /// Plan a collision-free, timed motion of a joint group among a scene's obstacles.
    Motion(cmd::motion::Args),
    /// Run a folder of motion queries (e.g. MotionBenchMaker's Fetch scenes): success rate
    /// and planning-time percentiles.
    MotionBench(cmd::motion_bench::Args),
    /// Where to stand for a grasp: reachable, collision-free, upright base poses, ranked.
    Place(cmd::place::Args),
    /// Analytical derivatives of inverse and forward dynamics (dτ/dq, dτ/dv, M; dq̈/dq,
    /// dq̈/dv, M⁻¹) on a list of states.
    Derivatives(cmd::derivatives::Args),
    /// Time the rigid-body algorithms (median ns per call) on seeded random states.
    Bench(cmd::bench::Args),
    /// Evaluate the chapter's closed-form models (m1–m6) on a case file.
    Eval(cmd::eval::Args),
    /// Run a simulation scenario (TOML) and write CSV, JSON and SVG outputs.
    Simulate(cmd::simulate::Args),
    /// Print an occupancy map's size, resolution, origin and cell counts.
    MapInfo(cmd::map_info::Args),
    /// Run a mission: plan on a map, track in dynamic simulation, re-plan, reach; write the report.
    Mission(cmd::mission::Args),
    /// Plan a path on an occupancy map.
    Plan(cmd::plan::Args),
    /// Run every problem of a Moving AI scenario file and compare with the optimal lengths.
    Scen(cmd::scen::Args),
    /// Compute manipulability measures of a (mobile) manipulator on a list of states.
    Manipulability(cmd::manipulability::Args),
    /// Inverse kinematics: arm-only or whole-body.
    Ik(cmd::ik::Args),
    /// Evaluate reachability and manipulability over a grid of base placements.
    ReachMap(cmd::reach_map::Args),
    /// Tip-over stability (ZMP, Force-Angle, Moment-Height) on a list of states.
    Stability(cmd::stability::Args),
    /// Polar plot of the tip-over acceleration limits and a ZMP-margin map over two joints.
    StabilityMap(cmd::stability_map::Args),
    /// Operational-space control quantities (Λ, J̄, N, J̇q̇, F, τ) of a frame on a list of states.
    Osc(cmd::osc::Args),
    /// Free-floating (space) robot: base motion from joint rates, generalized Jacobian and inertia.
    Space(cmd::space::Args),
    /// Render a mission's report.html and SVG figures from a saved MissionReport (JSON).
    #[command(hide = true)]
    RenderReport(cmd::render_report::Args),
    /// Sweep a stability, placement, mission, uncertainty or lift-off study over a grid
    /// or a seeded random sample (or one shard of it) into one CSV table; `moma sweep
    /// merge` joins shard tables.
    Sweep(cmd::sweep::Args),
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Inspect(a) => cmd::inspect::run(a),
        Command::Dynamics(a) => cmd::dynamics::run(a),
        Command::Derivatives(a) => cmd::derivatives::run(a),
        Command::Bench(a) => cmd::bench::run(a),
        Command::Collision(a) => cmd::collision::run(a),
        Command::Motion(a) => cmd::motion::run(a),
        Command::MotionBench(a) => cmd::motion_bench::run(a),
        Command::Place(a) => cmd::place::run(a),
        Command::Eval(a) => cmd::eval::run(a),
        Command::Simulate(a) => cmd::simulate::run(a),
        Command::MapInfo(a) => cmd::map_info::run(a),
        Command::Mission(a) => cmd::mission::run(a),
        Command::Plan(a) => cmd::plan::run(a),
        Command::Scen(a) => cmd::scen::run(a),
        Command::Manipulability(a) => cmd::manipulability::run(a),
        Command::Osc(a) => cmd::osc::run(a),
        Command::Ik(a) => cmd::ik::run(a),
        Command::ReachMap(a) => cmd::reach_map::run(a),
        Command::Stability(a) => cmd::stability::run(a),
        Command::StabilityMap(a) => cmd::stability_map::run(a),
        Command::Space(a) => cmd::space::run(a),
        Command::RenderReport(a) => cmd::render_report::run(a),
        Command::Sweep(a) => cmd::sweep::run(a),
    };
    if let Err(e) = result {
        if let Some(g) = e.downcast_ref::<cmd::common::GoalNotReached>() {
            eprintln!("goal not reached: {g}");
            std::process::exit(3);
        }
        eprintln!("error: {e:#}");
        std::process::exit(1);
    }
}

//! Motion planning on occupancy grids (chapter section 5.6).
//!
//! The pipeline: load a map ([`load_map`]: ROS `map_server` YAML + image, a bare
//! PGM/PNG, or a Moving AI `.map`), build the configuration space by dilating the
//! obstacles with the robot footprint ([`distance_transform`], [`costmap`]), search it
//! ([`astar()`], [`dstar_lite::DStarLite`] for re-planning, [`potential`] fields), then
//! turn the path into motion ([`smooth`], [`trajectory::time_parameterize`]).
//! 3-D voxel maps: [`Grid3`] and [`astar3d`].
//!
//! Arm motion in joint space, robot-independent (the planner sees only joint vectors and a
//! caller's [`StateValidity`] check): a [`JointSpace`] (joint-limit box, weighted norm,
//! segment-check resolution), [`rrt_connect()`], [`shortcut()`], then
//! [`time_optimal()`] (circular blends, velocity and acceleration limits).
//!
//! # How it is built
//!
//! * Loaders ([`rosmap`], [`movingai`]) produce an [`OccupancyGrid`] stored like
//!   `nav_msgs/OccupancyGrid` (row 0 at the bottom for ROS maps).
//! * The configuration space comes from one exact linear-time distance transform
//!   ([`edt`]): thresholding it gives disk dilation, a lookup gives nav2 inflation costs
//!   ([`costmap`]); polygonal footprints get per-heading masks.
//! * Searches run on a [`SearchGrid`] with a one-cell blocked border, reusable workspaces
//!   and generation counters ([`mod@astar`], [`dstar_lite`], [`grid3`]). The search grid keeps
//!   a one-byte legal-move mask per cell (8-connected, no corner cutting), updated by
//!   [`SearchGrid::set_free`] for the 3 × 3 block around a change; A* and D* Lite read only
//!   that byte to enumerate moves.
//! * Grid A* orders by an exact fixed-point integer f (straight step 2^k, diagonal √2·2^k
//!   rounded to an odd integer) in a calendar queue over A*'s bounded key window (a radix
//!   heap for the cost-aware search), f ties last-in-first-out, with a 4-byte g per cell
//!   (rerun on an 8-byte g when a cost outgrows 32 bits), and reports the length exactly
//!   as n_straight + n_diagonal·√2.
//! * D* Lite (Koenig and Likhachev's optimized version) uses the same integer costs, so
//!   its re-planned cost equals A* from scratch bit for bit; it keeps g and rhs per cell,
//!   an indexed 4-ary heap with each inconsistent cell once, re-keys stale keys in place
//!   (or in one linear pass once many are stale), and decides with a budgeted flood fill
//!   when the goal is cut off instead of expanding the rest of the map. `clone_from`
//!   snapshots a planner without allocating once the copy has reached the source's size.
//! * [`potential`] follows the chapter's formula in a Euclidean form (which can get stuck,
//!   and says where) and a geodesic form (no local minima; the proof is in its docs).
//! * [`smooth`] and [`trajectory`] turn a cell path into a differential-drive reference
//!   (t, x, y, θ, v, ω). [`curvature`] turns it into a path with continuous, bounded
//!   curvature between exact poses (pieces of linear curvature, sampled at every piece
//!   boundary so curvature is linear between samples), and
//!   [`trajectory::time_parameterize_curve`] times it by reachability analysis with every
//!   limit linear in the squared speeds; the tip-over limits enter as four plain numbers,
//!   so `planning` depends on nothing above `error`.
//! * [`pipeline`] is the one call of `moma plan` and the Python `plan` (map frame, point,
//!   disk or polygon footprint, search, smoothing, stop-and-turn timing).

pub mod astar;
pub mod costmap;
pub mod curvature;
pub mod curve_timing;
pub mod dstar_lite;
pub mod edt;
pub mod footprint_clearance;
pub mod grid;
pub mod grid3;
pub mod joint_space;
pub mod movingai;
pub mod pipeline;
pub mod potential;
pub mod render;
pub mod rosmap;
pub mod rrt_connect;
pub mod shortcut;
pub mod smooth;
pub mod time_optimal;
pub mod trajectory;

pub use astar::{AstarWorkspace, GridPath, SearchGrid, astar, astar_with, octile, wavefront};
pub use edt::{EdtWorkspace, distance_transform, distance_transform_into};
pub use grid::{CellCounts, MapKind, OccupancyGrid};
pub use grid3::{Astar3Workspace, Grid3, Path3, astar3d, astar3d_with};
pub use joint_space::{JointPath, JointSpace, StateValidity};
pub use movingai::{
    MovingAiScenario, Scen3Problem, ScenProblem, load_3dmap, load_3dscen, load_movingai_map,
};
pub use rosmap::{MapMode, RosMapMeta, load_image_map, load_ros_map};
pub use rrt_connect::{
    PlanLimit, PlanStats, Planned, RrtConnectOptions, RrtConnectWorkspace, rrt_connect,
};
pub use shortcut::{ShortcutOptions, shortcut};
pub use time_optimal::{JointLimits, JointTrajectory, TimingOptions, time_optimal};

use crate::{Error, Result};
use std::path::Path;

/// Most samples a timed trajectory or a sampled smooth path holds
/// ([`trajectory::time_parameterize`], [`trajectory::TimedPath::samples`],
/// [`curvature::SmoothPath`]; 48 bytes each: 480 MB). The count follows from the path
/// length, the limits and `dt`, all user input, so it is checked before anything is
/// allocated.
pub const MAX_TRAJECTORY_SAMPLES: usize = 10_000_000;

/// A loaded map with its ROS parameters (`None` for Moving AI maps).
#[derive(Debug, Clone, PartialEq)]
pub struct LoadedMap {
    /// The grid.
    pub grid: OccupancyGrid,
    /// The ROS map parameters, for YAML and bare-image maps.
    pub meta: Option<RosMapMeta>,
}

/// Loads a map, choosing the format by extension: `.yaml`/`.yml` (ROS map_server),
/// `.map` (Moving AI), anything else is read as a bare image (PGM, PNG) with the legacy
/// map_server defaults and `resolution` (default [`rosmap::DEFAULT_RESOLUTION`]).
pub fn load_map(path: &Path, resolution: Option<f64>) -> Result<LoadedMap> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    match ext.as_str() {
        "yaml" | "yml" => {
            if resolution.is_some() {
                return Err(Error::invalid(
                    "resolution",
                    "only applies to a bare image; a YAML map sets its own",
                ));
            }
            let (grid, meta) = load_ros_map(path)?;
            Ok(LoadedMap {
                grid,
                meta: Some(meta),
            })
        }
        "map" => {
            if resolution.is_some() {
                return Err(Error::invalid(
                    "resolution",
                    "only applies to a bare image; Moving AI maps are in cells",
                ));
            }
            Ok(LoadedMap {
                grid: load_movingai_map(path)?,
                meta: None,
            })
        }
        _ => {
            let (grid, meta) =
                load_image_map(path, resolution.unwrap_or(rosmap::DEFAULT_RESOLUTION))?;
            Ok(LoadedMap {
                grid,
                meta: Some(meta),
            })
        }
    }
}

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

pub mod astar;
pub mod costmap;
pub mod curvature;
pub mod dstar_lite;
pub mod edt;
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

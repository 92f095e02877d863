//! A `[task]`'s base goal: the best-ranked placement the base's planner reaches from the
//! start, chosen before the loop starts.

use std::time::Instant;

use super::plan::mission_planner;
use super::plant::start_configuration;
use super::reference::axle_pose;
use super::scenario::{GoalSpec, Mission};
use super::task::{PlacementChoice, Task, TaskResult};
use crate::error::Result;

/// Tolerances of the base at a task's placement (m, rad).
const PLACEMENT_TOLERANCE: [f64; 2] = [0.05, 0.05];

/// A `[task]`'s base goal: the best-ranked placement
/// ([`crate::motion::placement::place_base`], the arm at the transport posture) that the
/// base's planner reaches from the start (the footprint fits there and a path leads
/// there), with the task's record; or the start pose and the reason there is none.
pub(super) fn choose_placement(
    m: &Mission,
    task: &Task,
) -> Result<(GoalSpec, Option<TaskResult>, Option<String>)> {
    let clock = Instant::now();
    let f = &m.file;
    let posture = start_configuration(&m.robot, [0.0; 3], &m.transport);
    let placement = task.placements(&m.robot, &posture)?;
    let time_s = clock.elapsed().as_secs_f64();
    let goal_at =
        |pose: [f64; 3]| GoalSpec::base_pose(pose, PLACEMENT_TOLERANCE[0], PLACEMENT_TOLERANCE[1]);
    let mut result = TaskResult {
        object: task.object.clone(),
        scene_pose: task.scene_pose,
        placement: None,
        arm_plans: Vec::new(),
        payload: None,
        min_scene_distance: None,
        closest_scene_pair: None,
        min_self_distance: None,
        closest_self_pair: None,
        driving: None,
        support: task.support.clone(),
        drive_on_footprint_radius: None,
    };
    if let Some(reason) = placement.failure() {
        return Ok((
            goal_at(f.start.pose),
            Some(result),
            Some(format!("no placement for the pick: {reason}")),
        ));
    }
    let d = m.robot.base.drive.d;
    let s0 = axle_pose(f.start.pose, d);
    for (rank, c) in placement.candidates.iter().enumerate() {
        let g0 = axle_pose(c.base, d);
        let reached = mission_planner(m, &m.map.grid, &m.footprint, s0, g0);
        if let Ok((_, Some(_), _)) = reached {
            result.placement = Some(PlacementChoice {
                base: c.base,
                rank,
                candidates: placement.candidates.len(),
                score: c.score,
                manipulability: c.manipulability,
                clearance: c.clearance,
                tip_over_margin: c.tip_over_margin,
                counts: placement.counts,
                time_s,
            });
            return Ok((goal_at(c.base), Some(result), None));
        }
    }
    let n = placement.candidates.len();
    Ok((
        goal_at(f.start.pose),
        Some(result),
        Some(format!(
            "none of the {n} best placements that reach the grasp can be reached by the base: \
             the footprint does not fit there or no path leads there"
        )),
    ))
}

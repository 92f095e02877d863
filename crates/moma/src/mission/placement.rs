//! A `[task]`'s base goal: the best-ranked placement the base's planner reaches from the
//! start and, with a `[goal]`, that the drive on can leave holding the object, chosen
//! before the loop starts.

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
/// there) and, with a `[goal]`, that the drive on's planner accepts as its start: the
/// footprint that holds the object ([`Task::carrying_footprint`]) fits there on the drive
/// on's map (the placement search checks the robot at the transport posture in 3-D, the
/// drive on plans with the held object's outline on the ground, which may reach over
/// furniture the map blocks). With the task's record; or the start pose and the reason
/// there is none.
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
        min_box_distance: None,
        closest_box_pair: None,
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
    // the drive on's start check: its planner refuses a start where the footprint does
    // not fit (a path it does not find ends the run after the pick, naming what blocks)
    let drive_on = m.goal().zip(m.drive_on_map.as_ref());
    let (mut reached_count, mut cannot_leave) = (0, None);
    for (rank, c) in placement.candidates.iter().enumerate() {
        let g0 = axle_pose(c.base, d);
        let reached = mission_planner(m, &m.map.grid, &m.footprint, s0, g0);
        if !matches!(reached, Ok((_, Some(_), _))) {
            continue;
        }
        reached_count += 1;
        if let Some((goal, map)) = drive_on {
            let to = axle_pose(goal.pose, d);
            if let Err(e) = mission_planner(m, &map.grid, &task.carrying_footprint, g0, to) {
                cannot_leave = Some(e);
                continue;
            }
        }
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
    let n = placement.candidates.len();
    let reason = match cannot_leave {
        Some(e) => format!(
            "of the {n} best placements that reach the grasp the base reaches {reached_count}, \
             and the drive on holding '{}' can leave none: {e}",
            task.object
        ),
        None => format!(
            "none of the {n} best placements that reach the grasp can be reached by the \
             base: the footprint does not fit there or no path leads there"
        ),
    };
    Ok((goal_at(f.start.pose), Some(result), Some(reason)))
}

//! `moma mission`: the chapter end to end. A mission plans on an occupancy map's
//! configuration space, turns the path into a timed reference under the platform's
//! limits and the tip-over limits of its transport posture, tracks it in closed-loop
//! dynamic simulation of the URDF robot on its differential drive, re-plans with D* Lite
//! when obstacles appear, reaches an end-effector target at the goal, and monitors
//! stability, slip, limits, tracking, clearance and energy all along.
//!
//! | step | what runs |
//! | --- | --- |
//! | map → C-space | [`crate::planning::load_map`] plus the `[[map.boxes]]` and `[task]` scene objects the robot cannot pass under ([`heights`]), the distance transform, disk dilation by `footprint_radius` + ½ cell (with the robot's footprint polygon: by the largest disk about the axle inside it) |
//! | footprint polygon | every sample of a timed path checked with the polygon at its heading (the planning pipeline's check, [`crate::planning::footprint_clearance::PathCheck`]); colliding cells blocked and re-planned, the circumscribed disk as the fallback |
//! | search | [`crate::planning::dstar_lite::DStarLite`] from the start pose's cell to the goal's cell |
//! | path → motion | curvature-bounded smoothing from the exact start pose to the exact goal pose ([`crate::planning::curvature::smooth_diff_drive`]), then near time-optimal timing under v, ω, a, α and the tip-over accelerations ([`crate::stability::acceleration_limits`] of the transport posture, times `tip_fraction`; [`crate::planning::trajectory::time_parameterize_curve`]), re-plans continuing from the current speed |
//! | off-axle base (`d ≠ 0`) | search, smoothing, timing and Kanayama work on the driven-axle midpoint (base pose − d·heading), the unicycle point whose speed and yaw rate are the reduced platform inputs; its C-space is dilated by `footprint_radius + |d|` (the footprint disk about the base frame at every heading); reference, tracking error, paths and tolerances are reported for the base frame |
//! | tracking | Kanayama's law on the timed reference gives (v, ω); an inner loop turns them into wheel torques by computed torque on the reduced model `Mr v̇ + cr + Gr = N_Cᵀ S u`; the arm holds its transport posture (PD + gravity and coupling compensation, in the same computed torque) |
//! | plant | [`crate::sim::wheeled_system::WheeledSystem`] (reduced coordinates, C q̇ = 0 by construction), fixed-step RK4 with the torques held over each control period; or, with `simulation.plant = "contact"`, the contact plant ([`crate::contact`]) stepped at its own `dt` under the same held torques, measured through the reduced coordinates (`plant`) |
//! | obstacles | at time t their cells are blocked in D* Lite (`move_start`, `set_blocked`); if the remaining reference crosses a blocked cell, `compute` re-plans and the new path is smoothed and timed from the robot's current pose |
//! | goal | the base settles on the goal pose, then task-space inverse dynamics on the reduced model brings the end effector along a minimum-jerk line to its target while the platform holds still |
//! | pick (`[task]`) | the base goal is the best placement ([`crate::motion::placement::place_base`]) the planner reaches and, with a `[goal]`, the drive on can leave holding the object; the torso-arm motions to pre-grasp, grasp, lift and back ([`crate::motion::plan_motion`], the last two carrying the object) tracked in joint space by the same computed torque, the platform held; the payload attached to the law's, plant's and monitors' model; the placement, the arm motions and their distance monitor with the map's boxes near the pick ([`arm_scene`]); the distances to the scene and between links monitored (with the held object after the grasp); the drives' distances to the scene and the map's boxes monitored; then the drive on to `[goal]`, if any, with the footprint that holds the object |
//! | law `mpc` (`control.law = "mpc"`) | instead of tracking, arriving and reaching: the whole-body MPC of `[control.mpc]` (the schema of `moma simulate`'s `[controller.mpc]`, [`crate::sim::mpc_table`]) run as [`crate::sim::mpc_law::MpcLaw`] on the timed base reference and the end-effector target at once (`whole_body`), one solve per `control.period`, between solves the planned acceleration held (its torques recomputed at each step); done when the end effector has been within its tolerance and the base rests at the goal pose |
//! | monitors | ZMP margin, Force-Angle and Moment-Height minima ([`crate::stability::evaluate`] on the full multibody state q, q̇, q̈), wheel slip (the axle's lateral multiplier and the wheels' longitudinal forces against μ N, `stability::loads`), torque and speed saturation, tracking error, clearance, energy |
//!
//! A run that starts but cannot finish (an unreachable or sealed goal, a posture under
//! which every motion tips, a time-out) returns `reached: false` and a reason; input
//! errors are [`crate::Error`]s.
//!
//! # Files
//!
//! * [`scenario`] parses and validates the mission file (serde with unknown keys refused,
//!   every count bounded before allocation; the tables and the checks that need only the
//!   file are `schema`'s, re-exported by `scenario`) into a [`Mission`]: the loaded map, the
//!   `WheeledModel`, the end-effector frame and the arm postures. The map and URDF are
//!   parsed through a [`scenario::Loader`] (the file system, [`scenario::FileSystem`], on
//!   every normal path; the fuzz targets hand in the shipped files parsed once, and sweeps
//!   pass theirs through `Sweep::from_toml_str_with`).
//! * `plan` owns the known world: the occupancy mask (map plus appeared obstacles), its
//!   distance transform (for the clearance monitor), one D* Lite on the
//!   footprint-dilated C-space (`mission_planner` sets it up for the mission's footprint), so an obstacle is `move_start` + `set_blocked` and a
//!   re-plan one incremental `compute`, and the footprint polygon's check.
//! * [`footprint`] gives the footprint (a typed disk or the robot's polygon at the
//!   transport posture); [`heights`] checks `[[map.boxes]]` and a `[task]`'s scene
//!   objects in 3-D and rasterises the ones the robot cannot pass under.
//! * [`mod@reference`] turns a cell path into timed samples (curvature-bounded smoothing from
//!   the exact poses, then `time_parameterize_curve` under the platform and tip-over
//!   limits from the current speed).
//! * `run` is the closed loop at a fixed control period equal to the RK4 step (the step
//!   by step is in `ARCHITECTURE.md`): the `Runner`, its preparation, its step and its
//!   finish. The step's parts are files of their own: `replan` (a path smoothed, timed
//!   and checked into the reference; obstacles appearing and the re-plans they trigger),
//!   `arrival` (the phases' ends, the reach, law `mpc`'s step), `pick` (a `[task]`'s arm
//!   motions, the payload, the drive on), `recording` (samples, monitors and their
//!   events), `laws` (the platform, reach and arm laws with their gains and guards),
//!   `arm_motion` (the arm's references), `workspace` (the loop's buffers and the
//!   actuators), `tip_over` (the transport posture's tip-over limits, [`transport_tip_limits`])
//!   and `placement` (a `[task]`'s base goal). The results (`result`) are plain columns
//!   ([`Samples`]), plans and events, which the CLI turns into CSV, JSON, SVGs and the
//!   report.
//! * `plant` builds and checks the contact plant of `simulation.plant = "contact"` at load
//!   ([`MissionContact`]) and steps it in the loop, with its monitors and events.
//! * [`arm_scene`] picks the map's boxes a pick's arm can reach and adds them to the
//!   task's scene for the placement search, the arm planner and the arm monitor.
//! * [`task`] loads a `[task]` (the scene placed on the map, blocking the cells under the
//!   outline of the objects the robot cannot pass under; the grasp; the geometry; the payload robot) and holds its distance monitor
//!   and result records.
//! * `whole_body` is law `mpc`: the MPC, the knot reference it reads from the current
//!   plan and the target, and its solve period.
//! * [`planned`] offers the same planning calls to `moma simulate` as a platform reference.

mod arm_motion;
pub mod arm_scene;
mod arrival;
pub mod footprint;
pub mod heights;
mod laws;
mod pick;
mod placement;
pub(crate) mod plan;
pub mod planned;
mod plant;
mod recording;
pub mod reference;
mod replan;
mod result;
mod run;
pub mod scenario;
mod schema;
pub mod task;
mod tip_over;
mod whole_body;
mod workspace;

pub use footprint::{FootprintSource, MissionFootprint};
pub use plan::SearchTiming;
pub use plant::MissionContact;
pub use reference::{RefSample, Reference};
pub use result::{Event, MissionResult, PlanRecord, Samples, WallTimes};
pub use run::run;
pub use scenario::{Mission, MissionFile, load};
pub use tip_over::transport_tip_limits;

/// The summary of a finished mission that does not depend on how it was run: `mission`,
/// `reached`, `reason`, `time_to_goal`, `simulated_time`, `replans`, the stability,
/// clearance, tracking and slip extremes, `final_pose_error` ([m, rad]),
/// `end_effector_error`, saturation counts, energies, `tip_over_limits`,
/// `timing_acceleration` and `samples`; with `map.boxes` the 3-D verdict of each box
/// (`boxes`: `clearance`, `blocked`); on the contact plant `contact` (first lift-off,
/// first slip, per-contact totals, largest tilt); `min_scene_distance`,
/// `min_self_distance`, with law `mpc` `mpc` (the MPC's summary, as `moma simulate`'s) and, with a `[task]`, `task` ([`task::TaskResult`], whose placement and arm plans carry their wall-clock planning times). Non-finite
/// or missing values are `null`.
/// `moma mission` adds its timing and file keys to this map; the Python package returns
/// it as it is.
#[must_use]
pub fn summary(m: &Mission, r: &MissionResult) -> serde_json::Map<String, serde_json::Value> {
    use serde_json::json;
    let fin = |x: Option<f64>| x.filter(|v| v.is_finite());
    let last = r.samples.t.len().saturating_sub(1);
    let final_pose_error = r.samples.q.get(last).map(|q| {
        let g = r.goal_pose;
        [
            (q[0] - g[0]).hypot(q[1] - g[1]),
            crate::control::wrap_angle(g[2] - q[2]).abs(),
        ]
    });
    let ee_error = m.goal().and_then(|g| g.end_effector).and_then(|target| {
        r.samples.ee.get(last).map(|e| {
            ((e[0] - target[0]).powi(2) + (e[1] - target[1]).powi(2) + (e[2] - target[2]).powi(2))
                .sqrt()
        })
    });
    let doc = json!({
        "mission": m.name,
        "reached": r.reached,
        "reason": r.reason,
        "time_to_goal": fin(r.time_to_goal),
        "simulated_time": r.duration,
        "replans": r.replans(),
        "min_zmp_margin": fin(r.min_zmp_margin()),
        "min_force_angle": fin(r.min_force_angle()),
        "min_moment_height": fin(r.min_mhs()),
        "min_clearance": fin(r.min_clearance()),
        "max_tracking_error": fin(r.max_tracking_error()),
        "final_pose_error": final_pose_error,
        "end_effector_error": fin(ee_error),
        "max_slip_ratio": fin(r.max_slip_ratio()),
        "torque_saturated_steps": r.torque_saturated_steps,
        "speed_saturated_steps": r.speed_saturated_steps,
        "control_steps": r.steps,
        "actuator_energy": r.samples.energy.last().copied().unwrap_or(0.0),
        "input_work": r.input_work,
        "tip_over_limits": {
            "forward": fin(r.tip_limits.forward),
            "backward": fin(r.tip_limits.backward),
            "left": fin(r.tip_limits.left),
            "right": fin(r.tip_limits.right),
        },
        "timing_acceleration": r.timing_acceleration,
        "samples": r.samples.t.len(),
        "min_scene_distance": r.task.as_ref().and_then(|t| fin(t.min_scene_distance)),
        "min_self_distance": r.task.as_ref().and_then(|t| fin(t.min_self_distance)),
        "task": r.task,
    });
    let mut map = match doc {
        serde_json::Value::Object(map) => map,
        _ => unreachable!("json! of an object literal is an object"),
    };
    if !m.boxes.is_empty() {
        map.insert("boxes".into(), json!(m.boxes));
    }
    if let Some(mpc) = &r.mpc {
        map.insert("mpc".into(), json!(mpc));
    }
    if let Some(c) = &r.contact {
        map.insert(
            "contact".into(),
            json!({
                "first_lift_off": c.first_lift_off,
                "first_slip": c.first_slip,
                "max_tilt": fin(Some(c.max_tilt)),
                "totals": c.totals,
            }),
        );
    }
    map
}

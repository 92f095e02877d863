//! `moma mission`: the chapter end to end. A mission plans on an occupancy map's
//! configuration space, turns the path into a timed reference under the platform's
//! limits and the tip-over limits of its transport posture, tracks it in closed-loop
//! dynamic simulation of the URDF robot on its differential drive, re-plans with D* Lite
//! when obstacles appear, reaches an end-effector target at the goal, and monitors
//! stability, slip, limits, tracking, clearance and energy all along.
//!
//! | step | what runs |
//! | --- | --- |
//! | map → C-space | [`crate::planning::load_map`], the distance transform, disk dilation by `footprint_radius` + ½ cell |
//! | search | [`crate::planning::dstar_lite::DStarLite`] from the start pose's cell to the goal's cell |
//! | path → motion | shortcut smoothing against the C-space, then time parameterisation under v, ω, a, α and the tip-over accelerations ([`crate::stability::acceleration_limits`] of the transport posture, times `tip_fraction`) |
//! | tracking | Kanayama's law on the timed reference gives (v, ω); an inner loop turns them into wheel torques by computed torque on the reduced model `Mr v̇ + cr + Gr = N_Cᵀ S u`; the arm holds its transport posture (PD + gravity and coupling compensation, in the same computed torque) |
//! | plant | [`crate::sim::wheeled_system::WheeledSystem`] (reduced coordinates, C q̇ = 0 by construction), fixed-step RK4 with the torques held over each control period |
//! | obstacles | at time t their cells are blocked in D* Lite (`move_start`, `set_blocked`); if the remaining reference crosses a blocked cell, `compute` re-plans and the new path is smoothed and timed from the robot's current pose |
//! | goal | the base settles on the goal pose, then task-space inverse dynamics on the reduced model brings the end effector along a minimum-jerk line to its target while the platform holds still |
//! | monitors | ZMP margin, Force-Angle and Moment-Height minima ([`crate::stability::evaluate`] on the full multibody state q, q̇, q̈), wheel slip (the axle's lateral multiplier and the wheels' longitudinal forces against μ N, `stability::loads`), torque and speed saturation, tracking error, clearance, energy |
//!
//! A run that starts but cannot finish (an unreachable or sealed goal, a posture under
//! which every motion tips, a time-out) returns `reached: false` and a reason; input
//! errors are [`crate::Error`]s.

mod plan;
pub mod reference;
mod run;
pub mod scenario;

pub use plan::SearchTiming;
pub use reference::{RefSample, Reference};
pub use run::{Event, MissionResult, PlanRecord, Samples, WallTimes, run, transport_tip_limits};
pub use scenario::{Mission, MissionFile, load};

//! A platform reference planned on a map: the configuration space of the map (obstacles
//! dilated by the footprint radius), a grid search from the start cell to the goal cell
//! (D* Lite, as `moma mission` plans), curvature-bounded smoothing from the exact start
//! pose to the exact goal pose ([`crate::planning::curvature::smooth_diff_drive`]) and the
//! near time-optimal timing under the platform's v, ω, a, α limits
//! ([`crate::planning::trajectory::time_parameterize_curve`]) — the calls of
//! [`crate::mission`], with no tip-over bound — as a [`SampledTrajectory`] the platform
//! laws of [`crate::sim::feedback`] track (Kanayama) or follow (pure pursuit, its path).

use super::plan::first_plan_request;
use super::reference::reference_of_curve;
use crate::control::unicycle::Pose;
use crate::error::{Error, Result};
use crate::planning::OccupancyGrid;
use crate::planning::curve_timing::CurvatureTiming;
use crate::planning::pipeline::{self, PlanFields, Timing};
use crate::planning::trajectory::{DiffDriveLimits, TipOverAcceleration, TrajectoryPoint};
use crate::sim::feedback::SampledTrajectory;

/// What to plan.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlannedPathRequest {
    /// Start pose `[x, y, θ]` of the axle midpoint (world, m, rad).
    pub start: Pose,
    /// Goal pose.
    pub goal: Pose,
    /// Radius of the disk that covers the footprint (m), > 0.
    pub footprint_radius: f64,
    /// Unknown map cells count as obstacles.
    pub unknown_is_obstacle: bool,
    /// Platform limits of the timing.
    pub limits: DiffDriveLimits,
    /// Curvature bound of the smoothing (1/m), > 0 (tighter bounds, then the arrival
    /// heading, are tried as in `moma mission`).
    pub kappa_max: f64,
    /// Sampling step of the trajectory (s), > 0.
    pub dt: f64,
}

/// The planned reference.
#[derive(Clone, Debug)]
pub struct PlannedPath {
    /// The time-parameterised samples.
    pub trajectory: SampledTrajectory,
    /// The smoothed geometric path (world, m).
    pub path: Vec<[f64; 2]>,
    /// Cells of the grid path.
    pub cells: usize,
    /// The curvature bound used.
    pub kappa_max: f64,
    /// The path ends with its arrival heading and the goal heading is taken by a turn in
    /// place (no smooth path ends at the goal heading).
    pub turn_at_goal: bool,
}

/// The fields of the planning's and timing's own errors under `reference`.
fn rename(e: Error) -> Error {
    match e {
        Error::InvalidInput { field, message } if !field.starts_with("reference") => {
            Error::InvalidInput {
                field: format!("reference: {field}"),
                message,
            }
        }
        other => other,
    }
}

/// Plans a path on `grid` and times it (see the module documentation).
///
/// # Errors
/// Non-finite or non-positive numbers (named `reference.…`), start or goal outside the
/// map, in an obstacle or where the footprint does not fit; **an unreachable goal**
/// (`reference.goal`: no path of the footprint from the start); a path the smoothing or
/// the timing cannot produce.
pub fn plan_platform_reference(
    grid: &OccupancyGrid,
    request: &PlannedPathRequest,
) -> Result<PlannedPath> {
    let r = request;
    crate::error::ensure_finite("reference.start", &r.start)?;
    crate::error::ensure_finite("reference.goal", &r.goal)?;
    for (n, x) in [
        ("reference.footprint_radius", r.footprint_radius),
        ("reference.kappa_max", r.kappa_max),
        ("reference.timing.dt", r.dt),
    ] {
        crate::error::ensure_positive(n, x)?;
    }
    let extent = grid.width.max(grid.height) as f64 * grid.resolution;
    if r.footprint_radius > extent {
        return Err(Error::invalid(
            "reference.footprint_radius",
            format!(
                "{} m is larger than the whole map ({extent} m): it fits nowhere",
                r.footprint_radius
            ),
        ));
    }
    grid.world_to_cell("reference.start", r.start[0], r.start[1])?;
    grid.world_to_cell("reference.goal", r.goal[0], r.goal[1])?;
    let inf = f64::INFINITY;
    let tip = TipOverAcceleration {
        forward: inf,
        backward: inf,
        left: inf,
        right: inf,
    };
    let fields = PlanFields {
        start: "reference.start",
        goal: "reference.goal",
        radius: "reference.footprint_radius",
    };
    // the reference is planned for the point the platform law tracks (its base frame)
    let mut req = first_plan_request(
        r.unknown_is_obstacle,
        fields,
        r.footprint_radius,
        0.0,
        [r.start[0], r.start[1]],
        [r.goal[0], r.goal[1]],
    );
    req.start_yaw = Some(r.start[2]);
    req.goal_yaw = Some(r.goal[2]);
    req.timing = Some(Timing::Curvature {
        timing: CurvatureTiming {
            limits: r.limits,
            tip,
            kappa_max: r.kappa_max,
            dt: r.dt,
        },
    });
    let plan = pipeline::plan(grid, &req).map_err(rename)?;
    let Some(curve) = plan.curve else {
        return Err(Error::invalid(
            "reference.goal",
            format!(
                "unreachable: no path for a footprint of radius {} m from the start at ({}, {}) \
                 to the goal at ({}, {}) on the map",
                r.footprint_radius, r.start[0], r.start[1], r.goal[0], r.goal[1]
            ),
        ));
    };
    let reference = reference_of_curve(curve, 0.0, 0.0);
    let cells = plan.cells;
    let points: Vec<TrajectoryPoint> = reference
        .samples
        .iter()
        .map(|s| TrajectoryPoint {
            t: s.t,
            x: s.x,
            y: s.y,
            theta: s.theta,
            v: s.v,
            omega: s.omega,
        })
        .collect();
    Ok(PlannedPath {
        trajectory: SampledTrajectory::new(points)?,
        path: reference.path,
        cells: cells.len(),
        kappa_max: reference.kappa_max,
        turn_at_goal: reference.turn_at_goal,
    })
}

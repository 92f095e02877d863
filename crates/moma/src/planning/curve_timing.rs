//! The curvature-limited timing of a cell path: curvature-bounded smoothing against the
//! configuration space from an exact start pose to an exact goal pose
//! ([`smooth_diff_drive`]), then the near time-optimal time parameterisation under the
//! platform limits and given tip-over accelerations ([`time_parameterize_curve`]). The
//! mission's references are timed so, and [`super::pipeline`] offers it as
//! [`super::pipeline::Timing::Curvature`] beside the stop-and-turn timing.

use super::curvature::{SmoothOptions, SmoothPath, smooth_diff_drive};
use super::trajectory::{
    DiffDriveLimits, TimedSample, TipOverAcceleration, time_parameterize_curve,
};
use super::{OccupancyGrid, SearchGrid};
use crate::{Error, Result};

/// Limits and sampling of the curvature-limited timing.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvatureTiming {
    /// Platform limits.
    pub limits: DiffDriveLimits,
    /// The accelerations that keep the robot from tipping over (infinite: none).
    pub tip: TipOverAcceleration,
    /// Curvature bound of the smoothing (1/m).
    pub kappa_max: f64,
    /// Sampling period (s).
    pub dt: f64,
}

/// A cell path smoothed under a curvature bound and timed.
#[derive(Debug, Clone)]
pub struct TimedCurve {
    /// The smoothed geometry the samples follow.
    pub geometry: SmoothPath,
    /// The samples, from time 0 every `dt` (time, arc length, pose, speeds,
    /// accelerations, curvature).
    pub samples: Vec<TimedSample>,
    /// The curvature bound the smoothing used (1/m).
    pub kappa_max: f64,
    /// `true` when the path ends with the heading it arrives with (no smooth path ends
    /// at the goal heading): the goal heading is then left to a turn in place.
    pub turn_at_goal: bool,
    /// `Some(s)` when the timing started faster than the path allows at its start and
    /// braked past some limit of the path up to arc length `s`.
    pub overspeed_until: Option<f64>,
}

/// Smooths `cells` (on `cspace`, over `map`) from the exact pose `start` to the exact
/// pose `goal` and times the result from the speed `v_start` to rest. When no smooth path
/// ends at the goal pose with `timing.kappa_max`, tighter bounds (2x, 4x) are tried, then
/// the heading the cell path arrives with (the goal heading is then taken by a turn in
/// place, [`TimedCurve::turn_at_goal`]). A path that must begin with a turn in place
/// cannot start moving: it is then timed from rest.
///
/// # Errors
/// No smoothing succeeds (the first attempt's error); invalid limits or `dt`.
pub fn time_cells_curved(
    map: &OccupancyGrid,
    cspace: &SearchGrid,
    cells: &[(usize, usize)],
    start: [f64; 3],
    v_start: f64,
    goal: [f64; 3],
    timing: &CurvatureTiming,
) -> Result<TimedCurve> {
    // First the goal pose as given, with the curvature bound, then tighter bounds (2x,
    // 4x); last the heading the path arrives with, the goal heading then being taken by a
    // turn in place at the goal.
    let kappa_max = timing.kappa_max;
    let arrival = arrival_heading(map, cells, goal);
    let mut first_err = None;
    let mut found = None;
    for (k, g) in [
        (kappa_max, goal),
        (2.0 * kappa_max, goal),
        (4.0 * kappa_max, goal),
        (kappa_max, [goal[0], goal[1], arrival]),
        (4.0 * kappa_max, [goal[0], goal[1], arrival]),
    ] {
        match smooth_diff_drive(cspace, map, cells, start, g, &SmoothOptions::new(k)) {
            Ok(p) => {
                found = Some((p, k, g[2] != goal[2]));
                break;
            }
            Err(e) => {
                first_err.get_or_insert(e);
            }
        }
    }
    let Some((geometry, kappa_used, turn_at_goal)) = found else {
        return Err(first_err
            .unwrap_or_else(|| Error::Planning("no curvature-bounded smoothing ran".into())));
    };
    let v0 = if geometry.pivot() != 0.0 {
        0.0
    } else {
        v_start.max(0.0)
    };
    let timed = time_parameterize_curve(&geometry, &timing.limits, Some(&timing.tip), v0, 0.0)?;
    Ok(TimedCurve {
        samples: timed.samples(timing.dt)?,
        overspeed_until: timed.overspeed_until(),
        geometry,
        kappa_max: kappa_used,
        turn_at_goal,
    })
}

/// The direction (rad) from a point of the cell path about 0.6 m before the goal to the
/// goal: the heading a path arrives with when it does not turn to the goal heading.
fn arrival_heading(map: &OccupancyGrid, cells: &[(usize, usize)], goal: [f64; 3]) -> f64 {
    let back = ((0.6 / map.resolution).ceil() as usize).max(1);
    let n = cells.len();
    if n < 2 {
        return goal[2];
    }
    let (x, y) = cells[n.saturating_sub(1 + back)];
    let p = map.cell_to_world(x as f64, y as f64);
    let (dx, dy) = (goal[0] - p[0], goal[1] - p[1]);
    if dx.hypot(dy) < 1e-9 {
        goal[2]
    } else {
        dy.atan2(dx)
    }
}

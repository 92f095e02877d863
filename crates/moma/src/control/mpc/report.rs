//! What one MPC solve reports: its wall time, iterations, cost, and the largest
//! constraint violation of each kind over the planned horizon (physical units).

use std::time::Duration;

use super::constraints::KINDS;

/// Largest violation of each constraint kind over the horizon (0 when satisfied).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Violations {
    /// Torque beyond its limit (N·m or N).
    pub torque: f64,
    /// Wheel rate beyond its limit (rad/s).
    pub wheel_speed: f64,
    /// Joint speed beyond its limit (rad/s or m/s).
    pub joint_speed: f64,
    /// Joint position beyond its limit (rad or m).
    pub joint_position: f64,
    /// ZMP margin below the set value (m).
    pub zmp: f64,
    /// Clearance below the set value (m).
    pub clearance: f64,
    /// Map clearance of the base footprint below the set value (m); `None` without the
    /// map-clearance constraint (left out of the summary's kinds, as it was before the
    /// constraint existed).
    pub map_clearance: Option<f64>,
}

impl Violations {
    /// From per-kind values in [`KINDS`] order; the map clearance's only when
    /// `map_constraint` (the problem has that constraint).
    #[must_use]
    pub fn from_array(a: [f64; 7], map_constraint: bool) -> Self {
        Self {
            torque: a[0],
            wheel_speed: a[1],
            joint_speed: a[2],
            joint_position: a[3],
            zmp: a[4],
            clearance: a[5],
            map_clearance: map_constraint.then_some(a[6]),
        }
    }

    /// `(kind, value)` pairs in [`KINDS`] order (the map clearance's only with its
    /// constraint).
    #[must_use]
    pub fn pairs(&self) -> Vec<(&'static str, f64)> {
        let mut pairs = vec![
            (KINDS[0], self.torque),
            (KINDS[1], self.wheel_speed),
            (KINDS[2], self.joint_speed),
            (KINDS[3], self.joint_position),
            (KINDS[4], self.zmp),
            (KINDS[5], self.clearance),
        ];
        pairs.extend(self.map_clearance.map(|v| (KINDS[6], v)));
        pairs
    }

    /// The larger of `self` and `other`, kind by kind.
    #[must_use]
    pub fn max(&self, other: &Self) -> Self {
        Self {
            torque: self.torque.max(other.torque),
            wheel_speed: self.wheel_speed.max(other.wheel_speed),
            joint_speed: self.joint_speed.max(other.joint_speed),
            joint_position: self.joint_position.max(other.joint_position),
            zmp: self.zmp.max(other.zmp),
            clearance: self.clearance.max(other.clearance),
            map_clearance: match (self.map_clearance, other.map_clearance) {
                (Some(a), Some(b)) => Some(a.max(b)),
                (a, b) => a.or(b),
            },
        }
    }
}

/// One solve.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SolveReport {
    /// Wall-clock time of the solve.
    pub time: Duration,
    /// Solver iterations.
    pub iterations: usize,
    /// Line-search rollouts (each a pass over the horizon, or the part of one before it
    /// could no longer be accepted).
    pub rollouts: usize,
    /// Total cost (including the augmented-Lagrangian terms).
    pub cost: f64,
    /// Whether the solver met its tolerance within its iteration budget.
    pub converged: bool,
    /// Largest violation per kind over the planned trajectory.
    pub violations: Violations,
    /// Smallest ZMP margin over the planned trajectory (m).
    pub min_zmp_margin: f64,
    /// Smallest clearance over the planned trajectory (m), where it is below the
    /// distance beyond which the knot's clearance row is inactive (at least the set
    /// value; pairs farther apart are not queried), else that distance.
    pub min_clearance: f64,
}

//! What the whole-body MPC did in closed loop: one [`MpcSample`] per control period (the
//! solve report, the torques applied and what they did on the MPC's model of the robot:
//! ZMP margin, clearance, torque beyond the limits before clipping, end-effector error)
//! and the run's [`MpcRunSummary`] (solve-time percentiles, iterations and line-search
//! rollouts per solve, the largest planned violations and the closed loop's extremes),
//! which serialises as the `mpc` object of a run's report.

use nalgebra::DVector;

use crate::control::mpc::{MpcRobot, SolveReport, Violations};

/// One control period.
#[derive(Clone, Debug)]
pub struct MpcSample {
    /// Time at the start of the period (s).
    pub t: f64,
    /// Configuration at that time.
    pub q: Vec<f64>,
    /// Reduced velocity.
    pub v: Vec<f64>,
    /// Torques applied over the period (clipped to the limits).
    pub torque: Vec<f64>,
    /// The solve.
    pub solve: SolveReport,
    /// ZMP margin of the state and of the acceleration the applied torques give on the
    /// MPC's model (the plant's, unless the plant is perturbed) (m); `None` at lift-off.
    pub zmp_margin: Option<f64>,
    /// Smallest distance over the enabled self pairs and the scene (m; `∞` without
    /// geometry).
    pub clearance: f64,
    /// Largest torque beyond its limit that the MPC asked for (clipped before applying).
    pub torque_excess: f64,
    /// End-effector position error to the reference at `t`, if it has a target (m).
    pub ee_error: Option<f64>,
}

/// Percentiles of the solve times and the closed loop's extremes; serialised, the `mpc`
/// object of `moma simulate`'s summary (and of the Python package's `simulate`).
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct MpcRunSummary {
    /// Number of solves.
    pub solves: usize,
    /// Solve time percentiles (s).
    pub solve_time_s: SolveTimes,
    /// Iterations per solve.
    pub iterations: CountsPerSolve,
    /// Line-search rollouts per solve (the work of a solve that does not depend on the
    /// machine's load, with the iterations).
    pub rollouts: CountsPerSolve,
    /// Largest violation per kind over every planned horizon.
    #[serde(
        rename = "max_planned_violation",
        serialize_with = "violations_by_kind"
    )]
    pub planned_violations: Violations,
    /// Smallest ZMP margin of the plant (m).
    pub min_zmp_margin: f64,
    /// Smallest clearance of the plant (m).
    pub min_clearance: f64,
    /// Largest torque excess asked for (clipped).
    pub max_torque_excess: f64,
    /// Largest wheel rate beyond its limit in the plant (rad/s).
    pub wheel_speed_excess: f64,
    /// Largest joint speed beyond its limit in the plant.
    pub joint_speed_excess: f64,
    /// Largest joint position beyond its limit in the plant.
    pub joint_position_excess: f64,
    /// Smallest end-effector error over the run (m), if a target was set.
    pub min_ee_error: Option<f64>,
    /// First time the end-effector error fell below 2 cm (s).
    pub ee_reached_at: Option<f64>,
    /// Platform speed `|v|` at that time (m/s): non-zero when the arm reached on the move.
    pub base_speed_at_reach: Option<f64>,
}

/// Percentiles of the solve times (s), in [`MpcRunSummary`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SolveTimes {
    /// 50th percentile.
    pub median: f64,
    /// 90th percentile.
    pub p90: f64,
    /// 99th percentile.
    pub p99: f64,
    /// Largest.
    pub max: f64,
}

/// The distribution of a count per solve (iterations, rollouts), in [`MpcRunSummary`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct CountsPerSolve {
    /// Mean.
    pub mean: f64,
    /// 50th percentile (nearest rank).
    pub median: usize,
    /// 99th percentile (nearest rank).
    pub p99: usize,
    /// Largest.
    pub max: usize,
}

impl CountsPerSolve {
    /// Of one count per solve (all zero for no solves).
    #[must_use]
    pub fn of(counts: impl Iterator<Item = usize>) -> Self {
        let mut sorted: Vec<usize> = counts.collect();
        sorted.sort_unstable();
        Self {
            mean: sorted.iter().sum::<usize>() as f64 / sorted.len().max(1) as f64,
            median: nearest_rank(&sorted, 50.0).unwrap_or(0),
            p99: nearest_rank(&sorted, 99.0).unwrap_or(0),
            max: sorted.last().copied().unwrap_or(0),
        }
    }
}

/// [`Violations`] as a map from kind to its largest value, sorted by kind.
fn violations_by_kind<S: serde::Serializer>(v: &Violations, out: S) -> Result<S::Ok, S::Error> {
    let map: std::collections::BTreeMap<&'static str, f64> = v.pairs().into_iter().collect();
    serde::Serialize::serialize(&map, out)
}

/// A closed-loop run: samples and summary; `q`, `v` end at the final state.
#[derive(Clone, Debug)]
pub struct MpcRun {
    /// One sample per period.
    pub samples: Vec<MpcSample>,
    /// Summary.
    pub summary: MpcRunSummary,
}

/// The `p`-th percentile (nearest rank) of sorted values; `None` when there are none.
fn nearest_rank<T: Copy>(sorted: &[T], p: f64) -> Option<T> {
    if sorted.is_empty() {
        return None;
    }
    let rank = ((p / 100.0) * sorted.len() as f64).ceil() as usize;
    Some(sorted[rank.clamp(1, sorted.len()) - 1])
}

/// The summary of a run's samples (`robot`: the MPC's robot, for its limits).
#[must_use]
pub fn summarize(robot: &MpcRobot, samples: &[MpcSample]) -> MpcRunSummary {
    let mut times: Vec<f64> = samples.iter().map(|s| s.solve.time.as_secs_f64()).collect();
    times.sort_by(f64::total_cmp);
    let mut planned = Violations::default();
    let (mut wheel, mut speed, mut pos): (f64, f64, f64) = (0.0, 0.0, 0.0);
    for s in samples {
        planned = planned.max(&s.solve.violations);
        let mut xs = DVector::zeros(robot.nx());
        robot.state_from_plant(&s.q, &s.v, &mut xs);
        let nc = robot.n_moved();
        let rates = robot.wheel_map * nalgebra::Vector2::new(xs[3 + nc], xs[4 + nc]);
        wheel = wheel.max(rates.amax() - robot.wheel_rate_limit);
        for i in 0..nc {
            speed = speed.max(xs[5 + nc + i].abs() - robot.speed_limit[i]);
            pos = pos
                .max(xs[3 + i] - robot.upper[i])
                .max(robot.lower[i] - xs[3 + i]);
        }
    }
    let reached = samples
        .iter()
        .find(|s| s.ee_error.is_some_and(|e| e < 0.02));
    MpcRunSummary {
        solves: samples.len(),
        solve_time_s: SolveTimes {
            median: nearest_rank(&times, 50.0).unwrap_or(f64::NAN),
            p90: nearest_rank(&times, 90.0).unwrap_or(f64::NAN),
            p99: nearest_rank(&times, 99.0).unwrap_or(f64::NAN),
            max: times.last().copied().unwrap_or(f64::NAN),
        },
        iterations: CountsPerSolve::of(samples.iter().map(|s| s.solve.iterations)),
        rollouts: CountsPerSolve::of(samples.iter().map(|s| s.solve.rollouts)),
        planned_violations: planned,
        min_zmp_margin: samples
            .iter()
            .map(|s| s.zmp_margin.unwrap_or(f64::NEG_INFINITY))
            .fold(f64::INFINITY, f64::min),
        min_clearance: samples
            .iter()
            .map(|s| s.clearance)
            .fold(f64::INFINITY, f64::min),
        max_torque_excess: samples.iter().map(|s| s.torque_excess).fold(0.0, f64::max),
        wheel_speed_excess: wheel.max(0.0),
        joint_speed_excess: speed.max(0.0),
        joint_position_excess: pos.max(0.0),
        min_ee_error: samples.iter().filter_map(|s| s.ee_error).reduce(f64::min),
        ee_reached_at: reached.map(|s| s.t),
        base_speed_at_reach: reached.map(|s| s.v[0].abs()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_per_solve_give_the_nearest_rank_percentiles() {
        // 1 … 100 in a shuffled order: the 50th value is 50, the 99th 99.
        let counts = (1..=100).map(|i| (i * 37) % 101);
        let c = CountsPerSolve::of(counts);
        assert_eq!(c.median, 50);
        assert_eq!(c.p99, 99);
        assert_eq!(c.max, 100);
        assert!((c.mean - 50.5).abs() < 1e-12);
        // Seven solves: the 99th percentile is the largest, the median the fourth.
        let c = CountsPerSolve::of([6, 1, 22, 6, 1, 12, 1].into_iter());
        assert_eq!((c.median, c.p99, c.max), (6, 22, 22));
        assert_eq!(CountsPerSolve::of(std::iter::empty()).max, 0);
    }
}

//! Artificial potential fields on the grid, as the chapter describes them: the distance
//! from the nearest obstacle played against a weighted distance to the goal, followed by
//! steepest descent,
//!
//! `V(q) = w · G(q) − min(d_obs(q), ρ₀)`,
//!
//! where `d_obs` is the Euclidean distance (cells) to the nearest C-space obstacle, `ρ₀`
//! the obstacle's range of influence and `G` the distance to the goal, in two forms:
//!
//! * [`GoalTerm::Euclidean`] — the literal form, `G = ‖q − q_goal‖`. Like every
//!   attractive/repulsive field (Khatib 1986) it has local minima: a U-shaped obstacle
//!   between robot and goal traps the descent (Koren & Borenstein 1991). The descent
//!   detects this and reports where and why it stopped.
//! * [`GoalTerm::Geodesic`] — `G` is the wavefront (shortest-path) distance to the goal
//!   in the C-space (Barraquand & Latombe's NF1; the goal term of Corke's distance-
//!   transform planner). With `w > 1` it has **no local minimum** other than the goal:
//!   every reachable cell `q` has a neighbour `n` one step `ℓ` closer along a shortest
//!   path, `G(n) = G(q) − ℓ`, while the obstacle term changes by at most `ℓ` (a distance
//!   field is 1-Lipschitz), so `V(n) − V(q) ≤ −(w − 1) ℓ < 0`.
//!
//! Steps follow the A* move model (8-connected, no corner cutting, C-space cells only)
//! and go to the neighbour of steepest descent `(V(n) − V(q)) / ℓ`.

use super::astar::{SQRT2, SearchGrid, wavefront};
use super::edt::distance_transform;
use crate::{Error, Result};

/// Which distance to the goal the potential uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum GoalTerm {
    /// Straight-line distance (the literal textbook field; has local minima).
    Euclidean,
    /// Shortest-path (wavefront) distance in the C-space (no local minima for w > 1).
    Geodesic,
}

/// Parameters of the potential.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PotentialParams {
    /// Weight `w` of the goal distance (> 0; > 1 for the geodesic form).
    pub goal_weight: f64,
    /// Range of influence `ρ₀` of the obstacles (cells, ≥ 0).
    pub influence: f64,
}

impl Default for PotentialParams {
    fn default() -> Self {
        Self {
            goal_weight: 2.0,
            influence: 5.0,
        }
    }
}

/// A potential evaluated on every cell (`f64::INFINITY` on C-space obstacles and, for
/// the geodesic form, on cells that cannot reach the goal).
#[derive(Debug, Clone, PartialEq)]
pub struct PotentialField {
    /// Grid width.
    pub width: usize,
    /// Grid height.
    pub height: usize,
    /// Goal cell.
    pub goal: (usize, usize),
    /// Which goal term was used.
    pub term: GoalTerm,
    /// `V` row-major.
    pub values: Vec<f64>,
}

/// Why a descent ended.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(tag = "status", rename_all = "snake_case")]
pub enum DescentEnd {
    /// The goal was reached.
    Reached,
    /// A local minimum: no neighbour has a lower potential.
    LocalMinimum {
        /// The cell where the descent stopped.
        cell: (usize, usize),
        /// The potential there.
        potential: f64,
        /// Straight-line distance from there to the goal (cells).
        distance_to_goal: f64,
    },
    /// The start cannot reach the goal at all (geodesic form: infinite potential).
    Unreachable,
}

/// The cells visited by a descent and how it ended.
#[derive(Debug, Clone, PartialEq)]
pub struct Descent {
    /// Cells from the start to where the descent ended.
    pub cells: Vec<(usize, usize)>,
    /// How it ended.
    pub end: DescentEnd,
}

impl Descent {
    /// A one-line human-readable report.
    pub fn report(&self) -> String {
        match &self.end {
            DescentEnd::Reached => format!(
                "reached the goal in {} steps",
                self.cells.len().saturating_sub(1)
            ),
            DescentEnd::LocalMinimum {
                cell,
                potential,
                distance_to_goal,
            } => format!(
                "stuck in a local minimum of the potential at cell ({}, {}) (V = {potential:.3}), {distance_to_goal:.1} cells from the goal, after {} steps: no neighbour has a lower potential",
                cell.0,
                cell.1,
                self.cells.len().saturating_sub(1)
            ),
            DescentEnd::Unreachable => "the goal cannot be reached from the start".into(),
        }
    }
}

/// Builds the potential over the C-space `grid` for `goal`.
#[doc(alias = "artificial_potential_field")]
pub fn potential_field(
    grid: &SearchGrid,
    goal: (usize, usize),
    term: GoalTerm,
    params: &PotentialParams,
) -> Result<PotentialField> {
    grid.check_cell("goal", goal)?;
    let w = params.goal_weight;
    if !(w.is_finite() && w > 0.0) {
        return Err(Error::invalid(
            "goal weight",
            format!("must be finite and > 0, got {w}"),
        ));
    }
    if term == GoalTerm::Geodesic && w <= 1.0 {
        return Err(Error::invalid(
            "goal weight",
            format!("the geodesic potential needs w > 1 to be free of local minima, got {w:?}"),
        ));
    }
    if !(params.influence.is_finite() && params.influence >= 0.0) {
        return Err(Error::invalid(
            "influence",
            format!("must be finite and >= 0, got {}", params.influence),
        ));
    }
    let (width, height) = (grid.width(), grid.height());
    let obst = grid.obstacles();
    let clearance = distance_transform(&obst, width, height);
    let geo = if term == GoalTerm::Geodesic {
        Some(wavefront(grid, goal)?)
    } else {
        None
    };
    let mut values = vec![f64::INFINITY; width * height];
    for y in 0..height {
        for x in 0..width {
            let i = y * width + x;
            if obst[i] {
                continue;
            }
            let gdist = match &geo {
                Some(g) => g[i],
                None => {
                    ((x as f64 - goal.0 as f64).powi(2) + (y as f64 - goal.1 as f64).powi(2)).sqrt()
                }
            };
            let value = w * gdist - (clearance[i] as f64).min(params.influence);
            if gdist.is_finite() && !value.is_finite() {
                return Err(Error::invalid(
                    "goal weight",
                    format!(
                        "w = {w:e} times the goal distance {gdist:.1} at cell ({x}, {y}) overflows a double"
                    ),
                ));
            }
            values[i] = value;
        }
    }
    Ok(PotentialField {
        width,
        height,
        goal,
        term,
        values,
    })
}

/// Follows the steepest descent of `field` from `start` over the C-space `grid`.
pub fn descend(
    grid: &SearchGrid,
    field: &PotentialField,
    start: (usize, usize),
) -> Result<Descent> {
    grid.check_cell("start", start)?;
    if (grid.width(), grid.height()) != (field.width, field.height) {
        return Err(Error::invalid(
            "potential field",
            "size differs from the grid",
        ));
    }
    let v = |c: (i64, i64)| field.values[c.1 as usize * field.width + c.0 as usize];
    let mut cur = (start.0 as i64, start.1 as i64);
    let mut cells = vec![start];
    if !v(cur).is_finite() {
        return Ok(Descent {
            cells,
            end: DescentEnd::Unreachable,
        });
    }
    let goal = (field.goal.0 as i64, field.goal.1 as i64);
    // V strictly decreases, so the walk cannot cycle; the bound is a safety net.
    for _ in 0..field.values.len() {
        if cur == goal {
            return Ok(Descent {
                cells,
                end: DescentEnd::Reached,
            });
        }
        let here = v(cur);
        let mut best: Option<((i64, i64), f64)> = None;
        for dy in -1..=1 {
            for dx in -1..=1 {
                if (dx, dy) == (0, 0) || !grid.can_step(cur.0, cur.1, dx, dy) {
                    continue;
                }
                let n = (cur.0 + dx, cur.1 + dy);
                let len = if dx != 0 && dy != 0 { SQRT2 } else { 1.0 };
                let slope = (v(n) - here) / len;
                if slope < 0.0 && best.is_none_or(|b| slope < b.1) {
                    best = Some((n, slope));
                }
            }
        }
        match best {
            Some((n, _)) => {
                cur = n;
                cells.push((n.0 as usize, n.1 as usize));
            }
            None => {
                let d = (((cur.0 - goal.0).pow(2) + (cur.1 - goal.1).pow(2)) as f64).sqrt();
                return Ok(Descent {
                    cells,
                    end: DescentEnd::LocalMinimum {
                        cell: (cur.0 as usize, cur.1 as usize),
                        potential: here,
                        distance_to_goal: d,
                    },
                });
            }
        }
    }
    Err(Error::Numerical {
        t: 0.0,
        message: "potential descent did not terminate".into(),
    })
}

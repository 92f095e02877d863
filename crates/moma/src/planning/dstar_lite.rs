//! D* Lite (Koenig & Likhachev, AAAI 2002; IEEE T-RO 21(3), 2005): re-planning for a robot
//! that moves along its path while cells become blocked or free.
//!
//! The search runs from the goal toward the robot, keeping for every cell its cost-to-goal
//! `g` and a one-step look-ahead `rhs`; after a change only the locally inconsistent cells
//! are re-expanded, and the key modifier `k_m` keeps the queue valid as the robot moves.
//! Move model as [`super::astar`]: 8-connected, costs 1 / √2, no corner cutting, so
//! the cost after any change equals that of A* from scratch on the changed map.

use super::astar::{SQRT2, SearchGrid, octile};
use crate::{Error, Result};
use std::cmp::Ordering;
use std::collections::BinaryHeap;

#[derive(Clone, Copy, Debug)]
struct QEntry {
    k1: f64,
    k2: f64,
    idx: u32,
}
impl PartialEq for QEntry {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}
impl Eq for QEntry {}
impl Ord for QEntry {
    fn cmp(&self, o: &Self) -> Ordering {
        // Max-heap → reverse: the smallest key is the greatest entry.
        o.k1.total_cmp(&self.k1).then(o.k2.total_cmp(&self.k2))
    }
}
impl PartialOrd for QEntry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

#[inline]
fn key_less(a: (f64, f64), b: (f64, f64)) -> bool {
    a.0 < b.0 || (a.0 == b.0 && a.1 < b.1)
}

/// An incremental planner from a moving robot (`start`) to a fixed goal.
#[derive(Debug, Clone)]
#[doc(alias = "dstar")]
#[doc(alias = "d_star_lite")]
pub struct DStarLite {
    grid: SearchGrid,
    g: Vec<f64>,
    rhs: Vec<f64>,
    open_key: Vec<(f64, f64)>,
    in_open: Vec<bool>,
    heap: BinaryHeap<QEntry>,
    km: f64,
    start: usize,
    last: usize,
    goal: usize,
    expanded: usize,
    offsets: [(isize, bool); 8],
}

const NONE_KEY: (f64, f64) = (f64::INFINITY, f64::INFINITY);

impl DStarLite {
    /// Sets up a planner on a copy of `grid` from `start` to `goal` (cells `(x, y)`);
    /// call [`DStarLite::compute`] to plan.
    pub fn new(grid: &SearchGrid, start: (usize, usize), goal: (usize, usize)) -> Result<Self> {
        grid.check_cell("start", start)?;
        grid.check_cell("goal", goal)?;
        if grid.weight.is_some() {
            return Err(Error::invalid("grid", "D* Lite runs on an unweighted grid (octile costs)"));
        }
        let n = grid.pass.len();
        let pw = grid.pw as isize;
        let mut s = Self {
            grid: grid.clone(),
            g: vec![f64::INFINITY; n],
            rhs: vec![f64::INFINITY; n],
            open_key: vec![NONE_KEY; n],
            in_open: vec![false; n],
            heap: BinaryHeap::new(),
            km: 0.0,
            start: grid.pidx(start.0, start.1),
            last: grid.pidx(start.0, start.1),
            goal: grid.pidx(goal.0, goal.1),
            expanded: 0,
            offsets: [(1, false), (-1, false), (pw, false), (-pw, false), (pw + 1, true), (pw - 1, true), (-pw + 1, true), (-pw - 1, true)],
        };
        s.rhs[s.goal] = 0.0;
        let k = s.key(s.goal);
        s.push(s.goal, k);
        Ok(s)
    }

    #[inline]
    fn xy(&self, i: usize) -> (i64, i64) {
        ((i % self.grid.pw) as i64, (i / self.grid.pw) as i64)
    }

    #[inline]
    fn h(&self, a: usize, b: usize) -> f64 {
        let (ax, ay) = self.xy(a);
        let (bx, by) = self.xy(b);
        octile(ax - bx, ay - by)
    }

    #[inline]
    fn key(&self, s: usize) -> (f64, f64) {
        let m = self.g[s].min(self.rhs[s]);
        (m + self.h(self.start, s) + self.km, m)
    }

    fn push(&mut self, s: usize, k: (f64, f64)) {
        self.open_key[s] = k;
        self.in_open[s] = true;
        self.heap.push(QEntry { k1: k.0, k2: k.1, idx: s as u32 });
    }

    /// Cost of the step from `u` by offset `k`, infinite if illegal.
    #[inline]
    fn step_cost(&self, u: usize, off: isize, diag: bool) -> f64 {
        let pass = &self.grid.pass;
        let v = (u as isize + off) as usize;
        if !pass[u] || !pass[v] {
            return f64::INFINITY;
        }
        if diag {
            let pw = self.grid.pw as isize;
            let dx = if off == pw + 1 || off == -pw + 1 { 1 } else { -1 };
            let dy_off = off - dx;
            if !pass[(u as isize + dx) as usize] || !pass[(u as isize + dy_off) as usize] {
                return f64::INFINITY;
            }
            SQRT2
        } else {
            1.0
        }
    }

    fn inside(&self, i: usize) -> bool {
        let (x, y) = self.xy(i);
        x >= 1 && y >= 1 && (x as usize) <= self.grid.width && (y as usize) <= self.grid.height
    }

    fn update_vertex(&mut self, u: usize) {
        if u != self.goal {
            let mut best = f64::INFINITY;
            if self.grid.pass[u] {
                for &(off, diag) in &self.offsets {
                    let c = self.step_cost(u, off, diag);
                    if c.is_finite() {
                        let v = (u as isize + off) as usize;
                        best = best.min(c + self.g[v]);
                    }
                }
            }
            self.rhs[u] = best;
        }
        self.in_open[u] = false;
        if self.g[u] != self.rhs[u] {
            let k = self.key(u);
            self.push(u, k);
        }
    }

    fn top(&mut self) -> Option<((f64, f64), usize)> {
        while let Some(e) = self.heap.peek() {
            let i = e.idx as usize;
            if self.in_open[i] && self.open_key[i] == (e.k1, e.k2) {
                return Some(((e.k1, e.k2), i));
            }
            self.heap.pop();
        }
        None
    }

    /// (Re-)plans: brings the cells that matter for the robot's position up to date.
    /// Returns the cost from the robot to the goal, `None` if unreachable.
    pub fn compute(&mut self) -> Option<f64> {
        self.expanded = 0;
        loop {
            let Some((k_old, u)) = self.top() else { break };
            let ks = self.key(self.start);
            if !(key_less(k_old, ks) || self.rhs[self.start] != self.g[self.start]) {
                break;
            }
            self.heap.pop();
            self.in_open[u] = false;
            self.expanded += 1;
            let k_new = self.key(u);
            if key_less(k_old, k_new) {
                self.push(u, k_new);
            } else if self.g[u] > self.rhs[u] {
                self.g[u] = self.rhs[u];
                self.update_neighbours(u);
            } else {
                self.g[u] = f64::INFINITY;
                self.update_vertex(u);
                self.update_neighbours(u);
            }
        }
        let c = self.g[self.start].min(self.rhs[self.start]);
        c.is_finite().then_some(c)
    }

    fn update_neighbours(&mut self, u: usize) {
        for k in 0..8 {
            let v = (u as isize + self.offsets[k].0) as usize;
            if self.grid.pass[v] {
                self.update_vertex(v);
            }
        }
    }

    /// Number of cells expanded by the last [`DStarLite::compute`].
    pub fn expanded(&self) -> usize {
        self.expanded
    }

    /// The robot's cell.
    pub fn start(&self) -> (usize, usize) {
        let (x, y) = self.xy(self.start);
        (x as usize - 1, y as usize - 1)
    }

    /// The current grid (with every change applied).
    pub fn grid(&self) -> &SearchGrid {
        &self.grid
    }

    /// Moves the robot to `cell` (normally the next cell of its path).
    pub fn move_start(&mut self, cell: (usize, usize)) -> Result<()> {
        self.grid.check_cell("robot", cell)?;
        let s = self.grid.pidx(cell.0, cell.1);
        self.km += self.h(self.last, s);
        self.last = s;
        self.start = s;
        Ok(())
    }

    /// Marks a cell blocked or free (a sensed change) and updates the affected cells; the
    /// next [`DStarLite::compute`] re-plans. Blocking the goal is an error.
    pub fn set_blocked(&mut self, cell: (usize, usize), blocked: bool) -> Result<()> {
        if cell.0 >= self.grid.width || cell.1 >= self.grid.height {
            return Err(Error::Planning(format!("changed cell ({}, {}) lies outside the map", cell.0, cell.1)));
        }
        let c = self.grid.pidx(cell.0, cell.1);
        if blocked && c == self.goal {
            return Err(Error::Planning(format!("cannot block the goal cell ({}, {})", cell.0, cell.1)));
        }
        if self.grid.pass[c] == !blocked {
            return Ok(());
        }
        self.grid.set_free(cell.0, cell.1, !blocked);
        // Every step whose cost changed has both ends in the 3 x 3 block around the cell
        // (the cell itself, or the two cells of a diagonal it used to permit).
        let pw = self.grid.pw as isize;
        for dy in -1..=1isize {
            for dx in -1..=1isize {
                let u = (c as isize + dy * pw + dx) as usize;
                if self.inside(u) {
                    if !self.grid.pass[u] {
                        // A blocked cell has no steps: its cost-to-goal is infinite.
                        self.rhs[u] = f64::INFINITY;
                        self.g[u] = f64::INFINITY;
                        self.in_open[u] = false;
                    } else {
                        self.update_vertex(u);
                    }
                }
            }
        }
        Ok(())
    }

    /// The current best path from the robot to the goal (greedy descent of `c + g`),
    /// `None` if unreachable. Call after [`DStarLite::compute`].
    pub fn path(&self) -> Option<Vec<(usize, usize)>> {
        if !self.g[self.start].is_finite() {
            return None;
        }
        let mut out = vec![self.start()];
        let mut u = self.start;
        let limit = self.grid.pass.len();
        while u != self.goal {
            let mut best = (f64::INFINITY, usize::MAX);
            for &(off, diag) in &self.offsets {
                let c = self.step_cost(u, off, diag);
                if c.is_finite() {
                    let v = (u as isize + off) as usize;
                    let val = c + self.g[v];
                    if val < best.0 {
                        best = (val, v);
                    }
                }
            }
            if best.1 == usize::MAX || out.len() > limit {
                return None;
            }
            u = best.1;
            let (x, y) = self.xy(u);
            out.push((x as usize - 1, y as usize - 1));
        }
        Some(out)
    }
}

//! D* Lite (Koenig & Likhachev, AAAI 2002; IEEE T-RO 21(3), 2005): re-planning for a robot
//! that moves along its path while cells become blocked or free.
//!
//! The search runs from the goal toward the robot, keeping for every cell its cost-to-goal
//! `g` and a one-step look-ahead `rhs`; after a change only the locally inconsistent cells
//! are re-expanded, and the key modifier `k_m` keeps the queue valid as the robot moves.
//! Move model as [`super::astar()`]: 8-connected, costs 1 / √2, no corner cutting, so
//! the cost after any change equals that of A* from scratch on the changed map.
//!
//! Costs and keys are exact fixed-point integers (the same scale as the A* search: a
//! straight step 2^k, a diagonal ≈ √2 · 2^k), so cells on the equal-cost plateaus of open
//! maps tie exactly instead of being ordered by floating-point rounding noise, and the
//! reported cost n_straight + n_diag · √2 is recovered exactly from the integer g.

use super::astar::{SQRT2, SearchGrid, fixed_point_length, fixed_point_steps};
use crate::{Error, Result};
use std::cmp::Ordering;
use std::collections::BinaryHeap;

#[derive(Clone, Copy, Debug)]
struct QEntry {
    k1: u64,
    k2: u64,
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
        o.k1.cmp(&self.k1).then(o.k2.cmp(&self.k2))
    }
}
impl PartialOrd for QEntry {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

#[inline]
fn key_less(a: (u64, u64), b: (u64, u64)) -> bool {
    a < b
}

/// "Infinite" cost-to-goal.
const INF: u64 = u64::MAX;

/// An incremental planner from a moving robot (`start`) to a fixed goal.
#[derive(Debug)]
#[doc(alias = "dstar")]
#[doc(alias = "d_star_lite")]
pub struct DStarLite {
    grid: SearchGrid,
    /// Per-cell g, rhs and queue key, side by side so one cache line serves all three.
    cells: Vec<CellState>,
    heap: BinaryHeap<QEntry>,
    km: u64,
    /// Fixed-point step costs (see the module documentation).
    one: u64,
    diag: u64,
    start: usize,
    /// Padded coordinates of `start`.
    start_xy: (i64, i64),
    last: usize,
    goal: usize,
    expanded: usize,
    offsets: [(isize, bool); 8],
}

/// Queue key of a cell that is not in the queue (an inconsistent cell always has a finite
/// key).
const NONE_KEY: (u64, u64) = (INF, INF);

/// g, rhs and the key under which the cell is queued ([`NONE_KEY`] = not queued).
#[derive(Clone, Copy, Debug)]
struct CellState {
    g: u64,
    rhs: u64,
    key: (u64, u64),
}

impl Clone for DStarLite {
    /// A copy that keeps the queue's spare capacity, so re-planning on the copy does not
    /// start by reallocating (and copying) a queue of the map's size.
    fn clone(&self) -> Self {
        let mut queue = Vec::with_capacity(self.heap.capacity());
        queue.extend_from_slice(self.heap.as_slice());
        Self {
            grid: self.grid.clone(),
            cells: self.cells.clone(),
            // Already a valid heap: rebuilding it moves nothing.
            heap: BinaryHeap::from(queue),
            km: self.km,
            one: self.one,
            diag: self.diag,
            start: self.start,
            start_xy: self.start_xy,
            last: self.last,
            goal: self.goal,
            expanded: self.expanded,
            offsets: self.offsets,
        }
    }

    /// Copies `source` into `self` reusing `self`'s allocations (a snapshot without
    /// allocating when both plan on the same map size).
    fn clone_from(&mut self, source: &Self) {
        self.grid.clone_from(&source.grid);
        self.cells.clone_from(&source.cells);
        self.heap.clone_from(&source.heap);
        self.km = source.km;
        self.one = source.one;
        self.diag = source.diag;
        self.start = source.start;
        self.start_xy = source.start_xy;
        self.last = source.last;
        self.goal = source.goal;
        self.expanded = source.expanded;
        self.offsets = source.offsets;
    }
}

impl DStarLite {
    /// Sets up a planner on a copy of `grid` from `start` to `goal` (cells `(x, y)`);
    /// call [`DStarLite::compute`] to plan.
    pub fn new(grid: &SearchGrid, start: (usize, usize), goal: (usize, usize)) -> Result<Self> {
        grid.check_cell("start", start)?;
        grid.check_cell("goal", goal)?;
        if grid.weight.is_some() {
            return Err(Error::invalid(
                "grid",
                "D* Lite runs on an unweighted grid (octile costs)",
            ));
        }
        let n = grid.pass.len();
        let pw = grid.pw as isize;
        let (one, diag) = fixed_point_steps(n);
        let mut s = Self {
            grid: grid.clone(),
            cells: vec![
                CellState {
                    g: INF,
                    rhs: INF,
                    key: NONE_KEY
                };
                n
            ],
            heap: BinaryHeap::new(),
            km: 0,
            one,
            diag,
            start: grid.pidx(start.0, start.1),
            start_xy: (start.0 as i64 + 1, start.1 as i64 + 1),
            last: grid.pidx(start.0, start.1),
            goal: grid.pidx(goal.0, goal.1),
            expanded: 0,
            offsets: [
                (1, false),
                (-1, false),
                (pw, false),
                (-pw, false),
                (pw + 1, true),
                (pw - 1, true),
                (-pw + 1, true),
                (-pw - 1, true),
            ],
        };
        s.cells[s.goal].rhs = 0;
        let k = s.key(s.goal);
        s.push(s.goal, k);
        Ok(s)
    }

    #[inline]
    fn xy(&self, i: usize) -> (i64, i64) {
        let y = i / self.grid.pw;
        ((i - y * self.grid.pw) as i64, y as i64)
    }

    #[inline]
    fn h(&self, a: usize, b: usize) -> u64 {
        let (ax, ay) = self.xy(a);
        let (bx, by) = self.xy(b);
        let (dx, dy) = ((ax - bx).unsigned_abs(), (ay - by).unsigned_abs());
        let (lo, hi) = if dx < dy { (dx, dy) } else { (dy, dx) };
        hi * self.one + lo * (self.diag - self.one)
    }

    #[inline]
    fn key(&self, s: usize) -> (u64, u64) {
        let m = self.cells[s].g.min(self.cells[s].rhs);
        if m == INF {
            return NONE_KEY;
        }
        let (x, y) = self.xy(s);
        let (dx, dy) = (
            (x - self.start_xy.0).unsigned_abs(),
            (y - self.start_xy.1).unsigned_abs(),
        );
        let (lo, hi) = if dx < dy { (dx, dy) } else { (dy, dx) };
        (m + hi * self.one + lo * (self.diag - self.one) + self.km, m)
    }

    fn push(&mut self, s: usize, k: (u64, u64)) {
        self.cells[s].key = k;
        self.heap.push(QEntry {
            k1: k.0,
            k2: k.1,
            idx: s as u32,
        });
    }

    /// Cost of the step from `u` by offset `k`, infinite if illegal.
    #[inline]
    fn step_cost(&self, u: usize, off: isize, diag: bool) -> u64 {
        let pass = &self.grid.pass;
        let v = (u as isize + off) as usize;
        if !pass[u] || !pass[v] {
            return INF;
        }
        if diag {
            let pw = self.grid.pw as isize;
            let dx = if off == pw + 1 || off == -pw + 1 {
                1
            } else {
                -1
            };
            let dy_off = off - dx;
            if !pass[(u as isize + dx) as usize] || !pass[(u as isize + dy_off) as usize] {
                return INF;
            }
            self.diag
        } else {
            self.one
        }
    }

    fn inside(&self, i: usize) -> bool {
        let (x, y) = self.xy(i);
        x >= 1 && y >= 1 && (x as usize) <= self.grid.width && (y as usize) <= self.grid.height
    }

    /// The costs of the eight steps from `u` (offsets as `self.offsets`), `INF` if illegal.
    #[inline]
    fn step_costs(&self, u: usize) -> [u64; 8] {
        let pass = &self.grid.pass;
        let mut c = [INF; 8];
        if !pass[u] {
            return c;
        }
        let mut open = [false; 4];
        for k in 0..4 {
            open[k] = pass[(u as isize + self.offsets[k].0) as usize];
            if open[k] {
                c[k] = self.one;
            }
        }
        // Diagonals 4..8 pass between cardinals (0 | 1) and (2 | 3), as in the A* search.
        for k in 4..8 {
            let (a, b) = (k & 1, 2 + ((k - 4) >> 1));
            if open[a] && open[b] && pass[(u as isize + self.offsets[k].0) as usize] {
                c[k] = self.diag;
            }
        }
        c
    }

    /// rhs(u) = min over the steps u → v of c(u, v) + g(v) (0 at the goal).
    #[inline]
    fn recompute_rhs(&mut self, u: usize) {
        if u == self.goal {
            return;
        }
        let c = self.step_costs(u);
        let mut best = INF;
        for (k, &ck) in c.iter().enumerate() {
            if ck != INF {
                let v = (u as isize + self.offsets[k].0) as usize;
                best = best.min(ck.saturating_add(self.cells[v].g));
            }
        }
        self.cells[u].rhs = best;
    }

    /// Puts `u` in the queue with its current key if it is inconsistent (unless it is
    /// already there with that key), takes it out otherwise.
    #[inline]
    fn update_queue(&mut self, u: usize) {
        if self.cells[u].g != self.cells[u].rhs {
            let k = self.key(u);
            if self.cells[u].key != k {
                self.push(u, k);
            }
        } else {
            self.cells[u].key = NONE_KEY;
        }
    }

    fn update_vertex(&mut self, u: usize) {
        self.recompute_rhs(u);
        self.update_queue(u);
    }

    fn top(&mut self) -> Option<((u64, u64), usize)> {
        while let Some(e) = self.heap.peek() {
            let i = e.idx as usize;
            if self.cells[i].key == (e.k1, e.k2) {
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
        while let Some((k_old, u)) = self.top() {
            let st = self.start;
            let ms = self.cells[st].g.min(self.cells[st].rhs);
            let ks = if ms == INF {
                NONE_KEY
            } else {
                (ms + self.km, ms)
            };
            if !(key_less(k_old, ks) || self.cells[st].rhs != self.cells[st].g) {
                break;
            }
            self.heap.pop();
            self.cells[u].key = NONE_KEY;
            self.expanded += 1;
            let k_new = self.key(u);
            if key_less(k_old, k_new) {
                self.push(u, k_new);
            } else if self.cells[u].g > self.cells[u].rhs {
                // Overconsistent: g(u) drops to rhs(u); a neighbour's rhs can only fall
                // to the cost through u (Koenig & Likhachev's optimized D* Lite).
                let gu = self.cells[u].rhs;
                self.cells[u].g = gu;
                let c = self.step_costs(u);
                for (k, &ck) in c.iter().enumerate() {
                    if ck != INF {
                        let v = (u as isize + self.offsets[k].0) as usize;
                        if v != self.goal && ck + gu < self.cells[v].rhs {
                            self.cells[v].rhs = ck + gu;
                            self.update_queue(v);
                        }
                    }
                }
            } else {
                // Underconsistent: g(u) becomes infinite; only the neighbours whose rhs
                // came through u (and u itself) need their rhs recomputed.
                let g_old = self.cells[u].g;
                self.cells[u].g = INF;
                let c = self.step_costs(u);
                for (k, &ck) in c.iter().enumerate() {
                    if ck != INF {
                        let v = (u as isize + self.offsets[k].0) as usize;
                        if v != self.goal && self.cells[v].rhs == ck.saturating_add(g_old) {
                            self.update_vertex(v);
                        }
                    }
                }
                self.update_vertex(u);
            }
        }
        let c = self.cells[self.start].g.min(self.cells[self.start].rhs);
        if c == INF {
            return None;
        }
        fixed_point_length(c, self.one, self.diag).or_else(|| self.path_length())
    }

    /// n_straight + n_diag · √2 along [`DStarLite::path`] (huge maps only; see
    /// [`fixed_point_length`]).
    fn path_length(&self) -> Option<f64> {
        let p = self.path()?;
        Some(
            p.windows(2)
                .map(|w| {
                    if w[0].0 != w[1].0 && w[0].1 != w[1].1 {
                        SQRT2
                    } else {
                        1.0
                    }
                })
                .sum(),
        )
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
        self.start_xy = self.xy(s);
        Ok(())
    }

    /// Marks a cell blocked or free (a sensed change) and updates the affected cells; the
    /// next [`DStarLite::compute`] re-plans. Blocking the goal is an error.
    pub fn set_blocked(&mut self, cell: (usize, usize), blocked: bool) -> Result<()> {
        if cell.0 >= self.grid.width || cell.1 >= self.grid.height {
            return Err(Error::Planning(format!(
                "changed cell ({}, {}) lies outside the map",
                cell.0, cell.1
            )));
        }
        let c = self.grid.pidx(cell.0, cell.1);
        if blocked && c == self.goal {
            return Err(Error::Planning(format!(
                "cannot block the goal cell ({}, {})",
                cell.0, cell.1
            )));
        }
        if self.grid.pass[c] != blocked {
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
                        self.cells[u].rhs = INF;
                        self.cells[u].g = INF;
                        self.cells[u].key = NONE_KEY;
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
        if self.cells[self.start].g == INF {
            return None;
        }
        let mut out = vec![self.start()];
        let mut u = self.start;
        let limit = self.grid.pass.len();
        while u != self.goal {
            let mut best = (INF, usize::MAX);
            for &(off, diag) in &self.offsets {
                let c = self.step_cost(u, off, diag);
                if c != INF {
                    let v = (u as isize + off) as usize;
                    let val = c.saturating_add(self.cells[v].g);
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

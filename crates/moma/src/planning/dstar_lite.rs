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
//!
//! Queue: an indexed 4-ary min-heap with each inconsistent cell exactly once (keys are
//! raised, lowered and removed in place). After the robot moves, queued keys are lower
//! bounds (the `k_m` scheme); a popped stale key is re-keyed in place, and once stale keys
//! add up to 1/16 of the queue the whole queue is re-keyed in one linear pass (the k2 =
//! min(g, rhs) part is stored in the entry, so no cell state is read) and rebuilt.
//! Unreachable goal: when the robot's cell becomes consistent at infinite cost, a
//! budgeted flood fill from the robot decides whether the goal is cut off, instead of
//! letting the search expand every remaining queued cell.

use super::astar::{RowDivider, SQRT2, SearchGrid, fixed_point_length, fixed_point_steps};
use crate::{Error, Result};

/// "Infinite" cost-to-goal.
const INF: u64 = u64::MAX;

/// Heap slot of a cell that is not in the queue.
const NOT_QUEUED: u32 = u32::MAX;

/// Queue key `[k1, k2]`, compared lexicographically (exact integers).
type Key = (u64, u64);

/// Key of a cell that is not in the queue (an inconsistent cell always has a finite key).
const NONE_KEY: Key = (INF, INF);

/// Children per node of the queue's heap: four 24-byte entries side by side, so one
/// sift-down step compares entries that share one or two cache lines, and the heap is half
/// as deep as a binary one.
const ARITY: usize = 4;
// The sift-down's tournament is written for four children.
const _: () = assert!(ARITY == 4);

/// An entry of the indexed priority queue.
#[derive(Clone, Copy, Debug)]
struct QEntry {
    k1: u64,
    k2: u64,
    idx: u32,
}

impl QEntry {
    #[inline(always)]
    fn key(&self) -> Key {
        (self.k1, self.k2)
    }

    /// The key as one 128-bit integer (k1 in the high half): the same order as
    /// [`QEntry::key`] in a single wide compare.
    #[inline(always)]
    fn rank(&self) -> u128 {
        ((self.k1 as u128) << 64) | self.k2 as u128
    }
}

/// g and rhs of a cell, side by side (16 bytes: four cells per cache line).
#[derive(Clone, Copy, Debug)]
struct CellState {
    g: u64,
    rhs: u64,
}

/// An incremental planner from a moving robot (`start`) to a fixed goal.
#[derive(Debug)]
#[doc(alias = "dstar")]
#[doc(alias = "d_star_lite")]
pub struct DStarLite {
    grid: SearchGrid,
    /// Per-cell g and rhs.
    cells: Vec<CellState>,
    /// Per-cell slot in `heap` ([`NOT_QUEUED`] if absent); 4 bytes a cell, so the heap's
    /// bookkeeping touches few cache lines.
    slots: Vec<u32>,
    /// The open list U: an indexed 4-ary min-heap on the keys, holding every locally
    /// inconsistent cell exactly once (keys are updated and entries removed in place, so
    /// there are no stale duplicates).
    heap: Vec<QEntry>,
    km: u64,
    /// `true` while every queued key is exact for the current robot cell and `km` (the
    /// robot has not moved since the queue was last re-keyed).
    keys_exact: bool,
    /// Fixed-point step costs (see the module documentation).
    one: u64,
    diag: u64,
    start: usize,
    /// Padded coordinates of `start`.
    start_xy: (i64, i64),
    last: usize,
    goal: usize,
    expanded: usize,
    /// Scratch of the connectivity check (see [`DStarLite::compute`]): a visit stamp per
    /// cell, the stamp of the current check, and the flood's stack. Not part of the
    /// planner's state: copies start with their own.
    visit: Vec<u32>,
    visit_stamp: u32,
    flood: Vec<u32>,
    /// Padded row length, and division by it (row of an index without a `div`).
    pw: usize,
    rows: RowDivider,
    /// Padded-index offset and (dx, dy) of the eight moves: E, W, N, S, then the diagonals
    /// NE, NW, SE, SW (diagonal k passes between cardinals k & 1 and 2 + (k − 4) / 2).
    offsets: [(isize, i64, i64); 8],
}

impl Clone for DStarLite {
    /// A copy that keeps the queue's spare capacity, so re-planning on the copy does not
    /// start by reallocating (and copying) the queue.
    fn clone(&self) -> Self {
        let mut heap = Vec::with_capacity(self.heap.capacity());
        heap.extend_from_slice(&self.heap);
        Self {
            grid: self.grid.clone(),
            cells: self.cells.clone(),
            slots: self.slots.clone(),
            heap,
            km: self.km,
            keys_exact: self.keys_exact,
            one: self.one,
            diag: self.diag,
            start: self.start,
            start_xy: self.start_xy,
            last: self.last,
            goal: self.goal,
            expanded: self.expanded,
            visit: Vec::new(),
            visit_stamp: 0,
            flood: Vec::new(),
            pw: self.pw,
            rows: self.rows,
            offsets: self.offsets,
        }
    }

    /// Copies `source` into `self` reusing `self`'s allocations (a snapshot without
    /// allocating when both plan on the same map size).
    fn clone_from(&mut self, source: &Self) {
        self.grid.clone_from(&source.grid);
        self.cells.clone_from(&source.cells);
        self.slots.clone_from(&source.slots);
        self.heap.clone_from(&source.heap);
        self.km = source.km;
        self.keys_exact = source.keys_exact;
        self.one = source.one;
        self.diag = source.diag;
        self.start = source.start;
        self.start_xy = source.start_xy;
        self.last = source.last;
        self.goal = source.goal;
        self.expanded = source.expanded;
        self.pw = source.pw;
        self.rows = source.rows;
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
            cells: vec![CellState { g: INF, rhs: INF }; n],
            slots: vec![NOT_QUEUED; n],
            heap: Vec::new(),
            km: 0,
            keys_exact: true,
            one,
            diag,
            start: grid.pidx(start.0, start.1),
            start_xy: (start.0 as i64 + 1, start.1 as i64 + 1),
            last: grid.pidx(start.0, start.1),
            goal: grid.pidx(goal.0, goal.1),
            expanded: 0,
            visit: Vec::new(),
            visit_stamp: 0,
            flood: Vec::new(),
            pw: grid.pw,
            rows: RowDivider::new(grid.pw),
            offsets: [
                (1, 1, 0),
                (-1, -1, 0),
                (pw, 0, 1),
                (-pw, 0, -1),
                (pw + 1, 1, 1),
                (pw - 1, -1, 1),
                (-pw + 1, 1, -1),
                (-pw - 1, -1, -1),
            ],
        };
        let goal = s.goal;
        s.cells[goal].rhs = 0;
        let (gx, gy) = s.xy(goal);
        let k = s.key_at(goal, gx, gy);
        s.heap_set(goal, k);
        Ok(s)
    }

    /// Padded coordinates of index `i` (no integer division).
    #[inline]
    fn xy(&self, i: usize) -> (i64, i64) {
        self.rows.xy(i)
    }

    /// Octile heuristic in fixed point between padded coordinates.
    #[inline]
    fn h_xy(&self, a: (i64, i64), b: (i64, i64)) -> u64 {
        let (dx, dy) = ((a.0 - b.0).unsigned_abs(), (a.1 - b.1).unsigned_abs());
        let (lo, hi) = if dx < dy { (dx, dy) } else { (dy, dx) };
        hi * self.one + lo * (self.diag - self.one)
    }

    /// The key `[min(g, rhs) + h(start, s) + k_m, min(g, rhs)]` of cell `s` at padded
    /// coordinates `(x, y)`.
    #[inline]
    fn key_at(&self, s: usize, x: i64, y: i64) -> Key {
        let c = &self.cells[s];
        let m = c.g.min(c.rhs);
        if m == INF {
            return NONE_KEY;
        }
        (m + self.h_xy((x, y), self.start_xy) + self.km, m)
    }

    // ---- Indexed 4-ary min-heap --------------------------------------------------------

    #[inline(always)]
    fn heap_place(&mut self, slot: usize, e: QEntry) {
        self.slots[e.idx as usize] = slot as u32;
        self.heap[slot] = e;
    }

    #[inline]
    fn sift_up(&mut self, mut slot: usize, e: QEntry) {
        let k = e.rank();
        while slot > 0 {
            let parent = (slot - 1) / ARITY;
            let p = self.heap[parent];
            if p.rank() <= k {
                break;
            }
            self.heap_place(slot, p);
            slot = parent;
        }
        self.heap_place(slot, e);
    }

    #[inline]
    fn sift_down(&mut self, slot: usize, e: QEntry) {
        self.sift_down_impl::<true>(slot, e);
    }

    /// Sift-down; `TRACK` = keep `slots` up to date (off while re-heapifying, which
    /// rewrites every slot afterwards).
    #[inline]
    fn sift_down_impl<const TRACK: bool>(&mut self, mut slot: usize, e: QEntry) {
        let k = e.rank();
        let n = self.heap.len();
        loop {
            let first = slot * ARITY + 1;
            if first >= n {
                break;
            }
            let (best, bk) = if first + ARITY <= n {
                // A full node: a branch-free tournament over the four children.
                let q = &self.heap[first..first + ARITY];
                let (r0, r1, r2, r3) = (q[0].rank(), q[1].rank(), q[2].rank(), q[3].rank());
                let (a, ra) = if r1 < r0 { (1, r1) } else { (0, r0) };
                let (b, rb) = if r3 < r2 { (3, r3) } else { (2, r2) };
                if rb < ra {
                    (first + b, rb)
                } else {
                    (first + a, ra)
                }
            } else {
                let mut best = first;
                let mut bk = self.heap[first].rank();
                for c in first + 1..n {
                    let ck = self.heap[c].rank();
                    if ck < bk {
                        best = c;
                        bk = ck;
                    }
                }
                (best, bk)
            };
            if bk >= k {
                break;
            }
            let b = self.heap[best];
            if TRACK {
                self.heap_place(slot, b);
            } else {
                self.heap[slot] = b;
            }
            slot = best;
        }
        if TRACK {
            self.heap_place(slot, e);
        } else {
            self.heap[slot] = e;
        }
    }

    /// Recomputes every queued key for the current robot cell and `km` (k2 = min(g, rhs)
    /// is stored in the entry, so no cell state is read), then rebuilds the heap in
    /// O(n) (Floyd) and rewrites the slots.
    fn rekey_all(&mut self) {
        let (start_xy, km) = (self.start_xy, self.km);
        for i in 0..self.heap.len() {
            let e = self.heap[i];
            let h = self.h_xy(self.xy(e.idx as usize), start_xy);
            self.heap[i].k1 = e.k2 + h + km;
        }
        let n = self.heap.len();
        if n > 1 {
            for i in (0..=(n - 2) / ARITY).rev() {
                let e = self.heap[i];
                self.sift_down_impl::<false>(i, e);
            }
        }
        for (i, e) in self.heap.iter().enumerate() {
            self.slots[e.idx as usize] = i as u32;
        }
        self.keys_exact = true;
    }

    /// Inserts `u` with key `k`, or moves it to `k` if it is queued already.
    #[inline]
    fn heap_set(&mut self, u: usize, k: Key) {
        let e = QEntry {
            k1: k.0,
            k2: k.1,
            idx: u as u32,
        };
        let slot = self.slots[u];
        if slot == NOT_QUEUED {
            self.heap.push(e);
            let last = self.heap.len() - 1;
            self.sift_up(last, e);
        } else {
            let slot = slot as usize;
            let old = self.heap[slot].key();
            if k < old {
                self.sift_up(slot, e);
            } else if k > old {
                self.sift_down(slot, e);
            }
        }
    }

    /// Takes `u` out of the queue (if queued).
    #[inline]
    fn heap_remove(&mut self, u: usize) {
        let slot = self.slots[u];
        if slot == NOT_QUEUED {
            return;
        }
        self.slots[u] = NOT_QUEUED;
        let slot = slot as usize;
        let last = self.heap.pop().expect("a queued cell is in the heap");
        if slot < self.heap.len() {
            // The last entry fills the hole, moving up or down from there.
            let removed = self.heap[slot].key();
            if last.key() < removed {
                self.sift_up(slot, last);
            } else {
                self.sift_down(slot, last);
            }
        }
    }

    // ---- D* Lite -------------------------------------------------------------------------

    /// Cost of the step from `u` by move `k`, infinite if illegal.
    #[inline]
    fn step_cost(&self, u: usize, k: usize) -> u64 {
        if self.grid.moves[u] & (1 << k) == 0 {
            INF
        } else if k < 4 {
            self.one
        } else {
            self.diag
        }
    }

    fn inside(&self, i: usize) -> bool {
        let (x, y) = self.xy(i);
        x >= 1 && y >= 1 && (x as usize) <= self.grid.width && (y as usize) <= self.grid.height
    }

    /// The costs of the eight steps from `u` (offsets as `self.offsets`), `INF` if illegal
    /// (from the grid's legal-move mask: one byte read).
    #[inline]
    fn step_costs(&self, u: usize) -> [u64; 8] {
        let m = self.grid.moves[u];
        let mut c = [INF; 8];
        for (k, ck) in c.iter_mut().enumerate() {
            if m & (1 << k) != 0 {
                *ck = if k < 4 { self.one } else { self.diag };
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

    /// Queues `u` (at padded `(x, y)`) with its current key if it is inconsistent, takes
    /// it out of the queue otherwise.
    #[inline]
    fn update_queue_at(&mut self, u: usize, x: i64, y: i64) {
        if self.cells[u].g != self.cells[u].rhs {
            let k = self.key_at(u, x, y);
            self.heap_set(u, k);
        } else {
            self.heap_remove(u);
        }
    }

    fn update_vertex(&mut self, u: usize) {
        self.recompute_rhs(u);
        let (x, y) = self.xy(u);
        self.update_queue_at(u, x, y);
    }

    /// (Re-)plans: brings the cells that matter for the robot's position up to date.
    /// Returns the cost from the robot to the goal, `None` if unreachable.
    pub fn compute(&mut self) -> Option<f64> {
        self.expanded = 0;
        // Stale keys re-keyed one by one so far in this call.
        let mut stale = 0usize;
        // Connectivity check schedule (see below): expansion count of the next check and
        // the flood budget in cells.
        let mut next_check = 0usize;
        let mut budget = 16_384usize;
        while let Some(&top) = self.heap.first() {
            let k_old = top.key();
            let u = top.idx as usize;
            let st = self.start;
            let (gs, rs) = (self.cells[st].g, self.cells[st].rhs);
            let ms = gs.min(rs);
            let ks = if ms == INF {
                NONE_KEY
            } else {
                (ms + self.km, ms)
            };
            if k_old >= ks && rs == gs {
                break;
            }
            if ms == INF && rs == gs && self.expanded >= next_check {
                // The robot's cell is consistent at an infinite cost: either a lowering
                // wave has yet to reach it or the goal is cut off, in which case D* Lite
                // would expand every queued cell before giving up. A flood over the free
                // cells from the robot (4-connectivity = connectivity under the move
                // model) tells the two apart. A flood step costs a few ns, an expansion
                // some 100 ns: the checks come after 0, 512, 1024, 2048, … expansions with
                // budgets of 16 Ki, 64 Ki, 256 Ki, … cells (a flood never visits more than
                // the robot's component), so a cut-off goal is found after a few checks
                // and a check that gives up costs about as much as a few hundred
                // expansions.
                match self.goal_connected(budget) {
                    Some(false) => return None,
                    Some(true) => next_check = usize::MAX,
                    None => {
                        next_check = 2 * self.expanded.max(256);
                        budget *= 4;
                    }
                }
            }
            let (x, y) = self.xy(u);
            let k_new = self.key_at(u, x, y);
            if k_old < k_new {
                // A stale lower-bound key (the robot moved since it was queued). Re-keying
                // one entry is a sift-down with cache misses on the way; once they add up
                // to a fair fraction of the queue, re-key the whole queue in one linear
                // pass instead (its cost is then at most a small multiple of what was
                // already spent, and no stale key is left until the robot moves again).
                stale += 1;
                if !self.keys_exact && stale >= 16 && stale * 16 >= self.heap.len() {
                    self.rekey_all();
                    continue;
                }
                let e = QEntry {
                    k1: k_new.0,
                    k2: k_new.1,
                    idx: u as u32,
                };
                self.sift_down(0, e);
                continue;
            }
            self.expanded += 1;
            let CellState { g, rhs } = self.cells[u];
            if g > rhs {
                self.lower_to_rhs(u, x, y, rhs);
            } else {
                self.raise_to_infinity(u, x, y, g);
            }
        }
        let c = self.cells[self.start].g.min(self.cells[self.start].rhs);
        if c == INF {
            return None;
        }
        fixed_point_length(c, self.one, self.diag).or_else(|| self.path_length())
    }

    /// Expands the overconsistent cell `u` (at padded `(x, y)`): g(u) drops to rhs(u); a
    /// neighbour's rhs can only fall to the cost through u (Koenig & Likhachev's
    /// optimized D* Lite).
    #[inline(always)]
    fn lower_to_rhs(&mut self, u: usize, x: i64, y: i64, rhs: u64) {
        self.heap_remove(u);
        self.cells[u].g = rhs;
        let c = self.step_costs(u);
        for (k, &ck) in c.iter().enumerate() {
            if ck != INF {
                let (off, dx, dy) = self.offsets[k];
                let v = (u as isize + off) as usize;
                let through = ck + rhs;
                let cv = self.cells[v];
                if v != self.goal && through < cv.rhs {
                    self.cells[v].rhs = through;
                    if cv.g != through {
                        let kv = self.key_at(v, x + dx, y + dy);
                        self.heap_set(v, kv);
                    } else {
                        self.heap_remove(v);
                    }
                }
            }
        }
    }

    /// Expands the underconsistent cell `u` (at padded `(x, y)`, old g `g`): g(u) becomes
    /// infinite; only the neighbours whose rhs came through u need their rhs recomputed
    /// (rhs(u) itself does not depend on g(u)).
    #[inline(always)]
    fn raise_to_infinity(&mut self, u: usize, x: i64, y: i64, g: u64) {
        self.cells[u].g = INF;
        let c = self.step_costs(u);
        for (k, &ck) in c.iter().enumerate() {
            if ck != INF {
                let (off, dx, dy) = self.offsets[k];
                let v = (u as isize + off) as usize;
                if v != self.goal && self.cells[v].rhs == ck.saturating_add(g) {
                    self.recompute_rhs(v);
                    self.update_queue_at(v, x + dx, y + dy);
                }
            }
        }
        self.update_queue_at(u, x, y);
    }

    /// Whether the goal is reachable from the robot's cell on the current grid: a flood
    /// over free cells that gives up (`None`) after `budget` cells.
    fn goal_connected(&mut self, budget: usize) -> Option<bool> {
        if !self.grid.pass[self.start] {
            // A blocked robot cell has no legal step (its cost-to-goal is infinite).
            return Some(false);
        }
        let n = self.grid.pass.len();
        if self.visit.len() != n || self.visit_stamp == u32::MAX {
            self.visit = vec![0; n];
            self.visit_stamp = 0;
        }
        self.visit_stamp += 1;
        let stamp = self.visit_stamp;
        let pw = self.pw as isize;
        let mut stack = std::mem::take(&mut self.flood);
        stack.clear();
        stack.push(self.start as u32);
        self.visit[self.start] = stamp;
        let mut seen = 1usize;
        let mut result = Some(false);
        let goal_xy = self.xy(self.goal);
        'flood: while let Some(u) = stack.pop() {
            // Depth first, the neighbour nearest the goal on top of the stack: in open
            // space the flood runs straight to the goal, in a maze it still covers the
            // robot's component.
            let (ux, uy) = self.xy(u as usize);
            let (ddx, ddy) = (goal_xy.0 - ux, goal_xy.1 - uy);
            let (xt, yt) = (
                if ddx >= 0 { 1 } else { -1 },
                if ddy >= 0 { pw } else { -pw },
            );
            let order = if ddx.abs() >= ddy.abs() {
                [-xt, -yt, yt, xt]
            } else {
                [-xt, -yt, xt, yt]
            };
            for off in order {
                let v = (u as isize + off) as usize;
                if self.grid.pass[v] && self.visit[v] != stamp {
                    if v == self.goal {
                        result = Some(true);
                        break 'flood;
                    }
                    self.visit[v] = stamp;
                    seen += 1;
                    if seen > budget {
                        result = None;
                        break 'flood;
                    }
                    stack.push(v as u32);
                }
            }
        }
        self.flood = stack;
        result
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

    /// Number of cells expanded by the last [`DStarLite::compute`] (made consistent or
    /// raised; re-keying a stale queue entry is not counted).
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
        let dk = self.h_xy(self.xy(self.last), self.xy(s));
        self.km += dk;
        if dk != 0 {
            self.keys_exact = false;
        }
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
                        self.heap_remove(u);
                        self.cells[u].rhs = INF;
                        self.cells[u].g = INF;
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
            for (k, &(off, _, _)) in self.offsets.iter().enumerate() {
                let c = self.step_cost(u, k);
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

//! A* on the 8-connected grid: octile costs (1 and √2), no corner cutting, plus a
//! cost-aware variant over an inflation costmap and a Dijkstra wavefront.
//!
//! The move model is the Moving AI benchmarks' (hog2 `MapEnvironment`): a diagonal step
//! is legal only if both orthogonal cells it passes between are free.
//!
//! Implementation: the grid is stored with a one-cell border of blocked cells so the
//! eight neighbours are fixed index offsets with no bounds checks; search state lives in
//! flat arrays reused across queries and invalidated by a generation counter. The
//! unweighted search orders by exact fixed-point integer f (straight = 2^k, diagonal =
//! the odd integer nearest √2·2^k). Its state is one `u32` g per cell (k = 18; 1 MB for a
//! 512 × 512 map, so a search stays in the L2 cache even right after other work has
//! evicted it), reset through a list of the cells reached; a query whose costs outgrow 32
//! bits reruns the same search on a `u64` g. Its open list is a calendar queue over the
//! bounded window of keys an A* open list holds (`BandQueue`); the cost-aware search uses
//! a radix heap (`OpenList`); both pop
//! the same order: increasing f, ties toward the most recently generated (deepest,
//! larger-g) cells. The reported cost is n_straight + n_diag · √2 of the path found,
//! recovered exactly from its integer cost.

use super::grid::OccupancyGrid;
use crate::{Error, Result};
use std::cmp::Ordering;
use std::collections::BinaryHeap;

/// √2, the diagonal step cost.
pub const SQRT2: f64 = std::f64::consts::SQRT_2;

/// A padded passability grid for the searches (`true` = traversable).
#[derive(Debug, PartialEq)]
pub struct SearchGrid {
    pub(super) width: usize,
    pub(super) height: usize,
    pub(super) pw: usize,
    pub(super) pass: Vec<bool>,
    /// Per cell, bit k set ⇔ move k (order of [`move_offsets`]) from it is legal: both
    /// cells free and, for a diagonal, both cells it passes between free. Kept up to date
    /// by [`SearchGrid::set_free`]; lets a search visit the legal moves only.
    pub(super) moves: Vec<u8>,
    pub(super) weight: Option<Vec<f32>>,
}

impl Clone for SearchGrid {
    fn clone(&self) -> Self {
        Self {
            width: self.width,
            height: self.height,
            pw: self.pw,
            pass: self.pass.clone(),
            moves: self.moves.clone(),
            weight: self.weight.clone(),
        }
    }

    /// Copies `source` into `self` reusing `self`'s buffers (no allocation for grids of
    /// the same size; `D* Lite`'s snapshots rely on it).
    fn clone_from(&mut self, source: &Self) {
        self.width = source.width;
        self.height = source.height;
        self.pw = source.pw;
        self.pass.clone_from(&source.pass);
        self.moves.clone_from(&source.moves);
        self.weight.clone_from(&source.weight);
    }
}

/// The legal-move mask of padded cell `u` (see [`SearchGrid::moves`]).
#[inline]
fn move_mask(pass: &[bool], pw: usize, u: usize) -> u8 {
    if !pass[u] {
        return 0;
    }
    let off = move_offsets(pw);
    let mut m = 0u8;
    for k in 0..4 {
        if pass[(u as isize + off[k]) as usize] {
            m |= 1 << k;
        }
    }
    // Diagonals 4..8 pass between cardinals (0 | 1) and (2 | 3).
    for k in 4..8 {
        let (a, b) = (k & 1, 2 + ((k - 4) >> 1));
        if m & (1 << a) != 0 && m & (1 << b) != 0 && pass[(u as isize + off[k]) as usize] {
            m |= 1 << k;
        }
    }
    m
}

/// A found path.
#[derive(Debug, Clone, PartialEq)]
pub struct GridPath {
    /// Cells `(x, y)` from start to goal, both included.
    pub cells: Vec<(usize, usize)>,
    /// Path cost: its length in cells (1 per straight, √2 per diagonal step), or for the
    /// cost-aware search the weighted cost.
    pub cost: f64,
    /// Number of expanded (closed) cells.
    pub expanded: usize,
}

impl GridPath {
    /// Geometric length of the path in cells (1 per straight step, √2 per diagonal).
    pub fn length(&self) -> f64 {
        self.cells
            .windows(2)
            .map(|w| {
                if w[0].0 != w[1].0 && w[0].1 != w[1].1 {
                    SQRT2
                } else {
                    1.0
                }
            })
            .sum()
    }
}

impl SearchGrid {
    /// Builds the search grid from a row-major obstacle mask (`true` = obstacle).
    pub fn from_obstacles(obstacles: &[bool], width: usize, height: usize) -> Result<Self> {
        super::grid::check_size(width, height)?;
        crate::error::ensure_len("obstacle mask", width * height, obstacles.len())?;
        let pw = width + 2;
        let mut pass = vec![false; pw * (height + 2)];
        for y in 0..height {
            let src = &obstacles[y * width..(y + 1) * width];
            let dst = &mut pass[(y + 1) * pw + 1..(y + 1) * pw + 1 + width];
            for (d, &o) in dst.iter_mut().zip(src) {
                *d = !o;
            }
        }
        let mut moves = vec![0u8; pass.len()];
        for y in 1..=height {
            for u in y * pw + 1..y * pw + 1 + width {
                moves[u] = move_mask(&pass, pw, u);
            }
        }
        Ok(Self {
            width,
            height,
            pw,
            pass,
            moves,
            weight: None,
        })
    }

    /// Builds the search grid from an occupancy grid: cells ≥ 100 are obstacles, unknown
    /// cells too when `unknown_is_obstacle`.
    ///
    /// # Errors
    /// An inconsistent grid (its fields are public): a size out of range, or a cell
    /// vector whose length is not `width · height`.
    pub fn from_grid(grid: &OccupancyGrid, unknown_is_obstacle: bool) -> Result<Self> {
        super::grid::check_size(grid.width, grid.height)?;
        crate::error::ensure_len(
            "occupancy grid cells",
            grid.width * grid.height,
            grid.cells.len(),
        )?;
        let obst = grid.obstacle_mask(super::grid::OCCUPIED, unknown_is_obstacle);
        Self::from_obstacles(&obst, grid.width, grid.height)
    }

    /// A cost-aware grid from nav2-style costs (see [`super::costmap`]): cells with cost
    /// ≥ 253 (inscribed, lethal) are obstacles, 255 (unknown) too unless `allow_unknown`;
    /// every step into a cell of cost c costs `(1 or √2) · (1 + multiplier · c / 252)`
    /// (Smac 2D's `cost_travel_multiplier`; `multiplier` ≥ 0).
    pub fn from_costs(
        costs: &[u8],
        width: usize,
        height: usize,
        multiplier: f64,
        allow_unknown: bool,
    ) -> Result<Self> {
        if !(multiplier.is_finite() && multiplier >= 0.0) {
            return Err(Error::invalid(
                "cost multiplier",
                format!("must be finite and >= 0, got {multiplier}"),
            ));
        }
        crate::error::ensure_len("costmap", width * height, costs.len())?;
        let obst: Vec<bool> = costs
            .iter()
            .map(|&c| {
                if c == super::grid::NO_INFORMATION {
                    !allow_unknown
                } else {
                    c >= super::grid::INSCRIBED
                }
            })
            .collect();
        let mut g = Self::from_obstacles(&obst, width, height)?;
        let mut w = vec![1.0f32; g.pass.len()];
        for y in 0..height {
            for x in 0..width {
                let c = costs[y * width + x];
                let c = if c == super::grid::NO_INFORMATION {
                    0
                } else {
                    c
                };
                w[(y + 1) * g.pw + x + 1] = (1.0 + multiplier * c as f64 / 252.0) as f32;
            }
        }
        g.weight = Some(w);
        Ok(g)
    }

    /// Number of columns.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Number of rows.
    pub fn height(&self) -> usize {
        self.height
    }

    #[inline]
    pub(super) fn pidx(&self, x: usize, y: usize) -> usize {
        (y + 1) * self.pw + x + 1
    }

    /// `true` if `(x, y)` is inside the grid and traversable.
    pub fn is_free(&self, x: i64, y: i64) -> bool {
        x >= 0
            && y >= 0
            && (x as usize) < self.width
            && (y as usize) < self.height
            && self.pass[self.pidx(x as usize, y as usize)]
    }

    /// Marks `(x, y)` traversable or blocked.
    ///
    /// # Panics
    /// If the cell is outside the grid.
    pub fn set_free(&mut self, x: usize, y: usize, free: bool) {
        assert!(x < self.width && y < self.height, "cell outside the grid");
        let i = self.pidx(x, y);
        if self.pass[i] == free {
            return;
        }
        self.pass[i] = free;
        // The moves of the cell and of its eight neighbours depend on it (border cells
        // are blocked and keep an empty mask).
        let pw = self.pw;
        for r in [i - pw, i, i + pw] {
            for u in r - 1..=r + 1 {
                self.moves[u] = move_mask(&self.pass, pw, u);
            }
        }
    }

    /// `true` if the step from `(x, y)` by `(dx, dy)` (each in −1..=1) is legal under the
    /// no-corner-cutting model.
    pub fn can_step(&self, x: i64, y: i64, dx: i64, dy: i64) -> bool {
        self.is_free(x + dx, y + dy)
            && (dx == 0 || dy == 0 || (self.is_free(x + dx, y) && self.is_free(x, y + dy)))
    }

    /// The obstacle mask (`true` = blocked), row-major without the border.
    pub fn obstacles(&self) -> Vec<bool> {
        let mut out = Vec::with_capacity(self.width * self.height);
        for y in 0..self.height {
            for x in 0..self.width {
                out.push(!self.pass[self.pidx(x, y)]);
            }
        }
        out
    }

    /// Checks that a query cell lies inside the grid and is free.
    pub fn check_cell(&self, what: &str, c: (usize, usize)) -> Result<()> {
        if c.0 >= self.width || c.1 >= self.height {
            return Err(Error::Planning(format!(
                "{what} cell ({}, {}) lies outside the {} x {} map",
                c.0, c.1, self.width, self.height
            )));
        }
        if !self.pass[self.pidx(c.0, c.1)] {
            return Err(Error::Planning(format!(
                "{what} cell ({}, {}) is inside an obstacle (or the inflated obstacle region)",
                c.0, c.1
            )));
        }
        Ok(())
    }
}

/// The open list: a radix heap (Ahuja, Mehlhorn, Orlin, Tarjan 1990) on monotone `u64`
/// keys. A* with a consistent heuristic pops non-decreasing f, so every key pushed is at
/// least the last popped one: bucket `b` holds the keys whose highest bit differing from
/// the last popped key is bit `b − 1`; bucket 0 holds keys equal to it and is a
/// last-in first-out stack, which breaks f ties toward the most recently generated
/// (deepest, larger-g) cells without any reordering. A pop only scans the smallest
/// non-empty bucket when bucket 0 is empty, and every entry moves to a lower bucket at most
/// 64 times, so the cost per operation is small and independent of the frontier size.
#[derive(Debug, Clone)]
struct OpenList {
    last: u64,
    /// Bit b set ⇔ bucket b may be non-empty (bucket 0's bit is not maintained). Keys are
    /// below 2^63 (fixed-point costs, or the bits of a non-negative f64), so the highest
    /// differing bit is at most 62 and buckets 0..=63 suffice.
    mask: u64,
    buckets: Vec<Vec<(u64, u32)>>,
}

impl Default for OpenList {
    fn default() -> Self {
        Self {
            last: 0,
            mask: 0,
            buckets: vec![Vec::new(); 64],
        }
    }
}

impl OpenList {
    /// A queue without buckets (allocates nothing): only a stand-in while the
    /// workspace's own queue is taken out for a search.
    fn unallocated() -> Self {
        Self {
            last: 0,
            mask: 0,
            buckets: Vec::new(),
        }
    }

    fn clear(&mut self) {
        self.last = 0;
        self.mask = 0;
        self.buckets.iter_mut().for_each(Vec::clear);
    }

    #[inline]
    fn bucket(last: u64, key: u64) -> usize {
        64 - (key ^ last).leading_zeros() as usize
    }

    /// Pushes `key`, clamped to the last popped key (with float keys rounding can put a
    /// successor's f one ulp below its parent's; treating it as equal is harmless).
    #[inline]
    fn push(&mut self, key: u64, idx: u32) {
        let key = key.max(self.last);
        debug_assert!(key < 1 << 63);
        let b = Self::bucket(self.last, key);
        self.mask |= 1u64 << b;
        self.buckets[b].push((key, idx));
    }

    #[inline(always)]
    fn pop(&mut self) -> Option<(u64, u32)> {
        if let Some(e) = self.buckets[0].pop() {
            return Some(e);
        }
        self.refill()
    }

    /// Bucket 0 is empty: redistribute the smallest non-empty bucket around its minimum.
    #[inline(never)]
    fn refill(&mut self) -> Option<(u64, u32)> {
        let rest = self.mask & !1;
        if rest == 0 {
            return None;
        }
        let b = rest.trailing_zeros() as usize;
        self.mask &= !(1u64 << b);
        let (lower, upper) = self.buckets.split_at_mut(b);
        let moved = &mut upper[0];
        if moved.len() == 1 {
            // a lone entry is the minimum itself (the common case on narrow frontiers)
            let e = moved[0];
            moved.clear();
            self.last = e.0;
            return Some(e);
        }
        let min = moved
            .iter()
            .map(|e| e.0)
            .min()
            .expect("bucket is non-empty");
        self.last = min;
        // Every key of bucket b shares the bits above b − 1 with the new minimum and so
        // lands in a bucket below b.
        for &(k, i) in moved.iter() {
            let nb = Self::bucket(min, k);
            self.mask |= 1u64 << nb;
            lower[nb].push((k, i));
        }
        moved.clear();
        lower[0].pop()
    }
}

/// The compact search's open list: a calendar queue over the window of keys an A* open
/// list can hold. With a consistent heuristic every key pushed lies in
/// `[last, last + 2·diagonal]` (`last` = the last key popped), less than
/// `(CAL_BUCKETS − 1)·2^CAL_SHIFT` wide, so the coarse index `(key >> CAL_SHIFT) mod
/// CAL_BUCKETS` names one band of keys without collisions. Keys equal to `last` go on a
/// last-in first-out stack (f ties toward the deepest cells, as in [`OpenList`]), keys of
/// `last`'s band to a small binary heap (ties newest first), and any other key to its
/// band's unsorted vector, moved into the heap once when the band is reached: each entry
/// moves at most once, where a radix heap moves it down bucket after bucket (on a maze,
/// whose f rises at almost every step, that was the search's largest cost).
///
/// The band width is `2^shift` (default [`CAL_SHIFT`]; [`BandQueue::with_shift`] for
/// searches whose steps are larger, such as the 3-D one).
#[derive(Debug, Clone)]
pub(super) struct BandQueue {
    shift: u32,
    last: u64,
    /// Bit c set ⇔ band vector c is non-empty.
    mask: u64,
    /// Coarse index of `last`'s band.
    cur: u32,
    bands: Vec<Vec<(u64, u32)>>,
    equal: Vec<(u64, u32)>,
    /// Min-heap of `key << 64 | (u32::MAX − seq) << 32 | idx`.
    heap: Vec<u128>,
    seq: u32,
}

const CAL_SHIFT: u32 = 14;
pub(super) const CAL_BUCKETS: u32 = 64;

impl Default for BandQueue {
    fn default() -> Self {
        Self::with_shift(CAL_SHIFT)
    }
}

impl BandQueue {
    /// An empty queue of bands `2^shift` wide: it holds keys in `[last, last +
    /// (CAL_BUCKETS − 1)·2^shift)`.
    pub(super) fn with_shift(shift: u32) -> Self {
        assert!(shift < 57, "band width beyond the key range");
        Self {
            shift,
            last: 0,
            mask: 0,
            cur: 0,
            bands: vec![Vec::new(); CAL_BUCKETS as usize],
            equal: Vec::new(),
            heap: Vec::new(),
            seq: 0,
        }
    }

    /// Entries the queue's buffers can hold without growing.
    pub(super) fn capacity(&self) -> usize {
        self.bands.iter().map(Vec::capacity).sum::<usize>()
            + self.equal.capacity()
            + self.heap.capacity()
    }

    /// A queue without bands (allocates nothing): only a stand-in while the workspace's
    /// own queue is taken out for a search.
    fn unallocated() -> Self {
        Self {
            shift: CAL_SHIFT,
            last: 0,
            mask: 0,
            cur: 0,
            bands: Vec::new(),
            equal: Vec::new(),
            heap: Vec::new(),
            seq: 0,
        }
    }

    /// Empties the queue; keys pushed must be at least `first` and within the window.
    pub(super) fn clear(&mut self, first: u64) {
        self.last = first;
        self.mask = 0;
        self.cur = ((first >> self.shift) % u64::from(CAL_BUCKETS)) as u32;
        self.bands.iter_mut().for_each(Vec::clear);
        self.equal.clear();
        self.heap.clear();
        self.seq = 0;
    }

    #[inline(always)]
    fn heap_entry(&mut self, key: u64, idx: u32) -> u128 {
        self.seq = self.seq.wrapping_add(1);
        (u128::from(key) << 64) | (u128::from(u32::MAX - self.seq) << 32) | u128::from(idx)
    }

    #[inline(always)]
    pub(super) fn push(&mut self, key: u64, idx: u32) {
        debug_assert!(key >= self.last);
        debug_assert!(key - self.last < u64::from(CAL_BUCKETS - 1) << self.shift);
        if key == self.last {
            self.equal.push((key, idx));
        } else if key >> self.shift == self.last >> self.shift {
            let e = self.heap_entry(key, idx);
            band_push(&mut self.heap, e);
        } else {
            let c = ((key >> self.shift) % u64::from(CAL_BUCKETS)) as usize;
            self.mask |= 1u64 << c;
            self.bands[c].push((key, idx));
        }
    }

    #[inline(always)]
    pub(super) fn pop(&mut self) -> Option<(u64, u32)> {
        if let Some(e) = self.equal.pop() {
            return Some(e);
        }
        if let Some(e) = band_pop(&mut self.heap) {
            self.last = (e >> 64) as u64;
            return Some((self.last, e as u32));
        }
        self.advance()
    }

    /// Stack and heap are empty: move the next non-empty band into the heap.
    #[inline(never)]
    fn advance(&mut self) -> Option<(u64, u32)> {
        if self.mask == 0 {
            return None;
        }
        let r = self.mask.rotate_right(self.cur);
        let c = (self.cur + r.trailing_zeros()) % CAL_BUCKETS;
        self.cur = c;
        self.mask &= !(1u64 << c);
        let mut band = std::mem::take(&mut self.bands[c as usize]);
        if band.len() == 1 {
            let e = band[0];
            band.clear();
            self.bands[c as usize] = band;
            self.last = e.0;
            return Some(e);
        }
        // the band's minimum becomes `last`: its entries go on the stack in push order
        // (so the newest pops first), the band's larger keys into the heap
        let min = band
            .iter()
            .map(|e| e.0)
            .min()
            .expect("the band is non-empty");
        self.last = min;
        for &(k, i) in &band {
            if k == min {
                self.equal.push((k, i));
            } else {
                let e = self.heap_entry(k, i);
                band_push(&mut self.heap, e);
            }
        }
        band.clear();
        self.bands[c as usize] = band;
        self.equal.pop()
    }
}

/// Binary min-heap push.
#[inline(always)]
fn band_push(h: &mut Vec<u128>, e: u128) {
    let mut i = h.len();
    h.push(e);
    while i > 0 {
        let p = (i - 1) / 2;
        if h[p] <= e {
            break;
        }
        h[i] = h[p];
        i = p;
    }
    h[i] = e;
}

/// Binary min-heap pop.
#[inline(always)]
fn band_pop(h: &mut Vec<u128>) -> Option<u128> {
    let top = *h.first()?;
    let last = h.pop().expect("non-empty");
    let n = h.len();
    if n > 0 {
        let mut i = 0;
        loop {
            let l = 2 * i + 1;
            if l >= n {
                break;
            }
            let c = if l + 1 < n && h[l + 1] < h[l] {
                l + 1
            } else {
                l
            };
            if h[c] >= last {
                break;
            }
            h[i] = h[c];
            i = c;
        }
        h[i] = last;
    }
    Some(top)
}

/// Per-cell search state, 16 bytes so one cache line access serves a neighbour. `g` is
/// the fixed-point cost (unweighted search) or the IEEE bits of the f64 cost (weighted).
#[derive(Clone, Copy, Debug, Default)]
struct CellState {
    g: u64,
    parent: u32,
    stamp: u32,
}

#[derive(Clone, Copy, Debug)]
struct Node {
    f: f64,
    idx: u32,
}
impl PartialEq for Node {
    fn eq(&self, o: &Self) -> bool {
        self.f == o.f && self.idx == o.idx
    }
}
impl Eq for Node {}
impl Ord for Node {
    fn cmp(&self, o: &Self) -> Ordering {
        o.f.total_cmp(&self.f).then(o.idx.cmp(&self.idx))
    }
}
impl PartialOrd for Node {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

/// Reusable search state for [`astar_with`]: allocate once per map size, run any number
/// of queries without clearing (a generation counter invalidates old entries).
#[derive(Debug, Default, Clone)]
pub struct AstarWorkspace {
    state: Vec<CellState>,
    generation: u32,
    /// g of the unweighted search (see [`search_octile`]): 32-bit, or 64-bit for a query
    /// whose costs outgrow 32 bits; `MAX` = not reached.
    g32: Vec<u32>,
    g64: Vec<u64>,
    /// The cells the last unweighted query reached, reset at the start of the next one.
    touched: Vec<u32>,
    /// Whether the last unweighted query ran on `g32` (else `g64`).
    last_compact: bool,
    band_queue: BandQueue,
    heap: OpenList,
}

impl AstarWorkspace {
    /// An empty workspace; it grows to the grid on first use.
    pub fn new() -> Self {
        Self::default()
    }

    fn prepare(&mut self, n: usize) {
        if self.state.len() != n {
            self.state = vec![CellState::default(); n];
            self.generation = 0;
        }
        // Stamps: 2·gen = generated this query, 2·gen + 1 = closed this query.
        if self.generation >= u32::MAX / 2 - 1 {
            self.state.iter_mut().for_each(|c| c.stamp = 0);
            self.generation = 0;
        }
        self.generation += 1;
    }

    /// Resets the cells the last unweighted query reached and sizes `G`'s array to `n`.
    fn prepare_g<G: GValue>(&mut self, n: usize) {
        if self.last_compact {
            reset_touched(&mut self.g32, &self.touched);
        } else {
            reset_touched(&mut self.g64, &self.touched);
        }
        self.touched.clear();
        let g = G::array(self);
        if g.len() != n {
            *g = vec![G::MAX; n];
        }
    }
}

/// Sets the listed cells of `g` back to "not reached".
fn reset_touched<G: GValue>(g: &mut [G], touched: &[u32]) {
    if g.is_empty() {
        return;
    }
    for &c in touched {
        g[c as usize] = G::MAX;
    }
}

/// The integer type of the unweighted search's g: `u32` (1 MB for a 512 × 512 map) or
/// `u64` when a query's costs outgrow 32 bits.
trait GValue: Copy + Ord + std::fmt::Debug {
    const MAX: Self;
    fn from_u64(v: u64) -> Option<Self>;
    fn to_u64(self) -> u64;
    fn array(ws: &mut AstarWorkspace) -> &mut Vec<Self>;
}

impl GValue for u32 {
    const MAX: Self = u32::MAX;
    #[inline(always)]
    fn from_u64(v: u64) -> Option<Self> {
        u32::try_from(v).ok().filter(|&v| v != u32::MAX)
    }
    #[inline(always)]
    fn to_u64(self) -> u64 {
        u64::from(self)
    }
    fn array(ws: &mut AstarWorkspace) -> &mut Vec<Self> {
        &mut ws.g32
    }
}

impl GValue for u64 {
    const MAX: Self = u64::MAX;
    #[inline(always)]
    fn from_u64(v: u64) -> Option<Self> {
        Some(v)
    }
    #[inline(always)]
    fn to_u64(self) -> u64 {
        self
    }
    fn array(ws: &mut AstarWorkspace) -> &mut Vec<Self> {
        &mut ws.g64
    }
}

/// Octile distance: the exact cost of an unobstructed 8-connected path.
#[inline]
pub fn octile(dx: i64, dy: i64) -> f64 {
    let (a, b) = (dx.unsigned_abs() as f64, dy.unsigned_abs() as f64);
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    hi + (SQRT2 - 1.0) * lo
}

/// A* from `start` to `goal` (cells `(x, y)`); allocates a fresh workspace. Returns
/// `Ok(None)` when the goal is unreachable; errors if start or goal is outside the grid
/// or blocked.
#[doc(alias = "a_star")]
pub fn astar(
    grid: &SearchGrid,
    start: (usize, usize),
    goal: (usize, usize),
) -> Result<Option<GridPath>> {
    astar_with(grid, &mut AstarWorkspace::new(), start, goal)
}

/// [`astar`] with a reusable workspace (no allocation after the first query except the
/// returned path). On a grid built by [`SearchGrid::from_costs`] this is the cost-aware
/// search.
pub fn astar_with(
    grid: &SearchGrid,
    ws: &mut AstarWorkspace,
    start: (usize, usize),
    goal: (usize, usize),
) -> Result<Option<GridPath>> {
    grid.check_cell("start", start)?;
    grid.check_cell("goal", goal)?;
    let mut expanded = 0;
    let found = match &grid.weight {
        None => search_unweighted(grid, ws, start, goal, &mut expanded),
        Some(w) => search_weighted(grid, w, ws, start, goal, &mut expanded),
    };
    Ok(found.map(|cost| {
        let t = grid.pidx(goal.0, goal.1);
        let mut cells = Vec::new();
        let xy = |c: usize| (c % grid.pw - 1, c / grid.pw - 1);
        if grid.weight.is_some() {
            let mut cur = t as u32;
            while cur != u32::MAX {
                cells.push(xy(cur as usize));
                cur = ws.state[cur as usize].parent;
            }
        } else {
            let s = grid.pidx(start.0, start.1);
            let walk = if ws.last_compact {
                walk_back(grid, &ws.g32, s, t)
            } else {
                walk_back(grid, &ws.g64, s, t)
            };
            cells.extend(walk.into_iter().map(xy));
        }
        cells.reverse();
        GridPath {
            cells,
            cost,
            expanded,
        }
    }))
}

/// Runs a search and returns `(cost, expanded)` without building the path (for
/// benchmarks and scenario runs); `None` cost = unreachable.
pub fn astar_cost(
    grid: &SearchGrid,
    ws: &mut AstarWorkspace,
    start: (usize, usize),
    goal: (usize, usize),
) -> Result<(Option<f64>, usize)> {
    grid.check_cell("start", start)?;
    grid.check_cell("goal", goal)?;
    let mut expanded_out = 0;
    let r = match &grid.weight {
        None => search_unweighted(grid, ws, start, goal, &mut expanded_out),
        Some(w) => search_weighted(grid, w, ws, start, goal, &mut expanded_out),
    };
    Ok((r, expanded_out))
}

/// Bits available for a fixed-point path cost of [`fixed_point_steps`] (D* Lite's g).
pub(super) const G_BITS: u32 = 45;

/// Division of a padded cell index by the padded row width without a `div` instruction:
/// `i / pw = ⌊i · m / 2^64⌋` with `m = ⌊2^64 / pw⌋ + 1`, exact for `i · pw < 2^64`
/// (always: indices and widths are below 2^32).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct RowDivider {
    pw: usize,
    m: u128,
}

impl RowDivider {
    /// For rows of `pw` cells.
    pub(super) fn new(pw: usize) -> Self {
        Self {
            pw,
            m: u128::from(u64::MAX) / pw.max(1) as u128 + 1,
        }
    }

    /// Column and row of index `i`.
    #[inline(always)]
    pub(super) fn xy(&self, i: usize) -> (i64, i64) {
        let y = ((i as u128 * self.m) >> 64) as usize;
        ((i - y * self.pw) as i64, y as i64)
    }
}

/// Padded-index offsets of the eight moves: E, W, N(+y), S(−y), NE, NW, SE, SW.
#[inline]
fn move_offsets(pw: usize) -> [isize; 8] {
    let p = pw as isize;
    [1, -1, p, -p, p + 1, p - 1, -p + 1, -p - 1]
}

/// (dx, dy) of the eight moves, in the order of [`move_offsets`]; diagonals 4..8 pass
/// between cardinals (0|1) and (2|3).
const MOVE_DXY: [(i64, i64); 8] = [
    (1, 0),
    (-1, 0),
    (0, 1),
    (0, -1),
    (1, 1),
    (-1, 1),
    (1, -1),
    (-1, -1),
];

/// The integer octile heuristic toward `goal` (padded coordinates) for fixed-point steps
/// `one` and `diag`: `max · one + min · (diag − one)`, consistent with those step costs.
#[inline(always)]
fn fixed_point_octile(goal: (i64, i64), one: u64, diag: u64) -> impl Fn(i64, i64) -> u64 {
    let extra = diag - one;
    move |x: i64, y: i64| {
        let (a, b) = ((goal.0 - x).unsigned_abs(), (goal.1 - y).unsigned_abs());
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        hi * one + lo * extra
    }
}

/// Fixed-point scale of the unweighted search for a grid of `n` padded cells: a straight
/// step costs `one` = 2^shift, a diagonal `diag` ≈ √2 · 2^shift (rounded to the nearest odd
/// integer), with shift ≤ 20 chosen so that any path cost fits in [`G_BITS`] bits. Keys
/// and g are exact integers, so equal-f ties are exact and the search needs no float
/// compares; the rounding of √2 (relative ≤ 1e-6) can only prefer a path whose true length
/// exceeds the optimum by less than that relative amount. The integer heuristic uses the
/// per-diagonal term `diag − one`, which keeps it consistent with the integer step costs.
#[inline]
pub(super) fn fixed_point_steps(n: usize) -> (u64, u64) {
    let bits = usize::BITS - n.leading_zeros();
    let shift = (G_BITS - 1 - bits).min(20);
    let one = 1u64 << shift;
    let diag = (SQRT2 * one as f64).round() as u64 | 1;
    (one, diag)
}

/// Splits a fixed-point path cost `g = n_straight · one + n_diag · diag` back into its move
/// counts and returns the length `n_straight + n_diag · √2` (one rounding). `diag` is odd,
/// hence invertible modulo `one` = 2^shift, which gives `n_diag mod one`; that is `n_diag`
/// itself whenever `g / diag < one`. Returns `None` beyond that (only possible on maps of
/// more than 2^24 cells), when the caller recounts the moves along the path.
pub(super) fn fixed_point_length(g: u64, one: u64, diag: u64) -> Option<f64> {
    if g / diag >= one {
        return None;
    }
    let mut inv = diag; // Newton iteration for the inverse of an odd number modulo 2^64
    for _ in 0..6 {
        inv = inv.wrapping_mul(2u64.wrapping_sub(diag.wrapping_mul(inv)));
    }
    let n_diag = g.wrapping_mul(inv) & (one - 1);
    let rest = g.checked_sub(n_diag * diag)?;
    debug_assert_eq!(rest % one, 0);
    Some((rest / one) as f64 + n_diag as f64 * SQRT2)
}

/// Fixed-point steps of the compact search: a straight step 2^18, a diagonal the odd
/// integer nearest to √2 · 2^18, so the rounding of √2 is 1.6e-6 relative (a path the
/// search returns is at most that much longer than the shortest) and a path cost below
/// 2^32 (about 16,000 straight steps) fits in a `u32`.
const COMPACT_STEPS: (u64, u64) = (1 << 18, 370_727);

/// The unweighted search on a 32-bit g, rerun on a 64-bit g when a cost outgrows 32 bits.
fn search_unweighted(
    grid: &SearchGrid,
    ws: &mut AstarWorkspace,
    start: (usize, usize),
    goal: (usize, usize),
    expanded_out: &mut usize,
) -> Option<f64> {
    let found = search_octile::<u32>(grid, ws, start, goal, expanded_out);
    ws.last_compact = true;
    found.unwrap_or_else(|Overflow| {
        let wide = search_octile::<u64>(grid, ws, start, goal, expanded_out);
        ws.last_compact = false;
        wide.unwrap_or_else(|Overflow| unreachable!("64-bit costs of a grid below 2^32 cells"))
    })
}

/// Padded indices of the path from `t` back to `s`. No parent is stored: each step goes
/// to a neighbour whose g plus the move's cost is this cell's g. Such a neighbour's g is
/// optimal (it is at most optimal + 0), so the walk follows an optimal path and reaches
/// the start (g strictly decreases).
fn walk_back<G: GValue>(grid: &SearchGrid, g: &[G], s: usize, t: usize) -> Vec<usize> {
    let off = move_offsets(grid.pw);
    let (one, diag) = COMPACT_STEPS;
    let mut cur = t;
    let mut cells = vec![cur];
    while cur != s {
        let gc = g[cur].to_u64();
        cur = (0..8)
            .map(|k| (k, (cur as isize - off[k]) as usize))
            .find(|&(k, p)| {
                let c = if k < 4 { one } else { diag };
                grid.moves[p] & (1 << k) != 0 && g[p] != G::MAX && g[p].to_u64() + c == gc
            })
            .map(|(_, p)| p)
            .expect("a predecessor on an optimal path");
        cells.push(cur);
    }
    cells
}

/// A compact search met a path cost that does not fit its 32-bit g.
struct Overflow;

/// The unweighted (octile) search with one integer g per cell (`u32`: 4 bytes, or `u64`)
/// in the fixed point of [`COMPACT_STEPS`], and nothing else. No closed flag is needed:
/// with integer costs and a consistent integer heuristic each push strictly lowers g, so
/// an open-list entry is current exactly when its key equals g + h of its cell, and a
/// cell's one current entry is popped once; no parent is needed either ([`walk_back`]).
/// The small state (1 MB on a 512 × 512 map with `u32`) keeps the search in the cache;
/// cells reached are listed and reset at the next query. Reports [`Overflow`] when a cost
/// does not fit `G`.
fn search_octile<G: GValue>(
    grid: &SearchGrid,
    ws: &mut AstarWorkspace,
    start: (usize, usize),
    goal: (usize, usize),
    expanded_out: &mut usize,
) -> Result<Option<f64>, Overflow> {
    let n = grid.pass.len();
    ws.prepare_g::<G>(n);
    let (one, diag_cost) = COMPACT_STEPS;
    let pw = grid.pw;
    let rows = RowDivider::new(pw);
    let moves = &grid.moves[..];
    // taken out of the workspace for the search, put back before returning
    let mut g_cells = std::mem::take(G::array(ws));
    let mut touched = std::mem::take(&mut ws.touched);
    // (an unallocated stand-in: `take` would build a default queue, one allocation per
    // query)
    let mut heap = std::mem::replace(&mut ws.band_queue, BandQueue::unallocated());
    let g = &mut g_cells[..];
    let h = fixed_point_octile((goal.0 as i64 + 1, goal.1 as i64 + 1), one, diag_cost);
    let s = grid.pidx(start.0, start.1);
    let t = grid.pidx(goal.0, goal.1);
    g[s] = G::from_u64(0).expect("zero fits");
    touched.push(s as u32);
    let h0 = h(start.0 as i64 + 1, start.1 as i64 + 1);
    heap.clear(h0);
    heap.push(h0, s as u32);
    let off = move_offsets(pw);
    let mut expanded = 0usize;
    let mut found = false;
    let mut overflow = false;
    while let Some((key, ui)) = heap.pop() {
        let u = ui as usize;
        let gu = g[u].to_u64();
        let (x, y) = rows.xy(u);
        if key != gu + h(x, y) {
            continue; // superseded by a cheaper entry of the same cell
        }
        expanded += 1;
        if u == t {
            found = true;
            break;
        }
        let mut legal = moves[u];
        while legal != 0 {
            let k = legal.trailing_zeros() as usize;
            legal &= legal - 1;
            let v = (u as isize + off[k]) as usize;
            let ng = gu + if k < 4 { one } else { diag_cost };
            let Some(ngv) = G::from_u64(ng) else {
                overflow = true;
                break;
            };
            let gv = g[v];
            if ngv < gv {
                if gv == G::MAX {
                    touched.push(v as u32);
                }
                g[v] = ngv;
                let (dx, dy) = MOVE_DXY[k];
                heap.push(ng + h(x + dx, y + dy), v as u32);
            }
        }
        if overflow {
            break;
        }
    }
    // The length n_straight + n_diag · √2, decoded from the integer cost (or, beyond
    // 2^18 diagonal moves, counted along the path).
    let length = (found && !overflow).then(|| {
        fixed_point_length(g[t].to_u64(), one, diag_cost).unwrap_or_else(|| {
            let cells = walk_back(grid, g, s, t);
            let diagonal = cells
                .windows(2)
                .filter(|w| w[0].abs_diff(w[1]) != 1 && w[0].abs_diff(w[1]) != pw)
                .count();
            (cells.len() - 1 - diagonal) as f64 + diagonal as f64 * SQRT2
        })
    });
    *G::array(ws) = g_cells;
    ws.touched = touched;
    ws.band_queue = heap;
    if overflow {
        return Err(Overflow);
    }
    *expanded_out = expanded;
    Ok(length)
}

/// The cost-aware search: f64 costs, keys = IEEE bits of f (monotone for f ≥ 0).
fn search_weighted(
    grid: &SearchGrid,
    weight: &[f32],
    ws: &mut AstarWorkspace,
    start: (usize, usize),
    goal: (usize, usize),
    expanded_out: &mut usize,
) -> Option<f64> {
    let n = grid.pass.len();
    ws.prepare(n);
    let open_stamp = ws.generation * 2;
    let closed_stamp = open_stamp + 1;
    let stamps = (open_stamp, closed_stamp);
    let pw = grid.pw;
    let pwi = pw as isize;
    let rows = RowDivider::new(pw);
    let pass = &grid.pass[..];
    let st = &mut ws.state[..];
    let mut heap = std::mem::replace(&mut ws.heap, OpenList::unallocated());
    heap.clear();
    // Heuristic in padded coordinates (the offset cancels).
    let (gx, gy) = (goal.0 as i64 + 1, goal.1 as i64 + 1);
    let h = |x: i64, y: i64| octile(gx - x, gy - y);
    let s = grid.pidx(start.0, start.1);
    let t = grid.pidx(goal.0, goal.1);
    st[s] = CellState {
        g: 0.0f64.to_bits(),
        parent: u32::MAX,
        stamp: open_stamp,
    };
    heap.push(
        h(start.0 as i64 + 1, start.1 as i64 + 1).to_bits(),
        s as u32,
    );
    // Neighbour order: E, W, N(+y), S(−y), then diagonals NE, NW, SE, SW, each with the
    // indices (into the cardinals) of the two cells it passes between.
    let card: [(isize, i64, i64); 4] = [(1, 1, 0), (-1, -1, 0), (pwi, 0, 1), (-pwi, 0, -1)];
    let diag: [(isize, i64, i64, usize, usize); 4] = [
        (pwi + 1, 1, 1, 0, 2),
        (pwi - 1, -1, 1, 1, 2),
        (-pwi + 1, 1, -1, 0, 3),
        (-pwi - 1, -1, -1, 1, 3),
    ];
    let mut expanded = 0usize;
    let mut result = None;
    while let Some((_, ui)) = heap.pop() {
        let u = ui as usize;
        let su = st[u];
        if su.stamp == closed_stamp {
            continue;
        }
        st[u].stamp = closed_stamp;
        expanded += 1;
        if u == t {
            result = Some(f64::from_bits(su.g));
            break;
        }
        let (x, y) = rows.xy(u);
        let gu = f64::from_bits(su.g);
        let mut open_card = [false; 4];
        for (k, &(off, dx, dy)) in card.iter().enumerate() {
            let v = (u as isize + off) as usize;
            if !pass[v] {
                continue;
            }
            open_card[k] = true;
            let ng = gu + weight[v] as f64;
            relax_weighted(st, &mut heap, stamps, u, v, ng, || h(x + dx, y + dy));
        }
        for &(off, dx, dy, a, b) in &diag {
            if !(open_card[a] && open_card[b]) {
                continue;
            }
            let v = (u as isize + off) as usize;
            if !pass[v] {
                continue;
            }
            let ng = gu + SQRT2 * weight[v] as f64;
            relax_weighted(st, &mut heap, stamps, u, v, ng, || h(x + dx, y + dy));
        }
    }
    *expanded_out = expanded;
    ws.heap = heap;
    result
}

/// Relaxes the step `u → v` of the cost-aware search to the cost `ng` (`hv` gives the
/// heuristic at v, evaluated only for a push): unless v is closed, a lower or first g
/// opens v with parent u. `stamps` are the query's (open, closed) stamps.
#[inline(always)]
fn relax_weighted(
    st: &mut [CellState],
    heap: &mut OpenList,
    (open_stamp, closed_stamp): (u32, u32),
    u: usize,
    v: usize,
    ng: f64,
    hv: impl FnOnce() -> f64,
) {
    let sv = &mut st[v];
    if sv.stamp == closed_stamp {
        return;
    }
    if sv.stamp != open_stamp || ng < f64::from_bits(sv.g) {
        *sv = CellState {
            g: ng.to_bits(),
            parent: u as u32,
            stamp: open_stamp,
        };
        heap.push((ng + hv()).to_bits(), v as u32);
    }
}

/// Dijkstra wavefront from `goal` over the same move model: the geodesic (shortest-path)
/// distance in cells from every cell to the goal, `f64::INFINITY` where unreachable or
/// blocked. On a cost-aware grid the distances are weighted the same way as the search.
#[doc(alias = "nf1")]
#[doc(alias = "navigation_function")]
pub fn wavefront(grid: &SearchGrid, goal: (usize, usize)) -> Result<Vec<f64>> {
    grid.check_cell("goal", goal)?;
    let mut dist_p = vec![f64::INFINITY; grid.pass.len()];
    let pw = grid.pw as isize;
    let t = grid.pidx(goal.0, goal.1);
    dist_p[t] = 0.0;
    let mut heap = BinaryHeap::new();
    heap.push(Node {
        f: 0.0,
        idx: t as u32,
    });
    let card = [1isize, -1, pw, -pw];
    let diag = [
        (pw + 1, 0, 2),
        (pw - 1, 1, 2),
        (-pw + 1, 0, 3),
        (-pw - 1, 1, 3),
    ];
    while let Some(node) = heap.pop() {
        let u = node.idx as usize;
        if node.f > dist_p[u] {
            continue;
        }
        let du = node.f;
        let mut open = [false; 4];
        // Steps are symmetric (the same cells must be free in both directions), so the
        // distance *to* the goal equals the distance *from* it; weights apply to the
        // cell being entered on the way to the goal, i.e. the cell `u` here.
        let wu = grid.weight.as_ref().map_or(1.0, |w| w[u] as f64);
        for (k, &off) in card.iter().enumerate() {
            let v = (u as isize + off) as usize;
            if !grid.pass[v] {
                continue;
            }
            open[k] = true;
            let nd = du + wu;
            if nd < dist_p[v] {
                dist_p[v] = nd;
                heap.push(Node {
                    f: nd,
                    idx: v as u32,
                });
            }
        }
        for &(off, a, b) in &diag {
            let v = (u as isize + off) as usize;
            if !(open[a] && open[b] && grid.pass[v]) {
                continue;
            }
            let nd = du + SQRT2 * wu;
            if nd < dist_p[v] {
                dist_p[v] = nd;
                heap.push(Node {
                    f: nd,
                    idx: v as u32,
                });
            }
        }
    }
    let mut out = Vec::with_capacity(grid.width * grid.height);
    for y in 0..grid.height {
        for x in 0..grid.width {
            out.push(dist_p[grid.pidx(x, y)]);
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_point_costs_decode_to_exact_lengths() {
        // Map sizes from tiny to the largest the 45-bit state can hold at full scale.
        for n in [16usize, 264_196, 1 << 24] {
            let (one, diag) = fixed_point_steps(n);
            assert_eq!(diag % 2, 1);
            assert!(((diag as f64 / one as f64) - SQRT2).abs() < 2.0 / one as f64);
            for (ns, nd) in [
                (0u64, 0u64),
                (1, 0),
                (0, 1),
                (7, 3),
                (123_456, 98_765),
                (3, 400_000),
            ] {
                let g = ns * one + nd * diag;
                let l = fixed_point_length(g, one, diag).unwrap();
                assert_eq!(l, ns as f64 + nd as f64 * SQRT2, "n = {n}, ({ns}, {nd})");
            }
        }
        // Too many diagonals for the modular decoding: the caller must count moves.
        let (one, diag) = fixed_point_steps(1 << 30);
        assert!(fixed_point_length(one * diag, one, diag).is_none());
    }

    #[test]
    fn long_paths_fall_back_to_the_wide_search() {
        // a corridor of 20,000 cells: 19,999 straight steps overflow the 32-bit g
        // (2^32 / 2^18 = 16,384 steps), so the search reruns on a 64-bit g
        let w = 20_000;
        let grid = SearchGrid::from_obstacles(&vec![false; w], w, 1).unwrap();
        let mut ws = AstarWorkspace::new();
        let p = astar_with(&grid, &mut ws, (0, 0), (w - 1, 0))
            .unwrap()
            .unwrap();
        assert!(!ws.last_compact);
        assert_eq!(p.cost, (w - 1) as f64);
        assert_eq!(p.cells.len(), w);
        assert!(
            p.cells
                .windows(2)
                .all(|c| c[1].0 == c[0].0 + 1 && c[1].1 == 0)
        );
        // a short query on the same workspace takes the compact search again
        let q = astar_with(&grid, &mut ws, (10, 0), (5, 0))
            .unwrap()
            .unwrap();
        assert!(ws.last_compact);
        assert_eq!(q.cost, 5.0);
        assert_eq!(q.cells, (5..=10).rev().map(|x| (x, 0)).collect::<Vec<_>>());
    }

    #[test]
    fn compact_steps_are_the_rounded_odd_sqrt2() {
        let (one, diag) = COMPACT_STEPS;
        let exact = SQRT2 * one as f64;
        assert_eq!(diag % 2, 1);
        assert!((diag as f64 - exact).abs() < 1.0, "the nearest odd integer");
        assert!((diag as f64 / exact - 1.0).abs() < 2e-6);
    }

    #[test]
    fn row_divider_is_exact() {
        for pw in [1usize, 2, 3, 7, 258, 514, 1026, 4099, 65_537, (1 << 31) - 1] {
            let d = RowDivider::new(pw);
            let check = |i: usize| assert_eq!(d.xy(i), ((i % pw) as i64, (i / pw) as i64));
            for i in 0..3000 {
                check(i);
            }
            for k in 1..3000usize {
                let i = k.wrapping_mul(2_654_435_761) % (u32::MAX as usize);
                check(i);
                let row_start = (i / pw) * pw;
                check(row_start);
                if row_start > 0 {
                    check(row_start - 1);
                }
            }
        }
    }

    #[test]
    fn band_queue_pops_like_the_radix_heap() {
        // A*-like use: every key pushed lies in [last, last + 2 · diagonal]; both queues
        // must pop the same (key, idx) sequence, ties newest first
        let (one, diag) = COMPACT_STEPS;
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            seed = seed.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
            seed >> 33
        };
        for round in 0..200 {
            let mut radix = OpenList::default();
            let mut band = BandQueue::default();
            let first = next() % (1 << 30);
            band.clear(first);
            radix.push(first, 0);
            band.push(first, 0);
            let mut idx = 1u32;
            let mut pops = 0;
            while let Some(a) = radix.pop() {
                let b = band.pop();
                assert_eq!(Some(a), b, "round {round}, pop {pops}");
                pops += 1;
                if pops > 3000 {
                    continue;
                }
                for _ in 0..next() % 4 {
                    // exact ties, small steps and the window's far end
                    let key = a.0
                        + match next() % 4 {
                            0 => 0,
                            1 => next() % (1 << 13),
                            2 => (next() % 3) * one + (next() % 2) * diag,
                            _ => 2 * diag - next() % 3,
                        };
                    radix.push(key, idx);
                    band.push(key, idx);
                    idx += 1;
                }
            }
            assert_eq!(band.pop(), None);
        }
    }

    #[test]
    fn radix_open_list_pops_in_key_order_with_lifo_ties() {
        let mut q = OpenList::default();
        for (k, i) in [(5u64, 0u32), (9, 1), (5, 2), (1 << 40, 3), (7, 4)] {
            q.push(k, i);
        }
        let mut out = Vec::new();
        while let Some((k, i)) = q.pop() {
            out.push((k, i));
            if i == 2 {
                q.push(5, 5); // equal to the last popped key: popped next
                q.push(8, 6);
            }
        }
        assert_eq!(
            out,
            [(5, 2), (5, 5), (5, 0), (7, 4), (8, 6), (9, 1), (1 << 40, 3)]
        );
    }
}

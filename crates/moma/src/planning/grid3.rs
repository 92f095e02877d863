//! 3-D voxel grids and 26-connected A* (Moving AI 3-D benchmark move model).
//!
//! Implementation (the 2-D search's design carried to 3-D): the voxels are one bit each
//! in a grid with a one-voxel border of blocked voxels, so the 3 × 3 × 3 neighbourhood of
//! any voxel is nine 3-bit reads at fixed offsets with no bounds checks, and the 26
//! moves are fixed index offsets; the legal moves of a voxel come from its neighbourhood
//! bits in one step when they are all free (almost always on sparse maps), else from 26
//! precomputed masks. The search state is one `u64` g per voxel in pages of 4,096
//! consecutive voxels, allocated on first touch from a pool reused across queries
//! ([`Astar3Workspace`]): dense-array access without state for the whole (up to
//! 2^28-voxel, border included) grid. Keys are exact fixed-point integers and the open list is the 2-D
//! search's calendar queue (increasing f, equal-f ties to the newest, deepest voxel).

use super::astar::{BandQueue, CAL_BUCKETS};
use crate::{Error, Result};

/// A 3-D voxel occupancy grid stored as one bit per voxel (`true` = blocked), with a
/// one-voxel border of blocked voxels around it.
#[derive(Debug, Clone, PartialEq)]
pub struct Grid3 {
    /// Size along x.
    pub nx: usize,
    /// Size along y.
    pub ny: usize,
    /// Size along z.
    pub nz: usize,
    /// Padded row length (nx + 2) and slice size ((nx + 2)(ny + 2)).
    px: usize,
    pxy: usize,
    /// Bit `i` of the padded grid, little-endian within bytes, plus two spare bytes so a
    /// 3-bit read never runs past the end.
    bits: Vec<u8>,
}

impl Grid3 {
    /// An all-free grid of `nx × ny × nz` voxels.
    ///
    /// Errors unless every side is 1 to 65,535 voxels and there are at most
    /// [`MAX_PADDED_VOXELS`] (2^28) voxels counting the one-voxel border. The bound keeps a
    /// declared size from costing unbounded time and memory before a single voxel is
    /// read: the bits take at most 32 MiB, a search's 32-bit g at most 1 GiB, and writing
    /// the border stays well under a second even on a grid one voxel thin.
    pub fn new(nx: usize, ny: usize, nz: usize) -> Result<Self> {
        let n = nx
            .checked_mul(ny)
            .and_then(|v| v.checked_mul(nz))
            .unwrap_or(usize::MAX);
        let side = u16::MAX as usize;
        let padded = (nx + 2) as u128 * (ny + 2) as u128 * (nz + 2) as u128;
        if nx == 0
            || ny == 0
            || nz == 0
            || nx > side
            || ny > side
            || nz > side
            || n >= u32::MAX as usize / 2
            || padded > MAX_PADDED_VOXELS as u128
        {
            return Err(Error::invalid(
                "voxel grid size",
                format!(
                    "{nx} x {ny} x {nz}: need 1 to 65,535 voxels per side and at most 2^28 \
                     (268,435,456) voxels counting a one-voxel border"
                ),
            ));
        }
        let (px, pxy) = (nx + 2, (nx + 2) * (ny + 2));
        let np = padded as usize;
        let mut g = Self {
            nx,
            ny,
            nz,
            px,
            pxy,
            bits: vec![0; np.div_ceil(8) + 2],
        };
        // the border: slices z = 0 and z = nz + 1, rows y = 0 and y = ny + 1, columns
        // x = 0 and x = nx + 1
        for z in 0..nz + 2 {
            for y in 0..ny + 2 {
                let row = z * pxy + y * px;
                if z == 0 || z == nz + 1 || y == 0 || y == ny + 1 {
                    for i in row..row + px {
                        g.set_bit(i, true);
                    }
                } else {
                    g.set_bit(row, true);
                    g.set_bit(row + px - 1, true);
                }
            }
        }
        Ok(g)
    }

    #[inline]
    fn set_bit(&mut self, i: usize, on: bool) {
        if on {
            self.bits[i >> 3] |= 1 << (i & 7);
        } else {
            self.bits[i >> 3] &= !(1 << (i & 7));
        }
    }

    #[inline(always)]
    fn bit(&self, i: usize) -> bool {
        self.bits[i >> 3] >> (i & 7) & 1 == 1
    }

    /// The three bits `i − 1, i, i + 1` of the padded grid (bit 0 = `i − 1`).
    #[inline(always)]
    fn bits3(&self, i: usize) -> u32 {
        let b = i - 1;
        let w = u16::from_le_bytes([self.bits[b >> 3], self.bits[(b >> 3) + 1]]);
        u32::from(w >> (b & 7)) & 7
    }

    /// Padded index of voxel `(x, y, z)`.
    #[inline(always)]
    fn pidx(&self, x: usize, y: usize, z: usize) -> usize {
        ((z + 1) * (self.ny + 2) + (y + 1)) * self.px + (x + 1)
    }

    /// Linear index of voxel `(x, y, z)` (x fastest), in the unpadded grid.
    #[inline]
    pub fn index(&self, x: usize, y: usize, z: usize) -> usize {
        (z * self.ny + y) * self.nx + x
    }

    /// Marks voxel `(x, y, z)` blocked or free.
    ///
    /// # Panics
    /// If the voxel is outside the grid.
    pub fn set_blocked(&mut self, x: usize, y: usize, z: usize, blocked: bool) {
        assert!(
            x < self.nx && y < self.ny && z < self.nz,
            "voxel outside the grid"
        );
        let i = self.pidx(x, y, z);
        self.set_bit(i, blocked);
    }

    /// `true` if the voxel is blocked or outside the grid.
    #[inline]
    pub fn is_blocked(&self, x: i64, y: i64, z: i64) -> bool {
        if x < 0
            || y < 0
            || z < 0
            || x as usize >= self.nx
            || y as usize >= self.ny
            || z as usize >= self.nz
        {
            return true;
        }
        self.bit(self.pidx(x as usize, y as usize, z as usize))
    }

    /// Number of blocked voxels.
    pub fn blocked_count(&self) -> usize {
        let all: usize = self.bits.iter().map(|w| w.count_ones() as usize).sum();
        let padded = self.pxy * (self.nz + 2);
        all - (padded - self.nx * self.ny * self.nz)
    }

    /// Bit `nb(dx, dy, dz) = 9(dz + 1) + 3(dy + 1) + dx + 1` set ⇔ that voxel of the
    /// 3 × 3 × 3 neighbourhood of padded index `i` is blocked.
    #[inline(always)]
    fn blocked27(&self, i: usize) -> u32 {
        let mut m = 0;
        for (r, base) in [i - self.pxy, i, i + self.pxy].into_iter().enumerate() {
            m |= self.bits3(base - self.px) << (9 * r);
            m |= self.bits3(base) << (9 * r + 3);
            m |= self.bits3(base + self.px) << (9 * r + 6);
        }
        m
    }
}

/// Result of a 3-D search.
#[derive(Debug, Clone, PartialEq)]
pub struct Path3 {
    /// Voxels from start to goal.
    pub voxels: Vec<(usize, usize, usize)>,
    /// Path length (1 / √2 / √3 per move).
    pub cost: f64,
    /// Number of expanded voxels.
    pub expanded: usize,
}

/// Fixed-point costs of the three move kinds: 2^20, round(√2 · 2^20), round(√3 · 2^20).
/// Keys are exact integers, so f ties are exact and equal-f plateaus are expanded deepest
/// first (with float sums, ties differ in their last bits and a plateau of equal f is
/// expanded in arbitrary order); the rounding (below 5e-7 relative) can only prefer a
/// path longer than the shortest by less than that. The reported length counts the moves
/// of the path found: n₁ + n₂√2 + n₃√3.
/// The largest grid [`Grid3::new`] accepts, in voxels counting the one-voxel border.
pub const MAX_PADDED_VOXELS: u64 = 1 << 28;

const STEPS3: [u64; 3] = [1 << 20, 1_482_910, 1_816_187];

/// Band width of the calendar queue: A* with a consistent heuristic only pushes keys
/// within 2·√3·2^20 < (CAL_BUCKETS − 1)·2^16 of the last key popped.
const BAND_SHIFT3: u32 = 16;
const _: () = assert!(2 * STEPS3[2] < ((CAL_BUCKETS as u64) - 1) << BAND_SHIFT3);

/// Slots per state page (`2^PAGE_BITS`: 64 bricks of 4 × 4 × 4 voxels).
const PAGE_BITS: u32 = 12;
const NO_PAGE: u32 = u32::MAX;

/// The integer type of g: `u32` (4 bytes a voxel: twice the voxels per cache line) or
/// `u64` when a query's costs outgrow 32 bits.
trait G3: Copy + Ord + std::fmt::Debug {
    const MAX: Self;
    fn from_u64(v: u64) -> Option<Self>;
    fn to_u64(self) -> u64;
}

impl G3 for u32 {
    const MAX: Self = u32::MAX;
    #[inline(always)]
    fn from_u64(v: u64) -> Option<Self> {
        u32::try_from(v).ok().filter(|&g| g != u32::MAX)
    }
    #[inline(always)]
    fn to_u64(self) -> u64 {
        u64::from(self)
    }
}

impl G3 for u64 {
    const MAX: Self = u64::MAX;
    #[inline(always)]
    fn from_u64(v: u64) -> Option<Self> {
        (v != u64::MAX).then_some(v)
    }
    #[inline(always)]
    fn to_u64(self) -> u64 {
        self
    }
}

/// g per voxel, in 4 × 4 × 4 bricks (a voxel's 26 neighbours mostly share its brick's
/// few cache lines) grouped in pages allocated on first touch from a pool reused across
/// queries, reset through the list of pages used.
#[derive(Debug, Clone, Default)]
struct Pages<G> {
    /// Page of each range of `2^PAGE_BITS` slots, or [`NO_PAGE`].
    slot: Vec<u32>,
    /// The pages, `G::MAX` = not reached.
    pool: Vec<G>,
    /// The ranges that own a page.
    used: Vec<u32>,
}

impl<G: G3> Pages<G> {
    fn prepare(&mut self, slots: usize) {
        for &r in &self.used {
            self.slot[r as usize] = NO_PAGE;
        }
        self.used.clear();
        self.pool.clear();
        let ranges = slots.div_ceil(1 << PAGE_BITS);
        if self.slot.len() != ranges {
            self.slot = vec![NO_PAGE; ranges];
        }
    }

    /// g of slot `v` (`G::MAX` if not reached this query).
    #[inline(always)]
    fn get(&self, v: usize) -> G {
        match self.slot[v >> PAGE_BITS] {
            NO_PAGE => G::MAX,
            p => self.pool[((p as usize) << PAGE_BITS) | (v & ((1 << PAGE_BITS) - 1))],
        }
    }

    /// Sets g of slot `v`, allocating its page if needed.
    #[inline(always)]
    fn set(&mut self, v: usize, g: G) {
        let r = v >> PAGE_BITS;
        let mut p = self.slot[r];
        if p == NO_PAGE {
            p = self.new_page(r);
        }
        self.pool[((p as usize) << PAGE_BITS) | (v & ((1 << PAGE_BITS) - 1))] = g;
    }

    #[inline(never)]
    fn new_page(&mut self, r: usize) -> u32 {
        let p = (self.pool.len() >> PAGE_BITS) as u32;
        self.pool
            .extend(std::iter::repeat_n(G::MAX, 1 << PAGE_BITS));
        self.slot[r] = p;
        self.used.push(r as u32);
        p
    }
}

/// Reusable search state for [`astar3d_with`]: g per voxel (32-bit, or 64-bit for a
/// query whose costs outgrow 32 bits) and the open list. One workspace serves any number
/// of queries on grids of any size (it grows as needed).
#[derive(Debug, Clone)]
pub struct Astar3Workspace {
    g32: Pages<u32>,
    g64: Pages<u64>,
    /// Brick-layout slot = `sx[x] + sy[y] + sz[z]` (padded coordinates).
    sx: Vec<usize>,
    sy: Vec<usize>,
    sz: Vec<usize>,
    open: BandQueue,
}

impl Default for Astar3Workspace {
    fn default() -> Self {
        Self {
            g32: Pages::default(),
            g64: Pages::default(),
            sx: Vec::new(),
            sy: Vec::new(),
            sz: Vec::new(),
            open: BandQueue::with_shift(BAND_SHIFT3),
        }
    }
}

impl Astar3Workspace {
    /// An empty workspace; it grows to the grid on first use.
    pub fn new() -> Self {
        Self::default()
    }

    /// The brick-layout tables for `grid`; returns the number of slots.
    fn layout(&mut self, grid: &Grid3) -> usize {
        let (px, py, pz) = (grid.nx + 2, grid.ny + 2, grid.nz + 2);
        let (bx, by, bz) = (px.div_ceil(4), py.div_ceil(4), pz.div_ceil(4));
        if self.sx.len() != px || self.sy.len() != py || self.sz.len() != pz {
            self.sx = (0..px).map(|x| ((x >> 2) << 6) | (x & 3)).collect();
            self.sy = (0..py)
                .map(|y| (((y >> 2) * bx) << 6) | ((y & 3) << 2))
                .collect();
            self.sz = (0..pz)
                .map(|z| (((z >> 2) * bx * by) << 6) | ((z & 3) << 4))
                .collect();
        }
        (bx * by * bz) << 6
    }
}

const SQRT2: f64 = std::f64::consts::SQRT_2;
const SQRT3: f64 = 1.732_050_807_568_877_2;

/// The 3-D octile distance in the fixed-point units of [`STEPS3`]: the exact cost of an
/// unobstructed path, hence consistent with those step costs.
#[inline(always)]
fn octile3_fixed(dx: i64, dy: i64, dz: i64) -> u64 {
    let (a, b, c) = (dx.unsigned_abs(), dy.unsigned_abs(), dz.unsigned_abs());
    let lo = a.min(b).min(c);
    let hi = a.max(b).max(c);
    let mid = a + b + c - lo - hi;
    // lo·d3 + (mid − lo)·d2 + (hi − mid)·d1
    lo * (STEPS3[2] - STEPS3[1]) + mid * (STEPS3[1] - STEPS3[0]) + hi * STEPS3[0]
}

/// Admissible, consistent 3-D octile heuristic for costs 1 / √2 / √3.
#[inline]
pub fn octile3(dx: i64, dy: i64, dz: i64) -> f64 {
    let mut a = [dx.abs(), dy.abs(), dz.abs()];
    a.sort_unstable();
    let (lo, mid, hi) = (a[0] as f64, a[1] as f64, a[2] as f64);
    SQRT3 * lo + SQRT2 * (mid - lo) + (hi - mid)
}

/// Bit of neighbourhood voxel `(dx, dy, dz)` in [`Grid3::blocked27`].
const fn nb(dx: i64, dy: i64, dz: i64) -> u32 {
    ((dz + 1) * 9 + (dy + 1) * 3 + (dx + 1)) as u32
}

/// The 26 moves: `(dx, dy, dz)`, the kind (axes changed − 1) and the neighbourhood mask
/// of the voxels that must be free (the move's bounding box minus the centre).
struct Moves3 {
    d: [(i64, i64, i64); 26],
    kind: [usize; 26],
    need: [u32; 26],
}

const MOVES3: Moves3 = {
    let mut m = Moves3 {
        d: [(0, 0, 0); 26],
        kind: [0; 26],
        need: [0; 26],
    };
    let mut k = 0;
    let mut dz = -1;
    while dz <= 1 {
        let mut dy = -1;
        while dy <= 1 {
            let mut dx = -1;
            while dx <= 1 {
                let axes = (dx != 0) as usize + (dy != 0) as usize + (dz != 0) as usize;
                if axes > 0 {
                    let mut need = 0u32;
                    let mut c = 1; // corners of the bounding box but the centre
                    while c < 8 {
                        let (ex, ey, ez) = (dx * (c & 1), dy * ((c >> 1) & 1), dz * (c >> 2));
                        need |= 1 << nb(ex, ey, ez);
                        c += 1;
                    }
                    m.d[k] = (dx, dy, dz);
                    m.kind[k] = axes - 1;
                    m.need[k] = need;
                    k += 1;
                }
                dx += 1;
            }
            dy += 1;
        }
        dz += 1;
    }
    m
};

/// Bit k set ⇔ move k of [`MOVES3`] is legal, given the neighbourhood's blocked bits.
#[inline(always)]
fn legal_moves(blocked: u32) -> u32 {
    if blocked == 0 {
        return (1 << 26) - 1;
    }
    let mut legal = 0;
    for k in 0..26 {
        legal |= u32::from(MOVES3.need[k] & blocked == 0) << k;
    }
    legal
}

/// 26-connected A* on a voxel grid with the Moving AI 3-D move model: costs 1, √2, √3
/// and a move is legal only if **every voxel of its bounding box** is free (no corner
/// cutting). Returns `Ok(None)` when the goal is unreachable.
///
/// Errors if the start or goal lies outside the grid or in a blocked voxel. Allocates
/// its state per call; [`astar3d_with`] reuses it across queries.
#[doc(alias = "a_star_3d")]
pub fn astar3d(
    grid: &Grid3,
    start: (usize, usize, usize),
    goal: (usize, usize, usize),
) -> Result<Option<Path3>> {
    astar3d_with(grid, &mut Astar3Workspace::new(), start, goal)
}

/// [`astar3d`] with a reusable workspace (no allocation once it has grown).
///
/// Errors as [`astar3d`].
pub fn astar3d_with(
    grid: &Grid3,
    ws: &mut Astar3Workspace,
    start: (usize, usize, usize),
    goal: (usize, usize, usize),
) -> Result<Option<Path3>> {
    for (what, p) in [("start", start), ("goal", goal)] {
        if p.0 >= grid.nx || p.1 >= grid.ny || p.2 >= grid.nz {
            return Err(Error::Planning(format!(
                "{what} {p:?} lies outside the {} x {} x {} grid",
                grid.nx, grid.ny, grid.nz
            )));
        }
        if grid.is_blocked(p.0 as i64, p.1 as i64, p.2 as i64) {
            return Err(Error::Planning(format!(
                "{what} {p:?} is inside an obstacle"
            )));
        }
    }
    let slots = ws.layout(grid);
    let layout = Layout {
        sx: &ws.sx,
        sy: &ws.sy,
        sz: &ws.sz,
    };
    // A long query leaves each of the queue's 64 bands with the capacity of its own
    // peak; over many queries that adds up to gigabytes, so drop buffers beyond 2^24
    // entries (256 MB) before the next query instead of keeping them.
    if ws.open.capacity() > 1 << 24 {
        ws.open = BandQueue::with_shift(BAND_SHIFT3);
    }
    // the 32-bit g, unless a cost outgrows it (paths beyond ~4,000 straight steps)
    ws.g64.prepare(0);
    ws.g32.prepare(slots);
    if let Ok(r) = search(grid, &mut ws.g32, &layout, &mut ws.open, start, goal) {
        return Ok(r);
    }
    ws.g32.prepare(0);
    ws.g64.prepare(slots);
    Ok(
        search(grid, &mut ws.g64, &layout, &mut ws.open, start, goal)
            .unwrap_or_else(|_| unreachable!("64-bit costs of a grid below 2^32 voxels")),
    )
}

/// The brick-layout tables of [`Astar3Workspace`].
struct Layout<'a> {
    sx: &'a [usize],
    sy: &'a [usize],
    sz: &'a [usize],
}

/// A search met a path cost that does not fit its g type.
struct Overflow;

/// The fixed geometry of one 3-D search: padded-index offsets and fixed-point costs of
/// the 26 moves, index → coordinate dividers, the brick layout and the goal.
struct Frame3<'a> {
    off: [isize; 26],
    step: [u64; 26],
    rows: super::astar::RowDivider,
    slices: super::astar::RowDivider,
    lay: &'a Layout<'a>,
    /// The goal in padded coordinates.
    goal: (i64, i64, i64),
}

/// The brick-layout slots of the 3 × 3 × 3 block around a voxel, by axis.
type Around = ([usize; 3], [usize; 3], [usize; 3]);

impl<'a> Frame3<'a> {
    #[inline(always)]
    fn new(grid: &Grid3, lay: &'a Layout<'a>, goal: (usize, usize, usize)) -> Self {
        let (px, pxy) = (grid.px, grid.pxy);
        let mut off = [0isize; 26];
        let mut step = [0u64; 26];
        for k in 0..26 {
            let (dx, dy, dz) = MOVES3.d[k];
            off[k] = dx as isize + dy as isize * px as isize + dz as isize * pxy as isize;
            step[k] = STEPS3[MOVES3.kind[k]];
        }
        Self {
            off,
            step,
            // padded index → padded coordinates by multiply-high (no `div`)
            rows: super::astar::RowDivider::new(px),
            slices: super::astar::RowDivider::new(grid.ny + 2),
            lay,
            goal: (goal.0 as i64 + 1, goal.1 as i64 + 1, goal.2 as i64 + 1),
        }
    }

    /// Padded index → padded coordinates.
    #[inline(always)]
    fn coords(&self, i: usize) -> (usize, usize, usize) {
        let (x, r) = self.rows.xy(i);
        let (y, z) = self.slices.xy(r as usize);
        (x as usize, y as usize, z as usize)
    }

    /// The brick-layout slots of the 3 × 3 × 3 block around padded (x, y, z), by axis.
    #[inline(always)]
    fn around(&self, x: usize, y: usize, z: usize) -> Around {
        let lay = self.lay;
        (
            [lay.sx[x - 1], lay.sx[x], lay.sx[x + 1]],
            [lay.sy[y - 1], lay.sy[y], lay.sy[y + 1]],
            [lay.sz[z - 1], lay.sz[z], lay.sz[z + 1]],
        )
    }

    /// The slot of move `k`'s target in the block `nbr`.
    #[inline(always)]
    fn slot_of(nbr: &Around, k: usize) -> usize {
        let (ax, ay, az) = nbr;
        let (dx, dy, dz) = MOVES3.d[k];
        ax[(dx + 1) as usize] + ay[(dy + 1) as usize] + az[(dz + 1) as usize]
    }

    /// The slot of the block's centre voxel.
    #[inline(always)]
    fn centre(nbr: &Around) -> usize {
        nbr.0[1] + nbr.1[1] + nbr.2[1]
    }

    /// The integer heuristic from padded (x, y, z) to the goal.
    #[inline(always)]
    fn h(&self, x: usize, y: usize, z: usize) -> u64 {
        let (gx, gy, gz) = self.goal;
        octile3_fixed(gx - x as i64, gy - y as i64, gz - z as i64)
    }
}

/// The A* of [`astar3d`] with g of type `G`. No closed flag: with integer costs and a
/// consistent integer heuristic each push strictly lowers g, so an open-list entry is
/// current exactly when its key equals g + h of its voxel, and each voxel's current
/// entry is popped once. No parent: the path is walked back through neighbours whose g
/// plus the step cost equals the voxel's g.
fn search<G: G3>(
    grid: &Grid3,
    g: &mut Pages<G>,
    lay: &Layout<'_>,
    open: &mut BandQueue,
    start: (usize, usize, usize),
    goal: (usize, usize, usize),
) -> std::result::Result<Option<Path3>, Overflow> {
    let fr = Frame3::new(grid, lay, goal);
    let s = grid.pidx(start.0, start.1, start.2);
    let t = grid.pidx(goal.0, goal.1, goal.2);
    let Some(expanded) = expand_until_goal(grid, g, &fr, open, start, t)? else {
        return Ok(None);
    };
    let (path, n) = walk_back3(grid, g, &fr, s, t);
    let voxels = path
        .iter()
        .rev()
        .map(|&i| {
            let (x, y, z) = fr.coords(i);
            (x - 1, y - 1, z - 1)
        })
        .collect();
    // the length n₁ + n₂√2 + n₃√3 of the moves taken
    let cost = f64::from(n[0]) + f64::from(n[1]) * SQRT2 + f64::from(n[2]) * SQRT3;
    Ok(Some(Path3 {
        voxels,
        cost,
        expanded,
    }))
}

/// The search loop of [`search`]: expands voxels from `start` until the goal (padded
/// index `t`) is popped; `Some(expanded)` then, `None` when the open list runs dry.
#[inline(always)]
fn expand_until_goal<G: G3>(
    grid: &Grid3,
    g: &mut Pages<G>,
    fr: &Frame3<'_>,
    open: &mut BandQueue,
    start: (usize, usize, usize),
    t: usize,
) -> std::result::Result<Option<usize>, Overflow> {
    let lay = fr.lay;
    let s = grid.pidx(start.0, start.1, start.2);
    let (sx, sy, sz) = (start.0 + 1, start.1 + 1, start.2 + 1);
    let h0 = fr.h(sx, sy, sz);
    open.clear(h0);
    open.push(h0, s as u32);
    g.set(
        lay.sx[sx] + lay.sy[sy] + lay.sz[sz],
        G::from_u64(0).ok_or(Overflow)?,
    );
    let mut expanded = 0;
    while let Some((key, ui)) = open.pop() {
        let u = ui as usize;
        let (x, y, z) = fr.coords(u);
        let nbr = fr.around(x, y, z);
        let gu = g.get(Frame3::centre(&nbr)).to_u64();
        if key != gu + fr.h(x, y, z) {
            continue; // superseded by a cheaper entry of the same voxel
        }
        expanded += 1;
        if u == t {
            return Ok(Some(expanded));
        }
        let mut legal = legal_moves(grid.blocked27(u));
        while legal != 0 {
            let k = legal.trailing_zeros() as usize;
            legal &= legal - 1;
            let ng = gu + fr.step[k];
            let ngv = G::from_u64(ng).ok_or(Overflow)?;
            let vs = Frame3::slot_of(&nbr, k);
            if ngv < g.get(vs) {
                g.set(vs, ngv);
                let (dx, dy, dz) = MOVES3.d[k];
                let (vx, vy, vz) = (
                    (x as i64 + dx) as usize,
                    (y as i64 + dy) as usize,
                    (z as i64 + dz) as usize,
                );
                open.push(ng + fr.h(vx, vy, vz), (u as isize + fr.off[k]) as u32);
            }
        }
    }
    Ok(None)
}

/// Walks back from the goal `t` to the start `s` through neighbours whose g plus the
/// step equals the voxel's g (every reached voxel's g is the cost of a path through such
/// a chain). Returns the padded indices from `t` to `s` and the count of each move kind.
fn walk_back3<G: G3>(
    grid: &Grid3,
    g: &Pages<G>,
    fr: &Frame3<'_>,
    s: usize,
    t: usize,
) -> (Vec<usize>, [u32; 3]) {
    let mut path = vec![t];
    let mut n = [0u32; 3];
    let mut c = t;
    while c != s {
        let (x, y, z) = fr.coords(c);
        let nbr = fr.around(x, y, z);
        let gc = g.get(Frame3::centre(&nbr)).to_u64();
        let mut legal = legal_moves(grid.blocked27(c));
        let mut prev = None;
        while legal != 0 {
            let k = legal.trailing_zeros() as usize;
            legal &= legal - 1;
            let gv = g.get(Frame3::slot_of(&nbr, k));
            if gv != G::MAX && gv.to_u64() + fr.step[k] == gc {
                prev = Some(k);
                break;
            }
        }
        let k = prev.expect("a reached voxel has a predecessor on its g");
        n[MOVES3.kind[k]] += 1;
        c = (c as isize + fr.off[k]) as usize;
        path.push(c);
    }
    (path, n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// Move legality by the rule itself: every voxel of the bounding box is free.
    fn legal_by_rule(g: &Grid3, p: (i64, i64, i64), d: (i64, i64, i64)) -> bool {
        (0..8).all(|c| {
            let (ex, ey, ez) = (d.0 * (c & 1), d.1 * ((c >> 1) & 1), d.2 * (c >> 2));
            !g.is_blocked(p.0 + ex, p.1 + ey, p.2 + ez)
        })
    }

    /// Plain Dijkstra in f64 over the 26 moves, legality from [`legal_by_rule`].
    fn dijkstra(g: &Grid3, s: (usize, usize, usize), t: (usize, usize, usize)) -> Option<f64> {
        let n = g.nx * g.ny * g.nz;
        let mut dist = vec![f64::INFINITY; n];
        let mut done = vec![false; n];
        dist[g.index(s.0, s.1, s.2)] = 0.0;
        loop {
            let (mut best, mut bi) = (f64::INFINITY, usize::MAX);
            for i in 0..n {
                if !done[i] && dist[i] < best {
                    (best, bi) = (dist[i], i);
                }
            }
            if bi == usize::MAX {
                return None;
            }
            done[bi] = true;
            let p = (
                (bi % g.nx) as i64,
                ((bi / g.nx) % g.ny) as i64,
                (bi / (g.nx * g.ny)) as i64,
            );
            if (p.0 as usize, p.1 as usize, p.2 as usize) == t {
                return Some(best);
            }
            for dz in -1..=1i64 {
                for dy in -1..=1i64 {
                    for dx in -1..=1i64 {
                        let axes = (dx != 0) as i32 + (dy != 0) as i32 + (dz != 0) as i32;
                        if axes == 0 || !legal_by_rule(g, p, (dx, dy, dz)) {
                            continue;
                        }
                        let c = [1.0, SQRT2, SQRT3][axes as usize - 1];
                        let (x, y, z) = (p.0 + dx, p.1 + dy, p.2 + dz);
                        let j = g.index(x as usize, y as usize, z as usize);
                        dist[j] = dist[j].min(best + c);
                    }
                }
            }
        }
    }

    #[test]
    fn astar3d_matches_dijkstra_on_random_grids() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut ws = Astar3Workspace::new();
        let (mut solved, mut unreachable) = (0, 0);
        for trial in 0..150 {
            let (nx, ny, nz) = (
                rng.random_range(1..9),
                rng.random_range(1..8),
                rng.random_range(1..7),
            );
            let mut g = Grid3::new(nx, ny, nz).unwrap();
            let density = rng.random_range(0.0..0.45);
            for z in 0..nz {
                for y in 0..ny {
                    for x in 0..nx {
                        g.set_blocked(x, y, z, rng.random_bool(density));
                    }
                }
            }
            let mut pick = |g: &mut Grid3| {
                let p = (
                    rng.random_range(0..nx),
                    rng.random_range(0..ny),
                    rng.random_range(0..nz),
                );
                g.set_blocked(p.0, p.1, p.2, false);
                p
            };
            let (s, t) = (pick(&mut g), pick(&mut g));
            let want = dijkstra(&g, s, t);
            let got = astar3d_with(&g, &mut ws, s, t).unwrap();
            assert_eq!(
                got,
                astar3d(&g, s, t).unwrap(),
                "trial {trial}: fresh workspace"
            );
            match (want, got) {
                (None, None) => unreachable += 1,
                (Some(w), Some(p)) => {
                    // fixed-point rounding: at most 5e-7 relative longer than optimal
                    assert!(
                        p.cost >= w - 1e-9 && p.cost <= w * (1.0 + 5e-7) + 1e-9,
                        "trial {trial}: {} vs {w}",
                        p.cost
                    );
                    assert_eq!((p.voxels[0], *p.voxels.last().unwrap()), (s, t));
                    let mut len = 0.0;
                    for w in p.voxels.windows(2) {
                        let d = (
                            w[1].0 as i64 - w[0].0 as i64,
                            w[1].1 as i64 - w[0].1 as i64,
                            w[1].2 as i64 - w[0].2 as i64,
                        );
                        let a = (d.0 != 0) as usize + (d.1 != 0) as usize + (d.2 != 0) as usize;
                        assert!(a > 0 && d.0.abs() <= 1 && d.1.abs() <= 1 && d.2.abs() <= 1);
                        let from = (w[0].0 as i64, w[0].1 as i64, w[0].2 as i64);
                        assert!(legal_by_rule(&g, from, d), "trial {trial}: illegal move");
                        len += [1.0, SQRT2, SQRT3][a - 1];
                    }
                    assert!((len - p.cost).abs() < 1e-9);
                    solved += 1;
                }
                (w, p) => panic!("trial {trial}: {w:?} vs {p:?}"),
            }
        }
        assert!(
            solved > 60 && unreachable > 3,
            "{solved} solved, {unreachable} cut off"
        );
    }

    #[test]
    fn long_paths_rerun_on_64_bit_costs() {
        // 6,000 straight steps cost 6,000 · 2^20 > 2^32 fixed-point units
        let g = Grid3::new(6_001, 1, 2).unwrap();
        let mut ws = Astar3Workspace::new();
        let p = astar3d_with(&g, &mut ws, (0, 0, 0), (6_000, 0, 1))
            .unwrap()
            .unwrap();
        assert!((p.cost - (5_999.0 + SQRT2)).abs() < 1e-9, "{}", p.cost);
        assert_eq!(p.voxels.len(), 6_001);
        // and the next short query is back on 32 bits with clean state
        let q = astar3d_with(&g, &mut ws, (10, 0, 0), (13, 0, 0))
            .unwrap()
            .unwrap();
        assert_eq!(q.cost, 3.0);
        assert_eq!(q.expanded, 4);
    }

    #[test]
    fn border_and_counts() {
        let mut g = Grid3::new(3, 2, 2).unwrap();
        assert_eq!(g.blocked_count(), 0);
        assert!(g.is_blocked(-1, 0, 0) && g.is_blocked(3, 0, 0) && g.is_blocked(0, 2, 0));
        assert!(g.is_blocked(0, 0, 2) && !g.is_blocked(2, 1, 1));
        g.set_blocked(2, 1, 1, true);
        assert_eq!(g.blocked_count(), 1);
        assert!(g.is_blocked(2, 1, 1));
        let p = astar3d(&g, (0, 0, 0), (0, 0, 0)).unwrap().unwrap();
        assert_eq!((p.cost, p.expanded, p.voxels.len()), (0.0, 1, 1));
        assert!(astar3d(&g, (0, 0, 0), (2, 1, 1)).is_err());
        assert!(astar3d(&g, (3, 0, 0), (0, 0, 0)).is_err());
        // a grid whose border would take it past 2^28 padded voxels
        assert!(Grid3::new(65_535, 32_767, 1).is_err());
        // 645³ ≤ 2^28 < 646³
        assert!(Grid3::new(643, 643, 643).is_ok());
        assert!(Grid3::new(644, 644, 644).is_err());
        // the declared size a fuzzer found (694 M voxels, one axis three voxels thin,
        // 231 M border rows): refused at once instead of spending seconds on the border
        assert!(Grid3::new(3, 21_014, 11_014).is_err());
    }

    #[test]
    fn fixed_point_steps_round_the_true_costs_and_keep_the_octile_formula_exact() {
        let one = STEPS3[0] as f64;
        assert_eq!(STEPS3[1], (SQRT2 * one).round() as u64);
        assert_eq!(STEPS3[2], (SQRT3 * one).round() as u64);
        // the relations that make lo·d3 + (mid − lo)·d2 + (hi − mid)·d1 the free-space
        // shortest cost (hence a consistent heuristic): d3 − d2 ≤ d2 − d1 ≤ d1
        assert!(STEPS3[2] - STEPS3[1] <= STEPS3[1] - STEPS3[0]);
        assert!(STEPS3[1] - STEPS3[0] <= STEPS3[0]);
        // and it agrees with the float heuristic to the rounding
        for (dx, dy, dz) in [(3, -7, 2), (0, 0, 5), (10, 10, 10), (-4, 1, 0)] {
            let f = octile3(dx, dy, dz);
            let i = octile3_fixed(dx, dy, dz) as f64 / one;
            assert!((f - i).abs() < 1e-6 * f.max(1.0), "{dx} {dy} {dz}");
        }
    }
}

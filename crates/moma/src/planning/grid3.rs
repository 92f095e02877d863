//! 3-D voxel grids and 26-connected A* (Moving AI 3-D benchmark move model).

use crate::{Error, Result};
use std::collections::{BinaryHeap, HashMap};
use std::hash::{BuildHasherDefault, Hasher};

/// A 3-D voxel occupancy grid stored as one bit per voxel (`true` = blocked).
#[derive(Debug, Clone, PartialEq)]
pub struct Grid3 {
    /// Size along x.
    pub nx: usize,
    /// Size along y.
    pub ny: usize,
    /// Size along z.
    pub nz: usize,
    bits: Vec<u64>,
}

impl Grid3 {
    /// An all-free grid of `nx × ny × nz` voxels.
    pub fn new(nx: usize, ny: usize, nz: usize) -> Result<Self> {
        let n = nx.checked_mul(ny).and_then(|v| v.checked_mul(nz)).unwrap_or(usize::MAX);
        if nx == 0 || ny == 0 || nz == 0 || n >= u32::MAX as usize / 2 {
            return Err(Error::invalid("voxel grid size", format!("{nx} x {ny} x {nz}: need 1 to 2^31 voxels")));
        }
        Ok(Self { nx, ny, nz, bits: vec![0; n.div_ceil(64)] })
    }

    /// Linear index of voxel `(x, y, z)` (x fastest).
    #[inline]
    pub fn index(&self, x: usize, y: usize, z: usize) -> usize {
        (z * self.ny + y) * self.nx + x
    }

    /// Marks voxel `(x, y, z)` blocked or free.
    ///
    /// # Panics
    /// If the voxel is outside the grid.
    pub fn set_blocked(&mut self, x: usize, y: usize, z: usize, blocked: bool) {
        assert!(x < self.nx && y < self.ny && z < self.nz, "voxel outside the grid");
        let i = self.index(x, y, z);
        if blocked {
            self.bits[i >> 6] |= 1 << (i & 63);
        } else {
            self.bits[i >> 6] &= !(1 << (i & 63));
        }
    }

    /// `true` if the voxel is blocked or outside the grid.
    #[inline]
    pub fn is_blocked(&self, x: i64, y: i64, z: i64) -> bool {
        if x < 0 || y < 0 || z < 0 || x as usize >= self.nx || y as usize >= self.ny || z as usize >= self.nz {
            return true;
        }
        let i = self.index(x as usize, y as usize, z as usize);
        self.bits[i >> 6] >> (i & 63) & 1 == 1
    }

    /// Number of blocked voxels.
    pub fn blocked_count(&self) -> usize {
        self.bits.iter().map(|w| w.count_ones() as usize).sum()
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

#[derive(Default)]
struct MulHasher(u64);
impl Hasher for MulHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ b as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
    }
    fn write_u32(&mut self, v: u32) {
        self.0 = (v as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15).rotate_left(29);
    }
}
type FastMap<V> = HashMap<u32, V, BuildHasherDefault<MulHasher>>;

#[derive(Clone, Copy, PartialEq)]
struct Entry3 {
    f: f64,
    g: f64,
    idx: u32,
}
impl Eq for Entry3 {}
impl Ord for Entry3 {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        // Max-heap: smallest f first, ties to the larger g.
        o.f.total_cmp(&self.f).then(self.g.total_cmp(&o.g))
    }
}
impl PartialOrd for Entry3 {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}

const SQRT2: f64 = std::f64::consts::SQRT_2;
const SQRT3: f64 = 1.732_050_807_568_877_2;

/// Admissible, consistent 3-D octile heuristic for costs 1 / √2 / √3.
#[inline]
pub fn octile3(dx: i64, dy: i64, dz: i64) -> f64 {
    let mut a = [dx.abs(), dy.abs(), dz.abs()];
    a.sort_unstable();
    let (lo, mid, hi) = (a[0] as f64, a[1] as f64, a[2] as f64);
    SQRT3 * lo + SQRT2 * (mid - lo) + (hi - mid)
}

/// 26-connected A* on a voxel grid with the Moving AI 3-D move model: costs 1, √2, √3
/// and a move is legal only if **every voxel of its bounding box** is free (no corner
/// cutting). Returns `Ok(None)` when the goal is unreachable.
///
/// Errors if the start or goal lies outside the grid or in a blocked voxel.
#[doc(alias = "a_star_3d")]
pub fn astar3d(grid: &Grid3, start: (usize, usize, usize), goal: (usize, usize, usize)) -> Result<Option<Path3>> {
    for (what, p) in [("start", start), ("goal", goal)] {
        if p.0 >= grid.nx || p.1 >= grid.ny || p.2 >= grid.nz {
            return Err(Error::Planning(format!("{what} {p:?} lies outside the {} x {} x {} grid", grid.nx, grid.ny, grid.nz)));
        }
        if grid.is_blocked(p.0 as i64, p.1 as i64, p.2 as i64) {
            return Err(Error::Planning(format!("{what} {p:?} is inside an obstacle")));
        }
    }
    // The 26 moves and, for each, the bit mask of the 3x3x3 neighbourhood voxels that
    // must be free (its bounding box minus the centre).
    let mut moves: Vec<(i64, i64, i64, f64, u32)> = Vec::with_capacity(26);
    let nb = |dx: i64, dy: i64, dz: i64| ((dz + 1) * 9 + (dy + 1) * 3 + (dx + 1)) as u32;
    for dz in -1..=1i64 {
        for dy in -1..=1i64 {
            for dx in -1..=1i64 {
                let k = dx.abs() + dy.abs() + dz.abs();
                if k == 0 {
                    continue;
                }
                let mut need = 0u32;
                for ez in [0, dz] {
                    for ey in [0, dy] {
                        for ex in [0, dx] {
                            if ex != 0 || ey != 0 || ez != 0 {
                                need |= 1 << nb(ex, ey, ez);
                            }
                        }
                    }
                }
                let cost = match k {
                    1 => 1.0,
                    2 => SQRT2,
                    _ => SQRT3,
                };
                moves.push((dx, dy, dz, cost, need));
            }
        }
    }
    let coords = |i: u32| {
        let i = i as usize;
        ((i % grid.nx) as i64, ((i / grid.nx) % grid.ny) as i64, (i / (grid.nx * grid.ny)) as i64)
    };
    let (gx, gy, gz) = (goal.0 as i64, goal.1 as i64, goal.2 as i64);
    let h = |x: i64, y: i64, z: i64| octile3(gx - x, gy - y, gz - z);
    let s = grid.index(start.0, start.1, start.2) as u32;
    let t = grid.index(goal.0, goal.1, goal.2) as u32;
    // (g, parent, closed)
    let mut state: FastMap<(f64, u32, bool)> = FastMap::default();
    let mut open = BinaryHeap::new();
    state.insert(s, (0.0, u32::MAX, false));
    open.push(Entry3 { f: h(start.0 as i64, start.1 as i64, start.2 as i64), g: 0.0, idx: s });
    let mut expanded = 0;
    while let Some(Entry3 { g, idx, .. }) = open.pop() {
        let st = state.get_mut(&idx).expect("every queued voxel has a state");
        if st.2 || g > st.0 {
            continue;
        }
        st.2 = true;
        expanded += 1;
        if idx == t {
            let mut voxels = Vec::new();
            let mut cur = idx;
            while cur != u32::MAX {
                let (x, y, z) = coords(cur);
                voxels.push((x as usize, y as usize, z as usize));
                cur = state[&cur].1;
            }
            voxels.reverse();
            return Ok(Some(Path3 { voxels, cost: g, expanded }));
        }
        let (x, y, z) = coords(idx);
        let mut free = 0u32;
        for dz in -1..=1 {
            for dy in -1..=1 {
                for dx in -1..=1 {
                    if !grid.is_blocked(x + dx, y + dy, z + dz) {
                        free |= 1 << nb(dx, dy, dz);
                    }
                }
            }
        }
        for &(dx, dy, dz, c, need) in &moves {
            if free & need != need {
                continue;
            }
            let (nx, ny, nz) = (x + dx, y + dy, z + dz);
            let ni = grid.index(nx as usize, ny as usize, nz as usize) as u32;
            let ng = g + c;
            let e = state.entry(ni).or_insert((f64::INFINITY, u32::MAX, false));
            if e.2 || ng >= e.0 {
                continue;
            }
            *e = (ng, idx, false);
            open.push(Entry3 { f: ng + h(nx, ny, nz), g: ng, idx: ni });
        }
    }
    Ok(None)
}

//! 3-D voxel grids and 26-connected A* (Moving AI 3-D benchmark move model).

use crate::{Error, Result};
use std::collections::BinaryHeap;

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
        let n = nx
            .checked_mul(ny)
            .and_then(|v| v.checked_mul(nz))
            .unwrap_or(usize::MAX);
        let side = u16::MAX as usize;
        if nx == 0
            || ny == 0
            || nz == 0
            || nx > side
            || ny > side
            || nz > side
            || n >= u32::MAX as usize / 2
        {
            return Err(Error::invalid(
                "voxel grid size",
                format!(
                    "{nx} x {ny} x {nz}: need 1 to 65,535 voxels per side and fewer than 2^31 in all"
                ),
            ));
        }
        Ok(Self {
            nx,
            ny,
            nz,
            bits: vec![0; n.div_ceil(64)],
        })
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
        assert!(
            x < self.nx && y < self.ny && z < self.nz,
            "voxel outside the grid"
        );
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
        if x < 0
            || y < 0
            || z < 0
            || x as usize >= self.nx
            || y as usize >= self.ny
            || z as usize >= self.nz
        {
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

/// Search state of one voxel; `g` in the fixed-point units of [`STEPS3`].
#[derive(Clone, Copy)]
struct VoxelState {
    g: u64,
    parent: u32,
    closed: bool,
}

const UNSEEN: VoxelState = VoxelState {
    g: u64::MAX,
    parent: u32::MAX,
    closed: false,
};

/// Fixed-point costs of the three move kinds: 2^20, round(√2 · 2^20), round(√3 · 2^20).
/// Keys are exact integers, so f ties are exact and the tie-break toward larger g works
/// (with float sums, ties differ in their last bits and a plateau of equal f is expanded
/// in arbitrary order); the rounding (below 5e-7 relative) can only prefer a path longer
/// than the shortest by less than that. The reported length counts the moves of the path
/// found: n₁ + n₂√2 + n₃√3.
const STEPS3: [u64; 3] = [1 << 20, 1_482_910, 1_816_187];

/// Search state stored in lazily allocated 8 x 8 x 8 blocks: dense-array speed without
/// allocating state for the whole (possibly 10^8-voxel) grid.
struct BlockStates {
    nbx: usize,
    nby: usize,
    slot: Vec<u32>,
    blocks: Vec<VoxelState>,
}

impl BlockStates {
    fn new(g: &Grid3) -> Self {
        let (nbx, nby, nbz) = (g.nx.div_ceil(8), g.ny.div_ceil(8), g.nz.div_ceil(8));
        Self {
            nbx,
            nby,
            slot: vec![u32::MAX; nbx * nby * nbz],
            blocks: Vec::new(),
        }
    }
    #[inline]
    fn get_mut(&mut self, x: i64, y: i64, z: i64) -> &mut VoxelState {
        let (x, y, z) = (x as usize, y as usize, z as usize);
        let b = ((z >> 3) * self.nby + (y >> 3)) * self.nbx + (x >> 3);
        let mut s = self.slot[b];
        if s == u32::MAX {
            s = (self.blocks.len() / 512) as u32;
            self.slot[b] = s;
            self.blocks.extend(std::iter::repeat_n(UNSEEN, 512));
        }
        let off = ((z & 7) << 6) | ((y & 7) << 3) | (x & 7);
        &mut self.blocks[s as usize * 512 + off]
    }
}

#[derive(Clone, Copy, PartialEq)]
struct Entry3 {
    f: u64,
    g: u64,
    x: u16,
    y: u16,
    z: u16,
}
impl Eq for Entry3 {}
impl Ord for Entry3 {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        // Max-heap: smallest f first, ties to the larger g.
        o.f.cmp(&self.f).then(self.g.cmp(&o.g))
    }
}
impl PartialOrd for Entry3 {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}

const SQRT2: f64 = std::f64::consts::SQRT_2;
const SQRT3: f64 = 1.732_050_807_568_877_2;

/// The 3-D octile distance in the fixed-point units of [`STEPS3`]: the exact cost of an
/// unobstructed path, hence consistent with those step costs.
#[inline]
fn octile3_fixed(dx: i64, dy: i64, dz: i64) -> u64 {
    let mut a = [dx.unsigned_abs(), dy.unsigned_abs(), dz.unsigned_abs()];
    a.sort_unstable();
    let (lo, mid, hi) = (a[0], a[1], a[2]);
    STEPS3[2] * lo + STEPS3[1] * (mid - lo) + STEPS3[0] * (hi - mid)
}

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
pub fn astar3d(
    grid: &Grid3,
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
    // The 26 moves and, for each, the bit mask of the 3x3x3 neighbourhood voxels that
    // must be free (its bounding box minus the centre).
    let mut moves: Vec<(i64, i64, i64, u64, u32)> = Vec::with_capacity(26);
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
                let cost = STEPS3[k as usize - 1];
                moves.push((dx, dy, dz, cost, need));
            }
        }
    }
    let coords = |i: u32| {
        let i = i as usize;
        (
            (i % grid.nx) as i64,
            ((i / grid.nx) % grid.ny) as i64,
            (i / (grid.nx * grid.ny)) as i64,
        )
    };
    let (gx, gy, gz) = (goal.0 as i64, goal.1 as i64, goal.2 as i64);
    let h = |x: i64, y: i64, z: i64| octile3_fixed(gx - x, gy - y, gz - z);
    let mut state = BlockStates::new(grid);
    let mut open = BinaryHeap::new();
    let (sx, sy, sz) = (start.0 as i64, start.1 as i64, start.2 as i64);
    *state.get_mut(sx, sy, sz) = VoxelState {
        g: 0,
        parent: u32::MAX,
        closed: false,
    };
    open.push(Entry3 {
        f: h(sx, sy, sz),
        g: 0,
        x: sx as u16,
        y: sy as u16,
        z: sz as u16,
    });
    let mut expanded = 0;
    while let Some(Entry3 { g, x, y, z, .. }) = open.pop() {
        let (x, y, z) = (x as i64, y as i64, z as i64);
        let st = state.get_mut(x, y, z);
        if st.closed || g > st.g {
            continue;
        }
        st.closed = true;
        expanded += 1;
        if (x, y, z) == (gx, gy, gz) {
            let mut voxels = vec![(x as usize, y as usize, z as usize)];
            let mut cur = state.get_mut(x, y, z).parent;
            while cur != u32::MAX {
                let (cx, cy, cz) = coords(cur);
                voxels.push((cx as usize, cy as usize, cz as usize));
                cur = state.get_mut(cx, cy, cz).parent;
            }
            voxels.reverse();
            // the length n₁ + n₂√2 + n₃√3 of the moves taken
            let mut n = [0u32; 3];
            for w in voxels.windows(2) {
                let k = (w[0].0 != w[1].0) as usize
                    + (w[0].1 != w[1].1) as usize
                    + (w[0].2 != w[1].2) as usize;
                n[k - 1] += 1;
            }
            let cost = f64::from(n[0]) + f64::from(n[1]) * SQRT2 + f64::from(n[2]) * SQRT3;
            return Ok(Some(Path3 {
                voxels,
                cost,
                expanded,
            }));
        }
        let idx = grid.index(x as usize, y as usize, z as usize) as u32;
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
            let ng = g + c;
            let e = state.get_mut(nx, ny, nz);
            if e.closed || ng >= e.g {
                continue;
            }
            *e = VoxelState {
                g: ng,
                parent: idx,
                closed: false,
            };
            open.push(Entry3 {
                f: ng + h(nx, ny, nz),
                g: ng,
                x: nx as u16,
                y: ny as u16,
                z: nz as u16,
            });
        }
    }
    Ok(None)
}

#[cfg(test)]
mod tests {
    use super::*;

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

//! The CRBA's per-model schedule: subtree dof ranges, and which subtrees to finish at
//! their root joint (see `dynamics::crba`). Fixed once by `Data::new`.

use super::{JointType, Model};

/// How `composite_columns` handles a depth-first model, fixed once per model by
/// `CrbaPlan::new`.
///
/// Carrying a column F_c from frame i to its parent costs 24 products (fewer for the
/// last step to a revolute, prismatic or planar root); bringing an ancestor's motion
/// subspace down to frame i instead costs about 45 + 24 per ancestor dof, after which
/// each entry H[j, c] is a 6-product dot. For a large subtree under a long chain (a
/// hand on an arm) the second way is several times cheaper, so such subtrees are
/// "finished" at their root joint: their columns are never carried further.
#[derive(Clone, Debug)]
pub(crate) struct CrbaPlan {
    /// Dofs in each joint's subtree, the range `idx_v[i]..idx_v[i] + n`.
    pub(crate) nv_subtree: Vec<usize>,
    /// Joints whose subtree columns are finished there (the CRBA brings the ancestors' motion subspaces down to them); no two are
    /// on one root path.
    pub(crate) finish_here: Vec<bool>,
    /// Per joint, the column ranges of its subtree still carried up: the subtree minus
    /// finished descendants' subtrees, `live[live_start[i]..live_start[i + 1]]`.
    live_start: Vec<usize>,
    live: Vec<(usize, usize)>,
}

impl CrbaPlan {
    /// The plan for `model`, or `None` when its joints are not in depth-first order (some
    /// subtree's dofs are not one contiguous range).
    pub(crate) fn new(model: &Model) -> Option<Self> {
        let n = model.njoints;
        let nv_subtree = contiguous_subtrees(model)?;
        let root_of = |mut i: usize| {
            while model.parents[i].0 != 0 {
                i = model.parents[i].0;
            }
            i
        };
        // cost per column of one step from joint a to its parent b
        let step = |b: usize| {
            if model.parents[b].0 != 0 {
                return 24.0;
            }
            match model.joint_types[b] {
                JointType::RevoluteX | JointType::RevoluteY | JointType::RevoluteZ => 6.0,
                JointType::PrismaticX | JointType::PrismaticY | JointType::PrismaticZ => 3.0,
                JointType::Planar => 11.0,
                _ => 24.0,
            }
        };
        let mut saving = vec![0.0; n];
        for i in 1..n {
            if model.parents[i].0 == 0 {
                continue;
            }
            let m = nv_subtree[i] as f64;
            let (mut carry, mut finish) = (0.0, 0.0);
            let mut a = i;
            while model.parents[a].0 != 0 {
                let b = model.parents[a].0;
                carry += m * step(b);
                finish += 45.0 + model.nvs[b] as f64 * (24.0 + 6.0 * m);
                a = b;
            }
            debug_assert_eq!(a, root_of(i));
            // finish only where it is clearly cheaper
            if finish < 0.75 * carry {
                saving[i] = carry - finish;
            }
        }
        let mut order: Vec<usize> = (1..n).filter(|&i| saving[i] > 0.0).collect();
        order.sort_by(|&a, &b| saving[b].total_cmp(&saving[a]));
        let mut finish_here = vec![false; n];
        let is_ancestor = |a: usize, mut d: usize| {
            while d != 0 {
                if d == a {
                    return true;
                }
                d = model.parents[d].0;
            }
            false
        };
        for i in order {
            let clash = (1..n).any(|j| finish_here[j] && (is_ancestor(j, i) || is_ancestor(i, j)));
            if !clash {
                finish_here[i] = true;
            }
        }
        let mut live_start = Vec::with_capacity(n + 1);
        let mut live = Vec::new();
        for i in 0..n {
            live_start.push(live.len());
            if i == 0 {
                continue;
            }
            let (lo, hi) = (model.idx_v[i], model.idx_v[i] + nv_subtree[i]);
            let mut holes: Vec<(usize, usize)> = (i + 1..n)
                .filter(|&d| finish_here[d] && d != i && is_ancestor(i, d))
                .map(|d| (model.idx_v[d], model.idx_v[d] + nv_subtree[d]))
                .collect();
            holes.sort_unstable();
            let mut at = lo;
            for (a, b) in holes {
                if a > at {
                    live.push((at, a));
                }
                at = b;
            }
            if at < hi {
                live.push((at, hi));
            }
        }
        live_start.push(live.len());
        Some(Self {
            nv_subtree,
            finish_here,
            live_start,
            live,
        })
    }

    /// The column ranges of joint i's subtree still carried up (see the type's docs).
    #[inline]
    pub(crate) fn live(&self, i: usize) -> &[(usize, usize)] {
        &self.live[self.live_start[i]..self.live_start[i + 1]]
    }
}

/// Per joint, the number of dofs of its subtree, if every subtree's dofs form the range
/// starting at the joint's own `idx_v` (true for depth-first joint orders).
fn contiguous_subtrees(model: &Model) -> Option<Vec<usize>> {
    let n = model.njoints;
    let mut count = model.nvs.clone();
    let mut lo = model.idx_v.clone();
    let mut hi: Vec<usize> = (0..n).map(|i| model.idx_v[i] + model.nvs[i]).collect();
    for i in (1..n).rev() {
        let p = model.parents[i].0;
        if p > 0 {
            count[p] += count[i];
            lo[p] = lo[p].min(lo[i]);
            hi[p] = hi[p].max(hi[i]);
        }
    }
    (1..n)
        .all(|i| lo[i] == model.idx_v[i] && hi[i] - lo[i] == count[i])
        .then_some(count)
}

//! RRT-Connect (Kuffner and LaValle, ICRA 2000) in a [`JointSpace`]: two trees, one rooted
//! at the start and one at the goal; each iteration draws a uniform sample in the box,
//! *extends* one tree one step towards it, then greedily *connects* the other tree to the
//! new node (repeated steps until it is reached or blocked), and the trees swap roles.
//!
//! * **Steps** are at most [`RrtConnectOptions::max_step`] long in the weighted norm, and
//!   every step is a segment checked at the space's resolution ([`JointSpace`]), so the
//!   returned path (start, the tree nodes, goal) is valid at that resolution throughout.
//! * **Nearest neighbour** is a linear scan over the tree's flat node array in the same
//!   weighted norm (the tree sizes of arm queries keep it fast: see `benches/motion.rs`).
//! * **Determinism**: the samples come from ChaCha8 seeded with
//!   [`RrtConnectOptions::seed`], so the same query gives the same path, unless the time
//!   limit ends it.
//! * **Limits**: an iteration limit and a time limit (checked once per iteration); reaching
//!   either returns [`Planned::NotSolved`] with the counts.
//! * **Lazy edges** ([`RrtConnectOptions::lazy`]): a step is checked state by state at
//!   the space's resolution ([`JointSpace::discrete_segment_valid`], whatever the check's
//!   own [`StateValidity::segment_valid`]); when the trees meet, the edges of the path
//!   between them that no earlier path checked get the segment check, start end first. An
//!   edge that fails cuts its far node and every node below it from their tree (they are
//!   skipped from then on), and the search goes on; a returned path passed the segment
//!   check throughout, as without the option. A check that costs much more per segment
//!   than its states do at that resolution (a continuous one) then pays for the segments
//!   of the paths only. A probed step blocked part of the way keeps its last valid probe
//!   as a node (its edge checked later like any other), so the trees grow up to the
//!   obstacles instead of giving the step up, and the connecting tree stops there.
//! * **Dynamic domain** ([`RrtConnectOptions::domain_radius`]; Yershova, Jaillet, Siméon
//!   and LaValle, ICRA 2005): a node whose step towards a sample was blocked takes later
//!   samples only within that radius; a sample farther from its nearest node is drawn
//!   again without a check ([`MAX_DOMAIN_REDRAWS`] in a row at most, then taken). Nodes
//!   by the obstacles then stop drawing steps into them, and the samples they do take
//!   explore around them: in narrow passages (an arm between shelf boards) the trees need
//!   far fewer checked states.
//! * **Local samples** ([`RrtConnectOptions::local_share`]): that share of the samples
//!   is drawn near the extending tree's own nodes instead of over the whole box: a node
//!   picked uniformly (cut nodes excepted) and an offset uniform in
//!   ±[`RrtConnectOptions::local_radius`] per joint (over its weight), clamped to the box.
//!   A tree rooted in a pocket (an arm reaching between shelf boards) takes nearly all
//!   its uniform samples from far away: its steps towards them are blocked at the first
//!   probe, while a local sample gives a short step that fits the pocket. The rest of
//!   the samples keep RRT's pull towards the unexplored space.
//! * **Balanced trees** ([`RrtConnectOptions::balanced`]): the tree with fewer live
//!   nodes (cut nodes excepted) extends next, the other connects to it; on a tie they
//!   alternate, as without the option. A tree rooted in a pocket (an arm reaching between
//!   a cage's bars) has most of its steps blocked at the first probe, so it grows slowly;
//!   with plain alternation the tree in the open spends half the iterations, and the
//!   larger share of the checked states (its steps run their full length), growing far
//!   beyond what the join needs, and each of its new nodes costs the pocketed tree a
//!   blocked connection too. Balanced, the iterations go where the search is stuck, and a
//!   blocked step costs one probe.
//! * **Allocation**: the trees live in a [`RrtConnectWorkspace`] that keeps its capacity
//!   between queries; a query allocates only its returned path.

use super::joint_space::{JointPath, JointSpace, StateValidity};
use crate::{Error, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::time::{Duration, Instant};

/// The most samples in a row a dynamic domain redraws before one is taken anyway.
pub const MAX_DOMAIN_REDRAWS: usize = 200;

/// The options of a query.
#[derive(Debug, Clone, PartialEq)]
pub struct RrtConnectOptions {
    /// The longest step (weighted norm); `None`: 0.2 × the box diagonal (OMPL's default).
    pub max_step: Option<f64>,
    /// The most iterations (samples drawn).
    pub max_iterations: usize,
    /// The longest planning time.
    pub time_limit: Duration,
    /// The seed of the sampler.
    pub seed: u64,
    /// Probe steps state by state at the space's resolution, and give only the paths
    /// found the segment check (module docs).
    pub lazy: bool,
    /// The dynamic domain's radius (weighted norm) around a node that was blocked
    /// (module docs); `None`: none.
    pub domain_radius: Option<f64>,
    /// The share of samples drawn near the extending tree's own nodes, in `[0, 1]`
    /// (module docs); 0: every sample is uniform over the box.
    pub local_share: f64,
    /// The largest offset of a local sample from its node, per joint (weighted).
    pub local_radius: f64,
    /// Let the tree with fewer live nodes extend next instead of alternating every
    /// iteration (module docs).
    pub balanced: bool,
}

impl Default for RrtConnectOptions {
    fn default() -> Self {
        RrtConnectOptions {
            max_step: None,
            max_iterations: 100_000,
            time_limit: Duration::from_secs(1),
            seed: 0,
            lazy: false,
            domain_radius: None,
            local_share: 0.0,
            local_radius: 0.3,
            balanced: false,
        }
    }
}

/// What a query cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanStats {
    /// Iterations run (samples drawn).
    pub iterations: usize,
    /// Nodes in both trees, roots included.
    pub nodes: usize,
    /// Calls of the validity check.
    pub checks: u64,
    /// Wall-clock time of the query.
    pub elapsed: Duration,
}

/// The limit that ended an unsolved query.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlanLimit {
    /// [`RrtConnectOptions::max_iterations`].
    Iterations,
    /// [`RrtConnectOptions::time_limit`].
    Time,
}

/// The outcome of a query.
#[derive(Debug, Clone, PartialEq)]
pub enum Planned {
    /// A path from the start to the goal, valid at the space's resolution.
    Solved {
        /// The path.
        path: JointPath,
        /// The counts.
        stats: PlanStats,
    },
    /// No path was found before a limit.
    NotSolved {
        /// The limit reached.
        limit: PlanLimit,
        /// The counts.
        stats: PlanStats,
    },
}

impl Planned {
    /// The counts, solved or not.
    pub fn stats(&self) -> &PlanStats {
        match self {
            Planned::Solved { stats, .. } | Planned::NotSolved { stats, .. } => stats,
        }
    }

    /// The path, if solved.
    pub fn path(&self) -> Option<&JointPath> {
        match self {
            Planned::Solved { path, .. } => Some(path),
            Planned::NotSolved { .. } => None,
        }
    }
}

/// One tree: node states stored flat, each node's parent index (the root's is itself),
/// whether the edge to its parent is known valid, whether a failed edge above it cut
/// it off (lazy mode), the radius of its dynamic domain (infinite until a step from
/// it is blocked), and how many nodes are not cut.
#[derive(Debug, Clone, Default)]
struct Tree {
    states: Vec<f64>,
    parents: Vec<u32>,
    edge_checked: Vec<bool>,
    cut: Vec<bool>,
    radius: Vec<f64>,
    live: usize,
}

impl Tree {
    fn reset(&mut self, root: &[f64]) {
        self.states.clear();
        self.parents.clear();
        self.edge_checked.clear();
        self.cut.clear();
        self.radius.clear();
        self.states.extend_from_slice(root);
        self.parents.push(0);
        self.edge_checked.push(true);
        self.cut.push(false);
        self.radius.push(f64::INFINITY);
        self.live = 1;
    }

    /// Cuts node `i` and every node below it (children come after their parents).
    fn cut_below(&mut self, i: usize) {
        if !self.cut[i] {
            self.cut[i] = true;
            self.live -= 1;
        }
        for j in i + 1..self.len() {
            if !self.cut[j] && self.cut[self.parents[j] as usize] {
                self.cut[j] = true;
                self.live -= 1;
            }
        }
    }

    fn len(&self) -> usize {
        self.parents.len()
    }

    fn state(&self, i: usize, dim: usize) -> &[f64] {
        &self.states[i * dim..(i + 1) * dim]
    }

    fn push(&mut self, q: &[f64], parent: usize, edge_checked: bool) -> usize {
        self.states.extend_from_slice(q);
        self.parents.push(parent as u32);
        self.edge_checked.push(edge_checked);
        self.cut.push(false);
        self.radius.push(f64::INFINITY);
        self.live += 1;
        self.parents.len() - 1
    }

    /// The node nearest to `q` in the weighted norm (linear scan over the nodes not cut).
    fn nearest(&self, space: &JointSpace, q: &[f64]) -> usize {
        let dim = space.dim();
        let mut best = (0, f64::INFINITY);
        for (i, (node, cut)) in self.states.chunks_exact(dim).zip(&self.cut).enumerate() {
            let d = space.distance_squared(node, q);
            if d < best.1 && !cut {
                best = (i, d);
            }
        }
        best.0
    }
}

/// The reusable storage of RRT-Connect queries (both trees and scratch states).
#[derive(Debug, Clone, Default)]
pub struct RrtConnectWorkspace {
    trees: [Tree; 2],
    sample: Vec<f64>,
    step: Vec<f64>,
    scratch: Vec<f64>,
}

impl RrtConnectWorkspace {
    /// An empty workspace; it grows to the largest query it serves.
    pub fn new() -> Self {
        Self::default()
    }
}

/// The result of one extension step.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Extend {
    /// The target itself was added.
    Reached(usize),
    /// A node one step towards the target was added.
    Advanced(usize),
    /// The step was blocked after some progress: its last valid probe was added.
    Partial(usize),
    /// The step was invalid; nothing added.
    Trapped,
    /// The sample lay outside the nearest node's domain; nothing checked.
    Rejected,
}

/// Plans from `start` to `goal` (both checked: length, finite, in the box, valid).
///
/// # Errors
/// [`Error::InvalidInput`] naming `start`, `goal` or an option when one is malformed, out
/// of the box or invalid, [`Error::WrongLength`] / [`Error::NonFinite`] for the states.
pub fn rrt_connect(
    space: &JointSpace,
    validity: &mut impl StateValidity,
    start: &[f64],
    goal: &[f64],
    options: &RrtConnectOptions,
    ws: &mut RrtConnectWorkspace,
) -> Result<Planned> {
    let began = Instant::now();
    space.check_state("start", start)?;
    space.check_state("goal", goal)?;
    let max_step = options.max_step.unwrap_or(0.2 * space.diagonal());
    if !(max_step.is_finite() && max_step > 0.0) {
        return Err(Error::invalid(
            "max_step",
            format!("{max_step} is not a positive finite length"),
        ));
    }
    if let Some(r) = options.domain_radius
        && !(r.is_finite() && r > 0.0)
    {
        return Err(Error::invalid(
            "domain_radius",
            format!("{r} is not a positive finite length"),
        ));
    }
    if !(0.0..=1.0).contains(&options.local_share) {
        return Err(Error::invalid(
            "local_share",
            format!("{} is not a share in [0, 1]", options.local_share),
        ));
    }
    if options.local_share > 0.0
        && !(options.local_radius.is_finite() && options.local_radius > 0.0)
    {
        return Err(Error::invalid(
            "local_radius",
            format!("{} is not a positive finite length", options.local_radius),
        ));
    }
    let domain = options.domain_radius.unwrap_or(f64::INFINITY);
    let mut checks = 0u64;
    checks += 1;
    if !validity.is_valid(start) {
        return Err(Error::invalid("start", "the start state is not valid"));
    }
    checks += 1;
    if !validity.is_valid(goal) {
        return Err(Error::invalid("goal", "the goal state is not valid"));
    }
    let dim = space.dim();
    let [t0, t1] = &mut ws.trees;
    t0.reset(start);
    t1.reset(goal);
    let stats = |iterations, trees: &[Tree; 2], checks| PlanStats {
        iterations,
        nodes: trees[0].len() + trees[1].len(),
        checks,
        elapsed: began.elapsed(),
    };
    // The straight segment first: many queries need nothing else.
    if space.segment_valid(validity, start, goal, &mut ws.scratch, &mut checks) {
        let path = JointPath::from_flat(dim, [start, goal].concat());
        return Ok(Planned::Solved {
            path,
            stats: stats(0, &ws.trees, checks),
        });
    }
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    ws.sample.resize(dim, 0.0);
    // `a` is the tree that extends this iteration; the start tree is tree 0.
    let mut a = 0;
    for iteration in 0..options.max_iterations {
        if began.elapsed() >= options.time_limit {
            return Ok(Planned::NotSolved {
                limit: PlanLimit::Time,
                stats: stats(iteration, &ws.trees, checks),
            });
        }
        // Draw until a sample lies in its nearest node's domain (or the redraws run out).
        let mut redraws = 0;
        let outcome = loop {
            let local = options.local_share > 0.0 && rng.random::<f64>() < options.local_share;
            draw_sample(
                space,
                ws,
                a,
                local.then_some(options.local_radius),
                &mut rng,
            );
            let step = Step {
                max: max_step,
                lazy: options.lazy,
                domain: if redraws < MAX_DOMAIN_REDRAWS {
                    domain
                } else {
                    f64::INFINITY
                },
            };
            match extend(space, validity, ws, a, &step, &mut checks) {
                Extend::Rejected => redraws += 1,
                e => break e,
            }
        };
        let new = match outcome {
            Extend::Trapped | Extend::Rejected => {
                a = next_tree(&ws.trees, 1 - a, options.balanced);
                continue;
            }
            Extend::Reached(i) | Extend::Advanced(i) | Extend::Partial(i) => i,
        };
        // Connect the other tree to the new node.
        let b = 1 - a;
        ws.sample.clear();
        ws.sample.extend_from_slice(ws.trees[a].state(new, dim));
        loop {
            let step = Step {
                max: max_step,
                lazy: options.lazy,
                domain: f64::INFINITY,
            };
            match extend(space, validity, ws, b, &step, &mut checks) {
                Extend::Advanced(_) => continue,
                Extend::Trapped | Extend::Partial(_) | Extend::Rejected => break,
                Extend::Reached(joined) => {
                    let (from_start, from_goal) =
                        if a == 0 { (new, joined) } else { (joined, new) };
                    if !check_path_edges(space, validity, ws, from_start, from_goal, &mut checks) {
                        break;
                    }
                    let path = join(&ws.trees, dim, from_start, from_goal);
                    return Ok(Planned::Solved {
                        path,
                        stats: stats(iteration + 1, &ws.trees, checks),
                    });
                }
            }
        }
        a = next_tree(&ws.trees, b, options.balanced);
    }
    Ok(Planned::NotSolved {
        limit: PlanLimit::Iterations,
        stats: stats(options.max_iterations, &ws.trees, checks),
    })
}

/// The tree that extends next: `other` (the one that did not extend this iteration), or
/// when `balanced` the one with fewer live nodes (`other` on a tie).
fn next_tree(trees: &[Tree; 2], other: usize, balanced: bool) -> usize {
    if !balanced {
        return other;
    }
    match trees[0].live.cmp(&trees[1].live) {
        std::cmp::Ordering::Less => 0,
        std::cmp::Ordering::Greater => 1,
        std::cmp::Ordering::Equal => other,
    }
}

/// Draws `ws.sample`: uniform over the box, or with `local = Some(radius)` near a node of
/// tree `t` picked uniformly among those not cut (module docs).
fn draw_sample(
    space: &JointSpace,
    ws: &mut RrtConnectWorkspace,
    t: usize,
    local: Option<f64>,
    rng: &mut ChaCha8Rng,
) {
    let bounds = space.lower().iter().zip(space.upper());
    let Some(radius) = local else {
        for (s, (lo, hi)) in ws.sample.iter_mut().zip(bounds) {
            *s = lo + (hi - lo) * rng.random::<f64>();
        }
        return;
    };
    let tree = &ws.trees[t];
    // The root is never cut, so this ends.
    let node = loop {
        let i = rng.random_range(0..tree.len());
        if !tree.cut[i] {
            break i;
        }
    };
    let centre = tree.state(node, space.dim());
    for (((s, (lo, hi)), c), w) in ws
        .sample
        .iter_mut()
        .zip(bounds)
        .zip(centre)
        .zip(space.weights())
    {
        *s = (c + radius / w * (2.0 * rng.random::<f64>() - 1.0)).clamp(*lo, *hi);
    }
}

/// How [`extend`] steps.
struct Step {
    /// The longest step.
    max: f64,
    /// Probe the step at the space's resolution (lazy edges).
    lazy: bool,
    /// The radius given to a node whose step is blocked, and the test of the target: a
    /// finite radius marks the target a sample, rejected outside its nearest node's
    /// domain; an infinite one takes it whatever the domain.
    domain: f64,
}

/// Extends tree `t` one step towards `ws.sample` (see [`Step`]).
fn extend(
    space: &JointSpace,
    validity: &mut impl StateValidity,
    ws: &mut RrtConnectWorkspace,
    t: usize,
    step: &Step,
    checks: &mut u64,
) -> Extend {
    let dim = space.dim();
    let tree = &mut ws.trees[t];
    let near = tree.nearest(space, &ws.sample);
    let from = &tree.states[near * dim..(near + 1) * dim];
    let d = space.distance(from, &ws.sample);
    if step.domain.is_finite() && d > tree.radius[near] {
        return Extend::Rejected;
    }
    let reached = d <= step.max;
    ws.step.clear();
    if reached {
        ws.step.extend_from_slice(&ws.sample);
    } else {
        let f = step.max / d;
        ws.step
            .extend(from.iter().zip(&ws.sample).map(|(x, y)| x + f * (y - x)));
    }
    if step.lazy {
        let (k, n) = space.discrete_valid_prefix(validity, from, &ws.step, &mut ws.scratch, checks);
        if k < n {
            if step.domain.is_finite() {
                tree.radius[near] = step.domain;
            }
            if k == 0 {
                return Extend::Trapped;
            }
            // The last valid probe, computed as the probe was.
            let f = k as f64 / n as f64;
            for (s, x) in ws.step.iter_mut().zip(from) {
                *s = x + f * (*s - x);
            }
            return Extend::Partial(tree.push(&ws.step, near, false));
        }
    } else if !space.segment_valid(validity, from, &ws.step, &mut ws.scratch, checks) {
        if step.domain.is_finite() {
            tree.radius[near] = step.domain;
        }
        return Extend::Trapped;
    }
    let i = tree.push(&ws.step, near, !step.lazy);
    if reached {
        Extend::Reached(i)
    } else {
        Extend::Advanced(i)
    }
}

/// Checks the edges not yet known valid on the path through `from_start` (tree 0) and
/// `from_goal` (tree 1), from the start tree's root on; the first that fails cuts its node
/// and the nodes below it from their tree, and the answer is `false`.
fn check_path_edges(
    space: &JointSpace,
    validity: &mut impl StateValidity,
    ws: &mut RrtConnectWorkspace,
    from_start: usize,
    from_goal: usize,
    checks: &mut u64,
) -> bool {
    let dim = space.dim();
    // The start tree's edges root first, then the goal tree's from the junction on.
    let mut chain = Vec::new();
    let mut i = from_start;
    while i != 0 {
        chain.push((0, i));
        i = ws.trees[0].parents[i] as usize;
    }
    chain.reverse();
    let mut i = from_goal;
    while i != 0 {
        chain.push((1, i));
        i = ws.trees[1].parents[i] as usize;
    }
    for (t, i) in chain {
        let tree = &mut ws.trees[t];
        if tree.edge_checked[i] {
            continue;
        }
        let parent = tree.parents[i] as usize;
        // Along the path: parent → node in the start tree, node → parent in the goal tree.
        let (a, b) = if t == 0 { (parent, i) } else { (i, parent) };
        let ok = space.segment_valid(
            validity,
            tree.state(a, dim),
            tree.state(b, dim),
            &mut ws.scratch,
            checks,
        );
        if !ok {
            tree.cut_below(i);
            return false;
        }
        tree.edge_checked[i] = true;
    }
    true
}

/// The path root(0) → … → `from_start` then `from_goal` → … → root(1). The two nodes hold
/// the same state, which appears once.
fn join(trees: &[Tree; 2], dim: usize, from_start: usize, from_goal: usize) -> JointPath {
    let mut points = Vec::new();
    let mut i = from_start;
    loop {
        points.push(i);
        if i == 0 {
            break;
        }
        i = trees[0].parents[i] as usize;
    }
    let mut flat = Vec::with_capacity(dim * (points.len() + 8));
    for &i in points.iter().rev() {
        flat.extend_from_slice(trees[0].state(i, dim));
    }
    let mut i = trees[1].parents[from_goal] as usize;
    if from_goal != 0 {
        loop {
            flat.extend_from_slice(trees[1].state(i, dim));
            if i == 0 {
                break;
            }
            i = trees[1].parents[i] as usize;
        }
    }
    JointPath::from_flat(dim, flat)
}

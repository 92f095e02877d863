//! The collision check of a planning group, conservative along whole segments: the
//! clearance of one state vouches for a stretch of joint-space motion around it.
//!
//! **Displacement bound.** For a group joint `g` and a link `l` below it, `R[g][l]` bounds
//! how far any point of `l`'s collision geometry moves per unit of `q_g`: 1 for a
//! prismatic joint; for a revolute one the distance from the joint's origin (a point of its
//! axis) to the farthest geometry point, bounded over every configuration by the sum of the
//! joint offsets down the chain (plus the travel of any prismatic joint on it) and the
//! farthest point of the link's shapes (their bounding balls). Along a straight joint-space
//! segment a point of `l` therefore moves at most `Σ_g R[g][l] |Δq_g|`.
//!
//! **Pairs.** A link–scene pair closes its gap at most that fast. For a link–link pair only
//! the joints above one link and not the other count: a joint above both moves the two
//! rigidly together. Each pair `p` gets a row of coefficients `c_p` (one per group joint),
//! and a pair whose row is all zero never moves; it is checked once, with the start state.
//!
//! **Segments** (`a → b`, `δ = |b − a|`): at a checked state every pair's signed distance
//! `d_p` must exceed the margin, and pair `p` then stays at least half the margin apart for
//! a further fraction `(d_p − margin/2) / (c_p · δ)` of the segment; the next checked state
//! is the smallest such step further on (so steps never shrink below `(margin/2) / (c_p ·
//! δ)`). A segment that passes keeps half the margin at every state of it, not only at the
//! checked ones, up to the accuracy of the distances (1e-12 m). Pairs are not computed when
//! their bounding balls, or the distance found at an earlier state of the same segment less
//! the most it can have closed since, already cover the step found so far.
//!
//! **States** ([`StateValidity::is_valid`]) pass when every pair's distance exceeds the
//! margin plus `tube · ‖c_p ⊘ w‖₂`, the most the pair can close over any state within the
//! weighted distance `tube` ([`ClearanceChecker::set_tube`]; 0 by default). The time
//! parameterisation checks its blends state by state at the resolution; with the tube set
//! to half the resolution, every state of a blend is vouched for by a checked one.
//!
//! The shapes are the convex hulls of the URDF meshes (and the scene's primitives), which
//! hold the meshes: a positive hull distance is a positive mesh distance.

use super::group::JointGroup;
use crate::collision::gjk::{EpaWorkspace, WarmStart, signed_distance};
use crate::collision::{GeometryModel, Scene};
use crate::kinematics;
use crate::multibody::{Data, Model};
use crate::planning::{JointSpace, StateValidity};
use crate::{Error, Result};
use nalgebra::{DVector, Vector3};

/// The most checked states of one segment before it is given up as failed (a segment
/// grazing an obstacle within the margin needs ever shorter steps).
pub const MAX_STATES_PER_SEGMENT: u64 = 100_000;

/// The other side of a checked pair.
#[derive(Clone, Copy, Debug)]
enum Other {
    /// A robot object or ball group (index into `GeometryModel::objects` or the groups).
    Robot(usize),
    /// A scene shape: object, shape.
    Scene(usize, usize),
}

/// A ball around some of a link's objects, in its joint's frame.
#[derive(Clone, Copy, Debug)]
struct Ball {
    joint: usize,
    centre: Vector3<f64>,
    radius: f64,
}

/// Object pairs under one bounding test: a robot ball group against another group or a
/// scene shape.
#[derive(Clone, Copy, Debug)]
struct Block {
    a: usize,
    b: Other,
    /// Row of coefficients (pair of links, or link against the scene).
    row: usize,
    /// Its object pairs: `entries[first..first + count]`.
    first: usize,
    count: usize,
}

/// The closest pair found by [`ClearanceChecker::distance_report`].
#[derive(Clone, Debug, PartialEq)]
pub struct ClosestPair {
    /// Signed distance (m).
    pub distance: f64,
    /// The robot link.
    pub link: String,
    /// The other link, or the scene object's id.
    pub other: String,
    /// Whether `other` is a scene object.
    pub scene_object: bool,
}

/// Links with more objects than this (a mesh given as its triangles) are bounded by one
/// ball per link before their objects are.
const GROUP_ABOVE: usize = 4;

/// The conservative collision check of a group (module docs); it owns its kinematics and
/// geometry workspaces, so checks allocate nothing.
#[derive(Clone, Debug)]
pub struct ClearanceChecker<'a> {
    model: &'a Model,
    gm: &'a GeometryModel,
    scene: &'a Scene,
    group: &'a JointGroup,
    margin: f64,
    tube: f64,
    /// Ball per robot object (joint frame).
    object_balls: Vec<Ball>,
    /// Ball groups of robot objects.
    groups: Vec<Ball>,
    /// Object pairs, grouped by block: robot object, other object.
    entries: Vec<(usize, Other)>,
    /// Blocks whose gap can change.
    moving: Vec<Block>,
    /// Blocks that never move.
    fixed: Vec<Block>,
    /// `rows × dim` coefficients.
    coeff: Vec<f64>,
    /// `‖c_p ⊘ w‖₂` per row.
    tube_norm: Vec<f64>,
    /// `c_p · δ` per row for the current segment.
    rate: Vec<f64>,
    q: DVector<f64>,
    data: Data,
    warm: Vec<WarmStart>,
    epa: EpaWorkspace,
    delta: Vec<f64>,
    /// The block that limited the last step (checked first next time).
    last_limiting: usize,
    /// Per object pair: the distance last computed on this segment, where (segment
    /// fraction), and the segment it belongs to.
    cache_d: Vec<f64>,
    cache_t: Vec<f64>,
    cache_epoch: Vec<u64>,
    /// The current segment (0: none) and the fraction of it reached.
    epoch: u64,
    t_now: f64,
    /// States evaluated since construction.
    pub states_checked: u64,
}

impl<'a> ClearanceChecker<'a> {
    /// A checker for `group` of `model` with geometry `gm` among `scene`; `base` is the
    /// full configuration that fixes the joints outside the group; `margin` (m) is the
    /// clearance every state must keep; `weights` are the planning norm's (one per group
    /// joint).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for a margin that is negative or not finite, a base of the
    /// wrong length, weights of the wrong length or not positive, or a prismatic joint with
    /// unbounded travel between a group joint and a link (the bound would be infinite).
    pub fn new(
        model: &'a Model,
        gm: &'a GeometryModel,
        scene: &'a Scene,
        group: &'a JointGroup,
        base: &[f64],
        margin: f64,
        weights: &[f64],
    ) -> Result<Self> {
        if !(margin.is_finite() && margin >= 0.0) {
            return Err(Error::invalid(
                "margin",
                format!("{margin} is not a finite non-negative length"),
            ));
        }
        crate::error::ensure_len("start", model.nq, base.len())?;
        crate::error::ensure_len("weights", group.dim(), weights.len())?;
        if let Some(i) = weights.iter().position(|w| !(w.is_finite() && *w > 0.0)) {
            return Err(Error::invalid(
                format!("weights[{i}]"),
                format!("{} is not positive", weights[i]),
            ));
        }
        let dim = group.dim();
        let radii = link_radii(model, gm, group)?;
        let object_balls: Vec<Ball> = gm
            .objects
            .iter()
            .map(|o| Ball {
                joint: o.joint.0,
                centre: o.placement.act_point(&o.bounding_centre),
                radius: o.bounding_radius,
            })
            .collect();
        // Ball groups per link: one per object, or one for the whole link.
        let mut groups: Vec<Ball> = Vec::new();
        let mut link_groups: Vec<Vec<(usize, std::ops::Range<usize>)>> = Vec::new();
        for link in &gm.links {
            let objs = link.first..link.first + link.count;
            let mut mine = Vec::new();
            if link.count > GROUP_ABOVE {
                groups.push(enclosing_ball(&object_balls[objs.clone()]));
                mine.push((groups.len() - 1, objs));
            } else {
                for i in objs {
                    groups.push(object_balls[i]);
                    mine.push((groups.len() - 1, i..i + 1));
                }
            }
            link_groups.push(mine);
        }
        let mut coeff = Vec::new();
        let mut entries = Vec::new();
        let (mut moving, mut fixed) = (Vec::new(), Vec::new());
        let mut add_block =
            |row: usize,
             still: bool,
             a: usize,
             b: Other,
             pairs: &mut dyn Iterator<Item = (usize, Other)>| {
                let first = entries.len();
                entries.extend(pairs);
                let block = Block {
                    a,
                    b,
                    row,
                    first,
                    count: entries.len() - first,
                };
                if still {
                    fixed.push(block);
                } else {
                    moving.push(block);
                }
            };
        for (p, &[la, lb]) in gm.pairs.iter().enumerate() {
            if !gm.enabled[p] {
                continue;
            }
            let (ja, jb) = (gm.links[la].joint, gm.links[lb].joint);
            let row_values: Vec<f64> = (0..dim)
                .map(|g| {
                    let jg = group.joints[g];
                    match (model.is_ancestor(jg, ja), model.is_ancestor(jg, jb)) {
                        (true, false) => radii[la * dim + g],
                        (false, true) => radii[lb * dim + g],
                        _ => 0.0,
                    }
                })
                .collect();
            let still = row_values.iter().all(|c| *c == 0.0);
            coeff.extend_from_slice(&row_values);
            let row = coeff.len() / dim - 1;
            for (ga, ra) in &link_groups[la] {
                for (gb, rb) in &link_groups[lb] {
                    let mut pairs = ra
                        .clone()
                        .flat_map(|i| rb.clone().map(move |j| (i, Other::Robot(j))));
                    add_block(row, still, *ga, Other::Robot(*gb), &mut pairs);
                }
            }
        }
        if !scene.objects.is_empty() {
            for l in 0..gm.links.len() {
                let row_values = &radii[l * dim..(l + 1) * dim];
                let still = row_values.iter().all(|c| *c == 0.0);
                coeff.extend_from_slice(row_values);
                let row = coeff.len() / dim - 1;
                for (ga, ra) in &link_groups[l] {
                    for (o, obj) in scene.objects.iter().enumerate() {
                        for s in 0..obj.shapes.len() {
                            let mut pairs = ra.clone().map(|i| (i, Other::Scene(o, s)));
                            add_block(row, still, *ga, Other::Scene(o, s), &mut pairs);
                        }
                    }
                }
            }
        }
        let rows = coeff.len() / dim.max(1);
        let tube_norm = (0..rows)
            .map(|r| {
                coeff[r * dim..(r + 1) * dim]
                    .iter()
                    .zip(weights)
                    .map(|(c, w)| (c / w) * (c / w))
                    .sum::<f64>()
                    .sqrt()
            })
            .collect();
        let n_entries = entries.len();
        Ok(ClearanceChecker {
            model,
            gm,
            scene,
            group,
            margin,
            tube: 0.0,
            object_balls,
            groups,
            entries,
            moving,
            fixed,
            coeff,
            tube_norm,
            rate: vec![0.0; rows],
            q: DVector::from_column_slice(base),
            data: Data::new(model),
            warm: vec![WarmStart::default(); n_entries],
            epa: EpaWorkspace::default(),
            delta: vec![0.0; dim],
            last_limiting: 0,
            cache_d: vec![0.0; n_entries],
            cache_t: vec![0.0; n_entries],
            cache_epoch: vec![0; n_entries],
            epoch: 0,
            t_now: 0.0,
            states_checked: 0,
        })
    }

    /// The clearance every state keeps (m).
    #[must_use]
    pub fn margin(&self) -> f64 {
        self.margin
    }

    /// Sets the clearance every state keeps (m, finite, ≥ 0).
    pub fn set_margin(&mut self, margin: f64) {
        if margin.is_finite() && margin >= 0.0 {
            self.margin = margin;
        }
    }

    /// The weighted radius each state checked by `is_valid` vouches for (module docs).
    pub fn set_tube(&mut self, tube: f64) {
        self.tube = tube.max(0.0);
    }

    /// The displacement coefficients of every checked link pair and link–scene row,
    /// `rows × dim` (module docs).
    #[must_use]
    pub fn coefficients(&self) -> &[f64] {
        &self.coeff
    }

    /// The number of object pairs checked.
    #[must_use]
    pub fn pair_count(&self) -> usize {
        self.entries.len()
    }

    fn place(&mut self, x: &[f64]) {
        self.group.embed(x, self.q.as_mut_slice());
        kinematics::forward_kinematics(self.model, &mut self.data, &self.q);
    }

    fn ball_gap(&self, a: &Ball, b: Other, groups: bool) -> f64 {
        let ca = self.data.world_from_joint[a.joint].act_point(&a.centre);
        match b {
            Other::Robot(j) => {
                let bb = if groups {
                    &self.groups[j]
                } else {
                    &self.object_balls[j]
                };
                let cb = self.data.world_from_joint[bb.joint].act_point(&bb.centre);
                (ca - cb).norm() - a.radius - bb.radius
            }
            Other::Scene(o, s) => {
                let (lo, hi) = &self.scene.objects[o].shapes[s].aabb;
                let d = (lo - ca).sup(&(ca - hi)).sup(&Vector3::zeros());
                d.norm() - a.radius
            }
        }
    }

    fn exact(&mut self, k: usize) -> f64 {
        let (a, b) = self.entries[k];
        let oa = &self.gm.objects[a];
        let pa = self.data.world_from_joint[oa.joint.0] * oa.placement;
        let (shape, pose) = match b {
            Other::Robot(j) => {
                let ob = &self.gm.objects[j];
                (
                    &ob.shape,
                    self.data.world_from_joint[ob.joint.0] * ob.placement,
                )
            }
            Other::Scene(o, s) => {
                let sh = &self.scene.objects[o].shapes[s];
                (&sh.shape, sh.pose)
            }
        };
        signed_distance(
            &oa.shape,
            &pa,
            shape,
            &pose,
            &mut self.warm[k],
            &mut self.epa,
        )
        .distance
    }

    /// At the placed state: the largest further fraction of the current segment (rates in
    /// `self.rate`) that every moving pair vouches for, capped at `need` (`+∞` when no
    /// pair limits it), or `None` when a pair is within the margin (plus the tube).
    fn allowed_step(&mut self, need: f64, tube: f64) -> Option<f64> {
        // The step shrinks as limiting pairs are found, and a pair whose bounding balls
        // keep it clear over the step found so far is not computed; the block that limited
        // the last state goes first.
        let mut step = need;
        let n = self.moving.len();
        let first = self.last_limiting.min(n.saturating_sub(1));
        for i in 0..n {
            let bi = if i == 0 {
                first
            } else if i <= first {
                i - 1
            } else {
                i
            };
            let block = self.moving[bi];
            let (rate, extra) = (
                self.rate[block.row],
                self.margin + tube * self.tube_norm[block.row],
            );
            let slack = extra - 0.5 * self.margin;
            if self.ball_gap(&self.groups[block.a], block.b, true)
                > (slack + step * rate).max(extra)
            {
                continue;
            }
            for k in block.first..block.first + block.count {
                let (a, b) = self.entries[k];
                let bound = (slack + step * rate).max(extra);
                // The distance found earlier on this segment, less the most it can have
                // closed since, is a lower bound too.
                if self.cache_epoch[k] == self.epoch
                    && self.cache_d[k] - rate * (self.t_now - self.cache_t[k]) > bound
                {
                    continue;
                }
                if block.count > 1 && self.ball_gap(&self.object_balls[a], b, false) > bound {
                    continue;
                }
                let d = self.exact(k);
                self.cache_d[k] = d;
                self.cache_t[k] = self.t_now;
                self.cache_epoch[k] = self.epoch;
                if d <= extra {
                    self.last_limiting = bi;
                    return None;
                }
                // A checked state keeps the margin; the states it vouches for keep half
                // of it, so the steps stay longer than (margin / 2) / rate.
                let free = d - extra + 0.5 * self.margin;
                if free < step * rate {
                    step = free / rate;
                    self.last_limiting = bi;
                }
            }
        }
        Some(step)
    }

    /// The closest pair at the group state `x`, over every checked pair (moving or not),
    /// every distance computed exactly; `None` when nothing is checked.
    pub fn distance_report(&mut self, x: &[f64]) -> Option<ClosestPair> {
        self.place(x);
        let mut best: Option<(f64, usize)> = None;
        let blocks = self.moving.len() + self.fixed.len();
        for bi in 0..blocks {
            let block = if bi < self.moving.len() {
                self.moving[bi]
            } else {
                self.fixed[bi - self.moving.len()]
            };
            let cut = best.map_or(f64::INFINITY, |(b, _)| b);
            if self.ball_gap(&self.groups[block.a], block.b, true) >= cut {
                continue;
            }
            for k in block.first..block.first + block.count {
                let (a, b) = self.entries[k];
                let cut = best.map_or(f64::INFINITY, |(b, _)| b);
                if self.ball_gap(&self.object_balls[a], b, false) >= cut {
                    continue;
                }
                let d = self.exact(k);
                if d < cut {
                    best = Some((d, k));
                }
            }
        }
        best.map(|(distance, k)| {
            let (a, b) = self.entries[k];
            let link = self.gm.links[self.gm.objects[a].link].name.clone();
            let (other, scene_object) = match b {
                Other::Robot(j) => (self.gm.links[self.gm.objects[j].link].name.clone(), false),
                Other::Scene(o, _) => (self.scene.objects[o].id.clone(), true),
            };
            ClosestPair {
                distance,
                link,
                other,
                scene_object,
            }
        })
    }
}

/// The smallest ball (by this simple rule: centre at the mean of the centres) holding
/// every ball of `balls` (all on one joint).
fn enclosing_ball(balls: &[Ball]) -> Ball {
    let n = balls.len().max(1) as f64;
    let centre = balls.iter().fold(Vector3::zeros(), |s, b| s + b.centre) / n;
    let radius = balls
        .iter()
        .map(|b| (b.centre - centre).norm() + b.radius)
        .fold(0.0, f64::max);
    Ball {
        joint: balls.first().map_or(0, |b| b.joint),
        centre,
        radius,
    }
}

impl StateValidity for ClearanceChecker<'_> {
    fn is_valid(&mut self, x: &[f64]) -> bool {
        self.states_checked += 1;
        self.rate.iter_mut().for_each(|r| *r = 0.0);
        self.epoch += 1;
        self.t_now = 0.0;
        self.place(x);
        self.allowed_step(0.0, self.tube).is_some()
    }

    fn segment_valid(
        &mut self,
        _space: &JointSpace,
        a: &[f64],
        b: &[f64],
        scratch: &mut Vec<f64>,
        checks: &mut u64,
    ) -> bool {
        let dim = self.group.dim();
        for k in 0..dim {
            self.delta[k] = (b[k] - a[k]).abs();
        }
        for (r, rate) in self.rate.iter_mut().enumerate() {
            *rate = self.coeff[r * dim..(r + 1) * dim]
                .iter()
                .zip(&self.delta)
                .map(|(c, d)| c * d)
                .sum();
        }
        scratch.resize(dim, 0.0);
        self.epoch += 1;
        let mut t = 0.0;
        for _ in 0..MAX_STATES_PER_SEGMENT {
            self.t_now = t;
            for k in 0..dim {
                scratch[k] = a[k] + t * (b[k] - a[k]);
            }
            *checks += 1;
            self.states_checked += 1;
            self.place(scratch);
            let need = 1.0 - t;
            let Some(step) = self.allowed_step(need, 0.0) else {
                return false;
            };
            if step >= need {
                return true;
            }
            if step.is_nan() || step <= 1e-12 {
                return false;
            }
            t += step;
        }
        false
    }
}

/// `R[l][g]` (flat, `links × dim`): the bound on the speed of link `l`'s geometry per unit
/// speed of group joint `g` (module docs). For a revolute joint it bounds the distance from
/// its axis: the offset of the next joint down the chain counts only across the axis (it
/// is fixed in the joint's frame), every further offset (and prismatic travel) in full,
/// then the farthest point of the link's shapes from its own joint.
fn link_radii(model: &Model, gm: &GeometryModel, group: &JointGroup) -> Result<Vec<f64>> {
    let dim = group.dim();
    let mut radii = vec![0.0; gm.links.len() * dim];
    for (l, link) in gm.links.iter().enumerate() {
        let objects = &gm.objects[link.first..link.first + link.count];
        for g in 0..dim {
            let jg = group.joints[g];
            if !model.is_ancestor(jg, link.joint) {
                continue;
            }
            if group.prismatic[g] {
                radii[l * dim + g] = 1.0;
                continue;
            }
            let axis = model.joint_types[jg.0].axis().ok_or_else(|| {
                Error::invalid(format!("joint '{}'", group.names[g]), "has no axis")
            })?;
            let across = |p: Vector3<f64>| (p - axis * axis.dot(&p)).norm();
            if link.joint == jg {
                radii[l * dim + g] = objects
                    .iter()
                    .map(|o| across(o.placement.act_point(&o.bounding_centre)) + o.bounding_radius)
                    .fold(0.0, f64::max);
                continue;
            }
            let reach = objects
                .iter()
                .map(|o| o.placement.act_point(&o.bounding_centre).norm() + o.bounding_radius)
                .fold(0.0, f64::max);
            let mut chain = 0.0;
            let mut j = link.joint.0;
            loop {
                let parent = model.parents[j].0;
                let t = model.joint_placements[j].translation;
                if model.joint_types[j].is_prismatic() {
                    let iq = model.idx_q[j];
                    let travel = model.lower_position_limit[iq]
                        .abs()
                        .max(model.upper_position_limit[iq].abs());
                    if !travel.is_finite() {
                        return Err(Error::invalid(
                            format!("joint '{}'", model.names[j]),
                            "a prismatic joint without position limits lies between a group \
                             joint and a link; its travel bounds the clearance steps",
                        ));
                    }
                    chain += travel;
                }
                if parent == jg.0 {
                    chain += across(t);
                    break;
                }
                chain += t.norm();
                j = parent;
            }
            radii[l * dim + g] = chain + reach;
        }
    }
    Ok(radii)
}

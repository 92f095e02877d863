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
//! A link–object pair the scene object allows ([`crate::collision::SceneObject::touch_links`])
//! is not checked.
//!
//! **Segments** (`a → b`, `δ = |b − a|`): at a checked state every pair's signed distance
//! `d_p` must exceed the margin, and pair `p` then stays at least half the margin apart for
//! a fraction `(d_p − margin/2) / (c_p · δ)` of the segment on either side of the state;
//! the state vouches for the smallest such stretch (never shorter than `(margin/2) / (c_p ·
//! δ)`). The end state is checked first, then the start, then the middles of what is still
//! uncovered, coarse to fine. A segment that passes keeps half the margin at every state of
//! it, not only at the checked ones, up to the accuracy of the distances (1e-12 m). Pairs
//! are not computed when a lower bound already covers the stretch found so far: a ball
//! around each link against the other link's ball or the scene object's box (all of that
//! link's pairs with it at once; against a scene object of several shapes, a mesh's
//! triangles, the link's ball then descends the object's tree and only the shapes of the
//! leaves it reaches go on), their bounding balls, their world axis-aligned boxes
//! (robot objects against each other or against a scene shape), the balls of their hulls'
//! covers ([`crate::collision::ball_cover`]: every ball clear means the hull is) against
//! the other object's balls, against its 26 bounding planes, or against the scene shape in
//! closed form ([`crate::collision::ball_gap`]), or the
//! distance found at an earlier state of the same segment less the most it can have closed
//! since, or the plane the pair's last GJK run ended with
//! ([`crate::collision::separating_plane`]: one support point of each shape along that
//! normal, a true bound wherever the pair has moved since); the blocks go
//! best first (the one that limited the last state, then by the stretch their balls vouch
//! for), and GJK stops once a separating plane shows the distance covers it, or once a
//! point of the Minkowski difference shows the pair within the margin (no penetration
//! depth is computed for a pair that fails). A segment's first checked state tests every
//! link's ball; its later states only those that state left live: the balls close at
//! most the row's rate over the whole segment, so a cluster whose balls are farther
//! apart than that plus the most a later state asks for is clear at every later state.
//! Where every cluster's link-ball bound is wanted (a segment's first state, a state on
//! its own) one pass computes them all ([`super::link_ball_gaps`]); a cluster of two
//! links of one ball group each has one block, whose ball gap is the cluster's.
//!
//! **States** ([`StateValidity::is_valid`]) pass when every pair's distance exceeds the
//! margin plus `tube · ‖c_p ⊘ w‖₂`, the most the pair can close over any state within the
//! weighted distance `tube` ([`ClearanceChecker::set_tube`]; 0 by default): the block
//! that failed the last state first, then the links in turn, each bounded before its pairs,
//! up to the first pair within (no ordering, as no stretch is sought). The time
//! parameterisation checks its blends state by state at the resolution; with the tube set
//! to half the resolution, every state of a blend is vouched for by a checked one.
//!
//! The shapes are the convex hulls of the URDF meshes (and the scene's primitives), which
//! hold the meshes: a positive hull distance is a positive mesh distance.

use super::group::JointGroup;
use super::link_ball_gaps::LinkBallGaps;
use crate::collision::ball_cover::{MAX_SLABS, hull_ball_cover};
use crate::collision::ball_gap::PlacedShape;
use crate::collision::gjk::{EpaWorkspace, WarmStart, distance_outside, signed_distance};
use crate::collision::separating_plane::plane_gap;
use crate::collision::{Convex, GeometryModel, Scene};
use crate::kinematics;
use crate::multibody::{Data, Model};
use crate::planning::{JointSpace, StateValidity};
use crate::{Error, Result};
use nalgebra::{DVector, Matrix3, Vector3};
use std::collections::VecDeque;
use std::time::Instant;

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

/// The moving blocks of one link against one other link or one scene object, under one
/// bounding test: the link's ball against the other link's ball or the object's box.
#[derive(Clone, Copy, Debug)]
struct Cluster {
    /// The robot link.
    link: usize,
    /// The other link (`Other::Robot` holds a link index here) or scene object
    /// (`Other::Scene(object, _)`).
    other: Other,
    row: usize,
    /// Its blocks: `moving[first..first + count]`.
    first: usize,
    count: usize,
    /// Whether its one block's balls are the two links' balls (two links of one ball
    /// group each): the block's ball gap is the cluster's.
    shared_balls: bool,
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

/// Links with more objects than this (a mesh surface given as patches) are bounded by one
/// ball per run of [`GROUP_SIZE`] consecutive objects before their objects are.
const GROUP_ABOVE: usize = 4;
/// Objects per ball group of a link with many objects (consecutive surface patches are
/// neighbours: the patches come from a median split of the triangles).
const GROUP_SIZE: usize = 8;

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
    /// The groups' world centres at the placed state.
    group_centres: Vec<Vector3<f64>>,
    /// The objects' world ball centres, valid where `object_stamp` is `state_stamp`.
    object_centres: Vec<Vector3<f64>>,
    object_stamp: Vec<u64>,
    state_stamp: u64,
    /// Per robot object: its bounding box in its joint's frame (centre, rotation, half
    /// sides), and its world axis-aligned box, valid where `box_stamp` is `state_stamp`.
    object_boxes: Vec<(Vector3<f64>, Matrix3<f64>, Vector3<f64>)>,
    object_world_boxes: Vec<(Vector3<f64>, Vector3<f64>)>,
    box_stamp: Vec<u64>,
    /// Object pairs, grouped by block: robot object, other object.
    entries: Vec<(usize, Other)>,
    /// Blocks whose gap can change.
    moving: Vec<Block>,
    /// The moving blocks by link and other link or scene object.
    clusters: Vec<Cluster>,
    /// Per link: a ball holding all its objects (joint frame), and its world centre at
    /// the placed state.
    link_balls: Vec<Ball>,
    link_centres: Vec<Vector3<f64>>,
    /// Every cluster's link-ball bound, computed for all clusters in one pass.
    link_gaps: LinkBallGaps,
    /// Every scene shape placed for closed-form ball gaps, object by object: object `o`'s
    /// shape `s` is `scene_shapes[scene_first[o] + s]`.
    scene_shapes: Vec<PlacedShape>,
    scene_first: Vec<usize>,
    /// Balls whose union holds each robot object (joint frame; a hull's slabs, else its
    /// bounding ball): `cover[cover_of[i].0..][..cover_of[i].1]`, their world centres
    /// valid where `cover_stamp` is `state_stamp`.
    cover: Vec<Ball>,
    cover_of: Vec<(usize, usize)>,
    cover_centres: Vec<Vector3<f64>>,
    cover_stamp: Vec<u64>,
    /// Per robot object: its closed-form bound placed at the placed state, valid where
    /// `pose_stamp` is `state_stamp`.
    object_shapes: Vec<PlacedShape>,
    pose_stamp: Vec<u64>,
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
    /// The stretches of the current segment no checked state covers yet.
    open: VecDeque<(f64, f64)>,
    /// The blocks to compute at this state: the step their balls vouch for, block.
    order: Vec<(f64, usize)>,
    /// The block that limited the last step (checked first next time).
    last_limiting: usize,
    /// The blocks of the cluster at hand that its link's ball does not clear, as ranges
    /// `(first, end)` of `moving` ([`ClearanceChecker::near_blocks`]), and the scratch of
    /// the scene tree's descent.
    near: Vec<(usize, usize)>,
    near_shapes: Vec<(usize, usize)>,
    tree_stack: Vec<usize>,
    /// Per object pair: the distance last computed on this segment, where (segment
    /// fraction), and the segment it belongs to.
    cache_d: Vec<f64>,
    cache_t: Vec<f64>,
    cache_epoch: Vec<u64>,
    /// The current segment (0: none) and the fraction of it reached.
    epoch: u64,
    t_now: f64,
    /// States are refused unchecked from this instant on ([`Self::set_deadline`]).
    deadline: Option<Instant>,
    /// States evaluated since construction.
    pub states_checked: u64,
    /// Exact pair distances computed since construction (the pairs no bound ruled out).
    pub distances_computed: u64,
    /// Pairs cleared since construction by the plane their last GJK run ended with.
    pub planes_cleared: u64,
    /// The clusters the current segment's later states look at (the first state's
    /// balls leave the others clear over the whole segment), and whether the next
    /// checked state is a segment's first (then it fills them).
    live: Vec<usize>,
    fill_live: bool,
    /// Per object pair: the hull vertices that plane's support climbs start from.
    plane_hints: Vec<(usize, usize)>,
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
        // Ball groups per link: one per object, or one per run of `GROUP_SIZE` objects.
        let mut groups: Vec<Ball> = Vec::new();
        let mut link_groups: Vec<Vec<(usize, std::ops::Range<usize>)>> = Vec::new();
        for link in &gm.links {
            let objs = link.first..link.first + link.count;
            let mut mine = Vec::new();
            if link.count > GROUP_ABOVE {
                for lo in objs.clone().step_by(GROUP_SIZE) {
                    let run = lo..(lo + GROUP_SIZE).min(objs.end);
                    groups.push(enclosing_ball(&object_balls[run.clone()]));
                    mine.push((groups.len() - 1, run));
                }
            } else {
                for i in objs {
                    groups.push(object_balls[i]);
                    mine.push((groups.len() - 1, i..i + 1));
                }
            }
            link_groups.push(mine);
        }
        let mut cover = Vec::new();
        let mut cover_of = Vec::new();
        for (o, ball) in gm.objects.iter().zip(&object_balls) {
            let first = cover.len();
            if let Convex::Hull {
                vertices,
                neighbours,
            } = &o.shape
            {
                let (_, half) = o.shape.local_aabb();
                let mut sides = [half.x, half.y, half.z];
                sides.sort_unstable_by(|a, b| b.total_cmp(a));
                let slabs = if sides[1] > 0.0 {
                    ((2.0 * sides[0] / sides[1]).ceil() as usize).clamp(1, MAX_SLABS)
                } else {
                    MAX_SLABS
                };
                for (centre, radius) in hull_ball_cover(vertices, neighbours, slabs) {
                    cover.push(Ball {
                        joint: o.joint.0,
                        centre: o.placement.act_point(&centre),
                        radius,
                    });
                }
            } else {
                cover.push(*ball);
            }
            cover_of.push((first, cover.len() - first));
        }
        let link_balls: Vec<Ball> = gm
            .links
            .iter()
            .map(|link| enclosing_ball(&object_balls[link.first..link.first + link.count]))
            .collect();
        let scene_boxes: Vec<(Vector3<f64>, Vector3<f64>)> = scene
            .objects
            .iter()
            .map(|obj| {
                obj.shapes.iter().fold(
                    (
                        Vector3::repeat(f64::INFINITY),
                        Vector3::repeat(f64::NEG_INFINITY),
                    ),
                    |(lo, hi), s| (lo.inf(&s.aabb.0), hi.sup(&s.aabb.1)),
                )
            })
            .collect();
        let mut scene_first = Vec::with_capacity(scene.objects.len());
        let mut scene_shapes = Vec::new();
        for obj in &scene.objects {
            scene_first.push(scene_shapes.len());
            scene_shapes.extend(
                obj.shapes
                    .iter()
                    .map(|s| PlacedShape::new(&s.shape, &s.pose)),
            );
        }
        let mut coeff = Vec::new();
        let mut entries = Vec::new();
        let (mut moving, mut fixed) = (Vec::new(), Vec::new());
        let mut clusters = Vec::new();
        // The moving blocks added so far.
        let mut n_moving = 0usize;
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
            let first = n_moving;
            for (ga, ra) in &link_groups[la] {
                for (gb, rb) in &link_groups[lb] {
                    let mut pairs = ra
                        .clone()
                        .flat_map(|i| rb.clone().map(move |j| (i, Other::Robot(j))));
                    add_block(row, still, *ga, Other::Robot(*gb), &mut pairs);
                    n_moving += usize::from(!still);
                }
            }
            if !still {
                clusters.push(Cluster {
                    link: la,
                    other: Other::Robot(lb),
                    row,
                    first,
                    count: n_moving - first,
                    shared_balls: link_groups[la].len() == 1 && link_groups[lb].len() == 1,
                });
            }
        }
        if !scene.objects.is_empty() {
            for l in 0..gm.links.len() {
                let row_values = &radii[l * dim..(l + 1) * dim];
                let still = row_values.iter().all(|c| *c == 0.0);
                coeff.extend_from_slice(row_values);
                let row = coeff.len() / dim - 1;
                for (o, obj) in scene.objects.iter().enumerate() {
                    if obj.allows(&gm.links[l].name) {
                        continue;
                    }
                    let first = n_moving;
                    for s in 0..obj.shapes.len() {
                        for (ga, ra) in &link_groups[l] {
                            let mut pairs = ra.clone().map(|i| (i, Other::Scene(o, s)));
                            add_block(row, still, *ga, Other::Scene(o, s), &mut pairs);
                            n_moving += usize::from(!still);
                        }
                    }
                    if !still {
                        clusters.push(Cluster {
                            link: l,
                            other: Other::Scene(o, 0),
                            row,
                            first,
                            count: n_moving - first,
                            shared_balls: false,
                        });
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
        // The link–link clusters come first (built above in that order), as the pass
        // over them wants.
        let pairs: Vec<(usize, usize)> = clusters
            .iter()
            .map_while(|c| match c.other {
                Other::Robot(l) => Some((c.link, l)),
                Other::Scene(..) => None,
            })
            .collect();
        let boxes: Vec<(usize, Vector3<f64>, Vector3<f64>)> = clusters[pairs.len()..]
            .iter()
            .map(|c| match c.other {
                Other::Scene(o, _) => (c.link, scene_boxes[o].0, scene_boxes[o].1),
                Other::Robot(_) => unreachable!("link–link clusters precede the scene's"),
            })
            .collect();
        let link_gaps = LinkBallGaps::new(
            link_balls.iter().map(|b| b.radius).collect(),
            &pairs,
            &boxes,
        );
        Ok(ClearanceChecker {
            model,
            gm,
            scene,
            group,
            margin,
            tube: 0.0,
            group_centres: vec![Vector3::zeros(); groups.len()],
            object_centres: vec![Vector3::zeros(); object_balls.len()],
            object_stamp: vec![0; object_balls.len()],
            state_stamp: 0,
            object_boxes: gm
                .objects
                .iter()
                .map(|o| {
                    let (c, h) = o.shape.local_aabb();
                    (o.placement.act_point(&c), o.placement.rotation, h)
                })
                .collect(),
            object_world_boxes: vec![(Vector3::zeros(), Vector3::zeros()); object_balls.len()],
            box_stamp: vec![0; object_balls.len()],
            object_balls,
            groups,
            entries,
            moving,
            clusters,
            link_centres: vec![Vector3::zeros(); link_balls.len()],
            link_gaps,
            link_balls,
            scene_shapes,
            scene_first,
            cover_centres: vec![Vector3::zeros(); cover.len()],
            cover_stamp: vec![0; gm.objects.len()],
            object_shapes: gm
                .objects
                .iter()
                .map(|o| PlacedShape::new(&o.shape, &o.placement))
                .collect(),
            pose_stamp: vec![0; gm.objects.len()],
            cover,
            cover_of,
            fixed,
            coeff,
            tube_norm,
            rate: vec![0.0; rows],
            q: DVector::from_column_slice(base),
            data: Data::new(model),
            warm: vec![WarmStart::default(); n_entries],
            epa: EpaWorkspace::default(),
            delta: vec![0.0; dim],
            open: VecDeque::new(),
            order: Vec::new(),
            last_limiting: 0,
            near: Vec::new(),
            near_shapes: Vec::new(),
            tree_stack: Vec::new(),
            cache_d: vec![0.0; n_entries],
            cache_t: vec![0.0; n_entries],
            cache_epoch: vec![0; n_entries],
            epoch: 0,
            t_now: 0.0,
            deadline: None,
            states_checked: 0,
            distances_computed: 0,
            planes_cleared: 0,
            live: Vec::new(),
            fill_live: false,
            plane_hints: vec![(0, 0); n_entries],
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

    /// Sets the joints outside the group from the full configuration `q` (its group
    /// entries are ignored: each check places the group's state).
    ///
    /// # Panics
    /// If `q` is not of the model's length.
    pub fn set_fixed_joints(&mut self, q: &[f64]) {
        self.q.copy_from_slice(q);
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
        // The ball groups' centres in the world, once per state (every block tests one);
        // the objects' balls on demand (stamped with the state).
        for (c, g) in self.group_centres.iter_mut().zip(&self.groups) {
            *c = self.data.world_from_joint[g.joint].act_point(&g.centre);
        }
        for (l, (c, b)) in self
            .link_centres
            .iter_mut()
            .zip(&self.link_balls)
            .enumerate()
        {
            *c = self.data.world_from_joint[b.joint].act_point(&b.centre);
            self.link_gaps.set_centre(l, c);
        }
        self.state_stamp += 1;
    }

    /// The world centre of robot object `i`'s ball at the placed state.
    fn object_centre(&mut self, i: usize) -> Vector3<f64> {
        if self.object_stamp[i] != self.state_stamp {
            let b = &self.object_balls[i];
            self.object_centres[i] = self.data.world_from_joint[b.joint].act_point(&b.centre);
            self.object_stamp[i] = self.state_stamp;
        }
        self.object_centres[i]
    }

    /// The gap between the bounding balls of ball group `a` and `b` (a group, or a scene
    /// shape in closed form), at the placed state.
    fn group_gap(&self, a: usize, b: Other) -> f64 {
        let (ca, ra) = (self.group_centres[a], self.groups[a].radius);
        match b {
            Other::Robot(j) => (ca - self.group_centres[j]).norm() - ra - self.groups[j].radius,
            Other::Scene(o, s) => self.shape_gap(&ca, o, s) - ra,
        }
    }

    /// The gap between the bounding balls of robot object `a` and `b` (a robot object, or
    /// a scene shape in closed form), at the placed state.
    fn object_gap(&mut self, a: usize, b: Other) -> f64 {
        let ca = self.object_centre(a);
        let ra = self.object_balls[a].radius;
        match b {
            Other::Robot(j) => {
                (ca - self.object_centre(j)).norm() - ra - self.object_balls[j].radius
            }
            Other::Scene(o, s) => self.shape_gap(&ca, o, s) - ra,
        }
    }

    /// Places robot object `i`'s cover balls at the placed state (once per state); their
    /// range in `cover`.
    fn place_cover(&mut self, i: usize) -> std::ops::Range<usize> {
        let (first, count) = self.cover_of[i];
        if self.cover_stamp[i] != self.state_stamp {
            for k in first..first + count {
                let b = &self.cover[k];
                self.cover_centres[k] = self.data.world_from_joint[b.joint].act_point(&b.centre);
            }
            self.cover_stamp[i] = self.state_stamp;
        }
        first..first + count
    }

    /// Whether the cover balls of robot object `a` all lie farther than `bound` from `b`
    /// (a robot object's cover balls or closed-form bound, or a scene shape's), a proof
    /// that the pair is farther apart than `bound`, at the placed state. For two robot
    /// objects: every ball against every ball, else each side's balls against the other's
    /// bound ([`ShapeBound`](crate::collision::ball_gap::ShapeBound)).
    fn cover_clears(&mut self, a: usize, b: Other, bound: f64) -> bool {
        let mine = self.place_cover(a);
        match b {
            Other::Robot(j) => {
                let theirs = self.place_cover(j);
                let balls = mine.clone().all(|i| {
                    let (ci, ri) = (self.cover_centres[i], self.cover[i].radius);
                    theirs.clone().all(|k| {
                        (ci - self.cover_centres[k]).norm() - ri - self.cover[k].radius > bound
                    })
                });
                balls || self.balls_clear_bound(mine, j, bound) || {
                    let theirs = self.place_cover(j);
                    self.balls_clear_bound(theirs, a, bound)
                }
            }
            Other::Scene(o, s) => mine.into_iter().all(|i| {
                self.shape_gap(&self.cover_centres[i], o, s) - self.cover[i].radius > bound
            }),
        }
    }

    /// Whether every placed cover ball of `balls` lies farther than `bound` from robot
    /// object `j`'s closed-form bound, at the placed state.
    fn balls_clear_bound(&mut self, balls: std::ops::Range<usize>, j: usize, bound: f64) -> bool {
        if self.pose_stamp[j] != self.state_stamp {
            let o = &self.gm.objects[j];
            let pose = self.data.world_from_joint[o.joint.0] * o.placement;
            self.object_shapes[j].set_pose(&pose);
            self.pose_stamp[j] = self.state_stamp;
        }
        let shape = &self.object_shapes[j];
        balls
            .into_iter()
            .all(|i| shape.point_distance(&self.cover_centres[i]) - self.cover[i].radius > bound)
    }

    /// Robot object `a`'s world axis-aligned box at the placed state (computed once per
    /// state).
    fn object_world_box(&mut self, a: usize) -> (Vector3<f64>, Vector3<f64>) {
        if self.box_stamp[a] != self.state_stamp {
            let (c, r, h) = &self.object_boxes[a];
            let world = &self.data.world_from_joint[self.object_balls[a].joint];
            let centre = world.act_point(c);
            let half = (world.rotation * r).abs() * h;
            self.object_world_boxes[a] = (centre - half, centre + half);
            self.box_stamp[a] = self.state_stamp;
        }
        self.object_world_boxes[a]
    }

    /// The gap between robot object `a`'s world axis-aligned box and `b`'s (a robot
    /// object's, or a scene shape's), a lower bound on their distance, at the placed state.
    fn object_box_gap(&mut self, a: usize, b: Other) -> f64 {
        let (lo_a, hi_a) = self.object_world_box(a);
        let (lo_b, hi_b) = match b {
            Other::Robot(j) => self.object_world_box(j),
            Other::Scene(o, s) => self.scene.objects[o].shapes[s].aabb,
        };
        (lo_b - hi_a)
            .sup(&(lo_a - hi_b))
            .sup(&Vector3::zeros())
            .norm()
    }

    /// The blocks of `cluster` its link's ball does not clear by more than `bound`, at the
    /// placed state, into `self.near`: all of them against a robot link or a scene object
    /// of one shape; against a scene object of several shapes (a mesh as its triangles, a
    /// voxel grid) the blocks of the shapes its tree does not clear
    /// ([`SceneObject::shapes_near`](crate::collision::SceneObject::shapes_near)).
    fn near_blocks(&mut self, cluster: &Cluster, bound: f64) {
        self.near.clear();
        let obj = match cluster.other {
            Other::Scene(o, _) if self.scene.objects[o].shapes.len() > 1 => &self.scene.objects[o],
            _ => {
                self.near
                    .push((cluster.first, cluster.first + cluster.count));
                return;
            }
        };
        // The blocks go shape by shape, one per ball group of the link.
        let per_shape = cluster.count / obj.shapes.len();
        let (centre, radius) = (
            self.link_centres[cluster.link],
            self.link_balls[cluster.link].radius,
        );
        obj.shapes_near(
            &centre,
            radius,
            bound,
            &mut self.tree_stack,
            &mut self.near_shapes,
        );
        self.near.extend(
            self.near_shapes
                .iter()
                .map(|&(s, e)| (cluster.first + s * per_shape, cluster.first + e * per_shape)),
        );
    }

    /// The distance from `c` to scene shape `(o, s)` in closed form (a primitive's exact
    /// distance, a lower bound for a hull: [`ShapeBound`](crate::collision::ball_gap::ShapeBound)).
    fn shape_gap(&self, c: &Vector3<f64>, o: usize, s: usize) -> f64 {
        self.scene_shapes[self.scene_first[o] + s].point_distance(c)
    }

    /// The signed distance of entry `k`, or a lower bound on it above `enough`, or an
    /// upper bound on it at most `within` ([`distance_outside`]).
    /// Above `enough` the pair is first tried against the plane its last GJK run ended
    /// with ([`plane_gap`]): one support map per shape, and GJK only when that plane
    /// falls short.
    fn exact_outside(&mut self, k: usize, within: f64, enough: f64) -> f64 {
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
        if enough.is_finite() {
            let gap = plane_gap(
                &oa.shape,
                &pa,
                shape,
                &pose,
                &-self.warm[k].direction(),
                &mut self.plane_hints[k],
            );
            if gap > enough.max(0.0) {
                self.planes_cleared += 1;
                return gap;
            }
        }
        self.distances_computed += 1;
        if within.is_finite() || enough.is_finite() {
            return distance_outside(
                &oa.shape,
                &pa,
                shape,
                &pose,
                within,
                enough,
                &mut self.warm[k],
                &mut self.epa,
            );
        }
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

    /// At the placed state: whether every moving pair is farther apart than the margin
    /// plus `tube · ‖c_p ⊘ w‖₂` ([`StateValidity::is_valid`]). The block that failed last
    /// goes first, then the clusters in turn, each bounded before its pairs are; no
    /// pair is computed past the first one found within, and a pair's GJK stops at the
    /// first bound that decides it.
    fn state_clear(&mut self, tube: f64) -> bool {
        let last = self.last_limiting;
        if last < self.moving.len() && !self.block_clear(last, tube, false) {
            return false;
        }
        self.link_gaps.fill_all();
        for ci in 0..self.clusters.len() {
            let cluster = self.clusters[ci];
            let extra = self.margin + tube * self.tube_norm[cluster.row];
            if self.link_gaps.gap[ci] > extra {
                continue;
            }
            self.near_blocks(&cluster, extra);
            for r in 0..self.near.len() {
                let (from, to) = self.near[r];
                for bi in from..to {
                    if bi != last && !self.block_clear(bi, tube, cluster.shared_balls) {
                        self.last_limiting = bi;
                        return false;
                    }
                }
            }
        }
        true
    }

    /// Whether every object pair of moving block `bi` is farther apart than the margin
    /// plus the tube's share, at the placed state; `balls_near`: its balls are known to
    /// be within that (they are its cluster's, which did not clear it).
    fn block_clear(&mut self, bi: usize, tube: f64, balls_near: bool) -> bool {
        let block = self.moving[bi];
        let extra = self.margin + tube * self.tube_norm[block.row];
        if !balls_near && self.group_gap(block.a, block.b) > extra {
            return true;
        }
        for k in block.first..block.first + block.count {
            let (a, b) = self.entries[k];
            if block.count > 1 && self.object_gap(a, b) > extra {
                continue;
            }
            if self.object_box_gap(a, b) > extra || self.cover_clears(a, b, extra) {
                continue;
            }
            if self.exact_outside(k, extra, extra) <= extra {
                return false;
            }
        }
        true
    }

    /// At the placed state: the largest further fraction of the current segment (rates in
    /// `self.rate`) that every moving pair vouches for, capped at `need` (`+∞` when no
    /// pair limits it), or `None` when a pair is within the margin (plus the tube).
    fn allowed_step(&mut self, need: f64, tube: f64) -> Option<f64> {
        // Best first: the blocks whose bounding balls vouch for the shortest steps go
        // first, so the step shrinks early; a block whose balls keep it clear over the
        // step found so far (and every block after it) is not computed.
        let mut step = need;
        self.order.clear();
        // The segment's first state looks at every cluster, the later ones only at those
        // it left live.
        let first = self.fill_live;
        self.fill_live = false;
        if first {
            self.live.clear();
            self.link_gaps.fill_all();
        }
        let clusters = if first {
            self.clusters.len()
        } else {
            self.live.len()
        };
        for i in 0..clusters {
            let ci = if first { i } else { self.live[i] };
            let cluster = self.clusters[ci];
            let (rate, extra) = (
                self.rate[cluster.row],
                self.margin + tube * self.tube_norm[cluster.row],
            );
            let slack = extra - 0.5 * self.margin;
            let bound = (slack + step * rate).max(extra);
            let gap = if first {
                self.link_gaps.gap[ci]
            } else {
                self.link_gaps.fill_one(ci)
            };
            // Anywhere on the segment the balls are at least `gap - rate` apart, and a
            // later state needs at most `(slack + rate).max(extra)` (its `need` is at most
            // the whole segment): a cluster farther than that is clear at every later one.
            if first && gap - rate <= (slack + rate).max(extra) {
                self.live.push(ci);
            }
            // The link's ball clears the other link or object: so do all its blocks.
            if gap > bound {
                continue;
            }
            self.near_blocks(&cluster, bound);
            for r in 0..self.near.len() {
                let (from, to) = self.near[r];
                for bi in from..to {
                    let block = self.moving[bi];
                    let gap = if cluster.shared_balls {
                        gap
                    } else {
                        self.group_gap(block.a, block.b)
                    };
                    if gap > bound {
                        continue;
                    }
                    // The block that limited the last state goes first.
                    let vouched = if bi == self.last_limiting {
                        -1.0
                    } else if gap <= extra {
                        0.0
                    } else {
                        (gap - slack) / rate
                    };
                    self.order.push((vouched, bi));
                }
            }
        }
        self.order.sort_unstable_by(|x, y| x.0.total_cmp(&y.0));
        for o in 0..self.order.len() {
            let (vouched, bi) = self.order[o];
            if vouched > step {
                break;
            }
            let block = self.moving[bi];
            let (rate, extra) = (
                self.rate[block.row],
                self.margin + tube * self.tube_norm[block.row],
            );
            let slack = extra - 0.5 * self.margin;
            for k in block.first..block.first + block.count {
                let (a, b) = self.entries[k];
                let bound = (slack + step * rate).max(extra);
                // The distance found earlier on this segment, less the most it can have
                // closed since, is a lower bound too.
                if self.cache_epoch[k] == self.epoch
                    && self.cache_d[k] - rate * (self.t_now - self.cache_t[k]).abs() > bound
                {
                    continue;
                }
                if block.count > 1 && self.object_gap(a, b) > bound {
                    continue;
                }
                if self.object_box_gap(a, b) > bound || self.cover_clears(a, b, bound) {
                    continue;
                }
                // Above `bound` a lower bound is enough, at or below `extra` an upper
                // bound (GJK stops early either way).
                let d = self.exact_outside(k, extra, bound);
                if d <= extra {
                    self.last_limiting = bi;
                    return None;
                }
                self.cache_d[k] = d;
                self.cache_t[k] = self.t_now;
                self.cache_epoch[k] = self.epoch;
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
    /// its distance computed exactly (a pair's GJK stops once it shows the pair farther
    /// than the closest found so far); `None` when nothing is checked.
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
            if self.group_gap(block.a, block.b) >= cut {
                continue;
            }
            for k in block.first..block.first + block.count {
                let (a, b) = self.entries[k];
                let cut = best.map_or(f64::INFINITY, |(b, _)| b);
                if self.object_gap(a, b) >= cut {
                    continue;
                }
                // Above the closest distance so far a lower bound is enough.
                let d = self.exact_outside(k, f64::NEG_INFINITY, cut);
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
        if self.past_deadline() {
            return false;
        }
        self.states_checked += 1;
        self.rate.iter_mut().for_each(|r| *r = 0.0);
        self.epoch += 1;
        self.t_now = 0.0;
        self.place(x);
        self.state_clear(self.tube)
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
        self.fill_live = true;
        // The end state first (a segment towards an obstacle fails there at once), then
        // the start, then the stretch neither covers, coarse to fine: each checked state
        // vouches for the same fraction on both sides of it.
        let mut states = 2;
        let Some(s1) = self.check_at(a, b, 1.0, 1.0, scratch, checks) else {
            return false;
        };
        if s1 >= 1.0 {
            return true;
        }
        let Some(s0) = self.check_at(a, b, 0.0, 1.0 - s1, scratch, checks) else {
            return false;
        };
        if s0 >= 1.0 - s1 {
            return true;
        }
        self.open.clear();
        self.open.push_back((s0, 1.0 - s1));
        while let Some((lo, hi)) = self.open.pop_front() {
            states += 1;
            if states > MAX_STATES_PER_SEGMENT {
                return false;
            }
            let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
            let Some(s) = self.check_at(a, b, mid, half, scratch, checks) else {
                return false;
            };
            if s >= half {
                continue;
            }
            if s.is_nan() || s <= 1e-12 {
                return false;
            }
            self.open.push_back((lo, mid - s));
            self.open.push_back((mid + s, hi));
        }
        true
    }
}

impl ClearanceChecker<'_> {
    /// Checks the state at fraction `t` of the segment `a → b` (rates set): the fraction
    /// it vouches for on either side, capped at `need`, or `None` when it is too close.
    fn check_at(
        &mut self,
        a: &[f64],
        b: &[f64],
        t: f64,
        need: f64,
        scratch: &mut [f64],
        checks: &mut u64,
    ) -> Option<f64> {
        if self.past_deadline() {
            return None;
        }
        self.t_now = t;
        for (k, x) in scratch.iter_mut().enumerate() {
            *x = a[k] + t * (b[k] - a[k]);
        }
        *checks += 1;
        self.states_checked += 1;
        self.place(scratch);
        self.allowed_step(need, 0.0)
    }

    /// From `deadline` on, every state a check would evaluate is refused unchecked (not
    /// counted in `states_checked`): a state check fails, and so does a segment check at
    /// its next state. Refusing is always sound, and a caller bounded by a time limit
    /// then overruns it by at most the one state being evaluated as it passes. `None`:
    /// no deadline (the default). [`Self::distance_report`] ignores it.
    pub fn set_deadline(&mut self, deadline: Option<Instant>) {
        self.deadline = deadline;
    }

    fn past_deadline(&self) -> bool {
        self.deadline.is_some_and(|d| Instant::now() >= d)
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

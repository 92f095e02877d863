//! Where to stand for a grasp: the base poses of a mobile manipulator from which a joint
//! group reaches a grasp pose collision-free and stays upright with the payload, ranked.
//!
//! **Poses.** A grid of base poses `(x, y, θ)` ([`PlacementGrid`], by default a square
//! around the grasp as wide as the group's reach) is evaluated pose by pose in parallel
//! ([`evaluate_grid`]: one workspace per rayon worker). At each pose, in order:
//!
//! 1. *reach*: the grasp must lie within the ball that bounds every position of the grasp
//!    frame relative to the base (sum of the chain's joint offsets and prismatic travel);
//! 2. *base*: the links on the base body (the planar root's) must not touch the scene;
//! 3. *IK*: damped least squares over the group ([`ik_goals`]) from the posture's group
//!    coordinates, then `ik_attempts − 1` seeds uniform in the planning box (ChaCha8 with
//!    `seed`, the same seeds at every pose); a solution counts when it is within the
//!    position and orientation tolerances, inside the box and collision-free (self pairs
//!    and scene, the collision module's early-exit checks);
//! 4. *measures* of each distinct solution: **clearance** `c`, the smallest signed distance
//!    of the posture to the scene and between the enabled link pairs (it must exceed the
//!    margin); **tip-over margin** `t`, the ZMP margin of the posture at rest with the
//!    payload (a point mass at the object's centre, fixed in the grasp frame) over the base's
//!    support polygon (it must be positive); **manipulability** `m`, Yoshikawa's `√det(J Jᵀ)`
//!    of the grasp frame's 6 × n group Jacobian (world-aligned).
//!
//! **Score** (`docs/placement.md`): each measure is divided by its largest value over all
//! feasible solutions (clearance first capped at `clearance_cap`), and the score is the
//! weighted mean `(w_m m̂ + w_c ĉ + w_t t̂) / (w_m + w_c + w_t)`, in (0, 1]. Each base pose
//! keeps its best-scoring solution; candidates are sorted by score, ties by grid order.
//!
//! **Determinism and bounds.** Every pose starts from the same seeds and does not read
//! what other poses found, so the ranking does not depend on the thread count. The grid
//! holds at most `max_samples` poses, each at most `ik_attempts` IK solves of at most 100
//! iterations. Per pose, the IK set-up allocates (one model workspace); the collision,
//! clearance and stability evaluations reuse the worker's workspace.

use super::goal::{GoalPose, ik_goals};
use super::group::JointGroup;
use crate::collision::{
    GeometryData, GeometryModel, LinkGeometry, PairSelection, Scene, SceneData, compute_collision,
    compute_distances, compute_scene_distances, scene_collision, update_geometry_placements,
};
use crate::ik::placement::{PlacementGrid, evaluate_grid, platform_pose};
use crate::kinematics::{self, ReferenceFrame};
use crate::manipulability::JacobianSvd;
use crate::multibody::{Data, JointType, Model, RootJoint};
use crate::spatial::Inertia;
use crate::stability::{
    ExternalLoads, StabilityData, StabilityModel, SupportAttachment, SupportPolygon, evaluate,
};
use crate::{Error, Result};
use nalgebra::{DMatrix, DVector, Matrix6xX, Point3, Vector3};

/// The object held at the grasp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Payload {
    /// Its mass (kg), ≥ 0.
    pub mass: f64,
    /// Its centre of mass in the grasp frame (m).
    pub offset: Vector3<f64>,
}

/// The weights of the three measures in the score.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct ScoreWeights {
    /// Weight of the manipulability.
    pub manipulability: f64,
    /// Weight of the clearance.
    pub clearance: f64,
    /// Weight of the tip-over margin.
    pub tip_over: f64,
}

/// The options of [`place_base`].
#[derive(Clone, Debug, PartialEq)]
pub struct PlacementOptions {
    /// The base positions searched, `[x0, y0, x1, y1]` (world, m); `None`: the square
    /// centred on the grasp whose half side is the horizontal reach bound.
    pub area: Option<[f64; 4]>,
    /// Grid step (m).
    pub step: f64,
    /// Headings per grid cell, `θ_k = −π + 2πk/N`.
    pub headings: usize,
    /// IK seeds per base pose (the posture, then uniform in the box).
    pub ik_attempts: usize,
    /// The seed of the uniform IK seeds.
    pub seed: u64,
    /// The clearance a posture must exceed (m).
    pub margin: f64,
    /// Clearance above this (m) scores as this.
    pub clearance_cap: f64,
    /// The score's weights.
    pub weights: ScoreWeights,
    /// The most base poses the grid may hold.
    pub max_samples: usize,
    /// The most candidates returned (best first).
    pub max_candidates: usize,
}

impl Default for PlacementOptions {
    /// Step 0.1 m, 16 headings, 8 IK seeds, seed 0, margin 5 mm, clearance counted up to
    /// 0.1 m, equal weights, at most 200 000 poses, 20 candidates.
    fn default() -> Self {
        PlacementOptions {
            area: None,
            step: 0.1,
            headings: 16,
            ik_attempts: 8,
            seed: 0,
            margin: 0.005,
            clearance_cap: 0.1,
            weights: ScoreWeights {
                manipulability: 1.0,
                clearance: 1.0,
                tip_over: 1.0,
            },
            max_samples: 200_000,
            max_candidates: 20,
        }
    }
}

/// What a placement search is asked.
#[derive(Clone, Copy, Debug)]
pub struct PlacementProblem<'a> {
    /// The robot on a planar root (`q = [x, y, θ, …]`).
    pub model: &'a Model,
    /// Its collision geometry.
    pub geometry: &'a GeometryModel,
    /// The obstacles (world frame).
    pub scene: &'a Scene,
    /// The joints that reach.
    pub group: &'a JointGroup,
    /// A full configuration: the joints outside the group stay here (its base
    /// coordinates are replaced by each pose); its group coordinates are the first IK seed.
    pub posture: &'a [f64],
    /// The support polygon in the base frame.
    pub support: &'a SupportPolygon,
    /// The grasp pose of a frame, with tolerances.
    pub grasp: &'a GoalPose,
    /// The object held.
    pub payload: Payload,
}

/// One base placement.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Candidate {
    /// Base pose `[x, y, θ]`.
    pub base: [f64; 3],
    /// The grasping posture (full configuration).
    pub q: Vec<f64>,
    /// Yoshikawa's manipulability of the group Jacobian.
    pub manipulability: f64,
    /// The smallest signed distance to the scene and between links (m).
    pub clearance: f64,
    /// The pair at that distance: link, and the other link or scene object.
    pub closest: [String; 2],
    /// ZMP margin at rest with the payload (m).
    pub tip_over_margin: f64,
    /// The score in (0, 1].
    pub score: f64,
    /// The position and rotation errors of the grasp frame (m, rad).
    pub grasp_error: [f64; 2],
}

/// How many base poses failed at each stage, and the rest.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct PlacementCounts {
    /// Poses of the grid.
    pub poses: usize,
    /// Grasp beyond the reach bound.
    pub out_of_reach: usize,
    /// Base links touch the scene.
    pub base_in_collision: usize,
    /// No IK seed reached the grasp within the tolerances and the box.
    pub ik_not_reached: usize,
    /// Reached, but only in collision.
    pub reached_in_collision: usize,
    /// Collision-free, but every solution's clearance was within the margin.
    pub too_close: usize,
    /// Clear, but every such solution tips over with the payload.
    pub unstable: usize,
    /// Poses with at least one feasible solution.
    pub feasible: usize,
}

/// The result of [`place_base`].
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct Placement {
    /// The grid searched.
    pub grid: PlacementGrid,
    /// The best candidates, best first (one per base pose).
    pub candidates: Vec<Candidate>,
    /// Per-stage counts.
    pub counts: PlacementCounts,
    /// The reach bound: centre (base frame) and radius (m).
    pub reach: ([f64; 3], f64),
    /// The smallest position error any IK attempt ended with (m).
    pub best_position_error: f64,
}

impl Placement {
    /// Why no pose works, or `None` when some does.
    #[must_use]
    pub fn failure(&self) -> Option<String> {
        if !self.candidates.is_empty() {
            return None;
        }
        let c = &self.counts;
        Some(format!(
            "no base pose reaches the grasp collision-free and upright: of {} poses, {} out \
             of reach, {} with the base in the scene, {} where IK did not reach it (closest \
             {:.4} m), {} reached only in collision, {} closer than the margin, {} tipping \
             over with the payload",
            c.poses,
            c.out_of_reach,
            c.base_in_collision,
            c.ik_not_reached,
            self.best_position_error,
            c.reached_in_collision,
            c.too_close,
            c.unstable
        ))
    }
}

/// What one pose gave.
struct PoseOutcome {
    stage: Stage,
    solutions: Vec<Candidate>,
    best_position_error: f64,
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum Stage {
    OutOfReach,
    BaseInCollision,
    NotReached,
    InCollision,
    TooClose,
    Unstable,
    Feasible,
}

/// Per-worker buffers.
struct Workspace {
    data: Data,
    gd: GeometryData,
    sd: SceneData,
    base_gd: GeometryData,
    base_sd: SceneData,
    stab: StabilityData,
    q: DVector<f64>,
    zero: DVector<f64>,
    j6: Matrix6xX<f64>,
    jg: DMatrix<f64>,
}

/// The immutable set-up shared by the workers.
struct Setup<'a> {
    p: &'a PlacementProblem<'a>,
    o: &'a PlacementOptions,
    base_geometry: GeometryModel,
    payload_model: Model,
    stability: StabilityModel,
    reach_centre: Vector3<f64>,
    reach_radius: f64,
}

/// The reach bound of the grasp frame relative to the base: the origin of the first
/// joint below the planar root on the frame's chain (base frame) and the sum of the
/// offsets below it, the frame's own offset and every prismatic joint's largest travel.
fn reach_bound(model: &Model, frame: usize) -> Result<(Vector3<f64>, f64)> {
    let fr = &model.frames[frame];
    let mut path = Vec::new();
    let mut j = fr.parent_joint.0;
    while j != 0 && model.joint_types[j] != JointType::Planar {
        path.push(j);
        j = model.parents[j].0;
    }
    let Some(&first) = path.last() else {
        return Err(Error::invalid(
            "grasp frame",
            format!("'{}' is fixed to the base: no joint moves it", fr.name),
        ));
    };
    let mut radius = fr.placement.translation.norm();
    for &j in &path {
        let jt = model.joint_types[j];
        if jt.is_prismatic() {
            let iq = model.idx_q[j];
            let travel = model.lower_position_limit[iq]
                .abs()
                .max(model.upper_position_limit[iq].abs());
            if !travel.is_finite() {
                return Err(Error::invalid(
                    "grasp frame",
                    format!("prismatic joint '{}' has no travel limits", model.names[j]),
                ));
            }
            radius += travel;
        }
        if j != first {
            radius += model.joint_placements[j].translation.norm();
        }
    }
    Ok((model.joint_placements[first].translation, radius))
}

/// The links carried by the root joint's body, as a geometry model of their own (no
/// pairs): the base that must not stand in the scene.
fn base_geometry(model: &Model, gm: &GeometryModel) -> GeometryModel {
    let root = (1..model.njoints)
        .find(|&j| model.joint_types[j] == JointType::Planar)
        .unwrap_or(1);
    let mut out = GeometryModel {
        links: Vec::new(),
        objects: Vec::new(),
        pairs: Vec::new(),
        enabled: Vec::new(),
    };
    for link in gm.links.iter().filter(|l| l.joint.0 == root) {
        let first = out.objects.len();
        for o in &gm.objects[link.first..link.first + link.count] {
            let mut o = o.clone();
            o.link = out.links.len();
            out.objects.push(o);
        }
        out.links.push(LinkGeometry {
            name: link.name.clone(),
            joint: link.joint,
            first,
            count: link.count,
        });
    }
    out
}

fn check(p: &PlacementProblem<'_>, o: &PlacementOptions) -> Result<()> {
    if p.model.root != RootJoint::Planar {
        return Err(Error::invalid(
            "root",
            format!(
                "base placement needs a planar root, '{}' has a {} root",
                p.model.name, p.model.root
            ),
        ));
    }
    crate::error::ensure_len("posture", p.model.nq, p.posture.len())?;
    crate::error::ensure_finite("posture", p.posture)?;
    if !(p.payload.mass.is_finite() && p.payload.mass >= 0.0) {
        return Err(Error::invalid(
            "payload",
            format!("{} is not a mass in kg (≥ 0)", p.payload.mass),
        ));
    }
    crate::error::ensure_finite("payload offset", p.payload.offset.iter())?;
    let w = &o.weights;
    for (field, v) in [
        ("weight of manipulability", w.manipulability),
        ("weight of clearance", w.clearance),
        ("weight of tip-over", w.tip_over),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(Error::invalid(field, format!("{v} is not ≥ 0")));
        }
    }
    if w.manipulability + w.clearance + w.tip_over <= 0.0 {
        return Err(Error::invalid("weights", "at least one must be positive"));
    }
    for (field, v) in [("margin", o.margin), ("clearance cap", o.clearance_cap)] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(Error::invalid(field, format!("{v} is not a length ≥ 0")));
        }
    }
    if o.clearance_cap <= o.margin {
        return Err(Error::invalid(
            "clearance cap",
            format!("{} must exceed the margin {}", o.clearance_cap, o.margin),
        ));
    }
    if o.ik_attempts == 0 {
        return Err(Error::invalid("ik attempts", "must be at least 1"));
    }
    if o.max_candidates == 0 {
        return Err(Error::invalid("max candidates", "must be at least 1"));
    }
    Ok(())
}

/// Ranks the base poses from which the group reaches the grasp (module docs).
///
/// # Errors
/// [`Error::InvalidInput`] naming the field: a model without a planar root, a posture of
/// the wrong length, a negative payload, weights, margin or options out of range, an
/// area or grid beyond `max_samples` poses, a grasp frame that no joint moves; errors of
/// the IK solver.
pub fn place_base(problem: &PlacementProblem<'_>, options: &PlacementOptions) -> Result<Placement> {
    check(problem, options)?;
    let model = problem.model;
    let frame = problem.grasp.frame.0;
    let (centre, radius) = reach_bound(model, frame)?;
    let target = problem.grasp.target.translation.vector;
    let area = options.area.unwrap_or_else(|| {
        let half = centre.xy().norm() + radius;
        [
            target.x - half,
            target.y - half,
            target.x + half,
            target.y + half,
        ]
    });
    let grid = PlacementGrid::new(area, options.step, options.headings)?;
    if grid.len() > options.max_samples {
        return Err(Error::invalid(
            "step",
            format!(
                "{} base poses exceed the limit of {}; use a larger step, fewer headings or a smaller area",
                grid.len(),
                options.max_samples
            ),
        ));
    }
    // The payload: a point mass on the grasp frame's body.
    let mut payload_model = model.clone();
    let fr = &model.frames[frame];
    let at = fr.placement.act_point(&problem.payload.offset);
    let j = fr.parent_joint.0;
    payload_model.inertias[j] = model.inertias[j] + Inertia::point_mass(problem.payload.mass, at);
    let stability = StabilityModel::new(
        &payload_model,
        problem.support.clone(),
        SupportAttachment::Base,
        &crate::stability::BodySet::All,
    )?;
    let setup = Setup {
        p: problem,
        o: options,
        base_geometry: base_geometry(model, problem.geometry),
        payload_model,
        stability,
        reach_centre: centre,
        reach_radius: radius,
    };
    let outcomes = evaluate_grid(
        &grid,
        || setup.workspace(),
        |ws, _, base| setup.evaluate(ws, base),
    )?;
    let mut counts = PlacementCounts {
        poses: grid.len(),
        ..PlacementCounts::default()
    };
    let mut best_position_error = f64::INFINITY;
    let mut all: Vec<(usize, Candidate)> = Vec::new();
    for (i, out) in outcomes.into_iter().enumerate() {
        best_position_error = best_position_error.min(out.best_position_error);
        match out.stage {
            Stage::OutOfReach => counts.out_of_reach += 1,
            Stage::BaseInCollision => counts.base_in_collision += 1,
            Stage::NotReached => counts.ik_not_reached += 1,
            Stage::InCollision => counts.reached_in_collision += 1,
            Stage::TooClose => counts.too_close += 1,
            Stage::Unstable => counts.unstable += 1,
            Stage::Feasible => counts.feasible += 1,
        }
        all.extend(out.solutions.into_iter().map(|c| (i, c)));
    }
    let candidates = rank(all, options);
    Ok(Placement {
        grid,
        candidates,
        counts,
        reach: ([centre.x, centre.y, centre.z], radius),
        best_position_error,
    })
}

/// Scores every feasible solution (module docs), keeps each pose's best and sorts.
fn rank(mut all: Vec<(usize, Candidate)>, o: &PlacementOptions) -> Vec<Candidate> {
    let cap = |c: f64| c.min(o.clearance_cap);
    let max = |f: &dyn Fn(&Candidate) -> f64| all.iter().map(|(_, c)| f(c)).fold(0.0_f64, f64::max);
    let (m_max, c_max, t_max) = (
        max(&|c| c.manipulability),
        max(&|c| cap(c.clearance)),
        max(&|c| c.tip_over_margin),
    );
    let w = &o.weights;
    let wsum = w.manipulability + w.clearance + w.tip_over;
    let part = |x: f64, top: f64| if top > 0.0 { x / top } else { 0.0 };
    for (_, c) in &mut all {
        c.score = (w.manipulability * part(c.manipulability, m_max)
            + w.clearance * part(cap(c.clearance), c_max)
            + w.tip_over * part(c.tip_over_margin, t_max))
            / wsum;
    }
    // Best first; ties by grid order, then by the order the IK found them.
    all.sort_by(|(ia, a), (ib, b)| b.score.total_cmp(&a.score).then(ia.cmp(ib)));
    let mut seen = std::collections::BTreeSet::new();
    let mut out = Vec::new();
    for (i, c) in all {
        if seen.insert(i) {
            out.push(c);
            if out.len() == o.max_candidates {
                break;
            }
        }
    }
    out
}

impl Setup<'_> {
    fn workspace(&self) -> Workspace {
        let p = self.p;
        let dim = p.group.dim();
        Workspace {
            data: Data::new(p.model),
            gd: GeometryData::new(p.geometry),
            sd: SceneData::new(p.geometry, p.scene),
            base_gd: GeometryData::new(&self.base_geometry),
            base_sd: SceneData::new(&self.base_geometry, p.scene),
            stab: StabilityData::new(&self.stability),
            q: DVector::from_column_slice(p.posture),
            zero: DVector::zeros(p.model.nv),
            j6: Matrix6xX::zeros(p.model.nv),
            jg: DMatrix::zeros(6, dim),
        }
    }

    fn evaluate(&self, ws: &mut Workspace, base: [f64; 3]) -> Result<PoseOutcome> {
        let p = self.p;
        let grasp = p.grasp;
        let mut out = PoseOutcome {
            stage: Stage::OutOfReach,
            solutions: Vec::new(),
            best_position_error: f64::INFINITY,
        };
        // 1. Reach.
        let centre = platform_pose(base) * Point3::from(self.reach_centre);
        let gap = (grasp.target.translation.vector - centre.coords).norm() - self.reach_radius;
        if gap > grasp.position_tolerance {
            out.best_position_error = gap;
            return Ok(out);
        }
        // 2. The base in the scene. The collision workspaces start cold at every pose,
        // so no distance depends on which poses this worker evaluated before.
        for gd in [&mut ws.gd, &mut ws.base_gd] {
            gd.reset_warm_starts();
        }
        for sd in [&mut ws.sd, &mut ws.base_sd] {
            sd.reset_warm_starts();
        }
        ws.q.copy_from_slice(p.posture);
        ws.q[0] = base[0];
        ws.q[1] = base[1];
        ws.q[2] = base[2];
        kinematics::forward_kinematics(p.model, &mut ws.data, &ws.q);
        update_geometry_placements(&self.base_geometry, &ws.data, &mut ws.base_gd);
        if scene_collision(&self.base_geometry, &ws.base_gd, p.scene, &mut ws.base_sd).is_some() {
            out.stage = Stage::BaseInCollision;
            return Ok(out);
        }
        // 3. IK over the group, collision-free solutions only.
        let start: Vec<f64> = ws.q.as_slice().to_vec();
        let found = {
            let (data, gd, sd, q) = (&mut ws.data, &mut ws.gd, &mut ws.sd, &mut ws.q);
            let mut free = |x: &[f64]| {
                p.group.embed(x, q.as_mut_slice());
                kinematics::forward_kinematics(p.model, data, q);
                update_geometry_placements(p.geometry, data, gd);
                compute_collision(p.geometry, gd).is_none()
                    && scene_collision(p.geometry, gd, p.scene, sd).is_none()
            };
            ik_goals(
                p.model,
                p.group,
                &start,
                grasp,
                &mut free,
                self.o.ik_attempts,
                self.o.ik_attempts,
                self.o.seed,
                far_future(),
            )?
        };
        out.best_position_error = found.best_position_error;
        if found.states.is_empty() {
            out.stage = if found.reached == 0 {
                Stage::NotReached
            } else {
                Stage::InCollision
            };
            return Ok(out);
        }
        // 4. Measures.
        out.stage = Stage::TooClose;
        for x in &found.states {
            ws.q.copy_from_slice(&start);
            p.group.embed(x, ws.q.as_mut_slice());
            let (clearance, closest) = self.clearance(ws);
            if clearance <= self.o.margin {
                continue;
            }
            if out.stage == Stage::TooClose {
                out.stage = Stage::Unstable;
            }
            let report = evaluate(
                &self.payload_model,
                &mut ws.data,
                &self.stability,
                &mut ws.stab,
                &ws.q,
                &ws.zero,
                &ws.zero,
                &ExternalLoads::NONE,
            );
            let Some(tip) = report.zmp_margin.filter(|t| *t > 0.0) else {
                continue;
            };
            out.stage = Stage::Feasible;
            kinematics::frame_jacobian(
                p.model,
                &mut ws.data,
                &ws.q,
                grasp.frame,
                ReferenceFrame::LocalWorldAligned,
                &mut ws.j6,
            );
            let pose = ws.data.world_from_frame[grasp.frame.0].to_isometry();
            let (pe, re) = grasp.errors(&pose);
            for (k, &iv) in p.group.q_index.iter().enumerate() {
                for r in 0..6 {
                    ws.jg[(r, k)] = ws.j6[(r, iv)];
                }
            }
            let manipulability = JacobianSvd::new(&ws.jg)?.yoshikawa()?;
            out.solutions.push(Candidate {
                base,
                q: ws.q.as_slice().to_vec(),
                manipulability,
                clearance,
                closest,
                tip_over_margin: tip,
                score: 0.0,
                grasp_error: [pe, re],
            });
        }
        Ok(out)
    }

    /// The smallest signed distance of `ws.q` to the scene and between enabled link
    /// pairs, and the pair.
    fn clearance(&self, ws: &mut Workspace) -> (f64, [String; 2]) {
        let p = self.p;
        kinematics::forward_kinematics(p.model, &mut ws.data, &ws.q);
        update_geometry_placements(p.geometry, &ws.data, &mut ws.gd);
        let d_self = compute_distances(p.geometry, &mut ws.gd, PairSelection::Enabled);
        let d_scene = compute_scene_distances(p.geometry, &mut ws.gd, p.scene, &mut ws.sd);
        let links = &p.geometry.links;
        if d_scene <= d_self
            && let Some(k) = ws.sd.closest
        {
            let no = p.scene.objects.len();
            return (
                d_scene,
                [
                    links[k / no].name.clone(),
                    p.scene.objects[k % no].id.clone(),
                ],
            );
        }
        match ws.gd.closest {
            Some(i) => {
                let [a, b] = p.geometry.pairs[i];
                (d_self, [links[a].name.clone(), links[b].name.clone()])
            }
            None => (f64::INFINITY, [String::new(), String::new()]),
        }
    }
}

/// A deadline that never passes within a run (the search is bounded by its counts).
fn far_future() -> std::time::Instant {
    let now = std::time::Instant::now();
    now.checked_add(std::time::Duration::from_secs(365 * 24 * 3600))
        .unwrap_or(now)
}

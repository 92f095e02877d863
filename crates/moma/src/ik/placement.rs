//! Base-placement maps: reachability and manipulability over a grid of base poses.
//!
//! For a fixed end-effector target, every base pose `(x, y, θ)` of a grid is evaluated
//! independently (in parallel with rayon; each worker owns one evaluation workspace,
//! i.e. one model `Data` and one IK workspace): is the target reachable from there (IK of
//! the arm with the base fixed), and how good is the reaching configuration (a chosen
//! [`Measure`] of the arm's or of the whole body's Jacobian)? The map reports every
//! sample and the best placement.
//!
//! The maps live in `ik` (not in [`crate::manipulability`], which only measures a given
//! Jacobian) because every sample is an IK solve: `manipulability` sits below `ik`, and
//! the IK's manipulability objective already uses its measures.

use super::tasks::{FrameKinematics, PoseTask, TaskRows};
use super::{IkOptions, IkWorkspace, solve_with_restarts};
use crate::error::{Error, Result, ensure_finite};
use crate::manipulability::{JacobianSvd, Measure, evaluate_svd};
use crate::mobile::DiffDrive;
use crate::mobile::whole_body::{BaseInputs, compose_jacobian};
use nalgebra::{DMatrix, DVector, Isometry3, Translation3, UnitQuaternion, Vector3};
use rayon::prelude::*;

/// Largest number of samples a map may have (guards against typos in `--step`).
pub const MAX_SAMPLES: usize = 50_000_000;

/// A grid of base poses: x and y from the area corners in steps of `step` (both ends
/// included when they fall on the grid), and `headings` equally spaced headings
/// `θ_k = −π + 2πk/N`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct PlacementGrid {
    /// Lower x corner (m).
    pub x0: f64,
    /// Lower y corner (m).
    pub y0: f64,
    /// Upper x corner (m).
    pub x1: f64,
    /// Upper y corner (m).
    pub y1: f64,
    /// Grid step (m).
    pub step: f64,
    /// Number of headings per cell.
    pub headings: usize,
    /// Number of x samples.
    pub nx: usize,
    /// Number of y samples.
    pub ny: usize,
}

impl PlacementGrid {
    /// A validated grid over `[x0, x1] × [y0, y1]`.
    pub fn new(area: [f64; 4], step: f64, headings: usize) -> Result<Self> {
        ensure_finite("area", &area)?;
        let [x0, y0, x1, y1] = area;
        // (finite already checked, so `<=` is the exact negation of `>`)
        if x1 <= x0 || y1 <= y0 {
            return Err(Error::invalid(
                "area",
                format!(
                    "needs x0 < x1 and y0 < y1 (a non-empty rectangle), got x0={x0}, y0={y0}, x1={x1}, y1={y1}"
                ),
            ));
        }
        if !step.is_finite() || step <= 0.0 {
            return Err(Error::invalid("step", format!("must be > 0, got {step}")));
        }
        if headings == 0 {
            return Err(Error::invalid("headings", "must be at least 1"));
        }
        let count = |len: f64| ((len / step) * (1.0 + 1e-12)).floor() + 1.0;
        let (nxf, nyf) = (count(x1 - x0), count(y1 - y0));
        let total = nxf * nyf * headings as f64;
        if total > MAX_SAMPLES as f64 {
            return Err(Error::invalid(
                "step",
                format!("{total:.0} samples exceed the limit {MAX_SAMPLES}; use a larger step"),
            ));
        }
        Ok(Self {
            x0,
            y0,
            x1,
            y1,
            step,
            headings,
            nx: nxf as usize,
            ny: nyf as usize,
        })
    }

    /// Total number of base poses.
    pub fn len(&self) -> usize {
        self.nx * self.ny * self.headings
    }

    /// Always false for a validated grid.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Heading number `k`.
    pub fn heading(&self, k: usize) -> f64 {
        -std::f64::consts::PI + 2.0 * std::f64::consts::PI * k as f64 / self.headings as f64
    }

    /// The base pose of sample `index` (ordered x fastest, then y, heading slowest within
    /// a cell: `index = (iy·nx + ix)·headings + k`).
    pub fn pose(&self, index: usize) -> [f64; 3] {
        let k = index % self.headings;
        let cell = index / self.headings;
        let (ix, iy) = (cell % self.nx, cell / self.nx);
        [
            self.x0 + ix as f64 * self.step,
            self.y0 + iy as f64 * self.step,
            self.heading(k),
        ]
    }
}

/// The outcome at one base pose.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct PlacementSample {
    /// Base pose `[x, y, θ]`.
    pub base: [f64; 3],
    /// IK converged from this base pose.
    pub reachable: bool,
    /// The measure at the IK solution (`None` when unreachable or undefined there).
    pub measure: Option<f64>,
    /// Final IK residual norm.
    pub residual: f64,
    /// IK iterations used.
    pub iterations: usize,
}

/// Evaluates one base pose; shared read-only across workers, each with its own workspace.
pub trait PlacementEvaluator: Sync {
    /// Per-worker mutable state (model data, IK buffers).
    type Workspace: Send;
    /// A fresh workspace.
    fn workspace(&self) -> Self::Workspace;
    /// Evaluates the base pose `[x, y, θ]`. The result must depend on the pose alone
    /// (not on the poses evaluated before with the same workspace), so that a map does
    /// not depend on the order its poses are visited in.
    fn evaluate(&self, ws: &mut Self::Workspace, base: [f64; 3]) -> Result<PlacementSample>;
    /// Whether a larger measure is better (for picking the best placement).
    fn larger_is_better(&self) -> bool;
    /// Checks the evaluator's configuration before any workspace is built.
    fn validate(&self) -> Result<()> {
        Ok(())
    }
}

/// A base-placement map: every sample of the grid and the best reachable placement.
#[derive(Clone, Debug, serde::Serialize)]
pub struct PlacementMap {
    /// The grid.
    pub grid: PlacementGrid,
    /// All samples, in [`PlacementGrid::pose`] order.
    pub samples: Vec<PlacementSample>,
    /// The best reachable sample (largest measure, or smallest for smaller-is-better
    /// measures; among reachable samples with a measure).
    pub best: Option<PlacementSample>,
    /// Number of reachable samples.
    pub reachable: usize,
}

impl PlacementMap {
    /// Per cell (ny rows × nx columns, row-major from y0): the best measure over the
    /// headings at which the target is reachable, `None` if unreachable at all headings.
    pub fn cell_best(&self, larger_is_better: bool) -> Vec<Option<f64>> {
        let h = self.grid.headings;
        self.samples
            .chunks(h)
            .map(|cell| {
                cell.iter()
                    .filter(|s| s.reachable)
                    .filter_map(|s| s.measure)
                    .fold(None, |acc: Option<f64>, m| match acc {
                        None => Some(m),
                        Some(a) => Some(if (m > a) == larger_is_better { m } else { a }),
                    })
            })
            .collect()
    }
}

/// Evaluates every base pose of `grid` in parallel and picks the best placement.
///
/// The poses are distributed over the rayon workers, each with its own workspace. Every
/// pose is solved on its own, from the same starting points (no warm start from a
/// neighbouring pose), so the map depends neither on the number of threads nor on the
/// order the poses are visited in. (Warm-starting along grid rows carried one arm
/// posture through each row and drew horizontal stripes in the heat map: two rows that
/// started on different IK branches kept them.)
pub fn placement_map<E: PlacementEvaluator>(
    evaluator: &E,
    grid: &PlacementGrid,
) -> Result<PlacementMap> {
    evaluator.validate()?;
    let samples: Vec<PlacementSample> = evaluate_grid(
        grid,
        || evaluator.workspace(),
        |ws, _, base| evaluator.evaluate(ws, base),
    )?;
    let larger = evaluator.larger_is_better();
    let mut best: Option<PlacementSample> = None;
    let mut reachable = 0;
    for s in &samples {
        if !s.reachable {
            continue;
        }
        reachable += 1;
        if let Some(m) = s.measure {
            let better = match best.and_then(|b| b.measure) {
                None => true,
                Some(b) => (m > b) == larger && m != b,
            };
            if better {
                best = Some(*s);
            }
        }
    }
    Ok(PlacementMap {
        grid: grid.clone(),
        samples,
        best,
        reachable,
    })
}

/// Evaluates `evaluate(workspace, index, base pose)` at every pose of `grid` in
/// parallel: rayon workers, each with one workspace from `workspace` (built once per
/// worker, reused for every pose it visits); the results in grid order. The one
/// parallel loop over a grid of base poses, shared by [`placement_map`] and the grasp
/// placement of `motion::placement`; `evaluate` must depend on the pose alone for the
/// result to be independent of the thread count.
///
/// # Errors
/// The first error of `evaluate` (in grid order).
pub fn evaluate_grid<T, W>(
    grid: &PlacementGrid,
    workspace: impl Fn() -> W + Sync + Send,
    evaluate: impl Fn(&mut W, usize, [f64; 3]) -> Result<T> + Sync + Send,
) -> Result<Vec<T>>
where
    T: Send,
{
    (0..grid.len())
        .into_par_iter()
        .map_init(&workspace, |ws, i| evaluate(ws, i, grid.pose(i)))
        .collect()
}

/// Which Jacobian the placement measure is computed on.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum MeasureScope {
    /// The arm's frame Jacobian (task rows × arm joints).
    Arm,
    /// The whole-body Jacobian `J̄ = J N` of the arm on the differential drive.
    WholeBody(DiffDrive, BaseInputs),
}

/// Seed of the random restart configurations of [`ArmReachEvaluator`]: the same at every
/// base pose, so neighbouring poses that need restarts start from the same postures.
pub const RESTART_SEED: u64 = 0x9E37_79B9_7F4A_7C15;

/// Reachability by arm IK from each base pose, and a measure at the solution.
///
/// The arm model is fixed-based (its root is the arm base); it is mounted on the platform
/// at `mount` (arm base in the platform frame). From base pose `b = (x, y, θ)` the target
/// is expressed in the arm base frame as `(b · mount)⁻¹ · target` and solved with
/// [`solve_with_restarts`] from `seed`, then from `restarts` random configurations drawn
/// with [`RESTART_SEED`] (the same ones at every pose).
pub struct ArmReachEvaluator<K> {
    /// Arm kinematics (cloned per worker).
    pub arm: K,
    /// Arm base in the platform frame.
    pub mount: Isometry3<f64>,
    /// End-effector target in world.
    pub target: Isometry3<f64>,
    /// Task rows (position, full pose, …).
    pub rows: TaskRows,
    /// IK options.
    pub options: IkOptions,
    /// IK seed (arm joints).
    pub seed: DVector<f64>,
    /// Random restarts when the seed does not converge.
    pub restarts: usize,
    /// The measure.
    pub measure: Measure,
    /// Arm or whole-body Jacobian.
    pub scope: MeasureScope,
}

/// Per-worker state of [`ArmReachEvaluator`].
pub struct ArmReachWorkspace<K: FrameKinematics> {
    task: PoseTask<K>,
    ik: IkWorkspace,
    j6: DMatrix<f64>,
    /// The arm mounted on a planar base (whole-body scope only).
    mounted: Option<K>,
    /// `[x, y, θ, q_arm]` for `mounted`.
    q_full: DVector<f64>,
    jfull: DMatrix<f64>,
    jbar: DMatrix<f64>,
    pose: Isometry3<f64>,
    reach: Option<(Vector3<f64>, f64)>,
}

impl<K: FrameKinematics + Clone + Send + Sync> ArmReachEvaluator<K> {
    /// The arm mounted on the planar base ([`FrameKinematics::on_planar_base`]), for the
    /// whole-body scope.
    fn mounted_arm(&self) -> Result<K> {
        match self.arm.on_planar_base(&self.mount) {
            Some(k) => k,
            None => Err(Error::invalid(
                "measure scope",
                "the whole-body measure needs an arm kinematics that can be mounted on a \
                 planar base",
            )),
        }
    }

    /// The 6 × (nv + 3) `LocalWorldAligned` Jacobian of the frame with respect to
    /// `[ẋ, ẏ, θ̇, q̇_arm]` at base pose `base` and arm configuration `q`, from the
    /// kinematics of the arm mounted on a planar root, into `ws.jfull` (no allocation).
    fn planar_root_jacobian(
        ws: &mut ArmReachWorkspace<K>,
        base: [f64; 3],
        q: &DVector<f64>,
    ) -> Result<()> {
        let mounted = ws
            .mounted
            .as_mut()
            .expect("the workspace of a whole-body scope holds the mounted arm");
        ws.q_full[0] = base[0];
        ws.q_full[1] = base[1];
        ws.q_full[2] = base[2];
        ws.q_full.rows_mut(3, q.len()).copy_from(q);
        mounted.pose_and_jacobian(&ws.q_full, &mut ws.pose, &mut ws.jfull)
    }

    /// Measure at arm configuration `q` for base pose `base` (on the workspace buffers).
    fn measure_at(
        &self,
        ws: &mut ArmReachWorkspace<K>,
        base: [f64; 3],
        q: &DVector<f64>,
    ) -> Result<Option<f64>> {
        let rows = self.rows.indices();
        let j = match self.scope {
            MeasureScope::Arm => {
                ws.task
                    .kinematics
                    .pose_and_jacobian(q, &mut ws.pose, &mut ws.j6)?;
                ws.j6.select_rows(&rows)
            }
            MeasureScope::WholeBody(drive, inputs) => {
                Self::planar_root_jacobian(ws, base, q)?;
                compose_jacobian(&drive, inputs, base[2], &ws.jfull, &mut ws.jbar)?;
                ws.jbar.select_rows(&rows)
            }
        };
        let svd = JacobianSvd::new(&j)?;
        Ok(evaluate_svd(&self.measure, &svd).ok())
    }
}

/// The platform frame of base pose `[x, y, θ]` as a 3-D transform (z = 0).
pub fn platform_pose(base: [f64; 3]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(base[0], base[1], 0.0),
        UnitQuaternion::from_axis_angle(&Vector3::z_axis(), base[2]),
    )
}

impl<K: FrameKinematics + Clone + Send + Sync> PlacementEvaluator for ArmReachEvaluator<K> {
    type Workspace = ArmReachWorkspace<K>;

    fn workspace(&self) -> Self::Workspace {
        let task = PoseTask::new(self.arm.clone(), self.target, &self.rows)
            .expect("rows validated when the evaluator was built");
        let ik = IkWorkspace::new(&task);
        let n = self.arm.nv();
        let mounted = match self.scope {
            MeasureScope::Arm => None,
            MeasureScope::WholeBody(..) => Some(
                self.mounted_arm()
                    .expect("the mount was checked when the evaluator was validated"),
            ),
        };
        ArmReachWorkspace {
            task,
            ik,
            j6: DMatrix::zeros(6, n),
            mounted,
            q_full: DVector::zeros(self.arm.nq() + 3),
            jfull: DMatrix::zeros(6, n + 3),
            jbar: DMatrix::zeros(6, n + 2),
            pose: Isometry3::identity(),
            // Pruning by the reach sphere is valid only when all position rows are tasks.
            reach: if [0, 1, 2].iter().all(|r| self.rows.indices().contains(r)) {
                self.arm.reach_bound()
            } else {
                None
            },
        }
    }

    fn evaluate(&self, ws: &mut Self::Workspace, base: [f64; 3]) -> Result<PlacementSample> {
        let arm_base = platform_pose(base) * self.mount;
        let local = arm_base.inverse() * self.target;
        ws.task.target = local;
        // Far outside the arm's reach sphere: no IK needed.
        if let Some((center, radius)) = ws.reach {
            let gap = (local.translation.vector - center).norm() - radius;
            if gap > self.options.tolerance {
                return Ok(PlacementSample {
                    base,
                    reachable: false,
                    measure: None,
                    residual: gap,
                    iterations: 0,
                });
            }
        }
        // The seed, then the same restart configurations at every pose.
        let r = solve_with_restarts(
            &mut ws.task,
            &self.seed,
            &self.options,
            self.restarts,
            RESTART_SEED,
            &mut ws.ik,
        )?;
        let measure = if r.task_met {
            self.measure_at(ws, base, &r.q)?
        } else {
            None
        };
        Ok(PlacementSample {
            base,
            reachable: r.task_met,
            measure,
            residual: r.residual_norm,
            iterations: r.iterations,
        })
    }

    fn larger_is_better(&self) -> bool {
        self.measure.larger_is_better()
    }

    fn validate(&self) -> Result<()> {
        ArmReachEvaluator::validate(self)
    }
}

impl<K: FrameKinematics + Clone + Send + Sync> ArmReachEvaluator<K> {
    /// Validates the configuration (rows, seed length, finite target; for the
    /// whole-body scope, an arm that mounts on a planar base).
    pub fn validate(&self) -> Result<()> {
        self.rows.validate()?;
        crate::error::ensure_len("ik seed", self.arm.nq(), self.seed.len())?;
        ensure_finite("ik seed", self.seed.iter())?;
        ensure_finite(
            "target",
            self.target
                .translation
                .vector
                .iter()
                .chain(self.target.rotation.coords.iter()),
        )?;
        if let MeasureScope::WholeBody(..) = self.scope {
            let mounted = self.mounted_arm()?;
            crate::error::ensure_len("mounted arm nq", self.arm.nq() + 3, mounted.nq())?;
            crate::error::ensure_len("mounted arm nv", self.arm.nv() + 3, mounted.nv())?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ik::model::ModelFrame;
    use crate::multibody::{JointIndex, JointLimits, JointType, Model, ModelBuilder, RootJoint};
    use crate::spatial::{Inertia, SE3};
    use nalgebra::Matrix3;
    use rand::{Rng, SeedableRng};
    use std::sync::Arc;

    /// A fixed-based 5-joint arm with offsets, aligned and unaligned revolute axes and a
    /// prismatic joint, its root body carrying mass (fixed to the arm's world).
    fn arm(root: RootJoint) -> Model {
        let mut b = ModelBuilder::new("arm5");
        b.set_root(root);
        let link = Inertia::new(
            1.0,
            Vector3::new(0.1, 0.0, 0.05),
            Matrix3::identity() * 0.01,
        );
        let mut parent = JointIndex(0);
        if root == RootJoint::Planar {
            parent = b
                .add_joint(
                    parent,
                    "base",
                    JointType::Planar,
                    SE3::identity(),
                    JointLimits::unlimited(),
                )
                .unwrap();
        }
        b.append_body_inertia(parent, &link, &SE3::identity())
            .unwrap();
        let joints = [
            (JointType::RevoluteZ, [0.05, 0.0, 0.3], [0.0, 0.0, 0.4]),
            (
                JointType::revolute(Vector3::new(0.3, 1.0, -0.2)).unwrap(),
                [0.0, 0.1, 0.2],
                [0.2, 0.0, 0.0],
            ),
            (JointType::PrismaticX, [0.4, 0.0, 0.0], [0.0, 0.3, 0.0]),
            (JointType::RevoluteY, [0.3, -0.05, 0.1], [0.0, 0.0, -0.5]),
            (
                JointType::revolute(Vector3::new(1.0, -0.4, 0.6)).unwrap(),
                [0.0, 0.0, 0.15],
                [0.7, 0.2, 0.1],
            ),
        ];
        for (k, (jt, xyz, rpy)) in joints.into_iter().enumerate() {
            let limits = JointLimits::scalar(-2.5, 2.5, 1.0, 10.0);
            parent = b
                .add_joint(
                    parent,
                    &format!("j{k}"),
                    jt,
                    SE3::from_xyz_rpy(xyz, rpy),
                    limits,
                )
                .unwrap();
            b.append_body_inertia(parent, &link, &SE3::identity())
                .unwrap();
        }
        let tool = SE3::from_xyz_rpy([0.1, 0.02, 0.08], [0.3, 0.0, 0.2]);
        b.add_frame(
            "tool",
            parent,
            FrameIndex(b.nframes() - 1),
            tool,
            FrameKind::Operational,
        )
        .unwrap();
        b.build().unwrap()
    }

    use crate::multibody::{FrameIndex, FrameKind};

    /// The planar-root Jacobian built by hand from the arm's own Jacobian (the formula
    /// this module used before the mounted model existed): arm columns rotated into
    /// world, base columns of a planar root, `θ̇` column `ẑ × r` with `r` from the base
    /// origin to the frame.
    fn by_hand(
        j6: &DMatrix<f64>,
        arm_pose: &Isometry3<f64>,
        mount: &Isometry3<f64>,
        base: [f64; 3],
    ) -> DMatrix<f64> {
        let world_base = platform_pose(base) * mount;
        let rot = world_base.rotation.to_rotation_matrix();
        let n = j6.ncols();
        let p_e = world_base * nalgebra::Point3::from(arm_pose.translation.vector);
        let r = p_e.coords - Vector3::new(base[0], base[1], 0.0);
        let mut j = DMatrix::zeros(6, n + 3);
        j[(0, 0)] = 1.0;
        j[(1, 1)] = 1.0;
        j[(0, 2)] = -r.y;
        j[(1, 2)] = r.x;
        j[(5, 2)] = 1.0;
        for k in 0..n {
            let lin = rot * Vector3::new(j6[(0, k)], j6[(1, k)], j6[(2, k)]);
            let ang = rot * Vector3::new(j6[(3, k)], j6[(4, k)], j6[(5, k)]);
            for i in 0..3 {
                j[(i, k + 3)] = lin[i];
                j[(i + 3, k + 3)] = ang[i];
            }
        }
        j
    }

    fn evaluator(arm: ModelFrame, mount: Isometry3<f64>) -> ArmReachEvaluator<ModelFrame> {
        let seed = crate::multibody::neutral(arm.model());
        ArmReachEvaluator {
            arm,
            mount,
            target: Isometry3::translation(1.0, 0.5, 0.5),
            rows: TaskRows::Full,
            options: IkOptions::default(),
            seed,
            restarts: 0,
            measure: Measure::Yoshikawa,
            scope: MeasureScope::WholeBody(
                DiffDrive::new(0.1, 0.25, 0.0).unwrap(),
                BaseInputs::Platform,
            ),
        }
    }

    #[test]
    fn planar_root_jacobian_of_the_mounted_model_equals_the_hand_built_one() {
        let model = Arc::new(arm(RootJoint::Fixed));
        let tool = model.frame_id("tool").unwrap();
        let mut arm = ModelFrame::new(model.clone(), tool).unwrap();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for trial in 0..40 {
            // Mounts with yaw, a tilt and an offset; random postures and base poses.
            let mount = Isometry3::from_parts(
                Translation3::new(
                    rng.random_range(-0.3..0.3),
                    rng.random_range(-0.3..0.3),
                    rng.random_range(0.0..0.5),
                ),
                UnitQuaternion::from_euler_angles(
                    rng.random_range(-0.4..0.4),
                    rng.random_range(-0.4..0.4),
                    rng.random_range(-3.1..3.1),
                ),
            );
            let ev = evaluator(arm.clone(), mount);
            ev.validate().unwrap();
            let mut ws = ev.workspace();
            let q = crate::kinematics::random_configuration(&model, &mut rng);
            let base = [
                rng.random_range(-2.0..2.0),
                rng.random_range(-2.0..2.0),
                rng.random_range(-3.2..3.2),
            ];
            ArmReachEvaluator::planar_root_jacobian(&mut ws, base, &q).unwrap();
            let (mut pose, mut j6) = (Isometry3::identity(), DMatrix::zeros(6, model.nv));
            arm.pose_and_jacobian(&q, &mut pose, &mut j6).unwrap();
            let want = by_hand(&j6, &pose, &mount, base);
            let err = (&ws.jfull - &want).abs().max();
            assert!(err < 1e-12, "trial {trial}: max |ΔJ| = {err:e}");
            // The frame pose agrees too: the mounted model is the arm placed by b · mount.
            let world = platform_pose(base) * mount * pose;
            assert!((ws.pose.translation.vector - world.translation.vector).norm() < 1e-12);
            assert!(ws.pose.rotation.angle_to(&world.rotation) < 1e-12);
        }
    }

    #[test]
    fn the_whole_body_scope_needs_an_arm_that_mounts() {
        // An arm that already has a planar root is refused when the evaluator is
        // validated.
        let model = Arc::new(arm(RootJoint::Planar));
        let tool = model.frame_id("tool").unwrap();
        let ev = evaluator(ModelFrame::new(model, tool).unwrap(), Isometry3::identity());
        let err = ev.validate().unwrap_err().to_string();
        assert!(
            err.contains("only a fixed-based model can be mounted"),
            "{err}"
        );
    }
}

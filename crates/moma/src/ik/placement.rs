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
use super::{IkOptions, IkWorkspace, solve, solve_with_restarts};
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
    /// Evaluates the base pose `[x, y, θ]`. `warm_start` is the solution found at the
    /// neighbouring pose (previous cell of the same grid row, same heading), if any; the
    /// second return value is the solution to pass on.
    fn evaluate(
        &self,
        ws: &mut Self::Workspace,
        base: [f64; 3],
        warm_start: Option<&DVector<f64>>,
    ) -> Result<(PlacementSample, Option<DVector<f64>>)>;
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
/// Grid rows (constant y) are distributed over the rayon workers; along a row the poses
/// are visited in order and each IK is warm-started from the solution of the previous
/// cell at the same heading. Every row starts from the evaluator's own seed, so the
/// result does not depend on the number of threads.
pub fn placement_map<E: PlacementEvaluator>(
    evaluator: &E,
    grid: &PlacementGrid,
) -> Result<PlacementMap> {
    evaluator.validate()?;
    let h = grid.headings;
    let nx = grid.nx;
    let per_row: Vec<Result<Vec<PlacementSample>>> = (0..grid.ny)
        .into_par_iter()
        .map_init(
            || evaluator.workspace(),
            |ws, iy| {
                let mut warm: Vec<Option<DVector<f64>>> = vec![None; h];
                let mut row = Vec::with_capacity(nx * h);
                for ix in 0..nx {
                    let cell = iy * nx + ix;
                    for (k, w) in warm.iter_mut().enumerate() {
                        let (sample, next) =
                            evaluator.evaluate(ws, grid.pose(cell * h + k), w.as_ref())?;
                        *w = next;
                        row.push(sample);
                    }
                }
                Ok(row)
            },
        )
        .collect();
    let mut samples = Vec::with_capacity(grid.len());
    for r in per_row {
        samples.extend(r?);
    }
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

/// Which Jacobian the placement measure is computed on.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum MeasureScope {
    /// The arm's frame Jacobian (task rows × arm joints).
    Arm,
    /// The whole-body Jacobian `J̄ = J N` of the arm on the differential drive.
    WholeBody(DiffDrive, BaseInputs),
}

/// Reachability by arm IK from each base pose, and a measure at the solution.
///
/// The arm model is fixed-based (its root is the arm base); it is mounted on the platform
/// at `mount` (arm base in the platform frame). From base pose `b = (x, y, θ)` the target
/// is expressed in the arm base frame as `(b · mount)⁻¹ · target` and solved with
/// [`solve_with_restarts`] from `seed`.
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
    jfull: DMatrix<f64>,
    jbar: DMatrix<f64>,
    pose: Isometry3<f64>,
    reach: Option<(Vector3<f64>, f64)>,
}

impl<K: FrameKinematics + Clone + Send + Sync> ArmReachEvaluator<K> {
    /// Measure at arm configuration `q` for base pose `base` (on the workspace buffers).
    fn measure_at(
        &self,
        ws: &mut ArmReachWorkspace<K>,
        base: [f64; 3],
        q: &DVector<f64>,
    ) -> Result<Option<f64>> {
        ws.task
            .kinematics
            .pose_and_jacobian(q, &mut ws.pose, &mut ws.j6)?;
        let rows = self.rows.indices();
        let j = match self.scope {
            MeasureScope::Arm => ws.j6.select_rows(&rows),
            MeasureScope::WholeBody(drive, inputs) => {
                // World Jacobian of the frame w.r.t. [ẋ, ẏ, θ̇, q̇_arm]: arm columns
                // rotated into world, base columns of a planar root.
                let world_base = platform_pose(base) * self.mount;
                let rot = world_base.rotation.to_rotation_matrix();
                let n = ws.j6.ncols();
                let p_e = world_base * nalgebra::Point3::from(ws.pose.translation.vector);
                let r = p_e.coords - Vector3::new(base[0], base[1], 0.0);
                ws.jfull.fill(0.0);
                ws.jfull[(0, 0)] = 1.0;
                ws.jfull[(1, 1)] = 1.0;
                ws.jfull[(0, 2)] = -r.y;
                ws.jfull[(1, 2)] = r.x;
                ws.jfull[(5, 2)] = 1.0;
                for k in 0..n {
                    let lin = rot * Vector3::new(ws.j6[(0, k)], ws.j6[(1, k)], ws.j6[(2, k)]);
                    let ang = rot * Vector3::new(ws.j6[(3, k)], ws.j6[(4, k)], ws.j6[(5, k)]);
                    for i in 0..3 {
                        ws.jfull[(i, k + 3)] = lin[i];
                        ws.jfull[(i + 3, k + 3)] = ang[i];
                    }
                }
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
        ArmReachWorkspace {
            task,
            ik,
            j6: DMatrix::zeros(6, n),
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

    fn evaluate(
        &self,
        ws: &mut Self::Workspace,
        base: [f64; 3],
        warm_start: Option<&DVector<f64>>,
    ) -> Result<(PlacementSample, Option<DVector<f64>>)> {
        let arm_base = platform_pose(base) * self.mount;
        let local = arm_base.inverse() * self.target;
        ws.task.target = local;
        // Far outside the arm's reach sphere: no IK needed.
        if let Some((center, radius)) = ws.reach {
            let gap = (local.translation.vector - center).norm() - radius;
            if gap > self.options.tolerance {
                let sample = PlacementSample {
                    base,
                    reachable: false,
                    measure: None,
                    residual: gap,
                    iterations: 0,
                };
                return Ok((sample, None));
            }
        }
        let mut iterations = 0;
        let mut result = None;
        if let Some(w) = warm_start {
            let r = solve(&mut ws.task, w, &self.options, &mut ws.ik)?;
            iterations += r.iterations;
            if r.task_met {
                result = Some(r);
            }
        }
        let r = match result {
            Some(r) => r,
            None => {
                let seed_rng = (base[0].to_bits()
                    ^ base[1].to_bits().rotate_left(21)
                    ^ base[2].to_bits().rotate_left(42))
                .wrapping_mul(0x9E37_79B9_7F4A_7C15);
                let r = solve_with_restarts(
                    &mut ws.task,
                    &self.seed,
                    &self.options,
                    self.restarts,
                    seed_rng,
                    &mut ws.ik,
                )?;
                iterations += r.iterations;
                r
            }
        };
        let measure = if r.task_met {
            self.measure_at(ws, base, &r.q)?
        } else {
            None
        };
        let sample = PlacementSample {
            base,
            reachable: r.task_met,
            measure,
            residual: r.residual_norm,
            iterations,
        };
        Ok((sample, if r.task_met { Some(r.q) } else { None }))
    }

    fn larger_is_better(&self) -> bool {
        self.measure.larger_is_better()
    }

    fn validate(&self) -> Result<()> {
        ArmReachEvaluator::validate(self)
    }
}

impl<K: FrameKinematics + Clone + Send + Sync> ArmReachEvaluator<K> {
    /// Validates the configuration (rows, seed length, finite target).
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
        Ok(())
    }
}

//! The robot the whole-body MPC predicts: a differential-drive mobile manipulator on its
//! reduced model, restricted to the joints the MPC moves, and the evaluation of one knot
//! (torques by inverse dynamics, ZMP margin, clearance, end-effector pose, each with the
//! derivative the solver uses).
//!
//! State and input (`n_c` moved joints, in the order given):
//!
//! ```text
//! x = [x, y, θ, q_c (n_c), v, ω, q̇_c (n_c)]      nx = 5 + 2 n_c
//! u = [v̇, ω̇, q̈_c (n_c)]                         nu = 2 + n_c
//! ```
//!
//! `(v, ω)` are the platform's reduced velocities (the first two of
//! [`crate::mobile::WheeledModel`]'s), so `x` holds the reduced state. The other joints
//! (head, gripper fingers, wheel angles) are held where the caller's configuration puts
//! them: zero velocity and zero acceleration over the horizon.

use nalgebra::{DMatrix, DVector, Matrix2, Matrix3xX, Matrix6xX, Vector3, Vector6};

use crate::collision::{
    ClosestPair, GeometryData, GeometryModel, PairSelection, Scene, SceneData, compute_distances,
    compute_scene_distances_below, pair_distance_derivative, update_geometry_placements,
};
use crate::error::{Error, Result};
use crate::kinematics::{
    ReferenceFrame, compute_joint_jacobians, frame_jacobian_from_kinematics, update_frame_placement,
};
use crate::mobile::WheeledModel;
use crate::mobile::wheeled::{
    WheeledData, actuation_matrix, admissible_velocity_basis, reduced_dynamics_terms_crba,
    reduced_inverse_dynamics,
};
use crate::multibody::FrameIndex;
use crate::spatial::{Inertia, Motion, SE3};
use crate::stability::{ExternalLoads, StabilityData, StabilityModel, SupportPolygon, evaluate};

/// The robot's collision model and its scene.
#[derive(Clone, Debug)]
pub struct Clearance {
    /// Link geometry; only its enabled pairs are checked for self-distance.
    pub geometry: GeometryModel,
    /// Fixed obstacles.
    pub scene: Scene,
}

/// The robot as the MPC sees it, with its limits (all built once).
#[derive(Clone, Debug)]
pub struct MpcRobot {
    /// The constrained model.
    pub wheeled: WheeledModel,
    /// Support polygon (base frame) and gravity for the ZMP.
    pub stability: StabilityModel,
    /// Collision geometry and scene; `None`: no clearance constraint.
    pub clearance: Option<Clearance>,
    /// The end-effector frame.
    pub end_effector: FrameIndex,
    /// Index in `v`-coordinates (full model) of each moved joint.
    pub dofs: Vec<usize>,
    /// Index in the reduced velocity of each moved joint.
    pub reduced: Vec<usize>,
    /// `(N_Cᵀ S)⁻¹` (nu_full × nr): reduced generalised force → actuator torques.
    pub torque_map: DMatrix<f64>,
    /// Wheel rates `[φ̇_L, φ̇_R]` from `(v, ω)`.
    pub wheel_map: Matrix2<f64>,
    /// Torque limit of every actuator (nu_full: wheels, then the arm joints in
    /// [`WheeledModel::arm_dofs`] order).
    pub torque_limit: DVector<f64>,
    /// Wheel-rate limit (rad/s), both wheels.
    pub wheel_rate_limit: f64,
    /// Speed limit of each moved joint.
    pub speed_limit: DVector<f64>,
    /// Position limits of each moved joint (`±∞` for a continuous joint).
    pub lower: DVector<f64>,
    /// Upper position limits.
    pub upper: DVector<f64>,
}

impl MpcRobot {
    /// Builds the MPC's view of `wheeled` (tracked wheels needed for the wheel torques)
    /// moving the joints `moved` (URDF names) with the end effector `end_effector` (a
    /// frame name). Limits come from the URDF (`effort`, `velocity`, `lower`/`upper`).
    ///
    /// # Errors
    /// [`Error::Invalid`] naming the joint, frame or limit at fault.
    pub fn new(
        wheeled: WheeledModel,
        stability: StabilityModel,
        clearance: Option<Clearance>,
        moved: &[&str],
        end_effector: &str,
    ) -> Result<Self> {
        let model = &wheeled.model;
        let wheels = wheeled.wheel_dofs().ok_or_else(|| {
            Error::invalid(
                "wheel joints",
                "the MPC needs tracked wheel joints (torque limits)",
            )
        })?;
        let ee = model.frame_id(end_effector)?;
        let mut dofs = Vec::with_capacity(moved.len());
        let mut reduced = Vec::with_capacity(moved.len());
        for name in moved {
            let j = model.joint_id(name)?;
            let dof = model.idx_v[j.0];
            let pos = wheeled
                .arm_dofs()
                .iter()
                .position(|&d| d == dof)
                .ok_or_else(|| {
                    Error::invalid(
                        format!("joint '{name}'"),
                        "is not an arm joint of the platform",
                    )
                })?;
            if dofs.contains(&dof) {
                return Err(Error::invalid(format!("joint '{name}'"), "named twice"));
            }
            dofs.push(dof);
            reduced.push(2 + pos);
        }
        // (N_Cᵀ S) is constant with tracked wheels: evaluate it at q = 0.
        let (nv, nr, nu) = (wheeled.nv(), wheeled.nr(), wheeled.nu());
        let q0 = DVector::zeros(model.nq);
        let mut basis = DMatrix::zeros(nv, nr);
        let mut s = DMatrix::zeros(nv, nu);
        admissible_velocity_basis(&wheeled, &q0, &mut basis);
        actuation_matrix(&wheeled, &q0, &mut s);
        let p = basis.transpose() * s;
        let torque_map = p
            .try_inverse()
            .ok_or_else(|| Error::invalid("actuation", "N_Cᵀ S is singular"))?;
        let wheel_map = Matrix2::new(
            basis[(wheels[0], 0)],
            basis[(wheels[0], 1)],
            basis[(wheels[1], 0)],
            basis[(wheels[1], 1)],
        );
        let mut torque_limit = DVector::zeros(nu);
        torque_limit[0] = model.effort_limit[wheels[0]];
        torque_limit[1] = model.effort_limit[wheels[1]];
        for (k, &d) in wheeled.arm_dofs().iter().enumerate() {
            torque_limit[2 + k] = model.effort_limit[d];
        }
        let wheel_rate_limit = model.velocity_limit[wheels[0]].min(model.velocity_limit[wheels[1]]);
        for (i, &lim) in torque_limit.iter().enumerate() {
            if lim.is_nan() || lim <= 0.0 {
                return Err(Error::invalid(
                    format!("effort limit of input {i}"),
                    format!("must be positive, got {lim}"),
                ));
            }
        }
        let n = dofs.len();
        let mut speed_limit = DVector::zeros(n);
        let mut lower = DVector::zeros(n);
        let mut upper = DVector::zeros(n);
        for (i, &d) in dofs.iter().enumerate() {
            speed_limit[i] = model.velocity_limit[d];
            lower[i] = model.lower_position_limit[d];
            upper[i] = model.upper_position_limit[d];
            if speed_limit[i].is_nan() || speed_limit[i] <= 0.0 {
                return Err(Error::invalid(
                    format!("velocity limit of joint '{}'", moved[i]),
                    "must be positive",
                ));
            }
        }
        Ok(Self {
            wheeled,
            stability,
            clearance,
            end_effector: ee,
            dofs,
            reduced,
            torque_map,
            wheel_map,
            torque_limit,
            wheel_rate_limit,
            speed_limit,
            lower,
            upper,
        })
    }

    /// Number of moved joints n_c.
    #[must_use]
    pub fn n_moved(&self) -> usize {
        self.dofs.len()
    }

    /// State dimension `5 + 2 n_c`.
    #[must_use]
    pub fn nx(&self) -> usize {
        5 + 2 * self.dofs.len()
    }

    /// Input dimension `2 + n_c`.
    #[must_use]
    pub fn nu(&self) -> usize {
        2 + self.dofs.len()
    }

    /// The MPC state of the full reduced state `(q, v_r)` of the plant.
    pub fn state_from_plant(&self, q: &[f64], v_r: &[f64], x: &mut DVector<f64>) {
        let n = self.n_moved();
        x[0] = q[0];
        x[1] = q[1];
        x[2] = q[2];
        x[3 + n] = v_r[0];
        x[4 + n] = v_r[1];
        for i in 0..n {
            x[3 + i] = q[self.dofs[i]];
            x[5 + n + i] = v_r[self.reduced[i]];
        }
    }

    /// Writes the full `q`, `v_r`, `v̇_r` of `(x, u)` over `hold` (the held joints'
    /// positions).
    fn expand(
        &self,
        hold: &DVector<f64>,
        x: &DVector<f64>,
        u: Option<&DVector<f64>>,
        q: &mut DVector<f64>,
        v_r: &mut DVector<f64>,
        a_r: &mut DVector<f64>,
    ) {
        let n = self.n_moved();
        q.copy_from(hold);
        q[0] = x[0];
        q[1] = x[1];
        q[2] = x[2];
        v_r.fill(0.0);
        a_r.fill(0.0);
        v_r[0] = x[3 + n];
        v_r[1] = x[4 + n];
        if let Some(u) = u {
            a_r[0] = u[0];
            a_r[1] = u[1];
        }
        for i in 0..n {
            q[self.dofs[i]] = x[3 + i];
            v_r[self.reduced[i]] = x[5 + n + i];
            if let Some(u) = u {
                a_r[self.reduced[i]] = u[2 + i];
            }
        }
    }
}

/// The values (and, when asked, derivatives) of one knot.
#[derive(Clone, Debug)]
pub struct KnotValues {
    /// Actuator torques `(N_Cᵀ S)⁻¹ (Mr v̇_r + cr + Gr)` (nu_full).
    pub torque: DVector<f64>,
    /// ∂torque/∂u with Mr frozen (nu_full × nu).
    pub torque_du: DMatrix<f64>,
    /// ZMP margin (m, positive inside the support); `None` at lift-off.
    pub zmp_margin: Option<f64>,
    /// Its gradient in x (point-mass linearisation, see `docs/mpc.md`).
    pub zmp_dx: DVector<f64>,
    /// Its gradient in u (exact: the momentum rate is affine in q̈, see
    /// [`evaluate_knot`]).
    pub zmp_du: DVector<f64>,
    /// The gravito-inertial wrench `[f; M]` of the whole robot, its moment `M` about the
    /// ground point below the world origin `(0, 0, z_ground)`: the ZMP is
    /// `(−M_y / f_z, M_x / f_z)` where `f_z < 0`. Set with the derivatives.
    pub ground_wrench: Vector6<f64>,
    /// Its derivative in u (6 × nu), exact: the wrench is affine in u at a fixed state
    /// (the momentum rate is affine in q̈). Set with the derivatives.
    pub ground_wrench_du: DMatrix<f64>,
    /// The signed distances of the nearest pairs (self pairs and scene link–object
    /// pairs), ascending, one per clearance row (the workspace's `pair_rows` of them):
    /// `distances[0]` is the smallest distance. A slot no queried pair fills holds the
    /// knot's cut-off ([`KnotWorkspace::distance_cutoff`]), `+∞` without geometry or
    /// cut-off.
    pub distances: Vec<f64>,
    /// Each slot's pair's distance derivative in x (zero for an empty slot).
    pub distances_dx: Vec<DVector<f64>>,
    /// Clearance of the base footprint on the map (m), `+∞` without a map
    /// (`super::MapClearance::at`, set by the problem, not by [`evaluate_knot`]).
    pub map_clearance: f64,
    /// Its gradient in the base pose `(x, y, θ)`, the first three states.
    pub map_clearance_dx: [f64; 3],
    /// End-effector placement in the world.
    pub end_effector: SE3,
    /// End-effector Jacobian `[ṗ; ω]` (world axes) in x (6 × nx, velocity columns zero).
    pub end_effector_dx: DMatrix<f64>,
}

/// Workspace of [`evaluate_knot`] (allocated once).
#[derive(Clone, Debug)]
pub struct KnotWorkspace {
    wd: WheeledData,
    sd: StabilityData,
    /// The robot's geometry with only the self pairs of the current knot enabled, its
    /// workspace and the scene's.
    geometry: Option<(GeometryModel, GeometryData, SceneData)>,
    /// The self pairs selected for the current solve ([`select_pairs`]).
    selected: Vec<bool>,
    /// Each self pair's last query, which bounds its distance now ([`cull_pairs`]).
    history: PairHistory,
    /// The geometry objects' placements in the base frame (the frame of the model's
    /// first joint, which the base pose `(x, y, θ)` moves) at the knot being evaluated.
    in_base: Vec<SE3>,
    /// Self pairs the last [`evaluate_knot`] queried (those [`cull_pairs`] left).
    pub queried_pairs: usize,
    /// Distance at or beyond which a pair is not queried ([`evaluate_knot`]); `+∞`:
    /// every selected pair; `−∞`: none (the clearance is not needed).
    pub distance_cutoff: f64,
    /// The nearest pairs of the knot being evaluated, ascending (at most
    /// `values.distances.len()`, its capacity).
    nearest: Vec<(f64, ClosestPair)>,
    q: DVector<f64>,
    v_r: DVector<f64>,
    a_r: DVector<f64>,
    zero_u: Vec<f64>,
    reduced_force: DVector<f64>,
    qddot: DVector<f64>,
    jac: Matrix6xX<f64>,
    grad_nv: DVector<f64>,
    sub_mass: Vec<f64>,
    sub_moment: Vec<Vector3<f64>>,
    sub_inertia: Vec<Inertia>,
    jcom: Matrix3xX<f64>,
    /// The values of the last knot evaluated.
    pub values: KnotValues,
}

impl KnotWorkspace {
    /// The support polygon (world) of the last knot evaluated, placed at its base pose.
    #[must_use]
    pub fn support(&self) -> &SupportPolygon {
        &self.sd.support
    }

    /// The robot's total mass (kg), from the last knot evaluated.
    #[must_use]
    pub fn mass(&self) -> f64 {
        self.sd.wrench.mass
    }

    /// Buffers for `robot`, keeping the distances of the `pair_rows` nearest pairs
    /// (at least one).
    #[must_use]
    pub fn new(robot: &MpcRobot, pair_rows: usize) -> Self {
        let pair_rows = pair_rows.max(1);
        let wm = &robot.wheeled;
        let (nv, nr, nu_full) = (wm.nv(), wm.nr(), wm.nu());
        let (nx, nu) = (robot.nx(), robot.nu());
        let nj = wm.model.njoints;
        Self {
            wd: WheeledData::new(wm),
            sd: StabilityData::new(&robot.stability),
            geometry: robot.clearance.as_ref().map(|c| {
                (
                    c.geometry.clone(),
                    GeometryData::new(&c.geometry),
                    SceneData::new(&c.geometry, &c.scene),
                )
            }),
            selected: robot
                .clearance
                .as_ref()
                .map_or_else(Vec::new, |c| c.geometry.enabled.clone()),
            history: robot
                .clearance
                .as_ref()
                .map_or_else(PairHistory::default, |c| PairHistory::new(&c.geometry)),
            in_base: robot.clearance.as_ref().map_or_else(Vec::new, |c| {
                vec![SE3::identity(); c.geometry.objects.len()]
            }),
            queried_pairs: 0,
            distance_cutoff: f64::INFINITY,
            nearest: Vec::with_capacity(pair_rows),
            q: DVector::zeros(wm.model.nq),
            v_r: DVector::zeros(nr),
            a_r: DVector::zeros(nr),
            zero_u: vec![0.0; nu_full],
            reduced_force: DVector::zeros(nr),
            qddot: DVector::zeros(nv),
            jac: Matrix6xX::zeros(nv),
            grad_nv: DVector::zeros(nv),
            sub_mass: vec![0.0; nj],
            sub_moment: vec![Vector3::zeros(); nj],
            sub_inertia: vec![Inertia::zero(); nj],
            jcom: Matrix3xX::zeros(nv),
            values: KnotValues {
                torque: DVector::zeros(nu_full),
                torque_du: DMatrix::zeros(nu_full, nu),
                zmp_margin: None,
                zmp_dx: DVector::zeros(nx),
                zmp_du: DVector::zeros(nu),
                ground_wrench: Vector6::zeros(),
                ground_wrench_du: DMatrix::zeros(6, nu),
                distances: vec![f64::INFINITY; pair_rows],
                distances_dx: vec![DVector::zeros(nx); pair_rows],
                map_clearance: f64::INFINITY,
                map_clearance_dx: [0.0; 3],
                end_effector: SE3::identity(),
                end_effector_dx: DMatrix::zeros(6, nx),
            },
        }
    }
}

/// Enables, for the coming solve, only the robot's self pairs closer than `activation`
/// (m) at the configuration `q` (all of them with a non-finite `activation`): pairs
/// farther apart cannot come within the clearance before the next solve re-selects
/// them, and each pair skipped saves one distance query per knot evaluation.
pub fn select_pairs(robot: &MpcRobot, ws: &mut KnotWorkspace, q: &DVector<f64>, activation: f64) {
    let (Some(c), Some((active, gd, _))) = (&robot.clearance, &mut ws.geometry) else {
        return;
    };
    let model = &robot.wheeled.model;
    crate::kinematics::forward_kinematics(model, &mut ws.wd.data, q);
    update_geometry_placements(&c.geometry, &ws.wd.data, gd);
    placements_in_base(model, &ws.wd.data, gd, &mut ws.in_base);
    // Query only the pairs that may be closer than `activation`: those whose last query
    // less the motion since cannot be are not selected, and need no query.
    for p in 0..c.geometry.pairs.len() {
        active.enabled[p] = c.geometry.enabled[p]
            && ws.history.lower_bound(&c.geometry, &ws.in_base, p) < activation;
    }
    compute_distances(active, gd, PairSelection::Enabled);
    ws.history.record(active, gd, &ws.in_base);
    for (p, on) in ws.selected.iter_mut().enumerate() {
        *on = active.enabled[p]
            && (gd.results[p].distance < activation || gd.results[p].distance.is_nan());
    }
}

/// The placements of `gd`'s objects (in the world) in the frame of the model's first
/// joint, the base's, into `in_base`. A self pair's distance does not change when the
/// whole robot moves rigidly, so how far its objects moved in this frame bounds how
/// much its distance changed while the base drives and turns.
fn placements_in_base(
    model: &crate::multibody::Model,
    data: &crate::multibody::Data,
    gd: &GeometryData,
    in_base: &mut [SE3],
) {
    let base = &data.world_from_joint[model.joint_of_dof[0].0];
    for (rel, world) in in_base.iter_mut().zip(&gd.placements) {
        *rel = base.inverse_compose(world);
    }
}

/// The last distance query of each self pair: its distance and where its objects were
/// then in the base frame ([`placements_in_base`]). A pair whose objects have since
/// moved in that frame by at most `δ_a` and `δ_b` is at least `d − δ_a − δ_b` apart now
/// (each point of a shape moved by at most its shape's `δ`, and the distance is the
/// same in any frame).
#[derive(Clone, Debug, Default)]
struct PairHistory {
    /// Distance of the last query per pair (`NaN`: none yet).
    distance: Vec<f64>,
    /// Placements of the pair's objects then (base frame), link a's then link b's,
    /// from `offsets[p]`.
    placements: Vec<SE3>,
    offsets: Vec<usize>,
}

impl PairHistory {
    fn new(gm: &GeometryModel) -> Self {
        let mut offsets = vec![0];
        for &[a, b] in &gm.pairs {
            let n = gm.links[a].count + gm.links[b].count;
            offsets.push(offsets[offsets.len() - 1] + n);
        }
        Self {
            distance: vec![f64::NAN; gm.pairs.len()],
            placements: vec![SE3::identity(); offsets[offsets.len() - 1]],
            offsets,
        }
    }

    /// Records the pairs `gm` enables (those the last `compute_distances` queried), with
    /// the objects' placements in the base frame `in_base`.
    fn record(&mut self, gm: &GeometryModel, gd: &GeometryData, in_base: &[SE3]) {
        for p in 0..gm.pairs.len() {
            if !gm.enabled[p] {
                continue;
            }
            self.distance[p] = gd.results[p].distance;
            let mut slot = self.offsets[p];
            for link in gm.pairs[p] {
                let l = &gm.links[link];
                for i in l.first..l.first + l.count {
                    self.placements[slot] = in_base[i];
                    slot += 1;
                }
            }
        }
    }

    /// A lower bound of pair `p`'s distance at the base-frame placements `in_base`
    /// (`−∞` if never queried): the last distance less how far each link's objects may
    /// have moved, a point of an object moving by at most `|P c − P' c| + ‖R − R'‖_F r`
    /// for its bounding ball `(c, r)` between placements `P'` and `P`. A micrometre is
    /// taken off for the rounding of the query and of this bound.
    fn lower_bound(&self, gm: &GeometryModel, in_base: &[SE3], p: usize) -> f64 {
        let then = self.distance[p];
        if !then.is_finite() {
            return f64::NEG_INFINITY;
        }
        let mut slot = self.offsets[p];
        let mut moved = 0.0;
        for link in gm.pairs[p] {
            let l = &gm.links[link];
            let mut most: f64 = 0.0;
            for i in l.first..l.first + l.count {
                let (o, was, now) = (&gm.objects[i], &self.placements[slot], &in_base[i]);
                let shift = (now.act_point(&o.bounding_centre) - was.act_point(&o.bounding_centre))
                    .norm()
                    + (now.rotation - was.rotation).norm() * o.bounding_radius;
                most = most.max(shift);
                slot += 1;
            }
            moved += most;
        }
        then - moved - 1e-6
    }
}

/// Enables in `active` the pairs of `selected` that may be closer than `cutoff` at the
/// placements in `gd`: a pair is skipped when a lower bound of its distance is at least
/// `cutoff`, the larger of the smallest gap between the bounding balls of its two links'
/// shapes and its last query less the motion since ([`PairHistory::lower_bound`]).
fn cull_pairs(
    active: &mut GeometryModel,
    gd: &GeometryData,
    in_base: &[SE3],
    selected: &[bool],
    history: &PairHistory,
    cutoff: f64,
) {
    for p in 0..active.pairs.len() {
        active.enabled[p] = selected[p] && {
            let [la, lb] = active.pairs[p];
            let (a, b) = (&active.links[la], &active.links[lb]);
            let mut gap = f64::INFINITY;
            for i in a.first..a.first + a.count {
                let (oi, pi) = (&active.objects[i], &gd.placements[i]);
                let ci = pi.act_point(&oi.bounding_centre);
                for j in b.first..b.first + b.count {
                    let (oj, pj) = (&active.objects[j], &gd.placements[j]);
                    let cj = pj.act_point(&oj.bounding_centre);
                    gap = gap.min((ci - cj).norm() - oi.bounding_radius - oj.bounding_radius);
                }
            }
            gap < cutoff && history.lower_bound(active, in_base, p) < cutoff
        };
    }
}

/// Inserts `(distance, pair)` into `nearest`, kept ascending and at most `slots` long
/// (no allocation with a capacity of `slots`); a pair ties after those already in, so
/// the first slot holds the pair `closest_pair` would name.
fn keep_nearest(
    nearest: &mut Vec<(f64, ClosestPair)>,
    slots: usize,
    distance: f64,
    pair: ClosestPair,
) {
    let at = nearest
        .iter()
        .position(|&(d, _)| distance < d)
        .unwrap_or(nearest.len());
    if at < slots {
        if nearest.len() == slots {
            nearest.pop();
        }
        nearest.insert(at, (distance, pair));
    }
}

/// Column of x that a `v`-coordinate of the full model maps to (`None`: held).
fn x_column(robot: &MpcRobot, dof: usize) -> Option<usize> {
    if dof < 3 {
        Some(dof)
    } else {
        robot.dofs.iter().position(|&d| d == dof).map(|i| 3 + i)
    }
}

/// Evaluates the knot `(x, u)` (`u = None`: a terminal knot, zero acceleration) over the
/// held configuration `hold` into `ws.values`; with `derivatives`, also every gradient.
pub fn evaluate_knot(
    robot: &MpcRobot,
    ws: &mut KnotWorkspace,
    hold: &DVector<f64>,
    x: &DVector<f64>,
    u: Option<&DVector<f64>>,
    derivatives: bool,
) {
    let wm = &robot.wheeled;
    let model = &wm.model;
    robot.expand(hold, x, u, &mut ws.q, &mut ws.v_r, &mut ws.a_r);
    let vals = &mut ws.values;
    if derivatives {
        // Mr and cr + Gr at (q, v_r) (no forward dynamics: the torques are inverse
        // dynamics), and ∂τ/∂u = (N_Cᵀ S)⁻¹ Mr[:, moved columns].
        reduced_dynamics_terms_crba(wm, &mut ws.wd, &ws.q, &ws.v_r, &ws.zero_u);
        let red = &ws.wd.reduced;
        red.mass_matrix.mul_to(&ws.a_r, &mut ws.reduced_force);
        ws.reduced_force += &red.velocity_terms;
        let nc = robot.n_moved();
        for c in 0..2 + nc {
            let rc = if c < 2 { c } else { robot.reduced[c - 2] };
            for i in 0..vals.torque.len() {
                let mut s = 0.0;
                for j in 0..red.mass_matrix.nrows() {
                    s += robot.torque_map[(i, j)] * red.mass_matrix[(j, rc)];
                }
                vals.torque_du[(i, c)] = s;
            }
        }
    } else {
        // The same sum by one RNEA, without Mr.
        reduced_inverse_dynamics(
            wm,
            &mut ws.wd,
            &ws.q,
            &ws.v_r,
            &ws.a_r,
            &mut ws.reduced_force,
        );
    }
    robot.torque_map.mul_to(&ws.reduced_force, &mut vals.torque);
    // q̈ = N_C v̇_r + Ṅ_C v_r; the ZMP of (q, q̇, q̈).
    ws.wd.basis.mul_to(&ws.a_r, &mut ws.qddot);
    ws.qddot.gemv(1.0, &ws.wd.basis_dot, &ws.v_r, 1.0);
    let report = evaluate(
        model,
        &mut ws.wd.data,
        &robot.stability,
        &mut ws.sd,
        &ws.q,
        &ws.wd.qdot,
        &ws.qddot,
        &ExternalLoads::NONE,
    );
    vals.zmp_margin = report.zmp_margin;
    let critical = report.zmp_critical_edge;
    // The joint placements at q are in place (the ZMP's kinematics); the Jacobians only
    // for the derivatives.
    if derivatives {
        compute_joint_jacobians(model, &mut ws.wd.data, &ws.q);
    }
    let data = &mut ws.wd.data;
    // End effector.
    vals.end_effector = update_frame_placement(model, data, robot.end_effector);
    if derivatives {
        frame_jacobian_from_kinematics(
            model,
            data,
            robot.end_effector,
            ReferenceFrame::LocalWorldAligned,
            &mut ws.jac,
        );
        vals.end_effector_dx.fill(0.0);
        for d in 0..model.nv {
            if let Some(c) = x_column(robot, d) {
                for r in 0..6 {
                    vals.end_effector_dx[(r, c)] = ws.jac[(r, d)];
                }
            }
        }
    }
    // Clearance: the nearest pairs, each with its own distance and gradient.
    // Pairs at least `cutoff` apart (by their bounding balls) are not queried; a slot no
    // queried pair fills holds `cutoff` with a zero gradient.
    vals.distances.fill(f64::INFINITY);
    for g in &mut vals.distances_dx {
        g.fill(0.0);
    }
    ws.queried_pairs = 0;
    let cutoff = ws.distance_cutoff;
    if let (Some(c), Some((active, gd, scd)), false) = (
        &robot.clearance,
        &mut ws.geometry,
        cutoff == f64::NEG_INFINITY,
    ) {
        update_geometry_placements(active, data, gd);
        placements_in_base(model, data, gd, &mut ws.in_base);
        cull_pairs(active, gd, &ws.in_base, &ws.selected, &ws.history, cutoff);
        ws.queried_pairs = active.enabled.iter().filter(|&&on| on).count();
        compute_distances(active, gd, PairSelection::Enabled);
        ws.history.record(active, gd, &ws.in_base);
        compute_scene_distances_below(active, gd, &c.scene, scd, cutoff);
        let slots = vals.distances.len();
        ws.nearest.clear();
        for p in 0..active.pairs.len() {
            if active.enabled[p] {
                keep_nearest(
                    &mut ws.nearest,
                    slots,
                    gd.results[p].distance,
                    ClosestPair::SelfPair(p),
                );
            }
        }
        let objects = c.scene.objects.len();
        for (k, r) in scd.results.iter().enumerate() {
            if r.distance < cutoff {
                let pair = ClosestPair::scene_result(k, objects);
                keep_nearest(&mut ws.nearest, slots, r.distance, pair);
            }
        }
        vals.distances.fill(cutoff);
        for (slot, &(d, pair)) in ws.nearest.iter().enumerate() {
            vals.distances[slot] = d;
            if !derivatives {
                continue;
            }
            pair_distance_derivative(
                model,
                data,
                active,
                gd,
                &c.scene,
                scd,
                pair,
                &mut ws.grad_nv,
            );
            let dx = &mut vals.distances_dx[slot];
            for k in 0..model.nv {
                if let Some(col) = x_column(robot, k) {
                    dx[col] = ws.grad_nv[k];
                }
            }
        }
    }
    // The ground wrench and its exact derivative in u: the momentum rate ḣ (world
    // origin) is affine in q̈, with ∂ḣ/∂q̈_d = I_sub(d) J_d (the world inertia of the
    // subtree dof d moves times its joint Jacobian column), and q̈ = N_C v̇_r + Ṅ_C v_r.
    // The gravito-inertial force is f = m g − ḣ_lin and its moment about
    // p0 = (0, 0, z_ground) is M = m c × g − ḣ_ang + p0 × ḣ_lin.
    vals.zmp_dx.fill(0.0);
    vals.zmp_du.fill(0.0);
    if !derivatives {
        return;
    }
    let p0 = Vector3::new(0.0, 0.0, ws.sd.support.ground_z());
    let w = &ws.sd.wrench;
    let (f, m) = (w.force, w.moment_about(&p0));
    vals.ground_wrench = Vector6::new(f.x, f.y, f.z, m.x, m.y, m.z);
    let nj = model.njoints;
    for j in 0..nj {
        ws.sub_inertia[j] = if j == 0 {
            Inertia::zero()
        } else {
            model.inertias[j].transformed(&data.world_from_joint[j])
        };
    }
    for j in (1..nj).rev() {
        let sub = ws.sub_inertia[j];
        ws.sub_inertia[model.parents[j].0] += sub;
    }
    let nc = robot.n_moved();
    vals.ground_wrench_du.fill(0.0);
    for d in 0..model.nv {
        let col = data.joint_jacobians.column(d);
        let jd = Motion::new(
            Vector3::new(col[0], col[1], col[2]),
            Vector3::new(col[3], col[4], col[5]),
        );
        let dh = ws.sub_inertia[model.joint_of_dof[d].0].mul_motion(&jd);
        let df = -dh.linear;
        let dm = -dh.angular + p0.cross(&dh.linear);
        let dw = [df.x, df.y, df.z, dm.x, dm.y, dm.z];
        for c in 0..2 + nc {
            let rc = if c < 2 { c } else { robot.reduced[c - 2] };
            let b = ws.wd.basis[(d, rc)];
            if b != 0.0 {
                for (r, &v) in dw.iter().enumerate() {
                    vals.ground_wrench_du[(r, c)] += v * b;
                }
            }
        }
    }
    // ZMP gradient on the critical edge. In x: the point-mass ZMP
    // p = c_xy − h c̈_xy / (g + c̈_z), h = c_z − z_ground, with c̈ = J_c q̈ (the J̇_c q̇ term
    // and ∂c̈/∂q left out). In u: exact, the ZMP (−M_y / f_z, M_x / f_z) of the wrench's
    // derivative.
    let (Some(_), Some(e)) = (vals.zmp_margin, critical) else {
        return;
    };
    com_jacobian(
        model,
        data,
        &mut ws.sub_mass,
        &mut ws.sub_moment,
        &mut ws.jcom,
    );
    let com = ws.sd.wrench.com;
    let g = -robot.stability.gravity.z;
    let cdd = &ws.jcom * &ws.qddot;
    let h = com.z - ws.sd.support.ground_z();
    let den = g + cdd.z;
    let edge = ws.sd.support.edge(e);
    let n = edge.inward;
    let zmp = report_zmp(&com, &cdd, h, den);
    // ∂s/∂p = n (xy); base translation moves the edge: −n; yaw turns it about the base.
    let b = Vector3::new(ws.sd.base_pose[0], ws.sd.base_pose[1], 0.0);
    let rel = zmp - b;
    let dyaw = Vector3::z().cross(&n).dot(&rel);
    for d in 0..model.nv {
        let Some(col) = x_column(robot, d) else {
            continue;
        };
        let jc = ws.jcom.column(d);
        let dpx = jc[0] - cdd.x / den * jc[2];
        let dpy = jc[1] - cdd.y / den * jc[2];
        vals.zmp_dx[col] += n.x * dpx + n.y * dpy;
    }
    vals.zmp_dx[0] -= n.x;
    vals.zmp_dx[1] -= n.y;
    vals.zmp_dx[2] += dyaw;
    for c in 0..2 + nc {
        let dw = vals.ground_wrench_du.column(c);
        let dpx = (-dw[4] * f.z + m.y * dw[2]) / (f.z * f.z);
        let dpy = (dw[3] * f.z - m.x * dw[2]) / (f.z * f.z);
        vals.zmp_du[c] = n.x * dpx + n.y * dpy;
    }
}

/// The point-mass ZMP on the ground.
fn report_zmp(com: &Vector3<f64>, cdd: &Vector3<f64>, h: f64, den: f64) -> Vector3<f64> {
    Vector3::new(com.x - h * cdd.x / den, com.y - h * cdd.y / den, 0.0)
}

/// The centre-of-mass Jacobian (3 × nv) from the world joint Jacobians in `data`
/// (`compute_joint_jacobians` first): column k is `(m_sub lin_k + ang_k × s_sub) / m`,
/// with `m_sub`, `s_sub` the mass and first moment of the subtree the dof moves.
fn com_jacobian(
    model: &crate::multibody::Model,
    data: &crate::multibody::Data,
    sub_mass: &mut [f64],
    sub_moment: &mut [Vector3<f64>],
    out: &mut Matrix3xX<f64>,
) {
    let nj = model.njoints;
    for j in 0..nj {
        let inertia = &model.inertias[j];
        sub_mass[j] = inertia.mass();
        sub_moment[j] = if j == 0 {
            Vector3::zeros()
        } else {
            let w = &data.world_from_joint[j];
            inertia.mass() * w.act_point(&inertia.com())
        };
    }
    for j in (1..nj).rev() {
        let p = model.parents[j].0;
        let (m, s) = (sub_mass[j], sub_moment[j]);
        sub_mass[p] += m;
        sub_moment[p] += s;
    }
    let total: f64 = sub_mass[0];
    for k in 0..model.nv {
        let j = model.joint_of_dof[k].0;
        let col = data.joint_jacobians.column(k);
        let lin = Vector3::new(col[0], col[1], col[2]);
        let ang = Vector3::new(col[3], col[4], col[5]);
        let v = (sub_mass[j] * lin + ang.cross(&sub_moment[j])) / total;
        out.set_column(k, &v);
    }
}

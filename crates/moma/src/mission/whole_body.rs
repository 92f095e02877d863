//! Law `mpc` of a mission (`control.law = "mpc"`): the whole-body MPC, run as
//! [`MpcLaw`] (the law of `moma simulate`'s `mpc`), tracks the mission's timed base
//! reference and the end-effector target in one problem, so the arm reaches while the
//! base still drives.
//!
//! The knot reference at time `t`: the base frame's pose on the mission's reference
//! ([`base_reference`] of the axle midpoint's sample), and the end-effector target
//! (orientation: the world axes, weighed by `control.mpc.weights.ee_orientation`) at the
//! knots whose base pose lies within `control.reach_radius` of the target, horizontally.
//! Far from the target the MPC tracks the path alone; the horizon sees the target coming
//! and the arm moves out before the base gets there. A re-plan gives a new reference,
//! which the MPC tracks from its next solve on ([`WholeBodyLaw::track`]), warm-started as
//! every solve is.
//!
//! With `control.mpc.map_clearance`, the MPC keeps the disk of the footprint radius about
//! the base frame origin that far from the map's obstacles: its map is the planner's
//! distance transform ([`distance_field`]), handed over at the first solve and again
//! whenever an obstacle that appeared changed it (with or without a re-plan).

use nalgebra::{Matrix3, Vector3};

use super::plan::Planner;
use super::reference::{Reference, base_reference};
use crate::control::mpc::{DistanceField, KnotReference, MapClearance, WholeBodyMpc};
use crate::error::Result;
use crate::planning::{MapKind, OccupancyGrid};
use crate::sim::closed_loop::FeedbackLaw;
use crate::sim::mpc_law::MpcLaw;
use crate::sim::mpc_run::MpcRunSummary;

/// The knot reference at a time.
type KnotSource = Box<dyn FnMut(f64) -> KnotReference>;

/// What one control step of the law did.
#[derive(Clone, Copy, Debug)]
pub(super) struct Tick {
    /// The torques applied over this step were clipped at a limit.
    pub torque_clipped: bool,
    /// The end effector's error (m) when it first came within the tolerance, at this step.
    pub touched: Option<f64>,
}

/// The MPC, its solve period and the target it reaches for.
pub(super) struct WholeBodyLaw {
    law: MpcLaw<KnotSource>,
    /// Control steps per solve.
    every: usize,
    /// Base frame origin ahead of the axle midpoint (m).
    d: f64,
    target: Option<Vector3<f64>>,
    reach_radius: f64,
    tolerance: f64,
    /// The number of plans when the tracked reference was set (`None`: none yet).
    plans: Option<usize>,
    /// With the map-clearance constraint: the footprint radius (m), and the planner's
    /// `map_changes` when the MPC's map was last set (`None`: not yet).
    map: Option<(f64, Option<usize>)>,
    /// Mission time the end effector first came within the tolerance (s).
    pub touched_at: Option<f64>,
}

impl WholeBodyLaw {
    /// The law of `mpc`, solving every `every` control steps, for a robot whose base frame
    /// lies `d` ahead of the axle, reaching for `target` (if any) within `tolerance` (m)
    /// from the knots within `reach_radius` (m) of it; its footprint the disk of
    /// `footprint_radius` (m) about the base frame origin.
    pub(super) fn new(
        mpc: WholeBodyMpc,
        every: usize,
        d: f64,
        target: Option<[f64; 3]>,
        reach_radius: f64,
        tolerance: f64,
        footprint_radius: f64,
    ) -> Self {
        let idle: KnotSource = Box::new(|_| KnotReference::default());
        let map = mpc
            .problem
            .settings
            .constraints
            .map_clearance
            .map(|_| (footprint_radius, None));
        Self {
            map,
            law: MpcLaw::new(mpc, idle),
            every,
            d,
            target: target.map(Vector3::from),
            reach_radius,
            tolerance,
            plans: None,
            touched_at: None,
        }
    }

    /// Tracks `reference`, the mission's plan number `plans`, unless it already does;
    /// with the map-clearance constraint, keeps the MPC's map that of `planner` (on
    /// `grid`), refreshed when an obstacle has changed it.
    pub(super) fn track(
        &mut self,
        reference: &Reference,
        plans: usize,
        planner: &Planner,
        grid: &OccupancyGrid,
    ) {
        if let Some((radius, seen)) = &mut self.map
            && *seen != Some(planner.map_changes)
        {
            *seen = Some(planner.map_changes);
            self.law.set_map(MapClearance {
                field: distance_field(planner, grid),
                footprint_radius: *radius,
            });
        }
        if self.plans == Some(plans) {
            return;
        }
        self.plans = Some(plans);
        let (r, d, target, radius) = (reference.clone(), self.d, self.target, self.reach_radius);
        self.law.set_reference(Box::new(move |t| {
            let s = base_reference(r.at(t), d);
            let near = |p: &Vector3<f64>| (s.x - p.x).hypot(s.y - p.y) <= radius;
            KnotReference {
                base: [s.x, s.y, s.theta],
                end_effector: target.filter(near).map(|p| (p, Matrix3::identity())),
            }
        }));
    }

    /// Control step `k` at time `t` from the measured `(q, v)`: every `every` steps a
    /// solve; at every step the torques that realise the last solve's first planned input
    /// at `(q, v)` (clipped to the limits) into `u`. Holding the planned acceleration
    /// rather than the solve's torques keeps the plant on the plan between solves: on
    /// Fetch a held torque let the light roll joints drift within the period and the
    /// warehouse mission diverge.
    ///
    /// # Errors
    /// What the MPC reports.
    pub(super) fn tick(
        &mut self,
        k: usize,
        t: f64,
        q: &[f64],
        v: &[f64],
        u: &mut [f64],
    ) -> Result<Tick> {
        if !k.is_multiple_of(self.every) {
            return Ok(Tick {
                torque_clipped: self.law.hold_input(q, v, u)?,
                touched: None,
            });
        }
        let torque_clipped = self.law.control(t, q, v, u)?.torque;
        let error = self.law.samples().last().and_then(|s| s.ee_error);
        let mut touched = None;
        if let Some(e) = error
            && self.touched_at.is_none()
            && e <= self.tolerance
        {
            self.touched_at = Some(t);
            touched = Some(e);
        }
        Ok(Tick {
            torque_clipped,
            touched,
        })
    }

    /// The smallest end-effector error of the solves so far (m; `∞` while the target is
    /// not set), from the law's own samples.
    pub(super) fn min_ee_error(&self) -> f64 {
        self.law
            .samples()
            .iter()
            .filter_map(|s| s.ee_error)
            .fold(f64::INFINITY, f64::min)
    }

    /// The end effector has been within its tolerance of the target, or there is none.
    pub(super) fn reached(&self) -> bool {
        self.target.is_none() || self.touched_at.is_some()
    }

    /// The run's MPC summary (the `mpc` object of `moma simulate`'s summary).
    pub(super) fn summary(&self) -> Option<MpcRunSummary> {
        self.law.mpc_run().map(|r| r.summary)
    }
}

/// The planner's map as the MPC's distance field: at each cell centre the distance (m)
/// to the nearest occupied cell's edge, the distance transform's centre-to-centre
/// distance less half a cell (exact along the grid's axes, up to 0.21 cells over it
/// diagonally), on the grid's frame (a ROS map's origin and yaw; a MovingAI map's unit
/// cells centred on the integers).
pub(super) fn distance_field(planner: &Planner, grid: &OccupancyGrid) -> DistanceField {
    let res = grid.resolution;
    let origin = match grid.kind {
        MapKind::Ros => grid.origin,
        MapKind::MovingAi => [-0.5, -0.5, 0.0],
    };
    DistanceField {
        width: planner.width,
        height: planner.height,
        resolution: res,
        origin,
        distance: planner
            .dist
            .iter()
            .map(|&d| (f64::from(d) - 0.5).max(0.0) * res)
            .collect(),
    }
}

//! Tip-over stability and wheel–ground loads along a wheeled simulation.
//!
//! [`StabilityMonitor`] is a [`SampleObserver`]: at every recorded sample of a
//! [`WheeledModel`] run it rebuilds the full multibody state from the reduced one,
//! `q`, `q̇ = N_C v`, `q̈ = N_C v̇ + Ṅ_C v` (one reduced forward dynamics under the
//! sample's input), and evaluates on it
//!
//! * the measures of [`crate::stability`] over the support of the wheel set-up
//!   ([`SupportPolygon::from_wheeled_base`]: the two drive-wheel contacts and the
//!   casters, carried with the base): the ZMP margin and critical edge, the Force-Angle
//!   minimum θ and α, the Moment-Height minimum;
//! * the normal load of every contact ([`contact_normal_loads`]: exact for three contacts,
//!   minimum-norm for more) and, with a friction coefficient μ, the friction demand of
//!   the two driven wheels ([`driven_wheel_friction`]): the axle's lateral force `−λ₀`
//!   from the constraint multipliers and each wheel's longitudinal ground force (the
//!   rolling multipliers `−λ₁, −λ₂` with tracked wheels, `τ / r_w` with massless ones).
//!
//! Every sample goes into a [`StabilityTrace`]; [`first_crossing`] finds the first time
//! a measure reaches zero, and the monitor can stop the run at the first tip-over sample
//! (ZMP margin ≤ 0, or no ZMP at all).
//!
//! Edges are numbered in the **base frame**: edge i of the support polygon built once
//! from the base-frame contacts (clockwise from above, from the vertex of smallest base
//! x), so an edge keeps its number while the robot turns ([`StabilityMonitor::edges`]
//! names its two contacts).

use nalgebra::{DVector, Vector2};

use crate::error::{Error, Result};
use crate::mobile::{WheeledData, WheeledModel};
use crate::sim::wheeled::SampleObserver;
use crate::stability::{
    BodySet, ExternalLoads, GravitoInertialWrench, LoadRule, StabilityData, StabilityModel,
    SupportAttachment, SupportPolygon, WheelFriction, contact_normal_loads, driven_wheel_friction,
    evaluate,
};

/// What the monitor computes and when it stops a run.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StabilitySettings {
    /// Coulomb friction coefficient of the driven wheels; `None`: no slip check.
    pub mu: Option<f64>,
    /// Moment-Height body set (default: all moving bodies).
    pub bodies: BodySet,
    /// Height of the ground plane in the base frame (m). `None`: the tracked wheel
    /// joints' height minus the wheel radius, or 0 (base origin on the ground) without
    /// tracked wheels.
    pub ground_z: Option<f64>,
    /// Stop the run at the first sample that tips over (ZMP margin ≤ 0 or no ZMP).
    pub stop_at_tip: bool,
}

/// One edge of the base-frame support polygon, by the indices of its two contacts in
/// [`StabilityMonitor::contact_names`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct EdgeContacts {
    /// Contact at vertex i.
    pub from: usize,
    /// Contact at vertex i + 1.
    pub to: usize,
}

/// The stability record of a run, one entry per observed sample. Undefined values are
/// `None`, never NaN.
#[derive(Debug, Clone, Default)]
pub struct StabilityTrace {
    /// Sample times (s).
    pub times: Vec<f64>,
    /// ZMP `[x, y]` on the ground (world, m).
    pub zmp: Vec<Option<[f64; 2]>>,
    /// ZMP margin (m).
    pub zmp_margin: Vec<Option<f64>>,
    /// Critical edge (base-frame numbering).
    pub critical_edge: Vec<Option<usize>>,
    /// Force-Angle minimum `min θ_i` (rad).
    pub force_angle_min: Vec<Option<f64>>,
    /// Force-Angle `α = min θ_i |f_r|` (N·rad).
    pub force_angle_alpha: Vec<Option<f64>>,
    /// Moment-Height minimum `min M_i / I_i` (1/s²).
    pub mhs_min: Vec<Option<f64>>,
    /// Normal loads, `times.len() × contacts` row-major (N).
    pub normal_loads: Vec<f64>,
    /// `[left, right]` driven-wheel friction demand (only with μ).
    pub wheels: Vec<[WheelFriction; 2]>,
}

impl StabilityTrace {
    /// `1 − max slip ratio` of the two driven wheels per sample (positive: no slip), or
    /// `None` where a wheel has no ratio (unloaded). Empty without μ.
    #[must_use]
    pub fn slip_margin(&self) -> Vec<Option<f64>> {
        self.wheels
            .iter()
            .map(|w| match (w[0].slip_ratio, w[1].slip_ratio) {
                (Some(a), Some(b)) => Some(1.0 - a.max(b)),
                _ => None,
            })
            .collect()
    }

    /// Per sample: would a driven wheel slide? Empty without μ.
    #[must_use]
    pub fn slips(&self) -> Vec<bool> {
        self.wheels
            .iter()
            .map(|w| w[0].slips || w[1].slips)
            .collect()
    }
}

/// The first time a measure reaches zero.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Crossing {
    /// Crossing time (s): linear interpolation between the last sample above zero and
    /// the first at or below it; the sample's own time when the measure was already at
    /// or below zero at the first sample or became undefined.
    pub time: f64,
    /// Index of the first sample at or below zero (or undefined).
    pub sample: usize,
    /// Time of that sample (s).
    pub sample_time: f64,
}

/// The first sample at which `values` is `≤ 0` (or `None`, when `none_crosses`: an
/// undefined ZMP means the robot tips; otherwise undefined samples are skipped), with the
/// crossing time interpolated linearly from the previous sample when that one is
/// defined and above zero.
///
/// # Panics
/// If the lengths differ.
#[must_use]
pub fn first_crossing(
    times: &[f64],
    values: &[Option<f64>],
    none_crosses: bool,
) -> Option<Crossing> {
    assert_eq!(times.len(), values.len(), "one value per time");
    let mut prev: Option<(f64, f64)> = None;
    for (i, (&t, &y)) in times.iter().zip(values).enumerate() {
        let crossed = match y {
            Some(y) => y <= 0.0,
            None => none_crosses,
        };
        if crossed {
            let time = match (prev, y) {
                (Some((t0, y0)), Some(y1)) if y0 > y1 => t0 + (t - t0) * y0 / (y0 - y1),
                _ => t,
            };
            return Some(Crossing {
                time,
                sample: i,
                sample_time: t,
            });
        }
        // An undefined sample breaks the interpolation.
        prev = y.map(|y| (t, y));
    }
    None
}

/// The first sample at which a driven wheel would slide (see [`StabilityTrace::slips`]),
/// with the time interpolated on the slip margin `1 − max ratio` where it is defined on
/// both sides.
#[must_use]
pub fn first_slip(trace: &StabilityTrace) -> Option<Crossing> {
    let slips = trace.slips();
    let margin = trace.slip_margin();
    let i = slips.iter().position(|&s| s)?;
    let t = trace.times[i];
    let time = match (i.checked_sub(1).and_then(|p| margin[p]), margin[i]) {
        (Some(y0), Some(y1)) if y0 > 0.0 && y1 <= 0.0 && y0 > y1 => {
            let t0 = trace.times[i - 1];
            t0 + (t - t0) * y0 / (y0 - y1)
        }
        _ => t,
    };
    Some(Crossing {
        time,
        sample: i,
        sample_time: t,
    })
}

/// Stability and wheel loads of a wheeled model, sample by sample (see the module docs).
#[derive(Debug, Clone)]
pub struct StabilityMonitor {
    robot: WheeledModel,
    wd: WheeledData,
    sm: StabilityModel,
    sd: StabilityData,
    settings: StabilitySettings,
    ground_z: f64,
    contact_names: Vec<String>,
    contacts_base: Vec<Vector2<f64>>,
    contacts: Vec<Vector2<f64>>,
    edges: Vec<EdgeContacts>,
    loads: Vec<f64>,
    load_rule: Option<LoadRule>,
    q: DVector<f64>,
    v: DVector<f64>,
    /// The record of every observed sample.
    pub trace: StabilityTrace,
    tipped: bool,
}

/// Index of the contact at `p` (the nearest).
fn nearest(points: &[Vector2<f64>], p: &Vector2<f64>) -> usize {
    let mut best = 0;
    for (i, c) in points.iter().enumerate() {
        if (c - p).norm_squared() < (points[best] - p).norm_squared() {
            best = i;
        }
    }
    best
}

impl StabilityMonitor {
    /// A monitor for `robot` (a copy is kept, with its own workspace).
    ///
    /// # Errors
    /// [`Error::InvalidInput`] when the wheel set-up has fewer than three non-collinear
    /// contacts (add a caster off the axle), for a non-positive μ or a non-finite ground
    /// height; errors of [`BodySet::mask`] for an unknown joint or link.
    pub fn new(robot: &WheeledModel, settings: StabilitySettings) -> Result<Self> {
        if let Some(mu) = settings.mu {
            crate::error::ensure_positive("stability.mu", mu)?;
        }
        if let Some(z) = settings.ground_z {
            crate::error::ensure_finite("stability.ground_z", [z].iter())?;
        }
        let ground_z = settings.ground_z.unwrap_or_else(|| robot.ground_z());
        let contacts_base = robot.base.support_points();
        let support = SupportPolygon::from_wheeled_base(&robot.base).map_err(|e| {
            Error::invalid(
                "stability support",
                format!(
                    "{e}: the drive-wheel contacts and the casters must span a polygon \
                         (add a caster off the driven axle)"
                ),
            )
        })?;
        let support = SupportPolygon::from_points_at_height(support.vertices_xy(), ground_z)?;
        let edges = (0..support.len())
            .map(|i| {
                let v = support.vertices_xy();
                EdgeContacts {
                    from: nearest(&contacts_base, &v[i]),
                    to: nearest(&contacts_base, &v[(i + 1) % v.len()]),
                }
            })
            .collect();
        let wheel = |side: usize, fallback: &str| {
            robot
                .base
                .wheel_joints
                .as_ref()
                .map_or_else(|| fallback.to_string(), |w| w[side].clone())
        };
        let mut contact_names = vec![wheel(0, "left wheel"), wheel(1, "right wheel")];
        contact_names.extend(robot.base.casters.iter().map(|c| c.name.clone()));
        let sm = StabilityModel::new(
            &robot.model,
            support,
            SupportAttachment::Base,
            &settings.bodies,
        )?;
        let sd = StabilityData::new(&sm);
        let n = contacts_base.len();
        Ok(Self {
            wd: WheeledData::new(robot),
            robot: robot.clone(),
            sm,
            sd,
            settings,
            ground_z,
            contact_names,
            contacts: contacts_base.clone(),
            contacts_base,
            edges,
            loads: vec![0.0; n],
            load_rule: None,
            q: DVector::zeros(robot.model.nq),
            v: DVector::zeros(robot.nr()),
            trace: StabilityTrace::default(),
            tipped: false,
        })
    }

    /// The ground height used (base frame, m).
    #[must_use]
    pub fn ground_z(&self) -> f64 {
        self.ground_z
    }

    /// The settings.
    #[must_use]
    pub fn settings(&self) -> &StabilitySettings {
        &self.settings
    }

    /// Contact names: `[left wheel, right wheel, casters…]` (wheel joint names when
    /// tracked).
    #[must_use]
    pub fn contact_names(&self) -> &[String] {
        &self.contact_names
    }

    /// Contact points in the base frame `[x, y]`, in the order of the names.
    #[must_use]
    pub fn contacts_base(&self) -> &[Vector2<f64>] {
        &self.contacts_base
    }

    /// Edges of the base-frame support polygon (base-frame numbering).
    #[must_use]
    pub fn edges(&self) -> &[EdgeContacts] {
        &self.edges
    }

    /// Edge `i` named by its two contacts, `edge A-B` (the sweeps' `tip_contact`).
    #[must_use]
    pub fn edge_label(&self, i: usize) -> String {
        let e = self.edges[i];
        format!(
            "edge {}-{}",
            self.contact_names[e.from], self.contact_names[e.to]
        )
    }

    /// The rule of the normal loads (`None` before the first sample).
    #[must_use]
    pub fn load_rule(&self) -> Option<LoadRule> {
        self.load_rule
    }

    /// True once a sample has tipped over (margin ≤ 0 or no ZMP).
    #[must_use]
    pub fn tipped(&self) -> bool {
        self.tipped
    }

    /// The gravito-inertial wrench of the last sample.
    #[must_use]
    pub fn wrench(&self) -> &GravitoInertialWrench {
        &self.sd.wrench
    }

    /// The constraint multipliers λ of the last sample (no side slip, then the rolling
    /// rows of tracked wheels).
    #[must_use]
    pub fn multipliers(&self) -> &DVector<f64> {
        &self.wd.reduced.lambda
    }

    /// The full joint-space velocity `q̇ = N_C v` and acceleration `q̈ = N_C v̇ + Ṅ_C v`
    /// of the last sample.
    #[must_use]
    pub fn full_state_rates(&self) -> (&DVector<f64>, &DVector<f64>) {
        (&self.wd.qdot, &self.wd.reduced.qddot)
    }

    /// The contacts of the last sample in world coordinates (order of the names).
    #[must_use]
    pub fn contacts_world(&self) -> &[Vector2<f64>] {
        &self.contacts
    }

    /// The normal loads of the last sample (order of the names, N).
    #[must_use]
    pub fn normal_loads(&self) -> &[f64] {
        &self.loads
    }

    /// Evaluates one sample `(t, q, v, u)` and appends it to the trace; returns whether
    /// it tips over.
    ///
    /// # Errors
    /// [`Error::Singular`] from the reduced dynamics, errors of the loads for a
    /// non-finite state.
    ///
    /// # Panics
    /// On wrong lengths.
    pub fn sample(&mut self, t: f64, q: &[f64], v: &[f64], u: &[f64]) -> Result<bool> {
        self.q.copy_from_slice(q);
        self.v.copy_from_slice(v);
        let (robot, wd) = (&self.robot, &mut self.wd);
        crate::mobile::reduced_forward_dynamics(robot, wd, &self.q, &self.v, u)?;
        crate::mobile::wheeled::lagrange_multipliers(robot, wd, &self.q)?;
        self.record(t, None, u)
    }

    /// As [`StabilityMonitor::sample`] on a state whose dynamics the caller has already
    /// evaluated in `wd` (for this monitor's robot): the reduced forward dynamics at
    /// `(q, v)` under `u` (`qdot`, `reduced.qddot`) and the multipliers
    /// (`reduced.lambda`, from [`crate::mobile::wheeled::lagrange_multipliers`]). A
    /// closed loop that evaluates each state once shares that evaluation with its
    /// monitor this way. `wd.data` serves as the kinematics workspace.
    ///
    /// # Errors
    /// Errors of the loads for a non-finite state.
    ///
    /// # Panics
    /// On wrong lengths.
    pub fn sample_evaluated(
        &mut self,
        t: f64,
        q: &[f64],
        wd: &mut WheeledData,
        u: &[f64],
    ) -> Result<bool> {
        self.q.copy_from_slice(q);
        self.record(t, Some(wd), u)
    }

    /// Evaluates the stability measures, loads and slip of the state in `self.q` with the
    /// dynamics in `shared` (else in the monitor's own workspace) and appends them.
    fn record(&mut self, t: f64, shared: Option<&mut WheeledData>, u: &[f64]) -> Result<bool> {
        let robot = &self.robot;
        let wd = match shared {
            Some(w) => w,
            None => &mut self.wd,
        };
        // q̇ and q̈ of the full model are in wd.qdot and wd.reduced.qddot.
        let r = evaluate(
            &robot.model,
            &mut wd.data,
            &self.sm,
            &mut self.sd,
            &self.q,
            &wd.qdot,
            &wd.reduced.qddot,
            &ExternalLoads::NONE,
        );
        let (zmp, margin, critical) = (r.zmp, r.zmp_margin, r.zmp_critical_edge);
        let (fa_min, fa_alpha, mhs_min) = (r.force_angle_min, r.force_angle_alpha, r.mhs_min);
        // World numbering → base numbering: find the world vertex of base vertex 0.
        let [x, y, yaw] = self.sd.base_pose;
        let (s, c) = yaw.sin_cos();
        let v0 = self.sm.support.vertices_xy()[0];
        let v0w = Vector2::new(x + c * v0.x - s * v0.y, y + s * v0.x + c * v0.y);
        let shift = nearest(self.sd.support.vertices_xy(), &v0w);
        let ne = self.sm.support.len();
        let tr = &mut self.trace;
        tr.times.push(t);
        tr.zmp.push(zmp.map(|p| [p.x, p.y]));
        tr.zmp_margin.push(margin);
        tr.critical_edge
            .push(critical.map(|i| (i + ne - shift) % ne));
        tr.force_angle_min.push(fa_min);
        tr.force_angle_alpha.push(fa_alpha);
        tr.mhs_min.push(mhs_min);
        let tips = !margin.is_some_and(|m| m > 0.0);
        for (w, b) in self.contacts.iter_mut().zip(&self.contacts_base) {
            *w = Vector2::new(x + c * b.x - s * b.y, y + s * b.x + c * b.y);
        }
        let rule = contact_normal_loads(
            &self.contacts,
            self.ground_z,
            &self.sd.wrench,
            &mut self.loads,
        )?;
        self.load_rule = Some(rule);
        tr.normal_loads.extend_from_slice(&self.loads);
        if let Some(mu) = self.settings.mu {
            let lam = &wd.reduced.lambda;
            let longitudinal =
                crate::mobile::wheeled::wheel_longitudinal_forces(robot, lam.as_slice(), u);
            let f =
                driven_wheel_friction(-lam[0], longitudinal, [self.loads[0], self.loads[1]], mu)?;
            tr.wheels.push(f);
        }
        self.tipped |= tips;
        Ok(tips)
    }
}

impl SampleObserver for StabilityMonitor {
    fn observe(&mut self, t: f64, q: &[f64], v: &[f64], u: &[f64]) -> Result<bool> {
        let tips = self.sample(t, q, v, u)?;
        Ok(tips && self.settings.stop_at_tip)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crossing_is_interpolated_between_samples() {
        let t = [0.0, 0.1, 0.2, 0.3];
        let y = [Some(0.3), Some(0.1), Some(-0.1), Some(-0.2)];
        let c = first_crossing(&t, &y, true).unwrap();
        assert_eq!(c.sample, 2);
        assert!((c.time - 0.15).abs() < 1e-15);
        assert_eq!(c.sample_time, 0.2);
        // already below at the start, undefined, never
        let c = first_crossing(&t, &[Some(-1.0), Some(1.0), None, None], true).unwrap();
        assert_eq!((c.sample, c.time), (0, 0.0));
        let c = first_crossing(&t, &[Some(1.0), None, Some(-1.0), None], true).unwrap();
        assert_eq!((c.sample, c.time), (1, 0.1));
        let c = first_crossing(&t, &[Some(1.0), None, Some(-1.0), None], false).unwrap();
        assert_eq!((c.sample, c.time), (2, 0.2));
        assert!(first_crossing(&t, &[Some(1.0), Some(0.5), Some(0.2), Some(1e-9)], true).is_none());
        assert!(first_crossing(&t, &[None, None, None, None], false).is_none());
    }
}

//! Planning inside the loop: a cell path smoothed, timed and checked with the footprint
//! polygon into the reference to track (the first plan's, a pick's drive on), the
//! obstacles appearing on schedule, and the re-plan after one blocks the reference (from
//! the current pose and speed, or braking to rest along the old path first).

use std::time::Instant;

use super::laws::RunSettings;
use super::plan::SearchTiming;
use super::reference::{Reference, TimingStart, axle_pose, brake_along, build_reference};
use super::result::PlanRecord;
use super::run::{LoopState, Phase, Runner};
use crate::error::Result;

/// Spacing of the reference samples (s).
const REF_DT: f64 = 0.02;

/// Re-plans with the colliding cells blocked before the footprint polygon's search
/// falls back to the circumscribed disk.
const POLYGON_REPAIRS: usize = 10;

/// A path the footprint passes: its cells, its timed reference and the wall time (s) of
/// its smoothing, timing and checks.
struct CheckedPath {
    cells: Vec<(usize, usize)>,
    reference: Reference,
    smoothing_s: f64,
}

/// A re-plan that stops along the old path first.
struct StopAndGo {
    /// The cell path from the stop.
    cells: Vec<(usize, usize)>,
    /// The stop, then the new path.
    reference: Reference,
    /// Smoothing and timing wall time of the new path (s).
    smoothing_s: f64,
    /// The stop: its mission time and the axle-midpoint pose the new path starts from.
    stop: TimingStart,
}

/// Length of a polyline (m).
fn path_length(p: &[[f64; 2]]) -> f64 {
    p.windows(2)
        .map(|w| (w[1][0] - w[0][0]).hypot(w[1][1] - w[0][1]))
        .sum()
}

impl Runner<'_> {
    /// Smooths and times `cells` from `start`; records the plan. `false` on failure.
    pub(super) fn make_reference(
        &mut self,
        cells: Vec<(usize, usize)>,
        start: TimingStart,
        trigger: &str,
        mut search: SearchTiming,
    ) -> bool {
        match self.checked_reference(cells, &start, &mut search) {
            Some(Ok(p)) => {
                self.adopt(
                    p.cells,
                    p.reference,
                    start.t0,
                    start.v,
                    start.pose,
                    trigger,
                    search,
                    p.smoothing_s,
                );
                true
            }
            Some(Err(reason)) => {
                self.fail(start.t0, reason);
                false
            }
            None => false,
        }
    }

    /// Smooths and times `cells` from `start` ([`Runner::time_cells`]) and, with the
    /// robot's footprint polygon, checks every sample with the polygon at its heading:
    /// the axle cells of the samples that collide are blocked and D* Lite re-plans, up to
    /// [`POLYGON_REPAIRS`] times; then the search falls back to the circumscribed disk
    /// (`MissionFootprint::radius` about the base frame, `+ |d|` about the axle). The
    /// cells, reference and smoothing wall time it ends with, or the reason there is
    /// none (`None`: no timing accelerations, already reported).
    fn checked_reference(
        &mut self,
        mut cells: Vec<(usize, usize)>,
        start: &TimingStart,
        search: &mut SearchTiming,
    ) -> Option<std::result::Result<CheckedPath, String>> {
        let mut smoothing_s = 0.0;
        let mut repaired = 0;
        let mut polygon = self.planner.polygon.is_some();
        loop {
            let (r, st) = match self.time_cells(&cells, start)? {
                Ok(x) => x,
                Err(e) => return Some(Err(format!("the path could not be timed: {e}"))),
            };
            let clock = Instant::now();
            let bad = if polygon {
                self.colliding_cells(&r)
            } else {
                Vec::new()
            };
            let check_s = clock.elapsed().as_secs_f64();
            self.wall.smoothing_timing_s += check_s;
            smoothing_s += st + check_s;
            if bad.is_empty() {
                // after the fallback to the disk its own event has said how it ended
                if repaired > 0 && polygon {
                    let text = format!(
                        "the footprint polygon collided along the path: {repaired} re-plan(s) \
                         with the colliding cells blocked"
                    );
                    self.event(start.t0, "footprint", text);
                }
                return Some(Ok(CheckedPath {
                    cells,
                    reference: r,
                    smoothing_s,
                }));
            }
            let clock = Instant::now();
            let mut blocked = false;
            if repaired < POLYGON_REPAIRS {
                // neither the search's start cell nor the one the base stands in (the
                // timing's start, off the search's after a drive on from a placement)
                let robot = self.planner.dstar.start();
                let here = self.cell_of(start.pose);
                for c in bad.into_iter().filter(|&c| c != robot && c != here) {
                    blocked |= self.planner.block(c).unwrap_or(false);
                }
            }
            let (path, timing) = if blocked {
                repaired += 1;
                self.planner.replan()
            } else {
                // the polygon's lower bound gives no path it passes: the circumscribed disk
                polygon = false;
                let grid = &self.m.map.grid;
                let radius = self.footprint.radius + self.wm.base.drive.d.abs();
                let sc = self.cell_of(start.pose);
                let text = format!(
                    "the footprint polygon collides along every path found ({repaired} \
                     re-plan(s)): planning on the circumscribed disk of radius {:.3} m",
                    self.footprint.radius
                );
                self.event(start.t0, "footprint", text);
                match self.planner.use_disk(radius, grid.resolution, sc) {
                    Ok(true) => self.planner.replan(),
                    _ => (None, SearchTiming::default()),
                }
            };
            let dt = clock.elapsed().as_secs_f64();
            search.search_s += dt;
            search.expanded += timing.expanded;
            self.wall.planning_s += dt;
            match path {
                Some(p) => cells = p,
                None => {
                    return Some(Err(
                        "the goal is unreachable: no path on the configuration space that the \
                         robot's footprint polygon passes at the headings it is driven with"
                            .to_string(),
                    ));
                }
            }
        }
    }

    /// The cell of a world point (clamped to the map).
    pub(super) fn cell_of(&self, p: [f64; 3]) -> (usize, usize) {
        let grid = &self.m.map.grid;
        let [fx, fy] = grid.world_to_cell_f(p[0], p[1]);
        (
            (fx.floor().max(0.0) as usize).min(grid.width - 1),
            (fy.floor().max(0.0) as usize).min(grid.height - 1),
        )
    }

    /// The axle cells of the samples of `r` where the footprint polygon collides
    /// ([`super::plan::Planner::colliding_cells`]), each once.
    pub(super) fn colliding_cells(&mut self, r: &Reference) -> Vec<(usize, usize)> {
        let poses = r.samples.iter().map(|s| [s.x, s.y, s.theta]);
        self.planner.colliding_cells(&self.m.map.grid, poses)
    }

    /// Smooths and times `cells` from `start` (`None` without timing accelerations),
    /// with the wall time it took.
    pub(super) fn time_cells(
        &mut self,
        cells: &[(usize, usize)],
        start: &TimingStart,
    ) -> Option<Result<(Reference, f64)>> {
        let accel = self.timing_accel?;
        let clock = Instant::now();
        let r = build_reference(
            &self.m.map.grid,
            self.planner.dstar.grid(),
            cells,
            start,
            axle_pose(self.goal.pose, self.wm.base.drive.d),
            self.wm.base.drive.d,
            &self.limits,
            &accel,
            self.m.file.limits.kappa_max,
            REF_DT,
        );
        let st = clock.elapsed().as_secs_f64();
        self.wall.smoothing_timing_s += st;
        Some(r.map(|r| (r, st)))
    }

    /// Makes `r` (timed from `t0` at speed `v_start`, from `cells`, its path smoothed from
    /// the axle-midpoint pose `smoothed_from`) the reference to track and records it as a
    /// plan.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn adopt(
        &mut self,
        cells: Vec<(usize, usize)>,
        r: Reference,
        t0: f64,
        v_start: f64,
        smoothed_from: [f64; 3],
        trigger: &str,
        search: SearchTiming,
        smoothing_timing_s: f64,
    ) {
        if r.kappa_max != self.m.file.limits.kappa_max || r.turn_at_goal {
            let text = format!(
                "smoothing with kappa_max = {} 1/m{}",
                r.kappa_max,
                if r.turn_at_goal {
                    "; no smooth path ends at the goal heading: the path ends with its \
                     arrival heading and the base turns in place at the goal"
                } else {
                    ""
                }
            );
            self.event(t0, "smoothing", text);
        }
        self.plans.push(PlanRecord {
            t: t0,
            trigger: trigger.to_string(),
            cells,
            path: r.path.clone(),
            duration: r.t_end() - t0,
            search,
            smoothing_timing_s,
            v_start,
            smoothed_from,
        });
        self.reference = Some(r);
    }

    /// The obstacles whose time has come appear in the map, each re-planning the drive
    /// if it blocks the rest of the reference.
    pub(super) fn obstacle_arrivals(
        &mut self,
        c: &RunSettings,
        st: &mut LoopState,
        t: f64,
        axle: [f64; 3],
        v: f64,
    ) {
        while st.phase != Phase::Done
            && st.next_obstacle < c.obstacles.len()
            && c.obstacles[st.next_obstacle].1 <= t + 1e-12
        {
            let (oi, ot) = c.obstacles[st.next_obstacle];
            st.next_obstacle += 1;
            if !self.obstacle_appears(st, oi, ot, t, axle, v) {
                break;
            }
        }
    }

    /// Adds obstacle `oi` (due at `ot`) to the planner at time `t`; `false` when the run
    /// ends with it.
    pub(super) fn obstacle_appears(
        &mut self,
        st: &mut LoopState,
        oi: usize,
        ot: f64,
        t: f64,
        axle: [f64; 3],
        v: f64,
    ) -> bool {
        let m = self.m;
        let grid = &m.map.grid;
        let o = m.file.obstacles[oi];
        let clock = Instant::now();
        let c = grid.world_to_cell_f(o.center[0], o.center[1]);
        let [fx, fy] = grid.world_to_cell_f(axle[0], axle[1]);
        let rc = (
            (fx.floor().max(0.0) as usize).min(grid.width - 1),
            (fy.floor().max(0.0) as usize).min(grid.height - 1),
        );
        let added = self.planner.add_disk(c, o.radius / grid.resolution, rc);
        self.event(
            ot,
            "obstacle",
            format!(
                "obstacle {oi} appears at ({:.2}, {:.2}), radius {:.2} m",
                o.center[0], o.center[1], o.radius
            ),
        );
        let (newly, s_time) = match added {
            Ok(a) => a,
            Err(e) => {
                self.fail(t, format!("re-planning failed: {e}"));
                st.phase = Phase::Done;
                return false;
            }
        };
        if newly.contains(&self.planner.goal_cell) && st.phase.follows_reference() {
            self.wall.planning_s += s_time;
            st.excluded += clock.elapsed().as_secs_f64();
            self.fail(
                t,
                format!(
                    "obstacle {oi} (t = {ot} s) seals the goal: the footprint no \
                     longer fits at the goal pose"
                ),
            );
            st.phase = Phase::Done;
            return false;
        }
        let planner = &mut self.planner;
        let affected = st.phase.follows_reference()
            && self.reference.as_ref().is_some_and(|r| {
                r.samples
                    .iter()
                    .filter(|s| s.t >= t)
                    .any(|s| planner.axle_collides(grid, [s.x, s.y, s.theta]))
            });
        if affected {
            self.replan_after_obstacle(st, oi, ot, t, axle, v, s_time);
        } else {
            self.wall.planning_s += s_time;
        }
        st.excluded += clock.elapsed().as_secs_f64();
        true
    }

    /// Re-plans from the current axle pose and speed after obstacle `oi` blocked the
    /// reference (`s_time`: the wall time its map update took).
    #[allow(clippy::too_many_arguments)]
    pub(super) fn replan_after_obstacle(
        &mut self,
        st: &mut LoopState,
        oi: usize,
        ot: f64,
        t: f64,
        axle: [f64; 3],
        v: f64,
        s_time: f64,
    ) {
        let (path, mut timing) = self.planner.replan();
        timing.search_s += s_time;
        self.wall.planning_s += timing.search_s;
        let Some(cells) = path else {
            self.fail(
                t,
                format!(
                    "obstacle {oi} (t = {ot} s) seals the goal: no \
                     collision-free path remains"
                ),
            );
            st.phase = Phase::Done;
            return;
        };
        let start = TimingStart {
            t0: t,
            pose: axle,
            v,
        };
        let trigger = format!("obstacle {oi}");
        let old = self.reference.take();
        let (cells, r, st_s, stop) = match self.checked_reference(cells, &start, &mut timing) {
            Some(Ok(CheckedPath {
                cells,
                reference: r,
                smoothing_s: st_s,
            })) => {
                // a new path that does not admit the current speed at its start would be
                // braked onto past its limits (ω_max): stop along the old path instead,
                // then follow a path planned from there
                let brake = match (&old, r.overspeed_until) {
                    (Some(o), Some(_)) if v > 0.0 => self.brake_then_replan(o, t, v, &mut timing),
                    _ => None,
                };
                match brake {
                    Some(b) => (b.cells, b.reference, st_s + b.smoothing_s, Some(b.stop)),
                    None => (cells, r, st_s, None),
                }
            }
            Some(Err(reason)) => {
                self.fail(t, reason);
                st.phase = Phase::Done;
                return;
            }
            None => {
                st.phase = Phase::Done;
                return;
            }
        };
        let smoothed_from = stop.map_or(start.pose, |s| s.pose);
        self.adopt(cells, r, t, v, smoothed_from, &trigger, timing, st_s);
        let p = self.plans.last().expect("just pushed");
        let stop_text = stop.map_or(String::new(), |ts| {
            format!(
                "; the new path does not admit {v:.2} m/s at its start, so the base brakes \
                 to rest along the old path first ({:.2} s)",
                ts.t0 - t
            )
        });
        let text = format!(
            "re-plan after obstacle {oi}: D* Lite expanded {} cells, \
             new path {:.2} m, {:.2} s to go from {:.2} m/s{stop_text}",
            p.search.expanded,
            path_length(&p.path),
            p.duration,
            p.v_start
        );
        self.event(t, "replan", text);
    }

    /// The stop of a re-plan at speed: brakes from `v` to rest along the path of `old`
    /// from where it is at `t`, then plans and times a new path from that stop at rest.
    /// `None` when the stop
    /// cannot be made (it runs into a blocked cell, it cannot be timed, no path leaves
    /// it), the caller then keeps the path planned from where the base is.
    fn brake_then_replan(
        &mut self,
        old: &Reference,
        t: f64,
        v: f64,
        timing: &mut SearchTiming,
    ) -> Option<StopAndGo> {
        let accel = self.timing_accel?;
        let clock = Instant::now();
        let mut samples = brake_along(old, t, v, &self.limits, &accel, REF_DT).ok()?;
        self.wall.smoothing_timing_s += clock.elapsed().as_secs_f64();
        let grid = &self.m.map.grid;
        if samples
            .iter()
            .any(|p| self.planner.axle_collides(grid, [p.x, p.y, p.theta]))
        {
            return None;
        }
        let stop = *samples.last().expect("a timed stop has samples");
        let [fx, fy] = grid.world_to_cell_f(stop.x, stop.y);
        let cell = (
            (fx.floor().max(0.0) as usize).min(grid.width - 1),
            (fy.floor().max(0.0) as usize).min(grid.height - 1),
        );
        let search_clock = Instant::now();
        self.planner.move_start(cell).ok()?;
        let (path, second) = self.planner.replan();
        let search_s = search_clock.elapsed().as_secs_f64().max(second.search_s);
        timing.search_s += search_s;
        timing.expanded += second.expanded;
        self.wall.planning_s += search_s;
        let cells = path?;
        let from_stop = TimingStart {
            t0: stop.t,
            pose: [stop.x, stop.y, stop.theta],
            v: 0.0,
        };
        let CheckedPath {
            cells,
            reference: mut r,
            smoothing_s: st,
        } = self.checked_reference(cells, &from_stop, timing)?.ok()?;
        samples.pop();
        samples.append(&mut r.samples);
        r.samples = samples;
        // the joined reference's arc lengths: the new path's from the stop; the stretch
        // before it is not on that geometry (NaN: a re-plan during the stop cannot stop
        // along it again, and falls back to braking onto its new path)
        let n_brake = r.samples.len() - r.arc.len();
        let mut arc = vec![f64::NAN; n_brake];
        arc.append(&mut r.arc);
        r.arc = arc;
        let d = self.wm.base.drive.d;
        let mut drawn: Vec<[f64; 2]> = r.samples[..n_brake]
            .iter()
            .map(|p| {
                let (sn, cs) = p.theta.sin_cos();
                [p.x + d * cs, p.y + d * sn]
            })
            .collect();
        drawn.append(&mut r.path);
        r.path = drawn;
        Some(StopAndGo {
            cells,
            reference: r,
            smoothing_s: st,
            stop: from_stop,
        })
    }
}

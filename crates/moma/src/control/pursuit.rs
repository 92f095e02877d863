//! Regulated pure pursuit: the path follower nav2 ships as its default controller
//! (Macenski et al., "Regulated Pure Pursuit for Robot Path Tracking", 2023).
//!
//! Pure pursuit steers the axle midpoint onto the arc through a *lookahead point* on the
//! path, a distance `L` ahead: with `(l_x, l_y)` the lookahead point in the robot frame,
//! the curvature is `κ = 2 l_y / L²` (`L² = l_x² + l_y²`) and `ω = v κ`. The *regulated*
//! variant, as nav2's defaults, adds
//!
//! * velocity-scaled lookahead `L = clamp(|v| t_L, L_min, L_max)`;
//! * curvature regulation: on arcs of radius `1/|κ|` below `r_min` the speed is scaled by
//!   `r_min |κ|`'s inverse, i.e. `v ← v · (1/|κ|)/r_min`;
//! * approach scaling: within `d_approach` of the path end the speed is scaled by
//!   `remaining/d_approach`, never below `v_min_approach`;
//! * the lookahead point is the intersection of the circle of radius L with the path
//!   (interpolated on a segment), the path end when it lies inside the circle.
//!
//! The follower reports no Lyapunov function. It reports whether the goal (within
//! `goal_tolerance`) is reached, in which case it commands zero.

use super::Controller;
use super::unicycle::Pose;
use crate::error::{Error, Result};

/// Parameters (defaults are nav2's `RegulatedPurePursuitController` defaults).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PurePursuitParams {
    /// Desired linear speed (m/s), > 0. nav2: 0.5.
    pub desired_speed: f64,
    /// Lookahead time t_L (s) of the velocity-scaled lookahead. nav2: 1.5.
    pub lookahead_time: f64,
    /// L_min (m). nav2: 0.3.
    pub min_lookahead: f64,
    /// L_max (m). nav2: 0.9.
    pub max_lookahead: f64,
    /// Curvature-regulation radius r_min (m); 0 disables. nav2: 0.9.
    pub regulation_min_radius: f64,
    /// Distance to the end below which speed is scaled down (m). nav2: 0.6.
    pub approach_distance: f64,
    /// Smallest approach speed (m/s). nav2: 0.05.
    pub min_approach_speed: f64,
    /// Goal tolerance (m): within it the follower stops. nav2's goal checker: 0.25.
    pub goal_tolerance: f64,
}

impl Default for PurePursuitParams {
    fn default() -> Self {
        Self {
            desired_speed: 0.5,
            lookahead_time: 1.5,
            min_lookahead: 0.3,
            max_lookahead: 0.9,
            regulation_min_radius: 0.9,
            approach_distance: 0.6,
            min_approach_speed: 0.05,
            goal_tolerance: 0.25,
        }
    }
}

/// A regulated pure-pursuit follower of a polyline path `[(x, y), …]`.
///
/// It keeps the index of the path segment it last projected onto and only searches
/// forward from it, so a path that crosses itself is followed in order.
#[derive(Clone, Debug)]
pub struct PurePursuit {
    /// Parameters.
    pub params: PurePursuitParams,
    segment: usize,
    /// Whether the last call found the robot within the goal tolerance.
    pub goal_reached: bool,
    /// The last lookahead point (world frame).
    pub lookahead_point: [f64; 2],
}

impl PurePursuit {
    /// A follower with checked parameters.
    ///
    /// # Errors
    /// A parameter out of range, named.
    pub fn new(params: PurePursuitParams) -> Result<Self> {
        let p = &params;
        for (n, v) in [
            ("desired_speed", p.desired_speed),
            ("lookahead_time", p.lookahead_time),
            ("min_lookahead", p.min_lookahead),
            ("max_lookahead", p.max_lookahead),
            ("goal_tolerance", p.goal_tolerance),
        ] {
            crate::error::ensure_positive(n, v)?;
        }
        for (n, v) in [
            ("regulation_min_radius", p.regulation_min_radius),
            ("approach_distance", p.approach_distance),
            ("min_approach_speed", p.min_approach_speed),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(
                    n,
                    format!("must be >= 0 and finite, got {v}"),
                ));
            }
        }
        if p.max_lookahead < p.min_lookahead {
            return Err(Error::invalid("max_lookahead", "must be >= min_lookahead"));
        }
        Ok(Self {
            params,
            segment: 0,
            goal_reached: false,
            lookahead_point: [0.0; 2],
        })
    }

    /// Forgets the progress along the path (call before following a new path).
    pub fn reset(&mut self) {
        self.segment = 0;
        self.goal_reached = false;
    }

    /// The lookahead distance for speed v.
    #[must_use]
    pub fn lookahead(&self, v: f64) -> f64 {
        (v.abs() * self.params.lookahead_time)
            .clamp(self.params.min_lookahead, self.params.max_lookahead)
    }

    fn project(&mut self, path: &[[f64; 2]], p: [f64; 2]) {
        // Nearest point among the segments from the current one onwards, stopping once
        // the distance grows past the lookahead window (the local search nav2 does).
        let mut best = f64::INFINITY;
        let mut best_seg = self.segment;
        for k in self.segment..path.len().saturating_sub(1) {
            let d = dist_to_segment(p, path[k], path[k + 1]);
            if d < best {
                best = d;
                best_seg = k;
            } else if d > best + 2.0 * self.params.max_lookahead {
                break;
            }
        }
        self.segment = best_seg;
    }

    /// Length of the path from the projection of `p` on the current segment to the end.
    fn remaining(&self, path: &[[f64; 2]], p: [f64; 2]) -> f64 {
        let k = self.segment;
        if path.len() < 2 {
            return dist(p, path[0]);
        }
        let (a, b) = (path[k], path[k + 1]);
        let s = seg_param(p, a, b);
        let mut r = (1.0 - s) * dist(a, b);
        for w in path[k + 1..].windows(2) {
            r += dist(w[0], w[1]);
        }
        r
    }
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    (a[0] - b[0]).hypot(a[1] - b[1])
}

fn seg_param(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
    let l2 = dx * dx + dy * dy;
    if l2 == 0.0 {
        0.0
    } else {
        (((p[0] - a[0]) * dx + (p[1] - a[1]) * dy) / l2).clamp(0.0, 1.0)
    }
}

fn dist_to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let s = seg_param(p, a, b);
    dist(p, [a[0] + s * (b[0] - a[0]), a[1] + s * (b[1] - a[1])])
}

impl Controller for PurePursuit {
    type State = Pose;
    /// The path, at least one point.
    type Reference = [[f64; 2]];
    /// `[v, ω]`.
    type Actuation = [f64; 2];

    fn actuation(
        &mut self,
        _t: f64,
        s: &Pose,
        path: &[[f64; 2]],
        out: &mut [f64; 2],
    ) -> Result<()> {
        if path.is_empty() {
            return Err(Error::invalid("path", "no points"));
        }
        let p = [s[0], s[1]];
        let end = path[path.len() - 1];
        if path.len() >= 2 {
            self.project(path, p);
        }
        let remaining = self.remaining(path, p);
        if dist(p, end) <= self.params.goal_tolerance && self.segment + 2 >= path.len() {
            self.goal_reached = true;
            *out = [0.0, 0.0];
            return Ok(());
        }
        self.goal_reached = false;
        let l = self.lookahead(self.params.desired_speed);
        // First point along the path, from the current segment, at distance ≥ L.
        let mut target = end;
        if path.len() >= 2 {
            for k in self.segment..path.len() - 1 {
                let (a, b) = (path[k], path[k + 1]);
                if dist(p, b) >= l {
                    // circle–segment intersection, the far root
                    let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
                    let (fx, fy) = (a[0] - p[0], a[1] - p[1]);
                    let qa = dx * dx + dy * dy;
                    let qb = 2.0 * (fx * dx + fy * dy);
                    let qc = fx * fx + fy * fy - l * l;
                    let disc = (qb * qb - 4.0 * qa * qc).max(0.0);
                    let u = if qa > 0.0 {
                        ((-qb + disc.sqrt()) / (2.0 * qa)).clamp(0.0, 1.0)
                    } else {
                        1.0
                    };
                    target = [a[0] + u * dx, a[1] + u * dy];
                    break;
                }
            }
        }
        self.lookahead_point = target;
        let (sn, cs) = s[2].sin_cos();
        let (gx, gy) = (target[0] - p[0], target[1] - p[1]);
        let lx = cs * gx + sn * gy;
        let ly = -sn * gx + cs * gy;
        let l2 = lx * lx + ly * ly;
        let kappa = if l2 > 0.0 { 2.0 * ly / l2 } else { 0.0 };
        let mut v = self.params.desired_speed;
        let r_min = self.params.regulation_min_radius;
        if r_min > 0.0 && kappa.abs() > 1.0 / r_min {
            v *= 1.0 / (kappa.abs() * r_min);
        }
        let da = self.params.approach_distance;
        if da > 0.0 && remaining < da {
            v = (v * remaining / da).max(self.params.min_approach_speed.min(v));
        }
        *out = [v, v * kappa];
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::unicycle::unicycle_rhs;

    fn run(path: &[[f64; 2]], start: Pose, steps: usize) -> (PurePursuit, Pose, f64) {
        let mut pp = PurePursuit::new(PurePursuitParams::default()).unwrap();
        let mut s = start;
        let dt = 0.01;
        let mut worst_tail = 0.0f64;
        let mut u = [0.0; 2];
        for k in 0..steps {
            pp.actuation(0.0, &s, path, &mut u).unwrap();
            // RK4 with the input held over the step
            let f = |x: &Pose| unicycle_rhs(x, &u);
            let k1 = f(&s);
            let a = [
                s[0] + 0.5 * dt * k1[0],
                s[1] + 0.5 * dt * k1[1],
                s[2] + 0.5 * dt * k1[2],
            ];
            let k2 = f(&a);
            let b = [
                s[0] + 0.5 * dt * k2[0],
                s[1] + 0.5 * dt * k2[1],
                s[2] + 0.5 * dt * k2[2],
            ];
            let k3 = f(&b);
            let c = [s[0] + dt * k3[0], s[1] + dt * k3[1], s[2] + dt * k3[2]];
            let k4 = f(&c);
            for i in 0..3 {
                s[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
            if k > steps / 2 {
                let d = (0..path.len() - 1)
                    .map(|j| dist_to_segment([s[0], s[1]], path[j], path[j + 1]))
                    .fold(f64::INFINITY, f64::min);
                worst_tail = worst_tail.max(d);
            }
            if pp.goal_reached {
                break;
            }
        }
        (pp, s, worst_tail)
    }

    #[test]
    fn converges_onto_a_line_and_stops_at_the_goal() {
        let path: Vec<[f64; 2]> = (0..=50).map(|k| [0.2 * f64::from(k), 0.0]).collect();
        let (pp, s, tail) = run(&path, [0.0, 0.6, 0.4], 5000);
        assert!(pp.goal_reached, "{s:?}");
        assert!((s[0] - 10.0).abs() < 0.3 && s[1].abs() < 0.05, "{s:?}");
        assert!(tail < 0.05, "cross-track error late in the run {tail}");
    }

    #[test]
    fn follows_a_circle_with_small_cross_track_error() {
        let r = 2.0;
        let path: Vec<[f64; 2]> = (0..=200)
            .map(|k| {
                let a = std::f64::consts::PI * f64::from(k) / 200.0;
                [r * a.sin(), r * (1.0 - a.cos())]
            })
            .collect();
        let (pp, _, tail) = run(&path, [0.0, 0.0, 0.0], 5000);
        assert!(pp.goal_reached);
        // pure pursuit cuts corners by about L²/(2r) at most
        assert!(tail < 0.9 * 0.9 / (2.0 * r), "{tail}");
    }

    #[test]
    fn regulation_slows_down_on_tight_turns() {
        let mut pp = PurePursuit::new(PurePursuitParams::default()).unwrap();
        let path = [[0.0, 0.0], [0.0, 2.0]];
        let mut u = [0.0; 2];
        pp.actuation(0.0, &[0.0, 0.0, 0.0], &path, &mut u).unwrap();
        // By hand, from nav2's regulated pure pursuit: lookahead L = 0.5 m/s · 1.5 s =
        // 0.75 m, so the carrot is (0, 0.75) straight to the left; curvature 2 y / L² =
        // 2 / 0.75, radius 0.375 m < r_min = 0.9 m, so the speed is scaled to
        // 0.5 · 0.375 / 0.9 = 0.2083 m/s; ω = v κ.
        let (v, kappa) = (0.5 * 0.375 / 0.9, 2.0 / 0.75);
        assert!((u[0] - v).abs() < 1e-9, "{u:?} vs v = {v}");
        assert!(
            (u[1] - v * kappa).abs() < 1e-9,
            "{u:?} vs ω = {}",
            v * kappa
        );
        assert!(
            PurePursuit::new(PurePursuitParams {
                max_lookahead: 0.1,
                ..Default::default()
            })
            .is_err()
        );
    }
}

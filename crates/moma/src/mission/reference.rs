//! The timed reference the platform tracks: samples of pose, speeds and accelerations,
//! built from a planned cell path.

use crate::error::Result;
use crate::planning::trajectory::{DiffDriveLimits, DirectionalAcceleration};
use crate::planning::{OccupancyGrid, SearchGrid};

/// One reference sample (world frame).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct RefSample {
    /// Mission time (s).
    pub t: f64,
    /// Position x (m).
    pub x: f64,
    /// Position y (m).
    pub y: f64,
    /// Heading (rad).
    pub theta: f64,
    /// Forward speed (m/s).
    pub v: f64,
    /// Yaw rate (rad/s).
    pub omega: f64,
    /// Forward acceleration (m/s²).
    pub a: f64,
    /// Yaw acceleration (rad/s²).
    pub alpha: f64,
}

/// A timed reference: samples in increasing time.
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    /// The samples (at least one).
    pub samples: Vec<RefSample>,
    /// The smoothed geometric path (world, m), for drawing.
    pub path: Vec<[f64; 2]>,
}

impl Reference {
    /// First sample time.
    pub fn t_start(&self) -> f64 {
        self.samples[0].t
    }

    /// Last sample time.
    pub fn t_end(&self) -> f64 {
        self.samples[self.samples.len() - 1].t
    }

    /// The reference at mission time `t` (linear interpolation; before the start the
    /// first sample, after the end the last one at rest).
    pub fn at(&self, t: f64) -> RefSample {
        let s = &self.samples;
        if t <= s[0].t {
            return s[0];
        }
        let n = s.len();
        if t >= s[n - 1].t {
            let mut last = s[n - 1];
            last.t = t;
            last.v = 0.0;
            last.omega = 0.0;
            last.a = 0.0;
            last.alpha = 0.0;
            return last;
        }
        let i = s.partition_point(|p| p.t <= t) - 1;
        let (p, q) = (&s[i], &s[i + 1]);
        let dt = q.t - p.t;
        let f = if dt > 0.0 { (t - p.t) / dt } else { 0.0 };
        let lerp = |a: f64, b: f64| a + f * (b - a);
        let dth = crate::control::wrap_angle(q.theta - p.theta);
        RefSample {
            t,
            x: lerp(p.x, q.x),
            y: lerp(p.y, q.y),
            theta: crate::control::wrap_angle(p.theta + f * dth),
            v: lerp(p.v, q.v),
            omega: lerp(p.omega, q.omega),
            a: p.a,
            alpha: p.alpha,
        }
    }
}

/// What the timing of a new reference starts from.
#[derive(Debug, Clone, Copy)]
pub(crate) struct TimingStart {
    /// Mission time of the first sample (s).
    pub t0: f64,
    /// Exact start pose `[x, y, θ]`.
    pub pose: [f64; 3],
    /// Current forward speed (m/s).
    pub v: f64,
}

/// Builds a reference from a cell path: shortcut smoothing against the configuration
/// space, then the time parameterisation under the platform and tip-over limits. The
/// path runs from the exact start pose to the exact goal position.
pub(crate) fn build_reference(
    map: &OccupancyGrid,
    cspace: &SearchGrid,
    cells: &[(usize, usize)],
    start: &TimingStart,
    goal: [f64; 3],
    limits: &DiffDriveLimits,
    tip: &DirectionalAcceleration,
    dt: f64,
) -> Result<Reference> {
    let kept = crate::planning::smooth::smooth(cspace, cells);
    let mut pts: Vec<[f64; 2]> = kept
        .iter()
        .map(|&(x, y)| map.cell_to_world(x as f64, y as f64))
        .collect();
    if let Some(first) = pts.first_mut() {
        *first = [start.pose[0], start.pose[1]];
    }
    if let Some(last) = pts.last_mut() {
        *last = [goal[0], goal[1]];
    }
    let traj = crate::planning::trajectory::time_parameterize_directional(
        &pts,
        Some(start.pose[2]),
        limits,
        Some(tip),
        dt,
    )?;
    let mut samples: Vec<RefSample> = traj
        .iter()
        .map(|p| RefSample {
            t: start.t0 + p.t,
            x: p.x,
            y: p.y,
            theta: p.theta,
            v: p.v,
            omega: p.omega,
            a: 0.0,
            alpha: 0.0,
        })
        .collect();
    fill_accelerations(&mut samples);
    Ok(Reference { samples, path: pts })
}

/// Forward differences of v and ω into a and α (the last sample keeps the previous one).
fn fill_accelerations(s: &mut [RefSample]) {
    for i in 0..s.len().saturating_sub(1) {
        let dt = s[i + 1].t - s[i].t;
        if dt > 1e-12 {
            s[i].a = (s[i + 1].v - s[i].v) / dt;
            s[i].alpha = (s[i + 1].omega - s[i].omega) / dt;
        }
    }
    if s.len() >= 2 {
        let n = s.len();
        s[n - 1].a = 0.0;
        s[n - 1].alpha = 0.0;
    }
}

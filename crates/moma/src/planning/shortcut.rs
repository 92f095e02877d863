//! Path shortcutting in a [`JointSpace`]: random shortcuts, then removal of redundant
//! waypoints.
//!
//! 1. **Random shortcuts** (seeded ChaCha8): two arc-length positions `s1 < s2` are drawn
//!    uniformly along the path; their points `a`, `b` lie on segments `i` and `j > i`. The
//!    candidate replaces everything between waypoint `i` and waypoint `j + 1` by
//!    `waypoint i → a → b → waypoint j + 1`; it is taken when it is strictly shorter in the
//!    weighted norm and the one new segment `a → b` is valid at the space's resolution (the
//!    other two are parts of the path's segments `i` and `j`, valid already). A candidate
//!    that would shorten the path by less than [`ShortcutOptions::min_gain`] × its length
//!    is dropped unchecked: late attempts mostly offer such crumbs, each for a segment
//!    check.
//! 2. **Redundant waypoints** ([`ShortcutOptions::drop_redundant`]): in one pass, a
//!    waypoint whose neighbours are joined by a valid segment is dropped (the triangle
//!    inequality makes that never longer). A caller that shortcuts in rounds runs it once,
//!    after the last: the waypoints a pass keeps fail their check again in the next.
//!
//! 3. **Probes first** ([`ShortcutOptions::probe`]): a new segment (a shortcut, or the one
//!    that would drop a waypoint) can be probed state by state at a coarser spacing,
//!    coarse to fine, before its segment check: a segment through an obstacle usually
//!    fails at a probe, and a segment check that computes distances (a continuous one)
//!    then runs only on segments that passed the probes. The verdict on an accepted
//!    segment is still the segment check's.
//!
//! Every segment of the result was checked at the resolution, so a valid input path gives
//! a valid output path no longer than the input.

use super::joint_space::{JointPath, JointSpace, MAX_STATES_PER_SEGMENT, StateValidity};
use crate::{Error, Result};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::collections::VecDeque;

/// The options of [`shortcut`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShortcutOptions {
    /// Random shortcut attempts.
    pub attempts: usize,
    /// The seed of the attempts.
    pub seed: u64,
    /// The least a shortcut must gain, as a fraction of the path's length, to be checked
    /// (0: any gain).
    pub min_gain: f64,
    /// Run the redundant-waypoint pass after the attempts.
    pub drop_redundant: bool,
    /// Probe a candidate's new segment state by state this far apart (weighted norm),
    /// coarse to fine, before its segment check, and drop it at the first invalid probe;
    /// `None`: the segment check alone.
    pub probe: Option<f64>,
}

impl Default for ShortcutOptions {
    fn default() -> Self {
        ShortcutOptions {
            attempts: 100,
            seed: 0,
            min_gain: 0.0,
            drop_redundant: true,
            probe: None,
        }
    }
}

/// The most shortcut attempts accepted (each costs at most three segment checks).
pub const MAX_SHORTCUT_ATTEMPTS: usize = 10_000_000;

/// Shortens `path` (see the module docs); returns the new path and adds the validity
/// checks made to `checks`.
///
/// # Errors
/// [`Error::InvalidInput`] for `path` when its dimension is not the space's or a waypoint
/// lies outside the box, for `attempts` above [`MAX_SHORTCUT_ATTEMPTS`], for a
/// `min_gain` outside [0, 1], or for a `probe` that is not positive or would need more
/// than [`MAX_STATES_PER_SEGMENT`] probes across the box.
pub fn shortcut(
    space: &JointSpace,
    validity: &mut impl StateValidity,
    path: &JointPath,
    options: &ShortcutOptions,
    checks: &mut u64,
) -> Result<JointPath> {
    if path.dim() != space.dim() {
        return Err(Error::invalid(
            "path",
            format!("{} joints, the space has {}", path.dim(), space.dim()),
        ));
    }
    for i in 0..path.len() {
        space.check_state(&format!("path waypoint {i}"), path.waypoint(i))?;
    }
    if options.attempts > MAX_SHORTCUT_ATTEMPTS {
        return Err(Error::invalid(
            "attempts",
            format!("{} is above {MAX_SHORTCUT_ATTEMPTS}", options.attempts),
        ));
    }
    if !(0.0..=1.0).contains(&options.min_gain) {
        return Err(Error::invalid(
            "min_gain",
            format!("{} is not a fraction in [0, 1]", options.min_gain),
        ));
    }
    if let Some(r) = options.probe
        && !(r.is_finite() && r > 0.0 && space.diagonal() / r <= MAX_STATES_PER_SEGMENT)
    {
        return Err(Error::invalid(
            "probe",
            format!(
                "{r} is not a positive spacing of at most {MAX_STATES_PER_SEGMENT:.0e} \
                 probes across the box"
            ),
        ));
    }
    let dim = space.dim();
    let mut points: Vec<f64> = path.as_flat().to_vec();
    let mut rng = ChaCha8Rng::seed_from_u64(options.seed);
    let mut cumulative = Vec::new();
    let (mut a, mut b) = (vec![0.0; dim], vec![0.0; dim]);
    let mut work = Scratch::default();
    let wp = |i: usize| i * dim..(i + 1) * dim;
    for _ in 0..options.attempts {
        let n = points.len() / dim;
        if n < 3 {
            break;
        }
        cumulative.clear();
        cumulative.push(0.0);
        for i in 1..n {
            let d = space.distance(&points[wp(i - 1)], &points[wp(i)]);
            cumulative.push(cumulative[i - 1] + d);
        }
        let total = cumulative[n - 1];
        let (mut s1, mut s2) = (rng.random::<f64>() * total, rng.random::<f64>() * total);
        if s1 > s2 {
            std::mem::swap(&mut s1, &mut s2);
        }
        let i = segment_at(&cumulative, s1);
        let j = segment_at(&cumulative, s2);
        if j <= i {
            continue;
        }
        point_on(&points, dim, &cumulative, i, s1, &mut a);
        point_on(&points, dim, &cumulative, j, s2, &mut b);
        let (wi, wj) = (&points[wp(i)], &points[wp(j + 1)]);
        let new_len = space.distance(wi, &a) + space.distance(&a, &b) + space.distance(&b, wj);
        if new_len >= cumulative[j + 1] - cumulative[i] - options.min_gain * total {
            continue;
        }
        // `waypoint i → a` and `b → waypoint j + 1` lie on segments of the path (valid):
        // only the new segment needs a check.
        let valid = new_segment_valid(space, validity, &a, &b, options.probe, &mut work, checks);
        if valid {
            points.splice((i + 1) * dim..(j + 1) * dim, a.iter().chain(&b).copied());
        }
    }
    if options.drop_redundant {
        points = drop_redundant(
            space,
            validity,
            &points,
            dim,
            options.probe,
            &mut work,
            checks,
        );
    }
    Ok(JointPath::from_flat(dim, points))
}

/// The scratch space of the segment checks: the probed state and the stretches left.
#[derive(Default)]
struct Scratch {
    state: Vec<f64>,
    open: VecDeque<(usize, usize)>,
}

/// Whether a new segment `a → b` (its ends on the path, valid) is valid: with `probe =
/// Some(r)` its states at most `r` apart are probed first, coarse to fine (the middle,
/// then the middles of the halves), and the first invalid one ends the check; then the
/// segment check.
fn new_segment_valid(
    space: &JointSpace,
    validity: &mut impl StateValidity,
    a: &[f64],
    b: &[f64],
    probe: Option<f64>,
    work: &mut Scratch,
    checks: &mut u64,
) -> bool {
    if let Some(r) = probe {
        let n = (space.distance(a, b) / r).ceil().max(1.0) as usize;
        work.state.resize(a.len(), 0.0);
        work.open.clear();
        work.open.push_back((0, n));
        while let Some((lo, hi)) = work.open.pop_front() {
            if hi - lo < 2 {
                continue;
            }
            let mid = (lo + hi) / 2;
            let f = mid as f64 / n as f64;
            for ((s, x), y) in work.state.iter_mut().zip(a).zip(b) {
                *s = x + f * (y - x);
            }
            *checks += 1;
            if !validity.is_valid(&work.state) {
                return false;
            }
            work.open.push_back((lo, mid));
            work.open.push_back((mid, hi));
        }
    }
    space.segment_valid(validity, a, b, &mut work.state, checks)
}

/// The redundant-waypoint pass (module docs) over the flat waypoints `points`.
fn drop_redundant(
    space: &JointSpace,
    validity: &mut impl StateValidity,
    points: &[f64],
    dim: usize,
    probe: Option<f64>,
    work: &mut Scratch,
    checks: &mut u64,
) -> Vec<f64> {
    let wp = |i: usize| i * dim..(i + 1) * dim;
    let mut kept: Vec<f64> = Vec::with_capacity(points.len());
    let n = points.len() / dim;
    for k in 0..n {
        let here = &points[wp(k)];
        if k > 0 && k + 1 < n {
            let last = &kept[kept.len() - dim..];
            let next = &points[wp(k + 1)];
            if new_segment_valid(space, validity, last, next, probe, work, checks) {
                continue;
            }
        }
        kept.extend_from_slice(here);
    }
    kept
}

/// The segment `i` (from waypoint `i` to `i + 1`) holding arc length `s`.
fn segment_at(cumulative: &[f64], s: f64) -> usize {
    let n = cumulative.len();
    cumulative[1..n - 1].partition_point(|c| *c <= s).min(n - 2)
}

/// The point at arc length `s` on segment `i`.
fn point_on(points: &[f64], dim: usize, cumulative: &[f64], i: usize, s: f64, out: &mut [f64]) {
    let len = cumulative[i + 1] - cumulative[i];
    let f = if len > 0.0 {
        ((s - cumulative[i]) / len).clamp(0.0, 1.0)
    } else {
        0.0
    };
    let (p, q) = (
        &points[i * dim..(i + 1) * dim],
        &points[(i + 1) * dim..(i + 2) * dim],
    );
    for ((o, x), y) in out.iter_mut().zip(p).zip(q) {
        *o = x + f * (y - x);
    }
}

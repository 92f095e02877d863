//! The space an arm planner searches: a box of joint limits, a weighted Euclidean norm, the
//! resolution at which a straight segment is checked, the caller's state validity check
//! and the joint-space path the planner returns.
//!
//! **Norm.** `‖Δq‖_w = sqrt(Σ_i (w_i Δq_i)²)` with one positive weight per joint, so joints
//! of different units (a torso lift in metres beside arm joints in radians) can be put on
//! one scale; the weights default to 1.
//!
//! **Segment checks.** A straight segment `a → b` is checked at `n = ceil(‖b − a‖_w /
//! resolution)` evenly spaced states `a + k/n (b − a)`, `k = 1..=n` (the end included, the
//! start taken as already checked), so consecutive checked states are at most `resolution`
//! apart in that norm and every state of a checked segment lies within `resolution / 2`
//! of a checked valid state (an obstacle thinner than the resolution can be missed). The
//! check stops at the first invalid state.
//!
//! Joints are treated as intervals: a continuous joint gets a box from the caller (e.g.
//! `[-π, π]`) and the planner does not wrap around it.

use crate::{Error, Result, error::ensure_finite};

/// The most checked states one segment across the whole box may need (the box diagonal
/// over the resolution): bounds the time of a single segment check.
pub const MAX_STATES_PER_SEGMENT: f64 = 1e6;

/// A caller's state validity check (collision, self-collision, any constraint), `&mut` so
/// that it can keep its own workspace. It is only called with states inside the box.
pub trait StateValidity {
    /// Whether the joint state `q` (one value per joint of the space) is valid.
    fn is_valid(&mut self, q: &[f64]) -> bool;

    /// Whether the straight segment `a → b` is valid, `a` taken as already checked; adds
    /// the states checked to `checks`. The default checks states at the space's resolution
    /// ([`JointSpace::discrete_segment_valid`], module docs); a check that can vouch for a
    /// whole stretch of the segment from one state (a clearance bound, say) overrides it.
    fn segment_valid(
        &mut self,
        space: &JointSpace,
        a: &[f64],
        b: &[f64],
        scratch: &mut Vec<f64>,
        checks: &mut u64,
    ) -> bool {
        space.discrete_segment_valid(self, a, b, scratch, checks)
    }
}

impl<F: FnMut(&[f64]) -> bool> StateValidity for F {
    fn is_valid(&mut self, q: &[f64]) -> bool {
        self(q)
    }
}

/// A box of joint limits with a weighted norm and a segment-check resolution.
#[derive(Debug, Clone, PartialEq)]
pub struct JointSpace {
    lower: Vec<f64>,
    upper: Vec<f64>,
    weights: Vec<f64>,
    resolution: f64,
}

impl JointSpace {
    /// A space over `lower[i] ≤ q_i ≤ upper[i]`, weights 1, checked at `resolution`.
    pub fn new(lower: Vec<f64>, upper: Vec<f64>, resolution: f64) -> Result<Self> {
        let weights = vec![1.0; lower.len()];
        Self::with_weights(lower, upper, weights, resolution)
    }

    /// A space with per-joint weights in the norm (see the module docs).
    pub fn with_weights(
        lower: Vec<f64>,
        upper: Vec<f64>,
        weights: Vec<f64>,
        resolution: f64,
    ) -> Result<Self> {
        if lower.is_empty() {
            return Err(Error::invalid(
                "lower",
                "a joint space needs at least one joint",
            ));
        }
        crate::error::ensure_len("upper", lower.len(), upper.len())?;
        crate::error::ensure_len("weights", lower.len(), weights.len())?;
        ensure_finite("lower", &lower)?;
        ensure_finite("upper", &upper)?;
        ensure_finite("weights", &weights)?;
        ensure_finite("resolution", [&resolution])?;
        for (i, (lo, hi)) in lower.iter().zip(&upper).enumerate() {
            if lo > hi {
                return Err(Error::invalid(
                    format!("lower[{i}]"),
                    format!("{lo} is above upper[{i}] = {hi}"),
                ));
            }
        }
        if let Some(i) = weights.iter().position(|w| *w <= 0.0) {
            return Err(Error::invalid(
                format!("weights[{i}]"),
                format!("{} is not positive", weights[i]),
            ));
        }
        if resolution <= 0.0 {
            return Err(Error::invalid(
                "resolution",
                format!("{resolution} is not positive"),
            ));
        }
        let space = JointSpace {
            lower,
            upper,
            weights,
            resolution,
        };
        let diagonal = space.distance(&space.lower, &space.upper);
        if diagonal / resolution > MAX_STATES_PER_SEGMENT {
            return Err(Error::invalid(
                "resolution",
                format!(
                    "{resolution} needs {:.3e} states to cross the box (diagonal {diagonal}); \
                     at most {MAX_STATES_PER_SEGMENT:.0e}",
                    diagonal / resolution
                ),
            ));
        }
        Ok(space)
    }

    /// The number of joints.
    pub fn dim(&self) -> usize {
        self.lower.len()
    }

    /// The lower joint limits.
    pub fn lower(&self) -> &[f64] {
        &self.lower
    }

    /// The upper joint limits.
    pub fn upper(&self) -> &[f64] {
        &self.upper
    }

    /// The per-joint weights of the norm.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }

    /// The largest distance, in the weighted norm, between consecutive checked states.
    pub fn resolution(&self) -> f64 {
        self.resolution
    }

    /// The box diagonal in the weighted norm.
    pub fn diagonal(&self) -> f64 {
        self.distance(&self.lower, &self.upper)
    }

    /// `‖b − a‖_w`.
    pub fn distance(&self, a: &[f64], b: &[f64]) -> f64 {
        self.distance_squared(a, b).sqrt()
    }

    /// `‖b − a‖_w²`, summed in four interleaved partial sums (joints `k`, `k + 4`, … in
    /// the `k`-th) so that the compiler can use vector lanes: RRT-Connect's nearest-node
    /// scan runs it over every tree node.
    pub fn distance_squared(&self, a: &[f64], b: &[f64]) -> f64 {
        let mut acc = [0.0; 4];
        let lanes = a
            .chunks_exact(4)
            .zip(b.chunks_exact(4))
            .zip(self.weights.chunks_exact(4));
        for ((x, y), w) in lanes {
            for l in 0..4 {
                let d = w[l] * (y[l] - x[l]);
                acc[l] += d * d;
            }
        }
        let tail = a.len() - a.len() % 4;
        for (l, ((x, y), w)) in a[tail..]
            .iter()
            .zip(&b[tail..])
            .zip(&self.weights[tail..])
            .enumerate()
        {
            let d = w * (y - x);
            acc[l] += d * d;
        }
        (acc[0] + acc[2]) + (acc[1] + acc[3])
    }

    /// Whether `q` lies in the box.
    pub fn contains(&self, q: &[f64]) -> bool {
        q.len() == self.dim()
            && q.iter()
                .zip(self.lower.iter().zip(&self.upper))
                .all(|(x, (lo, hi))| lo <= x && x <= hi)
    }

    /// Checks a caller's state: its length, finiteness and the box; `field` names it.
    pub fn check_state(&self, field: &str, q: &[f64]) -> Result<()> {
        crate::error::ensure_len(field, self.dim(), q.len())?;
        ensure_finite(field, q)?;
        for (i, (x, (lo, hi))) in q.iter().zip(self.lower.iter().zip(&self.upper)).enumerate() {
            if x < lo || x > hi {
                return Err(Error::invalid(
                    format!("{field}[{i}]"),
                    format!("{x} is outside the joint limits [{lo}, {hi}]"),
                ));
            }
        }
        Ok(())
    }

    /// The number of steps a segment `a → b` is checked in (see the module docs).
    pub fn segment_steps(&self, a: &[f64], b: &[f64]) -> usize {
        (self.distance(a, b) / self.resolution).ceil() as usize
    }

    /// Checks the segment `a → b` with the validity check's own segment check
    /// ([`StateValidity::segment_valid`]; by default at the resolution, see the module
    /// docs), with `scratch` for the interpolated states; adds the number of states checked
    /// to `checks`. `a` itself is not checked.
    pub fn segment_valid(
        &self,
        validity: &mut impl StateValidity,
        a: &[f64],
        b: &[f64],
        scratch: &mut Vec<f64>,
        checks: &mut u64,
    ) -> bool {
        validity.segment_valid(self, a, b, scratch, checks)
    }

    /// Checks the segment `a → b` state by state at the resolution (see the module docs),
    /// with `scratch` (resized to the dimension) for the interpolated states; adds the
    /// number of states checked to `checks`. `a` itself is not checked.
    pub fn discrete_segment_valid<V: StateValidity + ?Sized>(
        &self,
        validity: &mut V,
        a: &[f64],
        b: &[f64],
        scratch: &mut Vec<f64>,
        checks: &mut u64,
    ) -> bool {
        let (valid, n) = self.discrete_valid_prefix(validity, a, b, scratch, checks);
        valid == n
    }

    /// Checks the segment `a → b` state by state at the resolution like
    /// [`Self::discrete_segment_valid`], from `a` on, and stops at the first invalid
    /// state: `(k, n)`, the segment's `n` steps of which the first `k` checked valid, so
    /// `a + k/n (b − a)` is the farthest state reached (`a` itself when `k` is 0).
    pub fn discrete_valid_prefix<V: StateValidity + ?Sized>(
        &self,
        validity: &mut V,
        a: &[f64],
        b: &[f64],
        scratch: &mut Vec<f64>,
        checks: &mut u64,
    ) -> (usize, usize) {
        let n = self.segment_steps(a, b);
        scratch.resize(self.dim(), 0.0);
        for k in 1..=n {
            let f = k as f64 / n as f64;
            for ((s, x), y) in scratch.iter_mut().zip(a).zip(b) {
                *s = if k == n { *y } else { x + f * (y - x) };
            }
            *checks += 1;
            if !validity.is_valid(scratch) {
                return (k - 1, n);
            }
        }
        (n, n)
    }
}

/// A joint-space path: waypoints joined by straight segments, stored flat.
#[derive(Debug, Clone, PartialEq)]
pub struct JointPath {
    dim: usize,
    points: Vec<f64>,
}

impl JointPath {
    /// A path of `points.len() / dim` waypoints stored one after the other.
    ///
    /// # Panics
    /// If `dim` is zero or does not divide `points.len()`.
    pub fn from_flat(dim: usize, points: Vec<f64>) -> Self {
        assert!(dim > 0 && points.len().is_multiple_of(dim), "path layout");
        JointPath { dim, points }
    }

    /// The number of joints.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// The number of waypoints.
    pub fn len(&self) -> usize {
        self.points.len() / self.dim
    }

    /// Whether the path has no waypoint.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Waypoint `i`.
    pub fn waypoint(&self, i: usize) -> &[f64] {
        &self.points[i * self.dim..(i + 1) * self.dim]
    }

    /// The waypoints one after the other.
    pub fn as_flat(&self) -> &[f64] {
        &self.points
    }

    /// The waypoints as one vector each.
    pub fn to_vecs(&self) -> Vec<Vec<f64>> {
        self.points.chunks(self.dim).map(<[f64]>::to_vec).collect()
    }

    /// The length in the space's weighted norm.
    pub fn length(&self, space: &JointSpace) -> f64 {
        (1..self.len())
            .map(|i| space.distance(self.waypoint(i - 1), self.waypoint(i)))
            .sum()
    }

    /// Whether every segment is valid at the space's resolution and the first waypoint is
    /// valid; adds the states checked to `checks`.
    pub fn is_valid(
        &self,
        space: &JointSpace,
        validity: &mut impl StateValidity,
        checks: &mut u64,
    ) -> bool {
        if self.is_empty() {
            return false;
        }
        *checks += 1;
        if !space.contains(self.waypoint(0)) || !validity.is_valid(self.waypoint(0)) {
            return false;
        }
        let mut scratch = Vec::with_capacity(self.dim);
        (1..self.len()).all(|i| {
            space.contains(self.waypoint(i))
                && space.segment_valid(
                    validity,
                    self.waypoint(i - 1),
                    self.waypoint(i),
                    &mut scratch,
                    checks,
                )
        })
    }
}

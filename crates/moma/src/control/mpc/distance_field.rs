//! The map the MPC keeps its base clear of: a grid of distances to the nearest obstacle,
//! sampled with bilinear interpolation, and the clearance of a disk footprint about the
//! base frame origin with its gradient in the base pose `(x, y, θ)`.
//!
//! The caller builds the field from its own map (`moma mission`: the planner's distance
//! transform, refreshed when obstacles appear); the MPC knows only this grid.

use crate::error::{Error, Result};

/// Distances (m) to the nearest obstacle at the centres of a grid's cells.
///
/// Cell `(i, j)` spans `[i, i + 1] × [j, j + 1]` resolutions in the grid's frame, whose
/// corner `(0, 0)` lies at the world pose `origin`; its value is the distance at its
/// centre. Between centres the distance is bilinear; beyond the outer centres it is the
/// border's (clamped). `+∞` where the map has no obstacle.
#[derive(Clone, Debug, PartialEq)]
pub struct DistanceField {
    /// Cells along the grid's x axis.
    pub width: usize,
    /// Cells along the grid's y axis.
    pub height: usize,
    /// Cell side (m).
    pub resolution: f64,
    /// World pose `(x, y, yaw)` of the grid's corner `(0, 0)`.
    pub origin: [f64; 3],
    /// Distance (m) at each cell centre, row by row (`j · width + i`).
    pub distance: Vec<f64>,
}

impl DistanceField {
    /// A field of `distance` (m, `width · height` values, row by row; `+∞`: no
    /// obstacle) on a grid of `resolution` (m) with its corner at `origin`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for an empty grid, a wrong number of values, a NaN value,
    /// a resolution that is not positive and finite, or a non-finite origin.
    pub fn new(
        width: usize,
        height: usize,
        resolution: f64,
        origin: [f64; 3],
        distance: Vec<f64>,
    ) -> Result<Self> {
        if width == 0 || height == 0 || distance.len() != width * height {
            return Err(Error::invalid(
                "distance field",
                format!("{} values for a {width} × {height} grid", distance.len()),
            ));
        }
        if !(resolution > 0.0 && resolution.is_finite()) {
            return Err(Error::invalid(
                "distance field resolution",
                format!("must be positive, got {resolution}"),
            ));
        }
        if origin.iter().any(|v| !v.is_finite()) || distance.iter().any(|v| v.is_nan()) {
            return Err(Error::invalid(
                "distance field",
                "origin and distances must be numbers",
            ));
        }
        Ok(Self {
            width,
            height,
            resolution,
            origin,
            distance,
        })
    }

    /// The distance (m) at the world point `(x, y)` and its gradient in `(x, y)`; `+∞`
    /// with a zero gradient where a cell of the interpolation has no obstacle in reach.
    /// The gradient is that of the bilinear patch the point lies in (one-sided on a
    /// patch's edge), zero across the clamped border.
    #[must_use]
    pub fn sample(&self, x: f64, y: f64) -> (f64, [f64; 2]) {
        let res = self.resolution;
        let (s, c) = self.origin[2].sin_cos();
        let (dx, dy) = (x - self.origin[0], y - self.origin[1]);
        // Grid coordinates in cells, measured from the centre of cell (0, 0).
        let gu = (c * dx + s * dy) / res - 0.5;
        let gv = (-s * dx + c * dy) / res - 0.5;
        let (i0, fu, inside_u) = patch(gu, self.width);
        let (j0, fv, inside_v) = patch(gv, self.height);
        let i1 = (i0 + 1).min(self.width - 1);
        let j1 = (j0 + 1).min(self.height - 1);
        let at = |i: usize, j: usize| self.distance[j * self.width + i];
        let (d00, d10, d01, d11) = (at(i0, j0), at(i1, j0), at(i0, j1), at(i1, j1));
        if [d00, d10, d01, d11].iter().any(|d| !d.is_finite()) {
            return (f64::INFINITY, [0.0, 0.0]);
        }
        let value = d00 * (1.0 - fu) * (1.0 - fv)
            + d10 * fu * (1.0 - fv)
            + d01 * (1.0 - fu) * fv
            + d11 * fu * fv;
        // ∂/∂(grid metres) of the patch, zero along a clamped axis.
        let du = if inside_u {
            ((d10 - d00) * (1.0 - fv) + (d11 - d01) * fv) / res
        } else {
            0.0
        };
        let dv = if inside_v {
            ((d01 - d00) * (1.0 - fu) + (d11 - d10) * fu) / res
        } else {
            0.0
        };
        // The grid's axes in the world: u = (c, s), v = (−s, c).
        (value, [c * du - s * dv, s * du + c * dv])
    }
}

/// The patch along one axis of `n` centres holding the coordinate `g` (cells from the
/// first centre): its first centre, the fraction across it, and whether `g` lies
/// between the outer centres (else it is clamped to the border).
fn patch(g: f64, n: usize) -> (usize, f64, bool) {
    let last = (n - 1) as f64;
    if n == 1 || !(g > 0.0 && g < last) {
        let clamped = g.clamp(0.0, last);
        let i = (clamped.floor() as usize).min(n.saturating_sub(2));
        return (i, clamped - i as f64, false);
    }
    let i = (g.floor() as usize).min(n - 2);
    (i, g - i as f64, true)
}

/// The map-clearance constraint's geometry: a disk footprint of `footprint_radius`
/// about the base frame origin on a [`DistanceField`].
#[derive(Clone, Debug, PartialEq)]
pub struct MapClearance {
    /// The distances to the map's obstacles.
    pub field: DistanceField,
    /// Radius of the disk about the base frame origin that covers the base (m).
    pub footprint_radius: f64,
}

impl MapClearance {
    /// The clearance (m) of the footprint with the base frame at the pose
    /// `(x, y, θ)`, the field's distance at the disk's centre less its radius, and its
    /// gradient in `(x, y, θ)`. The state's base point is the base frame origin, the
    /// disk's centre, so θ does not move the centre and `∂/∂θ = 0` (a disk offset by
    /// `o` in the base frame would add `∇d · R'(θ) o`).
    #[must_use]
    pub fn at(&self, pose: [f64; 3]) -> (f64, [f64; 3]) {
        let (d, g) = self.field.sample(pose[0], pose[1]);
        (d - self.footprint_radius, [g[0], g[1], 0.0])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bilinear_between_centres_and_clamped_outside() {
        // 2 × 2 cells of 0.5 m, centres at (0.25, 0.25) … (0.75, 0.75).
        let f = DistanceField::new(2, 2, 0.5, [0.0, 0.0, 0.0], vec![1.0, 2.0, 3.0, 4.0]).unwrap();
        let (d, g) = f.sample(0.5, 0.5);
        assert!((d - 2.5).abs() < 1e-12, "{d}");
        assert!(
            (g[0] - 2.0).abs() < 1e-12 && (g[1] - 4.0).abs() < 1e-12,
            "{g:?}"
        );
        let (d, g) = f.sample(-1.0, 0.25);
        assert!((d - 1.0).abs() < 1e-12 && g[0] == 0.0, "{d} {g:?}");
        let inf = DistanceField::new(1, 1, 1.0, [0.0; 3], vec![f64::INFINITY]).unwrap();
        assert_eq!(inf.sample(0.3, 0.3), (f64::INFINITY, [0.0, 0.0]));
        assert!(DistanceField::new(2, 2, 0.5, [0.0; 3], vec![1.0; 3]).is_err());
        assert!(DistanceField::new(1, 1, 0.0, [0.0; 3], vec![1.0]).is_err());
    }

    /// The clearance's gradient in `(x, y, θ)` against central differences, at random
    /// poses away from the patch edges (where the bilinear field has kinks), on a
    /// distance transform of scattered obstacles on a grid turned by 0.4 rad.
    #[test]
    fn clearance_gradient_matches_central_differences() {
        use rand::{Rng, SeedableRng};
        let (w, h, res) = (40, 30, 0.1);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        let mut occupied = vec![false; w * h];
        for _ in 0..25 {
            occupied[rng.random_range(0..w * h)] = true;
        }
        // Centre-to-centre distance (cells) to the nearest occupied cell.
        let dist: Vec<f64> = (0..w * h)
            .map(|i| {
                (0..w * h)
                    .filter(|&o| occupied[o])
                    .map(|o| {
                        let (dx, dy) = (
                            (i % w) as f64 - (o % w) as f64,
                            (i / w) as f64 - (o / w) as f64,
                        );
                        dx.hypot(dy)
                    })
                    .fold(f64::INFINITY, f64::min)
            })
            .collect();
        let origin = [1.5, -2.0, 0.4];
        let field =
            DistanceField::new(w, h, res, origin, dist.iter().map(|&d| d * res).collect()).unwrap();
        let map = MapClearance {
            field,
            footprint_radius: 0.3,
        };
        let (s, c) = origin[2].sin_cos();
        let mut checked = 0;
        while checked < 200 {
            // A point by its grid coordinates (cells from centre (0, 0)), kept 0.1 cell
            // off every patch edge.
            let gu = rng.random_range(0.0..(w - 1) as f64);
            let gv = rng.random_range(0.0..(h - 1) as f64);
            if [gu.fract(), gv.fract()]
                .iter()
                .any(|f| !(0.1..=0.9).contains(f))
            {
                continue;
            }
            let (lu, lv) = ((gu + 0.5) * res, (gv + 0.5) * res);
            let pose = [
                origin[0] + c * lu - s * lv,
                origin[1] + s * lu + c * lv,
                rng.random_range(-3.0..3.0),
            ];
            let (value, grad) = map.at(pose);
            assert!(value.is_finite());
            let step = 1e-6;
            for (i, g) in grad.iter().enumerate() {
                let (mut hi, mut lo) = (pose, pose);
                hi[i] += step;
                lo[i] -= step;
                let fd = (map.at(hi).0 - map.at(lo).0) / (2.0 * step);
                assert!(
                    (fd - g).abs() < 1e-6,
                    "pose {pose:?}, coordinate {i}: gradient {g}, differences {fd}"
                );
            }
            checked += 1;
        }
    }
}

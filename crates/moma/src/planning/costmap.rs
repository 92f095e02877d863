//! Configuration space from an occupancy grid: dilation by a disk (one distance
//! transform, whatever the radius), a nav2-style inflation cost layer, and a polygonal
//! footprint by per-heading dilation.

use super::edt::distance_transform;
use crate::{Error, Result};

/// nav2 `FREE_SPACE`.
pub const FREE_SPACE: u8 = 0;
/// nav2 `MAX_NON_OBSTACLE`: the highest cost a robot centre may occupy.
pub const MAX_NON_OBSTACLE: u8 = 252;
/// nav2 `INSCRIBED_INFLATED_OBSTACLE`: the robot centre here means a collision.
pub const INSCRIBED: u8 = 253;
/// nav2 `LETHAL_OBSTACLE`: an obstacle cell.
pub const LETHAL: u8 = 254;
/// nav2 `NO_INFORMATION`: unknown cell.
pub const NO_INFORMATION: u8 = 255;

/// Dilates obstacles by a disk: a cell is in the C-space obstacle if its centre lies
/// within `radius_cells` of an obstacle cell's centre (`dist ≤ radius`), `dist` being the
/// output of [`distance_transform`].
#[doc(alias = "c_space")]
#[doc(alias = "configuration_space")]
pub fn dilate_disk(dist: &[f32], radius_cells: f64) -> Vec<bool> {
    let r = radius_cells as f32;
    dist.iter().map(|&d| d <= r).collect()
}

/// Convenience: obstacle mask → distance transform → disk dilation.
pub fn inflate(obstacles: &[bool], width: usize, height: usize, radius_cells: f64) -> Result<Vec<bool>> {
    if !(radius_cells.is_finite() && radius_cells >= 0.0) {
        return Err(Error::invalid("robot radius", format!("must be finite and >= 0, got {radius_cells}")));
    }
    crate::error::ensure_len("obstacle mask", width * height, obstacles.len())?;
    Ok(dilate_disk(&distance_transform(obstacles, width, height), radius_cells))
}

/// Parameters of the inflation layer (nav2 `InflationLayer`; lengths in metres).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct InflationParams {
    /// Radius of the largest circle inside the footprint (m).
    pub inscribed_radius: f64,
    /// Distance up to which costs decay (nav2 default 0.55 m).
    pub inflation_radius: f64,
    /// Exponential decay rate (nav2 default 10 1/m).
    pub cost_scaling_factor: f64,
}

impl InflationParams {
    /// nav2's defaults (`inflation_radius` 0.55 m, `cost_scaling_factor` 10) with the
    /// given inscribed radius.
    pub fn nav2_defaults(inscribed_radius: f64) -> Self {
        Self { inscribed_radius, inflation_radius: 0.55, cost_scaling_factor: 10.0 }
    }

    fn validate(&self) -> Result<()> {
        for (n, v) in [
            ("inscribed_radius", self.inscribed_radius),
            ("inflation_radius", self.inflation_radius),
            ("cost_scaling_factor", self.cost_scaling_factor),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(n, format!("must be finite and >= 0, got {v}")));
            }
        }
        Ok(())
    }
}

/// nav2 `InflationLayer::computeCost` for a distance of `d_cells` cells.
#[inline]
pub fn inflation_cost(d_cells: f64, resolution: f64, p: &InflationParams) -> u8 {
    let d = d_cells * resolution;
    if d_cells == 0.0 {
        LETHAL
    } else if d <= p.inscribed_radius {
        INSCRIBED
    } else if d > p.inflation_radius {
        FREE_SPACE
    } else {
        let factor = (-p.cost_scaling_factor * (d - p.inscribed_radius)).exp();
        ((INSCRIBED - 1) as f64 * factor) as u8
    }
}

/// The inflation cost layer over an occupancy grid: 254 on obstacles, 253 within the
/// inscribed radius, `252 · exp(−k (d − r_in))` out to the inflation radius, 0 beyond.
/// Unknown cells (when `unknown` marks them) stay 255 unless the inflated cost reaches
/// 253 (nav2 with `inflate_unknown: false`). Distances come from one exact EDT (as nav2
/// since 2026), evaluated through a lookup table on the squared distance.
pub fn inflation_layer(
    obstacles: &[bool],
    unknown: Option<&[bool]>,
    width: usize,
    height: usize,
    resolution: f64,
    params: &InflationParams,
) -> Result<Vec<u8>> {
    params.validate()?;
    if !(resolution.is_finite() && resolution > 0.0) {
        return Err(Error::invalid("resolution", format!("must be positive, got {resolution}")));
    }
    crate::error::ensure_len("obstacle mask", width * height, obstacles.len())?;
    if let Some(u) = unknown {
        crate::error::ensure_len("unknown mask", width * height, u.len())?;
    }
    let dist = distance_transform(obstacles, width, height);
    Ok(dist
        .iter()
        .enumerate()
        .map(|(i, &d)| {
            let c = if d.is_finite() { inflation_cost(d as f64, resolution, params) } else { FREE_SPACE };
            match unknown {
                Some(u) if u[i] && c < INSCRIBED => NO_INFORMATION,
                _ => c,
            }
        })
        .collect())
}

/// A robot footprint: a simple polygon in the robot frame (metres), containing the
/// robot's reference point (the origin).
#[derive(Debug, Clone, PartialEq)]
pub struct Footprint {
    /// Vertices in order (either orientation).
    pub vertices: Vec<[f64; 2]>,
}

impl Footprint {
    /// Validates and builds a footprint.
    pub fn new(vertices: Vec<[f64; 2]>) -> Result<Self> {
        if vertices.len() < 3 {
            return Err(Error::invalid("footprint", format!("needs at least 3 vertices, got {}", vertices.len())));
        }
        if vertices.iter().flatten().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite { field: "footprint".into() });
        }
        let f = Self { vertices };
        if !f.contains(0.0, 0.0) {
            return Err(Error::invalid("footprint", "the polygon must contain the robot's origin (0, 0)"));
        }
        Ok(f)
    }

    /// Parses `"x1,y1;x2,y2;..."` or the nav2 style `"[[x1, y1], [x2, y2], ...]"`.
    pub fn parse(text: &str) -> Result<Self> {
        let nums: Vec<f64> = text
            .split(|c: char| c == ',' || c == ';' || c == '[' || c == ']' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .map(|s| s.parse::<f64>().map_err(|_| Error::invalid("footprint", format!("'{s}' is not a number"))))
            .collect::<Result<_>>()?;
        if nums.len() % 2 != 0 {
            return Err(Error::invalid("footprint", "expected x,y pairs"));
        }
        Self::new(nums.chunks(2).map(|c| [c[0], c[1]]).collect())
    }

    /// Point-in-polygon test (boundary counts as inside).
    pub fn contains(&self, x: f64, y: f64) -> bool {
        let v = &self.vertices;
        let n = v.len();
        let mut inside = false;
        for i in 0..n {
            let (a, b) = (v[i], v[(i + 1) % n]);
            // On the edge?
            let cross = (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]);
            let within = (x - a[0]) * (x - b[0]) <= 1e-12 && (y - a[1]) * (y - b[1]) <= 1e-12;
            if cross.abs() <= 1e-12 * (1.0 + (b[0] - a[0]).abs() + (b[1] - a[1]).abs()) && within {
                return true;
            }
            if (a[1] > y) != (b[1] > y) {
                let xi = a[0] + (y - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
                if x < xi {
                    inside = !inside;
                }
            }
        }
        inside
    }

    /// Radius of the largest origin-centred circle inside the polygon (nav2's inscribed
    /// radius): the distance from the origin to the nearest edge.
    pub fn inscribed_radius(&self) -> f64 {
        let v = &self.vertices;
        (0..v.len())
            .map(|i| point_segment_distance([0.0, 0.0], v[i], v[(i + 1) % v.len()]))
            .fold(f64::INFINITY, f64::min)
    }

    /// Distance from the origin to the farthest vertex.
    pub fn circumscribed_radius(&self) -> f64 {
        self.vertices.iter().map(|p| p[0].hypot(p[1])).fold(0.0, f64::max)
    }

    /// Integer cell offsets `(dx, dy)` whose centres lie inside the footprint rotated by
    /// `theta`, for cells of size `resolution`.
    pub fn cell_offsets(&self, theta: f64, resolution: f64) -> Vec<(i64, i64)> {
        let (s, c) = theta.sin_cos();
        let r = (self.circumscribed_radius() / resolution).ceil() as i64 + 1;
        let mut out = Vec::new();
        for dy in -r..=r {
            for dx in -r..=r {
                let (wx, wy) = (dx as f64 * resolution, dy as f64 * resolution);
                // Rotate the offset back into the robot frame.
                let (bx, by) = (c * wx + s * wy, -s * wx + c * wy);
                if self.contains(bx, by) {
                    out.push((dx, dy));
                }
            }
        }
        out
    }
}

fn point_segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (abx, aby) = (b[0] - a[0], b[1] - a[1]);
    let len2 = abx * abx + aby * aby;
    let t = if len2 > 0.0 { (((p[0] - a[0]) * abx + (p[1] - a[1]) * aby) / len2).clamp(0.0, 1.0) } else { 0.0 };
    (p[0] - a[0] - t * abx).hypot(p[1] - a[1] - t * aby)
}

/// The (x, y, θ) configuration space of a polygonal robot: one dilated obstacle mask per
/// heading `θ_k = 2πk / headings`, plus one per rotation `θ_k → θ_{k+1}` (the footprint
/// swept by the turn, sampled every ≤ 3°).
#[derive(Debug, Clone, PartialEq)]
pub struct FootprintCSpace {
    /// Number of headings.
    pub headings: usize,
    /// Grid width.
    pub width: usize,
    /// Grid height.
    pub height: usize,
    /// `slices[k][y * width + x]` = robot at (x, y) with heading θ_k collides.
    pub slices: Vec<Vec<bool>>,
    /// `sweeps[k]` = turning in place from θ_k to θ_{k+1} at (x, y) collides.
    pub sweeps: Vec<Vec<bool>>,
}

/// Builds the per-heading C-space of `footprint` (`resolution` m/cell). A robot pose
/// collides when an obstacle cell centre lies inside the footprint (cells outside the
/// map are not obstacles, as for the disk dilation). Cells closer to an obstacle than the
/// inscribed radius are blocked and cells farther than the circumscribed radius are free
/// at every heading, so the exact footprint test only runs in the band between.
pub fn footprint_cspace(
    obstacles: &[bool],
    width: usize,
    height: usize,
    resolution: f64,
    footprint: &Footprint,
    headings: usize,
) -> Result<FootprintCSpace> {
    if headings < 4 || headings > 360 {
        return Err(Error::invalid("headings", format!("must be in 4..=360, got {headings}")));
    }
    crate::error::ensure_len("obstacle mask", width * height, obstacles.len())?;
    let dist = distance_transform(obstacles, width, height);
    let r_in = footprint.inscribed_radius() / resolution;
    let r_out = footprint.circumscribed_radius() / resolution;
    let step = std::f64::consts::TAU / headings as f64;
    let dilate = |offsets: &[(i64, i64)]| -> Vec<bool> {
        let mut out = vec![false; width * height];
        for y in 0..height {
            for x in 0..width {
                let i = y * width + x;
                let d = dist[i] as f64;
                out[i] = if d <= r_in {
                    true
                } else if d > r_out + 1e-9 {
                    false
                } else {
                    offsets.iter().any(|&(dx, dy)| {
                        let (ox, oy) = (x as i64 + dx, y as i64 + dy);
                        ox >= 0 && oy >= 0 && (ox as usize) < width && (oy as usize) < height && obstacles[oy as usize * width + ox as usize]
                    })
                };
            }
        }
        out
    };
    let mut slices = Vec::with_capacity(headings);
    let mut sweeps = Vec::with_capacity(headings);
    let sub = ((step.to_degrees() / 3.0).ceil() as usize).max(1);
    for k in 0..headings {
        let theta = k as f64 * step;
        slices.push(dilate(&footprint.cell_offsets(theta, resolution)));
        let mut swept: Vec<(i64, i64)> = (0..=sub)
            .flat_map(|j| footprint.cell_offsets(theta + step * j as f64 / sub as f64, resolution))
            .collect();
        swept.sort_unstable();
        swept.dedup();
        sweeps.push(dilate(&swept));
    }
    Ok(FootprintCSpace { headings, width, height, slices, sweeps })
}

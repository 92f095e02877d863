//! Configuration space from an occupancy grid: dilation by a disk (one distance
//! transform, whatever the radius), a nav2-style inflation cost layer, and a polygonal
//! footprint by per-heading dilation. Both take an occupied cell as the square it covers,
//! not as its centre point.

use super::edt::distance_transform;
use crate::{Error, Result};

// The cost values are the grid's vocabulary (nav2's `cost_values.hpp`); re-exported here
// because the cost layer is where users meet them.
pub use super::grid::{FREE_SPACE, INSCRIBED, LETHAL, MAX_NON_OBSTACLE, NO_INFORMATION};

/// The centre-to-centre distance (cells) within which an obstacle cell blocks the centre of
/// a cell for a disk robot of `radius_cells`: the radius plus half a cell.
///
/// An occupied cell is a square of side one cell, not a point at its centre: the disk at a
/// cell centre touches the square of an obstacle cell `dist` cells away (centre to centre)
/// when `dist − ½ ≤ radius` along the grid's axes (the square's near edge lies half a cell
/// short of its centre), and diagonally when `dist − ½·√2 ≤ radius`. The rule
/// `dist ≤ radius + ½` is therefore exact along the axes and misses at most
/// ½·√2 − ½ ≈ 0.21 cells of overlap diagonally, where `dist ≤ radius` (the obstacle as its
/// centre point) would miss up to 0.71 cells everywhere. It is the distance the mission's
/// clearance and footprint-polygon checks, which measure to the occupied cells' edges,
/// agree with.
#[must_use]
pub fn disk_reach(radius_cells: f64) -> f64 {
    radius_cells + 0.5
}

/// Dilates obstacles by a disk: a cell is in the C-space obstacle if its centre lies
/// within [`disk_reach`]`(radius_cells)` (the radius plus half a cell) of an obstacle
/// cell's centre, `dist` being the output of [`distance_transform`].
#[doc(alias = "c_space")]
#[doc(alias = "configuration_space")]
pub fn dilate_disk(dist: &[f32], radius_cells: f64) -> Vec<bool> {
    let r = disk_reach(radius_cells);
    dist.iter().map(|&d| f64::from(d) <= r).collect()
}

/// Convenience: obstacle mask → distance transform → disk dilation.
pub fn inflate(
    obstacles: &[bool],
    width: usize,
    height: usize,
    radius_cells: f64,
) -> Result<Vec<bool>> {
    if !(radius_cells.is_finite() && radius_cells >= 0.0) {
        return Err(Error::invalid(
            "robot radius",
            format!("must be finite and >= 0, got {radius_cells}"),
        ));
    }
    crate::error::ensure_len("obstacle mask", width * height, obstacles.len())?;
    Ok(dilate_disk(
        &distance_transform(obstacles, width, height),
        radius_cells,
    ))
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
        Self {
            inscribed_radius,
            inflation_radius: 0.55,
            cost_scaling_factor: 10.0,
        }
    }

    fn validate(&self) -> Result<()> {
        for (n, v) in [
            ("inscribed_radius", self.inscribed_radius),
            ("inflation_radius", self.inflation_radius),
            ("cost_scaling_factor", self.cost_scaling_factor),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(Error::invalid(
                    n,
                    format!("must be finite and >= 0, got {v}"),
                ));
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
        return Err(Error::invalid(
            "resolution",
            format!("must be positive, got {resolution}"),
        ));
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
            let c = if d.is_finite() {
                inflation_cost(d as f64, resolution, params)
            } else {
                FREE_SPACE
            };
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
            return Err(Error::invalid(
                "footprint",
                format!("needs at least 3 vertices, got {}", vertices.len()),
            ));
        }
        if vertices.iter().flatten().any(|v| !v.is_finite()) {
            return Err(Error::NonFinite {
                field: "footprint".into(),
            });
        }
        let f = Self { vertices };
        let v = &f.vertices;
        let twice_area: f64 = (0..v.len())
            .map(|i| {
                let (a, b) = (v[i], v[(i + 1) % v.len()]);
                a[0] * b[1] - b[0] * a[1]
            })
            .sum();
        if !(twice_area.abs() > 0.0 && twice_area.is_finite()) {
            return Err(Error::invalid(
                "footprint",
                "the polygon must have a finite, non-zero area",
            ));
        }
        if !f.contains(0.0, 0.0) {
            return Err(Error::invalid(
                "footprint",
                "the polygon must contain the robot's origin (0, 0)",
            ));
        }
        Ok(f)
    }

    /// Parses `"x1,y1;x2,y2;..."` or the nav2 style `"[[x1, y1], [x2, y2], ...]"`.
    pub fn parse(text: &str) -> Result<Self> {
        let nums: Vec<f64> = text
            .split(|c: char| c == ',' || c == ';' || c == '[' || c == ']' || c.is_whitespace())
            .filter(|s| !s.is_empty())
            .map(|s| {
                s.parse::<f64>()
                    .map_err(|_| Error::invalid("footprint", format!("'{s}' is not a number")))
            })
            .collect::<Result<_>>()?;
        if !nums.len().is_multiple_of(2) {
            return Err(Error::invalid("footprint", "expected x,y pairs"));
        }
        Self::new(nums.chunks(2).map(|c| [c[0], c[1]]).collect())
    }

    /// Point-in-polygon test (boundary counts as inside).
    pub fn contains(&self, x: f64, y: f64) -> bool {
        polygon_contains(&self.vertices, x, y)
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
        self.vertices
            .iter()
            .map(|p| p[0].hypot(p[1]))
            .fold(0.0, f64::max)
    }

    /// Integer cell offsets `(dx, dy)` whose cells meet the footprint rotated by `theta`,
    /// for cells of size `resolution`: the cell at `(dx, dy)` is the square of side one
    /// cell centred `(dx, dy)` cells from the footprint's origin, and it counts when the
    /// rotated polygon and the square share a point (touching counts, so a footprint that
    /// clips only a corner of an occupied cell collides with it).
    pub fn cell_offsets(&self, theta: f64, resolution: f64) -> Vec<(i64, i64)> {
        let (s, c) = theta.sin_cos();
        // the polygon rotated into the grid's axes, in cells
        let poly: Vec<[f64; 2]> = self
            .vertices
            .iter()
            .map(|p| {
                [
                    (c * p[0] - s * p[1]) / resolution,
                    (s * p[0] + c * p[1]) / resolution,
                ]
            })
            .collect();
        let r = (self.circumscribed_radius() / resolution + std::f64::consts::FRAC_1_SQRT_2).ceil()
            as i64;
        cells_meeting(&poly, [-r, r], [-r, r], 0.0, CellContact::Touching)
    }
}

/// When a polygon counts as covering a cell's square.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CellContact {
    /// A cell the polygon touches counts (the square widened by [`CELL_CONTACT_SLACK`],
    /// so that rounding never misses a touch): the footprint C-space's conservative rule,
    /// a footprint that clips only a corner of an occupied cell collides with it.
    Touching,
    /// Only a cell the polygon enters counts (the square narrowed by [`TOUCH`]): the
    /// rasterisation of an obstacle's outline, whose edge on a cell boundary, off by
    /// rounding, only touches the cell beyond.
    Overlapping,
}

impl CellContact {
    /// Half the side (cells) of the square tested for a cell.
    fn half_side(self) -> f64 {
        match self {
            Self::Touching => 0.5 + CELL_CONTACT_SLACK,
            Self::Overlapping => 0.5 - TOUCH,
        }
    }
}

/// How far (cells) a cell's square is widened for [`CellContact::Touching`]: far below
/// any map's resolution, far above the rounding of a rotation.
const CELL_CONTACT_SLACK: f64 = 1e-9;

/// How deep (cells) a polygon must enter a cell for [`CellContact::Overlapping`] to
/// count it.
pub const TOUCH: f64 = 1e-9;

/// The cells of a `width` × `height` grid (cell `(x, y)` covers `[x, x + 1] × [y, y + 1]`)
/// that the simple polygon `vertices` (continuous cell coordinates, either orientation)
/// covers under `contact`, as `(x, y)` row by row: with [`CellContact::Overlapping`] the
/// rasterisation of an obstacle's outline. None for fewer than three vertices.
#[must_use]
pub fn polygon_cells(
    vertices: &[[f64; 2]],
    width: usize,
    height: usize,
    contact: CellContact,
) -> Vec<(usize, usize)> {
    if vertices.len() < 3 {
        return Vec::new();
    }
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for v in vertices {
        for k in 0..2 {
            lo[k] = lo[k].min(v[k]);
            hi[k] = hi[k].max(v[k]);
        }
    }
    // the cells whose squares, widened for a touch, meet the bounding box
    let span = |a: f64, b: f64, n: usize| {
        let first = (a - CELL_CONTACT_SLACK).floor().max(0.0);
        let last = (b + CELL_CONTACT_SLACK).floor().min(n as f64 - 1.0);
        (first <= last).then_some([first as i64, last as i64])
    };
    let (Some(xs), Some(ys)) = (span(lo[0], hi[0], width), span(lo[1], hi[1], height)) else {
        return Vec::new();
    };
    cells_meeting(vertices, xs, ys, 0.5, contact)
        .into_iter()
        .map(|(x, y)| (x as usize, y as usize))
        .collect()
}

/// The cells `(x, y)`, `x` in `xs[0]..=xs[1]` and `y` in `ys[0]..=ys[1]`, row by row,
/// whose square, centred at `(x + centre, y + centre)`, the polygon `poly` meets under
/// `contact`: an edge crosses or touches the square (which also finds a polygon inside
/// the square), or the square lies inside the polygon (its centre does). The one
/// cover of cells by a polygon: the footprint's stencil ([`Footprint::cell_offsets`],
/// centred on the offsets) and the outline's cells ([`polygon_cells`]).
fn cells_meeting(
    poly: &[[f64; 2]],
    xs: [i64; 2],
    ys: [i64; 2],
    centre: f64,
    contact: CellContact,
) -> Vec<(i64, i64)> {
    let h = contact.half_side();
    let n = poly.len();
    let mut out = Vec::new();
    for y in ys[0]..=ys[1] {
        for x in xs[0]..=xs[1] {
            let (cx, cy) = (x as f64 + centre, y as f64 + centre);
            let (lo, hi) = ([cx - h, cy - h], [cx + h, cy + h]);
            if (0..n).any(|i| segment_meets_box(poly[i], poly[(i + 1) % n], lo, hi))
                || polygon_contains(poly, cx, cy)
            {
                out.push((x, y));
            }
        }
    }
    out
}

/// Point-in-polygon test of a simple polygon (either orientation; the boundary counts as
/// inside).
fn polygon_contains(v: &[[f64; 2]], x: f64, y: f64) -> bool {
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

/// Whether the segment `a`–`b` meets the closed axis-aligned box `lo`–`hi` (the
/// segment clipped to the box's slabs, Liang–Barsky).
fn segment_meets_box(a: [f64; 2], b: [f64; 2], lo: [f64; 2], hi: [f64; 2]) -> bool {
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..2 {
        let d = b[k] - a[k];
        if d == 0.0 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return false;
            }
        } else {
            let (ta, tb) = ((lo[k] - a[k]) / d, (hi[k] - a[k]) / d);
            t0 = t0.max(ta.min(tb));
            t1 = t1.min(ta.max(tb));
            if t0 > t1 {
                return false;
            }
        }
    }
    true
}

fn point_segment_distance(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let (abx, aby) = (b[0] - a[0], b[1] - a[1]);
    let len2 = abx * abx + aby * aby;
    let t = if len2 > 0.0 {
        (((p[0] - a[0]) * abx + (p[1] - a[1]) * aby) / len2).clamp(0.0, 1.0)
    } else {
        0.0
    };
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

/// Most cells (one byte each) that [`footprint_cspace`] allocates: one mask per heading
/// and one per turn, `2 · headings · width · height` (1 GiB).
pub const MAX_FOOTPRINT_CSPACE_CELLS: usize = 1 << 30;

/// Most (x, y, heading) states [`astar_footprint`] allocates (13 bytes each: 1.7 GB).
pub const MAX_FOOTPRINT_STATES: usize = 1 << 27;

/// Builds the per-heading C-space of `footprint` (`resolution` m/cell). A robot pose (at
/// a cell centre) collides when the footprint meets an obstacle cell, taken as the
/// square it covers ([`Footprint::cell_offsets`]; cells outside the map are not
/// obstacles, as for the disk dilation): conservative, a corner clipped counts. Cells
/// whose nearest obstacle centre lies within the inscribed radius plus half a cell
/// ([`disk_reach`]: the inscribed disk then reaches the square) are blocked and cells
/// farther than the circumscribed radius plus half a cell's diagonal are free at every
/// heading, so the exact footprint test only runs in the band between.
pub fn footprint_cspace(
    obstacles: &[bool],
    width: usize,
    height: usize,
    resolution: f64,
    footprint: &Footprint,
    headings: usize,
) -> Result<FootprintCSpace> {
    check_cspace_size(width, height, headings)?;
    crate::error::ensure_len("obstacle mask", width * height, obstacles.len())?;
    let dist = distance_transform(obstacles, width, height);
    footprint_cspace_with_distance(
        obstacles, &dist, width, height, resolution, footprint, headings,
    )
}

/// The heading count and the C-space's size checked before anything is allocated.
fn check_cspace_size(width: usize, height: usize, headings: usize) -> Result<()> {
    if !(4..=360).contains(&headings) {
        return Err(Error::invalid(
            "headings",
            format!("must be in 4..=360, got {headings}"),
        ));
    }
    let cells = width
        .checked_mul(height)
        .and_then(|n| n.checked_mul(2 * headings))
        .filter(|&n| n <= MAX_FOOTPRINT_CSPACE_CELLS);
    if cells.is_none() {
        return Err(Error::invalid(
            "footprint C-space",
            format!(
                "{width} x {height} cells x {headings} headings x 2 (poses and turns) exceeds \
                 the limit of {MAX_FOOTPRINT_CSPACE_CELLS} cells; use a coarser map or fewer \
                 headings"
            ),
        ));
    }
    Ok(())
}

/// [`footprint_cspace`] on the caller's [`distance_transform`] `dist` of `obstacles`
/// (the planning pipeline has it already).
///
/// # Errors
/// As [`footprint_cspace`]; a `dist` of another size than the mask.
pub fn footprint_cspace_with_distance(
    obstacles: &[bool],
    dist: &[f32],
    width: usize,
    height: usize,
    resolution: f64,
    footprint: &Footprint,
    headings: usize,
) -> Result<FootprintCSpace> {
    check_cspace_size(width, height, headings)?;
    crate::error::ensure_len("obstacle mask", width * height, obstacles.len())?;
    crate::error::ensure_len("distance transform", width * height, dist.len())?;
    let r_in = footprint.inscribed_radius() / resolution;
    let r_out = footprint.circumscribed_radius() / resolution;
    // A footprint wider than the whole map collides everywhere, and its cell stencil
    // (side 2 r_out) would take for ever to build or overflow the cell index.
    let map_diagonal = (width as f64).hypot(height as f64);
    if r_out.is_nan() || r_out > map_diagonal {
        return Err(Error::invalid(
            "footprint",
            format!(
                "circumscribed radius {r_out:.3e} cells exceeds the map diagonal ({map_diagonal:.0} cells)"
            ),
        ));
    }
    // the inscribed disk about a cell centre reaches an obstacle's square when the
    // centres lie within r_in + ½; no point of a square lies nearer than its centre's
    // distance less half a diagonal, so beyond r_out + ½√2 the footprint cannot reach it
    let blocked_within = disk_reach(r_in);
    let free_beyond = r_out + std::f64::consts::FRAC_1_SQRT_2 + 1e-6;
    let step = std::f64::consts::TAU / headings as f64;
    // obstacles along each row before each cell, so that a run of a stencil's row is
    // tested at once: row_count[y * (width + 1) + x] counts row y's cells 0..x
    let mut row_count = vec![0u32; (width + 1) * height];
    for y in 0..height {
        let r = y * (width + 1);
        for x in 0..width {
            row_count[r + x + 1] = row_count[r + x] + u32::from(obstacles[y * width + x]);
        }
    }
    // What the distance alone decides, the same at every heading: blocked within the
    // inscribed reach, free beyond the circumscribed one; the cells between (the band)
    // are listed once and only they are tested against each stencil.
    let mut decided = vec![false; width * height];
    let mut band: Vec<usize> = Vec::new();
    for (i, &d) in dist.iter().enumerate() {
        let d = f64::from(d);
        if d <= blocked_within {
            decided[i] = true;
        } else if d <= free_beyond {
            band.push(i);
        }
    }
    // `true` when an obstacle lies in the stencil `runs` placed at cell i
    let hits = |runs: &[(i64, i64, i64)], i: usize| {
        let (x, y) = ((i % width) as i64, (i / width) as i64);
        runs.iter().any(|&(dy, lo, hi)| {
            let oy = y + dy;
            let (a, b) = ((x + lo).max(0), (x + hi).min(width as i64 - 1));
            if oy < 0 || oy >= height as i64 || a > b {
                return false;
            }
            let r = oy as usize * (width + 1);
            row_count[r + b as usize + 1] > row_count[r + a as usize]
        })
    };
    // The turns first: a turn's stencil (the footprint at every sampled heading from θ_k
    // to θ_{k+1}) holds the footprint's at θ_k and at θ_{k+1}, so where a turn is free
    // both headings are, and only the band cells where neither adjacent turn is free are
    // tested for a heading (the inclusion is checked, not assumed).
    let sub = ((step.to_degrees() / 3.0).ceil() as usize).max(1);
    let offsets: Vec<Vec<(i64, i64)>> = (0..headings)
        .map(|k| footprint.cell_offsets(k as f64 * step, resolution))
        .collect();
    let mut sweeps = Vec::with_capacity(headings);
    let mut swept_stencils = Vec::with_capacity(headings);
    for k in 0..headings {
        let theta = k as f64 * step;
        let swept = Stencil::of(
            (0..=sub)
                .flat_map(|j| {
                    footprint.cell_offsets(theta + step * j as f64 / sub as f64, resolution)
                })
                .collect(),
        );
        let runs = swept.row_runs();
        let mut out = decided.clone();
        for &i in &band {
            out[i] = hits(&runs, i);
        }
        sweeps.push(out);
        swept_stencils.push(swept);
    }
    let mut slices = Vec::with_capacity(headings);
    for (k, own) in offsets.iter().enumerate() {
        let before = (k + headings - 1) % headings;
        let runs = row_runs(own);
        let inside = |s: &Stencil| own.iter().all(|&o| s.holds(o));
        let (after_free, before_free) = (
            inside(&swept_stencils[k]).then_some(&sweeps[k]),
            inside(&swept_stencils[before]).then_some(&sweeps[before]),
        );
        let mut out = decided.clone();
        for &i in &band {
            let free_turn = after_free.is_some_and(|t| !t[i]) || before_free.is_some_and(|t| !t[i]);
            out[i] = !free_turn && hits(&runs, i);
        }
        slices.push(out);
    }
    Ok(FootprintCSpace {
        headings,
        width,
        height,
        slices,
        sweeps,
    })
}

/// A set of cell offsets `(dx, dy)` as a bitmap over their bounding box: the union of
/// the footprint's stencils over a turn without sorting them.
struct Stencil {
    /// Least `dx` and `dy`.
    lo: (i64, i64),
    /// Width and height of the box (cells).
    size: (usize, usize),
    /// `cells[(dy - lo.1) · size.0 + dx - lo.0]`: the offset is in the set.
    cells: Vec<bool>,
}

impl Stencil {
    fn of(offsets: Vec<(i64, i64)>) -> Self {
        let (mut lo, mut hi) = ((i64::MAX, i64::MAX), (i64::MIN, i64::MIN));
        for &(dx, dy) in &offsets {
            lo = (lo.0.min(dx), lo.1.min(dy));
            hi = (hi.0.max(dx), hi.1.max(dy));
        }
        if offsets.is_empty() {
            return Self {
                lo: (0, 0),
                size: (0, 0),
                cells: Vec::new(),
            };
        }
        let size = ((hi.0 - lo.0 + 1) as usize, (hi.1 - lo.1 + 1) as usize);
        let mut cells = vec![false; size.0 * size.1];
        for (dx, dy) in offsets {
            cells[(dy - lo.1) as usize * size.0 + (dx - lo.0) as usize] = true;
        }
        Self { lo, size, cells }
    }

    fn holds(&self, (dx, dy): (i64, i64)) -> bool {
        let (x, y) = (dx - self.lo.0, dy - self.lo.1);
        x >= 0
            && y >= 0
            && (x as usize) < self.size.0
            && (y as usize) < self.size.1
            && self.cells[y as usize * self.size.0 + x as usize]
    }

    /// The set as [`row_runs`] gives it, read off the bitmap row by row.
    fn row_runs(&self) -> Vec<(i64, i64, i64)> {
        let mut runs: Vec<(i64, i64, i64)> = Vec::new();
        for y in 0..self.size.1 {
            let row = &self.cells[y * self.size.0..(y + 1) * self.size.0];
            let dy = y as i64 + self.lo.1;
            for (x, _) in row.iter().enumerate().filter(|c| *c.1) {
                let dx = x as i64 + self.lo.0;
                match runs.last_mut() {
                    Some(run) if run.0 == dy && run.2 + 1 == dx => run.2 = dx,
                    _ => runs.push((dy, dx, dx)),
                }
            }
        }
        runs
    }
}

/// Cell offsets `(dx, dy)` as runs `(dy, dx_first, dx_last)` of consecutive cells along
/// each row (a non-convex footprint's row may hold several).
fn row_runs(offsets: &[(i64, i64)]) -> Vec<(i64, i64, i64)> {
    let mut sorted = offsets.to_vec();
    sorted.sort_unstable_by_key(|&(dx, dy)| (dy, dx));
    let mut runs: Vec<(i64, i64, i64)> = Vec::new();
    for (dx, dy) in sorted {
        match runs.last_mut() {
            Some(run) if run.0 == dy && run.2 + 1 >= dx => run.2 = run.2.max(dx),
            _ => runs.push((dy, dx, dx)),
        }
    }
    runs
}

/// A path of a polygonal robot through its (x, y, θ) C-space.
#[derive(Debug, Clone, PartialEq)]
pub struct FootprintPath {
    /// `(x, y, k)` states from start to goal; heading θ = 2πk / 8.
    pub states: Vec<(usize, usize, usize)>,
    /// Cost: path length in cells plus `turn_cost` per 45° turn.
    pub cost: f64,
    /// Expanded states.
    pub expanded: usize,
}

/// A* over (x, y, heading) for a polygonal robot with the C-space of
/// [`footprint_cspace`] built with **8 headings** (θ_k = k · 45°, the directions of the
/// 8 grid moves). From state (c, k) the robot may drive one cell along heading k (both
/// cells free in slice k; for diagonals the two side cells too) or turn in place by ±45°
/// (the swept footprint free), costing `turn_cost` (cells of travel per 45° turn). The
/// goal is reached at any heading. `Ok(None)` when unreachable.
pub fn astar_footprint(
    cs: &FootprintCSpace,
    start: (usize, usize, usize),
    goal: (usize, usize),
    turn_cost: f64,
) -> Result<Option<FootprintPath>> {
    check_footprint_query(cs, start, goal, turn_cost)?;
    Ok(footprint_search(cs, start, goal, turn_cost))
}

/// The checks of [`astar_footprint`] before it allocates: an 8-heading C-space of a
/// bounded state count, a usable turn cost, and start and goal on the map and free (the
/// start at its heading, the goal at some heading).
fn check_footprint_query(
    cs: &FootprintCSpace,
    start: (usize, usize, usize),
    goal: (usize, usize),
    turn_cost: f64,
) -> Result<()> {
    if cs.headings != 8 {
        return Err(Error::invalid(
            "headings",
            "the footprint search needs the 8-heading C-space",
        ));
    }
    if !(turn_cost.is_finite() && turn_cost >= 0.0) {
        return Err(Error::invalid(
            "turn cost",
            format!("must be finite and >= 0, got {turn_cost}"),
        ));
    }
    let (w, h) = (cs.width, cs.height);
    if w.checked_mul(h)
        .is_none_or(|n| n > MAX_FOOTPRINT_STATES / 8)
    {
        return Err(Error::invalid(
            "footprint search",
            format!(
                "{w} x {h} cells x 8 headings exceeds the limit of {MAX_FOOTPRINT_STATES} \
                 search states; use a coarser map"
            ),
        ));
    }
    for (what, (x, y)) in [("start", (start.0, start.1)), ("goal", goal)] {
        if x >= w || y >= h {
            return Err(Error::Planning(format!(
                "{what} cell ({x}, {y}) lies outside the {w} x {h} map"
            )));
        }
    }
    if start.2 >= 8 {
        return Err(Error::invalid("start heading", "index must be in 0..8"));
    }
    if cs.slices[start.2][start.1 * w + start.0] {
        return Err(Error::Planning(format!(
            "start pose ({}, {}, {}°) collides: the footprint overlaps an obstacle",
            start.0,
            start.1,
            start.2 * 45
        )));
    }
    if (0..8).all(|k| cs.slices[k][goal.1 * w + goal.0]) {
        return Err(Error::Planning(format!(
            "goal cell ({}, {}) collides at every heading",
            goal.0, goal.1
        )));
    }
    Ok(())
}

/// The search of [`astar_footprint`] on a checked query: states `(y · w + x) · 8 + k`.
fn footprint_search(
    cs: &FootprintCSpace,
    start: (usize, usize, usize),
    goal: (usize, usize),
    turn_cost: f64,
) -> Option<FootprintPath> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    const DIRS: [(i64, i64); 8] = [
        (1, 0),
        (1, 1),
        (0, 1),
        (-1, 1),
        (-1, 0),
        (-1, -1),
        (0, -1),
        (1, -1),
    ];
    let (w, h) = (cs.width, cs.height);
    let free = |k: usize, x: i64, y: i64| {
        x >= 0
            && y >= 0
            && (x as usize) < w
            && (y as usize) < h
            && !cs.slices[k][y as usize * w + x as usize]
    };
    let n = w * h * 8;
    let sid = |x: usize, y: usize, k: usize| (y * w + x) * 8 + k;
    let mut g = vec![f64::INFINITY; n];
    let mut parent = vec![u32::MAX; n];
    let mut closed = vec![false; n];
    let hfun = |x: usize, y: usize| {
        super::astar::octile(goal.0 as i64 - x as i64, goal.1 as i64 - y as i64)
    };
    // Keys as ordered integers (costs are finite and non-negative).
    let key = |f: f64| Reverse(f.to_bits());
    let mut heap = BinaryHeap::new();
    let s = sid(start.0, start.1, start.2);
    g[s] = 0.0;
    heap.push((key(hfun(start.0, start.1)), s as u32));
    let mut expanded = 0;
    while let Some((_, u)) = heap.pop() {
        let u = u as usize;
        if closed[u] {
            continue;
        }
        closed[u] = true;
        expanded += 1;
        let (k, cell) = (u % 8, u / 8);
        let (x, y) = (cell % w, cell / w);
        if (x, y) == goal {
            return Some(FootprintPath {
                states: footprint_states(&parent, u, w),
                cost: g[u],
                expanded,
            });
        }
        let mut relax = |v: usize, c: f64, heap: &mut BinaryHeap<(Reverse<u64>, u32)>| {
            let ng = g[u] + c;
            if !closed[v] && ng < g[v] {
                g[v] = ng;
                parent[v] = u as u32;
                let (vx, vy) = ((v / 8) % w, (v / 8) / w);
                heap.push((key(ng + hfun(vx, vy)), v as u32));
            }
        };
        // Drive forward.
        let (dx, dy) = DIRS[k];
        let (nx, ny) = (x as i64 + dx, y as i64 + dy);
        if free(k, nx, ny)
            && (dx == 0
                || dy == 0
                || (free(k, x as i64 + dx, y as i64) && free(k, x as i64, y as i64 + dy)))
        {
            let len = if dx != 0 && dy != 0 {
                super::astar::SQRT2
            } else {
                1.0
            };
            relax(sid(nx as usize, ny as usize, k), len, &mut heap);
        }
        // Turn in place by +45° (sweep k) or -45° (sweep k-1).
        let i = y * w + x;
        let kp = (k + 1) % 8;
        if !cs.sweeps[k][i] && !cs.slices[kp][i] {
            relax(sid(x, y, kp), turn_cost, &mut heap);
        }
        let km = (k + 7) % 8;
        if !cs.sweeps[km][i] && !cs.slices[km][i] {
            relax(sid(x, y, km), turn_cost, &mut heap);
        }
    }
    None
}

/// The (x, y, heading) states from the start to state `u`, by the parent links of a
/// map `w` cells wide.
fn footprint_states(parent: &[u32], u: usize, w: usize) -> Vec<(usize, usize, usize)> {
    let mut states = Vec::new();
    let mut c = u as u32;
    while c != u32::MAX {
        let ci = c as usize;
        states.push(((ci / 8) % w, (ci / 8) / w, ci % 8));
        c = parent[ci];
    }
    states.reverse();
    states
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An outline counts the cells it enters, not those it only touches; the footprint's
    /// rule counts the touched ones too (the same cover, the contact rule apart).
    #[test]
    fn a_polygon_covers_the_cells_it_overlaps_or_touches() {
        // a 2 x 1 rectangle on cell edges: exactly two cells entered, and the ten around
        // them touched; shifted by a quarter cell up, the row above is entered too
        let r = [[2.0, 3.0], [4.0, 3.0], [4.0, 4.0], [2.0, 4.0]];
        assert_eq!(
            polygon_cells(&r, 12, 12, CellContact::Overlapping),
            [(2, 3), (3, 3)]
        );
        let touched = polygon_cells(&r, 12, 12, CellContact::Touching);
        let expected: Vec<(usize, usize)> =
            (2..=4).flat_map(|y| (1..=4).map(move |x| (x, y))).collect();
        assert_eq!(touched, expected);
        let up: Vec<[f64; 2]> = r.iter().rev().map(|p| [p[0], p[1] + 0.25]).collect();
        assert_eq!(
            polygon_cells(&up, 12, 12, CellContact::Overlapping),
            [(2, 3), (3, 3), (2, 4), (3, 4)]
        );
        // a concave outline: the notch's cell is left out
        let u = [
            [0.0, 0.0],
            [3.0, 0.0],
            [3.0, 2.0],
            [2.0, 2.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, 2.0],
            [0.0, 2.0],
        ];
        let cells = polygon_cells(&u, 12, 12, CellContact::Overlapping);
        assert_eq!(cells, [(0, 0), (1, 0), (2, 0), (0, 1), (2, 1)]);
        // off the grid: none
        assert!(
            polygon_cells(
                &[[-3.0, -3.0], [-2.0, -3.0], [-2.0, -2.0]],
                12,
                12,
                CellContact::Touching
            )
            .is_empty()
        );
    }

    /// The bitmap of a turn's stencil gives the runs the sorted offsets give, whatever
    /// their order and repeats.
    #[test]
    fn a_stencil_bitmap_reads_off_the_sorted_runs() {
        let offsets = vec![
            (3, 0),
            (0, 1),
            (1, 0),
            (0, 0),
            (-1, 0),
            (5, 0),
            (1, 0),
            (0, -2),
        ];
        let stencil = Stencil::of(offsets.clone());
        assert_eq!(stencil.row_runs(), row_runs(&offsets));
        assert!(stencil.holds((5, 0)) && !stencil.holds((4, 0)) && !stencil.holds((9, 9)));
    }

    /// A row with a gap (a non-convex footprint's) keeps two runs; rows come in order.
    #[test]
    fn row_runs_merge_neighbours_and_keep_gaps() {
        let offsets = [(3, 0), (0, 1), (1, 0), (0, 0), (-1, 0), (5, 0)];
        assert_eq!(
            row_runs(&offsets),
            [(0, -1, 1), (0, 3, 3), (0, 5, 5), (1, 0, 0)]
        );
    }
}

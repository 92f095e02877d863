//! Exact Euclidean distance transform in linear time.
//!
//! Two passes as in Meijster, Roerdink & Hesselink (2000): the first pass computes, for
//! every cell, the distance `g` to the nearest obstacle in its own column (a forward and
//! a backward sweep over whole rows, so memory is read contiguously); the second pass
//! computes along every row the lower envelope of the parabolas `(x - q)^2 + g(q)^2`
//! (Felzenszwalb & Huttenlocher, "Distance Transforms of Sampled Functions", Theory of
//! Computing 8, 2012). Both passes are O(N); all arithmetic on squared distances is exact
//! (integers held in `f64`).

/// Reusable buffers for [`distance_transform_into`] (avoids allocating per call).
#[derive(Debug, Default, Clone)]
pub struct EdtWorkspace {
    column: Vec<u32>,
    f: Vec<f64>,
    v: Vec<u32>,
    z: Vec<f64>,
}

impl EdtWorkspace {
    /// An empty workspace; buffers grow on first use.
    pub fn new() -> Self {
        Self::default()
    }
}

/// Euclidean distance (in cells, between cell centres) from every cell to the nearest
/// obstacle cell; 0 on obstacles, `f32::INFINITY` everywhere if there is no obstacle.
///
/// `obstacles` is row-major, `width * height` long.
///
/// # Panics
/// If `obstacles.len() != width * height`.
#[doc(alias = "edt")]
#[doc(alias = "euclidean_distance_transform")]
pub fn distance_transform(obstacles: &[bool], width: usize, height: usize) -> Vec<f32> {
    let mut out = Vec::new();
    distance_transform_into(obstacles, width, height, &mut EdtWorkspace::new(), &mut out);
    out
}

/// [`distance_transform`] writing into `out` (resized) with reusable buffers.
///
/// # Panics
/// If `obstacles.len() != width * height`.
pub fn distance_transform_into(
    obstacles: &[bool],
    width: usize,
    height: usize,
    ws: &mut EdtWorkspace,
    out: &mut Vec<f32>,
) {
    assert_eq!(obstacles.len(), width * height, "obstacle mask must have width * height cells");
    out.resize(width * height, 0.0);
    if width == 0 || height == 0 {
        return;
    }
    // "No obstacle in this column": larger than any real distance, small enough that its
    // square stays exact.
    let inf = (width + height) as u32;
    // Phase 1: column distances, forward then backward, whole rows at a time.
    let g = &mut ws.column;
    g.resize(width * height, 0);
    for (gi, &o) in g[..width].iter_mut().zip(&obstacles[..width]) {
        *gi = if o { 0 } else { inf };
    }
    for y in 1..height {
        let (prev, cur) = g[(y - 1) * width..(y + 1) * width].split_at_mut(width);
        let obs = &obstacles[y * width..(y + 1) * width];
        for ((c, &p), &o) in cur.iter_mut().zip(prev.iter()).zip(obs) {
            *c = if o { 0 } else { (p + 1).min(inf) };
        }
    }
    for y in (0..height - 1).rev() {
        let (cur, next) = g[y * width..(y + 2) * width].split_at_mut(width);
        for (c, &n) in cur.iter_mut().zip(next.iter()) {
            *c = (*c).min(n + 1);
        }
    }
    // Phase 2: lower envelope of parabolas along each row.
    ws.f.resize(width, 0.0);
    ws.v.resize(width, 0);
    ws.z.resize(width + 1, 0.0);
    for y in 0..height {
        let row = &g[y * width..(y + 1) * width];
        let dst = &mut out[y * width..(y + 1) * width];
        envelope_row(row, inf, &mut ws.f, &mut ws.v, &mut ws.z, dst);
    }
}

#[inline]
fn envelope_row(row: &[u32], inf: u32, f: &mut [f64], v: &mut [u32], z: &mut [f64], dst: &mut [f32]) {
    let n = row.len();
    // f[q] = g(q)^2 + q^2 (the parabola's offset term), only for columns with an obstacle.
    let mut k: usize = 0;
    let mut have = false;
    for q in 0..n {
        let gq = row[q];
        if gq >= inf {
            continue;
        }
        let qf = q as f64;
        let fq = (gq as f64) * (gq as f64) + qf * qf;
        f[q] = fq;
        if !have {
            have = true;
            v[0] = q as u32;
            z[0] = f64::NEG_INFINITY;
            z[1] = f64::INFINITY;
            continue;
        }
        // z[0] = -inf, so the loop stops at k = 0 at the latest.
        let mut s;
        loop {
            let vk = v[k] as usize;
            s = (fq - f[vk]) / (2.0 * (qf - vk as f64));
            if s <= z[k] {
                k -= 1;
            } else {
                break;
            }
        }
        k += 1;
        v[k] = q as u32;
        z[k] = s;
        z[k + 1] = f64::INFINITY;
    }
    if !have {
        dst.fill(f32::INFINITY);
        return;
    }
    let mut k = 0usize;
    for q in 0..n {
        let qf = q as f64;
        while z[k + 1] < qf {
            k += 1;
        }
        let vk = v[k] as usize;
        let d = q as i64 - vk as i64;
        let gv = row[vk] as i64;
        // Exact integer squared distance; f32 square root (correctly rounded).
        dst[q] = ((d * d + gv * gv) as f32).sqrt();
    }
}

/// Brute-force reference transform, O(N * obstacles); for tests.
#[doc(hidden)]
pub fn distance_transform_brute_force(obstacles: &[bool], width: usize, height: usize) -> Vec<f32> {
    let obs: Vec<(i64, i64)> = (0..width * height)
        .filter(|&i| obstacles[i])
        .map(|i| ((i % width) as i64, (i / width) as i64))
        .collect();
    (0..width * height)
        .map(|i| {
            let (x, y) = ((i % width) as i64, (i / width) as i64);
            obs.iter()
                .map(|&(ox, oy)| ((ox - x) * (ox - x) + (oy - y) * (oy - y)) as f64)
                .fold(f64::INFINITY, f64::min)
                .sqrt() as f32
        })
        .collect()
}

//! Exact Euclidean distance transform in linear time.
//!
//! Two passes as in Meijster, Roerdink & Hesselink (2000): the first pass computes, for
//! every cell, the distance `g` to the nearest obstacle in its own column (a forward and
//! a backward sweep over whole rows, so memory is read contiguously); the second pass
//! computes along every row the lower envelope of the parabolas `(x - q)^2 + g(q)^2`
//! (Felzenszwalb & Huttenlocher, "Distance Transforms of Sampled Functions", Theory of
//! Computing 8, 2012). Both passes are O(N); all arithmetic on squared distances is exact
//! (integers; breakpoints compared as exact fractions).

/// Reusable buffers for [`distance_transform_into`] (avoids allocating per call).
#[derive(Debug, Default, Clone)]
pub struct EdtWorkspace {
    column: Vec<u16>,
    f: Vec<i64>,
    v: Vec<u32>,
    zn: Vec<i64>,
    zd: Vec<i64>,
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
/// If `obstacles.len() != width * height` or `height > 65,533` (the map loaders never
/// produce such grids).
pub fn distance_transform_into(
    obstacles: &[bool],
    width: usize,
    height: usize,
    ws: &mut EdtWorkspace,
    out: &mut Vec<f32>,
) {
    assert_eq!(
        obstacles.len(),
        width * height,
        "obstacle mask must have width * height cells"
    );
    out.resize(width * height, 0.0);
    if width == 0 || height == 0 {
        return;
    }
    // "No obstacle in this column": larger than any real column distance (< height).
    let inf = (height as u32 + 1).min(u16::MAX as u32) as u16;
    assert!(
        height < u16::MAX as usize - 1,
        "distance_transform supports at most 65,533 rows"
    );
    // Phase 1, forward sweep: distance to the nearest obstacle above (whole rows at a
    // time, u16 to halve the memory traffic).
    let g = &mut ws.column;
    g.resize(width * height, 0);
    for (gi, &o) in g[..width].iter_mut().zip(&obstacles[..width]) {
        *gi = if o { 0 } else { inf };
    }
    for y in 1..height {
        let (prev, cur) = g[(y - 1) * width..(y + 1) * width].split_at_mut(width);
        let obs = &obstacles[y * width..(y + 1) * width];
        for ((c, &p), &o) in cur.iter_mut().zip(prev.iter()).zip(obs) {
            *c = if o { 0 } else { p.saturating_add(1).min(inf) };
        }
    }
    // Phase 1 backward sweep fused with phase 2: each row is finished from the row below
    // it and its lower envelope computed while it is still in cache.
    ws.f.resize(width, 0);
    ws.v.resize(width, 0);
    ws.zn.resize(width + 1, 0);
    ws.zd.resize(width + 1, 1);
    for y in (0..height).rev() {
        if y + 1 < height {
            let (cur, next) = g[y * width..(y + 2) * width].split_at_mut(width);
            for (c, &n) in cur.iter_mut().zip(next.iter()) {
                *c = (*c).min(n.saturating_add(1));
            }
        }
        let row = &g[y * width..(y + 1) * width];
        let dst = &mut out[y * width..(y + 1) * width];
        envelope_row(row, inf, &mut ws.f, &mut ws.v, &mut ws.zn, &mut ws.zd, dst);
    }
}

#[inline]
fn envelope_row(
    row: &[u16],
    inf: u16,
    f: &mut [i64],
    v: &mut [u32],
    zn: &mut [i64],
    zd: &mut [i64],
    dst: &mut [f32],
) {
    let n = row.len();
    // Parabola q has offset f[q] = g(q)^2 + q^2. The envelope keeps parabolas v[0..=k]
    // with breakpoints z[1..=k] held as exact fractions zn / zd (zd > 0), so every
    // comparison is an integer cross-multiplication (no division, no rounding).
    let mut k: usize = 0;
    let mut have = false;
    for q in 0..n {
        let gq = row[q];
        if gq >= inf {
            continue;
        }
        let qi = q as i64;
        let fq = (gq as i64) * (gq as i64) + qi * qi;
        f[q] = fq;
        if !have {
            have = true;
            v[0] = q as u32;
            continue;
        }
        loop {
            let vk = v[k] as i64;
            let num = fq - f[vk as usize];
            let den = 2 * (qi - vk);
            // s = num / den <= z[k]  (z[0] = -inf never holds)
            if k > 0 && num * zd[k] <= zn[k] * den {
                k -= 1;
            } else {
                k += 1;
                v[k] = q as u32;
                zn[k] = num;
                zd[k] = den;
                break;
            }
        }
    }
    if !have {
        dst.fill(f32::INFINITY);
        return;
    }
    let kmax = k;
    let mut k = 0usize;
    for q in 0..n {
        let qi = q as i64;
        // Advance while the next breakpoint z[k+1] < q.
        while k < kmax && zn[k + 1] < qi * zd[k + 1] {
            k += 1;
        }
        let vk = v[k] as usize;
        let d = qi - vk as i64;
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

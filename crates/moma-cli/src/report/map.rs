//! The map on the page: the region the mission uses, and that part of the grid as a PNG
//! data URI (one pixel per cell, or per block of cells on very large crops).

use super::{MissionReport, ReportMap};
use crate::svg_map::b64;

/// Longest side of the embedded image, pixels; larger crops are drawn in blocks of cells.
pub(crate) const MAX_IMAGE_SIDE: usize = 2000;

pub(crate) const FREE: [u8; 3] = [255, 255, 255];
pub(crate) const OCCUPIED: [u8; 3] = [43, 43, 43];
pub(crate) const UNKNOWN: [u8; 3] = [200, 200, 200];

/// The world rectangle `[x0, y0, x1, y1]` (m) the mission uses: start, goal, the plans,
/// the executed path, the obstacles and the end-effector target, widened by the footprint
/// and a margin (a tenth of the span, at least 0.5 m), then clipped to the map when the two
/// overlap. Never narrower than 1 m.
pub(crate) fn view_region(r: &MissionReport) -> [f64; 4] {
    let (mut x0, mut y0, mut x1, mut y1) = (
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    );
    let mut add = |x: f64, y: f64, pad: f64| {
        if x.is_finite() && y.is_finite() && pad.is_finite() {
            x0 = x0.min(x - pad);
            y0 = y0.min(y - pad);
            x1 = x1.max(x + pad);
            y1 = y1.max(y + pad);
        }
    };
    add(r.start[0], r.start[1], 0.0);
    add(r.goal[0], r.goal[1], 0.0);
    if let Some(p) = r.end_effector_target {
        add(p[0], p[1], 0.0);
    }
    for p in r.plans.iter().flat_map(|p| &p.points) {
        add(p[0], p[1], 0.0);
    }
    for (&x, &y) in r.samples.x.iter().zip(&r.samples.y) {
        add(x, y, 0.0);
    }
    for o in &r.obstacles {
        add(o.center[0], o.center[1], o.radius.abs());
    }
    let m = &r.map;
    let (mx0, my0) = (m.origin[0], m.origin[1]);
    let (mx1, my1) = (
        mx0 + m.width as f64 * m.resolution,
        my0 + m.height as f64 * m.resolution,
    );
    if !x0.is_finite() {
        (x0, y0, x1, y1) = (mx0, my0, mx1, my1);
    }
    let span = (x1 - x0).max(y1 - y0);
    let pad = r.footprint_radius.max(0.0) + (0.1 * span).max(0.5);
    let (mut a, mut b, mut c, mut d) = (x0 - pad, y0 - pad, x1 + pad, y1 + pad);
    let (ca, cb, cc, cd) = (a.max(mx0), b.max(my0), c.min(mx1), d.min(my1));
    if ca < cc && cb < cd {
        (a, b, c, d) = (ca, cb, cc, cd);
    }
    let widen = |lo: f64, hi: f64| {
        if hi - lo < 1.0 {
            let m = 0.5 * (lo + hi);
            (m - 0.5, m + 0.5)
        } else {
            (lo, hi)
        }
    };
    let (a, c) = widen(a, c);
    let (b, d) = widen(b, d);
    [a, b, c, d]
}

/// The cropped map as an image.
pub(crate) struct MapImage {
    /// `data:image/png;base64,...`, or empty when the map has no cell in view.
    pub data_uri: String,
    /// World extent of the image, m.
    pub x0: f64,
    /// Lower edge, m.
    pub y0: f64,
    /// Right edge, m.
    pub x1: f64,
    /// Upper edge, m.
    pub y1: f64,
    /// Image size, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
}

/// The cells `[cx0, cx1) × [cy0, cy1)` that cover `view`, clamped to the map; the whole
/// map when `view` misses it.
pub(crate) fn crop_cells(m: &ReportMap, view: [f64; 4]) -> (usize, usize, usize, usize) {
    let cell = |v: f64, o: f64, n: usize, up: bool| -> usize {
        let c = (v - o) / m.resolution;
        let c = if up { c.ceil() } else { c.floor() };
        if c.is_nan() || c <= 0.0 {
            0
        } else {
            (c as usize).min(n)
        }
    };
    let cx0 = cell(view[0], m.origin[0], m.width, false);
    let cx1 = cell(view[2], m.origin[0], m.width, true);
    let cy0 = cell(view[1], m.origin[1], m.height, false);
    let cy1 = cell(view[3], m.origin[1], m.height, true);
    if cx0 < cx1 && cy0 < cy1 {
        (cx0, cx1, cy0, cy1)
    } else {
        (0, m.width, 0, m.height)
    }
}

/// The colour of a block of cells: occupied if any cell is, else unknown if any cell is
/// (or lies outside the map), else free.
pub(crate) fn block_colour(m: &ReportMap, x0: usize, y0: usize, k: usize) -> [u8; 3] {
    let mut unknown = false;
    for y in y0..y0 + k {
        for x in x0..x0 + k {
            if x >= m.width || y >= m.height {
                unknown = true;
                continue;
            }
            match m.cells[y * m.width + x] {
                0 => {}
                1 => return OCCUPIED,
                _ => unknown = true,
            }
        }
    }
    if unknown { UNKNOWN } else { FREE }
}

/// Encodes the part of the map inside `view` as a PNG data URI (north up).
pub(crate) fn encode(m: &ReportMap, view: [f64; 4]) -> MapImage {
    let (cx0, cx1, cy0, cy1) = crop_cells(m, view);
    let (cw, ch) = (cx1 - cx0, cy1 - cy0);
    let empty = MapImage {
        data_uri: String::new(),
        x0: view[0],
        y0: view[1],
        x1: view[2],
        y1: view[3],
        width: 0,
        height: 0,
    };
    if cw == 0 || ch == 0 {
        return empty;
    }
    let k = cw.max(ch).div_ceil(MAX_IMAGE_SIDE);
    let (pw, ph) = (cw.div_ceil(k), ch.div_ceil(k));
    let png = moma::planning::render::grid_png(pw, ph, true, |x, y| {
        block_colour(m, cx0 + x * k, cy0 + y * k, k)
    });
    let Ok(png) = png else {
        return empty;
    };
    let res = m.resolution;
    MapImage {
        data_uri: format!("data:image/png;base64,{}", b64(&png)),
        x0: m.origin[0] + cx0 as f64 * res,
        y0: m.origin[1] + cy0 as f64 * res,
        x1: m.origin[0] + (cx0 + pw * k) as f64 * res,
        y1: m.origin[1] + (cy0 + ph * k) as f64 * res,
        width: pw,
        height: ph,
    }
}

/// Most wall boxes the 3-D view receives; a crop that needs more is merged in blocks.
pub(crate) const MAX_WALLS: usize = 20_000;

/// The occupied cells of the crop inside `view` as axis-aligned rectangles for the 3-D
/// view's walls, `[x0, y0, x1, y1]` in world metres: runs of occupied cells along each
/// row, merged with the same run on the rows above. When that gives more than
/// [`MAX_WALLS`] rectangles the cells are taken in blocks of 2, 3, … (a block is occupied
/// if any of its cells is).
pub(crate) fn walls(m: &ReportMap, view: [f64; 4]) -> Vec<[f64; 4]> {
    let (cx0, cx1, cy0, cy1) = crop_cells(m, view);
    let res = m.resolution;
    for k in 1.. {
        let (bw, bh) = ((cx1 - cx0).div_ceil(k), (cy1 - cy0).div_ceil(k));
        let occupied =
            |bx: usize, by: usize| block_colour(m, cx0 + bx * k, cy0 + by * k, k) == OCCUPIED;
        // open rectangles: (x0, x1) run -> (y0 in blocks, index in out)
        let mut out: Vec<[usize; 4]> = Vec::new();
        let mut open: Vec<(usize, usize, usize)> = Vec::new(); // (x0, x1, rect index)
        for by in 0..bh {
            let mut runs = Vec::new();
            let mut bx = 0;
            while bx < bw {
                if occupied(bx, by) {
                    let a = bx;
                    while bx < bw && occupied(bx, by) {
                        bx += 1;
                    }
                    runs.push((a, bx));
                } else {
                    bx += 1;
                }
            }
            let mut next = Vec::with_capacity(runs.len());
            for (a, b) in runs {
                if let Some(&(_, _, r)) = open.iter().find(|o| o.0 == a && o.1 == b) {
                    out[r][3] = by + 1;
                    next.push((a, b, r));
                } else {
                    out.push([a, by, b, by + 1]);
                    next.push((a, b, out.len() - 1));
                }
            }
            open = next;
            if out.len() > MAX_WALLS {
                break;
            }
        }
        if out.len() <= MAX_WALLS {
            let x = |c: usize| m.origin[0] + (cx0 + c * k).min(cx1) as f64 * res;
            let y = |c: usize| m.origin[1] + (cy0 + c * k).min(cy1) as f64 * res;
            return out
                .iter()
                .map(|r| [x(r[0]), y(r[1]), x(r[2]), y(r[3])])
                .collect();
        }
    }
    unreachable!("a crop of one block has one rectangle at most")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn map(w: usize, h: usize) -> ReportMap {
        let mut cells = vec![0u8; w * h];
        cells[0] = 1; // lower-left cell occupied
        cells[w * h - 1] = 2; // upper-right cell unknown
        ReportMap {
            width: w,
            height: h,
            resolution: 0.1,
            origin: [-1.0, -2.0],
            cells,
        }
    }

    /// Width and height from the PNG's IHDR chunk.
    fn png_size(uri: &str) -> (u32, u32) {
        let b = b64_decode(uri.strip_prefix("data:image/png;base64,").unwrap());
        assert_eq!(&b[..8], b"\x89PNG\r\n\x1a\n");
        assert_eq!(&b[12..16], b"IHDR");
        let w = u32::from_be_bytes(b[16..20].try_into().unwrap());
        let h = u32::from_be_bytes(b[20..24].try_into().unwrap());
        (w, h)
    }

    #[test]
    fn walls_merge_occupied_runs_into_rectangles() {
        // a 6 x 4 map: an L of occupied cells (column 1 rows 0-2, row 0 columns 1-4)
        let (w, h) = (6, 4);
        let mut cells = vec![0u8; w * h];
        for y in 0..3 {
            cells[y * w + 1] = 1;
        }
        for x in 1..5 {
            cells[x] = 1;
        }
        cells[3 * w + 5] = 2; // unknown is no wall
        let m = ReportMap {
            width: w,
            height: h,
            resolution: 0.5,
            origin: [10.0, 20.0],
            cells,
        };
        let r = walls(&m, [10.0, 20.0, 13.0, 22.0]);
        assert_eq!(
            r,
            vec![[10.5, 20.0, 12.5, 20.5], [10.5, 20.5, 11.0, 21.5]],
            "row 0's run, then column 1 above it merged over rows 1 and 2"
        );
    }

    fn b64_decode(s: &str) -> Vec<u8> {
        let val = |c: u8| match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            _ => 63,
        } as u32;
        let mut out = Vec::new();
        for q in s.as_bytes().chunks(4) {
            let pad = q.iter().filter(|&&c| c == b'=').count();
            let n = q
                .iter()
                .map(|&c| if c == b'=' { 0 } else { val(c) })
                .fold(0, |a, v| a << 6 | v);
            let bytes = [(n >> 16) as u8, (n >> 8) as u8, n as u8];
            out.extend_from_slice(&bytes[..3 - pad]);
        }
        out
    }

    #[test]
    fn the_crop_covers_the_view_and_falls_back_to_the_whole_map() {
        let m = map(40, 30); // x in [-1, 3], y in [-2, 1]
        assert_eq!(crop_cells(&m, [0.0, -1.0, 1.05, 0.0]), (10, 21, 10, 20));
        assert_eq!(crop_cells(&m, [-5.0, -5.0, 9.0, 9.0]), (0, 40, 0, 30));
        assert_eq!(crop_cells(&m, [10.0, 10.0, 11.0, 11.0]), (0, 40, 0, 30));
    }

    #[test]
    fn cells_map_to_their_colours_and_blocks_keep_obstacles() {
        let m = map(4, 3);
        assert_eq!(block_colour(&m, 0, 0, 1), OCCUPIED);
        assert_eq!(block_colour(&m, 1, 0, 1), FREE);
        assert_eq!(block_colour(&m, 3, 2, 1), UNKNOWN);
        assert_eq!(block_colour(&m, 0, 0, 2), OCCUPIED);
        assert_eq!(block_colour(&m, 2, 0, 2), FREE);
        // a block reaching past the map's edge counts as unknown
        assert_eq!(block_colour(&m, 2, 2, 2), UNKNOWN);
    }

    #[test]
    fn the_image_has_one_pixel_per_cell_and_the_crop_extent() {
        let m = map(40, 30);
        let img = encode(&m, [0.0, -1.0, 1.05, 0.0]);
        assert_eq!((img.width, img.height), (11, 10));
        assert_eq!(png_size(&img.data_uri), (11, 10));
        assert!((img.x0 - 0.0).abs() < 1e-12 && (img.x1 - 1.1).abs() < 1e-12);
        assert!((img.y0 + 1.0).abs() < 1e-12 && (img.y1 - 0.0).abs() < 1e-12);
    }

    #[test]
    fn the_view_is_the_missions_region_with_a_margin_inside_the_map() {
        use crate::report::{ReportObstacle, ReportPlan, ReportSamples};
        let mut r = MissionReport {
            title: String::new(),
            map: map(400, 300), // x in [-1, 39], y in [-2, 28]
            footprint_radius: 0.5,
            start: [2.0, 1.0, 0.0],
            goal: [8.0, 4.0, 0.0],
            end_effector_target: None,
            plans: vec![ReportPlan {
                t: 0.0,
                points: vec![[2.0, 1.0], [5.0, 6.0], [8.0, 4.0]],
            }],
            obstacles: vec![ReportObstacle {
                t: 1.0,
                center: [9.0, 4.0],
                radius: 1.5,
            }],
            samples: ReportSamples {
                t: vec![0.0],
                x: vec![2.0],
                y: vec![1.0],
                theta: vec![0.0],
                v: vec![0.0],
                omega: vec![0.0],
                v_ref: vec![0.0],
                omega_ref: vec![0.0],
                zmp_margin: vec![None],
                force_angle_min: vec![None],
                clearance: vec![0.0],
                tracking_error: vec![0.0],
                torque_names: vec![],
                torques: vec![],
                arm_side: vec![vec![]],
            },
            events: vec![],
            summary: serde_json::Value::Null,
            view3d: None,
        };
        // box x [2, 10.5], y [1, 6]; span 8.5; pad 0.5 + 0.85
        let v = view_region(&r);
        let want = [0.65, -0.35, 11.85, 7.35];
        for (a, b) in v.iter().zip(want) {
            assert!((a - b).abs() < 1e-12, "{v:?}");
        }
        // clipped to the map where the region reaches past it
        r.start = [-0.9, -1.9, 0.0];
        let v = view_region(&r);
        assert_eq!((v[0], v[1]), (-1.0, -2.0));
    }

    #[test]
    fn large_crops_are_drawn_in_blocks() {
        let m = map(4500, 10);
        let img = encode(&m, [-10.0, -10.0, 1e4, 1e4]);
        // k = ceil(4500 / 2000) = 3
        assert_eq!((img.width, img.height), (1500, 4));
        assert_eq!(png_size(&img.data_uri), (1500, 4));
        assert!((img.y1 - (-2.0 + 12.0 * 0.1)).abs() < 1e-12);
    }
}

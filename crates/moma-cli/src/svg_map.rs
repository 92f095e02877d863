//! SVG pictures of planning results: the known part of the map (free, occupied, unknown,
//! inflated obstacles) as an embedded PNG with axes (world metres on ROS maps, cells on
//! Moving AI maps), a scale bar and a legend, the searched grid path and the smoothed
//! path drawn over it.

use anyhow::Result;
use moma::planning::{MapKind, OccupancyGrid, render::grid_png};
use std::fmt::Write;

/// What to draw.
pub struct Scene<'a> {
    /// The map.
    pub grid: &'a OccupancyGrid,
    /// C-space obstacle mask (`true` = blocked), row-major, for the inflated band.
    pub cspace: &'a [bool],
    /// The grid path (cells).
    pub path: &'a [(usize, usize)],
    /// The smoothed path (cells), if any.
    pub smooth: &'a [(usize, usize)],
    /// Start and goal cells.
    pub start: (usize, usize),
    /// Goal cell.
    pub goal: (usize, usize),
    /// Title line.
    pub title: String,
}

/// Standard base64 (with padding), for images embedded as data URIs.
pub(crate) fn b64(data: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(data.len().div_ceil(3) * 4);
    for c in data.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
        s.push(T[(n >> 18) as usize & 63] as char);
        s.push(T[(n >> 12) as usize & 63] as char);
        s.push(if c.len() > 1 {
            T[(n >> 6) as usize & 63] as char
        } else {
            '='
        });
        s.push(if c.len() > 2 {
            T[n as usize & 63] as char
        } else {
            '='
        });
    }
    s
}

/// The part of the map drawn: cells `[x0, x1) × [y0, y1)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Crop {
    x0: usize,
    x1: usize,
    y0: usize,
    y1: usize,
}

/// The bounding box of the known cells, the path, start and goal, widened by a margin of
/// 5 % (at least 2 cells) and clamped to the map. An all-unknown map is drawn whole.
fn crop(scene: &Scene) -> Crop {
    let g = scene.grid;
    let (w, h) = (g.width, g.height);
    let (mut x0, mut x1, mut y0, mut y1) = (usize::MAX, 0, usize::MAX, 0);
    let mut add = |x: usize, y: usize| {
        x0 = x0.min(x);
        x1 = x1.max(x + 1);
        y0 = y0.min(y);
        y1 = y1.max(y + 1);
    };
    for y in 0..h {
        for x in 0..w {
            if g.cells[y * w + x] >= 0 {
                add(x, y);
            }
        }
    }
    for &(x, y) in scene.path.iter().chain([&scene.start, &scene.goal]) {
        add(x, y);
    }
    let margin = ((x1 - x0).max(y1 - y0) / 20).max(2);
    Crop {
        x0: x0.saturating_sub(margin),
        x1: (x1 + margin).min(w),
        y0: y0.saturating_sub(margin),
        y1: (y1 + margin).min(h),
    }
}

/// A "nice" length (1, 2 or 5 × 10^k) close to a fifth of `span`.
fn scale_bar_length(span: f64) -> f64 {
    let target = span / 5.0;
    let mag = 10f64.powf(target.log10().floor());
    [5.0, 2.0, 1.0]
        .iter()
        .map(|m| m * mag)
        .find(|l| *l <= target)
        .unwrap_or(mag)
}

const ML: f64 = 70.0;
const MT: f64 = 52.0;
const MB: f64 = 50.0;
const MR: f64 = 250.0;

/// Renders the scene as an SVG document: the known part of the map with axes (world
/// metres on ROS maps, cells on Moving AI maps), a scale bar and a legend.
pub fn render(scene: &Scene) -> Result<String> {
    let g = scene.grid;
    let w = g.width;
    let y_up = g.kind == MapKind::Ros;
    let c = crop(scene);
    let (cw, ch) = (c.x1 - c.x0, c.y1 - c.y0);
    // pixels per cell: the longer side of the crop about 700 px
    let s = (700.0 / cw.max(ch) as f64).clamp(0.5, 40.0);
    // Small crops are upsampled in the PNG itself (whole pixels per cell), so that
    // viewers that smooth scaled images still show sharp cell edges.
    let f = (s.floor() as usize).clamp(1, 16);
    let png = grid_png(cw * f, ch * f, y_up, |x, y| {
        let i = (y / f + c.y0) * w + x / f + c.x0;
        match g.cells[i] {
            v if v >= 100 => [0, 0, 0],
            v if v < 0 => [170, 170, 170],
            _ if scene.cspace[i] => [255, 190, 190],
            v => {
                let s = 255 - (v as u16 * 2).min(200) as u8;
                [s, s, s]
            }
        }
    })?;
    let (pw, ph) = (cw as f64 * s, ch as f64 * s);
    let (tw, th) = (ML + pw + MR, MT + ph + MB);
    // continuous cell coordinates (cell i spans [i, i+1)) → picture
    let px = |x: f64| ML + (x - c.x0 as f64) * s;
    let py = |y: f64| {
        if y_up {
            MT + (c.y1 as f64 - y) * s
        } else {
            MT + (y - c.y0 as f64) * s
        }
    };
    let centre = |p: (usize, usize)| (px(p.0 as f64 + 0.5), py(p.1 as f64 + 0.5));
    let poly = |cells: &[(usize, usize)]| -> String {
        cells
            .iter()
            .map(|&p| {
                let (x, y) = centre(p);
                format!("{x:.1},{y:.1}")
            })
            .collect::<Vec<_>>()
            .join(" ")
    };
    let mut o = String::new();
    let _ = writeln!(
        o,
        r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" width="{tw:.0}" height="{th:.0}" viewBox="0 0 {tw:.0} {th:.0}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(o, r#"<rect width="100%" height="100%" fill="white"/>"#);
    for (i, line) in scene.title.lines().enumerate() {
        let _ = writeln!(
            o,
            r#"<text x="{ML}" y="{}" font-size="{}">{}</text>"#,
            18.0 + 17.0 * i as f64,
            if i == 0 { 14 } else { 12 },
            xml_escape(line)
        );
    }
    let _ = writeln!(
        o,
        r#"<image x="{ML}" y="{MT}" width="{pw:.2}" height="{ph:.2}" style="image-rendering:pixelated" preserveAspectRatio="none" xlink:href="data:image/png;base64,{}"/>"#,
        b64(&png)
    );
    axes(&mut o, scene, c, s, &px, &py);
    let stroke = 2.0;
    if scene.path.len() > 1 {
        let _ = writeln!(
            o,
            r##"<polyline points="{}" fill="none" stroke="#d62728" stroke-width="{stroke}" stroke-linejoin="round"/>"##,
            poly(scene.path)
        );
    }
    if scene.smooth.len() > 1 {
        let _ = writeln!(
            o,
            r##"<polyline points="{}" fill="none" stroke="#1f77b4" stroke-width="{stroke}" stroke-dasharray="6 4"/>"##,
            poly(scene.smooth)
        );
    }
    let (sx, sy) = centre(scene.start);
    let (gx, gy) = centre(scene.goal);
    let _ = writeln!(
        o,
        r##"<circle cx="{sx:.1}" cy="{sy:.1}" r="5" fill="#2ca02c" stroke="black" stroke-width="0.8"/><circle cx="{gx:.1}" cy="{gy:.1}" r="5" fill="none" stroke="#9467bd" stroke-width="2.5"/>"##
    );
    scale_bar(&mut o, scene, c, s, ph);
    legend(&mut o, ML + pw + 16.0);
    o.push_str("</svg>\n");
    Ok(o)
}

/// Frame, ticks and axis labels. ROS maps: world metres (the map frame's when its origin
/// is rotated); Moving AI maps: cells, rows counted downward.
fn axes(
    o: &mut String,
    scene: &Scene,
    c: Crop,
    s: f64,
    px: &dyn Fn(f64) -> f64,
    py: &dyn Fn(f64) -> f64,
) {
    let g = scene.grid;
    let ros = g.kind == MapKind::Ros;
    let rotated = ros && g.origin[2] != 0.0;
    // cell coordinate → axis value and back
    let (ox, oy, k) = if ros && !rotated {
        (g.origin[0], g.origin[1], g.resolution)
    } else if ros {
        (0.0, 0.0, g.resolution)
    } else {
        (0.0, 0.0, 1.0)
    };
    // Moving AI coordinates name cells, so value i sits at the centre of cell i
    let shift = if ros { 0.0 } else { 0.5 };
    let (pw, ph) = ((c.x1 - c.x0) as f64 * s, (c.y1 - c.y0) as f64 * s);
    let _ = writeln!(
        o,
        r##"<rect x="{ML}" y="{MT}" width="{pw:.2}" height="{ph:.2}" fill="none" stroke="#333"/>"##
    );
    let (xa, xb) = (
        ox + (c.x0 as f64 - shift) * k,
        ox + (c.x1 as f64 - shift) * k,
    );
    for t in crate::svg_plots::ticks(xa, xb) {
        let x = px((t - ox) / k + shift);
        let _ = writeln!(
            o,
            r##"<line x1="{x:.1}" y1="{:.1}" x2="{x:.1}" y2="{:.1}" stroke="#333"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
            MT + ph,
            MT + ph + 5.0,
            MT + ph + 18.0,
            crate::svg_plots::fmt_tick(t)
        );
    }
    let (ya, yb) = (
        oy + (c.y0 as f64 - shift) * k,
        oy + (c.y1 as f64 - shift) * k,
    );
    for t in crate::svg_plots::ticks(ya, yb) {
        let y = py((t - oy) / k + shift);
        let _ = writeln!(
            o,
            r##"<line x1="{:.1}" y1="{y:.1}" x2="{ML}" y2="{y:.1}" stroke="#333"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
            ML - 5.0,
            ML - 8.0,
            y + 4.0,
            crate::svg_plots::fmt_tick(t)
        );
    }
    let (xl, yl) = match (ros, rotated) {
        (true, false) => ("x [m]", "y [m]"),
        (true, true) => (
            "x [m] along the map's rows (origin rotated)",
            "y [m] (map frame)",
        ),
        (false, _) => ("x [cell]", "y [cell] (rows downward)"),
    };
    let _ = writeln!(
        o,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{xl}</text><text x="16" y="{:.1}" text-anchor="middle" transform="rotate(-90 16 {:.1})">{yl}</text>"#,
        ML + pw / 2.0,
        MT + ph + 38.0,
        MT + ph / 2.0,
        MT + ph / 2.0
    );
}

/// A scale bar in the lower-left corner of the map, on a white plate.
fn scale_bar(o: &mut String, scene: &Scene, c: Crop, s: f64, ph: f64) {
    let ros = scene.grid.kind == MapKind::Ros;
    let k = if ros { scene.grid.resolution } else { 1.0 };
    let span = (c.x1 - c.x0) as f64 * k;
    let len = scale_bar_length(span);
    let len_px = len / k * s;
    let unit = if ros { "m" } else { "cells" };
    let (x, y) = (ML + 10.0, MT + ph - 12.0);
    let _ = writeln!(
        o,
        r##"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="26" fill="white" fill-opacity="0.85" stroke="#999"/><line x1="{x:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="black" stroke-width="3"/><text x="{:.1}" y="{:.1}" text-anchor="middle">{} {unit}</text>"##,
        x - 6.0,
        y - 18.0,
        len_px + 12.0,
        x + len_px,
        x + len_px / 2.0,
        y - 5.0,
        crate::svg_plots::fmt_tick(len)
    );
}

/// What each colour and line means.
fn legend(o: &mut String, x: f64) {
    let swatch = |o: &mut String, i: usize, fill: &str, label: &str| {
        let y = MT + 4.0 + 22.0 * i as f64;
        let _ = writeln!(
            o,
            r##"<rect x="{x:.1}" y="{y:.1}" width="22" height="14" fill="{fill}" stroke="#333" stroke-width="0.6"/><text x="{:.1}" y="{:.1}">{label}</text>"##,
            x + 30.0,
            y + 11.0
        );
    };
    swatch(o, 0, "#ffffff", "free");
    swatch(o, 1, "#000000", "occupied");
    swatch(o, 2, "#aaaaaa", "unknown");
    swatch(o, 3, "#ffbebe", "inflated (C-space) obstacle");
    let line = |o: &mut String, i: usize, style: &str, label: &str| {
        let y = MT + 11.0 + 22.0 * i as f64;
        let _ = writeln!(
            o,
            r#"<line x1="{x:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" {style}/><text x="{:.1}" y="{:.1}">{label}</text>"#,
            x + 22.0,
            x + 30.0,
            y + 4.0
        );
    };
    line(
        o,
        4,
        r##"stroke="#d62728" stroke-width="2""##,
        "searched path (grid cells)",
    );
    line(
        o,
        5,
        r##"stroke="#1f77b4" stroke-width="2" stroke-dasharray="6 4""##,
        "smoothed path (waypoints)",
    );
    let y = MT + 11.0 + 22.0 * 6.0;
    let _ = writeln!(
        o,
        r##"<circle cx="{:.1}" cy="{y:.1}" r="5" fill="#2ca02c" stroke="black" stroke-width="0.8"/><text x="{:.1}" y="{:.1}">start</text><circle cx="{:.1}" cy="{:.1}" r="5" fill="none" stroke="#9467bd" stroke-width="2.5"/><text x="{:.1}" y="{:.1}">goal</text>"##,
        x + 11.0,
        x + 30.0,
        y + 4.0,
        x + 11.0,
        y + 22.0,
        x + 30.0,
        y + 26.0
    );
}

fn xml_escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

#[cfg(test)]
mod tests {
    use super::*;
    use moma::planning::OccupancyGrid;

    fn grid(kind: MapKind) -> OccupancyGrid {
        // 40 x 30, unknown except a known 10 x 5 block at x 20..30, y 10..15
        let (w, h) = (40, 30);
        let mut cells = vec![-1i8; w * h];
        for y in 10..15 {
            for x in 20..30 {
                cells[y * w + x] = if x == 25 { 100 } else { 0 };
            }
        }
        OccupancyGrid {
            width: w,
            height: h,
            resolution: 0.05,
            origin: [-1.0, -0.5, 0.0],
            cells,
            kind,
        }
    }

    #[test]
    fn the_view_is_cropped_to_the_known_part_and_the_path() {
        let g = grid(MapKind::Ros);
        let cs = vec![false; g.width * g.height];
        let path = [(21, 11), (22, 12)];
        let scene = Scene {
            grid: &g,
            cspace: &cs,
            path: &path,
            smooth: &path,
            start: (21, 11),
            goal: (22, 12),
            title: "t".into(),
        };
        assert_eq!(
            crop(&scene),
            Crop {
                x0: 18,
                x1: 32,
                y0: 8,
                y1: 17
            }
        );
        let far = [(21, 11), (2, 3)];
        let scene = Scene {
            path: &far,
            goal: (2, 3),
            ..scene
        };
        let c = crop(&scene);
        assert_eq!((c.x0, c.y0), (0, 1));
    }

    #[test]
    fn axes_scale_bar_and_legend_are_drawn() {
        for kind in [MapKind::Ros, MapKind::MovingAi] {
            let g = grid(kind);
            let cs = vec![false; g.width * g.height];
            let path = [(21, 11), (22, 12), (23, 12)];
            let svg = render(&Scene {
                grid: &g,
                cspace: &cs,
                path: &path,
                smooth: &[(21, 11), (23, 12)],
                start: (21, 11),
                goal: (23, 12),
                title: "A*\nfound".into(),
            })
            .unwrap();
            assert!(svg.contains("searched path") && svg.contains("smoothed path"));
            if kind == MapKind::Ros {
                // x from -1 + 18·0.05 = −0.1 m to 0.6 m: tick 0.2 is drawn
                assert!(svg.contains("x [m]") && svg.contains(">0.2<"), "{svg}");
                assert!(svg.contains(" m</text>"));
            } else {
                assert!(svg.contains("x [cell]") && svg.contains(" cells</text>"));
            }
        }
        assert_eq!(scale_bar_length(0.7), 0.1);
        assert_eq!(scale_bar_length(12.0), 2.0);
    }
}

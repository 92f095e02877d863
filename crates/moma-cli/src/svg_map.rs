//! SVG pictures of planning results: the map (free, occupied, unknown, inflated
//! obstacles) as an embedded PNG, with the path and the smoothed path drawn over it.

use anyhow::Result;
use moma::planning::{MapKind, OccupancyGrid, render::grid_png};

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

fn b64(data: &[u8]) -> String {
    const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut s = String::with_capacity(data.len().div_ceil(3) * 4);
    for c in data.chunks(3) {
        let n = (c[0] as u32) << 16 | (*c.get(1).unwrap_or(&0) as u32) << 8 | *c.get(2).unwrap_or(&0) as u32;
        s.push(T[(n >> 18) as usize & 63] as char);
        s.push(T[(n >> 12) as usize & 63] as char);
        s.push(if c.len() > 1 { T[(n >> 6) as usize & 63] as char } else { '=' });
        s.push(if c.len() > 2 { T[n as usize & 63] as char } else { '=' });
    }
    s
}

/// Renders the scene as an SVG document.
pub fn render(scene: &Scene) -> Result<String> {
    let g = scene.grid;
    let (w, h) = (g.width, g.height);
    let y_up = g.kind == MapKind::Ros;
    let png = grid_png(w, h, y_up, |x, y| {
        let i = y * w + x;
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
    // Cell centre → picture coordinates.
    let px = |c: (usize, usize)| -> (f64, f64) {
        let yy = if y_up { (h - 1 - c.1) as f64 } else { c.1 as f64 };
        (c.0 as f64 + 0.5, yy + 0.5)
    };
    let poly = |cells: &[(usize, usize)]| -> String {
        cells.iter().map(|&c| {
            let (x, y) = px(c);
            format!("{x:.1},{y:.1}")
        }).collect::<Vec<_>>().join(" ")
    };
    let scale = (1000.0 / w.max(h) as f64).clamp(0.25, 16.0);
    let stroke = (1.5 / scale).max(0.3);
    let (sx, sy) = px(scene.start);
    let (gx, gy) = px(scene.goal);
    let mut s = String::new();
    s.push_str(&format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" xmlns:xlink=\"http://www.w3.org/1999/xlink\" width=\"{:.0}\" height=\"{:.0}\" viewBox=\"0 0 {w} {h}\">\n",
        w as f64 * scale,
        h as f64 * scale
    ));
    s.push_str(&format!("<title>{}</title>\n", xml_escape(&scene.title)));
    s.push_str(&format!(
        "<image x=\"0\" y=\"0\" width=\"{w}\" height=\"{h}\" style=\"image-rendering:pixelated\" preserveAspectRatio=\"none\" xlink:href=\"data:image/png;base64,{}\"/>\n",
        b64(&png)
    ));
    if scene.path.len() > 1 {
        s.push_str(&format!("<polyline points=\"{}\" fill=\"none\" stroke=\"#d62728\" stroke-width=\"{stroke:.2}\"/>\n", poly(scene.path)));
    }
    if scene.smooth.len() > 1 {
        s.push_str(&format!(
            "<polyline points=\"{}\" fill=\"none\" stroke=\"#1f77b4\" stroke-width=\"{stroke:.2}\" stroke-dasharray=\"{:.2}\"/>\n",
            poly(scene.smooth),
            3.0 * stroke
        ));
    }
    let r = (4.0 / scale).max(0.6);
    s.push_str(&format!("<circle cx=\"{sx:.1}\" cy=\"{sy:.1}\" r=\"{r:.2}\" fill=\"#2ca02c\"/>\n"));
    s.push_str(&format!("<circle cx=\"{gx:.1}\" cy=\"{gy:.1}\" r=\"{r:.2}\" fill=\"none\" stroke=\"#9467bd\" stroke-width=\"{stroke:.2}\"/>\n"));
    s.push_str("</svg>\n");
    Ok(s)
}

fn xml_escape(t: &str) -> String {
    t.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;")
}

//! A small SVG heat map for base-placement maps: the grid cells as one embedded picture
//! coloured by value (viridis-like ramp), grey where the target is unreachable, axes in
//! metres, the target and the best placement marked, a colour bar with value ticks.

use crate::svg_map::b64;
use std::fmt::Write;

/// What to draw.
pub struct HeatMap<'a> {
    /// Title line.
    pub title: &'a str,
    /// Label of the values (colour bar).
    pub value_label: &'a str,
    /// Cell values, `ny` rows of `nx`, row 0 at y0 (bottom); `None` = unreachable.
    pub cells: &'a [Option<f64>],
    /// Grid size.
    pub nx: usize,
    /// Grid size.
    pub ny: usize,
    /// World coordinates of cell centres: first x, first y, step.
    pub x0: f64,
    /// First y.
    pub y0: f64,
    /// Grid step.
    pub step: f64,
    /// Target (x, y) in world.
    pub target: Option<(f64, f64)>,
    /// Best placement (x, y, θ).
    pub best: Option<(f64, f64, f64)>,
    /// Whether larger values are better (the ramp is reversed otherwise, so bright = good).
    pub larger_is_better: bool,
}

fn ramp(t: f64) -> (u8, u8, u8) {
    // Piecewise-linear viridis approximation (dark purple → teal → yellow).
    const STOPS: [(f64, f64, f64); 5] = [
        (68.0, 1.0, 84.0),
        (59.0, 82.0, 139.0),
        (33.0, 145.0, 140.0),
        (94.0, 201.0, 98.0),
        (253.0, 231.0, 37.0),
    ];
    let t = t.clamp(0.0, 1.0) * 4.0;
    let i = (t.floor() as usize).min(3);
    let f = t - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let mix = |x: f64, y: f64| (x + (y - x) * f).round() as u8;
    (mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

const ML: f64 = 76.0;
const MT: f64 = 44.0;
const MB: f64 = 56.0;
const MR: f64 = 170.0;
const UNREACHABLE: [u8; 3] = [208, 208, 208];

/// Renders the heat map as an SVG document: the cells as one embedded picture (no seams
/// between cells), axes in metres, a colour bar drawn as a gradient with its value
/// ticks, the unreachable swatch, the target and the best placement.
pub fn render(h: &HeatMap<'_>) -> String {
    let (lo, hi) = h
        .cells
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
            (a.min(v), b.max(v))
        });
    let have = lo.is_finite() && hi.is_finite();
    let span = if have && hi > lo { hi - lo } else { 1.0 };
    let colour = |v: Option<f64>| match v {
        Some(v) => {
            let t = (v - lo) / span;
            let (r, g, b) = ramp(if h.larger_is_better { t } else { 1.0 - t });
            [r, g, b]
        }
        None => UNREACHABLE,
    };
    // Pixel size per cell: fit the map in about 600 px; whole pixels per cell in the PNG.
    let px = (600.0 / h.nx.max(h.ny) as f64).clamp(1.0, 60.0);
    let f = (px.floor() as usize).clamp(1, 16);
    let (w, hgt) = (h.nx as f64 * px, h.ny as f64 * px);
    let title_w = ML + 7.0 * h.title.chars().count() as f64;
    let (tw, th) = ((ML + w + MR).max(title_w), MT + hgt + MB);
    let png = moma::planning::render::grid_png(h.nx * f, h.ny * f, true, |x, y| {
        colour(h.cells[(y / f) * h.nx + x / f])
    });
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" width="{tw:.0}" height="{th:.0}" viewBox="0 0 {tw:.0} {th:.0}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{ML}" y="24" font-size="13">{}</text>"#,
        esc(h.title)
    );
    match png {
        Ok(png) => {
            let _ = writeln!(
                s,
                r#"<image x="{ML}" y="{MT}" width="{w:.2}" height="{hgt:.2}" style="image-rendering:pixelated" preserveAspectRatio="none" xlink:href="data:image/png;base64,{}"/>"#,
                b64(&png)
            );
        }
        Err(_) => {
            // cannot happen for a grid of the sizes PlacementGrid allows; draw nothing
        }
    }
    let _ = writeln!(
        s,
        r##"<rect x="{ML}" y="{MT}" width="{w:.2}" height="{hgt:.2}" fill="none" stroke="#333"/>"##
    );
    axes(&mut s, h, px, w, hgt);
    markers(&mut s, h, px, hgt);
    colour_bar(&mut s, h, (lo, hi, have), ML + w + 24.0, hgt);
    s.push_str("</svg>\n");
    s
}

/// World (x, y) → picture; cell (ix, iy) is centred at (x0 + ix·step, y0 + iy·step).
fn to_px(h: &HeatMap<'_>, px: f64, hgt: f64, x: f64, y: f64) -> (f64, f64) {
    (
        ML + ((x - h.x0) / h.step + 0.5) * px,
        MT + hgt - ((y - h.y0) / h.step + 0.5) * px,
    )
}

fn axes(s: &mut String, h: &HeatMap<'_>, px: f64, w: f64, hgt: f64) {
    let half = 0.5 * h.step;
    let (xa, xb) = (h.x0 - half, h.x0 + (h.nx as f64 - 0.5) * h.step);
    let (ya, yb) = (h.y0 - half, h.y0 + (h.ny as f64 - 0.5) * h.step);
    for t in crate::svg_plots::ticks(xa, xb) {
        let (x, _) = to_px(h, px, hgt, t, h.y0);
        let _ = writeln!(
            s,
            r##"<line x1="{x:.1}" y1="{:.1}" x2="{x:.1}" y2="{:.1}" stroke="#333"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
            MT + hgt,
            MT + hgt + 5.0,
            MT + hgt + 18.0,
            crate::svg_plots::fmt_tick(t)
        );
    }
    for t in crate::svg_plots::ticks(ya, yb) {
        let (_, y) = to_px(h, px, hgt, h.x0, t);
        let _ = writeln!(
            s,
            r##"<line x1="{:.1}" y1="{y:.1}" x2="{ML}" y2="{y:.1}" stroke="#333"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
            ML - 5.0,
            ML - 8.0,
            y + 4.0,
            crate::svg_plots::fmt_tick(t)
        );
    }
    let _ = writeln!(
        s,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">base x [m]</text><text x="18" y="{:.1}" text-anchor="middle" transform="rotate(-90 18 {:.1})">base y [m]</text>"#,
        ML + w / 2.0,
        MT + hgt + 40.0,
        MT + hgt / 2.0,
        MT + hgt / 2.0
    );
}

fn markers(s: &mut String, h: &HeatMap<'_>, px: f64, hgt: f64) {
    if let Some((tx, ty)) = h.target {
        let (x, y) = to_px(h, px, hgt, tx, ty);
        let _ = writeln!(
            s,
            r#"<g stroke="red" stroke-width="2"><line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}"/><line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}"/></g><text x="{:.1}" y="{:.1}" fill="red" stroke="white" stroke-width="3" paint-order="stroke">target</text>"#,
            x - 7.0,
            y - 7.0,
            x + 7.0,
            y + 7.0,
            x - 7.0,
            y + 7.0,
            x + 7.0,
            y - 7.0,
            x + 9.0,
            y - 9.0
        );
    }
    if let Some((bx, by, bth)) = h.best {
        let (x, y) = to_px(h, px, hgt, bx, by);
        let len = (px * 1.5).max(14.0);
        let (x2, y2) = (x + len * bth.cos(), y - len * bth.sin());
        let _ = writeln!(
            s,
            r#"<circle cx="{x:.1}" cy="{y:.1}" r="5" fill="white" stroke="black" stroke-width="2"/><line x1="{x:.1}" y1="{y:.1}" x2="{x2:.1}" y2="{y2:.1}" stroke="black" stroke-width="2"/><text x="{:.1}" y="{:.1}" stroke="white" stroke-width="3" paint-order="stroke">best</text>"#,
            x + 8.0,
            y + 16.0
        );
    }
}

/// The colour bar (a gradient: no seams), its value ticks, the measure's name and the
/// unreachable swatch.
fn colour_bar(
    s: &mut String,
    h: &HeatMap<'_>,
    (lo, hi, have): (f64, f64, bool),
    cx: f64,
    hgt: f64,
) {
    let (cy, cw, ch) = (MT, 18.0, hgt.min(300.0));
    let _ = writeln!(
        s,
        r#"<defs><linearGradient id="ramp" x1="0" y1="1" x2="0" y2="0">"#
    );
    for k in 0..=8 {
        let t = k as f64 / 8.0;
        let (r, g, b) = ramp(if h.larger_is_better { t } else { 1.0 - t });
        let _ = writeln!(
            s,
            r##"<stop offset="{t:.3}" stop-color="#{r:02x}{g:02x}{b:02x}"/>"##
        );
    }
    let _ = writeln!(s, "</linearGradient></defs>");
    let _ = writeln!(
        s,
        r##"<rect x="{cx:.1}" y="{cy:.1}" width="{cw}" height="{ch:.1}" fill="url(#ramp)" stroke="#333"/>"##
    );
    if have {
        let ticks: Vec<f64> = if hi > lo {
            crate::svg_plots::ticks(lo, hi)
        } else {
            vec![lo]
        };
        for t in ticks {
            let y = if hi > lo {
                cy + ch * (1.0 - (t - lo) / (hi - lo))
            } else {
                cy + ch / 2.0
            };
            let _ = writeln!(
                s,
                r##"<line x1="{:.1}" y1="{y:.1}" x2="{:.1}" y2="{y:.1}" stroke="#333"/><text x="{:.1}" y="{:.1}">{}</text>"##,
                cx + cw,
                cx + cw + 4.0,
                cx + cw + 7.0,
                y + 4.0,
                crate::svg_plots::fmt_tick(t)
            );
        }
    } else {
        let _ = writeln!(
            s,
            r#"<text x="{:.1}" y="{:.1}">no reachable pose</text>"#,
            cx + cw + 6.0,
            cy + ch / 2.0
        );
    }
    let [r, g, b] = UNREACHABLE;
    let _ = writeln!(
        s,
        r##"<text x="{cx:.1}" y="{:.1}">{}{}</text><rect x="{cx:.1}" y="{:.1}" width="{cw}" height="12" fill="#{r:02x}{g:02x}{b:02x}" stroke="#333"/><text x="{:.1}" y="{:.1}">unreachable</text>"##,
        cy + ch + 20.0,
        esc(h.value_label),
        if h.larger_is_better {
            ""
        } else {
            " (lower is better)"
        },
        cy + ch + 30.0,
        cx + cw + 6.0,
        cy + ch + 40.0
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn axes_colour_bar_and_labels_fit_the_picture() {
        let cells = [Some(0.1), None, Some(0.3), Some(0.2)];
        let h = HeatMap {
            title: "t",
            value_label: "yoshikawa",
            cells: &cells,
            nx: 2,
            ny: 2,
            x0: 0.0,
            y0: -0.5,
            step: 0.5,
            target: Some((0.25, 0.0)),
            best: Some((0.0, 0.0, 0.5)),
            larger_is_better: true,
        };
        let svg = render(&h);
        assert!(svg.contains("base x [m]") && svg.contains("base y [m]"));
        assert!(svg.contains("unreachable") && svg.contains("url(#ramp)"));
        // one picture for the cells, not one rectangle per cell
        assert_eq!(svg.matches("<image").count(), 1);
        // every text starts inside the picture's width
        let width: f64 = svg
            .split("width=\"")
            .nth(1)
            .and_then(|r| r.split('"').next())
            .and_then(|w| w.parse().ok())
            .unwrap();
        for part in svg.split("<text x=\"").skip(1) {
            let x: f64 = part.split('"').next().unwrap().parse().unwrap();
            assert!(x >= 0.0 && x < width - 60.0, "text at {x} in {width}");
        }
    }
}

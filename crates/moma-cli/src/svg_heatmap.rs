//! A small, dependency-free SVG heat map for base-placement maps: one rectangle per grid
//! cell coloured by value (viridis-like ramp), grey where the target is unreachable, the
//! target and the best placement marked, a colour bar with the value range.

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

/// Renders the heat map as an SVG document.
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
    // Pixel size per cell: fit the map in about 600 px.
    let px = (600.0 / h.nx.max(h.ny) as f64).clamp(1.0, 60.0);
    let (w, hgt) = (h.nx as f64 * px, h.ny as f64 * px);
    let (ml, mt, mr, mb) = (60.0, 40.0, 110.0, 50.0);
    let (tw, th) = (ml + w + mr, mt + hgt + mb);
    let mut s = String::new();
    let _ = writeln!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{tw:.0}" height="{th:.0}" viewBox="0 0 {tw:.0} {th:.0}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(s, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        s,
        r#"<text x="{ml}" y="24" font-size="14">{}</text>"#,
        esc(h.title)
    );
    // World (x, y) → pixel; cell (ix, iy) centred at x0 + ix·step.
    let to_px = |x: f64, y: f64| {
        (
            ml + ((x - h.x0) / h.step + 0.5) * px,
            mt + hgt - ((y - h.y0) / h.step + 0.5) * px,
        )
    };
    let _ = writeln!(s, r#"<g shape-rendering="crispEdges">"#);
    for iy in 0..h.ny {
        for ix in 0..h.nx {
            let fill = match h.cells[iy * h.nx + ix] {
                Some(v) => {
                    let mut t = (v - lo) / span;
                    if !h.larger_is_better {
                        t = 1.0 - t;
                    }
                    let (r, g, b) = ramp(t);
                    format!("#{r:02x}{g:02x}{b:02x}")
                }
                None => "#d0d0d0".to_string(),
            };
            let x = ml + ix as f64 * px;
            let y = mt + hgt - (iy + 1) as f64 * px;
            let _ = writeln!(
                s,
                r#"<rect x="{x:.2}" y="{y:.2}" width="{px:.2}" height="{px:.2}" fill="{fill}"/>"#
            );
        }
    }
    let _ = writeln!(s, "</g>");
    let _ = writeln!(
        s,
        r#"<rect x="{ml}" y="{mt}" width="{w:.2}" height="{hgt:.2}" fill="none" stroke="black"/>"#
    );
    // Axes labels (corner coordinates).
    let x_last = h.x0 + (h.nx - 1) as f64 * h.step;
    let y_last = h.y0 + (h.ny - 1) as f64 * h.step;
    let _ = writeln!(
        s,
        r#"<text x="{ml}" y="{:.0}">x = {:.3} m</text><text x="{:.0}" y="{:.0}" text-anchor="end">x = {:.3} m</text>"#,
        mt + hgt + 18.0,
        h.x0,
        ml + w,
        mt + hgt + 18.0,
        x_last
    );
    let _ = writeln!(
        s,
        r#"<text x="{:.0}" y="{:.0}" text-anchor="end">y = {:.3}</text><text x="{:.0}" y="{:.0}" text-anchor="end">y = {:.3}</text>"#,
        ml - 4.0,
        mt + hgt,
        h.y0,
        ml - 4.0,
        mt + 10.0,
        y_last
    );
    if let Some((tx, ty)) = h.target {
        let (x, y) = to_px(tx, ty);
        let _ = writeln!(
            s,
            r#"<g stroke="red" stroke-width="2"><line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}"/><line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}"/></g><text x="{:.1}" y="{:.1}" fill="red">target</text>"#,
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
        let (x, y) = to_px(bx, by);
        let len = (px * 1.5).max(14.0);
        let (x2, y2) = (x + len * bth.cos(), y - len * bth.sin());
        let _ = writeln!(
            s,
            r#"<circle cx="{x:.1}" cy="{y:.1}" r="5" fill="white" stroke="black" stroke-width="2"/><line x1="{x:.1}" y1="{y:.1}" x2="{x2:.1}" y2="{y2:.1}" stroke="black" stroke-width="2"/><text x="{:.1}" y="{:.1}">best</text>"#,
            x + 8.0,
            y + 14.0
        );
    }
    // Colour bar.
    let (cx, cy, cw, ch) = (ml + w + 25.0, mt, 18.0, hgt.min(300.0));
    for k in 0..50 {
        let t = 1.0 - k as f64 / 49.0;
        let (r, g, b) = ramp(if h.larger_is_better { t } else { 1.0 - t });
        let _ = writeln!(
            s,
            r##"<rect x="{cx:.1}" y="{:.2}" width="{cw}" height="{:.2}" fill="#{r:02x}{g:02x}{b:02x}"/>"##,
            cy + k as f64 * ch / 50.0,
            ch / 50.0 + 0.5
        );
    }
    let (top, bottom) = if have { (hi, lo) } else { (f64::NAN, f64::NAN) };
    let fmt = |v: f64| {
        if v.is_finite() {
            format!("{v:.4}")
        } else {
            "n/a".to_string()
        }
    };
    let _ = writeln!(
        s,
        r#"<text x="{:.1}" y="{:.1}">{}</text><text x="{:.1}" y="{:.1}">{}</text><text x="{:.1}" y="{:.1}">{}</text>"#,
        cx + cw + 4.0,
        cy + 10.0,
        fmt(top),
        cx + cw + 4.0,
        cy + ch,
        fmt(bottom),
        cx,
        cy + ch + 18.0,
        esc(h.value_label)
    );
    let _ = writeln!(
        s,
        r##"<rect x="{cx:.1}" y="{:.1}" width="{cw}" height="12" fill="#d0d0d0"/><text x="{:.1}" y="{:.1}">unreachable</text>"##,
        cy + ch + 26.0,
        cx + cw + 4.0,
        cy + ch + 36.0
    );
    s.push_str("</svg>\n");
    s
}

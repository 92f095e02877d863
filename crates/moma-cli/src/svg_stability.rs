//! SVG drawings of `moma stability-map`: a polar plot of the tip-over acceleration limits
//! over the direction of travel, and a heat map of the ZMP margin over two arm joints
//! with a diverging ramp (red = outside the support, white = on an edge, green = inside).

use std::fmt::Write;

/// Polar plot of `limits[k]` (m/s², `None` = unlimited or undefined) at the base-frame
/// directions `angles[k]` (rad, 0 = forward, π/2 = left).
pub fn polar(title: &str, angles: &[f64], limits: &[Option<f64>]) -> String {
    let (w, h) = (560.0, 600.0);
    let (cx, cy, rad) = (280.0, 320.0, 220.0);
    let rmax = limits.iter().flatten().fold(0.0_f64, |a, &b| a.max(b));
    let rmax = if rmax > 0.0 { nice_ceiling(rmax) } else { 1.0 };
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#
    );
    let _ = write!(s, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    let _ = write!(
        s,
        r#"<text x="{cx}" y="28" text-anchor="middle" font-size="15">{}</text>"#,
        escape(title)
    );
    for k in 1..=4 {
        let r = rad * f64::from(k) / 4.0;
        let _ = write!(
            s,
            r##"<circle cx="{cx}" cy="{cy}" r="{r:.1}" fill="none" stroke="#ccc"/><text x="{:.1}" y="{:.1}" fill="#666">{:.3} m/s²</text>"##,
            cx + 3.0,
            cy - r - 3.0,
            rmax * f64::from(k) / 4.0
        );
    }
    // forward is up on the page, left is to the left
    for (label, ang) in [
        ("forward", 0.0_f64),
        ("left", 90.0),
        ("backward", 180.0),
        ("right", 270.0),
    ] {
        let a = ang.to_radians();
        let (x, y) = (cx - (rad + 22.0) * a.sin(), cy - (rad + 22.0) * a.cos());
        let (x1, y1) = (cx - rad * a.sin(), cy - rad * a.cos());
        let _ = write!(
            s,
            r##"<line x1="{cx}" y1="{cy}" x2="{x1:.1}" y2="{y1:.1}" stroke="#ddd"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{label}</text>"##,
            y + 4.0
        );
    }
    let mut path = String::new();
    let mut pen_up = true;
    for (a, l) in angles.iter().zip(limits) {
        match l {
            Some(l) => {
                let r = rad * (l / rmax).min(1.0);
                let (x, y) = (cx - r * a.sin(), cy - r * a.cos());
                let _ = write!(path, "{}{x:.2},{y:.2} ", if pen_up { "M" } else { "L" });
                pen_up = false;
            }
            None => pen_up = true,
        }
    }
    if let (Some(Some(first)), Some(Some(_))) = (limits.first(), limits.last()) {
        let r = rad * (first / rmax).min(1.0);
        let a = angles[0];
        let _ = write!(path, "L{:.2},{:.2}", cx - r * a.sin(), cy - r * a.cos());
    }
    let _ = write!(
        s,
        r##"<path d="{path}" fill="#4a90d9" fill-opacity="0.25" stroke="#1f5fa8" stroke-width="2"/>"##
    );
    let _ = write!(
        s,
        r##"<text x="{cx}" y="{}" text-anchor="middle" fill="#444">largest platform acceleration before the ZMP leaves the support (base axes)</text>"##,
        h - 14.0
    );
    s.push_str("</svg>\n");
    s
}

/// What the margin heat map shows.
pub struct MarginMap<'a> {
    /// Title line.
    pub title: &'a str,
    /// Joint names on the x and y axes.
    pub x_label: &'a str,
    /// Joint on the y axis.
    pub y_label: &'a str,
    /// Joint values of the columns and rows.
    pub xs: &'a [f64],
    /// Rows.
    pub ys: &'a [f64],
    /// Margins, `ys.len()` rows of `xs.len()`, row 0 at `ys[0]` (bottom); `None` = no ZMP.
    pub cells: &'a [Option<f64>],
}

/// Heat map of the ZMP margin over two joints.
pub fn margin_map(m: &MarginMap<'_>) -> String {
    let (nx, ny) = (m.xs.len(), m.ys.len());
    let (left, top, pw, ph) = (80.0, 50.0, 480.0, 420.0);
    let (w, h) = (left + pw + 120.0, top + ph + 70.0);
    let amax = m
        .cells
        .iter()
        .flatten()
        .fold(0.0_f64, |a, &b| a.max(b.abs()))
        .max(1e-12);
    let mut s = String::new();
    let _ = write!(
        s,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{h}" viewBox="0 0 {w} {h}" font-family="sans-serif" font-size="12">"#
    );
    let _ = write!(s, r#"<rect width="{w}" height="{h}" fill="white"/>"#);
    let _ = write!(
        s,
        r#"<text x="{:.1}" y="28" text-anchor="middle" font-size="15">{}</text>"#,
        left + pw / 2.0,
        escape(m.title)
    );
    let (cw, ch) = (pw / nx as f64, ph / ny as f64);
    for j in 0..ny {
        for i in 0..nx {
            let fill = match m.cells[j * nx + i] {
                Some(v) => diverging(v / amax),
                None => "#888888".to_string(),
            };
            let (x, y) = (left + i as f64 * cw, top + ph - (j + 1) as f64 * ch);
            let _ = write!(
                s,
                r#"<rect x="{x:.2}" y="{y:.2}" width="{:.2}" height="{:.2}" fill="{fill}"/>"#,
                cw + 0.3,
                ch + 0.3
            );
        }
    }
    let _ = write!(
        s,
        r#"<rect x="{left}" y="{top}" width="{pw}" height="{ph}" fill="none" stroke="black"/>"#
    );
    for frac in [0.0, 0.5, 1.0] {
        let xi = ((nx - 1) as f64 * frac).round() as usize;
        let yi = ((ny - 1) as f64 * frac).round() as usize;
        let x = left + (xi as f64 + 0.5) * cw;
        let y = top + ph - (yi as f64 + 0.5) * ch;
        let _ = write!(
            s,
            r#"<text x="{x:.1}" y="{:.1}" text-anchor="middle">{:.2}</text><text x="{:.1}" y="{:.1}" text-anchor="end">{:.2}</text>"#,
            top + ph + 16.0,
            m.xs[xi],
            left - 6.0,
            y + 4.0,
            m.ys[yi]
        );
    }
    let _ = write!(
        s,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">{} (rad)</text>"#,
        left + pw / 2.0,
        top + ph + 38.0,
        escape(m.x_label)
    );
    let _ = write!(
        s,
        r#"<text transform="translate(22,{:.1}) rotate(-90)" text-anchor="middle">{} (rad)</text>"#,
        top + ph / 2.0,
        escape(m.y_label)
    );
    // colour bar
    let bx = left + pw + 30.0;
    for k in 0..50 {
        let t = 1.0 - 2.0 * f64::from(k) / 49.0;
        let y = top + ph * f64::from(k) / 50.0;
        let _ = write!(
            s,
            r#"<rect x="{bx}" y="{y:.2}" width="20" height="{:.2}" fill="{}"/>"#,
            ph / 50.0 + 0.3,
            diverging(t)
        );
    }
    let _ = write!(
        s,
        r#"<text x="{:.1}" y="{:.1}">+{amax:.3} m</text><text x="{:.1}" y="{:.1}">0</text><text x="{:.1}" y="{:.1}">−{amax:.3} m</text><text x="{:.1}" y="{:.1}" font-size="11">ZMP margin</text>"#,
        bx + 24.0,
        top + 10.0,
        bx + 24.0,
        top + ph / 2.0 + 4.0,
        bx + 24.0,
        top + ph,
        bx - 10.0,
        top - 8.0
    );
    s.push_str("</svg>\n");
    s
}

/// Red (−1) → white (0) → green (+1).
fn diverging(t: f64) -> String {
    let t = t.clamp(-1.0, 1.0);
    let (r, g, b) = if t >= 0.0 {
        (255.0 - 229.0 * t, 255.0 - 103.0 * t, 255.0 - 190.0 * t)
    } else {
        let u = -t;
        (255.0 - 40.0 * u, 255.0 - 215.0 * u, 255.0 - 215.0 * u)
    };
    format!("#{:02x}{:02x}{:02x}", r as u8, g as u8, b as u8)
}

fn nice_ceiling(x: f64) -> f64 {
    let p = 10f64.powf(x.log10().floor());
    for m in [1.0, 2.0, 2.5, 5.0, 10.0] {
        if m * p >= x {
            return m * p;
        }
    }
    10.0 * p
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

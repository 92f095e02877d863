//! Small, dependency-free SVG line charts for simulation outputs: time series with axes,
//! ticks and a legend, and an equal-aspect x–y path plot.

use std::fmt::Write;

const W: f64 = 720.0;
const H: f64 = 420.0;
const ML: f64 = 80.0;
const MR: f64 = 160.0;
const MT: f64 = 40.0;
const MB: f64 = 56.0;
const COLORS: [&str; 8] = [
    "#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#e377c2", "#17becf",
];

/// One named curve `(x_i, y_i)`.
pub struct Series<'a> {
    /// Legend label.
    pub name: &'a str,
    /// Abscissae.
    pub x: &'a [f64],
    /// Ordinates.
    pub y: Vec<f64>,
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
}

/// "Nice" tick positions covering `[lo, hi]`.
pub(crate) fn ticks(lo: f64, hi: f64) -> Vec<f64> {
    let span = (hi - lo).max(1e-300);
    let raw = span / 6.0;
    let mag = 10f64.powf(raw.log10().floor());
    let step = [1.0, 2.0, 5.0, 10.0]
        .iter()
        .map(|m| m * mag)
        .find(|s| span / s <= 7.0)
        .unwrap_or(10.0 * mag);
    let mut t = (lo / step).ceil() * step;
    let mut out = Vec::new();
    while t <= hi + 1e-9 * step && out.len() < 20 {
        out.push(if t.abs() < 1e-12 * step { 0.0 } else { t });
        t += step;
    }
    out
}

pub(crate) fn fmt_tick(x: f64) -> String {
    if x == 0.0 {
        "0".into()
    } else if x.abs() >= 1e4 || x.abs() < 1e-3 {
        format!("{x:.1e}")
    } else {
        let s = format!("{x:.4}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    }
}

fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values.filter(|v| v.is_finite()) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (-1.0, 1.0);
    }
    if hi - lo < 1e-12 * (1.0 + lo.abs()) {
        let pad = 0.5 * (1.0 + lo.abs()) * 1e-3;
        return (lo - pad.max(1e-12), hi + pad.max(1e-12));
    }
    let pad = 0.05 * (hi - lo);
    (lo - pad, hi + pad)
}

struct Frame {
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    pw: f64,
    ph: f64,
}

impl Frame {
    fn px(&self, x: f64) -> f64 {
        ML + (x - self.x0) / (self.x1 - self.x0) * self.pw
    }
    fn py(&self, y: f64) -> f64 {
        MT + (1.0 - (y - self.y0) / (self.y1 - self.y0)) * self.ph
    }
}

fn axes(svg: &mut String, f: &Frame, title: &str, xlabel: &str, ylabel: &str) {
    let _ = write!(
        svg,
        r##"<rect x="{ML}" y="{MT}" width="{}" height="{}" fill="white" stroke="#333"/>"##,
        f.pw, f.ph
    );
    for t in ticks(f.x0, f.x1) {
        let x = f.px(t);
        let _ = write!(
            svg,
            r##"<line x1="{x:.2}" y1="{MT}" x2="{x:.2}" y2="{}" stroke="#e5e5e5"/><text x="{x:.2}" y="{}" font-size="11" text-anchor="middle">{}</text>"##,
            MT + f.ph,
            MT + f.ph + 16.0,
            fmt_tick(t)
        );
    }
    for t in ticks(f.y0, f.y1) {
        let y = f.py(t);
        let _ = write!(
            svg,
            r##"<line x1="{ML}" y1="{y:.2}" x2="{}" y2="{y:.2}" stroke="#e5e5e5"/><text x="{}" y="{:.2}" font-size="11" text-anchor="end">{}</text>"##,
            ML + f.pw,
            ML - 6.0,
            y + 4.0,
            fmt_tick(t)
        );
    }
    // A title with a newline takes two smaller lines above the plot.
    let lines: Vec<&str> = title.lines().collect();
    let (size, y0) = if lines.len() > 1 {
        (13, 16.0)
    } else {
        (15, 24.0)
    };
    for (i, line) in lines.iter().enumerate() {
        let _ = write!(
            svg,
            r#"<text x="{}" y="{}" font-size="{size}" text-anchor="middle">{}</text>"#,
            W / 2.0,
            y0 + 16.0 * i as f64,
            escape(line)
        );
    }
    let _ = write!(
        svg,
        r#"<text x="{}" y="{}" font-size="12" text-anchor="middle">{}</text><text x="18" y="{}" font-size="12" text-anchor="middle" transform="rotate(-90 18 {})">{}</text>"#,
        ML + f.pw / 2.0,
        H - 12.0,
        escape(xlabel),
        MT + f.ph / 2.0,
        MT + f.ph / 2.0,
        escape(ylabel)
    );
}

fn polyline(svg: &mut String, f: &Frame, x: &[f64], y: &[f64], color: &str) {
    let mut pts = String::new();
    for (a, b) in x.iter().zip(y) {
        if a.is_finite() && b.is_finite() {
            let _ = write!(pts, "{:.2},{:.2} ", f.px(*a), f.py(*b));
        }
    }
    let _ = write!(
        svg,
        r#"<polyline points="{}" fill="none" stroke="{color}" stroke-width="1.6"/>"#,
        pts.trim_end()
    );
}

/// The width the legend takes right of the plot (px): its 14 px gap, the 28 px sample
/// line, the longest name at 12 px sans-serif (at most 7.5 px a character) and a margin.
fn legend_width(names: &[&str]) -> f64 {
    let longest = names.iter().map(|n| n.chars().count()).max().unwrap_or(0);
    14.0 + 28.0 + 7.5 * longest as f64 + 10.0
}

fn legend(svg: &mut String, names: &[&str]) {
    for (i, n) in names.iter().enumerate() {
        let y = MT + 14.0 + 18.0 * i as f64;
        let x = W - MR + 14.0;
        let _ = write!(
            svg,
            r#"<line x1="{x}" y1="{y}" x2="{}" y2="{y}" stroke="{}" stroke-width="2.5"/><text x="{}" y="{}" font-size="12">{}</text>"#,
            x + 22.0,
            COLORS[i % COLORS.len()],
            x + 28.0,
            y + 4.0,
            escape(n)
        );
    }
}

/// A time-series chart of several curves sharing one y axis.
pub fn line_chart(title: &str, xlabel: &str, ylabel: &str, series: &[Series<'_>]) -> String {
    let (x0, x1) = range(series.iter().flat_map(|s| s.x.iter().copied()));
    let (y0, y1) = range(series.iter().flat_map(|s| s.y.iter().copied()));
    let f = Frame {
        x0,
        x1,
        y0,
        y1,
        pw: W - ML - MR,
        ph: H - MT - MB,
    };
    // the figure widens so that the longest legend entry fits right of the plot
    let names: Vec<&str> = series.iter().map(|s| s.name).collect();
    let width = W.max(W - MR + legend_width(&names));
    let mut svg = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{H}" viewBox="0 0 {width} {H}" font-family="sans-serif">"#
    );
    axes(&mut svg, &f, title, xlabel, ylabel);
    for (i, s) in series.iter().enumerate() {
        polyline(&mut svg, &f, s.x, &s.y, COLORS[i % COLORS.len()]);
    }
    legend(&mut svg, &names);
    svg.push_str("</svg>\n");
    svg
}

/// The points `(x_i, y_i)` of each series as markers, on equal x and y ranges, with the
/// line y = x across the plot (dashed grey, last in the legend).
pub fn identity_scatter_chart(
    title: &str,
    xlabel: &str,
    ylabel: &str,
    series: &[Series<'_>],
) -> String {
    let (lo, hi) = range(
        series
            .iter()
            .flat_map(|s| s.x.iter().chain(s.y.iter()).copied()),
    );
    let f = Frame {
        x0: lo,
        x1: hi,
        y0: lo,
        y1: hi,
        pw: W - ML - MR,
        ph: H - MT - MB,
    };
    let mut names: Vec<&str> = series.iter().map(|s| s.name).collect();
    let identity = "y = x";
    names.push(identity);
    let width = W.max(W - MR + legend_width(&names));
    let mut svg = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{width}" height="{H}" viewBox="0 0 {width} {H}" font-family="sans-serif">"#
    );
    axes(&mut svg, &f, title, xlabel, ylabel);
    let _ = write!(
        svg,
        r##"<line x1="{:.2}" y1="{:.2}" x2="{:.2}" y2="{:.2}" stroke="#888" stroke-width="1.2" stroke-dasharray="6 4"/>"##,
        f.px(lo),
        f.py(lo),
        f.px(hi),
        f.py(hi)
    );
    for (i, s) in series.iter().enumerate() {
        let color = COLORS[i % COLORS.len()];
        for (a, b) in s.x.iter().zip(&s.y) {
            if a.is_finite() && b.is_finite() {
                let _ = write!(
                    svg,
                    r#"<circle cx="{:.2}" cy="{:.2}" r="4" fill="{color}" fill-opacity="0.8"/>"#,
                    f.px(*a),
                    f.py(*b)
                );
            }
        }
    }
    legend(&mut svg, &names[..series.len()]);
    let (x, y) = (W - MR + 14.0, MT + 14.0 + 18.0 * series.len() as f64);
    let _ = write!(
        svg,
        r##"<line x1="{x}" y1="{y}" x2="{}" y2="{y}" stroke="#888" stroke-width="1.2" stroke-dasharray="6 4"/><text x="{}" y="{}" font-size="12">{identity}</text>"##,
        x + 22.0,
        x + 28.0,
        y + 4.0
    );
    svg.push_str("</svg>\n");
    svg
}

/// The path `(x(t), y(t))` in the plane with equal axis scales, start and end marked.
pub fn path_chart(title: &str, x: &[f64], y: &[f64]) -> String {
    let (mut x0, mut x1) = range(x.iter().copied());
    let (mut y0, mut y1) = range(y.iter().copied());
    let (pw, ph) = (W - ML - MR, H - MT - MB);
    // Equal scale: widen the narrower range.
    let sx = (x1 - x0) / pw;
    let sy = (y1 - y0) / ph;
    if sx > sy {
        let c = 0.5 * (y0 + y1);
        let half = 0.5 * sx * ph;
        y0 = c - half;
        y1 = c + half;
    } else {
        let c = 0.5 * (x0 + x1);
        let half = 0.5 * sy * pw;
        x0 = c - half;
        x1 = c + half;
    }
    let f = Frame {
        x0,
        x1,
        y0,
        y1,
        pw,
        ph,
    };
    let mut svg = format!(
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" viewBox="0 0 {W} {H}" font-family="sans-serif">"#
    );
    axes(&mut svg, &f, title, "x [m]", "y [m]");
    polyline(&mut svg, &f, x, y, COLORS[0]);
    if let (Some(&xs), Some(&ys), Some(&xe), Some(&ye)) = (x.first(), y.first(), x.last(), y.last())
    {
        let _ = write!(
            svg,
            r##"<circle cx="{:.2}" cy="{:.2}" r="4" fill="#2ca02c"/><circle cx="{:.2}" cy="{:.2}" r="4" fill="#d62728"/>"##,
            f.px(xs),
            f.py(ys),
            f.px(xe),
            f.py(ye)
        );
    }
    legend(&mut svg, &["path"]);
    let _ = write!(
        svg,
        r##"<circle cx="{}" cy="{}" r="4" fill="#2ca02c"/><text x="{}" y="{}" font-size="12">start</text><circle cx="{}" cy="{}" r="4" fill="#d62728"/><text x="{}" y="{}" font-size="12">end</text>"##,
        W - MR + 25.0,
        MT + 32.0,
        W - MR + 42.0,
        MT + 36.0,
        W - MR + 25.0,
        MT + 50.0,
        W - MR + 42.0,
        MT + 54.0
    );
    svg.push_str("</svg>\n");
    svg
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The joint torques' legend (long joint names) stays inside the figure: the figure
    /// is as wide as the longest entry needs at 7.5 px a character.
    #[test]
    fn a_long_legend_entry_fits_inside_the_figure() {
        let (x, y) = ([0.0, 1.0], [0.0, 1.0]);
        let name = "tau_shoulder_lift_joint_with_a_long_name";
        let svg = line_chart(
            "t",
            "t [s]",
            "τ",
            &[Series {
                name,
                x: &x,
                y: y.to_vec(),
            }],
        );
        let width: f64 = svg
            .split("width=\"")
            .nth(1)
            .and_then(|r| r.split('"').next())
            .unwrap()
            .parse()
            .unwrap();
        let text_start: f64 = svg
            .split(&format!(">{name}<"))
            .next()
            .and_then(|head| head.rsplit("<text x=\"").next())
            .and_then(|r| r.split('"').next())
            .unwrap()
            .parse()
            .unwrap();
        assert!(
            text_start + 7.5 * name.len() as f64 <= width,
            "legend text from {text_start} px, {} chars, figure {width} px",
            name.len()
        );
    }

    #[test]
    fn charts_are_well_formed_svg() {
        let t = [0.0, 0.5, 1.0];
        let svg = line_chart(
            "energy",
            "t [s]",
            "J",
            &[Series {
                name: "a<b",
                x: &t,
                y: vec![1.0, 2.0, f64::NAN],
            }],
        );
        assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
        assert!(svg.contains("a&lt;b") && !svg.contains("NaN"));
        let p = path_chart("path", &[0.0, 1.0], &[0.0, 0.0]);
        assert!(p.contains("polyline"));
        let sc = identity_scatter_chart(
            "a vs b",
            "a",
            "b",
            &[Series {
                name: "s",
                x: &[1.0, 2.0, f64::NAN],
                y: vec![1.1, 1.9, 3.0],
            }],
        );
        assert_eq!(sc.matches("<circle").count(), 2);
        assert!(sc.contains("y = x") && !sc.contains("NaN"));
        assert!(p.contains("polyline"));
        let tk = ticks(0.0, 1.0);
        assert_eq!(tk.len(), 6);
        assert!((tk[5] - 1.0).abs() < 1e-12 && tk[0] == 0.0);
    }
}

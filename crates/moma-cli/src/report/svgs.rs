//! The static figures beside the report: the top view on the map and the time plots
//! (through the CLI's line charts).

use super::embed::{MAX_SAMPLES, html_escape, kept_samples};
use super::numbers::decimate_indices;
use super::{MissionReport, map};
use crate::svg_plots::{Series, fmt_tick, line_chart, ticks};
use std::fmt::Write;

const ML: f64 = 70.0;
const MT: f64 = 46.0;
const MB: f64 = 50.0;
const MR: f64 = 230.0;

/// Every figure, in a fixed order.
pub(crate) fn render(r: &MissionReport) -> Vec<(String, String)> {
    // the same samples as the page: a few thousand, extremes kept
    let idx = decimate_indices(r.samples.t.len(), MAX_SAMPLES, &kept_samples(r));
    let mut out = vec![("top_view.svg".to_string(), top_view(r, &idx))];
    out.extend(time_plots(r, &idx));
    out
}

/// One named series over the times `x`.
fn series<'a>(name: &'a str, x: &'a [f64], y: Vec<f64>) -> Series<'a> {
    Series { name, x, y }
}

/// The time plots of the samples `idx`: speed, turn rate, ZMP margin, Force-Angle
/// measure, tracking error and clearance, and the joint torques when there are any.
fn time_plots(r: &MissionReport, idx: &[usize]) -> Vec<(String, String)> {
    let s = &r.samples;
    let pick = |v: &[f64]| -> Vec<f64> { idx.iter().map(|&i| v[i]).collect() };
    let opt =
        |v: &[Option<f64>]| -> Vec<f64> { idx.iter().map(|&i| v[i].unwrap_or(f64::NAN)).collect() };
    let t = &pick(&s.t);
    let chart = |title: &str, ylabel: &str, series: Vec<Series<'_>>| -> String {
        line_chart(&format!("{}\n{title}", r.title), "t [s]", ylabel, &series)
    };
    let mut out = vec![
        (
            "speed.svg".into(),
            chart(
                "forward speed: executed and reference",
                "v [m/s]",
                vec![
                    series("v", t, pick(&s.v)),
                    series("v reference", t, pick(&s.v_ref)),
                ],
            ),
        ),
        (
            "turn_rate.svg".into(),
            chart(
                "turn rate: executed and reference",
                "ω [rad/s]",
                vec![
                    series("ω", t, pick(&s.omega)),
                    series("ω reference", t, pick(&s.omega_ref)),
                ],
            ),
        ),
        (
            "zmp_margin.svg".into(),
            chart(
                "ZMP margin to the support polygon's edge (gaps: undefined)",
                "margin [m]",
                vec![series("ZMP margin", t, opt(&s.zmp_margin))],
            ),
        ),
        (
            "force_angle.svg".into(),
            chart(
                "Force-Angle measure, minimum over the tip-over axes",
                "angle [rad]",
                vec![series("FA minimum", t, opt(&s.force_angle_min))],
            ),
        ),
        (
            "tracking.svg".into(),
            chart(
                "tracking error and clearance to the nearest obstacle",
                "distance [m]",
                vec![
                    series("tracking error", t, pick(&s.tracking_error)),
                    series("clearance", t, pick(&s.clearance)),
                ],
            ),
        ),
    ];
    if !s.torque_names.is_empty() {
        let torques = s
            .torque_names
            .iter()
            .zip(&s.torques)
            .map(|(n, c)| series(n, t, pick(c)))
            .collect();
        out.push((
            "torques.svg".into(),
            chart("joint torques", "τ [N·m]", torques),
        ));
    }
    out
}

/// The map around the mission with every plan (the last one solid), the executed path,
/// the obstacles with their times, start, goal and re-plan points, axes in metres and a
/// legend.
fn top_view(r: &MissionReport, idx: &[usize]) -> String {
    let view = map::view_region(r);
    let img = map::encode(&r.map, view);
    let c = Canvas::new(view);
    let (pw, ph) = (c.pw, c.ph);
    let (tw, th) = (ML + pw + MR, MT + ph + MB);
    let mut o = String::new();
    let _ = writeln!(
        o,
        r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink" width="{tw:.0}" height="{th:.0}" viewBox="0 0 {tw:.0} {th:.0}" font-family="sans-serif" font-size="12">"#
    );
    let _ = writeln!(o, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        o,
        r#"<text x="{ML}" y="20" font-size="14">{}</text><text x="{ML}" y="37">top view: plans, executed path, obstacles</text>"#,
        html_escape(&r.title)
    );
    let _ = writeln!(
        o,
        r#"<defs><clipPath id="view"><rect x="{ML}" y="{MT}" width="{pw:.2}" height="{ph:.2}"/></clipPath></defs><g clip-path="url(#view)">"#
    );
    if !img.data_uri.is_empty() {
        let _ = writeln!(
            o,
            r#"<image x="{:.2}" y="{:.2}" width="{:.2}" height="{:.2}" style="image-rendering:pixelated" preserveAspectRatio="none" xlink:href="{}"/>"#,
            c.px(img.x0),
            c.py(img.y1),
            (img.x1 - img.x0) * c.scale,
            (img.y1 - img.y0) * c.scale,
            img.data_uri
        );
    }
    plans_and_obstacles(&mut o, &c, r);
    executed_path(&mut o, &c, r, idx);
    c.pose(&mut o, r, &r.start, "#2ca02c");
    c.pose(&mut o, r, &r.goal, "#9467bd");
    o.push_str("</g>\n");
    axes(&mut o, &c);
    legend(&mut o, ML + pw + 16.0);
    o.push_str("</svg>\n");
    o
}

/// Where the top view's map region lies on the figure: world metres to pixels.
struct Canvas {
    /// The region shown, `[x0, y0, x1, y1]` (m).
    view: [f64; 4],
    /// Pixels per metre.
    scale: f64,
    /// The plot's width and height (pixels).
    pw: f64,
    ph: f64,
}

impl Canvas {
    fn new(view: [f64; 4]) -> Self {
        let (vw, vh) = (view[2] - view[0], view[3] - view[1]);
        let scale = 700.0 / vw.max(vh);
        Canvas {
            view,
            scale,
            pw: vw * scale,
            ph: vh * scale,
        }
    }

    fn px(&self, x: f64) -> f64 {
        ML + (x - self.view[0]) * self.scale
    }

    fn py(&self, y: f64) -> f64 {
        MT + (self.view[3] - y) * self.scale
    }

    /// The `points` attribute of a polyline through the finite points of `pts`.
    fn points(&self, pts: &mut dyn Iterator<Item = (f64, f64)>) -> String {
        let mut s = String::new();
        for (x, y) in pts.filter(|(x, y)| x.is_finite() && y.is_finite()) {
            let _ = write!(s, "{:.1},{:.1} ", self.px(x), self.py(y));
        }
        s.trim_end().to_string()
    }

    /// A pose `[x, y, θ]`: the footprint circle (at least 4 px) and a heading line.
    fn pose(&self, o: &mut String, r: &MissionReport, p: &[f64; 3], colour: &str) {
        let (x, y) = (self.px(p[0]), self.py(p[1]));
        let rr = (r.footprint_radius * self.scale).max(4.0);
        let _ = writeln!(
            o,
            r#"<circle cx="{x:.1}" cy="{y:.1}" r="{rr:.1}" fill="none" stroke="{colour}" stroke-width="2"/><line x1="{x:.1}" y1="{y:.1}" x2="{:.1}" y2="{:.1}" stroke="{colour}" stroke-width="2"/>"#,
            x + rr * p[2].cos(),
            y - rr * p[2].sin()
        );
    }
}

/// Every plan (earlier ones dashed and light, the last one solid) and the obstacles with
/// the times they appear.
fn plans_and_obstacles(o: &mut String, c: &Canvas, r: &MissionReport) {
    let n = r.plans.len();
    for (i, p) in r.plans.iter().enumerate() {
        let last = i + 1 == n;
        let _ = writeln!(
            o,
            r##"<polyline points="{}" fill="none" stroke="{}" stroke-width="{}" {}/>"##,
            c.points(&mut p.points.iter().map(|q| (q[0], q[1]))),
            if last { "#1f77b4" } else { "#9bbbd8" },
            if last { 2.2 } else { 1.6 },
            if last {
                ""
            } else {
                r#"stroke-dasharray="5 4""#
            }
        );
    }
    for ob in &r.obstacles {
        let _ = writeln!(
            o,
            r##"<circle cx="{:.1}" cy="{:.1}" r="{:.1}" fill="#ff7f0e" fill-opacity="0.55" stroke="#b35300"/><text x="{:.1}" y="{:.1}" font-size="11" text-anchor="middle">t = {} s</text>"##,
            c.px(ob.center[0]),
            c.py(ob.center[1]),
            ob.radius * c.scale,
            c.px(ob.center[0]),
            c.py(ob.center[1]) - ob.radius * c.scale - 4.0,
            fmt_tick(ob.t)
        );
    }
}

/// The executed path (the samples `idx`) and a marker where the robot was at each
/// re-plan.
fn executed_path(o: &mut String, c: &Canvas, r: &MissionReport, idx: &[usize]) {
    let s = &r.samples;
    if s.t.len() > 1 {
        let _ = writeln!(
            o,
            r##"<polyline points="{}" fill="none" stroke="#d62728" stroke-width="2"/>"##,
            c.points(&mut idx.iter().map(|&i| (s.x[i], s.y[i])))
        );
    }
    for p in r.plans.iter().skip(1) {
        if s.t.is_empty() {
            break;
        }
        let i = s.t.partition_point(|&x| x < p.t).min(s.t.len() - 1);
        let (x, y) = (c.px(s.x[i]), c.py(s.y[i]));
        let _ = writeln!(
            o,
            r##"<path d="M{:.1},{:.1} l6,6 l-6,6 l-6,-6 z" fill="#9467bd" stroke="black" stroke-width="0.6"/>"##,
            x,
            y - 6.0
        );
    }
}

/// The frame around the plot, the ticks of both axes (metres) and the axis labels.
fn axes(o: &mut String, c: &Canvas) {
    let (view, pw, ph) = (c.view, c.pw, c.ph);
    let _ = writeln!(
        o,
        r##"<rect x="{ML}" y="{MT}" width="{pw:.2}" height="{ph:.2}" fill="none" stroke="#333"/>"##
    );
    for t in ticks(view[0], view[2]) {
        let x = c.px(t);
        let _ = writeln!(
            o,
            r##"<line x1="{x:.1}" y1="{:.1}" x2="{x:.1}" y2="{:.1}" stroke="#333"/><text x="{x:.1}" y="{:.1}" text-anchor="middle">{}</text>"##,
            MT + ph,
            MT + ph + 5.0,
            MT + ph + 18.0,
            fmt_tick(t)
        );
    }
    for t in ticks(view[1], view[3]) {
        let y = c.py(t);
        let _ = writeln!(
            o,
            r##"<line x1="{:.1}" y1="{y:.1}" x2="{ML}" y2="{y:.1}" stroke="#333"/><text x="{:.1}" y="{:.1}" text-anchor="end">{}</text>"##,
            ML - 5.0,
            ML - 8.0,
            y + 4.0,
            fmt_tick(t)
        );
    }
    let _ = writeln!(
        o,
        r#"<text x="{:.1}" y="{:.1}" text-anchor="middle">x [m]</text><text x="16" y="{:.1}" text-anchor="middle" transform="rotate(-90 16 {:.1})">y [m]</text>"#,
        ML + pw / 2.0,
        MT + ph + 38.0,
        MT + ph / 2.0,
        MT + ph / 2.0
    );
}

fn legend(o: &mut String, x: f64) {
    let rows: [(&str, &str); 10] = [
        (
            r##"<rect width="22" height="14" fill="#ffffff" stroke="#333" stroke-width="0.6"/>"##,
            "free",
        ),
        (
            r##"<rect width="22" height="14" fill="#2b2b2b"/>"##,
            "occupied",
        ),
        (
            r##"<rect width="22" height="14" fill="#c8c8c8"/>"##,
            "unknown",
        ),
        (
            r##"<line x1="0" y1="7" x2="22" y2="7" stroke="#1f77b4" stroke-width="2.2"/>"##,
            "last plan",
        ),
        (
            r##"<line x1="0" y1="7" x2="22" y2="7" stroke="#9bbbd8" stroke-width="1.6" stroke-dasharray="5 4"/>"##,
            "earlier plans",
        ),
        (
            r##"<line x1="0" y1="7" x2="22" y2="7" stroke="#d62728" stroke-width="2"/>"##,
            "executed path",
        ),
        (
            r##"<circle cx="11" cy="7" r="6" fill="#ff7f0e" fill-opacity="0.55" stroke="#b35300"/>"##,
            "obstacle (appearance time)",
        ),
        (
            r##"<path d="M11,1 l6,6 l-6,6 l-6,-6 z" fill="#9467bd" stroke="black" stroke-width="0.6"/>"##,
            "re-plan point",
        ),
        (
            r##"<circle cx="11" cy="7" r="6" fill="none" stroke="#2ca02c" stroke-width="2"/>"##,
            "start (footprint, heading)",
        ),
        (
            r##"<circle cx="11" cy="7" r="6" fill="none" stroke="#9467bd" stroke-width="2"/>"##,
            "goal (footprint, heading)",
        ),
    ];
    for (i, (shape, label)) in rows.iter().enumerate() {
        let y = MT + 4.0 + 22.0 * i as f64;
        let _ = writeln!(
            o,
            r#"<g transform="translate({x:.1} {y:.1})">{shape}<text x="30" y="11">{label}</text></g>"#
        );
    }
}

//! The mission report: one self-contained HTML page (inline CSS and JavaScript, the map as
//! a data-URI PNG, the run as JSON in a `<script type="application/json">` element; no
//! network reference of any kind) and the static SVG figures written beside it.
//!
//! The types are plain data, filled by `moma mission` from its run (and readable back
//! from JSON by the hidden `moma render-report` command, the entry point of the browser
//! test). The page animates the mission on the map (footprint and heading, the planned
//! paths with the active one highlighted, the executed path, obstacles appearing at their
//! times, re-plan markers), shows the arm's side view and the robot in 3-D (its URDF shapes
//! at poses from moma's forward kinematics, on the map with raised walls; three.js is
//! bundled in), and links every plot to one time
//! cursor (play/pause, slider, playback speed; clicking a plot seeks). For headless checks
//! the page writes its state into the DOM: `<body data-frame data-time data-plots-drawn
//! data-errors>` (see `docs/report.md`).

mod embed;
mod map;
mod numbers;
mod robot3d;
mod svgs;
mod view3d;

pub use robot3d::{RobotShapes, scene_shapes};
pub use view3d::{MAX_FRAMES, ReportView3d};

use serde::{Deserialize, Serialize};

/// Everything the report shows of one mission run.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct MissionReport {
    /// The page title (the scenario's name).
    pub title: String,
    /// The occupancy map the mission ran on.
    pub map: ReportMap,
    /// Radius of the platform's footprint disk, m.
    pub footprint_radius: f64,
    /// Start pose of the base frame in the world: x, y (m), θ (rad).
    pub start: [f64; 3],
    /// Goal pose of the base frame in the world: x, y (m), θ (rad).
    pub goal: [f64; 3],
    /// The end-effector target in the world (m), when the mission has one.
    pub end_effector_target: Option<[f64; 3]>,
    /// The planned (smoothed) paths: the first at t = 0, then one per re-plan.
    pub plans: Vec<ReportPlan>,
    /// Disks that appear at given times.
    pub obstacles: Vec<ReportObstacle>,
    /// The executed run, in equal-length columns.
    pub samples: ReportSamples,
    /// Re-plans, limit hits, the tip-over margin's minimum, goal reached, ...
    pub events: Vec<ReportEvent>,
    /// The `summary.json` object, shown as a table.
    pub summary: serde_json::Value,
    /// The robot (and a scene) in 3-D, animated with the samples' clock; `None`: no 3-D
    /// view (the map's walls and the obstacles are still drawn in 3-D).
    #[serde(default)]
    pub view3d: Option<ReportView3d>,
}

/// An occupancy grid in world coordinates (no rotation).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ReportMap {
    /// Number of cells along x.
    pub width: usize,
    /// Number of cells along y.
    pub height: usize,
    /// Cell size, m.
    pub resolution: f64,
    /// World position (m) of the lower-left corner of cell (0, 0).
    pub origin: [f64; 2],
    /// Row-major cells, row 0 at the bottom (y up): 0 free, 1 occupied, 2 unknown (any
    /// other value is drawn as unknown).
    pub cells: Vec<u8>,
}

/// One planned path.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ReportPlan {
    /// The time the plan was made, s.
    pub t: f64,
    /// The smoothed path, world m.
    pub points: Vec<[f64; 2]>,
}

/// A disk obstacle that becomes visible at time `t`.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ReportObstacle {
    /// Appearance time, s.
    pub t: f64,
    /// Centre, world m.
    pub center: [f64; 2],
    /// Radius, m.
    pub radius: f64,
}

/// Something that happened during the run.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ReportEvent {
    /// Time, s.
    pub t: f64,
    /// A short class name (`replan`, `obstacle`, `limit`, `goal`, ...).
    pub kind: String,
    /// One human-readable line.
    pub text: String,
}

/// The executed run: every column has the length of `t` (`torques` per channel and
/// `arm_side` too).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ReportSamples {
    /// Time, s.
    pub t: Vec<f64>,
    /// Base x, m (world).
    pub x: Vec<f64>,
    /// Base y, m (world).
    pub y: Vec<f64>,
    /// Base heading, rad (world).
    pub theta: Vec<f64>,
    /// Executed forward speed, m/s.
    pub v: Vec<f64>,
    /// Executed turn rate, rad/s.
    pub omega: Vec<f64>,
    /// Reference forward speed, m/s.
    pub v_ref: Vec<f64>,
    /// Reference turn rate, rad/s.
    pub omega_ref: Vec<f64>,
    /// ZMP margin to the support polygon's edge, m; `None` where undefined (tipping).
    pub zmp_margin: Vec<Option<f64>>,
    /// Minimum Force-Angle over the tip-over axes, rad; `None` where undefined.
    pub force_angle_min: Vec<Option<f64>>,
    /// Footprint edge to the nearest occupied cell, m.
    pub clearance: Vec<f64>,
    /// Distance from the reference position, m.
    pub tracking_error: Vec<f64>,
    /// Names of the torque channels.
    pub torque_names: Vec<String>,
    /// One column per channel (same order as `torque_names`), N·m.
    pub torques: Vec<Vec<f64>>,
    /// Per sample: the arm chain's joint origins, then the end effector, in the base
    /// frame's x–z plane (forward, up), m.
    pub arm_side: Vec<Vec<[f64; 2]>>,
}

/// Largest map the report accepts, cells (the hidden `render-report` command checks it;
/// the mission's maps are far smaller).
pub const MAX_MAP_CELLS: usize = 1 << 26;

impl MissionReport {
    /// Checks the shape of the data (equal-length columns, map size), naming the field at
    /// fault. [`render_html`] and [`render_svgs`] assert the same.
    pub fn check(&self) -> Result<(), String> {
        let m = &self.map;
        let cells = m
            .width
            .checked_mul(m.height)
            .filter(|&n| n <= MAX_MAP_CELLS);
        match cells {
            None => {
                return Err(format!(
                    "map: {} × {} cells exceed the limit of {MAX_MAP_CELLS}",
                    m.width, m.height
                ));
            }
            Some(n) if n != m.cells.len() => {
                return Err(format!(
                    "map.cells: {} values for {} × {} cells",
                    m.cells.len(),
                    m.width,
                    m.height
                ));
            }
            Some(_) => {}
        }
        if !(m.resolution.is_finite() && m.resolution > 0.0) {
            return Err(format!(
                "map.resolution: {} is not a positive number",
                m.resolution
            ));
        }
        if !(self.footprint_radius.is_finite() && self.footprint_radius >= 0.0) {
            return Err(format!(
                "footprint_radius: {} is not a non-negative number",
                self.footprint_radius
            ));
        }
        let s = &self.samples;
        let n = s.t.len();
        let columns: [(&str, usize); 12] = [
            ("x", s.x.len()),
            ("y", s.y.len()),
            ("theta", s.theta.len()),
            ("v", s.v.len()),
            ("omega", s.omega.len()),
            ("v_ref", s.v_ref.len()),
            ("omega_ref", s.omega_ref.len()),
            ("zmp_margin", s.zmp_margin.len()),
            ("force_angle_min", s.force_angle_min.len()),
            ("clearance", s.clearance.len()),
            ("tracking_error", s.tracking_error.len()),
            ("arm_side", s.arm_side.len()),
        ];
        for (name, len) in columns {
            if len != n {
                return Err(format!("samples.{name}: {len} values for {n} times"));
            }
        }
        if s.torques.len() != s.torque_names.len() {
            return Err(format!(
                "samples.torques: {} channels for {} names",
                s.torques.len(),
                s.torque_names.len()
            ));
        }
        for (i, c) in s.torques.iter().enumerate() {
            if c.len() != n {
                return Err(format!(
                    "samples.torques[{i}]: {} values for {n} times",
                    c.len()
                ));
            }
        }
        if let Some(v) = &self.view3d {
            v.check()?;
        }
        Ok(())
    }
}

const CSS: &str = include_str!("page.css");
const JS: &str = include_str!("page.js");
const ERRORS_JS: &str = include_str!("errors.js");
const VIEW3D_JS: &str = include_str!("view3d.js");
/// three.js (MIT licence, `vendor/three/LICENSE`): the parts the 3-D view uses, bundled
/// and minified as the global `THREE` (how: `vendor/three/README.md`).
const THREE_JS: &str = include_str!("vendor/three/three.min.js");

/// The whole self-contained page (inline CSS, JS and images; no network reference).
///
/// The run is decimated to at most [`embed::MAX_SAMPLES`] samples (uniformly, plus the
/// samples where the monitors reach their extremes) and each plan to at most
/// [`embed::MAX_PLAN_POINTS`] points; the map is cropped to the region the mission uses.
///
/// # Panics
///
/// When the data is malformed (see [`MissionReport::check`]): a programmer's error.
pub fn render_html(report: &MissionReport) -> String {
    if let Err(e) = report.check() {
        panic!("render_html: malformed MissionReport: {e}");
    }
    let data = embed::page_data(report);
    let json = embed::script_json(&data);
    let title = embed::html_escape(&report.title);
    let mut o = String::with_capacity(
        json.len() + CSS.len() + JS.len() + THREE_JS.len() + VIEW3D_JS.len() + 4096,
    );
    o.push_str("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n");
    o.push_str("<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n");
    o.push_str(&format!("<title>{title} · moma mission report</title>\n"));
    o.push_str("<style>\n");
    o.push_str(CSS);
    o.push_str("</style>\n</head>\n<body data-frame=\"0\" data-time=\"0\" data-plots-drawn=\"0\" data-errors=\"\" data-error-count=\"0\">\n<script>\n");
    o.push_str(ERRORS_JS);
    o.push_str("</script>\n");
    o.push_str(&body(&title));
    o.push_str("<script type=\"application/json\" id=\"mission-data\">");
    o.push_str(&json);
    o.push_str("</script>\n<script>\n");
    o.push_str(THREE_JS);
    o.push_str("\n</script>\n<script>\n");
    o.push_str(VIEW3D_JS);
    o.push_str("</script>\n<script>\n");
    o.push_str(JS);
    o.push_str("</script>\n</body>\n</html>\n");
    o
}

/// The page's static markup: header, the two views with the controls, the plot grid, the
/// summary table and the events list (filled by the script).
fn body(title: &str) -> String {
    format!(
        r#"<header>
<h1>{title}</h1>
<p class="sub">moma mission report: plan on the map, time the path under speed and tip-over limits, track it in dynamic simulation, re-plan when obstacles appear. <span id="status"></span></p>
</header>
<main>
<section class="views">
<div class="panel top">
<h2>Top view <span class="hint">(world frame, m)</span></h2>
<canvas id="top" width="760" height="560" aria-label="top view of the mission on the map"></canvas>
<div class="legend" id="top-legend"></div>
</div>
<div class="side-col">
<div class="panel side">
<h2>Arm, side view <span class="hint">(base frame x–z plane, m)</span></h2>
<canvas id="side" width="420" height="320" aria-label="side view of the arm"></canvas>
<div class="legend" id="side-legend"></div>
</div>
<div class="panel now">
<h2>Now</h2>
<table id="now"></table>
</div>
</div>
</section>
<section class="panel view3d">
<h2>3-D view <span class="hint">(drag to orbit, wheel to zoom, right-drag or shift-drag to pan, double-click to reset)</span> <label class="follow"><input type="checkbox" id="view3d-follow" checked> follow the robot</label></h2>
<canvas id="view3d" width="1200" height="500" aria-label="3-D view of the robot, the map and the obstacles"></canvas>
<div class="legend" id="view3d-note"></div>
</section>
<section class="controls panel">
<button id="play" type="button" title="play / pause (space)">Pause</button>
<input id="slider" type="range" min="0" max="1000" step="1" value="0" aria-label="time">
<span id="clock">t = 0.00 s</span>
<label>speed <select id="speed"><option value="0.25">0.25×</option><option value="0.5">0.5×</option><option value="1" selected>1×</option><option value="2">2×</option><option value="4">4×</option><option value="8">8×</option></select></label>
</section>
<section class="plots" id="plots"></section>
<section class="tables">
<div class="panel"><h2>Summary</h2><table id="summary"></table></div>
<div class="panel"><h2>Events <span class="hint">(click to jump)</span></h2><table id="events"></table></div>
</section>
</main>
<footer>Written by moma. This page is self-contained: it loads nothing from the network.</footer>
"#
    )
}

/// The SVG figures the mission also writes beside the report: (file name, SVG text).
///
/// `top_view.svg` (the map with every plan, the executed path, the obstacles and the
/// re-plan points), then time plots: `speed.svg`, `turn_rate.svg`, `zmp_margin.svg`,
/// `force_angle.svg`, `tracking.svg` and, when there are torque channels, `torques.svg`.
///
/// # Panics
///
/// When the data is malformed (see [`MissionReport::check`]).
pub fn render_svgs(report: &MissionReport) -> Vec<(String, String)> {
    if let Err(e) = report.check() {
        panic!("render_svgs: malformed MissionReport: {e}");
    }
    svgs::render(report)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A report with nothing but a map: no samples, plans, obstacles, torques or events.
    fn empty() -> MissionReport {
        MissionReport {
            title: "empty".into(),
            map: ReportMap {
                width: 4,
                height: 3,
                resolution: 0.5,
                origin: [0.0, 0.0],
                cells: vec![0; 12],
            },
            footprint_radius: 0.2,
            start: [0.5, 0.5, 0.0],
            goal: [1.5, 1.0, 1.0],
            end_effector_target: None,
            plans: vec![],
            obstacles: vec![],
            samples: ReportSamples {
                t: vec![],
                x: vec![],
                y: vec![],
                theta: vec![],
                v: vec![],
                omega: vec![],
                v_ref: vec![],
                omega_ref: vec![],
                zmp_margin: vec![],
                force_angle_min: vec![],
                clearance: vec![],
                tracking_error: vec![],
                torque_names: vec![],
                torques: vec![],
                arm_side: vec![],
            },
            events: vec![],
            summary: serde_json::json!({"reached": false, "reason": "no motion"}),
            view3d: None,
        }
    }

    #[test]
    fn the_page_assets_cannot_end_a_script_or_reach_the_network() {
        for (name, text) in [
            ("page.js", JS),
            ("errors.js", ERRORS_JS),
            ("page.css", CSS),
            ("view3d.js", VIEW3D_JS),
            ("three.min.js", THREE_JS),
        ] {
            // three.js names the XHTML namespace (an identifier, never fetched) and has
            // canvas.toDataURL( (which a CSS url( check would match, case aside)
            let lower = text
                .replace("http://www.w3.org/1999/xhtml", "")
                .replace("DataURL(", "")
                .to_ascii_lowercase();
            for bad in ["</script", "<!--", "http:", "https:", "@import", "url("] {
                assert!(!lower.contains(bad), "{name} contains {bad}");
            }
        }
    }

    #[test]
    fn an_empty_run_still_renders_a_whole_page_and_the_figures() {
        let r = empty();
        let html = render_html(&r);
        assert!(html.starts_with("<!DOCTYPE html>") && html.trim_end().ends_with("</html>"));
        assert!(html.contains(r#""t":[]"#) && html.contains(r#""ee_target":null"#));
        let names: Vec<String> = render_svgs(&r).into_iter().map(|(n, _)| n).collect();
        assert_eq!(
            names,
            [
                "top_view.svg",
                "speed.svg",
                "turn_rate.svg",
                "zmp_margin.svg",
                "force_angle.svg",
                "tracking.svg"
            ]
        );
    }

    #[test]
    fn malformed_data_is_named_by_check() {
        let mut r = empty();
        r.samples.torque_names.push("j1".into());
        assert_eq!(
            r.check().unwrap_err(),
            "samples.torques: 0 channels for 1 names"
        );
        let mut r = empty();
        r.map.cells.pop();
        assert_eq!(
            r.check().unwrap_err(),
            "map.cells: 11 values for 4 × 3 cells"
        );
        let mut r = empty();
        r.map.width = usize::MAX;
        assert!(r.check().unwrap_err().contains("exceed the limit"));
        let mut r = empty();
        r.map.resolution = 0.0;
        assert!(r.check().unwrap_err().starts_with("map.resolution"));
        let mut r = empty();
        r.samples.t.push(0.0);
        assert_eq!(r.check().unwrap_err(), "samples.x: 0 values for 1 times");
    }

    #[test]
    fn long_runs_are_decimated_in_the_page_and_the_figures() {
        let mut r = empty();
        let n = 50_000;
        let s = &mut r.samples;
        s.t = (0..n).map(|i| i as f64 * 1e-3).collect();
        for c in [
            &mut s.x,
            &mut s.y,
            &mut s.theta,
            &mut s.v,
            &mut s.omega,
            &mut s.v_ref,
            &mut s.omega_ref,
            &mut s.clearance,
            &mut s.tracking_error,
        ] {
            *c = s.t.iter().map(|t| (3.0 * t).sin()).collect();
        }
        // one sharp dip that uniform thinning would step over
        s.clearance[31_337] = -1.0;
        s.zmp_margin = vec![Some(0.1); n];
        s.force_angle_min = vec![Some(0.5); n];
        s.arm_side = vec![vec![[0.0, 0.3], [0.2, 0.6]]; n];
        let html = render_html(&r);
        let a = html.find(r#"id="mission-data">"#).unwrap() + r#"id="mission-data">"#.len();
        let b = a + html[a..].find("</script>").unwrap();
        let data: serde_json::Value = serde_json::from_str(&html[a..b]).unwrap();
        let clr = data["samples"]["clr"].as_array().unwrap();
        assert!(clr.len() <= embed::MAX_SAMPLES + 10, "{}", clr.len());
        assert!(
            clr.iter().any(|v| v.as_f64() == Some(-1.0)),
            "the dip is kept"
        );
        // the data stays under 0.4 MB beside three.js
        assert!(
            html.len() < 400_000 + THREE_JS.len(),
            "{} bytes",
            html.len()
        );
        for (name, svg) in render_svgs(&r) {
            let points = svg
                .split("<polyline points=\"")
                .skip(1)
                .map(|p| p[..p.find('"').unwrap()].split(' ').count())
                .max()
                .unwrap_or(0);
            assert!(points <= embed::MAX_SAMPLES + 10, "{name}: {points} points");
        }
    }

    #[test]
    #[should_panic(expected = "malformed MissionReport")]
    fn render_html_asserts_the_shape() {
        let mut r = empty();
        r.samples.t.push(0.0);
        let _ = render_html(&r);
    }
}

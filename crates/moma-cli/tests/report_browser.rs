//! The mission report in a real browser. A synthetic but realistic mission (a small
//! occupancy grid with walls, an S-curve path, one obstacle appearing at t = 3 s with a
//! re-plan, an arm chain, torques) is rendered through the hidden `moma render-report`
//! command (the CLI is a binary crate; that command is its test-reachable entry point to
//! the report module). The page must carry no external reference; when `chromium` (or
//! `chromium-browser`) is on PATH, headless Chromium loads it and the DOM state the page
//! writes on `<body>` must show no console error, every plot drawn and the frame
//! advancing, and two screenshots at different virtual times must differ. Without a
//! browser the test says so on stderr and checks the rest.

use serde_json::{Value, json};
use std::f64::consts::PI;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

fn moma() -> Command {
    Command::new(env!("CARGO_BIN_EXE_moma"))
}

/// Removes a test's folder, unless `MOMA_TEST_KEEP` is set (then it names the folder, to
/// look at the page and the screenshots by hand).
fn clean_up(dir: &Path) {
    if std::env::var_os("MOMA_TEST_KEEP").is_some() {
        eprintln!("kept {}", dir.display());
    } else {
        let _ = std::fs::remove_dir_all(dir);
    }
}

fn temp_dir(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("moma-report-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

const RES: f64 = 0.05;
const ORIGIN: [f64; 2] = [-0.5, -0.5];
const OBSTACLE: ([f64; 2], f64, f64) = ([3.3, 2.0], 0.2, 3.0); // centre, radius, time
const GOAL: [f64; 3] = [5.0, 3.0, 0.0];
const TARGET: [f64; 3] = [5.5, 3.0, 0.8];
const FOOTPRINT: f64 = 0.3;

/// A 6 m × 4.5 m room (120 × 90 cells): walls, a pillar, an unknown corner.
fn grid() -> (usize, usize, Vec<u8>) {
    let (w, h) = (120, 90);
    let mut cells = vec![0u8; w * h];
    for y in 0..h {
        for x in 0..w {
            let (wx, wy) = (
                ORIGIN[0] + (x as f64 + 0.5) * RES,
                ORIGIN[1] + (y as f64 + 0.5) * RES,
            );
            let wall = x < 3 || y < 3 || x >= w - 3 || y >= h - 3;
            let pillar = (2.5..3.0).contains(&wx) && (-0.5..0.8).contains(&wy);
            let unknown = wx > 4.6 && wy < 0.6;
            cells[y * w + x] = if wall || pillar {
                1
            } else if unknown {
                2
            } else {
                0
            };
        }
    }
    (w, h, cells)
}

/// The first plan: an S-curve from the start (0.5, 0.5) to the goal, heading 0 at both ends.
fn s_curve(s: f64) -> [f64; 2] {
    [0.5 + 4.5 * s, 0.5 + 2.5 * (3.0 * s * s - 2.0 * s * s * s)]
}

/// The re-plan: a cubic Hermite curve from `p0` (leaving along `m0`, so the heading stays
/// continuous) to the goal, bent north around the obstacle.
fn detour(p0: [f64; 2], m0: [f64; 2], s: f64) -> [f64; 2] {
    let (h00, h10) = (
        2.0 * s.powi(3) - 3.0 * s * s + 1.0,
        s.powi(3) - 2.0 * s * s + s,
    );
    let (h01, h11) = (-2.0 * s.powi(3) + 3.0 * s * s, s.powi(3) - s * s);
    let m1 = [3.0, 0.0];
    let bump = 0.6 * (PI * s).sin().powi(2);
    [
        h00 * p0[0] + h10 * m0[0] + h01 * GOAL[0] + h11 * m1[0],
        h00 * p0[1] + h10 * m0[1] + h01 * GOAL[1] + h11 * m1[1] + bump,
    ]
}

/// A polyline with its cumulative arc length.
struct Polyline {
    p: Vec<[f64; 2]>,
    cum: Vec<f64>,
}

impl Polyline {
    fn new(p: Vec<[f64; 2]>) -> Polyline {
        let mut cum = vec![0.0];
        for w in p.windows(2) {
            let d = ((w[1][0] - w[0][0]).powi(2) + (w[1][1] - w[0][1]).powi(2)).sqrt();
            cum.push(cum.last().unwrap() + d);
        }
        Polyline { p, cum }
    }
    fn len(&self) -> f64 {
        *self.cum.last().unwrap()
    }
    fn point(&self, s: f64) -> [f64; 2] {
        let s = s.clamp(0.0, self.len());
        let i = self
            .cum
            .partition_point(|&c| c <= s)
            .clamp(1, self.p.len() - 1);
        let (a, b) = (self.p[i - 1], self.p[i]);
        let f = (s - self.cum[i - 1]) / (self.cum[i] - self.cum[i - 1]).max(1e-12);
        [a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])]
    }
    /// Point and heading (the chord over ±5 cm, smoother than the segments') at arc
    /// length `s`.
    fn at(&self, s: f64) -> ([f64; 2], f64) {
        let (a, b) = (self.point(s - 0.05), self.point(s + 0.05));
        (self.point(s), (b[1] - a[1]).atan2(b[0] - a[0]))
    }
}

/// Joint angles (shoulder, elbow) of the two-link arm (0.35 m, 0.25 m) from its base at
/// (0.1, 0.55) in the base frame's x–z plane that put the end effector at `p`.
fn arm_ik(p: [f64; 2]) -> [f64; 2] {
    let (l1, l2) = (0.35, 0.25);
    let (x, z) = (p[0] - 0.1, p[1] - 0.55);
    let c2 = ((x * x + z * z - l1 * l1 - l2 * l2) / (2.0 * l1 * l2)).clamp(-1.0, 1.0);
    let q2 = -c2.acos();
    let q1 = z.atan2(x) - (l2 * q2.sin()).atan2(l1 + l2 * q2.cos());
    [q1, q2]
}

fn arm_chain(q: [f64; 2]) -> Value {
    let elbow = [0.1, 0.55];
    let wrist = [elbow[0] + 0.35 * q[0].cos(), elbow[1] + 0.35 * q[0].sin()];
    let ee = [
        wrist[0] + 0.25 * (q[0] + q[1]).cos(),
        wrist[1] + 0.25 * (q[0] + q[1]).sin(),
    ];
    json!([[0.1, 0.3], elbow, wrist, ee])
}

/// The whole synthetic mission as the JSON of a `MissionReport`: a trapezoidal speed
/// profile (0.6 m/s, 0.5 m/s²) along the first plan, a switch to the re-plan at t = 3 s
/// without stopping, arrival, then two seconds of the arm reaching the target.
fn mission() -> Value {
    let (w, h, cells) = grid();
    let dt = 0.01;
    let (v_max, a_max) = (0.6, 0.5);
    let t_switch = OBSTACLE.2;
    let plan0 = Polyline::new((0..=300).map(|k| s_curve(k as f64 / 300.0)).collect());
    let mut plan1: Option<Polyline> = None;
    let mut cols: Vec<Vec<f64>> = (0..10).map(|_| Vec::new()).collect();
    let (mut zmp, mut fa, mut arm) = (Vec::new(), Vec::new(), Vec::new());
    let mut torques: Vec<Vec<f64>> = (0..3).map(|_| Vec::new()).collect();
    let (mut s, mut v, mut theta_prev) = (0.0f64, 0.0f64, 0.0f64);
    let (mut t_arrive, mut min_zmp, mut min_clear, mut max_err) =
        (None, f64::INFINITY, f64::INFINITY, 0.0f64);
    let q_transport = arm_ik([0.35, 0.62]);
    let q_reach = arm_ik([TARGET[0] - GOAL[0], TARGET[2]]);
    let mut i = 0usize;
    loop {
        let t = i as f64 * dt;
        if t >= t_switch && plan1.is_none() {
            let (p0, th) = plan0.at(s);
            let m0 = [3.0 * th.cos(), 3.0 * th.sin()];
            plan1 = Some(Polyline::new(
                (0..=300)
                    .map(|k| detour(p0, m0, k as f64 / 300.0))
                    .collect(),
            ));
            s = 0.0;
        }
        let path = plan1.as_ref().unwrap_or(&plan0);
        let remaining = path.len() - s;
        let (p, th) = path.at(s);
        let th = if i == 0 { 0.0 } else { th };
        let om = if i == 0 { 0.0 } else { (th - theta_prev) / dt };
        theta_prev = th;
        if t_arrive.is_none() && remaining < 1e-3 && plan1.is_some() {
            t_arrive = Some(t);
        }
        // after arrival: two seconds of reaching
        let reach = t_arrive.map_or(0.0, |ta| ((t - ta) / 2.0).clamp(0.0, 1.0));
        let reach = reach * reach * (3.0 - 2.0 * reach);
        let sway = 0.05 * (1.5 * t).sin() * (1.0 - reach);
        let q = [
            q_transport[0] + reach * (q_reach[0] - q_transport[0]) + sway,
            q_transport[1] + reach * (q_reach[1] - q_transport[1]),
        ];
        let lateral = v * om;
        let m = 0.2 - 0.18 * lateral.abs().min(1.0) - 0.04 * reach;
        // a short stretch where the tip-over measures are undefined
        let undefined = (4.5..4.55).contains(&t);
        if !undefined {
            min_zmp = min_zmp.min(m);
        }
        zmp.push(if undefined { Value::Null } else { json!(m) });
        fa.push(if undefined {
            Value::Null
        } else {
            json!(0.7 * m / 0.2)
        });
        let d_obs = if t >= OBSTACLE.2 {
            ((p[0] - OBSTACLE.0[0]).powi(2) + (p[1] - OBSTACLE.0[1]).powi(2)).sqrt() - OBSTACLE.1
        } else {
            f64::INFINITY
        };
        let d_wall = (p[0] + 0.35)
            .min(5.35 - p[0])
            .min(p[1] + 0.35)
            .min(3.85 - p[1]);
        let clearance = d_obs.min(d_wall) - FOOTPRINT;
        min_clear = min_clear.min(clearance);
        let err = 0.003 + 0.004 * (1.3 * t).sin().abs() * v / v_max;
        max_err = max_err.max(err);
        let row = [
            t,
            p[0],
            p[1],
            th,
            v * (1.0 + 0.01 * (7.0 * t).sin()),
            om + 0.01 * (5.0 * t).sin() * v,
            v,
            om,
            clearance,
            err,
        ];
        for (c, x) in cols.iter_mut().zip(row) {
            c.push(x);
        }
        // gravity-like torques of the arm plus a share of the platform's acceleration
        let g = [
            9.0 * q[0].cos() + 3.0 * (q[0] + q[1]).cos(),
            3.0 * (q[0] + q[1]).cos(),
            0.8 * (q[0] + q[1]).cos(),
        ];
        for (k, c) in torques.iter_mut().enumerate() {
            c.push(g[k] + (2.0 - k as f64) * 0.8 * lateral);
        }
        arm.push(arm_chain(q));
        if t_arrive.is_some_and(|ta| t >= ta + 2.5) {
            break;
        }
        // the speed profile: accelerate, cruise, brake to stop at the path's end
        let v_next = (v + a_max * dt)
            .min(v_max)
            .min((2.0 * a_max * (remaining - v * dt).max(0.0)).sqrt());
        s += 0.5 * (v + v_next) * dt;
        v = v_next;
        i += 1;
    }
    let t_arrive = t_arrive.unwrap();
    let t_end = *cols[0].last().unwrap();
    json!({
        "title": "Synthetic S-curve </script><b>mission</b> & re-plan",
        "map": { "width": w, "height": h, "resolution": RES, "origin": ORIGIN, "cells": cells },
        "footprint_radius": FOOTPRINT,
        "start": [0.5, 0.5, 0.0],
        "goal": GOAL,
        "end_effector_target": TARGET,
        "plans": [ { "t": 0.0, "points": plan0.p }, { "t": t_switch, "points": plan1.unwrap().p } ],
        "obstacles": [ { "t": OBSTACLE.2, "center": OBSTACLE.0, "radius": OBSTACLE.1 } ],
        "samples": {
            "t": cols[0], "x": cols[1], "y": cols[2], "theta": cols[3],
            "v": cols[4], "omega": cols[5], "v_ref": cols[6], "omega_ref": cols[7],
            "zmp_margin": zmp, "force_angle_min": fa,
            "clearance": cols[8], "tracking_error": cols[9],
            "torque_names": ["shoulder_lift", "elbow", "wrist"],
            "torques": torques,
            "arm_side": arm,
        },
        "events": [
            { "t": OBSTACLE.2, "kind": "obstacle", "text": "a disk of radius 0.2 m appears at (3.3, 2.0) on the path" },
            { "t": t_switch, "kind": "replan", "text": "D* Lite re-plan from the current pose; new path smoothed and timed without stopping" },
            { "t": 4.5, "kind": "stability", "text": "ZMP margin undefined for 50 ms <script>" },
            { "t": t_arrive, "kind": "goal", "text": "base at the goal pose; the arm reaches for the target" },
            { "t": t_arrive + 2.0, "kind": "end_effector", "text": "end effector at the target" },
        ],
        "summary": {
            "reached": true, "time_to_goal": t_arrive, "replans": 1, "min_zmp_margin": min_zmp,
            "min_clearance": min_clear, "max_tracking_error": max_err,
            "final_pose_error": [0.004, 0.01], "end_effector_error": 0.002,
            "wall_time_s": 0.4, "reason": null, "simulated_time": t_end,
            "tip_over_limits": { "forward": 3.1, "backward": 2.2, "left": 4.0, "right": 4.0 },
            "replan_timing": [{
                "t": OBSTACLE.2, "trigger": "obstacle 0", "dstar_lite_ms": 0.8,
                "expanded": 412, "smoothing_timing_ms": 2.5, "v_start": 0.7, "duration": 6.2,
            }],
            "wall_time": { "planning_s": 0.01, "smoothing_timing_s": 0.02, "simulation_s": 0.3, "report_s": 0.05 },
            "files": ["summary.json", "report.html", "torques.svg"],
        },
    })
}

/// Renders the synthetic mission into `dir/out` and returns that folder.
fn render(dir: &Path) -> PathBuf {
    render_with(dir, "out", &[])
}

/// The repository's root (the CLI crate's manifest is two folders below it).
fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// Renders the synthetic mission into `dir/NAME` with more `render-report` arguments
/// (e.g. `--robot`), and returns that folder.
fn render_with(dir: &Path, name: &str, extra: &[String]) -> PathBuf {
    let input = dir.join("mission_report.json");
    std::fs::write(&input, serde_json::to_vec(&mission()).unwrap()).unwrap();
    let out = dir.join(name);
    let run = moma()
        .args(["render-report"])
        .arg(&input)
        .arg("--output")
        .arg(&out)
        .args(extra)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "render-report failed: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    out
}

/// The XHTML namespace three.js passes to `createElementNS`.
const XHTML_NS: &str = "http://www.w3.org/1999/xhtml";

/// Every way a page could reach the network.
fn external_references(text: &str) -> Vec<String> {
    let lower = text.to_ascii_lowercase();
    let mut found = Vec::new();
    for pat in [
        "http:",
        "https:",
        "@import",
        "url(http",
        "url(//",
        "src=\"//",
        "src='//",
        "href=\"//",
        "href='//",
        "ftp:",
        "ws://",
        "wss://",
    ] {
        if let Some(i) = lower.find(pat) {
            found.push(format!(
                "{pat:?} at byte {i}: {:?}",
                &lower[i..(i + 60).min(lower.len())]
            ));
        }
    }
    found
}

#[test]
fn report_is_self_contained_and_complete() {
    let dir = temp_dir("static");
    let out = render(&dir);
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    // three.js names the XHTML namespace (an identifier, never fetched)
    assert_eq!(html.matches(XHTML_NS).count(), 1);
    assert_eq!(
        external_references(&html.replace(XHTML_NS, "")),
        Vec::<String>::new()
    );
    // the title's markup is escaped and cannot close a script element early
    assert!(html.contains("Synthetic S-curve &lt;/script&gt;&lt;b&gt;mission"));
    assert_eq!(
        html.matches("<script").count(),
        html.matches("</script>").count()
    );
    assert_eq!(
        html.matches("</script>").count(),
        5,
        "errors, data, three.js, 3-D view, player"
    );
    assert!(html.contains(r#"<script type="application/json" id="mission-data">"#));
    assert!(html.contains("data:image/png;base64,"));
    // the embedded data reads back: decimated to the page's bound, None as null
    let start = html.find(r#"id="mission-data">"#).unwrap() + r#"id="mission-data">"#.len();
    let end = start + html[start..].find("</script>").unwrap();
    let data: Value = serde_json::from_str(&html[start..end]).unwrap();
    let t = data["samples"]["t"].as_array().unwrap();
    let n = mission()["samples"]["t"].as_array().unwrap().len();
    assert!(n > 1000 && n < 2000, "{n} samples");
    assert_eq!(t.len(), n, "fewer samples than the bound are kept whole");
    let zmp = data["samples"]["zmp"].as_array().unwrap();
    assert!(zmp.iter().any(Value::is_null) && zmp.iter().any(Value::is_f64));
    assert_eq!(data["plans"].as_array().unwrap().len(), 2);
    assert_eq!(
        data["events"][2]["text"],
        "ZMP margin undefined for 50 ms <script>"
    );
    // the view is zoomed to the mission's region, inside the map
    let view: Vec<f64> = serde_json::from_value(data["view"].clone()).unwrap();
    assert!(
        view[0] >= -0.5 && view[2] <= 5.5 && view[1] >= -0.5 && view[3] <= 4.0,
        "{view:?}"
    );
    // about 0.23 MB of page and data, 0.55 MB of three.js
    assert!(
        html.len() < 1_000_000,
        "report.html is {} bytes; the page should stay small",
        html.len()
    );
    // the occupied cells of the cropped map (x from -0.35 m, y from -0.35 m: the left and
    // bottom walls lie outside) as merged rectangles: the pillar, the right and top walls
    let walls: Vec<[f64; 4]> = serde_json::from_value(data["walls"].clone()).unwrap();
    assert_eq!(
        walls,
        [
            [2.5, -0.35, 3.0, 0.8],
            [5.35, -0.35, 5.5, 3.85],
            [-0.35, 3.85, 5.5, 3.9]
        ]
    );
    assert!(data["view3d"].is_null(), "no robot given, no 3-D robot");
    for f in [
        "top_view.svg",
        "speed.svg",
        "turn_rate.svg",
        "zmp_margin.svg",
        "force_angle.svg",
        "tracking.svg",
        "torques.svg",
    ] {
        let svg = std::fs::read_to_string(out.join(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(
            svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"),
            "{f}"
        );
        let without_ns = svg
            .replace(r#"xmlns="http://www.w3.org/2000/svg""#, "")
            .replace(r#"xmlns:xlink="http://www.w3.org/1999/xlink""#, "");
        assert_eq!(
            external_references(&without_ns),
            Vec::<String>::new(),
            "{f}"
        );
    }
    let top = std::fs::read_to_string(out.join("top_view.svg")).unwrap();
    assert!(top.contains("data:image/png;base64,") && top.contains("t = 3 s"));
    clean_up(&dir);
}

#[test]
fn malformed_reports_are_refused_with_the_field_named() {
    let dir = temp_dir("bad");
    let mut m = mission();
    m["samples"]["v"].as_array_mut().unwrap().pop();
    let n = m["samples"]["t"].as_array().unwrap().len();
    let input = dir.join("bad.json");
    std::fs::write(&input, serde_json::to_vec(&m).unwrap()).unwrap();
    let out = dir.join("out");
    let run = moma()
        .arg("render-report")
        .arg(&input)
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert_eq!(run.status.code(), Some(1));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains("bad.json")
            && err.contains(&format!("samples.v: {} values for {} times", n - 1, n)),
        "{err}"
    );
    assert!(!out.exists(), "no output on error");
    // a robot whose mesh does not resolve, a posture of the wrong length: exit 1, named,
    // nothing written
    std::fs::write(&input, serde_json::to_vec(&mission()).unwrap()).unwrap();
    let bad_urdf = dir.join("bad.urdf");
    std::fs::write(
        &bad_urdf,
        r#"<robot name="r"><link name="a"><visual><geometry><mesh filename="package://nowhere/m.stl"/></geometry></visual></link></robot>"#,
    )
    .unwrap();
    let posture = dir.join("posture.json");
    std::fs::write(&posture, r#"{"states": [{"q": [0.1, 0.2]}]}"#).unwrap();
    let urdf = repo().join("scenarios/robots/mobile_manipulator.urdf");
    for (extra, expect) in [
        (
            vec!["--robot".to_string(), bad_urdf.display().to_string()],
            "bad.urdf: link 'a' mesh 'package://nowhere/m.stl': cannot resolve",
        ),
        (
            vec![
                "--robot".to_string(),
                urdf.display().to_string(),
                "--posture".into(),
                posture.display().to_string(),
            ],
            "posture.json: q has 2 values, the model's nq is",
        ),
    ] {
        let run = moma()
            .arg("render-report")
            .arg(&input)
            .arg("-o")
            .arg(&out)
            .args(&extra)
            .output()
            .unwrap();
        assert_eq!(run.status.code(), Some(1), "{extra:?}");
        let err = String::from_utf8_lossy(&run.stderr);
        assert!(err.contains(expect), "{extra:?}: {err}");
        assert!(!out.exists(), "no output on error");
    }
    clean_up(&dir);
}

fn find_browser() -> Option<PathBuf> {
    let path = std::env::var_os("PATH")?;
    for dir in std::env::split_paths(&path) {
        for name in ["chromium", "chromium-browser"] {
            let p = dir.join(name);
            if p.is_file() {
                return Some(p);
            }
        }
    }
    None
}

/// Runs headless Chromium on `page` with `extra` arguments and a fresh profile folder
/// (`profile`, so that no earlier instance's lock is in the way); returns its stdout.
/// Headless Chromium now and then stalls on a loaded machine before its virtual-time
/// budget ends, so one attempt gets 90 s; a stalled attempt's whole process group is
/// killed and the run is tried again, three times at most.
fn chromium(browser: &Path, profile: &Path, page: &Path, extra: &[String]) -> String {
    for attempt in 1..=3 {
        if let Some(out) = chromium_once(browser, profile, page, extra) {
            return out;
        }
        let _ = writeln!(
            std::io::stderr(),
            "chromium {extra:?}: attempt {attempt} stalled for 90 s and was killed; retrying"
        );
    }
    panic!("chromium {extra:?} stalled three times");
}

fn chromium_once(browser: &Path, profile: &Path, page: &Path, extra: &[String]) -> Option<String> {
    let _ = std::fs::remove_dir_all(profile);
    let mut cmd = Command::new(browser);
    cmd.args([
        "--headless",
        "--no-sandbox",
        "--disable-gpu",
        "--hide-scrollbars",
        "--no-first-run",
        "--disable-extensions",
        "--disable-background-networking",
        "--run-all-compositor-stages-before-draw",
        // WebGL without a GPU: Chromium's software renderer, which it no longer picks on
        // its own
        "--enable-unsafe-swiftshader",
        "--window-size=1280,2000",
    ])
    .arg(format!("--user-data-dir={}", profile.display()))
    .args(extra)
    .arg(page)
    .stdin(Stdio::null())
    .stdout(Stdio::piped())
    .stderr(Stdio::null());
    #[cfg(unix)]
    std::os::unix::process::CommandExt::process_group(&mut cmd, 0);
    let mut child = cmd.spawn().expect("starting chromium");
    let mut stdout = child.stdout.take().unwrap();
    let reader = std::thread::spawn(move || {
        let mut s = String::new();
        let _ = std::io::Read::read_to_string(&mut stdout, &mut s);
        s
    });
    let started = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if started.elapsed() > Duration::from_secs(90) {
            // the launcher may be a shell script: end the whole group it leads
            let _ = Command::new("kill")
                .args(["-KILL", "--", &format!("-{}", child.id())])
                .status();
            let _ = child.kill();
            let _ = child.wait();
            return None;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    Some(reader.join().unwrap())
}

/// The attributes of the dumped `<body>` tag.
fn body_attr(dom: &str, name: &str) -> Option<String> {
    let start = dom.find("<body")?;
    let tag = &dom[start..start + dom[start..].find('>')?];
    let key = format!(" {name}=\"");
    let i = tag.find(&key)? + key.len();
    Some(tag[i..i + tag[i..].find('"')?].to_string())
}

#[test]
fn report_plays_in_headless_chromium() {
    let Some(browser) = find_browser() else {
        // written to the process's stderr directly, not through the test harness's
        // capture (which hides a passing test's output), so the skip is never silent
        let _ = writeln!(
            std::io::stderr(),
            "SKIPPED report_plays_in_headless_chromium: no chromium or chromium-browser on \
             PATH (Debian: apt-get install chromium); the static checks still ran"
        );
        return;
    };
    let dir = temp_dir("browser");
    // the shipped mission robot (primitives only), its planar base following the path
    let urdf = repo().join("scenarios/robots/mobile_manipulator.urdf");
    let out = render_with(&dir, "out", &["--robot".into(), urdf.display().to_string()]);
    let page = std::fs::canonicalize(out.join("report.html")).unwrap();
    let profile = dir.join("profile");
    let dump = |ms: u32| {
        chromium(
            &browser,
            &profile,
            &page,
            &["--dump-dom".into(), format!("--virtual-time-budget={ms}")],
        )
    };
    let early = dump(1000);
    let late = dump(5000);
    for (dom, when) in [(&early, "1 s"), (&late, "5 s")] {
        assert!(dom.contains("<body"), "no DOM dumped at {when}: {dom:.300}");
        assert_eq!(
            body_attr(dom, "data-errors").as_deref(),
            Some(""),
            "console errors at {when}"
        );
        assert_eq!(body_attr(dom, "data-error-count").as_deref(), Some("0"));
        let drawn = body_attr(dom, "data-plots-drawn").unwrap();
        assert_eq!(
            Some(drawn),
            body_attr(dom, "data-plots"),
            "plots drawn at {when}"
        );
        assert_eq!(body_attr(dom, "data-plots").as_deref(), Some("7"));
        assert_eq!(body_attr(dom, "data-view3d").as_deref(), Some("drawn"));
        // base box, 2 wheels, 4 casters, mount plate, 6 arm links
        assert_eq!(body_attr(dom, "data-view3d-shapes").as_deref(), Some("14"));
    }
    let frame = |dom: &str| -> usize { body_attr(dom, "data-frame").unwrap().parse().unwrap() };
    let time = |dom: &str| -> f64 { body_attr(dom, "data-time").unwrap().parse().unwrap() };
    assert!(frame(&early) > 0, "the animation did not start");
    assert!(
        frame(&late) > frame(&early),
        "the animation did not advance: frame {} then {}",
        frame(&early),
        frame(&late)
    );
    // autoplay at 1×: the clock follows the browser's virtual time (loosely: the budget
    // also covers loading, and the dump comes a little after it ends)
    let (te, tl) = (time(&early), time(&late));
    assert!(te > 0.2 && te < 3.0, "t = {te} s after 1 s");
    assert!(
        tl > 3.0 && tl > te + 1.0,
        "t = {tl} s after 5 s, {te} s after 1 s"
    );
    // by then the obstacle (t = 3 s) has appeared and the re-plan is the plan in use
    assert!(
        late.contains("re-plan 1"),
        "the 'now' table names the re-plan"
    );
    // the summary table: human labels with units, no raw key or JSON, every value shown
    let table = late
        .split("<table id=\"summary\">")
        .nth(1)
        .and_then(|r| r.split("</table>").next())
        .expect("the summary table");
    for label in [
        "smallest ZMP margin [m]",
        "tip-over acceleration limit, backward [m/s²]",
        "wall time, report [s]",
        "files written",
        "summary.json, report.html, torques.svg",
        "D* Lite 0.8 ms, 412 cells expanded",
    ] {
        assert!(
            table.contains(label),
            "no {label:?} in the summary table: {table}"
        );
    }
    for raw in ["{", "_s", "min zmp", "tip_over", "[]"] {
        assert!(
            !table.contains(raw),
            "raw {raw:?} in the summary table: {table}"
        );
    }
    let shot = |ms: u32, name: &str| -> Vec<u8> {
        let file = dir.join(name);
        chromium(
            &browser,
            &profile,
            &page,
            &[
                format!("--screenshot={}", file.display()),
                format!("--virtual-time-budget={ms}"),
            ],
        );
        std::fs::read(&file).unwrap_or_else(|e| panic!("no screenshot {name}: {e}"))
    };
    let a = shot(1000, "a.png");
    let b = shot(4000, "b.png");
    assert!(a.starts_with(b"\x89PNG") && b.starts_with(b"\x89PNG"));
    assert_ne!(a, b, "the screenshots after 1 s and 4 s are identical");
    // the 3-D canvas: the robot is in it, and it moves
    let rect = view3d_rect(&late);
    let (a, b) = (Screenshot::read(&a), Screenshot::read(&b));
    let (na, nb) = (a.robot_pixels(rect), b.robot_pixels(rect));
    assert!(
        na > 2000 && nb > 2000,
        "robot-coloured pixels in the 3-D view: {na} after 1 s, {nb} after 4 s"
    );
    let changed = a.changed_pixels(&b, rect);
    assert!(
        changed > rect[2] * rect[3] / 100,
        "only {changed} pixels of the 3-D view differ between 1 s and 4 s"
    );
    clean_up(&dir);
}

/// The 3-D canvas's rectangle in page pixels from the dumped `<body>`: x, y, w, h.
fn view3d_rect(dom: &str) -> [usize; 4] {
    let r: Vec<usize> = body_attr(dom, "data-view3d-rect")
        .expect("data-view3d-rect")
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    assert!(r.len() == 4 && r[2] > 300 && r[3] > 100, "{r:?}");
    [r[0], r[1], r[2], r[3]]
}

/// A decoded screenshot, RGB.
struct Screenshot {
    width: usize,
    height: usize,
    rgb: Vec<u8>,
}

impl Screenshot {
    fn read(bytes: &[u8]) -> Screenshot {
        let mut d = png::Decoder::new(std::io::Cursor::new(bytes));
        d.set_transformations(png::Transformations::EXPAND | png::Transformations::STRIP_16);
        let mut r = d.read_info().unwrap();
        let mut buf = vec![0; r.output_buffer_size().unwrap()];
        let info = r.next_frame(&mut buf).unwrap();
        let ch = info.color_type.samples();
        assert!(ch >= 3, "a colour screenshot");
        let rgb = buf[..info.buffer_size()]
            .chunks(ch)
            .flat_map(|p| [p[0], p[1], p[2]])
            .collect();
        Screenshot {
            width: info.width as usize,
            height: info.height as usize,
            rgb,
        }
    }
    /// The pixels of `rect` that lie in the screenshot.
    fn pixels(&self, rect: [usize; 4]) -> impl Iterator<Item = (usize, [u8; 3])> + '_ {
        let [x, y, w, h] = rect;
        (y..(y + h).min(self.height)).flat_map(move |row| {
            (x..(x + w).min(self.width)).map(move |col| {
                let i = 3 * (row * self.width + col);
                (i, [self.rgb[i], self.rgb[i + 1], self.rgb[i + 2]])
            })
        })
    }
    /// Pixels of the 3-D view's robot colour (teal, #2a9d8f and #1f7a6f, lit or shaded):
    /// green and blue well above red and close to each other. Nothing else in the 3-D
    /// view has that hue (grey walls, white and grey map, orange obstacles, red path,
    /// grey plan, magenta target, tan scene objects, dark wheels).
    fn robot_pixels(&self, rect: [usize; 4]) -> usize {
        self.pixels(rect)
            .filter(|(_, [r, g, b])| {
                let (r, g, b) = (i32::from(*r), i32::from(*g), i32::from(*b));
                g > r + 45 && b > r + 35 && (g - b).abs() < 60
            })
            .count()
    }
    fn changed_pixels(&self, other: &Screenshot, rect: [usize; 4]) -> usize {
        self.pixels(rect)
            .filter(|(i, p)| other.rgb.get(*i..*i + 3) != Some(&p[..]))
            .count()
    }
}

#[test]
fn the_3d_view_draws_fetch_meshes_in_a_scene_and_nothing_without_a_robot() {
    let Some(browser) = find_browser() else {
        let _ = writeln!(
            std::io::stderr(),
            "SKIPPED the_3d_view_draws_fetch_meshes_in_a_scene_and_nothing_without_a_robot: \
             no chromium or chromium-browser on PATH"
        );
        return;
    };
    let dir = temp_dir("fetch");
    let data = repo().join("crates/moma/tests/data");
    let fetch = data.join("robots/fetch/fetch_description/robots/fetch.urdf");
    let scene = data.join("scenes/motion_bench_maker/configs/scenes/bookshelf/scene_small.yaml");
    let with_fetch = render_with(
        &dir,
        "fetch",
        &[
            "--robot".into(),
            fetch.display().to_string(),
            "--root".into(),
            "fixed".into(),
            "--scene".into(),
            scene.display().to_string(),
        ],
    );
    let html = std::fs::read_to_string(with_fetch.join("report.html")).unwrap();
    let start = html.find(r#"id="mission-data">"#).unwrap() + r#"id="mission-data">"#.len();
    let end = start + html[start..].find("</script>").unwrap();
    let v: Value = serde_json::from_str::<Value>(&html[start..end]).unwrap()["view3d"].clone();
    let robot = v["robot"].as_array().unwrap();
    // Fetch's visuals are COLLADA for most links: those links are drawn with their
    // collision STL meshes, the rest with their visual STLs
    let meshes = robot.iter().filter(|s| s["g"]["type"] == "mesh").count();
    assert!(meshes >= 15, "{meshes} Fetch meshes of {}", robot.len());
    assert!(!v["scene"].as_array().unwrap().is_empty(), "the bookshelf");
    assert!(html.len() < 2_500_000, "{} bytes", html.len());
    let empty = render_with(&dir, "none", &[]);
    let mut counts = Vec::new();
    for (out, expect) in [(&with_fetch, "drawn"), (&empty, "none")] {
        let page = std::fs::canonicalize(out.join("report.html")).unwrap();
        let profile = dir.join("profile");
        let dom = chromium(
            &browser,
            &profile,
            &page,
            &["--dump-dom".into(), "--virtual-time-budget=1500".into()],
        );
        assert_eq!(body_attr(&dom, "data-errors").as_deref(), Some(""));
        assert_eq!(body_attr(&dom, "data-view3d").as_deref(), Some(expect));
        let file = out.join("shot.png");
        chromium(
            &browser,
            &profile,
            &page,
            &[
                format!("--screenshot={}", file.display()),
                "--virtual-time-budget=1500".into(),
            ],
        );
        let shot = Screenshot::read(&std::fs::read(&file).unwrap());
        counts.push(shot.robot_pixels(view3d_rect(&dom)));
    }
    assert!(
        counts[0] > 2000 && counts[1] < 50,
        "robot-coloured pixels in the 3-D view: {} with Fetch, {} without a robot",
        counts[0],
        counts[1]
    );
    clean_up(&dir);
}

//! The run as the page's JSON: decimation to a bounded number of samples, rounding to the
//! precision a picture needs, and embedding inside a `<script type="application/json">`
//! element without any way for the text to close it.

use super::numbers::{decimate_indices, num};
use super::{MissionReport, map};
use serde_json::{Map, Value, json};

/// Most samples the page receives (the uniform grid; the kept extremes come on top).
pub const MAX_SAMPLES: usize = 2000;
/// Most points of one plan on the page.
pub const MAX_PLAN_POINTS: usize = 1500;

fn opt(x: Option<f64>, dec: i32) -> Value {
    x.map_or(Value::Null, |v| num(v, dec))
}

fn column(v: &[f64], idx: &[usize], dec: i32) -> Value {
    Value::Array(idx.iter().map(|&i| num(v[i], dec)).collect())
}

fn opt_column(v: &[Option<f64>], idx: &[usize], dec: i32) -> Value {
    Value::Array(idx.iter().map(|&i| opt(v[i], dec)).collect())
}

/// Index of the smallest (`sign` = 1) or largest (`sign` = −1) finite value.
fn arg_extreme(v: impl Iterator<Item = Option<f64>>, sign: f64) -> Option<usize> {
    let mut best: Option<(usize, f64)> = None;
    for (i, x) in v.enumerate() {
        if let Some(x) = x.filter(|x| x.is_finite())
            && best.is_none_or(|(_, b)| sign * x < sign * b)
        {
            best = Some((i, x));
        }
    }
    best.map(|(i, _)| i)
}

/// The samples that decimation must keep: the monitors' extremes, the first undefined
/// tip-over measure, and the sample nearest each event, plan and obstacle time.
pub(crate) fn kept_samples(r: &MissionReport) -> Vec<usize> {
    let s = &r.samples;
    let mut keep = Vec::new();
    keep.extend(arg_extreme(s.zmp_margin.iter().copied(), 1.0));
    keep.extend(arg_extreme(s.force_angle_min.iter().copied(), 1.0));
    keep.extend(s.zmp_margin.iter().position(Option::is_none));
    keep.extend(s.force_angle_min.iter().position(Option::is_none));
    keep.extend(arg_extreme(s.clearance.iter().map(|&x| Some(x)), 1.0));
    keep.extend(arg_extreme(s.tracking_error.iter().map(|&x| Some(x)), -1.0));
    for c in &s.torques {
        keep.extend(arg_extreme(c.iter().map(|&x| Some(x.abs())), -1.0));
    }
    let times = r
        .events
        .iter()
        .map(|e| e.t)
        .chain(r.plans.iter().map(|p| p.t))
        .chain(r.obstacles.iter().map(|o| o.t));
    for t in times {
        if t.is_finite() && !s.t.is_empty() {
            // first sample at or after t (the times are increasing)
            let i = s.t.partition_point(|&x| x < t).min(s.t.len() - 1);
            keep.push(i);
        }
    }
    keep
}

/// The page's data object.
pub(crate) fn page_data(r: &MissionReport) -> Value {
    let s = &r.samples;
    let idx = decimate_indices(s.t.len(), MAX_SAMPLES, &kept_samples(r));
    let pose = |p: &[f64; 3]| json!([num(p[0], 4), num(p[1], 4), num(p[2], 4)]);
    let plans: Vec<Value> = r
        .plans
        .iter()
        .map(|p| {
            let pi = decimate_indices(p.points.len(), MAX_PLAN_POINTS, &[]);
            let flat: Vec<Value> = pi
                .iter()
                .flat_map(|&i| [num(p.points[i][0], 4), num(p.points[i][1], 4)])
                .collect();
            json!({ "t": num(p.t, 4), "p": flat })
        })
        .collect();
    let obstacles: Vec<Value> = r
        .obstacles
        .iter()
        .map(|o| {
            json!({
                "t": num(o.t, 4),
                "c": [num(o.center[0], 4), num(o.center[1], 4)],
                "r": num(o.radius, 4),
            })
        })
        .collect();
    let arm: Vec<Value> = idx
        .iter()
        .map(|&i| {
            Value::Array(
                s.arm_side[i]
                    .iter()
                    .flat_map(|p| [num(p[0], 4), num(p[1], 4)])
                    .collect(),
            )
        })
        .collect();
    let torques: Vec<Value> = s.torques.iter().map(|c| column(c, &idx, 3)).collect();
    let mut samples = Map::new();
    samples.insert("t".into(), column(&s.t, &idx, 4));
    samples.insert("x".into(), column(&s.x, &idx, 4));
    samples.insert("y".into(), column(&s.y, &idx, 4));
    samples.insert("th".into(), column(&s.theta, &idx, 4));
    samples.insert("v".into(), column(&s.v, &idx, 4));
    samples.insert("w".into(), column(&s.omega, &idx, 4));
    samples.insert("vr".into(), column(&s.v_ref, &idx, 4));
    samples.insert("wr".into(), column(&s.omega_ref, &idx, 4));
    samples.insert("zmp".into(), opt_column(&s.zmp_margin, &idx, 4));
    samples.insert("fa".into(), opt_column(&s.force_angle_min, &idx, 4));
    samples.insert("clr".into(), column(&s.clearance, &idx, 4));
    samples.insert("err".into(), column(&s.tracking_error, &idx, 5));
    samples.insert("tq".into(), Value::Array(torques));
    samples.insert("arm".into(), Value::Array(arm));
    let events: Vec<Value> = r
        .events
        .iter()
        .map(|e| json!({ "t": num(e.t, 4), "kind": e.kind, "text": e.text }))
        .collect();
    let view = map::view_region(r);
    let image = map::encode(&r.map, view);
    json!({
        "title": r.title,
        "footprint_radius": num(r.footprint_radius, 4),
        "start": pose(&r.start),
        "goal": pose(&r.goal),
        "ee_target": r.end_effector_target.map(|p| json!([num(p[0], 4), num(p[1], 4), num(p[2], 4)])),
        "map": {
            "png": image.data_uri,
            "x0": image.x0, "y0": image.y0, "x1": image.x1, "y1": image.y1,
            "w": image.width, "h": image.height,
        },
        "view": [view[0], view[1], view[2], view[3]],
        "plans": plans,
        "obstacles": obstacles,
        "torque_names": s.torque_names,
        "samples": Value::Object(samples),
        "events": events,
        "summary": r.summary,
        "walls": map::walls(&r.map, view)
            .iter()
            .map(|w| w.map(|x| num(x, 4)))
            .collect::<Vec<_>>(),
        "view3d": r.view3d.as_ref().map(super::view3d::page_value),
    })
}

/// JSON text safe inside `<script type="application/json">`: `<`, `>` and `&` (which only
/// occur inside JSON strings) become `\u003c`, `\u003e`, `\u0026`, so neither
/// `</script>` nor `<!--` can appear; `JSON.parse` reads the same strings back.
pub(crate) fn script_json(v: &Value) -> String {
    let text = v.to_string();
    let mut o = String::with_capacity(text.len() + 64);
    for c in text.chars() {
        match c {
            '<' => o.push_str("\\u003c"),
            '>' => o.push_str("\\u003e"),
            '&' => o.push_str("\\u0026"),
            '\u{2028}' => o.push_str("\\u2028"),
            '\u{2029}' => o.push_str("\\u2029"),
            c => o.push(c),
        }
    }
    o
}

/// Text for HTML element content and attribute values.
pub(crate) fn html_escape(t: &str) -> String {
    t.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn script_json_cannot_close_its_element_and_parses_back() {
        let v = json!({"text": "a </script><script>alert(1)</script> & <!-- b", "n": null});
        let s = script_json(&v);
        assert!(
            !s.contains('<') && !s.contains('>') && !s.contains('&'),
            "{s}"
        );
        assert!(!s.to_ascii_lowercase().contains("</script"));
        let back: Value = serde_json::from_str(&s).unwrap();
        assert_eq!(back, v);
    }

    #[test]
    fn none_and_non_finite_values_become_null() {
        assert_eq!(opt(None, 3), Value::Null);
        assert_eq!(num(f64::NAN, 3), Value::Null);
        assert_eq!(num(f64::INFINITY, 3), Value::Null);
        assert_eq!(opt(Some(0.123456), 3).to_string(), "0.123");
        assert_eq!(num(-0.00001, 3).to_string(), "0.0");
        assert_eq!(num(2.5e-3, 4).to_string(), "0.0025");
        let c = opt_column(&[Some(1.0), None, Some(-2.25)], &[0, 1, 2], 2);
        assert_eq!(c.to_string(), "[1.0,null,-2.25]");
    }

    #[test]
    fn extremes_are_found_and_undefined_values_skipped() {
        let v = [Some(0.3), None, Some(-0.1), Some(f64::NAN), Some(0.2)];
        assert_eq!(arg_extreme(v.iter().copied(), 1.0), Some(2));
        assert_eq!(arg_extreme(v.iter().copied(), -1.0), Some(0));
        assert_eq!(arg_extreme([None, None].into_iter(), 1.0), None);
    }
}

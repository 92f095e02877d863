//! Golden outputs of every shipped scenario: each `scenarios/mission*.toml` mission and
//! each `moma simulate` scenario of `scenarios/*.toml` runs through the library, and its
//! summary figures plus a few trajectory samples are held to the values stored in
//! `tests/data/scenario_golden.json` (relative tolerance 1e-9, absolute 1e-12).
//!
//! The file was captured from the code before the closed loop and the scenario schemas
//! were rebuilt; a change of behaviour must change a value here on purpose, with its
//! reason in the commit. `MOMA_WRITE_GOLDEN=1` rewrites the file from the current code
//! (the test then fails, so that a rewrite is never silent).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use moma::mission;
use moma::sim::free_floating;
use moma::sim::recorder::Recorder;
use moma::sim_config::{Run, load, prepare};

type Golden = BTreeMap<String, BTreeMap<String, Vec<f64>>>;

fn scenarios() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios")
}

fn golden_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/scenario_golden.json")
}

/// `None` as NaN, so a figure that becomes undefined (or defined) shows as a change.
fn opt(x: Option<f64>) -> f64 {
    x.unwrap_or(f64::NAN)
}

/// Indices of the first, a quarter, the middle, three quarters and the last sample.
fn picks(n: usize) -> Vec<usize> {
    if n == 0 {
        return Vec::new();
    }
    let mut p: Vec<usize> = [0, n / 4, n / 2, 3 * n / 4, n - 1].to_vec();
    p.dedup();
    p
}

fn recorder_rows(rec: &Recorder, out: &mut BTreeMap<String, Vec<f64>>) {
    out.insert("samples".into(), vec![rec.len() as f64]);
    for i in picks(rec.len()) {
        let mut row = vec![rec.times[i]];
        row.extend_from_slice(rec.q_row(i));
        row.extend_from_slice(rec.v_row(i));
        row.extend_from_slice(rec.u_row(i));
        row.push(rec.kinetic[i] + rec.potential[i]);
        row.push(rec.work[i]);
        out.insert(format!("sample_{i}"), row);
    }
}

fn run_simulate(path: &Path) -> BTreeMap<String, Vec<f64>> {
    let name = path.display().to_string();
    let sc = load(path).unwrap_or_else(|e| panic!("{name}: {e}"));
    let mut out = BTreeMap::new();
    match prepare(&sc, path).unwrap_or_else(|e| panic!("{name}: {e}")) {
        Run::Open(mut ol) => {
            let r = ol
                .run(&mut |_| {})
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            recorder_rows(&r.recorder, &mut out);
            out.insert(
                "monitor".into(),
                vec![r.monitor.max_energy_error, r.monitor.max_residual],
            );
            out.insert("stopped_at".into(), vec![opt(r.stopped_at)]);
            if let Some(m) = &ol.monitor {
                let tr = &m.trace;
                let zmp = tr.zmp_margin.iter().flatten().copied().reduce(f64::min);
                let fa = tr
                    .force_angle_min
                    .iter()
                    .flatten()
                    .copied()
                    .reduce(f64::min);
                out.insert("stability".into(), vec![opt(zmp), opt(fa)]);
            }
        }
        Run::Closed(mut cl) => {
            let r = cl
                .run(&mut |_| {})
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            recorder_rows(&r.recorder, &mut out);
            let n = r.error_names.len();
            if n > 0 {
                out.insert(
                    "final_error".into(),
                    r.errors[r.errors.len() - n..].to_vec(),
                );
            }
            out.insert("control_ticks".into(), vec![r.control_ticks as f64]);
            if let Some(m) = cl.law.mpc_run() {
                // The MPC's figures but its wall-clock solve times.
                let s = &m.summary;
                let v = &s.planned_violations;
                out.insert(
                    "mpc".into(),
                    vec![
                        s.solves as f64,
                        s.iterations.mean,
                        s.iterations.max as f64,
                        v.torque,
                        v.wheel_speed,
                        v.joint_speed,
                        v.joint_position,
                        v.zmp,
                        v.clearance,
                        s.min_zmp_margin,
                        s.min_clearance,
                        s.max_torque_excess,
                        opt(s.min_ee_error),
                    ],
                );
            }
        }
        Run::Space(sr) => {
            let r = free_floating::run(&sr.model, &sr.q0, &sr.v0, &sr.settings)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            out.insert("samples".into(), vec![r.samples.len() as f64]);
            for i in picks(r.samples.len()) {
                let s = &r.samples[i];
                let mut row = vec![s.t];
                row.extend(s.q.iter());
                row.extend(s.v.iter());
                row.extend(s.com.iter());
                out.insert(format!("sample_{i}"), row);
            }
            out.insert("steps".into(), vec![r.steps as f64]);
        }
    }
    out
}

fn run_mission(path: &Path) -> BTreeMap<String, Vec<f64>> {
    let name = path.display().to_string();
    let m = mission::load(path).unwrap_or_else(|e| panic!("{name}: {e}"));
    let r = mission::run(&m).unwrap_or_else(|e| panic!("{name}: {e}"));
    let mut out = BTreeMap::new();
    let mut s = mission::summary(&m, &r);
    // law mpc's figures but its wall-clock solve times
    if let Some(mpc) = s.get_mut("mpc").and_then(|m| m.as_object_mut()) {
        mpc.remove("solve_time_s");
    }
    // a pick's figures but its wall-clock planning times (and how many states the
    // planner's report reached within its time)
    if let Some(task) = s.get_mut("task").and_then(|t| t.as_object_mut()) {
        if let Some(p) = task.get_mut("placement").and_then(|p| p.as_object_mut()) {
            p.remove("time_s");
        }
        if let Some(plans) = task.get_mut("arm_plans").and_then(|a| a.as_array_mut()) {
            for plan in plans.iter_mut().filter_map(|p| p.as_object_mut()) {
                plan.remove("planning_time_s");
                plan.remove("min_distance_states");
            }
        }
    }
    for (k, v) in &s {
        let mut nums = Vec::new();
        collect_numbers(v, &mut nums);
        if !nums.is_empty() {
            out.insert(format!("summary.{k}"), nums);
        }
    }
    out.insert("reached".into(), vec![f64::from(u8::from(r.reached))]);
    let n = r.samples.t.len();
    for i in picks(n) {
        let mut row = vec![r.samples.t[i]];
        row.extend_from_slice(&r.samples.q[i]);
        row.push(r.samples.v[i]);
        row.push(r.samples.omega[i]);
        row.extend_from_slice(&r.samples.u[i]);
        row.push(opt(r.samples.zmp_margin[i]));
        row.push(opt(r.samples.slip_ratio[i]));
        row.push(r.samples.tracking_error[i]);
        row.extend_from_slice(&r.samples.ee[i]);
        out.insert(format!("sample_{i}"), row);
    }
    out.insert(
        "events".into(),
        r.events.iter().map(|e| e.t).collect::<Vec<_>>(),
    );
    out
}

fn collect_numbers(v: &serde_json::Value, out: &mut Vec<f64>) {
    match v {
        serde_json::Value::Number(n) => out.push(n.as_f64().unwrap_or(f64::NAN)),
        serde_json::Value::Bool(b) => out.push(f64::from(u8::from(*b))),
        serde_json::Value::Null => out.push(f64::NAN),
        serde_json::Value::Array(a) => a.iter().for_each(|x| collect_numbers(x, out)),
        serde_json::Value::Object(o) => o.values().for_each(|x| collect_numbers(x, out)),
        serde_json::Value::String(_) => {}
    }
}

fn close(a: f64, b: f64) -> bool {
    (a.is_nan() && b.is_nan()) || a == b || (a - b).abs() <= 1e-9 * a.abs().max(b.abs()) + 1e-12
}

/// NaN is stored as `null` in the JSON file.
fn to_json(g: &Golden) -> serde_json::Value {
    serde_json::to_value(g).expect("golden values serialise")
}

fn from_json(v: &serde_json::Value) -> Golden {
    let mut g = Golden::new();
    for (scenario, figures) in v.as_object().expect("golden file is an object") {
        let mut f = BTreeMap::new();
        for (k, xs) in figures.as_object().expect("figures are an object") {
            let xs = xs
                .as_array()
                .expect("figure is an array")
                .iter()
                .map(|x| x.as_f64().unwrap_or(f64::NAN))
                .collect();
            f.insert(k.clone(), xs);
        }
        g.insert(scenario.clone(), f);
    }
    g
}

#[test]
fn shipped_scenarios_keep_their_golden_outputs() {
    let mut names: Vec<String> = std::fs::read_dir(scenarios())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        // The contact plant's scenarios (`contact_*`) are checked without golden values,
        // against the rolling plant, by tests/sim_contact_plant.rs.
        .filter(|n| n.ends_with(".toml") && !n.starts_with("contact_"))
        .collect();
    names.sort();
    let mut now = Golden::new();
    for name in &names {
        let path = scenarios().join(name);
        let figures = if name.starts_with("mission") {
            run_mission(&path)
        } else {
            run_simulate(&path)
        };
        now.insert(name.clone(), figures);
    }
    assert!(
        now.len() >= 30,
        "only {} shipped scenarios found",
        now.len()
    );
    if std::env::var_os("MOMA_WRITE_GOLDEN").is_some() {
        let text = serde_json::to_string_pretty(&to_json(&now)).unwrap();
        std::fs::write(golden_path(), text + "\n").unwrap();
        panic!("golden values rewritten to {}", golden_path().display());
    }
    let text = std::fs::read_to_string(golden_path()).expect("golden file");
    let want = from_json(&serde_json::from_str(&text).expect("golden JSON"));
    let mut diffs = Vec::new();
    for (scenario, figures) in &now {
        let Some(w) = want.get(scenario) else {
            diffs.push(format!("{scenario}: no golden values"));
            continue;
        };
        for (k, xs) in figures {
            match w.get(k) {
                None => diffs.push(format!("{scenario}.{k}: not in the golden file")),
                Some(ys) if ys.len() != xs.len() => diffs.push(format!(
                    "{scenario}.{k}: {} values, golden {}",
                    xs.len(),
                    ys.len()
                )),
                Some(ys) => {
                    for (i, (x, y)) in xs.iter().zip(ys).enumerate() {
                        if !close(*x, *y) {
                            diffs.push(format!("{scenario}.{k}[{i}]: {x:e}, golden {y:e}"));
                        }
                    }
                }
            }
        }
        for k in w.keys().filter(|k| !figures.contains_key(*k)) {
            diffs.push(format!("{scenario}.{k}: golden but no longer produced"));
        }
    }
    assert!(
        diffs.is_empty(),
        "{} differences:\n{}",
        diffs.len(),
        diffs.join("\n")
    );
}

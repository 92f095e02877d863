//! Scenario runs (`moma.simulate`): a `moma simulate` file run as the command runs it
//! (the library's `sim_config` dispatch), its recorded samples as numpy arrays and the
//! summary values its results hold.

use crate::{chain, err, json_to_py};
use moma::contact::PlantKind;
use moma::ode::StepStats;
use moma::sim::contact_run::SETTLE_TIME;
use moma::sim::monitor::Monitor;
use moma::sim::recorder::Recorder;
use moma::sim_config::{Run, prepare};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use serde_json::{Map, Value, json};
use std::path::{Path, PathBuf};

/// Named columns of row-major samples (one row per recorded sample).
struct Table {
    names: Vec<String>,
    values: Vec<f64>,
}

/// What a finished run hands to Python.
struct Outcome {
    doc: Map<String, Value>,
    t: Vec<f64>,
    q: Table,
    v: Table,
    u: Table,
    errors: Option<Table>,
}

/// The recorder's samples and the summary values every reduced-coordinate run shares.
fn recorded(rec: &Recorder, doc: &mut Map<String, Value>) -> (Vec<f64>, Table, Table, Table) {
    let last = rec.len() - 1;
    doc.insert("samples".into(), json!(rec.len()));
    doc.insert("final_q".into(), json!(rec.q_row(last)));
    doc.insert("final_v".into(), json!(rec.v_row(last)));
    let table = |names: &[String], values: &[f64]| Table {
        names: names.to_vec(),
        values: values.to_vec(),
    };
    (
        rec.times.clone(),
        table(&rec.q_names, &rec.q),
        table(&rec.v_names, &rec.v),
        table(&rec.u_names, &rec.u),
    )
}

/// `"{path}: {what}: {cause}"`, as the command line prints a failed run.
/// The energy and constraint monitors and the step counts, as the CLI's summary has them.
fn monitored(monitor: &Monitor, stats: &StepStats, doc: &mut Map<String, Value>) {
    doc.insert("max_energy_error".into(), json!(monitor.max_energy_error));
    doc.insert(
        "relative_energy_error".into(),
        json!(monitor.relative_energy_error()),
    );
    doc.insert(
        "max_constraint_residual".into(),
        json!(monitor.max_residual),
    );
    doc.insert("accepted_steps".into(), json!(stats.accepted));
    doc.insert("rejected_steps".into(), json!(stats.rejected));
    doc.insert("rhs_evaluations".into(), json!(stats.rhs_evals));
}

fn failed(path: &Path, what: &str, e: &moma::Error) -> String {
    format!("{}: {what}: {}", path.display(), chain(e))
}

/// A serialisable report as JSON.
fn value<T: serde::Serialize>(x: &T) -> Result<Value, String> {
    serde_json::to_value(x).map_err(|e| e.to_string())
}

/// Loads, prepares and runs the scenario (what `moma simulate` does before writing).
fn run_scenario(path: &Path) -> Result<Outcome, String> {
    let lib = |e: moma::Error| chain(&e);
    let sc = moma::sim_config::load(path).map_err(lib)?;
    sc.check_header(path).map_err(lib)?;
    let mut doc = Map::new();
    doc.insert(
        "scenario".into(),
        json!(
            sc.name
                .clone()
                .unwrap_or_else(|| path.display().to_string())
        ),
    );
    doc.insert("duration".into(), json!(sc.duration));
    if sc.plant == PlantKind::Contact {
        let mut run = moma::sim_config::contact::prepare_contact(&sc, path).map_err(lib)?;
        let res = run
            .run(&mut |_| {})
            .map_err(|e| failed(path, "simulation failed", &e))?;
        let (nq, nv, nu) = (res.q_names.len(), res.v_names.len(), res.u_names.len());
        let ne = res.error_names.len();
        let col = |from: usize, n: usize| -> Vec<f64> {
            res.rows
                .iter()
                .flat_map(|r| r[from..from + n].iter().copied())
                .collect()
        };
        let last = &res.rows[res.rows.len() - 1];
        doc.insert("plant".into(), json!("contact"));
        doc.insert("contact".into(), value(&run.plant.params)?);
        doc.insert("samples".into(), json!(res.rows.len()));
        doc.insert("contact_steps".into(), json!(res.steps));
        doc.insert("control_evaluations".into(), json!(res.control_evaluations));
        doc.insert("steps_per_control".into(), json!(res.steps_per_control));
        doc.insert("final_q".into(), json!(&last[..nq]));
        doc.insert("final_v".into(), json!(&last[nq..nq + nv]));
        doc.insert("events_after_s".into(), json!(SETTLE_TIME));
        doc.insert("first_lift_off".into(), json!(res.first_lift_off));
        doc.insert("first_slip".into(), json!(res.first_slip));
        doc.insert("contacts".into(), json!(res.totals));
        doc.insert("max_tilt_rad".into(), json!(res.max_tilt));
        let width = res.column_names().len();
        let errors = (ne > 0).then(|| Table {
            names: res.error_names.clone(),
            values: col(width - ne, ne),
        });
        return Ok(Outcome {
            doc,
            t: res.times.clone(),
            q: Table {
                names: res.q_names.clone(),
                values: col(0, nq),
            },
            v: Table {
                names: res.v_names.clone(),
                values: col(nq, nv),
            },
            u: Table {
                names: res.u_names.clone(),
                values: col(nq + nv, nu),
            },
            errors,
        });
    }
    match prepare(&sc, path).map_err(lib)? {
        Run::Open(mut ol) => {
            let res = ol
                .run(&mut |_| {})
                .map_err(|e| failed(path, "simulation failed", &e))?;
            let rec = &res.recorder;
            let last = rec.len() - 1;
            doc.insert("robot".into(), json!(ol.robot_name));
            let (t, q, v, u) = recorded(rec, &mut doc);
            doc.insert(
                "initial_energy".into(),
                json!(rec.kinetic[0] + rec.potential[0]),
            );
            doc.insert(
                "final_energy".into(),
                json!(rec.kinetic[last] + rec.potential[last]),
            );
            doc.insert("input_work".into(), json!(rec.work[last]));
            monitored(&res.monitor, &res.stats, &mut doc);
            doc.insert("stopped_at".into(), json!(res.stopped_at));
            Ok(Outcome {
                doc,
                t,
                q,
                v,
                u,
                errors: None,
            })
        }
        Run::Closed(mut cl) => {
            let Some(c) = &sc.controller else {
                return Err(format!(
                    "{}: [reference] needs a [controller] table",
                    path.display()
                ));
            };
            let res = cl
                .run(&mut |_| {})
                // the command prints this failure without the error's causes
                .map_err(|e| format!("{}: closed-loop simulation failed: {e}", path.display()))?;
            let rec = &res.recorder;
            doc.insert("robot".into(), json!(cl.robot_name));
            doc.insert("law".into(), json!(c.law));
            doc.insert(
                "reference".into(),
                json!(sc.reference.as_ref().map_or("", |r| r.kind())),
            );
            doc.insert("warnings".into(), json!(cl.warnings));
            doc.insert("control_period".into(), json!(res.control_period));
            doc.insert("control_ticks".into(), json!(res.control_ticks));
            let (t, q, v, u) = recorded(rec, &mut doc);
            doc.insert("error_names".into(), json!(res.error_names));
            doc.insert("final_error".into(), json!(res.error_row(rec.len() - 1)));
            doc.insert("goal_tolerance".into(), json!(c.goal_tolerance));
            monitored(&res.monitor, &res.stats, &mut doc);
            if let Some(m) = cl.law.mpc_run() {
                doc.insert("mpc".into(), value(&m.summary)?);
            }
            Ok(Outcome {
                doc,
                t,
                q,
                v,
                u,
                errors: Some(Table {
                    names: res.error_names.clone(),
                    values: res.errors.clone(),
                }),
            })
        }
        Run::Space(sr) => {
            let run = moma::sim::free_floating::run(&sr.model, &sr.q0, &sr.v0, &sr.settings)
                .map_err(|e| failed(path, "simulation failed", &e))?;
            let last = &run.samples[run.samples.len() - 1];
            doc.insert("robot".into(), json!(sr.model.name));
            doc.insert("samples".into(), json!(run.samples.len()));
            doc.insert("final_q".into(), json!(last.q.as_slice()));
            doc.insert("final_v".into(), json!(last.v.as_slice()));
            doc.insert("accepted_steps".into(), json!(run.steps));
            doc.insert("rhs_evaluations".into(), json!(run.rhs_evals));
            let flat = |f: &dyn Fn(&moma::sim::free_floating::FloatingSample) -> &[f64]| {
                run.samples
                    .iter()
                    .flat_map(|s| f(s).iter().copied())
                    .collect()
            };
            Ok(Outcome {
                doc,
                t: run.samples.iter().map(|s| s.t).collect(),
                q: Table {
                    names: Vec::new(),
                    values: flat(&|s| s.q.as_slice()),
                },
                v: Table {
                    names: Vec::new(),
                    values: flat(&|s| s.v.as_slice()),
                },
                u: Table {
                    names: Vec::new(),
                    values: Vec::new(),
                },
                errors: None,
            })
        }
    }
}

/// A row-major table as a 2-D array of `n` rows.
fn matrix<'py>(py: Python<'py>, tab: Table, n: usize) -> PyResult<Bound<'py, PyAny>> {
    let cols = tab.values.len().checked_div(n).unwrap_or(0);
    Ok(PyArray1::from_vec(py, tab.values)
        .reshape([n, cols])?
        .into_any())
}

/// Runs a `moma simulate` scenario file as the command does (open loop, closed loop with
/// its `[controller]`, free-floating, or `plant = "contact"`), GIL released, and returns a
/// dict: `t` (1-D), `q`, `v`, `u` (2-D, one row per recorded sample) with `q_names`,
/// `v_names`, `u_names`; with a controller `errors` (2-D) and `error_names`; and the
/// summary values the run's results hold (`scenario`, `robot`, `duration`, `samples`,
/// `final_q`, `final_v`, step counts, energy and residual monitors; for law `mpc` the
/// `mpc` object, for the contact plant `contact` and its events). Writes no file.
/// Invalid input or a failing run raises MomaError with the command line's message.
#[pyfunction]
fn simulate<'py>(py: Python<'py>, path: PathBuf) -> PyResult<Bound<'py, PyDict>> {
    let clock = std::time::Instant::now();
    let out = py.detach(|| run_scenario(&path)).map_err(err)?;
    let wall = clock.elapsed().as_secs_f64();
    let d = json_to_py(py, &Value::Object(out.doc))?.cast_into::<PyDict>()?;
    d.set_item("wall_time_s", wall)?;
    let n = out.t.len();
    d.set_item("t", PyArray1::from_vec(py, out.t))?;
    for (key, tab) in [("q", out.q), ("v", out.v), ("u", out.u)] {
        d.set_item(format!("{key}_names"), tab.names.clone())?;
        d.set_item(key, matrix(py, tab, n)?)?;
    }
    if let Some(e) = out.errors {
        d.set_item("error_names", e.names.clone())?;
        d.set_item("errors", matrix(py, e, n)?)?;
    }
    Ok(d)
}

/// Registers the function.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(simulate, m)?)?;
    Ok(())
}

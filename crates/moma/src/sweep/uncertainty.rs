//! The uncertainty study: one closed-loop `moma simulate` scenario with an
//! `[uncertainty]` table, run once per seed (the point's `seed` replaces the table's), on
//! the scenario's plant (rolling or contact). Per seed: did it succeed (the law's final
//! tracking error within `controller.goal_tolerance`, when given, and no tip), the
//! smallest ZMP margin and the first tip and slip, and what the seed drew. A point whose
//! scenario is invalid or whose run fails is a row with `success = false` and the
//! message in `reason`. [`summarize`] turns the table into the success rate, the smallest
//! margin and the counts of tips and slips, per combination of the other parameters.
//!
//! Tip and slip: on the rolling plant, from the scenario's `[stability]` replayed on the
//! perturbed plant (the ZMP margin reaching zero; a driven wheel's friction demand above
//! `stability.mu`); on the contact plant, the first contact to lose its load and the
//! first wheel to slide (after the settling time of `sim::contact_run`), and no ZMP
//! margin (its ZMP is not evaluated).

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::{
    Parameter, Table, Value, file_error, num, require_non_negative, require_numbers, require_seeds,
    resolve, study_section,
};
use crate::contact::PlantKind;
use crate::error::{Error, Result};
use crate::sim::stability_monitor::{first_crossing, first_slip};
use crate::sim::uncertainty::Dist;
use crate::sim_config::{Run, Scenario};

/// Result columns.
pub(super) const RESULTS: &[&str] = &[
    "success",
    "reason",
    "final_error_norm",
    "min_zmp_margin",
    "tipped",
    "tip_time",
    "tip_contact",
    "slipped",
    "slip_time",
    "payload_mass_drawn",
    "link_mass_scale_drawn",
    "mu_drawn",
];

const NAMES: &str = "seed, payload_mass";

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Spec {
    scenario: String,
}

#[derive(Clone, Copy)]
enum Slot {
    Seed,
    PayloadMass,
}

/// The prepared study: the scenario's text, checked once at load.
pub(super) struct UncertaintyStudy {
    path: PathBuf,
    text: String,
    slots: Vec<Slot>,
}

/// Per-worker workspace (a run builds its own state).
pub(super) struct Workspace;

/// Reads the scenario at `path` with the point's seed and payload mass.
fn scenario(path: &Path, text: &str, seed: u64, payload_mass: Option<f64>) -> Result<Scenario> {
    let mut sc: Scenario = crate::sim_config::schema::parse_scenario(text, path)?;
    sc.check_header(path)?;
    let Some(u) = sc.uncertainty.as_mut() else {
        return Err(Error::parse(
            path,
            "the scenario has no [uncertainty] table",
        ));
    };
    u.seed = seed;
    if let Some(m) = payload_mass {
        let Some(p) = u.payload.as_mut() else {
            return Err(Error::parse(
                path,
                "parameter payload_mass: the scenario's [uncertainty] has no payload",
            ));
        };
        p.mass = Dist::Fixed(m);
    }
    Ok(sc)
}

impl UncertaintyStudy {
    pub(super) fn new(
        path: &Path,
        dir: &Path,
        section: toml::Value,
        params: &[Parameter],
    ) -> Result<Self> {
        let spec: Spec = study_section(path, "uncertainty", section)?;
        let scenario_path = resolve(dir, &spec.scenario);
        let text = std::fs::read_to_string(&scenario_path).map_err(|source| Error::Io {
            path: scenario_path.clone(),
            source,
        })?;
        let mut slots = Vec::with_capacity(params.len());
        for p in params {
            slots.push(match p.name.as_str() {
                "seed" => Slot::Seed,
                "payload_mass" => Slot::PayloadMass,
                n => {
                    return Err(file_error(
                        path,
                        &format!("parameters.{n}"),
                        format!("unknown parameter of the uncertainty study (expected {NAMES})"),
                    ));
                }
            });
            require_numbers(path, p)?;
            require_non_negative(path, p, "")?;
            if p.name == "seed" {
                require_seeds(path, p)?;
            }
        }
        if !slots.iter().any(|s| matches!(s, Slot::Seed)) {
            return Err(file_error(
                path,
                "parameters.seed",
                "the uncertainty study runs the scenario once per seed: list them",
            ));
        }
        // The scenario is valid with its own seed (the same checks `moma simulate` makes).
        let sc = scenario(&scenario_path, &text, 0, None)?;
        if sc.controller.is_none() {
            return Err(file_error(
                path,
                "uncertainty.scenario",
                format!("{} has no [controller]", scenario_path.display()),
            ));
        }
        prepare_check(&sc, &scenario_path)?;
        Ok(Self {
            path: scenario_path,
            text,
            slots,
        })
    }

    pub(super) fn workspace(&self) -> Workspace {
        Workspace
    }

    pub(super) fn evaluate(
        &self,
        _ws: &mut Workspace,
        point: &[Value],
        row: &mut Vec<Value>,
    ) -> Result<()> {
        let (mut seed, mut payload) = (0, None);
        for (s, v) in self.slots.iter().zip(point) {
            match s {
                Slot::Seed => seed = num(v) as u64,
                Slot::PayloadMass => payload = Some(num(v)),
            }
        }
        let outcome = scenario(&self.path, &self.text, seed, payload)
            .map_err(|e| format!("invalid scenario: {e}"))
            .and_then(|sc| run_seed(&sc, &self.path).map_err(|e| format!("run failed: {e}")));
        match outcome {
            Ok(o) => o.push(row),
            Err(reason) => {
                row.push(Value::Bool(false));
                row.push(Value::Text(reason));
                row.extend(std::iter::repeat_n(Value::Missing, RESULTS.len() - 2));
            }
        }
        Ok(())
    }
}

/// Builds the scenario's run once (every check of `moma simulate`), without running it.
fn prepare_check(sc: &Scenario, path: &Path) -> Result<()> {
    match sc.plant {
        PlantKind::Contact => crate::sim_config::contact::prepare_contact(sc, path).map(|_| ()),
        PlantKind::Rolling => match crate::sim_config::prepare(sc, path)? {
            Run::Closed(_) => Ok(()),
            _ => Err(Error::parse(path, "not a closed-loop scenario")),
        },
    }
}

/// What one seed's run did.
struct Outcome {
    success: bool,
    reason: Option<String>,
    final_error_norm: f64,
    min_zmp_margin: Option<f64>,
    tip: Option<(f64, Option<String>)>,
    slip: Option<f64>,
    payload_mass: Option<f64>,
    mass_scale: f64,
    mu: Option<f64>,
}

impl Outcome {
    fn push(self, row: &mut Vec<Value>) {
        row.push(Value::Bool(self.success));
        row.push(self.reason.map_or(Value::Missing, Value::Text));
        row.push(Value::Float(self.final_error_norm));
        row.push(Value::opt(self.min_zmp_margin));
        row.push(Value::Bool(self.tip.is_some()));
        row.push(Value::opt(self.tip.as_ref().map(|t| t.0)));
        row.push(
            self.tip
                .and_then(|t| t.1)
                .map_or(Value::Missing, Value::Text),
        );
        row.push(Value::Bool(self.slip.is_some()));
        row.push(Value::opt(self.slip));
        row.push(Value::opt(self.payload_mass));
        row.push(Value::Float(self.mass_scale));
        row.push(Value::opt(self.mu));
    }
}

/// Runs one seed's scenario on its plant.
fn run_seed(sc: &Scenario, path: &Path) -> Result<Outcome> {
    let spec = sc
        .uncertainty
        .as_ref()
        .ok_or_else(|| Error::parse(path, "no [uncertainty]"))?;
    let draw = spec.draw();
    let tolerance = sc.controller.as_ref().and_then(|c| c.goal_tolerance);
    let (final_error_norm, min_zmp_margin, tip, slip, mu) = match sc.plant {
        PlantKind::Contact => {
            let mut run = crate::sim_config::contact::prepare_contact(sc, path)?;
            let res = run.run(&mut |_| {})?;
            let ne = res.error_names.len();
            let last = res.rows.last().map_or(&[][..], |r| &r[r.len() - ne..]);
            let err = last.iter().map(|x| x * x).sum::<f64>().sqrt();
            let tip = res.first_lift_off.map(|e| (e.t, Some(e.contact)));
            let slip = res.first_slip.map(|e| e.t);
            (err, None, tip, slip, Some(run.plant.params.mu))
        }
        PlantKind::Rolling => {
            let Run::Closed(mut cl) = crate::sim_config::prepare(sc, path)? else {
                return Err(Error::parse(path, "not a closed-loop scenario"));
            };
            let res = cl.run(&mut |_| {})?;
            let n = res.recorder.len();
            let err = if n == 0 || res.error_names.is_empty() {
                0.0
            } else {
                res.error_row(n - 1)
                    .iter()
                    .map(|x| x * x)
                    .sum::<f64>()
                    .sqrt()
            };
            let (margin, tip, slip) = match &sc.stability {
                None => (None, None, None),
                Some(st) => {
                    let mon = crate::sim_config::replay_scenario(st, sc, path, &res.recorder)?;
                    let tr = &mon.trace;
                    let margin = tr
                        .zmp_margin
                        .iter()
                        .map(|m| m.unwrap_or(f64::NEG_INFINITY))
                        .fold(None, |a: Option<f64>, m| Some(a.map_or(m, |a| a.min(m))));
                    let tip = first_crossing(&tr.times, &tr.zmp_margin, true).map(|c| {
                        (
                            c.time,
                            tr.critical_edge[c.sample].map(|e| mon.edge_label(e)),
                        )
                    });
                    (
                        margin.filter(|m| m.is_finite()),
                        tip,
                        first_slip(tr).map(|c| c.time),
                    )
                }
            };
            (err, margin, tip, slip, None)
        }
    };
    let mut reasons = Vec::new();
    if let Some((t, _)) = &tip {
        reasons.push(format!("tipped at t = {t:.4} s"));
    }
    if let Some(tol) = tolerance
        && (final_error_norm > tol || final_error_norm.is_nan())
    {
        reasons.push(format!(
            "final tracking error {final_error_norm:.3e} > goal_tolerance {tol:e}"
        ));
    }
    Ok(Outcome {
        success: reasons.is_empty(),
        reason: (!reasons.is_empty()).then(|| reasons.join("; ")),
        final_error_norm,
        min_zmp_margin,
        tip,
        slip,
        payload_mass: draw.perturbation.payload.as_ref().map(|p| p.mass),
        mass_scale: draw.perturbation.mass_scale,
        mu: mu.filter(|_| spec.mu.is_some()),
    })
}

/// The summary of an uncertainty study's rows that share the values of `group`.
#[derive(Clone, Debug, PartialEq, serde::Serialize)]
pub struct SeedSummary {
    /// The grouping parameters and their values (every parameter but `seed`).
    pub group: Vec<(String, String)>,
    /// Number of seeds.
    pub seeds: usize,
    /// Fraction of seeds with `success`.
    pub success_rate: f64,
    /// The smallest `min_zmp_margin` over the seeds (m), and its seed; `None` without
    /// any margin (a contact-plant scenario, or no `[stability]`).
    pub min_zmp_margin: Option<(f64, u64)>,
    /// Seeds that tipped.
    pub tipped: Vec<u64>,
    /// Seeds that slipped.
    pub slipped: Vec<u64>,
}

fn cell_f64(v: &Value) -> Option<f64> {
    match v {
        Value::Float(f) => Some(*f),
        Value::Int(i) => Some(*i as f64),
        Value::Text(s) => s.parse().ok(),
        _ => None,
    }
}

fn cell_bool(v: &Value) -> Option<bool> {
    match v {
        Value::Bool(b) => Some(*b),
        Value::Text(s) => s.parse().ok(),
        _ => None,
    }
}

/// Summarises the table of an uncertainty study, or of a mission study over seeds (as
/// run, or read back from its CSV): per combination of the parameters other than `seed`
/// (in the order they first appear), the success rate (`success`; a mission's
/// `reached`), the smallest ZMP margin with its seed, the seeds that tipped and those
/// that slipped.
///
/// # Errors
/// [`Error::InvalidInput`] naming the column if the table lacks one of the study's
/// columns or a cell is not of its type.
pub fn summarize(table: &Table) -> Result<Vec<SeedSummary>> {
    let col = |name: &str| {
        table.column(name).ok_or_else(|| {
            Error::invalid(
                name,
                "no such column: not the table of an uncertainty study or of a mission study \
                 over seeds",
            )
        })
    };
    let success = col("success").or_else(|_| col("reached"))?;
    let (seed, margin, tipped, slipped) = (
        col("seed")?,
        col("min_zmp_margin")?,
        col("tipped")?,
        col("slipped")?,
    );
    // the parameters sit between the index and the first result
    let first_result = success;
    let group_cols: Vec<usize> = (1..first_result).filter(|&c| c != seed).collect();
    let mut out: Vec<SeedSummary> = Vec::new();
    let mut successes: Vec<usize> = Vec::new();
    for row in &table.rows {
        let bad = |c: usize| Error::invalid(table.columns[c].clone(), format!("{:?}", row[c]));
        let s = cell_f64(&row[seed]).ok_or_else(|| bad(seed))? as u64;
        let group: Vec<(String, String)> = group_cols
            .iter()
            .map(|&c| (table.columns[c].clone(), row[c].to_text()))
            .collect();
        let k = match out.iter().position(|g| g.group == group) {
            Some(k) => k,
            None => {
                out.push(SeedSummary {
                    group,
                    seeds: 0,
                    success_rate: 0.0,
                    min_zmp_margin: None,
                    tipped: Vec::new(),
                    slipped: Vec::new(),
                });
                successes.push(0);
                out.len() - 1
            }
        };
        let g = &mut out[k];
        g.seeds += 1;
        if cell_bool(&row[success]).ok_or_else(|| bad(success))? {
            successes[k] += 1;
        }
        if let Some(m) = cell_f64(&row[margin])
            && g.min_zmp_margin.is_none_or(|(b, _)| m < b)
        {
            g.min_zmp_margin = Some((m, s));
        }
        if cell_bool(&row[tipped]) == Some(true) {
            g.tipped.push(s);
        }
        if cell_bool(&row[slipped]) == Some(true) {
            g.slipped.push(s);
        }
    }
    for (g, n) in out.iter_mut().zip(successes) {
        g.success_rate = n as f64 / g.seeds as f64;
    }
    Ok(out)
}

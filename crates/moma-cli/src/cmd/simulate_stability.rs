//! The outputs of the `[stability]` table of `moma simulate` scenarios (tip-over
//! measures, wheel–ground loads and slip along a wheeled URDF run): the summary section,
//! `stability.csv` and the plots. The table and its monitor are built by the library
//! (`moma::sim_config::stability`); schema and outputs in docs/simulate.md.

use moma::sim::stability_monitor::{
    Crossing, StabilityMonitor, StabilityTrace, first_crossing, first_slip,
};
use moma::sim_config::StabilitySpec;
use serde::Serialize;

use crate::svg_plots::{Series, line_chart};

/// A named ground contact.
#[derive(Debug, Serialize)]
struct Contact {
    name: String,
    position: [f64; 2],
}

/// An edge of the base-frame support polygon.
#[derive(Debug, Serialize, Clone)]
struct EdgeName {
    index: usize,
    from: String,
    to: String,
}

/// The extreme of a measure and when it happened.
#[derive(Debug, Serialize)]
struct Extreme {
    value: f64,
    time: f64,
}

/// First zero crossing of each measure.
#[derive(Debug, Serialize)]
struct Crossings {
    zmp_margin: Option<Crossing>,
    force_angle_min: Option<Crossing>,
    mhs_min: Option<Crossing>,
    slip: Option<Crossing>,
}

/// The `stability` section of `summary.json`.
#[derive(Debug, Serialize)]
pub struct StabilitySummary {
    ground_z: f64,
    mu: Option<f64>,
    bodies: String,
    contacts: Vec<Contact>,
    edges: Vec<EdgeName>,
    load_rule: Option<moma::stability::LoadRule>,
    load_rule_description: Option<&'static str>,
    lateral_split_rule: &'static str,
    first_crossing: Crossings,
    tip_edge: Option<EdgeName>,
    min_zmp_margin: Option<Extreme>,
    min_force_angle: Option<Extreme>,
    min_mhs: Option<Extreme>,
    max_slip_ratio: Option<Extreme>,
    tipped: bool,
    stopped_at_tip: Option<f64>,
    require_stable: bool,
}

/// The smallest defined value and its time.
fn minimum(times: &[f64], values: &[Option<f64>]) -> Option<Extreme> {
    times
        .iter()
        .zip(values)
        .filter_map(|(&t, v)| v.map(|v| (t, v)))
        .fold(None, |best: Option<Extreme>, (t, v)| match best {
            Some(b) if b.value <= v => Some(b),
            _ => Some(Extreme { value: v, time: t }),
        })
}

fn edge_name(mon: &StabilityMonitor, i: usize) -> EdgeName {
    let e = mon.edges()[i];
    EdgeName {
        index: i,
        from: mon.contact_names()[e.from].clone(),
        to: mon.contact_names()[e.to].clone(),
    }
}

/// The summary section of a finished run.
pub fn summary(
    spec: &StabilitySpec,
    mon: &StabilityMonitor,
    stopped_at: Option<f64>,
) -> StabilitySummary {
    let tr = &mon.trace;
    let zmp = first_crossing(&tr.times, &tr.zmp_margin, true);
    let max_slip = if mon.settings().mu.is_some() {
        let ratios: Vec<Option<f64>> = tr
            .wheels
            .iter()
            .map(|w| match (w[0].slip_ratio, w[1].slip_ratio) {
                (Some(a), Some(b)) => Some(-a.max(b)),
                _ => None,
            })
            .collect();
        minimum(&tr.times, &ratios).map(|e| Extreme {
            value: -e.value,
            time: e.time,
        })
    } else {
        None
    };
    StabilitySummary {
        ground_z: mon.ground_z(),
        mu: mon.settings().mu,
        bodies: spec.bodies.clone().unwrap_or_else(|| "all".into()),
        contacts: mon
            .contact_names()
            .iter()
            .zip(mon.contacts_base())
            .map(|(n, p)| Contact {
                name: n.clone(),
                position: [p.x, p.y],
            })
            .collect(),
        edges: (0..mon.edges().len()).map(|i| edge_name(mon, i)).collect(),
        load_rule: mon.load_rule(),
        load_rule_description: mon.load_rule().map(|r| r.describe()),
        lateral_split_rule: "the axle's lateral force (-lambda_0) is shared by the two driven \
                             wheels in proportion to their normal loads (negative loads as zero)",
        first_crossing: Crossings {
            zmp_margin: zmp,
            force_angle_min: first_crossing(&tr.times, &tr.force_angle_min, false),
            mhs_min: first_crossing(&tr.times, &tr.mhs_min, false),
            slip: first_slip(tr),
        },
        tip_edge: zmp
            .and_then(|c| tr.critical_edge[c.sample])
            .map(|i| edge_name(mon, i)),
        min_zmp_margin: minimum(&tr.times, &tr.zmp_margin),
        min_force_angle: minimum(&tr.times, &tr.force_angle_min),
        min_mhs: minimum(&tr.times, &tr.mhs_min),
        max_slip_ratio: max_slip,
        tipped: mon.tipped(),
        stopped_at_tip: stopped_at,
        require_stable: spec.require_stable,
    }
}

/// The exit-status-3 message of a `require_stable` scenario that tipped.
pub fn tip_message(mon: &StabilityMonitor) -> String {
    let tr = &mon.trace;
    match first_crossing(&tr.times, &tr.zmp_margin, true) {
        Some(c) => format!(
            "the scenario requires the robot to stay stable (stability.require_stable), but \
             the ZMP margin reached zero at t = {:.4} s (sample {} at t = {} s)",
            c.time, c.sample, c.sample_time
        ),
        None => "the scenario requires the robot to stay stable, but it tipped over".into(),
    }
}

/// A CSV-safe column name.
fn column_name(s: &str) -> String {
    s.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

fn opt(x: Option<f64>) -> String {
    x.map_or_else(String::new, |v| format!("{v:e}"))
}

/// `stability.csv`: one row per sample; an undefined value is an empty field.
pub fn csv(mon: &StabilityMonitor) -> String {
    let tr: &StabilityTrace = &mon.trace;
    let names: Vec<String> = mon.contact_names().iter().map(|n| column_name(n)).collect();
    let mut cols: Vec<String> = [
        "t [s]",
        "zmp_x [m]",
        "zmp_y [m]",
        "zmp_margin [m]",
        "critical_edge",
        "force_angle_min [rad]",
        "force_angle_alpha [N rad]",
        "mhs_min [1/s^2]",
    ]
    .iter()
    .map(|s| (*s).to_string())
    .collect();
    cols.extend(names.iter().map(|n| format!("normal_load_{n} [N]")));
    let with_mu = !tr.wheels.is_empty();
    if with_mu {
        for n in &names[..2] {
            cols.push(format!("{n}_lateral [N]"));
            cols.push(format!("{n}_longitudinal [N]"));
            cols.push(format!("{n}_slip_ratio"));
        }
    }
    let nc = names.len();
    let mut out = cols.join(",");
    out.push('\n');
    for i in 0..tr.times.len() {
        let mut row = vec![
            format!("{:e}", tr.times[i]),
            opt(tr.zmp[i].map(|p| p[0])),
            opt(tr.zmp[i].map(|p| p[1])),
            opt(tr.zmp_margin[i]),
            tr.critical_edge[i].map_or_else(String::new, |e| e.to_string()),
            opt(tr.force_angle_min[i]),
            opt(tr.force_angle_alpha[i]),
            opt(tr.mhs_min[i]),
        ];
        row.extend(
            tr.normal_loads[i * nc..(i + 1) * nc]
                .iter()
                .map(|x| format!("{x:e}")),
        );
        if with_mu {
            for w in &tr.wheels[i] {
                row.push(format!("{:e}", w.lateral));
                row.push(format!("{:e}", w.longitudinal));
                row.push(opt(w.slip_ratio));
            }
        }
        out.push_str(&row.join(","));
        out.push('\n');
    }
    out
}

fn nan(v: &[Option<f64>]) -> Vec<f64> {
    // The plots leave undefined samples out (a gap in the line); no NaN is written.
    v.iter().map(|x| x.unwrap_or(f64::NAN)).collect()
}

/// The stability plots: the ZMP margin, the Force-Angle and Moment-Height minima, the
/// normal loads, and (with μ) the slip ratios.
pub fn plots(mon: &StabilityMonitor, files: &mut Vec<(String, Vec<u8>)>) {
    let tr = &mon.trace;
    let t = &tr.times;
    let zero = vec![0.0; t.len()];
    let s = |name: &'static str, y: Vec<f64>| Series { name, x: t, y };
    let mut push = |file: &str, title: &str, ylabel: &str, series: &[Series<'_>]| {
        files.push((
            file.to_string(),
            line_chart(title, "t [s]", ylabel, series).into_bytes(),
        ));
    };
    push(
        "stability_zmp.svg",
        "ZMP margin (distance to the critical edge, positive inside the support)",
        "margin [m]",
        &[
            s("ZMP margin", nan(&tr.zmp_margin)),
            s("zero", zero.clone()),
        ],
    );
    push(
        "stability_force_angle.svg",
        "Force-Angle minimum θ (positive = stable)",
        "θ min [rad]",
        &[
            s("Force-Angle θ min", nan(&tr.force_angle_min)),
            s("zero", zero.clone()),
        ],
    );
    push(
        "stability_mhs.svg",
        "Moment-Height minimum M/I (positive = stable)",
        "M/I min [1/s²]",
        &[
            s("Moment-Height min", nan(&tr.mhs_min)),
            s("zero", zero.clone()),
        ],
    );
    let nc = mon.contact_names().len();
    let loads: Vec<Series> = mon
        .contact_names()
        .iter()
        .enumerate()
        .map(|(j, name)| Series {
            name,
            x: t,
            y: (0..t.len()).map(|i| tr.normal_loads[i * nc + j]).collect(),
        })
        .collect();
    let rule = mon
        .load_rule()
        .map_or("", moma::stability::LoadRule::describe);
    files.push((
        "wheel_loads.svg".to_string(),
        line_chart(
            &format!("Normal ground loads ({rule})"),
            "t [s]",
            "load [N]",
            &loads,
        )
        .into_bytes(),
    ));
    if !tr.wheels.is_empty() {
        let names = mon.contact_names();
        let ratio = |k: usize| -> Vec<f64> {
            tr.wheels
                .iter()
                .map(|w| w[k].slip_ratio.unwrap_or(f64::NAN))
                .collect()
        };
        let series = [
            Series {
                name: &names[0],
                x: t,
                y: ratio(0),
            },
            Series {
                name: &names[1],
                x: t,
                y: ratio(1),
            },
            Series {
                name: "slip limit",
                x: t,
                y: vec![1.0; t.len()],
            },
        ];
        files.push((
            "slip.svg".to_string(),
            line_chart(
                "Driven-wheel slip ratio |F_tangential| / (μ N) (above 1: the wheel slides)",
                "t [s]",
                "slip ratio",
                &series,
            )
            .into_bytes(),
        ));
    }
}

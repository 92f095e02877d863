//! What `moma sweep` adds for a lift-off study: the figure of the simulated against the
//! predicted lift-off acceleration (one marker per point, one colour per payload, the line
//! y = x) and the largest relative deviation of the simulated limit from the prediction.

use anyhow::{Result, anyhow};
use moma::sweep::{Table, Value};

use crate::svg_plots::{Series, identity_scatter_chart};

fn number(v: &Value) -> Option<f64> {
    match v {
        Value::Float(x) => Some(*x),
        Value::Int(i) => Some(*i as f64),
        Value::Text(s) => s.parse().ok(),
        _ => None,
    }
}

/// The column `name` of `table` as numbers.
fn column(table: &Table, name: &str) -> Result<Vec<f64>> {
    let c = table
        .column(name)
        .ok_or_else(|| anyhow!("the lift-off table has no column '{name}'"))?;
    table
        .rows
        .iter()
        .map(|r| {
            number(&r[c])
                .ok_or_else(|| anyhow!("column '{name}': '{}' is not a number", r[c].to_text()))
        })
        .collect()
}

/// The largest relative deviation `simulated / predicted − 1` (by magnitude) and the
/// index of its point; `None` for an empty table.
pub fn largest_deviation(table: &Table) -> Result<Option<(f64, i64)>> {
    let ratio = column(table, "ratio")?;
    let index = column(table, "index")?;
    Ok(ratio
        .iter()
        .zip(&index)
        .map(|(r, i)| (r - 1.0, *i as i64))
        .max_by(|a, b| a.0.abs().total_cmp(&b.0.abs())))
}

/// The SVG figure: simulated against predicted limit, a series per payload value (one
/// series when the sweep has no `payload` parameter), and y = x.
pub fn figure(table: &Table, title: &str) -> Result<String> {
    let predicted = column(table, "predicted_limit")?;
    let simulated = column(table, "simulated_limit")?;
    let payload = match table.column("payload") {
        Some(_) => column(table, "payload")?,
        None => vec![0.0; predicted.len()],
    };
    let mut groups: Vec<f64> = Vec::new();
    for p in &payload {
        if !groups.contains(p) {
            groups.push(*p);
        }
    }
    groups.sort_by(f64::total_cmp);
    let split: Vec<(String, Vec<f64>, Vec<f64>)> = groups
        .iter()
        .map(|g| {
            let (x, y) = predicted
                .iter()
                .zip(&simulated)
                .zip(&payload)
                .filter(|(_, p)| *p == g)
                .map(|((x, y), _)| (*x, *y))
                .unzip();
            let name = if table.column("payload").is_some() {
                format!("payload {g} kg")
            } else {
                "postures".to_string()
            };
            (name, x, y)
        })
        .collect();
    let series: Vec<Series<'_>> = split
        .iter()
        .map(|(name, x, y)| Series {
            name,
            x,
            y: y.clone(),
        })
        .collect();
    Ok(identity_scatter_chart(
        title,
        "predicted tip-over limit [m/s²]",
        "simulated limit: first lift or tip-over [m/s²]",
        &series,
    ))
}

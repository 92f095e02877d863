//! `moma sweep SWEEP.toml`: a grid or seeded random sweep of a study (stability,
//! placement, mission, uncertainty, lift-off) on all cores (or one shard of it), into one
//! CSV table, with the uncertainty study's summary and the lift-off study's figure;
//! `moma sweep merge` joins shard tables. The schema and the sharding rule are in
//! `docs/sweep.md`.

use crate::output::write_atomic;
use anyhow::{Context, Result, anyhow, bail};
use moma::sweep::{Sweep, Table, merge};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `moma sweep`.
#[derive(clap::Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct Args {
    #[command(subcommand)]
    pub merge: Option<MergeCommand>,
    /// Sweep file (TOML; schema in docs/sweep.md).
    pub sweep: Option<PathBuf>,
    /// Output table (CSV), written atomically.
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    /// Run only shard K of N (1 <= K <= N): the points whose index i has i mod N = K - 1.
    #[arg(long)]
    pub shard: Option<String>,
    /// Worker threads (default: all cores).
    #[arg(long, default_value_t = 0)]
    pub threads: usize,
    /// No progress bar and no summary line.
    #[arg(long, short)]
    pub quiet: bool,
    /// Uncertainty study, or mission study over seeds: also write the per-group summary
    /// (success rate, smallest ZMP margin, seeds that tipped or slipped) as JSON,
    /// atomically.
    #[arg(long)]
    pub summary: Option<PathBuf>,
    /// Lift-off study: also draw the simulated against the predicted lift-off
    /// acceleration, with the line y = x (SVG), atomically.
    #[arg(long)]
    pub figure: Option<PathBuf>,
}

/// `moma sweep merge`.
#[derive(clap::Subcommand)]
pub enum MergeCommand {
    /// Join shard tables (equal headers, disjoint indices covering 0..n) into one, sorted
    /// by index.
    Merge {
        /// Merged table (CSV), written atomically.
        out: PathBuf,
        /// Shard tables (CSV).
        #[arg(required = true)]
        shards: Vec<PathBuf>,
    },
}

/// Parses `--shard K/N`.
fn parse_shard(text: &str) -> Result<(u64, u64)> {
    let (k, n) = text
        .split_once('/')
        .ok_or_else(|| anyhow!("--shard: expected K/N (e.g. 2/8), got '{text}'"))?;
    let parse = |s: &str, what: &str| -> Result<u64> {
        s.trim()
            .parse::<u64>()
            .map_err(|_| anyhow!("--shard: {what} '{s}' is not a positive integer"))
    };
    let (k, n) = (parse(k, "K")?, parse(n, "N")?);
    if n == 0 || k == 0 || k > n {
        bail!("--shard: needs 1 <= K <= N, got {k}/{n}");
    }
    Ok((k, n))
}

fn progress_bar(len: u64, quiet: bool) -> Option<indicatif::ProgressBar> {
    if quiet || !std::io::stderr().is_terminal() {
        return None;
    }
    let pb = indicatif::ProgressBar::new(len);
    pb.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} sweeping [{bar:40}] {pos}/{len} points  {elapsed_precise} (eta {eta})",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar())
        .progress_chars("=> "),
    );
    Some(pb)
}

fn run_merge(out: PathBuf, shards: Vec<PathBuf>) -> Result<()> {
    if shards.len() > 1_000_000 {
        bail!("merge: more than 1000000 shard files");
    }
    let mut tables = Vec::with_capacity(shards.len());
    for p in &shards {
        tables.push(Table::read_csv(p)?);
    }
    let names: Vec<String> = shards.iter().map(|p| p.display().to_string()).collect();
    let merged = merge(tables, &names)?;
    write_atomic(&out, merged.to_csv().as_bytes())?;
    outln!(
        "wrote {}: {} rows from {} shard tables",
        out.display(),
        merged.rows.len(),
        shards.len()
    );
    Ok(())
}

/// Runs `moma sweep`.
pub fn run(args: Args) -> Result<()> {
    if let Some(MergeCommand::Merge { out, shards }) = args.merge {
        return run_merge(out, shards);
    }
    let Some(path) = args.sweep else {
        bail!("give a sweep file (moma sweep SWEEP.toml -o OUT.csv) or use moma sweep merge");
    };
    let Some(output) = args.output else {
        bail!("--output: give the CSV file to write (moma sweep SWEEP.toml -o OUT.csv)");
    };
    let (k, n) = match &args.shard {
        Some(s) => parse_shard(s)?,
        None => (1, 1),
    };
    let sweep = Sweep::from_file(&path)?;
    if args.summary.is_some() && !sweep.has_summary() {
        bail!(
            "--summary: only the uncertainty study and a mission study over seeds have a \
             summary ({} is a {} study{})",
            path.display(),
            sweep.study(),
            if sweep.study() == "mission" {
                " without a seed parameter"
            } else {
                ""
            }
        );
    }
    if args.figure.is_some() && sweep.study() != "lift_off" {
        bail!(
            "--figure: only the lift_off study has a figure ({} is a {} study)",
            path.display(),
            sweep.study()
        );
    }
    let indices =
        moma::sweep::shard_indices(sweep.len(), k, n).map_err(|e| anyhow!("--shard: {e}"))?;
    let pb = progress_bar(indices.len() as u64, args.quiet);
    let start = Instant::now();
    let table = sweep
        .run_with_progress(&indices, args.threads, &|d| {
            if let Some(pb) = &pb {
                pb.inc(d);
            }
        })
        .map_err(|e| {
            // a point's error in the sweep file names it already (`lift_off.joint_gains`)
            let file = path.display().to_string();
            if e.to_string().contains(&file) {
                anyhow::Error::new(e)
            } else {
                anyhow::Error::new(e).context(file)
            }
        })?;
    let secs = start.elapsed().as_secs_f64();
    if let Some(pb) = &pb {
        pb.finish_and_clear();
    }
    // Everything is computed before anything is written.
    let summary = if sweep.has_summary() {
        Some(moma::sweep::summarize(&table)?)
    } else {
        None
    };
    let summary_json = match (&args.summary, &summary) {
        (Some(_), Some(s)) => {
            let mut j = serde_json::to_string_pretty(s).context("serialising the summary")?;
            j.push('\n');
            Some(j)
        }
        _ => None,
    };
    let deviation = if sweep.study() == "lift_off" {
        super::sweep_lift_off::largest_deviation(&table)?
    } else {
        None
    };
    let figure = match &args.figure {
        Some(_) => Some(super::sweep_lift_off::figure(
            &table,
            &format!(
                "Tip-over: simulated vs predicted limit\n{}",
                path.file_name()
                    .map_or(String::new(), |f| f.to_string_lossy().into_owned())
            ),
        )?),
        None => None,
    };
    write_atomic(&output, table.to_csv().as_bytes())?;
    if let (Some(p), Some(j)) = (&args.summary, &summary_json) {
        write_atomic(p, j.as_bytes())?;
    }
    if let (Some(p), Some(svg)) = (&args.figure, &figure) {
        write_atomic(p, svg.as_bytes())?;
    }
    if let (false, Some((dev, index))) = (args.quiet, deviation) {
        outln!(
            "largest deviation of the simulated lift-off from the predicted limit: {:+.2} % (point {index})",
            100.0 * dev
        );
    }
    if let (false, Some(groups)) = (args.quiet, &summary) {
        for g in groups {
            let group: Vec<String> = g.group.iter().map(|(k, v)| format!("{k} = {v}")).collect();
            outln!(
                "{}{} seeds: success rate {:.3}, smallest ZMP margin {}, tipped {}, slipped {}",
                if group.is_empty() {
                    String::new()
                } else {
                    format!("{}: ", group.join(", "))
                },
                g.seeds,
                g.success_rate,
                g.min_zmp_margin
                    .map_or("-".to_string(), |(m, s)| format!("{m:.4} m (seed {s})")),
                g.tipped.len(),
                g.slipped.len()
            );
        }
    }
    if !args.quiet {
        outln!(
            "wrote {}: {} of {} points (shard {k}/{n}, {} study) in {secs:.3} s",
            output.display(),
            table.rows.len(),
            sweep.len(),
            sweep.study()
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::parse_shard;

    #[test]
    fn shard_option() {
        assert_eq!(parse_shard("2/8").unwrap(), (2, 8));
        for bad in ["0/3", "4/3", "1/0", "a/2", "3", "-1/2"] {
            assert!(parse_shard(bad).is_err(), "{bad}");
        }
    }
}

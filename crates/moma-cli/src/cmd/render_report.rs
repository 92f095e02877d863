//! `moma render-report` (hidden from `--help`): renders a mission's `report.html` and
//! SVG figures from a `MissionReport` saved as JSON. It exists so that the report can be
//! checked on its own (the browser test feeds it a synthetic mission) and re-rendered
//! without re-running a mission; `moma mission` renders the same page from its run.

use crate::report::{MissionReport, render_html, render_svgs};
use anyhow::{Context, Result, bail};
use std::path::PathBuf;

/// Largest input file read, bytes (a long mission's report is a few tens of MB).
const MAX_INPUT_BYTES: u64 = 512 << 20;

/// Arguments of `moma render-report`.
#[derive(clap::Args)]
pub struct Args {
    /// The mission report as JSON (the fields of `MissionReport`, see docs/report.md).
    pub input: PathBuf,
    /// Output directory: report.html, the SVG figures and summary.json (replaced as a
    /// whole on a rerun).
    #[arg(short, long)]
    pub output: PathBuf,
}

/// Reads, checks and renders; writes the directory all or nothing.
pub fn run(a: Args) -> Result<()> {
    let path = &a.input;
    let len = std::fs::metadata(path)
        .with_context(|| format!("{}: cannot read the mission report", path.display()))?
        .len();
    if len > MAX_INPUT_BYTES {
        bail!(
            "{}: {len} bytes is more than the {MAX_INPUT_BYTES} a mission report may have",
            path.display()
        );
    }
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read the mission report", path.display()))?;
    let report: MissionReport = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a mission report", path.display()))?;
    if let Err(e) = report.check() {
        bail!("{}: {e}", path.display());
    }
    let mut files = vec![("report.html".to_string(), render_html(&report).into_bytes())];
    for (name, svg) in render_svgs(&report) {
        files.push((name, svg.into_bytes()));
    }
    let mut summary = serde_json::to_string_pretty(&report.summary)?;
    summary.push('\n');
    files.push(("summary.json".to_string(), summary.into_bytes()));
    crate::output::write_dir(&a.output, &files)?;
    outln!(
        "wrote {} ({} files: report.html, {} SVG figures, summary.json)",
        a.output.display(),
        files.len(),
        files.len() - 2
    );
    Ok(())
}

//! `moma render-report` (hidden from `--help`): renders a mission's `report.html` and
//! SVG figures from a `MissionReport` saved as JSON. It exists so that the report can be
//! checked on its own (the browser test feeds it a synthetic mission) and re-rendered
//! without re-running a mission; `moma mission` renders the same page from its run.
//! With `--robot` the 3-D view shows that robot instead: in one posture, its planar base
//! (if any) following the report's executed path, with an optional MoveIt scene.

use super::common::{load_model, parse_root, read_states};
use crate::report::{
    MAX_FRAMES, MissionReport, RobotShapes, render_html, render_svgs, scene_shapes,
};
use anyhow::{Context, Result, bail};
use moma::collision::{SceneOptions, read_scene};
use moma::multibody::{FrameKind, RootJoint};
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
    /// Draw this robot (URDF) in the 3-D view, replacing the report's own.
    #[arg(long)]
    pub robot: Option<PathBuf>,
    /// Its root joint: planar (the base follows the report's x, y, θ) or fixed.
    #[arg(long, value_parser = parse_root, default_value = "planar", requires = "robot")]
    pub root: RootJoint,
    /// Folder against which `package://PKG/...` mesh URIs resolve; repeatable.
    #[arg(long = "package-dir", requires = "robot")]
    pub package_dirs: Vec<PathBuf>,
    /// States file whose first state's `q` (full model order) is the posture; default:
    /// the model's neutral configuration.
    #[arg(long, requires = "robot")]
    pub posture: Option<PathBuf>,
    /// MoveIt planning-scene YAML drawn in the 3-D view (poses in `world`, or in the root
    /// link with a fixed root).
    #[arg(long, requires = "robot")]
    pub scene: Option<PathBuf>,
}

/// The report's 3-D view replaced by `--robot` in its posture.
fn robot_view(a: &Args, report: &mut MissionReport) -> Result<()> {
    let Some(urdf) = &a.robot else {
        return Ok(());
    };
    let model = load_model(urdf, a.root)?;
    let mut q = match &a.posture {
        Some(p) => {
            read_states(p, &["q"])?
                .into_iter()
                .next()
                .with_context(|| format!("{}: no state", p.display()))?
                .q
        }
        None => moma::multibody::neutral(&model).as_slice().to_vec(),
    };
    if q.len() != model.nq {
        bail!(
            "{}: q has {} values, the model's nq is {}",
            a.posture.as_ref().map_or(urdf, |p| p).display(),
            q.len(),
            model.nq
        );
    }
    let s = &report.samples;
    let (t, qs): (Vec<f64>, Vec<Vec<f64>>) = if a.root == RootJoint::Planar && !s.t.is_empty() {
        s.t.iter()
            .enumerate()
            .map(|(i, &t)| {
                q[..3].copy_from_slice(&[s.x[i], s.y[i], s.theta[i]]);
                (t, q.clone())
            })
            .unzip()
    } else {
        let t1 = s.t.last().copied().unwrap_or(0.0);
        (
            vec![s.t.first().copied().unwrap_or(0.0), t1],
            vec![q.clone(), q],
        )
    };
    let scene = match &a.scene {
        Some(path) => {
            let mut world_frames = vec!["world".to_string()];
            if a.root == RootJoint::Fixed
                && let Some(f) = model.frames.iter().find(|f| f.kind == FrameKind::Body)
            {
                world_frames.push(f.name.clone());
            }
            let opts = SceneOptions {
                world_frames,
                package_dirs: a.package_dirs.clone(),
            };
            scene_shapes(&read_scene(path, &opts)?)
        }
        None => Vec::new(),
    };
    let shapes = RobotShapes::from_urdf(urdf, &model, &a.package_dirs)?;
    report.view3d = Some(shapes.view(&model, &t, &qs, MAX_FRAMES, scene)?);
    Ok(())
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
    let mut report: MissionReport = serde_json::from_str(&text)
        .with_context(|| format!("{}: not a mission report", path.display()))?;
    if let Err(e) = report.check() {
        bail!("{}: {e}", path.display());
    }
    robot_view(&a, &mut report)?;
    if let Err(e) = report.check() {
        bail!("{}: {e}", a.robot.as_ref().map_or(path, |p| p).display());
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

//! `moma inspect ROBOT.urdf [--root fixed|planar|free-flyer] [--json]`: a robot model's
//! structure (nq, nv, total mass, joints, frames). Schema: `docs/cli.md`.

use super::common::{load_model, parse_root};
use anyhow::Result;
use moma::multibody::{Model, RootJoint};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Arguments of `moma inspect`.
#[derive(clap::Args)]
pub struct Args {
    /// The robot description (URDF).
    pub urdf: PathBuf,
    /// Root joint: fixed, planar (mobile base, q = [x, y, θ]) or free-flyer.
    #[arg(long, default_value = "fixed", value_parser = parse_root)]
    pub root: RootJoint,
    /// Print JSON instead of a table.
    #[arg(long)]
    pub json: bool,
}

/// One joint in the `inspect` output.
#[derive(Serialize)]
pub(crate) struct JointInfo {
    name: String,
    #[serde(rename = "type")]
    jtype: String,
    idx_q: usize,
    nq: usize,
    idx_v: usize,
    nv: usize,
    parent: String,
    lower: Vec<Option<f64>>,
    upper: Vec<Option<f64>>,
    velocity_limit: Vec<Option<f64>>,
    effort_limit: Vec<Option<f64>>,
}

/// One frame in the `inspect` output.
#[derive(Serialize)]
pub(crate) struct FrameInfo {
    name: String,
    kind: &'static str,
    parent_joint: String,
}

/// The `inspect` output.
#[derive(Serialize)]
pub(crate) struct Inspect {
    robot: String,
    source: String,
    root: String,
    nq: usize,
    nv: usize,
    njoints: usize,
    nframes: usize,
    total_mass: f64,
    gravity: [f64; 3],
    last_link: String,
    joints: Vec<JointInfo>,
    frames: Vec<FrameInfo>,
}

fn finite(x: f64) -> Option<f64> {
    x.is_finite().then_some(x)
}

pub(crate) fn describe(model: &Model, source: &Path) -> Inspect {
    let joints = (1..model.njoints)
        .map(|i| {
            let (iq, nq, iv, nv) = (model.idx_q[i], model.nqs[i], model.idx_v[i], model.nvs[i]);
            JointInfo {
                name: model.names[i].clone(),
                jtype: model.joint_types[i].name().to_string(),
                idx_q: iq,
                nq,
                idx_v: iv,
                nv,
                parent: model.names[model.parents[i].0].clone(),
                lower: (iq..iq + nq)
                    .map(|k| finite(model.lower_position_limit[k]))
                    .collect(),
                upper: (iq..iq + nq)
                    .map(|k| finite(model.upper_position_limit[k]))
                    .collect(),
                velocity_limit: (iv..iv + nv)
                    .map(|k| finite(model.velocity_limit[k]))
                    .collect(),
                effort_limit: (iv..iv + nv)
                    .map(|k| finite(model.effort_limit[k]))
                    .collect(),
            }
        })
        .collect();
    let frames = model
        .frames
        .iter()
        .map(|f| FrameInfo {
            name: f.name.clone(),
            kind: f.kind.name(),
            parent_joint: model.names[f.parent_joint.0].clone(),
        })
        .collect();
    Inspect {
        robot: model.name.clone(),
        source: source.display().to_string(),
        root: model.root.to_string(),
        nq: model.nq,
        nv: model.nv,
        njoints: model.njoints,
        nframes: model.nframes(),
        total_mass: model.total_mass(),
        gravity: [model.gravity.x, model.gravity.y, model.gravity.z],
        last_link: model.frames[model.last_link_frame().0].name.clone(),
        joints,
        frames,
    }
}

fn fmt_lim(v: &[Option<f64>]) -> String {
    v.iter()
        .map(|x| x.map_or("-".to_string(), |y| format!("{y:.4}")))
        .collect::<Vec<_>>()
        .join(",")
}

/// Runs `moma inspect`.
pub fn run(args: Args) -> Result<()> {
    let model = load_model(&args.urdf, args.root)?;
    let info = describe(&model, &args.urdf);
    if args.json {
        return crate::output::print_json(&info);
    }
    println!("robot      {} ({})", info.robot, info.source);
    println!("root       {}", info.root);
    println!("nq, nv     {}, {}", info.nq, info.nv);
    println!("total mass {:.6} kg (moving bodies)", info.total_mass);
    println!("last link  {}", info.last_link);
    println!("joints ({}):", info.joints.len());
    println!(
        "  {:<28} {:<20} {:>5} {:>3} {:>5} {:>3}  {:<24} lower / upper",
        "name", "type", "idx_q", "nq", "idx_v", "nv", "parent"
    );
    for j in &info.joints {
        println!(
            "  {:<28} {:<20} {:>5} {:>3} {:>5} {:>3}  {:<24} {} / {}",
            j.name,
            j.jtype,
            j.idx_q,
            j.nq,
            j.idx_v,
            j.nv,
            j.parent,
            fmt_lim(&j.lower),
            fmt_lim(&j.upper)
        );
    }
    println!("frames ({}):", info.frames.len());
    for f in &info.frames {
        println!(
            "  {:<32} {:<12} on joint {}",
            f.name, f.kind, f.parent_joint
        );
    }
    Ok(())
}

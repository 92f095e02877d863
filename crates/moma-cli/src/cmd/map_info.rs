//! `moma map-info`: size, resolution, origin and occupied/free/unknown counts of a map.
//!
//! A bare image (PGM/PNG) is read with the legacy `map_server <image> <resolution>`
//! defaults: resolution 0.05 m (unless `--resolution`), origin (0, 0, 0), negate 0,
//! occupied_thresh 0.65, free_thresh 0.196, mode trinary.

use crate::output::print_json;
use anyhow::Result;
use moma::planning::{MapKind, load_map};
use std::path::PathBuf;

/// Arguments of `moma map-info`.
#[derive(clap::Args)]
pub struct Args {
    /// The map: ROS YAML, Moving AI `.map`, or a bare PGM/PNG image.
    pub map: PathBuf,
    /// Resolution (m/cell) for a bare image (default 0.05).
    #[arg(long)]
    pub resolution: Option<f64>,
    /// Print JSON instead of text.
    #[arg(long)]
    pub json: bool,
}

/// The printed summary (`--json`).
#[derive(serde::Serialize)]
struct Info {
    file: String,
    format: &'static str,
    width: usize,
    height: usize,
    resolution: f64,
    origin: [f64; 3],
    occupied: usize,
    free: usize,
    unknown: usize,
    intermediate: usize,
    #[serde(skip_serializing_if = "Option::is_none")]
    ros: Option<moma::planning::RosMapMeta>,
}

/// Runs the subcommand.
pub fn run(args: Args) -> Result<()> {
    let m = load_map(&args.map, args.resolution)?;
    let c = m.grid.counts();
    let format = match (m.grid.kind, args.map.extension().and_then(|e| e.to_str())) {
        (MapKind::MovingAi, _) => "movingai",
        (_, Some("yaml" | "yml")) => "ros_yaml",
        _ => "ros_image",
    };
    let info = Info {
        file: args.map.display().to_string(),
        format,
        width: m.grid.width,
        height: m.grid.height,
        resolution: m.grid.resolution,
        origin: m.grid.origin,
        occupied: c.occupied,
        free: c.free,
        unknown: c.unknown,
        intermediate: c.intermediate,
        ros: m.meta,
    };
    if args.json {
        return print_json(&info);
    }
    outln!("map:        {} ({})", info.file, info.format);
    outln!("size:       {} x {} cells", info.width, info.height);
    outln!("resolution: {} m/cell", info.resolution);
    outln!(
        "origin:     [{}, {}, {}]",
        info.origin[0],
        info.origin[1],
        info.origin[2]
    );
    if let Some(r) = &info.ros {
        outln!(
            "thresholds: occupied > {}, free < {}, negate {}, mode {:?}",
            r.occupied_thresh,
            r.free_thresh,
            r.negate as u8,
            r.mode
        );
    }
    outln!("occupied:   {}", info.occupied);
    outln!("free:       {}", info.free);
    outln!("unknown:    {}", info.unknown);
    if info.intermediate > 0 {
        outln!("intermediate: {}", info.intermediate);
    }
    Ok(())
}

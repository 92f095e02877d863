//! `moma stability-map`: a polar plot of the tip-over acceleration limits of a posture
//! at rest, and a heat map of the ZMP margin over two arm joints while the platform
//! accelerates at a given rate (the whole robot translating, joints held).

use super::stability::{SupportArgs, setup};
use crate::output::write_all_atomic;
use crate::svg_stability::{MarginMap, margin_map, polar};
use anyhow::{Result, anyhow, bail};
use moma::kinematics::check_state;
use moma::multibody::{Data, Model};
use moma::stability::{ExternalLoads, StabilityData, StabilityModel, acceleration_limit, evaluate};
use nalgebra::{DVector, Vector3};
use serde::Serialize;
use std::path::{Path, PathBuf};

const MAX_GRID: usize = 400;
const MAX_DIRECTIONS: usize = 3600;

/// Arguments of `moma stability-map`.
#[derive(clap::Args)]
pub struct Args {
    /// Robot model (URDF).
    pub robot: PathBuf,
    /// Root joint: planar (mobile base), fixed or free-flyer.
    #[arg(long, default_value = "planar")]
    pub root: String,
    #[command(flatten)]
    pub support: SupportArgs,
    /// The posture q (comma-separated, nq values); default the neutral configuration.
    #[arg(long, allow_hyphen_values = true)]
    pub q: Option<String>,
    /// Layout of --q: moma or pinocchio (planar root [x, y, cos θ, sin θ]; continuous
    /// joints as cos, sin).
    #[arg(long, value_enum, default_value_t = super::common::Layout::Moma)]
    pub layout: super::common::Layout,
    /// The two arm joints of the heat map, "JOINT_X,JOINT_Y".
    #[arg(long)]
    pub joints: String,
    /// Ranges of the two joints "LO,HI;LO,HI" (rad); default their position limits.
    #[arg(long, allow_hyphen_values = true)]
    pub ranges: Option<String>,
    /// Cells per joint axis of the heat map (2..=400).
    #[arg(long, default_value_t = 41)]
    pub resolution: usize,
    /// Platform acceleration "AX,AY" in base axes (m/s², AX forward) for the heat map.
    #[arg(long, default_value = "0,0", allow_hyphen_values = true)]
    pub platform_acceleration: String,
    /// Directions of the polar plot (3..=3600).
    #[arg(long, default_value_t = 72)]
    pub directions: usize,
    /// Bodies of the Moment-Height inertia: all, subtree:JOINT or links:A,B,...
    #[arg(long, default_value = "all")]
    pub mhs_bodies: String,
    /// Gravity GX,GY,GZ (m/s²); default the model's.
    #[arg(long, allow_hyphen_values = true)]
    pub gravity: Option<String>,
    /// Output directory: acceleration_limits.svg, margin_map.svg, stability_map.json.
    #[arg(long, default_value = "stability_map")]
    pub output_dir: PathBuf,
}

#[derive(Serialize)]
struct Polar {
    angle: Vec<f64>,
    limit: Vec<Option<f64>>,
}

#[derive(Serialize)]
struct Heat {
    joints: [String; 2],
    x: Vec<f64>,
    y: Vec<f64>,
    platform_acceleration: [f64; 2],
    /// Rows over y, each over x.
    zmp_margin: Vec<Vec<Option<f64>>>,
}

#[derive(Serialize)]
struct MapOut {
    acceleration_limits: Polar,
    margin: Heat,
}

/// Runs `moma stability-map`.
pub fn run(args: Args) -> Result<()> {
    let (model, sm) = setup(
        &args.robot,
        &args.root,
        &args.support,
        &args.mhs_bodies,
        args.gravity.as_deref(),
    )?;
    check_counts(&args)?;
    let q0 = match &args.q {
        Some(t) => DVector::from_vec(
            super::common::LayoutConv::new(&model, args.layout)
                .q_in(super::common::parse_list("--q", t)?, "--q")?,
        ),
        None => moma::kinematics::neutral(&model),
    };
    check_state(&model, "--q", Some(q0.as_slice()), None, None, None)?;
    let (names, idx) = heat_map_joints(&model, &args.joints)?;
    let ranges = joint_ranges(&model, args.ranges.as_deref(), &names, idx)?;
    let pa = super::common::parse_list("--platform-acceleration", &args.platform_acceleration)?;
    if pa.len() != 2 {
        bail!("--platform-acceleration: expected AX,AY (2 numbers)");
    }
    let mut data = Data::new(&model);
    let mut sd = StabilityData::new(&sm);
    let polar_out = polar_limits(&model, &mut data, &sm, &mut sd, &q0, args.directions);
    let n = args.resolution;
    let lin = |r: [f64; 2], i: usize| r[0] + (r[1] - r[0]) * i as f64 / (n - 1) as f64;
    let xs: Vec<f64> = (0..n).map(|i| lin(ranges[0], i)).collect();
    let ys: Vec<f64> = (0..n).map(|i| lin(ranges[1], i)).collect();
    let grid = MarginGrid {
        idx,
        xs: &xs,
        ys: &ys,
        acceleration: [pa[0], pa[1]],
    };
    let cells = margin_cells(&model, &mut data, &sm, &mut sd, &q0, &grid);
    let title_polar = format!("{}: tip-over acceleration limits at rest", model.name);
    let svg_polar = polar(&title_polar, &polar_out.angle, &polar_out.limit);
    let title_heat = format!(
        "{}: ZMP margin, platform acceleration ({}, {}) m/s² in base axes",
        model.name, pa[0], pa[1]
    );
    let svg_heat = margin_map(&MarginMap {
        title: &title_heat,
        x_label: names[0],
        y_label: names[1],
        xs: &xs,
        ys: &ys,
        cells: &cells,
    });
    let out = MapOut {
        acceleration_limits: polar_out,
        margin: Heat {
            joints: [names[0].to_string(), names[1].to_string()],
            x: xs.clone(),
            y: ys.clone(),
            platform_acceleration: [pa[0], pa[1]],
            zmp_margin: cells.chunks(n).map(<[_]>::to_vec).collect(),
        },
    };
    let mut json = serde_json::to_string_pretty(&out)?;
    json.push('\n');
    write_outputs(&args.output_dir, svg_polar, svg_heat, json)
}

/// `--resolution` and `--directions` within their bounds (before anything is allocated).
fn check_counts(args: &Args) -> Result<()> {
    if !(2..=MAX_GRID).contains(&args.resolution) {
        bail!(
            "--resolution: must be in 2..={MAX_GRID}, got {}",
            args.resolution
        );
    }
    if !(3..=MAX_DIRECTIONS).contains(&args.directions) {
        bail!(
            "--directions: must be in 3..={MAX_DIRECTIONS}, got {}",
            args.directions
        );
    }
    Ok(())
}

/// The names of the two `--joints` of the heat map and their q indices (each a
/// one-coordinate joint).
fn heat_map_joints<'a>(model: &Model, joints: &'a str) -> Result<(Vec<&'a str>, [usize; 2])> {
    let names: Vec<&str> = joints.split(',').map(str::trim).collect();
    if names.len() != 2 {
        bail!("--joints: expected two joint names JOINT_X,JOINT_Y");
    }
    let mut idx = [0usize; 2];
    for (k, n) in names.iter().enumerate() {
        let j = model.joint_id(n).map_err(|e| anyhow!("--joints: {e}"))?;
        if model.nqs[j.0] != 1 {
            bail!("--joints: '{n}' must be a one-coordinate joint");
        }
        idx[k] = model.idx_q[j.0];
    }
    Ok((names, idx))
}

/// The two joints' ranges: `--ranges` "LO,HI;LO,HI", or else their (finite) position
/// limits.
fn joint_ranges(
    model: &Model,
    ranges: Option<&str>,
    names: &[&str],
    idx: [usize; 2],
) -> Result<[[f64; 2]; 2]> {
    let mut r = [[0.0; 2]; 2];
    match ranges {
        Some(t) => {
            let parts: Vec<&str> = t.split(';').collect();
            if parts.len() != 2 {
                bail!("--ranges: expected LO,HI;LO,HI");
            }
            for (k, p) in parts.iter().enumerate() {
                let v = super::common::parse_list("--ranges", p)?;
                if v.len() != 2 || v[0] >= v[1] {
                    bail!("--ranges: range {k} must be LO,HI with LO < HI");
                }
                r[k] = [v[0], v[1]];
            }
        }
        None => {
            for k in 0..2 {
                let (lo, hi) = (
                    model.lower_position_limit[idx[k]],
                    model.upper_position_limit[idx[k]],
                );
                if !(lo.is_finite() && hi.is_finite() && lo < hi) {
                    bail!(
                        "--ranges: joint '{}' has no finite limits; give --ranges",
                        names[k]
                    );
                }
                r[k] = [lo, hi];
            }
        }
    }
    Ok(r)
}

/// The polar plot of the posture `q0` at rest: the tip-over acceleration limit in each
/// of `directions` directions (angles from the base heading).
fn polar_limits(
    model: &Model,
    data: &mut Data,
    sm: &StabilityModel,
    sd: &mut StabilityData,
    q0: &DVector<f64>,
    directions: usize,
) -> Polar {
    let zero = DVector::zeros(model.nv);
    evaluate(model, data, sm, sd, q0, &zero, &zero, &ExternalLoads::NONE);
    let yaw = sd.base_pose[2];
    let mut polar_out = Polar {
        angle: Vec::with_capacity(directions),
        limit: Vec::with_capacity(directions),
    };
    for k in 0..directions {
        let ang = std::f64::consts::TAU * k as f64 / directions as f64;
        let d = Vector3::new((yaw + ang).cos(), (yaw + ang).sin(), 0.0);
        polar_out.angle.push(ang);
        polar_out.limit.push(acceleration_limit(
            sd.wrench.mass,
            &sd.wrench.com,
            &sm.gravity,
            &sd.support,
            &d,
        ));
    }
    polar_out
}

/// The heat map's grid: the q indices of its two joints, their values along x and y, and
/// the platform acceleration (base axes).
struct MarginGrid<'a> {
    idx: [usize; 2],
    xs: &'a [f64],
    ys: &'a [f64],
    acceleration: [f64; 2],
}

/// The ZMP margin over the grid (rows over y, each over x): the whole robot translating
/// at the platform acceleration (world axes of the base heading), joints held.
fn margin_cells(
    model: &Model,
    data: &mut Data,
    sm: &StabilityModel,
    sd: &mut StabilityData,
    q0: &DVector<f64>,
    grid: &MarginGrid<'_>,
) -> Vec<Option<f64>> {
    let zero = DVector::zeros(model.nv);
    let pa = grid.acceleration;
    let mut cells = Vec::with_capacity(grid.xs.len() * grid.ys.len());
    let mut q = q0.clone();
    let mut rep = moma::stability::StabilityReport::default();
    for &y in grid.ys {
        for &x in grid.xs {
            q[grid.idx[0]] = x;
            q[grid.idx[1]] = y;
            evaluate(model, data, sm, sd, &q, &zero, &zero, &ExternalLoads::NONE);
            let (s, c) = sd.base_pose[2].sin_cos();
            let acc = Vector3::new(c * pa[0] - s * pa[1], s * pa[0] + c * pa[1], 0.0);
            let mut w = sd.wrench;
            w.force -= acc * w.mass;
            moma::stability::evaluate_measures(&w, &sd.support, &sd.set_inertia, &mut rep);
            cells.push(rep.zmp_margin);
        }
    }
    cells
}

/// Writes the two figures and the JSON into `dir` (all or nothing).
fn write_outputs(dir: &Path, svg_polar: String, svg_heat: String, json: String) -> Result<()> {
    std::fs::create_dir_all(dir)
        .map_err(|e| anyhow!("{}: cannot create output directory: {e}", dir.display()))?;
    write_all_atomic(&[
        (dir.join("acceleration_limits.svg"), svg_polar.into_bytes()),
        (dir.join("margin_map.svg"), svg_heat.into_bytes()),
        (dir.join("stability_map.json"), json.into_bytes()),
    ])
}

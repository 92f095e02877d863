//! `moma place ROBOT.urdf [--srdf FILE] [--package-dir DIR]... --scene SCENE.yaml
//! (--grasp-pose FRAME:x,y,z,qx,qy,qz,qw | --query QUERY.yaml --frame FRAME) --group
//! J1,J2,… --wheels LEFT,RIGHT [--casters FILE] --payload KG [--area x0,y0,x1,y1]
//! [--step m] [--headings N] [--output OUT.json] [--svg FIG.svg]`: where a mobile
//! manipulator can stand to grasp: the reachable, collision-free, upright base poses,
//! ranked (`docs/placement.md`). Exit 3 with the reason when no pose works; the JSON is
//! written either way.

use super::common::{RobotArgs, goal_not_reached, parse_list};
use super::motion::{Robot, first_q, parse_goal_pose, parse_group};
use anyhow::{Context, Result, anyhow, bail};
use moma::collision::{Scene, SceneOptions, read_scene};
use moma::mobile::{read_casters, wheeled_base_from_urdf};
use moma::motion::GoalPose;
use moma::motion::grasp_query::read_grasp_query;
use moma::motion::placement::{
    Payload, Placement, PlacementOptions, PlacementProblem, ScoreWeights, place_base,
};
use moma::multibody::{FrameKind, RootJoint};
use moma::stability::SupportPolygon;
use nalgebra::Vector3;
use serde::Serialize;
use std::path::PathBuf;

/// Arguments of `moma place`.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    pub robot: RobotArgs,
    /// MoveIt planning-scene YAML (MotionBenchMaker's schema); poses in `world` or in the
    /// robot's root link, both meaning the world (the frame the robot's base poses are in).
    #[arg(long)]
    pub scene: PathBuf,
    /// The grasp: FRAME:x,y,z,qx,qy,qz,qw (or FRAME:x,y,z, identity rotation), world frame.
    #[arg(long, conflicts_with = "query", required_unless_present = "query")]
    pub grasp_pose: Option<String>,
    /// MotionBenchMaker query YAML: its goal query (an offset from a scene object, with
    /// per-axis tolerances) is the grasp of `--frame`.
    #[arg(long, requires = "frame")]
    pub query: Option<PathBuf>,
    /// Which goal query of `--query` (from 0).
    #[arg(long, default_value_t = 0)]
    pub query_index: usize,
    /// The grasp frame of `--query` (e.g. Fetch's gripper_link).
    #[arg(long)]
    pub frame: Option<String>,
    /// Largest distance of the frame from the grasp position (m; `--grasp-pose` only).
    #[arg(long, default_value_t = 0.01)]
    pub position_tolerance: f64,
    /// Largest rotation angle from the grasp orientation (rad; `--grasp-pose` only).
    #[arg(long, default_value_t = 0.01)]
    pub orientation_tolerance: f64,
    /// The joints that reach, comma-separated (e.g. Fetch's arm_with_torso).
    #[arg(long)]
    pub group: String,
    /// The driven wheels' joints, `LEFT,RIGHT`: the differential drive (radius, track) is
    /// read from the URDF.
    #[arg(long)]
    pub wheels: String,
    /// Casters file (TOML, `[[casters]]` with `name` and `position = [x, y]` in the base
    /// frame): with the wheel contacts, the support polygon.
    #[arg(long)]
    pub casters: Option<PathBuf>,
    /// The object's mass (kg).
    #[arg(long)]
    pub payload: f64,
    /// The object's centre in the grasp frame, `x,y,z` (m); default: the query's object
    /// origin, or the frame's origin with `--grasp-pose`.
    #[arg(long, allow_hyphen_values = true)]
    pub payload_offset: Option<String>,
    /// States file whose first `q` (full model order, base coordinates ignored) fixes the
    /// joints outside the group and seeds the IK; default: the neutral configuration.
    #[arg(long)]
    pub posture: Option<PathBuf>,
    /// Base positions searched: `x0,y0,x1,y1` (world, m); default: the square around the
    /// grasp as wide as the group's reach.
    #[arg(long, allow_hyphen_values = true)]
    pub area: Option<String>,
    /// Grid step (m).
    #[arg(long, default_value_t = 0.1)]
    pub step: f64,
    /// Headings per grid cell.
    #[arg(long, default_value_t = 16)]
    pub headings: usize,
    /// IK seeds per base pose.
    #[arg(long, default_value_t = 8)]
    pub ik_attempts: usize,
    /// Seed of the IK seeds.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Clearance a grasping posture must exceed (m).
    #[arg(long, default_value_t = 0.005)]
    pub margin: f64,
    /// Score weights of manipulability, clearance and tip-over margin: `wm,wc,wt`.
    #[arg(long, default_value = "1,1,1")]
    pub weights: String,
    /// The most base poses searched (a guard against a tiny step).
    #[arg(long, default_value_t = 200_000)]
    pub max_samples: usize,
    /// Candidates reported, best first.
    #[arg(long, default_value_t = 20)]
    pub candidates: usize,
    /// Write the JSON here (atomically) instead of standard output.
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// Draw the scene's top view, the grasp and the candidates into this SVG file.
    #[arg(long)]
    pub svg: Option<PathBuf>,
}

#[derive(Serialize)]
struct Output<'a> {
    found: bool,
    reason: Option<String>,
    grasp: GraspOut,
    payload_kg: f64,
    payload_offset: [f64; 3],
    group: Vec<String>,
    support: Vec<[f64; 2]>,
    weights: ScoreWeights,
    margin: f64,
    clearance_cap: f64,
    #[serde(flatten)]
    placement: &'a Placement,
    time_s: f64,
}

#[derive(Serialize)]
struct GraspOut {
    frame: String,
    pose: [f64; 7],
    position_tolerance: f64,
    orientation_tolerance: f64,
    object: Option<String>,
}

fn read_world_scene(robot: &Robot, path: &std::path::Path) -> Result<Scene> {
    let mut world_frames = vec!["world".to_string()];
    if let Some(f) = robot
        .model
        .frames
        .iter()
        .find(|f| f.kind == FrameKind::Body)
    {
        world_frames.push(f.name.clone());
    }
    Ok(read_scene(
        path,
        &SceneOptions {
            world_frames,
            package_dirs: robot.source.package_dirs.clone(),
        },
    )?)
}

fn triple(field: &str, text: &str) -> Result<Vector3<f64>> {
    let v = parse_list(field, text)?;
    if v.len() != 3 {
        bail!("{field}: expected x,y,z, got {} values", v.len());
    }
    Ok(Vector3::new(v[0], v[1], v[2]))
}

/// Runs `moma place`.
pub fn run(args: Args) -> Result<()> {
    let began = std::time::Instant::now();
    let robot = Robot::load(
        &args.robot.urdf,
        RootJoint::Planar,
        args.robot.srdf.as_deref(),
        &args.robot.package_dirs,
    )?;
    let model = &robot.model;
    let scene = read_world_scene(&robot, &args.scene)?;
    let group = parse_group(model, &args.group)?;
    let (goal, object, query_offset): (GoalPose, Option<String>, Option<Vector3<f64>>) =
        match (&args.grasp_pose, &args.query) {
            (Some(text), _) => (
                parse_goal_pose(
                    model,
                    text,
                    args.position_tolerance,
                    args.orientation_tolerance,
                )
                .map_err(|e| anyhow!("{e}").context("--grasp-pose"))?,
                None,
                None,
            ),
            (None, Some(path)) => {
                let name = args.frame.as_deref().unwrap_or_default();
                let frame = model.frame_id(name).map_err(|e| anyhow!("--frame: {e}"))?;
                let q = read_grasp_query(path, args.query_index, &scene)?;
                (
                    GoalPose {
                        frame,
                        target: q.target,
                        position_tolerance: q.position_tolerance,
                        orientation_tolerance: q.orientation_tolerance,
                    },
                    Some(q.object),
                    Some(q.object_in_grasp),
                )
            }
            (None, None) => bail!("give --grasp-pose or --query"),
        };
    let wheels: Vec<&str> = args.wheels.split(',').map(str::trim).collect();
    let [left, right] = wheels.as_slice() else {
        bail!(
            "--wheels: expected LEFT,RIGHT (two joint names), got '{}'",
            args.wheels
        );
    };
    let casters = match &args.casters {
        Some(p) => read_casters(p)?,
        None => Vec::new(),
    };
    let base = wheeled_base_from_urdf(model, &robot.geometry, [left, right], casters)
        .with_context(|| format!("--wheels ({})", args.robot.urdf.display()))?;
    let support = SupportPolygon::from_wheeled_base(&base).context("support polygon")?;
    let offset = match &args.payload_offset {
        Some(text) => triple("--payload-offset", text)?,
        None => query_offset.unwrap_or_else(Vector3::zeros),
    };
    let posture: Vec<f64> = match &args.posture {
        Some(p) => first_q(p)?,
        None => moma::multibody::neutral(model).as_slice().to_vec(),
    };
    let area = match &args.area {
        Some(text) => {
            let v = parse_list("--area", text)?;
            let [x0, y0, x1, y1] = v.as_slice() else {
                bail!("--area: expected x0,y0,x1,y1, got {} values", v.len());
            };
            Some([*x0, *y0, *x1, *y1])
        }
        None => None,
    };
    let w = parse_list("--weights", &args.weights)?;
    let [wm, wc, wt] = w.as_slice() else {
        bail!("--weights: expected wm,wc,wt, got {} values", w.len());
    };
    let options = PlacementOptions {
        area,
        step: args.step,
        headings: args.headings,
        ik_attempts: args.ik_attempts,
        seed: args.seed,
        margin: args.margin,
        weights: ScoreWeights {
            manipulability: *wm,
            clearance: *wc,
            tip_over: *wt,
        },
        max_samples: args.max_samples,
        max_candidates: args.candidates,
        ..PlacementOptions::default()
    };
    let problem = PlacementProblem {
        model,
        geometry: &robot.geometry,
        scene: &scene,
        group: &group,
        posture: &posture,
        support: &support,
        grasp: &goal,
        payload: Payload {
            mass: args.payload,
            offset,
        },
    };
    let placement = place_base(&problem, &options)?;
    let t = goal.target;
    let r = t.rotation.coords;
    let out = Output {
        found: !placement.candidates.is_empty(),
        reason: placement.failure(),
        grasp: GraspOut {
            frame: model.frames[goal.frame.0].name.clone(),
            pose: [
                t.translation.x,
                t.translation.y,
                t.translation.z,
                r.x,
                r.y,
                r.z,
                r.w,
            ],
            position_tolerance: goal.position_tolerance,
            orientation_tolerance: goal.orientation_tolerance,
            object,
        },
        payload_kg: args.payload,
        payload_offset: [offset.x, offset.y, offset.z],
        group: group.names.clone(),
        support: support.vertices_xy().iter().map(|v| [v.x, v.y]).collect(),
        weights: options.weights,
        margin: options.margin,
        clearance_cap: options.clearance_cap,
        placement: &placement,
        time_s: began.elapsed().as_secs_f64(),
    };
    let json = serde_json::to_vec_pretty(&out)?;
    let mut files = Vec::new();
    if let Some(p) = &args.svg {
        let svg = crate::svg_placement::render(&scene, &goal, &support, &placement);
        files.push((p.clone(), svg.into_bytes()));
    }
    match &args.output {
        Some(p) => {
            let mut json = json;
            json.push(b'\n');
            files.push((p.clone(), json));
            crate::output::write_all_atomic(&files)?;
        }
        None => {
            crate::output::write_all_atomic(&files)?;
            crate::output::print_json(&out)?;
        }
    }
    match placement.failure() {
        None => Ok(()),
        Some(reason) => goal_not_reached(reason),
    }
}

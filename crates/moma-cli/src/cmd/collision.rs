//! `moma collision ROBOT.urdf --root R [--srdf FILE] [--package-dir DIR]... [--scene
//! SCENE.yaml] --states STATES.json [--layout moma|pinocchio] [--all-pairs]
//! [--mesh convex|exact] [--voxels MAP.3dmap | --points CLOUD.xyz --voxel-size R [--voxel-origin X,Y,Z]]
//! [--footprint] [--gradient] [--output OUT.json] [--svg FIG.svg]`: signed distances
//! between the robot's links (and against the scene's objects) for each state, with the
//! robot's planar footprint and the minimum distance's derivative on request. Schema:
//! `docs/cli.md`.

use super::common::{Layout, LayoutConv, load_model, parse_root, read_states};
use anyhow::{Context, Result};
use moma::collision::{
    ExactGeometry, ExactScene, GeometryData, GeometryModel, GeometryOptions, PairDistance,
    PairSelection, Scene, SceneData, SceneOptions, base_ground_pose, compute_distances,
    compute_exact_distances, compute_exact_scene_distances, compute_scene_distances, footprint,
    footprint_in, min_distance_gradient, outline_points, point_cloud_object, read_points,
    read_scene, update_geometry_placements, voxel_object,
};
use moma::kinematics;
use moma::multibody::{Data, FrameKind, RootJoint};
use nalgebra::{DVector, Vector3};
use serde::Serialize;
use std::path::PathBuf;

/// Arguments of `moma collision`.
#[derive(clap::Args)]
pub struct Args {
    /// The robot description (URDF); its `<collision>` elements are the geometry (meshes
    /// as their convex hulls).
    pub urdf: PathBuf,
    /// Root joint: fixed, planar (q = [x, y, θ]) or free-flyer.
    #[arg(long, value_parser = parse_root)]
    pub root: RootJoint,
    /// SRDF whose `<disable_collisions>` pairs are not checked.
    #[arg(long)]
    pub srdf: Option<PathBuf>,
    /// Folder against which `package://PKG/...` mesh URIs resolve, as DIR/PKG/... (or
    /// DIR/... when DIR is named PKG); repeatable; ROS_PACKAGE_PATH is searched after.
    #[arg(long = "package-dir")]
    pub package_dirs: Vec<PathBuf>,
    /// MoveIt planning-scene YAML (MotionBenchMaker's schema); poses in `world` or, with a
    /// fixed root, in the robot's root link.
    #[arg(long)]
    pub scene: Option<PathBuf>,
    /// Blocked voxels of a Moving AI `.3dmap` as one more scene object (its id: the file
    /// name without extension), cubes of `--voxel-size` m, voxel (0, 0, 0) at
    /// `--voxel-origin`, world frame.
    #[arg(long, requires = "voxel_size")]
    pub voxels: Option<PathBuf>,
    /// A point cloud (text: `x y z` or `x,y,z` per line, world frame, `#` comments)
    /// binned into voxels of `--voxel-size` m (cells `floor(p / size)`) as one more scene
    /// object (its id: the file name without extension).
    #[arg(long, requires = "voxel_size")]
    pub points: Option<PathBuf>,
    /// Edge of the voxels of `--voxels` and `--points` (m).
    #[arg(long)]
    pub voxel_size: Option<f64>,
    /// World position of the `.3dmap`'s corner (voxel (0, 0, 0)'s low corner): `X,Y,Z`.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, default_values_t = [0.0, 0.0, 0.0])]
    pub voxel_origin: Vec<f64>,
    /// States file (as `moma dynamics`): `{"states": [{"q": [..]}, ..]}`.
    #[arg(long)]
    pub states: PathBuf,
    /// State layout of the states file: moma (continuous joints as one angle) or
    /// pinocchio (continuous joints as cos, sin; planar root [x, y, cos θ, sin θ]).
    #[arg(long, value_enum, default_value_t = Layout::Moma)]
    pub layout: Layout,
    /// Meshes (the links' and the scene's) as their convex hulls (signed distances,
    /// negative when overlapping) or exactly, as their triangles (surface distances, 0
    /// where triangles touch or cross, as coal's between BVH meshes; scene primitives and
    /// voxels are solid: 0 where a link's triangle touches or enters one).
    #[arg(long, value_enum, default_value_t = MeshMode::Convex)]
    pub mesh: MeshMode,
    /// List and check every link pair, not only the enabled ones (not adjacent, not
    /// fixed to each other, not disabled by the SRDF).
    #[arg(long)]
    pub all_pairs: bool,
    /// Add each state's planar footprint: the convex hull of the robot's collision
    /// geometry projected on the ground, in the base frame (x forward) for a planar or
    /// free-flyer root, in the world frame for a fixed one. In the JSON as `footprint`
    /// (vertices, counter-clockwise) and `footprint_text` (`x,y;x,y;...`, as `moma plan
    /// --footprint` takes it); with `--output`, the texts are also printed, one line per
    /// state.
    #[arg(long)]
    pub footprint: bool,
    /// Add each state's `gradient`: the derivative of `min_distance` (the closest pair's
    /// signed distance) with respect to the velocity coordinates (nv entries; ∂d/∂q for a
    /// fixed or planar root in the moma layout).
    #[arg(long)]
    pub gradient: bool,
    /// Write the JSON here (atomically) instead of standard output.
    #[arg(long)]
    pub output: Option<PathBuf>,
    /// Draw the robot's geometry (in the first state) and the scene, side and top views,
    /// into this SVG file.
    #[arg(long)]
    pub svg: Option<PathBuf>,
}

/// How link meshes enter the distances.
#[derive(Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum MeshMode {
    /// Each mesh as its convex hull.
    Convex,
    /// Each mesh as its triangles.
    Exact,
}

#[derive(Serialize)]
struct PairOut {
    a: String,
    b: String,
    distance: f64,
    witness_a: [f64; 3],
    witness_b: [f64; 3],
}

#[derive(Serialize)]
struct StateOut {
    min_distance: f64,
    in_collision: bool,
    closest: [String; 2],
    #[serde(skip_serializing_if = "Option::is_none")]
    gradient: Option<Vec<f64>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    footprint: Option<Vec<[f64; 2]>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    footprint_text: Option<String>,
    pairs: Vec<PairOut>,
}

#[derive(Serialize)]
struct Output {
    robot: String,
    source: String,
    root: String,
    layout: &'static str,
    mesh: &'static str,
    #[serde(skip_serializing_if = "Option::is_none")]
    footprint_frame: Option<&'static str>,
    pairs_enabled: Vec<[String; 2]>,
    scene_objects: Vec<String>,
    states: Vec<StateOut>,
}

fn v3(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

fn pair_out(a: &str, b: &str, r: &PairDistance) -> PairOut {
    PairOut {
        a: a.to_string(),
        b: b.to_string(),
        distance: r.distance,
        witness_a: v3(&r.witness_a),
        witness_b: v3(&r.witness_b),
    }
}

/// Runs `moma collision`.
pub fn run(args: Args) -> Result<()> {
    let model = load_model(&args.urdf, args.root)?;
    let gm = GeometryModel::from_urdf(
        &model,
        &args.urdf,
        &GeometryOptions {
            package_dirs: args.package_dirs.clone(),
            srdf: args.srdf.clone(),
        },
    )?;
    let scene = match &args.scene {
        Some(path) => {
            let mut world_frames = vec!["world".to_string()];
            if args.root == RootJoint::Fixed
                && let Some(f) = model.frames.iter().find(|f| f.kind == FrameKind::Body)
            {
                world_frames.push(f.name.clone());
            }
            read_scene(
                path,
                &SceneOptions {
                    world_frames,
                    package_dirs: args.package_dirs.clone(),
                },
            )?
        }
        None => Scene::default(),
    };
    let mut scene = scene;
    add_voxel_objects(&args, &mut scene)?;
    let mut states = read_states(&args.states, &["q"])?;
    let conv = LayoutConv::new(&model, args.layout);
    let mut data = Data::new(&model);
    let mut gd = GeometryData::new(&gm);
    let mut sd = SceneData::new(&gm, &scene);
    let which = if args.all_pairs {
        PairSelection::All
    } else {
        PairSelection::Enabled
    };
    let mut first_placements = None;
    let mut scratch = Vec::new();
    let exact = match args.mesh {
        MeshMode::Exact => Some((ExactGeometry::new(&gm)?, ExactScene::new(&scene)?)),
        MeshMode::Convex => None,
    };
    let mut out_states = Vec::with_capacity(states.len());
    for (k, s) in states.iter_mut().enumerate() {
        let src = format!("{}: states[{k}]", args.states.display());
        conv.state_in(s, &src)?;
        kinematics::check_state(&model, &src, Some(&s.q), None, None, None)?;
        let q = DVector::from_column_slice(&s.q);
        if args.gradient {
            // Forward kinematics and the joint Jacobians of q.
            kinematics::compute_joint_jacobians(&model, &mut data, &q);
        } else {
            kinematics::forward_kinematics(&model, &mut data, &q);
        }
        update_geometry_placements(&gm, &data, &mut gd);
        if first_placements.is_none() {
            first_placements = Some(gd.placements.clone());
        }
        match &exact {
            Some((ex, exs)) => {
                compute_exact_distances(&gm, ex, &mut gd, which);
                compute_exact_scene_distances(&gm, ex, &mut gd, &scene, exs, &mut sd)
            }
            None => {
                compute_distances(&gm, &mut gd, which);
                compute_scene_distances(&gm, &mut gd, &scene, &mut sd)
            }
        };
        let mut pairs = Vec::new();
        for (p, &[a, b]) in gm.pairs.iter().enumerate() {
            if args.all_pairs || gm.enabled[p] {
                pairs.push(pair_out(
                    &gm.links[a].name,
                    &gm.links[b].name,
                    &gd.results[p],
                ));
            }
        }
        let no = scene.objects.len();
        for (l, link) in gm.links.iter().enumerate() {
            for (o, obj) in scene.objects.iter().enumerate() {
                pairs.push(pair_out(&link.name, &obj.id, &sd.results[l * no + o]));
            }
        }
        let closest = pairs
            .iter()
            .min_by(|x, y| x.distance.total_cmp(&y.distance))
            .map(|p| (p.distance, [p.a.clone(), p.b.clone()]));
        let (min_distance, closest) =
            closest.unwrap_or((f64::INFINITY, [String::new(), String::new()]));
        if !min_distance.is_finite() {
            anyhow::bail!(
                "{src}: no pair to check (the robot has fewer than two links with enabled pairs and no scene is given)"
            );
        }
        let gradient = if args.gradient {
            let mut g = DVector::zeros(model.nv);
            min_distance_gradient(&model, &data, &gm, &gd, &scene, &sd, &mut g)
                .context("the closest pair for the gradient")?;
            Some(g.as_slice().to_vec())
        } else {
            None
        };
        let (footprint, footprint_text) = if args.footprint {
            let poly = match base_ground_pose(&model, &data) {
                Some((origin, yaw)) => footprint_in(&gm, &gd, &origin, yaw, &mut scratch),
                None => footprint(&gm, &gd, &mut scratch),
            };
            let text = poly
                .iter()
                .map(|p| format!("{},{}", p.x, p.y))
                .collect::<Vec<_>>()
                .join(";");
            (Some(poly.iter().map(|p| [p.x, p.y]).collect()), Some(text))
        } else {
            (None, None)
        };
        out_states.push(StateOut {
            min_distance,
            // Exact meshes touch at 0 (a surface distance is never negative).
            in_collision: min_distance < 0.0 || (exact.is_some() && min_distance <= 0.0),
            closest,
            gradient,
            footprint,
            footprint_text,
            pairs,
        });
    }
    let out = Output {
        robot: model.name.clone(),
        source: args.urdf.display().to_string(),
        root: model.root.to_string(),
        layout: match args.layout {
            Layout::Moma => "moma",
            Layout::Pinocchio => "pinocchio",
        },
        mesh: match args.mesh {
            MeshMode::Convex => "convex",
            MeshMode::Exact => "exact",
        },
        footprint_frame: args.footprint.then_some(if model.root == RootJoint::Fixed {
            "world"
        } else {
            "base"
        }),
        pairs_enabled: gm
            .pairs
            .iter()
            .zip(&gm.enabled)
            .filter(|(_, e)| **e)
            .map(|(&[a, b], _)| [gm.links[a].name.clone(), gm.links[b].name.clone()])
            .collect(),
        scene_objects: scene.objects.iter().map(|o| o.id.clone()).collect(),
        states: out_states,
    };
    let json = serde_json::to_vec_pretty(&out).context("serialising the output")?;
    let mut files = Vec::new();
    if let Some(svg) = &args.svg {
        let placements = first_placements.unwrap_or_else(|| gd.placements.clone());
        files.push((svg.clone(), draw(&gm, &placements, &scene).into_bytes()));
    }
    match &args.output {
        Some(p) => {
            files.push((p.clone(), json));
            crate::output::write_all_atomic(&files)?;
            for s in &out.states {
                if let Some(t) = &s.footprint_text {
                    println!("{t}");
                }
            }
            Ok(())
        }
        None => {
            crate::output::write_all_atomic(&files)?;
            crate::output::print_json(&out)
        }
    }
}

/// The `--voxels` and `--points` objects, appended to the scene.
fn add_voxel_objects(args: &Args, scene: &mut Scene) -> Result<()> {
    let id = |p: &std::path::Path| {
        p.file_stem().map_or_else(
            || "voxels".to_string(),
            |s| s.to_string_lossy().into_owned(),
        )
    };
    let size = args.voxel_size.unwrap_or(f64::NAN);
    if (args.voxels.is_some() || args.points.is_some()) && !(size.is_finite() && size > 0.0) {
        anyhow::bail!("--voxel-size: {size} must be a positive number of metres");
    }
    if let Some(path) = &args.voxels {
        let grid = moma::planning::movingai::load_3dmap(path)?;
        let o = &args.voxel_origin;
        if o.len() != 3 {
            anyhow::bail!("--voxel-origin: expected X,Y,Z, got {} numbers", o.len());
        }
        let origin = Vector3::new(o[0], o[1], o[2]);
        let obj = voxel_object(&id(path), &grid, size, origin)
            .with_context(|| format!("{}: --voxels", path.display()))?;
        scene.objects.push(obj);
    }
    if let Some(path) = &args.points {
        let points = read_points(path)?;
        let obj = point_cloud_object(&id(path), &points, size)
            .with_context(|| format!("{}: --points", path.display()))?;
        scene.objects.push(obj);
    }
    let mut ids: Vec<&str> = scene.objects.iter().map(|o| o.id.as_str()).collect();
    ids.sort_unstable();
    if let Some(w) = ids.windows(2).find(|w| w[0] == w[1]) {
        anyhow::bail!(
            "scene object id '{}' appears twice (a voxel or point file is named like another object)",
            w[0]
        );
    }
    Ok(())
}

/// Side (x–z) and top (x–y) views of the robot's shapes (blue) and the scene's (grey),
/// each shape drawn as the convex hull of its projection.
fn draw(gm: &GeometryModel, placements: &[moma::spatial::SE3], scene: &Scene) -> String {
    let mut shapes: Vec<(bool, Vec<Vector3<f64>>)> = Vec::new();
    for (o, pose) in gm.objects.iter().zip(placements) {
        let mut pts = Vec::new();
        outline_points(&o.shape, pose, &mut pts);
        shapes.push((true, pts));
    }
    for obj in &scene.objects {
        for s in obj.shapes.iter().take(20_000) {
            let mut pts = Vec::new();
            outline_points(&s.shape, &s.pose, &mut pts);
            shapes.push((false, pts));
        }
    }
    let mut lo = Vector3::repeat(f64::INFINITY);
    let mut hi = Vector3::repeat(f64::NEG_INFINITY);
    for (_, pts) in &shapes {
        for p in pts {
            lo = lo.inf(p);
            hi = hi.sup(p);
        }
    }
    let span = (hi - lo).max().max(1e-3);
    let size = 400.0;
    let scale = size / span;
    let mut svg = format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}\" height=\"{h}\" viewBox=\"0 0 {w} {h}\">\n\
         <text x=\"10\" y=\"16\" font-family=\"sans-serif\" font-size=\"13\">side view (x right, z up)</text>\n\
         <text x=\"{t}\" y=\"16\" font-family=\"sans-serif\" font-size=\"13\">top view (x right, y up)</text>\n",
        w = 2.0 * size + 60.0,
        h = size + 40.0,
        t = size + 50.0
    );
    for (x0, axis) in [(10.0, 2usize), (size + 50.0, 1usize)] {
        for (robot, pts) in &shapes {
            let poly = moma::collision::footprint::hull_2d(
                pts.iter().map(|p| nalgebra::Vector2::new(p.x, p[axis])),
            );
            let coords: Vec<String> = poly
                .iter()
                .map(|p| {
                    format!(
                        "{:.1},{:.1}",
                        x0 + (p.x - lo.x) * scale,
                        30.0 + (hi[axis] - p.y) * scale
                    )
                })
                .collect();
            let style = if *robot {
                "fill=\"#4477aa\" fill-opacity=\"0.35\" stroke=\"#224466\" stroke-width=\"0.6\""
            } else {
                "fill=\"#999999\" fill-opacity=\"0.35\" stroke=\"#555555\" stroke-width=\"0.6\""
            };
            svg.push_str(&format!(
                "<polygon points=\"{}\" {style}/>\n",
                coords.join(" ")
            ));
        }
    }
    svg.push_str("</svg>\n");
    svg
}

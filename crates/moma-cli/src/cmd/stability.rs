//! `moma stability`: tip-over measures (ZMP, Force-Angle, Moment-Height) of a wheeled
//! manipulator on a list of states, and the acceleration limits of the postures at rest.
//!
//! Also holds the input parsing shared with `moma stability-map`.

use crate::output::{print_json, write_json};
use anyhow::{Result, anyhow, bail};
use moma::kinematics::check_state;
use moma::mobile::{Caster, WheeledBase};
use moma::multibody::{Model, RootJoint};
use moma::stability::{
    AccelerationLimits, BodySet, ExternalLoads, PointForce, StabilityData, StabilityModel,
    SupportAttachment, SupportPolygon, evaluate,
};
use nalgebra::{DVector, Vector2, Vector3};
use serde::Serialize;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Largest number of states, support points and external loads accepted.
const MAX_POINTS: usize = 10_000;
const MAX_EXTERNAL: usize = 10_000;

/// Arguments of `moma stability`.
#[derive(clap::Args)]
pub struct Args {
    /// Robot model (URDF).
    pub robot: PathBuf,
    /// Root joint: planar (mobile base), fixed or free-flyer.
    #[arg(long, default_value = "planar")]
    pub root: String,
    #[command(flatten)]
    pub support: SupportArgs,
    /// States: JSON `{"states": [{"q": [...], "v": [...], "a": [...],
    /// "external": [{"point": [x,y,z], "force": [fx,fy,fz]}]}]}` (v, a, external optional;
    /// world frame).
    #[arg(long)]
    pub states: PathBuf,
    /// Bodies of the Moment-Height inertia: all, subtree:JOINT or links:A,B,...
    #[arg(long, default_value = "all")]
    pub mhs_bodies: String,
    /// Gravity GX,GY,GZ (m/s², world axes); default the model's (0, 0, −9.81).
    #[arg(long)]
    pub gravity: Option<String>,
    /// Write the JSON result to this file (default: standard output).
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    /// State layout of the states file: moma or pinocchio (planar root [x, y, cos θ,
    /// sin θ] with base-frame v and a; continuous joints as cos, sin).
    #[arg(long, value_enum, default_value_t = super::common::Layout::Moma)]
    pub layout: super::common::Layout,
}

/// The support options shared by `stability` and `stability-map`.
#[derive(clap::Args)]
#[group(required = true, multiple = false)]
pub struct SupportArgs {
    /// Support points in the base frame on the ground, "X,Y;X,Y;..." (m).
    #[arg(long)]
    pub support: Option<String>,
    /// Wheeled base: diff-drive:r_w=R,b=B,d=D[,casters=X,Y;X,Y;...] (the drive-wheel
    /// contacts d behind the base origin, ±b to the sides, plus the caster contacts).
    #[arg(long)]
    pub base: Option<String>,
}

fn parse_point_list(field: &str, text: &str) -> Result<Vec<Vector2<f64>>> {
    let mut pts = Vec::new();
    for (i, item) in text.split(';').map(str::trim).enumerate() {
        if item.is_empty() {
            continue;
        }
        if pts.len() >= MAX_POINTS {
            bail!("{field}: more than {MAX_POINTS} points");
        }
        let xy = super::common::parse_list(&format!("{field} point {i}"), item)?;
        if xy.len() != 2 {
            bail!(
                "{field}: point {i} '{item}' must be X,Y (2 numbers), got {}",
                xy.len()
            );
        }
        pts.push(Vector2::new(xy[0], xy[1]));
    }
    Ok(pts)
}

/// The support polygon in the base frame from `--support` or `--base`.
pub(crate) fn support_from_args(a: &SupportArgs) -> Result<SupportPolygon> {
    let pts = match (&a.support, &a.base) {
        (Some(s), None) => parse_point_list("--support", s)?,
        (None, Some(b)) => {
            let (drive, casters) = match b.find(",casters=") {
                Some(k) => (&b[..k], Some(&b[k + ",casters=".len()..])),
                None => (b.as_str(), None),
            };
            let dd = super::common::parse_base(drive)?;
            let mut base = WheeledBase::new(dd);
            if let Some(c) = casters {
                for (i, p) in parse_point_list("--base casters", c)?.iter().enumerate() {
                    base.casters.push(Caster {
                        name: format!("caster{i}"),
                        position: [p.x, p.y],
                    });
                }
            }
            base.support_points()
        }
        _ => bail!("give exactly one of --support and --base"),
    };
    let which = if a.support.is_some() {
        "--support"
    } else {
        "--base"
    };
    SupportPolygon::from_points(&pts).map_err(|e| anyhow!("{which}: {e}"))
}

/// Parses `--gravity`.
pub(crate) fn parse_gravity(text: Option<&str>, model: &Model) -> Result<Vector3<f64>> {
    match text {
        None => Ok(model.gravity),
        Some(t) => {
            let g = super::common::parse_list("--gravity", t)?;
            if g.len() != 3 {
                bail!("--gravity: expected GX,GY,GZ (3 numbers), got {}", g.len());
            }
            Ok(Vector3::new(g[0], g[1], g[2]))
        }
    }
}

/// Loads the model and builds the stability set-up shared by both commands.
pub(crate) fn setup(
    robot: &Path,
    root: &str,
    support: &SupportArgs,
    bodies: &str,
    gravity: Option<&str>,
) -> Result<(Model, StabilityModel)> {
    let root: RootJoint = root.parse().map_err(|e| anyhow!("--root: {e}"))?;
    let model = super::common::load_model(robot, root)?;
    let poly = support_from_args(support)?;
    let set: BodySet = bodies.parse().map_err(|e| anyhow!("--mhs-bodies: {e}"))?;
    let g = parse_gravity(gravity, &model)?;
    let sm = StabilityModel::new(&model, poly, SupportAttachment::Base, &set)
        .map_err(|e| anyhow!("--mhs-bodies: {e}"))?
        .with_gravity(g)?;
    Ok((model, sm))
}

/// One input state.
pub(crate) struct State {
    pub q: DVector<f64>,
    pub v: DVector<f64>,
    pub a: DVector<f64>,
    pub external: Vec<PointForce>,
    /// True if v and a are zero and there is no external load.
    pub at_rest: bool,
}

fn vec3(v: &Value, field: &str, path: &Path) -> Result<Vector3<f64>> {
    let x = super::common::number_array(v, field, path)?;
    if x.len() != 3 {
        bail!(
            "{}: {field}: expected length 3, got {}",
            path.display(),
            x.len()
        );
    }
    if x.iter().any(|y| !y.is_finite()) {
        bail!("{}: {field}: non-finite value", path.display());
    }
    Ok(Vector3::new(x[0], x[1], x[2]))
}

/// Reads and validates STATES.json for `model` (the one states reader of
/// `common::read_states`, with the `external` loads of this command).
pub(crate) fn read_states(
    path: &Path,
    model: &Model,
    layout: super::common::Layout,
) -> Result<Vec<State>> {
    let states = super::common::read_states(path, &["q", "v", "a", "external"])?;
    let conv = super::common::LayoutConv::new(model, layout);
    let mut out = Vec::with_capacity(states.len());
    for (i, mut st) in states.into_iter().enumerate() {
        let field = format!("states[{i}]");
        conv.state_in(&mut st, &format!("{}: {field}", path.display()))?;
        let q = st.q;
        let vv = st.v.unwrap_or_else(|| vec![0.0; model.nv]);
        let aa = st.a.unwrap_or_else(|| vec![0.0; model.nv]);
        check_state(model, &field, Some(&q), Some(&vv), Some(&aa), None)
            .map_err(|e| anyhow!("{}: {e}", path.display()))?;
        let mut external = Vec::new();
        if let Some(ext) = st.extra.get("external") {
            let list = ext.as_array().ok_or_else(|| {
                anyhow!("{}: {field}.external: expected an array", path.display())
            })?;
            if list.len() > MAX_EXTERNAL {
                bail!(
                    "{}: {field}.external: more than {MAX_EXTERNAL} loads",
                    path.display()
                );
            }
            for (k, e) in list.iter().enumerate() {
                let f = format!("{field}.external[{k}]");
                let pt = e
                    .get("point")
                    .ok_or_else(|| anyhow!("{}: {f}: missing field \"point\"", path.display()))?;
                let fo = e
                    .get("force")
                    .ok_or_else(|| anyhow!("{}: {f}: missing field \"force\"", path.display()))?;
                external.push(PointForce {
                    point: vec3(pt, &format!("{f}.point"), path)?,
                    force: vec3(fo, &format!("{f}.force"), path)?,
                });
            }
        }
        let at_rest = vv.iter().chain(&aa).all(|x| *x == 0.0) && external.is_empty();
        out.push(State {
            q: DVector::from_vec(q),
            v: DVector::from_vec(vv),
            a: DVector::from_vec(aa),
            external,
            at_rest,
        });
    }
    Ok(out)
}

#[derive(Serialize)]
struct Giw {
    force: [f64; 3],
    moment_about_com: [f64; 3],
}

#[derive(Serialize)]
struct EdgeOut {
    from: [f64; 3],
    to: [f64; 3],
    zmp_distance: Option<f64>,
    force_angle: Option<f64>,
    force_angle_no_couple: Option<f64>,
    force_angle_beta: Option<f64>,
    moment: f64,
    inertia: f64,
    mhs: Option<f64>,
}

#[derive(Serialize)]
struct StateOut {
    total_mass: f64,
    com: [f64; 3],
    giw: Giw,
    support: Vec<[f64; 3]>,
    zmp: Option<[f64; 3]>,
    zmp_margin: Option<f64>,
    zmp_critical_edge: Option<usize>,
    edges: Vec<EdgeOut>,
    force_angle_min: Option<f64>,
    force_angle_alpha: Option<f64>,
    force_angle_beta_min: Option<f64>,
    mhs_min: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    acceleration_limits: Option<AccelerationLimits>,
    stable: bool,
}

#[derive(Serialize)]
struct Output {
    states: Vec<StateOut>,
}

fn arr(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

/// Runs `moma stability`.
pub fn run(args: Args) -> Result<()> {
    let (model, sm) = setup(
        &args.robot,
        &args.root,
        &args.support,
        &args.mhs_bodies,
        args.gravity.as_deref(),
    )?;
    let states = read_states(&args.states, &model, args.layout)?;
    let mut data = moma::multibody::Data::new(&model);
    let mut sd = StabilityData::new(&sm);
    let mut out = Vec::with_capacity(states.len());
    for s in &states {
        let ext = ExternalLoads {
            forces: &s.external,
            moments: &[],
        };
        evaluate(&model, &mut data, &sm, &mut sd, &s.q, &s.v, &s.a, &ext);
        let (w, r, sup) = (&sd.wrench, &sd.report, &sd.support);
        out.push(StateOut {
            total_mass: w.mass,
            com: arr(&w.com),
            giw: Giw {
                force: arr(&w.force),
                moment_about_com: arr(&w.moment_about_com),
            },
            support: (0..sup.len()).map(|i| arr(&sup.vertex(i))).collect(),
            zmp: r.zmp.as_ref().map(arr),
            zmp_margin: r.zmp_margin,
            zmp_critical_edge: r.zmp_critical_edge,
            edges: r
                .edges
                .iter()
                .enumerate()
                .map(|(i, e)| {
                    let ed = sup.edge(i);
                    EdgeOut {
                        from: arr(&ed.from),
                        to: arr(&ed.to),
                        zmp_distance: e.zmp_distance,
                        force_angle: e.force_angle,
                        force_angle_no_couple: e.force_angle_no_couple,
                        force_angle_beta: e.force_angle_beta,
                        moment: e.moment,
                        inertia: e.inertia,
                        mhs: e.mhs,
                    }
                })
                .collect(),
            force_angle_min: r.force_angle_min,
            force_angle_alpha: r.force_angle_alpha,
            force_angle_beta_min: r.force_angle_beta_min,
            mhs_min: r.mhs_min,
            acceleration_limits: s.at_rest.then(|| sd.acceleration_limits(&sm)),
            stable: r.stable,
        });
    }
    let result = Output { states: out };
    match &args.output {
        Some(p) => write_json(p, &result),
        None => print_json(&result),
    }
}

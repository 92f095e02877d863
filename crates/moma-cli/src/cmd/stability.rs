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
    BodySet, ExternalLoads, PointForce, StabilityData, StabilityModel, StateReport,
    SupportAttachment, SupportPolygon, evaluate,
};
use nalgebra::{DVector, Vector2, Vector3};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Largest number of support points accepted.
const MAX_POINTS: usize = 10_000;

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
        let external: Vec<PointForce> = match st.extra.get("external") {
            Some(ext) => moma::io::states::point_loads(ext, &format!("{field}.external"), path)?
                .into_iter()
                .map(|l| PointForce {
                    point: Vector3::from(l.point),
                    force: Vector3::from(l.force),
                })
                .collect(),
            None => Vec::new(),
        };
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
struct Output {
    states: Vec<StateReport>,
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
        out.push(StateReport::new(&sm, &sd, s.at_rest));
    }
    let result = Output { states: out };
    match &args.output {
        Some(p) => write_json(p, &result),
        None => print_json(&result),
    }
}

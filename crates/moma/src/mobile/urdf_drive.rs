//! The differential drive of a robot read from its URDF: the two driven wheels are
//! continuous joints on the planar base, so the URDF holds everything the drive needs.
//!
//! * **Track**: the wheel joints' origins; the half track `b` is half their distance along
//!   the left wheel's axis.
//! * **Offset** `d`: the base origin lies `d` ahead of the axle midpoint, so `d` is minus
//!   the midpoint's x in the base frame.
//! * **Radius**: the largest distance of the wheel link's collision geometry from the
//!   wheel's axle line (a mesh's convex hull vertices, a cylinder's rim, a sphere's
//!   radius). The two wheels must agree to 1 mm.
//!
//! URDFs usually omit the passive casters (Fetch's does); they come from a separate casters
//! file ([`read_casters`]).

use super::diff_drive::DiffDrive;
use super::wheeled::{Caster, WheeledBase};
use crate::collision::{Convex, GeometryModel};
use crate::multibody::{JointType, Model, RootJoint};
use crate::{Error, Result};
use nalgebra::Vector3;
use std::path::Path;

/// The two wheels' radii may differ by at most this much (m).
pub const WHEEL_RADIUS_AGREEMENT: f64 = 1e-3;

/// The base of a planar-rooted `model` whose driven wheels are the joints `wheels`
/// (`[left, right]`), from the URDF's joints and the wheel links' collision geometry `gm`
/// (module docs); the wheel joints are tracked, and `casters` are the passive supports.
///
/// # Errors
/// [`Error::InvalidInput`] naming the wheel joint: not a continuous or revolute child of
/// the planar root, an axis not along the base y axis, a wheel link without collision
/// geometry, radii that differ by more than [`WHEEL_RADIUS_AGREEMENT`], or wheels on the
/// same side; the errors of [`DiffDrive::new`].
pub fn wheeled_base_from_urdf(
    model: &Model,
    gm: &GeometryModel,
    wheels: [&str; 2],
    casters: Vec<Caster>,
) -> Result<WheeledBase> {
    if model.root != RootJoint::Planar {
        return Err(Error::invalid(
            "root",
            format!(
                "the drive is read on a planar root, '{}' has a {} root",
                model.name, model.root
            ),
        ));
    }
    let mut axle = [Vector3::zeros(); 2];
    let mut axis = [Vector3::zeros(); 2];
    let mut radius = [0.0; 2];
    for (side, name) in wheels.iter().enumerate() {
        let field = format!("wheel joint '{name}'");
        let j = model.joint_id(name)?.0;
        let parent = model.parents[j].0;
        if parent == 0 || model.joint_types[parent] != JointType::Planar {
            return Err(Error::invalid(field, "must be a child of the planar base"));
        }
        let jt = model.joint_types[j];
        let local_axis = jt.axis().filter(|_| jt.is_revolute()).ok_or_else(|| {
            Error::invalid(field.clone(), "must be a continuous or revolute joint")
        })?;
        let placement = &model.joint_placements[j];
        let a = placement.rotation * local_axis;
        if a.y.abs() < 0.99 {
            return Err(Error::invalid(
                field,
                format!(
                    "axis must point along the base y axis, got [{:.3}, {:.3}, {:.3}]",
                    a.x, a.y, a.z
                ),
            ));
        }
        axle[side] = placement.translation;
        axis[side] = a;
        // Geometry on the wheel's body, in its joint frame: distance from the axle line.
        let mut r: Option<f64> = None;
        for o in gm.objects.iter().filter(|o| o.joint.0 == j) {
            let rim = object_rim_radius(&o.shape, &o.placement, &local_axis);
            r = Some(r.map_or(rim, |x: f64| x.max(rim)));
        }
        radius[side] = r.ok_or_else(|| {
            Error::invalid(
                field,
                "its link has no collision geometry to read the radius from",
            )
        })?;
    }
    if (radius[0] - radius[1]).abs() > WHEEL_RADIUS_AGREEMENT {
        return Err(Error::invalid(
            format!("wheel joints '{}', '{}'", wheels[0], wheels[1]),
            format!(
                "the wheel radii differ: {:.4} m and {:.4} m (at most {WHEEL_RADIUS_AGREEMENT} m apart)",
                radius[0], radius[1]
            ),
        ));
    }
    let lateral = (axle[0] - axle[1]).dot(&axis[0].normalize()) * axis[0].y.signum();
    if lateral <= 0.0 {
        return Err(Error::invalid(
            format!("wheel joint '{}'", wheels[0]),
            "the left wheel must lie on the base's +y side of the right one",
        ));
    }
    let mid = 0.5 * (axle[0] + axle[1]);
    let drive = DiffDrive::new(0.5 * (radius[0] + radius[1]), 0.5 * lateral, -mid.x)?;
    Ok(WheeledBase {
        drive,
        casters,
        wheel_joints: Some([wheels[0].to_string(), wheels[1].to_string()]),
    })
}

/// The largest distance of a shape (placed at `placement` in the joint frame) from the
/// axle line through the joint origin along `axis` (joint frame).
fn object_rim_radius(shape: &Convex, placement: &crate::spatial::SE3, axis: &Vector3<f64>) -> f64 {
    let radial = |p: Vector3<f64>| (p - axis * p.dot(axis)).norm();
    let margin = shape.margin();
    match shape {
        Convex::Hull { vertices, .. } => vertices
            .iter()
            .map(|v| radial(placement.act_point(v)))
            .fold(0.0, f64::max),
        Convex::Box { half } => {
            let mut best: f64 = 0.0;
            for k in 0..8 {
                let s = |b: usize| if k & b == 0 { -1.0 } else { 1.0 };
                let v = Vector3::new(s(1) * half.x, s(2) * half.y, s(4) * half.z);
                best = best.max(radial(placement.act_point(&v)));
            }
            best
        }
        Convex::Cylinder {
            radius,
            half_height,
        } => {
            // Every rim point is within `r` of its end centre and the distance from a
            // line is 1-Lipschitz, so `radial(centre) + r` bounds each rim; it is exact
            // for a wheel's own cylinder (along the axle, its rims circle the line).
            [-half_height, *half_height]
                .map(|h| radial(placement.act_point(&Vector3::new(0.0, 0.0, h))) + radius)
                .into_iter()
                .fold(0.0, f64::max)
        }
        Convex::Sphere { .. } | Convex::Capsule { .. } => {
            let core = match shape {
                Convex::Capsule { half_length, .. } => [
                    Vector3::new(0.0, 0.0, -half_length),
                    Vector3::new(0.0, 0.0, *half_length),
                ],
                _ => [Vector3::zeros(), Vector3::zeros()],
            };
            core.iter()
                .map(|c| radial(placement.act_point(c)) + margin)
                .fold(0.0, f64::max)
        }
    }
}

#[derive(serde::Deserialize)]
#[serde(deny_unknown_fields)]
struct CastersFile {
    casters: Vec<Caster>,
}

/// Reads a casters file: TOML with one `[[casters]]` table per caster, `name` and
/// `position = [x, y]` (ground contact point in the base frame, m).
///
/// # Errors
/// [`Error::Io`] for a file that cannot be read; [`Error::Parse`] naming the file and the
/// field for bad TOML, an unknown key, an empty list, an empty or repeated name or a
/// position that is not finite.
pub fn read_casters(path: &Path) -> Result<Vec<Caster>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    casters_from_str(&text, path)
}

/// [`read_casters`] on the text of the file `path`.
///
/// # Errors
/// As [`read_casters`].
pub fn casters_from_str(text: &str, path: &Path) -> Result<Vec<Caster>> {
    let parse = |message: String| Error::Parse {
        path: path.to_path_buf(),
        message,
    };
    let file: CastersFile = toml::from_str(text).map_err(|e| {
        // Where (the line and its text, which names the key), then toml's message.
        let at = e.span().map_or_else(String::new, |sp| {
            let start = sp.start.min(text.len());
            let line = text[..start].matches('\n').count() + 1;
            let line_text = text.lines().nth(line - 1).unwrap_or("").trim();
            format!("line {line} `{line_text}`: ")
        });
        parse(format!("{at}{}", e.message().trim().replace('\n', "; ")))
    })?;
    let casters = file.casters;
    if let Some(problem) = caster_list_problem(&casters) {
        return Err(parse(format!("casters{problem}")));
    }
    Ok(casters)
}

/// What is wrong with a list of casters, if anything: an empty list, an empty or
/// repeated name, a position that is not finite. The text starts with the entry it names
/// (`[k].name: ...`, `[k].position: ...`) or `: the list is empty`, to follow the field
/// that holds the list.
#[must_use]
pub fn caster_list_problem(casters: &[Caster]) -> Option<String> {
    if casters.is_empty() {
        return Some(": the list is empty".into());
    }
    for (k, c) in casters.iter().enumerate() {
        if c.name.trim().is_empty() {
            return Some(format!("[{k}].name: a caster needs a name"));
        }
        if casters[..k].iter().any(|o| o.name == c.name) {
            return Some(format!("[{k}].name: '{}' is named twice", c.name));
        }
        if !c.position.iter().all(|x| x.is_finite()) {
            return Some(format!("[{k}].position: not finite"));
        }
    }
    None
}

//! Mesh surfaces for concave links: a link whose mesh's convex hull covers a neighbour
//! (Fetch's `torso_lift_link`, whose hull swallows the shoulder in the tucked pose) is
//! given its mesh's triangles instead, each triangle a flat convex shape.
//!
//! A triangle soup has no inside: two bodies can only come into contact by their surfaces
//! meeting first, so along a motion checked continuously ([`super::clearance`]) from a
//! state that is free of contact, positive surface distances mean no contact. The one
//! thing the surface cannot tell is whether the start itself has one body wholly inside
//! another; [`surface_links_for_states`] only swaps a link when its hull is in contact at
//! the start (or at a goal state, reached by a motion checked from the start), and the
//! caller states that the start is free (the planner's input).

use super::clearance::ClearanceChecker;
use super::group::JointGroup;
use crate::collision::mesh::TriangleMesh;
use crate::collision::urdf_geometry::{GeometrySpec, read_link_mesh, read_urdf_geometry};
use crate::collision::{Convex, GeometryModel, GeometryObject, LinkGeometry, Scene};
use crate::multibody::{FrameKind, Model};
use crate::spatial::SE3;
use crate::{Error, Result};
use nalgebra::Vector3;
use std::path::PathBuf;

/// Where the URDF's meshes are: the file and the package folders.
#[derive(Clone, Debug)]
pub struct MeshSource {
    /// The URDF the model and geometry were loaded from.
    pub urdf: PathBuf,
    /// Folders `package://` URIs resolve against.
    pub package_dirs: Vec<PathBuf>,
}

/// The link's mesh objects replaced by their triangles in patches of at most `patch`
/// neighbouring triangles, each patch the convex hull of its triangles (primitives kept).
///
/// # Errors
/// [`Error::InvalidInput`] naming the link when it has no geometry; the URDF's and the
/// mesh files' read errors (naming the file).
pub fn with_mesh_surface(
    model: &Model,
    gm: &GeometryModel,
    source: &MeshSource,
    link: &str,
    patch: usize,
) -> Result<GeometryModel> {
    let Some(li) = gm.link_index(link) else {
        return Err(Error::invalid(
            format!("link '{link}'"),
            "has no collision geometry",
        ));
    };
    let text = std::fs::read_to_string(&source.urdf).map_err(|e| Error::Io {
        path: source.urdf.clone(),
        source: e,
    })?;
    let elements = read_urdf_geometry(&text, &source.urdf.display().to_string())?;
    let frame = model
        .frames
        .iter()
        .find(|f| f.kind == FrameKind::Body && f.name == link)
        .ok_or_else(|| Error::invalid(format!("link '{link}'"), "is not a body of the model"))?;
    let mine: Vec<_> = elements
        .collisions
        .iter()
        .filter(|g| g.link == link)
        .collect();
    let old = &gm.links[li];
    if mine.len() != old.count {
        return Err(Error::invalid(
            format!("link '{link}'"),
            format!(
                "the URDF gives {} collision elements, the geometry holds {}",
                mine.len(),
                old.count
            ),
        ));
    }
    let mut replaced: Vec<GeometryObject> = Vec::new();
    for (k, g) in mine.iter().enumerate() {
        let original = &gm.objects[old.first + k];
        let GeometrySpec::Mesh { uri, scale } = &g.spec else {
            replaced.push(original.clone());
            continue;
        };
        let mesh = read_link_mesh(&source.urdf, link, uri, *scale, &source.package_dirs)?;
        let placement: SE3 = frame.placement * g.origin;
        let mut order: Vec<usize> = (0..mesh.triangles.len()).collect();
        let mut leaves = Vec::new();
        split(&mesh, &mut order, patch.max(1), &mut leaves);
        for leaf in leaves {
            let mut v: Vec<Vector3<f64>> = leaf
                .iter()
                .flat_map(|&t| mesh.triangles[t].map(|i| mesh.vertices[i as usize]))
                .collect();
            v.sort_by(|a, b| {
                a.iter()
                    .zip(b.iter())
                    .map(|(x, y)| x.total_cmp(y))
                    .find(|o| o.is_ne())
                    .unwrap_or(std::cmp::Ordering::Equal)
            });
            v.dedup();
            let centre = v.iter().fold(Vector3::zeros(), |s, p| s + p) / v.len() as f64;
            let radius = v.iter().map(|p| (p - centre).norm()).fold(0.0, f64::max);
            replaced.push(GeometryObject {
                link: li,
                joint: original.joint,
                placement,
                shape: Convex::Hull {
                    vertices: v,
                    neighbours: Vec::new(),
                },
                hull_faces: Vec::new(),
                // One triangle, measured as its own hull: no mesh for the exact queries.
                mesh: None,
                bounding_centre: centre,
                bounding_radius: radius,
            });
        }
    }
    let mut out = gm.clone();
    let n_new = replaced.len();
    out.objects
        .splice(old.first..old.first + old.count, replaced);
    let shift = n_new as isize - old.count as isize;
    out.links[li] = LinkGeometry {
        count: n_new,
        ..old.clone()
    };
    for l in out.links.iter_mut().skip(li + 1) {
        l.first = (l.first as isize + shift) as usize;
    }
    Ok(out)
}

/// The volume a link's mesh hulls hold over the volume its meshes hold: 1 for convex
/// meshes, larger the more concave they are (`None` for a link without meshes).
fn concavity(gm: &GeometryModel, li: usize, source: &MeshSource) -> Result<Option<f64>> {
    let link = &gm.links[li];
    let signed = |v: &[Vector3<f64>], faces: &mut dyn Iterator<Item = [u32; 3]>| -> f64 {
        faces
            .map(|f| {
                let [a, b, c] = f.map(|i| v[i as usize]);
                a.dot(&b.cross(&c)) / 6.0
            })
            .sum::<f64>()
            .abs()
    };
    let mut hull = 0.0;
    for o in &gm.objects[link.first..link.first + link.count] {
        if let Convex::Hull { vertices, .. } = &o.shape {
            hull += signed(vertices, &mut o.hull_faces.iter().copied());
        }
    }
    let mut mesh = 0.0;
    let meshes = link_meshes(&link.name, source)?;
    for m in &meshes {
        mesh += signed(&m.vertices, &mut m.triangles.iter().copied());
    }
    Ok((!meshes.is_empty() && hull > 0.0).then(|| hull / mesh.max(1e-12)))
}

/// The meshes of a link's collision elements, in the elements' frames.
fn link_meshes(link: &str, source: &MeshSource) -> Result<Vec<TriangleMesh>> {
    let text = std::fs::read_to_string(&source.urdf).map_err(|e| Error::Io {
        path: source.urdf.clone(),
        source: e,
    })?;
    let elements = read_urdf_geometry(&text, &source.urdf.display().to_string())?;
    let mut out = Vec::new();
    for g in elements.collisions.iter().filter(|g| g.link == link) {
        if let GeometrySpec::Mesh { uri, scale } = &g.spec {
            out.push(read_link_mesh(
                &source.urdf,
                link,
                uri,
                *scale,
                &source.package_dirs,
            )?);
        }
    }
    Ok(out)
}

/// For each of `states` in turn (the start first, then a goal state): while the state's
/// closest pair is two links within `margin`, swaps one of them for its mesh surface and
/// looks again. A link not yet swapped goes first (of the pair's two, the one whose hull
/// volume exceeds its mesh volume the most: the more concave one), in patches of
/// [`PATCH_TRIANGLES`]; when both are swapped (or the other has no mesh) and the pair is
/// still in contact, the one with the larger patches is swapped again with patches half
/// as large, down to single triangles, since a patch's hull still fills the hollow between
/// its triangles. Returns the geometry and the links swapped (in order of their first
/// swap).
///
/// A state of the wrong length or with a non-finite coordinate is skipped: the planner's
/// check of it names it.
///
/// A goal state's swaps are as sound as the start's: the planner reaches the goal along a
/// motion checked continuously from the start, so the surfaces would meet before one body
/// could end up inside the other.
///
/// # Errors
/// Read errors of the URDF and mesh files; the checker's errors.
pub fn surface_links_for_states(
    model: &Model,
    gm: &GeometryModel,
    scene: &Scene,
    group: &JointGroup,
    states: &[&[f64]],
    margin: f64,
    source: &MeshSource,
) -> Result<(GeometryModel, Vec<String>)> {
    let mut current = gm.clone();
    // The swapped links and their patch sizes, in order of their first swap.
    let mut swapped: Vec<(String, usize)> = Vec::new();
    let weights = vec![1.0; group.dim()];
    let mut x = vec![0.0; group.dim()];
    // Each round swaps a new link or halves a patch size: bounded by this many rounds.
    let rounds = gm.links.len() * (1 + PATCH_TRIANGLES.ilog2() as usize);
    for state in states
        .iter()
        .filter(|q| q.len() == model.nq && q.iter().all(|v| v.is_finite()))
    {
        group.extract(state, &mut x);
        for _ in 0..rounds {
            let closest = {
                let mut checker =
                    ClearanceChecker::new(model, &current, scene, group, state, margin, &weights)?;
                checker.distance_report(&x)
            };
            // Only link–link contacts: a scene object inside a link's surface would not be
            // seen.
            let Some(c) = closest.filter(|c| c.distance <= margin && !c.scene_object) else {
                break;
            };
            let candidates = [c.link, c.other];
            let mut pick: Option<(String, f64)> = None;
            for name in candidates
                .iter()
                .filter(|name| swapped.iter().all(|(s, _)| s != *name))
            {
                let Some(li) = current.link_index(name) else {
                    continue;
                };
                if let Some(r) = concavity(&current, li, source)?
                    && pick.as_ref().is_none_or(|p| r > p.1)
                {
                    pick = Some((name.clone(), r));
                }
            }
            if let Some((name, _)) = pick {
                current = with_mesh_surface(model, &current, source, &name, PATCH_TRIANGLES)?;
                swapped.push((name, PATCH_TRIANGLES));
                continue;
            }
            // Both swapped and still in contact (a pair merely within the margin is left
            // as it is: the planner's margin shrinks to half the start's clearance): the
            // larger patches are halved, every swap redone from `gm`.
            if c.distance > 0.0 {
                break;
            }
            let Some(k) = (0..swapped.len())
                .filter(|&k| candidates.contains(&swapped[k].0) && swapped[k].1 > 1)
                .max_by_key(|&k| swapped[k].1)
            else {
                break;
            };
            swapped[k].1 /= 2;
            current = gm.clone();
            for (name, patch) in &swapped {
                current = with_mesh_surface(model, &current, source, name, *patch)?;
            }
        }
    }
    Ok((current, swapped.into_iter().map(|(name, _)| name).collect()))
}

/// Triangles per surface patch when a link is first swapped for its surface.
pub const PATCH_TRIANGLES: usize = 8;

/// Splits the triangles `order` at the median centroid along the longest axis of their
/// centroids' box until at most `patch` remain: neighbouring triangles end up in one
/// patch.
fn split(mesh: &TriangleMesh, order: &mut [usize], patch: usize, leaves: &mut Vec<Vec<usize>>) {
    if order.len() <= patch {
        if !order.is_empty() {
            leaves.push(order.to_vec());
        }
        return;
    }
    let centroid = |t: usize| -> Vector3<f64> {
        mesh.triangles[t]
            .iter()
            .fold(Vector3::zeros(), |s, &i| s + mesh.vertices[i as usize])
            / 3.0
    };
    let (mut lo, mut hi) = (
        Vector3::repeat(f64::INFINITY),
        Vector3::repeat(f64::NEG_INFINITY),
    );
    for &t in order.iter() {
        let c = centroid(t);
        lo = lo.inf(&c);
        hi = hi.sup(&c);
    }
    let axis = (hi - lo).imax();
    order.sort_by(|&a, &b| centroid(a)[axis].total_cmp(&centroid(b)[axis]));
    let mid = order.len() / 2;
    let (left, right) = order.split_at_mut(mid);
    split(mesh, left, patch, leaves);
    split(mesh, right, patch, leaves);
}

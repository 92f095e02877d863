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
use crate::collision::gjk::{WarmStart, overlaps};
use crate::collision::mesh::TriangleMesh;
use crate::collision::urdf_geometry::{GeometrySpec, read_link_mesh, read_urdf_geometry};
use crate::collision::{Convex, GeometryModel, GeometryObject, LinkGeometry, Scene};
use crate::kinematics::forward_kinematics;
use crate::multibody::{Data, FrameKind, Model};
use crate::spatial::SE3;
use crate::{Error, Result};
use nalgebra::{DVector, Vector3};
use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;

/// Where the URDF's meshes are: the file and the package folders.
#[derive(Clone, Debug)]
pub struct MeshSource {
    /// The URDF the model and geometry were loaded from.
    pub urdf: PathBuf,
    /// Folders `package://` URIs resolve against.
    pub package_dirs: Vec<PathBuf>,
}

/// How a link's mesh surface is cut into patches: the median splits of
/// [`with_mesh_surface`] down to at most `triangles` triangles, and further where a patch
/// was found in contact ([`surface_links_for_states`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Patching {
    /// Triangles per patch at most.
    pub triangles: usize,
    /// Patches split once more, each named by its mesh element's index among the link's
    /// collision elements and its triangles' indices (ascending).
    split: BTreeSet<(usize, Vec<usize>)>,
}

impl Patching {
    /// Patches of at most `triangles` triangles, nowhere finer.
    pub fn uniform(triangles: usize) -> Self {
        Self {
            triangles,
            split: BTreeSet::new(),
        }
    }

    /// The patches of element `element`'s mesh: its triangles split at the median centroid
    /// along the longest axis of their centroids' box while more than `triangles` remain
    /// or the set is one to split once more (neighbouring triangles end up in one patch).
    fn patches(&self, mesh: &TriangleMesh, element: usize) -> Vec<Vec<usize>> {
        let mut order: Vec<usize> = (0..mesh.triangles.len()).collect();
        let mut leaves = Vec::new();
        self.split_into(mesh, element, &mut order, &mut leaves);
        leaves
    }

    fn split_into(
        &self,
        mesh: &TriangleMesh,
        element: usize,
        order: &mut [usize],
        leaves: &mut Vec<Vec<usize>>,
    ) {
        if order.is_empty() {
            return;
        }
        let split_again = || {
            if self.split.is_empty() {
                return false;
            }
            let mut key = order.to_vec();
            key.sort_unstable();
            self.split.contains(&(element, key))
        };
        if order.len() == 1 || (order.len() <= self.triangles.max(1) && !split_again()) {
            leaves.push(order.to_vec());
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
        self.split_into(mesh, element, left, leaves);
        self.split_into(mesh, element, right, leaves);
    }
}

/// The link's mesh objects replaced by their triangles in patches of neighbouring
/// triangles as `patching` cuts them, each patch the convex hull of its triangles
/// (primitives kept).
///
/// # Errors
/// [`Error::InvalidInput`] naming the link when it has no geometry; the URDF's and the
/// mesh files' read errors (naming the file).
pub fn with_mesh_surface(
    model: &Model,
    gm: &GeometryModel,
    source: &MeshSource,
    link: &str,
    patching: &Patching,
) -> Result<GeometryModel> {
    surface_from_elements(model, gm, link, &link_elements(link, source)?, patching)
}

/// A link's collision elements (its origin in the link's frame and, for a mesh, the mesh
/// in the element's frame), as [`link_elements`] reads them.
type Elements = Vec<(SE3, Option<TriangleMesh>)>;

/// [`with_mesh_surface`] with the link's collision elements already read (`mine`).
fn surface_from_elements(
    model: &Model,
    gm: &GeometryModel,
    link: &str,
    mine: &[(SE3, Option<TriangleMesh>)],
    patching: &Patching,
) -> Result<GeometryModel> {
    let Some(li) = gm.link_index(link) else {
        return Err(Error::invalid(
            format!("link '{link}'"),
            "has no collision geometry",
        ));
    };
    let frame = model
        .frames
        .iter()
        .find(|f| f.kind == FrameKind::Body && f.name == link)
        .ok_or_else(|| Error::invalid(format!("link '{link}'"), "is not a body of the model"))?;
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
    for (k, (origin, mesh)) in mine.iter().enumerate() {
        let original = &gm.objects[old.first + k];
        let Some(mesh) = mesh else {
            replaced.push(original.clone());
            continue;
        };
        let placement: SE3 = frame.placement * *origin;
        for leaf in patching.patches(mesh, k) {
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
fn concavity(
    gm: &GeometryModel,
    li: usize,
    elements: &[(SE3, Option<TriangleMesh>)],
) -> Option<f64> {
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
    let mut meshes = 0;
    for m in elements.iter().filter_map(|(_, m)| m.as_ref()) {
        mesh += signed(&m.vertices, &mut m.triangles.iter().copied());
        meshes += 1;
    }
    (meshes > 0 && hull > 0.0).then(|| hull / mesh.max(1e-12))
}

/// A link's collision elements in the URDF's order: each one's origin in the link's frame
/// and, for a mesh, the mesh (in the element's frame).
fn link_elements(link: &str, source: &MeshSource) -> Result<Elements> {
    let text = std::fs::read_to_string(&source.urdf).map_err(|e| Error::Io {
        path: source.urdf.clone(),
        source: e,
    })?;
    let elements = read_urdf_geometry(&text, &source.urdf.display().to_string())?;
    let mut out = Vec::new();
    for g in elements.collisions.iter().filter(|g| g.link == link) {
        let mesh = match &g.spec {
            GeometrySpec::Mesh { uri, scale } => Some(read_link_mesh(
                &source.urdf,
                link,
                uri,
                *scale,
                &source.package_dirs,
            )?),
            _ => None,
        };
        out.push((g.origin, mesh));
    }
    Ok(out)
}

/// Marks to be split once more every patch of more than one triangle of `link`'s surface
/// (its `elements` cut as `patching`, the geometry `gm` built so) that overlaps one of
/// `other`'s objects at the placements of `data`; returns how many it marked.
fn split_patches_in_contact(
    data: &Data,
    gm: &GeometryModel,
    link: &str,
    other: &str,
    elements: &[(SE3, Option<TriangleMesh>)],
    patching: &mut Patching,
) -> usize {
    let (Some(li), Some(oi)) = (gm.link_index(link), gm.link_index(other)) else {
        return 0;
    };
    let world = |o: &GeometryObject| data.world_from_joint[o.joint.0].compose(&o.placement);
    let theirs = &gm.links[oi];
    let others: Vec<(&GeometryObject, SE3, Vector3<f64>)> = gm.objects
        [theirs.first..theirs.first + theirs.count]
        .iter()
        .map(|o| {
            let w = world(o);
            let centre = w.act_point(&o.bounding_centre);
            (o, w, centre)
        })
        .collect();
    let mine = &gm.links[li];
    let mut next = mine.first;
    let mut marked = Vec::new();
    for (k, (_, mesh)) in elements.iter().enumerate() {
        let Some(mesh) = mesh else {
            next += 1;
            continue;
        };
        for leaf in patching.patches(mesh, k) {
            let Some(o) = gm.objects[..mine.first + mine.count].get(next) else {
                return 0; // not the geometry `patching` built: nothing to tell
            };
            next += 1;
            if leaf.len() < 2 {
                continue;
            }
            let w = world(o);
            let centre = w.act_point(&o.bounding_centre);
            let touches = others.iter().any(|(p, pw, pc)| {
                (centre - pc).norm() <= o.bounding_radius + p.bounding_radius + 1e-9
                    && overlaps(&o.shape, &w, &p.shape, pw, &mut WarmStart::default())
            });
            if touches {
                let mut key = leaf;
                key.sort_unstable();
                marked.push((k, key));
            }
        }
    }
    let count = marked.len();
    patching.split.extend(marked);
    count
}

/// For each of `states` in turn (the start first, then a goal state): while the state's
/// closest pair is two links within `margin`, swaps one of them for its mesh surface and
/// looks again. While a swapped link is in contact with the other (a patch's hull still
/// fills the hollow between its triangles), each of its patches that overlaps the other
/// link is split in two, down to single triangles, the rest of its surface staying as it
/// was; otherwise a link not yet swapped is swapped (of the pair's two, the one whose
/// hull volume exceeds its mesh volume the most: the more concave one), in patches of
/// [`PATCH_TRIANGLES`]. Returns the geometry and the links swapped (in order of their
/// first swap).
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
    // The swapped links and how their surfaces are cut, in order of their first swap.
    let mut swapped: Vec<(String, Patching)> = Vec::new();
    // Each link's collision elements, read from the files once.
    let mut read: BTreeMap<String, Elements> = BTreeMap::new();
    let weights = vec![1.0; group.dim()];
    let mut x = vec![0.0; group.dim()];
    let mut data = Data::new(model);
    // Each round splits the patches in contact (at most log2 of the patch size times for
    // one pair) or swaps a new link: bounded by this many rounds.
    let rounds = gm.links.len() * (1 + PATCH_TRIANGLES.ilog2() as usize);
    for state in states
        .iter()
        .filter(|q| q.len() == model.nq && q.iter().all(|v| v.is_finite()))
    {
        group.extract(state, &mut x);
        forward_kinematics(model, &mut data, &DVector::from_column_slice(state));
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
            // In contact with a surface: the patches in contact are split first, every
            // swap redone from `gm` (a pair merely within the margin is left as it is:
            // the planner's margin shrinks to half the start's clearance).
            if c.distance <= 0.0 {
                let mut marked = 0;
                for (link, other) in [
                    (&candidates[0], &candidates[1]),
                    (&candidates[1], &candidates[0]),
                ] {
                    if let Some(k) = swapped.iter().position(|(s, _)| s == link) {
                        marked += split_patches_in_contact(
                            &data,
                            &current,
                            link,
                            other,
                            elements_of(&mut read, link, source)?,
                            &mut swapped[k].1,
                        );
                    }
                }
                if marked > 0 {
                    current = gm.clone();
                    for (name, patching) in &swapped {
                        let elements = elements_of(&mut read, name, source)?;
                        current = surface_from_elements(model, &current, name, elements, patching)?;
                    }
                    continue;
                }
            }
            let mut pick: Option<(String, f64)> = None;
            for name in candidates
                .iter()
                .filter(|name| swapped.iter().all(|(s, _)| s != *name))
            {
                let Some(li) = current.link_index(name) else {
                    continue;
                };
                if let Some(r) = concavity(&current, li, elements_of(&mut read, name, source)?)
                    && pick.as_ref().is_none_or(|p| r > p.1)
                {
                    pick = Some((name.clone(), r));
                }
            }
            let Some((name, _)) = pick else {
                break;
            };
            let patching = Patching::uniform(PATCH_TRIANGLES);
            let elements = elements_of(&mut read, &name, source)?;
            current = surface_from_elements(model, &current, &name, elements, &patching)?;
            swapped.push((name, patching));
        }
    }
    Ok((current, swapped.into_iter().map(|(name, _)| name).collect()))
}

/// The collision elements of `link` kept in `read`, read from the files the first time.
fn elements_of<'a>(
    read: &'a mut BTreeMap<String, Elements>,
    link: &str,
    source: &MeshSource,
) -> Result<&'a Elements> {
    if !read.contains_key(link) {
        let elements = link_elements(link, source)?;
        read.insert(link.to_string(), elements);
    }
    Ok(&read[link])
}

/// Triangles per surface patch when a link is first swapped for its surface.
pub const PATCH_TRIANGLES: usize = 8;

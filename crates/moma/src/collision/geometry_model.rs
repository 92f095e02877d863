//! `GeometryModel`: the robot's collision shapes, attached to the joints of the
//! rigid-body `Model`, and the link pairs to check.

use super::convex::Convex;
use super::mesh::{ConvexHullData, TriangleMesh, convex_hull_vertices};
use super::srdf::disabled_pairs;
use super::urdf_geometry::{GeometrySpec, UrdfGeometry, read_link_mesh, read_urdf_geometry};
use crate::multibody::{FrameKind, JointIndex, Model};
use crate::spatial::SE3;
use crate::{Error, Result};
use nalgebra::Vector3;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// One convex shape of a link.
#[derive(Clone, Debug)]
pub struct GeometryObject {
    /// Index of its link in [`GeometryModel::links`].
    pub link: usize,
    /// The joint whose body carries it.
    pub joint: JointIndex,
    /// `joint_from_object`: its placement in the joint frame (the link's fixed offset
    /// after merging fixed joints, times the element's `<origin>`).
    pub placement: SE3,
    /// The shape (a mesh becomes its convex hull).
    pub shape: Convex,
    /// Hull triangles for drawing (empty for primitives).
    pub hull_faces: Vec<[u32; 3]>,
    /// Centre (object frame) and radius of a ball that holds the shape.
    pub bounding_centre: Vector3<f64>,
    /// Radius of that ball.
    pub bounding_radius: f64,
    /// The mesh's triangles (object frame, scaled) for a mesh element, for exact
    /// distances ([`super::exact`]); `None` for primitives.
    pub mesh: Option<Arc<TriangleMesh>>,
}

/// A link with collision geometry.
#[derive(Clone, Debug)]
pub struct LinkGeometry {
    /// Link name.
    pub name: String,
    /// The joint whose body carries the link.
    pub joint: JointIndex,
    /// Its objects: `objects[first..first + count]`.
    pub first: usize,
    /// Number of objects.
    pub count: usize,
}

/// Where to find meshes and which pairs to drop.
#[derive(Clone, Debug, Default)]
pub struct GeometryOptions {
    /// Folders against which `package://` URIs resolve (as Pinocchio's `package_dirs`).
    pub package_dirs: Vec<PathBuf>,
    /// An SRDF whose `<disable_collisions>` pairs are not checked.
    pub srdf: Option<PathBuf>,
}

/// The robot's collision geometry: immutable after loading.
#[derive(Clone, Debug)]
pub struct GeometryModel {
    /// Links that carry geometry, in the order of their body frames in the `Model`.
    pub links: Vec<LinkGeometry>,
    /// All shapes, grouped by link.
    pub objects: Vec<GeometryObject>,
    /// Every pair of links `[a, b]` with `a < b` (indices into `links`).
    pub pairs: Vec<[usize; 2]>,
    /// Whether each pair of `pairs` is checked: not joined by one joint, not fixed to
    /// each other, not disabled by the SRDF.
    pub enabled: Vec<bool>,
}

impl GeometryModel {
    /// Reads the `<collision>` geometry of a URDF for `model` (loaded from the same file).
    ///
    /// # Errors
    /// [`Error::Io`] / [`Error::Parse`] naming the URDF or SRDF file and the element; for a
    /// mesh, the URDF file, the link and the URI, and why the URI does not resolve or the
    /// mesh file and what is wrong with it ([`read_link_mesh`]); an SRDF pair naming a
    /// link the URDF lacks.
    pub fn from_urdf(model: &Model, urdf: &Path, options: &GeometryOptions) -> Result<Self> {
        let text = std::fs::read_to_string(urdf).map_err(|source| Error::Io {
            path: urdf.to_path_buf(),
            source,
        })?;
        let elements = read_urdf_geometry(&text, &urdf.display().to_string())?;
        let mut gm = Self::from_elements(model, &elements.collisions, |g, uri, scale| {
            let mesh = read_link_mesh(urdf, &g.link, uri, scale, &options.package_dirs)?;
            Ok((convex_hull_vertices(&mesh.vertices), Arc::new(mesh)))
        })?;
        let adjacent: Vec<(usize, usize)> = elements
            .joints
            .iter()
            .filter_map(|(p, c)| Some((gm.link_index(p)?, gm.link_index(c)?)))
            .collect();
        let mut disabled: Vec<(usize, usize)> = Vec::new();
        if let Some(srdf) = &options.srdf {
            let stext = std::fs::read_to_string(srdf).map_err(|source| Error::Io {
                path: srdf.clone(),
                source,
            })?;
            for (k, p) in disabled_pairs(&stext, &srdf.display().to_string())?
                .iter()
                .enumerate()
            {
                for l in [&p.link1, &p.link2] {
                    if !elements.links.contains(l) {
                        return Err(Error::parse(
                            srdf,
                            format!(
                                "disable_collisions element {} names link '{l}', which the URDF lacks",
                                k + 1
                            ),
                        ));
                    }
                }
                if let (Some(a), Some(b)) = (gm.link_index(&p.link1), gm.link_index(&p.link2)) {
                    disabled.push((a, b));
                }
            }
        }
        let has = |set: &[(usize, usize)], a: usize, b: usize| {
            set.iter()
                .any(|&(x, y)| (x, y) == (a, b) || (y, x) == (a, b))
        };
        gm.enabled = gm
            .pairs
            .iter()
            .map(|&[a, b]| {
                gm.links[a].joint != gm.links[b].joint
                    && !has(&adjacent, a, b)
                    && !has(&disabled, a, b)
            })
            .collect();
        Ok(gm)
    }

    /// Builds the model from parsed elements; `hull` turns a mesh URI into its hull.
    fn from_elements(
        model: &Model,
        elements: &[UrdfGeometry],
        mut hull: impl FnMut(
            &UrdfGeometry,
            &str,
            [f64; 3],
        ) -> Result<(ConvexHullData, Arc<TriangleMesh>)>,
    ) -> Result<Self> {
        let mut links: Vec<LinkGeometry> = Vec::new();
        let mut objects: Vec<GeometryObject> = Vec::new();
        // Body frames in model order: the link order.
        for frame in model.frames.iter().filter(|f| f.kind == FrameKind::Body) {
            let mine: Vec<&UrdfGeometry> =
                elements.iter().filter(|g| g.link == frame.name).collect();
            if mine.is_empty() {
                continue;
            }
            let li = links.len();
            let first = objects.len();
            for g in &mine {
                let mut mesh = None;
                let (shape, hull_faces) = match &g.spec {
                    GeometrySpec::Box(s) => (
                        Convex::Box {
                            half: Vector3::from(*s) / 2.0,
                        },
                        Vec::new(),
                    ),
                    GeometrySpec::Cylinder { radius, length } => (
                        Convex::Cylinder {
                            radius: *radius,
                            half_height: length / 2.0,
                        },
                        Vec::new(),
                    ),
                    GeometrySpec::Sphere { radius } => {
                        (Convex::Sphere { radius: *radius }, Vec::new())
                    }
                    GeometrySpec::Capsule { radius, length } => (
                        Convex::Capsule {
                            radius: *radius,
                            half_length: length / 2.0,
                        },
                        Vec::new(),
                    ),
                    GeometrySpec::Mesh { uri, scale } => {
                        let (h, m) = hull(g, uri, *scale)?;
                        mesh = Some(m);
                        (
                            Convex::Hull {
                                vertices: h.vertices,
                                neighbours: h.neighbours,
                            },
                            h.faces,
                        )
                    }
                };
                let (centre, _) = shape.local_aabb();
                let bounding_radius = bounding_radius_about(&shape, &centre);
                objects.push(GeometryObject {
                    link: li,
                    joint: frame.parent_joint,
                    placement: frame.placement * g.origin,
                    shape,
                    hull_faces,
                    bounding_centre: centre,
                    bounding_radius,
                    mesh,
                });
            }
            links.push(LinkGeometry {
                name: frame.name.clone(),
                joint: frame.parent_joint,
                first,
                count: objects.len() - first,
            });
        }
        if let Some(g) = elements
            .iter()
            .find(|g| !links.iter().any(|l| l.name == g.link))
        {
            return Err(Error::invalid(
                format!("link '{}' geometry", g.link),
                "the link is not a link of the model",
            ));
        }
        let n = links.len();
        let pairs: Vec<[usize; 2]> = (0..n)
            .flat_map(|a| ((a + 1)..n).map(move |b| [a, b]))
            .collect();
        let enabled = vec![true; pairs.len()];
        Ok(GeometryModel {
            links,
            objects,
            pairs,
            enabled,
        })
    }

    /// Index of a link in [`GeometryModel::links`].
    #[must_use]
    pub fn link_index(&self, name: &str) -> Option<usize> {
        self.links.iter().position(|l| l.name == name)
    }

    /// Number of enabled pairs.
    #[must_use]
    pub fn n_enabled(&self) -> usize {
        self.enabled.iter().filter(|e| **e).count()
    }
}

pub(super) fn bounding_radius_about(shape: &Convex, centre: &Vector3<f64>) -> f64 {
    match shape {
        Convex::Hull { vertices, .. } => vertices
            .iter()
            .map(|v| (v - centre).norm())
            .fold(0.0, f64::max),
        other => other.bounding_radius(),
    }
}

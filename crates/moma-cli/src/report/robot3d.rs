//! The 3-D view built from a robot: its URDF's shapes attached to the model's joints,
//! the joints' world poses for recorded configurations (moma's forward kinematics), and a
//! scene's objects.
//!
//! Each link is drawn with its `<visual>` elements when all of them are primitives or
//! STL/OBJ meshes; otherwise (COLLADA visuals, which no reader here handles, or no visual
//! at all) with its `<collision>` elements. A robot with no geometry at all is drawn as
//! its kinematic skeleton (a rod from each joint to its children, a ball at each joint).
//! Meshes above a triangle budget are simplified by vertex clustering.

use super::view3d::{MAX_TRIANGLES, ReportGeometry, ReportShape, ReportView3d};
use moma::collision::mesh::{TriangleMesh, convex_hull_vertices};
use moma::collision::urdf_geometry::{
    GeometrySpec, UrdfGeometry, read_link_mesh, read_urdf_geometry,
};
use moma::collision::{Convex, Scene};
use moma::multibody::{Data, FrameKind, JointIndex, Model};
use moma::spatial::SE3;
use nalgebra::{DVector, Vector3};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Triangles all of the robot's meshes may keep together (the scene gets the rest).
const ROBOT_TRIANGLES: usize = MAX_TRIANGLES / 2;

/// The robot's shapes on its moving bodies.
#[derive(Debug, Clone)]
pub struct RobotShapes {
    /// The model joints that carry shapes (one pose track each).
    pub joints: Vec<JointIndex>,
    /// Their names (the joint's name; `world` for the fixed root).
    pub bodies: Vec<String>,
    /// The shapes, `body` indexing `joints`.
    pub shapes: Vec<ReportShape>,
}

fn pose7(m: &SE3) -> [f64; 7] {
    let q = m.quaternion();
    let t = m.translation;
    [t.x, t.y, t.z, q.i, q.j, q.k, q.w]
}

fn drawable(g: &UrdfGeometry) -> bool {
    match &g.spec {
        GeometrySpec::Mesh { uri, .. } => {
            let l = uri.to_ascii_lowercase();
            l.ends_with(".stl") || l.ends_with(".obj")
        }
        _ => true,
    }
}

/// Vertex clustering: vertices snapped to a grid whose cell grows until at most `max`
/// triangles survive (collapsed and repeated triangles dropped); each cluster's vertex is
/// the mean of its members. A mesh within the budget is returned as it is.
pub(crate) fn simplify(mesh: &TriangleMesh, max: usize) -> (Vec<[f64; 3]>, Vec<[u32; 3]>) {
    let verts = |m: &[Vector3<f64>]| m.iter().map(|v| [v.x, v.y, v.z]).collect::<Vec<_>>();
    if mesh.triangles.len() <= max || mesh.vertices.is_empty() {
        return (verts(&mesh.vertices), mesh.triangles.clone());
    }
    let (mut lo, mut hi) = (mesh.vertices[0], mesh.vertices[0]);
    for v in &mesh.vertices {
        lo = lo.inf(v);
        hi = hi.sup(v);
    }
    let mut cell = ((hi - lo).norm() / 400.0).max(1e-6);
    loop {
        let mut index: HashMap<[i64; 3], u32> = HashMap::new();
        let mut sums: Vec<(Vector3<f64>, f64)> = Vec::new();
        let map: Vec<u32> = mesh
            .vertices
            .iter()
            .map(|v| {
                let key = [0, 1, 2].map(|a| ((v[a] - lo[a]) / cell).floor() as i64);
                let k = *index.entry(key).or_insert_with(|| {
                    sums.push((Vector3::zeros(), 0.0));
                    (sums.len() - 1) as u32
                });
                sums[k as usize].0 += v;
                sums[k as usize].1 += 1.0;
                k
            })
            .collect();
        let mut seen = std::collections::HashSet::new();
        let tris: Vec<[u32; 3]> = mesh
            .triangles
            .iter()
            .map(|t| t.map(|i| map[i as usize]))
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .filter(|t| {
                let mut k = *t;
                k.sort_unstable();
                seen.insert(k)
            })
            .collect();
        if tris.len() <= max {
            let vs = sums
                .iter()
                .map(|(s, n)| [s.x / n, s.y / n, s.z / n])
                .collect();
            return (vs, tris);
        }
        cell *= 1.5;
    }
}

fn primitive(spec: &GeometrySpec) -> Option<ReportGeometry> {
    Some(match spec {
        GeometrySpec::Box(s) => ReportGeometry::Box { size: *s },
        GeometrySpec::Cylinder { radius, length } => ReportGeometry::Cylinder {
            radius: *radius,
            length: *length,
        },
        GeometrySpec::Sphere { radius } => ReportGeometry::Sphere { radius: *radius },
        GeometrySpec::Capsule { radius, length } => ReportGeometry::Capsule {
            radius: *radius,
            length: *length,
        },
        GeometrySpec::Mesh { .. } => return None,
    })
}

impl RobotShapes {
    /// Reads the URDF's shapes for `model` (loaded from the same file). `package://` URIs
    /// resolve against `package_dirs`, then the folders above the URDF (a URDF inside its
    /// own package, as ROS lays it out), then `ROS_PACKAGE_PATH`.
    ///
    /// # Errors
    /// The URDF or a mesh that cannot be read or resolved (naming the file, the link and
    /// the URI), a link the model lacks.
    pub fn from_urdf(urdf: &Path, model: &Model, package_dirs: &[PathBuf]) -> moma::Result<Self> {
        let text = std::fs::read_to_string(urdf).map_err(|source| moma::Error::Io {
            path: urdf.to_path_buf(),
            source,
        })?;
        let el = read_urdf_geometry(&text, &urdf.display().to_string())?;
        let dir = urdf.parent().unwrap_or(Path::new("."));
        let mut dirs = package_dirs.to_vec();
        dirs.extend(dir.ancestors().skip(1).take(3).map(Path::to_path_buf));
        // per link: its visuals when all are drawable, else its collisions
        let mut chosen: Vec<&UrdfGeometry> = Vec::new();
        for link in &el.links {
            let vis: Vec<&UrdfGeometry> = el.visuals.iter().filter(|g| &g.link == link).collect();
            let col: Vec<&UrdfGeometry> =
                el.collisions.iter().filter(|g| &g.link == link).collect();
            if !vis.is_empty() && vis.iter().all(|g| drawable(g)) || col.is_empty() {
                chosen.extend(vis.into_iter().filter(|g| drawable(g)));
            } else {
                chosen.extend(col.into_iter().filter(|g| drawable(g)));
            }
        }
        let mut meshes: Vec<Option<TriangleMesh>> = Vec::with_capacity(chosen.len());
        for g in &chosen {
            meshes.push(match &g.spec {
                GeometrySpec::Mesh { uri, scale } => {
                    Some(read_link_mesh(urdf, &g.link, uri, *scale, &dirs)?)
                }
                _ => None,
            });
        }
        let n_meshes = meshes.iter().flatten().count().max(1);
        let budget = (ROBOT_TRIANGLES / n_meshes).max(100);
        let mut out = RobotShapes {
            joints: Vec::new(),
            bodies: Vec::new(),
            shapes: Vec::new(),
        };
        for (g, mesh) in chosen.iter().zip(&meshes) {
            let frame = model
                .frames
                .iter()
                .find(|f| f.kind == FrameKind::Body && f.name == g.link)
                .ok_or_else(|| {
                    moma::Error::invalid(
                        format!("{}: link '{}'", urdf.display(), g.link),
                        "the link is not a body of the model",
                    )
                })?;
            let geometry = match mesh {
                Some(m) => {
                    let (vertices, triangles) = simplify(m, budget);
                    ReportGeometry::Mesh {
                        vertices,
                        triangles,
                    }
                }
                None => primitive(&g.spec).expect("a primitive"),
            };
            let body = out.body(model, frame.parent_joint);
            out.shapes.push(ReportShape {
                body,
                name: g.link.clone(),
                pose: pose7(&(frame.placement * g.origin)),
                geometry,
            });
        }
        if out.shapes.is_empty() {
            out.skeleton(model);
        }
        Ok(out)
    }

    /// Index of `joint`'s pose track (added on first use).
    fn body(&mut self, model: &Model, joint: JointIndex) -> usize {
        if let Some(k) = self.joints.iter().position(|&j| j == joint) {
            return k;
        }
        self.joints.push(joint);
        self.bodies.push(model.names[joint.0].clone());
        self.joints.len() - 1
    }

    /// The kinematic skeleton: a ball at each joint, a rod to each child joint and to
    /// each body frame away from its joint's origin.
    fn skeleton(&mut self, model: &Model) {
        const ROD: f64 = 0.025;
        let rod = |s: &mut Self, j: JointIndex, to: Vector3<f64>, name: &str| {
            let len = to.norm();
            if len < 1e-4 {
                return;
            }
            // a cylinder along z turned onto the segment, centred on its middle
            let rot = nalgebra::UnitQuaternion::rotation_between(&Vector3::z(), &to)
                .unwrap_or_else(|| {
                    nalgebra::UnitQuaternion::from_axis_angle(
                        &Vector3::x_axis(),
                        std::f64::consts::PI,
                    )
                });
            let c = to / 2.0;
            let body = s.body(model, j);
            s.shapes.push(ReportShape {
                body,
                name: name.to_string(),
                pose: [c.x, c.y, c.z, rot.i, rot.j, rot.k, rot.w],
                geometry: ReportGeometry::Cylinder {
                    radius: ROD,
                    length: len,
                },
            });
        };
        for j in 1..model.njoints {
            let body = self.body(model, JointIndex(j));
            self.shapes.push(ReportShape {
                body,
                name: model.names[j].clone(),
                pose: [0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0],
                geometry: ReportGeometry::Sphere { radius: 1.8 * ROD },
            });
            let p = model.parents[j];
            if p.0 > 0 {
                rod(
                    self,
                    p,
                    model.joint_placements[j].translation,
                    &model.names[j],
                );
            }
        }
        for f in model.frames.iter().filter(|f| f.kind == FrameKind::Body) {
            if f.parent_joint.0 > 0 {
                rod(self, f.parent_joint, f.placement.translation, &f.name);
            }
        }
    }

    /// The view for configurations `qs` at times `t` (frames thinned to at most `max`
    /// evenly spaced ones, first and last kept), with `scene`'s shapes.
    ///
    /// # Errors
    /// A configuration whose length is not the model's `nq` (naming the sample).
    pub fn view(
        &self,
        model: &Model,
        t: &[f64],
        qs: &[Vec<f64>],
        max: usize,
        scene: Vec<ReportShape>,
    ) -> moma::Result<ReportView3d> {
        let idx = super::numbers::decimate_indices(t.len().min(qs.len()), max, &[]);
        let mut data = Data::new(model);
        let mut poses = Vec::with_capacity(idx.len());
        for &i in &idx {
            if qs[i].len() != model.nq {
                return Err(moma::Error::invalid(
                    format!("sample {i} configuration"),
                    format!("{} values for the model's nq = {}", qs[i].len(), model.nq),
                ));
            }
            moma::kinematics::forward_kinematics(
                model,
                &mut data,
                &DVector::from_column_slice(&qs[i]),
            );
            poses.push(
                self.joints
                    .iter()
                    .map(|j| {
                        if j.0 == 0 {
                            pose7(&SE3::identity())
                        } else {
                            pose7(&data.world_from_joint[j.0])
                        }
                    })
                    .collect(),
            );
        }
        Ok(ReportView3d {
            t: idx.iter().map(|&i| t[i]).collect(),
            bodies: self.bodies.clone(),
            poses,
            robot: self.shapes.clone(),
            scene,
        })
    }
}

/// A scene's objects as world shapes (a mesh object's convex pieces as their hulls).
pub fn scene_shapes(scene: &Scene) -> Vec<ReportShape> {
    let mut out = Vec::new();
    for o in &scene.objects {
        for s in &o.shapes {
            let geometry = match &s.shape {
                Convex::Box { half } => ReportGeometry::Box {
                    size: [2.0 * half.x, 2.0 * half.y, 2.0 * half.z],
                },
                Convex::Cylinder {
                    radius,
                    half_height,
                } => ReportGeometry::Cylinder {
                    radius: *radius,
                    length: 2.0 * half_height,
                },
                Convex::Sphere { radius } => ReportGeometry::Sphere { radius: *radius },
                Convex::Capsule {
                    radius,
                    half_length,
                } => ReportGeometry::Capsule {
                    radius: *radius,
                    length: 2.0 * half_length,
                },
                Convex::Hull { vertices, .. } => {
                    let h = convex_hull_vertices(vertices);
                    ReportGeometry::Mesh {
                        vertices: h.vertices.iter().map(|v| [v.x, v.y, v.z]).collect(),
                        triangles: h.faces,
                    }
                }
            };
            out.push(ReportShape {
                body: 0,
                name: o.id.clone(),
                pose: pose7(&s.pose),
                geometry,
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use moma::multibody::RootJoint;

    fn repo(p: &str) -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(p)
    }

    #[test]
    fn the_mission_robot_is_drawn_from_its_primitives_at_the_recorded_poses() {
        let urdf = repo("scenarios/robots/mobile_manipulator.urdf");
        let model = moma::io::urdf::model_from_urdf_file(&urdf, RootJoint::Planar).unwrap();
        let shapes = RobotShapes::from_urdf(&urdf, &model, &[]).unwrap();
        assert_eq!(shapes.shapes.len(), 14);
        let boxes = shapes
            .shapes
            .iter()
            .filter(|s| matches!(s.geometry, ReportGeometry::Box { size } if size == [0.60, 0.44, 0.24]))
            .count();
        assert_eq!(boxes, 1, "the chassis");
        // base at (1, 2) facing +y, arm at zero: the shoulder pan joint sits 0.12 m ahead
        // of the axle (now along +y) and 0.34 + 0.089 m up (the URDF's origins)
        let mut q = moma::multibody::neutral(&model).as_slice().to_vec();
        q[..3].copy_from_slice(&[1.0, 2.0, std::f64::consts::FRAC_PI_2]);
        let v = shapes
            .view(&model, &[0.0, 1.0], &[q.clone(), q], 600, Vec::new())
            .unwrap();
        assert_eq!(v.check(), Ok(()));
        let k = v
            .bodies
            .iter()
            .position(|b| b == "shoulder_pan_joint")
            .unwrap();
        let p = v.poses[1][k];
        for (got, want) in p[..3].iter().zip([1.0, 2.12, 0.429]) {
            assert!((got - want).abs() < 1e-12, "{p:?}");
        }
        // a yaw of 90°: quaternion (0, 0, sin 45°, cos 45°)
        let h = std::f64::consts::FRAC_1_SQRT_2;
        for (got, want) in p[3..].iter().zip([0.0, 0.0, h, h]) {
            assert!((got - want).abs() < 1e-12, "{p:?}");
        }
        let short = vec![0.0; model.nq - 1];
        let e = shapes
            .view(&model, &[0.0], &[short], 600, Vec::new())
            .unwrap_err();
        assert!(e.to_string().contains("sample 0"), "{e}");
    }

    #[test]
    fn fetch_links_with_collada_visuals_fall_back_to_their_collision_meshes() {
        let urdf = repo("crates/moma/tests/data/robots/fetch/fetch_description/robots/fetch.urdf");
        let model = moma::io::urdf::model_from_urdf_file(&urdf, RootJoint::Fixed).unwrap();
        let shapes = RobotShapes::from_urdf(&urdf, &model, &[]).unwrap();
        let text = std::fs::read_to_string(&urdf).unwrap();
        let el = read_urdf_geometry(&text, "fetch.urdf").unwrap();
        let dae_links: Vec<&String> = el
            .visuals
            .iter()
            .filter(|g| !drawable(g))
            .map(|g| &g.link)
            .collect();
        assert!(dae_links.len() >= 10, "{dae_links:?}");
        let mut triangles = 0;
        for s in &shapes.shapes {
            let ReportGeometry::Mesh { triangles: t, .. } = &s.geometry else {
                continue;
            };
            triangles += t.len();
        }
        // every link with a COLLADA visual is drawn (from its collision mesh)
        for l in &dae_links {
            assert!(
                shapes.shapes.iter().any(|s| &&s.name == l),
                "link {l} is not drawn"
            );
        }
        assert!(triangles <= ROBOT_TRIANGLES, "{triangles} triangles");
        assert!(
            triangles > 5_000,
            "{triangles} triangles: too coarse to recognise"
        );
    }

    #[test]
    fn simplification_keeps_within_the_budget_and_the_extent() {
        // a finely tessellated unit sphere: 80 × 160 quads
        let (nu, nv) = (80usize, 160usize);
        let mut vertices = Vec::new();
        for i in 0..=nu {
            let th = std::f64::consts::PI * i as f64 / nu as f64;
            for j in 0..nv {
                let ph = 2.0 * std::f64::consts::PI * j as f64 / nv as f64;
                vertices.push(Vector3::new(
                    th.sin() * ph.cos(),
                    th.sin() * ph.sin(),
                    th.cos(),
                ));
            }
        }
        let mut triangles = Vec::new();
        for i in 0..nu {
            for j in 0..nv {
                let a = (i * nv + j) as u32;
                let b = (i * nv + (j + 1) % nv) as u32;
                let (c, d) = (a + nv as u32, b + nv as u32);
                triangles.push([a, c, b]);
                triangles.push([b, c, d]);
            }
        }
        let mesh = TriangleMesh {
            vertices,
            triangles,
        };
        let (v, t) = simplify(&mesh, 2000);
        assert!(t.len() <= 2000 && t.len() > 300, "{} triangles", t.len());
        let r: Vec<f64> = v
            .iter()
            .map(|p| (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt())
            .collect();
        let (lo, hi) = r
            .iter()
            .fold((f64::MAX, 0.0f64), |(l, h), x| (l.min(*x), h.max(*x)));
        assert!(lo > 0.9 && hi <= 1.0 + 1e-12, "radii {lo}..{hi}");
        assert!(t.iter().flatten().all(|&i| (i as usize) < v.len()));
    }

    #[test]
    fn a_robot_without_geometry_is_drawn_as_its_skeleton() {
        let urdf = r#"<robot name="r"><link name="a"/><link name="b"/><link name="c"/>
          <joint name="j1" type="revolute"><parent link="a"/><child link="b"/>
          <origin xyz="0 0 0.5"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
          <joint name="j2" type="revolute"><parent link="b"/><child link="c"/>
          <origin xyz="0.4 0 0"/><axis xyz="0 1 0"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
          </robot>"#;
        let dir = std::env::temp_dir().join(format!("moma-skeleton-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("r.urdf");
        std::fs::write(&path, urdf).unwrap();
        let model = moma::io::urdf::model_from_urdf_str(urdf, RootJoint::Fixed, "r.urdf").unwrap();
        let shapes = RobotShapes::from_urdf(&path, &model, &[]).unwrap();
        let _ = std::fs::remove_dir_all(&dir);
        // two joint balls and the rod from j1 to j2 (0.4 m)
        let rods: Vec<f64> = shapes
            .shapes
            .iter()
            .filter_map(|s| match s.geometry {
                ReportGeometry::Cylinder { length, .. } => Some(length),
                _ => None,
            })
            .collect();
        assert_eq!(rods, [0.4]);
        assert_eq!(shapes.shapes.len(), 3);
    }
}

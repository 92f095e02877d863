//! The 3-D view's data: the robot's shapes attached to its moving bodies, each body's
//! world pose over time (computed by moma's forward kinematics when the report is built,
//! so the page only interpolates and never re-implements kinematics), and static scene
//! shapes; and its compact form on the page (frames thinned, poses as integers, meshes as
//! base64 of 16-bit grid coordinates).

use super::numbers::{decimate_indices, num};
use crate::svg_map::b64;
use serde::{Deserialize, Serialize};
use serde_json::{Value, json};

/// Most pose frames the page receives (evenly spaced; the page interpolates between them).
pub const MAX_FRAMES: usize = 600;
/// Most triangles of all meshes together on the page (the report's builder simplifies
/// meshes to fit; [`MissionReport::check`](super::MissionReport::check) refuses more).
pub const MAX_TRIANGLES: usize = 60_000;
/// Most shapes (robot and scene together) on the page.
pub const MAX_SHAPES: usize = 20_000;

/// The robot and the scene in 3-D.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub struct ReportView3d {
    /// Times of the pose frames, s (increasing).
    pub t: Vec<f64>,
    /// Names of the moving bodies (one pose track each).
    pub bodies: Vec<String>,
    /// Per frame, per body: the world pose `[x, y, z, qx, qy, qz, qw]` (m, unit quaternion).
    pub poses: Vec<Vec<[f64; 7]>>,
    /// The robot's shapes, each on one body.
    pub robot: Vec<ReportShape>,
    /// Static shapes in the world (`body` ignored): a scene's objects.
    pub scene: Vec<ReportShape>,
}

/// One shape placed on a body (or in the world, for the scene).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ReportShape {
    /// Index into [`ReportView3d::bodies`] (robot shapes).
    pub body: usize,
    /// The link or scene object it belongs to.
    pub name: String,
    /// Its pose in the body frame (world for the scene): `[x, y, z, qx, qy, qz, qw]`.
    pub pose: [f64; 7],
    /// The geometry.
    pub geometry: ReportGeometry,
}

/// A primitive (URDF conventions: cylinders along z, full box sides) or a triangle mesh.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum ReportGeometry {
    /// Full side lengths, m.
    Box {
        /// x, y, z sides.
        size: [f64; 3],
    },
    /// Along z.
    Cylinder {
        /// Radius, m.
        radius: f64,
        /// Length, m.
        length: f64,
    },
    /// A ball.
    Sphere {
        /// Radius, m.
        radius: f64,
    },
    /// Along z: a cylinder of `length` with hemispherical caps.
    Capsule {
        /// Radius, m.
        radius: f64,
        /// Length of the cylindrical part, m.
        length: f64,
    },
    /// Triangles over shared vertices (shape frame, m).
    Mesh {
        /// Vertices.
        vertices: Vec<[f64; 3]>,
        /// Vertex indices, counter-clockwise seen from outside.
        triangles: Vec<[u32; 3]>,
    },
}

impl ReportView3d {
    /// Checks the shape of the data, naming the field at fault.
    pub fn check(&self) -> Result<(), String> {
        if self.poses.len() != self.t.len() {
            return Err(format!(
                "view3d.poses: {} frames for {} times",
                self.poses.len(),
                self.t.len()
            ));
        }
        let nb = self.bodies.len();
        for (k, row) in self.poses.iter().enumerate() {
            if row.len() != nb {
                return Err(format!(
                    "view3d.poses[{k}]: {} poses for {nb} bodies",
                    row.len()
                ));
            }
            if row.iter().flatten().any(|x| !x.is_finite()) {
                return Err(format!("view3d.poses[{k}]: a value is not finite"));
            }
        }
        if self.t.iter().any(|t| !t.is_finite()) || self.t.windows(2).any(|w| w[1] < w[0]) {
            return Err("view3d.t: the times are not finite and increasing".into());
        }
        if self.robot.len() + self.scene.len() > MAX_SHAPES {
            return Err(format!(
                "view3d: {} shapes exceed the limit of {MAX_SHAPES}",
                self.robot.len() + self.scene.len()
            ));
        }
        let mut triangles = 0usize;
        for (list, name) in [(&self.robot, "robot"), (&self.scene, "scene")] {
            for (k, s) in list.iter().enumerate() {
                let at = format!("view3d.{name}[{k}] ({})", s.name);
                if name == "robot" && s.body >= nb {
                    return Err(format!("{at}.body: {} for {nb} bodies", s.body));
                }
                if s.pose.iter().any(|x| !x.is_finite()) {
                    return Err(format!("{at}.pose: a value is not finite"));
                }
                let sizes: Vec<f64> = match &s.geometry {
                    ReportGeometry::Box { size } => size.to_vec(),
                    ReportGeometry::Cylinder { radius, length }
                    | ReportGeometry::Capsule { radius, length } => vec![*radius, *length],
                    ReportGeometry::Sphere { radius } => vec![*radius],
                    ReportGeometry::Mesh {
                        vertices,
                        triangles: tris,
                    } => {
                        triangles += tris.len();
                        let n = vertices.len();
                        if let Some(t) = tris.iter().find(|t| t.iter().any(|&i| i as usize >= n)) {
                            return Err(format!(
                                "{at}.triangles: index {} for {n} vertices",
                                t.iter().max().unwrap_or(&0)
                            ));
                        }
                        vertices.iter().flatten().copied().collect()
                    }
                };
                if sizes.iter().any(|x| !x.is_finite()) {
                    return Err(format!("{at}.geometry: a value is not finite"));
                }
            }
        }
        if triangles > MAX_TRIANGLES {
            return Err(format!(
                "view3d: {triangles} mesh triangles exceed the limit of {MAX_TRIANGLES}"
            ));
        }
        Ok(())
    }
}

/// Metres as whole millimetres, unit quaternion components as 1e-4 steps: plenty for a
/// picture, a third of the text of decimals.
fn pose_ints(p: &[f64; 7], out: &mut Vec<Value>) {
    for (k, x) in p.iter().enumerate() {
        let s = if k < 3 { 1e3 } else { 1e4 };
        out.push(json!((x * s).round() as i64));
    }
}

/// A mesh on the page: its bounding box, the vertices as base64 of little-endian u16
/// triples on a 65,535-step grid over that box (under 0.02 mm for a 1 m part), the
/// triangles as base64 of little-endian u16 (or u32 for more than 65,536 vertices).
fn mesh_value(vertices: &[[f64; 3]], triangles: &[[u32; 3]]) -> Value {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for v in vertices {
        for a in 0..3 {
            lo[a] = lo[a].min(v[a]);
            hi[a] = hi[a].max(v[a]);
        }
    }
    if vertices.is_empty() {
        lo = [0.0; 3];
        hi = [0.0; 3];
    }
    let mut vb = Vec::with_capacity(vertices.len() * 6);
    for v in vertices {
        for a in 0..3 {
            let span = hi[a] - lo[a];
            let q = if span > 0.0 {
                ((v[a] - lo[a]) / span * 65535.0).round() as u16
            } else {
                0
            };
            vb.extend_from_slice(&q.to_le_bytes());
        }
    }
    let wide = vertices.len() > 65_536;
    let mut fb = Vec::with_capacity(triangles.len() * if wide { 12 } else { 6 });
    for &i in triangles.iter().flatten() {
        if wide {
            fb.extend_from_slice(&i.to_le_bytes());
        } else {
            fb.extend_from_slice(&(i as u16).to_le_bytes());
        }
    }
    let bx: Vec<Value> = lo.iter().chain(hi.iter()).map(|&x| num(x, 6)).collect();
    json!({ "box": bx, "v": b64(&vb), "f": b64(&fb), "wide": wide })
}

fn shape_value(s: &ReportShape) -> Value {
    let pose: Vec<Value> = s.pose.iter().map(|&x| num(x, 5)).collect();
    let g = match &s.geometry {
        ReportGeometry::Box { size } => {
            json!({ "type": "box", "size": [num(size[0], 5), num(size[1], 5), num(size[2], 5)] })
        }
        ReportGeometry::Cylinder { radius, length } => {
            json!({ "type": "cylinder", "r": num(*radius, 5), "l": num(*length, 5) })
        }
        ReportGeometry::Capsule { radius, length } => {
            json!({ "type": "capsule", "r": num(*radius, 5), "l": num(*length, 5) })
        }
        ReportGeometry::Sphere { radius } => json!({ "type": "sphere", "r": num(*radius, 5) }),
        ReportGeometry::Mesh {
            vertices,
            triangles,
        } => {
            let mut m = mesh_value(vertices, triangles);
            m["type"] = json!("mesh");
            m
        }
    };
    json!({ "b": s.body, "name": s.name, "p": pose, "g": g })
}

/// The view's part of the page data: frames thinned to [`MAX_FRAMES`], each frame's poses
/// flattened as integers (mm, 1e-4), the shapes.
pub(crate) fn page_value(v: &ReportView3d) -> Value {
    let idx = decimate_indices(v.t.len(), MAX_FRAMES, &[]);
    let mut flat = Vec::with_capacity(idx.len() * v.bodies.len() * 7);
    for &i in &idx {
        for p in &v.poses[i] {
            pose_ints(p, &mut flat);
        }
    }
    json!({
        "t": idx.iter().map(|&i| num(v.t[i], 4)).collect::<Vec<_>>(),
        "bodies": v.bodies,
        "poses": flat,
        "robot": v.robot.iter().map(shape_value).collect::<Vec<_>>(),
        "scene": v.scene.iter().map(shape_value).collect::<Vec<_>>(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Standard base64 back to bytes (the page's `atob`).
    fn b64_decode(s: &str) -> Vec<u8> {
        const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut out = Vec::new();
        for c in s.as_bytes().chunks(4) {
            let v: Vec<u32> = c
                .iter()
                .filter(|&&b| b != b'=')
                .map(|b| T.iter().position(|t| t == b).unwrap() as u32)
                .collect();
            let n = v
                .iter()
                .enumerate()
                .fold(0u32, |n, (k, x)| n | x << (18 - 6 * k));
            out.extend((0..v.len() - 1).map(|k| (n >> (16 - 8 * k)) as u8));
        }
        out
    }

    fn unit() -> ReportView3d {
        ReportView3d {
            t: vec![0.0, 1.0],
            bodies: vec!["base".into()],
            poses: vec![vec![[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]]; 2],
            robot: vec![ReportShape {
                body: 0,
                name: "base".into(),
                pose: [0.0, 0.0, 0.1, 0.0, 0.0, 0.0, 1.0],
                geometry: ReportGeometry::Mesh {
                    vertices: vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.5, -0.25]],
                    triangles: vec![[0, 1, 2]],
                },
            }],
            scene: vec![],
        }
    }

    #[test]
    fn check_names_the_field_at_fault() {
        assert_eq!(unit().check(), Ok(()));
        let mut v = unit();
        v.poses.pop();
        assert_eq!(v.check().unwrap_err(), "view3d.poses: 1 frames for 2 times");
        let mut v = unit();
        v.robot[0].body = 3;
        assert_eq!(
            v.check().unwrap_err(),
            "view3d.robot[0] (base).body: 3 for 1 bodies"
        );
        let mut v = unit();
        if let ReportGeometry::Mesh { triangles, .. } = &mut v.robot[0].geometry {
            triangles[0][2] = 7;
        }
        assert_eq!(
            v.check().unwrap_err(),
            "view3d.robot[0] (base).triangles: index 7 for 3 vertices"
        );
        let mut v = unit();
        v.t[1] = -1.0;
        assert!(v.check().unwrap_err().starts_with("view3d.t"));
    }

    #[test]
    fn meshes_are_quantised_on_their_box_and_decode_back() {
        let v = unit();
        let page = page_value(&v);
        let g = &page["robot"][0]["g"];
        assert_eq!(g["type"], "mesh");
        let bx: Vec<f64> = serde_json::from_value(g["box"].clone()).unwrap();
        assert_eq!(bx, [0.0, 0.0, -0.25, 1.0, 0.5, 0.0]);
        // decode as the page does: u16 per coordinate over the box
        let bytes = b64_decode(g["v"].as_str().unwrap());
        let q: Vec<u16> = bytes
            .chunks(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]))
            .collect();
        assert_eq!(q, [0, 0, 65535, 65535, 0, 65535, 0, 65535, 0]);
        let f = b64_decode(g["f"].as_str().unwrap());
        assert_eq!(f, [0, 0, 1, 0, 2, 0]);
        // poses as integers: mm and 1e-4
        assert_eq!(
            page["poses"],
            json!([0, 0, 0, 0, 0, 0, 10000, 0, 0, 0, 0, 0, 0, 10000])
        );
    }

    #[test]
    fn long_runs_are_thinned_to_the_frame_bound() {
        let mut v = unit();
        let n = 10_000;
        v.t = (0..n).map(|i| i as f64 * 0.01).collect();
        v.poses = (0..n)
            .map(|i| vec![[i as f64 * 1e-3, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0]])
            .collect();
        let page = page_value(&v);
        let t = page["t"].as_array().unwrap();
        assert_eq!(t.len(), MAX_FRAMES);
        assert_eq!(page["poses"].as_array().unwrap().len(), MAX_FRAMES * 7);
        assert_eq!(t.last().unwrap().as_f64(), Some(99.99));
        // the last frame's x: 9.999 m as 9999 mm
        assert_eq!(page["poses"][(MAX_FRAMES - 1) * 7], json!(9999));
    }
}

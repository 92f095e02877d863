//! The URDF's `<collision>` and `<visual>` elements and its link tree, read in their own
//! pass with `quick-xml` (the rigid-body loader strips them), and their meshes read (URIs
//! resolved against package folders).

use super::mesh::{TriangleMesh, read_mesh};
use crate::spatial::SE3;
use crate::{Error, Result};
use quick_xml::events::{BytesStart, Event};
use std::path::{Path, PathBuf};

/// A geometric primitive or mesh as the URDF gives it.
#[derive(Clone, Debug, PartialEq)]
pub enum GeometrySpec {
    /// `<box size="x y z"/>`: full side lengths.
    Box([f64; 3]),
    /// `<cylinder radius length/>` along z.
    Cylinder {
        /// Radius (m).
        radius: f64,
        /// Length (m).
        length: f64,
    },
    /// `<sphere radius/>`.
    Sphere {
        /// Radius (m).
        radius: f64,
    },
    /// `<capsule radius length/>` along z (length of the cylindrical part).
    Capsule {
        /// Radius (m).
        radius: f64,
        /// Length of the cylindrical part (m).
        length: f64,
    },
    /// `<mesh filename scale/>`.
    Mesh {
        /// The URI as written.
        uri: String,
        /// Scale per axis.
        scale: [f64; 3],
    },
}

/// One `<collision>` or `<visual>` element.
#[derive(Clone, Debug, PartialEq)]
pub struct UrdfGeometry {
    /// The link that carries it.
    pub link: String,
    /// Its `<origin>` in the link frame.
    pub origin: SE3,
    /// Its geometry.
    pub spec: GeometrySpec,
}

/// What the geometry pass reads from a URDF.
#[derive(Clone, Debug, Default)]
pub struct UrdfGeometryElements {
    /// `<collision>` elements in file order.
    pub collisions: Vec<UrdfGeometry>,
    /// `<visual>` elements in file order.
    pub visuals: Vec<UrdfGeometry>,
    /// (parent link, child link) of every joint.
    pub joints: Vec<(String, String)>,
    /// Every link's name.
    pub links: Vec<String>,
}

fn attr(e: &BytesStart, name: &[u8]) -> Option<String> {
    e.attributes()
        .flatten()
        .find(|a| a.key.as_ref() == name)
        .and_then(|a| a.unescape_value().ok().map(|v| v.into_owned()))
}

fn numbers<const N: usize>(text: &str, what: &str) -> std::result::Result<[f64; N], String> {
    let v: Vec<f64> = text
        .split_whitespace()
        .map(str::parse::<f64>)
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| format!("{what} '{text}' is not a list of numbers"))?;
    let arr: [f64; N] = v
        .try_into()
        .map_err(|_| format!("{what} '{text}' must have {N} numbers"))?;
    if arr.iter().any(|x| !x.is_finite()) {
        return Err(format!("{what} '{text}' is not finite"));
    }
    Ok(arr)
}

fn positive(e: &BytesStart, name: &str, what: &str) -> std::result::Result<f64, String> {
    let text = attr(e, name.as_bytes()).ok_or(format!("<{what}> lacks '{name}'"))?;
    let [x] = numbers::<1>(&text, &format!("{what} {name}"))?;
    if x <= 0.0 {
        return Err(format!("{what} {name} must be > 0, got {x}"));
    }
    Ok(x)
}

/// Reads the geometry elements and the link tree of a URDF.
///
/// # Errors
/// [`Error::Parse`] naming `source_name` and the link for malformed XML, a missing or
/// non-positive size, a non-finite origin or an element with no geometry.
pub fn read_urdf_geometry(text: &str, source_name: &str) -> Result<UrdfGeometryElements> {
    let mut reader = quick_xml::Reader::from_str(text);
    let mut out = UrdfGeometryElements::default();
    let mut stack: Vec<String> = Vec::new();
    let mut link = String::new();
    let mut joint_parent: Option<String> = None;
    let mut joint_child: Option<String> = None;
    // The element being read: (is collision, origin, geometry).
    let mut current: Option<(bool, SE3, Option<GeometrySpec>)> = None;
    let fail = |link: &str, m: String| Error::parse(source_name, format!("link '{link}': {m}"));
    loop {
        let ev = reader.read_event().map_err(|e| {
            Error::parse(
                source_name,
                format!("malformed XML at byte {}: {e}", reader.error_position()),
            )
        })?;
        let (e, empty) = match &ev {
            Event::Start(e) => (Some(e.clone()), false),
            Event::Empty(e) => (Some(e.clone()), true),
            Event::End(_) => {
                let name = stack.pop().unwrap_or_default();
                match name.as_str() {
                    "collision" | "visual" => {
                        finish(&mut out, &mut current, &link).map_err(|m| fail(&link, m))?;
                    }
                    "joint" if stack.len() == 1 => {
                        if let (Some(p), Some(c)) = (joint_parent.take(), joint_child.take()) {
                            out.joints.push((p, c));
                        }
                    }
                    _ => {}
                }
                (None, false)
            }
            Event::Eof => break,
            _ => (None, false),
        };
        let Some(e) = e else { continue };
        let name = String::from_utf8_lossy(e.local_name().as_ref()).into_owned();
        let parent = stack.last().map(String::as_str);
        match (parent, name.as_str()) {
            (Some("robot"), "link") => {
                link = attr(&e, b"name").unwrap_or_default();
                out.links.push(link.clone());
            }
            (Some("link"), "collision" | "visual") => {
                current = Some((name == "collision", SE3::identity(), None));
                if empty {
                    finish(&mut out, &mut current, &link).map_err(|m| fail(&link, m))?;
                }
            }
            (Some("collision" | "visual"), "origin") => {
                if let Some(c) = current.as_mut() {
                    let xyz = attr(&e, b"xyz").unwrap_or("0 0 0".into());
                    let rpy = attr(&e, b"rpy").unwrap_or("0 0 0".into());
                    let xyz = numbers::<3>(&xyz, "origin xyz").map_err(|m| fail(&link, m))?;
                    let rpy = numbers::<3>(&rpy, "origin rpy").map_err(|m| fail(&link, m))?;
                    c.1 = SE3::from_xyz_rpy(xyz, rpy);
                }
            }
            (Some("geometry"), shape) => {
                if let Some(c) = current.as_mut() {
                    c.2 = Some(spec(&e, shape).map_err(|m| fail(&link, m))?);
                }
            }
            (Some("joint"), "parent") => joint_parent = attr(&e, b"link"),
            (Some("joint"), "child") => joint_child = attr(&e, b"link"),
            _ => {}
        }
        if !empty {
            stack.push(name);
        }
    }
    Ok(out)
}

fn spec(e: &BytesStart, shape: &str) -> std::result::Result<GeometrySpec, String> {
    Ok(match shape {
        "box" => {
            let size = attr(e, b"size").ok_or("<box> lacks 'size'")?;
            let s = numbers::<3>(&size, "box size")?;
            if s.iter().any(|x| *x <= 0.0) {
                return Err(format!("box size '{size}' must be > 0"));
            }
            GeometrySpec::Box(s)
        }
        "cylinder" => GeometrySpec::Cylinder {
            radius: positive(e, "radius", "cylinder")?,
            length: positive(e, "length", "cylinder")?,
        },
        "capsule" => GeometrySpec::Capsule {
            radius: positive(e, "radius", "capsule")?,
            length: positive(e, "length", "capsule")?,
        },
        "sphere" => GeometrySpec::Sphere {
            radius: positive(e, "radius", "sphere")?,
        },
        "mesh" => {
            let uri = attr(e, b"filename").ok_or("<mesh> lacks 'filename'")?;
            let scale = match attr(e, b"scale") {
                Some(s) => numbers::<3>(&s, "mesh scale")?,
                None => [1.0; 3],
            };
            GeometrySpec::Mesh { uri, scale }
        }
        other => return Err(format!("unsupported geometry <{other}>")),
    })
}

fn finish(
    out: &mut UrdfGeometryElements,
    current: &mut Option<(bool, SE3, Option<GeometrySpec>)>,
    link: &str,
) -> std::result::Result<(), String> {
    if let Some((collision, origin, spec)) = current.take() {
        let kind = if collision { "collision" } else { "visual" };
        let spec = spec.ok_or(format!("<{kind}> element has no geometry"))?;
        let g = UrdfGeometry {
            link: link.to_string(),
            origin,
            spec,
        };
        if collision {
            out.collisions.push(g);
        } else {
            out.visuals.push(g);
        }
    }
    Ok(())
}

/// Resolves a mesh URI: `package://PKG/REST` as `DIR/PKG/REST` (or `DIR/REST` when `DIR`
/// is the package folder itself) for each of `package_dirs` in turn, then each folder of
/// `ROS_PACKAGE_PATH`; `file://PATH` as `PATH`; any other URI relative to `dir` (the
/// folder of the file that names it).
///
/// # Errors
/// A message naming the URI and where it was looked for when no candidate file exists;
/// the caller names its file and element ([`read_link_mesh`] for a URDF's meshes).
pub fn resolve_uri(
    uri: &str,
    dir: &Path,
    package_dirs: &[PathBuf],
) -> std::result::Result<PathBuf, String> {
    if let Some(rest) = uri.strip_prefix("package://") {
        let (pkg, path) = rest.split_once('/').unwrap_or((rest, ""));
        let mut dirs: Vec<PathBuf> = package_dirs.to_vec();
        if let Some(ros) = std::env::var_os("ROS_PACKAGE_PATH") {
            dirs.extend(std::env::split_paths(&ros));
        }
        for d in &dirs {
            let candidates = [d.join(pkg).join(path), d.join(path)];
            let own = d.file_name().is_some_and(|n| n == pkg);
            for (k, c) in candidates.iter().enumerate() {
                if (k == 0 || own) && c.is_file() {
                    return Ok(c.clone());
                }
            }
        }
        return Err(format!(
            "cannot resolve '{uri}' ({})",
            if dirs.is_empty() {
                "no package folder given: use --package-dir"
            } else {
                "not found in any package folder"
            }
        ));
    }
    let path = uri.strip_prefix("file://").unwrap_or(uri);
    let p = Path::new(path);
    let p = if p.is_absolute() {
        p.to_path_buf()
    } else {
        dir.join(p)
    };
    if p.is_file() {
        Ok(p)
    } else {
        Err(format!(
            "cannot resolve '{uri}' (no such file {})",
            p.display()
        ))
    }
}

/// Reads the mesh of a `<mesh filename="uri" scale>` element of link `link` in the URDF
/// file `urdf`: the URI resolved against the URDF's folder and `package_dirs`
/// ([`resolve_uri`]), the file read and scaled ([`read_mesh`]).
///
/// # Errors
/// [`Error::Parse`] naming the URDF file, the link and the URI, and then either why the
/// URI does not resolve or the mesh file and what is wrong with it (unreadable, empty,
/// malformed, non-finite, not STL or OBJ).
pub fn read_link_mesh(
    urdf: &Path,
    link: &str,
    uri: &str,
    scale: [f64; 3],
    package_dirs: &[PathBuf],
) -> Result<TriangleMesh> {
    let at = |m: String| Error::parse(urdf, format!("link '{link}' mesh '{uri}': {m}"));
    let dir = urdf.parent().unwrap_or(Path::new("."));
    let path = resolve_uri(uri, dir, package_dirs).map_err(at)?;
    read_mesh(&path, scale).map_err(|e| at(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_collisions_visuals_and_joints() {
        let text = r#"<robot name="r">
  <link name="a"><collision><origin xyz="1 0 0"/><geometry><box size="1 2 3"/></geometry></collision>
    <visual><geometry><mesh filename="package://p/m.stl" scale="2 2 2"/></geometry></visual></link>
  <link name="b"><collision><geometry><sphere radius="0.5"/></geometry></collision></link>
  <joint name="j" type="fixed"><parent link="a"/><child link="b"/></joint>
</robot>"#;
        let g = read_urdf_geometry(text, "t.urdf").unwrap();
        assert_eq!(g.collisions.len(), 2);
        assert_eq!(g.collisions[0].spec, GeometrySpec::Box([1.0, 2.0, 3.0]));
        assert_eq!(g.collisions[0].origin.translation.x, 1.0);
        assert_eq!(g.visuals.len(), 1);
        assert_eq!(g.joints, vec![("a".into(), "b".into())]);
        let bad = text.replace("radius=\"0.5\"", "radius=\"-1\"");
        let e = read_urdf_geometry(&bad, "t.urdf").unwrap_err().to_string();
        assert!(
            e.contains("t.urdf") && e.contains("link 'b'") && e.contains("radius"),
            "{e}"
        );
    }
}

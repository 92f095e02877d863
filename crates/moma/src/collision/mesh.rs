//! Triangle meshes from STL (binary or ASCII, `stl_io`) and OBJ (`tobj`) files, and their
//! convex hulls (`parry3d-f64`'s quickhull, checked against every input vertex).

use crate::{Error, Result};
use nalgebra::Vector3;
use std::path::Path;

/// A triangle mesh in its own frame (metres, the URDF `scale` applied).
#[derive(Clone, Debug, PartialEq)]
pub struct TriangleMesh {
    /// Vertex positions.
    pub vertices: Vec<Vector3<f64>>,
    /// Triangles as indices into `vertices`.
    pub triangles: Vec<[u32; 3]>,
}

/// Largest number of vertices a mesh file may hold (bounds memory on hostile input).
pub const MAX_MESH_VERTICES: usize = 5_000_000;

/// Reads an STL (binary or ASCII) or OBJ mesh, chosen by the file's extension
/// (case-insensitive), and scales it.
///
/// # Errors
/// [`Error::Parse`] naming the file for an extension other than `.stl` / `.obj`, an empty
/// file (nothing but whitespace), a malformed mesh or one without triangles, a
/// non-finite vertex or an index out of range; [`Error::Io`] if the file cannot be read.
pub fn read_mesh(path: &Path, scale: [f64; 3]) -> Result<TriangleMesh> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let parse: fn(&[u8]) -> std::result::Result<TriangleMesh, String> = match ext.as_deref() {
        Some("stl") => stl_from_bytes,
        Some("obj") => obj_from_bytes,
        _ => {
            return Err(Error::parse(
                path,
                format!(
                    "unsupported mesh format '{}' (expected .stl or .obj)",
                    ext.unwrap_or_default()
                ),
            ));
        }
    };
    let bytes = std::fs::read(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(Error::parse(
            path,
            format!("the mesh file is empty ({} bytes)", bytes.len()),
        ));
    }
    let mesh = parse(&bytes).map_err(|m| Error::parse(path, m))?;
    scaled(mesh, scale).map_err(|m| Error::parse(path, m))
}

/// Parses STL bytes (binary or ASCII). The message names what is wrong.
///
/// # Errors
/// A message for malformed, empty or non-finite input.
pub fn stl_from_bytes(bytes: &[u8]) -> std::result::Result<TriangleMesh, String> {
    // A binary STL announces its triangle count; refuse a count its size cannot hold
    // before the reader reserves memory for it.
    if bytes.len() >= 84 && !bytes.starts_with(b"solid") {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if n.saturating_mul(50).saturating_add(84) > bytes.len() {
            return Err(format!(
                "malformed binary STL: header announces {n} triangles, the file holds {} bytes",
                bytes.len()
            ));
        }
    }
    let mut cursor = std::io::Cursor::new(bytes);
    let m = stl_io::read_stl(&mut cursor).map_err(|e| format!("malformed STL: {e}"))?;
    let vertices: Vec<Vector3<f64>> = m
        .vertices
        .iter()
        .map(|v| Vector3::new(f64::from(v[0]), f64::from(v[1]), f64::from(v[2])))
        .collect();
    let mut triangles = Vec::with_capacity(m.faces.len());
    for f in &m.faces {
        let t = f.vertices;
        if t.iter().any(|&i| i >= vertices.len()) {
            return Err("malformed STL: triangle index out of range".into());
        }
        triangles.push([t[0] as u32, t[1] as u32, t[2] as u32]);
    }
    checked(TriangleMesh {
        vertices,
        triangles,
    })
}

/// Parses OBJ text (all its objects and groups merged into one mesh, faces triangulated).
///
/// # Errors
/// A message for malformed, empty or non-finite input.
pub fn obj_from_bytes(bytes: &[u8]) -> std::result::Result<TriangleMesh, String> {
    let mut reader = std::io::BufReader::new(bytes);
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ..Default::default()
    };
    let (models, _) =
        tobj::load_obj_buf(&mut reader, &opts, |_| Err(tobj::LoadError::OpenFileFailed))
            .map_err(|e| format!("malformed OBJ: {e}"))?;
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for m in &models {
        let base = vertices.len();
        let p = &m.mesh.positions;
        if p.len() % 3 != 0 {
            return Err("malformed OBJ: vertex list is not a list of triples".into());
        }
        vertices.extend(
            p.chunks_exact(3)
                .map(|c| Vector3::new(f64::from(c[0]), f64::from(c[1]), f64::from(c[2]))),
        );
        for t in m.mesh.indices.chunks_exact(3) {
            let idx = [
                t[0] as usize + base,
                t[1] as usize + base,
                t[2] as usize + base,
            ];
            if idx.iter().any(|&i| i >= vertices.len()) {
                return Err("malformed OBJ: face index out of range".into());
            }
            triangles.push([idx[0] as u32, idx[1] as u32, idx[2] as u32]);
        }
        if vertices.len() > MAX_MESH_VERTICES {
            return Err(format!("OBJ has more than {MAX_MESH_VERTICES} vertices"));
        }
    }
    checked(TriangleMesh {
        vertices,
        triangles,
    })
}

fn checked(mesh: TriangleMesh) -> std::result::Result<TriangleMesh, String> {
    if mesh.triangles.is_empty() || mesh.vertices.is_empty() {
        return Err("mesh is empty (no triangles)".into());
    }
    if mesh.vertices.len() > MAX_MESH_VERTICES {
        return Err(format!("mesh has more than {MAX_MESH_VERTICES} vertices"));
    }
    if let Some(i) = mesh
        .vertices
        .iter()
        .position(|v| v.iter().any(|x| !x.is_finite()))
    {
        return Err(format!("vertex {i} is not finite"));
    }
    Ok(mesh)
}

fn scaled(mut mesh: TriangleMesh, scale: [f64; 3]) -> std::result::Result<TriangleMesh, String> {
    if scale.iter().any(|s| !s.is_finite() || *s == 0.0) {
        return Err(format!("mesh scale {scale:?} must be finite and non-zero"));
    }
    if scale != [1.0; 3] {
        for v in &mut mesh.vertices {
            v.component_mul_assign(&Vector3::from(scale));
        }
    }
    Ok(mesh)
}

/// The vertices of the convex hull of `points` (parry's quickhull), completed with every
/// input point that lies more than 1e-9 m outside the hull's faces, so the support
/// function of the result equals that of `points` (to that bound) whatever the hull
/// code's round-off. A flat or degenerate point set (no volume) keeps all its points,
/// without adjacency: its support function is still exact.
#[must_use]
pub fn convex_hull_vertices(points: &[Vector3<f64>]) -> ConvexHullData {
    let all = || ConvexHullData {
        vertices: points.to_vec(),
        faces: Vec::new(),
        neighbours: vec![Vec::new(); points.len()],
    };
    let glam_points: Vec<parry3d_f64::math::Vector3> = points
        .iter()
        .map(|p| parry3d_f64::math::Vector3::new(p.x, p.y, p.z))
        .collect();
    let Ok((hv, faces)) = parry3d_f64::transformation::try_convex_hull(&glam_points) else {
        return all();
    };
    let mut vertices: Vec<Vector3<f64>> = hv.iter().map(|v| Vector3::new(v.x, v.y, v.z)).collect();
    // Volume (divergence theorem over the faces) against the bounding box's.
    let volume: f64 = faces
        .iter()
        .map(|f| {
            let [a, b, c] = f.map(|i| vertices[i as usize]);
            a.dot(&b.cross(&c)) / 6.0
        })
        .sum();
    let (lo, hi) = points.iter().fold(
        (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    );
    let extent = (hi - lo).max();
    let flat = volume.is_nan() || volume.abs() <= 1e-9 * extent.powi(3);
    if vertices.len() < 4 || faces.len() < 4 || flat {
        return all();
    }
    let planes: Vec<(Vector3<f64>, f64)> = faces
        .iter()
        .filter_map(|f| {
            let [a, b, c] = f.map(|i| vertices[i as usize]);
            let n = (b - a).cross(&(c - a));
            let norm = n.norm();
            (norm > 0.0).then(|| (n / norm, n.dot(&a) / norm))
        })
        .collect();
    let hull_len = vertices.len();
    for p in points {
        if planes.iter().any(|(n, d)| n.dot(p) - d > 1e-9) {
            vertices.push(*p);
        }
    }
    let mut neighbours = vec![Vec::new(); vertices.len()];
    // With points outside the hull's faces the edge graph is not the hull's: leave it
    // empty so the support function scans every vertex.
    for f in faces.iter().filter(|_| vertices.len() == hull_len) {
        for k in 0..3 {
            let (a, b) = (f[k] as usize, f[(k + 1) % 3] as usize);
            if !neighbours[a].contains(&b) {
                neighbours[a].push(b);
            }
            if !neighbours[b].contains(&a) {
                neighbours[b].push(a);
            }
        }
    }
    ConvexHullData {
        vertices,
        faces,
        neighbours,
    }
}

/// A convex hull: its vertices, its triangles (for drawing) and each hull vertex's
/// neighbours along hull edges.
#[derive(Clone, Debug, PartialEq)]
pub struct ConvexHullData {
    /// Hull vertices (plus any input point the hull code left outside, which then has no
    /// neighbours).
    pub vertices: Vec<Vector3<f64>>,
    /// Hull triangles as indices into `vertices` (empty for a flat point set).
    pub faces: Vec<[u32; 3]>,
    /// Vertex adjacency along hull edges.
    pub neighbours: Vec<Vec<usize>>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ascii_stl_tetrahedron_and_its_hull() {
        let stl = b"solid t
facet normal 0 0 -1
outer loop
vertex 0 0 0
vertex 1 0 0
vertex 0 1 0
endloop
endfacet
facet normal 0 0 1
outer loop
vertex 0 0 0
vertex 0 1 0
vertex 0 0 1
endloop
endfacet
facet normal 1 1 1
outer loop
vertex 1 0 0
vertex 0 1 0
vertex 0 0 1
endloop
endfacet
endsolid t
";
        let m = stl_from_bytes(stl).unwrap();
        assert_eq!(m.vertices.len(), 4);
        assert_eq!(m.triangles.len(), 3);
        let h = convex_hull_vertices(&m.vertices);
        assert_eq!(h.vertices.len(), 4);
        assert!(h.neighbours.iter().all(|n| n.len() == 3));
    }

    #[test]
    fn bad_meshes_are_refused_with_a_reason() {
        assert!(stl_from_bytes(b"").is_err());
        let mut huge = vec![0u8; 84];
        huge[80..84].copy_from_slice(&u32::MAX.to_le_bytes());
        assert!(stl_from_bytes(&huge).unwrap_err().contains("announces"));
        let nan = b"v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n";
        assert!(obj_from_bytes(nan).unwrap_err().contains("not finite"));
        assert!(obj_from_bytes(b"v 0 0 0\n").unwrap_err().contains("empty"));
        let flat = [
            Vector3::zeros(),
            Vector3::x(),
            Vector3::y(),
            Vector3::new(1.0, 1.0, 0.0),
        ];
        // A flat mesh keeps its points and is scanned (no adjacency).
        let h = convex_hull_vertices(&flat);
        assert_eq!(h.vertices.len(), 4);
        assert!(h.neighbours.iter().all(Vec::is_empty));
    }
}

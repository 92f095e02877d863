//! The collision mesh readers on arbitrary bytes (first byte: STL or OBJ): a parsed mesh
//! of at most 20,000 vertices is also hulled and its distance to a unit box computed,
//! which must be finite.
#![no_main]
use libfuzzer_sys::fuzz_target;
use moma::collision::Convex;
use moma::collision::gjk::{EpaWorkspace, WarmStart, signed_distance};
use moma::collision::mesh::{convex_hull_vertices, obj_from_bytes, stl_from_bytes};
use moma::spatial::SE3;
use nalgebra::Vector3;

fuzz_target!(|data: &[u8]| {
    let Some((&sel, rest)) = data.split_first() else {
        return;
    };
    let mesh = if sel & 1 == 0 {
        stl_from_bytes(rest)
    } else {
        obj_from_bytes(rest)
    };
    let Ok(mesh) = mesh else { return };
    if mesh.vertices.len() > 20_000 || mesh.vertices.iter().any(|v| v.amax() > 1e6) {
        return;
    }
    let hull = convex_hull_vertices(&mesh.vertices);
    let shape = Convex::Hull {
        vertices: hull.vertices,
        neighbours: hull.neighbours,
    };
    let cube = Convex::Box {
        half: Vector3::repeat(0.5),
    };
    let r = signed_distance(
        &shape,
        &SE3::identity(),
        &cube,
        &SE3::from_translation(Vector3::new(0.3, 0.2, 0.1)),
        &mut WarmStart::default(),
        &mut EpaWorkspace::default(),
    );
    assert!(r.distance.is_finite(), "{r:?}");
});

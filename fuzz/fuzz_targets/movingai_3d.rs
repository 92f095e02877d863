//! Moving AI `.3dmap` and `.3dscen` parsers on arbitrary text (first byte: which one);
//! a parsed map with at most 4,096 voxels is also searched between two of its voxels.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Some((&sel, rest)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    if sel & 1 == 0 {
        if let Ok(g) = moma::planning::movingai::parse_3dmap(text, Path::new("fuzz.3dmap")) {
            if g.nx * g.ny * g.nz <= 4096 {
                let far = (g.nx - 1, g.ny - 1, g.nz - 1);
                let _ = moma::planning::astar3d(&g, (0, 0, 0), far);
            }
        }
    } else {
        let _ = moma::planning::movingai::parse_3dscen(text, Path::new("fuzz.3dscen"));
    }
});

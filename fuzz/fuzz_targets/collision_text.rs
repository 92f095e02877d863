//! The collision text readers on arbitrary UTF-8 (first byte: SRDF, planning-scene YAML
//! or point cloud): `collision::srdf::disabled_pairs`, `collision::scene::scene_from_str`
//! (mesh URIs resolve against a folder that does not exist, so no file is read) and
//! `collision::point_cloud::parse_points`, whose points (up to 10,000) are binned by
//! `collision::scene::point_cloud_object`.
#![no_main]
use libfuzzer_sys::fuzz_target;
use moma::collision::SceneOptions;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Some((&sel, rest)) = data.split_first() else {
        return;
    };
    let Ok(text) = std::str::from_utf8(rest) else {
        return;
    };
    if sel % 3 == 0 {
        let _ = moma::collision::srdf::disabled_pairs(text, "fuzz.srdf");
    } else if sel % 3 == 2 {
        if let Ok(points) = moma::collision::point_cloud::parse_points(text, Path::new("fuzz.xyz")) {
            if points.len() <= 10_000 {
                let _ = moma::collision::scene::point_cloud_object("fuzz", &points, 0.05);
            }
        }
    } else {
        let opts = SceneOptions {
            world_frames: vec!["base_link".into(), "world".into()],
            package_dirs: vec![],
        };
        let _ = moma::collision::scene::scene_from_str(text, Path::new("/nonexistent/fuzz.yaml"), &opts);
    }
});

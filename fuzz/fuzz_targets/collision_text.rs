//! The collision text readers on arbitrary UTF-8 (first byte: SRDF or planning-scene
//! YAML): `collision::srdf::disabled_pairs` and `collision::scene::scene_from_str` (mesh
//! URIs resolve against a folder that does not exist, so no file is read).
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
    if sel & 1 == 0 {
        let _ = moma::collision::srdf::disabled_pairs(text, "fuzz.srdf");
    } else {
        let opts = SceneOptions {
            world_frames: vec!["base_link".into(), "world".into()],
            package_dirs: vec![],
        };
        let _ = moma::collision::scene::scene_from_str(text, Path::new("/nonexistent/fuzz.yaml"), &opts);
    }
});

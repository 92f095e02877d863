//! `moma mission` files as raw text: parsed (`mission::scenario::parse_file`, whose error
//! names the line and column), validated and loaded (`from_file`, with the map and URDF
//! paths kept on shipped files), then the transport posture's tip-over limits.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

mod files;
mod mission_check;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(file) = moma::mission::scenario::parse_file(text, Path::new("fuzz.toml")) else {
        return;
    };
    mission_check::check(file);
});

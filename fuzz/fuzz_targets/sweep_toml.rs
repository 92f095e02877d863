//! `moma sweep` files as raw text: read and validated by `Sweep::from_toml_str` (robot
//! and mission paths kept on shipped files), then the points' values and, for cheap
//! studies, two evaluations (see `sweep_check`).
#![no_main]
use libfuzzer_sys::fuzz_target;

mod files;
mod sweep_check;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        sweep_check::check(text);
    }
});

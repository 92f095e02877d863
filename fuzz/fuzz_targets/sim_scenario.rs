//! `moma simulate` scenario files as raw text: the whole schema, its checks and the
//! system-size checks of the initial state and inputs (see `sim_check`).
#![no_main]
use libfuzzer_sys::fuzz_target;

mod files;
mod sim_check;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        sim_check::check(text);
    }
});

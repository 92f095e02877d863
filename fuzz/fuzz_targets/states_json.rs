//! The JSON states files of `moma dynamics`, `manipulability`, `stability`,
//! `stability-map`, `osc` and `space` on raw text: every reader of `moma::io::states`,
//! then the per-state checks the commands run against the Panda model.
#![no_main]
use libfuzzer_sys::fuzz_target;

mod states_check;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        states_check::all_readers(text);
    }
});

//! Moving AI `.map` and `.scen` parsers on arbitrary text (first byte: which one).
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
        let _ = moma::planning::movingai::parse_movingai_map(text, Path::new("fuzz.map"));
    } else {
        let _ = moma::planning::movingai::MovingAiScenario::parse(text, Path::new("fuzz.map.scen"));
    }
});

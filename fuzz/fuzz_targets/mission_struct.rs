//! Structured `moma mission` files: one of the two shipped missions (or a small one on the
//! Moving AI trap map), changed by `arbitrary`-derived edits (NaN, ±inf, huge, tiny and
//! negative numbers, wrong types, removed, added, repeated and cut fields), rendered to
//! TOML text, then parsed, validated and loaded as in `mission_toml`.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

mod files;
mod mission_check;
mod mutate;

const TEMPLATES: [&str; 3] = [
    include_str!("../../scenarios/mission.toml"),
    include_str!("../../scenarios/mission_sealed.toml"),
    include_str!("../corpus/mission_toml/trap.toml"),
];

#[derive(arbitrary::Arbitrary, Debug)]
struct Input {
    template: u8,
    edits: Vec<mutate::Edit>,
}

fuzz_target!(|input: Input| {
    let t = TEMPLATES[input.template as usize % TEMPLATES.len()];
    let mut doc: toml::Value = toml::from_str(t).expect("shipped missions are valid TOML");
    mutate::edit_toml(&mut doc, &input.edits);
    let Ok(text) = toml::to_string(&doc) else {
        return;
    };
    let Ok(file) = moma::mission::scenario::parse_file(&text, Path::new("fuzz.toml")) else {
        return;
    };
    mission_check::check(file);
});

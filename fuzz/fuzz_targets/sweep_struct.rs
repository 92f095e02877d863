//! Structured `moma sweep` files: one of the four shipped sweeps, changed by
//! `arbitrary`-derived edits (NaN, ±inf, huge, tiny and negative numbers, wrong types,
//! removed, added, repeated and cut fields), rendered to TOML text and checked as in
//! `sweep_toml`.
#![no_main]
use libfuzzer_sys::fuzz_target;

mod files;
mod mutate;
mod sweep_check;

const TEMPLATES: [&str; 4] = [
    include_str!("../../scenarios/sweeps/tiago_stability.toml"),
    include_str!("../../scenarios/sweeps/tiago_stability_random.toml"),
    include_str!("../../scenarios/sweeps/panda_placement.toml"),
    include_str!("../../scenarios/sweeps/mission_obstacle.toml"),
];

#[derive(arbitrary::Arbitrary, Debug)]
struct Input {
    template: u8,
    edits: Vec<mutate::Edit>,
}

fuzz_target!(|input: Input| {
    let t = TEMPLATES[input.template as usize % TEMPLATES.len()];
    let mut doc: toml::Value = toml::from_str(t).expect("shipped sweeps are valid TOML");
    mutate::edit_toml(&mut doc, &input.edits);
    if let Ok(text) = toml::to_string(&doc) {
        sweep_check::check(&text);
    }
});

//! Structured states files: one of the shipped example states files (generic, on a base,
//! stability with external loads, osc, space), changed by `arbitrary`-derived edits
//! (extreme numbers, wrong types, removed, added, repeated and cut fields), rendered to
//! JSON text and fed to every reader of `moma::io::states`.
#![no_main]
use libfuzzer_sys::fuzz_target;

mod mutate;
mod states_check;

const TEMPLATES: [&str; 5] = [
    include_str!("../../docs/examples/panda_states.json"),
    include_str!("../../docs/examples/panda_on_base_states.json"),
    include_str!("../../docs/examples/panda_stability_states.json"),
    include_str!("../../docs/examples/panda_osc_states.json"),
    include_str!("../../docs/examples/panda_space_states.json"),
];

#[derive(arbitrary::Arbitrary, Debug)]
struct Input {
    template: u8,
    edits: Vec<mutate::Edit>,
}

fuzz_target!(|input: Input| {
    let t = TEMPLATES[input.template as usize % TEMPLATES.len()];
    let mut doc: serde_json::Value = serde_json::from_str(t).expect("templates are valid");
    mutate::edit_json(&mut doc, &input.edits);
    let text = serde_json::to_string(&doc).expect("a JSON value renders");
    states_check::all_readers(&text);
});

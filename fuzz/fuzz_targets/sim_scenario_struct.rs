//! Structured `moma simulate` scenarios: one of the shipped scenario files, changed by
//! `arbitrary`-derived edits (NaN, ±inf, huge, tiny and negative numbers, wrong types,
//! removed, added, repeated and cut fields), rendered to TOML text and read through the
//! library's whole scenario schema and its checks, as in `sim_scenario` (see `sim_check`).
#![no_main]
use libfuzzer_sys::fuzz_target;
mod mutate;
mod files;
mod sim_check;

const TEMPLATES: [&str; 15] = [
    include_str!("../../scenarios/default.toml"),
    include_str!("../../scenarios/m1_unicycle.toml"),
    include_str!("../../scenarios/m2_platform_arm.toml"),
    include_str!("../../scenarios/m5_mobile_manipulator.toml"),
    include_str!("../../scenarios/space_capture.toml"),
    include_str!("../../scenarios/space_resolved_rate.toml"),
    include_str!("../../scenarios/brake_arm_tucked.toml"),
    include_str!("../../scenarios/control_osc_panda_fixed.toml"),
    include_str!("../../scenarios/control_kanayama.toml"),
    include_str!("../../scenarios/control_kanayama_planned.toml"),
    include_str!("../../scenarios/control_pure_pursuit.toml"),
    include_str!("../../scenarios/control_coordinated.toml"),
    include_str!("../../scenarios/control_osc_panda.toml"),
    include_str!("../../scenarios/control_m5_pd_plus.toml"),
    include_str!("../../scenarios/brake_arm_extended.toml"),
];

#[derive(arbitrary::Arbitrary, Debug)]
struct Input {
    template: u8,
    edits: Vec<mutate::Edit>,
}

fuzz_target!(|input: Input| {
    let t = TEMPLATES[input.template as usize % TEMPLATES.len()];
    let mut doc: toml::Value = toml::from_str(t).expect("scenarios are valid TOML");
    mutate::edit_toml(&mut doc, &input.edits);
    let Ok(text) = toml::to_string(&doc) else {
        return;
    };
    sim_check::check(&text);
});

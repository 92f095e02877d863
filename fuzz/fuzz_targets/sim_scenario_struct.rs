//! Structured `moma simulate` scenarios: one of the shipped scenario files, changed by
//! `arbitrary`-derived edits (NaN, ±inf, huge, tiny and negative numbers, wrong types,
//! removed, added, repeated and cut fields), rendered to TOML text and read through the
//! library's part of the schema (`[integrator]`, `[[inputs]]`, `[limits]`): serde,
//! validation, then the input profiles evaluated at four times.
#![no_main]
use libfuzzer_sys::fuzz_target;
use moma::sim::monitor::MonitorLimits;
use moma::sim::scenario::{ChannelProfile, InputProfile, IntegratorSettings};

mod mutate;

const TEMPLATES: [&str; 6] = [
    include_str!("../../scenarios/default.toml"),
    include_str!("../../scenarios/m1_unicycle.toml"),
    include_str!("../../scenarios/m2_platform_arm.toml"),
    include_str!("../../scenarios/m5_mobile_manipulator.toml"),
    include_str!("../../scenarios/space_capture.toml"),
    include_str!("../../scenarios/space_resolved_rate.toml"),
];

#[derive(serde::Deserialize)]
struct Tables {
    integrator: Option<IntegratorSettings>,
    inputs: Option<Vec<ChannelProfile>>,
    #[allow(dead_code)]
    limits: Option<MonitorLimits>,
}

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
    let Ok(t) = toml::from_str::<Tables>(&text) else {
        return;
    };
    if let Some(i) = t.integrator {
        let _ = i.validate();
    }
    if let Some(channels) = t.inputs {
        let p = InputProfile { channels };
        let ok = p
            .channels
            .iter()
            .enumerate()
            .all(|(k, c)| c.validate(&format!("inputs[{k}]")).is_ok());
        if ok && p.channels.len() <= 64 {
            let mut u = vec![0.0; p.channels.len()];
            for t in [0.0, 0.5, 1e9, -1.0] {
                p.eval(t, &mut u);
            }
            assert!(
                u.iter().all(|x| x.is_finite()),
                "a validated profile gave {u:?}"
            );
        }
    }
});

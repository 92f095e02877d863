//! The library part of the `moma simulate` scenario TOML: the `[integrator]` and
//! `[[inputs]]` tables (serde schema, validation, evaluation) on arbitrary text.
#![no_main]
use libfuzzer_sys::fuzz_target;
use moma::sim::scenario::{ChannelProfile, InputProfile, IntegratorSettings};

#[derive(serde::Deserialize)]
struct Tables {
    integrator: Option<IntegratorSettings>,
    inputs: Option<Vec<ChannelProfile>>,
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(t) = toml::from_str::<Tables>(text) else {
        return;
    };
    if let Some(i) = t.integrator {
        let _ = i.validate();
    }
    if let Some(channels) = t.inputs {
        let p = InputProfile { channels };
        if p.channels.len() > 64 {
            return;
        }
        let ok = p
            .channels
            .iter()
            .enumerate()
            .all(|(k, c)| c.validate(&format!("inputs.channels[{k}]")).is_ok());
        if ok {
            let mut u = vec![0.0; p.channels.len()];
            for t in [0.0, 0.5, 1e9, -1.0] {
                p.eval(t, &mut u);
            }
        }
    }
});

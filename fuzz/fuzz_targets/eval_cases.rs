//! `moma eval`'s case files (`closed_form::cases::evaluate_document`), structured: the
//! first case of one of the shipped case files (m1–m6, closed-loop unicycle), changed by
//! `arbitrary`-derived edits (extreme numbers, wrong types, removed, added, repeated and
//! cut fields), evaluated at one of three tolerances. The templates keep one case and
//! drop the long trajectories' reference outputs, so an evaluation stays well under the
//! 10 s timeout unless an edit makes it long.
#![no_main]
use libfuzzer_sys::fuzz_target;
use serde_json::Value;
use std::sync::OnceLock;

mod mutate;

const FILES: [&str; 7] = [
    include_str!("../../crates/moma/tests/data/chapter/m1_unicycle.json"),
    include_str!("../../crates/moma/tests/data/chapter/m2_platform_planar_arm.json"),
    include_str!("../../crates/moma/tests/data/chapter/m3_diffdrive_kinematics.json"),
    include_str!("../../crates/moma/tests/data/chapter/m4_cart_two_link.json"),
    include_str!("../../crates/moma/tests/data/chapter/m5_mobile_manipulator_3d.json"),
    include_str!("../../crates/moma/tests/data/chapter/m6_space_manipulator.json"),
    include_str!("../../crates/moma/tests/data/control/unicycle_control.json"),
];

/// Each file reduced to `model` and its first case without the reference outputs.
fn templates() -> &'static Vec<Value> {
    static T: OnceLock<Vec<Value>> = OnceLock::new();
    T.get_or_init(|| {
        FILES
            .iter()
            .map(|f| {
                let doc: Value = serde_json::from_str(f).expect("case files are valid");
                let mut case = doc["cases"][0].clone();
                if let Some(o) = case.as_object_mut() {
                    o.remove("outputs");
                    o.remove("expected");
                }
                serde_json::json!({ "model": doc["model"].clone(), "cases": [case] })
            })
            .collect()
    })
}

#[derive(arbitrary::Arbitrary, Debug)]
struct Input {
    template: u8,
    tol: u8,
    edits: Vec<mutate::Edit>,
}

fuzz_target!(|input: Input| {
    let t = templates();
    let mut doc = t[input.template as usize % t.len()].clone();
    mutate::edit_json(&mut doc, &input.edits);
    let tol = [1e-6, 1e-9, 1e-3][input.tol as usize % 3];
    if let Ok(out) = moma::closed_form::cases::evaluate_document(&doc, tol) {
        assert!(out.get("cases").is_some_and(Value::is_array));
    }
});

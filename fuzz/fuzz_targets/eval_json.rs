//! `moma eval`'s case files on raw text: JSON parse, then
//! `closed_form::cases::evaluate_document` at a loose tolerance (1e-6) so that the
//! seeds (one case of each shipped case file) evaluate quickly.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(doc) = serde_json::from_slice::<serde_json::Value>(data) else {
        return;
    };
    if let Ok(out) = moma::closed_form::cases::evaluate_document(&doc, 1e-6) {
        assert!(out.get("cases").is_some_and(serde_json::Value::is_array));
    }
});

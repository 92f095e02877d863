//! What the sweep targets do with one sweep file: keep the paths it names on shipped
//! files ([`files`]), read and validate it (`Sweep::from_toml_str_with`, which loads the
//! study's robot or mission, the shipped files parsed once per process:
//! [`files::Cached`]), then the cheap parts of a run: the columns, the parameter
//! values of the first, middle and last points (and the refusal of one past the end), and
//! for a stability study, or a placement study with a small IK budget, the evaluation of
//! the first and last points. A mission study's point runs a whole mission (seconds), so
//! it is never evaluated.

use std::path::Path;

use moma::sweep::Sweep;

use crate::files;

/// Largest placement IK budget (iterations × (restarts + 1)) a point may be evaluated with.
const MAX_IK_ITERS: i64 = 2_000;

/// Swaps each path of `doc` that is not one of the shipped files; true if one changed.
fn keep_paths(doc: &mut toml::Table) -> bool {
    let mut changed = false;
    for (section, key) in [
        ("stability", "robot"),
        ("placement", "robot"),
        ("mission", "scenario"),
    ] {
        if let Some(toml::Value::String(p)) = doc
            .get_mut(section)
            .and_then(|s| s.as_table_mut())
            .and_then(|s| s.get_mut(key))
        {
            let kept = files::pick(p, &files::SWEEP_FILES);
            if kept != p {
                *p = kept.to_string();
                changed = true;
            }
        }
    }
    changed
}

fn small_ik(doc: &toml::Table) -> bool {
    let get = |k: &str, d: i64| {
        doc.get("placement")
            .and_then(|s| s.get(k))
            .map_or(Some(d), toml::Value::as_integer)
    };
    match (get("max_iters", 100), get("restarts", 2)) {
        (Some(i), Some(r)) => i.saturating_mul(r.saturating_add(1)) <= MAX_IK_ITERS,
        _ => false,
    }
}

pub fn check(text: &str) {
    let dir = files::scenarios().join("sweeps");
    let path = Path::new("fuzz.toml");
    let (text, doc) = match text.parse::<toml::Table>() {
        Ok(mut doc) => {
            let text = if keep_paths(&mut doc) {
                match toml::to_string(&doc) {
                    Ok(t) => t,
                    Err(_) => return,
                }
            } else {
                text.to_string()
            };
            (text, Some(doc))
        }
        // malformed TOML never gets as far as reading a file
        Err(_) => (text.to_string(), None),
    };
    let Ok(s) = Sweep::from_toml_str_with(&text, path, &dir, &files::Cached) else {
        return;
    };
    let n = s.len();
    assert!(n >= 1, "a validated sweep has at least one point");
    assert_eq!(s.columns()[0], "index");
    for i in [0, n / 2, n - 1] {
        let p = s.point(i).expect("an index inside 0..len has a point");
        assert_eq!(p.len(), s.parameters().len());
    }
    assert!(s.point(n).is_err(), "index len is outside the sweep");
    let evaluate = match s.study() {
        "stability" => true,
        "placement" => doc.as_ref().is_some_and(small_ik),
        _ => false,
    };
    if evaluate {
        for i in [0, n - 1] {
            if let Ok(row) = s.evaluate(i) {
                assert_eq!(
                    row.len(),
                    s.columns().len(),
                    "row {i} and the columns differ"
                );
            }
        }
    }
}

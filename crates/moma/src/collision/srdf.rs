//! The SRDF's `<disable_collisions link1 link2/>` pairs (MoveIt's allowed-collision
//! matrix), read with `quick-xml`; the rest of the SRDF is ignored.

use crate::{Error, Result};
use quick_xml::events::Event;

/// One disabled pair with its reason.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DisabledPair {
    /// First link.
    pub link1: String,
    /// Second link.
    pub link2: String,
    /// The `reason` attribute (e.g. `Adjacent`, `Never`), empty if absent.
    pub reason: String,
}

/// Reads the `<disable_collisions>` elements of SRDF text.
///
/// # Errors
/// [`Error::Parse`] naming `source_name` for malformed XML or an element without
/// `link1` / `link2`.
pub fn disabled_pairs(text: &str, source_name: &str) -> Result<Vec<DisabledPair>> {
    let mut reader = quick_xml::Reader::from_str(text);
    let mut out = Vec::new();
    let mut n = 0usize;
    loop {
        let ev = reader.read_event().map_err(|e| {
            Error::parse(
                source_name,
                format!("malformed XML at byte {}: {e}", reader.error_position()),
            )
        })?;
        match ev {
            Event::Start(e) | Event::Empty(e)
                if e.local_name().as_ref() == b"disable_collisions" =>
            {
                n += 1;
                let get = |k: &[u8]| {
                    e.attributes()
                        .flatten()
                        .find(|a| a.key.as_ref() == k)
                        .and_then(|a| a.unescape_value().ok().map(|v| v.into_owned()))
                };
                let (Some(link1), Some(link2)) = (get(b"link1"), get(b"link2")) else {
                    return Err(Error::parse(
                        source_name,
                        format!("disable_collisions element {n} lacks link1 or link2"),
                    ));
                };
                out.push(DisabledPair {
                    link1,
                    link2,
                    reason: get(b"reason").unwrap_or_default(),
                });
            }
            Event::Eof => break,
            _ => {}
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reads_pairs_and_names_a_bad_one() {
        let t = r#"<robot name="r"><group name="g"/><disable_collisions link1="a" link2="b" reason="Adjacent"/></robot>"#;
        let p = disabled_pairs(t, "r.srdf").unwrap();
        assert_eq!(p[0].link2, "b");
        assert_eq!(p[0].reason, "Adjacent");
        let e = disabled_pairs(
            r#"<robot><disable_collisions link1="a"/></robot>"#,
            "r.srdf",
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("r.srdf") && e.contains("element 1"), "{e}");
        assert!(disabled_pairs("<robot><a></robot>", "r.srdf").is_err());
    }
}

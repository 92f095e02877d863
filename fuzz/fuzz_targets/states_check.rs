//! Every reader of `moma::io::states` on one text, and the checks the commands run on a
//! parsed state against the Panda model (fixed, planar and free-flyer roots).

use moma::io::states::{parse_osc_states, parse_space_states, parse_states, point_loads};
use moma::kinematics::check_state;
use moma::multibody::{Model, RootJoint};
use std::path::Path;
use std::sync::OnceLock;

const PANDA: &str = include_str!("../../scenarios/robots/panda.urdf");

fn models() -> &'static [Model; 3] {
    static M: OnceLock<[Model; 3]> = OnceLock::new();
    M.get_or_init(|| {
        [RootJoint::Fixed, RootJoint::Planar, RootJoint::FreeFlyer].map(|r| {
            moma::io::urdf::model_from_urdf_str(PANDA, r, "panda.urdf")
                .expect("the Panda URDF loads")
        })
    })
}

/// Runs every reader on `text`; panics only on a broken invariant.
pub fn all_readers(text: &str) {
    let path = Path::new("states.json");
    let allowed = ["q", "v", "a", "tau", "u", "external"];
    if let Ok(states) = parse_states(text, path, &allowed) {
        assert!(!states.is_empty() && states.len() <= moma::io::states::MAX_STATES);
        for (i, s) in states.iter().enumerate() {
            for m in models() {
                let _ = check_state(
                    m,
                    "states",
                    Some(&s.q),
                    s.v.as_deref(),
                    s.a.as_deref(),
                    s.tau.as_deref(),
                );
            }
            if let Some(ext) = s.extra.get("external") {
                if let Ok(l) = point_loads(ext, &format!("states[{i}].external"), path) {
                    assert!(l.len() <= moma::io::states::MAX_EXTERNAL);
                    assert!(
                        l.iter()
                            .all(|p| p.point.iter().chain(&p.force).all(|x| x.is_finite()))
                    );
                }
            }
        }
    }
    // A field outside `allowed` is always refused.
    if let Ok(states) = parse_states(text, path, &["q"]) {
        assert!(states.iter().all(|s| s.v.is_none() && s.extra.is_empty()));
    }
    if let Ok(states) = parse_osc_states(text, path) {
        assert!(!states.is_empty());
        let fixed = &models()[0];
        for (k, s) in states.iter().enumerate() {
            let _ = check_state(fixed, "states", Some(&s.q), s.v.as_deref(), None, None);
            for rows in [&[0, 1, 2, 3, 4, 5][..], &[0, 1, 2], &[5]] {
                if let Ok((a, t)) = s.task_inputs(rows, fixed.nv, k, path) {
                    assert_eq!(a.len(), rows.len());
                    assert_eq!(t.len(), fixed.nv);
                    assert!(a.iter().chain(&t).all(|x| x.is_finite()));
                }
            }
        }
    }
    if let Ok(states) = parse_space_states(text, path) {
        assert!(!states.is_empty());
        let ff = &models()[2];
        for (k, s) in states.iter().enumerate() {
            let _ = check_state(ff, "states", Some(&s.q), None, None, None);
            if let Ok(h) = s.check(ff.nv - 6, ff.nv, k, path) {
                assert!(h.iter().all(|x| x.is_finite()));
            }
        }
    }
}

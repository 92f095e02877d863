//! The mission study over the contact plant's parameters and the `[uncertainty]` seed
//! (`docs/sweep.md`): a row is the mission run with the point's `contact.mu` and seed
//! applied, its tip, lift-off and slip columns those of the run; the shipped sweep over
//! seeds and `tip_fraction` (`scenarios/sweeps/mission_contact_seeds.toml`) gives the
//! summary `docs/mission.md` quotes; bad parameters name the file and the field.

use std::path::PathBuf;

use moma::sim::stability_monitor::first_crossing;
use moma::sweep::{Sweep, Value, summarize};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn sweep(params: &str, scenario: &str) -> moma::Result<Sweep> {
    let text = format!(
        "study = \"mission\"\n[parameters]\n{params}\n[mission]\nscenario = \"{}\"\n",
        root().join("scenarios").join(scenario).display()
    );
    Sweep::from_toml_str(&text, &root().join("sweep.toml"), &root())
}

#[test]
fn a_row_is_the_contact_mission_with_the_point_applied() {
    let s = sweep(
        "\"contact.mu\" = [0.8]\nseed = [3]",
        "mission_contact_payload.toml",
    )
    .unwrap();
    let cols = s.columns();
    let row = &s.run(&[0], 1).unwrap().rows[0];
    let col = |n: &str| cols.iter().position(|c| c == n).unwrap();
    // the same point by hand
    let path = root().join("scenarios/mission_contact_payload.toml");
    let mut file = moma::mission::load(&path).unwrap().file;
    file.contact.as_mut().unwrap().mu = Some(0.8);
    file.uncertainty.as_mut().unwrap().seed = 3;
    let m = moma::mission::scenario::from_file(file, &path, &root().join("scenarios")).unwrap();
    assert_eq!(m.contact.as_ref().unwrap().plant.params.mu, 0.8);
    let r = moma::mission::run(&m).unwrap();
    assert_eq!(row[col("reached")], Value::Bool(r.reached));
    assert_eq!(row[col("min_zmp_margin")], Value::opt(r.min_zmp_margin()));
    let tip = first_crossing(&r.samples.t, &r.samples.zmp_margin, false);
    assert_eq!(row[col("tipped")], Value::Bool(tip.is_some()));
    assert_eq!(row[col("tip_time")], Value::opt(tip.map(|c| c.time)));
    let tally = r.contact.as_ref().unwrap();
    let lift = tally.first_lift_off.as_ref();
    assert_eq!(row[col("lift_off_time")], Value::opt(lift.map(|e| e.t)));
    let slip = tally.first_slip.as_ref().map(|e| e.t);
    assert_eq!(row[col("slipped")], Value::Bool(slip.is_some()));
    assert_eq!(row[col("slip_time")], Value::opt(slip));
}

#[test]
fn the_shipped_sweep_shows_what_tip_fraction_buys() {
    let path = root().join("scenarios/sweeps/mission_contact_seeds.toml");
    let s = Sweep::from_file(&path).unwrap();
    assert!(s.has_summary());
    assert_eq!(s.len(), 18);
    let idx: Vec<u64> = (0..s.len()).collect();
    let groups = summarize(&s.run(&idx, 0).unwrap()).unwrap();
    for g in &groups {
        eprintln!(
            "{:?}: success {}, smallest margin {:?}, tipped {:?}, slipped {:?}",
            g.group, g.success_rate, g.min_zmp_margin, g.tipped, g.slipped
        );
    }
    assert_eq!(groups.len(), 3);
    // measured: 0.2 reaches every goal with at least 2.7 cm of margin; 0.3 and 0.8 slide
    // braking for the crate in every seed, hit it in 4 of 6, and seed 3's centre of
    // pressure reaches the support's edge
    let (low, high) = (&groups[0], &groups[2]);
    assert_eq!(low.group, vec![("tip_fraction".into(), "0.2".into())]);
    assert_eq!(low.success_rate, 1.0);
    assert!(low.tipped.is_empty());
    assert!(low.min_zmp_margin.unwrap().0 > 0.02);
    assert!(high.success_rate < 0.5);
    assert_eq!(high.slipped.len(), high.seeds);
    assert!(!high.tipped.is_empty());
    assert!(high.min_zmp_margin.unwrap().0 < low.min_zmp_margin.unwrap().0);
}

#[test]
fn bad_parameters_name_the_field() {
    let e = sweep("\"contact.mu\" = [0.5]", "mission.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("parameters.\"contact.mu\"") && e.contains("rolling plant"),
        "{e}"
    );
    let e = sweep("seed = [1, 2]", "mission_contact.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("parameters.seed") && e.contains("no [uncertainty]"),
        "{e}"
    );
    let e = sweep("seed = [0.5]", "mission_contact_payload.toml")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("parameters.seed: expected a list of whole numbers"),
        "{e}"
    );
    let e = sweep("\"contact.friction\" = [0.5]", "mission_contact.toml")
        .unwrap_err()
        .to_string();
    assert!(e.contains("parameters.contact.friction"), "{e}");
    // a mission sweep without seeds has no summary
    assert!(
        !sweep("v_max = [0.5]", "mission.toml")
            .unwrap()
            .has_summary()
    );
}

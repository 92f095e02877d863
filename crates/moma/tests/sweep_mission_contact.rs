//! The mission study over the contact plant's parameters and the `[uncertainty]` seed and
//! payload (`docs/sweep.md`): a row is the mission run with the point's `contact.mu`, seed
//! and payload applied, its tip, lift-off and slip columns those of the run; the shipped
//! sweeps over seeds and `tip_fraction` (`scenarios/sweeps/mission_contact_seeds.toml`)
//! and over the payload's mass (`scenarios/sweeps/mission_contact_payload_mass.toml`)
//! give the summaries `docs/mission.md` quotes; bad parameters name the file and the
//! field.

use std::path::PathBuf;

use moma::sim::stability_monitor::first_crossing;
use moma::sim::uncertainty::Dist;
use moma::sweep::{Sweep, Table, Value, summarize};

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

/// The column `name` of `table`'s row `k`.
fn cell<'a>(table: &'a Table, k: usize, name: &str) -> &'a Value {
    &table.rows[k][table.column(name).unwrap()]
}

#[test]
fn the_payload_keys_replace_the_drawn_payload() {
    let s = sweep(
        "\"uncertainty.payload.mass\" = [0.0, 8.0]\n\"uncertainty.payload.position[2]\" = [0.05]\n\
         seed = [3]",
        "mission_contact_payload.toml",
    )
    .unwrap();
    let t = s.run(&[0, 1], 1).unwrap();
    // the 8 kg point by hand
    let path = root().join("scenarios/mission_contact_payload.toml");
    let mut file = moma::mission::load(&path).unwrap().file;
    let u = file.uncertainty.as_mut().unwrap();
    u.seed = 3;
    let p = u.payload.as_mut().unwrap();
    p.mass = Dist::Fixed(8.0);
    p.position[2] = Dist::Fixed(0.05);
    let m = moma::mission::scenario::from_file(file, &path, &root().join("scenarios")).unwrap();
    let r = moma::mission::run(&m).unwrap();
    assert_eq!(*cell(&t, 1, "reached"), Value::Bool(r.reached));
    assert_eq!(
        *cell(&t, 1, "min_zmp_margin"),
        Value::opt(r.min_zmp_margin())
    );
    assert_eq!(*cell(&t, 1, "input_work"), Value::Float(r.input_work));
    // 8 kg at the stretched arm's tool moves the centre of pressure towards the front
    // edge: the run's smallest margin shrinks against no payload
    let margin = |k| match cell(&t, k, "min_zmp_margin") {
        Value::Float(x) => *x,
        v => panic!("{v:?}"),
    };
    eprintln!("margins: 0 kg {}, 8 kg {}", margin(0), margin(1));
    assert!(
        margin(1) < margin(0) - 0.01,
        "{} vs {}",
        margin(1),
        margin(0)
    );
}

#[test]
fn the_shipped_sweep_shows_what_tip_fraction_buys() {
    let path = root().join("scenarios/sweeps/mission_contact_seeds.toml");
    let s = Sweep::from_file(&path).unwrap();
    assert!(s.has_summary());
    assert_eq!(s.len(), 18);
    let idx: Vec<u64> = (0..s.len()).collect();
    let table = s.run(&idx, 0).unwrap();
    // the edge a run tipped over, named by its contacts; none without a tip
    for k in 0..table.rows.len() {
        let edge = cell(&table, k, "tip_contact");
        eprintln!(
            "row {k}: tipped {:?}, tip_contact {edge:?}",
            cell(&table, k, "tipped")
        );
        match cell(&table, k, "tipped") {
            Value::Bool(true) => assert_eq!(*edge, Value::Text(TIP_EDGE.into()), "row {k}"),
            _ => assert_eq!(*edge, Value::Missing, "row {k}"),
        }
    }
    let groups = summarize(&table).unwrap();
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

/// The edge seed 3 tips over (measured): the front-left one, from the left drive wheel to
/// the front left caster: the arm and the payload stretched forward, the base braking in
/// a right turn, the centre of pressure pushed forward and to the left.
const TIP_EDGE: &str = "edge left_wheel_joint-front left";

#[test]
fn the_shipped_payload_sweep_shows_how_much_payload_tip_fraction_absorbs() {
    let path = root().join("scenarios/sweeps/mission_contact_payload_mass.toml");
    let s = Sweep::from_file(&path).unwrap();
    assert!(s.has_summary());
    assert_eq!(s.len(), 45);
    let idx: Vec<u64> = (0..s.len()).collect();
    let table = s.run(&idx, 0).unwrap();
    let groups = summarize(&table).unwrap();
    for g in &groups {
        eprintln!(
            "{:?}: success {}, smallest margin {:?}, tipped {:?}, slipped {:?}",
            g.group, g.success_rate, g.min_zmp_margin, g.tipped, g.slipped
        );
    }
    for k in 0..table.rows.len() {
        eprintln!(
            "row {k}: reached {:?} tipped {:?} {:?} at {:?}, slipped {:?}",
            cell(&table, k, "reached"),
            cell(&table, k, "tipped"),
            cell(&table, k, "tip_contact"),
            cell(&table, k, "tip_time"),
            cell(&table, k, "slipped")
        );
    }
    assert_eq!(groups.len(), 15);
    // groups in file order: mass 0, 2, 4, 6, 8 kg, each at tip_fraction 0.1, 0.2, 0.3
    let g = |mass: usize, fraction: usize| &groups[3 * mass + fraction];
    let margin = |mass, fraction| g(mass, fraction).min_zmp_margin.unwrap().0;
    assert_eq!(
        g(3, 1).group,
        vec![
            ("uncertainty.payload.mass".into(), "6.0".into()),
            ("tip_fraction".into(), "0.2".into())
        ]
    );
    // measured: up to 4 kg every seed arrives at every tip_fraction, with at least
    // 1.8 cm of margin
    for mass in 0..3 {
        for fraction in 0..3 {
            assert_eq!(g(mass, fraction).success_rate, 1.0);
            assert!(g(mass, fraction).tipped.is_empty());
            assert!(margin(mass, fraction) > 0.018);
        }
    }
    // up to 6 kg, the heavier the payload the smaller the margin, and the smaller
    // tip_fraction the larger
    for fraction in 0..3 {
        for mass in 1..4 {
            assert!(margin(mass, fraction) < margin(mass - 1, fraction));
        }
    }
    for mass in 0..4 {
        assert!(margin(mass, 0) > margin(mass, 1) && margin(mass, 1) > margin(mass, 2));
    }
    // 6 kg: only 0.1 keeps the centre of pressure inside (0.4 cm); at 0.2 and 0.3 two of
    // three seeds tip. 8 kg: every run tips, whatever the fraction.
    assert!(g(3, 0).tipped.is_empty() && margin(3, 0) > 0.0);
    assert_eq!(g(3, 1).tipped, vec![0, 2]);
    assert_eq!(g(3, 2).tipped, vec![0, 2]);
    for fraction in 0..3 {
        assert_eq!(g(4, fraction).tipped, vec![0, 1, 2]);
        assert_eq!(g(4, fraction).success_rate, 0.0);
    }
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
    let e = sweep(
        "\"uncertainty.payload.mass\" = [1.0]",
        "mission_contact.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("parameters.\"uncertainty.payload.mass\"")
            && e.contains("no uncertainty.payload"),
        "{e}"
    );
    let e = sweep(
        "\"uncertainty.payload.mass\" = [2.0, -1.0]",
        "mission_contact_payload.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("parameters.uncertainty.payload.mass: must be >= 0 kg, got -1"),
        "{e}"
    );
    let e = sweep(
        "\"uncertainty.payload.position[3]\" = [0.1]",
        "mission_contact_payload.toml",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("parameters.uncertainty.payload.position[3]: unknown parameter"),
        "{e}"
    );
    // a mission sweep without seeds has no summary
    assert!(
        !sweep("v_max = [0.5]", "mission.toml")
            .unwrap()
            .has_summary()
    );
}

//! The uncertainty study on `scenarios/sweeps/uncertainty_brake.toml`: with a 0.5 kg
//! payload every seed stops without tipping; with 4 kg at the tool the stop tips every
//! seed (the nominal robot's smallest ZMP margin is 0.051 m). And the rows repeat exactly
//! whatever the thread count.

use moma::sweep::{Sweep, Value, summarize};

#[test]
fn a_heavy_payload_tips_every_seed_and_a_light_one_none() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/sweeps/uncertainty_brake.toml");
    let sweep = Sweep::from_file(&path).unwrap();
    let idx: Vec<u64> = (0..sweep.len()).collect();
    let table = sweep.run(&idx, 2).unwrap();
    let groups = summarize(&table).unwrap();
    assert_eq!(groups.len(), 2);
    assert_eq!(groups[0].group, vec![("payload_mass".into(), "0.5".into())]);
    assert_eq!(groups[0].success_rate, 1.0);
    assert!(groups[0].tipped.is_empty());
    assert!(groups[0].min_zmp_margin.unwrap().0 > 0.0);
    assert_eq!(groups[1].success_rate, 0.0);
    assert_eq!(groups[1].tipped.len(), groups[1].seeds);
    assert!(groups[1].min_zmp_margin.unwrap().0 < 0.0);
    let one = sweep.run(&idx, 1).unwrap();
    let strip = |t: &moma::sweep::Table| -> Vec<Vec<Value>> {
        t.rows.iter().map(|r| r[..r.len() - 1].to_vec()).collect()
    };
    assert_eq!(strip(&table), strip(&one));
}

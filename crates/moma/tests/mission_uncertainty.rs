//! `moma mission` with an `[uncertainty]` table: the plant is built from the perturbed
//! model while the planner, reference, law and computed torque keep the nominal one, and
//! the law measures the plant's state through the table's sensor noise. A payload of 0 kg
//! or noise of zero leaves the default mission as it was; a heavy payload on the tool
//! changes what the plant does (its smallest ZMP margin); noise changes what the law
//! does, the same way for the same seed; on the contact plant the draw perturbs the
//! plant's model and its wheels' μ, and a μ below what the mission's turns need makes
//! the wheels slide; the draw depends on the seed only; a bad table names the file and
//! the `uncertainty.*` field.

mod mission_common;

use mission_common::{appended, load, run};
use moma::mission::{Mission, MissionResult};

/// The default mission with `table` appended, validated as if it were the file.
fn with_table(table: &str) -> moma::Result<Mission> {
    appended("mission.toml", table)
}

/// Largest difference of the recorded configurations of two runs of the same length.
fn max_q_difference(a: &MissionResult, b: &MissionResult) -> f64 {
    assert_eq!(a.samples.t, b.samples.t, "the same sample times");
    a.samples
        .q
        .iter()
        .zip(&b.samples.q)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).abs()))
        .fold(0.0, f64::max)
}

const HEAVY: &str = "[uncertainty]\nseed = 7\n\
    payload = { link = \"tool0\", mass = { uniform = [2.0, 3.0] }, position = [0.0, 0.0, 0.1] }";

#[test]
fn a_payload_of_nothing_reproduces_the_nominal_mission_and_a_heavy_one_does_not() {
    let nominal_m = load("mission.toml");
    assert!(nominal_m.plant_robot.is_none());
    let nominal = run(&nominal_m);
    assert!(nominal.reached, "{:?}", nominal.reason);

    let zero = with_table(
        "[uncertainty]\nseed = 1\npayload = { link = \"tool0\", mass = 0.0 }\nlink_mass_scale = 1.0",
    )
    .unwrap();
    assert!(zero.plant_robot.is_some());
    let same = run(&zero);
    assert!(same.reached, "{:?}", same.reason);
    assert_eq!(max_q_difference(&nominal, &same), 0.0);
    assert_eq!(nominal.samples.zmp_margin, same.samples.zmp_margin);
    let (z0, z1) = (
        nominal.min_zmp_margin().unwrap(),
        same.min_zmp_margin().unwrap(),
    );
    assert!((z0 - z1).abs() < 1e-9, "{z0} vs {z1}");

    let heavy_m = with_table(HEAVY).unwrap();
    let heavy = run(&heavy_m);
    let zh = heavy.min_zmp_margin().unwrap();
    eprintln!(
        "smallest ZMP margin: nominal {z0} m, 0 kg {z1} m, heavy {zh} m (reached {}, {:?})",
        heavy.reached, heavy.reason
    );
    assert!(zh < z0 - 1e-3, "heavy payload: {zh} m, nominal {z0} m");
    // the law's nominal model under-holds the payload: the reach falls short
    assert!(!heavy.reached);

    // the same seed draws the same payload and runs the same; another draws another
    let again = run(&with_table(HEAVY).unwrap());
    assert_eq!(heavy.samples.q, again.samples.q);
    let other_m = with_table(&HEAVY.replace("seed = 7", "seed = 8")).unwrap();
    let other = run(&other_m);
    let zo = other.min_zmp_margin().unwrap();
    eprintln!(
        "seed 8: smallest ZMP margin {zo} m, {} samples (seed 7: {})",
        other.samples.t.len(),
        heavy.samples.t.len()
    );
    assert_ne!(heavy.samples.q, other.samples.q);
    assert_ne!(zh, zo);
}

#[test]
fn a_bad_table_names_the_file_and_field() {
    let err = |t: &str| with_table(t).unwrap_err().to_string();
    let e = err("[uncertainty]\nseed = 1\npayload = { link = \"tool0\", mass = -1.0 }");
    assert!(
        e.contains("mission.toml") && e.contains("uncertainty.payload.mass"),
        "{e}"
    );
    let e = err("[uncertainty]\nseed = 1\npayload = { link = \"no_such_link\", mass = 1.0 }");
    assert!(
        e.contains("mission.toml") && e.contains("uncertainty.payload.link"),
        "{e}"
    );
    let e = err("[uncertainty]\nseed = 1\nlink_mass_scale = 0.0");
    assert!(e.contains("uncertainty.link_mass_scale"), "{e}");
    let e = err("[uncertainty]\nseed = 1\nsensor_noise = { v = [0.01, 0.01] }");
    assert!(
        e.contains("mission.toml") && e.contains("uncertainty.sensor_noise.v: expected"),
        "{e}"
    );
    let e = err("[uncertainty]\nseed = 1\nsensor_noise = { q = [0.01, -0.01] }");
    assert!(e.contains("uncertainty.sensor_noise.q[1]"), "{e}");
    let e = err("[uncertainty]\nseed = 1\nmu = 0.5");
    assert!(e.contains("uncertainty.mu"), "{e}");
    // unknown keys are refused by the table's schema
    let e = err("[uncertainty]\nseed = 1\nfriction = 0.3");
    assert!(e.contains("friction"), "{e}");
}

/// `sensor_noise = { q = [σ_q…], v = [σ_v…] }` with one deviation per coordinate and
/// velocity of `m`'s robot, each `q` and `v` (the base pose and speeds only, the joints
/// exact).
fn noise_table(m: &Mission, seed: u64, q: f64, v: f64) -> String {
    let (nq, nv) = (m.robot.q_names().len(), m.robot.v_names().len());
    let list = |n: usize, base: usize, s: f64| {
        let xs: Vec<String> = (0..n)
            .map(|i| if i < base { s } else { 0.0 }.to_string())
            .collect();
        xs.join(", ")
    };
    format!(
        "[uncertainty]\nseed = {seed}\nsensor_noise = {{ q = [{}], v = [{}] }}",
        list(nq, 3, q),
        list(nv, 2, v)
    )
}

#[test]
fn noise_of_zero_changes_nothing_and_seeded_noise_is_reproducible() {
    let nominal_m = load("mission.toml");
    let nominal = run(&nominal_m);
    // zero deviations: no noise, no perturbation; the run is the nominal one bit for bit
    let zero_m = with_table(&noise_table(&nominal_m, 3, 0.0, 0.0)).unwrap();
    assert!(zero_m.sensor_noise.is_none() && zero_m.plant_robot.is_none());
    assert_eq!(run(&zero_m).samples, nominal.samples);
    // 5 mm / 5 mrad on the measured pose, 2 cm/s / 2 cm rad/s on the measured speeds
    let noisy_m = with_table(&noise_table(&nominal_m, 3, 0.005, 0.02)).unwrap();
    assert!(noisy_m.sensor_noise.is_some() && noisy_m.plant_robot.is_none());
    let noisy = run(&noisy_m);
    let again = run(&noisy_m);
    assert_eq!(noisy.samples, again.samples, "the same seed runs the same");
    let other = run(&with_table(&noise_table(&nominal_m, 4, 0.005, 0.02)).unwrap());
    assert_ne!(
        noisy.samples.q, other.samples.q,
        "another seed, other noise"
    );
    assert_ne!(noisy.samples.q, nominal.samples.q);
    // the record is the plant's true state: the noise makes the law's torques rough, not
    // the recorded path; the base still reaches its goal
    let rough = |r: &MissionResult| {
        r.samples
            .u
            .windows(2)
            .map(|w| (w[1][0] - w[0][0]).abs())
            .fold(0.0, f64::max)
    };
    eprintln!(
        "noisy: reached {} ({:?}), largest tracking error {:?} m (nominal {:?}), largest \
         wheel-torque step {} N m (nominal {}), smallest ZMP margin {:?} (nominal {:?})",
        noisy.reached,
        noisy.reason,
        noisy.max_tracking_error(),
        nominal.max_tracking_error(),
        rough(&noisy),
        rough(&nominal),
        noisy.min_zmp_margin(),
        nominal.min_zmp_margin()
    );
    assert!(rough(&noisy) > 2.0 * rough(&nominal));
    assert!(noisy.events.iter().any(|e| e.kind == "arrived"));
}

#[test]
fn on_the_contact_plant_the_draw_perturbs_the_plant_and_its_friction() {
    let nominal_m = load("mission_contact.toml");
    let nominal_mass = nominal_m.contact.as_ref().unwrap().plant.model.total_mass();
    // a payload and μ drawn for the plant; the law's model is the nominal one
    let m = appended(
        "mission_contact.toml",
        "[uncertainty]\nseed = 2\nmu = { uniform = [0.8, 0.9] }\n\
         payload = { link = \"tool0\", mass = 1.5 }",
    )
    .unwrap();
    let plant = &m.contact.as_ref().unwrap().plant;
    assert!((plant.model.total_mass() - nominal_mass - 1.5).abs() < 1e-9);
    assert_eq!(
        m.robot.model.total_mass(),
        nominal_m.robot.model.total_mass()
    );
    assert!(m.plant_robot.is_none());
    let mu = plant.params.mu;
    assert!((0.8..=0.9).contains(&mu), "{mu}");
    // what the mission needs: the rolling mission's friction demand (its slip ratio times
    // limits.mu), largest where it drives straight (|ω| < 0.05 rad/s: accelerating and
    // braking) and where it turns. A μ drawn between the two makes the wheels slide, and
    // first in a turn.
    let rolling = run(&load("mission.toml"));
    let (mut straight, mut turn) = (0.0f64, 0.0f64);
    for (ratio, w) in rolling
        .samples
        .slip_ratio
        .iter()
        .zip(&rolling.samples.omega)
    {
        let need = ratio.unwrap_or(0.0) * rolling_mu();
        if w.abs() < 0.05 {
            straight = straight.max(need);
        } else {
            turn = turn.max(need);
        }
    }
    assert!(straight < turn, "straight {straight}, turn {turn}");
    let between = |f: f64| straight + f * (turn - straight);
    let low = format!(
        "[uncertainty]\nseed = 2\nmu = {{ uniform = [{}, {}] }}",
        between(0.25),
        between(0.4)
    );
    let slippery_m = appended("mission_contact.toml", &low).unwrap();
    let r = run(&slippery_m);
    let tally = r.contact.as_ref().unwrap();
    let slip = tally.first_slip.as_ref().expect("the wheels slide");
    let k = r.samples.t.partition_point(|t| *t < slip.t);
    let w = r.samples.omega[k];
    eprintln!(
        "friction needed: {straight} straight, {turn} in a turn; drawn μ {}: first slip at \
         {} s ('{}', ω = {w} rad/s), reached {}",
        slippery_m.contact.as_ref().unwrap().plant.params.mu,
        slip.t,
        slip.contact,
        r.reached
    );
    assert!(w.abs() > 0.1, "the first slip is in a turn: ω = {w} rad/s");
    assert!(r.events.iter().any(|e| e.kind == "slip"));
    // and the nominal μ = 1 does not
    let fine = run(&m);
    assert_eq!(fine.contact.as_ref().unwrap().first_slip, None);
}

/// `limits.mu` of the default mission (the friction its slip monitor divides by).
fn rolling_mu() -> f64 {
    load("mission.toml").file.limits.mu
}

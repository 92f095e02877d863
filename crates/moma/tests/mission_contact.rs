//! `moma mission` on the contact plant (`simulation.plant = "contact"`): the shipped
//! `scenarios/mission_contact.toml` (the default mission with μ = 1) reaches its goal
//! along the rolling mission's path with nothing slipping or lifting off; on ice the
//! plant's own slip flag makes the event; bad contact parameters are errors naming the
//! field before anything runs.

mod mission_common;

use mission_common::{load, run};
use moma::mission::{self, Mission, MissionResult};
use moma::mobile::wheeled::wheel_longitudinal_forces;

/// `mission_contact.toml` with `from` replaced by `to`, validated as if it were the file.
fn variant(from: &str, to: &str) -> moma::Result<Mission> {
    mission_common::variant("mission_contact.toml", from, to)
}

/// Largest deviations of the contact run from the rolling run, sample by sample (the
/// same control steps and record interval): base position (m), heading (rad), arm
/// joints (rad).
fn deviation(m: &Mission, rolling: &MissionResult, contact: &MissionResult) -> [f64; 3] {
    assert_eq!(
        rolling.samples.t, contact.samples.t,
        "the same sample times"
    );
    let arm: Vec<usize> = m.robot.arm_dofs().to_vec();
    let mut d = [0.0f64; 3];
    for (a, b) in rolling.samples.q.iter().zip(&contact.samples.q) {
        d[0] = d[0].max((a[0] - b[0]).hypot(a[1] - b[1]));
        d[1] = d[1].max((a[2] - b[2]).abs());
        for &i in &arm {
            d[2] = d[2].max((a[i] - b[i]).abs());
        }
    }
    d
}

#[test]
fn the_default_mission_on_the_contact_plant_follows_the_rolling_mission() {
    let rolling_m = load("mission.toml");
    let contact_m = load("mission_contact.toml");
    assert!(rolling_m.contact.is_none() && contact_m.contact.is_some());
    let rolling = run(&rolling_m);
    let contact = run(&contact_m);
    assert!(contact.reached, "{:?}", contact.reason);
    assert!(rolling.reached, "{:?}", rolling.reason);
    // the same law, phases and re-plan: one re-plan after the crate, at the same time
    assert_eq!(contact.replans(), 1);
    assert_eq!(contact.plans[1].t, rolling.plans[1].t);
    // measured: 3.3 mm, 5.4 mrad, 7.4 mrad; held to 1 cm, 15 mrad, 20 mrad
    let [pos, heading, joints] = deviation(&contact_m, &rolling, &contact);
    assert!(pos < 0.01, "base position deviates by {pos} m");
    assert!(heading < 0.015, "heading deviates by {heading} rad");
    assert!(joints < 0.02, "arm joints deviate by {joints} rad");
    // what the plant did: nothing slid or lifted off, the base stayed level
    let tally = contact
        .contact
        .as_ref()
        .expect("a contact run has its tally");
    assert!(rolling.contact.is_none());
    assert_eq!(tally.first_lift_off, None);
    assert_eq!(tally.first_slip, None);
    assert!(tally.max_tilt < 0.01, "tilt {}", tally.max_tilt);
    assert!(tally.totals.iter().all(|t| t.min_normal > 0.0));
    assert!(
        !contact
            .events
            .iter()
            .any(|e| e.kind == "slip" || e.kind == "lift_off")
    );
    // the monitors are the plant's: the start touches the ground without load (no centre
    // of pressure), then every sample has its centre-of-pressure margin, well inside the
    // support, and wheel friction below μ N
    assert_eq!(contact.samples.zmp_margin[0], None);
    assert!(contact.samples.zmp_margin[1..].iter().all(|z| z.is_some()));
    let zmp = contact.min_zmp_margin().unwrap();
    assert!(zmp > 0.1, "min ZMP margin {zmp}");
    let slip = contact.max_slip_ratio().unwrap();
    assert!(slip < 0.5, "largest slip ratio {slip}");
    // Force-Angle and Moment-Height of the plant's own state (stability::evaluate on its
    // free-flyer model, velocity and last step's acceleration) against the rolling
    // plant's, sample by sample once the plant has stepped. They differ most where the
    // torques jump (start, re-plan, reach) and the contacts' springs answer over a few
    // milliseconds; measured: largest 36 mrad and 1.58 1/s², 99 % of samples within 3.5
    // mrad and 0.092 1/s², the run's smallest values within 0.45 mrad and 0.013 1/s².
    let (s, r) = (&contact.samples, &rolling.samples);
    assert_eq!((s.force_angle_min[0], s.mhs_min[0]), (None, None));
    let deviations = |a: &[Option<f64>], b: &[Option<f64>]| {
        let mut d: Vec<f64> = a[1..]
            .iter()
            .zip(&b[1..])
            .map(|(x, y)| (x.expect("contact measure") - y.expect("rolling measure")).abs())
            .collect();
        d.sort_by(|x, y| y.total_cmp(x));
        (d[0], d[d.len() / 100])
    };
    let (fa, fa99) = deviations(&s.force_angle_min, &r.force_angle_min);
    let (mhs, mhs99) = deviations(&s.mhs_min, &r.mhs_min);
    let (fa0, mhs0) = (
        rolling.min_force_angle().unwrap(),
        rolling.min_mhs().unwrap(),
    );
    let (fa1, mhs1) = (
        contact.min_force_angle().unwrap(),
        contact.min_mhs().unwrap(),
    );
    eprintln!(
        "Force-Angle: deviation largest {fa} rad, 99 % {fa99} rad; smallest {fa1} (rolling \
         {fa0}). Moment-Height: deviation largest {mhs}, 99 % {mhs99}; smallest {mhs1} \
         (rolling {mhs0})"
    );
    assert!(fa < 0.05 && fa99 < 0.01, "Force-Angle deviates by {fa} rad");
    assert!(mhs < 2.0 && mhs99 < 0.2, "Moment-Height deviates by {mhs}");
    assert!(
        (fa1 - fa0).abs() < 2e-3,
        "smallest Force-Angle {fa1} vs {fa0}"
    );
    assert!(
        (mhs1 - mhs0).abs() < 0.05,
        "smallest Moment-Height {mhs1} vs {mhs0}"
    );
    // the summary names what the contacts did
    let s = mission::summary(&contact_m, &contact);
    assert_eq!(s["contact"]["first_slip"], serde_json::Value::Null);
    assert_eq!(s["contact"]["totals"].as_array().unwrap().len(), 6);
    assert!(!mission::summary(&rolling_m, &rolling).contains_key("contact"));
}

#[test]
fn on_ice_the_wheels_slide_and_the_plant_reports_it() {
    let m = variant("mu = 1.0", "mu = 0.1").unwrap();
    let r = run(&m);
    let tally = r.contact.as_ref().unwrap();
    let slip = tally.first_slip.as_ref().expect("the wheels slide on ice");
    assert!(slip.contact.ends_with("wheel_joint"), "{}", slip.contact);
    let event = r.events.iter().find(|e| e.kind == "slip").expect("event");
    assert_eq!(event.t, slip.t);
    // sliding wheels deliver μ N and no more
    let ratio = r.max_slip_ratio().unwrap();
    assert!((ratio - 1.0).abs() < 1e-9, "slip ratio {ratio}");
    assert!(!r.reached);
}

#[test]
fn bad_contact_input_names_the_field_before_running() {
    let cases = [
        ("mu = 1.0", "mu = 0.0", "contact.mu"),
        ("mu = 1.0", "mu = -0.5", "contact.mu"),
        // 1e12 N/m on a contact's normal effective mass (tens of kg) needs a step of
        // about 1e-5 s, ten times below contact.dt
        (
            "mu = 1.0",
            "mu = 1.0\nstiffness = 1e12",
            "contact.stiffness",
        ),
        ("mu = 1.0", "mu = 1.0\ndt = 3e-4", "contact.dt"),
        (
            "frame = \"caster_rear_right\"",
            "frame = \"no_such_frame\"",
            "no_such_frame",
        ),
        (
            "plant = \"contact\"",
            "plant = \"rolling\"",
            "contact: the [contact] table is read only",
        ),
    ];
    for (from, to, field) in cases {
        let e = variant(from, to).expect_err(to).to_string();
        assert!(e.contains(field), "{to}: {e}");
        assert!(e.contains("mission_contact.toml"), "{to}: {e}");
    }
    // the contact plant needs its table
    let e = mission_common::variant(
        "mission.toml",
        "[output]",
        "[simulation]\nplant = \"contact\"\n[output]",
    )
    .unwrap_err()
    .to_string();
    assert!(e.contains("simulation.plant"), "{e}");
}

/// The contact plant's normal forces over the shipped mission against the rolling
/// model's normal loads at the same state: `StabilityMonitor::sample` on the mission's
/// robot at each recorded driving sample of the contact run (its configuration, forward
/// speed, yaw rate and torques; the arm's rates by central differences of the recorded
/// joints, which the transport posture holds nearly still). With more than three
/// contacts the monitor's rule is the minimum-norm one, loads affine in the contact
/// position — what equal springs under a rigid base give, and the plant's springs are
/// equal (the casters are fixed balls at the description's positions, no trail). The
/// wheels' friction (`samples.contact_friction`) against the multipliers λ of the same
/// sample: each wheel's traction against the rolling rows' −λ₁, −λ₂, the summed lateral
/// force against the no-side-slip row's −λ₀.
#[test]
fn over_the_mission_the_contact_forces_match_the_rolling_loads_and_multipliers() {
    use moma::sim::stability_monitor::{StabilityMonitor, StabilitySettings};
    use moma::stability::{BodySet, LoadRule};
    // the plant's first samples: it sinks onto its springs from touching without load
    const SETTLE: f64 = 0.2;
    // a torque step (N·m) between two samples: the recorded torques are those of the
    // next control period, the plant's forces still those of the last
    const STEP: f64 = 0.1;
    let m = load("mission_contact.toml");
    let r = run(&m);
    assert!(r.reached, "{:?}", r.reason);
    let s = &r.samples;
    let settings = StabilitySettings {
        mu: None,
        bodies: BodySet::All,
        ground_z: None,
        stop_at_tip: false,
    };
    let mut monitor = StabilityMonitor::new(&m.robot, settings).unwrap();
    let names = monitor.contact_names().to_vec();
    assert_eq!(names.len(), 6);
    let arm = m.robot.arm_dofs().to_vec();
    let mut v = vec![0.0; m.robot.nr()];
    // (|difference|, time, contact) of the samples after no torque step, and of those
    let (mut smooth, mut stepped) = (Vec::new(), Vec::new());
    let mut swing = 0.0f64;
    // the wheels' forces: (|difference|, time) of each wheel's traction and of the
    // summed lateral force, after no torque step; the largest of each, rolling
    let (mut traction, mut lateral) = (Vec::new(), Vec::new());
    let (mut traction_max, mut lateral_max) = (0.0f64, 0.0f64);
    for k in 1..s.t.len() - 1 {
        if s.phase[k] != "drive" || s.t[k] < SETTLE {
            continue;
        }
        v[0] = s.v[k];
        v[1] = s.omega[k];
        for (j, &i) in arm.iter().enumerate() {
            v[2 + j] = (s.q[k + 1][i] - s.q[k - 1][i]) / (s.t[k + 1] - s.t[k - 1]);
        }
        monitor.sample(s.t[k], &s.q[k], &v, &s.u[k]).unwrap();
        assert_eq!(monitor.load_rule(), Some(LoadRule::MinimumNorm));
        let step = s.u[k]
            .iter()
            .zip(&s.u[k - 1])
            .any(|(a, b)| (a - b).abs() > STEP);
        // each wheel's traction against the rolling rows' −λ₁, −λ₂, their summed lateral
        // force against the no-side-slip row's −λ₀
        let lambda = monitor.multipliers().as_slice();
        let rolling = wheel_longitudinal_forces(&m.robot, lambda, &s.u[k]);
        let (sn, cs) = s.q[k][2].sin_cos();
        let f = &s.contact_friction[k];
        let lat: f64 = f[..2].iter().map(|w| -w[0] * sn + w[1] * cs).sum();
        if !step {
            for w in 0..2 {
                let along = f[w][0] * cs + f[w][1] * sn;
                traction.push(((along - rolling[w]).abs(), s.t[k]));
                traction_max = traction_max.max(rolling[w].abs());
            }
            lateral.push(((lat + lambda[0]).abs(), s.t[k]));
            lateral_max = lateral_max.max(lambda[0].abs());
        }
        let rows = if step { &mut stepped } else { &mut smooth };
        let at_rest = &s.contact_normal[1];
        for (c, (plant, rolling)) in s.contact_normal[k]
            .iter()
            .zip(monitor.normal_loads())
            .enumerate()
        {
            rows.push(((plant - rolling).abs(), s.t[k], c));
            swing = swing.max((rolling - at_rest[c]).abs());
        }
    }
    let weight: f64 = s.contact_normal[1].iter().sum();
    let (n_smooth, n_stepped) = (smooth.len() / 6, stepped.len() / 6);
    eprintln!(
        "{n_smooth} driving samples after no torque step, {n_stepped} after one; weight \
         {weight:.1} N, the rolling loads swing by up to {swing:.1} N from rest"
    );
    let mut largest = [0.0f64; 2];
    for (i, (label, rows)) in [("no step", &mut smooth), ("step", &mut stepped)]
        .into_iter()
        .enumerate()
    {
        rows.sort_by(|a, b| b.0.total_cmp(&a.0));
        let rms = (rows.iter().map(|x| x.0 * x.0).sum::<f64>() / rows.len() as f64).sqrt();
        largest[i] = rows[0].0;
        eprintln!(
            "{label}: largest {:.3} N, 99 % {:.3} N, RMS {rms:.3} N; largest at",
            rows[0].0,
            rows[rows.len() / 100].0
        );
        for (d, t, c) in rows.iter().take(6) {
            eprintln!("  {d:.3} N at {t:.2} s on {}", names[*c]);
        }
    }
    for (label, rows, of) in [
        ("traction", &mut traction, traction_max),
        ("lateral", &mut lateral, lateral_max),
    ] {
        rows.sort_by(|a, b| b.0.total_cmp(&a.0));
        let rms = (rows.iter().map(|x| x.0 * x.0).sum::<f64>() / rows.len() as f64).sqrt();
        eprintln!(
            "{label} (up to {of:.2} N): largest {:.4} N at {:.2} s, 99 % {:.4} N, RMS {rms:.4} N",
            rows[0].0,
            rows[0].1,
            rows[rows.len() / 100].0
        );
        for (d, t) in rows.iter().take(5) {
            eprintln!("  {d:.4} N at {t:.2} s");
        }
    }
    // Measured, after no torque step (a wheel or joint torque changing by more than
    // 0.1 N·m between samples; 58 of the 1101 driving samples): normal forces largest
    // 0.83 N (at 20.30 s, turning towards the shelf), 99 % within 0.31 N, RMS 0.12 N,
    // against loads that swing by 45.5 N on an 802 N robot; traction largest 0.20 N
    // (0.96 s, accelerating), 99 % within 0.14 N, RMS 0.026 N, of up to 23.4 N; summed
    // lateral force largest 0.93 N (20.30 s, turning), 99 % within 0.69 N, RMS 0.20 N,
    // of up to 35.6 N (the wheels creep sideways: friction is viscous below v_ε). At a
    // step the recorded torques are the next control period's and the plant has not yet
    // felt them: normal forces off by up to 10.9 N (2.00 s, the end of the acceleration:
    // the pitch load the step moves between front and rear casters; 9.0 N at 5.10 s,
    // braking for the crate).
    assert!(
        swing > 30.0,
        "the loads should move while driving: {swing} N"
    );
    assert!(
        traction_max > 15.0 && lateral_max > 20.0,
        "forces too small"
    );
    assert!(n_stepped * 12 < n_smooth, "{n_stepped} torque steps");
    let quantile = |rows: &[(f64, f64)]| rows[rows.len() / 100].0;
    let rms = |rows: &[(f64, f64)]| {
        (rows.iter().map(|x| x.0 * x.0).sum::<f64>() / rows.len() as f64).sqrt()
    };
    let normal: Vec<(f64, f64)> = smooth.iter().map(|x| (x.0, x.1)).collect();
    for (label, rows, [max, q99, rms_max]) in [
        ("normal force", &normal, [1.5, 0.5, 0.2]),
        ("traction", &traction, [0.4, 0.25, 0.05]),
        ("lateral force", &lateral, [1.5, 1.0, 0.3]),
    ] {
        assert!(
            rows[0].0 < max,
            "{label} differs by {} N at {} s",
            rows[0].0,
            rows[0].1
        );
        assert!(quantile(rows) < q99, "{label}: 99 % {} N", quantile(rows));
        assert!(rms(rows) < rms_max, "{label}: RMS {} N", rms(rows));
    }
    assert!(
        largest[1] < 15.0,
        "normal force at a torque step: {} N",
        largest[1]
    );
}

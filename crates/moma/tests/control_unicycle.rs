//! The unicycle laws against the reference runs, Lyapunov monitors along closed loops,
//! and Brockett's obstruction in a closed loop.

use moma::closed_form::cases::evaluate_document;
use moma::control::Controller;
use moma::control::lyapunov::LyapunovMonitor;
use moma::control::unicycle::{
    Aicardi, Astolfi, ConstantInputReference, Kanayama, Pose, Samson, WheelLimits, unicycle_rhs,
};
use moma::mobile::DiffDrive;
use moma::sim::{AdaptiveOptions, Dop853, OdeSystem};
use serde_json::Value;

fn load(name: &str) -> Value {
    let p = format!("{}/tests/data/control/{name}", env!("CARGO_MANIFEST_DIR"));
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

fn flat(v: &Value) -> Vec<f64> {
    match v {
        Value::Array(a) => a.iter().flat_map(flat).collect(),
        Value::Number(n) => vec![n.as_f64().unwrap()],
        _ => panic!("not numeric: {v}"),
    }
}

#[test]
fn eval_matches_public_cases() {
    let reference = load("unicycle_control.json");
    // Strip the expected values so nothing can leak from input to output.
    let mut input = reference.clone();
    for c in input["cases"].as_array_mut().unwrap() {
        let tr = c["trajectory"].as_object_mut().unwrap();
        tr.retain(|k, _| k == "t");
    }
    let out = evaluate_document(&input, 1e-12).unwrap();
    for (r, o) in reference["cases"]
        .as_array()
        .unwrap()
        .iter()
        .zip(out["cases"].as_array().unwrap())
    {
        for key in ["state", "v", "w", "V"] {
            match r["trajectory"].get(key) {
                Some(want) => {
                    let got = flat(&o["trajectory"][key]);
                    let want = flat(want);
                    assert_eq!(got.len(), want.len());
                    for (g, w) in got.iter().zip(&want) {
                        assert!((g - w).abs() < 1e-8, "case {} {key}: {g} vs {w}", r["id"]);
                    }
                }
                None => assert!(o["trajectory"].get(key).is_none(), "{key} for {}", r["law"]),
            }
        }
    }
}

#[test]
fn eval_names_violated_astolfi_condition_and_warns_on_strong_one() {
    let mut doc = load("unicycle_control.json");
    doc["cases"] = serde_json::json!([doc["cases"][2].clone()]);
    doc["cases"][0]["gains"]["k_beta"] = serde_json::json!(0.2);
    let e = evaluate_document(&doc, 1e-10).unwrap_err().to_string();
    assert!(e.contains("k_beta < 0") && e.contains("case 10"), "{e}");
    doc["cases"][0]["gains"] = serde_json::json!({"k_rho": 1.0, "k_alpha": 1.2, "k_beta": -0.5});
    let out = evaluate_document(&doc, 1e-10).unwrap();
    let w = out["cases"][0]["warnings"][0].as_str().unwrap();
    assert!(w.contains("strong condition"), "{w}");
    doc["cases"][0]["law"] = serde_json::json!("brockett");
    let e = evaluate_document(&doc, 1e-10).unwrap_err().to_string();
    assert!(e.contains("unknown law"), "{e}");
}

/// A closed-loop case's horizon is bounded like the chapter cases' (`MAX_CASE_TIME`).
#[test]
fn eval_refuses_a_horizon_past_the_case_bound() {
    let mut doc = load("unicycle_control.json");
    doc["cases"] = serde_json::json!([doc["cases"][0].clone()]);
    doc["cases"][0]["trajectory"]["t"] = serde_json::json!([0.0, 1.0, 1e9]);
    let e = evaluate_document(&doc, 1e-10).unwrap_err().to_string();
    assert!(e.contains("trajectory.t[2]") && e.contains("1000"), "{e}");
}

#[test]
fn kanayama_with_zero_yaw_rate_follows_a_line() {
    let doc = serde_json::json!({"model": "unicycle_control", "cases": [{
        "id": "line", "law": "kanayama", "gains": {"Kx": 1.0, "Ky": 4.0, "Kth": 4.0},
        "reference": {"vr": 0.5, "wr": 0.0}, "initial_state": [0.2, -0.3, 0.5],
        "trajectory": {"t": [0.0, 30.0]}}]});
    let out = evaluate_document(&doc, 1e-12).unwrap();
    let s = flat(&out["cases"][0]["trajectory"]["state"]);
    assert!(
        (s[3] - 15.0).abs() < 1e-6 && s[4].abs() < 1e-6 && s[5].abs() < 1e-6,
        "{s:?}"
    );
}

struct Closed<F: FnMut(f64, &Pose) -> [f64; 2]>(F);

impl<F: FnMut(f64, &Pose) -> [f64; 2]> OdeSystem for Closed<F> {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> moma::Result<()> {
        let s = [x[0], x[1], x[2]];
        dx.copy_from_slice(&unicycle_rhs(&s, &(self.0)(t, &s)));
        Ok(())
    }
}

fn run<F: FnMut(f64, &Pose) -> [f64; 2]>(f: F, x0: Pose, times: &[f64]) -> Vec<Pose> {
    let mut dp = Dop853::new(3, AdaptiveOptions::with_tolerance(1e-12)).unwrap();
    dp.solve_at(&mut Closed(f), 0.0, &x0, times)
        .unwrap()
        .into_iter()
        .map(|r| [r[0], r[1], r[2]])
        .collect()
}

fn grid(t_end: f64, n: usize) -> Vec<f64> {
    (0..=n).map(|k| t_end * k as f64 / n as f64).collect()
}

/// The worked runs of theory.md 2.3–2.5 (nonholonomic_controllers.json).
#[test]
fn theory_worked_runs() {
    let d = load("nonholonomic_controllers.json");
    let samples = |law: &str| -> Vec<(f64, Value)> {
        d[law]["samples"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| (s["t"].as_f64().unwrap(), s.clone()))
            .collect()
    };
    let goal = [0.0; 3];
    // Kanayama
    let k = Kanayama::new(1.0, 4.0, 4.0).unwrap();
    let r = ConstantInputReference { vr: 0.5, wr: 0.2 };
    let ss = samples("kanayama");
    let t: Vec<f64> = ss.iter().map(|s| s.0).collect();
    let states = run(|t, s| k.inputs(s, &r.at(t)), [-0.5, 0.4, 0.6], &t);
    for ((ti, s), x) in ss.iter().zip(&states) {
        let v = k.lyapunov(*ti, x, &r.at(*ti)).unwrap();
        let want = s["V"].as_f64().unwrap();
        assert!(
            (v - want).abs() < 1e-9 * (1.0 + want),
            "t {ti}: {v} vs {want}"
        );
        for (a, b) in x.iter().zip(flat(&s["state"])) {
            assert!((a - b).abs() < 1e-8);
        }
    }
    // Samson
    let sm = Samson::new(1.0, 1.0, 1.0).unwrap();
    let ss = samples("samson_time_varying");
    let t: Vec<f64> = ss.iter().map(|s| s.0).collect();
    let states = run(|t, s| sm.inputs(t, s, &goal), [1.0, 1.0, 0.5], &t);
    for ((ti, s), x) in ss.iter().zip(&states) {
        let v = sm.lyapunov(*ti, x, &goal).unwrap();
        assert!((v - s["V"].as_f64().unwrap()).abs() < 1e-7, "samson t {ti}");
    }
    // Astolfi: ρ samples and |α| < π/2 throughout
    let a = Astolfi::new(3.0, 8.0, -1.5).unwrap();
    let ss = samples("astolfi_polar");
    let t: Vec<f64> = ss.iter().map(|s| s.0).collect();
    let states = run(|_, s| a.inputs(s, &goal), [-1.0, -0.5, 0.3], &t);
    for ((ti, s), x) in ss.iter().zip(&states) {
        let p = Astolfi::polar(x, &goal);
        let want = flat(&s["rho_alpha_beta"]);
        assert!((p[0] - want[0]).abs() < 1e-9, "astolfi rho t {ti}");
    }
    let dense = run(
        |_, s| a.inputs(s, &goal),
        [-1.0, -0.5, 0.3],
        &grid(3.0, 300),
    );
    assert!(
        dense
            .iter()
            .all(|x| Astolfi::polar(x, &goal)[1].abs() < std::f64::consts::FRAC_PI_2)
    );
    assert!(Astolfi::polar(&dense[300], &goal)[0] < 1e-3);
    // Aicardi
    let ai = Aicardi::new(1.0, 3.0, 2.0).unwrap();
    let ss = samples("aicardi_polar");
    let t: Vec<f64> = ss.iter().map(|s| s.0).collect();
    let states = run(|_, s| ai.inputs(s, &goal), [-1.0, -0.5, 0.3], &t);
    for ((ti, s), x) in ss.iter().zip(&states) {
        let v = ai.lyapunov(*ti, x, &goal).unwrap();
        let want = s["V"].as_f64().unwrap();
        assert!(
            (v - want).abs() < 1e-9 * (1.0 + want),
            "aicardi t {ti}: {v} vs {want}"
        );
    }
}

/// V recorded along each run is monotone, and its integral matches ∫ V̇_analytic.
#[test]
fn lyapunov_monitors_along_runs() {
    let goal = [0.0; 3];
    let t = grid(20.0, 4000);
    let check = |v: &mut dyn FnMut(f64, &Pose) -> (f64, f64), states: &[Pose]| {
        let mut m = LyapunovMonitor::with_capacity(t.len(), 1e-10);
        for (ti, x) in t.iter().zip(states) {
            let (val, rate) = v(*ti, x);
            m.record(*ti, val, Some(rate));
        }
        let rep = m.report();
        assert!(rep.monotone(), "{:?}", rep.violations.first());
        // trapezoidal rule on a 5 ms grid: O(dt²) quadrature error only
        assert!(
            rep.max_integral_error.unwrap() < 1e-4 * rep.v_first,
            "{rep:?}"
        );
        assert!(rep.v_last < rep.v_first);
    };
    let k = Kanayama::new(1.9, 2.6, 4.5).unwrap();
    let r = ConstantInputReference { vr: 0.7, wr: -0.35 };
    let s = run(|t, s| k.inputs(s, &r.at(t)), [-0.2, 0.6, -0.4], &t);
    check(
        &mut |t, x| {
            (
                k.lyapunov(t, x, &r.at(t)).unwrap(),
                k.lyapunov_rate(t, x, &r.at(t)).unwrap(),
            )
        },
        &s,
    );
    let sm = Samson::new(1.9, 1.8, 1.7).unwrap();
    let s = run(|t, x| sm.inputs(t, x, &goal), [1.28, -0.93, 0.02], &t);
    check(
        &mut |t, x| {
            (
                sm.lyapunov(t, x, &goal).unwrap(),
                sm.lyapunov_rate(t, x, &goal).unwrap(),
            )
        },
        &s,
    );
    let ai = Aicardi::new(1.75, 2.9, 2.96).unwrap();
    let s = run(|_, x| ai.inputs(x, &goal), [1.38, -1.32, -0.9], &t);
    check(
        &mut |t, x| {
            (
                ai.lyapunov(t, x, &goal).unwrap(),
                ai.lyapunov_rate(t, x, &goal).unwrap(),
            )
        },
        &s,
    );
}

/// Wheel-speed saturation breaks Kanayama's V̇ ≤ 0 argument: the monitor reports the
/// first increase of V with its time.
#[test]
fn saturation_reported_by_the_monitor() {
    let k = Kanayama::new(3.0, 8.0, 6.0).unwrap();
    let r = ConstantInputReference { vr: 1.0, wr: 0.5 };
    let lim = WheelLimits::new(DiffDrive::new(0.1, 0.3, 0.0).unwrap(), 11.0, 1.0).unwrap();
    let saturated = std::cell::Cell::new(false);
    let t = grid(10.0, 2000);
    let s = run(
        |t, x| {
            let mut u = k.inputs(x, &r.at(t));
            if lim.limit_inputs(&mut u).speed {
                saturated.set(true);
            }
            u
        },
        [-1.5, 1.0, 2.5],
        &t,
    );
    assert!(saturated.get());
    let mut m = LyapunovMonitor::with_capacity(t.len(), 1e-10);
    for (ti, x) in t.iter().zip(&s) {
        m.record(
            *ti,
            k.lyapunov(*ti, x, &r.at(*ti)).unwrap(),
            k.lyapunov_rate(*ti, x, &r.at(*ti)),
        );
    }
    let rep = m.report();
    assert!(!rep.monotone());
    assert!(rep.violations[0].t > 0.0 && rep.violations[0].increase > 0.0);
}

/// Brockett in a closed loop: Kanayama's law with a standing reference (v_r = ω_r = 0) is
/// smooth and time-invariant; from a sideways offset it leaves the robot where it is,
/// while Samson's time-varying law drives V down.
#[test]
fn brockett_smooth_time_invariant_law_does_not_stabilise() {
    let k = Kanayama::new(1.0, 4.0, 4.0).unwrap();
    let stand = moma::control::unicycle::ReferenceSample {
        pose: [0.0; 3],
        v: 0.0,
        w: 0.0,
    };
    let x0 = [0.0, 1.0, 0.0];
    let s = run(|_, x| k.inputs(x, &stand), x0, &[50.0]);
    assert!(
        (s[0][1] - 1.0).abs() < 1e-12,
        "the sideways error never decays: {:?}",
        s[0]
    );
    let sm = Samson::new(1.0, 1.0, 1.0).unwrap();
    let s = run(|t, x| sm.inputs(t, x, &[0.0; 3]), x0, &[50.0]);
    assert!(sm.lyapunov(50.0, &s[0], &[0.0; 3]).unwrap() < 0.25 * 0.5);
}

struct CoordLoop(moma::control::coordinated::Coordinated);

fn path(t: f64) -> moma::control::coordinated::PointReference {
    moma::control::coordinated::PointReference {
        p: [1.0 + 0.2 * t, 0.5 + 0.1 * (0.3 * t).sin()],
        v: [0.2, 0.03 * (0.3 * t).cos()],
    }
}

impl OdeSystem for CoordLoop {
    fn dim(&self) -> usize {
        5
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> moma::Result<()> {
        let s = [x[0], x[1], x[2], x[3], x[4]];
        let u = self.0.rates(&s, &path(t))?;
        dx.copy_from_slice(&moma::control::coordinated::Coordinated::state_rate(&s, &u));
        Ok(())
    }
}

/// theory.md 2.6: both errors decay as exact exponentials, the samples of the reference
/// run, V monotone, and the singularity guard.
#[test]
fn coordinated_base_arm_control_reference_run() {
    use moma::control::coordinated::Coordinated;
    let d = load("coordinated_and_osf.json");
    let law = Coordinated {
        l: 0.3,
        l1: 0.6,
        l2: 0.5,
        q_star: [-0.6, std::f64::consts::FRAC_PI_2],
        k_e: 2.0,
        k_y: 1.0,
    };
    let samples = d["coordinated"]["samples"].as_array().unwrap();
    let t: Vec<f64> = samples.iter().map(|s| s["t"].as_f64().unwrap()).collect();
    let x0 = [0.0, 0.0, 0.2, 0.0, 1.2];
    let mut dp = Dop853::new(5, AdaptiveOptions::with_tolerance(1e-12)).unwrap();
    let rows = dp.solve_at(&mut CoordLoop(law), 0.0, &x0, &t).unwrap();
    let (ee0, ey0) = law.errors(&x0, &path(0.0));
    let (n_e0, n_y0) = (ee0[0].hypot(ee0[1]), ey0[0].hypot(ey0[1]));
    let mut mon = LyapunovMonitor::with_capacity(t.len(), 1e-12);
    for ((r, s), &ti) in rows.iter().zip(samples).zip(&t) {
        let x = [r[0], r[1], r[2], r[3], r[4]];
        let (ee, ey) = law.errors(&x, &path(ti));
        let (ne, ny) = (ee[0].hypot(ee[1]), ey[0].hypot(ey[1]));
        assert!((ne - n_e0 * (-2.0 * ti).exp()).abs() < 1e-9, "t {ti}");
        assert!((ny - n_y0 * (-ti).exp()).abs() < 1e-9, "t {ti}");
        assert!((ne - s["ee_error"].as_f64().unwrap()).abs() < 1e-8);
        assert!((ny - s["rel_error"].as_f64().unwrap()).abs() < 1e-8);
        for (a, b) in x.iter().zip(flat(&s["state_x_y_phi_q1_q2"])) {
            assert!((a - b).abs() < 1e-7, "t {ti}: {a} vs {b}");
        }
        let u = law.rates(&x, &path(ti)).unwrap();
        assert!((u[0] - s["v"].as_f64().unwrap()).abs() < 1e-8);
        assert!((u[1] - s["w"].as_f64().unwrap()).abs() < 1e-8);
        assert!((law.manipulability(&x) - s["arm_manipulability"].as_f64().unwrap()).abs() < 1e-8);
        mon.record(ti, law.lyapunov(ti, &x, &path(ti)).unwrap(), None);
    }
    assert!(mon.report().monotone());
    // singular arm (q2 = 0) is refused
    assert!(law.rates(&[0.0, 0.0, 0.0, 0.3, 0.0], &path(0.0)).is_err());
}

//! `[uncertainty]` sensor noise enters a `moma simulate` run through the held-input
//! loop's own noise argument, on the rolling and on the contact plant: at every control
//! evaluation the law measures the plant's state plus the next draw of the seeded noise
//! (one draw per evaluation, in order), while the record and the law's tracking errors
//! keep the plant's own state; a seed repeats its run bit for bit.

use std::cell::RefCell;
use std::path::Path;
use std::rc::Rc;

use moma::Result;
use moma::control::unicycle::{ConstantInputReference, Kanayama};
use moma::io::urdf::model_from_urdf_file;
use moma::mobile::{DiffDrive, WheeledBase, WheeledModel};
use moma::multibody::RootJoint;
use moma::sim::closed_loop::{
    ClosedLoopOptions, ClosedLoopResult, FeedbackLaw, Observation, SaturationFlags,
    simulate_closed_loop,
};
use moma::sim::contact_run::ContactDriver;
use moma::sim::feedback::{PlatformController, PlatformLaw, TrackingReference, VelocityServo};
use moma::sim::monitor::MonitorLimits;
use moma::sim::sensor_noise::SensorNoise;
use moma::sim::settings::IntegratorSettings;
use moma::sim::wheeled_system::WheeledSystem;
use moma::sim_config::contact::prepare_contact;
use moma::sim_config::schema::parse_scenario;

/// One logged call: time, configuration, velocity.
type Call = (f64, Vec<f64>, Vec<f64>);

/// The states a law was given: to `control` and to `observe`.
#[derive(Clone, Default)]
struct Log {
    controls: Vec<Call>,
    observes: Vec<Call>,
}

/// A law that logs the states it is given and passes them on.
struct Logged {
    inner: Box<dyn FeedbackLaw>,
    log: Rc<RefCell<Log>>,
}

impl FeedbackLaw for Logged {
    fn nu(&self) -> usize {
        self.inner.nu()
    }
    fn error_names(&self) -> Vec<String> {
        self.inner.error_names()
    }
    fn has_lyapunov(&self) -> bool {
        self.inner.has_lyapunov()
    }
    fn control(&mut self, t: f64, q: &[f64], v: &[f64], u: &mut [f64]) -> Result<SaturationFlags> {
        self.log
            .borrow_mut()
            .controls
            .push((t, q.to_vec(), v.to_vec()));
        self.inner.control(t, q, v, u)
    }
    fn observe(&mut self, t: f64, q: &[f64], v: &[f64], error: &mut [f64]) -> Result<Observation> {
        self.log
            .borrow_mut()
            .observes
            .push((t, q.to_vec(), v.to_vec()));
        self.inner.observe(t, q, v, error)
    }
}

const STD_Q: [f64; 8] = [0.01, 0.01, 0.02, 0.0, 0.0, 0.01, 0.01, 0.01];
const STD_V: [f64; 5] = [0.05, 0.05, 0.0, 0.0, 0.0];

fn noise(seed: u64) -> SensorNoise {
    SensorNoise::new(STD_Q.to_vec(), STD_V.to_vec(), seed).unwrap()
}

/// The offsets `σ ⊙ n` of the first `n` draws of `noise(seed)`: what each measurement
/// adds to the state it measures (the draws do not depend on the state).
fn offsets(seed: u64, n: usize) -> Vec<(Vec<f64>, Vec<f64>)> {
    let mut s = noise(seed);
    (0..n)
        .map(|_| {
            let (mut q, mut v) = (vec![0.0; STD_Q.len()], vec![0.0; STD_V.len()]);
            s.measure(&[0.0; 8], &[0.0; 5], &mut q, &mut v).unwrap();
            (q, v)
        })
        .collect()
}

/// `measured` is `state + offset` computed as the noise computes it, bit for bit.
fn is_measurement(measured: &[f64], state: &[f64], offset: &[f64]) -> bool {
    measured
        .iter()
        .zip(state.iter().zip(offset))
        .all(|(m, (x, o))| m.to_bits() == (x + o).to_bits())
}

fn diffdrive_arm() -> WheeledModel {
    let urdf = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mobile/diffdrive_arm.urdf");
    let model = model_from_urdf_file(urdf, RootJoint::Planar).unwrap();
    let mut base = WheeledBase::new(DiffDrive::new(0.08, 0.25, 0.1).unwrap());
    base.wheel_joints = Some(["left_wheel_joint".into(), "right_wheel_joint".into()]);
    WheeledModel::new(model, base).unwrap()
}

/// Kanayama on a constant reference, the rolling plant, 0.01 s ticks each recorded, the
/// law's measurement through `noise`.
fn run_rolling(
    noise: Option<&mut SensorNoise>,
    period: Option<f64>,
) -> (Result<ClosedLoopResult>, Log) {
    let wm = diffdrive_arm();
    let q0 = [0.1, 0.0, 0.0, 0.0, 0.0, 0.0, 2.8, 0.3];
    let arm: Vec<f64> = wm.arm_dofs().iter().map(|&d| q0[d]).collect();
    let ctl = PlatformController::new(
        wm.clone(),
        PlatformLaw::Kanayama(
            Kanayama::new(1.0, 4.0, 4.0).unwrap(),
            TrackingReference::Constant(ConstantInputReference { vr: 0.4, wr: 0.2 }),
        ),
        VelocityServo {
            gain: 20.0,
            arm_kp: 100.0,
            arm_kd: 20.0,
        },
        arm,
        None,
        None,
    )
    .unwrap();
    let log = Rc::new(RefCell::new(Log::default()));
    let mut law = Logged {
        inner: Box::new(ctl),
        log: log.clone(),
    };
    let mut plant = WheeledSystem::new(wm);
    let r = simulate_closed_loop(
        &mut plant,
        &mut law,
        &q0,
        &[0.0; 5],
        &ClosedLoopOptions {
            duration: 0.5,
            integrator: IntegratorSettings::rk4(0.002),
            control_period: period,
            record_interval: 0.01,
            limits: MonitorLimits::default(),
            lyapunov_tolerance: 1e-9,
        },
        noise,
        &mut |_| {},
    );
    let log = log.borrow().clone();
    (r, log)
}

#[test]
fn the_rolling_loop_measures_through_the_noise_and_records_the_plants_state() {
    let (r, law) = run_rolling(Some(&mut noise(7)), Some(0.01));
    let r = r.unwrap();
    let rec = &r.recorder;
    // 50 ticks, each recorded, plus the last sample; the law evaluated at the 50 ticks
    assert_eq!((rec.len(), law.controls.len()), (51, 50));
    let offs = offsets(7, law.controls.len());
    for (k, (t, q, v)) in law.controls.iter().enumerate() {
        assert_eq!(*t, rec.times[k]);
        // the law saw the plant's state plus the k-th draw...
        assert!(is_measurement(q, rec.q_row(k), &offs[k].0), "q at tick {k}");
        assert!(is_measurement(v, rec.v_row(k), &offs[k].1), "v at tick {k}");
        // ...which is not the plant's state
        assert!(q[0] != rec.q_row(k)[0] && v[0] != rec.v_row(k)[0]);
    }
    // the tracking errors are those of the plant's own state
    assert_eq!(law.observes.len(), rec.len());
    for (i, (t, q, v)) in law.observes.iter().enumerate() {
        assert_eq!(
            (*t, q.as_slice(), v.as_slice()),
            (rec.times[i], rec.q_row(i), rec.v_row(i))
        );
    }
    // the noise moves the run, a seed repeats it bit for bit, another seed does not
    let (quiet, _) = run_rolling(None, Some(0.01));
    let (again, _) = run_rolling(Some(&mut noise(7)), Some(0.01));
    let (other, _) = run_rolling(Some(&mut noise(8)), Some(0.01));
    let last = |r: &ClosedLoopResult| r.recorder.q_row(r.recorder.len() - 1).to_vec();
    let bits = |x: Vec<f64>| x.iter().map(|a| a.to_bits()).collect::<Vec<_>>();
    assert_ne!(last(&quiet.unwrap()), last(&r));
    assert_eq!(bits(last(&again.unwrap())), bits(last(&r)));
    assert_ne!(last(&other.unwrap()), last(&r));
    // continuous feedback has no tick to draw the noise at
    let (e, _) = run_rolling(Some(&mut noise(7)), None);
    assert!(e.unwrap_err().to_string().contains("sensor noise"));
}

/// `contact_coordinated.toml` shortened to 0.3 s, with the sensor noise of seed 3
/// on the base pose and speeds.
fn contact_scenario(noise: bool) -> (moma::sim_config::Scenario, std::path::PathBuf) {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/contact_coordinated.toml");
    let mut text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("duration = 12.0", "duration = 0.3");
    if noise {
        text.push_str(
            "\n[uncertainty]\nseed = 3\nsensor_noise = { q = [0.01, 0.01, 0.02, 0.0, 0.0, 0.01, \
             0.01, 0.01], v = [0.05, 0.05, 0.0, 0.0, 0.0] }\n",
        );
    }
    let sc = parse_scenario(&text, &path).unwrap();
    sc.check_header(&path).unwrap();
    (sc, path)
}

/// Runs the contact scenario with its law logged; returns the recorded times and rows
/// and the log.
fn run_contact(noise: bool) -> (Vec<f64>, Vec<Vec<f64>>, Log) {
    let (sc, path) = contact_scenario(noise);
    let mut run = prepare_contact(&sc, &path).unwrap();
    assert_eq!(run.noise.is_some(), noise);
    let log = Rc::new(RefCell::new(Log::default()));
    let ContactDriver::Law { law, .. } = &mut run.driver else {
        panic!("a closed loop")
    };
    let inner = std::mem::replace(law, Box::new(NoLaw));
    *law = Box::new(Logged {
        inner,
        log: log.clone(),
    });
    let res = run.run(&mut |_| {}).unwrap();
    let log = log.borrow().clone();
    (res.times, res.rows, log)
}

#[test]
fn the_contact_run_measures_through_the_noise_once_per_evaluation() {
    let (times, rows, log) = run_contact(true);
    // 0.3 s at a 0.01 s period: 30 evaluations and the one at the end
    assert_eq!(log.controls.len(), 31);
    let offs = offsets(3, log.controls.len());
    let mut checked = 0;
    for (k, (t, q, v)) in log.controls.iter().enumerate() {
        let Some(i) = times.iter().position(|s| s == t) else {
            continue;
        };
        // the row holds the plant's state [q (8), v (5), ...] of the same tick
        let (rq, rv) = (&rows[i][..8], &rows[i][8..13]);
        assert!(is_measurement(q, rq, &offs[k].0), "q at evaluation {k}");
        assert!(is_measurement(v, rv, &offs[k].1), "v at evaluation {k}");
        assert!(q[0] != rq[0]);
        checked += 1;
    }
    assert_eq!(checked, rows.len());
    // the tracking errors are those of the plant's own state
    assert_eq!(log.observes.len(), rows.len());
    for (i, (_, q, v)) in log.observes.iter().enumerate() {
        assert_eq!(
            (q.as_slice(), v.as_slice()),
            (&rows[i][..8], &rows[i][8..13])
        );
    }
    let (_, again, _) = run_contact(true);
    let (_, quiet, _) = run_contact(false);
    let bits = |r: &[Vec<f64>]| r.iter().flatten().map(|a| a.to_bits()).collect::<Vec<_>>();
    assert_eq!(bits(&again), bits(&rows));
    assert_ne!(bits(&quiet), bits(&rows));
}

/// A placeholder while the law is swapped.
struct NoLaw;

impl FeedbackLaw for NoLaw {
    fn nu(&self) -> usize {
        0
    }
    fn error_names(&self) -> Vec<String> {
        Vec::new()
    }
    fn has_lyapunov(&self) -> bool {
        false
    }
    fn control(&mut self, _: f64, _: &[f64], _: &[f64], _: &mut [f64]) -> Result<SaturationFlags> {
        unreachable!("the placeholder is never run")
    }
    fn observe(&mut self, _: f64, _: &[f64], _: &[f64], _: &mut [f64]) -> Result<Observation> {
        unreachable!("the placeholder is never run")
    }
}

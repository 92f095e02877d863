//! Runs the contact plant on the diff-drive arm (`scenarios/robots/diffdrive_arm.urdf` on a
//! free-flyer root, two drive wheels of radius 0.08 m and a ball caster of radius 0.03 m)
//! through the three scenarios that `bench/mujoco_contact_compare.py` replays in MuJoCo,
//! and writes each trajectory as JSON (the scenario's torque schedule included, so the
//! replay applies the same torques).
//!
//! * `roll`: μ = 1, moderate wheel torques (0.25, 0.45) N·m from 0.5 s to 3.5 s, arm held
//!   up by a PD law; nothing slips. 5 s.
//! * `brake`: μ = 1, arm stretched forward, driven backwards with (−3, −3) N·m from 0.3 s
//!   to 1.3 s, then braked with (12, 12) N·m: the robot tips back about the wheel axle and
//!   the caster lifts off. 2 s.
//! * `spin`: μ = 0.3, opposite wheel torques ramped from 0 at 0.3 s to ±6 N·m at 3.3 s:
//!   the wheels start to slip when the torque exceeds what friction carries. 3.3 s.
//!
//! Events, counted after the first 0.2 s of settling: `first_lift`, a contact's lowest
//! point 1 mm above the ground; `first_unloaded`, its normal force zero; `first_slip`, a
//! loaded wheel's contact point sliding at 0.2 m/s (four times v_ε); `first_saturated`,
//! friction at μ N (slip at v_ε).
//!
//! Every arm joint follows `u = k_p (q_ref − q) − k_d q̇` with the scenario's gains; wheel
//! torques are linear between the schedule's knots.
//!
//! The contact is stiff ([`STIFFNESS`], [`DAMPING`]; the other parameters moma's
//! defaults): MuJoCo's soft-constraint contact moves the load between the contacts in one
//! step when the torques jump, as a rigid contact does, and a penalty contact does so
//! within about 1 ms only when it is this stiff (at the default 1e5 N/m the caster needs
//! 13 ms to unload under the brake, and the wheels slide meanwhile; BENCHMARKS.md,
//! "Contact plant").
//!
//! Usage: `cargo run --release --example contact_rollout -- OUT_DIR [STIFFNESS DAMPING]`
//! (writes `OUT_DIR/contact_<scenario>.json`; `STIFFNESS` (N/m) and `DAMPING` (N·s/m)
//! replace the comparison's contact stiffness and damping).

use std::path::PathBuf;

use moma::contact::{CasterSpec, ContactParams, ContactPlant, ContactState, WheelSpec};
use moma::io::urdf::model_from_urdf_file;
use moma::multibody::RootJoint;
use serde_json::json;

struct Scenario {
    name: &'static str,
    duration: f64,
    mu: f64,
    arm_ref: [f64; 3],
    /// Knots `[t, tau_left, tau_right]`; linear in between, held after the last.
    wheel_knots: &'static [[f64; 3]],
}

const KP: f64 = 200.0;
const KD: f64 = 20.0;
/// Lift-off and slip events are counted after the initial settling.
const SETTLE: f64 = 0.2;
/// Lift-off: a contact's lowest point this high (m) above the ground.
const LIFT_HEIGHT: f64 = 1e-3;
/// Slip onset: a wheel's contact point sliding this fast (m/s).
const SLIP_SPEED: f64 = 0.2;
const RECORD_EVERY: f64 = 0.01;
/// Normal stiffness (N/m) of the comparison with MuJoCo.
const STIFFNESS: f64 = 1e7;
/// Normal damping (N·s/m) of the comparison with MuJoCo: the default 2e3 scaled with
/// `√k`, keeping the contact's damping ratio.
const DAMPING: f64 = 2e4;

const SCENARIOS: &[Scenario] = &[
    Scenario {
        name: "roll",
        duration: 5.0,
        mu: 1.0,
        arm_ref: [0.0, 0.3, 0.5],
        wheel_knots: &[
            [0.0, 0.0, 0.0],
            [0.5, 0.0, 0.0],
            [0.5, 0.25, 0.45],
            [3.5, 0.25, 0.45],
            [3.5, 0.0, 0.0],
        ],
    },
    Scenario {
        name: "brake",
        duration: 2.0,
        mu: 1.0,
        arm_ref: [0.0, 1.5, 0.0],
        wheel_knots: &[
            [0.0, 0.0, 0.0],
            [0.3, 0.0, 0.0],
            [0.3, -3.0, -3.0],
            [1.3, -3.0, -3.0],
            [1.3, 12.0, 12.0],
        ],
    },
    Scenario {
        name: "spin",
        duration: 3.3,
        mu: 0.3,
        arm_ref: [0.0, 0.3, 0.5],
        wheel_knots: &[[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [3.3, -6.0, 6.0]],
    },
];

fn wheel_torques(knots: &[[f64; 3]], t: f64) -> [f64; 2] {
    let mut out = [knots[0][1], knots[0][2]];
    for w in knots.windows(2) {
        let (a, b) = (w[0], w[1]);
        if t >= a[0] && t < b[0] {
            let s = (t - a[0]) / (b[0] - a[0]);
            return [a[1] + s * (b[1] - a[1]), a[2] + s * (b[2] - a[2])];
        }
    }
    if let Some(last) = knots.last()
        && t >= last[0]
    {
        out = [last[1], last[2]];
    }
    out
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let out_dir = PathBuf::from(args.first().map_or("out", String::as_str));
    let (stiffness, damping) = match &args[1.min(args.len())..] {
        [] => (STIFFNESS, DAMPING),
        [k, c] => (k.parse::<f64>()?, c.parse::<f64>()?),
        _ => return Err("usage: contact_rollout OUT_DIR [STIFFNESS DAMPING]".into()),
    };
    std::fs::create_dir_all(&out_dir)?;
    let urdf =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/robots/diffdrive_arm.urdf");
    for sc in SCENARIOS {
        let model = model_from_urdf_file(&urdf, RootJoint::FreeFlyer)?;
        let params = ContactParams {
            mu: sc.mu,
            stiffness,
            damping,
            ..ContactParams::default()
        };
        let wheels = [
            WheelSpec {
                joint: "left_wheel_joint".into(),
                radius: 0.08,
            },
            WheelSpec {
                joint: "right_wheel_joint".into(),
                radius: 0.08,
            },
        ];
        let casters = [CasterSpec::on_frame("caster", 0.03)];
        let plant = ContactPlant::new(model, &wheels, &casters, params)?;
        // [x, y, z, qx, qy, qz, qw, left, right, turret, shoulder, elbow]
        let mut q0 = vec![0.0, 0.0, 0.08, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0];
        q0.extend_from_slice(&sc.arm_ref);
        let v0 = vec![0.0; plant.model.nv];
        let mut st = ContactState::new(&plant, &q0, &v0)?;
        let dt = plant.params.dt;
        let nsteps = (sc.duration / dt).round() as usize;
        let every = (RECORD_EVERY / dt).round() as usize;
        let mut u = vec![0.0; plant.nu()];
        let mut records = Vec::new();
        let mut first_lift = None;
        let mut first_slip = None;
        let mut first_unloaded = None;
        let mut first_saturated = None;
        let started = std::time::Instant::now();
        for k in 0..=nsteps {
            let t = st.t;
            let w = wheel_torques(sc.wheel_knots, t);
            u[0] = w[0];
            u[1] = w[1];
            for j in 0..3 {
                u[2 + j] = KP * (sc.arm_ref[j] - st.q[9 + j]) - KD * st.v[8 + j];
            }
            if k > 0 {
                // Reports of the step just taken.
                if t > SETTLE {
                    for (c, r) in st.contacts.iter().enumerate() {
                        let name = || Some((t, plant.contact_name(c).to_string()));
                        if first_unloaded.is_none() && r.lifted {
                            first_unloaded = name();
                        }
                        if first_lift.is_none() && -r.depth >= LIFT_HEIGHT {
                            first_lift = name();
                        }
                        if first_saturated.is_none() && r.slipping {
                            first_saturated = name();
                        }
                        if first_slip.is_none() && c < 2 && !r.lifted && r.slip.norm() >= SLIP_SPEED
                        {
                            first_slip = name();
                        }
                    }
                }
                if k.is_multiple_of(every) {
                    let p = st.base_position();
                    let (roll, pitch, _) = st.base_orientation().euler_angles();
                    records.push(json!({
                        "t": t,
                        "x": p.x, "y": p.y, "z": p.z,
                        "yaw": st.yaw(), "pitch": pitch, "roll": roll,
                        "wheel_speeds": plant.wheel_speeds(&st).collect::<Vec<_>>(),
                        "arm_q": &st.joint_positions()[2..],
                        "normal": st.contacts.iter().map(|r| r.normal).collect::<Vec<_>>(),
                        "slip_speed": st.contacts.iter().map(|r| r.slip.norm()).collect::<Vec<_>>(),
                        "lifted": st.contacts.iter().map(|r| r.lifted).collect::<Vec<_>>(),
                        "slipping": st.contacts.iter().map(|r| r.slipping).collect::<Vec<_>>(),
                    }));
                }
            }
            if k < nsteps {
                plant.step(&mut st, &u)?;
            }
        }
        let wall = started.elapsed().as_secs_f64();
        let doc = json!({
            "scenario": sc.name,
            "duration": sc.duration,
            "mu": sc.mu,
            "arm_ref": sc.arm_ref,
            "kp": KP, "kd": KD,
            "settle": SETTLE,
            "wheel_knots": sc.wheel_knots,
            "params": plant.params,
            "contacts": (0..plant.ncontacts()).map(|c| plant.contact_name(c)).collect::<Vec<_>>(),
            "lift_height": LIFT_HEIGHT,
            "slip_speed": SLIP_SPEED,
            "first_lift": first_lift.as_ref().map(|(t, c)| json!({"t": t, "contact": c})),
            "first_slip": first_slip.as_ref().map(|(t, c)| json!({"t": t, "contact": c})),
            "first_unloaded": first_unloaded.as_ref().map(|(t, c)| json!({"t": t, "contact": c})),
            "first_saturated": first_saturated.as_ref().map(|(t, c)| json!({"t": t, "contact": c})),
            "wall_seconds": wall,
            "records": records,
        });
        let path = out_dir.join(format!("contact_{}.json", sc.name));
        std::fs::write(&path, serde_json::to_string(&doc)?)?;
        println!(
            "{}: {} steps in {:.3} s ({:.2} µs/step); first lift {:?}, first slip {:?} -> {}",
            sc.name,
            nsteps,
            wall,
            wall / nsteps as f64 * 1e6,
            first_lift,
            first_slip,
            path.display()
        );
    }
    Ok(())
}

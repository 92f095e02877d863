//! Runs the contact plant on a robot of the MuJoCo comparison through the three scenarios
//! that `bench/mujoco_contact_compare.py` replays in MuJoCo, and writes each trajectory as
//! JSON (the robot, the arm joints, the scenario's torque schedule and gains included, so
//! the replay applies the same torques). The robots:
//!
//! `diffdrive_arm` (`scenarios/robots/diffdrive_arm.urdf`, two drive wheels of radius
//! 0.08 m, a ball caster of radius 0.03 m):
//!
//! * `roll`: μ = 1, moderate wheel torques (0.25, 0.45) N·m from 0.5 s to 3.5 s, arm held
//!   up by a PD law; nothing slips. 5 s.
//! * `brake`: μ = 1, arm stretched forward, driven backwards with (−3, −3) N·m from 0.3 s
//!   to 1.3 s, then braked with (12, 12) N·m: the robot tips back about the wheel axle and
//!   the caster lifts off. 2 s.
//! * `spin`: μ = 0.3, opposite wheel torques ramped from 0 at 0.3 s to ±6 N·m at 3.3 s:
//!   the wheels start to slip when the torque exceeds what friction carries. 3.3 s.
//!
//! `mobile_manipulator` (the UR5-class mobile manipulator of
//! `scenarios/robots/mobile_manipulator.urdf`, 72 kg: drive wheels of radius 0.10 m, the
//! four ball casters of `scenarios/mission_contact.toml`, radius 0.04 m):
//!
//! * `roll`: μ = 1, the missions' transport posture, wheel torques (0.4, 0.64) N·m from
//!   0.5 s to 3.5 s (friction loaded as in the diff-drive arm's roll, T/N up to 0.05);
//!   nothing slips. 5 s.
//! * `brake`: μ = 1, arm stretched forward (shoulder lift π/2), driven forwards with
//!   (5, 5) N·m from 0.3 s to 1.3 s, then braked with (−60, −60) N·m: the wheels slide at
//!   once (friction carries 11.8 N·m a wheel), the brake's reaction on the chassis (past
//!   45 N·m a wheel it outweighs the robot's weight about the front casters) tips it
//!   forward on the front casters, and a rear caster lifts. 1.6 s.
//! * `spin`: μ = 0.3, transport posture, opposite wheel torques ramped from 0 at 0.3 s to
//!   ±20 N·m at 3.3 s. 3.3 s.
//!
//! Events, counted after the first 0.2 s of settling: `first_lift`, a contact's lowest
//! point 1 mm above the ground; `first_unloaded`, its normal force zero; `first_slip`, a
//! loaded wheel's contact point sliding at 0.2 m/s (four times v_ε); `first_saturated`,
//! friction at μ N (slip at v_ε).
//!
//! Every arm joint follows `u = k_p (q_ref − q) − k_d q̇` with the robot's gains; wheel
//! torques are linear between the schedule's knots.
//!
//! The contact is stiff ([`STIFFNESS`], [`DAMPING`]; the other parameters moma's
//! defaults): MuJoCo's soft-constraint contact moves the load between the contacts in one
//! step when the torques jump, as a rigid contact does, and a penalty contact does so
//! within about 1 ms only when it is this stiff (at the default 1e5 N/m the caster needs
//! 13 ms to unload under the brake, and the wheels slide meanwhile; BENCHMARKS.md,
//! "Contact plant").
//!
//! Usage: `cargo run --release --example contact_rollout -- ROBOT OUT_DIR [STIFFNESS DAMPING]`
//! (`ROBOT`: `diffdrive_arm` or `mobile_manipulator`; writes
//! `OUT_DIR/contact_<scenario>.json`; `STIFFNESS` (N/m) and `DAMPING` (N·s/m) replace the
//! comparison's contact stiffness and damping).

use std::f64::consts::FRAC_PI_2;
use std::path::PathBuf;

use moma::contact::{CasterSpec, ContactParams, ContactPlant, ContactState, WheelSpec};
use moma::io::urdf::model_from_urdf_file;
use moma::multibody::RootJoint;
use serde_json::json;

/// A robot of the comparison: its description, contacts, arm gains and scenarios.
struct Robot {
    name: &'static str,
    /// The description, relative to the repository root.
    urdf: &'static str,
    wheel_radius: f64,
    /// Ball casters: frame at the sphere's centre, radius (m).
    casters: &'static [(&'static str, f64)],
    /// Height (m) of the base frame when standing on the ground, level.
    base_height: f64,
    /// Arm PD gains, one per arm joint.
    kp: &'static [f64],
    kd: &'static [f64],
    scenarios: &'static [Scenario],
}

struct Scenario {
    name: &'static str,
    duration: f64,
    mu: f64,
    arm_ref: &'static [f64],
    /// Knots `[t, tau_left, tau_right]`; linear in between, held after the last.
    wheel_knots: &'static [[f64; 3]],
}

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

const DIFFDRIVE_ARM: Robot = Robot {
    name: "diffdrive_arm",
    urdf: "scenarios/robots/diffdrive_arm.urdf",
    wheel_radius: 0.08,
    casters: &[("caster", 0.03)],
    base_height: 0.08,
    kp: &[200.0; 3],
    kd: &[20.0; 3],
    scenarios: &[
        Scenario {
            name: "roll",
            duration: 5.0,
            mu: 1.0,
            arm_ref: &[0.0, 0.3, 0.5],
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
            arm_ref: &[0.0, 1.5, 0.0],
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
            arm_ref: &[0.0, 0.3, 0.5],
            wheel_knots: &[[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [3.3, -6.0, 6.0]],
        },
    ],
};

const MOBILE_MANIPULATOR: Robot = Robot {
    name: "mobile_manipulator",
    urdf: "scenarios/robots/mobile_manipulator.urdf",
    wheel_radius: 0.10,
    casters: &[
        ("caster_front_left", 0.04),
        ("caster_front_right", 0.04),
        ("caster_rear_left", 0.04),
        ("caster_rear_right", 0.04),
    ],
    base_height: 0.0,
    kp: &[2000.0, 2000.0, 1000.0, 100.0, 100.0, 100.0],
    kd: &[100.0, 100.0, 50.0, 2.0, 2.0, 1.0],
    scenarios: &[
        Scenario {
            name: "roll",
            duration: 5.0,
            mu: 1.0,
            arm_ref: &[0.0, -0.5, 2.6, 1.04, 0.0, 0.0],
            wheel_knots: &[
                [0.0, 0.0, 0.0],
                [0.5, 0.0, 0.0],
                [0.5, 0.4, 0.64],
                [3.5, 0.4, 0.64],
                [3.5, 0.0, 0.0],
            ],
        },
        Scenario {
            name: "brake",
            duration: 1.6,
            mu: 1.0,
            arm_ref: &[0.0, FRAC_PI_2, 0.0, 0.0, 0.0, 0.0],
            wheel_knots: &[
                [0.0, 0.0, 0.0],
                [0.3, 0.0, 0.0],
                [0.3, 5.0, 5.0],
                [1.3, 5.0, 5.0],
                [1.3, -60.0, -60.0],
            ],
        },
        Scenario {
            name: "spin",
            duration: 3.3,
            mu: 0.3,
            arm_ref: &[0.0, -0.5, 2.6, 1.04, 0.0, 0.0],
            wheel_knots: &[[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [3.3, -20.0, 20.0]],
        },
    ],
};

const ROBOTS: [&Robot; 2] = [&DIFFDRIVE_ARM, &MOBILE_MANIPULATOR];

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
    const USAGE: &str = "usage: contact_rollout ROBOT OUT_DIR [STIFFNESS DAMPING] \
                         (ROBOT: diffdrive_arm or mobile_manipulator)";
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (robot, out_dir, stiffness, damping) = match args.as_slice() {
        [r, o] => (r, o, STIFFNESS, DAMPING),
        [r, o, k, c] => (r, o, k.parse::<f64>()?, c.parse::<f64>()?),
        _ => return Err(USAGE.into()),
    };
    let robot = ROBOTS
        .iter()
        .find(|r| r.name == robot)
        .ok_or_else(|| format!("unknown robot {robot:?}; {USAGE}"))?;
    let out_dir = PathBuf::from(out_dir);
    std::fs::create_dir_all(&out_dir)?;
    let urdf = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(robot.urdf);
    let narm = robot.kp.len();
    for sc in robot.scenarios {
        let model = model_from_urdf_file(&urdf, RootJoint::FreeFlyer)?;
        let params = ContactParams {
            mu: sc.mu,
            stiffness,
            damping,
            ..ContactParams::default()
        };
        let wheels = ["left_wheel_joint", "right_wheel_joint"].map(|j| WheelSpec {
            joint: j.into(),
            radius: robot.wheel_radius,
        });
        let casters: Vec<CasterSpec> = robot
            .casters
            .iter()
            .map(|&(frame, r)| CasterSpec::on_frame(frame, r))
            .collect();
        let plant = ContactPlant::new(model, &wheels, &casters, params)?;
        // Inputs in model order (each one dof: input i is q[7 + i], v[6 + i]); the arm
        // joints are the inputs that are not wheels, in model order.
        let inputs = plant.input_names();
        let wheel_inputs = ["left_wheel_joint", "right_wheel_joint"]
            .map(|j| inputs.iter().position(|n| n == j).expect("a wheel input"));
        let arm_inputs: Vec<usize> = (0..inputs.len())
            .filter(|i| !wheel_inputs.contains(i))
            .collect();
        if arm_inputs.len() != narm {
            return Err(format!("{}: arm joints {arm_inputs:?}, {narm} gains", robot.urdf).into());
        }
        let mut q0 = vec![0.0, 0.0, robot.base_height, 0.0, 0.0, 0.0, 1.0];
        q0.resize(plant.model.nq, 0.0);
        for (j, &i) in arm_inputs.iter().enumerate() {
            q0[7 + i] = sc.arm_ref[j];
        }
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
            u[wheel_inputs[0]] = w[0];
            u[wheel_inputs[1]] = w[1];
            for (j, &i) in arm_inputs.iter().enumerate() {
                u[i] = robot.kp[j] * (sc.arm_ref[j] - st.q[7 + i]) - robot.kd[j] * st.v[6 + i];
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
                        "arm_q": arm_inputs.iter().map(|&i| st.q[7 + i]).collect::<Vec<_>>(),
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
            "robot": robot.name,
            "scenario": sc.name,
            "duration": sc.duration,
            "mu": sc.mu,
            "base_q0": &q0[..7],
            "arm_joints": arm_inputs.iter().map(|&i| &inputs[i]).collect::<Vec<_>>(),
            "wheel_radius": robot.wheel_radius,
            "arm_ref": sc.arm_ref,
            "kp": robot.kp, "kd": robot.kd,
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
            "{} {}: {} steps in {:.3} s ({:.2} µs/step); first lift {:?}, first unloaded {:?}, first slip {:?} -> {}",
            robot.name,
            sc.name,
            nsteps,
            wall,
            wall / nsteps as f64 * 1e6,
            first_lift,
            first_unloaded,
            first_slip,
            path.display()
        );
    }
    Ok(())
}

//! Dumps every rigid-body output of moma for a URDF and a list of states, as JSON on
//! standard output: the companion of `bench/xcheck_pinocchio.py`, which compares it with
//! Pinocchio on many robot descriptions. Unlike `moma dynamics` it reports every frame
//! (placement and LOCAL_WORLD_ALIGNED Jacobian) and keeps going when forward dynamics is
//! singular (a massless subtree): the non-finite accelerations are written as `null`.
//!
//! Usage: `cargo run --release --example rigid_body_dump -- ROBOT.urdf ROOT STATES.json`
//! with ROOT `fixed`, `planar` or `free-flyer` and STATES.json as for `moma dynamics`
//! (`{"states": [{"q": [..], "v": [..], "a": [..], "tau": [..], "q1": [..]}]}`, all five
//! required) and an optional top-level `"gravity": [gx, gy, gz]` (default [0, 0, −9.81]).
//!
//! Per state: rnea, crba, aba (`null` where non-finite), nonlinear effects, gravity,
//! Coriolis matrix, CoM, centroidal map, energies, `integrate(q, v)`, `difference(q, q1)`,
//! and per frame its placement, and in the three reference frames its Jacobian, its
//! velocity and its acceleration bias J̇·q̇ (the frame acceleration for q̈ = 0; the
//! LOCAL_WORLD_ALIGNED one is the classical acceleration [p̈; ω̇]), and its spatial
//! acceleration in its own axes for the state's a (`forward_kinematics_second_order`).

use moma::dynamics;
use moma::io::urdf::model_from_urdf_file;
use moma::kinematics::{self, ReferenceFrame};
use moma::multibody::{Data, FrameIndex, Model, RootJoint};
use nalgebra::{DMatrix, DVector, Matrix6xX};
use serde_json::{Value, json};

fn rows(m: &DMatrix<f64>) -> Value {
    json!(
        m.row_iter()
            .map(|r| r.iter().copied().collect::<Vec<_>>())
            .collect::<Vec<_>>()
    )
}

fn rows6(m: &Matrix6xX<f64>) -> Value {
    json!(
        m.row_iter()
            .map(|r| r.iter().copied().collect::<Vec<_>>())
            .collect::<Vec<_>>()
    )
}

fn motion(m: &moma::spatial::Motion) -> Value {
    json!([
        m.linear.x,
        m.linear.y,
        m.linear.z,
        m.angular.x,
        m.angular.y,
        m.angular.z
    ])
}

fn vecf(v: &Value, what: &str) -> Result<DVector<f64>, String> {
    let a = v
        .as_array()
        .ok_or_else(|| format!("{what}: expected an array"))?;
    let x: Option<Vec<f64>> = a.iter().map(Value::as_f64).collect();
    x.map(DVector::from_vec)
        .ok_or_else(|| format!("{what}: expected numbers"))
}

/// One state of the input file, checked against the model.
struct State {
    q: DVector<f64>,
    v: DVector<f64>,
    a: DVector<f64>,
    tau: DVector<f64>,
    q1: DVector<f64>,
}

/// Reads `states[k]` (`tag` names it in errors) and checks its sizes and values.
fn read_state(model: &Model, s: &Value, tag: &str) -> Result<State, String> {
    let q = vecf(&s["q"], &format!("{tag}.q"))?;
    let v = vecf(&s["v"], &format!("{tag}.v"))?;
    let a = vecf(&s["a"], &format!("{tag}.a"))?;
    let tau = vecf(&s["tau"], &format!("{tag}.tau"))?;
    let q1 = vecf(&s["q1"], &format!("{tag}.q1"))?;
    kinematics::check_state(
        model,
        tag,
        Some(q.as_slice()),
        Some(v.as_slice()),
        Some(a.as_slice()),
        Some(tau.as_slice()),
    )
    .map_err(|e| e.to_string())?;
    kinematics::check_state(model, tag, Some(q1.as_slice()), None, None, None)
        .map_err(|e| e.to_string())?;
    Ok(State { q, v, a, tau, q1 })
}

/// Every whole-model output for one state, and the frames' ones under `frames`.
fn dump_state(model: &Model, data: &mut Data, st: &State) -> Value {
    let (q, v, a, tau) = (&st.q, &st.v, &st.a, &st.tau);
    let rnea = dynamics::rnea(model, data, q, v, a).clone();
    let crba = dynamics::crba(model, data, q).clone();
    let aba: Vec<Option<f64>> = dynamics::aba(model, data, q, v, tau)
        .iter()
        .map(|x| x.is_finite().then_some(*x))
        .collect();
    let nle = dynamics::nonlinear_effects(model, data, q, v).clone();
    let grav = dynamics::gravity_torque(model, data, q).clone();
    let coriolis = dynamics::coriolis_matrix(model, data, q, v).clone();
    let com = dynamics::center_of_mass(model, data, q);
    let ag = dynamics::centroidal_momentum_matrix(model, data, q).clone();
    let ke = dynamics::kinetic_energy(model, data, q, v);
    let pe = dynamics::potential_energy(model, data, q);
    let mut q_next = DVector::zeros(model.nq);
    kinematics::integrate(model, q, v, &mut q_next);
    let mut dq = DVector::zeros(model.nv);
    kinematics::difference(model, q, &st.q1, &mut dq);
    let mut frames = Vec::with_capacity(model.nframes());
    let mut jac = Matrix6xX::zeros(model.nv);
    for f in 0..model.nframes() {
        frames.push(dump_frame(model, data, st, FrameIndex(f), &mut jac));
    }
    json!({
        "rnea_tau": rnea.as_slice(),
        "crba_M": rows(&crba),
        "aba_ddq": aba,
        "nle": nle.as_slice(),
        "gravity_torque": grav.as_slice(),
        "coriolis_C": rows(&coriolis),
        "com": [com.x, com.y, com.z],
        "centroidal_map_Ag": rows6(&ag),
        "kinetic_energy": ke,
        "potential_energy": pe,
        "integrate_q_v": q_next.as_slice(),
        "difference_q_q1": dq.as_slice(),
        "frames": frames,
    })
}

/// The reference frames each frame output is given in, with their names in the JSON.
const RFS: [(&str, ReferenceFrame); 3] = [
    ("local_world_aligned", ReferenceFrame::LocalWorldAligned),
    ("world", ReferenceFrame::World),
    ("local", ReferenceFrame::Local),
];

/// One frame's outputs: Jacobians, placement, acceleration biases, velocities (in the
/// three reference frames) and its spatial acceleration in its own axes (`jac` is
/// scratch space).
fn dump_frame(
    model: &Model,
    data: &mut Data,
    st: &State,
    fid: FrameIndex,
    jac: &mut Matrix6xX<f64>,
) -> Value {
    let (q, v) = (&st.q, &st.v);
    let mut fr = serde_json::Map::new();
    for (name, rf) in RFS {
        kinematics::frame_jacobian(model, data, q, fid, rf, jac);
        fr.insert(format!("jacobian_{name}"), rows6(jac));
    }
    let m = kinematics::update_frame_placement(model, data, fid);
    let r = m.rotation;
    fr.insert(
        "position".into(),
        json!([m.translation.x, m.translation.y, m.translation.z]),
    );
    fr.insert(
        "rotation".into(),
        json!([
            [r[(0, 0)], r[(0, 1)], r[(0, 2)]],
            [r[(1, 0)], r[(1, 1)], r[(1, 2)]],
            [r[(2, 0)], r[(2, 1)], r[(2, 2)]]
        ]),
    );
    for (name, rf) in RFS {
        let b = kinematics::frame_acceleration_bias(model, data, q, v, fid, rf);
        fr.insert(format!("bias_{name}"), motion(&b));
    }
    kinematics::forward_kinematics_second_order(model, data, q, v, &st.a);
    for (name, rf) in RFS {
        let w = kinematics::frame_velocity(model, data, fid, rf);
        fr.insert(format!("velocity_{name}"), motion(&w));
    }
    let frame = &model.frames[fid.0];
    let acc = frame
        .placement
        .inverse_act_motion(&data.a[frame.parent_joint.0]);
    fr.insert("acceleration_local".into(), motion(&acc));
    Value::Object(fr)
}

fn run() -> Result<(), String> {
    let args: Vec<String> = std::env::args().collect();
    let [_, urdf, root, states] = args.as_slice() else {
        return Err("usage: rigid_body_dump ROBOT.urdf fixed|planar|free-flyer STATES.json".into());
    };
    let root: RootJoint = root.parse().map_err(|e| format!("{e}"))?;
    let mut model = model_from_urdf_file(urdf, root).map_err(|e| e.to_string())?;
    let text = std::fs::read_to_string(states).map_err(|e| format!("{states}: {e}"))?;
    let input: Value = serde_json::from_str(&text).map_err(|e| format!("{states}: {e}"))?;
    let list = input["states"]
        .as_array()
        .ok_or_else(|| format!("{states}: no 'states' array"))?;
    if !input["gravity"].is_null() {
        let g = vecf(&input["gravity"], &format!("{states}: gravity"))?;
        if g.len() != 3 {
            return Err(format!("{states}: gravity must have 3 entries"));
        }
        model.gravity = nalgebra::Vector3::new(g[0], g[1], g[2]);
    }
    let mut data = Data::new(&model);
    let mut out = Vec::new();
    for (k, s) in list.iter().enumerate() {
        let st = read_state(&model, s, &format!("{states}: states[{k}]"))?;
        out.push(dump_state(&model, &mut data, &st));
    }
    println!(
        "{}",
        json!({ "nq": model.nq, "nv": model.nv, "states": out })
    );
    Ok(())
}

fn main() {
    if let Err(e) = run() {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

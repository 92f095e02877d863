//! `--layout pinocchio`: Pinocchio's states fed as they are (the shared Pinocchio 4.1.0
//! dumps of TIAGo on a planar and a free-flyer base, with continuous wheel joints), and
//! the outputs compared with Pinocchio's own (`dynamics`), or the same states given in
//! moma's layout give the same results (the other commands).

use serde_json::{Value, json};
use std::path::PathBuf;
use std::process::{Command, Output};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../moma/tests/data/pinocchio");

fn moma(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_moma"))
        .args(args)
        .output()
        .expect("run moma")
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("moma_layout_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn dump(name: &str) -> Value {
    serde_json::from_str(&std::fs::read_to_string(format!("{DATA}/{name}")).unwrap()).unwrap()
}

fn close(what: &str, got: &Value, want: &Value) {
    match (got, want) {
        (Value::Array(g), Value::Array(w)) => {
            assert_eq!(g.len(), w.len(), "{what}: length");
            for (k, (a, b)) in g.iter().zip(w).enumerate() {
                close(&format!("{what}[{k}]"), a, b);
            }
        }
        _ => {
            let (a, b) = (got.as_f64().unwrap(), want.as_f64().unwrap());
            assert!(
                (a - b).abs() <= 1e-9 * b.abs().max(1.0),
                "{what}: got {a}, want {b}"
            );
        }
    }
}

fn run_json(args: &[&str]) -> Value {
    let o = moma(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn dynamics_takes_and_gives_pinocchio_states_as_they_are() {
    for (file, root) in [
        ("tiago_planar.json", "planar"),
        ("tiago_freeflyer.json", "free-flyer"),
    ] {
        let d = dump(file);
        let states: Vec<Value> = d["states"]
            .as_array()
            .unwrap()
            .iter()
            .map(|s| json!({"q": s["q"], "v": s["v"], "a": s["a"], "tau": s["tau_in"]}))
            .collect();
        let p = tmp(&format!("pin_{root}.json"));
        std::fs::write(&p, json!({ "states": states }).to_string()).unwrap();
        let urdf = format!("{DATA}/{}", d["urdf"].as_str().unwrap());
        let out = run_json(&[
            "dynamics",
            &urdf,
            "--root",
            root,
            "--states",
            p.to_str().unwrap(),
            "--frame",
            "arm_tool_link",
            "--layout",
            "pinocchio",
        ]);
        assert_eq!(out["nq"], d["nq"], "{file}");
        assert_eq!(out["layout"], "pinocchio");
        for (k, s) in d["states"].as_array().unwrap().iter().enumerate() {
            let o = &out["states"][k];
            let w = |x: &str| format!("{file} state {k} {x}");
            close(&w("rnea"), &o["rnea_tau"], &s["rnea_tau"]);
            close(&w("crba"), &o["crba_M"], &s["crba_M"]);
            close(&w("aba"), &o["aba_ddq"], &s["aba_ddq"]);
            close(&w("nle"), &o["nle"], &s["nle"]);
            close(&w("gravity"), &o["gravity_torque"], &s["gravity_torque"]);
            close(&w("Ag"), &o["centroidal_map_Ag"], &s["centroidal_map_Ag"]);
            close(&w("com"), &o["com"], &s["com"]);
            assert_eq!(s["ee_frame"]["name"], "arm_tool_link");
            close(
                &w("J"),
                &o["jacobian_local_world_aligned"],
                &s["ee_frame"]["jacobian_local_world_aligned"],
            );
        }
        // a Pinocchio q of moma's length is one clear error
        let bad = tmp("bad.json");
        let mut q = d["states"][0]["q"].as_array().unwrap().clone();
        q.pop();
        std::fs::write(&bad, json!({"states": [{"q": q}]}).to_string()).unwrap();
        let o = moma(&[
            "dynamics",
            &urdf,
            "--root",
            root,
            "--states",
            bad.to_str().unwrap(),
            "--layout",
            "pinocchio",
        ]);
        assert_eq!(o.status.code(), Some(1));
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(
            e.contains("states[0].q") && e.contains("Pinocchio layout"),
            "{e}"
        );
    }
}

use moma::io::pinocchio_layout::PinocchioLayout;
use moma::multibody::RootJoint;

fn tiago_urdf() -> String {
    format!("{DATA}/urdf/tiago.urdf")
}

fn layout(root: RootJoint) -> (PinocchioLayout, usize) {
    let m = moma::io::urdf::model_from_urdf_file(tiago_urdf(), root).unwrap();
    (PinocchioLayout::new(&m), m.nq)
}

fn nums(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

/// Writes `{"states": states}` and returns its path.
fn states_file(name: &str, states: Vec<Value>) -> String {
    let p = tmp(name);
    std::fs::write(&p, json!({ "states": states }).to_string()).unwrap();
    p.to_str().unwrap().to_string()
}

/// The planar TIAGo dump's states in both layouts: (Pinocchio as given, moma converted).
fn planar_states(fields: &[&str]) -> (Vec<Value>, Vec<Value>) {
    let d = dump("tiago_planar.json");
    let (l, nq) = layout(RootJoint::Planar);
    let (mut pin, mut mom) = (Vec::new(), Vec::new());
    for s in d["states"].as_array().unwrap() {
        let (qp, vp, ap) = (nums(&s["q"]), nums(&s["v"]), nums(&s["a"]));
        let mut q = vec![0.0; nq];
        l.q_from_pinocchio(&qp, &mut q).unwrap();
        let (mut v, mut a) = (vec![0.0; vp.len()], vec![0.0; vp.len()]);
        l.v_from_pinocchio(&q, &vp, &mut v);
        l.a_from_pinocchio(&q, &v, &ap, &mut a);
        let mut p = serde_json::Map::new();
        let mut m = serde_json::Map::new();
        for f in fields {
            let (x, y) = match *f {
                "q" => (json!(qp), json!(q)),
                "v" => (json!(vp), json!(v)),
                _ => (json!(ap), json!(a)),
            };
            p.insert(f.to_string(), x);
            m.insert(f.to_string(), y);
        }
        pin.push(Value::Object(p));
        mom.push(Value::Object(m));
    }
    (pin, mom)
}

#[test]
fn stability_reads_pinocchio_states() {
    let (pin, mom) = planar_states(&["q", "v", "a"]);
    let base = "diff-drive:r_w=0.0985,b=0.2022,d=0,casters=0.1535,0.102;0.1535,-0.102;-0.1895,0.102;-0.1895,-0.102";
    let run = |file: &str, lay: &str| {
        run_json(&[
            "stability",
            &tiago_urdf(),
            "--base",
            base,
            "--states",
            file,
            "--layout",
            lay,
        ])
    };
    let a = run(&states_file("stab_pin.json", pin), "pinocchio");
    let b = run(&states_file("stab_moma.json", mom), "moma");
    for k in 0..3 {
        for key in ["zmp_margin", "force_angle_alpha", "mhs_min", "com"] {
            close(
                &format!("state {k} {key}"),
                &a["states"][k][key],
                &b["states"][k][key],
            );
        }
        close(
            &format!("state {k} giw"),
            &a["states"][k]["giw"]["force"],
            &b["states"][k]["giw"]["force"],
        );
    }
}

#[test]
fn manipulability_reads_and_writes_pinocchio_q() {
    let (pin, mom) = planar_states(&["q"]);
    let run = |file: &str, lay: &str| {
        run_json(&[
            "manipulability",
            &tiago_urdf(),
            "--base",
            "diff-drive:r_w=0.0985,b=0.2022,d=0",
            "--frame",
            "arm_tool_link",
            "--states",
            file,
            "--json",
            "--layout",
            lay,
        ])
    };
    let a = run(&states_file("man_pin.json", pin.clone()), "pinocchio");
    let b = run(&states_file("man_moma.json", mom), "moma");
    for k in 0..3 {
        close(
            &format!("state {k} arm"),
            &a["states"][k]["arm_value"],
            &b["states"][k]["arm_value"],
        );
        close(
            &format!("state {k} whole body"),
            &a["states"][k]["whole_body_value"],
            &b["states"][k]["whole_body_value"],
        );
        close(&format!("state {k} q"), &a["states"][k]["q"], &pin[k]["q"]);
    }
}

#[test]
fn space_and_osc_read_pinocchio_q() {
    // free-flyer TIAGo: only the continuous wheels differ
    let d = dump("tiago_freeflyer.json");
    let (l, nq) = layout(RootJoint::FreeFlyer);
    let s0 = &d["states"][0];
    let qp = nums(&s0["q"]);
    let mut q = vec![0.0; nq];
    l.q_from_pinocchio(&qp, &mut q).unwrap();
    assert_ne!(qp.len(), q.len());
    let qd: Vec<f64> = nums(&s0["v"])[6..].to_vec();
    let run = |qq: &Vec<f64>, lay: &str| {
        let f = states_file(
            &format!("space_{lay}.json"),
            vec![json!({"q": qq, "qdot_joints": qd})],
        );
        run_json(&[
            "space",
            &tiago_urdf(),
            "--frame",
            "arm_tool_link",
            "--states",
            &f,
            "--layout",
            lay,
        ])
    };
    let (a, b) = (run(&qp, "pinocchio"), run(&q, "moma"));
    close("space v", &a["states"][0]["v"], &b["states"][0]["v"]);
    close(
        "space J*",
        &a["states"][0]["generalized_jacobian"],
        &b["states"][0]["generalized_jacobian"],
    );

    // fixed TIAGo for osc: the planar dump's q without the base
    let (lf, nqf) = layout(RootJoint::Fixed);
    let qpf = nums(&dump("tiago_planar.json")["states"][1]["q"])[4..].to_vec();
    let mut qf = vec![0.0; nqf];
    lf.q_from_pinocchio(&qpf, &mut qf).unwrap();
    let run = |qq: &Vec<f64>, lay: &str| {
        let f = states_file(
            &format!("osc_{lay}.json"),
            vec![json!({"q": qq, "task_acceleration": [0.1, 0.0, -0.2, 0.0, 0.3, 0.0]})],
        );
        run_json(&[
            "osc",
            &tiago_urdf(),
            "--root",
            "fixed",
            "--frame",
            "arm_tool_link",
            "--states",
            &f,
            "--layout",
            lay,
        ])
    };
    let (a, b) = (run(&qpf, "pinocchio"), run(&qf, "moma"));
    close(
        "osc torque",
        &a["states"][0]["torque"],
        &b["states"][0]["torque"],
    );
    close(
        "osc Lambda",
        &a["states"][0]["task_inertia"],
        &b["states"][0]["task_inertia"],
    );
}

/// `osc --layout pinocchio` on a planar root: the states of the TIAGo planar dump as they
/// are (base-frame v, null torque in Pinocchio's layout) against Λ, J̄, N, J̇v, F and τ
/// computed with Pinocchio 4.1 and numpy in Pinocchio's layout
/// (`control/osc_tiago_planar.json`), to 1e-9; and the same states in moma's layout give
/// the task quantities unchanged and J̄, τ through T.
#[test]
fn osc_on_a_planar_root_takes_and_gives_pinocchio_quantities() {
    let refdoc: Value = serde_json::from_str(
        &std::fs::read_to_string(format!("{DATA}/../control/osc_tiago_planar.json")).unwrap(),
    )
    .unwrap();
    let states: Vec<Value> = refdoc["states"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| {
            json!({"q": s["q"], "v": s["v"], "task_acceleration": s["task_acceleration"],
                   "null_torque": s["null_torque"]})
        })
        .collect();
    let f = states_file("osc_planar.json", states.clone());
    let run = |f: &str, lay: &str| {
        run_json(&[
            "osc",
            &tiago_urdf(),
            "--root",
            "planar",
            "--frame",
            "arm_tool_link",
            "--states",
            f,
            "--layout",
            lay,
        ])
    };
    let got = run(&f, "pinocchio");
    let keys = [
        "task_inertia",
        "dynamically_consistent_inverse",
        "nullspace_projector",
        "acceleration_bias",
        "task_force",
        "torque",
    ];
    for (k, want) in refdoc["states"].as_array().unwrap().iter().enumerate() {
        for key in keys {
            close(
                &format!("osc state {k} {key}"),
                &got["states"][k][key],
                &want[key],
            );
        }
    }
    // moma's layout: the same physical states; J̄ and τ differ by T, Λ and F do not
    let (l, nq) = layout(RootJoint::Planar);
    let mut mom = Vec::new();
    for s in &states {
        let (qp, vp, tp) = (nums(&s["q"]), nums(&s["v"]), nums(&s["null_torque"]));
        let mut q = vec![0.0; nq];
        l.q_from_pinocchio(&qp, &mut q).unwrap();
        let (mut v, mut t) = (vec![0.0; vp.len()], vec![0.0; vp.len()]);
        l.v_from_pinocchio(&q, &vp, &mut v);
        l.tau_from_pinocchio(&q, &tp, &mut t);
        mom.push((
            q.clone(),
            json!({"q": q, "v": v, "task_acceleration": s["task_acceleration"],
                                     "null_torque": t}),
        ));
    }
    let fm = states_file(
        "osc_planar_moma.json",
        mom.iter().map(|m| m.1.clone()).collect(),
    );
    let base = run(&fm, "moma");
    for (k, (q, _)) in mom.iter().enumerate() {
        for key in ["task_inertia", "task_force"] {
            close(
                &format!("moma layout {key}"),
                &base["states"][k][key],
                &got["states"][k][key],
            );
        }
        let tau = nums(&base["states"][k]["torque"]);
        let mut tau_p = vec![0.0; tau.len()];
        l.tau_to_pinocchio(q, &tau, &mut tau_p);
        close(
            "moma layout torque",
            &json!(tau_p),
            &got["states"][k]["torque"],
        );
        let jbar = &base["states"][k]["dynamically_consistent_inverse"];
        assert!(
            (nums(&jbar[0])[0] - nums(&got["states"][k]["dynamically_consistent_inverse"][0])[0])
                .abs()
                > 1e-6,
            "J̄ must change with the layout on a rotated base"
        );
    }
}

#[test]
fn ik_takes_and_gives_pinocchio_q() {
    let (lf, nqf) = layout(RootJoint::Fixed);
    let qpf = nums(&dump("tiago_planar.json")["states"][0]["q"])[4..].to_vec();
    let mut qf = vec![0.0; nqf];
    lf.q_from_pinocchio(&qpf, &mut qf).unwrap();
    let join = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x}"))
            .collect::<Vec<_>>()
            .join(",")
    };
    let run = |q0: &str, lay: &str| {
        let o = moma(&[
            "ik",
            &tiago_urdf(),
            "--frame",
            "arm_tool_link",
            "--target",
            "0.6,0.1,0.9",
            "--q0",
            q0,
            "--layout",
            lay,
            "--json",
        ]);
        serde_json::from_slice::<Value>(&o.stdout).unwrap()
    };
    let a = run(&join(&qpf), "pinocchio");
    let b = run(&join(&qf), "moma");
    assert_eq!(a["converged"], b["converged"]);
    let qa = nums(&a["q"]);
    assert_eq!(qa.len(), qpf.len());
    let mut back = vec![0.0; nqf];
    lf.q_from_pinocchio(&qa, &mut back).unwrap();
    close("ik q", &json!(back), &b["q"]);
}

#[test]
fn stability_map_and_reach_map_read_a_pinocchio_q() {
    // a wrong-length Pinocchio q is refused with the option named; a right one runs
    let (pin, _) = planar_states(&["q"]);
    let qp = nums(&pin[0]["q"]);
    let join = |v: &[f64]| {
        v.iter()
            .map(|x| format!("{x}"))
            .collect::<Vec<_>>()
            .join(",")
    };
    let dir = tmp("smap");
    let base = "diff-drive:r_w=0.0985,b=0.2022,d=0,casters=0.1535,0.102;-0.1895,0.102";
    let args = |q: &str| {
        vec![
            "stability-map".to_string(),
            tiago_urdf(),
            "--base".into(),
            base.into(),
            "--q".into(),
            q.to_string(),
            "--joints".into(),
            "arm_1_joint,arm_2_joint".into(),
            "--resolution".into(),
            "3".into(),
            "--layout".into(),
            "pinocchio".into(),
            "--output-dir".into(),
            dir.to_str().unwrap().into(),
        ]
    };
    let o = Command::new(env!("CARGO_BIN_EXE_moma"))
        .args(args(&join(&qp)))
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = Command::new(env!("CARGO_BIN_EXE_moma"))
        .args(args(&join(&qp[1..])))
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--q: expected length"));
    let o = moma(&[
        "reach-map",
        &tiago_urdf(),
        "--frame",
        "arm_tool_link",
        "--target",
        "0.6,0.1,0.9",
        "--area",
        "-0.2,-0.2,0.2,0.2",
        "--step",
        "0.2",
        "--headings",
        "2",
        "--q0",
        &join(&qp[4..]),
        "--layout",
        "pinocchio",
    ]);
    assert!(
        o.status.code() == Some(0) || o.status.code() == Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

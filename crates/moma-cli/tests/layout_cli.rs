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

//! `moma derivatives`, run as the built binary: the Pinocchio 4.1 reference files of
//! `moma/tests/data/derivatives` through `--layout pinocchio` (the shared Panda file and
//! TIAGo on a planar root, where the layout's chain rule acts), moma's layout against the
//! library, and clear errors (exit status 1 or 2, no output file, no panic) on bad input.

use serde_json::Value;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn moma() -> Command {
    Command::new(env!("CARGO_BIN_EXE_moma"))
}

fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../moma/tests/data/derivatives")
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("moma_derivatives_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

const KEYS: [&str; 6] = [
    "drnea_dq",
    "drnea_dv",
    "drnea_da",
    "daba_dq",
    "daba_dv",
    "daba_dtau",
];

fn matrix(v: &Value) -> Vec<Vec<f64>> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|r| {
            r.as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        })
        .collect()
}

/// Runs the states of `file` through the binary with `--layout pinocchio` and compares
/// every matrix with 1e-8 relative to its largest entry.
fn reference_through_cli(file: &str) {
    let path = data_dir().join(file);
    let doc: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let states: Vec<Value> = doc["states"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| serde_json::json!({"q": s["q"], "v": s["v"], "a": s["a"], "tau": s["tau"]}))
        .collect();
    let input = tmp(&format!("states_{file}"));
    std::fs::write(&input, serde_json::json!({ "states": states }).to_string()).unwrap();
    let output = tmp(&format!("out_{file}"));
    let out = moma()
        .arg("derivatives")
        .arg(data_dir().join(doc["urdf"].as_str().unwrap()))
        .args(["--root", doc["root"].as_str().unwrap(), "--states"])
        .arg(&input)
        .args(["--layout", "pinocchio", "--output"])
        .arg(&output)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let got: Value = serde_json::from_str(&std::fs::read_to_string(&output).unwrap()).unwrap();
    assert_eq!(got["layout"], "pinocchio");
    let got_states = got["states"].as_array().unwrap();
    assert_eq!(got_states.len(), states.len());
    for (k, want) in doc["states"].as_array().unwrap().iter().enumerate() {
        for key in KEYS {
            let (g, w) = (matrix(&got_states[k][key]), matrix(&want[key]));
            assert_eq!(g.len(), w.len(), "{file} {k} {key} rows");
            let scale = w.iter().flatten().fold(1.0f64, |m, x| m.max(x.abs()));
            for (gr, wr) in g.iter().zip(&w) {
                assert_eq!(gr.len(), wr.len());
                for (x, y) in gr.iter().zip(wr) {
                    assert!(
                        (x - y).abs() <= 1e-8 * scale,
                        "{file} state {k} {key}: {x} vs {y}"
                    );
                }
            }
        }
    }
}

#[test]
fn shared_panda_reference_through_the_binary() {
    reference_through_cli("panda.json");
}

#[test]
fn tiago_planar_reference_through_the_binary() {
    reference_through_cli("tiago_planar.json");
}

#[test]
fn free_flyer_reference_through_the_binary() {
    reference_through_cli("ur5_freeflyer.json");
}

fn run_states(text: &str, extra: &[&str]) -> (Output, PathBuf) {
    let input = tmp(&format!("bad_{}.json", text.len()));
    std::fs::write(&input, text).unwrap();
    let output = tmp(&format!("never_{}.json", text.len()));
    let _ = std::fs::remove_file(&output);
    let out = moma()
        .arg("derivatives")
        .arg(data_dir().join("../pinocchio/urdf/panda.urdf"))
        .args(["--root", "fixed", "--states"])
        .arg(&input)
        .args(extra)
        .arg("--output")
        .arg(&output)
        .output()
        .unwrap();
    (out, output)
}

#[track_caller]
fn fails_with(out: &Output, output: &Path, code: i32, needles: &[&str]) {
    assert_eq!(
        out.status.code(),
        Some(code),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "moma panicked: {err}");
    for n in needles {
        assert!(err.contains(n), "stderr lacks '{n}': {err}");
    }
    assert!(!output.exists(), "a failed run left an output file");
}

#[test]
fn bad_input_is_reported() {
    let (out, o) = run_states(r#"{"states": [{"q": [0, 0, 0]}]}"#, &[]);
    fails_with(&out, &o, 1, &["states[0] q", "expected length 9, got 3"]);
    let q9 = "[0, 0, 0, 0, 0, 0, 0, 0, 0]";
    let (out, o) = run_states(
        &format!(r#"{{"states": [{{"q": {q9}, "v": [1, 2]}}]}}"#),
        &[],
    );
    fails_with(&out, &o, 1, &["states[0]", "v"]);
    let (out, o) = run_states(r#"{"states": [{"q": [0, 0, 0, 0, 0, 0, 0, 0, "x"]}]}"#, &[]);
    fails_with(&out, &o, 1, &["bad_"]);
    let (out, o) = run_states(
        &format!(r#"{{"states": [{{"q": {q9}}}]}}"#),
        &["--layout", "euler"],
    );
    fails_with(&out, &o, 2, &["euler"]);
}

/// Without `--layout`, the states and outputs are in moma's layout (a planar q of nv = nq
/// entries is accepted, which Pinocchio's layout would refuse).
#[test]
fn moma_layout_is_the_default() {
    let urdf = data_dir().join("../pinocchio/urdf/ur5_robot.urdf");
    let q = "[0.1, 0.2, 0.7, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6]";
    let v = "[0.3, -0.2, 0.5, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6]";
    let input = tmp("moma_layout.json");
    std::fs::write(&input, format!(r#"{{"states": [{{"q": {q}, "v": {v}}}]}}"#)).unwrap();
    let get = |layout: Option<&str>| -> Output {
        let mut cmd = moma();
        cmd.arg("derivatives")
            .arg(&urdf)
            .args(["--root", "planar", "--states"])
            .arg(&input);
        if let Some(l) = layout {
            cmd.args(["--layout", l]);
        }
        cmd.output().unwrap()
    };
    let json = |out: Output| -> Value {
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_slice(&out.stdout).unwrap()
    };
    let (default, explicit) = (json(get(None)), json(get(Some("moma"))));
    assert_eq!(default["layout"], "moma");
    assert_eq!(default["nv"], 9);
    assert_eq!(default["states"], explicit["states"]);
    let dq = matrix(&default["states"][0]["drnea_dq"]);
    assert_eq!((dq.len(), dq[0].len()), (9, 9));
    let pin = get(Some("pinocchio"));
    assert_eq!(pin.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&pin.stderr).contains("Pinocchio layout"));
}

/// `--frame`: the frame derivative fields of the Pinocchio 4.1 files `frame_*.json`
/// through `--layout pinocchio` (TIAGo on a planar root, where the chain rule acts, and
/// Panda on a free-flyer), every entry within 1e-8 of the matrix's largest.
fn frame_reference_through_cli(file: &str) {
    let path = data_dir().join(file);
    let doc: Value = serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let frame = doc["frame"].as_str().unwrap();
    let states: Vec<Value> = doc["states"]
        .as_array()
        .unwrap()
        .iter()
        .map(|s| serde_json::json!({"q": s["q"], "v": s["v"], "a": s["a"]}))
        .collect();
    let input = tmp(&format!("states_{file}"));
    std::fs::write(&input, serde_json::json!({ "states": states }).to_string()).unwrap();
    let out = moma()
        .arg("derivatives")
        .arg(data_dir().join(doc["urdf"].as_str().unwrap()))
        .args(["--root", doc["root"].as_str().unwrap(), "--states"])
        .arg(&input)
        .args(["--layout", "pinocchio", "--frame", frame])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let got: Value = serde_json::from_slice(&out.stdout).unwrap();
    for (k, want) in doc["states"].as_array().unwrap().iter().enumerate() {
        let g = &got["states"][k]["frame"];
        assert_eq!(g["name"], frame);
        let close = |g: &Value, w: &Value, what: &str| {
            let (g, w) = match (g.as_array().unwrap()[0].is_array(), w) {
                (true, _) => (matrix(g), matrix(w)),
                (false, _) => (vec![matrix_row(g)], vec![matrix_row(w)]),
            };
            let scale = w.iter().flatten().fold(1.0f64, |m, x| m.max(x.abs()));
            assert_eq!(g.len(), w.len(), "{file} {k} {what} rows");
            for (gr, wr) in g.iter().zip(&w) {
                assert_eq!(gr.len(), wr.len(), "{file} {k} {what} columns");
                for (x, y) in gr.iter().zip(wr) {
                    assert!(
                        (x - y).abs() <= 1e-8 * scale,
                        "{file} state {k} {what}: {x} vs {y}"
                    );
                }
            }
        };
        close(
            &g["placement"]["translation"],
            &want["placement"]["translation"],
            "translation",
        );
        close(
            &g["placement"]["rotation"],
            &want["placement"]["rotation"],
            "rotation",
        );
        for rf in ["local", "world", "local_world_aligned"] {
            for key in [
                "velocity",
                "acceleration",
                "jacobian",
                "dv_dq",
                "da_dq",
                "da_dv",
            ] {
                close(&g[rf][key], &want[rf][key], &format!("{rf} {key}"));
            }
        }
    }
}

fn matrix_row(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

#[test]
fn frame_reference_through_the_binary() {
    frame_reference_through_cli("frame_tiago_planar.json");
    frame_reference_through_cli("frame_panda_freeflyer.json");
}

#[test]
fn unknown_frame_is_reported() {
    let (out, o) = run_states(
        r#"{"states": [{"q": [0, 0, 0, 0, 0, 0, 0, 0, 0]}]}"#,
        &["--frame", "no_such_link"],
    );
    fails_with(&out, &o, 1, &["--frame", "no_such_link"]);
}

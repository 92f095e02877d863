//! End-to-end tests of `moma stability` and `moma stability-map`: the public multibody
//! cases (Panda on a planar base, reference values from an independent computation) and
//! the command's errors (clear message, exit status 1, no output file).

use serde_json::Value;
use std::path::PathBuf;
use std::process::{Command, Output};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../moma/tests/data");

fn panda() -> String {
    format!("{DATA}/pinocchio/urdf/panda.urdf")
}

fn moma(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_moma"))
        .args(args)
        .output()
        .expect("run moma")
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("moma_stability_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Every number of `want` matches `got` (relative 1e-9), `null` matches `null`, and every
/// key of `want` is present.
fn compare(got: &Value, want: &Value, path: &str) {
    match (got, want) {
        (Value::Object(g), Value::Object(w)) => {
            for (k, wv) in w {
                let gv = g.get(k).unwrap_or_else(|| panic!("{path}.{k} missing"));
                compare(gv, wv, &format!("{path}.{k}"));
            }
        }
        (Value::Array(g), Value::Array(w)) => {
            assert_eq!(g.len(), w.len(), "{path}: length");
            for (i, (a, b)) in g.iter().zip(w).enumerate() {
                compare(a, b, &format!("{path}[{i}]"));
            }
        }
        (Value::Number(_), Value::Number(_)) => {
            let (a, b) = (got.as_f64().unwrap(), want.as_f64().unwrap());
            assert!(
                (a - b).abs() <= 1e-9 * (1.0 + b.abs()),
                "{path}: got {a}, want {b}"
            );
        }
        _ => assert_eq!(got, want, "{path}"),
    }
}

fn support_arg(c: &Value) -> String {
    c["support_base"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| format!("{},{}", p[0], p[1]))
        .collect::<Vec<_>>()
        .join(";")
}

#[test]
fn public_multibody_cases() {
    let j: Value = serde_json::from_str(
        &std::fs::read_to_string(format!("{DATA}/stability/multibody_public.json")).unwrap(),
    )
    .unwrap();
    for (k, c) in j["cases"].as_array().unwrap().iter().enumerate() {
        let states = tmp(&format!("states{k}.json"));
        let out = tmp(&format!("out{k}.json"));
        std::fs::write(
            &states,
            serde_json::json!({"states": [c["state"]]}).to_string(),
        )
        .unwrap();
        let g = c["gravity"].as_array().unwrap();
        let gravity = format!("{},{},{}", g[0], g[1], g[2]);
        let support = support_arg(c);
        let o = moma(&[
            "stability",
            &panda(),
            "--root",
            "planar",
            "--support",
            &support,
            "--states",
            states.to_str().unwrap(),
            "--mhs-bodies",
            c["mhs_bodies"].as_str().unwrap(),
            &format!("--gravity={gravity}"),
            "--output",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let got: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        let s = &got["states"][0];
        compare(s, &c["expected"], &format!("case {k}"));
        let inside = c["expected"]["zmp_margin"].as_f64().unwrap() > 0.0;
        assert_eq!(s["stable"], Value::Bool(inside), "case {k}");
        assert_eq!(
            s.get("acceleration_limits").is_some(),
            c["kind"] == "static",
            "limits only at rest"
        );
    }
}

#[test]
fn wheeled_base_support_and_stdout() {
    let states = tmp("base_states.json");
    std::fs::write(
        &states,
        r#"{"states": [{"q": [0,0,0, 0,0,0,-1.5,0,1.5,0.8,0,0]}]}"#,
    )
    .unwrap();
    let o = moma(&[
        "stability",
        &panda(),
        "--base",
        "diff-drive:r_w=0.1,b=0.25,d=0.1,casters=0.35,0.2;0.35,-0.2",
        "--states",
        states.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: Value = serde_json::from_slice(&o.stdout).unwrap();
    let sup = v["states"][0]["support"].as_array().unwrap();
    assert_eq!(sup.len(), 4);
    // wheels at x = −d = −0.1, y = ±0.25; start at the smallest x then smallest y
    assert_eq!(sup[0][0].as_f64().unwrap(), -0.1);
    assert_eq!(sup[0][1].as_f64().unwrap(), -0.25);
    assert_eq!(sup[1][1].as_f64().unwrap(), 0.25);
    assert!(v["states"][0]["acceleration_limits"]["forward"].is_number());
}

fn expect_error(args: &[&str], needle: &str, out: &PathBuf) {
    let _ = std::fs::remove_file(out);
    let o = moma(args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
    assert!(err.contains(needle), "{args:?}: '{needle}' not in: {err}");
    assert!(!out.exists(), "{args:?}: output written on error");
}

#[test]
fn errors_are_clear_and_leave_no_output() {
    let out = tmp("err_out.json");
    let good = tmp("good.json");
    std::fs::write(
        &good,
        r#"{"states": [{"q": [0,0,0, 0,0,0,-1.5,0,1.5,0.8,0,0]}]}"#,
    )
    .unwrap();
    let short = tmp("short.json");
    std::fs::write(&short, r#"{"states": [{"q": [0,0,0, 0,0,0]}]}"#).unwrap();
    let bad_v = tmp("bad_v.json");
    std::fs::write(
        &bad_v,
        r#"{"states": [{"q": [0,0,0, 0,0,0,-1.5,0,1.5,0.8,0,0], "v": [1, 2]}]}"#,
    )
    .unwrap();
    let bad_ext = tmp("bad_ext.json");
    std::fs::write(
        &bad_ext,
        r#"{"states": [{"q": [0,0,0, 0,0,0,-1.5,0,1.5,0.8,0,0], "external": [{"point": [0,0], "force": [1,0,0]}]}]}"#,
    )
    .unwrap();
    let nan = tmp("nan.json");
    std::fs::write(
        &nan,
        r#"{"states": [{"q": [0,0,NaN, 0,0,0,-1.5,0,1.5,0.8,0,0]}]}"#,
    )
    .unwrap();
    let sq = "0.3,0.2;0.3,-0.2;-0.3,-0.2;-0.3,0.2";
    let p = panda();
    let (g, o) = (good.to_str().unwrap(), out.to_str().unwrap());
    let run = |support: &str, states: &str, extra: &[&str]| {
        let mut v = vec![
            "stability",
            p.as_str(),
            "--support",
            support,
            "--states",
            states,
        ];
        v.extend_from_slice(extra);
        v.extend_from_slice(&["--output", o]);
        v.into_iter().map(String::from).collect::<Vec<_>>()
    };
    let check = |args: Vec<String>, needle: &str| {
        let a: Vec<&str> = args.iter().map(String::as_str).collect();
        expect_error(&a, needle, &out);
    };
    check(run("0.3,0.2;0.3,-0.2", g, &[]), "three non-collinear");
    check(run("0,0;1,1;2,2", g, &[]), "three non-collinear");
    check(run("0.3,0.2;0.3;-0.3,0.1", g, &[]), "must be X,Y");
    check(run("0.3,0.2;nan,0;-0.3,0.1", g, &[]), "not finite");
    check(
        run(sq, g, &["--mhs-bodies", "subtree:no_such_joint"]),
        "unknown joint 'no_such_joint'",
    );
    check(
        run(sq, g, &["--mhs-bodies", "links:panda_link3,nope"]),
        "unknown link 'nope'",
    );
    check(run(sq, g, &["--mhs-bodies", "arm"]), "--mhs-bodies");
    check(run(sq, g, &["--gravity", "0,0"]), "--gravity");
    check(run(sq, g, &["--gravity=0,nan,-9.81"]), "not finite");
    check(
        run(sq, short.to_str().unwrap(), &[]),
        "states[0] q: expected length 12, got 6",
    );
    check(
        run(sq, bad_v.to_str().unwrap(), &[]),
        "states[0] v: expected length 12, got 2",
    );
    check(
        run(sq, bad_ext.to_str().unwrap(), &[]),
        "states[0].external[0].point: expected length 3",
    );
    check(run(sq, nan.to_str().unwrap(), &[]), "invalid JSON");
    // malformed command line: exit 2
    let o2 = moma(&["stability", &p, "--states", g]);
    assert_eq!(o2.status.code(), Some(2));
}

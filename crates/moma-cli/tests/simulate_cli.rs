//! `moma simulate`: the bundled default scenario runs with no argument, the chapter
//! scenarios run, and bad scenario files fail with a clear message and no output.

mod cli_common;

use cli_common::{moma, scenarios, summary, temp_dir};

#[test]
fn default_scenario_runs_without_an_argument() {
    let work = temp_dir("default");
    let out = work.join("out");
    // Run from an empty directory: the default is found next to the source tree.
    let run = moma()
        .current_dir(&work)
        .args(["simulate", "--quiet", "--output"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    for f in [
        "trajectory.csv",
        "summary.json",
        "path.svg",
        "joints.svg",
        "energy.svg",
        "energy_error.svg",
        "residual.svg",
        "multipliers.svg",
    ] {
        assert!(out.join(f).is_file(), "missing {f}");
    }
    let s = summary(&out);
    assert!(s["max_constraint_residual"].as_f64().unwrap() < 1e-12);
    assert!(s["relative_energy_error"].as_f64().unwrap() < 1e-6);
    assert_eq!(s["samples"].as_u64().unwrap(), 501);
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    assert!(
        csv.starts_with("t [s],x [m],y [m],theta [rad],left_wheel_joint [rad]"),
        "{}",
        csv.lines().next().unwrap()
    );
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .contains(",v [m/s],omega [rad/s],")
    );
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .contains(",tau_left [N m],tau_right [N m],")
    );
    assert!(
        csv.lines()
            .next()
            .unwrap()
            .ends_with("residual [m/s],lambda_0 [N],lambda_1 [N],lambda_2 [N]")
    );
    assert_eq!(csv.lines().count(), 502);
    // The platform moved along a curve.
    let fq: Vec<f64> = s["final_q"]
        .as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect();
    assert!(fq[0].hypot(fq[1]) > 0.5 && fq[2].abs() > 0.1, "{fq:?}");
}

#[test]
fn chapter_scenarios_run_and_print_a_summary() {
    for name in ["m1_unicycle", "m2_platform_arm", "m5_mobile_manipulator"] {
        let out = temp_dir(name);
        let run = moma()
            .arg("simulate")
            .arg(scenarios().join(format!("{name}.toml")))
            .arg("--output")
            .arg(&out)
            .output()
            .unwrap();
        assert!(
            run.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        let printed: serde_json::Value = serde_json::from_slice(&run.stdout).unwrap();
        assert_eq!(printed["duration"].as_f64(), Some(3.0));
        let s = summary(&out);
        assert!(
            s["max_constraint_residual"].as_f64().unwrap() < 1e-12,
            "{name}"
        );
        assert!(
            s["relative_energy_error"].as_f64().unwrap() < 1e-6,
            "{name}"
        );
        assert!(s["accepted_steps"].as_u64().unwrap() == 3000, "{name}");
    }
}

fn fails_with(tag: &str, text: &str, needles: &[&str]) {
    let dir = temp_dir(tag);
    let file = dir.join("bad.toml");
    std::fs::write(&file, text).unwrap();
    let out = dir.join("out");
    let run = moma()
        .arg("simulate")
        .arg(&file)
        .arg("--output")
        .arg(&out)
        .output()
        .unwrap();
    assert!(!run.status.success(), "{tag}: should fail");
    let err = String::from_utf8_lossy(&run.stderr);
    for n in needles {
        assert!(err.contains(n), "{tag}: error lacks '{n}': {err}");
    }
    assert!(!err.contains("panicked"), "{tag}: {err}");
    assert!(
        !out.exists() || std::fs::read_dir(&out).unwrap().next().is_none(),
        "{tag}: partial output"
    );
}

const M1: &str = r#"
duration = 1.0
[robot]
kind = "chapter"
model = "m1"
[robot.params]
m = 20.0
I = 0.5
d = 0.1
r_w = 0.05
b = 0.2
[integrator]
method = "rk4"
dt = 0.01
"#;

#[test]
fn bad_scenarios_fail_clearly_without_output() {
    fails_with(
        "unknown-model",
        &M1.replace("\"m1\"", "\"m7\""),
        &["bad.toml", "m7"],
    );
    fails_with(
        "missing-param",
        &M1.replace("b = 0.2\n", ""),
        &["bad.toml", "missing field `b`"],
    );
    fails_with(
        "nan-param",
        &M1.replace("m = 20.0", "m = nan"),
        &["bad.toml", "m"],
    );
    fails_with(
        "unknown-field",
        &M1.replace("duration = 1.0", "duration = 1.0\nspeed = 3"),
        &["bad.toml", "speed", "line"],
    );
    fails_with(
        "bad-dt",
        &M1.replace("dt = 0.01", "dt = -1.0"),
        &["bad.toml", "integrator.dt"],
    );
    fails_with(
        "bad-q",
        &format!("{M1}\n[initial]\nq = [0.0, 1.0]\n"),
        &["initial.q", "expected 3"],
    );
    fails_with(
        "bad-inputs",
        &format!("{M1}\n[[inputs]]\nkind = \"constant\"\nvalue = 1.0\n"),
        &["inputs", "expected 2"],
    );
    fails_with(
        "missing-urdf",
        r#"
duration = 1.0
[robot]
kind = "urdf"
urdf = "nowhere.urdf"
drive = { r_w = 0.1, b = 0.2, d = 0.0 }
[integrator]
method = "rk4"
dt = 0.01
"#,
        &["nowhere.urdf"],
    );
    fails_with("syntax", "duration = = 1", &["bad.toml", "line 1"]);
    // No silently ignored input: gravity for a horizontal chapter model, casters that
    // cannot be support points, casters on a chapter model.
    fails_with(
        "gravity-m1",
        &M1.replace(
            "duration = 1.0",
            "duration = 1.0
gravity = 9.81",
        ),
        &["bad.toml", "gravity", "m1", "no gravity term"],
    );
    // A parameter that the chapter model does not have is an error naming it and the
    // model's parameters, not ignored.
    fails_with(
        "unknown-param",
        &M1.replace("b = 0.2", "b = 0.2\nwheel_mass = 1.5"),
        &[
            "bad.toml",
            "params.wheel_mass",
            "unknown parameter 'wheel_mass' of model m1_unicycle",
            "m, I, d, r_w, b",
        ],
    );
    let urdf = scenarios().join("robots/diffdrive_arm.urdf");
    let urdf_robot = |casters: &str| {
        format!(
            "duration = 0.1
[robot]
kind = \"urdf\"
urdf = {:?}
             drive = {{ r_w = 0.08, b = 0.25, d = 0.1 }}
casters = {casters}
             [integrator]
method = \"rk4\"
dt = 0.01
",
            urdf.display().to_string()
        )
    };
    fails_with(
        "caster-twice",
        &urdf_robot(
            r#"[{ name = "rear", position = [0.2, 0.0] }, { name = "rear", position = [0.3, 0.0] }]"#,
        ),
        &["bad.toml", "caster 'rear'", "two casters"],
    );
    fails_with(
        "caster-unnamed",
        &urdf_robot(r#"[{ name = " ", position = [0.2, 0.0] }]"#),
        &["bad.toml", "casters[0] name"],
    );
    fails_with(
        "caster-on-chapter-model",
        &M1.replace(
            "[robot.params]",
            "casters = []
[robot.params]",
        ),
        &["bad.toml", "casters"],
    );
    // An initial state beyond the blow-up bound is refused before the run, naming it.
    fails_with(
        "blow-up-at-start",
        &format!(
            "{M1}\n[limits]\nblowup = 1.0\nmax_residual = 1.0\n[initial]\nq = [0.0, 0.0, 0.0]\nv = [5.0, 0.0]\n"
        ),
        &["initial.v[0]", "blowup"],
    );
    // A run that blows up on the way writes nothing.
    fails_with(
        "blow-up",
        &format!(
            "{M1}\n[limits]\nblowup = 1.0\nmax_residual = 1.0\n[initial]\nq = [0.0, 0.0, 0.0]\nv = [0.9, 0.0]\n[[inputs]]\nkind = \"constant\"\nvalue = 50.0\n[[inputs]]\nkind = \"constant\"\nvalue = 50.0\n"
        ),
        &["numerical failure"],
    );
}

#[test]
fn chapter_models_take_the_names_of_moma_eval() {
    // The canonical name of the one model registry runs exactly as the short alias.
    let mut finals = Vec::new();
    for name in ["m1", "m1_unicycle"] {
        let dir = temp_dir(&format!("name-{name}"));
        let file = dir.join("s.toml");
        std::fs::write(&file, M1.replace("\"m1\"", &format!("\"{name}\""))).unwrap();
        let out = dir.join("out");
        let run = moma()
            .args(["simulate", "--quiet"])
            .arg(&file)
            .arg("--output")
            .arg(&out)
            .output()
            .unwrap();
        assert!(
            run.status.success(),
            "{name}: {}",
            String::from_utf8_lossy(&run.stderr)
        );
        finals.push(summary(&out)["final_q"].clone());
    }
    assert!(finals[0].is_array());
    assert_eq!(finals[0], finals[1]);
    // A model `moma eval` knows but the simulator cannot run is refused by name.
    fails_with(
        "kinematic-model",
        &M1.replace("\"m1\"", "\"m3\""),
        &[
            "bad.toml",
            "m3_diffdrive_kinematics",
            "simulable models: m1_unicycle (m1)",
        ],
    );
}

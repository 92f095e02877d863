//! `moma sweep` on a lift-off study: a small cut of the shipped
//! `scenarios/sweeps/lift_off.toml` writes the table with the documented columns, the
//! figure (one marker per point and the line y = x) and the largest deviation line; the
//! figure is refused for another study; bad input is one error naming the file and the
//! field, with no output.

mod cli_common;

use cli_common::{moma, scenarios, temp_dir};
use std::path::{Path, PathBuf};

/// The shipped lift-off sweep cut to `params` (its robot path made absolute), with the
/// `[lift_off]` line `extra` (`key = value`) replacing that key's line, written to
/// `dir/name`.
fn lift_off_sweep(dir: &Path, name: &str, params: &str, extra: &str) -> PathBuf {
    let text = std::fs::read_to_string(scenarios().join("sweeps/lift_off.toml")).unwrap();
    let (head, section) = text.split_once("[lift_off]").unwrap();
    let (before, _) = head.split_once("[parameters]").unwrap();
    let robot = scenarios().join("robots/diffdrive_arm.urdf");
    let section = section.replace(
        "\"../robots/diffdrive_arm.urdf\"",
        &format!("\"{}\"", robot.display()),
    );
    let key = extra.split('=').next().unwrap().trim();
    let section: String = section
        .lines()
        .filter(|l| key.is_empty() || !l.starts_with(key))
        .map(|l| format!("{l}\n"))
        .collect();
    let text = format!("{before}[parameters]\n{params}\n[lift_off]{section}{extra}\n");
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn a_small_lift_off_sweep_writes_its_table_and_figure() {
    let dir = temp_dir("lift_off");
    let sw = lift_off_sweep(
        &dir,
        "small.toml",
        "\"q.shoulder_joint\" = [0.3, 1.5]\npayload = [0.0, 2.0]",
        "",
    );
    let (csv, svg) = (dir.join("lift.csv"), dir.join("lift.svg"));
    let o = moma()
        .args(["sweep", s(&sw), "-o", s(&csv), "--figure", s(&svg)])
        .output()
        .unwrap();
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(&csv).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(
        header,
        [
            "index",
            "q.shoulder_joint",
            "payload",
            "predicted_limit",
            "simulated_limit",
            "ratio",
            "lifted_contact",
            "bisection_runs",
            "eval_time_s"
        ]
    );
    let mut largest: f64 = 0.0;
    for line in lines {
        let f: Vec<&str> = line.split(',').collect();
        let ratio: f64 = f[5].parse().unwrap();
        assert!((ratio - 1.0).abs() < 0.05, "{line}");
        assert_eq!(f[6], "caster", "{line}");
        if (ratio - 1.0).abs() > largest.abs() {
            largest = ratio - 1.0;
        }
    }
    assert!(
        out.contains(&format!("{:+.2} %", 100.0 * largest)),
        "the printed largest deviation is the table's: {out}"
    );
    let fig = std::fs::read_to_string(&svg).unwrap();
    assert!(fig.starts_with("<svg") && fig.trim_end().ends_with("</svg>"));
    assert_eq!(fig.matches("<circle").count(), 4, "one marker per point");
    assert!(fig.contains("payload 0 kg") && fig.contains("payload 2 kg") && fig.contains("y = x"));
}

#[test]
fn bad_lift_off_input_is_one_error_and_no_output() {
    let dir = temp_dir("lift_off_bad");
    let good = "\"q.shoulder_joint\" = [1.5]";
    let cases = [
        (
            lift_off_sweep(&dir, "joint.toml", "\"q.wrist_joint\" = [0.1]", ""),
            "parameters.\"q.wrist_joint\"",
        ),
        (
            lift_off_sweep(&dir, "payload.toml", "payload = [-2.0]", ""),
            "parameters.payload",
        ),
        (
            lift_off_sweep(&dir, "tol.toml", good, "tolerance = 0.0"),
            "lift_off.tolerance",
        ),
        // A payload of 1e300 kg failed at a sweep point with "no tip-over limit", a
        // bracket of 1e300 with non-finite plant accelerations; both now name the field.
        (
            lift_off_sweep(&dir, "heavy.toml", "payload = [0.0, 1e300]", ""),
            "parameters.payload: must be at most 1e4 kg, got 1e300",
        ),
        (
            lift_off_sweep(&dir, "bracket.toml", good, "bracket = [0.8, 1e300]"),
            "lift_off.bracket: needs 0 <= lo < hi <= 10",
        ),
        // gains unstable at the plant's step fail the point before it runs; the sweep
        // file was named twice (by the library's error and by the command)
        (
            lift_off_sweep(&dir, "gains.toml", good, "joint_gains = [2000, 1e5]"),
            "lift_off.joint_gains",
        ),
    ];
    let csv = dir.join("never.csv");
    let svg = dir.join("never.svg");
    for (file, field) in &cases {
        let o = moma()
            .args(["sweep", s(file), "-o", s(&csv), "--figure", s(&svg)])
            .output()
            .unwrap();
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{field}: {e}");
        assert!(e.contains(field), "{field}: {e}");
        assert_eq!(e.matches(s(file)).count(), 1, "the file named once: {e}");
        assert!(!csv.exists() && !svg.exists(), "{field}: left an output");
    }
    // The figure belongs to the lift-off study.
    let o = moma()
        .args([
            "sweep",
            s(&scenarios().join("sweeps/tiago_stability.toml")),
            "-o",
            s(&csv),
            "--figure",
            s(&svg),
        ])
        .output()
        .unwrap();
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains("--figure"), "{e}");
    assert!(!csv.exists() && !svg.exists());
}

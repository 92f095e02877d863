//! The claims the user documentation makes about the command line: every example of the
//! README runs as written from the repository root, every command follows the one
//! exit-status rule of `docs/cli.md`, and a failed run leaves no file or directory.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn data(p: &str) -> String {
    repo().join(p).display().to_string()
}

fn scratch(tag: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("moma-claims-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn moma_in(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_moma"))
        .current_dir(dir)
        .args(args)
        .output()
        .expect("run moma")
}

fn moma(args: &[&str]) -> Output {
    moma_in(&std::env::temp_dir(), args)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn entries(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// The `moma …` lines of the README's ```sh blocks.
fn readme_commands() -> Vec<String> {
    let text = std::fs::read_to_string(repo().join("README.md")).unwrap();
    let mut out = Vec::new();
    let mut in_sh = false;
    for line in text.lines() {
        let t = line.trim();
        if t.starts_with("```") {
            in_sh = !in_sh && t == "```sh";
            continue;
        }
        if in_sh && (t.starts_with("moma ") || t.starts_with("mkdir -p ")) {
            out.push(t.to_string());
        }
    }
    out
}

#[test]
fn every_readme_example_runs_as_written_from_the_repository_root() {
    let cmds = readme_commands();
    // one per subcommand at least (a README that lost its examples must fail)
    for sub in [
        "inspect",
        "dynamics",
        "derivatives",
        "bench",
        "eval",
        "simulate",
        "mission",
        "manipulability",
        "ik",
        "reach-map",
        "map-info",
        "plan",
        "scen",
        "space",
        "stability",
        "stability-map",
        "osc",
    ] {
        assert!(
            cmds.iter()
                .any(|c| c.starts_with(&format!("moma {sub} ")) || c == &format!("moma {sub}")),
            "README has no example of `moma {sub}`"
        );
    }
    assert!(
        !std::fs::read_to_string(repo().join("README.md"))
            .unwrap()
            .contains("ROBOT.urdf"),
        "placeholder file names in the README"
    );
    // A scratch "repository root": the shipped inputs linked in, the outputs stay here.
    let root = scratch("readme");
    for d in ["crates", "scenarios", "docs"] {
        std::os::unix::fs::symlink(repo().join(d), root.join(d)).unwrap();
    }
    for cmd in &cmds {
        if let Some(dir) = cmd.strip_prefix("mkdir -p ") {
            std::fs::create_dir_all(root.join(dir)).unwrap();
            continue;
        }
        // the README quotes arguments that hold a `;` (support polygons): no argument
        // has a space, so removing the quotes is what the shell does
        let args: Vec<&str> = cmd
            .split_whitespace()
            .skip(1)
            .map(|a| a.trim_matches('"'))
            .collect();
        // `bench`'s timing loop is the example's point, not the test's: fewer batches
        let o = Command::new(env!("CARGO_BIN_EXE_moma"))
            .current_dir(&root)
            .env("NBATCH", "3")
            .env("WARMUP", "1")
            .args(&args)
            .output()
            .unwrap();
        assert_eq!(o.status.code(), Some(0), "`{cmd}` failed: {}", stderr(&o));
    }
    for f in [
        "out/dynamics.json",
        "out/m5.json",
        "out/m5/summary.json",
        "out/reach.svg",
        "out/reach.json",
        "out/path.json",
        "out/path.svg",
        "out/trap.svg",
        "out/results.csv",
        "out/sweep.csv",
        "out/stability.json",
        "out/stability-map/margin_map.svg",
        "out/unicycle.json",
        "out/osc.json",
        "simulation-output/default/summary.json",
        "mission-output/summary.json",
    ] {
        assert!(root.join(f).is_file(), "README example did not write {f}");
    }
    // every output lands in a folder git ignores: nothing untracked in the root
    let ignored = std::fs::read_to_string(repo().join(".gitignore")).unwrap();
    for e in entries(&root) {
        if ["crates", "scenarios", "docs"].contains(&e.as_str()) {
            continue;
        }
        assert!(
            ignored.lines().any(|l| l.trim_matches('/') == e.as_str()),
            "README example left {e} in the repository root, not ignored by .gitignore"
        );
    }
}

fn assert_status(o: &Output, code: i32, needle: &str) {
    let e = stderr(o);
    assert_eq!(o.status.code(), Some(code), "stderr: {e}");
    assert!(e.contains(needle), "expected '{needle}' in: {e}");
    assert!(!e.contains("panicked"), "{e}");
}

#[test]
fn exit_status_0_1_and_2() {
    let panda = data("crates/moma/tests/data/pinocchio/urdf/panda.urdf");
    assert_status(&moma(&["inspect", &panda, "--json"]), 0, "");
    assert_status(
        &moma(&["inspect", "/nonexistent.urdf"]),
        1,
        "nonexistent.urdf",
    );
    assert_status(
        &moma(&["inspect", &panda, "--no-such-option"]),
        2,
        "no-such-option",
    );
    assert_status(&moma(&["plan"]), 2, "Usage");
    assert_status(&moma(&["frobnicate"]), 2, "frobnicate");
}

#[test]
fn exit_status_3_ik_not_converged_keeps_its_diagnostics() {
    let dir = scratch("ik");
    let out = dir.join("ik.json");
    let o = moma(&[
        "ik",
        &data("crates/moma/tests/data/manipulability/panda.urdf"),
        "--target",
        "5,0,0.4",
        "--max-iters",
        "20",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_status(&o, 3, "did not converge");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(v["converged"], false);
}

#[test]
fn exit_status_3_potential_field_stuck() {
    let dir = scratch("trap");
    let (json, svg) = (dir.join("trap.json"), dir.join("trap.svg"));
    let o = moma(&[
        "plan",
        &data("scenarios/maps/potential_trap.map"),
        "--start",
        "16,12",
        "--goal",
        "34,12",
        "--algo",
        "potential",
        "--output",
        json.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
    ]);
    assert_status(&o, 3, "local minimum");
    assert!(json.is_file() && svg.is_file());
}

#[test]
fn exit_status_3_scen_mismatch_writes_the_csv() {
    let dir = scratch("scen");
    // one problem whose stated optimum (9.0) is wrong: the true octile length is 1.41421
    let scen = dir.join("wrong.scen");
    std::fs::write(&scen, "version 1\n0\tarena.map\t49\t49\t3\t1\t4\t2\t9.0\n").unwrap();
    let csv = dir.join("r.csv");
    let o = moma(&[
        "scen",
        &data("crates/moma/tests/data/planning/movingai/arena.map"),
        scen.to_str().unwrap(),
        "--output",
        csv.to_str().unwrap(),
    ]);
    assert_status(&o, 3, "do not match the optimal length");
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 2, "{text}");
    assert!(String::from_utf8_lossy(&o.stdout).contains("mismatches (relative tolerance 1e-5): 1"));
}

#[test]
fn exit_status_3_reach_map_target_reachable_from_nowhere() {
    let dir = scratch("reach");
    let (json, svg) = (dir.join("r.json"), dir.join("r.svg"));
    let o = moma(&[
        "reach-map",
        &data("crates/moma/tests/data/manipulability/panda.urdf"),
        "--target",
        "10,10,0.5",
        "--area",
        "0,0,0.2,0.2",
        "--step",
        "0.1",
        "--headings",
        "2",
        "--output",
        json.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
    ]);
    assert_status(&o, 3, "reachable from none");
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    assert_eq!(v["reachable"], 0);
    assert!(svg.is_file());
}

#[test]
fn a_failed_simulation_leaves_no_file_and_no_new_directory() {
    let dir = scratch("simfail");
    let text = std::fs::read_to_string(repo().join("scenarios/m1_unicycle.toml")).unwrap();
    assert!(text.contains("duration = 3.0"));
    // a blow-up limit the run must exceed at once: the simulation itself fails
    let bad = dir.join("blowup.toml");
    std::fs::write(
        &bad,
        format!("{}\n[limits]\nblowup = 1e-9\n", text.trim_end()),
    )
    .unwrap();
    let target = dir.join("new").join("deeper").join("out");
    let o = moma(&[
        "simulate",
        bad.to_str().unwrap(),
        "--output",
        target.to_str().unwrap(),
        "--quiet",
    ]);
    assert_status(&o, 1, "");
    assert_eq!(entries(&dir), ["blowup.toml"], "left behind");
}

#[test]
fn a_rerun_of_simulate_replaces_its_directory_and_spares_foreign_ones() {
    let dir = scratch("simrerun");
    let out = dir.join("out");
    let sc = data("scenarios/m1_unicycle.toml");
    let run = |o: &Path| moma(&["simulate", &sc, "--output", o.to_str().unwrap(), "--quiet"]);
    assert_status(&run(&out), 0, "");
    std::fs::write(out.join("stale.svg"), "old").unwrap();
    assert_status(&run(&out), 0, "");
    assert!(
        !out.join("stale.svg").exists(),
        "the folder was not replaced"
    );
    assert!(out.join("summary.json").is_file());
    assert_eq!(entries(&dir), ["out"], "no temporary directory left");
    let foreign = dir.join("mine");
    std::fs::create_dir(&foreign).unwrap();
    std::fs::write(foreign.join("notes.txt"), "keep").unwrap();
    assert_status(&run(&foreign), 1, "refusing to replace");
    assert_eq!(entries(&foreign), ["notes.txt"]);
}

#[test]
fn a_failed_plan_leaves_neither_of_its_two_outputs() {
    let dir = scratch("planfail");
    let (json, svg) = (dir.join("p.json"), dir.join("missing").join("p.svg"));
    let o = moma(&[
        "plan",
        &data("scenarios/maps/potential_trap.map"),
        "--start",
        "16,12",
        "--goal",
        "34,12",
        "--output",
        json.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
    ]);
    assert_status(&o, 1, "cannot write");
    assert!(entries(&dir).is_empty(), "left behind: {:?}", entries(&dir));
}

#[test]
fn planner_errors_name_world_coordinates_on_ros_maps() {
    let map = data("crates/moma/tests/data/planning/rosmaps/turtlebot3/map.yaml");
    // a radius so large that the start is inside the configuration-space obstacle
    let o = moma(&[
        "plan",
        &map,
        "--start=-2,-0.5",
        "--goal",
        "1.5,0.5",
        "--radius",
        "3",
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(e.contains(" m (cell ("), "{e}");
    assert!(e.contains("(-2.0") || e.contains("(-1.9"), "{e}");
}

#[test]
fn a_closed_standard_output_is_not_a_panic() {
    // `moma inspect … | head -0`: the reader is gone before the table is printed
    let mut child = Command::new(env!("CARGO_BIN_EXE_moma"))
        .args([
            "inspect",
            &data("crates/moma/tests/data/pinocchio/urdf/tiago.urdf"),
            "--root",
            "planar",
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let o = child.wait_with_output().unwrap();
    assert_status(&o, 0, "");
}

/// Every subcommand `moma --help` lists has its usage in `docs/cli.md`, and every flag its
/// own `--help` lists appears on the lines of `docs/cli.md` that show `moma NAME …` (the
/// long form, or the short one where it has one).
#[test]
fn every_subcommand_and_flag_of_help_is_in_the_cli_doc() {
    let doc =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../docs/cli.md")).unwrap();
    let top = String::from_utf8(moma(&["--help"]).stdout).unwrap();
    let commands: Vec<&str> = top
        .lines()
        .skip_while(|l| !l.starts_with("Commands:"))
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .filter_map(|l| l.split_whitespace().next())
        .filter(|c| *c != "help")
        .collect();
    assert!(commands.len() >= 20, "{commands:?}");
    let mut missing = Vec::new();
    for c in commands {
        let usage = format!("moma {c} ");
        let lines: String = doc
            .lines()
            .filter(|l| l.contains(&usage))
            .collect::<Vec<_>>()
            .join("\n");
        if lines.is_empty() {
            missing.push(format!("{c}: no usage line"));
            continue;
        }
        let help = String::from_utf8(moma(&[c, "--help"]).stdout).unwrap();
        for l in help.lines().map(str::trim_start) {
            let (short, long) = match l.split_once(", --") {
                Some((s, rest)) if s.starts_with('-') && s.len() == 2 => (Some(s), rest),
                _ => match l.strip_prefix("--") {
                    Some(rest) => (None, rest),
                    None => continue,
                },
            };
            let name: String = long
                .chars()
                .take_while(|ch| ch.is_ascii_alphanumeric() || *ch == '-')
                .collect();
            if name == "help" || name == "version" {
                continue;
            }
            let flag = format!("--{name}");
            let documented = lines.match_indices(&flag).any(|(i, _)| {
                !lines[i + flag.len()..]
                    .starts_with(|ch: char| ch.is_ascii_alphanumeric() || ch == '-')
            }) || short.is_some_and(|s| lines.contains(&format!("{s} ")));
            if !documented {
                missing.push(format!("{c}: {flag}"));
            }
        }
    }
    assert!(missing.is_empty(), "not in docs/cli.md: {missing:?}");
}

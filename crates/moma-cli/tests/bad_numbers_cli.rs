//! Bad numbers in, clear errors out: one property test per command. Each case puts one
//! extreme but well-formed number (NaN and ±inf in every spelling the parsers meet, huge,
//! tiny, subnormal, negative zero, integers past u32 and u64, random floats) into one
//! field (a command-line option, or a number inside the JSON, TOML, YAML, URDF, map or
//! scenario file the command reads), runs the `moma` binary and checks the rule of
//! `docs/cli.md`:
//!
//! - the exit status is 0, 1 (error), 2 (malformed command line) or 3 (ran, goal not
//!   reached): never a panic, a signal or another code;
//! - on 1 or 2, standard error holds one `error:` message naming the field (the option,
//!   or the file and the field inside it);
//! - on 1 or 2, no output file or directory is left behind (status 3 leaves the
//!   diagnostics docs/cli.md lists);
//! - the child finishes within a wall-clock cap (killed otherwise: a hang guard, not a
//!   speed target) and runs under an address-space limit (`ulimit -v`), so an allocation
//!   blow-up aborts it, which fails the test.
//!
//! Few cases per command keep tier 1 fast; `PROPTEST_CASES=N` runs more.

use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::{Duration, Instant};

/// Wall-clock cap of one run (a hang guard).
const TIME_CAP: Duration = Duration::from_secs(20);
/// Address-space limit of the child (KiB for `ulimit -v`): 4 GiB.
const AS_LIMIT_KIB: u64 = 4 * 1024 * 1024;

/// Extreme numbers as text, in the spellings users type.
const EXTREMES: &[&str] = &[
    "nan",
    "NaN",
    "inf",
    "-inf",
    "+inf",
    "infinity",
    "1e308",
    "-1e308",
    "1.7976931348623157e308",
    "1e309",
    "1e-308",
    "5e-324",
    "-5e-324",
    "0",
    "-0",
    "-0.0",
    "1e-300",
    "1e300",
    "-1",
    "-1e300",
    "4294967296",
    "18446744073709551615",
    "1e19",
];

fn extreme() -> impl Strategy<Value = String> {
    prop_oneof![
        4 => proptest::sample::select(EXTREMES).prop_map(str::to_string),
        1 => any::<f64>().prop_map(|x| format!("{x:e}")),
        1 => any::<u64>().prop_map(|x| x.to_string()),
    ]
}

fn repo(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").join(p)
}

fn panda() -> String {
    repo("crates/moma/tests/data/manipulability/panda.urdf")
        .display()
        .to_string()
}

/// A fresh scratch directory for one run.
fn scratch(cmd: &str) -> PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    let d = std::env::temp_dir().join(format!(
        "moma-extreme-{}-{cmd}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// One prepared run: the arguments, the outputs it may write, and the words of which
/// one must appear in an error message.
struct Case {
    args: Vec<String>,
    outputs: Vec<PathBuf>,
    needles: Vec<String>,
}

/// Builds a case from a field index, the extreme text and the scratch directory.
type Builder = fn(usize, &str, &Path) -> Case;

struct Outcome {
    code: Option<i32>,
    stderr: String,
    elapsed: Duration,
}

fn run_child(args: &[String], dir: &Path) -> Outcome {
    let err = dir.join("stderr.txt");
    let start = Instant::now();
    let mut child = Command::new("sh")
        .arg("-c")
        .arg(format!("ulimit -v {AS_LIMIT_KIB} && exec \"$0\" \"$@\""))
        .arg(env!("CARGO_BIN_EXE_moma"))
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(&err).unwrap())
        .spawn()
        .expect("spawn sh");
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break Some(s);
        }
        if start.elapsed() > TIME_CAP {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    Outcome {
        code: status.and_then(|s| s.code()),
        stderr: std::fs::read_to_string(&err).unwrap_or_default(),
        elapsed: start.elapsed(),
    }
}

/// `[cmd, args…]` with every `--opt VALUE` whose value starts with `-` (a negative
/// number) written `--opt=VALUE`, as a user must.
fn join_dash_values(cmd: &str, args: &[String]) -> Vec<String> {
    let mut out = vec![cmd.to_string()];
    let mut i = 0;
    while i < args.len() {
        let a = &args[i];
        match args.get(i + 1) {
            Some(next)
                if a.starts_with("--")
                    && !a.contains('=')
                    && next.starts_with('-')
                    && !next.starts_with("--") =>
            {
                out.push(format!("{a}={next}"));
                i += 2;
            }
            _ => {
                out.push(a.clone());
                i += 1;
            }
        }
    }
    out
}

/// Runs `cases` cases of `build` (field chosen at random among `fields`) and checks the
/// rule on each.
fn check_command(cmd: &'static str, fields: usize, cases: u32, build: Builder) {
    let cases = std::env::var("PROPTEST_CASES")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(cases);
    let mut runner = TestRunner::new(Config {
        cases,
        failure_persistence: None,
        ..Config::default()
    });
    runner
        .run(&(0..fields, extreme()), |(field, x)| {
            let dir = scratch(cmd);
            let case = build(field, &x, &dir);
            let args = join_dash_values(cmd, &case.args);
            let o = run_child(&args, &dir);
            let what = format!("moma {} (field {field}, value {x})", args.join(" "));
            prop_assert!(
                o.code.is_some(),
                "{what}: killed (time cap or signal) after {:?}; stderr: {}",
                o.elapsed,
                o.stderr
            );
            let code = o.code.unwrap();
            prop_assert!(
                [0, 1, 2, 3].contains(&code),
                "{what}: exit status {code}; stderr: {}",
                o.stderr
            );
            prop_assert!(!o.stderr.contains("panicked"), "{what}: {}", o.stderr);
            if code == 1 || code == 2 {
                prop_assert!(
                    o.stderr.starts_with("error:"),
                    "{what}: status {code} without one error message: {}",
                    o.stderr
                );
                let lower = o.stderr.to_lowercase();
                prop_assert!(
                    case.needles
                        .iter()
                        .any(|n| lower.contains(&n.to_lowercase())),
                    "{what}: the message names none of {:?}: {}",
                    case.needles,
                    o.stderr
                );
            }
            // Status 3 leaves the diagnostics docs/cli.md lists on purpose.
            if code == 1 || code == 2 {
                for p in &case.outputs {
                    prop_assert!(
                        !p.exists(),
                        "{what}: status {code} left {} behind",
                        p.display()
                    );
                }
            }
            std::fs::remove_dir_all(&dir).ok();
            Ok(())
        })
        .unwrap();
}

fn s(x: &str) -> String {
    x.to_string()
}

fn write(dir: &Path, name: &str, text: &str) -> String {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p.display().to_string()
}

/// A two-link URDF with one number replaced by `x` at slot `k` (0 mass, 1 ixx, 2 joint
/// upper limit, 3 joint origin z, 4 axis component, 5 effort); the needles name the
/// element.
fn urdf(k: usize, x: &str) -> (String, Vec<String>) {
    let v = |i: usize, dflt: &str| {
        if i == k {
            x.to_string()
        } else {
            dflt.to_string()
        }
    };
    let text = format!(
        r#"<robot name="two">
  <link name="base"><inertial><mass value="1"/><inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="arm"><inertial><origin xyz="0.1 0 0"/><mass value="{}"/><inertia ixx="{}" iyy="0.01" izz="0.01" ixy="0" ixz="0" iyz="0"/></inertial></link>
  <link name="tip"/>
  <joint name="j1" type="revolute"><parent link="base"/><child link="arm"/><origin xyz="0 0 {}"/><axis xyz="0 {} 1"/><limit lower="-1" upper="{}" effort="{}" velocity="1"/></joint>
  <joint name="tipj" type="fixed"><parent link="arm"/><child link="tip"/><origin xyz="0.2 0 0"/></joint>
</robot>"#,
        v(0, "0.5"),
        v(1, "0.01"),
        v(3, "0.3"),
        v(4, "0"),
        v(2, "1"),
        v(5, "10"),
    );
    let needles = match k {
        0 => ["arm", "mass"],
        1 => ["arm", "inertia"],
        3 => ["j1", "origin"],
        4 => ["j1", "axis"],
        _ => ["j1", "limit"],
    };
    (text, needles.iter().map(|n| n.to_string()).collect())
}

/// `{"states": [ONE_STATE]}` with `q` of `nq` zeros (Panda's fingers at 0.02) and the
/// other fields given; `x` replaces element `at` of field `field`.
fn states_json(fields: &[(&str, usize)], field: usize, at: usize, x: &str) -> String {
    let parts: Vec<String> = fields
        .iter()
        .enumerate()
        .map(|(i, (name, n))| {
            let vals: Vec<String> = (0..*n)
                .map(|j| {
                    if i == field && j == at {
                        x.to_string()
                    } else if *name == "q" && *n >= 9 && j + 2 >= *n {
                        "0.02".to_string()
                    } else {
                        "0.1".to_string()
                    }
                })
                .collect();
            format!("\"{name}\": [{}]", vals.join(", "))
        })
        .collect();
    format!("{{\"states\": [{{{}}}]}}", parts.join(", "))
}

// ---- the commands ------------------------------------------------------------------

#[test]
fn inspect_extremes() {
    check_command("inspect", 6, 16, |k, x, dir| {
        let (text, mut needles) = urdf(k, x);
        let f = write(dir, "robot.urdf", &text);
        needles.push(s("robot.urdf"));
        Case {
            args: vec![f, s("--json")],
            outputs: vec![],
            needles,
        }
    });
}

#[test]
fn dynamics_extremes() {
    check_command("dynamics", 4, 24, |k, x, dir| {
        let out = dir.join("out.json");
        let st =
            |field: usize, at: usize| states_json(&[("q", 9), ("v", 9), ("a", 9)], field, at, x);
        let (states, gravity, needles) = match k {
            0 => (st(0, 3), s("0,0,-9.81"), vec![s("states")]),
            1 => (st(1, 0), s("0,0,-9.81"), vec![s("states")]),
            2 => (st(2, 8), s("0,0,-9.81"), vec![s("states")]),
            _ => (st(9, 0), format!("0,{x},-9.81"), vec![s("--gravity")]),
        };
        let f = write(dir, "states.json", &states);
        Case {
            args: vec![
                panda(),
                s("--root"),
                s("fixed"),
                s("--states"),
                f,
                s("--gravity"),
                gravity,
                s("--output"),
                out.display().to_string(),
            ],
            outputs: vec![out],
            needles,
        }
    });
}

#[test]
fn bench_extremes() {
    // A bench times thousands of calls per algorithm: few cases.
    check_command("bench", 6, 8, |k, x, dir| {
        let (text, mut needles) = urdf(k, x);
        let f = write(dir, "robot.urdf", &text);
        needles.push(s("robot.urdf"));
        let out = dir.join("bench.json");
        Case {
            args: vec![
                f,
                s("--root"),
                s("fixed"),
                s("--output"),
                out.display().to_string(),
            ],
            outputs: vec![out],
            needles,
        }
    });
}

/// The m1 unicycle's first reference case with its outputs removed.
fn m1_case() -> serde_json::Value {
    let text =
        std::fs::read_to_string(repo("crates/moma/tests/data/chapter/m1_unicycle.json")).unwrap();
    let doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut case = doc["cases"][0].clone();
    case.as_object_mut().unwrap().remove("outputs");
    serde_json::json!({"model": doc["model"], "cases": [case]})
}

#[test]
fn eval_extremes() {
    check_command("eval", 4, 20, |k, x, dir| {
        let out = dir.join("out.json");
        let doc = m1_case();
        // Replace one number of the case by the raw text `x` (valid or not as JSON).
        let (text, tol, needles) = {
            let mut d = doc.clone();
            let marker = 123_456.789_f64;
            let field = match k {
                0 => {
                    d["cases"][0]["params"]["m"] = marker.into();
                    "m"
                }
                1 => {
                    d["cases"][0]["state"]["q"][0] = marker.into();
                    "state"
                }
                2 => {
                    d["cases"][0]["trajectory"]["t"] = serde_json::json!([0.0, marker]);
                    "trajectory"
                }
                _ => "--tol",
            };
            let text = serde_json::to_string(&d).unwrap();
            if k < 3 {
                (
                    text.replace("123456.789", x),
                    s("1e-9"),
                    vec![s(field), s("cases.json")],
                )
            } else {
                (text, x.to_string(), vec![s(field)])
            }
        };
        let f = write(dir, "cases.json", &text);
        Case {
            args: vec![f, s("--tol"), tol, s("--output"), out.display().to_string()],
            outputs: vec![out],
            needles,
        }
    });
}

#[test]
fn simulate_extremes() {
    check_command("simulate", 7, 24, |k, x, dir| {
        let out = dir.join("sim-out");
        let (name, val) = [
            ("duration", "1.0"),
            ("dt", "0.001"),
            ("record_interval", "0.01"),
            ("value", "0.8"),
            ("m", "26.44"),
            ("r_w", "0.048"),
            ("q", "0.5"),
        ][k];
        let sub = |n: &str, v: &str| {
            if n == name {
                x.to_string()
            } else {
                v.to_string()
            }
        };
        let text = format!(
            "name = \"extreme\"\nduration = {}\n[robot]\nkind = \"chapter\"\nmodel = \"m1\"\n\
             [robot.params]\nm = {}\nI = 0.358\nd = -0.134\nr_w = {}\nb = 0.176\n\
             [initial]\nq = [{}, -1.6, -2.2]\nv = [-0.9, -0.3]\n\
             [[inputs]]\nkind = \"constant\"\nvalue = {}\n[[inputs]]\nkind = \"constant\"\nvalue = 1.0\n\
             [integrator]\nmethod = \"rk4\"\ndt = {}\n[output]\nrecord_interval = {}\nplots = false\n",
            sub("duration", val),
            sub("m", val),
            sub("r_w", val),
            sub("q", val),
            sub("value", val),
            sub("dt", val),
            sub("record_interval", val),
        );
        let f = write(dir, "scenario.toml", &text);
        let needles = match name {
            "record_interval" => vec![s("record_interval"), s("record interval")],
            // A huge but finite input drives the state past the blow-up bound: the run
            // fails as a simulation, and says so.
            "value" => vec![s("inputs"), s("blow-up bound")],
            // Out of [1e-50, 1e50] the parameter is refused by name; a tiny one inside
            // (a 1e-39 kg robot, a 1e-39 m wheel under a 0.8 N m input) accelerates the
            // platform past the blow-up bound within a step, and the run says so.
            "m" | "r_w" => vec![s("params"), s(name), s("blow-up bound")],
            "q" => vec![s("initial"), s("q")],
            // Every failure names the file and, for a TOML parse error, the line.
            _ => vec![s(name)],
        };
        let mut needles = needles;
        needles.push(s("line "));
        Case {
            args: vec![f, s("--output"), out.display().to_string(), s("--quiet")],
            outputs: vec![out],
            needles,
        }
    });
}

#[test]
fn manipulability_extremes() {
    check_command("manipulability", 4, 20, |k, x, dir| {
        let out = dir.join("m.json");
        let mut args = vec![panda()];
        let states = if k == 0 {
            states_json(&[("q", 9)], 0, 2, x)
        } else {
            states_json(&[("q", 9)], 9, 0, x)
        };
        let needles = match k {
            0 => vec![s("states")],
            1 => {
                args.extend([s("--measure"), format!("directional:1,0,{x}")]);
                vec![s("directional"), s("--measure")]
            }
            2 => {
                args.extend([s("--direction"), format!("1,{x},0,0,0,0")]);
                vec![s("--direction")]
            }
            _ => {
                args.extend([s("--base"), format!("diff-drive:r_w={x},b=0.27,d=0.12")]);
                vec![s("--base"), s("r_w")]
            }
        };
        let states = if k == 3 {
            states_json(&[("q", 12)], 9, 0, x)
        } else {
            states
        };
        let f = write(dir, "states.json", &states);
        args.extend([s("--states"), f, s("--output"), out.display().to_string()]);
        Case {
            args,
            outputs: vec![out],
            needles,
        }
    });
}

#[test]
fn ik_extremes() {
    check_command("ik", 8, 24, |k, x, dir| {
        let out = dir.join("ik.json");
        let mut args = vec![panda()];
        let (target, needle) = match k {
            0 => (format!("0.5,{x},0.5"), "--target"),
            _ => (s("0.5,0.1,0.5"), ""),
        };
        args.extend([s("--target"), target]);
        let needle = match k {
            0 => needle,
            1 => {
                args.extend([s("--tol"), x.to_string()]);
                "--tol"
            }
            2 => {
                args.extend([s("--max-iters"), x.to_string()]);
                "--max-iters"
            }
            3 => {
                // An unreachable target makes every restart run.
                args[2] = s("5,5,5");
                args.extend([s("--restarts"), x.to_string(), s("--max-iters"), s("20")]);
                "--restarts"
            }
            4 => {
                args.extend([
                    s("--whole-body"),
                    s("--base"),
                    s("diff-drive:r_w=0.08,b=0.27,d=0.12"),
                    s("--base-weight"),
                    x.to_string(),
                ]);
                "--base-weight"
            }
            5 => {
                args.extend([
                    s("--null-space"),
                    s("posture"),
                    s("--null-gain"),
                    x.to_string(),
                ]);
                "--null-gain"
            }
            6 => {
                args.extend([s("--q0"), format!("0,0,{x},-1.5,0,1.5,0.7,0.02,0.02")]);
                "--q0"
            }
            _ => {
                args.extend([
                    s("--whole-body"),
                    s("--base"),
                    format!("diff-drive:r_w=0.08,b={x},d=0.12"),
                ]);
                "--base"
            }
        };
        args.extend([s("--output"), out.display().to_string()]);
        Case {
            args,
            outputs: vec![out],
            needles: vec![s(needle)],
        }
    });
}

#[test]
fn reach_map_extremes() {
    check_command("reach-map", 6, 20, |k, x, dir| {
        let out = dir.join("reach.json");
        let svg = dir.join("reach.svg");
        let mut area = s("0,0,1,1");
        let mut step = s("0.5");
        let mut headings = s("2");
        let mut extra = vec![];
        let needle = match k {
            0 => {
                step = x.to_string();
                "--step"
            }
            1 => {
                headings = x.to_string();
                "--headings"
            }
            2 => {
                area = format!("0,0,{x},1");
                "--area"
            }
            3 => {
                extra = vec![s("--mount"), format!("0,0,{x}")];
                "--mount"
            }
            4 => {
                extra = vec![s("--tol"), x.to_string()];
                "--tol"
            }
            _ => {
                extra = vec![s("--restarts"), x.to_string(), s("--max-iters"), s("10")];
                "--restarts"
            }
        };
        let mut args = vec![
            panda(),
            s("--target"),
            s("0.6,0.5,0.5"),
            s("--area"),
            area,
            s("--step"),
            step,
            s("--headings"),
            headings,
            s("--svg"),
            svg.display().to_string(),
            s("--output"),
            out.display().to_string(),
        ];
        args.extend(extra);
        Case {
            args,
            outputs: vec![out, svg],
            needles: vec![s(needle)],
        }
    });
}

/// A 4 × 3 PGM (P2) with free, occupied and unknown cells.
const PGM: &str = "P2\n4 3\n255\n254 254 0 205\n254 254 254 254\n0 254 254 254\n";

#[test]
fn map_info_extremes() {
    check_command("map-info", 4, 16, |k, x, dir| {
        write(dir, "map.pgm", PGM);
        let (res, origin, negate) = match k {
            0 => (x.to_string(), s("0, 0, 0"), s("0")),
            1 => (s("0.05"), format!("{x}, 0, 0"), s("0")),
            2 => (s("0.05"), s("0, 0, 0"), x.to_string()),
            _ => (s("0.05"), s("0, 0, 0"), s("0")),
        };
        let yaml = format!(
            "image: map.pgm\nresolution: {res}\norigin: [{origin}]\nnegate: {negate}\n\
             occupied_thresh: 0.65\nfree_thresh: 0.196\n"
        );
        let y = write(dir, "map.yaml", &yaml);
        let (args, needles) = if k == 3 {
            (
                vec![
                    dir.join("map.pgm").display().to_string(),
                    s("--resolution"),
                    x.to_string(),
                    s("--json"),
                ],
                vec![s("--resolution"), s("resolution")],
            )
        } else {
            let n = ["resolution", "origin", "negate"][k];
            (vec![y, s("--json")], vec![s(n), s("map.yaml")])
        };
        Case {
            args,
            outputs: vec![],
            needles,
        }
    });
}

/// An empty 12 × 10 Moving AI map.
fn movingai_map() -> String {
    let mut m = s("type octile\nheight 10\nwidth 12\nmap\n");
    for _ in 0..10 {
        m.push_str("............\n");
    }
    m
}

#[test]
fn plan_extremes() {
    const OPTS: [&str; 13] = [
        "--start",
        "--goal",
        "--radius",
        "--inflation-radius",
        "--cost-scaling",
        "--turn-cost",
        "--v-max",
        "--omega-max",
        "--a-max",
        "--alpha-max",
        "--dt",
        "--goal-weight",
        "--influence",
    ];
    check_command("plan", OPTS.len(), 32, |k, x, dir| {
        let map = write(dir, "room.map", &movingai_map());
        let out = dir.join("path.json");
        let svg = dir.join("path.svg");
        let opt = OPTS[k];
        let mut args = vec![map];
        let start = if k == 0 { format!("1,{x}") } else { s("1,1") };
        let goal = if k == 1 { format!("{x},8") } else { s("10,8") };
        args.push(format!("--start={start}"));
        args.push(format!("--goal={goal}"));
        if k >= 2 {
            args.push(format!("{opt}={x}"));
        }
        if k == 3 || k == 4 {
            args.push(s("--cost-aware"));
        }
        if k == 11 || k == 12 {
            args.push(s("--algo=potential-geodesic"));
        }
        args.extend([
            format!("--output={}", out.display()),
            format!("--svg={}", svg.display()),
        ]);
        // The library's range checks name the parameter (`v_max` for `--v-max`); a
        // finite limit too small for the path fails the sample-count bound, whose message
        // names the limits and dt.
        let snake = opt.trim_start_matches("--").replace('-', "_");
        let mut needles = vec![
            s(opt),
            snake,
            opt.trim_start_matches("--").replace('-', " "),
        ];
        if (6..=10).contains(&k) {
            needles.push(s("velocity and acceleration limits"));
        }
        Case {
            args,
            outputs: vec![out, svg],
            needles,
        }
    });
}

#[test]
fn scen_extremes() {
    check_command("scen", 5, 20, |k, x, dir| {
        let map = write(dir, "room.map", &movingai_map());
        let out = dir.join("scen.csv");
        let num = |i: usize, d: &str| {
            if i + 2 == k {
                x.to_string()
            } else {
                d.to_string()
            }
        };
        let scen = format!(
            "version 1\n0\troom.map\t12\t10\t1\t1\t10\t8\t{}\n0\troom.map\t12\t10\t{}\t2\t9\t{}\t8.0\n",
            num(0, "10.82842712"),
            num(1, "2"),
            num(2, "7"),
        );
        let sc = write(dir, "room.map.scen", &scen);
        let mut args = vec![map, sc, s("--output"), out.display().to_string()];
        let needles = match k {
            0 => {
                args.extend([s("--every"), x.to_string()]);
                vec![s("--every")]
            }
            1 => {
                args.extend([s("--tolerance"), x.to_string()]);
                vec![s("--tolerance")]
            }
            _ => vec![s("room.map.scen")],
        };
        Case {
            args,
            outputs: vec![out],
            needles,
        }
    });
}

const SUPPORT: &str = "0.35,-0.25;-0.3,0.25;0.35,0.25;-0.3,-0.25";

#[test]
fn stability_extremes() {
    check_command("stability", 6, 24, |k, x, dir| {
        let out = dir.join("st.json");
        let mut support = s(SUPPORT);
        let mut extra = vec![];
        let q = states_json(&[("q", 12)], 0, 4, x);
        let plain = states_json(&[("q", 12)], 9, 0, x);
        let (states, needles) = match k {
            0 => (q, vec![s("states")]),
            1 => {
                support = format!("0.35,{x};-0.3,0.25;0.35,0.25;-0.3,-0.25");
                (plain, vec![s("--support")])
            }
            2 => {
                extra = vec![s("--gravity"), format!("0,0,{x}")];
                (plain, vec![s("--gravity")])
            }
            3 => {
                let st = states_json(&[("q", 12)], 9, 0, x).replace(
                    "]}]}",
                    &format!(
                        "], \"external\": [{{\"point\": [1, 0, 0.5], \"force\": [0, {x}, 0]}}]}}]}}"
                    ),
                );
                (st, vec![s("external"), s("states")])
            }
            4 => (
                states_json(&[("q", 12), ("v", 12)], 1, 0, x),
                vec![s("states")],
            ),
            _ => {
                extra = vec![s("--mhs-bodies"), s("all")];
                (
                    states_json(&[("q", 12), ("a", 12)], 1, 3, x),
                    vec![s("states")],
                )
            }
        };
        let f = write(dir, "states.json", &states);
        let mut args = vec![
            panda(),
            s("--support"),
            support,
            s("--states"),
            f,
            s("--output"),
            out.display().to_string(),
        ];
        args.extend(extra);
        Case {
            args,
            outputs: vec![out],
            needles,
        }
    });
}

#[test]
fn stability_map_extremes() {
    check_command("stability-map", 6, 20, |k, x, dir| {
        let out = dir.join("smap");
        let mut args = vec![
            panda(),
            s("--support"),
            s(SUPPORT),
            s("--joints"),
            s("panda_joint2,panda_joint4"),
            s("--output-dir"),
            out.display().to_string(),
        ];
        let (opt, val) = match k {
            0 => ("--resolution", x.to_string()),
            1 => ("--directions", x.to_string()),
            2 => ("--ranges", format!("-1,{x};-2,-0.5")),
            3 => ("--platform-acceleration", format!("{x},0")),
            4 => ("--gravity", format!("0,{x},-9.81")),
            _ => ("--q", format!("0,0,0,0,{x},0,-2,0,1.5,0.7,0.02,0.02")),
        };
        args.extend([s(opt), val]);
        if k != 0 {
            args.extend([s("--resolution"), s("8"), s("--directions"), s("12")]);
        }
        Case {
            args,
            outputs: vec![out],
            needles: vec![s(opt)],
        }
    });
}

#[test]
fn osc_extremes() {
    check_command("osc", 4, 20, |k, x, dir| {
        let out = dir.join("osc.json");
        let fields = [
            ("q", 9),
            ("v", 9),
            ("task_acceleration", 6),
            ("null_torque", 9),
        ];
        let f = write(dir, "states.json", &states_json(&fields, k, 1, x));
        Case {
            args: vec![
                panda(),
                s("--root"),
                s("fixed"),
                s("--frame"),
                s("panda_hand"),
                s("--states"),
                f,
                s("--output"),
                out.display().to_string(),
            ],
            outputs: vec![out],
            needles: vec![s("states")],
        }
    });
}

#[test]
fn space_extremes() {
    check_command("space", 4, 20, |k, x, dir| {
        let out = dir.join("space.json");
        let q: Vec<String> = (0..16)
            .map(|i| match i {
                6 => s("1"),
                2 if k == 0 => x.to_string(),
                14 | 15 => s("0.02"),
                _ => s("0.1"),
            })
            .collect();
        let qd: Vec<String> = (0..9)
            .map(|i| {
                if k == 1 && i == 4 {
                    x.to_string()
                } else {
                    s("0.1")
                }
            })
            .collect();
        let lin = if k == 2 {
            format!("{x}, 0, 0")
        } else {
            s("0, 0, 0")
        };
        let ang = if k == 3 {
            format!("0, 0, {x}")
        } else {
            s("0, 0, 0")
        };
        let text = format!(
            "{{\"states\": [{{\"q\": [{}], \"qdot_joints\": [{}], \"momentum\": {{\"linear\": [{lin}], \"angular_about_com\": [{ang}]}}}}]}}",
            q.join(", "),
            qd.join(", ")
        );
        let f = write(dir, "states.json", &text);
        Case {
            args: vec![
                panda(),
                s("--frame"),
                s("panda_hand"),
                s("--states"),
                f,
                s("--output"),
                out.display().to_string(),
            ],
            outputs: vec![out],
            needles: vec![s("states")],
        }
    });
}

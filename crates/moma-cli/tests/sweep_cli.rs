//! End-to-end tests of `moma sweep`: a sweep run whole, on one thread, and as shards
//! merged gives the same result columns; the CSV has the documented columns; bad input is
//! one error naming the file and field (exit status 1, no output file); the merge checks
//! its inputs.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn moma(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_moma"))
        .args(args)
        .output()
        .expect("run moma")
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("moma_sweep_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The CSV without its `*_time_s` columns.
fn results(p: &Path) -> String {
    let text = std::fs::read_to_string(p).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let keep: Vec<usize> = (0..header.len())
        .filter(|&k| !header[k].ends_with("_time_s"))
        .collect();
    let mut out = String::new();
    for line in std::iter::once(header.join(",").as_str()).chain(lines) {
        let f: Vec<&str> = line.split(',').collect();
        out.push_str(&keep.iter().map(|&k| f[k]).collect::<Vec<_>>().join(","));
        out.push('\n');
    }
    out
}

fn small_sweep(name: &str) -> PathBuf {
    // the shipped random TIAGo sweep, cut to 200 points; one file per test, since the
    // tests run in parallel in one process (one shared file raced: a test read it while
    // another truncated it)
    let text = std::fs::read_to_string(root().join("scenarios/sweeps/tiago_stability_random.toml"))
        .unwrap()
        .replace("count = 10000", "count = 200")
        .replace(
            "../../crates/moma/tests/data/pinocchio/urdf/tiago.urdf",
            s(&root().join("crates/moma/tests/data/pinocchio/urdf/tiago.urdf")),
        );
    let p = tmp(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn shards_merged_equal_the_whole_run_on_any_thread_count() {
    let sw = small_sweep("small_shards.toml");
    let whole = tmp("whole.csv");
    let o = moma(&["sweep", s(&sw), "-o", s(&whole)]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(stdout.contains("200 of 200 points"), "{stdout}");
    let one = tmp("one.csv");
    assert!(
        moma(&["sweep", s(&sw), "-o", s(&one), "--threads", "1", "--quiet"])
            .status
            .success()
    );
    assert_eq!(results(&whole), results(&one));
    let mut shards = Vec::new();
    for k in 1..=3 {
        let p = tmp(&format!("shard{k}.csv"));
        let spec = format!("{k}/3");
        let o = moma(&["sweep", s(&sw), "-o", s(&p), "--shard", &spec, "--quiet"]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        assert!(o.stdout.is_empty(), "--quiet prints nothing");
        shards.push(p);
    }
    let merged = tmp("merged.csv");
    let mut args = vec!["sweep", "merge", s(&merged)];
    args.extend(shards.iter().map(|p| s(p)));
    let o = moma(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(results(&merged), results(&whole));

    let text = std::fs::read_to_string(&whole).unwrap();
    let header = text.lines().next().unwrap();
    assert_eq!(
        header,
        "index,posture,q.arm_1_joint,accel,yaw_rate,speed,yaw_accel,payload,stable,zmp_margin,\
         zmp_critical_edge,zmp_x,zmp_y,fa_alpha,fa_min,fa_beta,mhs_min,mass,com_x,com_y,com_z,eval_time_s"
    );
    assert_eq!(text.lines().count(), 201);

    // a missing shard and an overlap are errors naming the file
    let o = moma(&[
        "sweep",
        "merge",
        s(&tmp("m2.csv")),
        s(&shards[0]),
        s(&shards[2]),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("missing"));
    let o = moma(&[
        "sweep",
        "merge",
        s(&tmp("m3.csv")),
        s(&shards[0]),
        s(&shards[1]),
        s(&shards[1]),
        s(&shards[2]),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("shard2.csv") && e.contains("is also in"), "{e}");
    assert!(!tmp("m2.csv").exists() && !tmp("m3.csv").exists());
}

#[test]
fn bad_input_is_one_error_and_no_output() {
    let sw = small_sweep("small_bad.toml");
    let bad = tmp("bad.toml");
    std::fs::write(
        &bad,
        std::fs::read_to_string(&sw)
            .unwrap()
            .replace("payload = {", "payloud = {"),
    )
    .unwrap();
    let out = tmp("never.csv");
    let cases: Vec<(Vec<&str>, i32, &str)> = vec![
        (
            vec!["sweep", s(&bad), "-o", s(&out)],
            1,
            "parameters.payloud",
        ),
        (
            vec!["sweep", s(&sw), "-o", s(&out), "--shard", "4/3"],
            1,
            "--shard",
        ),
        (
            vec!["sweep", s(&sw), "-o", s(&out), "--shard", "x"],
            1,
            "--shard",
        ),
        (vec!["sweep", s(&sw)], 1, "--output"),
        (vec!["sweep", "nope.toml", "-o", s(&out)], 1, "nope.toml"),
        (vec!["sweep", "merge", s(&out)], 2, "SHARDS"),
    ];
    for (args, code, needle) in cases {
        let o = moma(&args);
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "{args:?}: {e}");
        assert!(e.contains(needle), "{args:?}: {e}");
        assert!(!out.exists(), "{args:?} left an output");
    }
    assert!(e_has_file(&bad));
}

fn e_has_file(bad: &Path) -> bool {
    let o = moma(&["sweep", s(bad), "-o", s(&tmp("never2.csv"))]);
    String::from_utf8_lossy(&o.stderr).contains(s(bad))
}

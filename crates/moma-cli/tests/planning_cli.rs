//! End-to-end tests of `moma map-info`, `moma plan` and `moma scen`.

use std::path::PathBuf;
use std::process::{Command, Output};

fn moma(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_moma"))
        .args(args)
        .output()
        .expect("run moma")
}

fn data(p: &str) -> String {
    format!(
        "{}/../moma/tests/data/planning/{p}",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn trap() -> String {
    format!(
        "{}/../../scenarios/maps/potential_trap.map",
        env!("CARGO_MANIFEST_DIR")
    )
}

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("moma-planning-cli-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

fn json(o: &Output) -> serde_json::Value {
    assert!(
        o.status.success(),
        "stderr: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn map_info_counts() {
    let v = json(&moma(&[
        "map-info",
        &data("rosmaps/nav2/tb3_sandbox.yaml"),
        "--json",
    ]));
    assert_eq!(
        (v["width"].as_u64(), v["height"].as_u64()),
        (Some(384), Some(384))
    );
    assert_eq!(
        (
            v["occupied"].as_u64(),
            v["free"].as_u64(),
            v["unknown"].as_u64()
        ),
        (Some(870), Some(7_903), Some(138_683))
    );
    assert_eq!(v["resolution"].as_f64(), Some(0.05));
    assert_eq!(v["origin"][0].as_f64(), Some(-10.0));
    // A bare image takes the legacy defaults; --resolution overrides 0.05.
    let v = json(&moma(&[
        "map-info",
        &data("rosmaps/willow_garage/willow-full-0.05.png"),
        "--json",
        "--resolution",
        "0.1",
    ]));
    assert_eq!(
        (
            v["occupied"].as_u64(),
            v["free"].as_u64(),
            v["unknown"].as_u64()
        ),
        (Some(13_459), Some(549_308), Some(538_158))
    );
    assert_eq!(v["resolution"].as_f64(), Some(0.1));
    let v = json(&moma(&[
        "map-info",
        &data("movingai/Berlin_0_256.map"),
        "--json",
    ]));
    assert_eq!(v["free"].as_u64(), Some(48_147));
    let text = moma(&["map-info", &data("rosmaps/nav2/depot.yaml")]);
    assert!(String::from_utf8_lossy(&text.stdout).contains("free:       179481"));
}

#[test]
fn map_info_bad_input() {
    let bad = tmp("broken.yaml");
    std::fs::write(
        &bad,
        "image: nowhere.pgm\nresolution: 0.05\norigin: [0, 0]\n",
    )
    .unwrap();
    let o = moma(&["map-info", bad.to_str().unwrap()]);
    assert!(!o.status.success());
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(e.contains("broken.yaml") && e.contains("origin"), "{e}");
    let o = moma(&["map-info", "/nonexistent/map.pgm"]);
    assert!(
        !o.status.success() && String::from_utf8_lossy(&o.stderr).contains("/nonexistent/map.pgm")
    );
}

#[test]
fn plan_on_a_ros_map_writes_path_and_svg() {
    let (out, svg) = (tmp("p.json"), tmp("p.svg"));
    let o = moma(&[
        "plan",
        &data("rosmaps/turtlebot3/map.yaml"),
        "--start=-2.0,-0.5",
        "--goal",
        "1.5,0.5",
        "--radius",
        "0.1",
        "--output",
        out.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(v["status"], "found");
    assert_eq!(v["frame"], "world");
    let wp = v["waypoints"].as_array().unwrap();
    assert!(wp.len() >= 2);
    // First waypoint = centre of the start cell (within half a cell).
    assert!((wp[0][0].as_f64().unwrap() + 2.0).abs() <= 0.025 + 1e-9);
    let traj = v["trajectory"].as_array().unwrap();
    let last = traj.last().unwrap();
    assert!((last["x"].as_f64().unwrap() - 1.5).abs() <= 0.025 + 1e-9);
    assert!(last["t"].as_f64().unwrap() > 0.0);
    for p in traj {
        assert!(p["v"].as_f64().unwrap() <= 0.5 + 1e-12);
    }
    assert!(v["cost"].as_f64().unwrap() >= v["length"].as_f64().unwrap() - 1e-9);
    let s = std::fs::read_to_string(&svg).unwrap();
    assert!(
        s.starts_with("<svg") && s.contains("data:image/png;base64,") && s.contains("<polyline")
    );
}

#[test]
fn plan_algorithms_agree_and_potential_trap_is_reported() {
    let map = data("movingai/den520d.map");
    let cost = |algo: &str| {
        let out = tmp(&format!("{algo}.json"));
        let o = moma(&[
            "plan",
            &map,
            "--start",
            "100,163",
            "--goal",
            "200,200",
            "--algo",
            algo,
            "--output",
            out.to_str().unwrap(),
        ]);
        assert!(
            o.status.success(),
            "{algo}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let v: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        v["cost"].as_f64().unwrap()
    };
    let a = cost("astar");
    assert!((a - cost("dstar-lite")).abs() < 1e-9);
    assert!(cost("potential-geodesic") >= a - 1e-9);
    // The literal field is stuck in the shipped trap map: exit status 3, report, status.
    let out = tmp("trap.json");
    let o = moma(&[
        "plan",
        &trap(),
        "--start",
        "16,12",
        "--goal",
        "34,12",
        "--algo",
        "potential",
        "--output",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(3));
    assert!(String::from_utf8_lossy(&o.stderr).contains("local minimum"));
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(v["status"], "local_minimum");
    let o = moma(&[
        "plan",
        &trap(),
        "--start",
        "16,12",
        "--goal",
        "34,12",
        "--algo",
        "potential-geodesic",
    ]);
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stdout).contains("reached the goal"));
    // Footprint planning on the trap map: a 3.5 x 1.6 cell rectangle. (A 4 x 2 one finds
    // no path since obstacle cells count as squares: its 45° turns next to the 4-row
    // corridors sweep into the walls' squares.)
    let o = moma(&[
        "plan",
        &trap(),
        "--start",
        "16,12",
        "--goal",
        "34,12",
        "--footprint",
        "-1,-0.8;2.5,-0.8;2.5,0.8;-1,0.8",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

#[test]
fn plan_bad_input_gives_errors_and_no_output() {
    let out = tmp("never.json");
    let map = data("movingai/maze512-1-0.map");
    let run = |extra: &[&str]| {
        let mut a = vec!["plan", map.as_str(), "--output", out.to_str().unwrap()];
        a.extend_from_slice(extra);
        let o = moma(&a);
        assert!(!o.status.success(), "{extra:?} should fail");
        assert!(!out.exists(), "no partial output");
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    // Start in a wall, goal outside, non-numeric.
    assert!(run(&["--start", "0,0", "--goal", "1,1"]).contains("obstacle"));
    assert!(run(&["--start", "1,1", "--goal", "900,1"]).contains("goal"));
    assert!(run(&["--start", "a,1", "--goal", "1,1"]).contains("--start"));
    // Corridors are one cell wide: any robot radius >= 1 closes them all.
    let e = run(&["--start", "1,1", "--goal", "3,1", "--radius", "1"]);
    assert!(e.contains("radius"), "{e}");
    let e = run(&[
        "--start",
        "1,1",
        "--goal",
        "3,1",
        "--footprint",
        "-2,-2;2,-2;2,2;-2,2",
    ]);
    assert!(e.contains("collides") || e.contains("no path"), "{e}");
    // Unreachable goal on a map split by a wall.
    let split = tmp("split.map");
    std::fs::write(
        &split,
        "type octile\nheight 3\nwidth 5\nmap\n..@..\n..@..\n..@..\n",
    )
    .unwrap();
    let o = moma(&[
        "plan",
        split.to_str().unwrap(),
        "--start",
        "0,0",
        "--goal",
        "4,2",
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("no path"));
}

#[test]
fn scen_csv_and_summary() {
    let out = tmp("arena.csv");
    let o = moma(&[
        "scen",
        &data("movingai/arena.map"),
        &data("movingai/arena.map.scen"),
        "--every",
        "4",
        "--output",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        stdout.contains("mismatches (relative tolerance 1e-5): 0") && stdout.contains("median"),
        "{stdout}"
    );
    let csv = std::fs::read_to_string(&out).unwrap();
    let mut lines = csv.lines();
    assert_eq!(
        lines.next(),
        Some("index,start [cell],goal [cell],cost [cell],optimal [cell],expanded,time [us]")
    );
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert_eq!(rows.len(), 40);
    assert_eq!(rows[1][0], "4");
    assert_eq!(rows[0][1].split(' ').count(), 2);
    // 3-D: two short problems of the A1 set.
    let s3 = tmp("short.3dscen");
    std::fs::write(&s3, "version 1\nA1.3dmap\n286 160 147 288 169 141 12.70674230 1.000\n737 294 120 749 249 110 53.24531152 1.000\n").unwrap();
    let out3 = tmp("a1.csv");
    let o = moma(&[
        "scen",
        &data("movingai/3d/A1.3dmap"),
        s3.to_str().unwrap(),
        "--output",
        out3.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let csv = std::fs::read_to_string(&out3).unwrap();
    assert_eq!(
        csv.lines().nth(1).unwrap().split(',').nth(1),
        Some("286 160 147")
    );
    // Bad scenario: a clear error naming the file and line.
    let bad = tmp("bad.scen");
    std::fs::write(&bad, "version 1\n0\tarena.map\t1\t1\t2\t2\t1.41421\n").unwrap();
    let o = moma(&["scen", &data("movingai/arena.map"), bad.to_str().unwrap()]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("line 2"));
}

/// A 30 x 12 Moving AI map with one obstacle cell at (15, 7), two rows above the
/// straight path along row 5 from (3, 5) to (27, 5).
fn one_obstacle_map() -> PathBuf {
    let p = tmp("one_obstacle.map");
    let mut text = String::from("type octile\nheight 12\nwidth 30\nmap\n");
    for row in 0..12 {
        let line: String = (0..30)
            .map(|x| if (x, row) == (15, 7) { '@' } else { '.' })
            .collect();
        text.push_str(&line);
        text.push('\n');
    }
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn plan_checks_a_disk_plans_path_with_a_polygon() {
    let map = one_obstacle_map();
    let out = tmp("checked.json");
    let plan = |extra: &[&str]| {
        std::fs::remove_file(&out).ok();
        let mut a = vec![
            "plan",
            map.to_str().unwrap(),
            "--start",
            "3,5",
            "--goal",
            "27,5",
            "--radius",
            "0.5",
            "--output",
            out.to_str().unwrap(),
        ];
        a.extend_from_slice(extra);
        moma(&a)
    };
    let written = || -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap()
    };
    // the disk passes along row 5; a chassis 5 cells along the path and 2 across passes
    // half a cell below the obstacle's square
    let along = "-2.5,-1;2.5,-1;2.5,1;-2.5,1";
    let o = plan(&["--check-footprint", along]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stdout).contains("the polygon clears the obstacles"));
    let v = written();
    assert_eq!(v["status"], "found");
    assert!(v["cells"].as_array().unwrap().iter().all(|c| c[1] == 5));
    assert_eq!(v["robot"]["kind"], "disk");
    assert_eq!(v["robot"]["radius"], 0.5);
    let check = &v["robot"]["check"];
    assert_eq!(check["kind"], "polygon");
    assert_eq!(check["vertices"].as_array().unwrap().len(), 4);
    assert_eq!(check["padding"], 0.0);
    assert_eq!(check["colliding"], serde_json::json!([]));
    // the same search; turned across the path (2 along, 5 across) it reaches the
    // obstacle's square from the cells next to it: written, status colliding, exit 3
    let o = plan(&["--check-footprint", "-1,-2.5;1,-2.5;1,2.5;-1,2.5"]);
    assert_eq!(
        o.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let e = String::from_utf8_lossy(&o.stderr);
    assert!(
        e.contains("--check-footprint") && e.contains("cell (14, 5)"),
        "{e}"
    );
    let v = written();
    assert_eq!(v["status"], "colliding");
    assert_eq!(
        v["robot"]["check"]["colliding"],
        serde_json::json!([[14, 5], [15, 5], [16, 5]])
    );
    // lengthwise again, asked to keep 0.6 cells from the obstacles
    let o = plan(&["--check-footprint", along, "--check-padding", "0.6"]);
    assert_eq!(o.status.code(), Some(3));
    assert_eq!(written()["robot"]["check"]["padding"], 0.6);
    // without the check the robot entry is the disk alone
    let o = plan(&[]);
    assert!(o.status.success());
    assert!(written()["robot"].get("check").is_none());
}

#[test]
fn plan_check_footprint_refuses_a_start_or_goal_the_polygon_collides_at() {
    // (15, 5) lies two cells below the obstacle: the disk fits, a chassis 5 cells wide
    // across its heading does not at heading 0 (the path's along row 5)
    let map = one_obstacle_map();
    let out = tmp("end-checked.json");
    let across = "-1,-2.5;1,-2.5;1,2.5;-1,2.5";
    for (start, goal, field) in [
        ("15,5", "27,5", "start: "),
        ("15,5,0", "27,5", "start: "),
        ("3,5", "15,5", "goal: "),
    ] {
        let o = moma(&[
            "plan",
            map.to_str().unwrap(),
            "--start",
            start,
            "--goal",
            goal,
            "--radius",
            "0.5",
            "--check-footprint",
            across,
            "--output",
            out.to_str().unwrap(),
        ]);
        let e = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{start} {goal}: {e}");
        assert!(
            e.contains(&format!(
                "{field}the footprint polygon with its origin at (15.000, 5.000) cells"
            )),
            "{e}"
        );
        assert!(!out.exists(), "no output");
    }
}

#[test]
fn plan_check_footprint_errors_name_the_option() {
    let map = one_obstacle_map();
    let out = tmp("never-checked.json");
    let run = |extra: &[&str]| {
        let mut a = vec![
            "plan",
            map.to_str().unwrap(),
            "--start",
            "3,5",
            "--goal",
            "27,5",
            "--output",
            out.to_str().unwrap(),
        ];
        a.extend_from_slice(extra);
        let o = moma(&a);
        assert_eq!(o.status.code(), Some(1), "{extra:?} should fail");
        assert!(!out.exists(), "no output");
        String::from_utf8_lossy(&o.stderr).into_owned()
    };
    let square = "-1,-1;1,-1;1,1;-1,1";
    let e = run(&["--footprint", square, "--check-footprint", square]);
    assert!(
        e.contains("--check-footprint") && e.contains("--footprint"),
        "{e}"
    );
    let e = run(&["--radius", "0.5", "--check-padding", "0.1"]);
    assert!(
        e.contains("--check-padding") && e.contains("--check-footprint"),
        "{e}"
    );
    let e = run(&["--check-footprint", square, "--check-padding=-0.1"]);
    assert!(e.contains("--check-padding"), "{e}");
    let e = run(&["--check-footprint", square, "--check-padding", "nan"]);
    assert!(e.contains("--check-padding"), "{e}");
    let concave = "-1,-1;1,-1;0.2,0;1,1;-1,1";
    let e = run(&["--radius", "0.5", "--check-footprint", concave]);
    assert!(
        e.contains("--check-footprint") && e.contains("convex"),
        "{e}"
    );
    let e = run(&["--check-footprint", "0,0;1,0"]);
    assert!(e.contains("--check-footprint"), "{e}");
}

//! End-to-end tests of `moma collision`: Fetch in Pinocchio-layout states against the
//! coal reference (self pairs and a MotionBenchMaker scene), Panda with its SRDF and a
//! table scene against its coal reference, the SVG figure, and the
//! errors (message naming file and element, exit status 1, no output file).

use serde_json::Value;
use std::path::PathBuf;
use std::process::{Command, Output};

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../moma/tests/data");

fn moma(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_moma"))
        .args(args)
        .output()
        .expect("run moma")
}

fn tmp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("moma_collision_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Fetch's URDF, SRDF and package folder (for its `package://` meshes) in the test data.
fn fetch_files() -> (String, String, String) {
    (
        format!("{DATA}/robots/fetch/fetch_description/robots/fetch.urdf"),
        format!("{DATA}/robots/fetch/fetch.srdf"),
        format!("{DATA}/robots/fetch"),
    )
}

/// Writes a states file of the reference states' `q` (Pinocchio layout) as `name`.
fn write_reference_states(name: &str, states: &[&Value]) -> PathBuf {
    let file = tmp(name);
    let qs: Vec<Value> = states
        .iter()
        .map(|s| serde_json::json!({"q": s["q"]}))
        .collect();
    std::fs::write(&file, serde_json::json!({ "states": qs }).to_string()).unwrap();
    file
}

fn fetch_args<'a>(urdf: &'a str, srdf: &'a str, pkg: &'a str) -> Vec<&'a str> {
    vec![
        "collision",
        urdf,
        "--root",
        "fixed",
        "--srdf",
        srdf,
        "--package-dir",
        pkg,
    ]
}

#[test]
fn fetch_against_coal_with_a_scene_and_a_figure() {
    let reference: Value = serde_json::from_str(
        &std::fs::read_to_string(format!("{DATA}/collision/fetch_scene_public.json")).unwrap(),
    )
    .unwrap();
    let states: Vec<&Value> = reference["states"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["scene"] == "table_pick")
        .collect();
    let states_file = write_reference_states("states.json", &states);
    let (urdf, srdf, pkg) = fetch_files();
    let scene = format!("{DATA}/scenes/motion_bench_maker/configs/scenes/table/scene_table.yaml");
    let (out, svg) = (tmp("out.json"), tmp("fig.svg"));
    let mut args = fetch_args(&urdf, &srdf, &pkg);
    args.extend([
        "--scene",
        &scene,
        "--states",
        states_file.to_str().unwrap(),
        "--layout",
        "pinocchio",
        "--output",
        out.to_str().unwrap(),
        "--svg",
        svg.to_str().unwrap(),
    ]);
    let o = moma(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(got["pairs_enabled"].as_array().unwrap().len(), 76);
    let ref_pairs = reference["scenes"]["table_pick"]["pairs"]
        .as_array()
        .unwrap();
    for (s, want) in got["states"].as_array().unwrap().iter().zip(&states) {
        let pairs = s["pairs"].as_array().unwrap();
        assert_eq!(pairs.len(), 76 + ref_pairs.len());
        for (k, p) in ref_pairs.iter().enumerate() {
            let mine = pairs
                .iter()
                .find(|x| x["a"] == p[0] && x["b"] == p[1])
                .unwrap_or_else(|| panic!("pair {p} missing"));
            let d = mine["distance"].as_f64().unwrap();
            let w = want["distance_convex"][k].as_f64().unwrap();
            assert!((d - w).abs() <= 1e-6, "{p}: {d} vs coal {w}");
        }
        let min = s["min_distance"].as_f64().unwrap();
        let all_min = pairs
            .iter()
            .map(|p| p["distance"].as_f64().unwrap())
            .fold(f64::INFINITY, f64::min);
        assert_eq!(min, all_min);
        assert_eq!(s["in_collision"].as_bool().unwrap(), min < 0.0);
    }
    let fig = std::fs::read_to_string(&svg).unwrap();
    assert!(fig.starts_with("<svg") && fig.matches("<polygon").count() >= 2 * (21 + 12));
}

/// Panda's URDF, SRDF and package folder in the test data.
fn panda_files() -> (String, String, String) {
    let pkg = format!("{DATA}/robots/panda");
    (
        format!("{DATA}/pinocchio/urdf/panda.urdf"),
        format!("{pkg}/example-robot-data/robots/panda_description/srdf/panda.srdf"),
        pkg,
    )
}

/// A reference's states of kind `near_contact`, the first `n` on each side of contact by
/// the reference's verdict `verdict_key`.
fn near_contact_states(reference: &Value, kind: &str, verdict_key: &str, n: usize) -> Vec<Value> {
    let near: Vec<&Value> = reference["states"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|s| s["kind"] == kind)
        .collect();
    let side = |hit: bool| {
        near.iter()
            .filter(move |s| s[verdict_key].as_bool() == Some(hit))
            .take(n)
            .map(|s| (*s).clone())
    };
    let states: Vec<Value> = side(true).chain(side(false)).collect();
    assert_eq!(states.len(), 2 * n, "near-contact states on both sides");
    states
}

/// Checks `moma collision`'s pairs of one state against a reference state: every reference
/// pair (either order) to 1e-6 m, its witness points to 1e-5 m where unique.
fn assert_pairs_match(got: &Value, want: &Value, ref_pairs: &[Value]) {
    let pairs = got["pairs"].as_array().unwrap();
    for (k, p) in ref_pairs.iter().enumerate() {
        let Some(mine) = pairs
            .iter()
            .find(|x| (x["a"] == p[0] && x["b"] == p[1]) || (x["a"] == p[1] && x["b"] == p[0]))
        else {
            continue;
        };
        let d = mine["distance"].as_f64().unwrap();
        let w = want["distance_convex"][k].as_f64().unwrap();
        assert!(
            (d - w).abs() <= 1e-6,
            "{} {p}: {d} vs coal {w}",
            want["label"]
        );
        if want["witness_unique"][k].as_bool() == Some(true) {
            let (wa, wb) = if mine["a"] == p[0] {
                ("witness_a", "witness_b")
            } else {
                ("witness_b", "witness_a")
            };
            for (m, t) in [
                (&mine[wa], &want["witness_a"][k]),
                (&mine[wb], &want["witness_b"][k]),
            ] {
                for i in 0..3 {
                    let e = (m[i].as_f64().unwrap() - t[i].as_f64().unwrap()).abs();
                    assert!(e <= 1e-5, "{} {p}: witness {m} vs coal {t}", want["label"]);
                }
            }
        }
    }
}

#[test]
fn panda_with_srdf_and_scene_reproduces_coal() {
    let (urdf, srdf, pkg) = panda_files();
    let read = |f: &str| -> Value {
        serde_json::from_str(&std::fs::read_to_string(format!("{DATA}/collision/{f}")).unwrap())
            .unwrap()
    };
    let run = |states: &[Value], scene: Option<&str>, name: &str| -> Value {
        let refs: Vec<&Value> = states.iter().collect();
        let states_file = write_reference_states(&format!("{name}_states.json"), &refs);
        let out = tmp(&format!("{name}_out.json"));
        let mut args = vec!["collision", &urdf, "--root", "fixed", "--srdf", &srdf];
        args.extend([
            "--package-dir",
            &pkg,
            "--states",
            states_file.to_str().unwrap(),
        ]);
        args.extend(["--output", out.to_str().unwrap()]);
        if let Some(scene) = scene {
            args.extend(["--scene", scene]);
        }
        let o = moma(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap()
    };
    // Self: the SRDF's enabled pairs, their distances, the minimum and the verdict, on
    // states within 3 mm of contact on both sides.
    let reference = read("panda_self.json");
    let states = near_contact_states(&reference, "near_contact", "in_collision_enabled", 2);
    let got = run(&states, None, "panda_self");
    let enabled: Vec<&Value> = reference["pairs"]
        .as_array()
        .unwrap()
        .iter()
        .zip(reference["pair_enabled"].as_array().unwrap())
        .filter(|(_, e)| e.as_bool().unwrap())
        .map(|(p, _)| p)
        .collect();
    let listed = got["pairs_enabled"].as_array().unwrap();
    assert_eq!(listed.len(), enabled.len());
    for p in &enabled {
        assert!(
            listed
                .iter()
                .any(|x| (x[0] == p[0] && x[1] == p[1]) || (x[0] == p[1] && x[1] == p[0])),
            "enabled pair {p} not listed"
        );
    }
    let ref_pairs = reference["pairs"].as_array().unwrap();
    for (s, want) in got["states"].as_array().unwrap().iter().zip(&states) {
        assert_eq!(s["pairs"].as_array().unwrap().len(), enabled.len());
        assert_pairs_match(s, want, ref_pairs);
        let min = s["min_distance"].as_f64().unwrap();
        let want_min = want["min_enabled_convex"].as_f64().unwrap();
        assert!(
            (min - want_min).abs() <= 1e-6,
            "{}: {min} vs {want_min}",
            want["label"]
        );
        assert_eq!(
            s["in_collision"], want["in_collision_enabled"],
            "{}",
            want["label"]
        );
    }
    // Scene: with the SRDF and the scene, every (link, object) pair of the reference; a
    // state the reference puts in collision with the scene is in collision.
    let reference = read("panda_scene.json");
    let states = near_contact_states(&reference, "near_contact", "in_collision", 2);
    let scene = format!("{DATA}/collision/panda_scene_table.yaml");
    let got = run(&states, Some(&scene), "panda_scene");
    let ref_pairs = reference["scenes"]["table"]["pairs"].as_array().unwrap();
    assert_eq!(got["scene_objects"].as_array().unwrap().len(), 3);
    for (s, want) in got["states"].as_array().unwrap().iter().zip(&states) {
        let pairs = s["pairs"].as_array().unwrap();
        assert_eq!(pairs.len(), enabled.len() + ref_pairs.len());
        for p in ref_pairs {
            assert!(
                pairs.iter().any(|x| x["a"] == p[0] && x["b"] == p[1]),
                "{p} missing"
            );
        }
        assert_pairs_match(s, want, ref_pairs);
        let scene_min = pairs
            .iter()
            .filter(|x| ref_pairs.iter().any(|p| x["a"] == p[0] && x["b"] == p[1]))
            .map(|x| x["distance"].as_f64().unwrap())
            .fold(f64::INFINITY, f64::min);
        let want_min = want["min_distance"].as_f64().unwrap();
        assert!(
            (scene_min - want_min).abs() <= 1e-6,
            "{}: {scene_min} vs {want_min}",
            want["label"]
        );
        if want["in_collision"] == true {
            assert_eq!(s["in_collision"], true, "{}", want["label"]);
        }
    }
}

#[test]
fn panda_exact_meshes_reproduce_coal() {
    // States bisected to within 3 mm of a mesh contact, two on each side: every enabled
    // pair and every (link, object) pair against coal's distance_mesh, the verdicts.
    let (urdf, srdf, pkg) = panda_files();
    let read = |f: &str| -> Value {
        serde_json::from_str(&std::fs::read_to_string(format!("{DATA}/collision/{f}")).unwrap())
            .unwrap()
    };
    let scene = format!("{DATA}/collision/panda_scene_table.yaml");
    for (file, verdict, scene) in [
        ("panda_self.json", "in_collision_enabled_mesh", None),
        (
            "panda_scene.json",
            "in_collision_mesh",
            Some(scene.as_str()),
        ),
    ] {
        let reference = read(file);
        let states = near_contact_states(&reference, "near_contact_mesh", verdict, 2);
        let refs: Vec<&Value> = states.iter().collect();
        let states_file = write_reference_states(&format!("exact_{file}"), &refs);
        let out = tmp(&format!("exact_out_{file}"));
        let mut args = vec!["collision", &urdf, "--root", "fixed", "--srdf", &srdf];
        args.extend(["--package-dir", &pkg, "--mesh", "exact"]);
        args.extend(["--states", states_file.to_str().unwrap()]);
        args.extend(["--output", out.to_str().unwrap()]);
        if let Some(scene) = scene {
            args.extend(["--scene", scene]);
        }
        let o = moma(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let got: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
        let ref_pairs = match scene {
            None => reference["pairs"].as_array().unwrap(),
            Some(_) => reference["scenes"]["table"]["pairs"].as_array().unwrap(),
        };
        for (s, want) in got["states"].as_array().unwrap().iter().zip(&states) {
            let pairs = s["pairs"].as_array().unwrap();
            let mut min = f64::INFINITY;
            for (k, p) in ref_pairs.iter().enumerate() {
                let Some(mine) = pairs.iter().find(|x| {
                    (x["a"] == p[0] && x["b"] == p[1]) || (x["a"] == p[1] && x["b"] == p[0])
                }) else {
                    continue;
                };
                let (d, w) = (
                    mine["distance"].as_f64().unwrap(),
                    want["distance_mesh"][k].as_f64().unwrap(),
                );
                assert!(
                    (d - w).abs() <= 1e-6,
                    "{} {p}: {d} vs coal {w}",
                    want["label"]
                );
                min = min.min(d);
            }
            if scene.is_none() {
                let want_min = want["min_enabled_mesh"].as_f64().unwrap();
                assert!((min - want_min).abs() <= 1e-6, "{}", want["label"]);
                assert_eq!(s["in_collision"], want[verdict], "{}", want["label"]);
            } else if want[verdict] == true {
                assert_eq!(s["in_collision"], true, "{}", want["label"]);
            }
        }
    }
}

#[test]
fn bad_input_exits_1_and_writes_nothing() {
    let (urdf, srdf, pkg) = fetch_files();
    let states = tmp("one.json");
    std::fs::write(
        &states,
        format!("{{\"states\": [{{\"q\": {:?}}}]}}", vec![0.0; 15]),
    )
    .unwrap();
    let bad_scene = tmp("bad.yaml");
    std::fs::write(
        &bad_scene,
        "world:\n  collision_objects:\n    - header: {frame_id: base_link}\n      id: Shelf\n      primitives: [{type: cylinder, dimensions: [0.5, -0.1]}]\n      primitive_poses: [{position: [1, 0, 0], orientation: [0, 0, 0, 1]}]\n",
    )
    .unwrap();
    let out = tmp("never.json");
    let mut args = fetch_args(&urdf, &srdf, &pkg);
    args.extend([
        "--scene",
        bad_scene.to_str().unwrap(),
        "--states",
        states.to_str().unwrap(),
        "--output",
        out.to_str().unwrap(),
    ]);
    let o = moma(&args);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.yaml") && err.contains("Shelf") && err.contains("-0.1"),
        "{err}"
    );
    assert!(!out.exists());
    // Without the package folder: the link and the URI.
    let o = moma(&[
        "collision",
        &urdf,
        "--root",
        "fixed",
        "--states",
        states.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("link 'base_link'") && err.contains("package://fetch_description"),
        "{err}"
    );
}

#[test]
fn scene_sizes_and_positions_beyond_the_bound_are_named() {
    // A box of 1e15 m around Fetch read as clear of some links (the distance query's
    // tolerances are fixed lengths); sizes and positions past 1e6 m are refused by name.
    let (urdf, srdf, pkg) = fetch_files();
    let states = tmp("huge_scene_states.json");
    std::fs::write(
        &states,
        format!("{{\"states\": [{{\"q\": {:?}}}]}}", vec![0.0; 15]),
    )
    .unwrap();
    let out = tmp("huge_scene_out.json");
    for (name, dims, position, expect) in [
        (
            "huge_box.yaml",
            "[1e15, 1e15, 1e15]",
            "[0, 0, 0]",
            "primitives[0]: box dimension 1e15 m is larger than 1e6 m",
        ),
        (
            "far_box.yaml",
            "[0.1, 0.1, 0.1]",
            "[1e300, 0, 0]",
            "primitive_poses[0]: position coordinate 1e300 m is beyond ±1e6 m",
        ),
    ] {
        let scene = tmp(name);
        std::fs::write(
            &scene,
            format!(
                "world:\n  collision_objects:\n    - id: Crate\n      primitives: [{{type: box, dimensions: {dims}}}]\n      primitive_poses: [{{position: {position}, orientation: [0, 0, 0, 1]}}]\n"
            ),
        )
        .unwrap();
        let mut args = fetch_args(&urdf, &srdf, &pkg);
        args.extend([
            "--scene",
            scene.to_str().unwrap(),
            "--states",
            states.to_str().unwrap(),
            "--output",
            out.to_str().unwrap(),
        ]);
        let o = moma(&args);
        assert_eq!(o.status.code(), Some(1), "{name}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains(&format!(
                "{name}: world.collision_objects[0] (id 'Crate'): {expect}"
            )),
            "{name}: {err}"
        );
        assert!(!out.exists(), "{name}: output written");
    }
}

#[test]
fn bad_geometry_srdf_and_scene_exit_1_name_file_and_element_and_write_nothing() {
    // A three-link robot (b and c each turn on a joint of a; the pair b–c is checked) whose
    // link b's mesh is `mesh`.
    let urdf_with = |mesh: &str| {
        format!(
            r#"<robot name="r"><link name="a"><collision><geometry><box size="0.2 0.2 0.2"/></geometry></collision></link>
<link name="b"><collision><origin xyz="0 0 0.5"/><geometry><mesh filename="{mesh}"/></geometry></collision></link>
<link name="c"><collision><origin xyz="0 0 0.5"/><geometry><sphere radius="0.05"/></geometry></collision></link>
<joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint>
<joint name="k" type="revolute"><parent link="a"/><child link="c"/><origin xyz="1 0 0"/><axis xyz="0 0 1"/><limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"#
        )
    };
    let file = |name: &str, text: &[u8]| {
        let p = tmp(name);
        std::fs::write(&p, text).unwrap();
        p.to_str().unwrap().to_string()
    };
    let states = file(
        "three_link_states.json",
        br#"{"states": [{"q": [0.3, 0.2]}]}"#,
    );
    file("empty.stl", b"");
    file("empty.obj", b"");
    file(
        "nan.obj",
        b"v 0 0 0\nv 1 0 0\nv 0 nan 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\n",
    );
    file("m.dae", b"<COLLADA/>");
    file(
        "tetra.obj",
        b"v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n",
    );
    let good = file("good.urdf", urdf_with("tetra.obj").as_bytes());
    let srdf = file(
        "ghost.srdf",
        br#"<robot name="r"><disable_collisions link1="a" link2="ghost" reason="Never"/></robot>"#,
    );
    let scene = file(
        "odom.yaml",
        b"world:\n  collision_objects:\n    - header: {frame_id: odom}\n      id: Crate\n      primitives: [{type: box, dimensions: [0.1, 0.2, 0.3]}]\n      primitive_poses: [{position: [1, 0, 0], orientation: [0, 0, 0, 1]}]\n",
    );
    let out = tmp("three_link_out.json");
    let run = |urdf: &str, extra: &[&str]| {
        let mut args = vec![
            "collision",
            urdf,
            "--root",
            "fixed",
            "--states",
            &states,
            "--output",
            out.to_str().unwrap(),
        ];
        args.extend(extra);
        moma(&args)
    };
    // The good robot runs, so each failure below is its one change.
    let o = run(&good, &[]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    std::fs::remove_file(&out).unwrap();
    let mesh_cases = [
        ("missing", "missing.stl", "cannot resolve"),
        (
            "empty_stl",
            "empty.stl",
            "empty.stl: the mesh file is empty",
        ),
        (
            "empty_obj",
            "empty.obj",
            "empty.obj: the mesh file is empty",
        ),
        ("nan", "nan.obj", "nan.obj: vertex 2 is not finite"),
        ("dae", "m.dae", "m.dae: unsupported mesh format 'dae'"),
    ];
    for (tag, mesh, reason) in mesh_cases {
        let name = format!("{tag}.urdf");
        let urdf = file(&name, urdf_with(mesh).as_bytes());
        let o = run(&urdf, &[]);
        assert_eq!(o.status.code(), Some(1), "{mesh}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            err.contains(&format!("{name}: link 'b' mesh '{mesh}'")) && err.contains(reason),
            "{mesh}: {err}"
        );
        assert!(!out.exists(), "{mesh}: output written");
    }
    for (extra, expect) in [
        (
            ["--srdf", srdf.as_str()],
            ["ghost.srdf", "disable_collisions element 1", "link 'ghost'"],
        ),
        (
            ["--scene", scene.as_str()],
            ["odom.yaml", "(id 'Crate')", "unknown frame 'odom'"],
        ),
    ] {
        let o = run(&good, &extra);
        assert_eq!(o.status.code(), Some(1), "{extra:?}");
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(expect.iter().all(|e| err.contains(e)), "{extra:?}: {err}");
        assert!(!out.exists(), "{extra:?}: output written");
    }
}

/// Runs `moma collision` on Fetch with the table scene over `states` (moma layout) with
/// `extra` flags; returns the parsed JSON and the standard output.
fn run_fetch(root: &str, states: &[Vec<f64>], extra: &[&str], name: &str) -> (Value, String) {
    let scene = format!("{DATA}/scenes/motion_bench_maker/configs/scenes/table/scene_table.yaml");
    let mut all = Vec::new();
    if root == "fixed" {
        all.extend(["--scene", scene.as_str()]);
    }
    all.extend(extra);
    run_fetch_with(root, states, &all, name)
}

/// As [`run_fetch`] without the table scene.
fn run_fetch_with(root: &str, states: &[Vec<f64>], extra: &[&str], name: &str) -> (Value, String) {
    let (urdf, srdf, pkg) = fetch_files();
    let states_file = tmp(&format!("{name}_states.json"));
    let qs: Vec<Value> = states
        .iter()
        .map(|q| serde_json::json!({ "q": q }))
        .collect();
    std::fs::write(
        &states_file,
        serde_json::json!({ "states": qs }).to_string(),
    )
    .unwrap();
    let out = tmp(&format!("{name}_out.json"));
    let mut args = fetch_args(&urdf, &srdf, &pkg);
    args[3] = root;
    args.extend([
        "--states",
        states_file.to_str().unwrap(),
        "--output",
        out.to_str().unwrap(),
    ]);
    args.extend(extra);
    let o = moma(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    (got, String::from_utf8(o.stdout).unwrap())
}

/// Arm postures of Fetch (moma layout, 15 joints) whose closest pairs are a link and the
/// table (overlapping) and two links.
fn postures() -> Vec<Vec<f64>> {
    vec![
        vec![
            0., 0., 0.38, 0.1, 0.2, 0.1, 0.5, -0.3, 0.4, 1.2, 0.3, 0.8, 0.2, 0.03, 0.03,
        ],
        vec![
            0., 0., 0.3, 0.1, 0.2, 0.1, 0.5, -0.3, 0.4, 1.2, 0.3, 0.8, 0.2, 0.03, 0.03,
        ],
        vec![
            0., 0., 0.1, 0.1, 0.2, 0.1, 0.3, 0.6, 0.4, 0.4, 0.3, 0.8, 0.2, 0.03, 0.03,
        ],
        vec![
            0., 0., 0.05, 0.1, 0.2, 0.1, 0.0, 0.9, 0.0, 0.2, 0.3, 0.5, 0.2, 0.03, 0.03,
        ],
        vec![
            0., 0., 0.3, -0.2, 0.4, 0.7, -1.1, 0.2, 2.0, -1.5, 1.0, 1.1, -0.6, 0.01, 0.02,
        ],
    ]
}

#[test]
fn gradient_matches_finite_differences_of_the_minimum() {
    let h = 1e-6;
    let base = postures();
    let mut states = Vec::new();
    for q in &base {
        states.push(q.clone());
        for k in 0..q.len() {
            for s in [h, -h] {
                let mut p = q.clone();
                p[k] += s;
                states.push(p);
            }
        }
    }
    let (got, _) = run_fetch("fixed", &states, &["--gradient"], "grad");
    let out = got["states"].as_array().unwrap();
    let n = base[0].len();
    let (mut checked, mut scene_pairs, mut self_pairs) = (0, 0, 0);
    for (i, _) in base.iter().enumerate() {
        let s = &out[i * (2 * n + 1)];
        let g: Vec<f64> = s["gradient"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(g.len(), n);
        let d0 = s["min_distance"].as_f64().unwrap();
        let objects = got["scene_objects"].as_array().unwrap();
        if objects.contains(&s["closest"][1]) {
            scene_pairs += 1;
        } else {
            self_pairs += 1;
        }
        for k in 0..n {
            let (p, m) = (
                &out[i * (2 * n + 1) + 1 + 2 * k],
                &out[i * (2 * n + 1) + 2 + 2 * k],
            );
            // The same closest pair on both sides, and no kink: the one-sided slopes agree.
            if p["closest"] != s["closest"] || m["closest"] != s["closest"] {
                continue;
            }
            let (dp, dm) = (
                p["min_distance"].as_f64().unwrap(),
                m["min_distance"].as_f64().unwrap(),
            );
            if ((dp - d0) / h - (d0 - dm) / h).abs() > 1e-3 {
                continue;
            }
            let fd = (dp - dm) / (2.0 * h);
            assert!(
                (fd - g[k]).abs() <= 1e-5 * (1.0 + fd.abs()),
                "posture {i} dof {k}: gradient {} vs finite difference {fd}",
                g[k]
            );
            if g[k].abs() > 1e-3 {
                checked += 1;
            }
        }
    }
    assert!(
        scene_pairs >= 1 && self_pairs >= 1,
        "{scene_pairs} {self_pairs}"
    );
    assert!(checked >= 15, "{checked} non-zero derivatives checked");
}

fn polygon(v: &Value) -> Vec<[f64; 2]> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|p| [p[0].as_f64().unwrap(), p[1].as_f64().unwrap()])
        .collect()
}

fn inside_convex(poly: &[[f64; 2]], p: [f64; 2]) -> bool {
    (0..poly.len()).all(|i| {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) >= -1e-9
    })
}

#[test]
fn footprint_holds_the_geometry_and_rides_with_the_base() {
    let arm = postures();
    let (fixed, stdout) = run_fetch("fixed", &arm, &["--footprint", "--all-pairs"], "fp_fixed");
    assert_eq!(fixed["footprint_frame"], "world");
    let objects = fixed["scene_objects"].as_array().unwrap();
    assert_eq!(objects.len(), 12);
    let lines: Vec<&str> = stdout.lines().collect();
    assert_eq!(lines.len(), arm.len());
    for (s, line) in fixed["states"].as_array().unwrap().iter().zip(&lines) {
        let poly = polygon(&s["footprint"]);
        assert!(poly.len() >= 3);
        // The printed text is the JSON's polygon, in `moma plan --footprint`'s syntax.
        assert_eq!(s["footprint_text"], *line);
        let parsed: Vec<f64> = line.split([';', ',']).map(|t| t.parse().unwrap()).collect();
        assert_eq!(parsed, poly.iter().flatten().copied().collect::<Vec<_>>());
        // Every witness point lies on the robot's geometry: its ground projection is in
        // the footprint (all link pairs, and each link against the table).
        let mut n = 0;
        for p in s["pairs"].as_array().unwrap() {
            let mut pts = vec![&p["witness_a"]];
            if !objects.contains(&p["b"]) {
                pts.push(&p["witness_b"]);
            }
            for w in pts {
                let xy = [w[0].as_f64().unwrap(), w[1].as_f64().unwrap()];
                assert!(inside_convex(&poly, xy), "{xy:?} outside the footprint");
                n += 1;
            }
        }
        assert!(n > 400, "{n}");
    }
    // On a planar base at (1, 2, 0.7) the footprint in the base frame is the fixed
    // robot's footprint in the world.
    let moved: Vec<Vec<f64>> = arm
        .iter()
        .map(|q| [&[1.0, 2.0, 0.7][..], q].concat())
        .collect();
    let (planar, _) = run_fetch("planar", &moved, &["--footprint"], "fp_planar");
    assert_eq!(planar["footprint_frame"], "base");
    for (a, b) in fixed["states"]
        .as_array()
        .unwrap()
        .iter()
        .zip(planar["states"].as_array().unwrap())
    {
        // The same polygon up to round-off (its first vertex may differ).
        let (pa, pb) = (polygon(&a["footprint"]), polygon(&b["footprint"]));
        assert!(
            pa.len().abs_diff(pb.len()) <= 2,
            "{} vs {}",
            pa.len(),
            pb.len()
        );
        assert!(pa.iter().all(|p| inside_convex(&pb, *p)));
        assert!(pb.iter().all(|p| inside_convex(&pa, *p)));
        let area = |p: &[[f64; 2]]| {
            (0..p.len())
                .map(|i| {
                    let (a, b) = (p[i], p[(i + 1) % p.len()]);
                    a[0] * b[1] - b[0] * a[1]
                })
                .sum::<f64>()
                / 2.0
        };
        assert!(area(&pa) > 0.2 && (area(&pa) - area(&pb)).abs() < 1e-9);
    }
}

#[test]
fn voxels_and_points_are_the_box_they_fill() {
    // A 1 m × 0.5 m × 0.1 m plate in front of Fetch as 20 × 10 × 2 voxels of 5 cm, as a
    // point cloud filling the same cells (two points per cell), and as one box.
    let (r, origin) = (0.05, [0.5, -0.25, 0.7]);
    let mut map = String::from("voxel 20 10 2\n");
    let mut cloud = String::from("# x y z\n");
    for x in 0..20 {
        for y in 0..10 {
            for z in 0..2 {
                map.push_str(&format!("{x} {y} {z}\n"));
                for f in [0.3, 0.7] {
                    let p = [x, y, z]
                        .iter()
                        .zip(origin)
                        .map(|(i, o)| o + (*i as f64 + f) * r)
                        .collect::<Vec<_>>();
                    cloud.push_str(&format!("{},{},{}\n", p[0], p[1], p[2]));
                }
            }
        }
    }
    let (map_file, cloud_file, box_file) =
        (tmp("plate.3dmap"), tmp("plate.xyz"), tmp("plate.yaml"));
    std::fs::write(&map_file, map).unwrap();
    std::fs::write(&cloud_file, cloud).unwrap();
    std::fs::write(
        &box_file,
        "world:\n  collision_objects:\n    - header: {frame_id: world}\n      id: plate\n      primitives: [{type: box, dimensions: [1.0, 0.5, 0.1]}]\n      primitive_poses: [{position: [1.0, 0.0, 0.75], orientation: [0, 0, 0, 1]}]\n",
    )
    .unwrap();
    let states = postures();
    let scene_pairs = |v: &Value| -> Vec<(String, f64)> {
        v["states"]
            .as_array()
            .unwrap()
            .iter()
            .flat_map(|s| s["pairs"].as_array().unwrap().clone())
            .filter(|p| p["b"] == "plate")
            .map(|p| {
                (
                    p["a"].as_str().unwrap().to_string(),
                    p["distance"].as_f64().unwrap(),
                )
            })
            .collect()
    };
    let (as_box, _) = run_fetch_with(
        "fixed",
        &states,
        &["--scene", box_file.to_str().unwrap()],
        "plate_box",
    );
    let size = r.to_string();
    let (as_voxels, _) = run_fetch_with(
        "fixed",
        &states,
        &[
            "--voxels",
            map_file.to_str().unwrap(),
            "--voxel-size",
            &size,
            "--voxel-origin",
            "0.5,-0.25,0.7",
        ],
        "plate_voxels",
    );
    let (as_points, _) = run_fetch_with(
        "fixed",
        &states,
        &[
            "--points",
            cloud_file.to_str().unwrap(),
            "--voxel-size",
            &size,
        ],
        "plate_points",
    );
    let want = scene_pairs(&as_box);
    assert_eq!(want.len(), 21 * states.len());
    let mut near = 0;
    for got in [scene_pairs(&as_voxels), scene_pairs(&as_points)] {
        assert_eq!(got.len(), want.len());
        for ((la, d), (lb, w)) in got.iter().zip(&want) {
            assert_eq!(la, lb);
            // Apart, the distance to a union of cubes that fills a box is the distance
            // to the box (overlapping, the depths differ: each cube is shallower).
            if *w > 0.0 {
                assert!((d - w).abs() < 1e-9, "{la}: {d} vs the box's {w}");
                near += usize::from(*w < 0.3);
            } else {
                assert!(*d < 0.0, "{la}: {d} apart but overlapping the box ({w})");
            }
        }
    }
    assert!(near >= 10, "{near} links within 0.3 m of the plate");
    // Bad input: a voxel size that is not positive, a bad point line.
    let o = moma(&[
        "collision",
        "x.urdf",
        "--root",
        "fixed",
        "--states",
        "s.json",
        "--points",
        cloud_file.to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "--points without --voxel-size is a usage error"
    );
    std::fs::write(&cloud_file, "0 0 0\n1 2\n").unwrap();
    let states_file = tmp("plate_bad_states.json");
    std::fs::write(
        &states_file,
        serde_json::json!({"states": [{"q": states[0]}]}).to_string(),
    )
    .unwrap();
    let (urdf, srdf, pkg) = fetch_files();
    let mut args = fetch_args(&urdf, &srdf, &pkg);
    args.extend([
        "--states",
        states_file.to_str().unwrap(),
        "--points",
        cloud_file.to_str().unwrap(),
        "--voxel-size",
        "0.05",
    ]);
    let o = moma(&args);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("plate.xyz") && err.contains("line 2"), "{err}");
    args.truncate(args.len() - 2);
    args.push("--voxel-size=-0.05");
    let o = moma(&args);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--voxel-size"));
}

#[test]
fn exact_meshes_match_coal_and_touch_at_zero() {
    let reference: Value = serde_json::from_str(
        &std::fs::read_to_string(format!("{DATA}/collision/fetch_self_public.json")).unwrap(),
    )
    .unwrap();
    let all = reference["states"].as_array().unwrap();
    // One state whose enabled meshes touch and one whose do not.
    let pick: Vec<&Value> = [true, false]
        .iter()
        .map(|t| {
            all.iter()
                .find(|s| s["in_collision_enabled_mesh"] == *t)
                .unwrap()
        })
        .collect();
    let states_file = write_reference_states("exact_states.json", &pick);
    let (urdf, srdf, pkg) = fetch_files();
    let out = tmp("exact_out.json");
    let mut args = fetch_args(&urdf, &srdf, &pkg);
    args.extend([
        "--states",
        states_file.to_str().unwrap(),
        "--layout",
        "pinocchio",
        "--mesh",
        "exact",
        "--output",
        out.to_str().unwrap(),
    ]);
    let o = moma(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(got["mesh"], "exact");
    let ref_pairs = reference["pairs"].as_array().unwrap();
    for (s, want) in got["states"].as_array().unwrap().iter().zip(&pick) {
        let pairs = s["pairs"].as_array().unwrap();
        assert_eq!(pairs.len(), 76);
        for p in pairs {
            let k = ref_pairs
                .iter()
                .position(|r| {
                    (r[0] == p["a"] && r[1] == p["b"]) || (r[0] == p["b"] && r[1] == p["a"])
                })
                .unwrap();
            let (d, w) = (
                p["distance"].as_f64().unwrap(),
                want["distance_mesh"][k].as_f64().unwrap(),
            );
            assert!(
                (d - w).abs() <= 1e-6,
                "{} {}: {d} vs coal {w}",
                p["a"],
                p["b"]
            );
            assert!(d >= 0.0);
        }
        assert_eq!(s["in_collision"], want["in_collision_enabled_mesh"]);
    }
}

#[test]
fn a_scene_with_exact_meshes_matches_coal_and_touches_at_zero() {
    let reference: Value = serde_json::from_str(
        &std::fs::read_to_string(format!("{DATA}/collision/fetch_scene_public.json")).unwrap(),
    )
    .unwrap();
    // The table scene: the tucked default state, one whose arm is in the table (coal:
    // seven link meshes cross it) and one 7.6 cm clear of it.
    let pick: Vec<&Value> = ["mbm_fetch_default", "random_002", "random_003"]
        .iter()
        .map(|label| {
            reference["states"]
                .as_array()
                .unwrap()
                .iter()
                .find(|s| s["scene"] == "table_pick" && s["label"] == *label)
                .unwrap()
        })
        .collect();
    let states_file = write_reference_states("exact_scene_states.json", &pick);
    let (urdf, srdf, pkg) = fetch_files();
    let scene = format!("{DATA}/scenes/motion_bench_maker/configs/scenes/table/scene_table.yaml");
    let out = tmp("exact_scene_out.json");
    let mut args = fetch_args(&urdf, &srdf, &pkg);
    args.extend([
        "--scene",
        &scene,
        "--states",
        states_file.to_str().unwrap(),
        "--layout",
        "pinocchio",
        "--mesh",
        "exact",
        "--output",
        out.to_str().unwrap(),
    ]);
    let o = moma(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got: Value = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    assert_eq!(got["mesh"], "exact");
    let ref_pairs = reference["scenes"]["table_pick"]["pairs"]
        .as_array()
        .unwrap();
    let mut touching = 0;
    for (s, want) in got["states"].as_array().unwrap().iter().zip(&pick) {
        let pairs = s["pairs"].as_array().unwrap();
        assert_eq!(pairs.len(), 76 + ref_pairs.len());
        let mut touches = false;
        for (k, p) in ref_pairs.iter().enumerate() {
            let mine = pairs
                .iter()
                .find(|x| x["a"] == p[0] && x["b"] == p[1])
                .unwrap_or_else(|| panic!("pair {p} missing"));
            let d = mine["distance"].as_f64().unwrap();
            let w = want["distance_mesh"][k].as_f64().unwrap();
            if w > 0.0 {
                assert!((d - w).abs() <= 1e-6, "{p}: {d} vs coal {w}");
            } else {
                assert_eq!(d, 0.0, "{p}: coal's triangles cross the object");
                touches = true;
                touching += 1;
            }
        }
        let min = s["min_distance"].as_f64().unwrap();
        assert!(min >= 0.0);
        assert_eq!(s["in_collision"].as_bool().unwrap(), min == 0.0);
        if touches {
            assert!(s["in_collision"].as_bool().unwrap());
        }
    }
    assert_eq!(touching, 7);
}

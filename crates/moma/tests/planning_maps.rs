//! Map loaders: ROS map_server maps reproduce the reference occupied/free/unknown counts;
//! Moving AI formats parse with CRLF, blank lines and both scenario versions; bad input
//! gives clear errors.

use moma::planning::{self, MapKind, MovingAiScenario, load_map};
use std::path::{Path, PathBuf};

fn data(p: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/planning").join(p)
}

fn counts(path: &str, res: Option<f64>) -> (usize, usize, usize, usize, usize) {
    let m = load_map(&data(path), res).unwrap();
    let c = m.grid.counts();
    assert_eq!(c.intermediate, 0);
    (m.grid.width, m.grid.height, c.occupied, c.free, c.unknown)
}

#[test]
fn ros_maps_reproduce_reference_counts() {
    assert_eq!(counts("rosmaps/nav2/tb3_sandbox.yaml", None), (384, 384, 870, 7_903, 138_683));
    assert_eq!(counts("rosmaps/nav2/depot.yaml", None), (604, 307, 5_947, 179_481, 0));
    assert_eq!(counts("rosmaps/nav2/warehouse_png.yaml", None), (1006, 1674, 30_951, 1_422_292, 230_801));
    assert_eq!(counts("rosmaps/nav2/100by100_20_png.yaml", None), (2000, 2000, 824_415, 3_175_585, 0));
    assert_eq!(counts("rosmaps/turtlebot3/map.yaml", None), (384, 384, 795, 7_939, 138_722));
    assert_eq!(counts("rosmaps/willow_garage/willow-full-0.05.png", Some(0.05)), (1165, 945, 13_459, 549_308, 538_158));
    // The PGM and PNG versions of testmap are the same image.
    assert_eq!(counts("rosmaps/nav2/testmap.pgm", None), (10, 10, 29, 71, 0));
    assert_eq!(counts("rosmaps/nav2/testmap.yaml", None), (10, 10, 29, 71, 0));
}

#[test]
fn yaml_fields_and_image_flip() {
    let m = load_map(&data("rosmaps/nav2/testmap.yaml"), None).unwrap();
    let meta = m.meta.unwrap();
    assert_eq!(meta.resolution, 0.1);
    assert_eq!(meta.origin, [2.0, 3.0, 1.0]);
    assert!(!meta.negate);
    assert_eq!(meta.mode, planning::MapMode::Trinary);
    // The PGM's first pixel (top-left) is 0 = occupied; it becomes grid row height-1.
    let g = &m.grid;
    assert_eq!(g.get(0, 9), Some(100));
    assert_eq!(g.get(1, 9), Some(0));
    let neg = load_map(&data("rosmaps/nav2/100by100_20_png.yaml"), None).unwrap();
    assert!(neg.meta.unwrap().negate);
}

#[test]
fn world_cell_round_trip_with_yaw() {
    let m = load_map(&data("rosmaps/nav2/testmap.yaml"), None).unwrap();
    let g = &m.grid;
    // Cell (0, 0)'s centre is origin + R(1 rad) (0.05, 0.05).
    let [wx, wy] = g.cell_to_world(0.0, 0.0);
    let (s, c) = 1.0f64.sin_cos();
    assert!((wx - (2.0 + 0.05 * c - 0.05 * s)).abs() < 1e-12);
    assert!((wy - (3.0 + 0.05 * s + 0.05 * c)).abs() < 1e-12);
    for (x, y) in [(0, 0), (3, 7), (9, 9), (5, 0)] {
        let [wx, wy] = g.cell_to_world(x as f64, y as f64);
        assert_eq!(g.world_to_cell("p", wx, wy).unwrap(), (x, y));
    }
    let err = g.world_to_cell("start", 0.0, 0.0).unwrap_err().to_string();
    assert!(err.contains("start") && err.contains("outside"), "{err}");
}

#[test]
fn movingai_maps_parse_crlf_and_sizes() {
    for (name, w, h, passable) in [
        ("arena", 49, 49, 2_054),
        ("den520d", 256, 257, 28_178),
        ("brc202d", 530, 481, 43_151),
        ("Berlin_0_256", 256, 256, 48_147),
        ("Berlin_0_1024", 1024, 1024, 794_748),
        ("maze512-1-0", 512, 512, 131_071),
        ("random512-10-0", 512, 512, 235_900),
        ("32room_000", 512, 512, 240_671),
    ] {
        let m = load_map(&data(&format!("movingai/{name}.map")), None).unwrap();
        assert_eq!((m.grid.width, m.grid.height), (w, h), "{name}");
        assert_eq!(m.grid.counts().free, passable, "{name}");
        assert_eq!(m.grid.kind, MapKind::MovingAi);
    }
}

#[test]
fn scen_files_parse_with_blank_lines_and_versions() {
    let den = MovingAiScenario::load(&data("movingai/den520d.map.scen")).unwrap();
    assert_eq!(den.version, 1);
    assert_eq!(den.problems.len(), 888);
    assert_eq!(den.problems[1].start, (100, 163));
    assert!((den.problems[1].optimal - 2.82843).abs() < 1e-12);
    let berlin = MovingAiScenario::load(&data("movingai/Berlin_0_256.map.scen")).unwrap();
    assert_eq!(berlin.problems.len(), 930);
    assert_eq!(berlin.problems[0].map, "Berlin_0_256.map");
    let counts: usize = ["arena", "den520d", "brc202d", "Berlin_0_256", "Berlin_0_1024", "maze512-1-0", "random512-10-0", "32room_000"]
        .iter()
        .map(|n| MovingAiScenario::load(&data(&format!("movingai/{n}.map.scen"))).unwrap().problems.len())
        .sum();
    assert_eq!(counts, 23_877);
    // Version 0: no header, no width/height columns; CRLF endings and blank lines.
    let v0 = "0\tmaps/a.map\t1\t2\t3\t4\t5.5\r\n\r\n1\tmaps/a.map\t0\t0\t4\t0\t4\r\n";
    let s = MovingAiScenario::parse(v0, Path::new("v0.scen")).unwrap();
    assert_eq!(s.version, 0);
    assert_eq!(s.problems.len(), 2);
    assert_eq!(s.problems[1].index, 1);
    assert_eq!(s.problems[0].map_width, None);
    assert_eq!(s.problems[0].goal, (3, 4));
}

#[test]
fn three_d_formats_parse() {
    let g = planning::load_3dmap(&data("movingai/3d/A1.3dmap")).unwrap();
    assert_eq!((g.nx, g.ny, g.nz), (896, 390, 255));
    assert_eq!(g.blocked_count(), 123_236);
    assert!(g.is_blocked(74, 80, 63));
    let p = planning::load_3dscen(&data("movingai/3d/A1.every10.3dscen")).unwrap();
    assert_eq!(p.len(), 1000);
    assert_eq!(p[0].start, (101, 109, 191));
    assert!((p[0].optimal - 562.04094761).abs() < 1e-12);
}

fn write_tmp(name: &str, text: &[u8]) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("moma-planning-maps-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

#[test]
fn bad_inputs_give_clear_errors() {
    let e = |p: &Path| load_map(p, None).unwrap_err().to_string();
    let missing_img = write_tmp("noimg.yaml", b"image: nothere.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n");
    let m = e(&missing_img);
    assert!(m.contains("nothere.pgm") && m.contains("cannot read"), "{m}");
    let bad_yaml = write_tmp("bad.yaml", b"image: [unterminated\nresolution: 0.05\n");
    assert!(e(&bad_yaml).contains("bad.yaml"), "{}", e(&bad_yaml));
    let no_res = write_tmp("nores.yaml", b"image: a.pgm\norigin: [0, 0, 0]\n");
    assert!(e(&no_res).contains("'resolution'"), "{}", e(&no_res));
    let bad_origin = write_tmp("origin.yaml", b"image: a.pgm\nresolution: 0.05\norigin: [0, 0]\n");
    assert!(e(&bad_origin).contains("'origin'"), "{}", e(&bad_origin));
    let neg_res = write_tmp("negres.yaml", b"image: a.pgm\nresolution: -1\norigin: [0, 0, 0]\n");
    assert!(e(&neg_res).contains("'resolution'"), "{}", e(&neg_res));
    let bad_mode = write_tmp("mode.yaml", b"image: a.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nmode: fancy\n");
    assert!(e(&bad_mode).contains("'mode'"), "{}", e(&bad_mode));
    let thresh = write_tmp("th.yaml", b"image: a.pgm\nresolution: 0.05\norigin: [0,0,0]\nfree_thresh: 0.7\noccupied_thresh: 0.6\n");
    assert!(e(&thresh).contains("free_thresh"), "{}", e(&thresh));
    let garbage_img = write_tmp("garbage.pgm", b"P5\n10 10\n255\nshort");
    assert!(e(&garbage_img).contains("garbage.pgm"), "{}", e(&garbage_img));
    let short_map = write_tmp("short.map", b"type octile\nheight 3\nwidth 2\nmap\n..\n.\n..\n");
    assert!(e(&short_map).contains("row 1"), "{}", e(&short_map));
    let few_rows = write_tmp("few.map", b"type octile\nheight 3\nwidth 2\nmap\n..\n");
    assert!(e(&few_rows).contains("expected height"), "{}", e(&few_rows));
    let bad_scen = write_tmp("bad.scen", b"version 1\n0\ta.map\t2\t2\t0\tx\t1\t1\t1\n");
    let m = MovingAiScenario::load(&bad_scen).unwrap_err().to_string();
    assert!(m.contains("line 2") && m.contains("start y"), "{m}");
    assert!(e(Path::new("/nonexistent/dir/map.yaml")).contains("cannot read"));
}

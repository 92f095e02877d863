//! Golden checks of `moma plan`: the README's and docs/planning.md's plan examples, and
//! one case per search (D* Lite, cost-aware A*, a polygonal footprint, a Moving AI map
//! without smoothing), compared with the `path.json` and SVG they wrote when recorded.
//! Numbers must agree to 1e-9 (relative), everything else exactly; the map path, which
//! depends on where the repository lies, is left out.
//!
//! To record them again after a deliberate change of output, run this test with
//! `MOMA_BLESS=1` and review the diff of `tests/data/plan_golden/`.

use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/plan_golden")
}

/// The cases: name, map (relative to the repository), arguments, expected exit status.
const CASES: &[(&str, &str, &[&str], i32)] = &[
    (
        "readme_turtlebot3",
        "crates/moma/tests/data/planning/rosmaps/turtlebot3/map.yaml",
        &["--start=-2,-0.5", "--goal", "1.5,0.5", "--radius", "0.1"],
        0,
    ),
    (
        "readme_trap_geodesic",
        "scenarios/maps/potential_trap.map",
        &[
            "--start",
            "16,12",
            "--goal",
            "34,12",
            "--algo",
            "potential-geodesic",
        ],
        0,
    ),
    (
        "docs_trap_potential",
        "scenarios/maps/potential_trap.map",
        &["--start", "16,12", "--goal", "34,12", "--algo", "potential"],
        3,
    ),
    (
        "dstar_turtlebot3",
        "crates/moma/tests/data/planning/rosmaps/turtlebot3/map.yaml",
        &[
            "--start=-2,-0.5",
            "--goal",
            "1.5,0.5",
            "--radius",
            "0.1",
            "--algo",
            "dstar-lite",
        ],
        0,
    ),
    (
        "cost_aware_turtlebot3",
        "crates/moma/tests/data/planning/rosmaps/turtlebot3/map.yaml",
        &[
            "--start=-2,-0.5",
            "--goal",
            "1.5,0.5",
            "--radius",
            "0.1",
            "--cost-aware",
        ],
        0,
    ),
    (
        "footprint_turtlebot3",
        "crates/moma/tests/data/planning/rosmaps/turtlebot3/map.yaml",
        &[
            "--start=-2,-0.5,0.3",
            "--goal",
            "1.5,0.5",
            "--footprint=-0.12,-0.08;0.12,-0.08;0.12,0.08;-0.12,0.08",
        ],
        0,
    ),
    (
        "movingai_no_smooth",
        "crates/moma/tests/data/planning/movingai/32room_000.map",
        &[
            "--start",
            "1,1",
            "--goal",
            "30,30",
            // the start is one cell from the wall: a disk of 0.5 cells there would touch
            // the wall's cell (the disk C-space blocks within the radius + half a cell)
            "--radius",
            "0.4",
            "--no-smooth",
        ],
        0,
    ),
];

/// `a` and `b` equal, numbers to a relative 1e-9; `at` names the place for the message.
fn same(a: &serde_json::Value, b: &serde_json::Value, at: &str) -> Result<(), String> {
    use serde_json::Value as V;
    match (a, b) {
        (V::Number(x), V::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            if (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1e-300) || x == y {
                Ok(())
            } else {
                Err(format!("{at}: {x} != {y}"))
            }
        }
        (V::Array(x), V::Array(y)) => {
            if x.len() != y.len() {
                return Err(format!("{at}: {} != {} entries", x.len(), y.len()));
            }
            x.iter()
                .zip(y)
                .enumerate()
                .try_for_each(|(i, (p, q))| same(p, q, &format!("{at}[{i}]")))
        }
        (V::Object(x), V::Object(y)) => {
            let kx: Vec<_> = x.keys().collect();
            let ky: Vec<_> = y.keys().collect();
            if kx != ky {
                return Err(format!("{at}: keys {kx:?} != {ky:?}"));
            }
            x.iter()
                .try_for_each(|(k, v)| same(v, &y[k], &format!("{at}.{k}")))
        }
        _ if a == b => Ok(()),
        _ => Err(format!("{at}: {a} != {b}")),
    }
}

#[test]
fn plan_outputs_match_the_recorded_ones() {
    let bless = std::env::var_os("MOMA_BLESS").is_some();
    let tmp = std::env::temp_dir().join(format!("moma-plan-golden-{}", std::process::id()));
    std::fs::create_dir_all(&tmp).unwrap();
    let mut failures = Vec::new();
    for (name, map, args, status) in CASES {
        let (json_path, svg_path) = (
            tmp.join(format!("{name}.json")),
            tmp.join(format!("{name}.svg")),
        );
        let o = Command::new(env!("CARGO_BIN_EXE_moma"))
            .current_dir(root())
            .arg("plan")
            .arg(map)
            .args(*args)
            .arg("--output")
            .arg(&json_path)
            .arg("--svg")
            .arg(&svg_path)
            .output()
            .expect("run moma");
        assert_eq!(
            o.status.code(),
            Some(*status),
            "{name}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let mut got: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&json_path).unwrap()).unwrap();
        got.as_object_mut().unwrap().remove("map");
        let svg = std::fs::read_to_string(&svg_path).unwrap();
        let (want_json, want_svg) = (
            golden_dir().join(format!("{name}.json")),
            golden_dir().join(format!("{name}.svg")),
        );
        if bless {
            std::fs::create_dir_all(golden_dir()).unwrap();
            let mut text = serde_json::to_string_pretty(&got).unwrap();
            text.push('\n');
            std::fs::write(&want_json, text).unwrap();
            std::fs::write(&want_svg, &svg).unwrap();
            continue;
        }
        let want: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&want_json).unwrap()).unwrap();
        if let Err(e) = same(&got, &want, name) {
            failures.push(e);
        }
        if svg != std::fs::read_to_string(&want_svg).unwrap() {
            failures.push(format!(
                "{name}: the SVG differs from {}",
                want_svg.display()
            ));
        }
    }
    std::fs::remove_dir_all(&tmp).ok();
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

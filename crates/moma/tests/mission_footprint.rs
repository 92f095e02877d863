//! The mission with the robot's footprint polygon and obstacles with heights: a long base
//! crosses a wall through a 0.70 m passage that the disk holding its polygon cannot pass
//! (tests/data/mission/narrow_passage.toml), the polygon check rejects a heading the
//! search's C-space admits, and a table blocks the map or not depending on whether the
//! robot's geometry at the transport posture passes under it.

use std::path::{Path, PathBuf};

use moma::mission::scenario::{from_file, parse_file};
use moma::mission::{Mission, run};
use moma::planning::costmap::Footprint;
use moma::planning::distance_transform;
use moma::planning::footprint_clearance::ConvexFootprint;

fn data() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/mission")
}

/// The narrow-passage mission with `from` replaced by `to`.
fn narrow(from: &str, to: &str) -> moma::Result<Mission> {
    let path = data().join("narrow_passage.toml");
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(from), "{from}");
    let file = parse_file(&text.replace(from, to), &path).unwrap();
    from_file(file, &path, &data())
}

/// The mission's footprint polygon and the largest disk about the axle inside it.
fn polygon(m: &Mission) -> (Footprint, f64) {
    m.footprint
        .planning_polygon(m.robot.base.drive.d)
        .expect("the robot's polygon")
}

#[test]
fn the_robot_polygon_passes_a_passage_the_disk_holding_it_cannot() {
    let m = narrow("", "").unwrap();
    let (_, inscribed) = polygon(&m);
    // the 1.00 m x 0.40 m chassis: 0.20 m about the axle, 0.54 m to its corners
    assert!((inscribed - 0.2).abs() < 1e-9, "{inscribed}");
    assert!((m.footprint.radius - 0.5f64.hypot(0.2)).abs() < 1e-6);
    let r = run(&m).unwrap();
    assert!(r.reached, "{:?}", r.reason);
    // lengthwise through the 0.70 m passage: 0.15 m on each side, never less
    let clear = r.min_clearance().unwrap();
    assert!(clear > 0.14 && clear < 0.15 + 1e-9, "{clear}");
    let through = r.samples.q.iter().any(|q| (q[0] - 4.0).abs() < 0.1);
    assert!(through, "the base drives through the wall's passage");

    // the disk about the base frame that holds the polygon: no way through
    let disk = narrow(
        "footprint = \"robot\"",
        &format!("footprint_radius = {}", m.footprint.radius),
    )
    .unwrap();
    let r = run(&disk).unwrap();
    assert!(!r.reached);
    let reason = r.reason.unwrap();
    assert!(reason.contains("unreachable"), "{reason}");
}

#[test]
fn the_check_catches_a_heading_where_the_polygon_collides() {
    let m = narrow("", "").unwrap();
    let grid = &m.map.grid;
    let res = grid.resolution;
    let mask = grid.obstacle_mask(100, true);
    let (fp, inscribed) = polygon(&m);
    let fp = ConvexFootprint::new(&fp, res).unwrap();
    // the middle of the passage
    let [fx, fy] = grid.world_to_cell_f(4.0, 2.0);
    let dist = distance_transform(&mask, grid.width, grid.height);
    let cell = fy.floor() as usize * grid.width + fx.floor() as usize;
    // the C-space the search runs on (the inscribed disk, dilated by half a cell) leaves
    // the passage's middle free at every heading
    assert!(f64::from(dist[cell]) > inscribed / res + 0.5);
    let mut buf = Vec::new();
    let at = |th: f64, buf: &mut Vec<[f64; 2]>| {
        fp.clearance(&mask, grid.width, grid.height, [fx, fy, th], 1.0 / res, buf)
            .map(|d| d * res)
    };
    let along = at(0.0, &mut buf).unwrap();
    assert!((along - 0.15).abs() < 1e-6, "{along}");
    // across the passage the 1 m chassis reaches 0.15 m into each wall
    let across = at(std::f64::consts::FRAC_PI_2, &mut buf).unwrap();
    assert!((across + 0.15).abs() < 1e-6, "{across}");
    // and at 30° off the passage's axis its corners are in the walls too
    assert!(at(30f64.to_radians(), &mut buf).unwrap() < 0.0);
}

/// The planning pipeline checks the start and goal poses with the polygon at their
/// headings: across the passage's middle the 1 m chassis reaches into both walls, though
/// the inscribed disk the search runs on fits there; each refusal names its field.
#[test]
fn a_start_or_goal_the_polygon_collides_at_is_refused_naming_the_field() {
    for (from, field) in [
        ("pose = [1.5, 2.0, 0.0]", "start.pose"),
        ("pose = [6.5, 2.0, 0.0]", "goal.pose"),
    ] {
        let across = narrow(from, "pose = [4.0, 2.0, 1.5708]").unwrap();
        let e = run(&across).unwrap_err().to_string();
        assert!(
            e.contains(&format!(
                "{field}: the footprint polygon with its origin at (4.000, 2.000) m and \
                 heading 1.571 rad overlaps"
            )),
            "{e}"
        );
        // along the passage it fits
        let along = narrow(from, "pose = [4.0, 2.0, 0.0]").unwrap();
        assert!(run(&along).is_ok(), "{field}");
    }
}

#[test]
fn a_path_the_polygon_collides_on_is_replanned_with_those_cells_blocked() {
    // from the upper left, the path on the inscribed disk's C-space enters the passage
    // at an angle that the 1 m chassis cannot take
    let m = narrow("[1.5, 2.0, 0.0]", "[2.8, 3.4, 0.0]").unwrap();
    let r = run(&m).unwrap();
    assert!(r.reached, "{:?}", r.reason);
    let repaired = r
        .events
        .iter()
        .find(|e| e.kind == "footprint")
        .expect("a footprint event");
    assert!(repaired.text.contains("re-plan"), "{}", repaired.text);
    assert!(r.min_clearance().unwrap() > 0.0);
}

/// The narrow mission with a table top across the whole map behind the wall
/// (z = 0.70 to 0.75 m) and the mast at `mast` (rad).
fn with_table(mast: &str, z: &str) -> moma::Result<Mission> {
    narrow(
        "transport_posture = [1.5708]",
        &format!(
            "transport_posture = [{mast}]\n\
             [[map.boxes]]\npose = [5.5, 2.0, 0.0]\nsize = [0.8, 3.8]\nz = {z}"
        ),
    )
}

#[test]
fn a_table_the_folded_mast_passes_under_is_no_obstacle_the_raised_mast_hits_it() {
    let plain = narrow("", "").unwrap();
    let occupied = |m: &Mission| m.map.grid.cells.iter().filter(|&&c| c >= 100).count();
    // folded, the mast's top is at z = 0.49: 0.21 m under the table top
    let folded = with_table("1.5708", "[0.7, 0.75]").unwrap();
    let v = folded.boxes[0];
    assert!(!v.blocked);
    assert!((v.clearance - 0.21).abs() < 1e-6, "{}", v.clearance);
    assert_eq!(occupied(&folded), occupied(&plain));
    let r = run(&folded).unwrap();
    assert!(r.reached, "{:?}", r.reason);

    // raised, the mast (up to z = 1.25) runs into the table top: its cells are blocked,
    // 0.8 m x 3.8 m = 16 x 76 cells, and the way is closed
    let raised = with_table("0.0", "[0.7, 0.75]").unwrap();
    let v = raised.boxes[0];
    assert!(v.blocked);
    assert!(v.clearance < 0.0, "{}", v.clearance);
    assert_eq!(occupied(&raised), occupied(&plain) + 16 * 76);
    let r = run(&raised).unwrap();
    assert!(!r.reached);

    // a beam above the raised mast is no obstacle either
    let high = with_table("0.0", "[1.5, 1.6]").unwrap();
    assert!(!high.boxes[0].blocked);
    assert!((high.boxes[0].clearance - 0.25).abs() < 1e-6);
}

#[test]
fn a_box_with_bad_numbers_is_refused_naming_the_field() {
    let err = with_table("1.5708", "[0.8, 0.7]").unwrap_err().to_string();
    assert!(
        err.contains("narrow_passage.toml") && err.contains("map.boxes[0].z"),
        "{err}"
    );
    let err = narrow(
        "[output]",
        "[[map.boxes]]\npose = [5.5, 2.0, 0.0]\nsize = [0.0, 1.0]\nz = [0.0, 1.0]\n[output]",
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("map.boxes[0].size"), "{err}");
}

/// A `w` × `h` map of 5 cm cells with a 1 m thick wall (cells x = 80–99) pierced by `n`
/// Z-shaped slots 9 cells (0.45 m) wide — in at cells y = 20 + 24 k to 28 + 24 k, up 10
/// cells in the wall's middle, out — which the long base's inscribed disk (0.2 m) passes
/// and its 1 m chassis cannot turn, the wall ending at cell y = `top`; written as a P2
/// image into `dir`.
fn slotted_wall(dir: &Path, n: i64, top: i64, w: i64, h: i64) -> PathBuf {
    let mut text = format!("P2\n{w} {h}\n255\n");
    for row in 0..h {
        // image rows run from the top; y from the bottom
        let y = h - 1 - row;
        for x in 0..w {
            let in_box =
                |x0: i64, x1: i64, y0: i64, y1: i64| x >= x0 && x < x1 && y >= y0 && y < y1;
            let slot = (0..n).any(|k| {
                let y0 = 20 + 24 * k;
                in_box(80, 95, y0, y0 + 9)
                    || in_box(86, 95, y0, y0 + 19)
                    || in_box(86, 100, y0 + 10, y0 + 19)
            });
            let wall = in_box(80, 100, 0, top) && !slot;
            text.push_str(if wall { "0 " } else { "254 " });
        }
        text.push('\n');
    }
    let path = dir.join("slotted_wall.pgm");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn after_ten_repairs_the_search_falls_back_to_the_circumscribed_disk() {
    let dir = std::env::temp_dir().join(format!("moma_footprint_fallback_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // eleven slots the polygon collides in, the way round above y = 14.5 m
    let map = slotted_wall(&dir, 11, 290, 180, 320);
    let path = data().join("narrow_passage.toml");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace(
            "file = \"narrow_passage.pgm\"",
            &format!("file = {:?}", map.display().to_string()),
        )
        .replace("[1.5, 2.0, 0.0]", "[2.0, 1.225, 0.0]")
        .replace("[6.5, 2.0, 0.0]", "[7.0, 1.725, 0.0]")
        // corners tight enough for the smoothing to follow a slot's one-cell C-space
        .replace("mu = 0.6", "mu = 0.6\nkappa_max = 20.0");
    let m = from_file(parse_file(&text, &path).unwrap(), &path, &data()).unwrap();
    let r = run(&m).unwrap();
    std::fs::remove_dir_all(&dir).ok();
    eprintln!("DBG {:?} {:?}", r.reached, r.reason);
    for e in &r.events {
        eprintln!("DBG {} {}", e.kind, e.text);
    }
    let events: Vec<&str> = r
        .events
        .iter()
        .filter(|e| e.kind == "footprint")
        .map(|e| e.text.as_str())
        .collect();
    assert_eq!(
        events,
        [
            "the footprint polygon collides along every path found (10 re-plan(s)): planning \
          on the circumscribed disk of radius 0.539 m"
        ],
    );
    // the disk's path goes round the wall's end and reaches the goal
    assert!(r.reached, "{:?}", r.reason);
    assert!(r.samples.q.iter().any(|q| q[1] > 14.5), "round the wall");
    assert!(r.min_clearance().unwrap() > 0.0);
}

//! A fixed number of D* Lite re-plans on nav2's `warehouse` map, for load-insensitive
//! counts (`perf stat -e instructions:u,cycles:u`):
//! `cargo run --release --locked -p moma --example dstar_replans -- [ROUNDS]`.
//!
//! The cases are the planning bench's `disk_replan/warehouse_png.yaml@*`: the robot has
//! driven 20 %, 40 % and 60 % of its path when a disk (obstacle 0.4 m plus robot 0.3 m)
//! appears centred on the path cell 1 m ahead. Each round re-plans every case once on a
//! fresh copy of the planner (`clone_from`, `set_blocked` of the disk's cells, `compute`,
//! `path`). With `ROUNDS = 0` only the setup runs, so the difference of two counts is the
//! cost of the re-plans alone. It prints the rounds, the summed expansions and path cells
//! (the same for any build of the same algorithm).

use moma::planning::{SearchGrid, costmap, dstar_lite::DStarLite, load_map};
use std::hint::black_box;
use std::path::Path;

/// The planner after driving part of the way and the C-space cells of the disk ahead.
struct Case {
    planner: DStarLite,
    disk: Vec<(usize, usize)>,
}

fn cases() -> Vec<Case> {
    let file = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/planning/rosmaps/nav2/warehouse_png.yaml");
    let (r_robot, r_obs) = (0.3, 0.4);
    let m = load_map(&file, None).expect("the bundled map").grid;
    let obst = m.obstacle_mask(100, true);
    let mask = costmap::inflate(&obst, m.width, m.height, r_robot / m.resolution).expect("mask");
    let cs = SearchGrid::from_obstacles(&mask, m.width, m.height).expect("grid");
    let sc = m.world_to_cell("start", -5.5, -20.0).expect("start");
    let gc = m.world_to_cell("goal", 11.0, 7.5).expect("goal");
    let mut d = DStarLite::new(&cs, sc, gc).expect("planner");
    d.compute().expect("goal reachable");
    let path = d.path().expect("a path");
    let ahead = (1.0 / m.resolution).round() as usize;
    let rc = (r_obs + r_robot) / m.resolution;
    let ri = rc.ceil() as i64;
    let mut out = Vec::new();
    for frac in [0.2, 0.4, 0.6] {
        let mut planner = d.clone();
        let k = (path.len() as f64 * frac) as usize;
        planner.move_start(path[k]).expect("a free cell");
        let c = path[k + ahead];
        let mut disk = Vec::new();
        for dy in -ri..=ri {
            for dx in -ri..=ri {
                let (x, y) = (c.0 as i64 + dx, c.1 as i64 + dy);
                let inside = x >= 0 && y >= 0 && (x as usize) < m.width && (y as usize) < m.height;
                let cell = (x as usize, y as usize);
                if ((dx * dx + dy * dy) as f64) <= rc * rc
                    && inside
                    && cell != gc
                    && cell != path[k]
                {
                    disk.push(cell);
                }
            }
        }
        out.push(Case { planner, disk });
    }
    out
}

fn main() {
    let rounds: usize = std::env::args()
        .nth(1)
        .map_or(100, |s| s.parse().expect("ROUNDS is a count"));
    let cases = cases();
    let mut p = cases[0].planner.clone();
    let (mut expanded, mut cells) = (0usize, 0usize);
    for _ in 0..rounds {
        for c in &cases {
            p.clone_from(&c.planner);
            for &cell in &c.disk {
                p.set_blocked(cell, true).expect("a cell of the map");
            }
            p.compute();
            cells += black_box(p.path()).map_or(0, |v| v.len());
            expanded += p.expanded();
        }
    }
    println!("rounds {rounds} expanded {expanded} path cells {cells}");
}

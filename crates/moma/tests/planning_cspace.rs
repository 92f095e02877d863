//! Configuration space: disk dilation equals brute-force dilation; nav2 inflation costs;
//! polygonal footprints; smoothing and time parameterisation.

use moma::planning::costmap::{
    self, Footprint, INSCRIBED, InflationParams, LETHAL, NO_INFORMATION,
};
use moma::planning::footprint_clearance::ConvexFootprint;
use moma::planning::smooth::{line_of_sight, polyline_length, smooth};
use moma::planning::trajectory::{DiffDriveLimits, time_parameterize};
use moma::planning::{self, SearchGrid, load_map};
use rand::{Rng, SeedableRng};
use std::path::Path;

fn random_obstacles(w: usize, h: usize, p: f64, seed: u64) -> Vec<bool> {
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    (0..w * h).map(|_| rng.random_bool(p)).collect()
}

/// The disk C-space against the geometry it stands for: an occupied cell is a square of
/// side one cell, and a cell is blocked when the disk about its centre reaches into an
/// obstacle's square. Every blocked cell's disk does; a free cell's disk overlaps none
/// along the grid's axes and none by more than ½·√2 − ½ cells diagonally.
#[test]
fn disk_dilation_follows_the_obstacle_squares() {
    let (w, h) = (37, 29);
    let obst = random_obstacles(w, h, 0.03, 1);
    let slack = std::f64::consts::FRAC_1_SQRT_2 - 0.5;
    for r in [0.0, 1.0, 1.5, 1.6, 2.3, 4.0] {
        let fast = costmap::inflate(&obst, w, h, r).unwrap();
        for y in 0..h as i64 {
            for x in 0..w as i64 {
                // distance from the cell's centre to the nearest obstacle square, over all
                // obstacles and over those in its own row or column
                let (mut any, mut axis) = (f64::INFINITY, f64::INFINITY);
                for oy in 0..h as i64 {
                    for ox in 0..w as i64 {
                        if !obst[(oy * w as i64 + ox) as usize] {
                            continue;
                        }
                        let gap = |d: i64| (d.abs() as f64 - 0.5).max(0.0);
                        let e = gap(ox - x).hypot(gap(oy - y));
                        any = any.min(e);
                        if ox == x || oy == y {
                            axis = axis.min(e);
                        }
                    }
                }
                let blocked = fast[(y * w as i64 + x) as usize];
                if blocked {
                    assert!(any <= r, "r {r} at ({x}, {y}): blocked {any} from a square");
                } else {
                    assert!(axis > r, "r {r} at ({x}, {y}): free {axis} along an axis");
                    assert!(
                        any > r - slack - 1e-12,
                        "r {r} at ({x}, {y}): free at {any}"
                    );
                }
            }
        }
    }
    assert!(costmap::inflate(&obst, w, h, -1.0).is_err());
    // one obstacle cell: the disk of 1.6 cells two cells away reaches 0.1 cell into it
    let mut one = vec![false; 25];
    one[2 * 5 + 2] = true;
    assert!(costmap::inflate(&one, 5, 5, 1.6).unwrap()[2 * 5 + 4]);
    assert!(!costmap::inflate(&one, 5, 5, 1.4).unwrap()[2 * 5 + 4]);
}

#[test]
fn inflation_costs_follow_nav2() {
    let p = InflationParams::nav2_defaults(0.2);
    let res = 0.05;
    assert_eq!(costmap::inflation_cost(0.0, res, &p), LETHAL);
    assert_eq!(costmap::inflation_cost(4.0, res, &p), INSCRIBED); // 0.20 m
    // 0.30 m: 252 exp(-10 * 0.1) = 92.7 -> 92 (truncated as nav2).
    assert_eq!(costmap::inflation_cost(6.0, res, &p), 92);
    assert_eq!(
        costmap::inflation_cost(11.0, res, &p),
        (252.0 * (-10.0f64 * 0.35).exp()) as u8
    );
    assert_eq!(costmap::inflation_cost(12.0, res, &p), 0); // beyond 0.55 m
    // A layer over a real map: unknown stays 255 away from obstacles, obstacles 254.
    let m = load_map(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/planning/rosmaps/turtlebot3/map.yaml"),
        None,
    )
    .unwrap();
    let g = &m.grid;
    let obst = g.obstacle_mask(100, false);
    let unknown: Vec<bool> = g.cells.iter().map(|&v| v < 0).collect();
    let costs =
        costmap::inflation_layer(&obst, Some(&unknown), g.width, g.height, g.resolution, &p)
            .unwrap();
    assert_eq!(costs.iter().filter(|&&c| c == LETHAL).count(), 795);
    for i in 0..costs.len() {
        if obst[i] {
            assert_eq!(costs[i], LETHAL);
        } else if unknown[i] {
            assert!(costs[i] == NO_INFORMATION || costs[i] == INSCRIBED);
        }
    }
    assert!(costs.iter().any(|&c| c > 0 && c < INSCRIBED));
}

#[test]
fn cost_aware_search_prefers_clearance() {
    // A corridor map: open field with one obstacle block; the cost-aware path keeps more
    // clearance than the plain shortest path and costs at least its length.
    let (w, h) = (60, 40);
    let mut obst = vec![false; w * h];
    for y in 10..30 {
        for x in 28..32 {
            obst[y * w + x] = true;
        }
    }
    let p = InflationParams {
        inscribed_radius: 1.0,
        inflation_radius: 8.0,
        cost_scaling_factor: 0.5,
    };
    let costs = costmap::inflation_layer(&obst, None, w, h, 1.0, &p).unwrap();
    let weighted = SearchGrid::from_costs(&costs, w, h, 2.0, false).unwrap();
    let plain = SearchGrid::from_costs(&costs, w, h, 0.0, false).unwrap();
    let a = planning::astar(&weighted, (5, 20), (55, 20))
        .unwrap()
        .unwrap();
    let b = planning::astar(&plain, (5, 20), (55, 20)).unwrap().unwrap();
    assert!(a.cost >= a.length() - 1e-9);
    assert!(a.length() >= b.length() - 1e-9);
    let clearance = |path: &planning::GridPath| {
        path.cells
            .iter()
            .map(|&(x, y)| costs[y * w + x])
            .max()
            .unwrap()
    };
    assert!(
        clearance(&a) < clearance(&b),
        "weighted {} vs plain {}",
        clearance(&a),
        clearance(&b)
    );
    // Optimality of the weighted search against Dijkstra (the wavefront).
    let wf = planning::wavefront(&weighted, (55, 20)).unwrap();
    assert!((wf[20 * w + 5] - a.cost).abs() < 1e-6 * a.cost);
}

/// The polygon C-space against the geometry it stands for, as the disk's above: an
/// occupied cell is a square of side one cell, and a pose (a cell centre at heading θ_k)
/// is blocked exactly when the footprint there meets an obstacle's square. The oracle is
/// the separating-axis distance of `footprint_clearance` (a pose blocked when it is ≤ 0),
/// which shares no code with the C-space.
#[test]
fn footprint_cspace_matches_brute_force_and_bounds() {
    let (w, h) = (40, 30);
    let obst = random_obstacles(w, h, 0.02, 5);
    let fp = Footprint::parse("[[0.5, 0.2], [0.5, -0.2], [-0.3, -0.2], [-0.3, 0.2]]").unwrap();
    assert!((fp.inscribed_radius() - 0.2).abs() < 1e-12);
    let res = 0.1;
    let cs = costmap::footprint_cspace(&obst, w, h, res, &fp, 8).unwrap();
    assert_eq!(cs.slices.len(), 8);
    let convex = ConvexFootprint::new(&fp, res).unwrap();
    let mut placed = Vec::new();
    // bounds: the inscribed disk reaches every square within r_in + ½ (centre to
    // centre); no square beyond r_out + ½√2 comes near the footprint
    let dist = planning::distance_transform(&obst, w, h);
    let within = |r: f64| -> Vec<bool> { dist.iter().map(|&d| f64::from(d) <= r).collect() };
    let disk_in = within(fp.inscribed_radius() / res + 0.5);
    let disk_out = within(fp.circumscribed_radius() / res + std::f64::consts::FRAC_1_SQRT_2);
    let mut corner_only = 0;
    for k in 0..8 {
        let theta = k as f64 * std::f64::consts::TAU / 8.0;
        let offs = fp.cell_offsets(theta, res);
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                let pose = [x as f64 + 0.5, y as f64 + 0.5, theta];
                let d = convex.clearance(&obst, w, h, pose, 1.0, &mut placed);
                if let Some(d) = d.filter(|d| d.abs() < 1e-7) {
                    panic!("pose ({x}, {y}, {k}) touches an obstacle ({d}): pick another map");
                }
                let meets = d.is_some_and(|d| d < 0.0);
                assert_eq!(cs.slices[k][i], meets, "heading {k} at ({x}, {y}): {d:?}");
                assert!(!disk_in[i] || cs.slices[k][i]);
                assert!(disk_out[i] || !cs.slices[k][i]);
                assert!(!cs.slices[k][i] || cs.sweeps[k][i]);
                // blocked although no obstacle centre lies inside the footprint
                let centre_inside = offs.iter().any(|&(dx, dy)| {
                    let (ox, oy) = (x as i64 + dx, y as i64 + dy);
                    let (bx, by) = (dx as f64 * res, dy as f64 * res);
                    let (s, c) = theta.sin_cos();
                    ox >= 0
                        && oy >= 0
                        && ox < w as i64
                        && oy < h as i64
                        && obst[oy as usize * w + ox as usize]
                        && fp.contains(c * bx + s * by, -s * bx + c * by)
                });
                corner_only += usize::from(meets && !centre_inside);
            }
        }
    }
    // the poses an obstacle's centre rule would have missed
    assert!(corner_only > 0);
    // Headings differ for an elongated robot.
    assert_ne!(cs.slices[0], cs.slices[2]);
    assert!(
        Footprint::parse("1,1;2,1;2,2")
            .unwrap_err()
            .to_string()
            .contains("origin")
    );
    assert!(Footprint::parse("1,1;2").is_err());
}

#[test]
fn smoothing_is_collision_free_and_shorter() {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/planning/movingai/den520d.map");
    let grid = load_map(&p, None).unwrap().grid;
    let sg = SearchGrid::from_grid(&grid, true).unwrap();
    let path = planning::astar(&sg, (100, 163), (200, 200))
        .unwrap()
        .unwrap();
    let s = smooth(&sg, &path.cells);
    assert_eq!(s[0], path.cells[0]);
    assert_eq!(s.last(), path.cells.last());
    assert!(s.len() < path.cells.len() / 4);
    assert!(polyline_length(&s) <= path.length() + 1e-9);
    for w in s.windows(2) {
        assert!(line_of_sight(&sg, w[0], w[1]));
        // Dense sampling of the segment stays in free cells.
        for k in 0..=200 {
            let t = k as f64 / 200.0;
            let x = w[0].0 as f64 + t * (w[1].0 as f64 - w[0].0 as f64);
            let y = w[0].1 as f64 + t * (w[1].1 as f64 - w[0].1 as f64);
            assert!(
                sg.is_free((x + 0.5).floor() as i64, (y + 0.5).floor() as i64)
                    || sg.is_free(
                        (x + 0.5 - 1e-9).floor() as i64,
                        (y + 0.5 - 1e-9).floor() as i64
                    )
            );
        }
    }
    // Line of sight rejects a segment through a wall and a corner squeeze.
    let mut o = vec![false; 9];
    o[1] = true;
    o[3] = true;
    let g3 = SearchGrid::from_obstacles(&o, 3, 3).unwrap();
    assert!(!line_of_sight(&g3, (0, 0), (2, 2)));
    // (2, 0) -> (0, 2) squeezes between (1, 0) and (2, 1) at a corner: rejected.
    assert!(!line_of_sight(&g3, (2, 0), (0, 2)));
    assert!(line_of_sight(&g3, (2, 0), (2, 2)));
    assert!(line_of_sight(&g3, (1, 1), (2, 2)));
}

#[test]
fn time_parameterisation_respects_limits() {
    let lim = DiffDriveLimits {
        v_max: 0.5,
        omega_max: 1.0,
        a_max: 0.4,
        alpha_max: 2.0,
    };
    let wp = [[0.0, 0.0], [2.0, 0.0], [2.0, 1.5], [2.05, 1.55], [0.0, 3.0]];
    let traj = time_parameterize(&wp, Some(0.0), &lim, 0.01).unwrap();
    let last = traj.last().unwrap();
    assert!((last.x - 0.0).abs() < 1e-9 && (last.y - 3.0).abs() < 1e-9);
    assert_eq!((last.v, last.omega), (0.0, 0.0));
    for w in traj.windows(2) {
        let (a, b) = (w[0], w[1]);
        let dt = b.t - a.t;
        assert!(dt > 0.0);
        assert!(b.v.abs() <= lim.v_max + 1e-12 && b.omega.abs() <= lim.omega_max + 1e-12);
        assert!(
            (b.v - a.v).abs() <= lim.a_max * dt + 1e-9,
            "acc at t = {}",
            b.t
        );
        assert!((b.omega - a.omega).abs() <= lim.alpha_max * dt + 1e-9);
        // Non-holonomic: displacement along the heading only.
        let (dx, dy) = (b.x - a.x, b.y - a.y);
        assert!((-a.theta.sin() * dx + a.theta.cos() * dy).abs() < 1e-9 || (dx.hypot(dy)) < 1e-12);
        // Position integrates the velocity (the trapezoid rule is exact except across a
        // profile kink, where it errs by at most a_max dt^2 / 4).
        assert!((dx.hypot(dy) - 0.5 * (a.v + b.v) * dt).abs() <= lim.a_max * dt * dt / 4.0 + 1e-12);
    }
    // 2 m at 0.5 m/s with a = 0.4: 1.25 s up, 2.75 s cruise, 1.25 s down = 5.25 s.
    let first_end = traj
        .iter()
        .find(|p| (p.x - 2.0).abs() < 1e-12 && p.y == 0.0)
        .unwrap();
    assert!((first_end.t - 5.25).abs() < 1e-9);
    let bad = DiffDriveLimits { v_max: 0.0, ..lim };
    assert!(
        time_parameterize(&wp, None, &bad, 0.01)
            .unwrap_err()
            .to_string()
            .contains("v_max")
    );
    assert!(time_parameterize(&[], None, &lim, 0.01).is_err());
    assert!(time_parameterize(&[[0.0, f64::NAN]], None, &lim, 0.01).is_err());
}

//! Curvature-bounded smoothing of grid paths on real ROS maps, and the near time-optimal
//! speed profile along the smooth path: curvature bound, heading continuity, exact start
//! and goal poses, collision-free in the C-space, every limit on every knot (checked by
//! finite differences), closed-form optima on a line and a circle, re-planning from a
//! moving start, and the errors.

use moma::planning::curvature::{PathSample, SmoothOptions, SmoothPath, smooth_diff_drive};
use moma::planning::trajectory::{
    DiffDriveLimits, TimedPath, TipOverAcceleration, time_parameterize_curve,
};
use moma::planning::{OccupancyGrid, SearchGrid, astar, costmap, load_map};
use std::f64::consts::PI;
use std::path::Path;

fn map(name: &str) -> OccupancyGrid {
    load_map(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("tests/data/planning/rosmaps")
            .join(name),
        None,
    )
    .unwrap()
    .grid
}

/// The C-space of a disk robot of `radius` metres (unknown cells are obstacles).
fn cspace(m: &OccupancyGrid, radius: f64) -> SearchGrid {
    let obst = m.obstacle_mask(100, true);
    let mask = costmap::inflate(&obst, m.width, m.height, radius / m.resolution).unwrap();
    SearchGrid::from_obstacles(&mask, m.width, m.height).unwrap()
}

fn plan(
    m: &OccupancyGrid,
    cs: &SearchGrid,
    start: [f64; 3],
    goal: [f64; 3],
    opts: &SmoothOptions,
) -> moma::Result<SmoothPath> {
    let s = m.world_to_cell("start", start[0], start[1]).unwrap();
    let g = m.world_to_cell("goal", goal[0], goal[1]).unwrap();
    let cells = astar(cs, s, g).unwrap().expect("reachable").cells;
    smooth_diff_drive(cs, m, &cells, start, goal, opts)
}

fn wrap(a: f64) -> f64 {
    (a + PI).rem_euclid(2.0 * PI) - PI
}

/// Every property a smooth path promises, checked on its samples.
fn check_path(
    p: &SmoothPath,
    m: &OccupancyGrid,
    cs: &SearchGrid,
    start: [f64; 3],
    goal: [f64; 3],
    kmax: f64,
) {
    let smp = p.samples();
    let (first, last) = (smp[0], *smp.last().unwrap());
    assert_eq!((first.x, first.y), (start[0], start[1]), "exact start");
    assert!((first.theta - (start[2] + p.pivot())).abs() < 1e-12);
    assert!(p.pivot().abs() <= PI);
    assert!(
        (last.x - goal[0]).abs() < 1e-9 && (last.y - goal[1]).abs() < 1e-9,
        "end {last:?}"
    );
    assert!(
        wrap(last.theta - goal[2]).abs() < 1e-9,
        "goal heading {} vs {}",
        last.theta,
        goal[2]
    );
    assert!((last.s - p.length()).abs() < 1e-12);
    assert!(p.max_abs_curvature() <= kmax * (1.0 + 1e-12));
    // the first and last pieces run straight along the headings: κ = 0 at both ends
    assert!(first.kappa.abs() < 1e-12 && last.kappa.abs() < 1e-12);
    for w in smp.windows(2) {
        let (a, b): (&PathSample, &PathSample) = (&w[0], &w[1]);
        let ds = b.s - a.s;
        assert!(ds > 0.0 && ds <= 0.02 + 1e-12, "spacing {ds}");
        // heading continuous: θ' = κ, κ linear in between
        let dth = b.theta - a.theta;
        assert!(
            (dth - 0.5 * (a.kappa + b.kappa) * ds).abs() < 1e-9,
            "dθ {dth} at s = {}",
            a.s
        );
        // position continuous: the chord is nearly the arc
        let chord = (b.x - a.x).hypot(b.y - a.y);
        assert!(chord <= ds + 1e-12 && chord >= ds * (1.0 - kmax * kmax * ds * ds / 6.0) - 1e-12);
        // direction of travel follows the heading (no reversing)
        let dir = (b.y - a.y).atan2(b.x - a.x);
        assert!(wrap(dir - 0.5 * (a.theta + b.theta)).abs() < 1e-3);
    }
    for q in smp {
        let c = m.world_to_cell("sample", q.x, q.y).unwrap();
        assert!(
            cs.is_free(c.0 as i64, c.1 as i64),
            "sample {q:?} in a C-space obstacle"
        );
        // at(s) agrees with the sample
        let r = p.at(q.s);
        assert!(
            (r.x - q.x).abs() < 1e-12
                && (r.y - q.y).abs() < 1e-12
                && (r.theta - q.theta).abs() < 1e-12
        );
    }
    // between samples too (every 5 mm)
    let n = (p.length() / 0.005) as usize;
    for k in 0..=n {
        let q = p.at(k as f64 * 0.005);
        let c = m.world_to_cell("point", q.x, q.y).unwrap();
        assert!(
            cs.is_free(c.0 as i64, c.1 as i64),
            "point {q:?} in a C-space obstacle"
        );
    }
}

#[test]
fn smooth_path_on_tb3_sandbox_between_the_pillars() {
    let m = map("nav2/tb3_sandbox.yaml");
    let cs = cspace(&m, 0.12);
    let opts = SmoothOptions::new(4.0);
    // across the arena, weaving between the pillars, arriving facing up
    for (start, goal) in [
        ([-2.0, -0.5, 0.0], [2.0, 0.55, PI / 2.0]),
        ([-1.6, 1.6, -0.3], [1.55, -1.6, 0.0]),
        ([0.55, 0.0, -PI / 2.0], [-0.55, -0.6, -PI]),
    ] {
        let p = plan(&m, &cs, start, goal, &opts).unwrap();
        check_path(&p, &m, &cs, start, goal, 4.0);
        assert_eq!(p.pivot(), 0.0, "{start:?} should drive off directly");
        let straight = (goal[0] - start[0]).hypot(goal[1] - start[1]);
        assert!(p.length() > straight && p.length() < 2.0 * straight);
    }
    // start heading pointing away: a turn in place first, then forwards
    let (start, goal) = ([-2.0, -0.5, PI], [2.0, 0.55, PI / 2.0]);
    let p = plan(&m, &cs, start, goal, &opts).unwrap();
    check_path(&p, &m, &cs, start, goal, 4.0);
    assert!(p.pivot().abs() > PI / 2.0, "pivot {}", p.pivot());
}

#[test]
fn smooth_path_on_warehouse() {
    let m = map("nav2/warehouse_png.yaml");
    let cs = cspace(&m, 0.3);
    let opts = SmoothOptions::new(1.5);
    let (start, goal) = ([-5.5, -9.4, PI / 2.0], [2.2, -9.4, -PI / 2.0]);
    let p = plan(&m, &cs, start, goal, &opts).unwrap();
    check_path(&p, &m, &cs, start, goal, 1.5);
}

fn limits() -> DiffDriveLimits {
    DiffDriveLimits {
        v_max: 1.0,
        omega_max: 1.5,
        a_max: 0.8,
        alpha_max: 2.0,
    }
}

/// Every limit at every knot, with the accelerations checked by finite differences.
fn check_timing(tp: &TimedPath, lim: &DiffDriveLimits, tip: Option<&TipOverAcceleration>) {
    let k = tp.knots();
    let tol = 1e-9;
    for q in &k {
        assert!(q.v >= 0.0 && q.v <= lim.v_max + tol, "v {}", q.v);
        assert!(q.omega.abs() <= lim.omega_max + tol, "ω {}", q.omega);
        assert!((q.omega - q.kappa * q.v).abs() < 1e-12);
        assert!(q.a.abs() <= lim.a_max + tol, "a {}", q.a);
        assert!(
            q.alpha.abs() <= lim.alpha_max + 1e-7,
            "α {} at s = {}",
            q.alpha,
            q.s
        );
        if let Some(t) = tip {
            let an = q.kappa * q.v * q.v;
            let ta = if q.a >= 0.0 {
                q.a / t.forward
            } else {
                -q.a / t.backward
            };
            let na = if an >= 0.0 {
                an / t.left
            } else {
                -an / t.right
            };
            assert!(ta + na <= 1.0 + 1e-7, "diamond {} at s = {}", ta + na, q.s);
        }
    }
    for w in k.windows(2) {
        let dt = w[1].t - w[0].t;
        assert!(dt > 0.0);
        let a_fd = (w[1].v - w[0].v) / dt;
        assert!(
            (a_fd - w[0].a).abs() < 1e-7 * (1.0 + a_fd.abs()),
            "a {a_fd} vs {}",
            w[0].a
        );
        assert!(a_fd.abs() <= lim.a_max + tol);
        let alpha_fd = (w[1].omega - w[0].omega) / dt;
        assert!(
            alpha_fd.abs() <= lim.alpha_max + 1e-7,
            "α_fd {alpha_fd} at s = {}",
            w[0].s
        );
        // s advances by the trapezoid rule of v over the interval
        assert!(((w[1].s - w[0].s) - 0.5 * (w[0].v + w[1].v) * dt).abs() < 1e-9);
    }
    // sample(t) interpolates the knots and the geometry
    for q in k.iter().step_by(7) {
        let r = tp.sample(q.t);
        assert!(
            (r.s - q.s).abs() < 1e-9 && (r.v - q.v).abs() < 1e-9,
            "{r:?} vs {q:?}"
        );
        assert!((r.x - q.x).abs() < 1e-9 && (r.y - q.y).abs() < 1e-9);
    }
    let d = tp.duration();
    let ss = tp.samples(0.05).unwrap();
    assert_eq!(ss.last().unwrap().t, d);
    for w in ss.windows(2) {
        assert!(w[1].t > w[0].t && w[1].s >= w[0].s - 1e-12);
        // positions move consistently with the speed
        let dist = (w[1].x - w[0].x).hypot(w[1].y - w[0].y);
        assert!(dist <= (w[1].t - w[0].t) * lim.v_max + 1e-9);
    }
}

#[test]
fn timing_on_a_straight_line_matches_the_trapezoid() {
    let lim = limits();
    let l = 5.0;
    let p = SmoothPath::from_curvature([1.0, 2.0, 0.3], &[(l, 0.0, 0.0)], 0.02).unwrap();
    let tp = time_parameterize_curve(&p, &lim, None, 0.0, 0.0).unwrap();
    check_timing(&tp, &lim, None);
    // rest to rest: L / v + v / a
    let opt = l / lim.v_max + lim.v_max / lim.a_max;
    assert!(tp.duration() >= opt - 1e-9);
    assert!(tp.duration() < opt * 1.01, "{} vs {opt}", tp.duration());
    // asymmetric tip-over braking: L / v + v / (2 a_f) + v / (2 a_b)
    let tip = TipOverAcceleration {
        forward: 0.6,
        backward: 0.3,
        left: f64::INFINITY,
        right: f64::INFINITY,
    };
    let tp = time_parameterize_curve(&p, &lim, Some(&tip), 0.0, 0.0).unwrap();
    check_timing(&tp, &lim, Some(&tip));
    let opt = l / lim.v_max + lim.v_max / 1.2 + lim.v_max / 0.6;
    assert!(
        tp.duration() >= opt - 1e-9 && tp.duration() < opt * 1.01,
        "{} vs {opt}",
        tp.duration()
    );
    let end = tp.sample(f64::INFINITY);
    assert!((end.x - (1.0 + l * 0.3f64.cos())).abs() < 1e-9 && end.v < 1e-6);
}

#[test]
fn timing_on_a_circle_matches_the_closed_form() {
    let lim = limits();
    // radius 0.5 m: cruise at ω_max R = 0.75 m/s; on a circle α = κ a, so the
    // acceleration is bounded by min(a_max, α_max R) = 0.8 (a_max binds).
    // Enter and leave along clothoids? No: a pure circle entered at rest.
    let r = 0.5;
    let l = 2.0 * PI * r;
    let p = SmoothPath::from_curvature([0.0, 0.0, 0.0], &[(l, 1.0 / r, 1.0 / r)], 0.01).unwrap();
    let tp = time_parameterize_curve(&p, &lim, None, 0.0, 0.0).unwrap();
    check_timing(&tp, &lim, None);
    let vc = lim.omega_max * r;
    let ae = lim.a_max.min(lim.alpha_max * r);
    let opt = l / vc + vc / ae;
    assert!(
        tp.duration() >= opt - 1e-9 && tp.duration() < opt * 1.01,
        "{} vs {opt}",
        tp.duration()
    );
    // the closed curve comes back to its start
    let end = tp.sample(tp.duration());
    assert!(end.x.abs() < 1e-9 && end.y.abs() < 1e-9 && (end.theta - 2.0 * PI).abs() < 1e-9);
    // with a lateral tip-over limit the circle is driven at sqrt(A_left R)
    let tip = TipOverAcceleration {
        forward: 10.0,
        backward: 10.0,
        left: 0.5,
        right: 0.5,
    };
    let tp = time_parameterize_curve(&p, &lim, Some(&tip), 0.0, 0.0).unwrap();
    check_timing(&tp, &lim, Some(&tip));
    let vc = (0.5 * r).sqrt();
    let mid = tp.sample(0.5 * tp.duration());
    assert!((mid.v - vc).abs() < 1e-6, "{} vs {vc}", mid.v);
    // the diamond couples: speeding up on the circle must leave lateral room, so the
    // time exceeds the decoupled bound L / v_c + v_c / a_max
    assert!(tp.duration() > l / vc + vc / lim.a_max);
}

#[test]
fn timing_along_a_smoothed_map_path_respects_every_limit() {
    let m = map("nav2/tb3_sandbox.yaml");
    let cs = cspace(&m, 0.12);
    let (start, goal) = ([-2.0, -0.5, PI], [2.0, 0.55, PI / 2.0]);
    let p = plan(&m, &cs, start, goal, &SmoothOptions::new(4.0)).unwrap();
    let lim = limits();
    let tip = TipOverAcceleration {
        forward: 0.5,
        backward: 0.4,
        left: 0.6,
        right: 0.35,
    };
    let tp = time_parameterize_curve(&p, &lim, Some(&tip), 0.0, 0.0).unwrap();
    check_timing(&tp, &lim, Some(&tip));
    // the pivot comes first: at rest, turning within ω_max and α_max, then the path
    let tpiv = tp.pivot_duration();
    assert!(tpiv > 0.0);
    let mid = tp.sample(0.5 * tpiv);
    assert_eq!((mid.v, mid.s, mid.x, mid.y), (0.0, 0.0, start[0], start[1]));
    assert!(mid.omega.abs() > 0.0 && mid.omega.abs() <= lim.omega_max + 1e-12);
    let after = tp.sample(tpiv);
    assert!((after.theta - p.samples()[0].theta).abs() < 1e-9);
    // no stop between the start and the goal: positive speed at every interior knot
    let k = tp.knots();
    assert!(k[1..k.len() - 1].iter().all(|q| q.v > 0.0));
    assert!(
        time_parameterize_curve(&p, &lim, None, 0.3, 0.0).is_err(),
        "v_start with a pivot"
    );
}

#[test]
fn replan_continues_from_the_current_speed() {
    let lim = limits();
    let p = SmoothPath::from_curvature(
        [0.0, 0.0, 0.0],
        &[
            (1.0, 0.0, 0.0),
            (0.5, 0.0, 2.0),
            (0.6, 2.0, 2.0),
            (0.5, 2.0, 0.0),
            (1.5, 0.0, 0.0),
        ],
        0.02,
    )
    .unwrap();
    let tp = time_parameterize_curve(&p, &lim, None, 0.6, 0.0).unwrap();
    check_timing(&tp, &lim, None);
    assert_eq!(tp.knots()[0].v, 0.6);
    assert_eq!(tp.overspeed_until(), None);
    // faster than the curve allows at its start: brakes as hard as allowed, and says so
    let p = SmoothPath::from_curvature([0.0, 0.0, 0.0], &[(3.0, 2.0, 2.0)], 0.02).unwrap();
    let tp = time_parameterize_curve(&p, &lim, None, 1.0, 0.0).unwrap();
    let s = tp.overspeed_until().expect("overspeed at the start");
    let k = tp.knots();
    // v drops at a_max until it is within ω_max / κ = 0.75 m/s
    let s_expected = (1.0 - 0.75f64 * 0.75) / (2.0 * lim.a_max);
    assert!(
        s >= s_expected - 0.021 && s <= s_expected + 0.021,
        "{s} vs {s_expected}"
    );
    for q in k.iter().filter(|q| q.s >= s) {
        assert!(q.omega.abs() <= lim.omega_max + 1e-9);
    }
    // ends at (most) v_end
    let p = SmoothPath::from_curvature([0.0, 0.0, 0.0], &[(4.0, 0.0, 0.0)], 0.02).unwrap();
    let tp = time_parameterize_curve(&p, &lim, None, 0.5, 0.4).unwrap();
    assert!((tp.sample(tp.duration()).v - 0.4).abs() < 1e-9);
}

#[test]
fn a_speed_limit_above_any_reachable_speed_times_like_no_limit() {
    // On a 5 m line from rest under a_max = 0.5 no profile exceeds √(2 a_max L) ≈ 2.24 m/s,
    // so v_max = 3, 1e100 and 1e300 (whose square overflows) give the same profile: the
    // rest-to-rest bang-bang one, 2 √(L / a_max).
    let p = SmoothPath::from_curvature([0.0, 0.0, 0.0], &[(5.0, 0.0, 0.0)], 0.02).unwrap();
    let reference = {
        let mut lim = limits();
        lim.v_max = 3.0;
        time_parameterize_curve(&p, &lim, None, 0.0, 0.0).unwrap()
    };
    let bang_bang = 2.0 * (5.0 / limits().a_max).sqrt();
    assert!(
        (reference.duration() - bang_bang).abs() < 1e-2 * bang_bang,
        "{} vs {bang_bang}",
        reference.duration()
    );
    for v_max in [1e100, 1e300, f64::MAX] {
        let mut lim = limits();
        lim.v_max = v_max;
        let tp = time_parameterize_curve(&p, &lim, None, 0.0, 0.0)
            .unwrap_or_else(|e| panic!("v_max = {v_max}: {e}"));
        check_timing(&tp, &lim, None);
        assert!(
            (tp.duration() - reference.duration()).abs() < 1e-9,
            "v_max = {v_max}: {} s vs {} s",
            tp.duration(),
            reference.duration()
        );
    }
    // a start speed whose square overflows names v_start
    let e = time_parameterize_curve(&p, &limits(), None, 1e200, 0.0).unwrap_err();
    assert!(e.to_string().contains("v_start"), "{e}");
}

#[test]
fn errors_are_reported() {
    let m = map("nav2/tb3_sandbox.yaml");
    let cs = cspace(&m, 0.12);
    let (start, goal) = ([-2.0, -0.5, 0.0], [2.0, 0.55, PI / 2.0]);
    let s = m.world_to_cell("start", start[0], start[1]).unwrap();
    let g = m.world_to_cell("goal", goal[0], goal[1]).unwrap();
    let cells = astar(&cs, s, g).unwrap().unwrap().cells;
    let opts = SmoothOptions::new(4.0);
    let err = |st: [f64; 3], gl: [f64; 3], o: &SmoothOptions| {
        smooth_diff_drive(&cs, &m, &cells, st, gl, o)
            .unwrap_err()
            .to_string()
    };
    assert!(err([f64::NAN, 0.0, 0.0], goal, &opts).contains("non-finite"));
    assert!(err(start, [2.0, 0.55, f64::INFINITY], &opts).contains("non-finite"));
    for bad in [0.0, -1.0, f64::NAN] {
        let mut o = opts;
        o.kappa_max = bad;
        assert!(err(start, goal, &o).contains("kappa_max"));
        let mut o = opts;
        o.ds = bad;
        assert!(err(start, goal, &o).contains("ds"));
    }
    assert!(
        err([0.0, 0.0, 0.0], goal, &opts).contains("obstacle"),
        "start on the pillar"
    );
    assert!(err([20.0, 0.0, 0.0], goal, &opts).contains("outside"));
    assert!(smooth_diff_drive(&cs, &m, &[], start, goal, &opts).is_err());
    // a wide turn radius cannot pass between the pillars
    let e = err(start, goal, &SmoothOptions::new(0.5));
    assert!(e.contains("no feasible smooth path"), "{e}");
    // a goal just ahead facing back cannot be reached driving forwards without a loop
    let e = err(start, [-1.9, -0.5, PI], &opts);
    assert!(e.contains("no feasible smooth path"), "{e}");

    let p = SmoothPath::from_curvature([0.0, 0.0, 0.0], &[(1.0, 0.0, 0.0)], 0.02).unwrap();
    let lim = limits();
    for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        for k in 0..4 {
            let mut l = lim;
            [
                &mut l.v_max,
                &mut l.omega_max,
                &mut l.a_max,
                &mut l.alpha_max,
            ][k]
                .clone_from(&bad);
            assert!(time_parameterize_curve(&p, &l, None, 0.0, 0.0).is_err());
        }
    }
    let tip = TipOverAcceleration {
        forward: 1.0,
        backward: 0.0,
        left: 1.0,
        right: 1.0,
    };
    assert!(time_parameterize_curve(&p, &lim, Some(&tip), 0.0, 0.0).is_err());
    let tip = TipOverAcceleration {
        backward: f64::NAN,
        ..tip
    };
    assert!(time_parameterize_curve(&p, &lim, Some(&tip), 0.0, 0.0).is_err());
    for v in [-0.1, f64::NAN] {
        assert!(time_parameterize_curve(&p, &lim, None, v, 0.0).is_err());
        assert!(time_parameterize_curve(&p, &lim, None, 0.0, v).is_err());
    }
    assert!(SmoothPath::from_curvature([0.0, 0.0, 0.0], &[(-1.0, 0.0, 0.0)], 0.02).is_err());
    assert!(SmoothPath::from_curvature([0.0, 0.0, 0.0], &[(1e9, 0.0, 0.0)], 1e-6).is_err());
    let tp = time_parameterize_curve(&p, &lim, None, 0.0, 0.0).unwrap();
    assert!(tp.samples(0.0).is_err() && tp.samples(1e-12).is_err());
}

#[test]
fn replan_on_the_map_continues_without_stopping() {
    // Drive part of a timed path, then re-plan from the robot's exact pose and speed (a
    // new grid path from its cell): the new path starts where the robot is, along its
    // heading, without a turn in place, and its timing starts at the robot's speed.
    let m = map("nav2/tb3_sandbox.yaml");
    let cs = cspace(&m, 0.12);
    let opts = SmoothOptions::new(4.0);
    let (start, goal) = ([-2.0, -0.5, 0.0], [2.0, 0.55, PI / 2.0]);
    let p = plan(&m, &cs, start, goal, &opts).unwrap();
    let lim = limits();
    let tp = time_parameterize_curve(&p, &lim, None, 0.0, 0.0).unwrap();
    let mut continued = 0;
    for frac in [0.2, 0.35, 0.5, 0.7] {
        let now = tp.sample(frac * tp.duration());
        assert!(now.v > 0.1);
        let pose = [now.x, now.y, now.theta];
        let Ok(q) = plan(&m, &cs, pose, goal, &opts) else {
            continue;
        };
        check_path(&q, &m, &cs, pose, goal, 4.0);
        if q.pivot() != 0.0 {
            continue;
        }
        continued += 1;
        let tq = time_parameterize_curve(&q, &lim, None, now.v, 0.0).unwrap();
        let k = tq.knots();
        assert_eq!(k[0].v, now.v);
        if tq.overspeed_until().is_none() {
            check_timing(&tq, &lim, None);
        }
        assert!(
            k[1..k.len() - 1].iter().all(|q| q.v > 0.0),
            "no stop on the way"
        );
    }
    assert!(
        continued >= 3,
        "only {continued} of 4 re-plans continued without stopping"
    );
}

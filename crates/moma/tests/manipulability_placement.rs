//! Base-placement maps on an analytic planar arm: reachability must match the arm's
//! reach circle, the best placement must be reachable and have the best measure, the
//! whole-body measure must dominate the arm's, and bad grids must be errors.

mod ik_common;

use ik_common::PlanarChain;
use moma::ik::IkOptions;
use moma::ik::placement::{ArmReachEvaluator, MeasureScope, PlacementGrid, placement_map};
use moma::ik::tasks::TaskRows;
use moma::manipulability::Measure;
use moma::mobile::DiffDrive;
use moma::mobile::whole_body::BaseInputs;
use nalgebra::{DVector, Isometry3};

fn evaluator(scope: MeasureScope, measure: Measure) -> ArmReachEvaluator<PlanarChain> {
    let mut arm = PlanarChain::arm(vec![0.5, 0.4]);
    arm.lower = vec![-3.1; 2];
    arm.upper = vec![3.1; 2];
    ArmReachEvaluator {
        arm,
        mount: Isometry3::translation(0.2, 0.0, 0.0),
        target: Isometry3::translation(1.0, 0.5, 0.0),
        rows: TaskRows::Rows(vec![0, 1]),
        options: IkOptions {
            tolerance: 1e-9,
            ..IkOptions::default()
        },
        seed: DVector::from_vec(vec![0.3, 1.0]),
        // Joint limits at ±3.1 rad create genuine local minima; restarts escape them.
        restarts: 16,
        measure,
        scope,
    }
}

#[test]
fn reachability_matches_the_reach_annulus() {
    let ev = evaluator(MeasureScope::Arm, Measure::Yoshikawa);
    ev.validate().unwrap();
    let grid = PlacementGrid::new([-0.5, -0.5, 2.0, 1.5], 0.1, 4).unwrap();
    assert_eq!((grid.nx, grid.ny), (26, 21));
    let map = placement_map(&ev, &grid).unwrap();
    assert_eq!(map.samples.len(), grid.len());
    let mut checked = 0;
    for s in &map.samples {
        let [x, y, th] = s.base;
        // Arm base in world, distance to the target.
        let bx = x + 0.2 * th.cos();
        let by = y + 0.2 * th.sin();
        let dist = (1.0 - bx).hypot(0.5 - by);
        // Reach annulus [0.1, 0.9]; only poses within 1 mm of its edges are not judged.
        if dist < 0.899 && dist > 0.101 {
            assert!(s.reachable, "{s:?} dist {dist}");
            let m = s.measure.unwrap();
            // Planar 2R: w = l1 l2 |sin q2| with cos q2 = (d² − l1² − l2²)/(2 l1 l2).
            let c2 = (dist * dist - 0.25 - 0.16) / 0.4;
            let w = 0.2 * (1.0 - c2 * c2).sqrt();
            assert!((m - w).abs() < 1e-6, "{m} vs {w}");
            checked += 1;
        } else if !(0.099..=0.901).contains(&dist) {
            assert!(!s.reachable, "{s:?} dist {dist}");
            assert!(s.measure.is_none());
            assert!(s.residual.is_finite() && s.residual > 0.0);
        }
    }
    assert!(checked > 100);
    let best = map.best.unwrap();
    assert!(best.reachable);
    let bm = best.measure.unwrap();
    assert!(
        map.samples
            .iter()
            .filter_map(|s| s.measure)
            .all(|m| m <= bm)
    );
    // The best pose is the grid pose with the largest analytic w (w peaks at q2 = ±π/2,
    // dist = √(l1² + l2²) = 0.6403, w = 0.2; the grid only comes close).
    let analytic = |s: &moma::ik::placement::PlacementSample| {
        let [x, y, th] = s.base;
        let dist = (1.0 - x - 0.2 * th.cos()).hypot(0.5 - y - 0.2 * th.sin());
        let c2 = (dist * dist - 0.25 - 0.16) / 0.4;
        (c2.abs() <= 1.0).then(|| 0.2 * (1.0 - c2 * c2).sqrt())
    };
    let grid_max = map
        .samples
        .iter()
        .filter_map(analytic)
        .fold(0.0f64, f64::max);
    assert!((bm - grid_max).abs() < 1e-6, "{bm} vs {grid_max}");
    assert!(bm <= 0.2 + 1e-9 && bm > 0.19, "{bm}");
    // Per-cell summary: the best measure over the cell's headings, None if none reaches.
    let cells = map.cell_best(true);
    assert_eq!(cells.len(), grid.nx * grid.ny);
    for (c, best) in cells.iter().enumerate() {
        let here = &map.samples[c * grid.headings..(c + 1) * grid.headings];
        let want = here
            .iter()
            .filter_map(|s| s.measure)
            .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v))));
        assert_eq!(*best, want, "cell {c}");
    }
}

#[test]
fn whole_body_measure_dominates_the_arm_measure() {
    let drive = DiffDrive::new(0.1, 0.25, 0.0).unwrap();
    let arm = evaluator(MeasureScope::Arm, Measure::Yoshikawa);
    let wb = evaluator(
        MeasureScope::WholeBody(drive, BaseInputs::Platform),
        Measure::Yoshikawa,
    );
    let grid = PlacementGrid::new([0.0, 0.0, 1.0, 1.0], 0.25, 3).unwrap();
    let ma = placement_map(&arm, &grid).unwrap();
    let mw = placement_map(&wb, &grid).unwrap();
    let mut n = 0;
    for (a, w) in ma.samples.iter().zip(&mw.samples) {
        assert_eq!(a.reachable, w.reachable);
        if let (Some(x), Some(y)) = (a.measure, w.measure) {
            assert!(y >= x * (1.0 - 1e-9), "{y} < {x}");
            n += 1;
        }
    }
    assert!(n > 5);
    // Smaller-is-better measure: best is the minimum.
    let ecc = evaluator(MeasureScope::Arm, Measure::Eccentricity);
    let me = placement_map(&ecc, &grid).unwrap();
    let b = me.best.unwrap().measure.unwrap();
    assert!(me.samples.iter().filter_map(|s| s.measure).all(|m| m >= b));
}

#[test]
fn bad_grids_are_errors() {
    assert!(PlacementGrid::new([0.0, 0.0, 0.0, 1.0], 0.1, 8).is_err()); // zero width
    assert!(PlacementGrid::new([0.0, 1.0, 1.0, 1.0], 0.1, 8).is_err()); // zero height
    assert!(PlacementGrid::new([1.0, 0.0, 0.0, 1.0], 0.1, 8).is_err()); // reversed
    assert!(PlacementGrid::new([0.0, 0.0, 1.0, 1.0], 0.0, 8).is_err());
    assert!(PlacementGrid::new([0.0, 0.0, 1.0, 1.0], -0.1, 8).is_err());
    assert!(PlacementGrid::new([0.0, 0.0, 1.0, 1.0], 0.1, 0).is_err());
    assert!(PlacementGrid::new([0.0, f64::NAN, 1.0, 1.0], 0.1, 8).is_err());
    assert!(PlacementGrid::new([0.0, 0.0, 1e6, 1e6], 1e-3, 8).is_err()); // too many
    let g = PlacementGrid::new([0.0, 0.0, 1.0, 1.0], 0.1, 8).unwrap();
    assert_eq!((g.nx, g.ny, g.len()), (11, 11, 968));
    let p = g.pose(g.len() - 1);
    assert!((p[0] - 1.0).abs() < 1e-12 && (p[1] - 1.0).abs() < 1e-12);
    let mut ev = evaluator(MeasureScope::Arm, Measure::Yoshikawa);
    ev.seed = DVector::from_vec(vec![0.0]);
    assert!(ev.validate().is_err());
}

/// The map depends on the base pose alone: evaluating every pose on its own, in
/// column-major order with headings reversed and one reused workspace, gives the samples
/// of `placement_map` bit for bit (the IK used to warm-start along grid rows, which drew
/// horizontal stripes of another IK branch in the heat map).
#[test]
fn the_map_does_not_depend_on_the_order_poses_are_visited_in() {
    use moma::ik::model::ModelFrame;
    use moma::ik::placement::PlacementEvaluator;
    use moma::io::urdf::model_from_urdf_file;
    use moma::multibody::RootJoint;
    use std::sync::Arc;
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/manipulability/panda.urdf"
    );
    let model = Arc::new(model_from_urdf_file(path, RootJoint::Fixed).unwrap());
    let arm = ModelFrame::by_name(model.clone(), "panda_hand_tcp").unwrap();
    let drive = DiffDrive::new(0.08, 0.27, 0.12).unwrap();
    for scope in [
        MeasureScope::Arm,
        MeasureScope::WholeBody(drive, BaseInputs::Platform),
    ] {
        let ev = ArmReachEvaluator {
            arm: arm.clone(),
            mount: Isometry3::translation(0.1, 0.0, 0.3),
            target: Isometry3::translation(1.0, 0.5, 0.5),
            rows: TaskRows::Full,
            options: IkOptions::default(),
            seed: moma::kinematics::neutral(&model),
            restarts: 2,
            measure: Measure::Yoshikawa,
            scope,
        };
        let grid = PlacementGrid::new([0.0, -0.5, 2.0, 1.5], 0.25, 4).unwrap();
        let map = placement_map(&ev, &grid).unwrap();
        assert!(map.reachable > 50, "{}", map.reachable);
        let mut ws = ev.workspace();
        let h = grid.headings;
        for ix in 0..grid.nx {
            for iy in 0..grid.ny {
                for k in (0..h).rev() {
                    let index = (iy * grid.nx + ix) * h + k;
                    let alone = ev.evaluate(&mut ws, grid.pose(index)).unwrap();
                    assert_eq!(alone, map.samples[index], "pose {index} ({ix}, {iy}, {k})");
                }
            }
        }
    }
}

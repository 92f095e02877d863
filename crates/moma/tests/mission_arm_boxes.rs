//! The pick's arm motions against the map's boxes (`[[map.boxes]]`): the boxes the robot
//! can reach from a placement join the arm's scene in the map frame, as the mission file
//! places them (not through `task.pose`, which places the task's scene); the placement
//! search, the arm planner and the arm phases' distance monitor measure them. On the
//! shipped pick mission with a bracket where the arm's straight approach passes, the
//! approach goes round it, and the monitor reports its smallest distance to it.

use moma::mission::arm_scene::robot_reach;
use moma::mission::task::{DistanceMonitor, Holding};
use moma::mission::{run, scenario};
use moma::multibody::Data;
use nalgebra::DVector;
use std::path::{Path, PathBuf};

fn mission_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenarios/mission_fetch_pick.toml")
}

/// The shipped pick mission with `boxes` (`[[map.boxes]]` tables) on the map and the
/// task's scene at `task_pose`.
fn with_boxes(boxes: &str, task_pose: &str) -> moma::mission::Mission {
    let path = mission_path();
    let text = std::fs::read_to_string(&path).unwrap();
    let map = "file = \"maps/depot.yaml\"\n";
    let pose = "pose = [5.0, 8.0, 0.0]";
    assert!(text.contains(map) && text.contains(pose));
    let text = text
        .replace(map, &format!("{map}\n{boxes}\n"))
        .replace(pose, &format!("pose = {task_pose}"));
    let f = scenario::parse_file(&text, &path).unwrap();
    scenario::from_file(f, &path, path.parent().unwrap()).unwrap()
}

/// `map.boxes[0]`: near the pick, turned by 0.2 rad. `map.boxes[1]`: at (0.5, 0) on the
/// map, 9.6 m from the grasp; placed wrongly through `task.pose` [5.0, 8.0, 0.3] it would
/// stand at (5.478, 8.148), beside the grasp.
const TWO_BOXES: &str = "[[map.boxes]]\npose = [5.05, 8.05, 0.2]\nsize = [0.3, 0.1]\nz = [0.70, 0.78]\n\n\
                         [[map.boxes]]\npose = [0.5, 0.0, 0.0]\nsize = [0.2, 0.2]\nz = [1.5, 1.6]\n";

#[test]
fn the_arm_scene_holds_the_boxes_near_the_pick_where_the_map_places_them() {
    let m = with_boxes(TWO_BOXES, "[5.0, 8.0, 0.3]");
    let task = m.task.as_ref().unwrap();
    let ids: Vec<&str> = task.boxes.iter().map(|o| o.id.as_str()).collect();
    assert_eq!(ids, ["map.boxes[0]"]);
    // map.boxes[0] from the mission file, by hand: centre (5.05, 8.05) at the middle of
    // z 0.70-0.78, yaw 0.2 rad (cos 0.980067, sin 0.198669), half sides 0.15, 0.05, 0.04
    let [shape] = task.boxes[0].shapes.as_slice() else {
        panic!("one shape")
    };
    let t = shape.pose.translation;
    assert!(
        (t - nalgebra::Vector3::new(5.05, 8.05, 0.74)).norm() < 1e-12,
        "{t}"
    );
    let r = shape.pose.rotation;
    let (c, s) = (0.980_066_577_841_241_6, 0.198_669_330_795_061_2);
    let by_hand = nalgebra::Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0);
    assert!((r - by_hand).norm() < 1e-12, "{r}");
    match &shape.shape {
        moma::collision::Convex::Box { half } => {
            assert!((half - nalgebra::Vector3::new(0.15, 0.05, 0.04)).norm() < 1e-12)
        }
        other => panic!("{other:?}"),
    }
    // the wrongly placed map.boxes[1] would lie within reach of the grasp; where the map
    // places it, it does not
    let reach = robot_reach(&m.robot.model, &task.carried, task.grasp.frame);
    let g = task.grasp.target.translation.vector;
    let wrong = nalgebra::Vector2::new(5.0 + 0.5 * 0.3f64.cos(), 8.0 + 0.5 * 0.3f64.sin());
    assert!((wrong - g.xy()).norm() < 2.0 * reach);
    assert!((nalgebra::Vector2::new(0.5, 0.0) - g.xy()).norm() - 0.15 > 2.0 * reach);
    // the arm phases' monitor measures it: the robot at the transport posture with its
    // base centred on the box (under it) is at the box's distance
    let mut q = vec![0.0; m.robot.model.nq];
    q[..3].copy_from_slice(&[5.05, 8.05, 0.0]);
    for (&i, &a) in m.robot.arm_dofs().iter().zip(&m.transport) {
        q[i] = a;
    }
    let mut dm = DistanceMonitor::new(task, &m.robot);
    let (d, _) = dm.sample(task, &m.robot, &q, Holding::Nothing);
    assert!(d < 0.0, "{d}");
    let why = dm.touch(task).unwrap();
    assert!(why.contains("touches map box 'map.boxes[0]'"), "{why}");
    assert_eq!(dm.min_box.as_ref().unwrap().1[1], "map.boxes[0]");
}

/// Every point of the robot holding the can lies within [`robot_reach`] of the base
/// frame's origin, at configurations spread over the joint box.
#[test]
fn the_robot_reach_bounds_every_point_of_the_robot() {
    use moma::collision::{GeometryData, update_geometry_placements};
    let m = with_boxes("", "[5.0, 8.0, 0.0]");
    let task = m.task.as_ref().unwrap();
    let gm = &task.carried;
    let model = &m.robot.model;
    let reach = robot_reach(model, gm, task.grasp.frame);
    let mut data = Data::new(model);
    let mut gd = GeometryData::new(gm);
    let mut farthest: f64 = 0.0;
    for k in 0..64 {
        let mut q = vec![0.0; model.nq];
        for (n, &i) in m.robot.arm_dofs().iter().enumerate() {
            let (lo, hi) = (model.lower_position_limit[i], model.upper_position_limit[i]);
            let (lo, hi) = if lo.is_finite() && hi.is_finite() {
                (lo, hi)
            } else {
                (-std::f64::consts::PI, std::f64::consts::PI)
            };
            // a low-discrepancy point of the joint box, its corners included
            let s = ((k * (2 * n + 1) * 7 + n * 3) % 64) as f64 / 63.0;
            q[i] = lo + s * (hi - lo);
        }
        moma::kinematics::forward_kinematics(model, &mut data, &DVector::from_column_slice(&q));
        update_geometry_placements(gm, &data, &mut gd);
        for (o, p) in gm.objects.iter().zip(&gd.placements) {
            let far = p.act_point(&o.bounding_centre).norm() + o.bounding_radius;
            farthest = farthest.max(far);
        }
    }
    eprintln!("farthest {farthest} m, reach {reach} m");
    assert!(
        farthest <= reach && farthest > 0.5 * reach,
        "{farthest} {reach}"
    );
}

/// A bracket between the placement and the shelf, 0.70-0.78 m high, where the forearm
/// and wrist pass as the arm rises from its transport posture to the pre-grasp. The base
/// searched at (5.1, 8.5) only, where the shipped pick stands (the bracket lowers the
/// clearance there, and the search would otherwise rank another pose first), and the
/// run ends after the pick (no `[goal]`).
const BRACKET: &str =
    "[[map.boxes]]\npose = [5.05, 8.05, 0.0]\nsize = [0.3, 0.1]\nz = [0.70, 0.78]\n";

/// The whole pick with the bracket: the straight joint-space line from where the approach
/// starts to where it ends meets the bracket (the monitor names it and the link), the
/// planned approach goes round it, and the arm phases' monitor reports its smallest
/// distance to it, positive.
#[test]
fn the_arm_goes_round_a_map_box_in_its_straight_path_and_reports_its_distance() {
    let path = mission_path();
    let text = std::fs::read_to_string(&path).unwrap();
    let (map, area, goal) = (
        "file = \"maps/depot.yaml\"\n",
        "area = [4.5, 7.4, 5.1, 8.6]",
        "[goal]\npose = [9.0, 8.0, 0.0]\n",
    );
    assert!(text.contains(map) && text.contains(area) && text.contains(goal));
    let text = text
        .replace(map, &format!("{map}\n{BRACKET}\n"))
        .replace(area, "area = [5.1, 8.5, 5.15, 8.55]")
        .replace(goal, "");
    let f = scenario::parse_file(&text, &path).unwrap();
    let m = scenario::from_file(f, &path, path.parent().unwrap()).unwrap();
    let task = m.task.as_ref().unwrap();
    assert_eq!(task.boxes.len(), 1);
    let r = run(&m).unwrap();
    assert!(r.reached, "{:?}", r.reason);
    let tr = r.task.as_ref().unwrap();
    assert!(tr.arm_plans.iter().all(|a| a.solved));
    // the approach's recorded states: its first and its last
    let approach: Vec<&Vec<f64>> = (r.samples.q.iter().zip(&r.samples.phase))
        .filter(|(_, p)| **p == "approach")
        .map(|(q, _)| q)
        .collect();
    let (from, to) = (approach[0], *approach.last().unwrap());
    // the straight line between them in the arm's joints touches the bracket (measured
    // against the bracket alone: it also passes through the shelf's bottom board)
    let mut bracket_only = task.clone();
    bracket_only.scene.objects.clear();
    let mut straight = DistanceMonitor::new(&bracket_only, &m.robot);
    let mut touch = None;
    for k in 0..=200 {
        let s = k as f64 / 200.0;
        let mut q = from.clone();
        for &i in &task.group.q_index {
            q[i] = from[i] + s * (to[i] - from[i]);
        }
        straight.sample(&bracket_only, &m.robot, &q, Holding::Nothing);
        if let Some(why) = straight.touch(&bracket_only) {
            touch = Some(why);
            break;
        }
    }
    eprintln!("straight: {:?}", straight.min_box);
    let why = touch.expect("the straight approach meets the bracket");
    eprintln!("straight: {why}");
    assert!(
        why.starts_with("link '") && why.contains("' touches map box 'map.boxes[0]' (-"),
        "{why}"
    );
    // the executed motions kept clear of it: the monitor's smallest distance to the
    // bracket, at every control step, positive and no larger than at the recorded
    // approach states
    let (d_box, pair) = (
        tr.min_box_distance.unwrap(),
        tr.closest_box_pair.clone().unwrap(),
    );
    eprintln!(
        "executed: {d_box} m from {pair:?}; scene {:?}",
        tr.min_scene_distance
    );
    assert!(d_box > 0.0 && pair[1] == "map.boxes[0]", "{d_box} {pair:?}");
    let mut at_samples = DistanceMonitor::new(task, &m.robot);
    for q in &approach {
        at_samples.sample(task, &m.robot, q, Holding::Nothing);
    }
    assert!(d_box <= at_samples.min_box.as_ref().unwrap().0 + 1e-9);
    assert!(tr.min_scene_distance.unwrap() <= d_box);
    assert!(tr.min_self_distance.unwrap() > 0.0);
}

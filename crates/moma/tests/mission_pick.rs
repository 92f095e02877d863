//! The shipped pick mission (`scenarios/mission_fetch_pick.toml`): Fetch drives to the
//! placement its planner reaches, grasps Can2 on the bookshelf (the gripper at the grasp
//! by forward kinematics), attaches the can (the ZMP monitor's margin changes at the same
//! state, the drive on is timed under the tip-over limits with it), retreats without
//! touching the scene or itself and drives on to its goal; bad `[task]` input names the
//! field (and the object); a transport posture that holds the grasped can inside the
//! robot is refused at load.

use moma::kinematics::{forward_kinematics, update_frame_placements};
use moma::mission::{load, run, scenario, transport_tip_limits};
use moma::multibody::Data;
use nalgebra::DVector;
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn mission_path() -> PathBuf {
    root().join("scenarios/mission_fetch_pick.toml")
}

/// The pick mission with `from` replaced by `to`, loaded.
fn with(from: &str, to: &str) -> moma::Result<moma::mission::Mission> {
    let path = mission_path();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.contains(from), "{from}");
    let f = scenario::parse_file(&text.replace(from, to), &path)?;
    scenario::from_file(f, &path, path.parent().unwrap())
}

#[test]
fn the_shipped_pick_mission_reaches_picks_and_never_touches() {
    let m = load(&mission_path()).unwrap();
    let r = run(&m).unwrap();
    assert!(r.reached, "{:?}", r.reason);
    let task = m.task.as_ref().unwrap();
    let tr = r.task.as_ref().unwrap();
    // the base stood at the placement it drove to, then drove on to the goal
    let p = tr.placement.as_ref().unwrap();
    assert_eq!(r.goal_pose, m.goal().unwrap().pose);
    assert_eq!(r.plans.len(), 2);
    assert_eq!(r.plans[1].trigger, "drive on");
    let end = r.samples.q.last().unwrap();
    assert!((end[0] - r.goal_pose[0]).hypot(end[1] - r.goal_pose[1]) < 0.1);
    let at_pick = r
        .samples
        .phase
        .iter()
        .position(|&ph| ph == "approach")
        .unwrap();
    let q = &r.samples.q[at_pick];
    assert!((q[0] - p.base[0]).hypot(q[1] - p.base[1]) < 0.05);
    // the drive on was timed under the tip-over limits of the transport posture with the
    // can in hand
    let bare = transport_tip_limits(&m).unwrap();
    assert_ne!(r.tip_limits.forward, bare.forward);
    let area = task.placement.area.unwrap();
    assert!(p.base[0] >= area[0] - 1e-9 && p.base[0] <= area[2] + 1e-9);
    assert!(p.base[1] >= area[1] - 1e-9 && p.base[1] <= area[3] + 1e-9);
    // three arm motions, each solved, in order
    let stages: Vec<&str> = tr.arm_plans.iter().map(|a| a.stage.as_str()).collect();
    assert_eq!(stages, ["approach", "grasp", "retreat"]);
    assert!(tr.arm_plans.iter().all(|a| a.solved && a.checks > 0));
    // the payload is attached after the grasp motion, and the ZMP margin at that state
    // differs with it
    let pay = tr.payload.as_ref().unwrap();
    assert!(pay.t > tr.arm_plans[1].t && pay.t <= tr.arm_plans[2].t);
    let (without, with) = (
        pay.zmp_margin_without.unwrap(),
        pay.zmp_margin_with.unwrap(),
    );
    assert!(without > 0.0 && with > 0.0);
    assert!((with - without).abs() > 1e-6, "{without} {with}");
    // at the attach the gripper is at the grasp (forward kinematics of the recorded state
    // nearest to it), within the grasp's tolerance and the tracking's settling bound
    let k = r.samples.t.iter().position(|&t| t >= pay.t - 1e-9).unwrap();
    let model = &m.robot.model;
    let mut data = Data::new(model);
    forward_kinematics(
        model,
        &mut data,
        &DVector::from_column_slice(&r.samples.q[k]),
    );
    update_frame_placements(model, &mut data);
    let pose = data.world_from_frame[task.grasp.frame.0].to_isometry();
    let off = (pose.translation.vector - task.grasp.target.translation.vector).norm();
    assert!(off < 0.02, "gripper {off} m from the grasp");
    // the samples after the attach are the retreat's, then the drive on's
    let phases: Vec<&str> = r.samples.phase[k..].to_vec();
    let first_drive = phases.iter().position(|&ph| ph == "drive").unwrap();
    assert!(phases[..first_drive].iter().all(|&ph| ph == "retreat"));
    assert!(
        phases[first_drive..]
            .iter()
            .all(|&ph| ["drive", "arrive", "done"].contains(&ph))
    );
    // never touched: the executed arm motions kept clear of the scene and of itself
    assert!(tr.min_scene_distance.unwrap() > 0.0);
    assert!(tr.min_self_distance.unwrap() > 0.0);
    assert!(r.min_clearance().unwrap() > 0.0);
    assert!(r.min_zmp_margin().unwrap() > 0.0);
}

#[test]
fn a_transport_posture_that_holds_the_can_inside_the_robot_is_refused() {
    // the shipped file's posture before: the wrist flexed to 1.66 rad holds the can,
    // attached at its grasp, 12.2 mm deep in the torso
    let e = with(
        "transport_posture = [0.0, 1.32, 1.40, -0.2, 1.72, 0.0, 1.30, 0.0]",
        "transport_posture = [0.0, 1.32, 1.40, -0.2, 1.72, 0.0, 1.66, 0.0]",
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("robot.transport_posture")
            && e.contains("'Can2' held at its grasp")
            && e.contains("enters 'torso_lift_link' by 12.2 mm"),
        "{e}"
    );
    assert!(e.contains("mission_fetch_pick.toml"), "{e}");
    // the same posture without a [task] carries nothing and loads (mission_fetch.toml's)
    assert!(load(&root().join("scenarios/mission_fetch.toml")).is_ok());
    // the shipped posture (the wrist flexed to 1.30 rad) holds it clear
    assert!(load(&mission_path()).is_ok());
}

#[test]
fn bad_task_input_names_the_field_and_the_object() {
    let err = with("object = \"Can2\"", "object = \"Can9\"")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("task.object") && err.contains("Can9") && err.contains("shelf_bottom"),
        "{err}"
    );
    // the shelf's frame moved so that its boards come within 0.08 m of the start (2.5, 3.0)
    let err = with("pose = [5.0, 8.0, 0.0]", "pose = [1.5, 3.6, 0.0]")
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("task.pose") && err.contains("overlaps the start pose"),
        "{err}"
    );
    assert!(err.contains("scene object 'shelf_bottom'"), "{err}");
    let err = with(
        "pose = [9.0, 8.0, 0.0]",
        "pose = [9.0, 8.0, 0.0]\nend_effector = [9.5, 8.0, 0.8]",
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("goal.end_effector"), "{err}");
    let err = with(
        "mass = 0.35",
        "mass = 0.35\nquery = \"../crates/moma/tests/data/scenes/motion_bench_maker/configs/scenes/bookshelf/hard_queries_small.yaml\"",
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("task.query"), "{err}");
    let err = with("mass = 0.35", "mass = -1.0").unwrap_err().to_string();
    assert!(err.contains("task.mass"), "{err}");
}

#[test]
fn a_query_file_gives_the_grasp_of_its_object() {
    // MotionBenchMaker's bookshelf query grasps Can1: 0.2 m behind it, 5 cm up
    let query = "../crates/moma/tests/data/scenes/motion_bench_maker/configs/scenes/bookshelf/hard_queries_small.yaml";
    let m = with(
        "object = \"Can2\"",
        &format!("object = \"Can1\"\nquery = \"{query}\""),
    );
    // both the query and the grasp offset: refused
    assert!(m.unwrap_err().to_string().contains("task.query"));
    let path = mission_path();
    let text = std::fs::read_to_string(&path).unwrap();
    let start = text.find("grasp = [").unwrap();
    let end = start + text[start..].find('\n').unwrap();
    let text = text.replace(&text[start..end], &format!("query = \"{query}\""));
    let text = text.replace("object = \"Can2\"", "object = \"Can1\"");
    let f = scenario::parse_file(&text, &path).unwrap();
    let m = scenario::from_file(f, &path, path.parent().unwrap()).unwrap();
    let task = m.task.as_ref().unwrap();
    let can = task.scene.objects.iter().find(|o| o.id == "Can1").unwrap();
    let c = can.shapes[0].pose.translation;
    let t = task.grasp.target.translation.vector;
    // the scene's frame is at (5, 8) unrotated
    assert!((t - (c + nalgebra::Vector3::new(-0.2, 0.0, 0.05))).norm() < 1e-12);
    assert!((c.x - 5.9).abs() < 1e-12 && (c.z - 1.08).abs() < 1e-12);
    // the pre-grasp is the approach distance further back along the gripper's x axis
    let pre = task.pre_grasp.target.translation.vector;
    assert!((pre - t - nalgebra::Vector3::new(-0.1, 0.0, 0.0)).norm() < 1e-12);
    // the scene's outline blocks the map under the shelf
    let g = &m.map.grid;
    let (cx, cy) = g.world_to_cell("shelf", 6.0, 8.0).unwrap();
    assert!(g.cells[g.index(cx, cy)] >= 100);
}

/// The pick mission with the shipped scene plus `extra` (MoveIt YAML collision objects,
/// in the scene's frame), written to a fresh folder.
fn with_scene_objects(tag: &str, extra: &str) -> moma::Result<moma::mission::Mission> {
    let dir = std::env::temp_dir().join(format!("moma-pick-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let shipped =
        std::fs::read_to_string(root().join("scenarios/scenes/bookshelf_small_can1.yaml")).unwrap();
    let scene = dir.join("scene.yaml");
    std::fs::write(&scene, format!("{}\n{extra}", shipped.trim_end())).unwrap();
    let path = mission_path();
    let text = std::fs::read_to_string(&path).unwrap().replace(
        "scene = \"scenes/bookshelf_small_can1.yaml\"",
        &format!("scene = {:?}", scene.display().to_string()),
    );
    let f = scenario::parse_file(&text, &path)?;
    scenario::from_file(f, &path, path.parent().unwrap())
}

/// A MoveIt YAML box object.
fn box_yaml(id: &str, size: [f64; 3], at: [f64; 3]) -> String {
    format!(
        "    - header: {{frame_id: base_link}}\n      id: {id}\n      primitives:\n        - type: box\n          dimensions: {size:?}\n      primitive_poses:\n        - position: {at:?}\n          orientation: [0.0, 0.0, 0.0, 1.0]\n"
    )
}

#[test]
fn a_table_top_the_robot_clears_is_left_off_the_map_its_legs_are_not() {
    // a table over the start (2.5, 3.0), the scene's frame at (5, 8): its top at
    // z 1.45-1.5 m, well above Fetch with the arm tucked, and one leg 0.8 m from the start
    let table = |z: f64| {
        box_yaml("table_top", [1.6, 1.6, 0.05], [-2.5, -5.0, z])
            + &box_yaml("table_leg", [0.05, 0.05, 1.45], [-1.8, -5.4, 0.725])
    };
    let m = with_scene_objects("table", &table(1.475)).unwrap();
    let task = m.task.as_ref().unwrap();
    let ids: Vec<&str> = task.scene.objects.iter().map(|o| o.id.as_str()).collect();
    let verdict = |id: &str| task.heights[ids.iter().position(|&i| i == id).unwrap()];
    let (top, leg) = (verdict("table_top"), verdict("table_leg"));
    assert!(!top.blocked && top.clearance > 0.2, "{top:?}");
    assert!(leg.blocked && leg.clearance < 0.0, "{leg:?}");
    // the shelf's boards and sides, at the robot's height, stay obstacles
    assert!(verdict("shelf_bottom").blocked && verdict("side_left").blocked);
    let g = &m.map.grid;
    let cell = |x: f64, y: f64| {
        let (cx, cy) = g.world_to_cell("table", x, y).unwrap();
        g.cells[g.index(cx, cy)]
    };
    // under the top, away from the leg: as free as the map has it
    let bare = load(&mission_path()).unwrap();
    let b = &bare.map.grid;
    for (x, y) in [(2.5, 3.0), (2.0, 2.5), (3.0, 3.5)] {
        let (cx, cy) = b.world_to_cell("table", x, y).unwrap();
        assert_eq!(cell(x, y), b.cells[b.index(cx, cy)], "({x}, {y})");
    }
    assert!(cell(2.5, 3.0) < 100);
    // under the leg: blocked
    assert!(cell(3.2, 2.6) >= 100);
    // the same top at table height (z 0.7-0.75 m) is an obstacle where the robot starts
    let err = with_scene_objects("low-table", &table(0.725))
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("task.pose") && err.contains("'table_top'"),
        "{err}"
    );
}

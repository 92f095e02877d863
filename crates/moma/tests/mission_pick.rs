//! The shipped pick mission (`scenarios/mission_fetch_pick.toml`): Fetch drives to the
//! placement its planner reaches, grasps Can2 on the bookshelf (the gripper at the grasp
//! by forward kinematics), attaches the can (the ZMP monitor's margin changes at the same
//! state, the drive on is timed under the tip-over limits with it), lifts and retreats
//! without touching the scene or itself and drives on to its goal; bad `[task]` input
//! names the field (and the object); a transport posture that holds the grasped can inside
//! the robot is refused at load. After the grasp the can is carried: the distance monitor
//! measures it (naming it on a touch), the retreat is planned with it (a path planned
//! without it would carry it through a lowered shelf board), and the drive on's footprint
//! holds it.

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
    assert_eq!(stages, ["approach", "grasp", "lift", "retreat"]);
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
    assert!(
        phases[..first_drive]
            .iter()
            .all(|&ph| ph == "lift" || ph == "retreat")
    );
    assert!(
        phases[first_drive..]
            .iter()
            .all(|&ph| ["drive", "arrive", "done"].contains(&ph))
    );
    // never touched: the executed arm motions kept clear of the scene and of itself
    assert!(tr.min_scene_distance.unwrap() > 0.0);
    assert!(tr.min_self_distance.unwrap() > 0.0);
    // from the attach on the monitor measured the held can: its distances to the scene
    // (but its support, the board it stands 10 mm into) and to the robot at every
    // retreat sample, computed here on the carrying geometry, are no smaller than the
    // monitor's minima, and the can kept clear
    assert_eq!(task.support, ["shelf_bottom"]);
    assert_eq!(tr.support, ["shelf_bottom"]);
    let retreat: Vec<Vec<f64>> = (k..r.samples.t.len())
        .filter(|&i| r.samples.phase[i] == "retreat")
        .map(|i| r.samples.q[i].clone())
        .collect();
    let (can_scene, can_self) = can_distances_over(&m, &task.scene_after_grasp, &retreat);
    eprintln!(
        "the held can along the retreat: {can_scene} m from the scene, {can_self} m from the robot"
    );
    assert!(can_scene > 0.0 && can_self > 0.0, "{can_scene} {can_self}");
    assert!(tr.min_scene_distance.unwrap() <= can_scene + 1e-9);
    assert!(tr.min_self_distance.unwrap() <= can_self + 1e-9);
    // the drive on went with the footprint that holds the can
    assert_eq!(
        tr.drive_on_footprint_radius,
        Some(task.carrying_footprint.radius)
    );
    assert!(task.carrying_footprint.radius > m.footprint.radius);
    assert!(r.events.iter().any(|e| {
        e.kind == "footprint"
            && e.text
                .starts_with("driving on with 'Can2': the footprint holds it")
    }));
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
    with_scene(tag, |shipped| format!("{}\n{extra}", shipped.trim_end()))
}

/// The pick mission with the shipped scene's text passed through `edit`, written to a
/// fresh folder.
fn with_scene(tag: &str, edit: impl Fn(&str) -> String) -> moma::Result<moma::mission::Mission> {
    with_scene_and_task(tag, edit, "")
}

/// [`with_scene`] with `task_lines` added at the end of the mission's `[task]`.
fn with_scene_and_task(
    tag: &str,
    edit: impl Fn(&str) -> String,
    task_lines: &str,
) -> moma::Result<moma::mission::Mission> {
    let dir = std::env::temp_dir().join(format!("moma-pick-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let shipped =
        std::fs::read_to_string(root().join("scenarios/scenes/bookshelf_small_can1.yaml")).unwrap();
    let scene = dir.join("scene.yaml");
    std::fs::write(&scene, edit(&shipped)).unwrap();
    let path = mission_path();
    let text = std::fs::read_to_string(&path).unwrap().replace(
        "scene = \"scenes/bookshelf_small_can1.yaml\"",
        &format!("scene = {:?}", scene.display().to_string()),
    );
    let text = text.replace("headings = 8\n", &format!("headings = 8\n{task_lines}\n"));
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

/// An open square ring of walls (no floor, no top): 1.2 m square, 0.3 m high, its
/// centre at the origin of its frame, eight triangles, as an OBJ file in `dir`; and the
/// scene object (MoveIt YAML) of it with its centre at `at` (scene frame).
fn ring_yaml(dir: &Path, at: [f64; 3]) -> String {
    let file = dir.join("ring.obj");
    let mut obj = String::new();
    for z in [0.0, 0.3] {
        for (x, y) in [(-0.6, -0.6), (0.6, -0.6), (0.6, 0.6), (-0.6, 0.6)] {
            obj.push_str(&format!("v {x} {y} {z}\n"));
        }
    }
    for k in 0..4 {
        let (a, b) = (k + 1, (k + 1) % 4 + 1);
        obj.push_str(&format!("f {a} {b} {}\nf {a} {} {}\n", b + 4, b + 4, a + 4));
    }
    std::fs::create_dir_all(dir).unwrap();
    std::fs::write(&file, obj).unwrap();
    format!(
        "    - header: {{frame_id: base_link}}\n      id: ring\n      meshes:\n        - resource: {:?}\n      mesh_poses:\n        - position: {at:?}\n          orientation: [0.0, 0.0, 0.0, 1.0]\n",
        file.display().to_string()
    )
}

#[test]
fn a_task_scene_keeps_its_meshes_and_measures_them_exactly_on_request() {
    use moma::collision::{
        Convex, GeometryData, Scene, SceneData, SceneObject, SceneOptions, compute_scene_distances,
        read_scene, update_geometry_placements,
    };
    use moma::spatial::SE3;
    let dir = std::env::temp_dir().join(format!("moma-pick-ring-mesh-{}", std::process::id()));
    // the ring 2 m behind and 2 m right of the shelf's frame: at (3, 6) on the map
    let ring = ring_yaml(&dir, [-2.0, -2.0, 0.0]);
    let add = |shipped: &str| format!("{}\n{ring}", shipped.trim_end());
    let convex = with_scene_and_task("ring-convex", add, "").unwrap();
    let exact = with_scene_and_task("ring-exact", add, "mesh = \"exact\"").unwrap();
    // the base in the ring's middle, the arm at its transport posture
    let mut q = at_posture(&exact, &exact.transport);
    q[..3].copy_from_slice(&[3.0, 6.0, 0.0]);
    let distances = |m: &moma::mission::Mission, scene: &Scene, q: &[f64]| {
        let task = m.task.as_ref().unwrap();
        let model = &m.robot.model;
        let mut data = Data::new(model);
        forward_kinematics(model, &mut data, &DVector::from_column_slice(q));
        let mut gd = GeometryData::new(&task.geometry);
        update_geometry_placements(&task.geometry, &data, &mut gd);
        let mut sd = SceneData::new(&task.geometry, scene);
        compute_scene_distances(&task.geometry, &mut gd, scene, &mut sd);
        let o = scene.objects.iter().position(|o| o.id == "ring").unwrap();
        let no = scene.objects.len();
        (0..task.geometry.links.len())
            .map(|l| sd.results[l * no + o].distance)
            .collect::<Vec<f64>>()
    };
    let task = exact.task.as_ref().unwrap();
    let base = task.geometry.link_index("base_link").unwrap();
    let hull = distances(&convex, &convex.task.as_ref().unwrap().scene, &q);
    let surface = distances(&exact, &task.scene, &q);
    // the hull is a solid block round the base; the walls stand clear of it
    assert!(hull[base] < -0.1, "{}", hull[base]);
    assert!(surface[base] > 0.2, "{}", surface[base]);
    // the walls as four boxes 0.2 µm thick at the same places: the same distances
    let wall = |c: [f64; 2], half: [f64; 2]| {
        (
            SE3::from_translation(nalgebra::Vector3::new(3.0 + c[0], 6.0 + c[1], 0.15)),
            Convex::Box {
                half: nalgebra::Vector3::new(half[0], half[1], 0.15),
            },
        )
    };
    let t = 1e-7;
    let walls = Scene {
        objects: vec![
            SceneObject::new(
                "ring",
                vec![
                    wall([-0.6, 0.0], [t, 0.6]),
                    wall([0.6, 0.0], [t, 0.6]),
                    wall([0.0, -0.6], [0.6, t]),
                    wall([0.0, 0.6], [0.6, t]),
                ],
            )
            .unwrap(),
        ],
    };
    let boxes = distances(&exact, &walls, &q);
    for (l, (a, b)) in surface.iter().zip(&boxes).enumerate() {
        assert!(
            (a - b).abs() < 1e-6,
            "{}: {a} vs {b}",
            task.geometry.links[l].name
        );
    }
    // placing keeps the triangles: the scene as read, in its own frame, with the robot
    // moved by the inverse of the scene's placement measures the same
    let local = read_scene(
        &std::env::temp_dir()
            .join(format!("moma-pick-ring-exact-{}", std::process::id()))
            .join("scene.yaml"),
        &SceneOptions {
            world_frames: vec!["world".into(), "base_link".into()],
            package_dirs: vec![],
        },
    )
    .unwrap()
    .with_mesh_triangles()
    .unwrap();
    let mut q_local = q.clone();
    q_local[..3].copy_from_slice(&[-2.0, -2.0, 0.0]);
    let unplaced = distances(&exact, &local, &q_local);
    for (l, (a, b)) in surface.iter().zip(&unplaced).enumerate() {
        assert!(
            (a - b).abs() < 1e-9,
            "{}: {a} vs {b}",
            task.geometry.links[l].name
        );
    }
    // the convex mission keeps the meshes too (the hulls measure, the triangles ride along)
    let kept = &convex.task.as_ref().unwrap().scene;
    let ring_obj = kept.objects.iter().find(|o| o.id == "ring").unwrap();
    assert!(ring_obj.shapes.iter().all(|s| s.mesh.is_some()));
    // a mode that is not one is refused, naming the field
    let err = with_scene_and_task("ring-bad", add, "mesh = \"hull\"")
        .unwrap_err()
        .to_string();
    assert!(err.contains("task.mesh") && err.contains("'hull'"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// The configuration with the platform at the origin (the base frame on the world frame),
/// the arm joints at `arm` (one per arm dof), the wheels at zero.
fn at_posture(m: &moma::mission::Mission, arm: &[f64]) -> Vec<f64> {
    let mut q = vec![0.0; m.robot.model.nq];
    for (&i, &a) in m.robot.arm_dofs().iter().zip(arm) {
        q[i] = a;
    }
    q
}

/// The world pose of the held can at the configuration `q`: the end effector's pose
/// there composed with the can's pose seen from the grasp (forward kinematics, not the
/// attached geometry).
fn can_pose(m: &moma::mission::Mission, q: &[f64]) -> moma::spatial::SE3 {
    let task = m.task.as_ref().unwrap();
    let model = &m.robot.model;
    let mut data = Data::new(model);
    forward_kinematics(model, &mut data, &DVector::from_column_slice(q));
    update_frame_placements(model, &mut data);
    let ee = data.world_from_frame[task.grasp.frame.0];
    let grasp = moma::spatial::SE3::from_isometry(&task.grasp.target);
    let can = task.scene.objects.iter().find(|o| o.id == "Can2").unwrap();
    ee.compose(&grasp.inverse_compose(&can.shapes[0].pose))
}

#[test]
fn after_the_grasp_the_distance_monitor_measures_the_held_can() {
    use moma::collision::{Convex, SceneObject};
    use moma::mission::task::{DistanceMonitor, Holding};
    let m = load(&mission_path()).unwrap();
    let task = m.task.as_ref().unwrap();
    // a 2 cm cube where the can is at the shipped transport posture (the can 46.6 mm
    // clear of the robot): the robot alone clears it, the held can touches it
    let q = at_posture(&m, &m.transport);
    let cube = SceneObject::new(
        "cube",
        vec![(
            can_pose(&m, &q),
            Convex::Box {
                half: nalgebra::Vector3::repeat(0.01),
            },
        )],
    )
    .unwrap();
    let mut task = task.clone();
    task.scene.objects.push(cube.clone());
    task.scene_after_grasp.objects.push(cube);
    let mut dm = DistanceMonitor::new(&task, &m.robot);
    let (d_bare, _) = dm.sample(&task, &m.robot, &q, Holding::Nothing);
    assert!(d_bare > 0.02 && dm.touch(&task).is_none(), "{d_bare}");
    let (d_held, _) = dm.sample(&task, &m.robot, &q, Holding::Carrying);
    assert!(d_held < -0.01, "{d_held}");
    let why = dm.touch(&task).unwrap();
    assert!(
        why.starts_with("held object 'Can2' touches scene object 'cube'"),
        "{why}"
    );
    assert_eq!(
        dm.min_scene.as_ref().unwrap().1,
        ["Can2".to_string(), "cube".to_string()]
    );
    // while lifting, the scene the lift checks (its support allowed to touch the can):
    // the cube as the can's support is no touch
    let mut support = task.scene_after_grasp.objects.last().unwrap().clone();
    support.touch_links.push("Can2".into());
    task.scene_lifting.objects.push(support);
    let mut dm = DistanceMonitor::new(&task, &m.robot);
    let (d_lifting, _) = dm.sample(&task, &m.robot, &q, Holding::Lifting);
    assert!(d_lifting > 0.02 && dm.touch(&task).is_none(), "{d_lifting}");
}

#[test]
fn the_drive_on_footprint_holds_the_can_where_it_sticks_out() {
    use moma::mission::{FootprintSource, MissionFootprint};
    let m = load(&mission_path()).unwrap();
    let task = m.task.as_ref().unwrap();
    let (bare, carrying) = (&m.footprint, &task.carrying_footprint);
    let polygon = |f: &MissionFootprint| match &f.source {
        FootprintSource::Robot { polygon, .. } => polygon.clone(),
        FootprintSource::Radius => panic!("the shipped footprint is the robot's"),
    };
    let inside = |poly: &[[f64; 2]], p: [f64; 2]| {
        (0..poly.len()).all(|k| {
            let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
            (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]) >= -1e-12
        })
    };
    // the can's rims at the transport posture (radius 0.03 m, 0.07 m above and below its
    // centre), by forward kinematics: some of it outside the robot's polygon, all of it
    // inside the carrying one
    let can = can_pose(&m, &at_posture(&m, &m.transport));
    let rims: Vec<[f64; 2]> = (0..64)
        .flat_map(|k| {
            let t = std::f64::consts::TAU * f64::from(k) / 64.0;
            [-0.07, 0.07].map(|z| {
                let p = can.act_point(&nalgebra::Vector3::new(0.03 * t.cos(), 0.03 * t.sin(), z));
                [p.x, p.y]
            })
        })
        .collect();
    let (pb, pc) = (polygon(bare), polygon(carrying));
    assert!(rims.iter().any(|&p| !inside(&pb, p)));
    assert!(rims.iter().all(|&p| inside(&pc, p)));
    // the robot's polygon lies inside the carrying one, which is larger
    assert!(pb.iter().all(|&p| inside(&pc, p)));
    assert!(
        carrying.radius > bare.radius + 0.02,
        "{} {}",
        carrying.radius,
        bare.radius
    );
    // where the can lies inside the polygon (a 1.2 m square about the base), the
    // footprint is unchanged; a typed radius stays as typed
    let square = MissionFootprint {
        radius: 0.6f64.hypot(0.6),
        source: FootprintSource::Robot {
            polygon: vec![[-0.6, -0.6], [0.6, -0.6], [0.6, 0.6], [-0.6, 0.6]],
            circumscribed: 0.6f64.hypot(0.6),
            padding: 0.0,
        },
    };
    assert_eq!(
        square.carrying(&m.robot, &task.carried, &m.transport),
        square
    );
    let typed = MissionFootprint::given(0.3);
    assert_eq!(typed.carrying(&m.robot, &task.carried, &m.transport), typed);
}

/// The held can's smallest distance to `scene` and to the robot over the states `qs`
/// (the carrying geometry, the can's own pairs only).
fn can_distances_over(
    m: &moma::mission::Mission,
    scene: &moma::collision::Scene,
    qs: &[Vec<f64>],
) -> (f64, f64) {
    use moma::collision::{
        GeometryData, PairSelection, SceneData, compute_distances, compute_scene_distances,
        update_geometry_placements,
    };
    let gm = &m.task.as_ref().unwrap().carried;
    let can = gm.links.len() - 1;
    let model = &m.robot.model;
    let mut data = Data::new(model);
    let mut gd = GeometryData::new(gm);
    let mut sd = SceneData::new(gm, scene);
    let no = scene.objects.len();
    let (mut to_scene, mut to_robot) = (f64::INFINITY, f64::INFINITY);
    for q in qs {
        forward_kinematics(model, &mut data, &DVector::from_column_slice(q));
        update_geometry_placements(gm, &data, &mut gd);
        compute_distances(gm, &mut gd, PairSelection::Enabled);
        compute_scene_distances(gm, &mut gd, scene, &mut sd);
        for o in 0..no {
            to_scene = to_scene.min(sd.results[can * no + o].distance);
        }
        for (p, pair) in gm.pairs.iter().enumerate() {
            if gm.enabled[p] && pair[1] == can {
                to_robot = to_robot.min(gd.results[p].distance);
            }
        }
    }
    (to_scene, to_robot)
}

#[test]
fn the_retreat_is_planned_with_the_held_can() {
    use moma::motion::plan::{MotionGoal, MotionOptions, MotionProblem, MotionResult, plan_motion};
    // the shelf's top board 3 cm lower (its centre at z 1.27 m, not 1.30 m): the can,
    // lifted, passes close under it on the way out
    let m = with_scene("low-top", |shipped| {
        let board = "        - position: [1.0, 0.0, 1.3]";
        assert_eq!(shipped.matches(board).count(), 1);
        shipped.replace(board, "        - position: [1.0, 0.0, 1.27]")
    })
    .unwrap();
    let r = run(&m).unwrap();
    assert!(r.reached, "{:?}", r.reason);
    let task = m.task.as_ref().unwrap();
    let tr = r.task.as_ref().unwrap();
    // the run's retreat kept the can clear of the board (the monitor's closest pair)
    assert_eq!(
        tr.closest_scene_pair.as_ref().unwrap(),
        &["Can2".to_string(), "shelf_top".to_string()]
    );
    let k = r
        .samples
        .phase
        .iter()
        .position(|&p| p == "retreat")
        .unwrap();
    let retreat: Vec<Vec<f64>> = (k..r.samples.t.len())
        .filter(|&i| r.samples.phase[i] == "retreat")
        .map(|i| r.samples.q[i].clone())
        .collect();
    let (executed, _) = can_distances_over(&m, &task.scene_after_grasp, &retreat);
    assert!(executed > 0.0, "{executed}");
    // the same retreat planned again from the state the lift ended in, with the can and
    // without it: the path planned without it carries it through the board
    let g = &task.group;
    let mut start = r.samples.q[k - 1].clone();
    for (j, &i) in g.q_index.iter().enumerate() {
        start[i] = start[i].clamp(g.lower[j], g.upper[j]);
    }
    let mut goal = start.clone();
    for (a, &i) in m.robot.arm_dofs().iter().enumerate() {
        if g.q_index.contains(&i) {
            goal[i] = m.transport[a];
        }
    }
    let mut options = MotionOptions::new(g.dim());
    options.time_limit = std::time::Duration::from_secs_f64(task.planning_time);
    options.margin = moma::mission::task::ARM_MARGIN;
    // Uniform samples: their retreat passes the can 7.6 mm from the top board, closer than
    // any pair of the robot, so the plan's closest pair shows that it counts the can.
    options.search_local_share = 0.0;
    let plan = |geometry| {
        let problem = MotionProblem {
            model: &m.robot.model,
            geometry,
            scene: &task.scene_after_grasp,
            group: g,
        };
        let out =
            plan_motion(&problem, &start, &MotionGoal::State(goal.clone()), &options).unwrap();
        assert!(out.not_solved.is_none(), "{:?}", out.not_solved);
        out
    };
    let states = |o: &MotionResult| {
        let mut qs = o.path.clone();
        qs.extend(o.trajectory.as_ref().unwrap().q.iter().cloned());
        qs
    };
    let with = plan(&task.carried);
    let without = plan(&task.geometry);
    let (with_scene, with_robot) = can_distances_over(&m, &task.scene_after_grasp, &states(&with));
    let (without_scene, _) = can_distances_over(&m, &task.scene_after_grasp, &states(&without));
    eprintln!(
        "the can: {executed} m from the scene along the executed retreat; planned with it \
         {with_scene} m, without it {without_scene} m"
    );
    assert!(without_scene < 0.0, "{without_scene}");
    assert!(with_scene >= 0.5 * options.margin, "{with_scene}");
    // the plan's smallest distance counts the can's pairs
    let closest = with.closest.as_ref().unwrap();
    assert!(closest.distance <= with_scene.min(with_robot) + 1e-12);
    assert_eq!(
        (closest.link.as_str(), closest.other.as_str()),
        ("Can2", "shelf_top")
    );
}

/// The recorded state at the payload attach of the shipped pick (the grasp), and the
/// mission.
fn grasp_state() -> (moma::mission::Mission, Vec<f64>) {
    let m = load(&mission_path()).unwrap();
    let r = run(&m).unwrap();
    assert!(r.reached, "{:?}", r.reason);
    let pay = r.task.as_ref().unwrap().payload.as_ref().unwrap().t;
    let k = r.samples.t.iter().position(|&t| t >= pay - 1e-9).unwrap();
    let q = r.samples.q[k].clone();
    (m, q)
}

/// `q` with the torso lift joint moved by `dz` (m): the held can moves straight up by it.
fn torso_by(m: &moma::mission::Mission, q: &[f64], dz: f64) -> Vec<f64> {
    let model = &m.robot.model;
    let j = model
        .names
        .iter()
        .position(|n| n == "torso_lift_joint")
        .unwrap();
    let mut q = q.to_vec();
    q[model.idx_q[j]] += dz;
    q
}

#[test]
fn a_lift_that_pushes_the_can_into_its_support_or_drags_it_along_it_is_a_touch() {
    use moma::collision::{Convex, SceneObject};
    use moma::mission::task::{DistanceMonitor, Holding};
    let (m, q) = grasp_state();
    let task = m.task.as_ref().unwrap();
    // the lift's first sample is the grasp: no touch; the can rises 3 cm: still none
    let mut dm = DistanceMonitor::new(task, &m.robot);
    dm.sample(task, &m.robot, &q, Holding::Lifting);
    assert!(dm.touch(task).is_none(), "{:?}", dm.touch(task));
    dm.sample(task, &m.robot, &torso_by(&m, &q, 0.03), Holding::Lifting);
    assert!(dm.touch(task).is_none(), "{:?}", dm.touch(task));
    // pressed 1.5 cm down from the grasp instead: into the board it stands on
    let mut dm = DistanceMonitor::new(task, &m.robot);
    dm.sample(task, &m.robot, &q, Holding::Lifting);
    dm.sample(task, &m.robot, &torso_by(&m, &q, -0.015), Holding::Lifting);
    let why = dm.touch(task).expect("pressed into its support");
    assert!(
        why.starts_with("held object 'Can2' enters its support 'shelf_bottom'"),
        "{why}"
    );
    // a wall 1 mm beyond the can (world +x, the side away from the gripper), part of
    // its support: lifting 3 cm straight up drags the can along it
    let can = can_pose(&m, &q);
    let wall = SceneObject::new(
        "wall",
        vec![(
            moma::spatial::SE3::from_translation(
                can.translation + nalgebra::Vector3::new(0.031 + 0.005, 0.0, 0.0),
            ),
            Convex::Box {
                half: nalgebra::Vector3::new(0.005, 0.05, 0.06),
            },
        )],
    )
    .unwrap();
    let mut task = task.clone();
    task.scene.objects.push(wall.clone());
    task.support.push("wall".into());
    task.scene_after_grasp.objects.push(wall.clone());
    let mut lifting = wall;
    lifting.touch_links.push("Can2".into());
    task.scene_lifting.objects.push(lifting);
    let mut dm = DistanceMonitor::new(&task, &m.robot);
    dm.sample(&task, &m.robot, &q, Holding::Lifting);
    assert!(dm.touch(&task).is_none(), "{:?}", dm.touch(&task));
    dm.sample(&task, &m.robot, &torso_by(&m, &q, 0.01), Holding::Lifting);
    assert!(dm.touch(&task).is_none(), "{:?}", dm.touch(&task));
    dm.sample(&task, &m.robot, &torso_by(&m, &q, 0.03), Holding::Lifting);
    let why = dm.touch(&task).expect("dragged along the wall");
    assert!(
        why.starts_with("held object 'Can2' is still on its support 'wall'"),
        "{why}"
    );
}

#[test]
fn the_distance_monitor_sees_every_control_step_of_the_arm_motions() {
    use moma::mission::task::DistanceMonitor;
    // recorded every 0.5 s (250 control steps): the monitor's smallest distances are
    // those of every step, below those of the recorded samples
    let m = with(
        "[limits]",
        "[simulation]\nrecord_interval = 0.5\n\n[limits]",
    )
    .unwrap();
    let r = run(&m).unwrap();
    assert!(r.reached, "{:?}", r.reason);
    let task = m.task.as_ref().unwrap();
    let tr = r.task.as_ref().unwrap();
    let mut dm = DistanceMonitor::new(task, &m.robot);
    let mut arm_samples = 0;
    for (q, holding) in arm_states(&r) {
        arm_samples += 1;
        dm.sample(task, &m.robot, q, holding);
    }
    let (at_samples, every_step) = (
        dm.min_scene.as_ref().unwrap().0,
        tr.min_scene_distance.unwrap(),
    );
    let (self_samples, self_steps) = (
        dm.min_self.as_ref().unwrap().0,
        tr.min_self_distance.unwrap(),
    );
    eprintln!(
        "{arm_samples} arm samples: scene {at_samples} m at them, {every_step} m at every \
         step; self {self_samples} m, {self_steps} m"
    );
    assert!(every_step < at_samples - 1e-4, "{every_step} {at_samples}");
    assert!(self_steps <= self_samples, "{self_steps} {self_samples}");
}

/// The monitor's step measures a state only when the motion since its last sample could
/// have brought a distance down to the minima so far. Over the recorded states of the
/// shipped pick's arm motions it skips some, and after every state its minima are those
/// of a monitor that samples every state.
#[test]
fn the_distance_monitor_step_skips_only_states_that_cannot_lower_the_minima() {
    use moma::mission::task::DistanceMonitor;
    let m = load(&mission_path()).unwrap();
    let r = run(&m).unwrap();
    assert!(r.reached, "{:?}", r.reason);
    let task = m.task.as_ref().unwrap();
    let mut stepped = DistanceMonitor::new(task, &m.robot);
    let mut sampled = DistanceMonitor::new(task, &m.robot);
    let mut states = 0;
    for (q, holding) in arm_states(&r) {
        states += 1;
        stepped.step(task, &m.robot, q, holding);
        sampled.sample(task, &m.robot, q, holding);
        // equal up to GJK's tolerance: the skipped states leave the two monitors'
        // warm starts at different states
        for (a, b) in [
            (&stepped.min_scene, &sampled.min_scene),
            (&stepped.min_self, &sampled.min_self),
        ] {
            let (a, b) = (a.as_ref().unwrap(), b.as_ref().unwrap());
            assert!(
                (a.0 - b.0).abs() < 1e-9 && a.1 == b.1,
                "state {states}: {a:?} {b:?}"
            );
        }
    }
    assert!(
        stepped.skipped > states / 10 && stepped.skipped < states,
        "{} of {states} states skipped",
        stepped.skipped
    );
    assert_eq!(sampled.skipped, 0);
}

/// The drives, to the placement and on from it, have their own distance monitor of the
/// robot against the scene, run at every control step: its minimum is at or below that of
/// the recorded drive samples measured afresh, and above it less the most the base can move
/// between two samples.
#[test]
fn the_drives_distances_are_monitored_at_every_control_step() {
    use moma::mission::task::{DistanceMonitor, Holding};
    let m = load(&mission_path()).unwrap();
    let r = run(&m).unwrap();
    assert!(r.reached, "{:?}", r.reason);
    let task = m.task.as_ref().unwrap();
    let driving = r.task.as_ref().unwrap().driving.clone().expect("monitored");
    let mut dm = DistanceMonitor::scene_only(task, &m.robot, &m.box_objects);
    let (mut grasped, mut before, mut after) = (false, 0, 0);
    for (q, &phase) in r.samples.q.iter().zip(&r.samples.phase) {
        grasped |= phase == "lift";
        if matches!(phase, "drive" | "arrive") {
            let holding = if grasped {
                after += 1;
                Holding::Carrying
            } else {
                before += 1;
                Holding::Nothing
            };
            dm.sample(task, &m.robot, q, holding);
        }
    }
    assert!(
        before > 100 && after > 100,
        "{before} {after} drive samples"
    );
    assert!(dm.min_self.is_none());
    let at_samples = dm.scene_minimum().unwrap();
    eprintln!("every step {driving:?}\nat the samples {at_samples:?}");
    // between two samples (0.02 s) at most 0.8 m/s and 1 rad/s (the mission's limits) move
    // no point of the robot within 1 m of its base by more than 0.04 m
    let (every, sampled) = (driving.min_scene_distance, at_samples.min_scene_distance);
    assert!(every > 0.0 && every <= sampled + 1e-9 && every > sampled - 0.04);
}

/// The recorded states of a run's arm motions with what the robot holds in each.
fn arm_states(
    r: &moma::mission::MissionResult,
) -> impl Iterator<Item = (&Vec<f64>, moma::mission::task::Holding)> {
    use moma::mission::task::Holding;
    r.samples
        .q
        .iter()
        .zip(&r.samples.phase)
        .filter_map(|(q, phase)| {
            let holding = match *phase {
                "approach" | "grasp" => Holding::Nothing,
                "lift" => Holding::Lifting,
                "retreat" => Holding::Carrying,
                _ => return None,
            };
            Some((q, holding))
        })
}

/// The pick mission with the arm's transport posture `posture` (e.g. [`RAISED`] or
/// [`OVERHEAD`], holding the can above Fetch's head) and `boxes` (`[[map.boxes]]` tables)
/// on the map.
fn with_posture_and_boxes(posture: &str, boxes: &str) -> moma::Result<moma::mission::Mission> {
    let path = mission_path();
    let text = std::fs::read_to_string(&path).unwrap();
    let shipped = "transport_posture = [0.0, 1.32, 1.40, -0.2, 1.72, 0.0, 1.30, 0.0]";
    let map = "file = \"maps/depot.yaml\"\n";
    assert!(text.contains(shipped) && text.contains(map));
    let text = text
        .replace(shipped, &format!("transport_posture = {posture}"))
        .replace(map, &format!("{map}\n{boxes}\n"));
    let f = scenario::parse_file(&text, &path)?;
    scenario::from_file(f, &path, path.parent().unwrap())
}

/// Torso down, the arm turned to the right (away from the shelf at the placement) and
/// raised, the gripper pointing up: the held can stands above every link of the robot.
const RAISED: &str = "[0.0, -1.57, -1.2, 0.0, -1.0, 0.0, -0.9, 0.0]";

/// A beam across the drive on's way from the shelf (5, 8) to the goal (9, 8): x 7.4–7.8,
/// y 6.5–9.5 (or `y` wide), over the raised arm's top and under the held can's.
fn beam(y: f64) -> String {
    format!("[[map.boxes]]\npose = [7.6, 8.0, 0.0]\nsize = [0.4, {y}]\nz = {BEAM_Z}\n")
}

const BEAM_Z: &str = "[1.47, 1.6]";

#[test]
fn the_drive_on_map_blocks_a_beam_that_only_the_held_can_would_hit() {
    let m = with_posture_and_boxes(RAISED, &beam(3.0)).unwrap();
    // the robot alone passes under the beam: it is not on the mission's map
    let bare = m.boxes[0];
    assert!(!bare.blocked && bare.clearance > 0.0, "{bare:?}");
    let g = &m.map.grid;
    let cell = |g: &moma::planning::OccupancyGrid, x: f64, y: f64| {
        let (cx, cy) = g.world_to_cell("beam", x, y).unwrap();
        g.cells[g.index(cx, cy)]
    };
    assert!(cell(g, 7.6, 8.0) < 100);
    // holding the can it does not: the drive on's map blocks the beam
    let drive_on = m.drive_on_map.as_ref().unwrap();
    assert_eq!(drive_on.blocks.len(), 1, "{:?}", drive_on.blocks);
    let b = &drive_on.blocks[0];
    assert_eq!(b.name, "map.boxes[0]");
    assert_eq!(b.bare, bare);
    assert!(b.holding.blocked && b.holding.clearance < 0.0, "{b:?}");
    assert!(cell(&drive_on.grid, 7.6, 8.0) >= 100);
    assert!(cell(&drive_on.grid, 7.6, 6.6) >= 100 && cell(&drive_on.grid, 7.6, 6.4) < 100);
    // the map gains the beam's cells and nothing else
    let added = (drive_on.grid.cells.iter().zip(&g.cells))
        .filter(|(a, b)| a != b)
        .count();
    let res = g.resolution;
    assert!(
        added as f64 <= (0.4 / res + 2.0) * (3.0 / res + 2.0),
        "{added} cells"
    );
    // planned for the footprint that holds the can (its circumscribed disk) from in front
    // of the shelf to the goal: on the mission's map under the beam, on the drive on's
    // round its ends
    use moma::planning::pipeline::{
        Frame, PlanFields, PlanRequest, PlanStatus, RobotFootprint, Search, plan,
    };
    let task = m.task.as_ref().unwrap();
    let request = PlanRequest {
        start: [4.0, 8.0],
        start_yaw: None,
        goal_yaw: None,
        goal: m.goal().unwrap().pose[..2].try_into().unwrap(),
        frame: Frame::World,
        unknown_is_obstacle: true,
        footprint: RobotFootprint::Disk(task.carrying_footprint.radius),
        axle_offset: 0.0,
        fields: PlanFields::default(),
        search: Search::Astar,
        turn_cost: 1.0,
        smooth: false,
        timing: None,
        polygon_check: None,
    };
    let under_the_beam = |grid: &moma::planning::OccupancyGrid| {
        let p = plan(grid, &request).unwrap();
        assert_eq!(p.status, PlanStatus::Found);
        p.cells.iter().any(|&(x, y)| {
            let [wx, wy] = grid.cell_to_world(x as f64, y as f64);
            (7.4..=7.8).contains(&wx) && (6.5..=9.5).contains(&wy)
        })
    };
    assert!(under_the_beam(&m.map.grid));
    assert!(!under_the_beam(&drive_on.grid));
}

#[test]
fn a_drive_on_with_no_way_round_the_beam_fails_naming_it() {
    // the beam across the whole map: the robot passes under it to the shelf, but holding
    // the can no way leads to the goal
    let m = with_posture_and_boxes(RAISED, &beam(40.0)).unwrap();
    assert!(!m.boxes[0].blocked);
    let r = run(&m).unwrap();
    assert!(!r.reached);
    let why = r.reason.unwrap();
    assert!(
        why.contains("'map.boxes[0]'") && why.contains("holding 'Can2'"),
        "{why}"
    );
    let tr = r.task.unwrap();
    assert!(tr.payload.is_some(), "failed after the pick");
    // the best-ranked placement puts the can held beside the robot over the shelf's
    // cells, where the drive on could not start: the run stood at one it can leave, and
    // the drive on failed for want of a way round the beam
    assert!(tr.placement.unwrap().rank > 0);
    assert!(why.contains("no collision-free path"), "{why}");
    let ev = r.events.iter().find(|e| e.kind == "heights").unwrap();
    eprintln!("{}", ev.text);
    assert!(
        ev.text.starts_with(
            "holding 'Can2' at the transport posture the robot no longer passes under \
             'map.boxes[0]' (clearance 0.0381 m bare, -0.0462 m holding it)"
        ),
        "{}",
        ev.text
    );
}

/// Torso down, the arm turned to the right, raised and bent back over the robot, the
/// gripper up: the held can stands over the robot, inside its footprint, above every link.
const OVERHEAD: &str = "[0.0, -1.57, -1.2, 0.0, -1.0, 0.0, 0.3, 0.0]";

/// The heights of the beams over [`OVERHEAD`]: above the gripper's top (1.696 m), under
/// the held can's.
const OVERHEAD_BEAM_Z: &str = "[1.70, 1.85]";

/// Two beams at [`OVERHEAD_BEAM_Z`]: `map.boxes[0]` across the drive on's way from the
/// shelf to the goal (x 7.4–7.8, y 6.5–9.5), `map.boxes[1]` across the way from the start
/// to the shelf (y 5.3–5.7, the whole map wide; the drive on, north of it, does not come
/// near it).
fn overhead_beams() -> String {
    format!(
        "[[map.boxes]]\npose = [7.6, 8.0, 0.0]\nsize = [0.4, 3.0]\nz = {OVERHEAD_BEAM_Z}\n\n\
         [[map.boxes]]\npose = [10.0, 5.5, 0.0]\nsize = [40.0, 0.4]\nz = {OVERHEAD_BEAM_Z}\n"
    )
}

/// The drives' distance monitor measures the map's boxes with the task's scene: under
/// the beam the robot's distance is the clearance the load's height check found, its
/// pair the beam's; holding the can there is a touch naming the beam as a map box.
#[test]
fn the_drives_distance_monitor_measures_the_map_boxes() {
    use moma::mission::task::{DistanceMonitor, Holding};
    let m = with_posture_and_boxes(OVERHEAD, &overhead_beams()).unwrap();
    let task = m.task.as_ref().unwrap();
    let bare = m.boxes[1];
    assert!(!bare.blocked && bare.clearance > 0.0, "{bare:?}");
    // the base under the middle of map.boxes[1], far from the shelf
    let mut q = at_posture(&m, &m.transport);
    q[..3].copy_from_slice(&[3.0, 5.5, 0.0]);
    let mut dm = DistanceMonitor::scene_only(task, &m.robot, &m.box_objects);
    let (d, _) = dm.sample(task, &m.robot, &q, Holding::Nothing);
    eprintln!(
        "under the beam {d} m; the load's clearance {} m",
        bare.clearance
    );
    assert!((d - bare.clearance).abs() < 1e-4, "{d} {bare:?}");
    assert_eq!(dm.min_scene.as_ref().unwrap().1[1], "map.boxes[1]");
    assert!(dm.touch(task).is_none());
    let (d_held, _) = dm.sample(task, &m.robot, &q, Holding::Carrying);
    assert!(d_held < 0.0, "{d_held}");
    let why = dm.touch(task).unwrap();
    assert!(
        why.starts_with("held object 'Can2' touches map box 'map.boxes[1]' (-"),
        "{why}"
    );
    // the arm motions' monitor measures the boxes within the robot's reach of the pick
    // too (both beams, 1.2 m and 2.2 m from the grasp): the same touch
    let ids: Vec<&str> = task.boxes.iter().map(|o| o.id.as_str()).collect();
    assert_eq!(ids, ["map.boxes[0]", "map.boxes[1]"]);
    let mut arm = DistanceMonitor::new(task, &m.robot);
    let (d_arm, _) = arm.sample(task, &m.robot, &q, Holding::Carrying);
    assert!((d_arm - d_held).abs() < 1e-9, "{d_arm} {d_held}");
    assert_eq!(arm.touch(task), Some(why));
}

/// The drive on's base positions (x, y) of a run: the drive samples after the lift.
fn drive_on_path(r: &moma::mission::MissionResult) -> Vec<[f64; 2]> {
    let lift = r.samples.phase.iter().position(|&p| p == "lift").unwrap();
    (lift..r.samples.t.len())
        .filter(|&i| matches!(r.samples.phase[i], "drive" | "arrive"))
        .map(|i| [r.samples.q[i][0], r.samples.q[i][1]])
        .collect()
}

/// How far `p` lies outside the drive on's beam (x 7.4–7.8, y 6.5–9.5; 0 inside).
fn off_the_beam(p: [f64; 2]) -> f64 {
    let dx = (7.4 - p[0]).max(p[0] - 7.8).max(0.0);
    let dy = (6.5 - p[1]).max(p[1] - 9.5).max(0.0);
    dx.hypot(dy)
}

/// The whole mission with the can held over Fetch's head: the robot drives under a beam
/// to the shelf, picks the can, and drives on round the beam across its straight way
/// that only the held can would hit; the drives' distance monitor, measuring the scene
/// and the beams, sees no touch.
#[test]
fn the_drive_on_goes_round_a_beam_that_only_the_held_can_would_hit() {
    let m = with_posture_and_boxes(OVERHEAD, &overhead_beams()).unwrap();
    assert!(!m.boxes[0].blocked && !m.boxes[1].blocked, "{:?}", m.boxes);
    let drive_on = m.drive_on_map.as_ref().unwrap();
    let blocked: Vec<&str> = drive_on.blocks.iter().map(|b| b.name.as_str()).collect();
    assert_eq!(blocked, ["map.boxes[0]", "map.boxes[1]"]);
    let r = run(&m).unwrap();
    assert!(r.reached, "{:?}", r.reason);
    let tr = r.task.as_ref().unwrap();
    assert!(tr.payload.is_some());
    // the first drive crossed under map.boxes[1] (y 5.3-5.7) bare
    let first: Vec<f64> = (r.samples.q.iter().zip(&r.samples.phase))
        .take_while(|(_, p)| **p != "approach")
        .map(|(q, _)| q[1])
        .collect();
    assert!(first.iter().any(|&y| y < 5.3) && first.iter().any(|&y| y > 5.7));
    // the drive on crossed from the shelf's side of map.boxes[0] to the goal's, round
    // its end: its base never stood under the beam's outline
    let path = drive_on_path(&r);
    assert!(path.iter().any(|p| p[0] < 7.4) && path.iter().any(|p| p[0] > 7.8));
    let nearest = path
        .iter()
        .map(|&p| off_the_beam(p))
        .fold(f64::INFINITY, f64::min);
    eprintln!("the drive on's base came {nearest:.3} m from the beam's outline");
    assert!(nearest > 0.0, "{nearest}");
    // no touch: the drives' smallest distance to the scene and the beams is positive,
    // and no larger than the bare robot's under map.boxes[1]
    let driving = tr.driving.clone().expect("monitored");
    eprintln!(
        "drives: {driving:?}; the load's clearance: {:?}",
        m.boxes[1]
    );
    assert!(driving.min_scene_distance > 0.0);
    assert!(driving.min_scene_distance <= m.boxes[1].clearance + 1e-3);
    assert!(tr.min_scene_distance.unwrap() > 0.0 && tr.min_self_distance.unwrap() > 0.0);
    assert!(r.min_clearance().unwrap() > 0.0);
}

/// The same mission with the drive on's height check left out (its map the mission's,
/// where the robot passes under the beams bare): the drive on takes the straight way
/// under map.boxes[0] and the drives' distance monitor stops the run as the held can
/// touches it.
#[test]
fn without_the_drive_ons_height_check_the_held_can_touches_the_beam() {
    let mut m = with_posture_and_boxes(OVERHEAD, &overhead_beams()).unwrap();
    let drive_on = m.drive_on_map.as_mut().unwrap();
    drive_on.grid = m.map.grid.clone();
    drive_on.blocks.clear();
    let r = run(&m).unwrap();
    assert!(!r.reached);
    let why = r.reason.clone().unwrap();
    eprintln!("{why}");
    assert!(
        why.starts_with("collision: held object 'Can2' touches map box 'map.boxes[0]' ("),
        "{why}"
    );
    assert!(r.task.as_ref().unwrap().payload.is_some());
    let path = drive_on_path(&r);
    assert!(off_the_beam(*path.last().unwrap()) < 0.5, "{path:?}");
}

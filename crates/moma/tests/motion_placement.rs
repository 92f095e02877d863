//! Base placement for a grasp on Fetch among MotionBenchMaker's bookshelf: the best
//! candidate reaches the grasp, is collision-free by the collision module and by coal's
//! distances (Pinocchio + coal reference postures), its tip-over margin is the stability
//! module's with the payload as an external force, the ranking follows the stated rule
//! and does not depend on the thread count, and an unreachable grasp says why.

use moma::collision::{
    GeometryData, GeometryModel, PairSelection, Scene, SceneData, SceneOptions, compute_distances,
    compute_scene_distances, read_scene, update_geometry_placements,
};
use moma::kinematics::{forward_kinematics, update_frame_placements};
use moma::mobile::{read_casters, wheeled_base_from_urdf};
use moma::motion::grasp_query::{grasp_query_from_str, read_grasp_query};
use moma::motion::placement::{
    Payload, PlacementOptions, PlacementProblem, ScoreWeights, place_base,
};
use moma::motion::{GoalPose, JointGroup};
use moma::multibody::{Data, Model, RootJoint, neutral};
use moma::stability::{
    BodySet, ExternalLoads, PointForce, StabilityData, StabilityModel, SupportAttachment,
    SupportPolygon, evaluate,
};
use nalgebra::{DVector, Isometry3, Translation3, UnitQuaternion, Vector3};
use std::path::Path;

const GROUP: [&str; 8] = [
    "torso_lift_joint",
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "upperarm_roll_joint",
    "elbow_flex_joint",
    "forearm_roll_joint",
    "wrist_flex_joint",
    "wrist_roll_joint",
];

mod fetch_common;
use fetch_common::{data_dir, fetch_dir, fetch_geometry};

struct Fetch {
    model: Model,
    gm: GeometryModel,
    group: JointGroup,
    support: SupportPolygon,
}

fn fetch() -> Fetch {
    let (model, gm) = fetch_geometry(RootJoint::Planar);
    let casters = read_casters(&fetch_dir().join("casters.toml")).unwrap();
    let base =
        wheeled_base_from_urdf(&model, &gm, ["l_wheel_joint", "r_wheel_joint"], casters).unwrap();
    let support = SupportPolygon::from_wheeled_base(&base).unwrap();
    let group = JointGroup::new(&model, &GROUP).unwrap();
    Fetch {
        model,
        gm,
        group,
        support,
    }
}

/// The bookshelf scene of the first query, poses in `base_link` (the robot's start at
/// the world origin).
fn bookshelf() -> Scene {
    let dir = data_dir().join("scenes/motion_bench_maker/fetch_queries");
    read_scene(
        &dir.join("scenes/bookshelf_small-Front-Can1-0.yaml"),
        &SceneOptions {
            world_frames: vec!["world".into(), "base_link".into()],
            package_dirs: vec![],
        },
    )
    .unwrap()
}

/// The first query's grasp: 0.2 m behind Can1 (centre (0.9, 0.405…, 1.08)), 5 cm up.
fn grasp(model: &Model) -> GoalPose {
    GoalPose {
        frame: model.frame_id("gripper_link").unwrap(),
        target: Isometry3::from_parts(
            Translation3::new(0.7, 0.4054173266933418, 1.1300000000000001),
            UnitQuaternion::identity(),
        ),
        position_tolerance: 1e-3,
        orientation_tolerance: 1e-2,
    }
}

fn posture(model: &Model) -> Vec<f64> {
    // MotionBenchMaker's Fetch start: torso 0.1, arm tucked.
    let mut q = neutral(model);
    for (name, v) in [
        ("torso_lift_joint", 0.1),
        ("shoulder_pan_joint", 1.32),
        ("shoulder_lift_joint", 1.4),
        ("upperarm_roll_joint", -0.2),
        ("elbow_flex_joint", 1.72),
        ("forearm_roll_joint", 0.0),
        ("wrist_flex_joint", 1.66),
        ("wrist_roll_joint", 0.0),
    ] {
        let j = model.joint_id(name).unwrap().0;
        q[model.idx_q[j]] = v;
    }
    q.as_slice().to_vec()
}

fn options() -> PlacementOptions {
    PlacementOptions {
        area: Some([-0.4, -0.4, 0.6, 1.2]),
        step: 0.1,
        headings: 8,
        ..PlacementOptions::default()
    }
}

const PAYLOAD: Payload = Payload {
    mass: 0.35,
    offset: Vector3::new(0.2, 0.0, -0.05),
};

fn problem<'a>(
    f: &'a Fetch,
    scene: &'a Scene,
    goal: &'a GoalPose,
    posture: &'a [f64],
) -> PlacementProblem<'a> {
    PlacementProblem {
        model: &f.model,
        geometry: &f.gm,
        scene,
        group: &f.group,
        posture,
        support: &f.support,
        grasp: goal,
        payload: PAYLOAD,
    }
}

/// Smallest signed distance (enabled self pairs and scene) of `q` by the collision module.
fn clearance(f: &Fetch, scene: &Scene, q: &[f64]) -> f64 {
    let mut data = Data::new(&f.model);
    let mut gd = GeometryData::new(&f.gm);
    let mut sd = SceneData::new(&f.gm, scene);
    forward_kinematics(&f.model, &mut data, &DVector::from_column_slice(q));
    update_geometry_placements(&f.gm, &data, &mut gd);
    let d_self = compute_distances(&f.gm, &mut gd, PairSelection::Enabled);
    let d_scene = compute_scene_distances(&f.gm, &mut gd, scene, &mut sd);
    d_self.min(d_scene)
}

#[test]
fn the_best_placements_reach_the_grasp_clear_and_upright() {
    let f = fetch();
    let scene = bookshelf();
    let goal = grasp(&f.model);
    let posture = posture(&f.model);
    let opts = options();
    let r = place_base(&problem(&f, &scene, &goal, &posture), &opts).unwrap();
    assert!(r.failure().is_none());
    assert!(r.candidates.len() >= 5, "{:?}", r.counts);
    assert_eq!(r.counts.poses, r.grid.len());
    let mut data = Data::new(&f.model);
    // The payload as an external force: its weight at the object's centre (world).
    let sm = StabilityModel::new(
        &f.model,
        f.support.clone(),
        SupportAttachment::Base,
        &BodySet::All,
    )
    .unwrap();
    let mut stab = StabilityData::new(&sm);
    let zero = DVector::zeros(f.model.nv);
    for (k, c) in r.candidates.iter().take(5).enumerate() {
        let q = DVector::from_column_slice(&c.q);
        assert_eq!(&c.q[..3], &c.base[..], "candidate {k}: base coordinates");
        // Grasp reached: the frame's pose by forward kinematics.
        forward_kinematics(&f.model, &mut data, &q);
        update_frame_placements(&f.model, &mut data);
        let pose = data.world_from_frame[goal.frame.0].to_isometry();
        let dp = (pose.translation.vector - goal.target.translation.vector).norm();
        let dr = pose.rotation.angle_to(&goal.target.rotation);
        assert!(dp <= goal.position_tolerance, "candidate {k}: {dp} m off");
        assert!(
            dr <= goal.orientation_tolerance,
            "candidate {k}: {dr} rad off"
        );
        // Inside the joint box.
        for (i, &iq) in f.group.q_index.iter().enumerate() {
            assert!(f.group.lower[i] <= c.q[iq] && c.q[iq] <= f.group.upper[i]);
        }
        // Clear, by the collision module's distances.
        let d = clearance(&f, &scene, &c.q);
        assert!(d > opts.margin, "candidate {k}: clearance {d}");
        assert!(
            (d - c.clearance).abs() < 1e-9,
            "candidate {k}: {d} vs {}",
            c.clearance
        );
        // Upright: the stability module with the payload's weight as an external force.
        let object = pose * nalgebra::Point3::from(PAYLOAD.offset);
        let forces = [PointForce {
            point: object.coords,
            force: f.model.gravity * PAYLOAD.mass,
        }];
        let loads = ExternalLoads {
            forces: &forces,
            moments: &[],
        };
        let rep = evaluate(
            &f.model, &mut data, &sm, &mut stab, &q, &zero, &zero, &loads,
        );
        let t = rep.zmp_margin.unwrap();
        assert!(
            (t - c.tip_over_margin).abs() < 1e-9,
            "candidate {k}: {t} vs {}",
            c.tip_over_margin
        );
        // Without the payload the margin differs: the mass is really there.
        let bare = evaluate(
            &f.model,
            &mut data,
            &sm,
            &mut stab,
            &q,
            &zero,
            &zero,
            &ExternalLoads::NONE,
        )
        .zmp_margin
        .unwrap();
        assert!(
            (bare - t).abs() > 1e-4,
            "candidate {k}: payload without effect"
        );
    }
    // Ranked best first, scores in (0, 1].
    for w in r.candidates.windows(2) {
        assert!(w[0].score >= w[1].score);
    }
    assert!(r.candidates.iter().all(|c| c.score > 0.0 && c.score <= 1.0));
}

#[test]
fn each_weight_alone_ranks_by_its_measure() {
    let f = fetch();
    let scene = bookshelf();
    let goal = grasp(&f.model);
    let posture = posture(&f.model);
    let mut opts = options();
    opts.max_candidates = 1000;
    for (w, name) in [((1.0, 0.0, 0.0), "m"), ((0.0, 0.0, 1.0), "t")] {
        opts.weights = ScoreWeights {
            manipulability: w.0,
            clearance: w.1,
            tip_over: w.2,
        };
        let r = place_base(&problem(&f, &scene, &goal, &posture), &opts).unwrap();
        let key = |c: &moma::motion::placement::Candidate| {
            if name == "m" {
                c.manipulability
            } else {
                c.tip_over_margin
            }
        };
        let best = key(&r.candidates[0]);
        assert!(r.candidates.len() > 10);
        assert!(r.candidates.iter().all(|c| key(c) <= best), "{name}");
        assert!((r.candidates[0].score - 1.0).abs() < 1e-12);
    }
}

#[test]
fn the_thread_count_does_not_change_the_ranking() {
    let f = fetch();
    let scene = bookshelf();
    let goal = grasp(&f.model);
    let posture = posture(&f.model);
    let mut opts = options();
    opts.area = Some([-0.2, 0.0, 0.3, 0.6]);
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| place_base(&problem(&f, &scene, &goal, &posture), &opts).unwrap())
    };
    let (a, b) = (run(1), run(3));
    assert!(!a.candidates.is_empty());
    assert_eq!(a.counts, b.counts);
    assert_eq!(a.candidates.len(), b.candidates.len());
    for (x, y) in a.candidates.iter().zip(&b.candidates) {
        assert_eq!(x.base, y.base);
        assert_eq!(x.q, y.q);
        assert!((x.score - y.score).abs() < 1e-9);
    }
}

#[test]
fn an_unreachable_grasp_says_why() {
    let f = fetch();
    let scene = bookshelf();
    let mut goal = grasp(&f.model);
    // 3 m up: above everything Fetch reaches from any pose.
    goal.target.translation.z = 3.0;
    let posture = posture(&f.model);
    let r = place_base(&problem(&f, &scene, &goal, &posture), &options()).unwrap();
    assert!(r.candidates.is_empty());
    assert_eq!(r.counts.out_of_reach, r.counts.poses);
    let why = r.failure().unwrap();
    let n = r.counts.poses;
    assert!(
        why.contains(&format!("of {n} poses, {n} out of reach")),
        "{why}"
    );
    // Between the shelf boards: reached only through the board, or not at all.
    let mut goal = grasp(&f.model);
    goal.target.translation.z = 1.0;
    let r = place_base(&problem(&f, &scene, &goal, &posture), &options()).unwrap();
    assert!(r.candidates.is_empty());
    assert_eq!(r.counts.feasible, 0);
    assert!(r.failure().unwrap().contains("reached only in collision"));
}

#[test]
fn bad_problems_are_refused() {
    let f = fetch();
    let scene = bookshelf();
    let goal = grasp(&f.model);
    let posture = posture(&f.model);
    let mut p = problem(&f, &scene, &goal, &posture);
    p.payload.mass = -1.0;
    let err = place_base(&p, &options()).unwrap_err().to_string();
    assert!(err.contains("payload"), "{err}");
    let short = &posture[..5];
    let p = problem(&f, &scene, &goal, short);
    let err = place_base(&p, &options()).unwrap_err().to_string();
    assert!(err.contains("posture"), "{err}");
    let mut o = options();
    o.step = 0.001;
    let err = place_base(&problem(&f, &scene, &goal, &posture), &o)
        .unwrap_err()
        .to_string();
    assert!(err.contains("exceed the limit"), "{err}");
}

#[test]
fn a_motion_bench_maker_query_gives_the_grasp() {
    let f = fetch();
    let scene = bookshelf();
    let path = data_dir()
        .join("scenes/motion_bench_maker/configs/scenes/bookshelf/hard_queries_small.yaml");
    let q = read_grasp_query(&path, 0, &scene).unwrap();
    assert_eq!(q.object, "Can1");
    // Can1 at (0.9, 0.4054…, 1.08), identity; offset (−0.2, 0, 0.05).
    let want = grasp(&f.model).target.translation.vector;
    assert!((q.target.translation.vector - want).norm() < 1e-12);
    assert_eq!(
        (q.position_tolerance, q.orientation_tolerance),
        (0.01, 0.01)
    );
    assert!((q.object_in_grasp - Vector3::new(0.2, 0.0, -0.05)).norm() < 1e-15);
    let err = read_grasp_query(&path, 1, &scene).unwrap_err().to_string();
    assert!(
        err.contains("hard_queries_small.yaml") && err.contains("goal_queries[1]"),
        "{err}"
    );
    let text = "goal_queries:\n  - objects: [Mug]\n    offset: {position: [0, 0, 0], orientation: [0, 0, 0, 1]}\n";
    let err = grasp_query_from_str(text, Path::new("q.yaml"), 0, &scene)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("q.yaml") && err.contains("'Mug' is not in the scene"),
        "{err}"
    );
}

//! Sweeps: a stability row equals the stability library on the same state (the payload
//! checked through two independent routes: an external point force for the ZMP, and a
//! point-mass link added to the URDF for every measure), result columns are
//! identical whatever the thread count and the sharding, random points depend only on
//! the seed and the index, and bad sweep files are errors naming the field.

use moma::io::urdf::model_from_urdf_file;
use moma::multibody::{Data, RootJoint, neutral};
use moma::stability::{
    BodySet, ExternalLoads, PointForce, StabilityData, StabilityModel, SupportAttachment,
    SupportPolygon, evaluate,
};
use moma::sweep::{Sweep, Value, merge, shard_indices};
use nalgebra::{DVector, Vector2, Vector3};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn tiago() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/pinocchio/urdf/tiago.urdf")
}

const CASTERS: [[f64; 2]; 4] = [
    [0.1535, 0.102],
    [0.1535, -0.102],
    [-0.1895, 0.102],
    [-0.1895, -0.102],
];

fn stability_toml(sample: &str, params: &str) -> String {
    format!(
        r#"study = "stability"
[sample]
{sample}
[parameters]
{params}
[stability]
robot = "{}"
base = {{ r_w = 0.0985, b = 0.2022, d = 0.0, casters = [[0.1535, 0.102], [0.1535, -0.102], [-0.1895, 0.102], [-0.1895, -0.102]] }}
payload_frame = "arm_tool_link"
[[stability.postures]]
name = "forward"
q = {{ torso_lift_joint = 0.2, arm_1_joint = 1.5 }}
[[stability.postures]]
name = "tucked"
q = {{ arm_1_joint = 0.2, arm_2_joint = -1.34, arm_4_joint = 1.94 }}
"#,
        tiago().display()
    )
}

fn sweep(text: &str) -> moma::Result<Sweep> {
    Sweep::from_toml_str(text, Path::new("test.toml"), Path::new("."))
}

fn f(v: &Value) -> f64 {
    match v {
        Value::Float(x) => *x,
        other => panic!("not a float: {other:?}"),
    }
}

#[test]
fn a_row_is_the_stability_of_its_state_with_the_payload_as_a_point_force() {
    let s = sweep(&stability_toml(
        "mode = \"grid\"",
        "posture = [\"forward\", \"tucked\"]\naccel = [-2.5, 0.0, 1.5]\npayload = [0.0, 2.0]",
    ))
    .unwrap();
    assert_eq!(s.len(), 12);
    let cols = s.columns();
    assert_eq!(cols[..4], ["index", "posture", "accel", "payload"]);
    assert_eq!(cols.last().unwrap(), "eval_time_s");
    let col = |n: &str| cols.iter().position(|c| c == n).unwrap();

    // The same state through the stability library, the payload as a force m (g − a) at
    // the tool frame (the whole robot translates rigidly with acceleration (accel, 0, 0)).
    let model = model_from_urdf_file(tiago(), RootJoint::Planar).unwrap();
    let mut pts: Vec<Vector2<f64>> = vec![Vector2::new(0.0, 0.2022), Vector2::new(0.0, -0.2022)];
    pts.extend(CASTERS.iter().map(|c| Vector2::new(c[0], c[1])));
    let sm = StabilityModel::new(
        &model,
        SupportPolygon::from_points(&pts).unwrap(),
        SupportAttachment::Base,
        &BodySet::All,
    )
    .unwrap();
    let mut data = Data::new(&model);
    let mut sd = StabilityData::new(&sm);
    // TIAGo with a 2 kg point-mass link fixed at the tool frame
    let urdf = std::fs::read_to_string(tiago()).unwrap().replace(
        "</robot>",
        r#"<link name="payload"><inertial><mass value="2.0"/><origin xyz="0 0 0"/>
           <inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/></inertial></link>
           <joint name="payload_joint" type="fixed"><parent link="arm_tool_link"/>
           <child link="payload"/><origin xyz="0 0 0"/></joint></robot>"#,
    );
    let loaded =
        moma::io::urdf::model_from_urdf_str(&urdf, RootJoint::Planar, "tiago+payload.urdf")
            .unwrap();
    let sm_loaded = StabilityModel::new(
        &loaded,
        sm.support.clone(),
        SupportAttachment::Base,
        &BodySet::All,
    )
    .unwrap();
    let mut data_loaded = Data::new(&loaded);
    let mut sd_loaded = StabilityData::new(&sm_loaded);
    let tool = model.frame_id("arm_tool_link").unwrap();
    let mut checked = 0;
    for i in 0..s.len() {
        let row = s.evaluate(i).unwrap();
        let posture = match &row[col("posture")] {
            Value::Text(n) => n.clone(),
            other => panic!("{other:?}"),
        };
        let (accel, payload) = (f(&row[col("accel")]), f(&row[col("payload")]));
        let mut q = neutral(&model);
        let set = |q: &mut DVector<f64>, j: &str, x: f64| {
            q[model.idx_q[model.joint_id(j).unwrap().0]] = x;
        };
        if posture == "forward" {
            set(&mut q, "torso_lift_joint", 0.2);
            set(&mut q, "arm_1_joint", 1.5);
        } else {
            set(&mut q, "arm_1_joint", 0.2);
            set(&mut q, "arm_2_joint", -1.34);
            set(&mut q, "arm_4_joint", 1.94);
        }
        let v = DVector::zeros(model.nv);
        let mut a = DVector::zeros(model.nv);
        a[0] = accel;
        moma::kinematics::forward_kinematics(&model, &mut data, &q);
        let fr = &model.frames[tool.0];
        let p = data.world_from_joint[fr.parent_joint.0]
            .compose(&fr.placement)
            .translation;
        let force = [PointForce {
            point: p,
            force: payload * (model.gravity - Vector3::new(accel, 0.0, 0.0)),
        }];
        let ext = ExternalLoads {
            forces: &force,
            moments: &[],
        };
        let r = evaluate(&model, &mut data, &sm, &mut sd, &q, &v, &a, &ext).clone();
        let close = |name: &str, want: f64| {
            let got = f(&row[col(name)]);
            assert!(
                (got - want).abs() <= 1e-9 * want.abs().max(1.0),
                "point {i} {name}: {got} vs {want}"
            );
        };
        close("zmp_margin", r.zmp_margin.unwrap());
        close("zmp_x", r.zmp.unwrap().x);
        assert_eq!(row[col("stable")], Value::Bool(r.stable), "point {i}");
        close("mass", model.total_mass() + payload);
        // every measure against the model that carries the payload as a link
        let r = if payload == 0.0 {
            evaluate(
                &model,
                &mut data,
                &sm,
                &mut sd,
                &q,
                &v,
                &a,
                &ExternalLoads::NONE,
            )
            .clone()
        } else {
            assert_eq!(payload, 2.0);
            evaluate(
                &loaded,
                &mut data_loaded,
                &sm_loaded,
                &mut sd_loaded,
                &q,
                &v,
                &a,
                &ExternalLoads::NONE,
            )
            .clone()
        };
        close("zmp_margin", r.zmp_margin.unwrap());
        close("fa_alpha", r.force_angle_alpha.unwrap());
        close("fa_min", r.force_angle_min.unwrap());
        close("fa_beta", r.force_angle_beta_min.unwrap());
        close("mhs_min", r.mhs_min.unwrap());
        checked += 1;
    }
    assert_eq!(checked, 12);
}

#[test]
fn a_robot_rooted_at_axle_height_stands_on_the_ground_under_its_wheels() {
    // TIAGo without its base_footprint link: rooted at base_link, on the wheel axes,
    // 0.0985 m (the wheel radius) above the ground
    let text = std::fs::read_to_string(tiago()).unwrap();
    let cut = |s: &str, from: &str, to: &str| {
        let a = s.find(from).unwrap();
        let b = a + s[a..].find(to).unwrap() + to.len();
        format!("{}{}", &s[..a], &s[b..])
    };
    let axle = cut(&text, "<joint name=\"base_footprint_joint\"", "</joint>");
    let axle = cut(&axle, "<link name=\"base_footprint\">", "</link>");
    // the two other links fixed to base_footprint, re-attached to base_link
    let axle = axle
        .replace(
            "<parent link=\"base_footprint\"/>\n    <child link=\"base_cover_link\"/>\n    <origin rpy=\"0 0 0\" xyz=\"0 0 0.13\"/>",
            "<parent link=\"base_link\"/>\n    <child link=\"base_cover_link\"/>\n    <origin rpy=\"0 0 0\" xyz=\"0 0 0.0315\"/>",
        )
        .replace(
            "<parent link=\"base_footprint\"/>\n    <child link=\"rgbd_laser_link\"/>\n    <origin rpy=\"0 0 0\" xyz=\"-0.9 0 0\"/>",
            "<parent link=\"base_link\"/>\n    <child link=\"rgbd_laser_link\"/>\n    <origin rpy=\"0 0 0\" xyz=\"-0.9 0 -0.0985\"/>",
        );
    assert!(!axle.contains("\"base_footprint\""));
    let path = std::env::temp_dir().join(format!("moma_tiago_axle_{}.urdf", std::process::id()));
    std::fs::write(&path, axle).unwrap();
    let params =
        "posture = [\"forward\", \"tucked\"]\naccel = [-2.5, 0.0, 1.5]\nyaw_rate = [0.0, 1.0]";
    let ground = stability_toml("mode = \"grid\"", params);
    let wheels = "d = 0.0, wheel_joints = [\"wheel_left_joint\", \"wheel_right_joint\"], casters";
    let run = |text: &str| {
        let s = sweep(text).unwrap();
        let rows: Vec<Vec<Value>> = (0..s.len()).map(|i| s.evaluate(i).unwrap()).collect();
        (s.columns(), rows)
    };
    let (cols, at_ground) = run(&ground);
    let on_axle = ground.replace(&tiago().display().to_string(), &path.display().to_string());
    let (_, axle_wheels) = run(&on_axle.replace("d = 0.0, casters", wheels));
    let (_, axle_flat) = run(&on_axle);
    std::fs::remove_file(&path).ok();
    let col = |n: &str| cols.iter().position(|c| c == n).unwrap();
    let mut flat_differs = false;
    for ((g, w), z0) in at_ground.iter().zip(&axle_wheels).zip(&axle_flat) {
        for name in ["zmp_margin", "zmp_x", "fa_min", "mhs_min"] {
            let (a, b) = (f(&g[col(name)]), f(&w[col(name)]));
            assert!(
                (a - b).abs() <= 1e-9 * (1.0 + a.abs()),
                "{name}: {a} vs {b}"
            );
        }
        // the same robot: its centre of mass is 0.0985 m lower in the axle-rooted frame
        let (a, b) = (f(&g[col("com_z")]), f(&w[col("com_z")]));
        assert!((a - b - 0.0985).abs() < 1e-9, "com_z {a} vs {b}");
        flat_differs |= (f(&g[col("zmp_margin")]) - f(&z0[col("zmp_margin")])).abs() > 1e-3;
    }
    // without the wheel joints the ground is the axle plane, and accelerating rows differ
    assert!(flat_differs);
}

#[test]
fn results_do_not_depend_on_threads_or_shards() {
    for sample in ["mode = \"grid\"", "mode = \"random\"\ncount = 60\nseed = 7"] {
        let s = sweep(&stability_toml(
            sample,
            "posture = [\"forward\", \"tucked\"]\naccel = { linspace = [-3, 3, 5] }\nyaw_rate = { linspace = [-1, 1, 3] }\npayload = { linspace = [0, 3, 2] }\nspeed = 0.5",
        ))
        .unwrap();
        let all: Vec<u64> = (0..s.len()).collect();
        let one = s.run(&all, 1).unwrap().without_timing();
        let two = s.run(&all, 2).unwrap().without_timing();
        assert_eq!(one.to_csv(), two.to_csv(), "{sample}");
        assert_eq!(one.rows.len() as u64, s.len());
        for n in [2, 3, 7] {
            let shards: Vec<_> = (1..=n)
                .map(|k| s.run(&shard_indices(s.len(), k, n).unwrap(), 2).unwrap())
                .collect();
            let names: Vec<String> = (1..=n).map(|k| format!("shard {k}")).collect();
            // through CSV text, as `moma sweep merge` does
            let read: Vec<_> = shards
                .iter()
                .map(|t| moma::sweep::Table::parse_csv(&t.to_csv(), Path::new("s.csv")).unwrap())
                .collect();
            let merged = merge(read, &names).unwrap().without_timing();
            assert_eq!(merged.to_csv(), one.to_csv(), "{sample}, {n} shards");
        }
    }
}

#[test]
fn random_points_depend_on_the_seed_and_index_only() {
    let text = |seed: u64| {
        stability_toml(
            &format!("mode = \"random\"\ncount = 1000\nseed = {seed}"),
            "posture = [\"forward\", \"tucked\"]\naccel = { linspace = [-3, 3, 2] }\npayload = [0.5, 1.5]",
        )
    };
    let (a, b, c) = (
        sweep(&text(1)).unwrap(),
        sweep(&text(1)).unwrap(),
        sweep(&text(2)).unwrap(),
    );
    let mut seen = [0usize; 2];
    for i in [0, 1, 17, 999] {
        assert_eq!(a.point(i).unwrap(), b.point(i).unwrap());
        assert_ne!(a.point(i).unwrap(), c.point(i).unwrap());
    }
    for i in 0..1000 {
        let p = a.point(i).unwrap();
        let x = f(&p[1]);
        assert!((-3.0..=3.0).contains(&x));
        assert!(p[2] == Value::Float(0.5) || p[2] == Value::Float(1.5));
        seen[usize::from(p[0] == Value::Text("tucked".into()))] += 1;
    }
    // both postures drawn, roughly evenly
    assert!(seen[0] > 400 && seen[1] > 400, "{seen:?}");
    assert!(a.point(1000).is_err());
}

#[test]
fn shards_partition_the_indices() {
    let mut all: Vec<u64> = (1..=4)
        .flat_map(|k| shard_indices(10, k, 4).unwrap())
        .collect();
    assert_eq!(shard_indices(10, 2, 4).unwrap(), [1, 5, 9]);
    all.sort_unstable();
    assert_eq!(all, (0..10).collect::<Vec<_>>());
    assert!(shard_indices(3, 5, 5).unwrap().is_empty());
    for (k, n) in [(0, 3), (4, 3), (1, 0)] {
        let e = shard_indices(10, k, n).unwrap_err().to_string();
        assert!(e.contains("1 <= K <= N"), "{e}");
    }
}

#[test]
fn bad_sweep_files_name_the_field() {
    let huge = "accel = { linspace = [0, 1, 1000000] }\nspeed = { linspace = [0, 1, 1000000] }";
    let cases = [
        (
            stability_toml("mode = \"grid\"", huge),
            "more than 1000000000 points",
        ),
        (
            stability_toml("mode = \"grid\"", "wobble = [1]"),
            "parameters.wobble",
        ),
        (
            stability_toml("mode = \"grid\"", "posture = [\"nope\"]"),
            "parameters.posture[0]",
        ),
        (
            stability_toml("mode = \"grid\"", "payload = [-1]"),
            "parameters.payload",
        ),
        (
            stability_toml("mode = \"grid\"", "accel = [\"x\"]"),
            "parameters.accel[0]",
        ),
        (
            stability_toml("mode = \"grid\"", "\"q.nope\" = [1]"),
            "q.nope",
        ),
        (
            stability_toml("mode = \"random\"\ncount = 5", "accel = [1]"),
            "sample.seed",
        ),
        (
            stability_toml("mode = \"grid\"", "accel = { linspace = [1, 0, 3] }"),
            "lo <= hi",
        ),
        (
            stability_toml("mode = \"fancy\"", "accel = [1]"),
            "sample.mode",
        ),
        (
            stability_toml("mode = \"grid\"", "accel = [1]")
                .replace("payload_frame", "payload_frme"),
            "payload_frme",
        ),
    ];
    for (text, needle) in cases {
        let e = sweep(&text).unwrap_err().to_string();
        assert!(e.contains(needle), "{needle}: {e}");
        assert!(e.contains("test.toml"), "{e}");
    }
}

#[test]
fn placement_reaches_near_targets_and_not_far_ones() {
    let text = format!(
        r#"study = "placement"
[parameters]
target = ["near", "far"]
base_x = [0.0, 5.0]
[placement]
robot = "{}"
frame = "panda_hand"
mount = [0.0, 0.0, 0.4]
[[placement.targets]]
name = "near"
pose = [0.4, 0.1, 0.9]
[[placement.targets]]
name = "far"
pose = [0.4, 0.1, 3.0]
"#,
        root().join("scenarios/robots/panda.urdf").display()
    );
    let s = sweep(&text).unwrap();
    let t = s.run(&[0, 1, 2, 3], 2).unwrap();
    let c = t.column("reachable").unwrap();
    let reach: Vec<_> = t.rows.iter().map(|r| r[c].clone()).collect();
    // (near, 0), (near, 5), (far, 0), (far, 5)
    assert_eq!(
        reach,
        [
            Value::Bool(true),
            Value::Bool(false),
            Value::Bool(false),
            Value::Bool(false)
        ]
    );
    let m = t.column("measure").unwrap();
    assert!(f(&t.rows[0][m]) > 0.0);
    assert_eq!(t.rows[1][m], Value::Missing);
}

#[test]
fn shipped_example_sweeps_load() {
    for name in [
        "tiago_stability.toml",
        "tiago_stability_random.toml",
        "panda_placement.toml",
    ] {
        let s = Sweep::from_file(root().join("scenarios/sweeps").join(name)).unwrap();
        assert!(!s.is_empty(), "{name}");
        s.evaluate(s.len() - 1).unwrap();
    }
    let s = Sweep::from_file(root().join("scenarios/sweeps/tiago_stability.toml")).unwrap();
    assert_eq!(s.len(), 10_000);
}

#[test]
fn a_mission_row_is_the_mission_run_with_the_point_applied() {
    let text = format!(
        "study = \"mission\"\n[parameters]\nobstacle_t = [1.0, 9.0]\n[mission]\nscenario = \"{}\"\n",
        root().join("scenarios/mission.toml").display()
    );
    let s = sweep(&text).unwrap();
    let cols = s.columns();
    let one = s.run(&[0, 1], 1).unwrap().without_timing();
    let two = s.run(&[0, 1], 2).unwrap().without_timing();
    assert_eq!(one, two);
    // point 1 by hand: the scenario with its obstacle arriving at t = 9 s
    let path = root().join("scenarios/mission.toml");
    let mut file = moma::mission::load(&path).unwrap().file;
    file.obstacles[0].t = 9.0;
    let m = moma::mission::scenario::from_file(file, &path, &root().join("scenarios")).unwrap();
    let r = moma::mission::run(&m).unwrap();
    let col = |n: &str| cols.iter().position(|c| c == n).unwrap();
    let row = &one.rows[1];
    assert_eq!(row[col("reached")], Value::Bool(r.reached));
    assert_eq!(row[col("time_to_goal")], Value::opt(r.time_to_goal));
    assert_eq!(row[col("replans")], Value::Int(r.replans() as i64));
    assert_eq!(row[col("min_zmp_margin")], Value::opt(r.min_zmp_margin()));
    // an obstacle parameter needs an obstacle in the scenario
    let e = sweep(&text.replace("obstacle_t", "wobble"))
        .unwrap_err()
        .to_string();
    assert!(e.contains("parameters.wobble"), "{e}");
}

/// Counts the robots a sweep asks its loader for, delegating to the file system.
struct CountingLoader(std::cell::RefCell<Vec<(PathBuf, RootJoint)>>);

impl moma::mission::scenario::Loader for CountingLoader {
    fn map(&self, path: &Path, resolution: Option<f64>) -> moma::Result<moma::planning::LoadedMap> {
        moma::mission::scenario::FileSystem.map(path, resolution)
    }
    fn urdf(&self, path: &Path, root: RootJoint) -> moma::Result<moma::multibody::Model> {
        self.0.borrow_mut().push((path.to_path_buf(), root));
        moma::mission::scenario::FileSystem.urdf(path, root)
    }
}

#[test]
fn a_sweep_loads_its_robot_through_the_loader_it_is_given() {
    let text = stability_toml(
        "mode = \"grid\"",
        "posture = [\"forward\", \"tucked\"]\npayload = [0.0, 2.0]",
    );
    let l = CountingLoader(Default::default());
    let s = Sweep::from_toml_str_with(&text, Path::new("test.toml"), Path::new("."), &l).unwrap();
    assert_eq!(*l.0.borrow(), [(tiago(), RootJoint::Planar)]);
    // the same rows as the file system's path (all but the last column, eval_time_s)
    let direct = sweep(&text).unwrap();
    assert_eq!(s.len(), direct.len());
    assert_eq!(s.columns().last().unwrap(), "eval_time_s");
    for i in 0..s.len() {
        let (a, b) = (s.evaluate(i).unwrap(), direct.evaluate(i).unwrap());
        assert_eq!(a[..a.len() - 1], b[..b.len() - 1]);
    }
}

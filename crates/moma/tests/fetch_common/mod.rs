//! Fetch as the tests load it: its folder (URDF, meshes, SRDF, casters) and its model with
//! its collision geometry (`package://` meshes resolved in that folder, the SRDF's
//! disabled pairs), shared by the collision, motion and robot tests; and Panda's, for the
//! collision tests against coal.
#![allow(dead_code)]

use moma::collision::{GeometryModel, GeometryOptions};
use moma::multibody::{Model, RootJoint};
use std::path::{Path, PathBuf};

/// The tests' data folder.
pub fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

/// Fetch's folder: `fetch_description/`, `fetch.srdf`, `casters.toml`.
pub fn fetch_dir() -> PathBuf {
    data_dir().join("robots/fetch")
}

/// Fetch's URDF.
pub fn fetch_urdf() -> PathBuf {
    fetch_dir().join("fetch_description/robots/fetch.urdf")
}

/// Fetch's model on `root` and its collision geometry with the SRDF's disabled pairs.
pub fn fetch_geometry(root: RootJoint) -> (Model, GeometryModel) {
    let dir = fetch_dir();
    let urdf = fetch_urdf();
    let model = moma::io::urdf::model_from_urdf_file(&urdf, root).unwrap();
    let gm = GeometryModel::from_urdf(
        &model,
        &urdf,
        &GeometryOptions {
            package_dirs: vec![dir.clone()],
            srdf: Some(dir.join("fetch.srdf")),
        },
    )
    .unwrap();
    (model, gm)
}

/// Panda (example-robot-data's URDF: STL meshes, four boxes per finger) on a fixed root
/// and its collision geometry with its SRDF's disabled pairs.
pub fn panda_geometry() -> (Model, GeometryModel) {
    let urdf = data_dir().join("pinocchio/urdf/panda.urdf");
    let pkg = data_dir().join("robots/panda");
    let model = moma::io::urdf::model_from_urdf_file(&urdf, RootJoint::Fixed).unwrap();
    let gm = GeometryModel::from_urdf(
        &model,
        &urdf,
        &GeometryOptions {
            srdf: Some(pkg.join("example-robot-data/robots/panda_description/srdf/panda.srdf")),
            package_dirs: vec![pkg],
        },
    )
    .unwrap();
    (model, gm)
}

/// MotionBenchMaker's Fetch queries (`scenes/motion_bench_maker/fetch_queries`): the
/// planning group, each query's start, goal state and scene.
pub struct FetchQueries {
    /// The queries' folder.
    pub dir: PathBuf,
    /// `queries.json`.
    pub json: serde_json::Value,
}

impl FetchQueries {
    pub fn load() -> Self {
        let dir = data_dir().join("scenes/motion_bench_maker/fetch_queries");
        let json =
            serde_json::from_str(&std::fs::read_to_string(dir.join("queries.json")).unwrap())
                .unwrap();
        FetchQueries { dir, json }
    }

    /// The planning group of every query.
    pub fn group(&self, model: &Model) -> moma::motion::JointGroup {
        let names: Vec<&str> = self.json["group"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_str().unwrap())
            .collect();
        moma::motion::JointGroup::new(model, &names).unwrap()
    }

    /// The query named `name`.
    pub fn query(&self, name: &str) -> &serde_json::Value {
        self.json["queries"]
            .as_array()
            .unwrap()
            .iter()
            .find(|q| q["name"] == name)
            .unwrap()
    }

    /// A query's scene, poses in `world` or `base_link` (the robot at the origin).
    pub fn scene(&self, query: &serde_json::Value) -> moma::collision::Scene {
        moma::collision::read_scene(
            &self.dir.join(query["scene"].as_str().unwrap()),
            &moma::collision::SceneOptions {
                world_frames: vec!["world".into(), "base_link".into()],
                package_dirs: Vec::new(),
            },
        )
        .unwrap()
    }
}

/// A query made ready to plan: its scene, start, goal state, and the robot's geometry with
/// the links that touch at the start measured as their mesh surfaces (2 mm margin).
pub struct PreparedQuery {
    pub scene: moma::collision::Scene,
    pub start: Vec<f64>,
    pub goal: moma::motion::MotionGoal,
    pub geometry: GeometryModel,
}

impl FetchQueries {
    /// The query named `name` made ready to plan for `group` on `model` with `gm`.
    pub fn prepare(
        &self,
        model: &Model,
        gm: &GeometryModel,
        group: &moma::motion::JointGroup,
        name: &str,
    ) -> PreparedQuery {
        let query = self.query(name);
        let scene = self.scene(query);
        let start = numbers(&query["start"]);
        let source = moma::motion::MeshSource {
            urdf: fetch_urdf(),
            package_dirs: vec![fetch_dir()],
        };
        let goal = moma::motion::MotionGoal::State(numbers(&query["goal_state"]));
        let states: Vec<&[f64]> = std::iter::once(start.as_slice())
            .chain(goal.state())
            .collect();
        let (geometry, _) = moma::motion::surface_links_for_states(
            model, gm, &scene, group, &states, 2e-3, &source,
        )
        .unwrap();
        PreparedQuery {
            scene,
            start,
            goal,
            geometry,
        }
    }
}

/// A JSON list of numbers.
pub fn numbers(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

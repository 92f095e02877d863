//! Fetch as the tests load it: its folder (URDF, meshes, SRDF, casters) and its model with
//! its collision geometry (`package://` meshes resolved in that folder, the SRDF's
//! disabled pairs), shared by the collision, motion and robot tests.
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

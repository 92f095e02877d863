//! Collision geometry: `GeometryModel.from_urdf`, `Scene.from_yaml`, `distances` (with
//! the minimum distance's gradient on request) and `footprint`.

use crate::err;
use crate::model::{PyModel, Vec1, check_state, load};
use moma::collision::{
    ExactGeometry, ExactScene, GeometryData, GeometryModel, GeometryOptions, PairSelection, Scene,
    SceneData, SceneOptions, base_ground_pose, compute_distances, compute_exact_distances,
    compute_exact_scene_distances, compute_scene_distances, footprint as world_footprint,
    footprint_in, min_distance_gradient, read_scene, update_geometry_placements,
};
use moma::motion::MeshSource;
use moma::multibody::Data;
use nalgebra::DVector;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// A robot's collision geometry (the URDF's `<collision>` elements, meshes as their
/// convex hulls) and the link pairs it checks.
#[pyclass(module = "moma", name = "GeometryModel", frozen)]
pub struct PyGeometryModel {
    pub(crate) inner: GeometryModel,
    /// Where the meshes are: `plan_motion` swaps concave links for their mesh surfaces.
    pub(crate) source: MeshSource,
}

#[pymethods]
impl PyGeometryModel {
    /// Reads the collision geometry of the URDF that `model` was loaded from.
    /// `package_dirs` resolve `package://` URIs; `srdf` disables its
    /// `<disable_collisions>` pairs.
    ///
    /// Raises MomaError naming the file, link and URI or element at fault.
    #[staticmethod]
    #[pyo3(signature = (model, path, srdf = None, package_dirs = Vec::new()))]
    fn from_urdf(
        py: Python<'_>,
        model: PyRef<'_, PyModel>,
        path: PathBuf,
        srdf: Option<PathBuf>,
        package_dirs: Vec<PathBuf>,
    ) -> PyResult<Self> {
        let source = MeshSource {
            urdf: path.clone(),
            package_dirs: package_dirs.clone(),
        };
        let opts = GeometryOptions { package_dirs, srdf };
        let m = &model.inner;
        let inner = py
            .detach(|| GeometryModel::from_urdf(m, &path, &opts))
            .map_err(err)?;
        Ok(Self { inner, source })
    }

    /// Names of the links that carry geometry.
    #[getter]
    fn links(&self) -> Vec<String> {
        self.inner.links.iter().map(|l| l.name.clone()).collect()
    }

    /// The enabled link pairs (not adjacent, not fixed together, not disabled by the SRDF).
    #[getter]
    fn pairs_enabled(&self) -> Vec<(String, String)> {
        let l = &self.inner.links;
        self.inner
            .pairs
            .iter()
            .zip(&self.inner.enabled)
            .filter(|(_, e)| **e)
            .map(|(&[a, b], _)| (l[a].name.clone(), l[b].name.clone()))
            .collect()
    }

    fn __repr__(&self) -> String {
        format!(
            "GeometryModel({} links, {} pairs, {} enabled)",
            self.inner.links.len(),
            self.inner.pairs.len(),
            self.inner.n_enabled()
        )
    }
}

/// Scene objects from a MoveIt planning-scene YAML file (MotionBenchMaker's schema).
#[pyclass(module = "moma", name = "Scene", frozen)]
pub struct PyScene {
    pub(crate) inner: Scene,
}

#[pymethods]
impl PyScene {
    /// Reads a planning-scene YAML; poses must be in one of `world_frames`.
    ///
    /// Raises MomaError naming the file and the object at fault.
    #[staticmethod]
    #[pyo3(signature = (path, world_frames = vec!["world".to_string()], package_dirs = Vec::new()))]
    fn from_yaml(
        py: Python<'_>,
        path: PathBuf,
        world_frames: Vec<String>,
        package_dirs: Vec<PathBuf>,
    ) -> PyResult<Self> {
        let opts = SceneOptions {
            world_frames,
            package_dirs,
        };
        let inner = py.detach(|| read_scene(&path, &opts)).map_err(err)?;
        Ok(Self { inner })
    }

    /// The objects' ids.
    #[getter]
    fn ids(&self) -> Vec<String> {
        self.inner.objects.iter().map(|o| o.id.clone()).collect()
    }
}

/// Signed distances in configuration `q`: the enabled self pairs (every link pair with
/// `all_pairs=True`) and every (link, scene object) pair. Returns a dict with
/// `pairs` (list of (a, b) names), `distance` (n,), `witness_a` and `witness_b` (n, 3,
/// world frame), `min_distance`, `in_collision` (min < 0) and `closest` (a, b); with
/// `gradient=True` also `gradient` (nv,): the derivative of `min_distance` (the closest
/// pair's signed distance) with respect to the velocity coordinates (∂d/∂q for a fixed
/// or planar root). `mesh="exact"` measures with the triangle meshes, the links' and the
/// scene's (surface distances, 0 where triangles touch; scene primitives are solid, 0
/// where a link's triangle enters one; `in_collision` when the minimum is 0) instead of
/// their convex hulls (`"convex"`, the default).
#[pyfunction]
#[pyo3(signature = (model, geom, q, scene = None, all_pairs = false, gradient = false, mesh = "convex"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn distances<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    geom: PyRef<'py, PyGeometryModel>,
    q: Vec1<'py>,
    scene: Option<PyRef<'py, PyScene>>,
    all_pairs: bool,
    gradient: bool,
    mesh: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let empty = Scene::default();
    let scene = scene.as_ref().map_or(&empty, |s| &s.inner);
    let exact = match mesh {
        "convex" => None,
        "exact" => Some((
            ExactGeometry::new(&geom.inner).map_err(err)?,
            ExactScene::new(scene).map_err(err)?,
        )),
        other => {
            return Err(err(moma::Error::invalid(
                "distances: mesh",
                format!("'{other}' is not 'convex' or 'exact'"),
            )));
        }
    };
    let m = &model.inner;
    let gm = &geom.inner;
    let mut qv = DVector::zeros(m.nq);
    load("distances", "q", q.as_array(), &mut qv)?;
    check_state(m, || "distances".into(), qv.as_slice(), None, None, None)?;
    let mut data = Data::new(m);
    let mut gd = GeometryData::new(gm);
    let mut sd = SceneData::new(gm, scene);
    if gradient {
        moma::kinematics::compute_joint_jacobians(m, &mut data, &qv);
    } else {
        moma::kinematics::forward_kinematics(m, &mut data, &qv);
    }
    update_geometry_placements(gm, &data, &mut gd);
    let which = if all_pairs {
        PairSelection::All
    } else {
        PairSelection::Enabled
    };
    match &exact {
        Some((ex, exs)) => {
            compute_exact_distances(gm, ex, &mut gd, which);
            compute_exact_scene_distances(gm, ex, &mut gd, scene, exs, &mut sd)
        }
        None => {
            compute_distances(gm, &mut gd, which);
            compute_scene_distances(gm, &mut gd, scene, &mut sd)
        }
    };
    let mut names = Vec::new();
    let mut results = Vec::new();
    for (p, &[a, b]) in gm.pairs.iter().enumerate() {
        if all_pairs || gm.enabled[p] {
            names.push((gm.links[a].name.clone(), gm.links[b].name.clone()));
            results.push(gd.results[p]);
        }
    }
    let no = scene.objects.len();
    for (l, link) in gm.links.iter().enumerate() {
        for (o, obj) in scene.objects.iter().enumerate() {
            names.push((link.name.clone(), obj.id.clone()));
            results.push(sd.results[l * no + o]);
        }
    }
    let n = results.len();
    let dist: Vec<f64> = results.iter().map(|r| r.distance).collect();
    let wa: Vec<Vec<f64>> = results
        .iter()
        .map(|r| r.witness_a.as_slice().to_vec())
        .collect();
    let wb: Vec<Vec<f64>> = results
        .iter()
        .map(|r| r.witness_b.as_slice().to_vec())
        .collect();
    let best = (0..n).min_by(|&i, &j| dist[i].total_cmp(&dist[j]));
    let out = PyDict::new(py);
    let min = best.map_or(f64::INFINITY, |i| dist[i]);
    out.set_item("min_distance", min)?;
    out.set_item("in_collision", min < 0.0 || (exact.is_some() && min <= 0.0))?;
    out.set_item("closest", best.map(|i| names[i].clone()))?;
    out.set_item("pairs", names)?;
    out.set_item("distance", PyArray1::from_vec(py, dist))?;
    let mat = |w: Vec<Vec<f64>>| -> PyResult<Bound<'py, PyArray2<f64>>> {
        if w.is_empty() {
            return Ok(PyArray2::zeros(py, [0, 3], false));
        }
        PyArray2::from_vec2(py, &w).map_err(err)
    };
    out.set_item("witness_a", mat(wa)?)?;
    out.set_item("witness_b", mat(wb)?)?;
    if gradient {
        let mut g = DVector::zeros(m.nv);
        if min_distance_gradient(m, &data, gm, &gd, scene, &sd, &mut g).is_none() {
            return Err(err(moma::Error::invalid(
                "distances",
                "no pair to differentiate (no enabled pair and no scene)",
            )));
        }
        out.set_item("gradient", PyArray1::from_vec(py, g.as_slice().to_vec()))?;
    }
    Ok(out)
}

/// The robot's planar footprint in configuration `q`: the convex hull (m, 2),
/// counter-clockwise, of its collision geometry projected on the ground (round shapes
/// through circumscribed 32-gons). `frame="base"` (the default for a planar or
/// free-flyer root) expresses it in the base's ground frame (x forward), as `moma plan
/// --footprint` takes it; `frame="world"` (the default for a fixed root) in the world.
#[pyfunction]
#[pyo3(signature = (model, geom, q, frame = None))]
pub(crate) fn footprint<'py>(
    py: Python<'py>,
    model: PyRef<'py, PyModel>,
    geom: PyRef<'py, PyGeometryModel>,
    q: Vec1<'py>,
    frame: Option<&str>,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let m = &model.inner;
    let gm = &geom.inner;
    let mut qv = DVector::zeros(m.nq);
    load("footprint", "q", q.as_array(), &mut qv)?;
    check_state(m, || "footprint".into(), qv.as_slice(), None, None, None)?;
    let mut data = Data::new(m);
    let mut gd = GeometryData::new(gm);
    moma::kinematics::forward_kinematics(m, &mut data, &qv);
    update_geometry_placements(gm, &data, &mut gd);
    let base = base_ground_pose(m, &data);
    let mut scratch = Vec::new();
    let poly = match (frame, base) {
        (None | Some("base"), Some((origin, yaw))) => {
            footprint_in(gm, &gd, &origin, yaw, &mut scratch)
        }
        (None | Some("world"), _) => world_footprint(gm, &gd, &mut scratch),
        (Some("base"), None) => {
            return Err(err(moma::Error::invalid(
                "footprint: frame",
                "'base' needs a planar or free-flyer root (a fixed root's base is the world)",
            )));
        }
        (Some(other), _) => {
            return Err(err(moma::Error::invalid(
                "footprint: frame",
                format!("'{other}' is not 'base' or 'world'"),
            )));
        }
    };
    let rows: Vec<Vec<f64>> = poly.iter().map(|p| vec![p.x, p.y]).collect();
    if rows.is_empty() {
        return Ok(PyArray2::zeros(py, [0, 2], false));
    }
    PyArray2::from_vec2(py, &rows).map_err(err)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyGeometryModel>()?;
    m.add_class::<PyScene>()?;
    m.add_function(wrap_pyfunction!(distances, m)?)?;
    m.add_function(wrap_pyfunction!(footprint, m)?)?;
    Ok(())
}

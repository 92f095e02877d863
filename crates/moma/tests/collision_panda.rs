//! Panda (example-robot-data's URDF with its STL collision meshes, and boxes on the
//! fingers) loads with its meshes and matches coal: every link pair's distance between
//! convex hulls on the seeded states of `tests/data/collision/panda_self.json` (Pinocchio
//! 4.1.0 + coal 3.0.3 at a 1e-12 m gap; SOURCES.md there) to 1e-6 m.

use moma::collision::{
    GeometryData, GeometryModel, GeometryOptions, PairSelection, compute_distances,
    update_geometry_placements,
};
use moma::kinematics::forward_kinematics;
use moma::multibody::{Data, RootJoint};
use nalgebra::DVector;
use serde_json::Value;
use std::path::Path;

#[test]
fn panda_hull_distances_match_coal() {
    let data_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let urdf = data_dir.join("pinocchio/urdf/panda.urdf");
    let model = moma::io::urdf::model_from_urdf_file(&urdf, RootJoint::Fixed).unwrap();
    let opts = GeometryOptions {
        package_dirs: vec![data_dir.join("robots/panda")],
        srdf: None,
    };
    let gm = GeometryModel::from_urdf(&model, &urdf, &opts).unwrap();
    assert_eq!(gm.objects.len(), 17);
    let r: Value = serde_json::from_str(
        &std::fs::read_to_string(data_dir.join("collision/panda_self.json")).unwrap(),
    )
    .unwrap();
    let pairs: Vec<usize> = r["pairs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let a = gm.link_index(p[0].as_str().unwrap()).unwrap();
            let b = gm.link_index(p[1].as_str().unwrap()).unwrap();
            gm.pairs
                .iter()
                .position(|x| *x == [a.min(b), a.max(b)])
                .unwrap()
        })
        .collect();
    let mut data = Data::new(&model);
    let mut gd = GeometryData::new(&gm);
    let (mut worst, mut overlapping, mut checked) = (0.0_f64, 0, 0);
    for s in r["states"].as_array().unwrap() {
        let q: Vec<f64> = s["q"]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect();
        assert_eq!(q.len(), model.nq);
        forward_kinematics(&model, &mut data, &DVector::from_vec(q));
        update_geometry_placements(&gm, &data, &mut gd);
        compute_distances(&gm, &mut gd, PairSelection::All);
        for (k, want) in s["distance_convex"].as_array().unwrap().iter().enumerate() {
            let (got, want) = (gd.results[pairs[k]].distance, want.as_f64().unwrap());
            assert!(
                (got - want).abs() <= 1e-6,
                "pair {:?}: {got} vs coal {want}",
                r["pairs"][k]
            );
            worst = worst.max((got - want).abs());
            overlapping += usize::from(want < 0.0);
            checked += 1;
        }
    }
    eprintln!("{checked} pairs ({overlapping} overlapping), worst error {worst:e} m");
    assert!(checked >= 250 && overlapping > 0);
}

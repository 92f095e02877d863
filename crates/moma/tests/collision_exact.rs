//! Exact triangle-mesh distances (`collision::exact`) against coal 3.0.3's distances
//! between Fetch's BVH meshes (through Pinocchio 4.1.0): `distance_mesh` of the 76
//! SRDF-enabled link pairs of every state of `tests/data/collision/fetch_self_public.json`
//! (see its SOURCES.md), 0 where triangles intersect. (Every one of the 210 pairs of the
//! 20 states agrees too, worst 3.6e-11 m, but takes a minute: mesh–mesh queries cost
//! milliseconds.)

use moma::collision::{
    ExactGeometry, GeometryData, GeometryModel, GeometryOptions, PairSelection,
    compute_exact_distances, update_geometry_placements,
};
use moma::kinematics::forward_kinematics;
use moma::multibody::{Data, RootJoint};
use nalgebra::DVector;
use serde_json::Value;
use std::path::Path;

#[test]
fn fetch_mesh_distances_match_coal() {
    let data_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data");
    let dir = data_dir.join("robots/fetch");
    let urdf = dir.join("fetch_description/robots/fetch.urdf");
    let model = moma::io::urdf::model_from_urdf_file(&urdf, RootJoint::Fixed).unwrap();
    let opts = GeometryOptions {
        package_dirs: vec![dir.clone()],
        srdf: Some(dir.join("fetch.srdf")),
    };
    let gm = GeometryModel::from_urdf(&model, &urdf, &opts).unwrap();
    let ex = ExactGeometry::new(&gm).unwrap();
    let text = std::fs::read_to_string(data_dir.join("collision/fetch_self_public.json")).unwrap();
    let r: Value = serde_json::from_str(&text).unwrap();
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
    let (mut worst, mut zeros, mut checked) = (0.0_f64, 0, 0);
    for s in r["states"].as_array().unwrap() {
        let mut q = DVector::zeros(model.nq);
        for (name, v) in s["q_by_joint"].as_object().unwrap() {
            let j = model.joint_id(name).unwrap();
            q[model.idx_q[j.0]] = v.as_f64().unwrap();
        }
        forward_kinematics(&model, &mut data, &q);
        update_geometry_placements(&gm, &data, &mut gd);
        compute_exact_distances(&gm, &ex, &mut gd, PairSelection::Enabled);
        let convex = s["distance_convex"].as_array().unwrap();
        for (k, want) in s["distance_mesh"].as_array().unwrap().iter().enumerate() {
            if !gm.enabled[pairs[k]] {
                continue;
            }
            let want = want.as_f64().unwrap();
            let res = &gd.results[pairs[k]];
            let err = (res.distance - want).abs();
            assert!(
                err <= 1e-6,
                "state {} pair {:?}: exact {} vs coal {want}",
                s["index"],
                r["pairs"][k],
                res.distance
            );
            // Never below the hulls' distance; the witnesses are the distance apart.
            assert!(res.distance >= convex[k].as_f64().unwrap() - 1e-9);
            assert!(((res.witness_b - res.witness_a).norm() - res.distance).abs() < 1e-9);
            worst = worst.max(err);
            zeros += usize::from(want == 0.0);
            checked += 1;
        }
    }
    eprintln!("{checked} pairs, {zeros} touching, worst error {worst:e} m");
    assert!(checked == 76 * 20 && zeros > 0, "{checked} {zeros}");
}

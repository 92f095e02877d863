//! Fetch's and Panda's collision geometry against coal 3.0.3 (through Pinocchio 4.1.0), the
//! same checks for both robots: every link pair of every state of
//! `tests/data/collision/{fetch,panda}_self*.json` (see its SOURCES.md), the distance
//! between convex hulls to 1e-6 m, unique witness points to 1e-5 m, the SRDF-enabled pairs,
//! the minimum over them and the in-collision verdicts exactly; and every (link, object)
//! pair of the robots against their scenes (Fetch: three MotionBenchMaker scenes; Panda: a
//! table, a box and a post in its base frame) with the same tolerances.

use moma::collision::{
    GeometryData, GeometryModel, PairSelection, SceneData, SceneOptions, compute_collision,
    compute_distances, compute_scene_distances, read_scene, scene_collision,
    update_geometry_placements,
};
use moma::kinematics::forward_kinematics;
use moma::multibody::{Data, Model, RootJoint};
use nalgebra::DVector;
use serde_json::Value;
use std::path::Path;

mod fetch_common;
use fetch_common::{data_dir, fetch_geometry, panda_geometry};

fn fetch() -> (Model, GeometryModel) {
    fetch_geometry(RootJoint::Fixed)
}

/// Panda (example-robot-data's URDF: STL meshes, four boxes per finger) with its SRDF.
fn panda() -> (Model, GeometryModel) {
    let (model, gm) = panda_geometry();
    assert_eq!(gm.objects.len(), 17);
    (model, gm)
}

fn read_reference(file: &str) -> Value {
    let text = std::fs::read_to_string(data_dir().join("collision").join(file)).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn q_of(model: &Model, state: &Value) -> DVector<f64> {
    let mut q = DVector::zeros(model.nq);
    for (name, v) in state["q_by_joint"].as_object().unwrap() {
        let j = model.joint_id(name).unwrap();
        q[model.idx_q[j.0]] = v.as_f64().unwrap();
    }
    q
}

fn vec3(v: &Value) -> [f64; 3] {
    let a = v.as_array().unwrap();
    [0, 1, 2].map(|i| a[i].as_f64().unwrap())
}

/// What a comparison covered: unique witness pairs, and the verdicts compared (in
/// collision, free).
#[derive(Debug, Default)]
struct Checked {
    witnesses: usize,
    hits: usize,
    frees: usize,
}

#[test]
fn fetch_self_distances_match_coal() {
    let (model, gm) = fetch();
    let c = check_self(&model, &gm, &read_reference("fetch_self_public.json"));
    assert!(c.witnesses > 1000 && c.hits > 0 && c.frees > 0, "{c:?}");
}

#[test]
fn panda_self_distances_match_coal() {
    let (model, gm) = panda();
    let r = read_reference("panda_self.json");
    assert!(r["states"].as_array().unwrap().len() >= 60);
    let c = check_self(&model, &gm, &r);
    assert!(c.witnesses > 1000 && c.hits >= 5 && c.frees > 0, "{c:?}");
}

#[test]
fn fetch_scene_distances_match_coal() {
    let (model, gm) = fetch();
    let r = read_reference("fetch_scene_public.json");
    let scenes = data_dir().join("scenes/motion_bench_maker");
    let c = check_scenes(&model, &gm, &r, &scenes, "base_link");
    assert!(c.witnesses > 1000 && c.hits > 0 && c.frees > 0, "{c:?}");
}

#[test]
fn panda_scene_distances_match_coal() {
    let (model, gm) = panda();
    let r = read_reference("panda_scene.json");
    assert!(r["states"].as_array().unwrap().len() >= 30);
    let c = check_scenes(&model, &gm, &r, &data_dir(), "panda_link0");
    assert!(c.witnesses > 1000 && c.hits >= 5 && c.frees > 0, "{c:?}");
}

/// Every pair of every state of a self reference: distances, unique witnesses, the
/// enabled pairs, the minimum over them and the verdict (skipped when |min| <= 1e-6).
fn check_self(model: &Model, gm: &GeometryModel, r: &Value) -> Checked {
    let mut data = Data::new(model);
    let mut gd = GeometryData::new(gm);
    // The pairs: same links, and the enabled set equals the reference's.
    let pairs = r["pairs"].as_array().unwrap();
    assert_eq!(gm.pairs.len(), pairs.len());
    let index: Vec<usize> = pairs
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
    let swapped: Vec<bool> = pairs
        .iter()
        .zip(&index)
        .map(|(p, &k)| gm.links[gm.pairs[k][0]].name != p[0].as_str().unwrap())
        .collect();
    for (k, e) in r["pair_enabled"].as_array().unwrap().iter().enumerate() {
        assert_eq!(
            gm.enabled[index[k]],
            e.as_bool().unwrap(),
            "pair {:?}",
            pairs[k]
        );
    }
    let (mut worst_d, mut worst_w, mut checked) = (0.0f64, 0.0f64, Checked::default());
    for s in r["states"].as_array().unwrap() {
        let q = q_of(model, s);
        forward_kinematics(model, &mut data, &q);
        update_geometry_placements(gm, &data, &mut gd);
        compute_distances(gm, &mut gd, PairSelection::All);
        let label = s["label"].as_str().unwrap();
        for (k, p) in pairs.iter().enumerate() {
            let got = gd.results[index[k]];
            let want = s["distance_convex"][k].as_f64().unwrap();
            let err = (got.distance - want).abs();
            worst_d = worst_d.max(err);
            assert!(err <= 1e-6, "{label} {p}: {} vs coal {want}", got.distance);
            if s["witness_unique"][k].as_bool() == Some(true) {
                let (wa, wb) = if swapped[k] {
                    (got.witness_b, got.witness_a)
                } else {
                    (got.witness_a, got.witness_b)
                };
                for (mine, theirs) in [(wa, &s["witness_a"][k]), (wb, &s["witness_b"][k])] {
                    let t = vec3(theirs);
                    for i in 0..3 {
                        let e = (mine[i] - t[i]).abs();
                        worst_w = worst_w.max(e);
                        assert!(e <= 1e-5, "{label} {p}: witness {mine:?} vs coal {t:?}");
                    }
                }
                checked.witnesses += 1;
            }
        }
        // The minimum and the verdict over the enabled pairs.
        let min = compute_distances(gm, &mut gd, PairSelection::Enabled);
        let want_min = s["min_enabled_convex"].as_f64().unwrap();
        assert!(
            (min - want_min).abs() <= 1e-6,
            "{label}: min {min} vs {want_min}"
        );
        let hit = compute_collision(gm, &mut gd).is_some();
        if want_min.abs() > 1e-6 {
            assert_eq!(hit, s["in_collision_enabled"].as_bool().unwrap(), "{label}");
            count_verdict(&mut checked, hit);
        }
    }
    eprintln!(
        "{}: worst distance error {worst_d:e} m, worst witness error {worst_w:e} m over {} unique pairs; verdicts: {} in collision, {} free",
        r["robot"].as_str().unwrap(),
        checked.witnesses,
        checked.hits,
        checked.frees
    );
    checked
}

fn count_verdict(checked: &mut Checked, hit: bool) {
    if hit {
        checked.hits += 1;
    } else {
        checked.frees += 1;
    }
}

/// Every (link, object) pair of every state of a scene reference (scene YAMLs under
/// `scene_dir`, poses in `base`): distances, unique witnesses, the minimum and the verdict.
fn check_scenes(
    model: &Model,
    gm: &GeometryModel,
    r: &Value,
    scene_dir: &Path,
    base: &str,
) -> Checked {
    let mut data = Data::new(model);
    let mut gd = GeometryData::new(gm);
    let opts = SceneOptions {
        world_frames: vec![base.into(), "world".into()],
        package_dirs: vec![],
    };
    let (mut worst_d, mut worst_w, mut checked) = (0.0f64, 0.0f64, Checked::default());
    for (name, sc) in r["scenes"].as_object().unwrap() {
        let yaml = scene_dir.join(sc["scene_yaml"].as_str().unwrap());
        let scene = read_scene(&yaml, &opts).unwrap();
        let mut sd = SceneData::new(gm, &scene);
        let pairs = sc["pairs"].as_array().unwrap();
        let index: Vec<usize> = pairs
            .iter()
            .map(|p| {
                let l = gm.link_index(p[0].as_str().unwrap()).unwrap();
                let o = scene
                    .objects
                    .iter()
                    .position(|o| o.id == p[1].as_str().unwrap())
                    .unwrap();
                l * scene.objects.len() + o
            })
            .collect();
        assert_eq!(pairs.len(), gm.links.len() * scene.objects.len(), "{name}");
        for s in r["states"]
            .as_array()
            .unwrap()
            .iter()
            .filter(|s| s["scene"] == name.as_str())
        {
            let q = q_of(model, s);
            forward_kinematics(model, &mut data, &q);
            update_geometry_placements(gm, &data, &mut gd);
            let min = compute_scene_distances(gm, &mut gd, &scene, &mut sd);
            let label = format!("{name} {}", s["label"].as_str().unwrap());
            for (k, p) in pairs.iter().enumerate() {
                let got = sd.results[index[k]];
                let want = s["distance_convex"][k].as_f64().unwrap();
                worst_d = worst_d.max((got.distance - want).abs());
                assert!(
                    (got.distance - want).abs() <= 1e-6,
                    "{label} {p}: {} vs coal {want}",
                    got.distance
                );
                if s["witness_unique"][k].as_bool() == Some(true) {
                    for (mine, theirs) in [
                        (got.witness_a, &s["witness_a"][k]),
                        (got.witness_b, &s["witness_b"][k]),
                    ] {
                        let t = vec3(theirs);
                        for i in 0..3 {
                            let e = (mine[i] - t[i]).abs();
                            worst_w = worst_w.max(e);
                            assert!(e <= 1e-5, "{label} {p}: witness {mine:?} vs coal {t:?}");
                        }
                    }
                    checked.witnesses += 1;
                }
            }
            let want_min = s["min_distance"].as_f64().unwrap();
            assert!(
                (min - want_min).abs() <= 1e-6,
                "{label}: min {min} vs {want_min}"
            );
            if want_min.abs() > 1e-6 {
                let hit = scene_collision(gm, &gd, &scene, &mut sd).is_some();
                assert_eq!(hit, s["in_collision"].as_bool().unwrap(), "{label}");
                count_verdict(&mut checked, hit);
            }
        }
    }
    eprintln!(
        "{} scenes: worst distance error {worst_d:e} m, worst witness error {worst_w:e} m over {} unique pairs; verdicts: {} in collision, {} free",
        r["robot"].as_str().unwrap(),
        checked.witnesses,
        checked.hits,
        checked.frees
    );
    checked
}

//! The stability measures of a full multibody robot (Panda on a planar base) against the
//! public reference cases (an independent computation from Pinocchio's centroidal
//! momentum rate): wrench, support, ZMP, per-edge FA and MHS, minima and acceleration
//! limits; plus the no-allocation guarantee of `evaluate`.

use moma::io::urdf::model_from_urdf_file;
use moma::multibody::{Data, RootJoint};
use moma::stability::{
    BodySet, ExternalLoads, PointForce, StabilityData, StabilityModel, SupportAttachment,
    SupportPolygon, evaluate,
};
use nalgebra::{DVector, Vector2, Vector3};
use serde_json::Value;

fn cases() -> Value {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/stability/multibody_public.json"
    );
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn vecf(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn v3(v: &Value) -> Vector3<f64> {
    Vector3::from_column_slice(&vecf(v))
}

fn close(got: f64, want: f64, what: &str) {
    let tol = 1e-9 * (1.0 + want.abs());
    assert!((got - want).abs() < tol, "{what}: got {got}, want {want}");
}

fn close_opt(got: Option<f64>, want: &Value, what: &str) {
    match want.as_f64() {
        Some(w) => close(got.unwrap_or_else(|| panic!("{what}: None")), w, what),
        None => assert_eq!(got, None, "{what}"),
    }
}

#[test]
fn public_multibody_cases() {
    let j = cases();
    let urdf = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/pinocchio/urdf/panda.urdf"
    );
    let model = model_from_urdf_file(urdf, RootJoint::Planar).unwrap();
    let mut data = Data::new(&model);
    for (k, c) in j["cases"].as_array().unwrap().iter().enumerate() {
        let ctx = format!("case {k} ({} {})", c["kind"], c["mhs_bodies"]);
        let pts: Vec<_> = c["support_base"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| {
                let p = vecf(p);
                Vector2::new(p[0], p[1])
            })
            .collect();
        let support = SupportPolygon::from_points(&pts).unwrap();
        let bodies: BodySet = c["mhs_bodies"].as_str().unwrap().parse().unwrap();
        let sm = StabilityModel::new(&model, support, SupportAttachment::Base, &bodies)
            .unwrap()
            .with_gravity(v3(&c["gravity"]))
            .unwrap();
        let mut sd = StabilityData::new(&sm);
        let st = &c["state"];
        let q = DVector::from_vec(vecf(&st["q"]));
        let v = DVector::from_vec(vecf(&st["v"]));
        let a = DVector::from_vec(vecf(&st["a"]));
        let forces: Vec<PointForce> = st["external"]
            .as_array()
            .map(|l| {
                l.iter()
                    .map(|e| PointForce {
                        point: v3(&e["point"]),
                        force: v3(&e["force"]),
                    })
                    .collect()
            })
            .unwrap_or_default();
        let ext = ExternalLoads {
            forces: &forces,
            moments: &[],
        };
        evaluate(&model, &mut data, &sm, &mut sd, &q, &v, &a, &ext);
        let e = &c["expected"];
        let (w, r) = (&sd.wrench, &sd.report);
        close(
            w.mass,
            e["total_mass"].as_f64().unwrap(),
            &format!("{ctx} mass"),
        );
        for i in 0..3 {
            close(w.com[i], vecf(&e["com"])[i], &format!("{ctx} com"));
            close(w.force[i], vecf(&e["giw"]["force"])[i], &format!("{ctx} f"));
            let n = vecf(&e["giw"]["moment_about_com"])[i];
            close(w.moment_about_com[i], n, &format!("{ctx} n"));
        }
        let sup = e["support"].as_array().unwrap();
        assert_eq!(sup.len(), sd.support.len(), "{ctx}");
        for (i, p) in sup.iter().enumerate() {
            assert!(
                (sd.support.vertex(i) - v3(p)).norm() < 1e-12,
                "{ctx} vertex {i}"
            );
        }
        let zmp = r.zmp.unwrap();
        assert!((zmp - v3(&e["zmp"])).norm() < 1e-9, "{ctx} zmp");
        close_opt(r.zmp_margin, &e["zmp_margin"], &format!("{ctx} margin"));
        assert_eq!(
            r.zmp_critical_edge,
            e["zmp_critical_edge"].as_u64().map(|x| x as usize),
            "{ctx}"
        );
        for (i, ee) in e["edges"].as_array().unwrap().iter().enumerate() {
            let g = &r.edges[i];
            let ed = sd.support.edge(i);
            assert!((ed.from - v3(&ee["from"])).norm() < 1e-12);
            assert!((ed.to - v3(&ee["to"])).norm() < 1e-12);
            let x = |n: &str| format!("{ctx} edge {i} {n}");
            close_opt(g.zmp_distance, &ee["zmp_distance"], &x("s"));
            close_opt(g.force_angle, &ee["force_angle"], &x("θ"));
            close_opt(
                g.force_angle_no_couple,
                &ee["force_angle_no_couple"],
                &x("θ'"),
            );
            close_opt(g.force_angle_beta, &ee["force_angle_beta"], &x("β"));
            close(g.moment, ee["moment"].as_f64().unwrap(), &x("M"));
            close(g.inertia, ee["inertia"].as_f64().unwrap(), &x("I"));
            close_opt(g.mhs, &ee["mhs"], &x("mhs"));
        }
        close_opt(
            r.force_angle_min,
            &e["force_angle_min"],
            &format!("{ctx} θmin"),
        );
        close_opt(
            r.force_angle_alpha,
            &e["force_angle_alpha"],
            &format!("{ctx} α"),
        );
        close_opt(
            r.force_angle_beta_min,
            &e["force_angle_beta_min"],
            &format!("{ctx} β"),
        );
        close_opt(r.mhs_min, &e["mhs_min"], &format!("{ctx} mhs"));
        if let Some(lim) = e.get("acceleration_limits") {
            let l = sd.acceleration_limits(&sm);
            for (name, got) in [
                ("forward", l.forward),
                ("backward", l.backward),
                ("left", l.left),
                ("right", l.right),
            ] {
                close_opt(got, &lim[name], &format!("{ctx} a_{name}"));
            }
        }
        assert_eq!(r.stable, r.zmp_margin.unwrap() > 0.0);
    }
}

//! Tip-over measures against the worked box example of the theory notes (1.6, tolerance
//! 1e-6) and the properties a test can check (1.8, items 1–9): polygon order, ZMP
//! formulas, cross-measure identities, yaw invariance, height sensitivity, the moment
//! couple, the Moment-Height inertia, lift-off.

use moma::multibody::{Data, JointIndex, JointLimits, JointType, Model, ModelBuilder};
use moma::spatial::{Inertia, SE3};
use moma::stability::{
    BodySet, ExternalLoads, GravitoInertialWrench, PointForce, StabilityData, StabilityModel,
    StabilityReport, SupportAttachment, SupportPolygon, evaluate, evaluate_measures,
    gravito_inertial_wrench, gravito_inertial_wrench_per_body,
};
use nalgebra::{DVector, Matrix3, Vector2, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde_json::Value;

const TOL: f64 = 1e-6;

fn box_json() -> Value {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/stability/tipover_box.json"
    );
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

fn v3(v: &Value) -> Vector3<f64> {
    Vector3::new(
        v[0].as_f64().unwrap(),
        v[1].as_f64().unwrap(),
        v[2].as_f64().unwrap(),
    )
}

fn box_contacts() -> Vec<Vector2<f64>> {
    vec![
        Vector2::new(0.5, 0.3),
        Vector2::new(0.5, -0.3),
        Vector2::new(-0.5, -0.3),
        Vector2::new(-0.5, 0.3),
    ]
}

/// Our edge index of the theory's named edges: our polygon starts at (−0.5, −0.3), so
/// edge 0 = rear, 1 = left, 2 = front, 3 = right.
fn our_edge(name: &str) -> usize {
    match name {
        "rear" => 0,
        "left" => 1,
        "front" => 2,
        "right" => 3,
        _ => panic!("{name}"),
    }
}

/// The box robot as a multibody: a free-flying 40 kg box (origin at its CoM) carrying a
/// 10 kg point mass on three prismatic joints (x, y, z), so that any platform and arm
/// accelerations of the worked example can be imposed.
fn box_model() -> Model {
    let mut b = ModelBuilder::new("box");
    let base = b
        .add_joint(
            JointIndex(0),
            "base",
            JointType::FreeFlyer,
            SE3::identity(),
            JointLimits::unlimited(),
        )
        .unwrap();
    let ic = Matrix3::from_diagonal(&Vector3::new(
        1.733_333_333_333_333_4,
        3.866_666_666_666_667,
        4.533_333_333_333_333,
    ));
    b.append_body_inertia(
        base,
        &Inertia::new(40.0, Vector3::zeros(), ic),
        &SE3::identity(),
    )
    .unwrap();
    let px = b
        .add_joint(
            base,
            "px",
            JointType::PrismaticX,
            SE3::from_translation(Vector3::new(0.5, 0.0, 0.6)),
            JointLimits::unlimited(),
        )
        .unwrap();
    let py = b
        .add_joint(
            px,
            "py",
            JointType::PrismaticY,
            SE3::identity(),
            JointLimits::unlimited(),
        )
        .unwrap();
    let pz = b
        .add_joint(
            py,
            "pz",
            JointType::PrismaticZ,
            SE3::identity(),
            JointLimits::unlimited(),
        )
        .unwrap();
    b.append_body_inertia(
        pz,
        &Inertia::point_mass(10.0, Vector3::zeros()),
        &SE3::identity(),
    )
    .unwrap();
    b.build().unwrap()
}

/// The state `(q, v, a)` of the box model that realises a case of the worked example.
fn box_state(case: &Value) -> (DVector<f64>, DVector<f64>, DVector<f64>) {
    let mut q = DVector::zeros(10);
    q[2] = 0.2;
    q[6] = 1.0;
    let v = DVector::zeros(9);
    let ap = v3(&case["acc_platform"]);
    let aa = v3(&case["acc_arm"]);
    let hdot = v3(&case["hdot_platform_about_own_com"]);
    let ic = Matrix3::from_diagonal(&Vector3::new(
        1.733_333_333_333_333_4,
        3.866_666_666_666_667,
        4.533_333_333_333_333,
    ));
    let wd = ic.try_inverse().unwrap() * hdot;
    let rel = aa - ap - wd.cross(&Vector3::new(0.5, 0.0, 0.6));
    let mut a = DVector::zeros(9);
    for k in 0..3 {
        a[k] = ap[k];
        a[3 + k] = wd[k];
        a[6 + k] = rel[k];
    }
    (q, v, a)
}

fn check_case_report(case: &Value, r: &StabilityReport, what: &str) {
    let name = case["case"].as_str().unwrap();
    let ctx = format!("{what} {name}");
    let zmp = r.zmp.unwrap();
    let ez = v3(&case["zmp"]);
    assert!(
        (zmp.xy() - ez.xy()).norm() < TOL,
        "{ctx}: zmp {zmp} vs {ez}"
    );
    assert!((r.zmp_margin.unwrap() - case["zmp_margin"].as_f64().unwrap()).abs() < TOL);
    for (edge, s) in case["edge_signed_distance"].as_object().unwrap() {
        let i = our_edge(edge);
        let got = r.edges[i].zmp_distance.unwrap();
        assert!(
            (got - s.as_f64().unwrap()).abs() < TOL,
            "{ctx} {edge}: s {got}"
        );
    }
    for fa in case["force_angle"].as_array().unwrap() {
        let i = our_edge(fa["edge"].as_str().unwrap());
        let e = &r.edges[i];
        let theta = fa["theta"].as_f64().unwrap();
        assert!((e.force_angle.unwrap() - theta).abs() < TOL, "{ctx} θ {i}");
        assert!((e.lever.unwrap() - fa["d_norm"].as_f64().unwrap()).abs() < TOL);
        let beta = fa["beta_2000"].as_f64().unwrap();
        assert!(
            (e.force_angle_beta.unwrap() - beta).abs() < TOL,
            "{ctx} β {i}"
        );
    }
    for fa in case["force_angle_without_moment_term"].as_array().unwrap() {
        let i = our_edge(fa["edge"].as_str().unwrap());
        let theta = fa["theta"].as_f64().unwrap();
        let got = r.edges[i].force_angle_no_couple.unwrap();
        assert!((got - theta).abs() < TOL, "{ctx} θ' {i}: {got} vs {theta}");
    }
    for m in case["mhs"].as_array().unwrap() {
        let i = our_edge(m["edge"].as_str().unwrap());
        let e = &r.edges[i];
        assert!(
            (e.moment - m["M_axis"].as_f64().unwrap()).abs() < TOL,
            "{ctx} M {i}"
        );
        assert!((e.inertia - m["I_arm_axis"].as_f64().unwrap()).abs() < TOL);
        let mhs = m["mhs_arm_inverse"].as_f64().unwrap();
        assert!((e.mhs.unwrap() - mhs).abs() < TOL, "{ctx} mhs {i}");
    }
    let close = |x: Option<f64>, key: &str| {
        let want = case[key].as_f64().unwrap();
        assert!(
            (x.unwrap() - want).abs() < TOL,
            "{ctx} {key}: {x:?} vs {want}"
        );
    };
    close(r.force_angle_min, "fa_theta_min");
    close(r.force_angle_alpha, "fa_alpha_min");
    close(r.force_angle_beta_min, "fa_beta_min");
    close(r.mhs_min, "mhs_arm_inverse_min");
}

/// 1.8 item 3: every number of the worked example (1.6), from the wrench of the
/// reference and from the full multibody pipeline of the box model.
#[test]
fn worked_box_example_numbers() {
    let j = box_json();
    let support = SupportPolygon::from_points(&box_contacts()).unwrap();
    let arm = Inertia::point_mass(10.0, Vector3::new(0.5, 0.0, 0.8));
    let model = box_model();
    let mut data = Data::new(&model);
    let arm_set = BodySet::Subtree("px".into());
    let sm = StabilityModel::new(&model, support.clone(), SupportAttachment::World, &arm_set)
        .unwrap()
        .with_gravity(Vector3::new(0.0, 0.0, -9.81))
        .unwrap();
    let mut sd = StabilityData::new(&sm);
    for case in j["cases"].as_array().unwrap() {
        let name = case["case"].as_str().unwrap();
        // (a) from the reference wrench
        let w = GravitoInertialWrench {
            mass: 50.0,
            com: v3(&case["com"]),
            force: v3(&case["f_r"]),
            moment_about_com: v3(&case["n_r_about_com"]),
        };
        let mut r = StabilityReport::default();
        evaluate_measures(&w, &support, &arm, &mut r);
        if name != "critical_braking" {
            check_case_report(case, &r, "wrench");
        }
        // (b) from the multibody state
        let (q, v, a) = box_state(case);
        let push = [PointForce {
            point: Vector3::new(0.5, 0.0, 0.8),
            force: v3(&case["f_ext_at_arm_point"]),
        }];
        let ext = ExternalLoads {
            forces: &push,
            moments: &[],
        };
        evaluate(&model, &mut data, &sm, &mut sd, &q, &v, &a, &ext);
        let (w, r) = (&sd.wrench, &sd.report);
        assert!((w.mass - 50.0).abs() < 1e-12);
        assert!((w.com - v3(&case["com"])).norm() < 1e-12, "{name}");
        assert!(
            (w.force - v3(&case["f_r"])).norm() < 1e-9,
            "{name}: {}",
            w.force
        );
        let n_r = v3(&case["n_r_about_com"]);
        assert!(
            (w.moment_about_com - n_r).norm() < 1e-9,
            "{name}: {}",
            w.moment_about_com
        );
        if name == "critical_braking" {
            // 1.8 item 4: all three per-edge values vanish together on the front edge.
            let front = &r.edges[our_edge("front")];
            assert!(front.zmp_distance.unwrap().abs() < 1e-9);
            assert!(front.force_angle.unwrap().abs() < 1e-9);
            assert!(front.force_angle_beta.unwrap().abs() < 1e-9);
            assert!(front.moment.abs() < 1e-9);
            assert_eq!(r.zmp_critical_edge, Some(our_edge("front")));
        } else {
            check_case_report(case, r, "multibody");
        }
        let want_edge = our_edge(case["zmp_critical_edge"].as_str().unwrap());
        // the theory's tie right/left (static, 0.3 both) resolves to our lowest index
        let tie_ok = name == "static" && r.zmp_critical_edge == Some(our_edge("left"));
        assert!(r.zmp_critical_edge == Some(want_edge) || tie_ok, "{name}");
    }
    // The system-inertia variant of the reference: the whole body set.
    let sm_all =
        StabilityModel::new(&model, support, SupportAttachment::World, &BodySet::All).unwrap();
    let mut sd = StabilityData::new(&sm_all);
    let case = &j["cases"][0];
    let (q, v, a) = box_state(case);
    let r = evaluate(
        &model,
        &mut data,
        &sm_all,
        &mut sd,
        &q,
        &v,
        &a,
        &ExternalLoads::NONE,
    );
    for m in case["mhs"].as_array().unwrap() {
        let i = our_edge(m["edge"].as_str().unwrap());
        let want = m["I_system_axis"].as_f64().unwrap();
        assert!((r.edges[i].inertia - want).abs() < TOL);
    }
    let want = case["mhs_system_inverse_min"].as_f64().unwrap();
    assert!((r.mhs_min.unwrap() - want).abs() < TOL);
    // 1.6: at 1.2 a* the front values of the theory text
    let tip = &j["cases"][4];
    let (q, v, a) = box_state(tip);
    let sm = StabilityModel::new(
        &model,
        sm_all.support.clone(),
        SupportAttachment::World,
        &BodySet::Subtree("px".into()),
    )
    .unwrap();
    let mut sd = StabilityData::new(&sm);
    let r = evaluate(
        &model,
        &mut data,
        &sm,
        &mut sd,
        &q,
        &v,
        &a,
        &ExternalLoads::NONE,
    );
    let f = &r.edges[our_edge("front")];
    assert!((f.force_angle.unwrap() + 0.086738).abs() < 1e-6);
    assert!((f.force_angle_beta.unwrap() + 3.4036).abs() < 1e-4);
    assert!((f.moment + 39.24).abs() < 1e-9);
    assert!((f.mhs.unwrap() + 6.1312).abs() < 1e-4);
    assert!(!r.stable);
}

/// 1.8 item 1: any input order and both orientations give the same polygon and margins.
#[test]
fn polygon_orientation_and_interior_points() {
    let cw = box_contacts();
    let mut ccw = cw.clone();
    ccw.reverse();
    let mut with_inner = ccw.clone();
    with_inner.insert(1, Vector2::new(0.0, 0.1));
    with_inner.push(Vector2::new(0.5, 0.0)); // on the front edge
    let w = GravitoInertialWrench {
        mass: 50.0,
        com: Vector3::new(0.1, 0.0, 0.32),
        force: Vector3::new(160.0, -110.0, -500.5),
        moment_about_com: Vector3::new(4.4, 9.4, -5.5),
    };
    let set = Inertia::point_mass(10.0, Vector3::new(0.5, 0.0, 0.8));
    let mut reports = Vec::new();
    for pts in [&cw, &ccw, &with_inner] {
        let p = SupportPolygon::from_points(pts).unwrap();
        assert_eq!(p.len(), 4);
        let mut r = StabilityReport::default();
        evaluate_measures(&w, &p, &set, &mut r);
        reports.push(r);
    }
    assert_eq!(reports[0], reports[1]);
    assert_eq!(reports[0], reports[2]);
}

fn random_wrench(rng: &mut ChaCha8Rng) -> GravitoInertialWrench {
    let mut r = |lo: f64, hi: f64| rng.random_range(lo..hi);
    GravitoInertialWrench {
        mass: 50.0,
        com: Vector3::new(r(-0.3, 0.3), r(-0.2, 0.2), r(0.2, 1.0)),
        force: Vector3::new(r(-200.0, 200.0), r(-200.0, 200.0), r(-700.0, -100.0)),
        moment_about_com: Vector3::new(r(-30.0, 30.0), r(-30.0, 30.0), r(-30.0, 30.0)),
    }
}

fn random_polygon(rng: &mut ChaCha8Rng) -> SupportPolygon {
    let n = rng.random_range(3..9);
    let pts: Vec<_> = (0..n)
        .map(|k| {
            let ang = std::f64::consts::TAU * (k as f64 + rng.random_range(0.0..0.8)) / n as f64;
            let rad = rng.random_range(0.3..0.8);
            Vector2::new(rad * ang.cos(), rad * ang.sin())
        })
        .collect();
    SupportPolygon::from_points(&pts).unwrap()
}

/// 1.8 item 4: `M_i = |f_z| s_i` and `sign θ_i = sign M_i` on flat ground, random wrenches.
#[test]
fn cross_measure_identities_on_random_wrenches() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let set = Inertia::point_mass(5.0, Vector3::new(0.1, 0.0, 0.9));
    let mut r = StabilityReport::default();
    for _ in 0..500 {
        let w = random_wrench(&mut rng);
        let p = random_polygon(&mut rng);
        evaluate_measures(&w, &p, &set, &mut r);
        for (i, e) in r.edges.iter().enumerate() {
            let s = e.zmp_distance.unwrap();
            let scale = w.force.norm() + w.moment_about_com.norm();
            assert!(
                (e.moment - w.force.z.abs() * s).abs() < 1e-12 * scale,
                "edge {i}"
            );
            let th = e.force_angle.unwrap();
            if e.moment.abs() > 1e-9 * scale {
                assert_eq!(th > 0.0, e.moment > 0.0, "edge {i}: θ {th}, M {}", e.moment);
            }
            let b = e.force_angle_beta.unwrap();
            assert_eq!(b > 0.0, th > 0.0);
        }
        // the three minima point at the same edge sign-wise
        assert_eq!(
            r.zmp_margin.unwrap() > 0.0,
            r.force_angle_min.unwrap() > 0.0
        );
        assert_eq!(r.stable, r.zmp_margin.unwrap() > 0.0);
    }
}

/// 1.8 item 5: a yaw-only disturbance changes neither the ZMP, nor θ_i, nor M_i.
#[test]
fn yaw_moments_change_nothing() {
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let set = Inertia::point_mass(5.0, Vector3::new(0.1, 0.0, 0.9));
    let (mut r0, mut r1) = (StabilityReport::default(), StabilityReport::default());
    for _ in 0..100 {
        let w = random_wrench(&mut rng);
        let p = random_polygon(&mut rng);
        let mut w1 = w;
        w1.moment_about_com.z += rng.random_range(-50.0..50.0);
        evaluate_measures(&w, &p, &set, &mut r0);
        evaluate_measures(&w1, &p, &set, &mut r1);
        assert!((r0.zmp.unwrap() - r1.zmp.unwrap()).norm() < 1e-12);
        for (a, b) in r0.edges.iter().zip(&r1.edges) {
            assert!((a.force_angle.unwrap() - b.force_angle.unwrap()).abs() < 1e-12);
            assert!((a.moment - b.moment).abs() < 1e-10);
        }
    }
}

/// 1.8 item 6: raising the CoM at a fixed ground projection (static) lowers every θ_i and
/// β_i strictly and leaves the margin and every M_i unchanged.
#[test]
fn force_angle_is_height_sensitive() {
    let p = SupportPolygon::from_points(&box_contacts()).unwrap();
    let set = Inertia::point_mass(10.0, Vector3::new(0.5, 0.0, 0.8));
    let mut prev: Option<StabilityReport> = None;
    for k in 0..6 {
        let w = GravitoInertialWrench {
            mass: 50.0,
            com: Vector3::new(0.1, -0.05, 0.2 + 0.15 * k as f64),
            force: Vector3::new(0.0, 0.0, -490.5),
            moment_about_com: Vector3::zeros(),
        };
        let mut r = StabilityReport::default();
        evaluate_measures(&w, &p, &set, &mut r);
        if let Some(pr) = &prev {
            assert!((pr.zmp_margin.unwrap() - r.zmp_margin.unwrap()).abs() < 1e-14);
            for (a, b) in pr.edges.iter().zip(&r.edges) {
                assert!(b.force_angle.unwrap() < a.force_angle.unwrap());
                assert!(b.force_angle_beta.unwrap() < a.force_angle_beta.unwrap());
                assert!((a.moment - b.moment).abs() < 1e-12);
            }
        }
        prev = Some(r);
    }
}

/// 1.8 item 7 (second half): a pure moment about axis i moves θ_i with its sign.
#[test]
fn pure_moment_about_an_axis_moves_theta_with_its_sign() {
    let p = SupportPolygon::from_points(&box_contacts()).unwrap();
    let set = Inertia::zero();
    for i in 0..4 {
        let a = p.edge(i).axis;
        let theta = |k: f64| {
            let w = GravitoInertialWrench {
                mass: 50.0,
                com: Vector3::new(0.1, 0.0, 0.32),
                force: Vector3::new(30.0, -20.0, -490.5),
                moment_about_com: Vector3::new(1.0, -2.0, 0.5) + a * k,
            };
            let mut r = StabilityReport::default();
            evaluate_measures(&w, &p, &set, &mut r);
            (r.edges[i].force_angle.unwrap(), r.edges[i].mhs)
        };
        let (tm, mm) = theta(-20.0);
        let (t0, _) = theta(0.0);
        let (tp, _) = theta(20.0);
        assert!(tm < t0 && t0 < tp, "edge {i}: {tm} {t0} {tp}");
        assert_eq!(mm, None, "empty body set: I_i = 0, M/I undefined");
    }
}

/// 1.8 item 8: raising the arm (same horizontal position) raises I_i and lowers M_i / I_i,
/// M_i unchanged; through the multibody model (the arm's prismatic z joint).
#[test]
fn moment_height_inertia_grows_with_arm_height() {
    let model = box_model();
    let mut data = Data::new(&model);
    let support = SupportPolygon::from_points(&box_contacts()).unwrap();
    let sm = StabilityModel::new(
        &model,
        support,
        SupportAttachment::World,
        &"subtree:px".parse().unwrap(),
    )
    .unwrap();
    let mut sd = StabilityData::new(&sm);
    let mut q = DVector::zeros(10);
    q[2] = 0.2;
    q[6] = 1.0;
    let z = DVector::zeros(9);
    let r0 = evaluate(
        &model,
        &mut data,
        &sm,
        &mut sd,
        &q,
        &z,
        &z,
        &ExternalLoads::NONE,
    )
    .clone();
    q[9] = 0.5;
    let r1 = evaluate(
        &model,
        &mut data,
        &sm,
        &mut sd,
        &q,
        &z,
        &z,
        &ExternalLoads::NONE,
    )
    .clone();
    for (a, b) in r0.edges.iter().zip(&r1.edges) {
        assert!(b.inertia > a.inertia);
        assert!(b.mhs.unwrap() < a.mhs.unwrap());
        assert!((a.moment - b.moment).abs() < 1e-10);
    }
    // the MHS critical edge (rear, largest moment) differs from the ZMP's (left/right)
    let crit = |r: &StabilityReport| {
        let mut best = 0;
        for (i, e) in r.edges.iter().enumerate() {
            if e.mhs.unwrap() < r.edges[best].mhs.unwrap() {
                best = i;
            }
        }
        best
    };
    assert_eq!(crit(&r0), our_edge("rear"));
    assert_eq!(r0.zmp_critical_edge, Some(our_edge("left")));
}

/// 1.8 item 9: lift-off (upward net force) gives no ZMP, an unstable flag and
/// non-positive FA and MHS; free fall (zero wrench) leaves θ undefined, never NaN.
#[test]
fn lift_off_and_free_fall() {
    let model = box_model();
    let mut data = Data::new(&model);
    let support = SupportPolygon::from_points(&box_contacts()).unwrap();
    let sm = StabilityModel::new(&model, support, SupportAttachment::World, &BodySet::All).unwrap();
    let mut sd = StabilityData::new(&sm);
    let mut q = DVector::zeros(10);
    q[2] = 0.2;
    q[6] = 1.0;
    let v = DVector::zeros(9);
    // exact free fall (a = g: no force at all), then lifted by an upward pull above the CoM
    for pull in [0.0, 500.0, 900.0] {
        let mut a = DVector::zeros(9);
        if pull == 0.0 {
            a[2] = -9.81;
        }
        let f = [PointForce {
            point: Vector3::new(0.1, 0.0, 1.5),
            force: Vector3::new(0.0, 0.0, pull),
        }];
        let ext = ExternalLoads {
            forces: &f,
            moments: &[],
        };
        let r = evaluate(&model, &mut data, &sm, &mut sd, &q, &v, &a, &ext);
        assert_eq!(r.zmp, None);
        assert_eq!(r.zmp_margin, None);
        assert_eq!(r.zmp_critical_edge, None);
        assert!(!r.stable);
        for e in &r.edges {
            assert_eq!(e.zmp_distance, None);
            assert!(e.moment <= 1e-12, "M {}", e.moment);
            assert!(e.mhs.unwrap() <= 1e-12);
            if pull > 0.0 {
                assert!(e.force_angle.unwrap() < 0.0);
                assert!(e.force_angle_beta.unwrap() < 0.0);
            } else {
                assert_eq!(e.force_angle, None);
                assert_eq!(e.force_angle_beta, None);
                assert!(e.moment.abs() < 1e-12);
            }
        }
        if pull > 0.0 {
            assert!(r.force_angle_min.unwrap() < 0.0 && r.mhs_min.unwrap() < 0.0);
        } else {
            assert_eq!(r.force_angle_min, None);
            assert_eq!(r.force_angle_alpha, None);
        }
    }
}

/// 1.8 item 2: static ZMP = CoM projection; the wrench ZMP equals the flat-ground
/// multibody formula and the two wrench implementations agree to 1e-12 on random states.
#[test]
fn zmp_formulas_and_two_wrench_implementations_agree() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/pinocchio/urdf");
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    for (file, root) in [
        ("panda.urdf", moma::multibody::RootJoint::Planar),
        ("panda.urdf", moma::multibody::RootJoint::FreeFlyer),
        ("tiago.urdf", moma::multibody::RootJoint::Planar),
        ("tiago.urdf", moma::multibody::RootJoint::FreeFlyer),
    ] {
        let model = moma::io::urdf::model_from_urdf_file(format!("{dir}/{file}"), root).unwrap();
        let mut data = Data::new(&model);
        let mut data2 = Data::new(&model);
        for trial in 0..20 {
            let mut q = moma::kinematics::random_configuration(&model, &mut rng);
            if root == moma::multibody::RootJoint::FreeFlyer {
                for k in 0..3 {
                    q[k] = rng.random_range(-1.0..1.0);
                }
            }
            let mut rv = |n| DVector::from_fn(n, |_, _| rng.random_range(-2.0..2.0));
            let v = rv(model.nv);
            let a = rv(model.nv);
            let g = if trial % 2 == 0 {
                Vector3::new(0.0, 0.0, -9.81)
            } else {
                Vector3::new(0.7, -0.4, -9.5)
            };
            let pf = [PointForce {
                point: Vector3::new(0.3, -0.2, 1.1),
                force: Vector3::new(5.0, -3.0, 2.0),
            }];
            let mom = [Vector3::new(0.5, 1.5, -0.3)];
            let ext = ExternalLoads {
                forces: &pf,
                moments: &mom,
            };
            let w1 = gravito_inertial_wrench(&model, &mut data, &q, &v, &a, &g, &ext);
            let w2 = gravito_inertial_wrench_per_body(&model, &mut data2, &q, &v, &a, &g, &ext);
            let ctx = format!("{file} {root} trial {trial}");
            let tolf = 1e-12 * w2.force.norm().max(1.0);
            let tolm = 1e-12 * (w2.moment_about_com.norm() + w2.force.norm()).max(1.0);
            assert!((w1.mass - w2.mass).abs() < 1e-12 * w2.mass, "{ctx}");
            assert!((w1.com - w2.com).norm() < 1e-12, "{ctx}");
            assert!(
                (w1.force - w2.force).norm() < tolf,
                "{ctx}: {}",
                w1.force - w2.force
            );
            let dm = w1.moment_about_com - w2.moment_about_com;
            assert!(dm.norm() < tolm, "{ctx}: {dm}");
            // flat-ground multibody ZMP formula (theory 1.3), gravity along −z only
            if trial % 2 == 0 {
                let z = moma::stability::zero_moment_point(&w1, 0.0);
                let (x, y) = multibody_zmp(&model, &data2, 9.81, &ext);
                if let Some(z) = z {
                    let scale = 1.0 + x.abs().max(y.abs());
                    assert!((z.x - x).abs() < 1e-10 * scale, "{ctx}: {} vs {x}", z.x);
                    assert!((z.y - y).abs() < 1e-10 * scale, "{ctx}: {} vs {y}", z.y);
                }
            }
            // static: ZMP = CoM projection
            let zero = DVector::zeros(model.nv);
            let ws = gravito_inertial_wrench(
                &model,
                &mut data,
                &q,
                &zero,
                &zero,
                &g,
                &ExternalLoads::NONE,
            );
            let z = moma::stability::zero_moment_point(&ws, 0.0).unwrap();
            let proj = ws.com - g * (ws.com.z / g.z);
            assert!((z - proj).norm() < 1e-12 * (1.0 + proj.norm()), "{ctx}");
        }
    }
}

/// `x_zmp = [Σ m_k((g + z̈_k) x_k − z_k ẍ_k) − Σ Ḣ_k,y + ext] / [Σ m_k (g + z̈_k) − ext_z]`
/// (and y), per body, from kinematics already in `data`.
fn multibody_zmp(model: &Model, data: &Data, g: f64, ext: &ExternalLoads<'_>) -> (f64, f64) {
    let (mut nx, mut ny, mut den) = (0.0, 0.0, 0.0);
    for i in 1..model.njoints {
        let inertia = &model.inertias[i];
        let m = inertia.mass();
        let x = &data.world_from_joint[i];
        let c = inertia.com();
        let (vo, w) = (data.v[i].linear, data.v[i].angular);
        let (ao, wd) = (data.a[i].linear, data.a[i].angular);
        let acc = x.rotation * (ao + wd.cross(&c) + w.cross(&(vo + w.cross(&c))));
        let r = x.rotation * c + x.translation;
        let ik = x.rotation * inertia.inertia_about_com() * x.rotation.transpose();
        let (wk, wdk) = (x.rotation * w, x.rotation * wd);
        let hd = ik * wdk + wk.cross(&(ik * wk));
        nx += m * ((g + acc.z) * r.x - r.z * acc.x) - hd.y;
        ny += m * ((g + acc.z) * r.y - r.z * acc.y) + hd.x;
        den += m * (g + acc.z);
    }
    // external force f at s: moment about the origin adds (s × f); its ground terms
    for f in ext.forces {
        let (s, fv) = (f.point, f.force);
        nx += s.x * (-fv.z) + s.z * fv.x;
        ny += s.y * (-fv.z) + s.z * fv.y;
        den -= fv.z;
    }
    for n in ext.moments {
        nx += n.y;
        ny -= n.x;
    }
    (nx / den, ny / den)
}

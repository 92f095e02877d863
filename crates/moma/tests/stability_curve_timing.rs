//! The tip-over diamond of `time_parameterize_curve` keeps a loaded robot upright: a
//! Panda on a planar base, arm reaching forward, driven along a path with sharp left and
//! right curves at speed. With the four axis limits from `moma::stability` the ZMP margin
//! stays positive at every knot of the timed path (the robot translating with the base,
//! the approximation the limits make); without them the same path at the same speed
//! limits tips it.

use moma::io::urdf::model_from_urdf_file;
use moma::multibody::{Data, Model, RootJoint};
use moma::planning::curvature::SmoothPath;
use moma::planning::trajectory::{
    DiffDriveLimits, TimedPath, TipOverAcceleration, time_parameterize_curve,
};
use moma::stability::{
    BodySet, ExternalLoads, StabilityData, StabilityModel, SupportAttachment, SupportPolygon,
    evaluate,
};
use nalgebra::{DVector, Vector2};

fn setup() -> (Model, StabilityModel, DVector<f64>) {
    let urdf = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/pinocchio/urdf/panda.urdf"
    );
    let model = model_from_urdf_file(urdf, RootJoint::Planar).unwrap();
    // a narrow, long base: the lateral limits are the tight ones
    let support = SupportPolygon::from_points(&[
        Vector2::new(0.45, 0.22),
        Vector2::new(0.45, -0.22),
        Vector2::new(-0.35, -0.22),
        Vector2::new(-0.35, 0.22),
    ])
    .unwrap();
    let sm = StabilityModel::new(&model, support, SupportAttachment::Base, &BodySet::All).unwrap();
    // arm reaching forward and a little to the left: all four limits differ
    let mut q = DVector::zeros(model.nq);
    q[3] = 0.4; // panda_joint1
    q[4] = 1.2; // panda_joint2
    q[6] = -0.3; // panda_joint4
    q[8] = 1.0; // panda_joint6
    (model, sm, q)
}

/// The smallest ZMP margin over the knots, the whole robot translating with the base at
/// the knot's velocity and planar acceleration (tangential a, lateral κ v²).
fn worst_margin(model: &Model, sm: &StabilityModel, q_arm: &DVector<f64>, tp: &TimedPath) -> f64 {
    let mut data = Data::new(model);
    let mut sd = StabilityData::new(sm);
    let mut worst = f64::INFINITY;
    for k in tp.knots() {
        let mut q = q_arm.clone();
        q[0] = k.x;
        q[1] = k.y;
        q[2] = k.theta;
        let (s, c) = k.theta.sin_cos();
        let an = k.kappa * k.v * k.v;
        let mut v = DVector::zeros(model.nv);
        let mut a = DVector::zeros(model.nv);
        v[0] = k.v * c;
        v[1] = k.v * s;
        a[0] = k.a * c - an * s;
        a[1] = k.a * s + an * c;
        let r = evaluate(
            model,
            &mut data,
            sm,
            &mut sd,
            &q,
            &v,
            &a,
            &ExternalLoads::NONE,
        );
        worst = worst.min(r.zmp_margin.unwrap());
    }
    worst
}

#[test]
fn tip_over_diamond_keeps_the_zmp_inside_on_sharp_curves() {
    let (model, sm, q) = setup();
    let mut data = Data::new(&model);
    let mut sd = StabilityData::new(&sm);
    let z = DVector::zeros(model.nv);
    evaluate(
        &model,
        &mut data,
        &sm,
        &mut sd,
        &q,
        &z,
        &z,
        &ExternalLoads::NONE,
    );
    assert!(sd.report.stable);
    // base heading 0 at the evaluation: base axes = world axes
    let lim = sd.acceleration_limits(&sm);
    let inf = |x: Option<f64>| x.unwrap_or(f64::INFINITY);
    let tip = TipOverAcceleration {
        forward: inf(lim.forward),
        backward: inf(lim.backward),
        left: inf(lim.left),
        right: inf(lim.right),
    };
    let all = [tip.forward, tip.backward, tip.left, tip.right];
    assert!(all.iter().all(|x| x.is_finite() && *x > 0.0), "{tip:?}");
    // the limits differ per side (the test exercises the asymmetric diamond)
    assert!(
        tip.backward < tip.forward && tip.left != tip.right,
        "{tip:?}"
    );
    let biggest = all.iter().cloned().fold(0.0, f64::max);
    let dd = DiffDriveLimits {
        v_max: 2.5,
        omega_max: 4.0,
        a_max: 3.0 * biggest,
        alpha_max: 20.0,
    };
    // straight, sharp left curve (radius 0.5 m), straight, sharp right curve, straight
    let p = SmoothPath::from_curvature(
        [0.0, 0.0, 0.0],
        &[
            (3.0, 0.0, 0.0),
            (0.3, 0.0, 2.0),
            (0.8, 2.0, 2.0),
            (0.3, 2.0, 0.0),
            (1.5, 0.0, 0.0),
            (0.3, 0.0, -2.0),
            (1.0, -2.0, -2.0),
            (0.3, -2.0, 0.0),
            (2.0, 0.0, 0.0),
        ],
        0.01,
    )
    .unwrap();
    let free = time_parameterize_curve(&p, &dd, None, 0.0, 0.0).unwrap();
    let m_free = worst_margin(&model, &sm, &q, &free);
    assert!(
        m_free < -0.01,
        "without the limits the robot should tip: margin {m_free}"
    );
    let safe = time_parameterize_curve(&p, &dd, Some(&tip), 0.0, 0.0).unwrap();
    let m = worst_margin(&model, &sm, &q, &safe);
    assert!(m > -1e-9, "margin {m}");
    // the curves are driven at speed (the lateral limit, not a crawl) ...
    let k = safe.knots();
    let v_curve = k
        .iter()
        .filter(|q| q.kappa.abs() > 1.99)
        .map(|q| q.v)
        .fold(0.0, f64::max);
    let v_static = (tip.left.min(tip.right) / 2.0).sqrt();
    assert!(
        v_curve > 0.9 * v_static,
        "curve speed {v_curve}, static bound {v_static}"
    );
    // ... and the diamond is tight somewhere: the margin comes close to zero
    assert!(m < 0.02, "margin {m}");
    // the diamond itself holds at every knot
    for q in &k {
        let an = q.kappa * q.v * q.v;
        let ta = if q.a >= 0.0 {
            q.a / tip.forward
        } else {
            -q.a / tip.backward
        };
        let na = if an >= 0.0 {
            an / tip.left
        } else {
            -an / tip.right
        };
        assert!(ta + na <= 1.0 + 1e-7);
    }
}

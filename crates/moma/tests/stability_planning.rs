//! Tip-over acceleration limits feed the time parameterisation of planned paths: a
//! loaded Panda on a planar base with its arm reaching forward keeps its ZMP inside the
//! support along the whole timed path when the limits are passed in, and tips when they
//! are not.

use moma::io::urdf::model_from_urdf_file;
use moma::multibody::{Data, RootJoint};
use moma::planning::trajectory::{
    DiffDriveLimits, DirectionalAcceleration, TrajectoryPoint, time_parameterize,
    time_parameterize_directional,
};
use moma::stability::{
    BodySet, ExternalLoads, StabilityData, StabilityModel, SupportAttachment, SupportPolygon,
    evaluate,
};
use nalgebra::{DVector, Vector2};

fn setup() -> (moma::multibody::Model, StabilityModel, DVector<f64>) {
    let urdf = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/data/pinocchio/urdf/panda.urdf"
    );
    let model = model_from_urdf_file(urdf, RootJoint::Planar).unwrap();
    let support = SupportPolygon::from_points(&[
        Vector2::new(0.45, 0.3),
        Vector2::new(0.45, -0.3),
        Vector2::new(-0.35, -0.3),
        Vector2::new(-0.35, 0.3),
    ])
    .unwrap();
    let sm = StabilityModel::new(&model, support, SupportAttachment::Base, &BodySet::All).unwrap();
    // arm stretched forward and down a little: the CoM sits ahead of the base centre
    let mut q = DVector::zeros(model.nq);
    q[4] = 1.2; // panda_joint2
    q[6] = -0.3; // panda_joint4
    q[8] = 1.0; // panda_joint6
    (model, sm, q)
}

/// The smallest ZMP margin over the straight-segment samples, with the base translating
/// at the finite-difference acceleration of the profile.
fn worst_margin(
    model: &moma::multibody::Model,
    sm: &StabilityModel,
    q_arm: &DVector<f64>,
    traj: &[TrajectoryPoint],
) -> f64 {
    let mut data = Data::new(model);
    let mut sd = StabilityData::new(sm);
    let mut worst = f64::INFINITY;
    for w in traj.windows(2) {
        let (p, n) = (&w[0], &w[1]);
        if p.omega != 0.0 || n.omega != 0.0 || n.t <= p.t {
            continue;
        }
        let acc = (n.v - p.v) / (n.t - p.t);
        let mut q = q_arm.clone();
        q[0] = p.x;
        q[1] = p.y;
        q[2] = p.theta;
        let mut v = DVector::zeros(model.nv);
        let mut a = DVector::zeros(model.nv);
        let (s, c) = p.theta.sin_cos();
        v[0] = p.v * c;
        v[1] = p.v * s;
        a[0] = acc * c;
        a[1] = acc * s;
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
fn timed_path_with_tipover_limits_does_not_tip() {
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
    let lim = sd.acceleration_limits(&sm);
    let (fwd, bwd) = (lim.forward.unwrap(), lim.backward.unwrap());
    // the CoM is ahead of the centre: braking (backward) is the tighter limit
    assert!(bwd < fwd, "forward {fwd}, backward {bwd}");
    let dd = DiffDriveLimits {
        v_max: 2.0,
        omega_max: 1.0,
        a_max: 3.0 * fwd.max(bwd),
        alpha_max: 2.0,
    };
    let path = [[0.0, 0.0], [4.0, 0.0], [4.0, 3.0], [1.0, 5.0]];
    let free = time_parameterize(&path, None, &dd, 0.01).unwrap();
    assert!(
        worst_margin(&model, &sm, &q, &free) < 0.0,
        "unlimited profile should tip"
    );
    let accel = DirectionalAcceleration {
        forward: fwd,
        backward: bwd,
    };
    let safe = time_parameterize_directional(&path, None, &dd, Some(&accel), 0.01).unwrap();
    let m = worst_margin(&model, &sm, &q, &safe);
    assert!(m > -1e-9, "margin {m}");
    // the limits are tight: the braking phases reach the support edge
    assert!(m < 1e-6, "margin {m}");
    // every finite-difference acceleration obeys the directional limits
    for w in safe.windows(2) {
        if w[0].omega == 0.0 && w[1].omega == 0.0 && w[1].t > w[0].t {
            let acc = (w[1].v - w[0].v) / (w[1].t - w[0].t);
            assert!(acc <= fwd + 1e-9 && -acc <= bwd + 1e-9, "a = {acc}");
        }
    }
    let bad = DirectionalAcceleration {
        forward: 0.0,
        backward: 1.0,
    };
    assert!(time_parameterize_directional(&path, None, &dd, Some(&bad), 0.01).is_err());
}

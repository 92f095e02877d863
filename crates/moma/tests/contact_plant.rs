//! The contact plant (`moma::contact`) on the diff-drive arm of
//! `scenarios/robots/diffdrive_arm.urdf`: static loads against the stability module's
//! load model, trajectories against the reduced (rolling) model, slip beyond μ, lift-off
//! under a hard brake, and the bad-input errors.

use moma::contact::{CasterSpec, ContactParams, ContactPlant, ContactState, WheelSpec};
use moma::dynamics::center_of_mass;
use moma::io::urdf::model_from_urdf_file;
use moma::mobile::wheeled::{
    WheeledBase, WheeledData, WheeledModel, admissible_velocity_basis, lagrange_multipliers,
    wheel_longitudinal_forces,
};
use moma::mobile::{Caster, DiffDrive, reduced_forward_dynamics};
use moma::multibody::{Data, Model, RootJoint};
use moma::stability::{GravitoInertialWrench, contact_normal_loads};
use nalgebra::{DMatrix, DVector, Vector2, Vector3};

const KP: f64 = 200.0;
const KD: f64 = 20.0;

fn urdf_model(root: RootJoint) -> Model {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenarios/robots/diffdrive_arm.urdf");
    model_from_urdf_file(path, root).unwrap()
}

fn wheels() -> [WheelSpec; 2] {
    [
        WheelSpec {
            joint: "left_wheel_joint".into(),
            radius: 0.08,
        },
        WheelSpec {
            joint: "right_wheel_joint".into(),
            radius: 0.08,
        },
    ]
}

fn casters() -> [CasterSpec; 1] {
    [CasterSpec::on_frame("caster", 0.03)]
}

fn plant(params: ContactParams) -> ContactPlant {
    ContactPlant::new(
        urdf_model(RootJoint::FreeFlyer),
        &wheels(),
        &casters(),
        params,
    )
    .unwrap()
}

/// At rest on the ground at axle height 0.08 m, arm at `arm`.
fn start(p: &ContactPlant, arm: [f64; 3]) -> ContactState {
    let mut q0 = vec![0.0, 0.0, 0.08, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0];
    q0.extend_from_slice(&arm);
    ContactState::new(p, &q0, &vec![0.0; p.model.nv]).unwrap()
}

/// Runs the contact plant for `duration` with wheel torques `wheel(t)` and the arm held at
/// `arm` by `u = k_p (q_ref − q) − k_d q̇`; calls `each` after every step.
fn run(
    p: &ContactPlant,
    st: &mut ContactState,
    duration: f64,
    arm: [f64; 3],
    wheel: impl Fn(f64) -> [f64; 2],
    mut each: impl FnMut(&ContactState),
) {
    let n = (duration / p.params.dt).round() as usize;
    let mut u = [0.0; 5];
    for _ in 0..n {
        let w = wheel(st.t);
        u[0] = w[0];
        u[1] = w[1];
        for j in 0..3 {
            u[2 + j] = KP * (arm[j] - st.q[9 + j]) - KD * st.v[8 + j];
        }
        p.step(st, &u).unwrap();
        each(st);
    }
}

#[test]
fn at_rest_the_normal_forces_carry_the_weight_and_match_the_static_wheel_loads() {
    let p = plant(ContactParams::default());
    for arm in [[0.0, 0.3, 0.5], [0.0, 1.5, 0.0], [0.8, -1.0, 1.2]] {
        let mut st = start(&p, arm);
        run(&p, &mut st, 1.5, arm, |_| [0.0, 0.0], |_| {});
        // One more step so the reports describe the settled state.
        run(&p, &mut st, p.params.dt, arm, |_| [0.0, 0.0], |_| {});
        assert!(st.v.norm() < 1e-3, "not at rest: |v| = {}", st.v.norm());
        let weight = p.model.total_mass() * 9.81;
        let total: f64 = st.contacts.iter().map(|r| r.normal).sum();
        assert!(
            (total - weight).abs() < 1e-3 * weight,
            "normal forces {total} N vs weight {weight} N"
        );
        // Independent evaluation: the stability module's load model on the planar model
        // of the same robot, at the settled joint positions.
        let planar = urdf_model(RootJoint::Planar);
        let mut data = Data::new(&planar);
        let mut qp = DVector::zeros(planar.nq);
        qp[0] = st.q[0];
        qp[1] = st.q[1];
        qp[2] = st.yaw();
        for k in 0..5 {
            qp[3 + k] = st.joint_positions()[k];
        }
        let com = center_of_mass(&planar, &mut data, &qp);
        let mass = planar.total_mass();
        let wrench = GravitoInertialWrench {
            mass,
            com,
            force: Vector3::new(0.0, 0.0, -9.81 * mass),
            moment_about_com: Vector3::zeros(),
        };
        let base = WheeledBase {
            drive: DiffDrive::new(0.08, 0.25, 0.1).unwrap(),
            casters: vec![Caster {
                name: "rear caster".into(),
                position: [0.25, 0.0],
            }],
            wheel_joints: None,
        };
        let (s, c) = qp[2].sin_cos();
        let pts: Vec<Vector2<f64>> = base
            .support_points()
            .iter()
            .map(|b| Vector2::new(qp[0] + c * b.x - s * b.y, qp[1] + s * b.x + c * b.y))
            .collect();
        let mut loads = [0.0; 3];
        contact_normal_loads(&pts, -0.08, &wrench, &mut loads).unwrap();
        for k in 0..3 {
            let n = st.contacts[k].normal;
            eprintln!(
                "arm {arm:?} contact {k}: plant {n:.3} N, static model {:.3} N",
                loads[k]
            );
            // Tolerance 0.2 % of the weight: the settled base pitches by the difference
            // of the contacts' penetrations (about a milliradian), moving the CoM and the
            // caster's contact point by a fraction of a millimetre.
            assert!(
                (n - loads[k]).abs() < 2e-3 * weight,
                "arm {arm:?} contact {k}: {n} N vs static load {} N",
                loads[k]
            );
        }
    }
}

/// The reduced (rolling) model of the same robot: planar root, tracked wheels, exact
/// no-side-slip and rolling constraints.
fn reduced() -> WheeledModel {
    let base = WheeledBase {
        drive: DiffDrive::new(0.08, 0.25, 0.1).unwrap(),
        casters: vec![Caster {
            name: "rear caster".into(),
            position: [0.25, 0.0],
        }],
        wheel_joints: Some(["left_wheel_joint".into(), "right_wheel_joint".into()]),
    };
    WheeledModel::new(urdf_model(RootJoint::Planar), base).unwrap()
}

#[test]
fn with_high_friction_and_moderate_torques_the_contact_plant_follows_the_rolling_model() {
    let arm = [0.0, 0.3, 0.5];
    let wheel = |t: f64| {
        if (0.5..3.5).contains(&t) {
            [0.25, 0.45]
        } else {
            [0.0, 0.0]
        }
    };
    let duration = 5.0;
    let p = plant(ContactParams::default());
    let mut st = start(&p, arm);
    let mut contact_traj = Vec::new();
    let mut any_slip = false;
    let every = (0.1 / p.params.dt).round() as usize;
    let mut k = 0usize;
    run(&p, &mut st, duration, arm, wheel, |s| {
        k += 1;
        // After the first 0.2 s, in which the robot settles onto its contacts.
        any_slip |= s.t > 0.2 && s.contacts.iter().any(|r| r.slipping || r.lifted);
        if k.is_multiple_of(every) {
            let mut row = vec![s.q[0], s.q[1], s.yaw()];
            row.extend_from_slice(&s.joint_positions()[2..]);
            // The wheels' ground forces along the heading and across it (summed), applied
            // over the step just taken.
            let (sn, cs) = s.yaw().sin_cos();
            for r in &s.contacts[..2] {
                row.push(r.friction.x * cs + r.friction.y * sn);
            }
            let lat: f64 = s.contacts[..2]
                .iter()
                .map(|r| -r.friction.x * sn + r.friction.y * cs)
                .sum();
            row.push(lat);
            contact_traj.push(row);
        }
    });
    assert!(!any_slip, "a wheel slipped or lifted");

    // The same torque law on the reduced model, semi-implicit Euler at the same step.
    let wm = reduced();
    let mut wd = WheeledData::new(&wm);
    let mut q = DVector::from_vec(vec![0.0, 0.0, 0.0, 0.0, 0.0, arm[0], arm[1], arm[2]]);
    let mut vr = DVector::zeros(wm.nr());
    let mut basis = DMatrix::zeros(wm.nv(), wm.nr());
    let dt = p.params.dt;
    let n = (duration / dt).round() as usize;
    let mut reduced_traj = Vec::new();
    let mut u = [0.0; 5];
    for i in 0..n {
        let t = i as f64 * dt;
        let w = wheel(t);
        u[0] = w[0];
        u[1] = w[1];
        for j in 0..3 {
            u[2 + j] = KP * (arm[j] - q[5 + j]) - KD * vr[2 + j];
        }
        let vdot = reduced_forward_dynamics(&wm, &mut wd, &q, &vr, &u)
            .unwrap()
            .clone();
        let lambda = lagrange_multipliers(&wm, &mut wd, &q).unwrap().clone();
        let f = wheel_longitudinal_forces(&wm, lambda.as_slice(), &u);
        vr += vdot * dt;
        admissible_velocity_basis(&wm, &q, &mut basis);
        q += &basis * &vr * dt;
        if (i + 1).is_multiple_of(every) {
            // Forces of the step just taken; the axle's lateral ground force is −λ₀.
            reduced_traj.push(vec![
                q[0], q[1], q[2], q[5], q[6], q[7], f[0], f[1], -lambda[0],
            ]);
        }
    }
    let mut worst_pos: f64 = 0.0;
    let mut worst_yaw: f64 = 0.0;
    let mut worst_arm: f64 = 0.0;
    let mut worst_long: f64 = 0.0;
    let mut worst_lat: f64 = 0.0;
    let (mut largest_long, mut largest_lat) = (0.0f64, 0.0f64);
    for (i, (a, b)) in contact_traj.iter().zip(&reduced_traj).enumerate() {
        // Forces away from the torque steps at 0.5 s and 3.5 s (samples every 0.1 s),
        // where the contact plant's compliant contacts take a few milliseconds to follow.
        let t = (i + 1) as f64 * 0.1;
        if (0.65..3.45).contains(&t) || t > 3.65 {
            worst_long = worst_long.max((a[6] - b[6]).abs().max((a[7] - b[7]).abs()));
            worst_lat = worst_lat.max((a[8] - b[8]).abs());
            largest_long = largest_long.max(b[6].abs().max(b[7].abs()));
            largest_lat = largest_lat.max(b[8].abs());
        }
        worst_pos = worst_pos.max(((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt());
        worst_yaw = worst_yaw.max((a[2] - b[2]).abs());
        for j in 3..6 {
            worst_arm = worst_arm.max((a[j] - b[j]).abs());
        }
    }
    let travelled =
        (reduced_traj.last().unwrap()[0].powi(2) + reduced_traj.last().unwrap()[1].powi(2)).sqrt();
    eprintln!(
        "over {duration} s ({travelled:.3} m travelled): base position {worst_pos:.4} m, yaw {worst_yaw:.4} rad, arm joints {worst_arm:.5} rad; wheel forces: longitudinal {worst_long:.4} N (of up to {largest_long:.3} N), lateral {worst_lat:.4} N (of up to {largest_lat:.3} N)"
    );
    assert!(travelled > 2.0, "the robot should travel: {travelled} m");
    // Tolerances (measured: 2.8 mm, 2.2 mrad, 0.5 mrad): 1 cm over the 2.7 m travelled,
    // 5 mrad of heading, 2 mrad on the arm joints. The contact plant creeps (friction is
    // viscous below v_ε) and sinks into the ground by its static penetration.
    assert!(worst_pos < 0.01, "base position differs by {worst_pos} m");
    assert!(worst_yaw < 5e-3, "yaw differs by {worst_yaw} rad");
    assert!(worst_arm < 2e-3, "arm joints differ by {worst_arm} rad");
    // The contact forces against the reduced model's multipliers: each wheel's traction
    // against the rolling rows' −λ₁, −λ₂, the wheels' summed lateral force against the
    // no-side-slip row's −λ₀. Tolerances 0.05 N and 0.1 N.
    assert!(
        largest_long > 1.0 && largest_lat > 0.1,
        "forces too small to compare"
    );
    assert!(worst_long < 0.05, "traction differs by {worst_long} N");
    assert!(worst_lat < 0.1, "lateral force differs by {worst_lat} N");
}

/// Spins in place with opposite wheel torques ±`tau` for 0.5 s; returns whether a wheel
/// slipped and the largest wheel slip speed.
fn spin(mu: f64, tau: f64) -> (bool, f64) {
    let p = plant(ContactParams {
        mu,
        ..ContactParams::default()
    });
    let arm = [0.0, 0.3, 0.5];
    let mut st = start(&p, arm);
    let (mut slipped, mut worst) = (false, 0.0f64);
    run(
        &p,
        &mut st,
        0.7,
        arm,
        |t| if t >= 0.2 { [-tau, tau] } else { [0.0, 0.0] },
        |s| {
            if s.t > 0.2 {
                slipped |= s.contacts[..2].iter().any(|r| r.slipping);
                worst = worst.max(s.contacts[0].slip.norm().max(s.contacts[1].slip.norm()));
            }
        },
    );
    (slipped, worst)
}

#[test]
fn a_turn_beyond_mu_makes_the_wheels_slip() {
    // ±2 N·m at r = 0.08 m asks 25 N of each wheel along its heading, plus a lateral
    // share of the centripetal force of the CoM (0.19 m ahead of the axle, about 25 N at
    // the 3 rad/s reached after 0.5 s); the settled wheel loads are about 78 N (arm up and
    // forward), so friction carries it with μ = 1 (78 N) but not with μ = 0.3 (23 N).
    let (slipped, worst) = spin(1.0, 2.0);
    assert!(!slipped, "μ = 1 should hold: slip speed up to {worst} m/s");
    assert!(worst < 0.05, "μ = 1: slip speed {worst} m/s");
    let (slipped, worst) = spin(0.3, 2.0);
    assert!(slipped, "μ = 0.3 should slip");
    assert!(worst > 1.0, "μ = 0.3: slip speed only {worst} m/s");
}

/// Drives backwards at (−3, −3) N·m for 1 s with the arm stretched forward, then brakes
/// with (`brake`, `brake`) N·m; returns the first time a contact lifted after the first
/// 0.2 s, and which.
fn brake(brake: f64) -> Option<(f64, usize)> {
    let p = plant(ContactParams::default());
    let arm = [0.0, 1.5, 0.0];
    let mut st = start(&p, arm);
    let mut lift = None;
    run(
        &p,
        &mut st,
        1.6,
        arm,
        |t| {
            if t < 0.3 {
                [0.0, 0.0]
            } else if t < 1.3 {
                [-3.0, -3.0]
            } else {
                [brake, brake]
            }
        },
        |s| {
            if lift.is_none() && s.t > 0.2 {
                lift = s.contacts.iter().position(|r| r.lifted).map(|k| (s.t, k));
            }
        },
    );
    lift
}

#[test]
fn a_hard_brake_with_the_arm_stretched_forward_lifts_the_caster() {
    // Braking a backwards motion pushes the robot forwards: it pitches back about the
    // wheel axle, 0.19 m behind the centre of mass (arm stretched forward, CoM 0.21 m
    // high), so the caster lifts once the deceleration passes g·0.19/0.21 ≈ 8.5 m/s²,
    // which friction (μ = 1, up to g) allows.
    let (t, k) = brake(12.0).expect("the caster should lift");
    assert_eq!(k, 2, "the caster (contact 2) lifts");
    assert!(
        (1.3..1.4).contains(&t),
        "lift-off at {t} s, the brake starts at 1.3 s"
    );
    // A gentle brake (2 N·m: 50 N, 1.8 m/s²) lifts nothing.
    assert_eq!(brake(2.0), None);
}

fn err_text<T>(r: moma::Result<T>) -> String {
    match r {
        Ok(_) => panic!("should fail"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_input_names_the_field() {
    let model = || urdf_model(RootJoint::FreeFlyer);
    for (params, field) in [
        (
            ContactParams {
                mu: 0.0,
                ..ContactParams::default()
            },
            "contact.mu",
        ),
        (
            ContactParams {
                mu: -0.5,
                ..ContactParams::default()
            },
            "contact.mu",
        ),
        (
            ContactParams {
                dt: f64::NAN,
                ..ContactParams::default()
            },
            "contact.dt",
        ),
    ] {
        let e = err_text(ContactPlant::new(model(), &wheels(), &casters(), params));
        assert!(e.contains(field), "{e}");
    }
    let mut w = wheels();
    w[1].radius = 0.0;
    let e = err_text(ContactPlant::new(
        model(),
        &w,
        &casters(),
        ContactParams::default(),
    ));
    assert!(e.contains("contact.wheels[1].radius"), "{e}");
    let mut w = wheels();
    w[0].joint = "turret_joint_x".into();
    let e = err_text(ContactPlant::new(
        model(),
        &w,
        &casters(),
        ContactParams::default(),
    ));
    assert!(e.contains("turret_joint_x"), "{e}");
    let mut c = casters();
    c[0].frame = Some("nowhere".into());
    let e = err_text(ContactPlant::new(
        model(),
        &wheels(),
        &c,
        ContactParams::default(),
    ));
    assert!(e.contains("contact.casters[0].frame"), "{e}");
    let planar = urdf_model(RootJoint::Planar);
    let e = err_text(ContactPlant::new(
        planar,
        &wheels(),
        &casters(),
        ContactParams::default(),
    ));
    assert!(e.contains("free-flyer"), "{e}");

    // A stiffness the step cannot integrate: said before running.
    let p = plant(ContactParams {
        stiffness: 1e11,
        ..ContactParams::default()
    });
    let q0 = [0.0, 0.0, 0.08, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.3, 0.5];
    let v0 = [0.0; 11];
    let e = err_text(ContactState::new(&p, &q0, &v0));
    assert!(e.contains("contact.stiffness") && e.contains("dt <"), "{e}");
    // Friction's viscous branch too stiff for the step.
    let p = plant(ContactParams {
        slip_velocity: 1e-4,
        ..ContactParams::default()
    });
    let e = err_text(ContactState::new(&p, &q0, &v0));
    assert!(e.contains("contact.slip_velocity"), "{e}");

    // Below the ground at the start: the base 1 cm low puts both wheels 1 cm deep.
    let p = plant(ContactParams::default());
    let mut low = q0;
    low[2] = 0.07;
    let e = err_text(ContactState::new(&p, &low, &v0));
    assert!(
        e.contains("contact.wheels[0] 'left_wheel_joint'") && e.contains("below the ground"),
        "{e}"
    );
    // A base pitched forward by 0.1 rad about the axle puts the caster in the ground.
    let mut pitched = q0;
    let (s, c) = (0.05f64).sin_cos();
    pitched[4] = s;
    pitched[6] = c;
    let e = err_text(ContactState::new(&p, &pitched, &v0));
    assert!(e.contains("contact.casters[0] 'caster'"), "{e}");
    // Wrong lengths and a non-unit quaternion.
    let e = err_text(ContactState::new(&p, &q0[..11], &v0));
    assert!(e.contains("initial q"), "{e}");
    let mut unnorm = q0;
    unnorm[6] = 2.0;
    let e = err_text(ContactState::new(&p, &unnorm, &v0));
    assert!(e.contains("initial q[3..7]"), "{e}");
    // Inputs.
    let mut st = ContactState::new(&p, &q0, &v0).unwrap();
    let e = err_text(p.step(&mut st, &[0.0; 4]));
    assert!(e.contains("contact input u"), "{e}");
    let e = err_text(p.step(&mut st, &[0.0, f64::INFINITY, 0.0, 0.0, 0.0]));
    assert!(e.contains("contact input u"), "{e}");
}

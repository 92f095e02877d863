//! The chapter's robots (m1, m2, m5) rebuilt as general multibody models on a planar
//! root with a [`WheeledBase`], so the general reduced dynamics can be checked against
//! the closed forms of this module (and simulated on the general path).
//!
//! They live here rather than in [`crate::mobile`] because they are built from the
//! closed forms' parameter types: `closed_form` sits above `mobile` and may use it, not
//! the other way round.
//!
//! Coordinates are the multibody joint coordinates: `[x, y, φ]` for m1,
//! `[x, y, φ, θ1, θ2]` for m2 (the same as the closed form), and
//! `q_j = [x, y, φ, φ1, θ1, θ2]` for m5 (the closed form uses the absolute angles
//! `q = P q_j`, see [`super::m5_mobile_manipulator::joint_to_absolute`]).
//! The base origin is the platform CM, `d` ahead of the driven axle.

use nalgebra::{Matrix3, Vector3};

use super::m1_unicycle::UnicycleParams;
use super::m2_platform_arm::PlatformArmParams;
use super::m5_mobile_manipulator::MobileManipulatorParams;
use crate::error::Result;
use crate::mobile::diff_drive::DiffDrive;
use crate::mobile::wheeled::{WheeledBase, WheeledModel};
use crate::multibody::{
    FrameIndex, FrameKind, JointIndex, JointLimits, JointType, ModelBuilder, RootJoint,
};
use crate::spatial::{Inertia, SE3};

fn platform(b: &mut ModelBuilder, mass: f64, yaw_inertia: f64) -> Result<JointIndex> {
    b.set_root(RootJoint::Planar);
    let base = b.add_joint(
        JointIndex(0),
        "base",
        JointType::Planar,
        SE3::identity(),
        JointLimits::unlimited(),
    )?;
    // Roll and pitch inertias never matter on a planar base; give them the yaw value.
    let inertia = Inertia::new(mass, Vector3::zeros(), Matrix3::identity() * yaw_inertia);
    b.append_body_inertia(base, &inertia, &SE3::identity())?;
    Ok(base)
}

fn diag(x: f64, y: f64, z: f64) -> Matrix3<f64> {
    Matrix3::from_diagonal(&Vector3::new(x, y, z))
}

/// m1: the unicycle platform (mass m, yaw inertia I at the CM, axle d behind it).
pub fn m1_model(p: &UnicycleParams) -> Result<WheeledModel> {
    p.validate()?;
    let mut b = ModelBuilder::new("m1_unicycle");
    b.set_gravity(Vector3::new(0.0, 0.0, -9.81));
    platform(&mut b, p.m, p.inertia)?;
    WheeledModel::new(
        b.build()?,
        WheeledBase::new(DiffDrive::new(p.r_w, p.b, p.d)?),
    )
}

/// m2: platform + horizontal two-link arm with lumped elbow and tip masses.
pub fn m2_model(p: &PlatformArmParams) -> Result<WheeledModel> {
    p.validate()?;
    let mut b = ModelBuilder::new("m2_platform_planar_arm");
    b.set_gravity(Vector3::new(0.0, 0.0, -9.81));
    let base = platform(&mut b, p.m_p, p.I_p)?;
    let j1 = b.add_joint(
        base,
        "theta1",
        JointType::RevoluteZ,
        SE3::from_translation(Vector3::new(p.L, 0.0, 0.0)),
        JointLimits::unlimited(),
    )?;
    let k1 = p.m1 * p.k1 * p.k1;
    b.append_body_inertia(
        j1,
        &Inertia::new(p.m1, Vector3::new(p.L1cm, 0.0, 0.0), diag(k1, k1, k1)),
        &SE3::identity(),
    )?;
    b.append_body_inertia(
        j1,
        &Inertia::point_mass(p.M1, Vector3::new(p.L1, 0.0, 0.0)),
        &SE3::identity(),
    )?;
    let j2 = b.add_joint(
        j1,
        "theta2",
        JointType::RevoluteZ,
        SE3::from_translation(Vector3::new(p.L1, 0.0, 0.0)),
        JointLimits::unlimited(),
    )?;
    let k2 = p.m2 * p.k2 * p.k2;
    b.append_body_inertia(
        j2,
        &Inertia::new(p.m2, Vector3::new(p.L2cm, 0.0, 0.0), diag(k2, k2, k2)),
        &SE3::identity(),
    )?;
    b.append_body_inertia(
        j2,
        &Inertia::point_mass(p.M2, Vector3::new(p.L2, 0.0, 0.0)),
        &SE3::identity(),
    )?;
    WheeledModel::new(
        b.build()?,
        WheeledBase::new(DiffDrive::new(p.r_w, p.b, p.d)?),
    )
}

/// m5: platform + capstan (yaw inertia I_c) + shoulder (pitch θ1 from the upward
/// vertical, about the capstan's y axis) + elbow (θ2, about −y so that link 2 is at
/// θ12 = θ1 − θ2 from the vertical); slender links with pitch radius of gyration k_i and
/// k_iy about the in-plane normal, lumped masses M1 at the elbow and M2 at the tip.
/// Gravity is `(0, 0, −g)`. The capstan axis B is the joint frame `phi1`; the end
/// effector E is the operational frame `tip`.
pub fn m5_model(p: &MobileManipulatorParams) -> Result<WheeledModel> {
    p.validate()?;
    let mut b = ModelBuilder::new("m5_mobile_manipulator_3d");
    b.set_gravity(Vector3::new(0.0, 0.0, -p.g));
    let base = platform(&mut b, p.M_cart, p.I_p)?;
    let capstan = b.add_joint(
        base,
        "phi1",
        JointType::RevoluteZ,
        SE3::from_translation(Vector3::new(p.L, 0.0, 0.0)),
        JointLimits::unlimited(),
    )?;
    b.append_body_inertia(
        capstan,
        &Inertia::new(0.0, Vector3::zeros(), diag(0.0, 0.0, p.I_c)),
        &SE3::identity(),
    )?;
    let shoulder = b.add_joint(
        capstan,
        "theta1",
        JointType::RevoluteY,
        SE3::identity(),
        JointLimits::unlimited(),
    )?;
    let link = |m: f64, k: f64, ky: f64, cm: f64| {
        Inertia::new(
            m,
            Vector3::new(0.0, 0.0, cm),
            diag(m * ky * ky, m * k * k, 0.0),
        )
    };
    b.append_body_inertia(shoulder, &link(p.m1, p.k1, p.k1y, p.L1cm), &SE3::identity())?;
    b.append_body_inertia(
        shoulder,
        &Inertia::point_mass(p.M1, Vector3::new(0.0, 0.0, p.L1)),
        &SE3::identity(),
    )?;
    let elbow = b.add_joint(
        shoulder,
        "theta2",
        JointType::revolute(Vector3::new(0.0, -1.0, 0.0))?,
        SE3::from_translation(Vector3::new(0.0, 0.0, p.L1)),
        JointLimits::unlimited(),
    )?;
    b.append_body_inertia(elbow, &link(p.m2, p.k2, p.k2y, p.L2cm), &SE3::identity())?;
    b.append_body_inertia(
        elbow,
        &Inertia::point_mass(p.M2, Vector3::new(0.0, 0.0, p.L2)),
        &SE3::identity(),
    )?;
    // The end effector E (link 2's tip) as an operational frame named "tip".
    let parent_frame = FrameIndex(b.nframes() - 1);
    b.add_frame(
        "tip",
        elbow,
        parent_frame,
        SE3::from_translation(Vector3::new(0.0, 0.0, p.L2)),
        FrameKind::Operational,
    )?;
    WheeledModel::new(
        b.build()?,
        WheeledBase::new(DiffDrive::new(p.r_w, p.b, p.d)?),
    )
}

//! The tip-over acceleration limits of the robot in its transport posture (with a
//! `[task]`'s payload once grasped) and the share of them the path timing may use.

use super::scenario::Mission;
use crate::error::Result;
use crate::mobile::WheeledModel;
use crate::multibody::Data;
use crate::planning::trajectory::TipOverAcceleration;
use crate::stability::{AccelerationLimits, SupportPolygon};
use nalgebra::DVector;

/// The tip-over limits the timing may use (`tip_fraction` of them): a side no edge limits
/// is unbounded; a posture that tips at rest (or has no room to accelerate) cannot be
/// timed (`None`).
pub(super) fn timing_acceleration(
    tip: &AccelerationLimits,
    tip_fraction: f64,
) -> Option<TipOverAcceleration> {
    match (tip.forward, tip.backward) {
        (Some(fw), Some(bw)) if fw > 0.0 && bw > 0.0 => {
            let side = |x: Option<f64>| x.map_or(f64::INFINITY, |a| tip_fraction * a);
            Some(TipOverAcceleration {
                forward: tip_fraction * fw,
                backward: tip_fraction * bw,
                left: side(tip.left),
                right: side(tip.right),
            })
            .filter(|t| t.left > 0.0 && t.right > 0.0)
        }
        _ => None,
    }
}

/// The tip-over acceleration limits of the robot in its transport posture, at rest, in
/// base axes.
pub fn transport_tip_limits(m: &Mission) -> Result<AccelerationLimits> {
    tip_limits_of(m, &m.robot)
}

/// [`transport_tip_limits`] of `robot` (the mission's, or with a `[task]`'s payload).
pub(super) fn tip_limits_of(m: &Mission, robot: &WheeledModel) -> Result<AccelerationLimits> {
    let model = &robot.model;
    let mut q = DVector::zeros(model.nq);
    for (k, &i) in m.robot.arm_dofs().iter().enumerate() {
        q[i] = m.transport[k];
    }
    let mut data = Data::new(model);
    let com = crate::dynamics::center_of_mass(model, &mut data, &q);
    let support = SupportPolygon::from_wheeled_model(robot)?;
    Ok(crate::stability::acceleration_limits(
        model.total_mass(),
        &com,
        &model.gravity,
        &support,
        0.0,
    ))
}

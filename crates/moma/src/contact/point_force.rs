//! The generalised force `Jᵀ f` of a point force on one body, without forming `J`.

use nalgebra::Vector3;

use crate::multibody::{Data, Model};
use crate::spatial::Force;

/// Adds to `tau` (nv) the generalised force `Jᵀ f` of the world force `force` applied at
/// the world point `point` of the body of joint `body`: the force is expressed in that
/// body's joint frame and carried up the tree, each joint taking `Sᵀ f`. Needs
/// `data.world_from_joint` and `data.parent_from_joint` of configuration `q`.
pub(crate) fn add_point_force(
    model: &Model,
    data: &Data,
    body: usize,
    point: &Vector3<f64>,
    force: &Vector3<f64>,
    q: &[f64],
    tau: &mut [f64],
) {
    let x = &data.world_from_joint[body];
    let rt = x.rotation.transpose();
    let arm = point - x.translation;
    let mut f = Force::new(rt * force, rt * arm.cross(force));
    let mut i = body;
    let mut buf = [0.0; 6];
    while i > 0 {
        let (iq, iv, nv) = (model.idx_q[i], model.idx_v[i], model.nvs[i]);
        model.joint_types[i].project_force(&q[iq..iq + model.nqs[i]], &f, &mut buf[..nv]);
        for k in 0..nv {
            tau[iv + k] += buf[k];
        }
        f = data.parent_from_joint[i].act_force(&f);
        i = model.parents[i].0;
    }
}

//! Composite rigid-body algorithm.

use crate::kinematics::{assert_sizes, update_joint_placement};
use crate::multibody::{Data, JointType, Model};
use crate::spatial::Motion;
use nalgebra::{DMatrix, DVector};

/// Joint-space inertia matrix H(q) (nv × nv, symmetric positive definite; both triangles
/// filled) by the composite rigid-body algorithm, returned and stored in
/// `data.mass_matrix`.
///
/// Runs in the world frame: forward kinematics (`data.world_from_joint`), composite
/// inertias summed in world coordinates (`data.composite_inertias`), then
/// H[j, i] = S_jᵀ·(I^c_i S_i) for every ancestor j of i, with no per-ancestor transform.
/// Entries coupling joints on different branches are structurally zero: they are zeroed
/// by `Data::new` and never written (do not write into `data.mass_matrix` yourself).
///
/// # Panics
/// If q has the wrong length or `data` was not made for `model`.
///
/// # References
/// R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, §6.2.
#[doc(alias = "H")]
#[doc(alias = "M")]
#[doc(alias = "mass_matrix")]
pub fn crba<'d>(model: &Model, data: &'d mut Data, q: &DVector<f64>) -> &'d DMatrix<f64> {
    assert_sizes(model, data, q);
    let qs = q.as_slice();
    let n = model.njoints;
    let nv = model.nv;
    for i in 1..n {
        update_joint_placement(model, data, i, qs);
        let p = model.parents[i].0;
        let m = if p == 0 {
            data.parent_from_joint[i]
        } else {
            data.world_from_joint[p].compose(&data.parent_from_joint[i])
        };
        data.world_from_joint[i] = m;
        data.composite_inertias[i] = model.inertias[i].transformed(&m);
        let iv = model.idx_v[i];
        data.sw[iv] = match model.joint_types[i] {
            // world column of an axis-aligned revolute joint: [p × ω; ω], ω a column of R
            JointType::RevoluteX | JointType::RevoluteY | JointType::RevoluteZ => {
                let c = match model.joint_types[i] {
                    JointType::RevoluteX => 0,
                    JointType::RevoluteY => 1,
                    _ => 2,
                };
                let w = m.rotation.column(c).into_owned();
                Motion::new(m.translation.cross(&w), w)
            }
            _ => {
                for k in 1..model.nvs[i] {
                    data.sw[iv + k] = m.act_motion(&data.s[iv + k]);
                }
                m.act_motion(&data.s[iv])
            }
        };
    }
    for i in (2..n).rev() {
        let p = model.parents[i].0;
        if p > 0 {
            let yi = data.composite_inertias[i];
            data.composite_inertias[p] += yi;
        }
    }
    let mm = data.mass_matrix.as_mut_slice();
    for i in 1..n {
        let iv = model.idx_v[i];
        let yi = data.composite_inertias[i];
        for k in 0..model.nvs[i] {
            let f = yi.mul_motion(&data.sw[iv + k]);
            let col = iv + k;
            let mut j = i;
            while j != 0 {
                let jv = model.idx_v[j];
                let nvj = if j == i { k + 1 } else { model.nvs[j] };
                for l in 0..nvj {
                    let val = data.sw[jv + l].dot(&f);
                    mm[col * nv + jv + l] = val;
                    mm[(jv + l) * nv + col] = val;
                }
                j = model.parents[j].0;
            }
        }
    }
    &data.mass_matrix
}

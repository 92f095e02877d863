//! Composite rigid-body algorithm.

use crate::kinematics::{assert_sizes, update_joint_placement};
use crate::multibody::{Data, Model};
use nalgebra::{DMatrix, DVector};

/// Joint-space inertia matrix H(q) (nv × nv, symmetric positive definite; both triangles
/// filled) by the composite rigid-body algorithm, returned and stored in
/// `data.mass_matrix`. Also fills `data.parent_from_joint` and
/// `data.composite_inertias` (joint frames).
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
        data.composite_inertias[i] = model.inertias[i];
    }
    let mm = data.mass_matrix.as_mut_slice();
    mm.fill(0.0);
    for i in (1..n).rev() {
        let iv = model.idx_v[i];
        let nvi = model.nvs[i];
        let yi = data.composite_inertias[i];
        for k in 0..nvi {
            data.fcol[k] = yi.mul_motion(&data.s[iv + k]);
        }
        let mut j = i;
        loop {
            let jv = model.idx_v[j];
            let jt = &model.joint_types[j];
            if model.nvs[j] == 1 {
                for k in 0..nvi {
                    let val = jt.project_force_1dof(&data.fcol[k]);
                    mm[(iv + k) * nv + jv] = val;
                    mm[jv * nv + iv + k] = val;
                }
            } else {
                for l in 0..model.nvs[j] {
                    let s = data.s[jv + l];
                    for k in 0..nvi {
                        let val = s.dot(&data.fcol[k]);
                        mm[(iv + k) * nv + jv + l] = val;
                        mm[(jv + l) * nv + iv + k] = val;
                    }
                }
            }
            let pj = model.parents[j].0;
            if pj == 0 {
                break;
            }
            let x = data.parent_from_joint[j];
            for k in 0..nvi {
                data.fcol[k] = x.act_force(&data.fcol[k]);
            }
            j = pj;
        }
        let p = model.parents[i].0;
        if p > 0 {
            let yp = yi.transformed(&data.parent_from_joint[i]);
            data.composite_inertias[p] += yp;
        }
    }
    &data.mass_matrix
}

//! Christoffel-consistent Coriolis matrix.

use crate::kinematics::{assert_nv, assert_sizes, forward_kinematics_second_order_impl};
use crate::multibody::{Data, JointType, Model};
use crate::spatial::{Force, Motion, skew};
use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Vector6};

fn crf(v: &Motion) -> Matrix6<f64> {
    // v ×* : [[ω×, 0], [v×, ω×]]
    let mut m = Matrix6::zeros();
    let w = skew(&v.angular);
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&w);
    m.fixed_view_mut::<3, 3>(3, 3).copy_from(&w);
    m.fixed_view_mut::<3, 3>(3, 0).copy_from(&skew(&v.linear));
    m
}

fn crm(v: &Motion) -> Matrix6<f64> {
    // v × : [[ω×, v×], [0, ω×]]
    let mut m = Matrix6::zeros();
    let w = skew(&v.angular);
    m.fixed_view_mut::<3, 3>(0, 0).copy_from(&w);
    m.fixed_view_mut::<3, 3>(3, 3).copy_from(&w);
    m.fixed_view_mut::<3, 3>(0, 3).copy_from(&skew(&v.linear));
    m
}

fn bar(h: &Force) -> Matrix6<f64> {
    // (h)×̄ with (h)×̄ v = v ×* h: [[0, −[h_l]×], [−[h_l]×, −[h_a]×]]
    let mut m = Matrix6::zeros();
    let hl: Matrix3<f64> = -skew(&h.linear);
    m.fixed_view_mut::<3, 3>(0, 3).copy_from(&hl);
    m.fixed_view_mut::<3, 3>(3, 0).copy_from(&hl);
    m.fixed_view_mut::<3, 3>(3, 3)
        .copy_from(&(-skew(&h.angular)));
    m
}

/// Coriolis matrix C(q, v) (nv × nv), consistent with the Christoffel symbols of H(q):
/// C(q, v)·v + g(q) = h(q, v) and Ḣ − 2C is skew-symmetric. Stored in `data.coriolis`.
///
/// Computed as C = Σ_b J_bᵀ (I_b J̇_b + B_b J_b) over the bodies, in the world frame, with
/// B(v) = ½ (v×* I − I v× + (I v)×̄), accumulated over subtrees (O(n²)). Also fills
/// `data.joint_jacobians` (world-frame joint Jacobians) and the kinematics.
///
/// # Panics
/// On wrong vector lengths.
///
/// # References
/// J. Echeandia, P. M. Wensing, "Numerical methods to compute the Coriolis matrix and
/// Christoffel symbols for rigid-body systems", J. Comput. Nonlinear Dyn. 16(9), 2021,
/// doi:10.1115/1.4051169.
#[doc(alias = "C")]
pub fn coriolis_matrix<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
) -> &'d DMatrix<f64> {
    assert_sizes(model, data, q);
    assert_nv(model, v, "v");
    let (qs, vs) = (q.as_slice(), v.as_slice());
    forward_kinematics_second_order_impl(model, data, qs, vs, None);
    let n = model.njoints;
    for i in 1..n {
        let m = data.world_from_joint[i];
        let vw = m.act_motion(&data.v[i]);
        data.vworld[i] = vw;
        let iv = model.idx_v[i];
        let nvi = model.nvs[i];
        for k in 0..nvi {
            let sw = m.act_motion(&data.s[iv + k]);
            let mut sdot = vw.cross_motion(&sw);
            if matches!(model.joint_types[i], JointType::Planar) && k < 2 {
                // d/dt of the q-dependent local columns: col0' = −θ̇ col1, col1' = θ̇ col0
                let th_dot = vs[iv + 2];
                let local = if k == 0 {
                    data.s[iv + 1] * (-th_dot)
                } else {
                    data.s[iv] * th_dot
                };
                sdot += m.act_motion(&local);
            }
            data.joint_jacobians
                .fixed_view_mut::<6, 1>(0, iv + k)
                .copy_from(&sw.to_vector());
            data.jdot
                .fixed_view_mut::<6, 1>(0, iv + k)
                .copy_from(&sdot.to_vector());
        }
        let iw = model.inertias[i].transformed(&m);
        let im = iw.to_matrix();
        let h = iw.mul_motion(&vw);
        data.mat6[i] = im;
        data.mat6b[i] = (crf(&vw) * im - im * crm(&vw) + bar(&h)) * 0.5;
    }
    for i in (1..n).rev() {
        let p = model.parents[i].0;
        if p > 0 {
            let (a, b) = (data.mat6[i], data.mat6b[i]);
            data.mat6[p] += a;
            data.mat6b[p] += b;
        }
    }
    let nv = model.nv;
    let cm = data.coriolis.as_mut_slice();
    cm.fill(0.0);
    for i in 1..n {
        let iv = model.idx_v[i];
        let ic = &data.mat6[i];
        let bc = &data.mat6b[i];
        for k in 0..model.nvs[i] {
            let s_ik: Vector6<f64> = data.joint_jacobians.column(iv + k).into();
            let sd_ik: Vector6<f64> = data.jdot.column(iv + k).into();
            // F = Ic Ṡ + Bc S for column (i, k)
            let f_ik = ic * sd_ik + bc * s_ik;
            let mut j = i;
            while j != 0 {
                let jv = model.idx_v[j];
                for l in 0..model.nvs[j] {
                    let s_jl: Vector6<f64> = data.joint_jacobians.column(jv + l).into();
                    // C[j_l, i_k] = S_jlᵀ (Ic Ṡ_ik + Bc S_ik)
                    cm[(iv + k) * nv + jv + l] = s_jl.dot(&f_ik);
                    if j != i {
                        let sd_jl: Vector6<f64> = data.jdot.column(jv + l).into();
                        // C[i_k, j_l] = S_ikᵀ (Ic Ṡ_jl + Bc S_jl)
                        cm[(jv + l) * nv + iv + k] = s_ik.dot(&(ic * sd_jl + bc * s_jl));
                    }
                }
                j = model.parents[j].0;
            }
        }
    }
    &data.coriolis
}

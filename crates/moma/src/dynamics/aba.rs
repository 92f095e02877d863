//! Articulated-body algorithm (forward dynamics).

use crate::kinematics::{assert_nv, assert_sizes, update_joint_placement};
use crate::multibody::{ArticulatedInertia, Data, Model};
use crate::spatial::{Force, Inertia, Motion, SE3, skew};
use nalgebra::{DVector, Matrix3, Matrix6, Vector3};

impl ArticulatedInertia {
    /// The 6 × 6 form of a rigid-body inertia.
    #[inline]
    #[must_use]
    pub fn from_inertia(i: &Inertia) -> Self {
        Self {
            a: Matrix3::identity() * i.mass(),
            b: -skew(&i.first_moment()),
            c: i.inertia_about_origin(),
        }
    }

    /// `IA · v`.
    #[inline]
    #[must_use]
    pub fn mul_motion(&self, v: &Motion) -> Force {
        Force {
            linear: self.a * v.linear + self.b * v.angular,
            angular: self.b.tr_mul(&v.linear) + self.c * v.angular,
        }
    }

    /// `self −= s · u uᵀ` for a force-like 6-vector u.
    #[inline]
    pub fn sub_outer(&mut self, u: &Force, w: &Force, s: f64) {
        self.a -= u.linear * w.linear.transpose() * s;
        self.b -= u.linear * w.angular.transpose() * s;
        self.c -= u.angular * w.angular.transpose() * s;
    }

    /// The inertia expressed in frame `a`, given `a_from_b` and this inertia in `b`:
    /// `X* · IA · X⁻¹`.
    #[inline]
    #[must_use]
    pub fn transformed(&self, a_from_b: &SE3) -> Self {
        let r = &a_from_b.rotation;
        let px = skew(&a_from_b.translation);
        let a1 = r * self.a * r.transpose();
        let b1 = r * self.b * r.transpose();
        let c1 = r * self.c * r.transpose();
        let pa = px * a1;
        let pb = px * b1;
        Self {
            a: a1,
            b: b1 - a1 * px,
            c: c1 - pa * px + pb + pb.transpose(),
        }
    }

    /// The full 6 × 6 matrix.
    #[must_use]
    pub fn to_matrix(&self) -> Matrix6<f64> {
        let mut m = Matrix6::zeros();
        m.fixed_view_mut::<3, 3>(0, 0).copy_from(&self.a);
        m.fixed_view_mut::<3, 3>(0, 3).copy_from(&self.b);
        m.fixed_view_mut::<3, 3>(3, 0)
            .copy_from(&self.b.transpose());
        m.fixed_view_mut::<3, 3>(3, 3).copy_from(&self.c);
        m
    }
}

impl std::ops::AddAssign for ArticulatedInertia {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        self.a += o.a;
        self.b += o.b;
        self.c += o.c;
    }
}

/// Forward dynamics by the articulated-body algorithm: q̈ = H(q)⁻¹ (τ − h(q, v)) (nv),
/// returned and stored in `data.ddq`. Also fills `data.parent_from_joint`, `data.v` and
/// `data.a` (body accelerations including −gravity, joint frames).
///
/// A model whose bodies make H singular (e.g. a joint moving only massless links) gives
/// non-finite accelerations; check with `ddq.iter().all(|x| x.is_finite())`.
///
/// # Panics
/// On wrong vector lengths.
///
/// # References
/// R. Featherstone, *Rigid Body Dynamics Algorithms*, Springer 2008, §7.3.
// Kept whole on purpose (about 100 lines): split into per-pass and per-joint helpers, even
// inlined, it measured 3.5 % (fixed Panda) to 6 % (planar Panda) slower per call, best of
// several runs side by side with this version, so the kernel stays one function.
#[doc(alias = "forward_dynamics")]
pub fn aba<'d>(
    model: &Model,
    data: &'d mut Data,
    q: &DVector<f64>,
    v: &DVector<f64>,
    tau: &DVector<f64>,
) -> &'d DVector<f64> {
    assert_sizes(model, data, q);
    assert_nv(model, v, "v");
    assert_nv(model, tau, "tau");
    let (qs, vs, ts) = (q.as_slice(), v.as_slice(), tau.as_slice());
    let n = model.njoints;
    aba_forward_pass(model, data, qs, vs);
    for i in (1..n).rev() {
        let iv = model.idx_v[i];
        let nvi = model.nvs[i];
        let ia = data.ia[i];
        let pa = data.pa[i];
        let p = model.parents[i].0;
        if nvi == 1 {
            let u = ia.mul_motion(&data.s[iv]);
            let d = data.s[iv].dot(&u);
            let dinv = 1.0 / d;
            let uu = ts[iv] - data.s[iv].dot(&pa);
            data.u[iv] = u;
            data.uu[iv] = uu;
            data.dinv[i][(0, 0)] = dinv;
            if p > 0 {
                let mut ia2 = ia;
                ia2.sub_outer(&u, &u, dinv);
                let pa2 = pa + ia2.mul_motion(&data.c[i]) + u * (dinv * uu);
                let x = data.parent_from_joint[i];
                data.ia[p] += ia2.transformed(&x);
                data.pa[p] += x.act_force(&pa2);
            }
        } else {
            let mut d = Matrix6::identity();
            for k in 0..nvi {
                let u = ia.mul_motion(&data.s[iv + k]);
                data.u[iv + k] = u;
                data.uu[iv + k] = ts[iv + k] - data.s[iv + k].dot(&pa);
            }
            for k in 0..nvi {
                for l in 0..nvi {
                    d[(k, l)] = data.s[iv + k].dot(&data.u[iv + l]);
                }
            }
            let dinv = d
                .try_inverse()
                .unwrap_or_else(|| Matrix6::from_element(f64::NAN));
            data.dinv[i] = dinv;
            if p > 0 {
                let mut ia2 = ia;
                let mut pa2 = pa;
                for k in 0..nvi {
                    let mut w = Force::zero();
                    let mut s = 0.0;
                    for l in 0..nvi {
                        w += data.u[iv + l] * dinv[(k, l)];
                        s += dinv[(k, l)] * data.uu[iv + l];
                    }
                    ia2.sub_outer(&data.u[iv + k], &w, 1.0);
                    pa2 += data.u[iv + k] * s;
                }
                pa2 += ia2.mul_motion(&data.c[i]);
                let x = data.parent_from_joint[i];
                data.ia[p] += ia2.transformed(&x);
                data.pa[p] += x.act_force(&pa2);
            }
        }
    }
    data.a[0] = Motion::new(-model.gravity, Vector3::zeros());
    for i in 1..n {
        let iv = model.idx_v[i];
        let nvi = model.nvs[i];
        let p = model.parents[i].0;
        let mut acc = data.parent_from_joint[i].inverse_act_motion(&data.a[p]) + data.c[i];
        if nvi == 1 {
            let qdd = data.dinv[i][(0, 0)] * (data.uu[iv] - data.u[iv].dot(&acc));
            data.ddq[iv] = qdd;
            acc += data.s[iv] * qdd;
        } else {
            let mut rhs = [0.0; 6];
            for k in 0..nvi {
                rhs[k] = data.uu[iv + k] - data.u[iv + k].dot(&acc);
            }
            for k in 0..nvi {
                let mut s = 0.0;
                for l in 0..nvi {
                    s += data.dinv[i][(k, l)] * rhs[l];
                }
                data.ddq[iv + k] = s;
            }
            for k in 0..nvi {
                acc += data.s[iv + k] * data.ddq[iv + k];
            }
        }
        data.a[i] = acc;
    }
    &data.ddq
}

/// Backward-pass step of the one-dof joint `i` given `U = IA S` and `D = Sᵀ U`: stores
/// `U`, `u = τ − Sᵀ pA` and `D⁻¹`, and adds the joint's articulated inertia
/// `IA − U D⁻¹ Uᵀ` and bias `pA + IA c + U D⁻¹ u` (in the parent's frame) to its
/// parent's. Used by the root-constrained variant in `mobile::constrained_aba` (the same
/// step as in [`aba`]).
#[inline(always)]
pub(crate) fn condense_one_dof(
    model: &Model,
    data: &mut Data,
    ts: &[f64],
    i: usize,
    u: Force,
    d: f64,
) {
    let iv = model.idx_v[i];
    let ia = data.ia[i];
    let pa = data.pa[i];
    let p = model.parents[i].0;
    let dinv = 1.0 / d;
    let uu = ts[iv] - data.s[iv].dot(&pa);
    data.u[iv] = u;
    data.uu[iv] = uu;
    data.dinv[i][(0, 0)] = dinv;
    if p > 0 {
        let mut ia2 = ia;
        ia2.sub_outer(&u, &u, dinv);
        let pa2 = pa + ia2.mul_motion(&data.c[i]) + u * (dinv * uu);
        add_to_parent(data, i, p, &ia2, &pa2);
    }
}

/// Adds joint `i`'s condensed inertia `ia2` and bias `pa2` to its parent `p`'s, moved
/// into the parent's frame.
#[inline(always)]
fn add_to_parent(data: &mut Data, i: usize, p: usize, ia2: &ArticulatedInertia, pa2: &Force) {
    let x = data.parent_from_joint[i];
    data.ia[p] += ia2.transformed(&x);
    data.pa[p] += x.act_force(pa2);
}

/// Acceleration-pass step of the one-dof joint `i`: `q̈ᵢ = D⁻¹ (u − Uᵀ a')` with `a'` the
/// parent's acceleration seen in the joint's frame plus `c`; sets `data.ddq` and
/// `data.a[i]`. Used by `mobile::constrained_aba` (the same step as in [`aba`]).
#[inline(always)]
pub(crate) fn accelerate_one_dof(model: &Model, data: &mut Data, i: usize) {
    let iv = model.idx_v[i];
    let p = model.parents[i].0;
    let mut acc = data.parent_from_joint[i].inverse_act_motion(&data.a[p]) + data.c[i];
    let qdd = data.dinv[i][(0, 0)] * (data.uu[iv] - data.u[iv].dot(&acc));
    data.ddq[iv] = qdd;
    acc += data.s[iv] * qdd;
    data.a[i] = acc;
}

/// First pass of the articulated-body algorithm, shared with the root-constrained variant
/// in `mobile::constrained_aba`: joint placements, body velocities, velocity-product
/// accelerations `c`, and each body's rigid inertia and bias force as the starting
/// articulated quantities.
#[inline]
pub(crate) fn aba_forward_pass(model: &Model, data: &mut Data, qs: &[f64], vs: &[f64]) {
    data.v[0] = Motion::zero();
    for i in 1..model.njoints {
        update_joint_placement(model, data, i, qs);
        let jt = &model.joint_types[i];
        let p = model.parents[i].0;
        let (iq, iv) = (model.idx_q[i], model.idx_v[i]);
        let qi = &qs[iq..iq + model.nqs[i]];
        let vi = &vs[iv..iv + model.nvs[i]];
        let vj = jt.motion(qi, vi);
        let vel = data.parent_from_joint[i].inverse_act_motion(&data.v[p]) + vj;
        let mut c = vel.cross_motion(&vj);
        if jt.has_bias() {
            c += jt.bias(qi, vi);
        }
        data.v[i] = vel;
        data.c[i] = c;
        let inertia = &model.inertias[i];
        data.ia[i] = ArticulatedInertia::from_inertia(inertia);
        data.pa[i] = vel.cross_force(&inertia.mul_motion(&vel));
    }
}

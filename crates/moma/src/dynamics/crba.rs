//! Composite rigid-body algorithm.

use crate::kinematics::{assert_sizes, update_joint_placement};
use crate::multibody::{Data, JointType, Model};
use crate::spatial::{Force, Inertia, Motion, SE3};
use nalgebra::{DMatrix, DVector, Vector3};

/// Joint-space inertia matrix H(q) (nv × nv, symmetric positive definite; both triangles
/// filled) by the composite rigid-body algorithm, returned and stored in
/// `data.mass_matrix`.
///
/// Runs in local joint frames (Featherstone's CRBA): joint placements
/// (`data.parent_from_joint`), composite inertias I^c_i summed in each joint's own frame
/// (`data.composite_inertias`), then for every dof column F = I^c_i S_i is carried up the
/// ancestor chain with the parent transforms and H[j, i] = S_jᵀ F; each entry is written
/// to both triangles as it is computed. For a large subtree under a long chain (a hand on
/// an arm) the ancestors' motion subspaces are brought down to the subtree's frame
/// instead, chosen once per model by a cost model in `Data::new`.
/// `data.world_from_joint` is not updated.
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
    for i in 1..n {
        update_joint_placement(model, data, i, qs);
        data.composite_inertias[i] = model.inertias[i];
    }
    if data.crba_plan.is_some() {
        composite_columns(model, data);
    } else {
        ancestor_walk(model, data);
    }
    &data.mass_matrix
}

/// F = I·S for column `k` of the motion subspace S of joint type `jt` (both in the joint
/// frame); axis-aligned and free-flyer joints have unit columns, so F is one column of
/// the 6 × 6 inertia `[m·1, −[h]×; [h]×, I_o]`.
#[inline(always)]
fn inertia_times_subspace(y: &Inertia, jt: &JointType, k: usize, s: &Motion) -> Force {
    let h = y.first_moment();
    let io = y.inertia_about_origin();
    let m = y.mass();
    // I·[e_k; 0] = [m e_k; h × e_k], I·[0; e_k] = [−h × e_k; I_o e_k]
    let linear = |axis: usize| match axis {
        0 => Force::new(Vector3::new(m, 0.0, 0.0), Vector3::new(0.0, h.z, -h.y)),
        1 => Force::new(Vector3::new(0.0, m, 0.0), Vector3::new(-h.z, 0.0, h.x)),
        _ => Force::new(Vector3::new(0.0, 0.0, m), Vector3::new(h.y, -h.x, 0.0)),
    };
    let angular = |axis: usize| match axis {
        0 => Force::new(Vector3::new(0.0, -h.z, h.y), io.column(0).into()),
        1 => Force::new(Vector3::new(h.z, 0.0, -h.x), io.column(1).into()),
        _ => Force::new(Vector3::new(-h.y, h.x, 0.0), io.column(2).into()),
    };
    match jt {
        JointType::RevoluteX => angular(0),
        JointType::RevoluteY => angular(1),
        JointType::RevoluteZ => angular(2),
        JointType::FreeFlyer if k < 3 => linear(k),
        JointType::FreeFlyer => angular(k - 3),
        // S = [(c, −s, 0); 0], [(s, c, 0); 0], [0; e_z]
        JointType::Planar if k < 2 => {
            let v = s.linear;
            Force::new(v * m, h.cross(&v))
        }
        JointType::Planar => angular(2),
        _ => y.mul_motion(s),
    }
}

/// Sᵀ·F for one motion-subspace column S of joint type `jt`.
#[inline]
fn subspace_dot(jt: &JointType, s: &Motion, f: &Force) -> f64 {
    match jt {
        JointType::RevoluteX => f.angular.x,
        JointType::RevoluteY => f.angular.y,
        JointType::RevoluteZ => f.angular.z,
        JointType::PrismaticX => f.linear.x,
        JointType::PrismaticY => f.linear.y,
        JointType::PrismaticZ => f.linear.z,
        _ => s.dot(f),
    }
}

/// Backward pass for depth-first models (Pinocchio's local CRBA): when joint i is reached,
/// the live force columns of its subtree are in frame i; Sᵢᵀ F fills row(s) i of those
/// columns, then all of them move to the parent frame at once (only the components a
/// root joint needs when the parent is the root), or, at a joint the CRBA plan
/// finishes, the ancestors' rows are filled by [`finish_subtree`] and nothing moves.
fn composite_columns(model: &Model, data: &mut Data) {
    let nv = model.nv;
    let Some(plan) = data.crba_plan.as_ref() else {
        return;
    };
    let mm = data.mass_matrix.as_mut_slice();
    // force column c = [f_x, f_y, f_z, n_x, n_y, n_z]
    let (fc, _) = data.fcrb.as_chunks_mut::<6>();
    for i in (1..model.njoints).rev() {
        let iv = model.idx_v[i];
        let ns = plan.nv_subtree[i];
        let jt = &model.joint_types[i];
        let (head, tail) = data.composite_inertias.split_at_mut(i);
        let yi = &tail[0];
        for k in 0..model.nvs[i] {
            let f = inertia_times_subspace(yi, jt, k, &data.s[iv + k]);
            fc[iv + k] = [
                f.linear.x,
                f.linear.y,
                f.linear.z,
                f.angular.x,
                f.angular.y,
                f.angular.z,
            ];
        }
        let live = plan.live(i);
        for k in 0..model.nvs[i] {
            let col = iv + k;
            // H[c, col] = S_colᵀ F_c for the subtree's live columns c ≥ col, stored in
            // both triangles (entries above the diagonal of this joint's own block come
            // from its earlier columns, so every entry is written once and H is exactly
            // symmetric)
            for &(lo, hi) in live {
                let lo = lo.max(col);
                let cols = &fc[lo..hi];
                match jt {
                    JointType::RevoluteX => store_symmetric(mm, nv, col, lo, cols, |f| f[3]),
                    JointType::RevoluteY => store_symmetric(mm, nv, col, lo, cols, |f| f[4]),
                    JointType::RevoluteZ => store_symmetric(mm, nv, col, lo, cols, |f| f[5]),
                    JointType::PrismaticX => store_symmetric(mm, nv, col, lo, cols, |f| f[0]),
                    JointType::PrismaticY => store_symmetric(mm, nv, col, lo, cols, |f| f[1]),
                    JointType::PrismaticZ => store_symmetric(mm, nv, col, lo, cols, |f| f[2]),
                    // S = 1 (6 × 6): row k of H's block is component k of F
                    JointType::FreeFlyer => store_symmetric(mm, nv, col, lo, cols, |f| f[k]),
                    JointType::Planar if k == 2 => {
                        store_symmetric(mm, nv, col, lo, cols, |f| f[5]);
                    }
                    // S_k = [(s_x, s_y, 0); 0]: only F's x and y force components are
                    // needed (the planar-root shortcut below leaves the others stale)
                    JointType::Planar => {
                        let (sx, sy) = (data.s[col].linear.x, data.s[col].linear.y);
                        store_symmetric(mm, nv, col, lo, cols, |f| sx * f[0] + sy * f[1]);
                    }
                    _ => {
                        let s = &data.s[col];
                        store_symmetric(mm, nv, col, lo, cols, |f| dot6(s, f));
                    }
                }
            }
        }
        let p = model.parents[i].0;
        if p == 0 {
            continue;
        }
        let m = &data.parent_from_joint[i];
        head[p] += yi.transformed(m);
        if plan.finish_here[i] {
            finish_subtree(
                model,
                &data.parent_from_joint,
                &data.s,
                i,
                &fc[iv..iv + ns],
                mm,
            );
            continue;
        }
        for &(lo, hi) in live {
            let sub = &mut fc[lo..hi];
            if model.parents[p].0 == 0 {
                // p is the root joint: its rows need only S_pᵀ of the transformed columns
                match model.joint_types[p] {
                    JointType::RevoluteX => act_force_moment::<0>(m, sub),
                    JointType::RevoluteY => act_force_moment::<1>(m, sub),
                    JointType::RevoluteZ => act_force_moment::<2>(m, sub),
                    JointType::PrismaticX => act_force_force::<0>(m, sub),
                    JointType::PrismaticY => act_force_force::<1>(m, sub),
                    JointType::PrismaticZ => act_force_force::<2>(m, sub),
                    JointType::Planar => act_force_planar(m, sub),
                    _ => act_force_columns(m, sub),
                }
            } else {
                act_force_columns(m, sub);
            }
        }
    }
}

/// Rows of every proper ancestor j of joint `i` for the force columns `cols` of i's
/// subtree (in frame i, starting at dof `idx_v[i]`): H[j, c] = (X_{i←j} S_j) · F_c, the
/// ancestor's motion subspace brought down to frame i instead of every column carried up.
fn finish_subtree(
    model: &Model,
    parent_from_joint: &[SE3],
    subspace: &[Motion],
    i: usize,
    cols: &[[f64; 6]],
    mm: &mut [f64],
) {
    let nv = model.nv;
    let iv = model.idx_v[i];
    // i_from_j, starting with j = parent(i)
    let mut i_from_j = parent_from_joint[i].inverse();
    let mut j = model.parents[i].0;
    while j > 0 {
        let jv = model.idx_v[j];
        for k in 0..model.nvs[j] {
            let s = i_from_j.act_motion(&subspace[jv + k]);
            let row = jv + k;
            for (o, f) in cols.iter().enumerate() {
                let v = dot6(&s, f);
                mm[row * nv + iv + o] = v;
                mm[(iv + o) * nv + row] = v;
            }
        }
        let p = model.parents[j].0;
        if p > 0 {
            i_from_j = i_from_j.compose(&parent_from_joint[j].inverse());
        }
        j = p;
    }
}

/// Sᵀ F for a motion vector S and a force column F = [f; n].
#[inline(always)]
fn dot6(s: &Motion, f: &[f64; 6]) -> f64 {
    s.linear.x * f[0]
        + s.linear.y * f[1]
        + s.linear.z * f[2]
        + s.angular.x * f[3]
        + s.angular.y * f[4]
        + s.angular.z * f[5]
}

/// H[lo + o, col] = H[col, lo + o] = `value(cols[o])` (part of column `col` of the
/// column-major nv × nv matrix `mm` at or below its diagonal, and the matching part of
/// row `col`).
#[inline(always)]
fn store_symmetric(
    mm: &mut [f64],
    nv: usize,
    col: usize,
    lo: usize,
    cols: &[[f64; 6]],
    value: impl Fn(&[f64; 6]) -> f64,
) {
    for (o, f) in cols.iter().enumerate() {
        let v = value(f);
        mm[col * nv + lo + o] = v;
        mm[(lo + o) * nv + col] = v;
    }
}

/// Force component K of `m.act_force` on force columns; only that component is
/// overwritten (what a root prismatic joint along axis K needs: 3 products per column).
#[inline]
fn act_force_force<const K: usize>(m: &SE3, cols: &mut [[f64; 6]]) {
    let r = &m.rotation;
    let (rk0, rk1, rk2) = (r[(K, 0)], r[(K, 1)], r[(K, 2)]);
    for f in cols {
        f[K] = rk0 * f[0] + rk1 * f[1] + rk2 * f[2];
    }
}

/// Moment about axis K (component `3 + K`) of `m.act_force` on force columns; only that
/// component is overwritten (what a root revolute joint about axis K needs: 6 products
/// per column instead of 24).
#[inline]
fn act_force_moment<const K: usize>(m: &SE3, cols: &mut [[f64; 6]]) {
    let r = &m.rotation;
    let t = &m.translation;
    // moment_K = R_K·n + (t × R f)_K = R_K·n + (t_U R_V − t_V R_U)·f, (K, U, V) cyclic
    let (u, v) = ((K + 1) % 3, (K + 2) % 3);
    let (rk0, rk1, rk2) = (r[(K, 0)], r[(K, 1)], r[(K, 2)]);
    let w0 = t[u] * r[(v, 0)] - t[v] * r[(u, 0)];
    let w1 = t[u] * r[(v, 1)] - t[v] * r[(u, 1)];
    let w2 = t[u] * r[(v, 2)] - t[v] * r[(u, 2)];
    for f in cols {
        f[3 + K] = rk0 * f[3] + rk1 * f[4] + rk2 * f[5] + w0 * f[0] + w1 * f[1] + w2 * f[2];
    }
}

/// The x and y forces and the z moment of `m.act_force` on force columns (what a planar
/// root needs: 11 products per column instead of 24); the other components are left as
/// they were.
#[inline]
fn act_force_planar(m: &SE3, cols: &mut [[f64; 6]]) {
    let r = &m.rotation;
    let t = &m.translation;
    let (r00, r01, r02) = (r[(0, 0)], r[(0, 1)], r[(0, 2)]);
    let (r10, r11, r12) = (r[(1, 0)], r[(1, 1)], r[(1, 2)]);
    let (r20, r21, r22) = (r[(2, 0)], r[(2, 1)], r[(2, 2)]);
    for f in cols {
        let [x, y, z, nx, ny, nz] = *f;
        let fx = r00 * x + r01 * y + r02 * z;
        let fy = r10 * x + r11 * y + r12 * z;
        // moment_z = R_z·n + t_x (R f)_y − t_y (R f)_x
        f[5] = r20 * nx + r21 * ny + r22 * nz + (t.x * fy - t.y * fx);
        f[0] = fx;
        f[1] = fy;
    }
}

/// `m.act_force` on force columns.
#[inline]
fn act_force_columns(m: &SE3, cols: &mut [[f64; 6]]) {
    let r = &m.rotation;
    let (c0, c1, c2) = (
        r.column(0).into_owned(),
        r.column(1).into_owned(),
        r.column(2).into_owned(),
    );
    let p = m.translation;
    for f in cols {
        let [x, y, z, nx, ny, nz] = *f;
        let fl = c0 * x + c1 * y + c2 * z;
        let fa = c0 * nx + c1 * ny + c2 * nz + p.cross(&fl);
        *f = [fl.x, fl.y, fl.z, fa.x, fa.y, fa.z];
    }
}

/// Backward pass for any joint order: each force column is carried up its ancestor chain
/// and fills the upper-triangle part of its H column.
fn ancestor_walk(model: &Model, data: &mut Data) {
    let nv = model.nv;
    let mm = data.mass_matrix.as_mut_slice();
    for i in (1..model.njoints).rev() {
        let iv = model.idx_v[i];
        let jt = &model.joint_types[i];
        let yi = data.composite_inertias[i];
        for k in 0..model.nvs[i] {
            let col = iv + k;
            // column `col` of H, rows ≤ col (upper triangle), stored contiguously
            let hcol = &mut mm[col * nv..col * nv + col + 1];
            let mut f = inertia_times_subspace(&yi, jt, k, &data.s[col]);
            for l in 0..=k {
                hcol[iv + l] = subspace_dot(jt, &data.s[iv + l], &f);
            }
            let mut j = i;
            loop {
                let p = model.parents[j].0;
                if p == 0 {
                    break;
                }
                f = data.parent_from_joint[j].act_force(&f);
                let pv = model.idx_v[p];
                let jp = &model.joint_types[p];
                for l in 0..model.nvs[p] {
                    hcol[pv + l] = subspace_dot(jp, &data.s[pv + l], &f);
                }
                j = p;
            }
        }
        let p = model.parents[i].0;
        if p > 0 {
            data.composite_inertias[p] += yi.transformed(&data.parent_from_joint[i]);
        }
    }
    // mirror the upper triangle into the lower one
    for c in 0..nv {
        for r in c + 1..nv {
            mm[c * nv + r] = mm[r * nv + c];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::rnea;
    use crate::kinematics::{integrate, neutral};
    use crate::multibody::{JointIndex, JointLimits, ModelBuilder, RootJoint};
    use crate::spatial::SE3;
    use nalgebra::{Matrix3, Vector3};

    /// A branched tree with every joint type; `interleaved` adds the two branches'
    /// joints alternately, so subtree dofs are not contiguous.
    fn tree(interleaved: bool, root: RootJoint) -> Model {
        let mut b = ModelBuilder::new("tree");
        b.set_root(root);
        let axis = Vector3::new(1.0, 2.0, -0.5).normalize();
        let types = [
            JointType::RevoluteX,
            JointType::RevoluteY,
            JointType::RevoluteZ,
            JointType::PrismaticX,
            JointType::PrismaticY,
            JointType::PrismaticZ,
            JointType::RevoluteUnaligned { axis },
            JointType::PrismaticUnaligned { axis },
        ];
        let add = |b: &mut ModelBuilder, parent: JointIndex, k: usize| {
            let x = SE3::from_xyz_rpy([0.1 * k as f64, 0.2, -0.05], [0.3, -0.2, 0.1 * k as f64]);
            let j = b
                .add_joint(
                    parent,
                    &format!("j{k}"),
                    types[k % 8],
                    x,
                    JointLimits::unlimited(),
                )
                .unwrap();
            let c = Vector3::new(0.05, -0.02 * k as f64, 0.1);
            let ic = Matrix3::new(0.02, 0.001, 0.0, 0.001, 0.03, -0.002, 0.0, -0.002, 0.04);
            b.append_body_inertia(
                j,
                &Inertia::new(1.0 + 0.1 * k as f64, c, ic),
                &SE3::identity(),
            )
            .unwrap();
            j
        };
        let root = if root == RootJoint::Planar {
            b.add_joint(
                JointIndex(0),
                "base",
                JointType::Planar,
                SE3::identity(),
                JointLimits::unlimited(),
            )
            .unwrap()
        } else {
            JointIndex(0)
        };
        let base = add(&mut b, root, 0);
        let (mut left, mut right) = (base, base);
        if interleaved {
            for k in 0..4 {
                left = add(&mut b, left, 1 + 2 * k);
                right = add(&mut b, right, 2 + 2 * k);
            }
        } else {
            for k in 0..4 {
                left = add(&mut b, left, 1 + 2 * k);
            }
            for k in 0..4 {
                right = add(&mut b, right, 2 + 2 * k);
            }
        }
        b.build().unwrap()
    }

    /// H by columns of inverse dynamics: H e_k = τ(q, 0, e_k) − τ(q, 0, 0).
    fn h_by_rnea(model: &Model, q: &DVector<f64>) -> DMatrix<f64> {
        let mut data = Data::new(model);
        let zero = DVector::zeros(model.nv);
        let g = rnea(model, &mut data, q, &zero, &zero).clone();
        DMatrix::from_fn(model.nv, model.nv, |r, c| {
            let mut e = DVector::zeros(model.nv);
            e[c] = 1.0;
            rnea(model, &mut data, q, &zero, &e)[r] - g[r]
        })
    }

    /// A six-joint arm carrying a four-finger hand (four joints per finger), every joint
    /// type mixed in, under `root_type` (none: fixed base).
    fn hand_on_arm(root_type: Option<JointType>) -> Model {
        let mut b = ModelBuilder::new("hand_on_arm");
        let axis = Vector3::new(0.3, -1.0, 0.4).normalize();
        let types = [
            JointType::RevoluteZ,
            JointType::RevoluteX,
            JointType::RevoluteUnaligned { axis },
            JointType::RevoluteY,
            JointType::PrismaticUnaligned { axis },
            JointType::PrismaticX,
        ];
        let mut k = 0usize;
        let mut add = |b: &mut ModelBuilder, parent: JointIndex, jt: JointType| {
            k += 1;
            let x = SE3::from_xyz_rpy(
                [0.05 * k as f64, -0.1, 0.2],
                [0.2 * k as f64, 0.4, -0.1 * k as f64],
            );
            let j = b
                .add_joint(parent, &format!("j{k:02}"), jt, x, JointLimits::unlimited())
                .unwrap();
            let c = Vector3::new(0.02, 0.03 * (k % 3) as f64, -0.05);
            let ic = Matrix3::new(0.03, 0.002, 0.0, 0.002, 0.02, 0.001, 0.0, 0.001, 0.01);
            b.append_body_inertia(
                j,
                &Inertia::new(0.5 + 0.05 * k as f64, c, ic),
                &SE3::identity(),
            )
            .unwrap();
            j
        };
        let mut parent = JointIndex(0);
        if let Some(jt) = root_type {
            b.set_root(match jt {
                JointType::Planar => RootJoint::Planar,
                JointType::FreeFlyer => RootJoint::FreeFlyer,
                _ => RootJoint::Fixed,
            });
            parent = add(&mut b, parent, jt);
        }
        for t in 0..6 {
            parent = add(&mut b, parent, types[t % types.len()]);
        }
        for finger in 0..4 {
            let mut p = parent;
            for t in 0..4 {
                p = add(&mut b, p, types[(finger + t) % types.len()]);
            }
        }
        b.build().unwrap()
    }

    #[test]
    fn finished_subtrees_match_inverse_dynamics() {
        for root in [
            None,
            Some(JointType::RevoluteZ),
            Some(JointType::PrismaticY),
            Some(JointType::Planar),
            Some(JointType::FreeFlyer),
        ] {
            let model = hand_on_arm(root);
            let mut data = Data::new(&model);
            let plan = data.crba_plan.as_ref().unwrap();
            // the hand (16 dofs under a 6-joint arm) is finished at the arm's last joint
            assert!(plan.finish_here.iter().any(|&f| f), "{root:?}");
            let q0 = neutral(&model);
            let dq = DVector::from_fn(model.nv, |i, _| 0.9 * ((i * 5 + 1) as f64).cos());
            let mut q = q0.clone();
            integrate(&model, &q0, &dq, &mut q);
            let want = h_by_rnea(&model, &q);
            let got = crba(&model, &mut data, &q).clone();
            let scale = want.amax();
            assert!((&got - &want).amax() < 1e-12 * scale, "{root:?}");
            assert_eq!(got, got.transpose());
        }
    }

    #[test]
    fn both_backward_passes_match_inverse_dynamics() {
        for (interleaved, root) in [
            (false, RootJoint::Planar),
            (true, RootJoint::Planar),
            (false, RootJoint::Fixed),
            (true, RootJoint::Fixed),
        ] {
            let model = tree(interleaved, root);
            let mut data = Data::new(&model);
            assert_eq!(data.crba_plan.is_some(), !interleaved);
            let q0 = neutral(&model);
            let dq = DVector::from_fn(model.nv, |i, _| 0.7 * ((i * 7 + 3) as f64).sin());
            let mut q = q0.clone();
            integrate(&model, &q0, &dq, &mut q);
            let want = h_by_rnea(&model, &q);
            let got = crba(&model, &mut data, &q).clone();
            assert!((&got - &want).amax() < 1e-12, "interleaved={interleaved}");
            assert_eq!(got, got.transpose());
            // the general path on a depth-first model gives the same matrix
            if !interleaved {
                data.mass_matrix.fill(0.0);
                data.composite_inertias.clone_from(&model.inertias);
                ancestor_walk(&model, &mut data);
                assert!((&data.mass_matrix - &want).amax() < 1e-12);
            }
        }
    }
}

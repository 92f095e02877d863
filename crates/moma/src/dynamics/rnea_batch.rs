//! Multi-state RNEA: the recursive Newton–Euler pass run on [`RNEA_LANES`] states at
//! once, structure-of-arrays over the lanes.
//!
//! Every scalar of the pass (a twist component, a rotation entry, a torque) is stored as
//! `[f64; RNEA_LANES]`, one entry per state, and every arithmetic step is a loop over the
//! lanes that LLVM turns into SIMD instructions. The pass is compiled three times and the
//! widest copy the CPU runs is chosen at run time ([`BatchIsa`]): the portable baseline
//! (four SSE2 registers per lane group on x86-64), AVX2 (two registers) and AVX-512F (one
//! register). One walk over the model's joints thus does the arithmetic of eight states,
//! whose independent operations also keep the core's pipelines full where one state's
//! chain of dependent steps would stall them, and the per-joint bookkeeping (joint kind,
//! parent, indices) is paid once for the eight.
//!
//! Each lane performs exactly the floating-point operations of the scalar
//! [`rnea`](super::rnea), in the same order (the same [`trig::sin_cos`] per lane, the same
//! products and sums, no fused multiply–add), so the torques are bit-for-bit those of the
//! scalar call on every state.

use crate::multibody::{JointType, Model};
#[cfg(test)]
use crate::spatial::Motion;
use crate::spatial::{Force, trig};

/// Number of states one pass of [`rnea_batch`] processes together.
pub const RNEA_LANES: usize = 8;

const L: usize = RNEA_LANES;
type Lane = [f64; L];

const ZERO: Lane = [0.0; L];

#[inline(always)]
fn add(a: Lane, b: Lane) -> Lane {
    let mut r = ZERO;
    for k in 0..L {
        r[k] = a[k] + b[k];
    }
    r
}

#[inline(always)]
fn sub(a: Lane, b: Lane) -> Lane {
    let mut r = ZERO;
    for k in 0..L {
        r[k] = a[k] - b[k];
    }
    r
}

#[inline(always)]
fn mul(a: Lane, b: Lane) -> Lane {
    let mut r = ZERO;
    for k in 0..L {
        r[k] = a[k] * b[k];
    }
    r
}

#[inline(always)]
fn neg(a: Lane) -> Lane {
    let mut r = ZERO;
    for k in 0..L {
        r[k] = -a[k];
    }
    r
}

#[inline(always)]
fn scale(a: Lane, s: f64) -> Lane {
    let mut r = ZERO;
    for k in 0..L {
        r[k] = a[k] * s;
    }
    r
}

/// A 3-vector over the lanes.
#[derive(Clone, Copy, Debug, Default)]
struct V3 {
    x: Lane,
    y: Lane,
    z: Lane,
}

impl V3 {
    const ZERO: V3 = V3 {
        x: ZERO,
        y: ZERO,
        z: ZERO,
    };

    #[inline(always)]
    fn add(&self, o: &V3) -> V3 {
        V3 {
            x: add(self.x, o.x),
            y: add(self.y, o.y),
            z: add(self.z, o.z),
        }
    }

    #[inline(always)]
    fn sub(&self, o: &V3) -> V3 {
        V3 {
            x: sub(self.x, o.x),
            y: sub(self.y, o.y),
            z: sub(self.z, o.z),
        }
    }

    /// The cross product, component by component as nalgebra's `cross`.
    #[inline(always)]
    fn cross(&self, b: &V3) -> V3 {
        V3 {
            x: sub(mul(self.y, b.z), mul(self.z, b.y)),
            y: sub(mul(self.z, b.x), mul(self.x, b.z)),
            z: sub(mul(self.x, b.y), mul(self.y, b.x)),
        }
    }

    /// `self × (w·e_j)` without the products by zero (as the scalar `rnea`'s
    /// `cross_axis`).
    #[inline(always)]
    fn cross_axis(&self, j: usize, w: &Lane) -> V3 {
        match j {
            0 => V3 {
                x: ZERO,
                y: mul(self.z, *w),
                z: neg(mul(self.y, *w)),
            },
            1 => V3 {
                x: neg(mul(self.z, *w)),
                y: ZERO,
                z: mul(self.x, *w),
            },
            _ => V3 {
                x: mul(self.y, *w),
                y: neg(mul(self.x, *w)),
                z: ZERO,
            },
        }
    }

    /// The cross product with a vector constant over the lanes (`c × self` when
    /// `left`, as nalgebra's `c.cross(&self)`).
    #[inline(always)]
    fn const_cross(c: &[f64; 3], b: &V3) -> V3 {
        V3 {
            x: sub(scale(b.z, c[1]), scale(b.y, c[2])),
            y: sub(scale(b.x, c[2]), scale(b.z, c[0])),
            z: sub(scale(b.y, c[0]), scale(b.x, c[1])),
        }
    }
}

/// A spatial vector (twist or wrench) over the lanes.
#[derive(Clone, Copy, Debug, Default)]
struct S6 {
    lin: V3,
    ang: V3,
}

impl S6 {
    const ZERO: S6 = S6 {
        lin: V3::ZERO,
        ang: V3::ZERO,
    };

    #[inline(always)]
    fn add(&self, o: &S6) -> S6 {
        S6 {
            lin: self.lin.add(&o.lin),
            ang: self.ang.add(&o.ang),
        }
    }

    /// `self × m` (as `Motion::cross_motion`).
    #[inline(always)]
    fn cross_motion(&self, m: &S6) -> S6 {
        S6 {
            lin: self.ang.cross(&m.lin).add(&self.lin.cross(&m.ang)),
            ang: self.ang.cross(&m.ang),
        }
    }

    /// `self ×* f` (as `Motion::cross_force`).
    #[inline(always)]
    fn cross_force(&self, f: &S6) -> S6 {
        S6 {
            lin: self.ang.cross(&f.lin),
            ang: self.ang.cross(&f.ang).add(&self.lin.cross(&f.lin)),
        }
    }

    /// Coordinate `k` of `[lin; ang]` (0–2 linear, 3–5 angular, as
    /// [`JointType::axis_slot`]).
    #[inline(always)]
    fn slot_mut(&mut self, k: usize) -> &mut Lane {
        match k {
            0 => &mut self.lin.x,
            1 => &mut self.lin.y,
            2 => &mut self.lin.z,
            3 => &mut self.ang.x,
            4 => &mut self.ang.y,
            _ => &mut self.ang.z,
        }
    }

    /// `self += x·e_k` (as the scalar `rnea`'s `add_to_slot`).
    #[inline(always)]
    fn add_to_slot(&mut self, k: usize, x: &Lane) {
        let c = self.slot_mut(k);
        *c = add(*c, *x);
    }

    /// `self × (w·e_k)` (as the scalar `rnea`'s `cross_slot`).
    #[inline(always)]
    fn cross_slot(&self, k: usize, w: &Lane) -> S6 {
        if k < 3 {
            S6 {
                lin: self.ang.cross_axis(k, w),
                ang: V3::ZERO,
            }
        } else {
            S6 {
                lin: self.lin.cross_axis(k - 3, w),
                ang: self.ang.cross_axis(k - 3, w),
            }
        }
    }

    fn set_lane(&mut self, k: usize, lin: [f64; 3], ang: [f64; 3]) {
        self.lin.x[k] = lin[0];
        self.lin.y[k] = lin[1];
        self.lin.z[k] = lin[2];
        self.ang.x[k] = ang[0];
        self.ang.y[k] = ang[1];
        self.ang.z[k] = ang[2];
    }

    #[cfg(test)]
    fn motion_lane(&self, k: usize) -> Motion {
        Motion::new(
            nalgebra::Vector3::new(self.lin.x[k], self.lin.y[k], self.lin.z[k]),
            nalgebra::Vector3::new(self.ang.x[k], self.ang.y[k], self.ang.z[k]),
        )
    }

    fn force_lane(&self, k: usize) -> Force {
        Force::new(
            nalgebra::Vector3::new(self.lin.x[k], self.lin.y[k], self.lin.z[k]),
            nalgebra::Vector3::new(self.ang.x[k], self.ang.y[k], self.ang.z[k]),
        )
    }
}

/// A rigid transform over the lanes: rotation columns `r[col]` and translation `t`.
#[derive(Clone, Copy, Debug, Default)]
struct Pose {
    r: [V3; 3],
    t: V3,
}

impl Pose {
    /// `R · v` in nalgebra's order: `(c0·x + c1·y) + c2·z`.
    #[inline(always)]
    fn rot_mul(&self, v: &V3) -> V3 {
        let [c0, c1, c2] = &self.r;
        V3 {
            x: add(add(mul(c0.x, v.x), mul(c1.x, v.y)), mul(c2.x, v.z)),
            y: add(add(mul(c0.y, v.x), mul(c1.y, v.y)), mul(c2.y, v.z)),
            z: add(add(mul(c0.z, v.x), mul(c1.z, v.y)), mul(c2.z, v.z)),
        }
    }

    /// `Rᵀ · v` in nalgebra's order (`tr_mul`): one dot product per column.
    #[inline(always)]
    fn rot_tr_mul(&self, v: &V3) -> V3 {
        V3 {
            x: dot(&self.r[0], v),
            y: dot(&self.r[1], v),
            z: dot(&self.r[2], v),
        }
    }

    /// As `SE3::inverse_act_motion`.
    #[inline(always)]
    fn inverse_act_motion(&self, m: &S6) -> S6 {
        S6 {
            lin: self.rot_tr_mul(&m.lin.sub(&self.t.cross(&m.ang))),
            ang: self.rot_tr_mul(&m.ang),
        }
    }

    /// As `SE3::act_force`.
    #[inline(always)]
    fn act_force(&self, f: &S6) -> S6 {
        let lin = self.rot_mul(&f.lin);
        S6 {
            ang: self.rot_mul(&f.ang).add(&self.t.cross(&lin)),
            lin,
        }
    }

    fn set_lane(&mut self, k: usize, m: &crate::spatial::SE3) {
        for (c, col) in self.r.iter_mut().enumerate() {
            col.x[k] = m.rotation[(0, c)];
            col.y[k] = m.rotation[(1, c)];
            col.z[k] = m.rotation[(2, c)];
        }
        self.t.x[k] = m.translation.x;
        self.t.y[k] = m.translation.y;
        self.t.z[k] = m.translation.z;
    }
}

/// `c · v` in nalgebra's order: `(x·x' + y·y') + z·z'`.
#[inline(always)]
fn dot(c: &V3, v: &V3) -> Lane {
    add(add(mul(c.x, v.x), mul(c.y, v.y)), mul(c.z, v.z))
}

/// Column `c` of a rotation matrix.
#[inline(always)]
fn col(r: &nalgebra::Matrix3<f64>, c: usize) -> [f64; 3] {
    [r[(0, c)], r[(1, c)], r[(2, c)]]
}

/// A body's spatial inertia, constant over the lanes.
#[derive(Clone, Copy, Debug)]
struct BodyInertia {
    mass: f64,
    h: [f64; 3],
    /// Rotational inertia about the origin, by columns.
    io: [[f64; 3]; 3],
}

impl BodyInertia {
    /// As `Inertia::mul_motion`.
    #[inline(always)]
    fn mul_motion(&self, v: &S6) -> S6 {
        let lin = V3 {
            x: scale(v.lin.x, self.mass),
            y: scale(v.lin.y, self.mass),
            z: scale(v.lin.z, self.mass),
        }
        .sub(&V3::const_cross(&self.h, &v.ang));
        let [c0, c1, c2] = &self.io;
        let w = &v.ang;
        let iw = V3 {
            x: add(add(scale(w.x, c0[0]), scale(w.y, c1[0])), scale(w.z, c2[0])),
            y: add(add(scale(w.x, c0[1]), scale(w.y, c1[1])), scale(w.z, c2[1])),
            z: add(add(scale(w.x, c0[2]), scale(w.y, c1[2])), scale(w.z, c2[2])),
        };
        S6 {
            lin,
            ang: iw.add(&V3::const_cross(&self.h, &v.lin)),
        }
    }
}

/// Workspace of [`rnea_batch`] for one model: the per-joint lane buffers and the
/// transposed inputs of one group of [`RNEA_LANES`] states. Allocated once by
/// [`BatchData::new`]; [`rnea_batch`] does not allocate.
#[derive(Clone, Debug)]
pub struct BatchData {
    njoints: usize,
    nq: usize,
    nv: usize,
    inertias: Vec<BodyInertia>,
    poses: Vec<Pose>,
    v: Vec<S6>,
    a: Vec<S6>,
    f: Vec<S6>,
    q: Vec<Lane>,
    qd: Vec<Lane>,
    qdd: Vec<Lane>,
    tau: Vec<Lane>,
}

impl BatchData {
    /// The workspace for `model`.
    #[must_use]
    pub fn new(model: &Model) -> Self {
        let inertias = model
            .inertias
            .iter()
            .map(|i| {
                let h = i.first_moment();
                let io = i.inertia_about_origin();
                BodyInertia {
                    mass: i.mass(),
                    h: [h.x, h.y, h.z],
                    io: [0, 1, 2].map(|c| [io[(0, c)], io[(1, c)], io[(2, c)]]),
                }
            })
            .collect();
        let nj = model.njoints;
        BatchData {
            njoints: nj,
            nq: model.nq,
            nv: model.nv,
            inertias,
            poses: vec![Pose::default(); nj],
            v: vec![S6::ZERO; nj],
            a: vec![S6::ZERO; nj],
            f: vec![S6::ZERO; nj],
            q: vec![ZERO; model.nq],
            qd: vec![ZERO; model.nv],
            qdd: vec![ZERO; model.nv],
            tau: vec![ZERO; model.nv],
        }
    }
}

/// Inverse dynamics of many states: row `k` of the row-major `out` (n × nv) receives
/// τ = H(q)a + C(q, v)v + g(q) for row `k` of `qs` (n × nq), `vs` and `as_` (n × nv).
///
/// The states are processed [`RNEA_LANES`] at a time by one structure-of-arrays pass (see
/// the [module documentation](self)); a last group of fewer states is padded with copies
/// of its last state, whose results are discarded. Every joint kind is covered: the
/// axis-aligned revolute and prismatic joints (URDF revolute, continuous and prismatic;
/// fixed joints are merged into their parent body by the model builder) run fully in the
/// lanes; unaligned axes, the planar and the free-flyer root compute their placement,
/// joint twist and torque projection with the scalar joint code lane by lane, and the rest
/// of their pass in the lanes.
///
/// The result is bit-for-bit that of calling [`rnea`](super::rnea) on each row. No
/// allocation after [`BatchData::new`].
///
/// # Panics
/// If `qs.len()` is not a multiple of `model.nq`, if `vs`, `as_` or `out` do not hold
/// n × nv values for the n = `qs.len() / nq` states, or if `data` was not made for
/// `model`. A model with nq = 0 has nothing to compute (all slices must then be empty).
///
/// # Examples
/// ```
/// # use moma::{io::urdf::model_from_urdf_str, multibody::RootJoint};
/// # use moma::dynamics::{rnea_batch, BatchData};
/// # let urdf = r#"<robot name="r"><link name="a"/><link name="b">
/// #   <inertial><mass value="1"/><origin xyz="0.5 0 0"/>
/// #   <inertia ixx="0.1" iyy="0.1" izz="0.1" ixy="0" ixz="0" iyz="0"/></inertial></link>
/// #   <joint name="j" type="continuous"><parent link="a"/><child link="b"/>
/// #   <axis xyz="0 1 0"/></joint></robot>"#;
/// let model = model_from_urdf_str(urdf, RootJoint::Fixed, "r.urdf")?;
/// let mut batch = BatchData::new(&model);
/// let qs = [0.0, 0.5, 1.0];            // three states, nq = nv = 1
/// let (vs, accs) = ([0.0; 3], [0.0; 3]);
/// let mut tau = [0.0; 3];
/// rnea_batch(&model, &mut batch, &qs, &vs, &accs, &mut tau);
/// let mut data = moma::multibody::Data::new(&model);
/// let q = nalgebra::DVector::from_element(1, 0.5);
/// let zero = nalgebra::DVector::zeros(1);
/// assert_eq!(tau[1], moma::dynamics::rnea(&model, &mut data, &q, &zero, &zero)[0]);
/// # Ok::<(), moma::Error>(())
/// ```
pub fn rnea_batch(
    model: &Model,
    data: &mut BatchData,
    qs: &[f64],
    vs: &[f64],
    as_: &[f64],
    out: &mut [f64],
) {
    let n = checked_rows(model, data, qs, vs, as_, out);
    run_groups(BatchIsa::detected(), model, data, qs, vs, as_, out, n);
}

/// The number of states of [`rnea_batch`]'s slices, after checking their lengths and the
/// workspace (panics as documented there).
fn checked_rows(
    model: &Model,
    data: &BatchData,
    qs: &[f64],
    vs: &[f64],
    as_: &[f64],
    out: &[f64],
) -> usize {
    let (nq, nv) = (model.nq, model.nv);
    assert!(
        data.njoints == model.njoints && data.nq == nq && data.nv == nv,
        "rnea_batch: BatchData was made for another model"
    );
    let n = if nq == 0 {
        0
    } else {
        assert!(
            qs.len().is_multiple_of(nq),
            "rnea_batch: qs has {} values, not a multiple of nq = {nq}",
            qs.len()
        );
        qs.len() / nq
    };
    for (name, len) in [("vs", vs.len()), ("as", as_.len()), ("out", out.len())] {
        assert!(
            len == n * nv,
            "rnea_batch: {name} has {len} values, expected {n} × {nv}"
        );
    }
    n
}

/// The instruction sets [`rnea_batch`] is compiled for. It picks the widest one the CPU
/// has ([`BatchIsa::detected`]); [`rnea_batch_isa`] runs a given one, so that tests and
/// benchmarks can compare them. Every one performs the same floating-point operations in
/// the same order (no fused multiply–add: Rust never contracts `a * b + c`), so all give
/// the same bits.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BatchIsa {
    /// The build's baseline (SSE2 on x86-64): two lanes per register.
    Portable,
    /// AVX2 (x86-64): four lanes per register.
    Avx2,
    /// AVX-512F (x86-64): one 512-bit register per group of eight lanes.
    Avx512,
}

impl BatchIsa {
    /// Whether this CPU can run `self`.
    #[must_use]
    pub fn is_supported(self) -> bool {
        match self {
            BatchIsa::Portable => true,
            #[cfg(target_arch = "x86_64")]
            BatchIsa::Avx2 => std::arch::is_x86_feature_detected!("avx2"),
            #[cfg(target_arch = "x86_64")]
            BatchIsa::Avx512 => std::arch::is_x86_feature_detected!("avx512f"),
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The instruction sets this CPU can run, baseline first.
    #[must_use]
    pub fn available() -> Vec<BatchIsa> {
        [BatchIsa::Portable, BatchIsa::Avx2, BatchIsa::Avx512]
            .into_iter()
            .filter(|i| i.is_supported())
            .collect()
    }

    /// The widest instruction set this CPU can run (what [`rnea_batch`] uses).
    #[must_use]
    pub fn detected() -> BatchIsa {
        [BatchIsa::Avx512, BatchIsa::Avx2]
            .into_iter()
            .find(|i| i.is_supported())
            .unwrap_or(BatchIsa::Portable)
    }
}

/// [`rnea_batch`] compiled for the instruction set `isa` rather than the detected one.
///
/// # Panics
/// As [`rnea_batch`], and if this CPU lacks `isa` (see [`BatchIsa::available`]).
pub fn rnea_batch_isa(
    isa: BatchIsa,
    model: &Model,
    data: &mut BatchData,
    qs: &[f64],
    vs: &[f64],
    as_: &[f64],
    out: &mut [f64],
) {
    assert!(
        isa.is_supported(),
        "rnea_batch_isa: this CPU cannot run {isa:?}"
    );
    let n = checked_rows(model, data, qs, vs, as_, out);
    run_groups(isa, model, data, qs, vs, as_, out, n);
}

/// Runs [`groups`] compiled for `isa`, which the caller has checked this CPU supports.
#[allow(clippy::too_many_arguments)]
fn run_groups(
    isa: BatchIsa,
    model: &Model,
    data: &mut BatchData,
    qs: &[f64],
    vs: &[f64],
    as_: &[f64],
    out: &mut [f64],
    n: usize,
) {
    if n == 0 {
        return;
    }
    match isa {
        #[cfg(target_arch = "x86_64")]
        BatchIsa::Avx512 => {
            #[allow(unsafe_code)]
            // SAFETY: `groups_avx512` only requires AVX-512F, which the callers detected.
            unsafe {
                groups_avx512(model, data, qs, vs, as_, out, n);
            }
        }
        #[cfg(target_arch = "x86_64")]
        BatchIsa::Avx2 => {
            #[allow(unsafe_code)]
            // SAFETY: `groups_avx2` only requires AVX2, which the callers detected.
            unsafe {
                groups_avx2(model, data, qs, vs, as_, out, n);
            }
        }
        _ => groups(model, data, qs, vs, as_, out, n),
    }
}

/// [`groups`] compiled for AVX2 (two 256-bit registers per lane group), chosen at run
/// time by [`rnea_batch`]. The floating-point operations are the same (no fused
/// multiply–add: Rust never contracts `a * b + c`), so the torques are too.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn groups_avx2(
    model: &Model,
    data: &mut BatchData,
    qs: &[f64],
    vs: &[f64],
    as_: &[f64],
    out: &mut [f64],
    n: usize,
) {
    groups(model, data, qs, vs, as_, out, n);
}

/// [`groups`] compiled for AVX-512F (one 512-bit register per lane group of eight).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f")]
fn groups_avx512(
    model: &Model,
    data: &mut BatchData,
    qs: &[f64],
    vs: &[f64],
    as_: &[f64],
    out: &mut [f64],
    n: usize,
) {
    groups(model, data, qs, vs, as_, out, n);
}

/// The `n` states of the checked slices, [`RNEA_LANES`] at a time: transpose a group
/// into the lanes, one [`pass`], torques back into the rows of `out`.
#[inline(always)]
fn groups(
    model: &Model,
    data: &mut BatchData,
    qs: &[f64],
    vs: &[f64],
    as_: &[f64],
    out: &mut [f64],
    n: usize,
) {
    let (nq, nv) = (model.nq, model.nv);
    let mut start = 0;
    while start < n {
        let count = L.min(n - start);
        for k in 0..L {
            let row = start + k.min(count - 1);
            load_lane(&mut data.q, &qs[row * nq..(row + 1) * nq], k);
            load_lane(&mut data.qd, &vs[row * nv..(row + 1) * nv], k);
            load_lane(&mut data.qdd, &as_[row * nv..(row + 1) * nv], k);
        }
        pass(model, data);
        for k in 0..count {
            let row = start + k;
            for (j, o) in out[row * nv..(row + 1) * nv].iter_mut().enumerate() {
                *o = data.tau[j][k];
            }
        }
        start += count;
    }
}

/// One state's `row` into lane `k` of `dst` (one [`Lane`] per coordinate).
#[inline(always)]
fn load_lane(dst: &mut [Lane], row: &[f64], k: usize) {
    for (d, x) in dst.iter_mut().zip(row) {
        d[k] = *x;
    }
}

/// The twist `axis · x` over the lanes of an unaligned prismatic joint, component by
/// component as `axis * v`.
#[inline(always)]
fn prismatic_motion(axis: &nalgebra::Vector3<f64>, x: Lane) -> S6 {
    S6 {
        lin: V3 {
            x: scale(x, axis.x),
            y: scale(x, axis.y),
            z: scale(x, axis.z),
        },
        ang: V3::ZERO,
    }
}

/// A vector constant over the lanes.
#[inline(always)]
fn splat(v: [f64; 3]) -> V3 {
    V3 {
        x: [v[0]; L],
        y: [v[1]; L],
        z: [v[2]; L],
    }
}

/// `a·c + b·s` (or `a·c − b·s` when `minus`) per component, as nalgebra's
/// `r.column(i) * c + r.column(j) * s`.
#[inline(always)]
fn comb(a: [f64; 3], cs: &Lane, b: [f64; 3], sn: &Lane, minus: bool) -> V3 {
    V3 {
        x: comb1(a[0], cs, b[0], sn, minus),
        y: comb1(a[1], cs, b[1], sn, minus),
        z: comb1(a[2], cs, b[2], sn, minus),
    }
}

/// One component of [`comb`] (a function, not a closure: a closure is not always inlined
/// into the AVX copies of the pass, and then runs as scalar code).
#[inline(always)]
fn comb1(ai: f64, cs: &Lane, bi: f64, sn: &Lane, minus: bool) -> Lane {
    let mut o = ZERO;
    for k in 0..L {
        o[k] = if minus {
            ai * cs[k] - bi * sn[k]
        } else {
            ai * cs[k] + bi * sn[k]
        };
    }
    o
}

/// `parent_from_joint` of a revolute joint over the lanes: columns `i` and `j` of the
/// placement rotate in their plane, column `keep` stays (`sign_first` for the X and Z
/// axes, whose first rotating column gains `+ r_j s`; the Y axis's loses `r_2 s`).
#[inline(always)]
fn revolute_pose(
    placement: &crate::spatial::SE3,
    q: &Lane,
    out: &mut Pose,
    [keep, i, j]: [usize; 3],
    sign_first: bool,
) {
    let r = &placement.rotation;
    let t = placement.translation;
    let mut s = ZERO;
    let mut c = ZERO;
    // `trig::sin_cos` lane by lane: the branch-free body on all lanes (SIMD), then the
    // platform's values for any angle beyond its range
    for k in 0..L {
        (s[k], c[k]) = trig::sin_cos_reduced(q[k]);
    }
    for k in 0..L {
        if !trig::in_reduced_range(q[k]) {
            (s[k], c[k]) = q[k].sin_cos();
        }
    }
    out.r[keep] = splat(col(r, keep));
    out.t = splat([t.x, t.y, t.z]);
    let (ri, rj) = (col(r, i), col(r, j));
    if sign_first {
        // X and Z: c_i = r_i c + r_j s, c_j = r_j c − r_i s
        out.r[i] = comb(ri, &c, rj, &s, false);
        out.r[j] = comb(rj, &c, ri, &s, true);
    } else {
        // Y: c_0 = r_0 c − r_2 s, c_2 = r_0 s + r_2 c
        out.r[i] = comb(ri, &c, rj, &s, true);
        out.r[j] = comb(ri, &s, rj, &c, false);
    }
}

/// `parent_from_joint` of a prismatic joint on frame axis `axis` over the lanes:
/// translation + (column `axis`) · q, component by component.
#[inline(always)]
fn prismatic_pose(placement: &crate::spatial::SE3, q: Lane, out: &mut Pose, axis: usize) {
    let r = &placement.rotation;
    let t = placement.translation;
    out.r = [splat(col(r, 0)), splat(col(r, 1)), splat(col(r, 2))];
    let a = col(r, axis);
    out.t = V3 {
        x: add([t.x; L], scale(q, a[0])),
        y: add([t.y; L], scale(q, a[1])),
        z: add([t.z; L], scale(q, a[2])),
    };
}

/// `parent_from_joint` over the lanes for the revolute and prismatic kinds on a frame axis
/// and the unaligned prismatic one, in the
/// operations of `JointType::parent_from_joint`; `false` for the other kinds.
#[inline(always)]
fn aligned_pose(jt: &JointType, placement: &crate::spatial::SE3, q: Lane, out: &mut Pose) -> bool {
    let r = &placement.rotation;
    let t = placement.translation;
    let tr = [t.x, t.y, t.z];
    match jt {
        JointType::RevoluteX => revolute_pose(placement, &q, out, [0, 1, 2], true),
        JointType::RevoluteY => revolute_pose(placement, &q, out, [1, 0, 2], false),
        JointType::RevoluteZ => revolute_pose(placement, &q, out, [2, 0, 1], true),
        JointType::PrismaticX => prismatic_pose(placement, q, out, 0),
        JointType::PrismaticY => prismatic_pose(placement, q, out, 1),
        JointType::PrismaticZ => prismatic_pose(placement, q, out, 2),
        JointType::PrismaticUnaligned { axis } => {
            // translation + R · (axis · q), R · w in nalgebra's order
            out.r = [splat(col(r, 0)), splat(col(r, 1)), splat(col(r, 2))];
            let w = V3 {
                x: scale(q, axis.x),
                y: scale(q, axis.y),
                z: scale(q, axis.z),
            };
            out.t = splat(tr).add(&out.rot_mul(&w));
        }
        _ => return false,
    }
    true
}

/// Placement, joint twist, joint acceleration and bias of joint `i` lane by lane with the
/// scalar joint code, for the kinds [`aligned_pose`] does not cover. Kept out of line so
/// that the lane values of [`pass`] stay in registers (a local whose address escapes into
/// a call is kept in memory and copied whole).
#[inline(never)]
fn joint_by_lanes(model: &Model, d: &mut BatchData, i: usize) -> (S6, S6, S6) {
    let jt = &model.joint_types[i];
    let (iq, iv) = (model.idx_q[i], model.idx_v[i]);
    let (nqi, nvi) = (model.nqs[i], model.nvs[i]);
    let mut qi = [0.0; 7];
    let mut vi = [0.0; 6];
    let mut ai = [0.0; 6];
    let (mut vj, mut aj, mut cj) = (S6::ZERO, S6::ZERO, S6::ZERO);
    let pose = &mut d.poses[i];
    for k in 0..L {
        for j in 0..nqi {
            qi[j] = d.q[iq + j][k];
        }
        for j in 0..nvi {
            vi[j] = d.qd[iv + j][k];
            ai[j] = d.qdd[iv + j][k];
        }
        let qk = &qi[..nqi];
        let m = jt.parent_from_joint(&model.joint_placements[i], qk);
        pose.set_lane(k, &m);
        let w = jt.motion(qk, &vi[..nvi]);
        vj.set_lane(k, w.linear.into(), w.angular.into());
        let w = jt.motion(qk, &ai[..nvi]);
        aj.set_lane(k, w.linear.into(), w.angular.into());
        if jt.has_bias() {
            let w = jt.bias(qk, &vi[..nvi]);
            cj.set_lane(k, w.linear.into(), w.angular.into());
        }
    }
    (vj, aj, cj)
}

/// `Sᵀ f` of joint `i` lane by lane with the scalar joint code, into `d.tau`, for the
/// kinds other than the aligned revolute and prismatic ones (out of line, as
/// [`joint_by_lanes`]).
#[inline(never)]
fn project_by_lanes(model: &Model, d: &mut BatchData, i: usize) {
    let jt = &model.joint_types[i];
    let (iq, iv) = (model.idx_q[i], model.idx_v[i]);
    let (nqi, nvi) = (model.nqs[i], model.nvs[i]);
    let mut qi = [0.0; 7];
    let mut out = [0.0; 6];
    for k in 0..L {
        for j in 0..nqi {
            qi[j] = d.q[iq + j][k];
        }
        jt.project_force(&qi[..nqi], &d.f[i].force_lane(k), &mut out[..nvi]);
        for (j, o) in out[..nvi].iter().enumerate() {
            d.tau[iv + j][k] = *o;
        }
    }
}

/// Body twist and acceleration of a joint with full twists `vj`, `aj` (and bias), in the
/// operations of the scalar `rnea`.
#[inline(always)]
fn general_twists(pose: &Pose, vp: &S6, ap: &S6, vj: &S6, aj: &S6, bias: Option<&S6>) -> (S6, S6) {
    let acc = pose.inverse_act_motion(ap).add(aj);
    let vel = pose.inverse_act_motion(vp).add(vj);
    let mut acc = acc.add(&vel.cross_motion(vj));
    if let Some(c) = bias {
        acc = acc.add(c);
    }
    (vel, acc)
}

/// One RNEA pass over the lanes' states held in `d.q`, `d.qd`, `d.qdd`, into `d.tau`.
#[inline(always)]
fn pass(model: &Model, d: &mut BatchData) {
    let g = model.gravity;
    d.v[0] = S6::ZERO;
    d.a[0] = S6::ZERO;
    d.a[0].lin = V3 {
        x: [-g.x; L],
        y: [-g.y; L],
        z: [-g.z; L],
    };
    for i in 1..model.njoints {
        let jt = &model.joint_types[i];
        let p = model.parents[i].0;
        let (iq, iv) = (model.idx_q[i], model.idx_v[i]);
        let aligned = aligned_pose(jt, &model.joint_placements[i], d.q[iq], &mut d.poses[i]);
        let (vel, acc) = match (aligned, jt.axis_slot(), jt) {
            // as the scalar `rnea`: the joint twist q̇·e_k added and crossed by its slot
            (true, Some(k), _) => {
                let pose = &d.poses[i];
                let mut acc = pose.inverse_act_motion(&d.a[p]);
                acc.add_to_slot(k, &d.qdd[iv]);
                let mut vel = pose.inverse_act_motion(&d.v[p]);
                vel.add_to_slot(k, &d.qd[iv]);
                let acc = acc.add(&vel.cross_slot(k, &d.qd[iv]));
                (vel, acc)
            }
            (true, None, JointType::PrismaticUnaligned { axis }) => {
                let vj = prismatic_motion(axis, d.qd[iv]);
                let aj = prismatic_motion(axis, d.qdd[iv]);
                general_twists(&d.poses[i], &d.v[p], &d.a[p], &vj, &aj, None)
            }
            _ => {
                let (vj, aj, cj) = joint_by_lanes(model, d, i);
                let bias = jt.has_bias().then_some(&cj);
                general_twists(&d.poses[i], &d.v[p], &d.a[p], &vj, &aj, bias)
            }
        };
        let inertia = &d.inertias[i];
        d.f[i] = inertia
            .mul_motion(&acc)
            .add(&vel.cross_force(&inertia.mul_motion(&vel)));
        d.v[i] = vel;
        d.a[i] = acc;
    }
    for i in (1..model.njoints).rev() {
        let jt = &model.joint_types[i];
        let iv = model.idx_v[i];
        match (jt.axis_slot(), jt) {
            (Some(k), _) => d.tau[iv] = *d.f[i].slot_mut(k),
            // `axis.dot(f.linear)`: nalgebra's 3-vector dot is (x·x' + y·y') + z·z'
            (None, JointType::PrismaticUnaligned { axis }) => {
                let f = &d.f[i].lin;
                d.tau[iv] = add(
                    add(scale(f.x, axis.x), scale(f.y, axis.y)),
                    scale(f.z, axis.z),
                );
            }
            _ => project_by_lanes(model, d, i),
        }
        let p = model.parents[i].0;
        if p > 0 {
            let fp = d.poses[i].act_force(&d.f[i]);
            d.f[p] = d.f[p].add(&fp);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lane_spatial_ops_match_scalar_ones() {
        let m = Motion::new(
            nalgebra::Vector3::new(0.3, -1.2, 0.7),
            nalgebra::Vector3::new(-0.4, 0.9, 2.1),
        );
        let n = Motion::new(
            nalgebra::Vector3::new(1.1, 0.2, -0.5),
            nalgebra::Vector3::new(0.6, -0.8, 0.25),
        );
        let mut a = S6::ZERO;
        let mut b = S6::ZERO;
        for k in 0..L {
            a.set_lane(k, m.linear.into(), m.angular.into());
            b.set_lane(k, n.linear.into(), n.angular.into());
        }
        let fb = b.force_lane(0);
        for k in 0..L {
            assert_eq!(a.cross_motion(&b).motion_lane(k), m.cross_motion(&n));
            assert_eq!(a.cross_force(&b).force_lane(k), m.cross_force(&fb));
        }
    }
}

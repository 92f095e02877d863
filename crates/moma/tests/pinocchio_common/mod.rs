//! Shared by the Pinocchio cross-checks (`rigid_body_pinocchio.rs`,
//! `rigid_body_pinocchio_more.rs`, `io_pinocchio_layout.rs`, and the derivatives'
//! `dynamics_derivatives.rs` and `dynamics_frame_derivatives.rs`): reading a reference file of `tests/data/pinocchio`,
//! converting Pinocchio's coordinates to ours, and the comparisons both make, every value
//! to 1e-9 relative (absolute below 1).
//!
//! Pinocchio's planar base uses q = [x, y, cos θ, sin θ] and a base-frame velocity
//! v_P = T v with T = diag(Rᵀ(θ), 1); ours is q = [x, y, θ] with world-axes v. Hence
//! τ = Tᵀ τ_P, H = Tᵀ H_P T, J = J_P T, A_g = A_g,P T, and accelerations
//! a = T⁻¹ a_P + Ṫ⁻¹ v_P. Continuous joints ([cos, sin] in Pinocchio) become one angle.

#![allow(dead_code)] // each test file uses its own part

use moma::dynamics;
use moma::io::urdf::model_from_urdf_file;
use moma::kinematics::{self, ReferenceFrame};
use moma::multibody::{Data, FrameIndex, Model, RootJoint};
use nalgebra::{DMatrix, DVector, Matrix6xX};
use serde_json::Value;
use std::path::PathBuf;

/// Relative tolerance of every comparison (absolute below 1).
pub const REL_TOL: f64 = 1e-9;

pub fn data_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("tests/data/pinocchio")
}

pub fn vecf(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

pub fn matf(v: &Value) -> DMatrix<f64> {
    let rows: Vec<Vec<f64>> = v.as_array().unwrap().iter().map(vecf).collect();
    let (r, c) = (rows.len(), rows[0].len());
    DMatrix::from_fn(r, c, |i, j| rows[i][j])
}

/// The root a reference file names (`"fixed"`, `"planar"`, `"free-flyer"`).
pub fn root_of(name: &str) -> RootJoint {
    match name {
        "fixed" => RootJoint::Fixed,
        "planar" => RootJoint::Planar,
        "free-flyer" => RootJoint::FreeFlyer,
        other => panic!("unknown root {other}"),
    }
}

/// The largest `|got − want|` over `max(1, max |want|)`.
pub fn rel_err(got: &DMatrix<f64>, want: &DMatrix<f64>) -> f64 {
    assert_eq!(got.shape(), want.shape());
    (got - want).amax() / want.amax().max(1.0)
}

fn usize_of(v: &Value) -> usize {
    v.as_u64().unwrap() as usize
}

/// Asserts `got` equals `want` elementwise to [`REL_TOL`]; returns the worst error.
#[track_caller]
pub fn check(what: &str, got: &[f64], want: &[f64]) -> f64 {
    assert_eq!(got.len(), want.len(), "{what}: length");
    let mut worst: f64 = 0.0;
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        let err = (g - w).abs() / w.abs().max(1.0);
        assert!(
            err <= REL_TOL,
            "{what}[{k}]: got {g}, want {w} (rel err {err:e})"
        );
        worst = worst.max(err);
    }
    worst
}

/// How a Pinocchio joint's coordinates map to ours.
#[derive(Clone, Copy, PartialEq, Debug)]
pub enum Kind {
    /// The same coordinates.
    Same,
    /// Planar: [x, y, cos θ, sin θ] → [x, y, θ], base-frame → world-axes velocity.
    Planar,
    /// Continuous: [cos θ, sin θ] → θ.
    Unbounded,
}

/// Pinocchio's coordinates → ours, for one reference file.
pub struct Conv {
    /// (pinocchio idx_q, our idx_q, idx_v, nq (pinocchio), kind) per joint.
    pub joints: Vec<(usize, usize, usize, usize, Kind)>,
}

impl Conv {
    pub fn new(j: &Value) -> Self {
        let mut joints = Vec::new();
        let mut oq = 0;
        for jt in j["joints"].as_array().unwrap() {
            let ty = jt["type"].as_str().unwrap();
            let u = |k: &str| usize_of(&jt[k]);
            let kind = if ty.contains("Planar") {
                Kind::Planar
            } else if ty.contains("RUB") || ty.contains("Unbounded") {
                Kind::Unbounded
            } else {
                Kind::Same
            };
            joints.push((u("idx_q"), oq, u("idx_v"), u("nq"), kind));
            oq += match kind {
                Kind::Planar => 3,
                Kind::Unbounded => 1,
                Kind::Same => u("nq"),
            };
        }
        Self { joints }
    }

    pub fn q(&self, qp: &[f64], nq: usize) -> DVector<f64> {
        let mut q = DVector::zeros(nq);
        for &(iq, oq, _, pnq, kind) in &self.joints {
            match kind {
                Kind::Planar => {
                    q[oq] = qp[iq];
                    q[oq + 1] = qp[iq + 1];
                    q[oq + 2] = qp[iq + 3].atan2(qp[iq + 2]);
                }
                Kind::Unbounded => q[oq] = qp[iq + 1].atan2(qp[iq]),
                Kind::Same => q.rows_mut(oq, pnq).copy_from_slice(&qp[iq..iq + pnq]),
            }
        }
        q
    }

    /// The planar base angle θ and v index, if any.
    fn planar(&self, q: &DVector<f64>) -> Option<(f64, usize)> {
        self.joints
            .iter()
            .find(|j| j.4 == Kind::Planar)
            .map(|&(_, oq, iv, _, _)| (q[oq + 2], iv))
    }

    /// T (nv × nv) with v_P = T v.
    pub fn t(&self, q: &DVector<f64>, nv: usize) -> DMatrix<f64> {
        let mut t = DMatrix::identity(nv, nv);
        if let Some((th, iv)) = self.planar(q) {
            let (s, c) = th.sin_cos();
            // Rᵀ = [c s; -s c]
            t[(iv, iv)] = c;
            t[(iv, iv + 1)] = s;
            t[(iv + 1, iv)] = -s;
            t[(iv + 1, iv + 1)] = c;
        }
        t
    }

    /// Our acceleration from Pinocchio's (a = T⁻¹ a_P + Ṫ⁻¹ v_P).
    pub fn acc(&self, q: &DVector<f64>, v_p: &DVector<f64>, a_p: &DVector<f64>) -> DVector<f64> {
        let t = self.t(q, v_p.len());
        let mut a = t.transpose() * a_p; // T⁻¹ = Tᵀ (rotation block)
        if let Some((_, iv)) = self.planar(q) {
            let v_w = t.transpose() * v_p;
            let w = v_p[iv + 2];
            a[iv] += -w * v_w[iv + 1];
            a[iv + 1] += w * v_w[iv];
        }
        a
    }
}

/// One reference file with the model it describes.
pub struct Case {
    pub file: String,
    pub j: Value,
    pub model: Model,
    pub conv: Conv,
}

impl Case {
    /// Reads `file` of [`data_dir`] and loads its URDF with `root` and its gravity.
    pub fn load(file: &str, root: RootJoint) -> Self {
        let text = std::fs::read_to_string(data_dir().join(file)).unwrap();
        let j: Value = serde_json::from_str(&text).unwrap();
        let urdf = data_dir().join(j["urdf"].as_str().unwrap());
        let mut model = model_from_urdf_file(&urdf, root).unwrap();
        model.gravity = nalgebra::Vector3::from_vec(vecf(&j["gravity"]));
        let conv = Conv::new(&j);
        Self {
            file: file.to_string(),
            j,
            model,
            conv,
        }
    }

    /// The structure every reference file has: nv, njoints, nframes, total mass, and per
    /// joint its order, parent, idx_v and (one-coordinate joints with the same
    /// coordinates) position limits.
    pub fn check_structure(&self) {
        let (model, j) = (&self.model, &self.j);
        assert_eq!(model.nv, usize_of(&j["nv"]), "nv");
        assert_eq!(model.njoints, usize_of(&j["njoints"]), "njoints");
        assert_eq!(model.nframes(), usize_of(&j["nframes"]), "nframes");
        check(
            "total_mass",
            &[model.total_mass()],
            &[j["total_mass"].as_f64().unwrap()],
        );
        let (lo, hi) = (
            vecf(&j["lower_position_limit"]),
            vecf(&j["upper_position_limit"]),
        );
        for (k, jt) in j["joints"].as_array().unwrap().iter().enumerate() {
            let name = jt["name"].as_str().unwrap();
            let id = k + 1;
            assert_eq!(model.names[id], name, "joint order");
            assert_eq!(model.joint_id(name).unwrap().0, id, "joint order of {name}");
            assert_eq!(
                model.names[model.parents[id].0],
                jt["parent"].as_str().unwrap(),
                "parent of {name}"
            );
            assert_eq!(model.idx_v[id], usize_of(&jt["idx_v"]), "idx_v {name}");
            if self.conv.joints[k].4 == Kind::Same && model.nvs[id] == 1 {
                let (iq, oq) = (self.conv.joints[k].0, model.idx_q[id]);
                check(
                    &format!("position limits of {name}"),
                    &[
                        model.lower_position_limit[oq],
                        model.upper_position_limit[oq],
                    ],
                    &[lo[iq], hi[iq]],
                );
            }
        }
    }

    /// For every state of the file: converts it to our coordinates, compares what every
    /// reference file has (RNEA, CRBA, ABA, nonlinear effects, gravity, CoM, centroidal
    /// momentum matrix) and then `extra`'s comparisons; prints the worst error.
    pub fn compare_states(&self, mut extra: impl FnMut(&mut Data, &State, &mut Tally)) {
        let mut data = Data::new(&self.model);
        let mut tally = Tally {
            file: self.file.clone(),
            state: 0,
            worst: 0.0,
        };
        for (si, s) in self.j["states"].as_array().unwrap().iter().enumerate() {
            tally.state = si;
            let st = State::new(self, s);
            self.compare_dynamics(&mut data, &st, &mut tally);
            extra(&mut data, &st, &mut tally);
        }
        eprintln!("{}: worst relative error {:e}", self.file, tally.worst);
    }

    fn compare_dynamics(&self, data: &mut Data, st: &State, tally: &mut Tally) {
        let (model, conv, s, t, q) = (&self.model, &self.conv, st.s, &st.t, &st.q);
        let want = t.transpose() * DVector::from_vec(vecf(&s["rnea_tau"]));
        let got = dynamics::rnea(model, data, q, &st.v, &st.a);
        tally.cmp("rnea_tau", got.as_slice(), want.as_slice());

        let m_p = matf(&s["crba_M"]);
        let want = t.transpose() * &m_p * t;
        let got = dynamics::crba(model, data, q);
        tally.cmp("crba_M", got.as_slice(), want.as_slice());

        let want = conv.acc(q, &st.v_p, &DVector::from_vec(vecf(&s["aba_ddq"])));
        let got = dynamics::aba(model, data, q, &st.v, &st.tau_in);
        tally.cmp("aba_ddq", got.as_slice(), want.as_slice());

        // nle: our a = 0 is Pinocchio's a_P = −T Ṫ⁻¹ v_P
        let zero = DVector::zeros(model.nv);
        let a0_p = t * (&zero - conv.acc(q, &st.v_p, &zero));
        let want = t.transpose() * (&m_p * a0_p + DVector::from_vec(vecf(&s["nle"])));
        let got = dynamics::nonlinear_effects(model, data, q, &st.v);
        tally.cmp("nle", got.as_slice(), want.as_slice());

        let want = t.transpose() * DVector::from_vec(vecf(&s["gravity_torque"]));
        let got = dynamics::gravity_torque(model, data, q);
        tally.cmp("gravity_torque", got.as_slice(), want.as_slice());

        let got = dynamics::center_of_mass(model, data, q);
        tally.cmp("com", got.as_slice(), &vecf(&s["com"]));

        let want = matf(&s["centroidal_map_Ag"]) * t;
        let got = dynamics::centroidal_momentum_matrix(model, data, q);
        tally.cmp("centroidal_map_Ag", got.as_slice(), want.as_slice());
        tally.cmp("ccrba com", data.com.as_slice(), &vecf(&s["com"]));
    }

    /// Compares our LOCAL_WORLD_ALIGNED Jacobian of `frame` with Pinocchio's `want_p`
    /// (converted: J = J_P T).
    pub fn compare_frame_jacobian(
        &self,
        data: &mut Data,
        st: &State,
        frame: FrameIndex,
        want_p: &Value,
        tally: &mut Tally,
    ) {
        let mut jac = Matrix6xX::zeros(self.model.nv);
        kinematics::frame_jacobian(
            &self.model,
            data,
            &st.q,
            frame,
            ReferenceFrame::LocalWorldAligned,
            &mut jac,
        );
        let want = matf(want_p) * &st.t;
        tally.cmp(
            &format!(
                "jacobian of frame {} ({})",
                frame.0, self.model.frames[frame.0].name
            ),
            jac.as_slice(),
            want.as_slice(),
        );
    }
}

/// One state of a reference file in our coordinates, with its JSON.
pub struct State<'a> {
    pub s: &'a Value,
    pub q: DVector<f64>,
    /// Pinocchio's velocity v_P.
    pub v_p: DVector<f64>,
    /// T with v_P = T v.
    pub t: DMatrix<f64>,
    pub v: DVector<f64>,
    pub a: DVector<f64>,
    pub tau_in: DVector<f64>,
}

impl<'a> State<'a> {
    fn new(case: &Case, s: &'a Value) -> Self {
        let q = case.conv.q(&vecf(&s["q"]), case.model.nq);
        let v_p = DVector::from_vec(vecf(&s["v"]));
        let a_p = DVector::from_vec(vecf(&s["a"]));
        let tau_p = DVector::from_vec(vecf(&s["tau_in"]));
        let t = case.conv.t(&q, case.model.nv);
        let v = t.transpose() * &v_p;
        let a = case.conv.acc(&q, &v_p, &a_p);
        let tau_in = t.transpose() * &tau_p;
        Self {
            s,
            q,
            v_p,
            t,
            v,
            a,
            tau_in,
        }
    }
}

/// The comparisons of one file: each asserted to [`REL_TOL`], the worst error kept.
pub struct Tally {
    file: String,
    state: usize,
    worst: f64,
}

impl Tally {
    #[track_caller]
    pub fn cmp(&mut self, what: &str, got: &[f64], want: &[f64]) {
        let tag = format!("{} state {} {what}", self.file, self.state);
        self.worst = self.worst.max(check(&tag, got, want));
    }
}

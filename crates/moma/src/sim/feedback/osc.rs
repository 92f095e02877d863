//! Operational-space control of a frame's position: on a wheeled robot through the
//! reduced model ([`OscController`]) and on a fixed-base arm ([`FixedOscController`]).

use super::references::PointReference;
use crate::control::osc::{ReducedOscData, osc_reduced};
use crate::error::{Error, Result};
use crate::mobile::WheeledModel;
use crate::multibody::FrameIndex;
use crate::sim::closed_loop::{FeedbackLaw, Observation, SaturationFlags, clip_inputs};
use crate::sim::computed_torque::ComputedTorque;
use nalgebra::{DMatrix, DVector};

/// Gains of [`OscController`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OscGains {
    /// Task stiffness k_p (1/s²).
    pub kp: f64,
    /// Task damping k_v (1/s).
    pub kv: f64,
    /// Null-space posture stiffness on the arm joints (N·m/rad).
    pub posture_kp: f64,
    /// Null-space damping on every reduced velocity (N·m·s/rad).
    pub posture_kd: f64,
}

/// Operational-space control of a frame's position on a wheeled robot, through the
/// reduced model (see the module documentation).
#[derive(Clone, Debug)]
pub struct OscController {
    wm: WheeledModel,
    rod: ReducedOscData,
    frame: FrameIndex,
    /// The end-effector reference.
    pub reference: PointReference,
    /// Gains.
    pub gains: OscGains,
    torque: ComputedTorque,
    posture: Vec<f64>,
    q: DVector<f64>,
    v: DVector<f64>,
    zero_a: DVector<f64>,
    tau0: DVector<f64>,
    tau_r: DVector<f64>,
}

impl OscController {
    /// OSC of the position of `frame` (named) of `wm`; the null space holds the arm at
    /// `posture` (one value per arm joint); `max_torque` clips every input.
    ///
    /// # Errors
    /// An unknown frame, bad gains, reference or posture.
    pub fn new(
        wm: WheeledModel,
        frame: &str,
        reference: PointReference,
        gains: OscGains,
        posture: Vec<f64>,
        max_torque: Option<f64>,
    ) -> Result<Self> {
        let fid = wm.model.frame_id(frame)?;
        reference.validate()?;
        check_osc_gains(&gains, max_torque)?;
        crate::error::ensure_len("posture", wm.nr() - 2, posture.len())?;
        crate::error::ensure_finite("posture", &posture)?;
        let (nq, nr, nu) = (wm.model.nq, wm.nr(), wm.nu());
        Ok(Self {
            rod: ReducedOscData::new(&wm, &[0, 1, 2]),
            frame: fid,
            reference,
            gains,
            torque: ComputedTorque::new(&wm, vec![max_torque.unwrap_or(f64::INFINITY); nu])?,
            posture,
            q: DVector::zeros(nq),
            v: DVector::zeros(nr),
            zero_a: DVector::zeros(3),
            tau0: DVector::zeros(nr),
            tau_r: DVector::zeros(nr),
            wm,
        })
    }

    /// OSC update at `(q, v)` with a zero task acceleration; returns the frame position
    /// and its velocity `J_r v_r`.
    fn update(&mut self, q: &[f64], v: &[f64]) -> Result<([f64; 3], [f64; 3])> {
        self.q.copy_from_slice(q);
        self.v.copy_from_slice(v);
        let g = self.gains;
        self.tau0[0] = -g.posture_kd * v[0];
        self.tau0[1] = -g.posture_kd * v[1];
        for (j, &dof) in self.wm.arm_dofs().iter().enumerate() {
            self.tau0[2 + j] = g.posture_kp * (self.posture[j] - q[dof]) - g.posture_kd * v[2 + j];
        }
        osc_reduced(
            &self.wm,
            &mut self.rod,
            self.frame,
            &self.q,
            &self.v,
            &self.zero_a,
            &self.tau0,
        )?;
        let p = self.rod.wheeled.data.world_from_frame[self.frame.0].translation;
        Ok(([p[0], p[1], p[2]], task_velocity(&self.rod.osc.jacobian, v)))
    }
}

impl FeedbackLaw for OscController {
    fn nu(&self) -> usize {
        self.wm.nu()
    }

    fn error_names(&self) -> Vec<String> {
        position_error_names()
    }

    fn has_lyapunov(&self) -> bool {
        true
    }

    fn control(&mut self, t: f64, q: &[f64], v: &[f64], u: &mut [f64]) -> Result<SaturationFlags> {
        let (x, xdot) = self.update(q, v)?;
        osc_torque(
            &self.rod.osc,
            &self.gains,
            &self.reference,
            t,
            x,
            xdot,
            self.tau_r.as_mut_slice(),
        );
        let torque = self
            .torque
            .inputs_from_reduced_force(self.tau_r.as_slice(), u);
        Ok(SaturationFlags {
            speed: false,
            torque,
        })
    }

    fn observe(&mut self, t: f64, q: &[f64], v: &[f64], e: &mut [f64]) -> Result<Observation> {
        let (x, xdot) = self.update(q, v)?;
        Ok(osc_observation(&self.gains, &self.reference, t, x, xdot, e))
    }
}

/// Operational-space control of a frame's position on a fixed-base arm
/// ([`crate::control::osc::osc_fixed_base`]), plant [`crate::sim::fixed_base::FixedBaseSystem`]:
/// `a_des = ẍ_d + k_v (ẋ_d − ẋ) + k_p (x_d − x)`, null-space posture
/// `τ₀ = posture_kp (q* − q) − posture_kd q̇`; V as [`OscController`].
#[derive(Clone, Debug)]
pub struct FixedOscController {
    model: crate::multibody::Model,
    data: crate::multibody::Data,
    od: crate::control::osc::OscData,
    frame: FrameIndex,
    /// The end-effector reference.
    pub reference: PointReference,
    /// Gains.
    pub gains: OscGains,
    max_torque: Option<f64>,
    posture: Vec<f64>,
    q: DVector<f64>,
    v: DVector<f64>,
    zero_a: DVector<f64>,
    tau0: DVector<f64>,
}

impl FixedOscController {
    /// OSC of the position of `frame` (named) of `model`; the null space holds `posture`
    /// (one value per joint); `max_torque` clips every input.
    ///
    /// # Errors
    /// An unknown frame, bad gains, reference or posture.
    pub fn new(
        model: crate::multibody::Model,
        frame: &str,
        reference: PointReference,
        gains: OscGains,
        posture: Vec<f64>,
        max_torque: Option<f64>,
    ) -> Result<Self> {
        let fid = model.frame_id(frame)?;
        reference.validate()?;
        check_osc_gains(&gains, max_torque)?;
        crate::error::ensure_len("posture", model.nv, posture.len())?;
        crate::error::ensure_finite("posture", &posture)?;
        let (nq, nv) = (model.nq, model.nv);
        Ok(Self {
            data: crate::multibody::Data::new(&model),
            od: crate::control::osc::OscData::new(nv, &[0, 1, 2]),
            frame: fid,
            reference,
            gains,
            max_torque,
            posture,
            q: DVector::zeros(nq),
            v: DVector::zeros(nv),
            zero_a: DVector::zeros(3),
            tau0: DVector::zeros(nv),
            model,
        })
    }

    fn update(&mut self, q: &[f64], v: &[f64]) -> Result<([f64; 3], [f64; 3])> {
        self.q.copy_from_slice(q);
        self.v.copy_from_slice(v);
        let g = self.gains;
        for i in 0..self.model.nv {
            self.tau0[i] = g.posture_kp * (self.posture[i] - q[i]) - g.posture_kd * v[i];
        }
        crate::control::osc::osc_fixed_base(
            &self.model,
            &mut self.data,
            &mut self.od,
            self.frame,
            &self.q,
            &self.v,
            &self.zero_a,
            &self.tau0,
        )?;
        let p = self.data.world_from_frame[self.frame.0].translation;
        Ok(([p[0], p[1], p[2]], task_velocity(&self.od.jacobian, v)))
    }
}

/// `J v` for the three position rows of a task Jacobian.
fn task_velocity(j: &DMatrix<f64>, v: &[f64]) -> [f64; 3] {
    let mut xd = [0.0; 3];
    for (k, x) in xd.iter_mut().enumerate() {
        *x = (0..j.ncols()).map(|c| j[(k, c)] * v[c]).sum();
    }
    xd
}

/// The error names of a frame-position task.
fn position_error_names() -> Vec<String> {
    ["e_x [m]", "e_y [m]", "e_z [m]"]
        .iter()
        .map(|s| (*s).to_string())
        .collect()
}

fn check_osc_gains(gains: &OscGains, max_torque: Option<f64>) -> Result<()> {
    for (n, x) in [
        ("controller.kp", gains.kp),
        ("controller.kv", gains.kv),
        ("controller.posture_kp", gains.posture_kp),
        ("controller.posture_kd", gains.posture_kd),
    ] {
        if !(x.is_finite() && x >= 0.0) {
            return Err(Error::invalid(
                n,
                format!("must be >= 0 and finite, got {x}"),
            ));
        }
    }
    if let Some(m) = max_torque {
        crate::error::ensure_positive("controller.max_torque", m)?;
    }
    Ok(())
}

/// `a = ẍ_d + k_v (ẋ_d − ẋ) + k_p (x_d − x)`, then `τ = τ(a = 0) + Jᵀ Λ a` into `u`.
fn osc_torque(
    od: &crate::control::osc::OscData,
    gains: &OscGains,
    reference: &PointReference,
    t: f64,
    x: [f64; 3],
    xdot: [f64; 3],
    u: &mut [f64],
) {
    let (xd, vd, ad) = reference.at(t);
    let mut a = [0.0; 3];
    for k in 0..3 {
        a[k] = ad[k] + gains.kv * (vd[k] - xdot[k]) + gains.kp * (xd[k] - x[k]);
    }
    let mut la = [0.0; 3];
    for (i, l) in la.iter_mut().enumerate() {
        *l = (0..3).map(|k| od.task_inertia[(i, k)] * a[k]).sum();
    }
    for (c, uc) in u.iter_mut().enumerate() {
        *uc = od.torque[c] + (0..3).map(|k| od.jacobian[(k, c)] * la[k]).sum::<f64>();
    }
}

fn osc_observation(
    gains: &OscGains,
    reference: &PointReference,
    t: f64,
    x: [f64; 3],
    xdot: [f64; 3],
    e: &mut [f64],
) -> Observation {
    let (xd, vd, _) = reference.at(t);
    let (mut ee, mut ed) = (0.0, 0.0);
    for k in 0..3 {
        e[k] = xd[k] - x[k];
        let d = vd[k] - xdot[k];
        ee += e[k] * e[k];
        ed += d * d;
    }
    Observation {
        lyapunov: Some(0.5 * ed + 0.5 * gains.kp * ee),
        lyapunov_rate: Some(-gains.kv * ed),
    }
}

impl FeedbackLaw for FixedOscController {
    fn nu(&self) -> usize {
        self.model.nv
    }

    fn error_names(&self) -> Vec<String> {
        position_error_names()
    }

    fn has_lyapunov(&self) -> bool {
        true
    }

    fn control(&mut self, t: f64, q: &[f64], v: &[f64], u: &mut [f64]) -> Result<SaturationFlags> {
        let (x, xdot) = self.update(q, v)?;
        osc_torque(&self.od, &self.gains, &self.reference, t, x, xdot, u);
        let torque = self.max_torque.is_some_and(|m| clip_inputs(u, m));
        Ok(SaturationFlags {
            speed: false,
            torque,
        })
    }

    fn observe(&mut self, t: f64, q: &[f64], v: &[f64], e: &mut [f64]) -> Result<Observation> {
        let (x, xdot) = self.update(q, v)?;
        Ok(osc_observation(&self.gains, &self.reference, t, x, xdot, e))
    }
}

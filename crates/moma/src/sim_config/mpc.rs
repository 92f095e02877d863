//! The `[controller.mpc]` table of `moma simulate` and the law `mpc` it configures: the
//! whole-body MPC ([`crate::control::mpc::WholeBodyMpc`]) of a URDF robot on a
//! differential drive with tracked wheels, run as a [`crate::sim::mpc_law::MpcLaw`]
//! (schema in docs/simulate.md, the MPC in docs/mpc.md). The table's schema and checks
//! are [`crate::sim::mpc_table`]'s, shared with `moma mission`'s `[control.mpc]`; its
//! errors name `controller.mpc.*`.

use std::path::Path;

use nalgebra::{Matrix3, Vector3};

use crate::control::mpc::KnotReference;
use crate::error::Result;
use crate::mobile::WheeledModel;
use crate::sim::closed_loop::FeedbackLaw;
use crate::sim::mpc_law::MpcLaw;
use crate::sim::mpc_table::build_mpc;
pub use crate::sim::mpc_table::{MpcSpec, WeightsSpec};

/// The reference of law `mpc`: the base along +x from the origin at `vr` (pose
/// `[vr t, 0, 0]`, as reference kind `line`) and, from `target_from` on, the end
/// effector at `target`.
#[derive(Clone, Copy, Debug)]
pub struct LineReach {
    /// Base speed (m/s).
    pub vr: f64,
    /// End-effector target (m, world).
    pub target: [f64; 3],
    /// Time the target becomes active (s).
    pub target_from: f64,
}

impl LineReach {
    /// The knot reference at `t` (target orientation: the world axes).
    #[must_use]
    pub fn at(&self, t: f64) -> KnotReference {
        KnotReference {
            base: [self.vr * t, 0.0, 0.0],
            end_effector: (t >= self.target_from)
                .then_some((Vector3::from(self.target), Matrix3::identity())),
        }
    }
}

/// The law `mpc` of `spec` on `wm` (loaded from `urdf`), the end effector `frame`, from
/// the initial configuration `q0`, tracking `reference`; `base_dir` resolves paths.
///
/// # Errors
/// [`crate::Error::Scenario`] naming the `controller.mpc.*` field, the frame or a joint.
pub fn mpc_law(
    spec: &MpcSpec,
    frame: &str,
    wm: &WheeledModel,
    urdf: &Path,
    q0: &[f64],
    reference: LineReach,
    base_dir: &Path,
) -> Result<Box<dyn FeedbackLaw>> {
    if spec.map_clearance.is_some() {
        return Err(crate::Error::Scenario(
            "controller.mpc.map_clearance: moma simulate has no map to keep the base clear \
             of (the key is read by moma mission's [control.mpc])"
                .to_string(),
        ));
    }
    let mpc = build_mpc(
        spec,
        "controller.mpc",
        frame,
        "controller.frame",
        wm,
        urdf,
        q0,
        base_dir,
    )?;
    Ok(Box::new(MpcLaw::new(mpc, move |t| reference.at(t))))
}

//! What several subcommands share: loading a robot model, reading a states file, parsing
//! number lists and the other options of the kinematics commands, and the "ran but did
//! not reach its goal" outcome (exit status 3, see `docs/cli.md`).

use anyhow::{Context, Result, anyhow, bail};
use moma::ik::model::ModelFrame;
use moma::ik::tasks::TaskRows;
use moma::mobile::DiffDrive;
use moma::multibody::{Model, RootJoint};
use nalgebra::{DMatrix, DVector};
use std::path::Path;
use std::sync::Arc;

/// The command ran to the end but did not reach its goal (IK not converged, a potential
/// field stuck in a local minimum, `scen` mismatches, a target reachable from no base
/// pose). `main` prints the message and exits with status 3; whatever diagnostics the
/// command wrote before returning it stay in place (documented per command).
#[derive(Debug)]
pub struct GoalNotReached(pub String);

impl std::fmt::Display for GoalNotReached {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for GoalNotReached {}

/// Returns the [`GoalNotReached`] error with `message`.
pub fn goal_not_reached<T>(message: impl Into<String>) -> Result<T> {
    Err(GoalNotReached(message.into()).into())
}

/// Parses a `--root` value.
pub fn parse_root(s: &str) -> Result<RootJoint, String> {
    s.parse::<RootJoint>().map_err(|e| e.to_string())
}

/// Loads a URDF model with the given root joint. moma's URDF errors name the file and the
/// element at fault; the error itself (not its text) is kept so the cause of an I/O error
/// is printed too.
pub fn load_model(path: &Path, root: RootJoint) -> Result<Model> {
    Ok(moma::io::urdf::model_from_urdf_file(path, root)?)
}

pub use moma::io::states::State;

/// Reads a states file and parses it with [`moma::io::states::parse_states`] (schema,
/// `allowed` fields and bounds documented there); errors name the file and the field.
pub fn read_states(path: &Path, allowed: &[&str]) -> Result<Vec<State>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read states file", path.display()))?;
    Ok(moma::io::states::parse_states(&text, path, allowed)?)
}

/// One state's `q`, `v`, `a` and `tau` as vectors (an absent one is zero), after
/// [`moma::kinematics::check_state`] checks their lengths and values against `model`;
/// `src` names the state in errors.
pub fn state_vectors(model: &Model, s: &State, src: &str) -> Result<[DVector<f64>; 4]> {
    moma::kinematics::check_state(
        model,
        src,
        Some(&s.q),
        s.v.as_deref(),
        s.a.as_deref(),
        s.tau.as_deref(),
    )?;
    let or_zero = |x: &Option<Vec<f64>>| {
        x.as_ref().map_or_else(
            || DVector::zeros(model.nv),
            |x| DVector::from_column_slice(x),
        )
    };
    Ok([
        DVector::from_column_slice(&s.q),
        or_zero(&s.v),
        or_zero(&s.a),
        or_zero(&s.tau),
    ])
}

/// A matrix as a list of its rows (the JSON outputs' layout).
pub fn rows(m: &DMatrix<f64>) -> Vec<Vec<f64>> {
    m.row_iter().map(|r| r.iter().copied().collect()).collect()
}

/// Reads the text of a states file (the error names the file).
pub fn read_states_text(path: &Path) -> Result<String> {
    std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read states file", path.display()))
}

/// The state layout of a command's inputs and outputs (`--layout`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum Layout {
    /// moma's: planar root `[x, y, θ]` with world-axes velocity, continuous joints as one
    /// angle.
    #[default]
    Moma,
    /// Pinocchio's: planar root `[x, y, cos θ, sin θ]` with base-frame velocity,
    /// continuous joints as `[cos θ, sin θ]` (see `moma::io::pinocchio_layout`).
    Pinocchio,
}

/// The conversions of one command run between `--layout` and moma's layout (the identity
/// for `--layout moma`).
pub struct LayoutConv {
    map: Option<moma::io::pinocchio_layout::PinocchioLayout>,
    nq: usize,
    nv: usize,
    planar: bool,
}

impl LayoutConv {
    /// The conversions for `model` in `layout`.
    pub fn new(model: &Model, layout: Layout) -> Self {
        Self {
            map: (layout == Layout::Pinocchio)
                .then(|| moma::io::pinocchio_layout::PinocchioLayout::new(model)),
            nq: model.nq,
            nv: model.nv,
            planar: model
                .joint_types
                .iter()
                .any(|j| matches!(j, moma::multibody::JointType::Planar)),
        }
    }

    /// True for `--layout pinocchio` on a model with a planar root (where velocities,
    /// forces and matrices change, not only q).
    pub fn moves_velocities(&self) -> bool {
        self.map.is_some() && self.planar
    }

    /// moma's q from a q in the command's layout; `field` names it in errors. A q of the
    /// wrong length is passed through for the command's own length check.
    pub fn q_in(&self, q: Vec<f64>, field: &str) -> Result<Vec<f64>> {
        match &self.map {
            None => Ok(q),
            Some(m) => {
                if q.len() != m.nq() {
                    bail!(
                        "{field}: expected length {} (nq in the Pinocchio layout), got {}",
                        m.nq(),
                        q.len()
                    );
                }
                let mut out = vec![0.0; self.nq];
                m.q_from_pinocchio(&q, &mut out)
                    .map_err(|e| anyhow!("{field}: {e}"))?;
                Ok(out)
            }
        }
    }

    /// moma's velocity (or generalised force) from one in the command's layout at moma's
    /// `q`; a vector of the wrong length is passed through for the command's length check.
    pub fn v_in(&self, q: &[f64], x: Vec<f64>) -> Vec<f64> {
        match &self.map {
            Some(m) if x.len() == self.nv && q.len() == self.nq => {
                let mut out = vec![0.0; self.nv];
                m.v_from_pinocchio(q, &x, &mut out);
                out
            }
            _ => x,
        }
    }

    /// moma's acceleration from one in the command's layout at moma's `q` and `v` (zero
    /// when not given).
    pub fn a_in(&self, q: &[f64], v: Option<&[f64]>, a: Vec<f64>) -> Vec<f64> {
        match &self.map {
            Some(m) if a.len() == self.nv && q.len() == self.nq => {
                let zero = vec![0.0; self.nv];
                let v = v.filter(|v| v.len() == self.nv).unwrap_or(&zero);
                let mut out = vec![0.0; self.nv];
                m.a_from_pinocchio(q, v, &a, &mut out);
                out
            }
            _ => a,
        }
    }

    /// Converts one states-file state (q, v, a, tau) into moma's layout; `field` names it.
    pub fn state_in(&self, st: &mut State, field: &str) -> Result<()> {
        if self.map.is_none() {
            return Ok(());
        }
        st.q = self.q_in(std::mem::take(&mut st.q), &format!("{field}.q"))?;
        let q = st.q.clone();
        st.v = st.v.take().map(|v| self.v_in(&q, v));
        st.a = st.a.take().map(|a| self.a_in(&q, st.v.as_deref(), a));
        st.tau = st.tau.take().map(|t| self.v_in(&q, t));
        Ok(())
    }

    /// A moma q in the command's layout.
    pub fn q_out(&self, q: &[f64]) -> Vec<f64> {
        match &self.map {
            None => q.to_vec(),
            Some(m) => {
                let mut out = vec![0.0; m.nq()];
                m.q_to_pinocchio(q, &mut out);
                out
            }
        }
    }

    /// A moma velocity or generalised force at moma's `q` in the command's layout.
    pub fn v_out(&self, q: &[f64], x: &[f64]) -> Vec<f64> {
        match &self.map {
            None => x.to_vec(),
            Some(m) => {
                let mut out = vec![0.0; self.nv];
                m.v_to_pinocchio(q, x, &mut out);
                out
            }
        }
    }

    /// A moma acceleration at moma's `(q, v)` in the command's layout.
    pub fn a_out(&self, q: &[f64], v: &[f64], a: &[f64]) -> Vec<f64> {
        match &self.map {
            None => a.to_vec(),
            Some(m) => {
                let mut out = vec![0.0; self.nv];
                m.a_to_pinocchio(q, v, a, &mut out);
                out
            }
        }
    }

    /// The acceleration (moma layout) that is zero in the command's layout at `(q, v)`:
    /// RNEA there gives the layout's bias forces.
    pub fn zero_acceleration(&self, q: &[f64], v: &[f64]) -> Vec<f64> {
        self.a_in(q, Some(v), vec![0.0; self.nv])
    }

    /// An nv × nv velocity-to-force matrix (the mass matrix) in the command's layout.
    pub fn matrix_out(&self, q: &[f64], h: &nalgebra::DMatrix<f64>) -> nalgebra::DMatrix<f64> {
        match &self.map {
            None => h.clone(),
            Some(m) => {
                let mut out = nalgebra::DMatrix::zeros(self.nv, self.nv);
                m.matrix_to_pinocchio(q, h, &mut out);
                out
            }
        }
    }

    /// RNEA's derivatives (∂τ/∂q, ∂τ/∂v, H, moma's layout, at moma's `(q, v, a)` with
    /// `tau` = RNEA there) turned, in place, into the command's layout.
    pub fn rnea_derivatives_out(
        &self,
        q: &[f64],
        v: &[f64],
        a: &[f64],
        tau: &[f64],
        m: &mut [nalgebra::DMatrix<f64>; 3],
    ) {
        if let Some(map) = &self.map {
            let [dq, dv, h] = m;
            map.rnea_derivatives_to_pinocchio(q, v, a, tau, dq, dv, h);
        }
    }

    /// ABA's derivatives (∂q̈/∂q, ∂q̈/∂v, H⁻¹, moma's layout, at moma's `(q, v, tau)` with
    /// `ddq` = ABA there) turned, in place, into the command's layout.
    pub fn aba_derivatives_out(
        &self,
        q: &[f64],
        v: &[f64],
        tau: &[f64],
        ddq: &[f64],
        m: &mut [nalgebra::DMatrix<f64>; 3],
    ) {
        if let Some(map) = &self.map {
            let [dq, dv, minv] = m;
            map.aba_derivatives_to_pinocchio(q, v, tau, ddq, dq, dv, minv);
        }
    }

    /// A frame's ∂V/∂q, ∂A/∂q, ∂A/∂v and Jacobian (moma's layout, at moma's `(q, v, a)`)
    /// turned, in place, into the command's layout.
    pub fn frame_derivatives_out(
        &self,
        q: &[f64],
        v: &[f64],
        a: &[f64],
        [vq, aq, av, jac]: [&mut nalgebra::Matrix6xX<f64>; 4],
    ) {
        if let Some(map) = &self.map {
            map.frame_acceleration_derivatives_to_pinocchio(q, v, a, vq, aq, av, jac);
        }
    }

    /// A Jacobian (any rows, nv columns) in the command's layout.
    pub fn jacobian_out(&self, q: &[f64], j: &nalgebra::DMatrix<f64>) -> nalgebra::DMatrix<f64> {
        match &self.map {
            None => j.clone(),
            Some(m) => {
                let mut out = nalgebra::DMatrix::zeros(j.nrows(), self.nv);
                m.jacobian_to_pinocchio(q, j, &mut out);
                out
            }
        }
    }
}

/// Parses a comma-separated list of finite numbers for option `field`.
pub fn parse_list(field: &str, text: &str) -> Result<Vec<f64>> {
    let mut out = Vec::new();
    for (i, part) in text.split(',').enumerate() {
        let p = part.trim();
        let x: f64 = p
            .parse()
            .map_err(|_| anyhow!("{field}: element {i} '{p}' is not a number"))?;
        if !x.is_finite() {
            bail!("{field}: element {i} is not finite");
        }
        out.push(x);
    }
    Ok(out)
}

/// The end-effector frame (by name, or the model's deepest link).
pub fn frame_of(model: &Arc<Model>, name: Option<&str>, path: &Path) -> Result<ModelFrame> {
    let frame = match name {
        Some(n) => model
            .frame_id(n)
            .map_err(|e| anyhow!("{}: --frame: {e}", path.display()))?,
        None => model.last_link_frame(),
    };
    Ok(ModelFrame::new(model.clone(), frame)?)
}

/// A frame name for output.
pub fn frame_name(kin: &ModelFrame) -> String {
    kin.model().frames[kin.frame().0].name.clone()
}

/// Parses `--base`.
pub fn parse_base(spec: &str) -> Result<DiffDrive> {
    if !spec.trim_start().starts_with("diff-drive") {
        bail!("--base: unknown platform '{spec}'; expected diff-drive:r_w=R,b=B,d=D");
    }
    spec.parse::<DiffDrive>()
        .map_err(|e| anyhow!("--base: {e}"))
}

/// Parses `--rows` (default: position for a 3-value target, full for a 7-value one) and
/// checks that orientation rows come with an orientation in the target `tvals`.
pub fn parse_task_rows(rows: Option<&str>, tvals: &[f64]) -> Result<TaskRows> {
    let rows: TaskRows = match rows {
        Some(r) => r.parse().map_err(|e| anyhow!("--rows: {e}"))?,
        None if tvals.len() == 3 => TaskRows::Position,
        None => TaskRows::Full,
    };
    if tvals.len() == 3 && rows.indices().iter().any(|&r| r >= 3) {
        bail!("--rows: orientation rows need a 7-value target x,y,z,qx,qy,qz,qw");
    }
    Ok(rows)
}

/// Largest number of IK iterations one solve may spend over all its attempts,
/// `(--restarts + 1) × --max-iters` (about a second of a 7-joint arm).
pub const MAX_IK_ITERATIONS: usize = 1_000_000;

/// Checks the IK budget options `--tol` (> 0), `--max-iters` (>= 1) and `--restarts`:
/// together at most [`MAX_IK_ITERATIONS`] iterations per solve, so an unreachable target
/// cannot keep the command restarting for ever.
pub fn check_ik_budget(tol: f64, max_iters: usize, restarts: usize) -> Result<()> {
    if !(tol.is_finite() && tol > 0.0) {
        bail!("--tol: must be > 0, got {tol}");
    }
    if max_iters == 0 {
        bail!("--max-iters: must be at least 1");
    }
    let total = restarts
        .checked_add(1)
        .and_then(|a| a.checked_mul(max_iters));
    if total.is_none_or(|t| t > MAX_IK_ITERATIONS) {
        bail!(
            "--restarts/--max-iters: ({restarts} + 1) attempts × {max_iters} iterations exceed \
             the budget of {MAX_IK_ITERATIONS} iterations per solve"
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(name: &str, text: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("moma-common-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn states_errors_name_the_file() {
        let p = write("bad.json", r#"{"states": [{"q": [1], "u": [2]}]}"#);
        let e = format!("{:#}", read_states(&p, &["q", "v"]).unwrap_err());
        assert!(e.contains("states[0].u: unknown field"), "{e}");
        assert!(e.contains(&p.display().to_string()), "{e}");
        let missing = p.with_file_name("absent.json");
        let e = format!("{:#}", read_states(&missing, &["q"]).unwrap_err());
        assert!(e.contains("cannot read states file"), "{e}");
    }

    #[test]
    fn ik_budget_is_bounded() {
        assert!(check_ik_budget(1e-6, 200, 10).is_ok());
        for (max_iters, restarts) in [(20, usize::MAX), (usize::MAX, 0), (1000, 1000)] {
            let e = check_ik_budget(1e-6, max_iters, restarts).unwrap_err();
            assert!(e.to_string().contains("--restarts/--max-iters"), "{e}");
        }
    }

    #[test]
    fn goal_not_reached_is_recognisable() {
        let e = goal_not_reached::<()>("stuck").unwrap_err();
        assert!(e.downcast_ref::<GoalNotReached>().is_some());
        assert_eq!(e.to_string(), "stuck");
    }
}

/// The robot description and where its collision geometry comes from: the arguments the
/// geometry commands share (`moma collision`, `moma motion`, `moma place`).
#[derive(clap::Args, Clone, Debug)]
pub struct RobotArgs {
    /// The robot description (URDF); its `<collision>` elements are the geometry (meshes
    /// as their convex hulls).
    pub urdf: std::path::PathBuf,
    /// SRDF whose `<disable_collisions>` pairs are not checked.
    #[arg(long)]
    pub srdf: Option<std::path::PathBuf>,
    /// Folder against which `package://PKG/...` mesh URIs resolve, as DIR/PKG/... (or
    /// DIR/... when DIR is named PKG); repeatable; ROS_PACKAGE_PATH is searched after.
    #[arg(long = "package-dir")]
    pub package_dirs: Vec<std::path::PathBuf>,
}

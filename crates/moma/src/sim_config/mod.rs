//! The `moma simulate` scenario file and what makes it runnable: the file's schema and
//! parser ([`schema`]: robot, initial state, inputs, integrator, output and limits), the
//! command's `[space]`, `[stability]`,
//! `[controller]` and `[reference]` tables ([`SpaceSpec`], [`StabilitySpec`],
//! [`ControllerSpec`], [`ReferenceSpec`]), their checks, and the builders that turn a
//! parsed [`Scenario`] into what a run needs: the robot ([`robot`]), the open-loop run
//! ([`OpenLoop`]), the closed loop ([`ClosedLoop`]: plant and feedback law), the
//! free-floating run ([`SpaceRun`]) and the stability monitor.
//!
//! The module stands above `sim` and `mission`: a `planned` reference is planned by
//! `mission::planned`, which `sim` may not import. The simulator (`sim`) reads no file:
//! it takes the settings of [`crate::sim::settings`], which this schema reads. The schema is in `docs/simulate.md`
//! and `docs/space.md`.
//!
//! Every error is an [`Error::Scenario`] whose message is the one the command prints:
//! the scenario file, the table and field at fault, and the causes joined by `": "`.

use std::path::Path;

use crate::error::{Error, Result};
use crate::sim::reduced_system::ReducedSystem;
use crate::sim::settings::InputProfile;
use crate::sim::stability_monitor::StabilityMonitor;
use crate::sim::wheeled::{
    MAX_RECORDED_SAMPLES, SampleObserver, SimulationOptions, SimulationResult, simulate_observed,
};

pub mod contact;
pub mod control;
pub mod mpc;
pub mod robot;
pub mod rolling_plant;
pub mod schema;
pub mod space;
pub mod stability;
pub mod uncertainty;

pub use control::{ClosedLoop, ControllerSpec, ReferenceSpec, TimingSpec, closed_loop};
pub use robot::{build_robot, build_wheeled_model, chapter_params_json, fixed_base_model};
pub use space::{CaptureSpec, ControlSpec, MomentumSpec, SpaceRun, SpaceSpec, space_run};
pub use stability::{StabilitySpec, monitor, replay, replay_scenario};

/// A `moma simulate` scenario: the schema of [`crate::sim_config::schema`] with this module's
/// tables.
pub type Scenario =
    crate::sim_config::schema::Scenario<SpaceSpec, StabilitySpec, ControllerSpec, ReferenceSpec>;

/// `return Err(Error::Scenario(format!(…)))`.
macro_rules! bail {
    ($($t:tt)*) => {
        return Err($crate::error::Error::Scenario(format!($($t)*)))
    };
}
pub(crate) use bail;

/// An [`Error::Scenario`] with a formatted message.
macro_rules! err {
    ($($t:tt)*) => {
        $crate::error::Error::Scenario(format!($($t)*))
    };
}
pub(crate) use err;

pub(crate) use crate::error::{at, chain};

/// Puts what was being done in front of an error: `"{what}: {error and its causes}"`.
pub(crate) trait Context<T> {
    /// With a fixed context.
    fn ctx(self, what: &str) -> Result<T>;
    /// With a context built only on failure.
    fn with_ctx(self, what: impl FnOnce() -> String) -> Result<T>;
}

impl<T, E: std::error::Error> Context<T> for std::result::Result<T, E> {
    fn ctx(self, what: &str) -> Result<T> {
        self.map_err(|e| err!("{what}: {}", chain(&e)))
    }
    fn with_ctx(self, what: impl FnOnce() -> String) -> Result<T> {
        self.map_err(|e| err!("{}: {}", what(), chain(&e)))
    }
}

/// `Err` naming `field[i]` unless every value is finite.
pub(crate) fn finite(field: &str, xs: &[f64]) -> Result<()> {
    if let Some(i) = crate::error::first_non_finite(xs) {
        bail!("{field}[{i}] is not a finite number");
    }
    Ok(())
}

/// Reads and parses a scenario file; errors name the file and the line or field.
///
/// # Errors
/// [`Error::Scenario`] when the file cannot be read or does not parse.
pub fn load(path: &Path) -> Result<Scenario> {
    let text = std::fs::read_to_string(path)
        .with_ctx(|| format!("{}: cannot read scenario file", path.display()))?;
    crate::sim_config::schema::parse_scenario(&text, path).ctx_plain()
}

/// Turns any error into an [`Error::Scenario`] with the same message (causes included).
trait Plain<T> {
    fn ctx_plain(self) -> Result<T>;
}

impl<T> Plain<T> for Result<T> {
    fn ctx_plain(self) -> Result<T> {
        self.map_err(|e| match e {
            Error::Scenario(m) => Error::Scenario(m),
            e => Error::Scenario(chain(&e)),
        })
    }
}

/// An open-loop (input-profile) run of a wheeled, chapter or fixed-base robot.
pub struct OpenLoop {
    /// The plant.
    pub system: Box<dyn ReducedSystem>,
    /// How the summary names the robot (`chapter model m2`, `URDF robots/x.urdf`, …).
    pub robot_name: String,
    /// The `[stability]` monitor (a URDF robot on a wheeled base), observing every sample.
    pub monitor: Option<StabilityMonitor>,
    /// Initial configuration.
    pub q0: Vec<f64>,
    /// Initial reduced velocity.
    pub v0: Vec<f64>,
    /// The input profile.
    pub input: InputProfile,
    /// Duration, integrator, recording interval and limits.
    pub options: SimulationOptions,
}

impl OpenLoop {
    /// Runs the input profile from the initial state, the `[stability]` monitor (if any)
    /// observing every recorded sample; `progress` gets the simulated time as it advances.
    ///
    /// # Errors
    /// As [`simulate_observed`].
    pub fn run(&mut self, progress: &mut dyn FnMut(f64)) -> Result<SimulationResult> {
        let observer = self.monitor.as_mut().map(|m| m as &mut dyn SampleObserver);
        simulate_observed(
            self.system.as_mut(),
            &self.input,
            &self.q0,
            &self.v0,
            &self.options,
            progress,
            observer,
        )
    }
}

/// What a scenario runs: chosen by its robot and tables.
pub enum Run {
    /// Input profiles on a wheeled, chapter or fixed-base robot.
    Open(Box<OpenLoop>),
    /// A `[controller]` and its `[reference]`.
    Closed(Box<ClosedLoop>),
    /// A free-floating robot.
    Space(Box<SpaceRun>),
}

/// Both run kinds that take `[uncertainty]` refuse it without a `[controller]`.
pub(crate) const UNCERTAINTY_NEEDS_CONTROLLER: &str = "[uncertainty] perturbs the plant under a \
     [controller] (the controller keeps the nominal model): add a [controller] or remove \
     [uncertainty]";

const STABILITY_NEEDS_URDF: &str =
    "[stability] needs a URDF robot on a wheeled base (robot.kind = \"urdf\")";

/// Checks the scenario's tables against each other and builds its run; `path` is the
/// scenario file (named in every error; relative robot, map and URDF paths are resolved
/// from its directory). [`Scenario::check_header`] is the caller's first step.
///
/// # Errors
/// [`Error::Scenario`] naming the file and the field at fault.
pub fn prepare(sc: &Scenario, path: &Path) -> Result<Run> {
    contact::check_rolling(sc.plant, sc.contact.is_some()).with_ctx(|| at(path, "plant"))?;
    let base_dir = path.parent().unwrap_or(Path::new("."));
    let (duration, interval) = (sc.duration, sc.output.record_interval);
    let samples = (duration / interval).ceil();
    if interval > 0.0 && samples > MAX_RECORDED_SAMPLES {
        bail!(
            "{}",
            at(
                path,
                &format!(
                    "duration = {duration:e} s at output.record_interval = {interval} s \
                     records {samples:e} samples, more than {MAX_RECORDED_SAMPLES:e}: \
                     shorten duration or raise output.record_interval"
                )
            )
        );
    }
    if sc.controller.is_some() || sc.reference.is_some() {
        if sc.stability.as_ref().is_some_and(|s| s.stop_at_tip) {
            bail!(
                "{}",
                at(
                    path,
                    "stability.stop_at_tip is not available in closed-loop runs (their samples are evaluated after the run): remove it"
                )
            );
        }
        if sc.stability.is_some()
            && !matches!(sc.robot, crate::sim_config::schema::RobotSpec::Urdf { .. })
        {
            bail!("{}", at(path, STABILITY_NEEDS_URDF));
        }
        let cl = closed_loop(sc, path, base_dir)?;
        return Ok(Run::Closed(Box::new(match &sc.uncertainty {
            Some(spec) => rolling_plant::apply_to_rolling(spec, cl, sc, path)?,
            None => cl,
        })));
    }
    if sc.uncertainty.is_some() {
        bail!("{}", at(path, UNCERTAINTY_NEEDS_CONTROLLER));
    }
    if let crate::sim_config::schema::RobotSpec::FreeFloating { urdf, frame } = &sc.robot {
        if sc.stability.is_some() {
            bail!("{}", at(path, STABILITY_NEEDS_URDF));
        }
        return Ok(Run::Space(Box::new(space_run(
            sc, path, base_dir, urdf, frame,
        )?)));
    }
    Ok(Run::Open(Box::new(open_loop(sc, path, base_dir)?)))
}

/// The open-loop run of a scenario without `[controller]` on a robot that is not free
/// floating; `base_dir` resolves relative URDF paths.
///
/// # Errors
/// [`Error::Scenario`] naming the file and the field at fault.
pub fn open_loop(sc: &Scenario, path: &Path, base_dir: &Path) -> Result<OpenLoop> {
    use crate::sim_config::schema::RobotSpec;
    if sc.space.is_some() {
        bail!(
            "{}",
            at(path, "[space] is only for robot.kind = \"free_floating\"")
        );
    }
    let (system, robot_name) =
        build_robot(&sc.robot, sc.gravity, base_dir).with_ctx(|| at(path, "robot"))?;
    let monitor = match (&sc.stability, &sc.robot) {
        (None, _) => None,
        (
            Some(spec),
            RobotSpec::Urdf {
                urdf,
                drive,
                wheel_joints,
                casters,
            },
        ) => {
            let wm = build_wheeled_model(
                &base_dir.join(urdf),
                drive,
                wheel_joints.clone(),
                casters,
                sc.gravity,
            )
            .with_ctx(|| at(path, "robot"))?;
            Some(monitor(spec, &wm).with_ctx(|| at(path, "stability"))?)
        }
        (Some(_), _) => bail!("{}", at(path, STABILITY_NEEDS_URDF)),
    };
    let (q0, v0, input) = initial_state(sc, system.as_ref(), path)?;
    sc.integrator
        .validate()
        .with_ctx(|| at(path, "integrator"))?;
    let options = SimulationOptions {
        duration: sc.duration,
        integrator: sc.integrator,
        record_interval: sc.output.record_interval,
        limits: sc.limits.unwrap_or_default(),
    };
    Ok(OpenLoop {
        system,
        robot_name,
        monitor,
        q0,
        v0,
        input,
        options,
    })
}

/// The initial configuration, reduced velocity and input profile of a scenario, checked
/// against the system's sizes (errors name the file, the field and the expected channels).
///
/// # Errors
/// [`Error::Scenario`] naming the file and the field at fault.
pub fn initial_state(
    sc: &Scenario,
    system: &dyn ReducedSystem,
    path: &Path,
) -> Result<(Vec<f64>, Vec<f64>, InputProfile)> {
    sc.initial_state(system, Path::new(""))
        .map_err(|e| match e {
            Error::Parse { message, .. } => err!("{}", at(path, &message)),
            e => Error::Scenario(chain(&e)),
        })
}

/// The wheel joints a scenario's URDF robot tracks (empty otherwise).
pub fn wheel_joints(sc: &Scenario) -> Vec<String> {
    match &sc.robot {
        crate::sim_config::schema::RobotSpec::Urdf {
            wheel_joints: Some(w),
            ..
        } => w.to_vec(),
        _ => Vec::new(),
    }
}

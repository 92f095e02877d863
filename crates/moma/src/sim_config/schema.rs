//! The `moma simulate` scenario file: its serde schema ([`Scenario`] with the robot,
//! initial-state, input, integrator, output and limit tables), its parser
//! ([`parse_scenario`]) and the checks that need no robot model ([`Scenario::check_header`])
//! or only the system's sizes ([`Scenario::initial_state`]).

use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::contact::{ContactSpec, PlantKind};
use crate::error::{Error, Result};
/// `robot.drive`: the mission file's table, the same `{ r_w, b, d }`.
pub use crate::mission::scenario::DriveSpec;
use crate::sim::monitor::MonitorLimits;
use crate::sim::reduced_system::ReducedSystem;
use crate::sim::settings::{ChannelProfile, InputProfile, IntegratorSettings};

// ---- the whole scenario file -------------------------------------------------------

/// A `moma simulate` scenario file (schema in `docs/simulate.md`).
///
/// The `[space]`, `[stability]`, `[controller]` and `[reference]` tables are read by the
/// command that runs them, so their types are parameters; they default to any TOML table
/// (the shape is then checked only by the command).
#[derive(Debug, Deserialize)]
#[serde(
    deny_unknown_fields,
    bound(deserialize = "Space: Deserialize<'de>, Stability: Deserialize<'de>, \
                       Controller: Deserialize<'de>, Reference: Deserialize<'de>")
)]
pub struct Scenario<
    Space = toml::Table,
    Stability = toml::Table,
    Controller = toml::Table,
    Reference = toml::Table,
> {
    /// Free-text name, copied into the summary.
    #[serde(default)]
    pub name: Option<String>,
    /// Simulated time (s).
    pub duration: f64,
    /// Gravity magnitude g (m/s², acting along −z). For URDF robots it sets the model's
    /// gravity (default 9.81); for m5 it sets `params.g` if that is absent.
    #[serde(default)]
    pub gravity: Option<f64>,
    /// The robot.
    pub robot: RobotSpec,
    /// The plant a wheeled URDF robot runs on: `rolling` (the reduced model, default) or
    /// `contact` (the contact plant, with the `[contact]` table).
    #[serde(default)]
    pub plant: PlantKind,
    /// The contact plant's parameters and casters (`plant = "contact"`).
    #[serde(default)]
    pub contact: Option<ContactSpec>,
    /// Initial state.
    #[serde(default)]
    pub initial: InitialState,
    /// One profile per input channel (default: all zero).
    #[serde(default)]
    pub inputs: Option<Vec<ChannelProfile>>,
    /// Integrator.
    pub integrator: IntegratorSettings,
    /// Outputs.
    #[serde(default)]
    pub output: OutputSpec,
    /// Monitor limits.
    #[serde(default)]
    pub limits: Option<MonitorLimits>,
    /// Free-floating settings (robot kind `free_floating`; schema in docs/space.md).
    #[serde(default)]
    pub space: Option<Space>,
    /// Tip-over stability, wheel loads and slip (URDF robots; docs/simulate.md).
    #[serde(default)]
    pub stability: Option<Stability>,
    /// Closed-loop control: the law and its gains (schema in docs/simulate.md).
    #[serde(default)]
    pub controller: Option<Controller>,
    /// What the closed-loop law tracks or stabilises to.
    #[serde(default)]
    pub reference: Option<Reference>,
    /// How the plant differs from the controller's model, and the measurement noise
    /// (closed loop on a wheeled URDF robot; docs/simulate.md).
    #[serde(default)]
    pub uncertainty: Option<crate::sim::uncertainty::UncertaintySpec>,
}

/// The robot of a scenario.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum RobotSpec {
    /// A URDF model on a differential-drive base.
    Urdf {
        /// URDF file, relative to the scenario file.
        urdf: PathBuf,
        /// Differential drive: `{ r_w, b, d }`.
        drive: DriveSpec,
        /// Names of the `[left, right]` wheel joints to track (optional).
        #[serde(default)]
        wheel_joints: Option<[String; 2]>,
        /// Passive casters (optional).
        #[serde(default)]
        casters: Vec<crate::mobile::Caster>,
    },
    /// A URDF arm with a fixed base (every joint actuated).
    FixedBase {
        /// URDF file, relative to the scenario file.
        urdf: PathBuf,
    },
    /// A URDF model as a free-floating (space) robot in zero gravity.
    FreeFloating {
        /// URDF file, relative to the scenario file.
        urdf: PathBuf,
        /// Frame recorded, controlled and used for a capture.
        frame: String,
    },
    /// One of the chapter's closed-form models.
    Chapter {
        /// `m1`, `m2` or `m5` (or a canonical name such as `m1_unicycle`; the names of
        /// `moma eval`).
        model: String,
        /// Its parameters (names as in docs/simulate.md).
        params: toml::Table,
    },
}

/// Initial configuration and reduced velocity (default: zeros).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct InitialState {
    /// Configuration q.
    #[serde(default)]
    pub q: Option<Vec<f64>>,
    /// Reduced velocity v.
    #[serde(default)]
    pub v: Option<Vec<f64>>,
}

/// Output settings.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Output directory (relative to the current directory).
    #[serde(default = "default_dir")]
    pub dir: PathBuf,
    /// Recording interval (s).
    #[serde(default = "default_interval")]
    pub record_interval: f64,
    /// Write the SVG plots.
    #[serde(default = "default_true")]
    pub plots: bool,
}

fn default_dir() -> PathBuf {
    PathBuf::from("simulation-output")
}
fn default_interval() -> f64 {
    0.01
}
fn default_true() -> bool {
    true
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self {
            dir: default_dir(),
            record_interval: default_interval(),
            plots: true,
        }
    }
}

/// Parses the text of a scenario file; `path` names it in errors.
///
/// # Errors
/// [`Error::Parse`] naming the file, the line and column and the key (toml's message) for
/// malformed TOML, an unknown or missing key or a value of the wrong type.
pub fn parse_scenario<S, T, C, R>(text: &str, path: &Path) -> Result<Scenario<S, T, C, R>>
where
    Scenario<S, T, C, R>: serde::de::DeserializeOwned,
{
    toml::from_str(text).map_err(|e| Error::parse(path, e.to_string().trim_end()))
}

/// `xs[i]` of `field` is not finite: the message `"{field}[{i}] is not a finite number"`.
fn first_non_finite(field: &str, xs: &[f64]) -> Option<String> {
    xs.iter()
        .position(|x| !x.is_finite())
        .map(|i| format!("{field}[{i}] is not a finite number"))
}

impl<S, T, C, R> Scenario<S, T, C, R> {
    /// Checks the top-level numbers: a positive finite `duration` and a finite `gravity`.
    ///
    /// # Errors
    /// [`Error::Parse`] for `path`, naming the field.
    pub fn check_header(&self, path: &Path) -> Result<()> {
        if !(self.duration.is_finite() && self.duration > 0.0) {
            return Err(Error::parse(
                path,
                format!(
                    "duration must be a positive finite number, got {}",
                    self.duration
                ),
            ));
        }
        if let Some(g) = self.gravity
            && !g.is_finite()
        {
            return Err(Error::parse(path, "gravity is not a finite number"));
        }
        Ok(())
    }

    /// The initial configuration, reduced velocity and input profile, checked against the
    /// system's sizes: `initial.q` (default zeros) must have `nq` finite values and
    /// `initial.v` `nv`, both within the blow-up bound `limits.blowup`; `[[inputs]]`
    /// (default all zero) one valid channel per input.
    ///
    /// # Errors
    /// [`Error::Parse`] for `path`, naming the field (and the expected names for a wrong
    /// count).
    pub fn initial_state(
        &self,
        system: &dyn ReducedSystem,
        path: &Path,
    ) -> Result<(Vec<f64>, Vec<f64>, InputProfile)> {
        let (nq, nv, nu) = (system.nq(), system.nv(), system.nu());
        let err = |m: String| Error::parse(path, m);
        let q0 = self.initial.q.clone().unwrap_or_else(|| vec![0.0; nq]);
        let v0 = self.initial.v.clone().unwrap_or_else(|| vec![0.0; nv]);
        if q0.len() != nq {
            return Err(err(format!(
                "initial.q: expected {nq} values ({}), got {}",
                system.q_names().join(", "),
                q0.len()
            )));
        }
        if v0.len() != nv {
            return Err(err(format!(
                "initial.v: expected {nv} values ({}), got {}",
                system.v_names().join(", "),
                v0.len()
            )));
        }
        for (name, xs) in [("initial.q", &q0), ("initial.v", &v0)] {
            if let Some(m) = first_non_finite(name, xs) {
                return Err(err(format!("initial state: {m}")));
            }
        }
        let blowup = self.limits.unwrap_or_default().blowup;
        for (name, xs) in [("initial.q", &q0), ("initial.v", &v0)] {
            if let Some(i) = xs.iter().position(|x| x.abs() > blowup) {
                return Err(err(format!(
                    "{name}[{i}] = {:e} exceeds the blow-up bound limits.blowup = {blowup:e}",
                    xs[i]
                )));
            }
        }
        let input = match &self.inputs {
            None => InputProfile::zero(nu),
            Some(ch) => {
                if ch.len() != nu {
                    return Err(err(format!(
                        "inputs: expected {nu} channels ({}), got {}",
                        system.u_names().join(", "),
                        ch.len()
                    )));
                }
                for (i, c) in ch.iter().enumerate() {
                    c.validate(&format!("inputs[{i}]"))
                        .map_err(|e| err(format!("inputs: {e}")))?;
                }
                InputProfile {
                    channels: ch.clone(),
                }
            }
        };
        Ok((q0, v0, input))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The schema and its checks on the shipped m1 scenario and on edits of it: every
    /// error names the file and the field, as `moma simulate` prints it.
    #[test]
    fn scenario_file_parses_and_checks() {
        let text = include_str!("../../../../scenarios/m1_unicycle.toml");
        let path = Path::new("m1.toml");
        let sc: Scenario = parse_scenario(text, path).unwrap();
        sc.check_header(path).unwrap();
        assert!(matches!(&sc.robot, RobotSpec::Chapter { model, .. } if model == "m1"));
        let RobotSpec::Chapter { params, .. } = &sc.robot else {
            unreachable!()
        };
        let json = serde_json::to_value(params).unwrap();
        let sys = crate::sim::chapter_models::chapter_system("m1", &json).unwrap();
        let (q, v, u) = sc.initial_state(sys.as_ref(), path).unwrap();
        assert_eq!((q.len(), v.len(), u.channels.len()), (3, 2, 2));
        assert_eq!(sc.output.record_interval, 0.01);

        let msg = |t: &str| match parse_scenario::<toml::Table, toml::Table, toml::Table, toml::Table>(
            t, path,
        ) {
            Ok(_) => String::new(),
            Err(e) => e.to_string(),
        };
        let e = msg(&text.replace("duration = 3.0", "duration = 3.0\nspeed = 1"));
        assert!(
            e.starts_with("m1.toml: ") && e.contains("unknown field `speed`"),
            "{e}"
        );
        let e = msg(&text.replace("kind = \"chapter\"", "kind = \"wheelbarrow\""));
        assert!(e.contains("wheelbarrow"), "{e}");

        let bad = |from: &str, to: &str| {
            let sc: Scenario = parse_scenario(&text.replace(from, to), path).unwrap();
            match sc.check_header(path) {
                Err(e) => e.to_string(),
                Ok(()) => match sc.initial_state(sys.as_ref(), path) {
                    Err(e) => e.to_string(),
                    Ok(_) => String::new(),
                },
            }
        };
        assert_eq!(
            bad("duration = 3.0", "duration = -1.0"),
            "m1.toml: duration must be a positive finite number, got -1"
        );
        assert_eq!(
            bad("duration = 3.0", "duration = 3.0\ngravity = nan"),
            "m1.toml: gravity is not a finite number"
        );
        assert_eq!(
            bad("v = [-0.959265, -0.368072]", "v = [1.0]"),
            "m1.toml: initial.v: expected 2 values (v_F, v_T), got 1"
        );
        assert_eq!(
            bad("v = [-0.959265, -0.368072]", "v = [1.0, inf]"),
            "m1.toml: initial state: initial.v[1] is not a finite number"
        );
        assert!(
            bad("q = [0.520404,", "q = [1e300,")
                .contains("initial.q[0] = 1e300 exceeds the blow-up bound"),
        );
        assert!(bad("value = 0.8", "value = nan").starts_with("m1.toml: inputs: "));
    }
}

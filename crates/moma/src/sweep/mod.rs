//! Parameter sweeps: a grid or a seeded random sample over the parameters of a study,
//! evaluated point by point on all cores, into one results table.
//!
//! A sweep file (TOML, schema in `docs/sweep.md`) names a study, its fixed set-up, the
//! sampling, and the parameters:
//!
//! ```toml
//! study = "stability"            # stability | placement | mission | uncertainty | lift_off
//! [sample]
//! mode = "grid"                  # grid (cartesian product) | random (count, seed)
//! [parameters]
//! accel = { linspace = [-2.0, 2.0, 5] }
//! payload = [0.0, 1.5, 3.0]
//! [stability]
//! robot = "robot.urdf"           # relative to the sweep file
//! base = { r_w = 0.1, b = 0.2, d = 0.0, casters = [[0.2, 0.0]] }
//! ```
//!
//! # Points and indices
//!
//! Points are numbered `0 .. len()`. On a grid the last parameter varies fastest
//! (row-major order of the listed parameters). A random sample draws point `i` from a
//! ChaCha8 generator seeded with `seed` on stream `i`, so each point depends only on the
//! seed and its index: any subset of indices, on any number of threads or shards, gives
//! the same rows. A `linspace = [lo, hi, n]` parameter takes `n` equally spaced values on
//! a grid and a uniform draw in `[lo, hi]` in a random sample; a list of values is taken
//! as it is on a grid and drawn uniformly in a random sample.
//!
//! # Shards
//!
//! Shard `K` of `N` (`1 ≤ K ≤ N`) holds the indices `i` with `i mod N = K − 1`
//! ([`shard_indices`]): round-robin, so neighbouring (similarly costly) points spread
//! over the shards, and a missing shard always leaves a hole that [`merge`] detects.
//!
//! # Tables
//!
//! A [`Table`] has the columns `index`, every parameter (in file order), every result of
//! the study, and the timing columns (named `*_time_s`) last. Values are written with
//! Rust's shortest round-trip formatting, so the result columns are byte-identical
//! whatever the thread count, the shard count or the machine's load.
//!
//! # How it runs
//!
//! A [`Sweep`] is a validated sweep file: a study (stability or placement, each holding
//! its loaded robot and set-up immutably; mission, holding the parsed mission file that
//! each point modifies, re-validates and runs; uncertainty, holding its scenario's text;
//! lift-off, holding its contact plant and base posture, each point a `sim::lift_off`
//! search), the parameters in file order and the sampling. [`Sweep::run`] evaluates a list of indices on a rayon pool with one study
//! workspace per worker (the stability study's workspace holds its own copy of the model,
//! whose payload body inertia it sets per point); a [`Table`] keeps typed cells
//! ([`Value`]); [`merge`] joins shard tables.

mod lift_off;
mod mission;
mod placement;
mod stability;
mod table;
mod uncertainty;

pub use table::{Table, Value, merge};
pub use uncertainty::{SeedSummary, summarize};

use std::path::{Path, PathBuf};
use std::time::Instant;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use serde::Deserialize;

use crate::error::{Error, Result};

/// Largest number of points a sweep may define (grid product or random count).
pub const MAX_POINTS: u64 = 1_000_000_000;
/// Largest number of points one run (one call of [`Sweep::run`], one shard) evaluates;
/// larger sweeps are split into shards.
pub const MAX_RUN_POINTS: usize = 10_000_000;
/// Largest number of values one parameter may list or space.
pub const MAX_VALUES: usize = 1_000_000;
/// Largest sweep file read.
const MAX_FILE_BYTES: u64 = 64 << 20;

/// One parameter's values as given in the file.
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    /// `n` equally spaced values from `lo` to `hi` (a uniform draw in a random sample).
    Linspace {
        /// First value.
        lo: f64,
        /// Last value.
        hi: f64,
        /// Number of values (≥ 1; 1 gives `lo`).
        n: usize,
    },
    /// Listed values (numbers or names).
    List(Vec<Value>),
}

impl Values {
    /// Number of grid values.
    #[must_use]
    pub fn len(&self) -> usize {
        match self {
            Values::Linspace { n, .. } => *n,
            Values::List(v) => v.len(),
        }
    }

    /// True if there is no value (never, once validated).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The `k`-th grid value.
    fn grid(&self, k: usize) -> Value {
        match self {
            Values::Linspace { lo, hi, n } => {
                if *n == 1 {
                    Value::Float(*lo)
                } else if k + 1 == *n {
                    Value::Float(*hi)
                } else {
                    Value::Float(lo + (hi - lo) * (k as f64) / ((n - 1) as f64))
                }
            }
            Values::List(v) => v[k].clone(),
        }
    }

    /// A random draw.
    fn draw(&self, rng: &mut ChaCha8Rng) -> Value {
        match self {
            Values::Linspace { lo, hi, .. } => {
                let u: f64 = rng.random();
                Value::Float(lo + (hi - lo) * u)
            }
            Values::List(v) => v[rng.random_range(0..v.len())].clone(),
        }
    }
}

/// A named parameter of a sweep.
#[derive(Clone, Debug, PartialEq)]
pub struct Parameter {
    /// The column name (and the study's parameter name).
    pub name: String,
    /// Its values.
    pub values: Values,
}

/// How the points are chosen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampling {
    /// The cartesian product of the parameters' values.
    Grid,
    /// `count` points drawn with generator seed `seed`.
    Random {
        /// Number of points.
        count: u64,
        /// Generator seed.
        seed: u64,
    },
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct FileSpec {
    study: String,
    #[serde(default)]
    sample: SampleSpec,
    /// Keys with their spans, to keep the file order.
    #[serde(default)]
    parameters: std::collections::BTreeMap<toml::Spanned<String>, toml::Value>,
    stability: Option<toml::Value>,
    placement: Option<toml::Value>,
    mission: Option<toml::Value>,
    uncertainty: Option<toml::Value>,
    lift_off: Option<toml::Value>,
}

#[derive(Deserialize, Default)]
#[serde(deny_unknown_fields)]
struct SampleSpec {
    mode: Option<String>,
    count: Option<u64>,
    seed: Option<u64>,
}

/// The prepared study.
enum Study {
    Stability(Box<stability::StabilityStudy>),
    Placement(placement::PlacementStudy),
    Mission(Box<mission::MissionStudy>),
    Uncertainty(Box<uncertainty::UncertaintyStudy>),
    LiftOff(Box<lift_off::LiftOffStudy>),
}

/// Per-worker workspace of a study.
enum Workspace {
    Stability(Box<stability::Workspace>),
    Placement(Box<placement::Workspace>),
    Mission(mission::Workspace),
    Uncertainty(uncertainty::Workspace),
    LiftOff(lift_off::Workspace),
}

/// A loaded, validated sweep: the study with its robot, the parameters and the sampling.
pub struct Sweep {
    source: PathBuf,
    study_name: String,
    parameters: Vec<Parameter>,
    sampling: Sampling,
    len: u64,
    study: Study,
}

impl std::fmt::Debug for Sweep {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Sweep")
            .field("source", &self.source)
            .field("study", &self.study_name)
            .field("parameters", &self.parameters)
            .field("sampling", &self.sampling)
            .field("len", &self.len)
            .finish_non_exhaustive()
    }
}

/// A study's table (`[mission]`, `[stability]`, …) of sweep file `path` as its schema
/// `T`; errors name the file and the table.
pub(crate) fn study_section<T: serde::de::DeserializeOwned>(
    path: &Path,
    table: &str,
    section: toml::Value,
) -> Result<T> {
    section
        .try_into()
        .map_err(|e: toml::de::Error| file_error(path, table, e.message()))
}

/// The error for `field` of sweep file `path`.
pub(crate) fn file_error(path: &Path, field: &str, message: impl std::fmt::Display) -> Error {
    Error::parse(path, format!("{field}: {message}"))
}

fn parse_values(path: &Path, name: &str, v: &toml::Value) -> Result<Values> {
    let field = format!("parameters.{name}");
    match v {
        toml::Value::Array(a) => parse_list(path, a, &field),
        toml::Value::Table(t) => {
            if let Some(k) = t.keys().find(|k| *k != "linspace" && *k != "values") {
                return Err(file_error(
                    path,
                    &format!("{field}.{k}"),
                    "unknown key (expected linspace = [lo, hi, n] or values = [...])",
                ));
            }
            match (t.get("linspace"), t.get("values")) {
                (Some(l), None) => parse_linspace(path, l, &format!("{field}.linspace")),
                (None, Some(toml::Value::Array(a))) => {
                    parse_list(path, a, &format!("{field}.values"))
                }
                (None, Some(_)) => Err(file_error(
                    path,
                    &format!("{field}.values"),
                    "expected an array",
                )),
                _ => Err(file_error(
                    path,
                    &field,
                    "give exactly one of linspace = [lo, hi, n] and values = [...]",
                )),
            }
        }
        other => {
            let one = parse_scalar(path, other, field.clone())?;
            Ok(Values::List(vec![one]))
        }
    }
}

/// One listed value (field `at`): a finite number, a name or a boolean.
fn parse_scalar(path: &Path, x: &toml::Value, at: String) -> Result<Value> {
    match x {
        toml::Value::Float(f) if f.is_finite() => Ok(Value::Float(*f)),
        toml::Value::Float(_) => Err(file_error(path, &at, "must be finite")),
        toml::Value::Integer(i) => Ok(Value::Float(*i as f64)),
        toml::Value::String(s) => Ok(Value::Text(s.clone())),
        toml::Value::Boolean(b) => Ok(Value::Bool(*b)),
        other => Err(file_error(
            path,
            &at,
            format!("expected a number or a name, got {}", other.type_str()),
        )),
    }
}

/// A list of 1 to [`MAX_VALUES`] values (field `at`).
fn parse_list(path: &Path, a: &[toml::Value], at: &str) -> Result<Values> {
    if a.is_empty() {
        return Err(file_error(path, at, "needs at least one value"));
    }
    if a.len() > MAX_VALUES {
        return Err(file_error(
            path,
            at,
            format!("more than {MAX_VALUES} values"),
        ));
    }
    let vals = a
        .iter()
        .enumerate()
        .map(|(k, x)| parse_scalar(path, x, format!("{at}[{k}]")))
        .collect::<Result<Vec<_>>>()?;
    Ok(Values::List(vals))
}

/// `linspace = [lo, hi, n]` (field `at`): finite `lo <= hi`, `n` from 1 to [`MAX_VALUES`].
fn parse_linspace(path: &Path, l: &toml::Value, at: &str) -> Result<Values> {
    let a = l
        .as_array()
        .filter(|a| a.len() == 3)
        .ok_or_else(|| file_error(path, at, "expected [lo, hi, n]"))?;
    let num = |x: &toml::Value, what: &str| -> Result<f64> {
        let f = x
            .as_float()
            .or_else(|| x.as_integer().map(|i| i as f64))
            .ok_or_else(|| file_error(path, at, format!("{what} must be a number")))?;
        if f.is_finite() {
            Ok(f)
        } else {
            Err(file_error(path, at, format!("{what} must be finite")))
        }
    };
    let (lo, hi) = (num(&a[0], "lo")?, num(&a[1], "hi")?);
    let n = a[2]
        .as_integer()
        .filter(|&n| n >= 1 && n as u64 <= MAX_VALUES as u64)
        .ok_or_else(|| {
            file_error(
                path,
                at,
                format!("n must be an integer from 1 to {MAX_VALUES}"),
            )
        })? as usize;
    if hi < lo {
        return Err(file_error(
            path,
            at,
            format!("needs lo <= hi, got {lo} > {hi}"),
        ));
    }
    Ok(Values::Linspace { lo, hi, n })
}

/// The `[sample]` table: a grid (no count or seed), or a random sample with both.
fn parse_sampling(path: &Path, sample: &SampleSpec) -> Result<Sampling> {
    match sample.mode.as_deref().unwrap_or("grid") {
        "grid" => {
            if sample.count.is_some() || sample.seed.is_some() {
                return Err(file_error(
                    path,
                    "sample",
                    "count and seed belong to mode = \"random\"",
                ));
            }
            Ok(Sampling::Grid)
        }
        "random" => {
            let count = sample.count.ok_or_else(|| {
                file_error(path, "sample.count", "mode = \"random\" needs a count")
            })?;
            let seed = sample
                .seed
                .ok_or_else(|| file_error(path, "sample.seed", "mode = \"random\" needs a seed"))?;
            Ok(Sampling::Random { count, seed })
        }
        other => Err(file_error(
            path,
            "sample.mode",
            format!("unknown mode '{other}' (expected grid or random)"),
        )),
    }
}

/// The number of points, from 1 to [`MAX_POINTS`]: the grid's product of value counts
/// or the random count.
fn point_count(path: &Path, sampling: Sampling, parameters: &[Parameter]) -> Result<u64> {
    let len = match sampling {
        Sampling::Grid => parameters.iter().try_fold(1u64, |acc, p| {
            acc.checked_mul(p.values.len() as u64)
                .filter(|&n| n <= MAX_POINTS)
        }),
        Sampling::Random { count, .. } => Some(count).filter(|&n| n <= MAX_POINTS),
    }
    .ok_or_else(|| {
        file_error(
            path,
            if sampling == Sampling::Grid {
                "parameters"
            } else {
                "sample.count"
            },
            format!("more than {MAX_POINTS} points"),
        )
    })?;
    if len == 0 {
        return Err(file_error(path, "sample.count", "must be at least 1"));
    }
    Ok(len)
}

/// Prepares the study the file names from its own section; a section of another study
/// is an error.
fn prepare_study(
    path: &Path,
    dir: &Path,
    spec: &FileSpec,
    parameters: &[Parameter],
    files: &dyn crate::mission::scenario::Loader,
) -> Result<Study> {
    let section = |name: &str, v: &Option<toml::Value>| -> Result<toml::Value> {
        v.clone().ok_or_else(|| {
            file_error(
                path,
                name,
                format!("study = \"{name}\" needs a [{name}] section"),
            )
        })
    };
    let other_sections = [
        ("stability", &spec.stability),
        ("placement", &spec.placement),
        ("mission", &spec.mission),
        ("uncertainty", &spec.uncertainty),
        ("lift_off", &spec.lift_off),
    ];
    for (name, v) in other_sections {
        if v.is_some() && name != spec.study {
            return Err(file_error(
                path,
                name,
                format!(
                    "section [{name}] does not belong to study = \"{}\"",
                    spec.study
                ),
            ));
        }
    }
    Ok(match spec.study.as_str() {
        "stability" => Study::Stability(Box::new(stability::StabilityStudy::new(
            path,
            dir,
            section("stability", &spec.stability)?,
            parameters,
            files,
        )?)),
        "placement" => Study::Placement(placement::PlacementStudy::new(
            path,
            dir,
            section("placement", &spec.placement)?,
            parameters,
            files,
        )?),
        "mission" => Study::Mission(Box::new(mission::MissionStudy::new(
            path,
            dir,
            section("mission", &spec.mission)?,
            parameters,
            files,
        )?)),
        "uncertainty" => Study::Uncertainty(Box::new(uncertainty::UncertaintyStudy::new(
            path,
            dir,
            section("uncertainty", &spec.uncertainty)?,
            parameters,
        )?)),
        "lift_off" => Study::LiftOff(Box::new(lift_off::LiftOffStudy::new(
            path,
            dir,
            section("lift_off", &spec.lift_off)?,
            parameters,
            files,
        )?)),
        other => {
            return Err(file_error(
                path,
                "study",
                format!(
                    "unknown study '{other}' (expected stability, placement, mission, uncertainty or lift_off)"
                ),
            ));
        }
    })
}

impl Sweep {
    /// Reads and validates a sweep file (paths in it are relative to its directory).
    ///
    /// # Errors
    /// [`Error::Io`] if it cannot be read; [`Error::Parse`] naming the file and the field
    /// for malformed TOML, an unknown key, a bad value or a point count over
    /// [`MAX_POINTS`]; errors of loading the study's robot.
    pub fn from_file(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        let io = |source| Error::Io {
            path: path.to_path_buf(),
            source,
        };
        let size = std::fs::metadata(path).map_err(io)?.len();
        if size > MAX_FILE_BYTES {
            return Err(Error::parse(
                path,
                format!("larger than {MAX_FILE_BYTES} bytes"),
            ));
        }
        let text = std::fs::read_to_string(path).map_err(io)?;
        let dir = path.parent().unwrap_or_else(|| Path::new("."));
        Self::from_toml_str(&text, path, dir)
    }

    /// Parses a sweep from TOML `text`; `path` names it in errors and relative paths are
    /// taken from `dir`.
    ///
    /// # Errors
    /// As [`Sweep::from_file`].
    pub fn from_toml_str(text: &str, path: &Path, dir: &Path) -> Result<Self> {
        Self::from_toml_str_with(text, path, dir, &crate::mission::scenario::FileSystem)
    }

    /// As [`Sweep::from_toml_str`], with the study's robot (and a mission study's map and
    /// robot) read through `files` (see [`crate::mission::scenario::Loader`]). A mission
    /// study's points still load their mission's files from the file system when they
    /// are evaluated.
    ///
    /// # Errors
    /// As [`Sweep::from_file`].
    pub fn from_toml_str_with(
        text: &str,
        path: &Path,
        dir: &Path,
        files: &dyn crate::mission::scenario::Loader,
    ) -> Result<Self> {
        let spec: FileSpec = toml::from_str(text)
            .map_err(|e| Error::parse(path, format!("invalid sweep file: {e}")))?;
        let mut entries: Vec<_> = spec.parameters.iter().collect();
        entries.sort_by_key(|(k, _)| k.span().start);
        let mut parameters = Vec::with_capacity(entries.len());
        for (name, v) in entries {
            let name = name.get_ref();
            parameters.push(Parameter {
                name: name.clone(),
                values: parse_values(path, name, v)?,
            });
        }
        let sampling = parse_sampling(path, &spec.sample)?;
        let len = point_count(path, sampling, &parameters)?;
        let study = prepare_study(path, dir, &spec, &parameters, files)?;
        Ok(Self {
            source: path.to_path_buf(),
            study_name: spec.study,
            parameters,
            sampling,
            len,
            study,
        })
    }

    /// The study's name (`stability`, `placement`, `mission`, `uncertainty`, `lift_off`).
    #[must_use]
    pub fn study(&self) -> &str {
        &self.study_name
    }

    /// True if [`summarize`] summarises its table: an uncertainty study, or a mission
    /// study over seeds (a `seed` parameter).
    #[must_use]
    pub fn has_summary(&self) -> bool {
        match self.study_name.as_str() {
            "uncertainty" => true,
            "mission" => self.parameters.iter().any(|p| p.name == "seed"),
            _ => false,
        }
    }

    /// The sweep file.
    #[must_use]
    pub fn source(&self) -> &Path {
        &self.source
    }

    /// The parameters, in file order.
    #[must_use]
    pub fn parameters(&self) -> &[Parameter] {
        &self.parameters
    }

    /// The sampling.
    #[must_use]
    pub fn sampling(&self) -> Sampling {
        self.sampling
    }

    /// Number of points.
    #[must_use]
    pub fn len(&self) -> u64 {
        self.len
    }

    /// True if the sweep has no point (never: a sweep has at least one).
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    fn result_columns(&self) -> &'static [&'static str] {
        match &self.study {
            Study::Stability(_) => stability::RESULTS,
            Study::Placement(_) => placement::RESULTS,
            Study::Mission(_) => mission::RESULTS,
            Study::Uncertainty(_) => uncertainty::RESULTS,
            Study::LiftOff(_) => lift_off::RESULTS,
        }
    }

    /// The table's columns: `index`, the parameters, the results, then `eval_time_s`.
    #[must_use]
    pub fn columns(&self) -> Vec<String> {
        let mut c = vec!["index".to_string()];
        c.extend(self.parameters.iter().map(|p| p.name.clone()));
        c.extend(self.result_columns().iter().map(|s| (*s).to_string()));
        c.push("eval_time_s".to_string());
        c
    }

    /// The parameter values of point `index`.
    ///
    /// # Errors
    /// [`Error::InvalidInput`] for an index outside `0 .. len()`.
    pub fn point(&self, index: u64) -> Result<Vec<Value>> {
        self.check_index(index)?;
        Ok(match self.sampling {
            Sampling::Grid => {
                let mut rest = index;
                let mut vals = vec![Value::Missing; self.parameters.len()];
                for (k, p) in self.parameters.iter().enumerate().rev() {
                    let n = p.values.len() as u64;
                    vals[k] = p.values.grid((rest % n) as usize);
                    rest /= n;
                }
                vals
            }
            Sampling::Random { seed, .. } => {
                let mut rng = ChaCha8Rng::seed_from_u64(seed);
                rng.set_stream(index);
                self.parameters
                    .iter()
                    .map(|p| p.values.draw(&mut rng))
                    .collect()
            }
        })
    }

    fn check_index(&self, index: u64) -> Result<()> {
        if index >= self.len {
            return Err(Error::invalid(
                "sweep index",
                format!("{index} is outside 0..{}", self.len),
            ));
        }
        Ok(())
    }

    fn workspace(&self) -> Workspace {
        match &self.study {
            Study::Stability(s) => Workspace::Stability(Box::new(s.workspace())),
            Study::Placement(s) => Workspace::Placement(Box::new(s.workspace())),
            Study::Mission(s) => Workspace::Mission(s.workspace()),
            Study::Uncertainty(s) => Workspace::Uncertainty(s.workspace()),
            Study::LiftOff(s) => Workspace::LiftOff(s.workspace()),
        }
    }

    fn evaluate_in(&self, ws: &mut Workspace, index: u64) -> Result<Vec<Value>> {
        let point = self.point(index)?;
        let mut row = Vec::with_capacity(self.columns_len());
        row.push(Value::Int(index as i64));
        row.extend(point.iter().cloned());
        let start = Instant::now();
        match (&self.study, ws) {
            (Study::Stability(s), Workspace::Stability(w)) => s.evaluate(w, &point, &mut row),
            (Study::Placement(s), Workspace::Placement(w)) => s.evaluate(w, &point, &mut row),
            (Study::Mission(s), Workspace::Mission(w)) => s.evaluate(w, &point, &mut row),
            (Study::Uncertainty(s), Workspace::Uncertainty(w)) => s.evaluate(w, &point, &mut row),
            (Study::LiftOff(s), Workspace::LiftOff(w)) => s.evaluate(w, &point, &mut row),
            _ => unreachable!("a workspace is made by its own study"),
        }
        .map_err(|e| Error::invalid(format!("sweep point {index}"), e.to_string()))?;
        row.push(Value::Float(start.elapsed().as_secs_f64()));
        debug_assert_eq!(row.len(), self.columns_len());
        Ok(row)
    }

    fn columns_len(&self) -> usize {
        2 + self.parameters.len() + self.result_columns().len()
    }

    /// Evaluates point `index` into one table row (the [`Sweep::columns`]).
    ///
    /// # Errors
    /// An index outside `0 .. len()`; a failing evaluation (naming the point).
    pub fn evaluate(&self, index: u64) -> Result<Vec<Value>> {
        let mut ws = self.workspace();
        self.evaluate_in(&mut ws, index)
    }

    /// Evaluates `indices` on `threads` threads (0: all cores) into a table sorted by
    /// index. See [`Sweep::run_with_progress`].
    ///
    /// # Errors
    /// As [`Sweep::run_with_progress`].
    pub fn run(&self, indices: &[u64], threads: usize) -> Result<Table> {
        self.run_with_progress(indices, threads, &|_| {})
    }

    /// Evaluates `indices` (each in `0 .. len()`, no duplicates) on a rayon pool of
    /// `threads` threads (0: all cores), one study workspace per worker; `progress(n)` is
    /// called after every `n` finished points, from the workers. The rows are sorted by
    /// index.
    ///
    /// # Errors
    /// More than [`MAX_RUN_POINTS`] indices, an index out of range or repeated, a pool
    /// that cannot be built, or the first failing point.
    pub fn run_with_progress(
        &self,
        indices: &[u64],
        threads: usize,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Table> {
        if indices.len() > MAX_RUN_POINTS {
            return Err(Error::invalid(
                "sweep run",
                format!(
                    "{} points in one run; at most {MAX_RUN_POINTS} (split the sweep into shards)",
                    indices.len()
                ),
            ));
        }
        let mut sorted = indices.to_vec();
        sorted.sort_unstable();
        for w in sorted.windows(2) {
            if w[0] == w[1] {
                return Err(Error::invalid(
                    "sweep run",
                    format!("index {} given twice", w[0]),
                ));
            }
        }
        if let Some(&last) = sorted.last() {
            self.check_index(last)?;
        }
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .map_err(|e| Error::invalid("threads", e.to_string()))?;
        let rows: Result<Vec<Vec<Value>>> = pool.install(|| {
            sorted
                .par_iter()
                .with_min_len(8)
                .map_init(
                    || self.workspace(),
                    |ws, &i| {
                        let r = self.evaluate_in(ws, i);
                        progress(1);
                        r
                    },
                )
                .collect()
        });
        Ok(Table {
            columns: self.columns(),
            rows: rows?,
        })
    }

    /// Runs every point of shard `k` of `n` (see [`shard_indices`]).
    ///
    /// # Errors
    /// As [`shard_indices`] and [`Sweep::run_with_progress`].
    pub fn run_shard(
        &self,
        k: u64,
        n: u64,
        threads: usize,
        progress: &(dyn Fn(u64) + Sync),
    ) -> Result<Table> {
        let idx = shard_indices(self.len, k, n)?;
        self.run_with_progress(&idx, threads, progress)
    }
}

/// The indices of shard `k` of `n` over `len` points: `i` with `i mod n = k − 1`.
///
/// # Errors
/// [`Error::InvalidInput`] unless `1 ≤ k ≤ n`, or if the shard holds more than
/// [`MAX_RUN_POINTS`] points.
pub fn shard_indices(len: u64, k: u64, n: u64) -> Result<Vec<u64>> {
    if n == 0 || k == 0 || k > n {
        return Err(Error::invalid(
            "shard",
            format!("needs 1 <= K <= N, got {k}/{n}"),
        ));
    }
    let count = len.saturating_sub(k - 1).div_ceil(n);
    if count > MAX_RUN_POINTS as u64 {
        return Err(Error::invalid(
            "shard",
            format!(
                "shard {k}/{n} holds {count} of {len} points; at most {MAX_RUN_POINTS} per run (use more shards)"
            ),
        ));
    }
    Ok((k - 1..len).step_by(n as usize).collect())
}

/// Numeric value of a parameter (validated at load to be a number).
pub(crate) fn num(v: &Value) -> f64 {
    match v {
        Value::Float(f) => *f,
        Value::Int(i) => *i as f64,
        _ => f64::NAN,
    }
}

/// Checks that parameter `p` lists seeds: whole numbers from 0 to `u64::MAX`.
pub(crate) fn require_seeds(path: &Path, p: &Parameter) -> Result<()> {
    let seeds = match &p.values {
        Values::List(v) => v.iter().all(|x| {
            matches!(x, Value::Float(_) | Value::Int(_))
                && num(x).fract() == 0.0
                && (0.0..=u64::MAX as f64).contains(&num(x))
        }),
        Values::Linspace { .. } => false,
    };
    if !seeds {
        return Err(file_error(
            path,
            &format!("parameters.{}", p.name),
            "expected a list of whole numbers (seeds), e.g. seed = [0, 1, 2]",
        ));
    }
    Ok(())
}

/// Checks that every value of parameter `p` is a number.
pub(crate) fn require_numbers(path: &Path, p: &Parameter) -> Result<()> {
    if let Values::List(v) = &p.values
        && let Some(k) = v
            .iter()
            .position(|x| !matches!(x, Value::Float(_) | Value::Int(_)))
    {
        return Err(file_error(
            path,
            &format!("parameters.{}[{k}]", p.name),
            "expected a number",
        ));
    }
    Ok(())
}

/// Checks that no value of parameter `p` (numbers: [`require_numbers`] first) is below
/// zero; `unit` follows the bound in the message (`" kg"`).
pub(crate) fn require_non_negative(path: &Path, p: &Parameter, unit: &str) -> Result<()> {
    let lo = match &p.values {
        Values::Linspace { lo, hi, .. } => lo.min(*hi),
        Values::List(v) => v.iter().map(num).fold(f64::INFINITY, f64::min),
    };
    if lo < 0.0 {
        return Err(file_error(
            path,
            &format!("parameters.{}", p.name),
            format!("must be >= 0{unit}, got {lo}"),
        ));
    }
    Ok(())
}

/// Checks that every value of parameter `p` is one of `names` (their positions are
/// looked up at evaluation).
pub(crate) fn require_names(path: &Path, p: &Parameter, names: &[String]) -> Result<()> {
    let Values::List(v) = &p.values else {
        return Err(file_error(
            path,
            &format!("parameters.{}", p.name),
            "expects a list of names, not a linspace",
        ));
    };
    for (k, x) in v.iter().enumerate() {
        let ok = matches!(x, Value::Text(s) if names.contains(s));
        if !ok {
            return Err(file_error(
                path,
                &format!("parameters.{}[{k}]", p.name),
                format!("expected one of {}", names.join(", ")),
            ));
        }
    }
    Ok(())
}

/// q index of the one-coordinate joint `name` (not the root); `field` names it in errors.
pub(crate) fn joint_coordinate(
    model: &crate::multibody::Model,
    path: &Path,
    field: &str,
    name: &str,
) -> Result<usize> {
    let id = model
        .joint_id(name)
        .map_err(|e| file_error(path, field, e))?;
    if id.0 == 1 || model.nqs[id.0] != 1 {
        return Err(file_error(
            path,
            field,
            format!("joint '{name}' is not a one-coordinate arm joint"),
        ));
    }
    Ok(model.idx_q[id.0])
}

/// q index of the joint a `"q.JOINT"` sweep parameter names (`name` starts with `q.`).
pub(crate) fn joint_parameter(
    model: &crate::multibody::Model,
    path: &Path,
    name: &str,
) -> Result<usize> {
    joint_coordinate(model, path, &format!("parameters.\"{name}\""), &name[2..])
}

/// Sets the joints a posture table (`{ JOINT = value, ... }`, field `at`) lists in `q`.
pub(crate) fn set_joints(
    path: &Path,
    model: &crate::multibody::Model,
    at: &str,
    table: &toml::Table,
    q: &mut nalgebra::DVector<f64>,
) -> Result<()> {
    for (joint, x) in table {
        let f = format!("{at}.{joint}");
        let iq = joint_coordinate(model, path, &f, joint)?;
        q[iq] = x
            .as_float()
            .or_else(|| x.as_integer().map(|i| i as f64))
            .filter(|x| x.is_finite())
            .ok_or_else(|| file_error(path, &f, "expected a finite number"))?;
    }
    Ok(())
}

/// Resolves `rel` against the sweep file's directory.
pub(crate) fn resolve(dir: &Path, rel: &str) -> PathBuf {
    let p = Path::new(rel);
    if p.is_absolute() {
        p.to_path_buf()
    } else {
        dir.join(p)
    }
}

//! The library's error type: every user input and every solver that can fail returns
//! [`Result`]. Variants carry structured fields naming the file, element or field at fault.

use std::path::PathBuf;

/// Convenience alias for `Result<T, moma::Error>`.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Everything that can go wrong with user input or a solver in moma.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A file could not be read.
    #[error("{path}: cannot read file")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying I/O error.
        source: std::io::Error,
    },
    /// A file could be read but its contents are malformed.
    #[error("{path}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the line, element or field.
        message: String,
    },
    /// An invalid value in a named field of some input.
    #[error("invalid {field}: {message}")]
    InvalidInput {
        /// The field at fault (e.g. `joint 'elbow' inertial.mass`).
        field: String,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A non-finite (NaN or infinite) number where a finite one is required.
    #[error("non-finite value in {field}")]
    NonFinite {
        /// The field holding the value.
        field: String,
    },
    /// A vector or matrix of the wrong size in user input.
    #[error("{field}: expected length {expected}, got {got}")]
    WrongLength {
        /// The field at fault.
        field: String,
        /// Expected length.
        expected: usize,
        /// Actual length.
        got: usize,
    },
    /// A name (joint, frame, link, model) that does not exist.
    #[error("unknown {kind} '{name}'")]
    Unknown {
        /// What kind of name it is (e.g. `frame`).
        kind: &'static str,
        /// The name that was not found.
        name: String,
    },

    // ---- rigid-body core --------------------------------------------------------------
    /// The robot model is invalid (cyclic tree, bad inertia, unsupported joint, ...).
    #[error("invalid model: {0}")]
    Model(String),

    // ---- non-holonomic mobile robots and simulation ----------------------------------
    /// A matrix that must be invertible is (numerically) singular.
    #[error("singular {what}{}", .detail.as_ref().map(|d| format!(": {d}")).unwrap_or_default())]
    Singular {
        /// The matrix or configuration (e.g. `N_C at d = 0`).
        what: String,
        /// Extra context, e.g. the condition number.
        detail: Option<String>,
    },

    // ---- numerical trouble during simulation -----------------------------------------
    /// A simulation or iterative solver went numerically wrong (NaN, blow-up, drift).
    #[error("numerical failure at t = {t}: {message}")]
    Numerical {
        /// Simulation time (or iteration) where it happened.
        t: f64,
        /// What went wrong.
        message: String,
    },

    // ---- motion planning ------------------------------------------------------------
    /// A planning query is invalid (start/goal outside the map or in an obstacle, ...).
    #[error("planning: {0}")]
    Planning(String),

    // ---- `moma simulate` scenarios --------------------------------------------------
    /// A `moma simulate` scenario that cannot run as written (`crate::sim_config`): the
    /// message names the file, the table and the field, with the causes that led to it.
    #[error("{0}")]
    Scenario(String),
}

impl Error {
    /// A [`Error::Parse`] for `path` with a message.
    pub fn parse(path: impl Into<PathBuf>, message: impl Into<String>) -> Self {
        Error::Parse {
            path: path.into(),
            message: message.into(),
        }
    }

    /// An [`Error::InvalidInput`] for a field with a message.
    pub fn invalid(field: impl Into<String>, message: impl Into<String>) -> Self {
        Error::InvalidInput {
            field: field.into(),
            message: message.into(),
        }
    }

    /// Adds the simulation time to an [`Error::Singular`] raised inside an ODE
    /// right-hand side (`"<what> at t = <t>"`); other errors pass through unchanged.
    pub(crate) fn singular_at_time(self, t: f64) -> Self {
        match self {
            Error::Singular { what, detail } => Error::Singular {
                what: format!("{what} at t = {t}"),
                detail,
            },
            other => other,
        }
    }
}

/// Returns `Err(Error::NonFinite)` unless every value is finite.
pub fn ensure_finite<'a>(field: &str, values: impl IntoIterator<Item = &'a f64>) -> Result<()> {
    if values.into_iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(Error::NonFinite {
            field: field.to_string(),
        })
    }
}

/// The one check of a positive finite number (a duration, a step, a gain, a limit): `None`
/// when `x` is one, else what is wrong with it (`must be a positive finite number, got
/// {x}`) for the reader of a file to put after the field's name in its own error.
#[must_use]
pub fn not_positive_finite(x: f64) -> Option<String> {
    if x.is_finite() && x > 0.0 {
        None
    } else {
        Some(format!("must be a positive finite number, got {x}"))
    }
}

/// Returns `Err(Error::InvalidInput)` naming `field` unless `x` is a positive finite
/// number ([`not_positive_finite`]).
pub fn ensure_positive(field: &str, x: f64) -> Result<()> {
    match not_positive_finite(x) {
        None => Ok(()),
        Some(message) => Err(Error::invalid(field, message)),
    }
}

/// The index of the first value of `xs` that is not finite, for a reader to name the entry
/// in its own error.
#[must_use]
pub fn first_non_finite(xs: &[f64]) -> Option<usize> {
    xs.iter().position(|x| !x.is_finite())
}

/// Returns `Err(Error::WrongLength)` unless `got == expected`.
pub fn ensure_len(field: &str, expected: usize, got: usize) -> Result<()> {
    if expected == got {
        Ok(())
    } else {
        Err(Error::WrongLength {
            field: field.to_string(),
            expected,
            got,
        })
    }
}

/// The message of `e` followed by its causes, joined by `": "`.
pub(crate) fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut cause = e.source();
    while let Some(c) = cause {
        s.push_str(": ");
        s.push_str(&c.to_string());
        cause = c.source();
    }
    s
}

/// `"{path}: {what}"`.
pub(crate) fn at(path: &std::path::Path, what: &str) -> String {
    format!("{}: {what}", path.display())
}

//! The JSON states files of the command line (`STATES.json` of `moma dynamics`,
//! `manipulability`, `stability`, `stability-map`, `osc` and `space`; schemas in
//! `docs/cli.md`), parsed and validated here so that every reader is reachable from the
//! fuzz targets and from library users.
//!
//! The functions take the file's text and its path; the path only names the file in
//! errors ([`Error::Parse`], displayed as `PATH: FIELD: what is wrong`, where FIELD is
//! the JSON path such as `states[3].external[0].force`). Reading the file is the
//! caller's business. Every count is bounded before anything is allocated for it
//! ([`MAX_STATES`], [`MAX_EXTERNAL`]); lengths against a model are checked by the caller
//! (e.g. `kinematics::check_state`) or by the `check` methods here, which take the sizes.

use crate::error::{Error, Result};
use serde::Deserialize;
use serde_json::{Map, Value};
use std::path::Path;

/// Largest number of states a states file may hold (checked before they are converted).
pub const MAX_STATES: usize = 1_000_000;

/// Largest number of external point loads of one state (`stability`'s `external`).
pub const MAX_EXTERNAL: usize = 10_000;

/// One state of a generic states file: `q` and whichever of `v`, `a`, `tau`, `u` it gives.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct State {
    /// Configuration (nq).
    pub q: Vec<f64>,
    /// Velocity (nv), if given.
    pub v: Option<Vec<f64>>,
    /// Acceleration (nv), if given.
    pub a: Option<Vec<f64>>,
    /// Generalised force (nv), if given.
    pub tau: Option<Vec<f64>>,
    /// Whole-body inputs, if given.
    pub u: Option<Vec<f64>>,
    /// The other fields the caller allowed (e.g. `stability`'s `external`), as given.
    pub extra: Map<String, Value>,
}

/// The fields of [`State`] that are number arrays.
pub const NUMBER_FIELDS: [&str; 5] = ["q", "v", "a", "tau", "u"];

/// The JSON array `v` as numbers; errors name the file and `field[i]`.
///
/// # Errors
/// [`Error::Parse`] if `v` is not an array or an element is not a number.
pub fn number_array(v: &Value, field: &str, path: &Path) -> Result<Vec<f64>> {
    let arr = v
        .as_array()
        .ok_or_else(|| Error::parse(path, format!("{field}: expected an array of numbers")))?;
    arr.iter()
        .enumerate()
        .map(|(i, x)| {
            x.as_f64().ok_or_else(|| {
                Error::parse(path, format!("{field}[{i}]: expected a number, got {x}"))
            })
        })
        .collect()
}

fn parse_state(s: &Value, i: usize, path: &Path, allowed: &[&str]) -> Result<State> {
    let o = match s {
        Value::Array(_) => {
            return Ok(State {
                q: number_array(s, &format!("states[{i}]"), path)?,
                ..State::default()
            });
        }
        Value::Object(o) => o,
        _ => {
            return Err(Error::parse(
                path,
                format!("states[{i}]: expected an object with \"q\" or an array of numbers"),
            ));
        }
    };
    for key in o.keys() {
        if !allowed.contains(&key.as_str()) {
            return Err(Error::parse(
                path,
                format!(
                    "states[{i}].{key}: unknown field (this command reads {})",
                    allowed.join(", ")
                ),
            ));
        }
    }
    let get = |name: &str| -> Result<Option<Vec<f64>>> {
        o.get(name)
            .map(|x| number_array(x, &format!("states[{i}].{name}"), path))
            .transpose()
    };
    let q =
        get("q")?.ok_or_else(|| Error::parse(path, format!("states[{i}]: missing field \"q\"")))?;
    let extra = o
        .iter()
        .filter(|(k, _)| !NUMBER_FIELDS.contains(&k.as_str()))
        .map(|(k, v)| (k.clone(), v.clone()))
        .collect();
    Ok(State {
        q,
        v: get("v")?,
        a: get("a")?,
        tau: get("tau")?,
        u: get("u")?,
        extra,
    })
}

/// The list of a states document: `{"states": [...]}` or a bare `[...]`, 1 to
/// [`MAX_STATES`] entries.
fn state_list<'a>(doc: &'a Value, path: &Path) -> Result<&'a [Value]> {
    let list = match doc {
        Value::Array(a) => a,
        Value::Object(o) => {
            if let Some(k) = o.keys().find(|k| *k != "states") {
                return Err(Error::parse(
                    path,
                    format!("{k}: unknown field (expected only \"states\")"),
                ));
            }
            o.get("states")
                .and_then(|s| s.as_array())
                .ok_or_else(|| Error::parse(path, "expected a \"states\" array"))?
        }
        _ => return Err(Error::parse(path, "expected a JSON object or array")),
    };
    check_count(list.len(), path)?;
    Ok(list)
}

fn check_count(n: usize, path: &Path) -> Result<()> {
    if n == 0 {
        return Err(Error::parse(path, "'states' is empty"));
    }
    if n > MAX_STATES {
        return Err(Error::parse(
            path,
            format!("states: more than {MAX_STATES} states"),
        ));
    }
    Ok(())
}

/// Parses a generic states file: `{"states": [STATE, ...]}` or a bare `[STATE, ...]`,
/// where a STATE is an object `{"q": [..], ...}` or a bare q array. `allowed` lists the
/// fields the command reads: number arrays among `q, v, a, tau, u`, any other name is
/// handed over raw in [`State::extra`]; a field not allowed is an error naming it, so no
/// input is silently ignored. The list must hold 1 to [`MAX_STATES`] states. Lengths and
/// finiteness are left to the caller, who knows the model.
///
/// # Errors
/// [`Error::Parse`] naming `path` and the field: invalid JSON, a wrong shape, an unknown
/// or missing field, a non-number, an empty or oversized list.
pub fn parse_states(text: &str, path: &Path, allowed: &[&str]) -> Result<Vec<State>> {
    let doc: Value = serde_json::from_str(text).map_err(|e| {
        Error::parse(
            path,
            format!(
                "invalid states file: invalid JSON (expected {{\"states\": [{{\"q\": [..], ...}}]}}): {e}"
            ),
        )
    })?;
    parse_states_value(&doc, path, allowed)
}

/// [`parse_states`] on an already parsed JSON document.
///
/// # Errors
/// As [`parse_states`], except invalid JSON.
pub fn parse_states_value(doc: &Value, path: &Path, allowed: &[&str]) -> Result<Vec<State>> {
    state_list(doc, path)?
        .iter()
        .enumerate()
        .map(|(i, s)| parse_state(s, i, path, allowed))
        .collect()
}

/// One external point load of `stability`: a force applied at a point (both world, SI).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointLoad {
    /// Point of application (m, world).
    pub point: [f64; 3],
    /// Force (N, world).
    pub force: [f64; 3],
}

fn finite3(v: &Value, field: &str, path: &Path) -> Result<[f64; 3]> {
    let x = number_array(v, field, path)?;
    if x.len() != 3 {
        return Err(Error::parse(
            path,
            format!("{field}: expected length 3, got {}", x.len()),
        ));
    }
    if x.iter().any(|y| !y.is_finite()) {
        return Err(Error::parse(path, format!("{field}: non-finite value")));
    }
    Ok([x[0], x[1], x[2]])
}

/// The `external` loads of a `stability` state (`field` is e.g. `states[2].external`):
/// an array of at most [`MAX_EXTERNAL`] objects `{"point": [3], "force": [3]}` of finite
/// numbers. Fields other than `point` and `force` are ignored, as the command always did.
///
/// # Errors
/// [`Error::Parse`] naming `path` and the field at fault.
pub fn point_loads(v: &Value, field: &str, path: &Path) -> Result<Vec<PointLoad>> {
    let list = v
        .as_array()
        .ok_or_else(|| Error::parse(path, format!("{field}: expected an array")))?;
    if list.len() > MAX_EXTERNAL {
        return Err(Error::parse(
            path,
            format!("{field}: more than {MAX_EXTERNAL} loads"),
        ));
    }
    list.iter()
        .enumerate()
        .map(|(k, e)| {
            let f = format!("{field}[{k}]");
            let pt = e
                .get("point")
                .ok_or_else(|| Error::parse(path, format!("{f}: missing field \"point\"")))?;
            let fo = e
                .get("force")
                .ok_or_else(|| Error::parse(path, format!("{f}: missing field \"force\"")))?;
            Ok(PointLoad {
                point: finite3(pt, &format!("{f}.point"), path)?,
                force: finite3(fo, &format!("{f}.force"), path)?,
            })
        })
        .collect()
}

/// One state of `moma osc`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OscState {
    /// Configuration (nq).
    pub q: Vec<f64>,
    /// Velocity (nv); zero if absent.
    #[serde(default)]
    pub v: Option<Vec<f64>>,
    /// Desired task acceleration: 6 values `[vx, vy, vz, wx, wy, wz]` or one per
    /// selected row.
    pub task_acceleration: Vec<f64>,
    /// Torque projected into the task null space (nv); zero if absent.
    #[serde(default)]
    pub null_torque: Option<Vec<f64>>,
}

#[derive(Deserialize)]
struct OscStates {
    states: Vec<OscState>,
}

/// Parses the states file of `moma osc`: `{"states": [{"q": [..], "v": [..],
/// "task_acceleration": [6], "null_torque": [nv]}, ..]}` (1 to [`MAX_STATES`] states).
///
/// # Errors
/// [`Error::Parse`] naming `path`: invalid JSON or a wrong schema (serde's message with
/// line and column), an empty or oversized list.
pub fn parse_osc_states(text: &str, path: &Path) -> Result<Vec<OscState>> {
    let s: OscStates = serde_json::from_str(text).map_err(|e| {
        Error::parse(
            path,
            format!(
                "invalid states file (expected {{\"states\": [{{\"q\": [..], \"v\": [..], \"task_acceleration\": [6], \"null_torque\": [nv]}}]}}): {e}"
            ),
        )
    })?;
    check_count(s.states.len(), path)?;
    Ok(s.states)
}

impl OscState {
    /// The desired acceleration of the selected task `rows` (indices into `[vx, vy, vz,
    /// wx, wy, wz]`) and the null-space torque (zero if absent) of state `k`, for a model
    /// of `nv` velocities; errors name `path` and `states[k].FIELD`.
    ///
    /// # Errors
    /// [`Error::Parse`] for a wrong length or a non-finite value.
    pub fn task_inputs(
        &self,
        rows: &[usize],
        nv: usize,
        k: usize,
        path: &Path,
    ) -> Result<(Vec<f64>, Vec<f64>)> {
        let m = rows.len();
        let a = &self.task_acceleration;
        let a_des: Vec<f64> = if a.len() == m {
            a.clone()
        } else if a.len() == 6 && rows.iter().all(|&r| r < 6) {
            rows.iter().map(|&r| a[r]).collect()
        } else {
            return Err(Error::parse(
                path,
                format!(
                    "states[{k}].task_acceleration: expected 6 values (or {m}, one per selected row), got {}",
                    a.len()
                ),
            ));
        };
        if let Some(i) = a_des.iter().position(|x| !x.is_finite()) {
            return Err(Error::parse(
                path,
                format!("states[{k}].task_acceleration[{i}]: not finite"),
            ));
        }
        let tau0 = match &self.null_torque {
            Some(t) => {
                if t.len() != nv {
                    return Err(Error::parse(
                        path,
                        format!(
                            "states[{k}].null_torque: expected {nv} values (nv), got {}",
                            t.len()
                        ),
                    ));
                }
                if let Some(i) = t.iter().position(|x| !x.is_finite()) {
                    return Err(Error::parse(
                        path,
                        format!("states[{k}].null_torque[{i}]: not finite"),
                    ));
                }
                t.clone()
            }
            None => vec![0.0; nv],
        };
        Ok((a_des, tau0))
    }
}

/// The momentum of a `moma space` state (world axes, angular part about the system CoM).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpaceMomentum {
    /// Linear momentum (3, N·s).
    pub linear: Vec<f64>,
    /// Angular momentum about the system CoM (3, N·m·s).
    pub angular_about_com: Vec<f64>,
}

/// One state of `moma space`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpaceState {
    /// Configuration (nq, free-flyer root first).
    pub q: Vec<f64>,
    /// Joint rates (nv − 6).
    pub qdot_joints: Vec<f64>,
    /// Momentum; zero if absent.
    #[serde(default)]
    pub momentum: Option<SpaceMomentum>,
}

#[derive(Deserialize)]
struct SpaceStates {
    states: Vec<SpaceState>,
}

/// Parses the states file of `moma space`: `{"states": [{"q": [nq], "qdot_joints":
/// [nv − 6], "momentum": {"linear": [3], "angular_about_com": [3]}}]}` (1 to
/// [`MAX_STATES`] states).
///
/// # Errors
/// [`Error::Parse`] naming `path`: invalid JSON or a wrong schema (serde's message with
/// line and column), an empty or oversized list.
pub fn parse_space_states(text: &str, path: &Path) -> Result<Vec<SpaceState>> {
    let s: SpaceStates = serde_json::from_str(text).map_err(|e| {
        Error::parse(
            path,
            format!(
                "invalid states file (expected {{\"states\": [{{\"q\": [..], \"qdot_joints\": [..], \"momentum\": {{\"linear\": [3], \"angular_about_com\": [3]}}}}]}}): {e}"
            ),
        )
    })?;
    check_count(s.states.len(), path)?;
    Ok(s.states)
}

impl SpaceState {
    /// Checks `qdot_joints` (length `n` = nv − 6, finite) and returns the momentum as
    /// `[linear; angular_about_com]` (zero if absent), for state `k` of a model with `nv`
    /// velocities; errors name `path` and `states[k] FIELD`.
    ///
    /// # Errors
    /// [`Error::Parse`] for a wrong length or a non-finite value.
    pub fn check(&self, n: usize, nv: usize, k: usize, path: &Path) -> Result<[f64; 6]> {
        let src = format!("states[{k}]");
        if self.qdot_joints.len() != n {
            return Err(Error::parse(
                path,
                format!(
                    "{src} qdot_joints: expected {n} numbers (nv − 6 = {nv} − 6), got {}",
                    self.qdot_joints.len()
                ),
            ));
        }
        if let Some(i) = self.qdot_joints.iter().position(|y| !y.is_finite()) {
            return Err(Error::parse(
                path,
                format!("{src} qdot_joints[{i}]: not finite"),
            ));
        }
        let Some(m) = &self.momentum else {
            return Ok([0.0; 6]);
        };
        let mut h = [0.0; 6];
        for (name, x, off) in [
            ("momentum.linear", &m.linear, 0),
            ("momentum.angular_about_com", &m.angular_about_com, 3),
        ] {
            if x.len() != 3 {
                return Err(Error::parse(
                    path,
                    format!("{src} {name}: expected 3 numbers, got {}", x.len()),
                ));
            }
            if let Some(i) = x.iter().position(|y| !y.is_finite()) {
                return Err(Error::parse(path, format!("{src} {name}[{i}]: not finite")));
            }
            h[off..off + 3].copy_from_slice(x);
        }
        Ok(h)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p() -> &'static Path {
        Path::new("s.json")
    }

    #[test]
    fn states_in_every_accepted_shape() {
        let s = parse_states(
            r#"{"states": [{"q": [1, 2], "v": [3, 4]}, [5, 6]]}"#,
            p(),
            &["q", "v"],
        )
        .unwrap();
        assert_eq!(s[0].q, [1.0, 2.0]);
        assert_eq!(s[0].v.as_deref(), Some(&[3.0, 4.0][..]));
        assert_eq!(s[1].q, [5.0, 6.0]);
        assert!(s[1].v.is_none());
        assert_eq!(parse_states("[[0.5]]", p(), &["q"]).unwrap()[0].q, [0.5]);
    }

    #[test]
    fn states_errors_name_the_file_and_field() {
        let cases = [
            (
                r#"{"states": [{"q": [1], "u": [2]}]}"#,
                "states[0].u: unknown field",
            ),
            (r#"{"states": [{"v": [1]}]}"#, "missing field \"q\""),
            (r#"{"states": [{"q": [1, "x"]}]}"#, "states[0].q[1]"),
            (r#"{"states": []}"#, "'states' is empty"),
            (r#"{"state": []}"#, "state: unknown field"),
            (r#"{"states": [1]}"#, "states[0]: expected an object"),
            (r#"{"states": {"q": [1]}}"#, "expected a \"states\" array"),
            ("3", "expected a JSON object or array"),
            ("{", "invalid states file"),
            // serde_json refuses numbers beyond f64's range instead of making them inf.
            (r#"[[1e400]]"#, "invalid states file"),
        ];
        for (text, needle) in cases {
            let e = parse_states(text, p(), &["q", "v"])
                .unwrap_err()
                .to_string();
            assert!(e.contains(needle), "{text}: {e}");
            assert!(e.starts_with("s.json: "), "{e}");
        }
    }

    #[test]
    fn point_loads_are_checked() {
        let v: Value =
            serde_json::from_str(r#"[{"point": [0, 0, 1], "force": [1, 2, 3]}]"#).unwrap();
        let l = point_loads(&v, "states[0].external", p()).unwrap();
        assert_eq!(l[0].force, [1.0, 2.0, 3.0]);
        for (text, needle) in [
            (r#"{}"#, "states[0].external: expected an array"),
            (
                r#"[{"force": [1, 2, 3]}]"#,
                "external[0]: missing field \"point\"",
            ),
            (
                r#"[{"point": [0, 0], "force": [1, 2, 3]}]"#,
                "external[0].point: expected length 3",
            ),
        ] {
            let v: Value = serde_json::from_str(text).unwrap();
            let e = point_loads(&v, "states[0].external", p())
                .unwrap_err()
                .to_string();
            assert!(e.contains(needle), "{text}: {e}");
        }
    }

    #[test]
    fn osc_and_space_states() {
        let s = parse_osc_states(
            r#"{"states": [{"q": [0], "task_acceleration": [1, 2, 3, 4, 5, 6]}]}"#,
            p(),
        )
        .unwrap();
        let (a, t) = s[0].task_inputs(&[0, 2], 1, 0, p()).unwrap();
        assert_eq!(a, [1.0, 3.0]);
        assert_eq!(t, [0.0]);
        let short = parse_osc_states(
            r#"{"states": [{"q": [0], "task_acceleration": [1, 2, 3, 4]}]}"#,
            p(),
        )
        .unwrap();
        let e = short[0].task_inputs(&[0, 1, 2], 2, 0, p()).unwrap_err();
        assert!(
            e.to_string()
                .contains("states[0].task_acceleration: expected 6")
        );
        let e = parse_osc_states(r#"{"states": []}"#, p()).unwrap_err();
        assert!(e.to_string().contains("'states' is empty"));
        let e = parse_osc_states(r#"{"states": [{"q": [0]}]}"#, p()).unwrap_err();
        assert!(e.to_string().contains("task_acceleration"), "{e}");

        let s = parse_space_states(
            r#"{"states": [{"q": [0], "qdot_joints": [1],
                "momentum": {"linear": [1, 2, 3], "angular_about_com": [4, 5, 6]}}]}"#,
            p(),
        )
        .unwrap();
        assert_eq!(
            s[0].check(1, 7, 0, p()).unwrap(),
            [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]
        );
        let e = s[0].check(2, 8, 0, p()).unwrap_err().to_string();
        assert!(
            e.contains("states[0] qdot_joints: expected 2 numbers"),
            "{e}"
        );
    }
}

//! The `unicycle_control` case schema of `moma eval`: closed-loop runs of the unicycle
//! laws of [`crate::control::unicycle`].
//!
//! Each case names a `law` (`kanayama`, `samson`, `astolfi`, `aicardi`), its `gains`
//! (`Kx, Ky, Kth`; `k1, k2, k3`; `k_rho, k_alpha, k_beta`; `gamma, k, h`), for Kanayama a
//! `reference` `{vr, wr}` (the constant-input circle from the origin heading +x, a line
//! when `wr = 0`), an `initial_state` `[x, y, θ]` and `trajectory.t`. The stabilisers
//! drive to the origin with heading 0 (or to an optional `goal` `[x, y, θ]`). The run is
//! integrated with DOP853 at `rtol = atol = tol`; `trajectory.state` (θ continuous, not
//! wrapped), `trajectory.v`, `trajectory.w` (the commanded inputs at the sample times) and,
//! for the laws with a Lyapunov function, `trajectory.V` are filled in. A violated
//! Astolfi strong condition adds a `warnings` list to the case.

use crate::control::Controller;
use crate::control::unicycle::{
    Aicardi, Astolfi, ConstantInputReference, Kanayama, Pose, Samson, unicycle_rhs,
};
use crate::error::{Error, Result};
use crate::ode::{AdaptiveOptions, Dop853, OdeSystem};
use serde_json::{Map, Value, json};

/// Largest number of output samples per case.
pub const MAX_SAMPLES: usize = 1_000_000;

enum Law {
    Kanayama(Kanayama, ConstantInputReference),
    Samson(Samson, Pose),
    Astolfi(Astolfi, Pose),
    Aicardi(Aicardi, Pose),
}

impl Law {
    fn inputs(&self, t: f64, s: &Pose) -> [f64; 2] {
        match self {
            Law::Kanayama(k, r) => k.inputs(s, &r.at(t)),
            Law::Samson(k, g) => k.inputs(t, s, g),
            Law::Astolfi(k, g) => k.inputs(s, g),
            Law::Aicardi(k, g) => k.inputs(s, g),
        }
    }

    fn lyapunov(&self, t: f64, s: &Pose) -> Option<f64> {
        match self {
            Law::Kanayama(k, r) => k.lyapunov(t, s, &r.at(t)),
            Law::Samson(k, g) => k.lyapunov(t, s, g),
            Law::Astolfi(k, g) => k.lyapunov(t, s, g),
            Law::Aicardi(k, g) => k.lyapunov(t, s, g),
        }
    }
}

struct Loop<'a>(&'a Law);

impl OdeSystem for Loop<'_> {
    fn dim(&self) -> usize {
        3
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<()> {
        let s = [x[0], x[1], x[2]];
        let f = unicycle_rhs(&s, &self.0.inputs(t, &s));
        dx.copy_from_slice(&f);
        Ok(())
    }
}

fn number(v: &Value, name: &str) -> Result<f64> {
    let x = v
        .as_f64()
        .ok_or_else(|| Error::invalid(name, "expected a number"))?;
    if !x.is_finite() {
        return Err(Error::NonFinite { field: name.into() });
    }
    Ok(x)
}

fn gain(case: &Value, name: &str) -> Result<f64> {
    let g = case
        .get("gains")
        .ok_or_else(|| Error::invalid("gains", "missing"))?;
    if !g.is_object() {
        return Err(Error::invalid("gains", "expected an object"));
    }
    number(
        g.get(name)
            .ok_or_else(|| Error::invalid(format!("gains.{name}"), "missing"))?,
        &format!("gains.{name}"),
    )
}

fn pose(case: &Value, key: &str) -> Result<Option<Pose>> {
    let Some(v) = case.get(key) else {
        return Ok(None);
    };
    let a = v
        .as_array()
        .ok_or_else(|| Error::invalid(key, "expected [x, y, θ]"))?;
    crate::error::ensure_len(key, 3, a.len())?;
    let mut p = [0.0; 3];
    for (i, x) in a.iter().enumerate() {
        p[i] = number(x, &format!("{key}[{i}]"))?;
    }
    Ok(Some(p))
}

fn times(case: &Value) -> Result<Vec<f64>> {
    let t = case
        .get("trajectory")
        .and_then(|t| t.get("t"))
        .ok_or_else(|| Error::invalid("trajectory.t", "missing"))?
        .as_array()
        .ok_or_else(|| Error::invalid("trajectory.t", "expected a list of times"))?;
    if t.len() > MAX_SAMPLES {
        return Err(Error::invalid(
            "trajectory.t",
            format!("{} samples, at most {MAX_SAMPLES}", t.len()),
        ));
    }
    let mut out = Vec::with_capacity(t.len());
    for (i, x) in t.iter().enumerate() {
        let x = number(x, &format!("trajectory.t[{i}]"))?;
        if i == 0 && x < 0.0 {
            return Err(Error::invalid(
                "trajectory.t[0]",
                "times must not be negative",
            ));
        }
        if let Some(&prev) = out.last()
            && x < prev
        {
            return Err(Error::invalid(
                format!("trajectory.t[{i}]"),
                "times must be non-decreasing",
            ));
        }
        out.push(x);
    }
    super::check_horizon("trajectory.t", &out)?;
    Ok(out)
}

fn law(case: &Value, warnings: &mut Vec<String>) -> Result<Law> {
    let name = case
        .get("law")
        .ok_or_else(|| Error::invalid("law", "missing"))?
        .as_str()
        .ok_or_else(|| Error::invalid("law", "expected a string"))?;
    let goal = pose(case, "goal")?.unwrap_or([0.0; 3]);
    Ok(match name {
        "kanayama" => {
            let r = case
                .get("reference")
                .ok_or_else(|| Error::invalid("reference", "missing (expected {vr, wr})"))?;
            let vr = number(
                r.get("vr")
                    .ok_or_else(|| Error::invalid("reference.vr", "missing"))?,
                "reference.vr",
            )?;
            let wr = number(
                r.get("wr")
                    .ok_or_else(|| Error::invalid("reference.wr", "missing"))?,
                "reference.wr",
            )?;
            Law::Kanayama(
                Kanayama::new(gain(case, "Kx")?, gain(case, "Ky")?, gain(case, "Kth")?)?,
                ConstantInputReference { vr, wr },
            )
        }
        "samson" => Law::Samson(
            Samson::new(gain(case, "k1")?, gain(case, "k2")?, gain(case, "k3")?)?,
            goal,
        ),
        "astolfi" => {
            let a = Astolfi::new(
                gain(case, "k_rho")?,
                gain(case, "k_alpha")?,
                gain(case, "k_beta")?,
            )?;
            if let Some(w) = a.warning() {
                warnings.push(w);
            }
            Law::Astolfi(a, goal)
        }
        "aicardi" => Law::Aicardi(
            Aicardi::new(gain(case, "gamma")?, gain(case, "k")?, gain(case, "h")?)?,
            goal,
        ),
        other => {
            return Err(Error::invalid(
                "law",
                format!("unknown law '{other}'; expected kanayama, samson, astolfi or aicardi"),
            ));
        }
    })
}

/// Fills `trajectory.{state, v, w, V}` (and `warnings`) of one case.
///
/// # Errors
/// A missing or malformed field (named), violated gain conditions, an integration
/// failure.
pub fn evaluate_unicycle_case(case: &Value, tol: f64) -> Result<Value> {
    let mut warnings = Vec::new();
    let law = law(case, &mut warnings)?;
    let x0 =
        pose(case, "initial_state")?.ok_or_else(|| Error::invalid("initial_state", "missing"))?;
    let t = times(case)?;
    let mut dp = Dop853::new(3, AdaptiveOptions::with_tolerance(tol))?;
    // The initial state is at t = 0 (times are checked non-negative).
    let rows = dp.solve_at(&mut Loop(&law), 0.0, &x0, &t)?;
    let mut state = Vec::with_capacity(t.len());
    let (mut v, mut w, mut lv) = (
        Vec::with_capacity(t.len()),
        Vec::with_capacity(t.len()),
        Vec::with_capacity(t.len()),
    );
    for (r, &ti) in rows.iter().zip(&t) {
        let s = [r[0], r[1], r[2]];
        let u = law.inputs(ti, &s);
        state.push(json!(s));
        v.push(u[0]);
        w.push(u[1]);
        if let Some(val) = law.lyapunov(ti, &s) {
            lv.push(val);
        }
    }
    let mut traj: Map<String, Value> = case
        .get("trajectory")
        .and_then(|t| t.as_object())
        .cloned()
        .unwrap_or_default();
    traj.insert("t".into(), json!(t));
    traj.insert("state".into(), Value::Array(state));
    traj.insert("v".into(), json!(v));
    traj.insert("w".into(), json!(w));
    if lv.len() == t.len() {
        traj.insert("V".into(), json!(lv));
    } else {
        traj.remove("V");
    }
    let mut out = case.clone();
    let obj = out
        .as_object_mut()
        .ok_or_else(|| Error::invalid("case", "expected an object"))?;
    obj.insert("trajectory".into(), Value::Object(traj));
    if !warnings.is_empty() {
        obj.insert("warnings".into(), json!(warnings));
    }
    Ok(out)
}

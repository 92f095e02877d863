//! The mission study: one full mission run ([`crate::mission::run`]) per point, with the
//! scenario's start, goal, first obstacle and limits taken from the point, its contact
//! plant's parameters (`"contact.mu"`, `"contact.stiffness"`, `"contact.damping"`,
//! `"contact.slip_velocity"`, `"contact.dt"`, with `simulation.plant = "contact"`), its
//! `[uncertainty]` seed (`seed`) and payload (`"uncertainty.payload.mass"`,
//! `"uncertainty.payload.position[i]"`: the point's value replaces that distribution; the
//! seed still draws the rest). Each point re-validates the modified scenario as `moma
//! mission` would; a point whose scenario is invalid (a start off the map, say) or whose
//! run fails is a row with `reached = false` and the message in `reason`, so one bad
//! corner of a sweep does not stop it.
//!
//! Tip, lift-off and slip: `tipped` at the first recorded sample whose ZMP margin reaches
//! zero (on the contact plant its centre of pressure reaches the support's boundary; on
//! the rolling plant an undefined ZMP counts too), `tip_contact` the support edge of that
//! sample's margin (`edge A-B` by its two contacts, as the uncertainty study names the
//! edge on the rolling plant); `lift_off` at the first contact to lose its load (contact
//! plant only: with more than three contacts one may lift while the robot stands);
//! `slipped` at the first `slip` event (contact plant: a wheel slides; rolling plant: a
//! driven wheel's friction demand above `limits.mu`).

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::{
    Parameter, Value, file_error, num, require_non_negative, require_numbers, require_seeds,
    resolve, study_section,
};
use crate::contact::ContactSpec;
use crate::error::Result;
use crate::mission::scenario::Loader;
use crate::mission::{self, MissionFile};
use crate::sim::stability_monitor::first_crossing;
use crate::sim::uncertainty::{Dist, PayloadSpec};

/// Result columns of the mission study (the summary's fields).
pub(super) const RESULTS: &[&str] = &[
    "reached",
    "reason",
    "time_to_goal",
    "simulated_time",
    "replans",
    "min_zmp_margin",
    "min_force_angle",
    "min_moment_height",
    "min_clearance",
    "max_tracking_error",
    "max_slip_ratio",
    "torque_saturated_steps",
    "speed_saturated_steps",
    "input_work",
    "tipped",
    "tip_time",
    "tip_contact",
    "lift_off_time",
    "lift_off_contact",
    "slipped",
    "slip_time",
];

const NAMES: &str = "start_x, start_y, start_yaw, goal_x, goal_y, goal_yaw, obstacle_t, \
                     obstacle_x, obstacle_y, obstacle_radius, v_max, omega_max, a_max, \
                     alpha_max, mu, tip_fraction, \"contact.mu\", \"contact.stiffness\", \
                     \"contact.damping\", \"contact.slip_velocity\", \"contact.dt\", seed, \
                     \"uncertainty.payload.mass\", \"uncertainty.payload.position[0]\" \
                     ([1], [2])";

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Spec {
    scenario: String,
}

#[derive(Clone, Copy)]
enum Slot {
    StartX,
    StartY,
    StartYaw,
    GoalX,
    GoalY,
    GoalYaw,
    ObstacleT,
    ObstacleX,
    ObstacleY,
    ObstacleRadius,
    VMax,
    OmegaMax,
    AMax,
    AlphaMax,
    Mu,
    TipFraction,
    ContactMu,
    ContactStiffness,
    ContactDamping,
    ContactSlipVelocity,
    ContactDt,
    Seed,
    PayloadMass,
    /// Coordinate `i` of `uncertainty.payload.position`.
    PayloadPosition(usize),
}

/// The prepared study: the scenario as loaded (validated once at load).
pub(super) struct MissionStudy {
    path: PathBuf,
    base: PathBuf,
    file: MissionFile,
    slots: Vec<Slot>,
}

/// Per-worker workspace (a mission run builds its own state).
pub(super) struct Workspace;

impl MissionStudy {
    pub(super) fn new(
        path: &Path,
        dir: &Path,
        section: toml::Value,
        params: &[Parameter],
        files: &dyn Loader,
    ) -> Result<Self> {
        let spec: Spec = study_section(path, "mission", section)?;
        let scenario = resolve(dir, &spec.scenario);
        let m = mission::scenario::load_with(&scenario, files)?;
        let mut slots = Vec::with_capacity(params.len());
        for p in params {
            let slot = match p.name.as_str() {
                "start_x" => Slot::StartX,
                "start_y" => Slot::StartY,
                "start_yaw" => Slot::StartYaw,
                "goal_x" => Slot::GoalX,
                "goal_y" => Slot::GoalY,
                "goal_yaw" => Slot::GoalYaw,
                "obstacle_t" => Slot::ObstacleT,
                "obstacle_x" => Slot::ObstacleX,
                "obstacle_y" => Slot::ObstacleY,
                "obstacle_radius" => Slot::ObstacleRadius,
                "v_max" => Slot::VMax,
                "omega_max" => Slot::OmegaMax,
                "a_max" => Slot::AMax,
                "alpha_max" => Slot::AlphaMax,
                "mu" => Slot::Mu,
                "tip_fraction" => Slot::TipFraction,
                "contact.mu" => Slot::ContactMu,
                "contact.stiffness" => Slot::ContactStiffness,
                "contact.damping" => Slot::ContactDamping,
                "contact.slip_velocity" => Slot::ContactSlipVelocity,
                "contact.dt" => Slot::ContactDt,
                "seed" => Slot::Seed,
                "uncertainty.payload.mass" => Slot::PayloadMass,
                "uncertainty.payload.position[0]" => Slot::PayloadPosition(0),
                "uncertainty.payload.position[1]" => Slot::PayloadPosition(1),
                "uncertainty.payload.position[2]" => Slot::PayloadPosition(2),
                n => {
                    return Err(file_error(
                        path,
                        &format!("parameters.{n}"),
                        format!("unknown parameter of the mission study (expected {NAMES})"),
                    ));
                }
            };
            if matches!(
                slot,
                Slot::ObstacleT | Slot::ObstacleX | Slot::ObstacleY | Slot::ObstacleRadius
            ) && m.file.obstacles.is_empty()
            {
                return Err(file_error(
                    path,
                    &format!("parameters.{}", p.name),
                    format!(
                        "the scenario {} has no [[obstacles]] entry",
                        scenario.display()
                    ),
                ));
            }
            let contact = matches!(
                slot,
                Slot::ContactMu
                    | Slot::ContactStiffness
                    | Slot::ContactDamping
                    | Slot::ContactSlipVelocity
                    | Slot::ContactDt
            );
            if contact && m.contact.is_none() {
                return Err(file_error(
                    path,
                    &format!("parameters.\"{}\"", p.name),
                    format!(
                        "the scenario {} runs the rolling plant: the contact parameters need \
                         simulation.plant = \"contact\" and its [contact] table",
                        scenario.display()
                    ),
                ));
            }
            if matches!(slot, Slot::Seed) {
                if m.file.uncertainty.is_none() {
                    return Err(file_error(
                        path,
                        "parameters.seed",
                        format!(
                            "the scenario {} has no [uncertainty] table to seed",
                            scenario.display()
                        ),
                    ));
                }
                require_seeds(path, p)?;
            }
            let payload = matches!(slot, Slot::PayloadMass | Slot::PayloadPosition(_));
            if payload
                && m.file
                    .uncertainty
                    .as_ref()
                    .is_none_or(|u| u.payload.is_none())
            {
                return Err(file_error(
                    path,
                    &format!("parameters.\"{}\"", p.name),
                    format!(
                        "the scenario {} has no uncertainty.payload to vary",
                        scenario.display()
                    ),
                ));
            }
            require_numbers(path, p)?;
            if matches!(slot, Slot::PayloadMass) {
                require_non_negative(path, p, " kg")?;
            }
            slots.push(slot);
        }
        let base = scenario
            .parent()
            .unwrap_or_else(|| Path::new("."))
            .to_path_buf();
        Ok(Self {
            path: scenario,
            base,
            file: m.file,
            slots,
        })
    }

    pub(super) fn workspace(&self) -> Workspace {
        Workspace
    }

    pub(super) fn evaluate(
        &self,
        _ws: &mut Workspace,
        point: &[Value],
        row: &mut Vec<Value>,
    ) -> Result<()> {
        let mut f = self.file.clone();
        for (s, v) in self.slots.iter().zip(point) {
            let x = num(v);
            match s {
                Slot::StartX => f.start.pose[0] = x,
                Slot::StartY => f.start.pose[1] = x,
                Slot::StartYaw => f.start.pose[2] = x,
                Slot::GoalX => {
                    if let Some(g) = &mut f.goal {
                        g.pose[0] = x;
                    }
                }
                Slot::GoalY => {
                    if let Some(g) = &mut f.goal {
                        g.pose[1] = x;
                    }
                }
                Slot::GoalYaw => {
                    if let Some(g) = &mut f.goal {
                        g.pose[2] = x;
                    }
                }
                Slot::ObstacleT => f.obstacles[0].t = x,
                Slot::ObstacleX => f.obstacles[0].center[0] = x,
                Slot::ObstacleY => f.obstacles[0].center[1] = x,
                Slot::ObstacleRadius => f.obstacles[0].radius = x,
                Slot::VMax => f.limits.v_max = x,
                Slot::OmegaMax => f.limits.omega_max = x,
                Slot::AMax => f.limits.a_max = x,
                Slot::AlphaMax => f.limits.alpha_max = x,
                Slot::Mu => f.limits.mu = x,
                Slot::TipFraction => f.limits.tip_fraction = x,
                Slot::ContactMu => contact(&mut f).mu = Some(x),
                Slot::ContactStiffness => contact(&mut f).stiffness = Some(x),
                Slot::ContactDamping => contact(&mut f).damping = Some(x),
                Slot::ContactSlipVelocity => contact(&mut f).slip_velocity = Some(x),
                Slot::ContactDt => contact(&mut f).dt = Some(x),
                Slot::Seed => {
                    if let Some(u) = f.uncertainty.as_mut() {
                        u.seed = x as u64;
                    }
                }
                Slot::PayloadMass => payload(&mut f).mass = Dist::Fixed(x),
                Slot::PayloadPosition(i) => payload(&mut f).position[*i] = Dist::Fixed(x),
            }
        }
        let outcome = mission::scenario::from_file(f, &self.path, &self.base)
            .map_err(|e| format!("invalid scenario: {e}"))
            .and_then(|m| mission::run(&m).map_err(|e| format!("run failed: {e}")));
        match outcome {
            Ok(r) => {
                row.push(Value::Bool(r.reached));
                row.push(r.reason.clone().map_or(Value::Missing, Value::Text));
                row.push(Value::opt(r.time_to_goal));
                row.push(Value::Float(r.duration));
                row.push(Value::Int(r.replans() as i64));
                row.push(Value::opt(r.min_zmp_margin()));
                row.push(Value::opt(r.min_force_angle()));
                row.push(Value::opt(r.min_mhs()));
                row.push(Value::opt(r.min_clearance()));
                row.push(Value::opt(r.max_tracking_error()));
                row.push(Value::opt(r.max_slip_ratio()));
                row.push(Value::Int(r.torque_saturated_steps as i64));
                row.push(Value::Int(r.speed_saturated_steps as i64));
                row.push(Value::Float(r.input_work));
                let tip = first_crossing(&r.samples.t, &r.samples.zmp_margin, r.contact.is_none());
                row.push(Value::Bool(tip.is_some()));
                row.push(Value::opt(tip.map(|c| c.time)));
                let edge = tip.and_then(|c| r.samples.zmp_critical_edge[c.sample]);
                row.push(edge.map_or(Value::Missing, |e| Value::Text(r.support_edges[e].clone())));
                let lift = r.contact.as_ref().and_then(|c| c.first_lift_off.as_ref());
                row.push(Value::opt(lift.map(|e| e.t)));
                row.push(lift.map_or(Value::Missing, |e| Value::Text(e.contact.clone())));
                let slip = r.events.iter().find(|e| e.kind == "slip").map(|e| e.t);
                row.push(Value::Bool(slip.is_some()));
                row.push(Value::opt(slip));
            }
            Err(reason) => {
                row.push(Value::Bool(false));
                row.push(Value::Text(reason));
                row.extend(std::iter::repeat_n(Value::Missing, RESULTS.len() - 2));
            }
        }
        Ok(())
    }
}

/// The file's `uncertainty.payload` (present: a payload parameter is refused at load
/// without it).
fn payload(f: &mut MissionFile) -> &mut PayloadSpec {
    f.uncertainty
        .as_mut()
        .and_then(|u| u.payload.as_mut())
        .expect("checked at load: the scenario has an uncertainty.payload")
}

/// The file's `[contact]` table (present: a contact parameter is refused at load
/// without it).
fn contact(f: &mut MissionFile) -> &mut ContactSpec {
    f.contact
        .as_mut()
        .expect("checked at load: the scenario has a [contact] table")
}

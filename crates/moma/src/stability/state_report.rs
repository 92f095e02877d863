//! The per-state result document of a stability evaluation: the `states[i]` object of
//! `moma stability` (schema in `docs/cli.md`) and the dictionary of the Python
//! package's `moma.stability`, built from one place so both stay identical.

use super::{AccelerationLimits, StabilityData, StabilityModel};
use nalgebra::Vector3;
use serde::Serialize;

/// The gravito-inertial wrench of a state (world axes).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WrenchState {
    /// Resultant force (N).
    pub force: [f64; 3],
    /// Moment about the centre of mass (N·m).
    pub moment_about_com: [f64; 3],
}

/// The measures of one support edge, with its end points (world coordinates).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct EdgeState {
    /// First vertex.
    pub from: [f64; 3],
    /// Second vertex.
    pub to: [f64; 3],
    /// Signed distance of the ZMP to the edge line (m), positive inside.
    pub zmp_distance: Option<f64>,
    /// Force-Angle θ_i (rad) with the moment couple.
    pub force_angle: Option<f64>,
    /// θ_i without the couple.
    pub force_angle_no_couple: Option<f64>,
    /// `β_i = θ_i |d_i| |f_r|` (N·m·rad).
    pub force_angle_beta: Option<f64>,
    /// Moment `M_i` about the edge axis (N·m), positive = restoring.
    pub moment: f64,
    /// Inertia `I_i` of the Moment-Height body set about the axis (kg·m²).
    pub inertia: f64,
    /// `M_i / I_i` (1/s²).
    pub mhs: Option<f64>,
}

/// Everything reported for one state (`moma stability`'s `states[i]`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StateReport {
    /// Total mass (kg).
    pub total_mass: f64,
    /// Centre of mass (world).
    pub com: [f64; 3],
    /// Gravito-inertial wrench.
    pub giw: WrenchState,
    /// Support polygon vertices in world coordinates.
    pub support: Vec<[f64; 3]>,
    /// The Zero-Moment Point on the ground plane; `None` at lift-off or free fall.
    pub zmp: Option<[f64; 3]>,
    /// `min_i s_i` (m).
    pub zmp_margin: Option<f64>,
    /// The edge attaining the margin.
    pub zmp_critical_edge: Option<usize>,
    /// Per-edge measures.
    pub edges: Vec<EdgeState>,
    /// `min_i θ_i` (rad).
    pub force_angle_min: Option<f64>,
    /// `α = min_i θ_i · |f_r|` (N·rad).
    pub force_angle_alpha: Option<f64>,
    /// `min_i β_i`.
    pub force_angle_beta_min: Option<f64>,
    /// `min_i M_i / I_i` (1/s²).
    pub mhs_min: Option<f64>,
    /// The acceleration limits of the posture, reported for states at rest only.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub acceleration_limits: Option<AccelerationLimits>,
    /// True when a ZMP exists and lies strictly inside the support.
    pub stable: bool,
}

fn arr(v: &Vector3<f64>) -> [f64; 3] {
    [v.x, v.y, v.z]
}

impl StateReport {
    /// The report of the state last evaluated into `sd` by
    /// [`evaluate`](super::evaluate); `at_rest` adds the posture's acceleration limits
    /// (meaningful only when v, a and the external loads are zero).
    #[must_use]
    pub fn new(sm: &StabilityModel, sd: &StabilityData, at_rest: bool) -> Self {
        let (w, r, sup) = (&sd.wrench, &sd.report, &sd.support);
        Self {
            total_mass: w.mass,
            com: arr(&w.com),
            giw: WrenchState {
                force: arr(&w.force),
                moment_about_com: arr(&w.moment_about_com),
            },
            support: (0..sup.len()).map(|i| arr(&sup.vertex(i))).collect(),
            zmp: r.zmp.as_ref().map(arr),
            zmp_margin: r.zmp_margin,
            zmp_critical_edge: r.zmp_critical_edge,
            edges: r
                .edges
                .iter()
                .enumerate()
                .map(|(i, e)| {
                    let ed = sup.edge(i);
                    EdgeState {
                        from: arr(&ed.from),
                        to: arr(&ed.to),
                        zmp_distance: e.zmp_distance,
                        force_angle: e.force_angle,
                        force_angle_no_couple: e.force_angle_no_couple,
                        force_angle_beta: e.force_angle_beta,
                        moment: e.moment,
                        inertia: e.inertia,
                        mhs: e.mhs,
                    }
                })
                .collect(),
            force_angle_min: r.force_angle_min,
            force_angle_alpha: r.force_angle_alpha,
            force_angle_beta_min: r.force_angle_beta_min,
            mhs_min: r.mhs_min,
            acceleration_limits: at_rest.then(|| sd.acceleration_limits(sm)),
            stable: r.stable,
        }
    }
}

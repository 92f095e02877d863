//! The three tip-over measures over one gravito-inertial wrench and one support: the
//! Zero-Moment Point with its per-edge distances, the Force-Angle measure (with and
//! without the moment couple) and the Moment-Height measure.

use nalgebra::Vector3;

use super::polygon::{Edge, SupportPolygon};
use super::wrench::GravitoInertialWrench;
use crate::spatial::Inertia;

/// Relative size under which an effective force counts as zero (the Force-Angle θ_i is
/// then undefined), times the size of the wrench.
const VANISHING: f64 = 1e-12;
/// Absolute floor of that threshold per kilogram of robot (N/kg): an effective force
/// below a nano-newton per kilogram (free fall up to rounding) is no force.
const VANISHING_PER_KG: f64 = 1e-9;

/// The measures of one tip-over axis (edge i). Undefined values are `None`, never NaN.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct EdgeMeasures {
    /// Signed distance `s_i = nin_i · (p_zmp − p_i)` of the ZMP to the edge line (m),
    /// positive inside; `None` without a ZMP.
    pub zmp_distance: Option<f64>,
    /// Force-Angle θ_i (rad) with the moment couple `f_ni`; `None` when the effective
    /// force vanishes (below 1e-12 of the wrench's size and below 1e-9 N per kg of robot)
    /// or the centre of mass lies on the axis.
    pub force_angle: Option<f64>,
    /// θ_i without the couple (the force `P_i f_r` alone, as hector_stability_metrics).
    pub force_angle_no_couple: Option<f64>,
    /// `β_i = θ_i |d_i| |f_r|` (N·m·rad), the height-sensitive measure of 2000.
    pub force_angle_beta: Option<f64>,
    /// Lever `|d_i|` of the effective force about the axis (m).
    pub lever: Option<f64>,
    /// Moment `M_i = a_i · M_gi(p_i)` about the axis (N·m), positive = restoring.
    pub moment: f64,
    /// Inertia `I_i` of the chosen body set about the axis (kg·m²).
    pub inertia: f64,
    /// `M_i / I_i` (1/s²); `None` when `I_i = 0`.
    pub mhs: Option<f64>,
}

/// Every measure of one state over one support.
#[derive(Clone, Debug, PartialEq, Default)]
pub struct StabilityReport {
    /// The Zero-Moment Point on the ground plane; `None` when `n · f_gi ≥ 0` (lift-off
    /// or free fall).
    pub zmp: Option<Vector3<f64>>,
    /// `min_i s_i` (m); `None` without a ZMP.
    pub zmp_margin: Option<f64>,
    /// The edge attaining the margin (lowest index on ties).
    pub zmp_critical_edge: Option<usize>,
    /// Per-edge measures, edge i from support vertex i to i + 1.
    pub edges: Vec<EdgeMeasures>,
    /// `min_i θ_i` (rad) over the defined angles.
    pub force_angle_min: Option<f64>,
    /// The 1996 measure `α = min_i θ_i · |f_r|` (N·rad).
    pub force_angle_alpha: Option<f64>,
    /// The 2000 measure `β = min_i β_i`.
    pub force_angle_beta_min: Option<f64>,
    /// `min_i M_i / I_i` over the defined ratios.
    pub mhs_min: Option<f64>,
    /// True when a ZMP exists and lies strictly inside the support (margin > 0).
    pub stable: bool,
}

impl StabilityReport {
    /// An empty report with room for `n_edges` edges.
    #[must_use]
    pub fn with_capacity(n_edges: usize) -> Self {
        Self {
            edges: Vec::with_capacity(n_edges),
            ..Self::default()
        }
    }
}

/// The Zero-Moment Point of `w` on the horizontal plane `z = ground_z`:
/// `p0 + n × M_gi(p0) / (n · f_gi)` with `n = ẑ`; `None` unless `n · f_gi < 0`.
#[must_use]
pub fn zero_moment_point(w: &GravitoInertialWrench, ground_z: f64) -> Option<Vector3<f64>> {
    let fz = w.force.z;
    // also rejects NaN
    if fz.is_nan() || fz >= 0.0 {
        return None;
    }
    let p0 = Vector3::new(0.0, 0.0, ground_z);
    let m = w.moment_about(&p0);
    Some(Vector3::new(-m.y / fz, m.x / fz, ground_z))
}

/// Force-Angle of one axis for an effective force `fs` and the normal `l` from the CoM to
/// the axis: `(θ, |d|)`, or `None` if either vanishes.
fn force_angle(
    axis: &Vector3<f64>,
    l: &Vector3<f64>,
    fs: &Vector3<f64>,
    threshold: f64,
) -> Option<(f64, f64)> {
    let (ln, fn_) = (l.norm(), fs.norm());
    if !(ln > 0.0 && fn_ > threshold) {
        return None;
    }
    let (lh, fh) = (l / ln, fs / fn_);
    let cos = fh.dot(&lh).clamp(-1.0, 1.0);
    let sigma = if lh.cross(&fh).dot(axis) < 0.0 {
        1.0
    } else {
        -1.0
    };
    let d = -l + fh * l.dot(&fh);
    Some((sigma * cos.acos(), d.norm()))
}

/// Inertia of a body set (world spatial inertia) about the line through `p` along the
/// unit vector `a`: `aᵀ I_O a − 2 (h × a)·(p × a) + m |p × a|²`.
#[must_use]
pub fn inertia_about_axis(set: &Inertia, p: &Vector3<f64>, a: &Vector3<f64>) -> f64 {
    let pa = p.cross(a);
    let ha = set.first_moment().cross(a);
    a.dot(&(set.inertia_about_origin() * a)) - 2.0 * ha.dot(&pa) + set.mass() * pa.norm_squared()
}

/// Measures of one edge.
fn edge_measures(
    w: &GravitoInertialWrench,
    e: &Edge,
    zmp: Option<&Vector3<f64>>,
    set: &Inertia,
) -> EdgeMeasures {
    let a = &e.axis;
    let c = &w.com;
    let f_r = &w.force;
    let n_r = &w.moment_about_com;
    let zmp_distance = zmp.map(|p| e.inward.dot(&(p - e.from)));
    // Force-Angle (Papadopoulos & Rey): l_i = P_i (p_i − p_c), f_i = P_i f_r,
    // n_i = (a aᵀ) n_r, f_ni = l̂ × n_i / |l_i|.
    let rel = e.from - c;
    let l = rel - a * a.dot(&rel);
    let f_i = f_r - a * a.dot(f_r);
    let n_i = a * a.dot(n_r);
    let ln = l.norm();
    let f_ni = if ln > 0.0 {
        (l / ln).cross(&n_i) / ln
    } else {
        Vector3::zeros()
    };
    let fr_norm = f_r.norm();
    let floor = VANISHING_PER_KG * w.mass;
    let scale = fr_norm + if ln > 0.0 { n_i.norm() / ln } else { 0.0 };
    let with = force_angle(a, &l, &(f_i + f_ni), (VANISHING * scale).max(floor));
    let without = force_angle(a, &l, &f_i, (VANISHING * fr_norm).max(floor));
    // Moment-Height: M_i = a_i · M_gi(p_i), I_i of the body set about axis i.
    let moment = a.dot(&w.moment_about(&e.from));
    let inertia = inertia_about_axis(set, &e.from, a);
    EdgeMeasures {
        zmp_distance,
        force_angle: with.map(|(t, _)| t),
        force_angle_no_couple: without.map(|(t, _)| t),
        force_angle_beta: with.map(|(t, d)| t * d * fr_norm),
        lever: with.map(|(_, d)| d),
        moment,
        inertia,
        mhs: (inertia > 0.0).then(|| moment / inertia),
    }
}

fn min_opt(acc: Option<f64>, x: Option<f64>) -> Option<f64> {
    match (acc, x) {
        (Some(a), Some(b)) => Some(a.min(b)),
        (None, b) => b,
        (a, None) => a,
    }
}

/// Evaluates every measure of wrench `w` over `support`, with the Moment-Height inertia
/// of the body set `set` (world spatial inertia), into `out` (allocation-free once `out`
/// has held as many edges).
pub fn evaluate_measures(
    w: &GravitoInertialWrench,
    support: &SupportPolygon,
    set: &Inertia,
    out: &mut StabilityReport,
) {
    let zmp = zero_moment_point(w, support.ground_z());
    out.zmp = zmp;
    out.edges.clear();
    out.zmp_margin = None;
    out.zmp_critical_edge = None;
    out.force_angle_min = None;
    out.force_angle_beta_min = None;
    out.mhs_min = None;
    for i in 0..support.len() {
        let m = edge_measures(w, &support.edge(i), zmp.as_ref(), set);
        if let Some(s) = m.zmp_distance
            && out.zmp_margin.is_none_or(|best| s < best)
        {
            out.zmp_margin = Some(s);
            out.zmp_critical_edge = Some(i);
        }
        out.force_angle_min = min_opt(out.force_angle_min, m.force_angle);
        out.force_angle_beta_min = min_opt(out.force_angle_beta_min, m.force_angle_beta);
        out.mhs_min = min_opt(out.mhs_min, m.mhs);
        out.edges.push(m);
    }
    out.force_angle_alpha = out.force_angle_min.map(|t| t * w.force.norm());
    out.stable = out.zmp_margin.is_some_and(|s| s > 0.0);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Theory 1.8 item 7: with the moment couple, the Force-Angle of an axis crosses zero
    /// exactly where the ZMP crosses that edge, as the couple carries the wrench's moment
    /// about the CoM into the effective force. A 10 kg body with its CoM at (0.1, 0, 0.8)
    /// on the square support [−0.5, 0.5]², standing still, with a pitch moment τ about its
    /// CoM: statics by hand put the ZMP at x = 0.1 + τ / (m g), on the edge x = 0.5 at
    /// τ = 0.4 m g. Without the couple the angle ignores τ (atan(0.4 / 0.8) throughout).
    #[test]
    fn force_angle_with_the_couple_vanishes_where_the_zmp_crosses_the_edge() {
        let (m, g) = (10.0, 9.81);
        let com = Vector3::new(0.1, 0.0, 0.8);
        let square = [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)]
            .map(|(x, y)| nalgebra::Vector2::new(x, y));
        let support = SupportPolygon::from_points(&square).unwrap();
        let front = (0..support.len())
            .find(|&i| {
                let e = support.edge(i);
                e.from.x == 0.5 && e.to.x == 0.5
            })
            .expect("the square has the edge x = 0.5");
        let set = Inertia::point_mass(m, com);
        let threshold = 0.4 * m * g;
        let mut out = StabilityReport::default();
        for f in [0.0, 0.5, 0.99, 1.0, 1.01, 1.5] {
            let tau = f * threshold;
            let w = GravitoInertialWrench {
                mass: m,
                com,
                force: Vector3::new(0.0, 0.0, -m * g),
                moment_about_com: Vector3::new(0.0, tau, 0.0),
            };
            evaluate_measures(&w, &support, &set, &mut out);
            let zmp = out.zmp.expect("the body presses on the ground");
            assert!((zmp.x - (0.1 + tau / (m * g))).abs() < 1e-12, "ZMP {zmp:?}");
            let e = &out.edges[front];
            let (theta, no_couple) = (e.force_angle.unwrap(), e.force_angle_no_couple.unwrap());
            assert!((no_couple - 0.5f64.atan()).abs() < 1e-12, "{no_couple}");
            let s = e.zmp_distance.unwrap();
            if f == 1.0 {
                assert!(theta.abs() < 1e-6 && s.abs() < 1e-12, "θ {theta}, s {s}");
            } else {
                // same side of the edge as the ZMP, and as the moment about the axis
                assert_eq!(theta > 0.0, s > 0.0, "τ = {tau}: θ {theta}, s {s}");
                assert_eq!(e.moment > 0.0, s > 0.0, "τ = {tau}: M {}", e.moment);
            }
        }
    }

    #[test]
    fn axis_inertia_matches_the_point_mass_formula() {
        let set = Inertia::point_mass(3.0, Vector3::new(0.2, 0.5, 0.9))
            + Inertia::point_mass(2.0, Vector3::new(-0.4, 0.1, 0.3));
        let p = Vector3::new(0.5, -0.3, 0.0);
        let a = Vector3::new(0.6, 0.8, 0.0);
        let direct = |m: f64, r: Vector3<f64>| m * a.cross(&(r - p)).norm_squared();
        let want =
            direct(3.0, Vector3::new(0.2, 0.5, 0.9)) + direct(2.0, Vector3::new(-0.4, 0.1, 0.3));
        assert!((inertia_about_axis(&set, &p, &a) - want).abs() < 1e-13);
    }
}

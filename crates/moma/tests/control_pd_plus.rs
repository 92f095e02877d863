//! PD+ (the chapter's law 5.122 in corrected form) on a planar 2R arm in task space,
//! closed loop: with the Christoffel-consistent C_x (Λ̇ − 2 C_x skew) W decreases at
//! −ėᵀ K_d ė; with a deliberately non-skew C_x' (same C_x' ẋ, so the same task model,
//! but Λ̇ − 2 C_x' not skew) the rate of W is the corrected
//! `−ėᵀ K_d ė + ėᵀ(½ Λ̇ − C_x') ė` — the ½ ėᵀ Λ̇ ė term the chapter drops matters — and
//! W rises, which the Lyapunov monitor reports with its time (theory notes 5.2, 5.7 item 4).

use moma::control::lyapunov::LyapunovMonitor;
use moma::control::task::pd_plus;
use moma::ode::{AdaptiveOptions, Dop853, OdeSystem};
use nalgebra::{Matrix2, Vector2};

/// Point masses m1 (elbow), m2 (tip), links a1, a2, gravity −y (theory notes 5.6).
const M1: f64 = 2.0;
const M2: f64 = 1.0;
const A1: f64 = 0.6;
const A2: f64 = 0.5;
const G: f64 = 9.81;

fn mass(q: &Vector2<f64>) -> Matrix2<f64> {
    let c2 = q[1].cos();
    let m12 = M2 * A2 * A2 + M2 * A1 * A2 * c2;
    Matrix2::new(
        (M1 + M2) * A1 * A1 + M2 * A2 * A2 + 2.0 * M2 * A1 * A2 * c2,
        m12,
        m12,
        M2 * A2 * A2,
    )
}

fn coriolis(q: &Vector2<f64>, qd: &Vector2<f64>) -> Matrix2<f64> {
    let h = -M2 * A1 * A2 * q[1].sin();
    Matrix2::new(h * qd[1], h * (qd[0] + qd[1]), -h * qd[0], 0.0)
}

fn gravity(q: &Vector2<f64>) -> Vector2<f64> {
    let (c1, c12) = (q[0].cos(), (q[0] + q[1]).cos());
    Vector2::new(
        (M1 + M2) * G * A1 * c1 + M2 * G * A2 * c12,
        M2 * G * A2 * c12,
    )
}

fn tip(q: &Vector2<f64>) -> Vector2<f64> {
    let (a, b) = (q[0], q[0] + q[1]);
    Vector2::new(A1 * a.cos() + A2 * b.cos(), A1 * a.sin() + A2 * b.sin())
}

fn jac(q: &Vector2<f64>) -> Matrix2<f64> {
    let (a, b) = (q[0], q[0] + q[1]);
    Matrix2::new(
        -A1 * a.sin() - A2 * b.sin(),
        -A2 * b.sin(),
        A1 * a.cos() + A2 * b.cos(),
        A2 * b.cos(),
    )
}

fn jac_dot(q: &Vector2<f64>, qd: &Vector2<f64>) -> Matrix2<f64> {
    let (a, b) = (q[0], q[0] + q[1]);
    let w = qd[0] + qd[1];
    Matrix2::new(
        -A1 * a.cos() * qd[0] - A2 * b.cos() * w,
        -A2 * b.cos() * w,
        -A1 * a.sin() * qd[0] - A2 * b.sin() * w,
        -A2 * b.sin() * w,
    )
}

/// Λ, the Christoffel-consistent C_x = J⁻ᵀ C_q J⁻¹ − Λ J̇ J⁻¹, and p = J⁻ᵀ g.
fn task_model(q: &Vector2<f64>, qd: &Vector2<f64>) -> (Matrix2<f64>, Matrix2<f64>, Vector2<f64>) {
    let ji = jac(q).try_inverse().unwrap();
    let lam = ji.transpose() * mass(q) * ji;
    let cx = ji.transpose() * coriolis(q, qd) * ji - lam * jac_dot(q, qd) * ji;
    (lam, cx, ji.transpose() * gravity(q))
}

/// The non-skew alternative C_x' = C_x + α ẋ⊥ ẋ⊥ᵀ (ẋ⊥ = (−ẋ₂, ẋ₁)): C_x' ẋ = C_x ẋ, so
/// the task model `Λ ẍ + C_x' ẋ + p = F` is the same, but `Λ̇ − 2 C_x'` is not skew.
fn skewed(cx: &Matrix2<f64>, xdot: &Vector2<f64>, alpha: f64) -> Matrix2<f64> {
    let w = Vector2::new(-xdot[1], xdot[0]);
    cx + alpha * w * w.transpose()
}

fn desired(t: f64) -> (Vector2<f64>, Vector2<f64>, Vector2<f64>) {
    let (c, r, w) = (Vector2::new(0.5, 0.6), 0.15, 1.5);
    let (s, co) = (w * t).sin_cos();
    (
        c + r * Vector2::new(co, s),
        r * w * Vector2::new(-s, co),
        -r * w * w * Vector2::new(co, s),
    )
}

struct PdPlusLoop {
    alpha: f64,
    kp: Matrix2<f64>,
    kd: Matrix2<f64>,
}

impl PdPlusLoop {
    fn errors(q: &Vector2<f64>, qd: &Vector2<f64>, t: f64) -> (Vector2<f64>, Vector2<f64>) {
        let (xd, vd, _) = desired(t);
        (tip(q) - xd, jac(q) * qd - vd)
    }

    fn w(&self, q: &Vector2<f64>, qd: &Vector2<f64>, t: f64) -> f64 {
        let (e, ed) = Self::errors(q, qd, t);
        let (lam, _, _) = task_model(q, qd);
        0.5 * ed.dot(&(lam * ed)) + 0.5 * e.dot(&(self.kp * e))
    }

    /// The law's C_x at (q, q̇).
    fn cx(&self, q: &Vector2<f64>, qd: &Vector2<f64>) -> Matrix2<f64> {
        let (_, cx, _) = task_model(q, qd);
        skewed(&cx, &(jac(q) * qd), self.alpha)
    }
}

impl OdeSystem for PdPlusLoop {
    fn dim(&self) -> usize {
        4
    }
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> moma::Result<()> {
        let (q, qd) = (Vector2::new(x[0], x[1]), Vector2::new(x[2], x[3]));
        let (_, vd, ad) = desired(t);
        let (e, ed) = Self::errors(&q, &qd, t);
        let (lam, _, p) = task_model(&q, &qd);
        let (f, _) = pd_plus(
            &lam,
            &self.cx(&q, &qd),
            &p,
            &e,
            &ed,
            &vd,
            &ad,
            &self.kp,
            &self.kd,
        );
        let tau = jac(&q).transpose() * f;
        let qdd = mass(&q).try_inverse().unwrap() * (tau - coriolis(&q, &qd) * qd - gravity(&q));
        dx.copy_from_slice(&[qd[0], qd[1], qdd[0], qdd[1]]);
        Ok(())
    }
}

/// Runs the loop and returns the monitor plus the largest gaps between the numerical
/// rate of W and (corrected formula, formula without ½ ėᵀ Λ̇ ė).
fn run(alpha: f64) -> (moma::control::lyapunov::LyapunovReport, f64, f64) {
    let mut sys = PdPlusLoop {
        alpha,
        kp: Matrix2::new(30.0, 0.0, 0.0, 30.0),
        kd: Matrix2::new(2.0, 0.0, 0.0, 2.0),
    };
    let x0 = [0.5, 1.2, 0.8, -1.5];
    let times: Vec<f64> = (0..=200).map(|k| 0.01 * f64::from(k)).collect();
    let mut dp = Dop853::new(4, AdaptiveOptions::with_tolerance(1e-12)).unwrap();
    let rows = dp.solve_at(&mut sys, 0.0, &x0, &times).unwrap();
    let mut mon = LyapunovMonitor::with_capacity(times.len(), 1e-12);
    let (mut gap_corrected, mut gap_chapter) = (0.0f64, 0.0f64);
    let h = 1e-6;
    for (r, &t) in rows.iter().zip(&times) {
        let (q, qd) = (Vector2::new(r[0], r[1]), Vector2::new(r[2], r[3]));
        let (_, ed) = PdPlusLoop::errors(&q, &qd, t);
        let cx = sys.cx(&q, &qd);
        // Λ̇ along the motion, and the numerical Ẇ, by central differences of the flow
        let mut d = [0.0; 4];
        sys.rhs(t, r, &mut d).unwrap();
        let step = |s: f64| -> (Vector2<f64>, Vector2<f64>) {
            (
                Vector2::new(r[0] + s * d[0], r[1] + s * d[1]),
                Vector2::new(r[2] + s * d[2], r[3] + s * d[3]),
            )
        };
        let ((qp, qdp), (qm, qdm)) = (step(h), step(-h));
        let lam_dot = (task_model(&qp, &qdp).0 - task_model(&qm, &qdm).0) / (2.0 * h);
        let w_dot = (sys.w(&qp, &qdp, t + h) - sys.w(&qm, &qdm, t - h)) / (2.0 * h);
        let dissipation = -ed.dot(&(sys.kd * ed));
        let corrected = dissipation + ed.dot(&((0.5 * lam_dot - cx) * ed));
        let chapter = dissipation - ed.dot(&(cx * ed));
        let scale = 1.0 + w_dot.abs();
        gap_corrected = gap_corrected.max((w_dot - corrected).abs() / scale);
        gap_chapter = gap_chapter.max((w_dot - chapter).abs() / scale);
        mon.record(t, sys.w(&q, &qd, t), Some(corrected));
    }
    (mon.report(), gap_corrected, gap_chapter)
}

#[test]
fn christoffel_cx_is_skew_consistent_and_w_decreases() {
    let (rep, gap_corrected, _) = run(0.0);
    assert!(gap_corrected < 1e-6, "{gap_corrected}");
    assert!(rep.monotone(), "{:?}", rep.violations);
    assert!(rep.v_last < 0.5 * rep.v_first, "{rep:?}");
    // Λ̇ − 2 C_x is skew at random states
    for k in 0..20 {
        let f = |i: u32| ((f64::from(k * 5 + i) * 0.618_033_988_7).fract() - 0.5) * 2.0;
        let (q, qd) = (
            Vector2::new(0.3 + f(1), 1.0 + 0.5 * f(2)),
            Vector2::new(f(3), f(4)),
        );
        let h = 1e-6;
        let lam_dot =
            (task_model(&(q + h * qd), &qd).0 - task_model(&(q - h * qd), &qd).0) / (2.0 * h);
        let s = lam_dot - 2.0 * task_model(&q, &qd).1;
        assert!((s + s.transpose()).norm() < 1e-7 * (1.0 + s.norm()), "{s}");
    }
}

#[test]
fn non_skew_cx_needs_the_half_lambda_dot_term_and_breaks_monotonicity() {
    let (rep, gap_corrected, gap_chapter) = run(-400.0);
    // the corrected rate (with ½ ėᵀ Λ̇ ė) is what the run shows; the chapter's is not
    assert!(gap_corrected < 1e-6, "corrected: {gap_corrected}");
    assert!(gap_chapter > 1e-2, "chapter: {gap_chapter}");
    // and W rises: the monitor reports when
    assert!(!rep.monotone(), "{rep:?}");
    assert!(rep.violations[0].t > 0.0);
    // W ends above where it started, and the integral of the corrected rate follows it
    // (trapezoidal rule on 10 ms samples: its quadrature error only)
    assert!(rep.v_last > rep.v_first, "{rep:?}");
    assert!(
        rep.max_integral_error.unwrap() < 1e-2 * rep.v_first,
        "{:?}",
        rep.max_integral_error
    );
}

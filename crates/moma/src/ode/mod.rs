//! ODE integrators: fixed-step RK4, adaptive Dormand–Prince 5(4) and DOP853.
//!
//! Both work on any [`OdeSystem`] `ẋ = f(t, x)` of dimension `n`, allocate their stage
//! buffers once (in `new`) and never per step. The right-hand side returns a
//! [`Result`], so a singular mass matrix or other numerical trouble inside `f` stops the
//! integration with that error. Non-finite states and states whose magnitude exceeds
//! [`AdaptiveOptions::blowup`] are reported as [`Error::Numerical`] with the time.
//! The adaptive driver lands exactly on requested output times, keeps step statistics
//! ([`StepStats`]), reports a step-size underflow and stops at a step budget.

use crate::error::{Error, Result};

/// A first-order ODE system `ẋ = f(t, x)`.
pub trait OdeSystem {
    /// The state dimension `n`.
    fn dim(&self) -> usize;
    /// Writes `f(t, x)` into `dx` (both of length [`OdeSystem::dim`]).
    fn rhs(&mut self, t: f64, x: &[f64], dx: &mut [f64]) -> Result<()>;
}

/// Step statistics of an integrator (cumulative since creation or the last reset).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct StepStats {
    /// Accepted steps.
    pub accepted: usize,
    /// Rejected steps (adaptive integrators only).
    pub rejected: usize,
    /// Right-hand-side evaluations.
    pub rhs_evals: usize,
}

fn check_state(t: f64, x: &[f64], blowup: f64) -> Result<()> {
    for (i, xi) in x.iter().enumerate() {
        if !xi.is_finite() {
            return Err(Error::Numerical {
                t,
                message: format!("state component {i} is not finite"),
            });
        }
        if xi.abs() > blowup {
            return Err(Error::Numerical {
                t,
                message: format!(
                    "state component {i} = {xi:e} exceeds the blow-up bound {blowup:e}"
                ),
            });
        }
    }
    Ok(())
}

fn check_dim(sys: &impl OdeSystem, n: usize, x: &[f64]) -> Result<()> {
    if sys.dim() != n || x.len() != n {
        return Err(Error::WrongLength {
            field: "ODE state".into(),
            expected: n,
            got: if sys.dim() != n { sys.dim() } else { x.len() },
        });
    }
    Ok(())
}

/// Classical fourth-order Runge–Kutta with a fixed step.
#[doc(alias = "RK4")]
#[derive(Clone, Debug)]
pub struct Rk4 {
    k1: Vec<f64>,
    k2: Vec<f64>,
    k3: Vec<f64>,
    k4: Vec<f64>,
    tmp: Vec<f64>,
    /// Blow-up bound on |x_i| (default 1e12).
    pub blowup: f64,
    /// Statistics.
    pub stats: StepStats,
}

impl Rk4 {
    /// Allocates the stage buffers for a system of dimension `n`.
    pub fn new(n: usize) -> Self {
        Rk4 {
            k1: vec![0.0; n],
            k2: vec![0.0; n],
            k3: vec![0.0; n],
            k4: vec![0.0; n],
            tmp: vec![0.0; n],
            blowup: 1e12,
            stats: StepStats::default(),
        }
    }

    /// One step of size `h` from `(t, x)`; `x` is overwritten with the state at `t + h`.
    pub fn step<S: OdeSystem>(&mut self, sys: &mut S, t: f64, x: &mut [f64], h: f64) -> Result<()> {
        check_dim(sys, self.k1.len(), x)?;
        sys.rhs(t, x, &mut self.k1)?;
        self.stats.rhs_evals += 1;
        self.finish_step(sys, t, x, h)
    }

    /// One step of size `h` from `(t, x)` whose first stage `ẋ(t, x)` the caller has
    /// already evaluated (`dx`, e.g. from the dynamics a controller computed at the same
    /// state and input): three evaluations of `sys` instead of four, the same result as
    /// [`Rk4::step`] when `dx` equals `sys.rhs(t, x)`.
    ///
    /// # Errors
    /// As [`Rk4::step`]; [`Error::WrongLength`] when `dx` has the wrong length.
    pub fn step_from_derivative<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: f64,
        x: &mut [f64],
        dx: &[f64],
        h: f64,
    ) -> Result<()> {
        check_dim(sys, self.k1.len(), x)?;
        check_dim(sys, self.k1.len(), dx)?;
        self.k1.copy_from_slice(dx);
        self.finish_step(sys, t, x, h)
    }

    /// Stages 2 to 4 and the update, from the first stage in `k1`.
    fn finish_step<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: f64,
        x: &mut [f64],
        h: f64,
    ) -> Result<()> {
        let n = self.k1.len();
        for i in 0..n {
            self.tmp[i] = x[i] + 0.5 * h * self.k1[i];
        }
        sys.rhs(t + 0.5 * h, &self.tmp, &mut self.k2)?;
        for i in 0..n {
            self.tmp[i] = x[i] + 0.5 * h * self.k2[i];
        }
        sys.rhs(t + 0.5 * h, &self.tmp, &mut self.k3)?;
        for i in 0..n {
            self.tmp[i] = x[i] + h * self.k3[i];
        }
        sys.rhs(t + h, &self.tmp, &mut self.k4)?;
        for i in 0..n {
            x[i] += h / 6.0 * (self.k1[i] + 2.0 * self.k2[i] + 2.0 * self.k3[i] + self.k4[i]);
        }
        self.stats.accepted += 1;
        self.stats.rhs_evals += 3;
        check_state(t + h, x, self.blowup)
    }

    /// Integrates from `t0` to `t1` with `steps` equal steps, overwriting `x`.
    pub fn integrate<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t0: f64,
        x: &mut [f64],
        t1: f64,
        steps: usize,
    ) -> Result<()> {
        if steps == 0 || !(t1 - t0).is_finite() {
            return Err(Error::invalid(
                "RK4 steps",
                "need at least one step over a finite interval",
            ));
        }
        let h = (t1 - t0) / steps as f64;
        for s in 0..steps {
            self.step(sys, t0 + s as f64 * h, x, h)?;
        }
        Ok(())
    }
}

/// Error-control settings of the adaptive integrator.
#[derive(Clone, Copy, Debug)]
pub struct AdaptiveOptions {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance.
    pub atol: f64,
    /// First step size; `None` picks it automatically (Hairer's heuristic).
    pub initial_step: Option<f64>,
    /// Largest step allowed.
    pub max_step: f64,
    /// Maximum number of steps (accepted + rejected) per call of `integrate_to`, and for
    /// the whole of a `solve_at`.
    pub max_steps: usize,
    /// Blow-up bound on |x_i|.
    pub blowup: f64,
}

impl Default for AdaptiveOptions {
    fn default() -> Self {
        AdaptiveOptions {
            rtol: 1e-9,
            atol: 1e-9,
            initial_step: None,
            max_step: f64::INFINITY,
            max_steps: 1_000_000,
            blowup: 1e12,
        }
    }
}

impl AdaptiveOptions {
    /// Options with `rtol = atol = tol`.
    pub fn with_tolerance(tol: f64) -> Self {
        AdaptiveOptions {
            rtol: tol,
            atol: tol,
            ..Default::default()
        }
    }

    fn validate(&self) -> Result<()> {
        if !(self.rtol > 0.0 && self.rtol.is_finite()) {
            return Err(Error::invalid("rtol", "must be positive and finite"));
        }
        if !(self.atol > 0.0 && self.atol.is_finite()) {
            return Err(Error::invalid("atol", "must be positive and finite"));
        }
        if self.max_step.is_nan() || self.max_step <= 0.0 {
            return Err(Error::invalid("max_step", "must be positive"));
        }
        if let Some(h) = self.initial_step
            && !(h > 0.0 && h.is_finite())
        {
            return Err(Error::invalid(
                "initial_step",
                "must be positive and finite",
            ));
        }
        Ok(())
    }
}

/// The step budget of a whole run that may call `integrate_to` many times (once per
/// recording interval or control tick) and several integrators (one per phase): every
/// step taken, accepted or rejected, fixed or adaptive, is charged to it, so the run
/// as a whole is bounded and not each call.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StepBudget {
    /// Steps allowed in all.
    pub limit: usize,
    /// Steps taken so far.
    pub used: usize,
}

impl StepBudget {
    /// A fresh budget of `limit` steps.
    #[must_use]
    pub fn new(limit: usize) -> Self {
        Self { limit, used: 0 }
    }

    /// Steps still allowed.
    #[must_use]
    pub fn remaining(&self) -> usize {
        self.limit.saturating_sub(self.used)
    }

    /// Charges `n` fixed steps if they fit; `false` (nothing charged) when they do not.
    pub fn take(&mut self, n: usize) -> bool {
        if n <= self.remaining() {
            self.used += n;
            true
        } else {
            false
        }
    }
}

/// The tableau and error estimate of an embedded explicit Runge–Kutta pair with the
/// first-same-as-last property, used by [`AdaptiveRk`].
pub trait EmbeddedMethod {
    /// Number of stage buffers, including the FSAL stage `f(t + h, x_new)`.
    const STAGES: usize;
    /// Order used by the step-size controller (`err ∝ h^(ORDER+1)`).
    const ORDER: i32;
    /// Short name (for diagnostics).
    const NAME: &'static str;
    /// One trial step of size `h` from `(t, x)`: `k[0] = f(t, x)` on entry; writes the
    /// candidate into `y1` and `f(t + h, y1)` into `k[STAGES − 1]`, and returns the error
    /// norm (≤ 1 means acceptable) for the given scaling.
    #[allow(clippy::too_many_arguments)]
    fn try_step<S: OdeSystem>(
        sys: &mut S,
        k: &mut [Vec<f64>],
        y1: &mut [f64],
        tmp: &mut [f64],
        t: f64,
        x: &[f64],
        h: f64,
        opts: &AdaptiveOptions,
    ) -> Result<f64>;
}

/// Writes `tmp = x + h Σ_j a_j k_j` over the listed `(j, a_j)`.
#[inline]
fn combine(tmp: &mut [f64], x: &[f64], h: f64, k: &[Vec<f64>], coeffs: &[(usize, f64)]) {
    for i in 0..x.len() {
        let mut s = 0.0;
        for &(j, a) in coeffs {
            s += a * k[j][i];
        }
        tmp[i] = x[i] + h * s;
    }
}

/// Evaluates the stages `1..=last_stage` of an explicit tableau given as coefficient lists.
fn stages<S: OdeSystem>(
    sys: &mut S,
    k: &mut [Vec<f64>],
    tmp: &mut [f64],
    t: f64,
    x: &[f64],
    h: f64,
    c: &[f64],
    a: &[&[(usize, f64)]],
) -> Result<()> {
    for s in 1..a.len() {
        combine(tmp, x, h, k, a[s]);
        let (_, rest) = k.split_at_mut(s);
        sys.rhs(t + c[s] * h, tmp, &mut rest[0])?;
    }
    Ok(())
}

/// Dormand–Prince 5(4) (Dormand & Prince 1980; Hairer, Nørsett & Wanner, *Solving ODEs I*,
/// table II.5.2): 7 stages with FSAL, 5th-order solution propagated.
#[derive(Clone, Copy, Debug)]
pub struct Dp45Method;

const DP45_C: [f64; 7] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];
const DP45_A: [&[(usize, f64)]; 7] = [
    &[],
    &[(0, 1.0 / 5.0)],
    &[(0, 3.0 / 40.0), (1, 9.0 / 40.0)],
    &[(0, 44.0 / 45.0), (1, -56.0 / 15.0), (2, 32.0 / 9.0)],
    &[
        (0, 19372.0 / 6561.0),
        (1, -25360.0 / 2187.0),
        (2, 64448.0 / 6561.0),
        (3, -212.0 / 729.0),
    ],
    &[
        (0, 9017.0 / 3168.0),
        (1, -355.0 / 33.0),
        (2, 46732.0 / 5247.0),
        (3, 49.0 / 176.0),
        (4, -5103.0 / 18656.0),
    ],
    &[],
];
const DP45_B: [(usize, f64); 5] = [
    (0, 35.0 / 384.0),
    (2, 500.0 / 1113.0),
    (3, 125.0 / 192.0),
    (4, -2187.0 / 6784.0),
    (5, 11.0 / 84.0),
];
// E = b(5th) − b̂(4th)
const DP45_E: [(usize, f64); 6] = [
    (0, 71.0 / 57600.0),
    (2, -71.0 / 16695.0),
    (3, 71.0 / 1920.0),
    (4, -17253.0 / 339200.0),
    (5, 22.0 / 525.0),
    (6, -1.0 / 40.0),
];

impl EmbeddedMethod for Dp45Method {
    const STAGES: usize = 7;
    const ORDER: i32 = 4;
    const NAME: &'static str = "Dormand-Prince 5(4)";
    fn try_step<S: OdeSystem>(
        sys: &mut S,
        k: &mut [Vec<f64>],
        y1: &mut [f64],
        tmp: &mut [f64],
        t: f64,
        x: &[f64],
        h: f64,
        opts: &AdaptiveOptions,
    ) -> Result<f64> {
        stages(sys, k, tmp, t, x, h, &DP45_C, &DP45_A[..6])?;
        combine(y1, x, h, k, &DP45_B);
        sys.rhs(t + h, y1, &mut k[6])?;
        let n = x.len();
        let mut acc = 0.0;
        for i in 0..n {
            let mut e = 0.0;
            for &(j, c) in &DP45_E {
                e += c * k[j][i];
            }
            let sc = opts.atol + opts.rtol * x[i].abs().max(y1[i].abs());
            acc += (h * e / sc).powi(2);
        }
        Ok((acc / n.max(1) as f64).sqrt())
    }
}

/// DOP853: the explicit Runge–Kutta method of order 8 by Dormand & Prince with Hairer's
/// combined 5th/3rd-order error estimator (Hairer, Nørsett & Wanner, *Solving ODEs I*,
/// §II.10; coefficients of the published `dop853` code): 12 stages plus FSAL.
#[derive(Clone, Copy, Debug)]
pub struct Dop853Method;

#[allow(clippy::excessive_precision)] // the published digits are kept verbatim
const DOP853_C: [f64; 12] = [
    0.0,
    0.526001519587677318785587544488e-01,
    0.789002279381515978178381316732e-01,
    0.118350341907227396726757197510,
    0.281649658092772603273242802490,
    0.333333333333333333333333333333,
    0.25,
    0.307692307692307692307692307692,
    0.651282051282051282051282051282,
    0.6,
    0.857142857142857142857142857142,
    1.0,
];
#[allow(clippy::excessive_precision)] // the published digits are kept verbatim
const DOP853_A: [&[(usize, f64)]; 12] = [
    &[],
    &[(0, 5.26001519587677318785587544488e-2)],
    &[
        (0, 1.97250569845378994544595329183e-2),
        (1, 5.91751709536136983633785987549e-2),
    ],
    &[
        (0, 2.95875854768068491816892993775e-2),
        (2, 8.87627564304205475450678981324e-2),
    ],
    &[
        (0, 2.41365134159266685502369798665e-1),
        (2, -8.84549479328286085344864962717e-1),
        (3, 9.24834003261792003115737966543e-1),
    ],
    &[
        (0, 3.7037037037037037037037037037e-2),
        (3, 1.70828608729473871279604482173e-1),
        (4, 1.25467687566822425016691814123e-1),
    ],
    &[
        (0, 3.7109375e-2),
        (3, 1.70252211019544039314978060272e-1),
        (4, 6.02165389804559606850219397283e-2),
        (5, -1.7578125e-2),
    ],
    &[
        (0, 3.70920001185047927108779319836e-2),
        (3, 1.70383925712239993810214054705e-1),
        (4, 1.07262030446373284651809199168e-1),
        (5, -1.53194377486244017527936158236e-2),
        (6, 8.27378916381402288758473766002e-3),
    ],
    &[
        (0, 6.24110958716075717114429577812e-1),
        (3, -3.36089262944694129406857109825),
        (4, -8.68219346841726006818189891453e-1),
        (5, 2.75920996994467083049415600797e1),
        (6, 2.01540675504778934086186788979e1),
        (7, -4.34898841810699588477366255144e1),
    ],
    &[
        (0, 4.77662536438264365890433908527e-1),
        (3, -2.48811461997166764192642586468),
        (4, -5.90290826836842996371446475743e-1),
        (5, 2.12300514481811942347288949897e1),
        (6, 1.52792336328824235832596922938e1),
        (7, -3.32882109689848629194453265587e1),
        (8, -2.03312017085086261358222928593e-2),
    ],
    &[
        (0, -9.3714243008598732571704021658e-1),
        (3, 5.18637242884406370830023853209),
        (4, 1.09143734899672957818500254654),
        (5, -8.14978701074692612513997267357),
        (6, -1.85200656599969598641566180701e1),
        (7, 2.27394870993505042818970056734e1),
        (8, 2.49360555267965238987089396762),
        (9, -3.0467644718982195003823669022),
    ],
    &[
        (0, 2.27331014751653820792359768449),
        (3, -1.05344954667372501984066689879e1),
        (4, -2.00087205822486249909675718444),
        (5, -1.79589318631187989172765950534e1),
        (6, 2.79488845294199600508499808837e1),
        (7, -2.85899827713502369474065508674),
        (8, -8.87285693353062954433549289258),
        (9, 1.23605671757943030647266201528e1),
        (10, 6.43392746015763530355970484046e-1),
    ],
];
#[allow(clippy::excessive_precision)] // the published digits are kept verbatim
const DOP853_B: [(usize, f64); 8] = [
    (0, 5.42937341165687622380535766363e-2),
    (5, 4.45031289275240888144113950566),
    (6, 1.89151789931450038304281599044),
    (7, -5.8012039600105847814672114227),
    (8, 3.1116436695781989440891606237e-1),
    (9, -1.52160949662516078556178806805e-1),
    (10, 2.01365400804030348374776537501e-1),
    (11, 4.47106157277725905176885569043e-2),
];
// 3rd-order error weights: b − (b̂3 at stages 0, 8, 11).
#[allow(clippy::excessive_precision)] // the published digits are kept verbatim
const DOP853_E3_CORR: [(usize, f64); 3] = [
    (0, 0.244094488188976377952755905512),
    (8, 0.733846688281611857341361741547),
    (11, 0.220588235294117647058823529412e-1),
];
#[allow(clippy::excessive_precision)] // the published digits are kept verbatim
const DOP853_E5: [(usize, f64); 8] = [
    (0, 0.1312004499419488073250102996e-1),
    (5, -0.1225156446376204440720569753e1),
    (6, -0.4957589496572501915214079952),
    (7, 0.1664377182454986536961530415e1),
    (8, -0.3503288487499736816886487290),
    (9, 0.3341791187130174790297318841),
    (10, 0.8192320648511571246570742613e-1),
    (11, -0.2235530786388629525884427845e-1),
];

impl EmbeddedMethod for Dop853Method {
    const STAGES: usize = 13;
    const ORDER: i32 = 7;
    const NAME: &'static str = "DOP853";
    fn try_step<S: OdeSystem>(
        sys: &mut S,
        k: &mut [Vec<f64>],
        y1: &mut [f64],
        tmp: &mut [f64],
        t: f64,
        x: &[f64],
        h: f64,
        opts: &AdaptiveOptions,
    ) -> Result<f64> {
        stages(sys, k, tmp, t, x, h, &DOP853_C, &DOP853_A)?;
        combine(y1, x, h, k, &DOP853_B);
        sys.rhs(t + h, y1, &mut k[12])?;
        let n = x.len();
        let (mut e5n, mut e3n) = (0.0, 0.0);
        for i in 0..n {
            let sc = opts.atol + opts.rtol * x[i].abs().max(y1[i].abs());
            let mut bsum = 0.0;
            for &(j, b) in &DOP853_B {
                bsum += b * k[j][i];
            }
            let mut e3 = bsum;
            for &(j, c) in &DOP853_E3_CORR {
                e3 -= c * k[j][i];
            }
            let mut e5 = 0.0;
            for &(j, c) in &DOP853_E5 {
                e5 += c * k[j][i];
            }
            e5n += (e5 / sc).powi(2);
            e3n += (e3 / sc).powi(2);
        }
        if e5n == 0.0 && e3n == 0.0 {
            return Ok(0.0);
        }
        let denom = e5n + 0.01 * e3n;
        Ok(h.abs() * e5n / (denom * n.max(1) as f64).sqrt())
    }
}

/// An adaptive embedded Runge–Kutta integrator with error control: local extrapolation
/// (the higher-order solution is propagated), FSAL, error scaled by
/// `atol + rtol·max(|x|, |x_new|)`, step factor `0.9·err^(−1/(ORDER+1))` clamped to
/// [0.2, 5] (accepted) or [0.1, 0.9] (rejected).
///
/// Output at requested times is exact (steps are shortened to land on them), so no
/// interpolation error is added. Buffers are allocated once in `new`.
#[derive(Clone, Debug)]
pub struct AdaptiveRk<M: EmbeddedMethod> {
    /// Error-control settings.
    pub options: AdaptiveOptions,
    k: Vec<Vec<f64>>,
    y1: Vec<f64>,
    tmp: Vec<f64>,
    h: Option<f64>,
    fsal_valid: bool,
    /// Statistics.
    pub stats: StepStats,
    _method: std::marker::PhantomData<M>,
}

/// Adaptive Dormand–Prince 5(4).
#[doc(alias = "DOPRI5")]
#[doc(alias = "RK45")]
pub type DormandPrince45 = AdaptiveRk<Dp45Method>;

/// Adaptive DOP853 (order 8 with a 5(3) error estimator).
#[doc(alias = "DOP853")]
pub type Dop853 = AdaptiveRk<Dop853Method>;

impl<M: EmbeddedMethod> AdaptiveRk<M> {
    /// Allocates the buffers for dimension `n` with the given options.
    pub fn new(n: usize, options: AdaptiveOptions) -> Result<Self> {
        options.validate()?;
        Ok(AdaptiveRk {
            options,
            k: (0..M::STAGES).map(|_| vec![0.0; n]).collect(),
            y1: vec![0.0; n],
            tmp: vec![0.0; n],
            h: options.initial_step,
            fsal_valid: false,
            stats: StepStats::default(),
            _method: std::marker::PhantomData,
        })
    }

    /// Forgets the step-size history and the cached derivative (call before integrating
    /// a new problem, or after changing the state between calls of `integrate_to`).
    pub fn reset(&mut self) {
        self.h = self.options.initial_step;
        self.fsal_valid = false;
        self.stats = StepStats::default();
    }

    /// Forgets only the cached derivative `f(t, x)` and keeps the step-size history and
    /// the statistics: call it when the right-hand side changes between calls of
    /// `integrate_to` (a zero-order-hold input switching at a control tick).
    pub fn invalidate_derivative(&mut self) {
        self.fsal_valid = false;
    }

    /// The step size the controller proposes next (if any step was taken).
    pub fn next_step(&self) -> Option<f64> {
        self.h
    }

    fn scale(&self, a: f64) -> f64 {
        self.options.atol + self.options.rtol * a.abs()
    }

    fn initial_step<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: f64,
        x: &[f64],
        span: f64,
    ) -> Result<f64> {
        let n = x.len();
        let (mut d0, mut d1) = (0.0, 0.0);
        for i in 0..n {
            let sc = self.scale(x[i]);
            d0 += (x[i] / sc).powi(2);
            d1 += (self.k[0][i] / sc).powi(2);
        }
        let nf = n.max(1) as f64;
        let (d0, d1) = ((d0 / nf).sqrt(), (d1 / nf).sqrt());
        let h0 = if d0 < 1e-5 || d1 < 1e-5 {
            1e-6
        } else {
            0.01 * d0 / d1
        };
        let h0 = h0.min(span).min(self.options.max_step);
        for i in 0..n {
            self.tmp[i] = x[i] + h0 * self.k[0][i];
        }
        sys.rhs(t + h0, &self.tmp, &mut self.k[1])?;
        self.stats.rhs_evals += 1;
        let mut d2 = 0.0;
        for i in 0..n {
            let sc = self.scale(x[i]);
            d2 += ((self.k[1][i] - self.k[0][i]) / sc).powi(2);
        }
        let d2 = (d2 / nf).sqrt() / h0;
        let h1 = if d1.max(d2) <= 1e-15 {
            (h0 * 1e-3).max(1e-6)
        } else {
            (0.01 / d1.max(d2)).powf(1.0 / f64::from(M::ORDER + 1))
        };
        Ok((100.0 * h0).min(h1).min(span).min(self.options.max_step))
    }

    /// Integrates from `*t` to `t_end` (≥ `*t`), overwriting `x` and `*t`. The step-size
    /// history and the last derivative are kept between calls (do not modify `x` between
    /// calls without [`AdaptiveRk::reset`]).
    pub fn integrate_to<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
    ) -> Result<()> {
        if self.integrate_within(sys, t, x, t_end, self.options.max_steps)? {
            Ok(())
        } else {
            Err(self.too_many_steps(*t, t_end))
        }
    }

    /// [`AdaptiveRk::integrate_to`] charging every step (accepted or rejected) to
    /// `budget`, the budget of a whole run that may span many calls and integrators;
    /// [`AdaptiveOptions::max_steps`] is not applied. Returns `Ok(false)` when the budget
    /// ran out before `t_end` (`*t` and `x` then hold the last accepted state), so that
    /// the caller can say what ran out in its own terms.
    ///
    /// # Errors
    /// As [`AdaptiveRk::integrate_to`], except the step limit.
    pub fn integrate_to_within<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
        budget: &mut StepBudget,
    ) -> Result<bool> {
        let before = self.stats.accepted + self.stats.rejected;
        let reached = self.integrate_within(sys, t, x, t_end, budget.remaining());
        budget.used += self.stats.accepted + self.stats.rejected - before;
        reached
    }

    fn too_many_steps(&self, t: f64, t_end: f64) -> Error {
        Error::Numerical {
            t,
            message: format!(
                "{}: maximum number of steps ({}) exceeded before t = {t_end}",
                M::NAME,
                self.options.max_steps
            ),
        }
    }

    /// Integrates to `t_end` with at most `limit` steps (accepted + rejected); `Ok(false)`
    /// when the limit is reached first.
    fn integrate_within<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t: &mut f64,
        x: &mut [f64],
        t_end: f64,
        limit: usize,
    ) -> Result<bool> {
        let n = self.y1.len();
        check_dim(sys, n, x)?;
        if !t_end.is_finite() || !t.is_finite() || t_end < *t {
            return Err(Error::invalid(
                "output time",
                format!("must be finite and not before the current time {}", *t),
            ));
        }
        check_state(*t, x, self.options.blowup)?;
        if t_end == *t {
            return Ok(true);
        }
        if !self.fsal_valid {
            sys.rhs(*t, x, &mut self.k[0])?;
            self.stats.rhs_evals += 1;
            self.fsal_valid = true;
        }
        let mut h = match self.h {
            Some(h) => h,
            None => self.initial_step(sys, *t, x, t_end - *t)?,
        };
        let expo = -1.0 / f64::from(M::ORDER + 1);
        let mut steps = 0usize;
        loop {
            let remaining = t_end - *t;
            if remaining <= 0.0 {
                return Ok(true);
            }
            steps += 1;
            if steps > limit {
                return Ok(false);
            }
            h = h.min(self.options.max_step);
            let last = h >= remaining * (1.0 - 1e-12);
            let hs = if last { remaining } else { h };
            if hs <= 16.0 * f64::EPSILON * t.abs().max(1e-300) {
                return Err(Error::Numerical {
                    t: *t,
                    message: format!("{}: step size underflow (h = {hs:e})", M::NAME),
                });
            }
            let err = M::try_step(
                sys,
                &mut self.k,
                &mut self.y1,
                &mut self.tmp,
                *t,
                x,
                hs,
                &self.options,
            )?;
            self.stats.rhs_evals += M::STAGES - 1;
            let err = if err.is_nan() { f64::INFINITY } else { err };
            if err <= 1.0 {
                *t = if last { t_end } else { *t + hs };
                x.copy_from_slice(&self.y1);
                self.k.swap(0, M::STAGES - 1);
                self.stats.accepted += 1;
                check_state(*t, x, self.options.blowup)?;
                let fac = if err == 0.0 {
                    5.0
                } else {
                    (0.9 * err.powf(expo)).clamp(0.2, 5.0)
                };
                // Do not let a short final step shrink the remembered step.
                h = if last { h.max(hs * fac) } else { hs * fac };
                self.h = Some(h);
                if last {
                    return Ok(true);
                }
            } else {
                self.stats.rejected += 1;
                h = if err.is_finite() {
                    hs * (0.9 * err.powf(expo)).clamp(0.1, 0.9)
                } else {
                    hs * 0.1
                };
            }
        }
    }

    /// Integrates from `(t0, x0)` and returns the states at the requested `times`
    /// (non-decreasing, ≥ `t0`), one row per time. `max_steps` bounds the whole solve,
    /// not each output interval.
    pub fn solve_at<S: OdeSystem>(
        &mut self,
        sys: &mut S,
        t0: f64,
        x0: &[f64],
        times: &[f64],
    ) -> Result<Vec<Vec<f64>>> {
        self.reset();
        let mut x = x0.to_vec();
        let mut t = t0;
        let mut out = Vec::with_capacity(times.len());
        for (i, &te) in times.iter().enumerate() {
            if !te.is_finite() || te < t {
                return Err(Error::invalid(
                    format!("t[{i}]"),
                    "output times must be finite, non-decreasing and not before the start",
                ));
            }
            let used = self.stats.accepted + self.stats.rejected;
            let left = self.options.max_steps.saturating_sub(used);
            if !self.integrate_within(sys, &mut t, &mut x, te, left)? {
                return Err(self.too_many_steps(t, te));
            }
            out.push(x.clone());
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Decay;
    impl OdeSystem for Decay {
        fn dim(&self) -> usize {
            1
        }
        fn rhs(&mut self, _t: f64, x: &[f64], dx: &mut [f64]) -> Result<()> {
            dx[0] = -x[0];
            Ok(())
        }
    }

    /// A step from a given first stage is the full step when the stage is the true
    /// derivative, uses one evaluation fewer, and moves with a different stage.
    #[test]
    fn rk4_step_from_derivative_matches_the_full_step() {
        let (mut a, mut b) = (Rk4::new(1), Rk4::new(1));
        let (mut xa, mut xb) = ([1.0], [1.0]);
        for k in 0..10 {
            let t = 0.1 * k as f64;
            a.step(&mut Decay, t, &mut xa, 0.1).unwrap();
            let dx = [-xb[0]];
            b.step_from_derivative(&mut Decay, t, &mut xb, &dx, 0.1)
                .unwrap();
        }
        assert_eq!(xa, xb);
        assert!((xa[0] - (-1.0f64).exp()).abs() < 1e-6);
        assert_eq!((a.stats.rhs_evals, b.stats.rhs_evals), (40, 30));
        let mut xc = [1.0];
        b.step_from_derivative(&mut Decay, 0.0, &mut xc, &[0.0], 0.1)
            .unwrap();
        assert_ne!(xc[0], (-0.1f64).exp());
        assert!(
            b.step_from_derivative(&mut Decay, 0.0, &mut xc, &[0.0, 1.0], 0.1)
                .is_err()
        );
    }

    #[test]
    fn dop853_exponential_decay() {
        let mut dp = Dop853::new(1, AdaptiveOptions::with_tolerance(1e-12)).unwrap();
        let out = dp
            .solve_at(&mut Decay, 0.0, &[1.0], &[0.5, 1.0, 2.0])
            .unwrap();
        for (row, t) in out.iter().zip([0.5f64, 1.0, 2.0]) {
            assert!((row[0] - (-t).exp()).abs() < 1e-13);
        }
    }

    #[test]
    fn a_step_budget_is_charged_across_calls() {
        let mut dp = DormandPrince45::new(1, AdaptiveOptions::with_tolerance(1e-10)).unwrap();
        let mut budget = StepBudget::new(usize::MAX);
        let (mut t, mut x) = (0.0, [1.0]);
        for k in 1..=10 {
            assert!(
                dp.integrate_to_within(&mut Decay, &mut t, &mut x, f64::from(k) * 0.1, &mut budget)
                    .unwrap()
            );
        }
        let all = budget.used;
        assert_eq!(all, dp.stats.accepted + dp.stats.rejected);
        assert!(all > 20, "{all}");
        // half of it: each call needs only a tenth, but the ten calls share it
        dp.reset();
        let mut budget = StepBudget::new(all / 2);
        let (mut t, mut x) = (0.0, [1.0]);
        let mut reached = 0;
        for k in 1..=10 {
            let te = f64::from(k) * 0.1;
            if !dp
                .integrate_to_within(&mut Decay, &mut t, &mut x, te, &mut budget)
                .unwrap()
            {
                break;
            }
            reached = k;
        }
        assert!((3..9).contains(&reached), "{reached}");
        assert_eq!(budget.used, all / 2);
        assert_eq!(budget.remaining(), 0);
        // the state is the last accepted one
        assert!((x[0] - (-t).exp()).abs() < 1e-9);
        assert!(!budget.take(1));
    }

    #[test]
    fn dp45_exponential_decay() {
        let mut dp = DormandPrince45::new(1, AdaptiveOptions::with_tolerance(1e-12)).unwrap();
        let out = dp
            .solve_at(&mut Decay, 0.0, &[1.0], &[0.5, 1.0, 2.0])
            .unwrap();
        for (row, t) in out.iter().zip([0.5f64, 1.0, 2.0]) {
            assert!((row[0] - (-t).exp()).abs() < 1e-11);
        }
    }
}

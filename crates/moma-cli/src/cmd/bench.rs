//! `moma bench ROBOT.urdf --root R [--frame NAME] [--json]`: median nanoseconds per call
//! of the rigid-body algorithms and the derivatives of the dynamics, with the method of the Pinocchio benchmark
//! (`bench/pinocchio/pinocchio_bench.cpp`): 100 seeded random states (q = neutral ⊕ dq,
//! dq ~ π·U(−1, 1), v, a, τ ~ U(−1, 1)); each batch calls the algorithm once per state;
//! WARMUP batches are discarded, then the median per-call time over NBATCH batches is
//! reported (env `NBATCH`, default 300; `WARMUP`, default 30).

use super::common::{load_model, parse_root};
use anyhow::{Context, Result};
use moma::dynamics;
use moma::kinematics::{self, ReferenceFrame};
use moma::multibody::{Data, FrameIndex, Model, RootJoint};
use nalgebra::{DVector, Matrix6xX};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Serialize;
use std::hint::black_box;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `moma bench`.
#[derive(clap::Args)]
pub struct Args {
    /// The robot description (URDF).
    pub urdf: PathBuf,
    /// Root joint: fixed, planar or free-flyer.
    #[arg(long, value_parser = parse_root)]
    pub root: RootJoint,
    /// Frame for the Jacobian benchmark (default: the last link).
    #[arg(long)]
    pub frame: Option<String>,
    /// Label printed as "robot" (default: the URDF robot name).
    #[arg(long)]
    pub label: Option<String>,
    /// Zero gravity (as the Pinocchio benchmark does for free-floating robots).
    #[arg(long)]
    pub zero_gravity: bool,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    /// Also write the JSON report to this file (atomically).
    #[arg(long)]
    pub output: Option<PathBuf>,
}

const NSTATES: usize = 100;

#[derive(Serialize)]
struct Times {
    rnea: f64,
    crba: f64,
    aba: f64,
    fk: f64,
    frame_jacobian: f64,
    nle: f64,
    gravity: f64,
    fk_frames: f64,
    joint_jacobians: f64,
    /// One operational-space update (Λ, J̄, N, F, τ) of the frame, 6 task rows; NaN when
    /// nv < 6.
    osc: f64,
    /// ∂τ/∂q, ∂τ/∂v and H (`dynamics::rnea_derivatives`, Pinocchio's
    /// `computeRNEADerivatives`).
    rnea_derivatives: f64,
    /// ∂q̈/∂q, ∂q̈/∂v and H⁻¹ (`dynamics::aba_derivatives`, Pinocchio's
    /// `computeABADerivatives`); NaN if H was singular at a state.
    aba_derivatives: f64,
}

#[derive(Serialize)]
struct Report {
    robot: String,
    root: String,
    frame: String,
    nq: usize,
    nv: usize,
    nstates: usize,
    nbatch: usize,
    warmup: usize,
    median_ns: Times,
    min_ns: Times,
}

fn env_usize(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

/// (median, min) per-call nanoseconds of `f(i)` over batches of `NSTATES` calls.
fn time(nbatch: usize, warmup: usize, mut f: impl FnMut(usize) -> f64) -> (f64, f64) {
    let mut per_call = Vec::with_capacity(nbatch);
    let mut sink = 0.0;
    for b in 0..warmup + nbatch {
        let t0 = Instant::now();
        for i in 0..NSTATES {
            sink += f(i);
        }
        let dt = t0.elapsed().as_secs_f64() * 1e9 / NSTATES as f64;
        if b >= warmup {
            per_call.push(dt);
        }
    }
    black_box(sink);
    per_call.sort_by(f64::total_cmp);
    (per_call[per_call.len() / 2], per_call[0])
}

/// (median, min) per-call nanoseconds of each algorithm.
struct Measured {
    rnea: (f64, f64),
    crba: (f64, f64),
    aba: (f64, f64),
    fk: (f64, f64),
    frame_jacobian: (f64, f64),
    nle: (f64, f64),
    gravity: (f64, f64),
    fk_frames: (f64, f64),
    joint_jacobians: (f64, f64),
    osc: (f64, f64),
    rnea_derivatives: (f64, f64),
    aba_derivatives: (f64, f64),
}

impl Measured {
    /// One figure (`f`: the median or the min) of each algorithm.
    fn pick(&self, f: fn(&(f64, f64)) -> f64) -> Times {
        Times {
            rnea: f(&self.rnea),
            crba: f(&self.crba),
            aba: f(&self.aba),
            fk: f(&self.fk),
            frame_jacobian: f(&self.frame_jacobian),
            nle: f(&self.nle),
            gravity: f(&self.gravity),
            fk_frames: f(&self.fk_frames),
            joint_jacobians: f(&self.joint_jacobians),
            osc: f(&self.osc),
            rnea_derivatives: f(&self.rnea_derivatives),
            aba_derivatives: f(&self.aba_derivatives),
        }
    }
}

/// Runs `moma bench`.
pub fn run(args: Args) -> Result<()> {
    let (model, fid) = bench_model(&args)?;
    let nbatch = env_usize("NBATCH", 300).max(1);
    // at least one timed batch
    let warmup = env_usize("WARMUP", 30).min(nbatch - 1);
    let measured = measure(&model, fid, nbatch, warmup);
    let report = Report {
        robot: args.label.clone().unwrap_or_else(|| model.name.clone()),
        root: model.root.to_string(),
        frame: model.frames[fid.0].name.clone(),
        nq: model.nq,
        nv: model.nv,
        nstates: NSTATES,
        nbatch,
        warmup,
        median_ns: measured.pick(|x| x.0),
        min_ns: measured.pick(|x| x.1),
    };
    print_report(&args, &report)
}

/// The model of `moma bench` (gravity zeroed on request) and the Jacobian's frame; an
/// error for an unknown frame or a model without degrees of freedom.
fn bench_model(args: &Args) -> Result<(Model, FrameIndex)> {
    let mut model = load_model(&args.urdf, args.root)?;
    if args.zero_gravity {
        model.gravity = nalgebra::Vector3::zeros();
    }
    let fid = match &args.frame {
        Some(name) => model
            .frame_id(name)
            .with_context(|| format!("{}: --frame", args.urdf.display()))?,
        None => model.last_link_frame(),
    };
    if model.nv == 0 {
        anyhow::bail!(
            "{}: the model has no degrees of freedom: nothing to benchmark",
            args.urdf.display()
        );
    }
    Ok((model, fid))
}

/// Times every algorithm over the seeded random states.
fn measure(model: &Model, fid: FrameIndex, nbatch: usize, warmup: usize) -> Measured {
    let nv = model.nv;
    let [qs, vs, as_, ts] = random_states(model);
    let mut data = Data::new(model);
    let mut jac = Matrix6xX::zeros(nv);
    let m = model;
    let last = model.njoints - 1;
    let rnea = time(nbatch, warmup, |i| {
        dynamics::rnea(m, &mut data, &qs[i], &vs[i], &as_[i])[0]
    });
    let nle = time(nbatch, warmup, |i| {
        dynamics::nonlinear_effects(m, &mut data, &qs[i], &vs[i])[0]
    });
    let gravity = time(nbatch, warmup, |i| {
        dynamics::gravity_torque(m, &mut data, &qs[i])[0]
    });
    let crba = time(nbatch, warmup, |i| {
        dynamics::crba(m, &mut data, &qs[i])[(0, 0)]
    });
    let aba = time(nbatch, warmup, |i| {
        dynamics::aba(m, &mut data, &qs[i], &vs[i], &ts[i])[0]
    });
    let fk = time(nbatch, warmup, |i| {
        kinematics::forward_kinematics(m, &mut data, &qs[i]);
        data.world_from_joint[last].translation[0]
    });
    let fk_frames = time(nbatch, warmup, |i| {
        kinematics::frames_forward_kinematics(m, &mut data, &qs[i]);
        data.world_from_frame[fid.0].translation[0]
    });
    let frame_jacobian = time(nbatch, warmup, |i| {
        kinematics::frame_jacobian(
            m,
            &mut data,
            &qs[i],
            fid,
            ReferenceFrame::LocalWorldAligned,
            &mut jac,
        );
        jac[(0, nv - 1)]
    });
    let joint_jacobians = time(nbatch, warmup, |i| {
        kinematics::compute_joint_jacobians(m, &mut data, &qs[i]);
        data.joint_jacobians[(0, nv - 1)]
    });
    let osc = time_osc(m, &mut data, fid, &qs, &vs, &ts, nbatch, warmup);
    let mut dd = dynamics::DerivativeData::new(m);
    let rnea_derivatives = time(nbatch, warmup, |i| {
        dynamics::rnea_derivatives(m, &mut dd, &qs[i], &vs[i], &as_[i]);
        dd.drnea_dq[(0, nv - 1)]
    });
    let aba_derivatives = time(nbatch, warmup, |i| {
        match dynamics::aba_derivatives(m, &mut dd, &qs[i], &vs[i], &ts[i]) {
            Ok(()) => dd.daba_dq[(0, nv - 1)],
            Err(_) => f64::NAN,
        }
    });
    Measured {
        rnea,
        crba,
        aba,
        fk,
        frame_jacobian,
        nle,
        gravity,
        fk_frames,
        joint_jacobians,
        osc,
        rnea_derivatives,
        aba_derivatives,
    }
}

/// One OSC update per state: the same computation as Pinocchio's side of the benchmark
/// (crba, nonLinearEffects, classical acceleration, frame Jacobian, two Cholesky); NaN
/// when nv < 6.
fn time_osc(
    m: &Model,
    data: &mut Data,
    fid: FrameIndex,
    qs: &[DVector<f64>],
    vs: &[DVector<f64>],
    ts: &[DVector<f64>],
    nbatch: usize,
    warmup: usize,
) -> (f64, f64) {
    if m.nv < 6 {
        return (f64::NAN, f64::NAN);
    }
    let mut od = moma::control::osc::OscData::new(m.nv, &[0, 1, 2, 3, 4, 5]);
    let a6 = DVector::from_fn(6, |k, _| 0.1 * (k as f64 + 1.0));
    time(
        nbatch,
        warmup,
        |i| match moma::control::osc::osc_fixed_base(
            m, data, &mut od, fid, &qs[i], &vs[i], &a6, &ts[i],
        ) {
            Ok(()) => od.torque[0],
            Err(_) => f64::NAN,
        },
    )
}

/// The seeded random states of the Pinocchio benchmark: q = neutral ⊕ π·U(−1,1)^nv and
/// v, a, τ ~ U(−1,1).
fn random_states(model: &Model) -> [Vec<DVector<f64>>; 4] {
    let nv = model.nv;
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let q0 = kinematics::neutral(model);
    let mut qs = Vec::new();
    let (mut vs, mut as_, mut ts) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..NSTATES {
        let dq = DVector::from_fn(nv, |_, _| {
            std::f64::consts::PI * rng.random_range(-1.0..1.0)
        });
        let mut q = q0.clone();
        kinematics::integrate(model, &q0, &dq, &mut q);
        qs.push(q);
        vs.push(DVector::from_fn(nv, |_, _| rng.random_range(-1.0..1.0)));
        as_.push(DVector::from_fn(nv, |_, _| rng.random_range(-1.0..1.0)));
        ts.push(DVector::from_fn(nv, |_, _| rng.random_range(-1.0..1.0)));
    }
    [qs, vs, as_, ts]
}

/// Writes `--output`, then prints JSON or the Pinocchio benchmark's line format.
fn print_report(args: &Args, report: &Report) -> Result<()> {
    let (nq, nv, nbatch, warmup) = (report.nq, report.nv, report.nbatch, report.warmup);
    if let Some(p) = &args.output {
        let mut text = serde_json::to_string_pretty(report).context("serialising JSON output")?;
        text.push('\n');
        crate::output::write_all_atomic(&[(p.clone(), text.into_bytes())])?;
    }
    if args.json {
        return crate::output::print_json(report);
    }
    outln!(
        "# moma bench {} (root {}, frame {}, nq {nq}, nv {nv}; {NSTATES} states, {nbatch} batches after {warmup} warm-up)",
        report.robot,
        report.root,
        report.frame
    );
    outln!("# robot algorithm nq nv median_ns min_ns");
    let med = &report.median_ns;
    let min = &report.min_ns;
    for (name, a, b) in [
        ("rnea", med.rnea, min.rnea),
        ("nle", med.nle, min.nle),
        ("gravity", med.gravity, min.gravity),
        ("crba", med.crba, min.crba),
        ("aba", med.aba, min.aba),
        ("fk", med.fk, min.fk),
        ("fk_frames", med.fk_frames, min.fk_frames),
        ("frame_jacobian", med.frame_jacobian, min.frame_jacobian),
        ("joint_jacobians", med.joint_jacobians, min.joint_jacobians),
        ("osc", med.osc, min.osc),
        (
            "rnea_derivatives",
            med.rnea_derivatives,
            min.rnea_derivatives,
        ),
        ("aba_derivatives", med.aba_derivatives, min.aba_derivatives),
    ] {
        outln!("{} {name} {nq} {nv} {a:.1} {b:.1}", report.robot);
    }
    Ok(())
}

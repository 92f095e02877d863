#!/usr/bin/env python3
"""Cross-checks moma's URDF loader and rigid-body algorithms against Pinocchio on every
robot description of example-robot-data.

Not part of the default tests. Needs Pinocchio's Python bindings (`pip install pin==4.1.0`;
the wheel depends on `example-robot-data`, which provides the robots) and release builds
of the `moma` command line and of the `rigid_body_dump` example:
    cargo build --release --locked -p moma-cli
    cargo build --release --locked -p moma --example rigid_body_dump

Usage:
    python bench/xcheck_pinocchio.py [--robots ROBOTS_DIR] [--extra URDF_OR_DIR ...]
        [--filter SUBSTRING] [--random N] [--states N] [--gravity GX,GY,GZ]
        [--tol 1e-9] [--markdown OUT.md] [--json OUT.json]
        [--moma PATH/TO/moma] [--dump PATH/TO/rigid_body_dump]

ROBOTS_DIR defaults to example-robot-data's `robots` folder found next to the installed
Pinocchio (`<prefix>/share/example-robot-data/robots`); every `*.urdf` two levels below it
is checked, plus the `--extra` files (default: the edge cases in `bench/xcheck_urdf/`)
and `--random N` seeded random robot descriptions (random trees with every joint kind,
odd axes, rotated origins and inertials, massless links).
The binaries default to `$CARGO_TARGET_DIR` (or `target`)`/release/`.
Each file is loaded with each root: `fixed` (Pinocchio: no root joint), `planar`
(`pin.JointModelPlanar()`) and `free-flyer` (`pin.JointModelFreeFlyer()`).

For each (URDF, root) the script
  1. loads the file in Pinocchio (`buildModelFromUrdf`, mimic joints independent) and with
     `moma inspect --json`; a refusal by either side is reported with its message;
  2. compares the structure: nq (after the coordinate conversion below), nv, njoints,
     joint names / order / parents / idx_v / type, position limits of bounded
     one-degree-of-freedom joints, velocity and effort limits, total mass, the frame
     list (name, kind, parent joint, in order) and the default end-effector (moma's last
     link must be Pinocchio's last BODY frame);
  3. for N seeded random states (q = neutral ⊕ U(−π, π)^nv, v, a, τ ~ U(−1, 1)), runs
     `rigid_body_dump` and compares RNEA, CRBA, ABA, nonlinear effects, generalised
     gravity, the Coriolis matrix (not for the planar root, whose C differs by the
     coordinate change), CoM, centroidal momentum matrix, kinetic and potential energy,
     and for EVERY frame its placement, its Jacobian, velocity and J̇·q̇ in the three
     reference frames (LOCAL_WORLD_ALIGNED, WORLD, LOCAL), its spatial acceleration for
     the state's a; plus integrate and difference (not for the planar root).
     A massless subtree makes ABA singular: both must then give non-finite values. When
     H(q) is ill-conditioned (iCub: cond(H) up to 4e9), a q̈ beyond the tolerance passes
     if its backward error |H q̈ + h − τ| / (|H| |q̈| + |h| + |τ|) is ≤ 1e-14 and its
     forward error ≤ 100 cond(H) ε (noted in the table).
     A massless model has no CoM (Pinocchio: NaN, moma: the origin, documented).
  4. runs `moma dynamics` (the command line, default frame) on the same states and checks
     that it prints the same numbers as the library (and a unit quaternion of the frame
     rotation); it may refuse only states whose ABA is singular.

Errors are |moma − pinocchio| / max(|pinocchio|, 1) (relative, absolute below 1); a case
passes when every error is ≤ --tol (1e-9).

Conventions (docs/cli.md): moma's planar base is q = [x, y, θ] with world-axes velocity,
Pinocchio's q = [x, y, cos θ, sin θ] with a base-frame velocity v_P = T v,
T = diag(Rᵀ(θ), 1); continuous joints are one angle in moma, [cos, sin] in Pinocchio. So
τ = Tᵀ τ_P, H = Tᵀ H_P T, J = J_P T, A_g = A_g,P T and a = T⁻¹ a_P + Ṫ⁻¹ v_P.

Output: a table (robot, root, status, worst error, message) on standard output and
optionally as Markdown (--markdown) and JSON (--json). Exit status 1 if any case fails
or if moma and Pinocchio disagree on whether a file loads.
"""
import argparse
import glob
import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import pinocchio as pin

ROOTS = ["fixed", "planar", "free-flyer"]

# Files on which moma and Pinocchio knowingly differ, with the reason (status expected
# for every root). "both refuse" needs no entry.
EXPECTED = {
    "romeo_laas_small.urdf": (
        "moma refuses",
        "links 'body', 'LHipPitch_link', 'RHipPitch_link'... have indefinite rotational "
        "inertias (eigenvalue -0.021 kg m2): not a rigid body; Pinocchio loads them unchecked"),
    "edge_floating_joint.urdf": (
        "moma refuses",
        "floating joints inside the URDF are rejected by design, naming the joint "
        "(use the free-flyer root); Pinocchio adds a free-flyer joint"),
    "edge_planar_joint.urdf": (
        "moma refuses",
        "planar joints inside the URDF are rejected by design, naming the joint (use the "
        "planar root); Pinocchio adds a planar joint and ignores its axis"),
    "edge_negative_mass.urdf": (
        "moma refuses", "negative mass: not a rigid body; Pinocchio loads it unchecked"),
    "edge_root_joint_name.urdf": (
        "moma refuses",
        "a URDF joint named 'root_joint' clashes with the planar/free-flyer root joint: moma "
        "refuses those roots naming it; Pinocchio makes two joints of that name"),
    "edge_reversed_limits.urdf": (
        "moma refuses",
        "lower position limit above the upper one: an empty range, rejected naming the joint; "
        "Pinocchio loads it unchecked"),
}
SEED = 20261122

PIN_TYPES = {
    "JointModelRX": "revolute_x",
    "JointModelRY": "revolute_y",
    "JointModelRZ": "revolute_z",
    "JointModelRUBX": "revolute_x",
    "JointModelRUBY": "revolute_y",
    "JointModelRUBZ": "revolute_z",
    "JointModelRevoluteUnaligned": "revolute_unaligned",
    "JointModelRevoluteUnboundedUnaligned": "revolute_unaligned",
    "JointModelPX": "prismatic_x",
    "JointModelPY": "prismatic_y",
    "JointModelPZ": "prismatic_z",
    "JointModelPrismaticUnaligned": "prismatic_unaligned",
    "JointModelPlanar": "planar",
    "JointModelFreeFlyer": "free_flyer",
}

FRAME_KINDS = {
    pin.FrameType.JOINT: "joint",
    pin.FrameType.FIXED_JOINT: "fixed_joint",
    pin.FrameType.BODY: "body",
    pin.FrameType.OP_FRAME: "operational",
    pin.FrameType.SENSOR: "sensor",
}


def default_robots_dir():
    here = os.path.abspath(os.path.dirname(pin.__file__))
    while True:
        cand = os.path.join(here, "share", "example-robot-data", "robots")
        if os.path.isdir(cand):
            return cand
        for sub in ("cmeel.prefix",):
            cand = os.path.join(here, sub, "share", "example-robot-data", "robots")
            if os.path.isdir(cand):
                return cand
        parent = os.path.dirname(here)
        if parent == here:
            sys.exit("cannot find example-robot-data's robots folder; pass --robots")
        here = parent


def target_dir():
    repo = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    return os.environ.get("CARGO_TARGET_DIR", os.path.join(repo, "target"))


class Conv:
    """Pinocchio <-> moma coordinates for one model."""

    def __init__(self, model):
        self.joints = []  # (pin idx_q, moma idx_q, idx_v, nv, kind)
        oq = 0
        for j in range(1, model.njoints):
            jm = model.joints[j]
            sn = jm.shortname()
            if sn == "JointModelPlanar":
                kind, onq = 1, 3
            elif "RUB" in sn or "Unbounded" in sn:
                kind, onq = 2, 1
            else:
                kind, onq = 0, jm.nq
            self.joints.append((jm.idx_q, oq, jm.idx_v, jm.nv, kind))
            oq += onq
        self.nq = oq
        self.nv = model.nv

    def q(self, qp):
        q = np.zeros(self.nq)
        for iq, oq, _, nv, kind in self.joints:
            if kind == 1:
                q[oq:oq + 2] = qp[iq:iq + 2]
                q[oq + 2] = np.arctan2(qp[iq + 3], qp[iq + 2])
            elif kind == 2:
                q[oq] = np.arctan2(qp[iq + 1], qp[iq])
            else:
                n = 7 if nv == 6 else nv
                q[oq:oq + n] = qp[iq:iq + n]
        return q

    def planar(self, q):
        for _, oq, iv, _, kind in self.joints:
            if kind == 1:
                return q[oq + 2], iv
        return None

    def t(self, q):
        t = np.eye(self.nv)
        p = self.planar(q)
        if p is not None:
            th, iv = p
            c, s = np.cos(th), np.sin(th)
            t[iv:iv + 2, iv:iv + 2] = [[c, s], [-s, c]]
        return t

    def acc(self, q, v_p, a_p):
        t = self.t(q)
        a = t.T @ a_p
        p = self.planar(q)
        if p is not None:
            _, iv = p
            v_w = t.T @ v_p
            w = v_p[iv + 2]
            a[iv] += -w * v_w[iv + 1]
            a[iv + 1] += w * v_w[iv]
        return a


def relerr(got, want):
    got = np.asarray(got, dtype=float).ravel()
    want = np.asarray(want, dtype=float).ravel()
    if got.shape != want.shape:
        return float("inf"), "shape %s vs %s" % (got.shape, want.shape)
    if got.size == 0:
        return 0.0, None
    if not np.all(np.isfinite(got)) or not np.all(np.isfinite(want)):
        same = np.array_equal(np.isfinite(got), np.isfinite(want))
        return (0.0 if same and np.allclose(got[np.isfinite(got)], want[np.isfinite(want)])
                else float("inf")), "non-finite"
    err = np.abs(got - want) / np.maximum(np.abs(want), 1.0)
    k = int(np.argmax(err))
    return float(err[k]), "[%d] got %.17g want %.17g" % (k, got[k], want[k])


def run(cmd):
    p = subprocess.run(cmd, capture_output=True, text=True)
    return p.returncode, p.stdout, p.stderr.strip()


def pin_model(urdf, root):
    # urdfdom prints its errors on the C-level standard error: keep them out of the table
    sys.stderr.flush()
    saved = os.dup(2)
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 2)
    try:
        if root == "fixed":
            return pin.buildModelFromUrdf(urdf)
        rj = pin.JointModelPlanar() if root == "planar" else pin.JointModelFreeFlyer()
        return pin.buildModelFromUrdf(urdf, rj)
    finally:
        os.dup2(saved, 2)
        os.close(saved)
        os.close(devnull)


def lim(x):
    return None if x is None else float(x)


class Case:
    def __init__(self, robot, root):
        self.robot, self.root = robot, root
        self.worst = 0.0
        self.worst_what = ""
        self.problems = []
        self.status = "ok"
        self.message = ""
        self.notes = []
        self.nq_nv = ""

    def err(self, what, got, want, tol):
        e, detail = relerr(got, want)
        if e > self.worst:
            self.worst, self.worst_what = e, "%s %s" % (what, detail)
        if e > tol:
            self.problems.append("%s: rel err %.3e %s" % (what, e, detail))

    def mismatch(self, what):
        self.problems.append(what)


def compare_structure(case, model, conv, info):
    if info["nv"] != model.nv:
        case.mismatch("nv: moma %d, pinocchio %d" % (info["nv"], model.nv))
    if info["nq"] != conv.nq:
        case.mismatch("nq: moma %d, expected %d (pinocchio %d)" % (info["nq"], conv.nq, model.nq))
    if info["njoints"] != model.njoints:
        case.mismatch("njoints: moma %d, pinocchio %d" % (info["njoints"], model.njoints))
    case.err("total_mass", [info["total_mass"]], [pin.computeTotalMass(model)], 1e-9)
    mj = info["joints"]
    for k in range(1, model.njoints):
        if k - 1 >= len(mj):
            break
        jm = model.joints[k]
        name = model.names[k]
        oj = mj[k - 1]
        if oj["name"] != name:
            case.mismatch("joint %d: moma '%s', pinocchio '%s'" % (k, oj["name"], name))
            break
        if oj["parent"] != model.names[model.parents[k]]:
            case.mismatch("parent of %s: moma %s, pinocchio %s"
                          % (name, oj["parent"], model.names[model.parents[k]]))
        if oj["idx_v"] != jm.idx_v:
            case.mismatch("idx_v of %s" % name)
        want = PIN_TYPES.get(jm.shortname(), jm.shortname())
        if oj["type"] != want:
            family = lambda t: t.split("_")[0]  # noqa: E731
            if family(oj["type"]) == family(want):
                # same joint, one side uses the axis-aligned specialisation (Pinocchio keeps
                # e.g. axis (0, 0, 2) unaligned; moma normalises it first): the numbers below
                # decide
                case.notes.append("%s: moma %s, pinocchio %s" % (name, oj["type"], jm.shortname()))
            else:
                case.mismatch("type of %s: moma %s, pinocchio %s" % (name, oj["type"], jm.shortname()))
        if jm.nv == 1 and conv.joints[k - 1][4] == 0:
            iq, iv = jm.idx_q, jm.idx_v
            got = [lim(oj["lower"][0]), lim(oj["upper"][0])]
            want = [model.lowerPositionLimit[iq], model.upperPositionLimit[iq]]
            if None in got:
                case.mismatch("position limits of %s: moma %s, pinocchio %s" % (name, got, want))
            else:
                case.err("position limits of %s" % name, got, want, 1e-12)
        if jm.nv == 1:
            iv = jm.idx_v
            for key, arr in (("velocity_limit", model.velocityLimit),
                             ("effort_limit", model.effortLimit)):
                g = oj[key][0]
                w = float(arr[iv])
                # moma: a zero/absent limit is "unlimited" (null)
                if g is None:
                    if w not in (0.0, np.inf) and w < 1e300:
                        case.mismatch("%s of %s: moma unlimited, pinocchio %g" % (key, name, w))
                else:
                    case.err("%s of %s" % (key, name), [g], [w], 1e-12)
    # frames
    pf = [(f.name, FRAME_KINDS.get(f.type, "universe") if i > 0 else "universe",
           model.names[f.parentJoint]) for i, f in enumerate(model.frames)]
    of = [(f["name"], f["kind"], f["parent_joint"]) for f in info["frames"]]
    if len(pf) != len(of):
        case.mismatch("nframes: moma %d, pinocchio %d" % (len(of), len(pf)))
    for i, (a, b) in enumerate(zip(of, pf)):
        if a != b:
            case.mismatch("frame %d: moma %s, pinocchio %s" % (i, a, b))
            break


def check_case(args, urdf, robot, root, tmp):
    case = Case(robot, root)
    try:
        model = pin_model(urdf, root)
        pin_err = None
    except Exception as e:  # noqa: BLE001 - Pinocchio raises plain exceptions
        model, pin_err = None, str(e).strip().splitlines()[0]
    rc, out, err = run([args.moma, "inspect", urdf, "--root", root, "--json"])
    moma_err = None if rc == 0 else (err.splitlines()[-1] if err else "exit %d" % rc)
    if pin_err and moma_err:
        case.status, case.message = "both refuse", "moma: %s | pinocchio: %s" % (moma_err, pin_err)
        return case
    if pin_err:
        case.status, case.message = "pinocchio refuses", pin_err
        return case
    if moma_err:
        case.status, case.message = "moma refuses", moma_err
        return case
    info = json.loads(out)
    conv = Conv(model)
    case.nq_nv = "%d/%d" % (info["nq"], info["nv"])
    compare_structure(case, model, conv, info)
    if case.problems and any(p.startswith(("nv", "nq", "njoints", "joint ")) for p in case.problems):
        case.status, case.message = "FAIL", "; ".join(case.problems[:3])
        return case

    model.gravity.linear = np.array(args.gravity)
    data = model.createData()
    rng = np.random.default_rng(SEED)
    pstates, mstates = [], []
    for _ in range(args.states):
        dq = rng.uniform(-np.pi, np.pi, model.nv)
        qp = pin.integrate(model, pin.neutral(model), dq)
        vp = rng.uniform(-1, 1, model.nv)
        ap = rng.uniform(-1, 1, model.nv)
        taup = rng.uniform(-1, 1, model.nv)
        q = conv.q(qp)
        t = conv.t(q)
        q1p = pin.integrate(model, qp, 2.5 * vp)
        pstates.append((qp, vp, ap, taup, q, t, q1p))
        mstates.append({"q": q.tolist(), "v": (t.T @ vp).tolist(),
                        "a": conv.acc(q, vp, ap).tolist(), "tau": (t.T @ taup).tolist(),
                        "q1": conv.q(q1p).tolist()})
    sfile = os.path.join(tmp, "states.json")
    with open(sfile, "w") as f:
        json.dump({"states": mstates, "gravity": args.gravity}, f)

    frames = [i for i, f in enumerate(model.frames) if f.type == pin.FrameType.BODY]
    if frames and info["last_link"] != model.frames[frames[-1]].name:
        case.mismatch("last link: moma %s, pinocchio's last BODY frame %s"
                      % (info["last_link"], model.frames[frames[-1]].name))
    rc, out, err = run([args.dump, urdf, root, sfile])
    if rc != 0:
        case.status, case.message = "moma refuses", "dump: " + (err.splitlines()[-1] if err else "exit %d" % rc)
        return case
    res = json.loads(out)["states"]
    mass = pin.computeTotalMass(model)
    notes = set()
    nv = model.nv
    planar = conv.planar(conv.q(pin.neutral(model))) is not None
    rfs = [("local_world_aligned", pin.LOCAL_WORLD_ALIGNED), ("world", pin.WORLD),
           ("local", pin.LOCAL)]
    for si, ((qp, vp, ap, taup, q, t, q1p), r) in enumerate(zip(pstates, res)):
        tag = "s%d " % si
        zero = np.zeros(nv)
        a0p = t @ (zero - conv.acc(q, vp, zero))  # our q̈ = 0 in Pinocchio's coordinates
        pin.forwardKinematics(model, data, qp, vp, a0p)
        pin.updateFramePlacements(model, data)
        for fid in range(model.nframes):
            fname = model.frames[fid].name
            Mf = data.oMf[fid]
            rf = r["frames"][fid]
            case.err(tag + "position " + fname, rf["position"], Mf.translation, args.tol)
            case.err(tag + "rotation " + fname, rf["rotation"], Mf.rotation, args.tol)
            for key, ref in rfs:
                J = np.asarray(pin.computeFrameJacobian(model, data, qp, fid, ref)).reshape(6, nv)
                case.err(tag + "jacobian %s %s" % (key, fname),
                         np.array(rf["jacobian_" + key], dtype=float).reshape(6, nv),
                         J @ t, args.tol)
                case.err(tag + "velocity %s %s" % (key, fname), rf["velocity_" + key],
                         pin.getFrameVelocity(model, data, fid, ref).vector, args.tol)
                acc = (pin.getFrameClassicalAcceleration(model, data, fid, ref)
                       if ref == pin.LOCAL_WORLD_ALIGNED
                       else pin.getFrameAcceleration(model, data, fid, ref))
                case.err(tag + "bias %s %s" % (key, fname), rf["bias_" + key], acc.vector,
                         args.tol)
        pin.forwardKinematics(model, data, qp, vp, ap)
        for fid in range(model.nframes):
            case.err(tag + "acceleration local " + model.frames[fid].name,
                     r["frames"][fid]["acceleration_local"],
                     pin.getFrameAcceleration(model, data, fid, pin.LOCAL).vector, args.tol)
        if not planar:
            # integrate and difference (the planar root's conventions differ by design)
            want = conv.q(pin.integrate(model, qp, vp))
            got = np.array(r["integrate_q_v"], dtype=float)
            d = got - want
            for iq, oq, iv, jnv, kind in conv.joints:
                if kind == 2:  # continuous: one angle, equal modulo 2π
                    d[oq] = (d[oq] + np.pi) % (2 * np.pi) - np.pi
                elif jnv == 6 and np.dot(got[oq + 3:oq + 7], want[oq + 3:oq + 7]) < 0:
                    d[oq + 3:oq + 7] = got[oq + 3:oq + 7] + want[oq + 3:oq + 7]  # q ~ −q
            case.err(tag + "integrate", want + d, want, args.tol)
            want = pin.difference(model, qp, q1p)
            got = np.array(r["difference_q_q1"], dtype=float)
            d = got - want
            for iq, oq, iv, jnv, kind in conv.joints:
                if kind == 2:
                    d[iv] = (d[iv] + np.pi) % (2 * np.pi) - np.pi
            case.err(tag + "difference", want + d, want, args.tol)
        case.err(tag + "rnea", r["rnea_tau"], t.T @ pin.rnea(model, data, qp, vp, ap), args.tol)
        M = np.asarray(pin.crba(model, data, qp)).reshape(nv, nv)
        M = np.triu(M) + np.triu(M, 1).T
        case.err(tag + "crba", np.array(r["crba_M"], dtype=float).reshape(nv, nv), t.T @ M @ t, args.tol)
        ddq = pin.aba(model, data, qp, vp, taup)
        got = np.array([np.nan if x is None else x for x in r["aba_ddq"]], dtype=float)
        nle = pin.nonLinearEffects(model, data, qp, vp)
        h = t.T @ (M @ a0p + nle)  # our h(q, v)
        if np.all(np.isfinite(ddq)):
            want = conv.acc(q, vp, ddq)
            fwd, _ = relerr(got, want)
            if fwd > args.tol:
                # M(q) can be ill-conditioned (iCub: cond up to 4e9, so a 1e-16 change of M
                # moves q̈ by 1e-7); then judge ABA by its backward error: the residual of
                # H q̈ + h = τ with Pinocchio's H and h, relative to the terms' sizes
                H, tau = t.T @ M @ t, t.T @ taup
                res = np.abs(H @ got + h - tau).max() / (
                    np.abs(H).sum(axis=1).max() * np.abs(got).max() + np.abs(h).max()
                    + np.abs(tau).max())
                cond = np.linalg.cond(H)
                if res <= 1e-14 and fwd <= 100 * cond * np.finfo(float).eps:
                    notes.add("ABA ill-conditioned: cond(H) up to %.1e, forward error %.1e, "
                              "backward error %.1e" % (cond, fwd, res))
                    want = got
            case.err(tag + "aba", got, want, args.tol)
        elif np.all(np.isfinite(got)):
            case.mismatch(tag + "aba: pinocchio non-finite, moma finite")
        else:
            notes.add("ABA singular in both (massless subtree)")
        case.err(tag + "nle", r["nle"], h, args.tol)
        case.err(tag + "gravity", r["gravity_torque"],
                 t.T @ pin.computeGeneralizedGravity(model, data, qp), args.tol)
        if conv.planar(q) is None:
            C = np.asarray(pin.computeCoriolisMatrix(model, data, qp, vp)).reshape(nv, nv)
            case.err(tag + "coriolis", np.array(r["coriolis_C"], dtype=float).reshape(nv, nv),
                     C, args.tol)
        if mass > 0:
            case.err(tag + "com", r["com"], pin.centerOfMass(model, data, qp), args.tol)
        else:
            notes.add("massless model: CoM undefined (Pinocchio NaN, moma the origin)")
        ag = np.asarray(pin.ccrba(model, data, qp, vp)).reshape(6, nv)
        if mass > 0:
            case.err(tag + "Ag", np.array(r["centroidal_map_Ag"], dtype=float).reshape(6, nv),
                     ag @ t, args.tol)
        case.err(tag + "kinetic", [r["kinetic_energy"]],
                 [pin.computeKineticEnergy(model, data, qp, vp)], args.tol)
        case.err(tag + "potential", [r["potential_energy"]],
                 [pin.computePotentialEnergy(model, data, qp)], args.tol)
    # the command line: `moma dynamics` (default frame: the last link) must print the
    # library's values (row-major matrices, unit quaternion; to the tolerance, as the
    # order of the calls differs from the dump's)
    g = ",".join("%.17g" % x for x in args.gravity)
    rc, out, err = run([args.moma, "dynamics", urdf, "--root", root, "--states", sfile,
                        "--gravity", g])
    if rc != 0:
        if "singular" in err and "ABA singular in both (massless subtree)" in notes:
            notes.add("moma dynamics refuses the singular ABA, as documented")
        else:
            case.mismatch("moma dynamics: " + (err.splitlines()[-1] if err else "exit %d" % rc))
    else:
        cli = json.loads(out)
        fid = [i for i, f in enumerate(model.frames) if f.name == cli["frame"]][0]
        for si, (c, r) in enumerate(zip(cli["states"], res)):
            tag = "cli s%d " % si
            for key in ("rnea_tau", "nle", "gravity_torque", "com", "kinetic_energy",
                        "potential_energy"):
                case.err(tag + key, np.atleast_1d(c[key]), np.atleast_1d(r[key]), args.tol)
            for key in ("crba_M", "centroidal_map_Ag"):
                case.err(tag + key, np.array(c[key], dtype=float).ravel(),
                         np.array(r[key], dtype=float).ravel(), args.tol)
            case.err(tag + "aba_ddq", c["aba_ddq"], r["aba_ddq"], args.tol)
            rf = r["frames"][fid]
            case.err(tag + "position", c["position"], rf["position"], args.tol)
            case.err(tag + "rotation", c["rotation"], rf["rotation"], args.tol)
            case.err(tag + "jacobian", np.array(c["jacobian_local_world_aligned"]).ravel(),
                     np.array(rf["jacobian_local_world_aligned"]).ravel(), args.tol)
            quat = np.array(c["quaternion_xyzw"])
            rot = pin.Quaternion(quat[3], quat[0], quat[1], quat[2]).toRotationMatrix()
            case.err(tag + "quaternion", rot, np.array(rf["rotation"]), args.tol)
            case.err(tag + "quaternion norm", [np.linalg.norm(quat)], [1.0], args.tol)
    case.notes += sorted(notes)
    if case.problems:
        case.status = "FAIL"
        case.message = "; ".join(case.problems[:3]) + (
            " (+%d more)" % (len(case.problems) - 3) if len(case.problems) > 3 else "")
    else:
        case.message = "; ".join(case.notes + ["worst: " + case.worst_what.split(" got ")[0]])
    return case


def random_urdf(rng, index):
    """A random robot description: a random tree of 2-14 links with revolute, continuous,
    prismatic and fixed joints, links and joints in random document order, random joint
    names (mixed case, digits, underscores), unit / negative /
    non-normalised / arbitrary axes, rotated origins, rotated inertials (some zero-mass with
    inertia, some point masses, a few links without <inertial>)."""
    def f(x):
        return " ".join("%.17g" % v for v in x)

    def name():
        alphabet = "abcXYZ_019"
        return "".join(rng.choice(list(alphabet), size=rng.integers(1, 6)))

    n = int(rng.integers(2, 15))
    links = ["L%d_%s" % (k, name()) for k in range(n)]
    out = ['<?xml version="1.0"?>', '<robot name="random_%d">' % index]
    for k, ln in enumerate(links):
        u = rng.uniform()
        if u < 0.08 and k > 0:
            out.append('  <link name="%s"/>' % ln)
            continue
        # a massless root body next to a prismatic joint makes a free-flyer or planar
        # root redundant (H singular): keep the root massive
        mass = 0.0 if u < 0.15 and k > 0 else float(rng.uniform(0.05, 5.0))
        if u > 0.92:
            inertia = np.zeros((3, 3))  # point mass
        else:
            p = rng.uniform(0.01, 0.3, 3)
            moments = np.array([p[1] + p[2], p[0] + p[2], p[0] + p[1]]) * max(mass, 0.1) * 0.05
            q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
            inertia = q @ np.diag(moments) @ q.T
        out.append('  <link name="%s"><inertial><origin xyz="%s" rpy="%s"/><mass value="%.17g"/>'
                   '<inertia ixx="%.17g" ixy="%.17g" ixz="%.17g" iyy="%.17g" iyz="%.17g" '
                   'izz="%.17g"/></inertial></link>'
                   % (ln, f(rng.uniform(-0.2, 0.2, 3)), f(rng.uniform(-np.pi, np.pi, 3)), mass,
                      inertia[0, 0], inertia[0, 1], inertia[0, 2], inertia[1, 1],
                      inertia[1, 2], inertia[2, 2]))
    used = set()
    for k in range(1, n):
        parent = links[int(rng.integers(0, k))]
        jt = rng.choice(["revolute", "continuous", "prismatic", "fixed"], p=[0.4, 0.15, 0.2, 0.25])
        jn = name()
        while jn in used:
            jn = name()
        used.add(jn)
        kind = rng.integers(0, 4)
        if kind == 0:
            axis = np.eye(3)[rng.integers(0, 3)] * rng.choice([-1.0, 1.0])
        elif kind == 1:
            axis = np.eye(3)[rng.integers(0, 3)] * rng.uniform(0.2, 3.0)
        else:
            axis = rng.normal(size=3)
        lo = float(rng.uniform(-3, 0))
        out.append('  <joint name="%s" type="%s"><parent link="%s"/><child link="%s"/>'
                   '<origin xyz="%s" rpy="%s"/><axis xyz="%s"/>'
                   '<limit lower="%.17g" upper="%.17g" effort="%.17g" velocity="%.17g"/></joint>'
                   % (jn, jt, parent, links[k], f(rng.uniform(-0.5, 0.5, 3)),
                      f(rng.uniform(-np.pi, np.pi, 3)), f(axis), lo, lo + float(rng.uniform(0.1, 4)),
                      float(rng.uniform(0, 100)), float(rng.uniform(0, 10))))
    body = out[2:]
    rng.shuffle(body)  # document order must not matter
    return "\n".join(out[:2] + body + ["</robot>"]) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--moma", default=os.path.join(target_dir(), "release", "moma"))
    ap.add_argument("--dump", default=os.path.join(target_dir(), "release", "examples",
                                                   "rigid_body_dump"))
    ap.add_argument("--robots", default=None)
    ap.add_argument("--extra", nargs="*", default=[os.path.join(
        os.path.dirname(os.path.abspath(__file__)), "xcheck_urdf")])
    ap.add_argument("--filter", default="")
    ap.add_argument("--random", type=int, default=0,
                    help="also check this many seeded random robot descriptions")
    ap.add_argument("--states", type=int, default=3)
    ap.add_argument("--gravity", default="0,0,-9.81",
                    help="gravity gx,gy,gz (world axes) for both libraries")
    ap.add_argument("--tol", type=float, default=1e-9)
    ap.add_argument("--markdown", default=None)
    ap.add_argument("--json", default=None)
    args = ap.parse_args()
    args.gravity = [float(x) for x in args.gravity.split(",")]
    robots = args.robots or default_robots_dir()
    files = [(os.path.relpath(f, robots), f)
             for f in sorted(glob.glob(os.path.join(robots, "*", "*", "*.urdf")))]
    for e in args.extra:
        extra = sorted(glob.glob(os.path.join(e, "*.urdf"))) if os.path.isdir(e) else [e]
        files += [(os.path.basename(f), f) for f in extra]
    files = [(n, f) for n, f in files if args.filter in n]
    cases = []
    with tempfile.TemporaryDirectory() as tmp:
        rng = np.random.default_rng(SEED)
        for k in range(args.random):
            path = os.path.join(tmp, "random_%03d.urdf" % k)
            with open(path, "w") as f:
                f.write(random_urdf(rng, k))
            files.append(("random_%03d.urdf" % k, path))
        for robot, f in files:
            for root in ROOTS:
                c = check_case(args, f, robot, root, tmp)
                c.message = c.message.replace(os.path.dirname(f) + os.sep, "")
                exp = EXPECTED.get(os.path.basename(c.robot))
                if exp and c.status == exp[0]:
                    c.status += " (expected)"
                    c.message += " -- " + exp[1]
                cases.append(c)
                print("%-62s %-10s %-17s %9.2e  %s" % (c.robot, c.root, c.status, c.worst,
                                                       c.message[:300]), flush=True)
    bad = [c for c in cases if c.status not in ("ok", "both refuse")
           and not c.status.endswith("(expected)")]
    print("\n%d cases, %d unexpected: %s" % (len(cases), len(bad),
                                            ", ".join("%s/%s" % (c.robot, c.root) for c in bad)))
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write("Generated by `bench/xcheck_pinocchio.py` (Pinocchio %s, example-robot-data "
                    "robots and `bench/xcheck_urdf/`): %d seeded states per case, tolerance "
                    "%.0e relative (absolute below 1); nq/nv are moma's. %d cases, %d "
                    "unexpected.\n\n" % (pin.__version__, args.states, args.tol, len(cases),
                                          len(bad)))
            f.write("| robot | root | nq/nv | status | worst rel. error | where / message |\n")
            f.write("| --- | --- | --- | --- | --- | --- |\n")
            for c in cases:
                msg = c.message.replace("|", "\\|")
                f.write("| %s | %s | %s | %s | %.1e | %s |\n"
                        % (c.robot, c.root, c.nq_nv, c.status, c.worst, msg))
    if args.json:
        with open(args.json, "w") as f:
            json.dump([{"robot": c.robot, "root": c.root, "status": c.status, "worst": c.worst,
                        "message": c.message, "problems": c.problems} for c in cases], f, indent=1)
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Peer measurement for the "Whole-body kinematics and manipulability" benches: the same
quantities computed with Pinocchio (PyPI `pin`) + numpy, in the same run as
`cargo bench -p moma --bench manipulability`.

  python3 bench/manip_pinocchio.py [path/to/panda.urdf]

1. whole-body Jacobian (Panda on a differential drive, 6 x 11) plus all measures;
2. LM IK to 1e-6 (full pose) on 100 seeded reachable targets (FK of random
   configurations within the limits) from the neutral configuration, with restarts;
3. a base-placement map (position target, 8 headings) on a 25 x 25 sub-grid of the Rust
   bench's 100 x 100 grid (the full map is too slow from Python); per-pose cost reported.

The IK is the same damped least-squares / Levenberg-Marquardt iteration as moma's
(adaptive damping, limits by projection) so iteration counts are comparable.
"""
import sys
import time

import numpy as np
import pinocchio as pin

URDF = sys.argv[1] if len(sys.argv) > 1 else "crates/moma/tests/data/manipulability/panda.urdf"
FRAME = "panda_hand_tcp"
R_W, B, D = 0.08, 0.27, 0.12


def measures(j, u):
    s = np.linalg.svd(j, compute_uv=True)
    U, sv = s[0], s[1]
    w = float(np.prod(sv))
    ratio = sv[-1] / sv[0]
    c = U.T @ u
    inside = sv > 1e-12 * sv[0]
    rv = 1.0 / np.sqrt(np.sum((c[inside] / sv[inside]) ** 2))
    sup = np.linalg.norm(j.T @ u)
    return dict(
        w=w,
        inv_cond=ratio,
        cond=1.0 / ratio,
        smin=sv[-1],
        gmean=w ** (1.0 / len(sv)),
        ecc=np.sqrt(1 - ratio ** 2),
        rv=rv,
        sup=sup,
        rf=1.0 / sup,
        psum=float(np.sum(sv * np.abs(c))),
    )


def whole_body_bench():
    model = pin.buildModelFromUrdf(URDF, pin.JointModelPlanar())
    data = model.createData()
    fid = model.getFrameId(FRAME)
    lo = model.lowerPositionLimit.copy()
    hi = model.upperPositionLimit.copy()
    lo[:4], hi[:4] = -1.0, 1.0  # planar root: finite bounds for sampling
    qs = [pin.randomConfiguration(model, lo, hi) for _ in range(64)]
    # Pinocchio's planar joint: q = [x, y, cos θ, sin θ], v = [vx, vy, ω] in the base
    # frame. Base origin d ahead of the axle: v_local = [v, d ω, ω]; wheels -> (v, ω).
    Wm = np.array([[R_W / 2, R_W / 2], [-R_W / (2 * B), R_W / (2 * B)]])
    Nb = np.array([[1.0, 0.0], [0.0, D], [0.0, 1.0]]) @ Wm
    N = np.zeros((model.nv, model.nv - 1))
    N[:3, :2] = Nb
    N[3:, 2:] = np.eye(model.nv - 3)
    u = np.array([1.0, 0, 0, 0, 0, 0])
    n = 20000
    t0 = time.perf_counter()
    for i in range(n):
        q = qs[i % 64]
        J = pin.computeFrameJacobian(model, data, q, fid, pin.LOCAL_WORLD_ALIGNED)
        Jbar = J @ N
        measures(Jbar, u)
    dt = (time.perf_counter() - t0) / n
    t0 = time.perf_counter()
    for i in range(n):
        J = pin.computeFrameJacobian(model, data, qs[i % 64], fid, pin.LOCAL_WORLD_ALIGNED)
        Jbar = J @ N
    dj = (time.perf_counter() - t0) / n
    print(f"pinocchio whole_body/jacobian_6x11: {dj * 1e6:.2f} us  (shape {Jbar.shape})")
    print(f"pinocchio whole_body/jacobian_and_all_measures: {dt * 1e6:.2f} us")


class Ik:
    def __init__(self, model):
        self.model = model
        self.data = model.createData()
        self.fid = model.getFrameId(FRAME)
        self.lo = model.lowerPositionLimit
        self.hi = model.upperPositionLimit

    def residual_jac(self, q, target, rows):
        J = pin.computeFrameJacobian(self.model, self.data, q, self.fid, pin.LOCAL_WORLD_ALIGNED)
        M = self.data.oMf[self.fid]
        e = np.concatenate([M.translation - target.translation, pin.log3(M.rotation @ target.rotation.T)])
        return e[rows], J[rows]

    def solve(self, q0, target, rows, tol=1e-6, max_it=200):
        q = np.clip(q0, self.lo, self.hi)
        e, J = self.residual_jac(q, target, rows)
        err = np.linalg.norm(e)
        lam, it, slow = 1e-3, 0, 0
        while err > tol and it < max_it and lam <= 1e8:
            it += 1
            A = J @ J.T + lam * np.eye(len(e))
            dq = -J.T @ np.linalg.solve(A, e)
            nrm = np.linalg.norm(dq)
            if nrm > 0.5:
                dq *= 0.5 / nrm
            qt = np.clip(pin.integrate(self.model, q, dq), self.lo, self.hi)
            et, Jt = self.residual_jac(qt, target, rows)
            errt = np.linalg.norm(et)
            if errt < err:
                slow = slow + 1 if err - errt <= 1e-3 * err else 0
                q, e, J, err = qt, et, Jt, errt
                lam = max(lam / 3, 1e-10)
                if slow >= 4:
                    break
            else:
                lam *= 8
        return q, err <= tol, it, err

    def solve_restarts(self, q0, target, rows, restarts, rng):
        q, ok, it, err = self.solve(q0, target, rows)
        total = it
        for _ in range(restarts):
            if ok:
                break
            qs = rng.uniform(self.lo, self.hi)
            q2, ok2, it2, err2 = self.solve(qs, target, rows)
            total += it2
            if ok2 or err2 < err:
                q, ok, err = q2, ok2, err2
        return q, ok, total, err


def ik_bench():
    model = pin.buildModelFromUrdf(URDF)
    ik = Ik(model)
    rng = np.random.default_rng(5)
    targets = []
    for _ in range(100):
        q = rng.uniform(model.lowerPositionLimit, model.upperPositionLimit)
        pin.framesForwardKinematics(model, ik.data, q)
        targets.append(ik.data.oMf[ik.fid].copy())
    q0 = pin.neutral(model)
    rows = np.arange(6)
    t0 = time.perf_counter()
    conv, iters = 0, 0
    for s, t in enumerate(targets):
        _, ok, it, _ = ik.solve_restarts(q0, t, rows, 10, np.random.default_rng(s))
        conv += ok
        iters += it
    dt = time.perf_counter() - t0
    print(f"pinocchio ik/panda_100_targets: {dt * 1e3:.1f} ms, {conv}/100 converged, {iters} iterations")


def placement_bench():
    model = pin.buildModelFromUrdf(URDF)
    ik = Ik(model)
    target_w = np.array([1.0, 0.5, 0.5])
    q0 = pin.neutral(model)
    rows = np.arange(3)
    xs = np.arange(100) * 0.02
    ys = -0.5 + np.arange(100) * 0.02
    heads = -np.pi + 2 * np.pi * np.arange(8) / 8
    n, reach = 0, 0
    t0 = time.perf_counter()
    for iy in range(0, 100, 4):
        warm = [None] * 8
        for ix in range(0, 100, 4):
            for k, th in enumerate(heads):
                c, s = np.cos(th), np.sin(th)
                d = target_w - np.array([xs[ix], ys[iy], 0.0])
                local = pin.SE3(np.eye(3), np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1], d[2]]))
                ok = False
                if warm[k] is not None:
                    q, ok, _, _ = ik.solve(warm[k], local, rows, max_it=100)
                if not ok:
                    q, ok, _, _ = ik.solve_restarts(q0, local, rows, 2, np.random.default_rng(n))
                warm[k] = q if ok else None
                if ok:
                    J = pin.computeFrameJacobian(model, ik.data, q, ik.fid, pin.LOCAL_WORLD_ALIGNED)
                    np.prod(np.linalg.svd(J[:3], compute_uv=False))
                    reach += 1
                n += 1
    dt = time.perf_counter() - t0
    print(
        f"pinocchio placement/panda 25x25x8 sub-grid: {dt:.2f} s for {n} poses "
        f"({dt / n * 1e6:.0f} us/pose, {reach} reachable); x{80000 / n:.0f} for 100x100x8: {dt * 80000 / n:.1f} s"
    )


if __name__ == "__main__":
    print(f"pinocchio {pin.__version__}, numpy {np.__version__}")
    whole_body_bench()
    ik_bench()
    placement_bench()

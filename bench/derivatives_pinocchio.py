"""Writes the Pinocchio 4.1 reference cases of moma's dynamics derivatives
(`crates/moma/tests/data/derivatives/*.json`, the schema of the shared `panda.json`).

Usage (from the repository root, Pinocchio 4.1.0 in the Python environment:
`pip install pin==4.1.0`):

    python bench/derivatives_pinocchio.py crates/moma/tests/data/derivatives

For each robot (URDFs of `crates/moma/tests/data/pinocchio/urdf/`) and root (fixed,
planar, free-flyer), a few seeded random states q = neutral ⊕ U(−π, π)^nv, v, a, τ ~
U(−1, 1), and the outputs of `computeRNEADerivatives(model, data, q, v, a)` and
`computeABADerivatives(model, data, q, v, tau)` in Pinocchio's layout (planar root
[x, y, cos θ, sin θ] with a base-frame velocity, continuous joints [cos θ, sin θ]).
The mass matrix and its inverse are symmetrised from Pinocchio's upper triangle.
Each file also records the largest relative deviation of Pinocchio's values from central
finite differences (q through pinocchio.integrate), as a check on the reference itself.
"""
import json
import os
import sys

import numpy as np
import pinocchio as pin

SEED = 20261204
URDF_DIR = "../pinocchio/urdf"  # relative to the output folder
CASES = [
    ("panda_fixed", "panda.urdf", "fixed"),
    ("panda_planar", "panda.urdf", "planar"),
    ("panda_freeflyer", "panda.urdf", "free-flyer"),
    ("ur5_fixed", "ur5_robot.urdf", "fixed"),
    ("ur5_planar", "ur5_robot.urdf", "planar"),
    ("ur5_freeflyer", "ur5_robot.urdf", "free-flyer"),
    ("tiago_fixed", "tiago.urdf", "fixed"),
    ("tiago_planar", "tiago.urdf", "planar"),
    ("tiago_freeflyer", "tiago.urdf", "free-flyer"),
]
ROOTS = {"fixed": None, "planar": pin.JointModelPlanar, "free-flyer": pin.JointModelFreeFlyer}


def sym(m):
    m = np.asarray(m)
    return np.triu(m) + np.triu(m, 1).T


def fd_check(model, data, q, v, a, tau, out, h=1e-6):
    """Largest |FD − analytic| / max(1, max|analytic|) over the four derivative matrices."""
    nv = model.nv
    worst = 0.0
    for key, f in [("drnea", lambda q, v: pin.rnea(model, data, q, v, a)),
                   ("daba", lambda q, v: pin.aba(model, data, q, v, tau))]:
        dq = np.zeros((nv, nv))
        dv = np.zeros((nv, nv))
        for j in range(nv):
            e = np.zeros(nv)
            e[j] = h
            dq[:, j] = (f(pin.integrate(model, q, e), v) - f(pin.integrate(model, q, -e), v)) / (2 * h)
            dv[:, j] = (f(q, v + e) - f(q, v - e)) / (2 * h)
        for name, m in [(key + "_dq", dq), (key + "_dv", dv)]:
            ref = np.asarray(out[name])
            worst = max(worst, np.abs(m - ref).max() / max(1.0, np.abs(ref).max()))
    return worst


def main(out_dir):
    for name, urdf, root in CASES:
        path = os.path.join(out_dir, URDF_DIR, urdf)
        model = (pin.buildModelFromUrdf(path) if ROOTS[root] is None
                 else pin.buildModelFromUrdf(path, ROOTS[root]()))
        data = model.createData()
        rng = np.random.default_rng(SEED)
        nv = model.nv
        states = []
        fd_worst = 0.0
        for _ in range(3):
            q = pin.integrate(model, pin.neutral(model), rng.uniform(-np.pi, np.pi, nv))
            v = rng.uniform(-1, 1, nv)
            a = rng.uniform(-1, 1, nv)
            tau = rng.uniform(-1, 1, nv)
            s = {"q": q.tolist(), "v": v.tolist(), "a": a.tolist(), "tau": tau.tolist()}
            dq, dv, da = pin.computeRNEADerivatives(model, data, q, v, a)
            s["drnea_dq"] = np.asarray(dq).tolist()
            s["drnea_dv"] = np.asarray(dv).tolist()
            s["drnea_da"] = sym(da).tolist()
            dq, dv, dtau = pin.computeABADerivatives(model, data, q, v, tau)
            s["daba_dq"] = np.asarray(dq).tolist()
            s["daba_dv"] = np.asarray(dv).tolist()
            s["daba_dtau"] = sym(dtau).tolist()
            fd_worst = max(fd_worst, fd_check(model, data, q, v, a, tau, s))
            states.append(s)
        joints = []
        for j in range(1, model.njoints):
            jm = model.joints[j]
            joints.append({"name": model.names[j], "type": jm.shortname(), "idx_q": jm.idx_q,
                           "idx_v": jm.idx_v, "nq": jm.nq, "nv": jm.nv})
        doc = {
            "source": {
                "pinocchio_version": pin.__version__,
                "script": "bench/derivatives_pinocchio.py",
                "seed": SEED, "numpy_rng": "default_rng (PCG64)",
                "functions": "computeRNEADerivatives(model, data, q, v, a); "
                             "computeABADerivatives(model, data, q, v, tau)",
                "finite_difference_check": fd_worst,
            },
            "robot": name, "urdf": URDF_DIR + "/" + urdf, "root": root,
            "layout": "pinocchio", "gravity": model.gravity.linear.tolist(),
            "nq": model.nq, "nv": nv, "joints": joints, "states": states,
        }
        with open(os.path.join(out_dir, name + ".json"), "w") as f:
            json.dump(doc, f)
        print(name, "nv", nv, "fd check", fd_worst)


if __name__ == "__main__":
    main(sys.argv[1])
